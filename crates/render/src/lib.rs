//! keyrig-render: the wgpu renderer of keyrig.
//!
//! - [`skinning`]: the four skin deformers and MD2 vertex morphing as WGSL compute passes.
//! - [`gpu`]: opening a device without a window, reading buffers back.
//!
//! See docs/rendering.md for the architecture, the data layouts and how the editor embeds it.

mod error;
pub mod gpu;
pub mod skinning;

pub use error::RenderError;
pub use gpu::GpuContext;
pub use skinning::{
    joint_poses, BlendBinding, GpuSkinner, JointPose, OwnedSkinInput, SkinMeshInput, SkinnedVertex,
};
