//! The viewport drawn by keyrig-render on eframe's wgpu device: GPU skinning with the object's
//! deformer, lights, grid, skeletons and the selection's motion path, rendered into an
//! offscreen texture that the viewport panel shows as an egui image (docs/rendering.md,
//! "Embedding in the editor"). The editor's scene evaluator (with pose overrides) provides the
//! state of the frame; the [`SceneRig`] shares that evaluator and is rebuilt, with its vertex
//! buffers uploaded, only when the evaluator is (the document or its loaded meshes changed).
//! A frame uploads joint palettes, morph frames and uniforms only.
//!
//! Without a wgpu render state (the UI tests, or a failure here) the viewport panel falls back
//! to drawing the CPU-skinned mesh with egui's painter.

use egui::TextureId;
use egui_wgpu::{wgpu, RenderState};
use keyrig_render::{FrameStats, Renderer, SceneRig, ViewOptions, Viewport};

/// Why the GPU viewport could not draw a frame (shown over the viewport).
#[derive(Debug, thiserror::Error)]
pub enum GpuViewError {
    #[error(transparent)]
    Render(#[from] keyrig_render::RenderError),
    #[error(transparent)]
    Scene(#[from] keyrig_render::SceneFrameError),
    #[error("no scene prepared for rendering")]
    NoScene,
    #[error("no viewport texture")]
    NoTarget,
}

/// The colour format of the offscreen viewport (sRGB: the shaders write linear colour).
const FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// What the viewport panel hands over each frame.
pub struct GpuFrame<'a> {
    pub scene: &'a keyrig_core::Scene,
    /// [`crate::app::EditorApp::evaluator_key`]: the rig is rebuilt when it changes.
    pub rig_key: (u64, u64, u64),
    /// The document's evaluator, shared with the rig when it is rebuilt.
    pub evaluator: std::sync::Arc<keyrig_eval::SceneEvaluator>,
    /// The frame, evaluated with the editor's pose overrides.
    pub state: &'a keyrig_eval::SceneState,
    pub overrides: &'a keyrig_eval::Overrides,
    pub view: ViewOptions,
    /// Vertex-animated meshes (MD2) of objects whose mesh is a file, by object index; only
    /// read when the rig is rebuilt (see [`GpuView::needs_rig`]).
    pub morph_meshes: std::collections::HashMap<usize, std::sync::Arc<keyrig_render::MorphMesh>>,
    /// Materials of skinned file meshes, by object (read, like `morph_meshes`, only when the
    /// rig is rebuilt).
    pub materials: std::collections::HashMap<usize, std::sync::Arc<keyrig_core::Material>>,
    /// Onion-skin ghosts: an object's state at another frame and how to draw it (farthest
    /// first).
    pub ghosts: Vec<(usize, keyrig_eval::ObjectState, keyrig_render::Ghost)>,
}

/// keyrig-render's renderer and offscreen viewport on the editor's device.
pub struct GpuView {
    render_state: RenderState,
    renderer: Renderer,
    target: Option<(Viewport, TextureId)>,
    rig: Option<((u64, u64, u64), SceneRig)>,
    /// The ghost meshes on the GPU: (object, count) for the current rig.
    ghost_meshes: Option<(usize, usize)>,
    /// Statistics of the last rendered frame.
    pub last_stats: Option<FrameStats>,
    /// Wall-clock time of the last [`GpuView::render`] call (the frame benchmark's split).
    pub last_render_time: std::time::Duration,
    /// Frame-rate log to stderr, when `KEYRIG_FRAME_LOG` is set.
    frame_log: Option<FrameLog>,
}

/// Counts viewport frames and prints the frame rate every two seconds (`KEYRIG_FRAME_LOG=1`),
/// to measure the running editor from outside (docs/benchmarks.md, "Editor").
struct FrameLog {
    since: std::time::Instant,
    frames: u32,
}

impl FrameLog {
    const PERIOD_S: f64 = 2.0;

