//! keyrig-render: the wgpu renderer of keyrig.
//!
//! - [`skinning`]: the four skin deformers and MD2 vertex morphing as WGSL compute passes.
//! - [`renderer`]: meshes, lights, render styles, grid, skeletons, motion paths, selection,
//!   rendered into an offscreen [`Viewport`] — shared by the editor and headless rendering.
//! - [`headless`]: its own device, frames to [`image::RgbaImage`].
//! - [`gpu`]: opening a device without a window, reading buffers back.
//!
//! See docs/rendering.md for the architecture, the data layouts and how the editor embeds it.

pub mod camera;
mod error;
pub mod gpu;
pub mod headless;
pub mod overlay;
pub mod renderer;
pub mod scene_frame;
pub mod skinning;

pub use error::RenderError;
pub use gpu::GpuContext;
pub use headless::{HeadlessRenderer, HEADLESS_FORMAT};
/// The `image` crate this crate renders into (re-exported so callers save PNGs with the same version).
pub use image;
pub use overlay::{LightGizmo, MotionPath, SkeletonOverlay};
pub use renderer::{
    Deform, DrawItem, FrameInput, FrameStats, LightInput, MeshData, MeshId, RenderStyle, Renderer, Viewport,
};
pub use scene_frame::{ObjectState, SceneFrameError, SceneRig, Selection, ViewOptions};
pub use skinning::{
    joint_poses, BlendBinding, GpuSkinner, JointPose, OwnedSkinInput, SkinMeshInput, SkinnedVertex,
};
