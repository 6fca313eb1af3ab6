//! The viewport drawn by keyrig-render on eframe's wgpu device: GPU skinning with the object's
//! deformer, lights, grid, skeletons and the selection's motion path, rendered into an
//! offscreen texture that the viewport panel copies into egui's render pass with a paint
//! callback of its own ([`ViewportImage`]: one unblended triangle, far cheaper on a CPU
//! rasterizer than egui's textured-mesh shader; docs/rendering.md, "Embedding in the editor"). The editor's scene evaluator (with pose overrides) provides the
//! state of the frame; the [`SceneRig`] shares that evaluator and is rebuilt, with its vertex
//! buffers uploaded, only when the evaluator is (the document or its loaded meshes changed).
//! A frame uploads joint palettes, morph frames and uniforms only.
//!
//! Without a wgpu render state (the UI tests, or a failure here) the viewport panel falls back
//! to drawing the CPU-skinned mesh with egui's painter.

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

/// The pipeline that copies the viewport's image into egui's render pass
/// (`shaders/viewport_blit.wgsl`), for the window's format.
struct Blit {
    pipeline: wgpu::RenderPipeline,
    /// The image blended over what lies beneath (premultiplied alpha), for a viewport that shows
    /// the reference image behind the scene.
    over: wgpu::RenderPipeline,
    layout: wgpu::BindGroupLayout,
    /// Pixel for pixel (the image has the rect's size in pixels) and scaled up.
    samplers: [wgpu::Sampler; 2],
    /// The window's format decodes sRGB on write: sample the image's sRGB view (linear
    /// values), otherwise its encoded view (the stored values), so the copy is exact either way.
    srgb_target: bool,
}

impl Blit {
    fn new(device: &wgpu::Device, target: wgpu::TextureFormat, depth: Option<wgpu::TextureFormat>) -> Self {
        let module = device.create_shader_module(wgpu::include_wgsl!("shaders/viewport_blit.wgsl"));
        let layout = keyrig_render::sampled_texture_layout(device, "viewport blit");
        let pipeline = callback_pipeline(device, &module, (target, depth), "fs_blit", Some(&layout), None);
        let premultiplied = Some(wgpu::BlendState::PREMULTIPLIED_ALPHA_BLENDING);
        let over =
            callback_pipeline(device, &module, (target, depth), "fs_blit_over", Some(&layout), premultiplied);
        let sampler = |filter: wgpu::FilterMode| {
            device.create_sampler(&wgpu::SamplerDescriptor {
                label: Some("viewport blit"),
                mag_filter: filter,
                min_filter: filter,
                ..wgpu::SamplerDescriptor::default()
            })
        };
        Blit {
            pipeline,
            over,
            layout,
            samplers: [sampler(wgpu::FilterMode::Nearest), sampler(wgpu::FilterMode::Linear)],
            srgb_target: target.is_srgb(),
        }
    }

    /// The bind groups that read `viewport`'s image: pixel for pixel, scaled.
    fn bind_groups(&self, device: &wgpu::Device, viewport: &Viewport) -> [wgpu::BindGroup; 2] {
        let view = if self.srgb_target { viewport.color_view() } else { viewport.encoded_color_view() };
        self.samplers.clone().map(|sampler| {
            device.create_bind_group(&wgpu::BindGroupDescriptor {
                label: Some("viewport blit"),
                layout: &self.layout,
                entries: &[
                    wgpu::BindGroupEntry { binding: 0, resource: wgpu::BindingResource::TextureView(view) },
                    wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&sampler) },
                ],
            })
        })
    }
}

/// The pipeline of [`FlatFill`]: a triangle over the callback's rect whose fragments (all
/// ones) are multiplied by the render pass's blend constant (source factor: the constant,
/// destination: zero), so the fragment shader reads nothing. Kept in egui-wgpu's callback resources.
pub struct FlatFillPipeline {
    pipeline: wgpu::RenderPipeline,
    srgb_target: bool,
}

impl FlatFillPipeline {
    fn new(device: &wgpu::Device, target: wgpu::TextureFormat, depth: Option<wgpu::TextureFormat>) -> Self {
        let module = device.create_shader_module(wgpu::include_wgsl!("shaders/viewport_blit.wgsl"));
        let constant = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::Constant,
            dst_factor: wgpu::BlendFactor::Zero,
            operation: wgpu::BlendOperation::Add,
        };
        let blend = wgpu::BlendState { color: constant, alpha: constant };
        let pipeline = callback_pipeline(device, &module, (target, depth), "fs_flat_fill", None, Some(blend));
        FlatFillPipeline { pipeline, srgb_target: target.is_srgb() }
    }
}