    fn from_env() -> Option<Self> {
        std::env::var_os("KEYRIG_FRAME_LOG").map(|_| FrameLog { since: std::time::Instant::now(), frames: 0 })
    }

    fn tick(&mut self, size_px: [u32; 2], samples: u32) {
        self.frames += 1;
        let elapsed = self.since.elapsed().as_secs_f64();
        if elapsed >= Self::PERIOD_S {
            eprintln!(
                "keyrig frames: {} in {elapsed:.2} s = {:.1} fps ({:.1} ms/frame), viewport {}x{} at {samples} sample(s)",
                self.frames,
                f64::from(self.frames) / elapsed,
                elapsed * 1000.0 / f64::from(self.frames),
                size_px[0],
                size_px[1],
            );
            self.frames = 0;
            self.since = std::time::Instant::now();
        }
    }
}

impl GpuView {
    /// Creates the renderer on eframe's device: with 4× MSAA on a GPU, without anti-aliasing
    /// on a CPU rasterizer, where clearing and resolving four samples per pixel cost more than
    /// the whole rest of the viewport (docs/benchmarks.md, "Editor").
    #[must_use]
    pub fn new(render_state: &RenderState) -> Self {
        let samples = if is_cpu(render_state) { 1 } else { keyrig_render::SAMPLE_COUNT };
        let (device, queue) = (&render_state.device, &render_state.queue);
        let renderer = Renderer::with_sample_count(device, queue, FORMAT, samples)
            .unwrap_or_else(|_| Renderer::new(device, queue, FORMAT));
        GpuView {
            render_state: render_state.clone(),
            renderer,
            target: None,
            rig: None,
            ghost_meshes: None,
            last_stats: None,
            last_render_time: std::time::Duration::ZERO,
            frame_log: FrameLog::from_env(),
        }
    }

    /// Whether wgpu runs on a CPU rasterizer (lavapipe, llvmpipe, WARP).
    #[must_use]
    pub fn is_cpu_adapter(&self) -> bool {
        is_cpu(&self.render_state)
    }

    /// Whether the viewport renders with 4× MSAA (otherwise one sample per pixel).
    #[must_use]
    pub fn antialiasing(&self) -> bool {
        self.renderer.sample_count() > 1
    }

    /// Turns 4× MSAA on or off; the next frame rebuilds the draw pipelines and the viewport
    /// texture when this changes anything (the uploaded meshes stay).
    ///
    /// # Errors
    /// The renderer's error (it cannot refuse 1 or 4 samples).
    pub fn set_antialiasing(&mut self, on: bool) -> Result<(), GpuViewError> {
        let samples = if on { keyrig_render::SAMPLE_COUNT } else { 1 };
        Ok(self.renderer.set_sample_count(samples)?)
    }

    /// The adapter's name and backend, for the status bar and benchmarks.
    #[must_use]
    pub fn adapter_name(&self) -> String {
        let info = self.render_state.adapter.get_info();
        format!("{} ({:?})", info.name, info.backend)
    }

    fn ensure_target(&mut self, width: u32, height: u32) -> Result<TextureId, GpuViewError> {
        let samples = self.renderer.sample_count();
        if let Some((viewport, id)) = &self.target {
            if viewport.size() == (width, height) && viewport.sample_count() == samples {
                return Ok(*id);
            }
        }
        let device = &self.render_state.device;
        let viewport = Viewport::with_sample_count(device, width, height, FORMAT, samples)?;
        let mut egui_renderer = self.render_state.renderer.write();
        let id = match &self.target {
            Some((_, id)) => {
                egui_renderer.update_egui_texture_from_wgpu_texture(
                    device,
                    viewport.encoded_color_view(),
                    wgpu::FilterMode::Linear,
                    *id,
                );
                *id
            }
            None => egui_renderer.register_native_texture(
                device,
                viewport.encoded_color_view(),
                wgpu::FilterMode::Linear,
            ),
        };
        drop(egui_renderer);
        self.target = Some((viewport, id));
        Ok(id)
    }

