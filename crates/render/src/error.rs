//! The renderer's error type.

use thiserror::Error;

/// What can go wrong while setting up the GPU, uploading data or rendering.
#[derive(Debug, Error)]
pub enum RenderError {
    /// wgpu found no adapter at all. On a machine without a GPU, lavapipe (the CPU Vulkan
    /// driver) provides one.
    #[error(
        "no GPU adapter found ({0}); on a machine without a GPU install the CPU Vulkan driver \
         lavapipe (Debian/Ubuntu package `mesa-vulkan-drivers`, with `libvulkan1`)"
    )]
    NoAdapter(String),
    /// The adapter refused to open a device.
    #[error("could not open a GPU device on adapter `{adapter}`: {message}")]
    RequestDevice { adapter: String, message: String },
    /// Mesh data whose arrays disagree in length.
    #[error("mesh data: `{field}` has {actual} entries, expected {expected}")]
    LengthMismatch { field: &'static str, expected: usize, actual: usize },
    /// A vertex refers to a joint the skeleton does not have.
    #[error("mesh data: vertex {vertex} refers to joint {joint}, but the skeleton has {joint_count} joints")]
    JointOutOfRange { vertex: usize, joint: u32, joint_count: usize },
    /// A triangle refers to a vertex the mesh does not have.
    #[error(
        "mesh data: index {position} refers to vertex {index}, but the mesh has {vertex_count} vertices"
    )]
    IndexOutOfRange { position: usize, index: u32, vertex_count: usize },
    /// NaN or infinity in input data.
    #[error("{what} [{index}] is not finite")]
    NonFinite { what: &'static str, index: usize },
    /// A negative skin weight or a vertex whose weights are all zero.
    #[error("mesh data: vertex {vertex} has invalid weights {weights:?} (need non-negative, not all zero)")]
    BadWeights { vertex: usize, weights: [f32; 4] },
    /// The mesh has no vertices, no joints, or more than one dispatch can cover.
    #[error("mesh data: {0}")]
    BadCount(String),
    /// A frame refers to a mesh that was never uploaded (or was removed).
    #[error("no mesh with id {0} has been uploaded")]
    UnknownMesh(u64),
    /// The joint data of a frame does not fit the uploaded mesh.
    #[error("mesh {mesh}: frame has {actual} joints, the uploaded skin has {expected}")]
    JointCountMismatch { mesh: u64, expected: usize, actual: usize },
    /// A morph frame index past the uploaded frames.
    #[error("mesh {mesh}: morph frame {frame} out of range ({frame_count} frames)")]
    MorphFrameOutOfRange { mesh: u64, frame: u32, frame_count: u32 },
    /// An image size that is zero or beyond the device's texture limit.
    #[error("image size {width}×{height} is invalid: {reason}")]
    InvalidSize { width: u32, height: u32, reason: String },
    /// A sample count other than 1 or 4 (the counts every WebGPU adapter supports).
    #[error("{0} samples per pixel is not supported (use 1 or 4)")]
    UnsupportedSampleCount(u32),
    /// wgpu reported a validation or out-of-memory error, or a buffer could not be mapped.
    #[error("GPU error: {0}")]
    Gpu(String),
}