/// A pipeline of `shaders/viewport_blit.wgsl` for a paint callback in egui's render pass: one
/// triangle over the callback's rect (`vs_blit`), fragment entry `fs`, one sample; depth
/// neither tested nor written, in a pass with a depth attachment of format `depth`.
fn callback_pipeline(
    device: &wgpu::Device,
    module: &wgpu::ShaderModule,
    (target, depth): (wgpu::TextureFormat, Option<wgpu::TextureFormat>),
    fs: &str,
    bind_group: Option<&wgpu::BindGroupLayout>,
    blend: Option<wgpu::BlendState>,
) -> wgpu::RenderPipeline {
    let layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
        label: Some(fs),
        bind_group_layouts: &bind_group.map_or(Vec::new(), |l| vec![Some(l)]),
        immediate_size: 0,
    });
    device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
        label: Some(fs),
        layout: Some(&layout),
        vertex: wgpu::VertexState {
            module,
            entry_point: Some("vs_blit"),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            buffers: &[],
        },
        fragment: Some(wgpu::FragmentState {
            module,
            entry_point: Some(fs),
            compilation_options: wgpu::PipelineCompilationOptions::default(),
            targets: &[Some(wgpu::ColorTargetState {
                format: target,
                blend,
                write_mask: wgpu::ColorWrites::ALL,
            })],
        }),
        primitive: wgpu::PrimitiveState::default(),
        depth_stencil: depth.map(|format| wgpu::DepthStencilState {
            format,
            depth_write_enabled: Some(false),
            depth_compare: Some(wgpu::CompareFunction::Always),
            stencil: wgpu::StencilState::default(),
            bias: wgpu::DepthBiasState::default(),
        }),
        multisample: wgpu::MultisampleState::default(),
        multiview_mask: None,
        cache: None,
    })
}

/// An opaque colour filled over a paint callback's rect ([`crate::widgets::flat_fill`]).
pub struct FlatFill(pub egui::Color32);

impl egui_wgpu::CallbackTrait for FlatFill {
    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        render_pass: &mut wgpu::RenderPass<'static>,
        resources: &egui_wgpu::CallbackResources,
    ) {
        let Some(fill) = resources.get::<FlatFillPipeline>() else { return };
        // The constant is written as is to a plain target, encoded to sRGB by an sRGB one.
        let [r, g, b, a] = if fill.srgb_target {
            egui::Rgba::from(self.0).to_array()
        } else {
            self.0.to_normalized_gamma_f32()
        };
        render_pass.set_pipeline(&fill.pipeline);
        render_pass.set_blend_constant(wgpu::Color { r: r.into(), g: g.into(), b: b.into(), a: a.into() });
        render_pass.draw(0..3, 0..1);
    }
}

/// The viewport in egui's render pass, drawn by a paint callback over the viewport's rect
/// ([`ViewportImage::paint_callback`]): the offscreen image copied in, or the frame's draws
/// (background first) recorded straight into the pass.
#[derive(Clone)]
pub enum ViewportImage {
    Copy { pipeline: wgpu::RenderPipeline, bind_group: wgpu::BindGroup },
    Direct(keyrig_render::FrameDraws),
}

impl ViewportImage {
    /// The egui shape that paints the viewport into `rect`.
    #[must_use]
    pub fn paint_callback(self, rect: egui::Rect) -> egui::PaintCallback {
        egui_wgpu::Callback::new_paint_callback(rect, self)
    }
}

impl egui_wgpu::CallbackTrait for ViewportImage {
    fn paint(
        &self,
        _info: egui::PaintCallbackInfo,
        render_pass: &mut wgpu::RenderPass<'static>,
        _resources: &egui_wgpu::CallbackResources,
    ) {
        match self {
            ViewportImage::Copy { pipeline, bind_group } => {
                render_pass.set_pipeline(pipeline);
                render_pass.set_bind_group(0, bind_group, &[]);
                render_pass.draw(0..3, 0..1);
            }
            ViewportImage::Direct(draws) => draws.record(render_pass),
        }
    }
}

/// The depth buffer eframe gives egui's render pass in the window on a CPU rasterizer, so that
/// the viewport can be drawn straight into it ([`GpuView::new`]): 32 bits, keyrig-render's
/// [`keyrig_render::DEPTH_FORMAT`].
pub const WINDOW_DEPTH_BITS: u8 = 32;

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
    /// The scene is drawn over a picture egui painted beneath (the reference image): the image
    /// is cleared to transparent and blended over it.
    pub see_through: bool,
}