    /// Whether the next [`GpuView::render`] for `rig_key` rebuilds the scene rig (and so reads
    /// [`GpuFrame::morph_meshes`]).
    #[must_use]
    pub fn needs_rig(&self, rig_key: (u64, u64, u64)) -> bool {
        self.rig.as_ref().is_none_or(|(key, _)| *key != rig_key)
    }

    /// Renders the frame into a texture of `size_px` pixels and returns its egui texture id.
    pub fn render(&mut self, frame: GpuFrame<'_>, size_px: [u32; 2]) -> Result<TextureId, GpuViewError> {
        let started = std::time::Instant::now();
        let result = self.render_inner(frame, size_px);
        self.last_render_time = started.elapsed();
        result
    }

    fn render_inner(&mut self, frame: GpuFrame<'_>, size_px: [u32; 2]) -> Result<TextureId, GpuViewError> {
        let texture = self.ensure_target(size_px[0].max(1), size_px[1].max(1))?;
        if self.needs_rig(frame.rig_key) {
            let rig = SceneRig::with_evaluator(frame.scene, frame.evaluator, &frame.morph_meshes)
                .with_materials(&frame.materials);
            // Only the meshes the edit rebuilt go to the GPU again.
            let previous = self.rig.take().map(|(_, rig)| rig);
            rig.upload_changed(&mut self.renderer, previous.as_ref())?;
            self.rig = Some((frame.rig_key, rig));
            self.ghost_meshes = None;
        }
        let Some((_, rig)) = &self.rig else { return Err(GpuViewError::NoScene) };
        let mut input = rig.frame_from_state(frame.state, &frame.view)?;
        if let Some(&(object, _, _)) = frame.ghosts.first() {
            // Each ghost needs mesh buffers of its own; uploaded once per rig and object.
            let count = frame.ghosts.len();
            if !self.ghost_meshes.is_some_and(|(o, n)| o == object && n >= count) {
                rig.upload_ghosts(&mut self.renderer, object, count)?;
                self.ghost_meshes = Some((object, count));
            }
            for (g, (o, state, ghost)) in frame.ghosts.iter().enumerate() {
                input.items.extend(rig.ghost_items(*o, g, state, &frame.view, *ghost)?);
            }
        }
        if frame.view.motion_path {
            if let Some(path) = rig.motion_path(frame.view.selection, frame.state.time, frame.overrides)? {
                input.motion_paths.push(path);
            }
        }
        if frame.view.cameras {
            input.camera_gizmos = rig.camera_gizmos(&frame.view, frame.state);
        }
        let Some((viewport, _)) = &self.target else { return Err(GpuViewError::NoTarget) };
        self.last_stats = Some(self.renderer.render(&input, viewport)?);
        if let Some(log) = &mut self.frame_log {
            log.tick(size_px, self.renderer.sample_count());
        }
        Ok(texture)
    }
}

/// Whether the adapter eframe will pick (wgpu's preferred one for eframe's default backends and
/// power preference, the same request eframe makes) is a CPU rasterizer such as lavapipe. Asked
/// before the window opens, because the present mode must be chosen then: on a CPU rasterizer
/// the editor presents without waiting for vsync (docs/benchmarks.md, "Editor"). Opens a
/// throw-away wgpu instance; false when there is no adapter at all.
#[must_use]
pub fn default_adapter_is_cpu() -> bool {
    let setup = egui_wgpu::WgpuSetupCreateNew::without_display_handle();
    let power_preference = setup.power_preference;
    let instance = pollster::block_on(egui_wgpu::WgpuSetup::CreateNew(setup).new_instance());
    pollster::block_on(instance.request_adapter(&wgpu::RequestAdapterOptions {
        power_preference,
        force_fallback_adapter: false,
        compatible_surface: None,
    }))
    .is_ok_and(|adapter| adapter.get_info().device_type == wgpu::DeviceType::Cpu)
}

fn is_cpu(render_state: &RenderState) -> bool {
    render_state.adapter.get_info().device_type == wgpu::DeviceType::Cpu
}
