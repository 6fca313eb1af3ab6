//! keyrig-render: the wgpu renderer of keyrig.
//!
//! - [`skinning`]: the four skin deformers and MD2 vertex morphing as WGSL compute passes.
//! - [`renderer`]: meshes, lights, render styles, grid, skeletons, motion paths, selection,
//!   rendered into an offscreen [`Viewport`] — shared by the editor and headless rendering.
//! - [`headless`]: its own device, frames to [`image::RgbaImage`], motion-blurred frames
//!   through [`accumulate`] (sub-frames averaged on the GPU).
//! - [`gpu`]: opening a device without a window, reading buffers back.
//!
//! See docs/rendering.md for the architecture, the data layouts and how the editor embeds it.
//!
//! Headless, from a scene to a PNG:
//!
//! ```no_run
//! use keyrig_render::{HeadlessRenderer, SceneRig, ViewOptions};
//!
//! # fn demo(scene: &keyrig_core::Scene) -> Result<(), Box<dyn std::error::Error>> {
//! let mut headless = HeadlessRenderer::new()?; // lavapipe when there is no GPU
//! let rig = SceneRig::new(scene)?; // validates tracks, builds meshes and bindings once
//! rig.upload(headless.renderer_mut())?; // vertex data goes to the GPU once
//! let frame = rig.frame(rig.time_of_frame(30.0), &ViewOptions::default())?;
//! let (image, stats) = headless.render_image(&frame, 1280, 720)?;
//! image.save("frame30.png")?;
//! println!("{} bytes uploaded this frame", stats.bytes_uploaded());
//! # Ok(())
//! # }
//! ```

pub mod accumulate;
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
pub use overlay::{CameraGizmo, LightGizmo, MotionPath, SkeletonOverlay};
pub use renderer::sampled_texture_layout;
pub use renderer::{
    Deform, DrawItem, FrameDraws, FrameInput, FrameStats, Ghost, LightInput, MeshData, MeshId, RenderStyle,
    Renderer, Viewport, DEPTH_FORMAT, SAMPLE_COUNT, SUPPORTED_SAMPLE_COUNTS,
};
pub use scene_frame::{
    MorphBlend, MorphClip, MorphError, MorphMesh, SceneFrameError, SceneRig, Selected, ViewOptions,
    GHOST_MESHES, MAX_GHOSTS,
};
pub use skinning::{
    joint_poses, BlendBinding, GpuSkinner, JointPose, OwnedSkinInput, SkinMeshInput, SkinnedVertex,
};