/// keyrig-render's renderer and offscreen viewport on the editor's device.
pub struct GpuView {
    render_state: RenderState,
    renderer: Renderer,
    /// The offscreen image and the blit's bind groups reading it.
    target: Option<(Viewport, [wgpu::BindGroup; 2])>,
    blit: Blit,
    /// Samples per pixel the viewport is drawn with (4× MSAA or 1).
    samples: u32,
    /// The depth format of egui's render pass in the window, when it has a depth attachment:
    /// then a viewport at one sample per pixel, shown pixel for pixel, is drawn straight into
    /// that pass instead of into the offscreen image and copied (docs/rendering.md,
    /// "Embedding in the editor").
    window_depth: Option<wgpu::TextureFormat>,
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
    /// the whole rest of the viewport (docs/benchmarks.md, "Editor"). `window_depth` is the
    /// depth format of egui's render pass ([`WINDOW_DEPTH_BITS`]), `None` when it has none.
    #[must_use]
    pub fn new(render_state: &RenderState, window_depth: Option<wgpu::TextureFormat>) -> Self {
        let target = render_state.target_format;
        let fills = FlatFillPipeline::new(&render_state.device, target, window_depth);
        render_state.renderer.write().callback_resources.insert(fills);
        let samples = if is_cpu(render_state) { 1 } else { keyrig_render::SAMPLE_COUNT };
        let (device, queue) = (&render_state.device, &render_state.queue);
        let renderer = Renderer::with_sample_count(device, queue, FORMAT, samples)
            .unwrap_or_else(|_| Renderer::new(device, queue, FORMAT));
        GpuView {
            render_state: render_state.clone(),
            blit: Blit::new(device, target, window_depth),
            samples: renderer.sample_count(),
            window_depth,
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
        self.samples > 1
    }

    /// Turns 4× MSAA on or off; the next frame rebuilds the draw pipelines and the viewport
    /// texture when this changes anything (the uploaded meshes stay).
    ///
    /// # Errors
    /// None today: 1 and 4 samples are both supported (the renderer's error type is kept for
    /// the next frame's rebuild).
    pub fn set_antialiasing(&mut self, on: bool) -> Result<(), GpuViewError> {
        self.samples = if on { keyrig_render::SAMPLE_COUNT } else { 1 };
        Ok(())
    }

    /// The adapter's name and backend, for the status bar and benchmarks.
    #[must_use]
    pub fn adapter_name(&self) -> String {
        let info = self.render_state.adapter.get_info();
        format!("{} ({:?})", info.name, info.backend)
    }

    fn ensure_target(&mut self, width: u32, height: u32) -> Result<(), GpuViewError> {
        let samples = self.samples;
        if let Some((viewport, _)) = &self.target {
            if viewport.size() == (width, height) && viewport.sample_count() == samples {
                return Ok(());
            }
        }
        let device = &self.render_state.device;
        let viewport = Viewport::with_sample_count(device, width, height, FORMAT, samples)?;
        let bind_groups = self.blit.bind_groups(device, &viewport);
        self.target = Some((viewport, bind_groups));
        Ok(())
    }

    /// Whether the next [`GpuView::render`] for `rig_key` rebuilds the scene rig (and so reads
    /// [`GpuFrame::morph_meshes`]).
    #[must_use]
    pub fn needs_rig(&self, rig_key: (u64, u64, u64)) -> bool {
        self.rig.as_ref().is_none_or(|(key, _)| *key != rig_key)
    }

    /// Renders the frame for a viewport of `size_px` pixels and returns what paints it;
    /// `one_to_one` when it is shown pixel for pixel. Drawn straight into egui's pass when the
    /// window has a depth attachment, the viewport one sample per pixel and shown pixel for
    /// pixel (the draws are recorded there); otherwise rendered into the offscreen texture
    /// and copied in, sampled without filtering when `one_to_one`, else scaled up bilinearly.
    pub fn render(
        &mut self,
        frame: GpuFrame<'_>,
        size_px: [u32; 2],
        one_to_one: bool,
    ) -> Result<ViewportImage, GpuViewError> {
        let started = std::time::Instant::now();
        // The reference image lies beneath: the scene is rendered over transparency and blended
        // over it by the copy, not drawn straight into the pass.
        let direct = self.window_depth == Some(keyrig_render::DEPTH_FORMAT)
            && self.samples == 1
            && one_to_one
            && !frame.see_through;
        let result = self.render_inner(frame, [size_px[0].max(1), size_px[1].max(1)], direct, one_to_one);
        self.last_render_time = started.elapsed();
        if let Some(log) = &mut self.frame_log {
            log.tick(size_px, self.samples);
        }
        result
    }

    fn render_inner(
        &mut self,
        frame: GpuFrame<'_>,
        size_px: [u32; 2],
        direct: bool,
        one_to_one: bool,
    ) -> Result<ViewportImage, GpuViewError> {
        let format = if direct { self.render_state.target_format } else { FORMAT };
        self.renderer.set_target(format, self.samples)?;
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
        input.transparent_background = frame.see_through;
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
        if direct {
            // The offscreen image is not used while drawing straight into egui's pass.
            self.target = None;
            let (draws, stats) = self.renderer.prepare(&input, (size_px[0], size_px[1]))?;
            self.last_stats = Some(stats);
            return Ok(ViewportImage::Direct(draws));
        }
        self.ensure_target(size_px[0], size_px[1])?;
        let Some((viewport, bind_groups)) = &self.target else { return Err(GpuViewError::NoTarget) };
        self.last_stats = Some(self.renderer.render(&input, viewport)?);
        // Pixel for pixel without filtering, else scaled up bilinearly; blended over the
        // reference image when one lies beneath.
        let bind_group = bind_groups[usize::from(!one_to_one)].clone();
        let pipeline = if frame.see_through { &self.blit.over } else { &self.blit.pipeline };
        Ok(ViewportImage::Copy { pipeline: pipeline.clone(), bind_group })
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
