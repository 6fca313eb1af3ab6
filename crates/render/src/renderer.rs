//! The renderer: meshes uploaded once, then per frame a compute pass per deformed mesh and a
//! render pass into a [`Viewport`] (an offscreen colour + depth target, 4× MSAA by default, or
//! one sample per pixel where anti-aliasing costs too much, e.g. on a CPU rasterizer).
//!
//! The same code runs headless ([`crate::HeadlessRenderer`], its own device) and inside the
//! editor (eframe's device and queue, the viewport's colour texture shown as an egui image).

use std::collections::HashMap;
use std::sync::Arc;

use bytemuck::{Pod, Zeroable};
use glam::{Mat4, Vec2, Vec3};
use keyrig_core::{Camera, DeformerKind, LightKind, TextureImage};
use keyrig_skin::MeshBindings;

use crate::camera;
use crate::gpu::with_error_scope;
use crate::overlay::{self, CameraGizmo, LightGizmo, LineVertex, Lines, MotionPath, SkeletonOverlay};
use crate::skinning::{GpuSkinner, JointPose, MorphBuffers, SkinBuffers, SkinMeshInput, SkinnedVertex};
use crate::RenderError;

/// Identifies an uploaded mesh; chosen by the caller (e.g. the scene object's index).
pub type MeshId = u64;

/// Depth buffer format of every viewport.
pub const DEPTH_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Depth32Float;
/// Samples per pixel of [`Renderer::new`] and [`Viewport::new`], so of every headless image
/// (4 is supported by every WebGPU adapter for the formats used here).
pub const SAMPLE_COUNT: u32 = 4;
/// The sample counts [`Renderer::with_sample_count`] and [`Viewport::with_sample_count`]
/// accept: 1 (no anti-aliasing) and 4, the two that every WebGPU adapter supports for the
/// colour and depth formats used here (2 and 8 depend on the adapter).
pub const SUPPORTED_SAMPLE_COUNTS: [u32; 2] = [1, 4];
/// Most lights a frame can use; further lights are ignored (and counted in [`FrameStats`]).
pub const MAX_LIGHTS: usize = 8;
/// Stride of the per-object uniforms (the largest `min_uniform_buffer_offset_alignment`).
const OBJECT_STRIDE: u64 = 256;
/// Format of every mesh texture: RGBA8 holding sRGB-encoded colour (as PNG and JPEG store
/// it), so that sampling returns linear colour for the lighting.
pub const TEXTURE_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// Mesh data to upload.
#[derive(Clone, Copy, Debug)]
pub enum MeshData<'a> {
    /// A mesh that does not deform (positions and normals as drawn).
    Static { vertices: &'a [SkinnedVertex], indices: &'a [u32] },
    /// A skinned mesh, deformed each frame by a compute pass.
    Skinned { skin: SkinMeshInput<'a>, indices: &'a [u32] },
    /// A vertex-animated (MD2) mesh: all frames, interpolated each frame by a compute pass.
    Morph { frames: &'a [Vec<SkinnedVertex>], indices: &'a [u32] },
}

/// How meshes are drawn (seed text 002's render styles). Textures are a separate switch
/// ([`FrameInput::textures`]): they apply to the solid style.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum RenderStyle {
    /// Lit, filled surfaces (textured when textures are on).
    #[default]
    Solid,
    /// Triangle edges only.
    Wireframe,
    /// Vertices only.
    Points,
}

impl RenderStyle {
    pub const ALL: [RenderStyle; 3] = [RenderStyle::Solid, RenderStyle::Wireframe, RenderStyle::Points];

    /// `Solid`, `Wireframe`, `Points`: the editor's menu labels.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            RenderStyle::Solid => "Solid",
            RenderStyle::Wireframe => "Wireframe",
            RenderStyle::Points => "Points",
        }
    }

    /// `solid`, `wireframe`, `points`.
    #[must_use]
    pub fn cli_name(self) -> &'static str {
        match self {
            RenderStyle::Solid => "solid",
            RenderStyle::Wireframe => "wireframe",
            RenderStyle::Points => "points",
        }
    }

    #[must_use]
    pub fn from_cli_name(name: &str) -> Option<Self> {
        RenderStyle::ALL.into_iter().find(|s| s.cli_name() == name)
    }
}

/// How a mesh is deformed this frame.
#[derive(Clone, Debug, PartialEq)]
pub enum Deform {
    /// Drawn as uploaded (static meshes; skinned/morph meshes keep their last output).
    None,
    /// Skin with `deformer` and one [`JointPose`] per joint. `bindings`: the bones-blending
    /// bindings of a keyed blend zone at this frame (keyrig-eval's `ObjectState::zone_bindings`),
    /// written over the uploaded ones when they are other bindings than the mesh holds (compared
    /// by identity); `None` puts the uploaded ones back. `morph`: the rest positions and normals
    /// morphed by the frame's morph-target weights (glTF targets; keyrig-skin's
    /// `SkinnedMesh::morphed`), one per vertex, written over the uploaded ones likewise before
    /// skinning; `None` while no target weighs.
    Skin {
        deformer: DeformerKind,
        joints: Vec<JointPose>,
        bindings: Option<Arc<MeshBindings>>,
        morph: Option<Arc<[SkinnedVertex]>>,
    },
    /// Interpolate morph frames `frame_a` → `frame_b` by `t` in 0..=1.
    Morph { frame_a: u32, frame_b: u32, t: f32 },
}

/// One mesh drawn in a frame.
#[derive(Clone, Debug, PartialEq)]
pub struct DrawItem {
    pub mesh: MeshId,
    /// Object transform: world space from the mesh's model space.
    pub world_from_model: Mat4,
    pub deform: Deform,
    /// Linear RGB albedo.
    pub colour: Vec3,
    /// 1 opaque; below 1 the item is blended over the opaque ones (alpha blending, drawn after
    /// them without writing depth).
    pub opacity: f32,
    pub selected: bool,
    /// Drawn as a translucent, tinted ghost (onion skinning) after the opaque items.
    pub ghost: Option<Ghost>,
}

/// How a ghost (another frame's pose, for onion skinning) is drawn: its shaded colour mixed
/// half-way towards `tint`, with `opacity` (0–1) over what lies behind it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Ghost {
    /// Linear RGB.
    pub tint: Vec3,
    pub opacity: f32,
}

/// A light's values at the frame's time (world space).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightInput {
    pub kind: LightKind,
    pub position: Vec3,
    /// The direction the light shines in (need not be unit).
    pub direction: Vec3,
    /// Linear RGB.
    pub colour: Vec3,
    /// Distance beyond which the light has no effect, with glTF's smooth falloff
    /// `clamp(1 − (d/range)⁴, 0, 1)` on top of 1/d² (`KHR_lights_punctual`); `None`: unlimited.
    pub range: Option<f32>,
    pub intensity: f32,
}

/// Everything one frame needs; built by [`crate::scene_frame`] from a scene, or by hand.
#[derive(Clone, Debug, PartialEq)]
pub struct FrameInput {
    pub camera: Camera,
    /// Near and far planes (view-space distances); `None`: from the orbit distance.
    pub depth_range: Option<[f32; 2]>,
    pub style: RenderStyle,
    /// Linear RGB ambient light.
    pub ambient: Vec3,
    pub lights: Vec<LightInput>,
    pub items: Vec<DrawItem>,
    /// Ground grid on y = 0 with this spacing (world units); `None` hides it.
    pub grid_spacing: Option<f32>,
    pub skeletons: Vec<SkeletonOverlay>,
    pub motion_paths: Vec<MotionPath>,
    /// Lights drawn as gizmos (position, direction, cone).
    pub light_gizmos: Vec<LightGizmo>,
    /// Scene cameras drawn as frustums.
    pub camera_gizmos: Vec<CameraGizmo>,
    /// Look through this scene camera instead of [`FrameInput::camera`] (whose orbit
    /// distance still sizes the overlays).
    pub through: Option<keyrig_eval::CameraState>,
    /// Linear RGB background.
    pub background: Vec3,
    /// Clear to transparent black instead of `background`: the image is premultiplied RGBA,
    /// opaque where something was drawn, for a caller that composites it over a picture of its
    /// own (the editor's reference image).
    pub transparent_background: bool,
    /// Multiply each mesh's colour by its texture ([`Renderer::set_texture`]) in the solid
    /// style; `false` draws every mesh in its plain colour.
    pub textures: bool,
}

impl FrameInput {
    /// An empty frame seen by `camera`: solid style, default grid, dark background.
    #[must_use]
    pub fn new(camera: Camera) -> Self {
        FrameInput {
            camera,
            depth_range: None,
            style: RenderStyle::Solid,
            ambient: Vec3::splat(0.1),
            lights: Vec::new(),
            items: Vec::new(),
            grid_spacing: Some(overlay::grid_spacing_for(camera.distance)),
            skeletons: Vec::new(),
            motion_paths: Vec::new(),
            light_gizmos: Vec::new(),
            camera_gizmos: Vec::new(),
            through: None,
            background: Vec3::new(0.018, 0.02, 0.025),
            transparent_background: false,
            textures: true,
        }
    }
}

/// What a frame cost: bytes written to the GPU and work done.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FrameStats {
    /// Joint data of skinned meshes (240 bytes per joint per skinned mesh).
    pub joint_bytes: u64,
    /// Morph parameters (16 bytes per morphing mesh).
    pub morph_bytes: u64,
    /// Camera, lights and per-object uniforms.
    pub uniform_bytes: u64,
    /// Overlay line vertices (grid, skeletons, motion paths).
    pub overlay_bytes: u64,
    /// Vertices run through a compute pass.
    pub deformed_vertices: u64,
    pub draw_calls: u32,
    /// Lights beyond [`MAX_LIGHTS`] that were not used.
    pub lights_dropped: u32,
}

impl FrameStats {
    /// Every byte written to the GPU this frame.
    #[must_use]
    pub fn bytes_uploaded(&self) -> u64 {
        self.joint_bytes + self.morph_bytes + self.uniform_bytes + self.overlay_bytes
    }

    /// Adds `other`'s counts to these (the frames of a motion-blurred image); dropped lights
    /// keep the largest count.
    pub fn add(&mut self, other: &FrameStats) {
        self.joint_bytes += other.joint_bytes;
        self.morph_bytes += other.morph_bytes;
        self.uniform_bytes += other.uniform_bytes;
        self.overlay_bytes += other.overlay_bytes;
        self.deformed_vertices += other.deformed_vertices;
        self.draw_calls += other.draw_calls;
        self.lights_dropped = self.lights_dropped.max(other.lights_dropped);
    }
}

/// An offscreen render target: colour + depth, with MSAA resolved into a single-sample colour
/// texture (or, at one sample per pixel, drawn into it directly) that can be read back or shown
/// as an egui texture.
pub struct Viewport {
    width: u32,
    height: u32,
    format: wgpu::TextureFormat,
    samples: u32,
    /// The multisampled colour target; `None` at one sample per pixel.
    msaa_view: Option<wgpu::TextureView>,
    depth_view: wgpu::TextureView,
    resolved: wgpu::Texture,
    resolved_view: wgpu::TextureView,
    /// `resolved` viewed without sRGB decoding (same bytes), for egui.
    encoded_view: wgpu::TextureView,
}

impl Viewport {
    /// Creates the textures with [`SAMPLE_COUNT`] samples per pixel. The resolved colour
    /// texture has `TEXTURE_BINDING | COPY_SRC` usage so the editor can sample it and headless
    /// rendering can read it back.
    ///
    /// # Errors
    /// [`RenderError::InvalidSize`] for a zero size or one beyond the device's limit.
    pub fn new(
        device: &wgpu::Device,
        width: u32,
        height: u32,
        format: wgpu::TextureFormat,
    ) -> Result<Self, RenderError> {
        Self::with_sample_count(device, width, height, format, SAMPLE_COUNT)
    }

    /// Like [`Viewport::new`] with `samples` per pixel (one of [`SUPPORTED_SAMPLE_COUNTS`]); it
    /// must match the sample count of the [`Renderer`] that draws into it.
    ///
    /// # Errors
    /// [`RenderError::InvalidSize`] as for [`Viewport::new`];
    /// [`RenderError::UnsupportedSampleCount`] for another sample count.
    pub fn with_sample_count(
        device: &wgpu::Device,
        width: u32,
        height: u32,
        format: wgpu::TextureFormat,
        samples: u32,
    ) -> Result<Self, RenderError> {
        check_sample_count(samples)?;
        let max = device.limits().max_texture_dimension_2d;
        if width == 0 || height == 0 {
            return Err(RenderError::InvalidSize {
                width,
                height,
                reason: "width and height must be at least 1".into(),
            });
        }
        if width > max || height > max {
            return Err(RenderError::InvalidSize {
                width,
                height,
                reason: format!("the GPU allows at most {max} pixels per side"),
            });
        }
        let size = wgpu::Extent3d { width, height, depth_or_array_layers: 1 };
        // The colour texture can also be viewed without the sRGB decode, for egui (below).
        let plain_format = format.remove_srgb_suffix();
        let texture = |label, format, samples, usage, view_formats: &[wgpu::TextureFormat]| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size,
                mip_level_count: 1,
                sample_count: samples,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats,
            })
        };
        let msaa = (samples > 1).then(|| {
            texture("keyrig viewport msaa", format, samples, wgpu::TextureUsages::RENDER_ATTACHMENT, &[])
                .create_view(&Default::default())
        });
        let depth = texture(
            "keyrig viewport depth",
            DEPTH_FORMAT,
            samples,
            wgpu::TextureUsages::RENDER_ATTACHMENT,
            &[],
        );
        let resolved = texture(
            "keyrig viewport colour",
            format,
            1,
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
            if plain_format == format { &[] } else { std::slice::from_ref(&plain_format) },
        );
        let encoded_view = resolved.create_view(&wgpu::TextureViewDescriptor {
            label: Some("keyrig viewport colour (sRGB-encoded)"),
            format: Some(plain_format),
            ..Default::default()
        });
        Ok(Viewport {
            width,
            height,
            format,
            samples,
            msaa_view: msaa,
            depth_view: depth.create_view(&Default::default()),
            resolved_view: resolved.create_view(&Default::default()),
            encoded_view,
            resolved,
        })
    }

    #[must_use]
    pub fn size(&self) -> (u32, u32) {
        (self.width, self.height)
    }

    #[must_use]
    pub fn format(&self) -> wgpu::TextureFormat {
        self.format
    }

    /// Samples per pixel (1 or 4).
    #[must_use]
    pub fn sample_count(&self) -> u32 {
        self.samples
    }

    /// The finished image (after [`Renderer::render`]) in the viewport's format: sampling an
    /// sRGB format through it returns linear colour.
    #[must_use]
    pub fn color_view(&self) -> &wgpu::TextureView {
        &self.resolved_view
    }

    /// The finished image viewed without the sRGB suffix (`Rgba8Unorm` for `Rgba8UnormSrgb`):
    /// sampling returns the stored sRGB-encoded values. Register this one with egui-wgpu, whose
    /// shader expects gamma-encoded textures (through [`Viewport::color_view`] the image would
    /// be shown linear, far too dark).
    #[must_use]
    pub fn encoded_color_view(&self) -> &wgpu::TextureView {
        &self.encoded_view
    }

    #[must_use]
    pub fn color_texture(&self) -> &wgpu::Texture {
        &self.resolved
    }
}

fn address_mode(mode: keyrig_core::WrapMode) -> wgpu::AddressMode {
    match mode {
        keyrig_core::WrapMode::ClampToEdge => wgpu::AddressMode::ClampToEdge,
        keyrig_core::WrapMode::MirroredRepeat => wgpu::AddressMode::MirrorRepeat,
        keyrig_core::WrapMode::Repeat => wgpu::AddressMode::Repeat,
    }
}

fn filter_mode(mode: keyrig_core::FilterMode) -> wgpu::FilterMode {
    match mode {
        keyrig_core::FilterMode::Nearest => wgpu::FilterMode::Nearest,
        keyrig_core::FilterMode::Linear => wgpu::FilterMode::Linear,
    }
}

/// The mip chain of `image` (level 0 first), each level half the size of the one before
/// (rounded down, at least 1), down to 1×1; only level 0 when `mipmaps` is false. Levels
/// are box-filtered in the stored (sRGB-encoded) values, as most tools make them. Level 0 is
/// scaled down to fit `max_size` per side.
fn mip_chain(image: &TextureImage, mipmaps: bool, max_size: u32) -> Vec<image::RgbaImage> {
    use image::imageops::{resize, FilterType};
    let Some(mut level) = image::RgbaImage::from_raw(image.width(), image.height(), image.rgba().to_vec())
    else {
        return vec![image::RgbaImage::from_pixel(1, 1, image::Rgba([255; 4]))];
    };
    let max_size = max_size.max(1);
    if level.width() > max_size || level.height() > max_size {
        let scale = f64::from(max_size) / f64::from(level.width().max(level.height()));
        let w = ((f64::from(level.width()) * scale) as u32).clamp(1, max_size);
        let h = ((f64::from(level.height()) * scale) as u32).clamp(1, max_size);
        level = resize(&level, w, h, FilterType::Triangle);
    }
    let mut levels = Vec::new();
    loop {
        let (w, h) = level.dimensions();
        let next = (mipmaps && (w > 1 || h > 1))
            .then(|| resize(&level, (w / 2).max(1), (h / 2).max(1), FilterType::Triangle));
        levels.push(level);
        match next {
            Some(n) => level = n,
            None => return levels,
        }
    }
}

/// Uploads `image` (with its mip chain when its sampler filters between mips) and makes the
/// bind group of the draw shader's group 2: the texture and its sampler.
fn texture_bind_group(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    layout: &wgpu::BindGroupLayout,
    image: &TextureImage,
) -> wgpu::BindGroup {
    let sampler_info = image.sampler;
    let levels =
        mip_chain(image, sampler_info.mipmap_filter.is_some(), device.limits().max_texture_dimension_2d);
    let size =
        wgpu::Extent3d { width: levels[0].width(), height: levels[0].height(), depth_or_array_layers: 1 };
    let texture = device.create_texture(&wgpu::TextureDescriptor {
        label: Some("keyrig base-colour texture"),
        size,
        mip_level_count: levels.len() as u32,
        sample_count: 1,
        dimension: wgpu::TextureDimension::D2,
        format: TEXTURE_FORMAT,
        usage: wgpu::TextureUsages::TEXTURE_BINDING | wgpu::TextureUsages::COPY_DST,
        view_formats: &[],
    });
    for (mip, level) in levels.iter().enumerate() {
        queue.write_texture(
            wgpu::TexelCopyTextureInfo {
                texture: &texture,
                mip_level: mip as u32,
                origin: wgpu::Origin3d::ZERO,
                aspect: wgpu::TextureAspect::All,
            },
            level.as_raw(),
            wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(4 * level.width()),
                rows_per_image: Some(level.height()),
            },
            wgpu::Extent3d { width: level.width(), height: level.height(), depth_or_array_layers: 1 },
        );
    }
    let sampler = device.create_sampler(&wgpu::SamplerDescriptor {
        label: Some("keyrig base-colour sampler"),
        address_mode_u: address_mode(sampler_info.wrap_u),
        address_mode_v: address_mode(sampler_info.wrap_v),
        address_mode_w: wgpu::AddressMode::ClampToEdge,
        mag_filter: filter_mode(sampler_info.mag_filter),
        min_filter: filter_mode(sampler_info.min_filter),
        mipmap_filter: match sampler_info.mipmap_filter {
            Some(keyrig_core::FilterMode::Linear) => wgpu::MipmapFilterMode::Linear,
            Some(keyrig_core::FilterMode::Nearest) | None => wgpu::MipmapFilterMode::Nearest,
        },
        ..Default::default()
    });
    device.create_bind_group(&wgpu::BindGroupDescriptor {
        label: Some("keyrig base-colour texture"),
        layout,
        entries: &[
            wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(&texture.create_view(&Default::default())),
            },
            wgpu::BindGroupEntry { binding: 1, resource: wgpu::BindingResource::Sampler(&sampler) },
        ],
    })
}

/// [`RenderError::UnsupportedSampleCount`] unless `samples` is in [`SUPPORTED_SAMPLE_COUNTS`].
fn check_sample_count(samples: u32) -> Result<(), RenderError> {
    if SUPPORTED_SAMPLE_COUNTS.contains(&samples) {
        Ok(())
    } else {
        Err(RenderError::UnsupportedSampleCount(samples))
    }
}

enum Deformation {
    Static(wgpu::Buffer),
    Skinned(SkinBuffers),
    Morph(MorphBuffers),
}

struct GpuMesh {
    deformation: Deformation,
    /// Texture coordinates, one `vec2<f32>` per vertex (zeros for a mesh without any); they
    /// do not deform, so the compute passes never touch them.
    uvs: wgpu::Buffer,
    /// The base-colour texture and its sampler ([`Renderer::set_texture`]).
    texture: Option<wgpu::BindGroup>,
    vertex_count: u32,
    triangles: wgpu::Buffer,
    triangle_index_count: u32,
    edges: wgpu::Buffer,
    edge_index_count: u32,
}

impl GpuMesh {
    fn vertex_buffer(&self) -> &wgpu::Buffer {
        match &self.deformation {
            Deformation::Static(buffer) => buffer,
            Deformation::Skinned(skin) => &skin.output,
            Deformation::Morph(morph) => &morph.output,
        }
    }
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuLight {
    position: [f32; 4],
    direction: [f32; 4],
    radiance: [f32; 4],
    spot: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuGlobals {
    clip_from_world: [[f32; 4]; 4],
    camera_position: [f32; 4],
    ambient: [f32; 4],
    counts: [u32; 4],
    lights: [GpuLight; MAX_LIGHTS],
    /// The background (linear RGB): what the fill of a frame drawn into another pass paints.
    background: [f32; 4],
}

#[repr(C)]
#[derive(Clone, Copy, Pod, Zeroable)]
struct GpuObject {
    world_from_model: [[f32; 4]; 4],
    normal_from_model: [[f32; 4]; 4],
    colour: [f32; 4],
    flags: [f32; 4],
    /// A ghost's tint (rgb) and opacity (w); unused for opaque items.
    tint: [f32; 4],
}

fn gpu_light(light: &LightInput) -> GpuLight {
    let direction = light.direction.normalize_or(Vec3::NEG_Y);
    let (kind, spot) = match light.kind {
        LightKind::Directional => (0.0, [0.0; 4]),
        LightKind::Point => (1.0, [0.0; 4]),
        LightKind::Spot { cutoff_deg, inner_angle_deg, dropoff } => {
            let cutoff = cutoff_deg.clamp(0.0, 180.0);
            let inner = inner_angle_deg.clamp(0.0, cutoff);
            (2.0, [cutoff.to_radians().cos(), inner.to_radians().cos(), dropoff.max(0.0), 0.0])
        }
    };
    let mut spot = spot;
    // w: the range (0 for none); directional lights have none.
    spot[3] = match (light.kind, light.range) {
        (LightKind::Directional, _) | (_, None) => 0.0,
        (_, Some(r)) if r.is_finite() && r > 0.0 => r,
        _ => 0.0,
    };
    GpuLight {
        position: light.position.extend(kind).to_array(),
        direction: direction.extend(0.0).to_array(),
        radiance: (light.colour * light.intensity).extend(1.0).to_array(),
        spot,
    }
}

/// The wgpu renderer. Create once per device; upload meshes; render frames into viewports.
pub struct Renderer {
    device: wgpu::Device,
    queue: wgpu::Queue,
    color_format: wgpu::TextureFormat,
    skinner: GpuSkinner,
    module: wgpu::ShaderModule,
    mesh_layout: wgpu::PipelineLayout,
    line_layout: wgpu::PipelineLayout,
    pipelines: DrawPipelines,
    globals: wgpu::Buffer,
    globals_bind_group: wgpu::BindGroup,
    object_layout: wgpu::BindGroupLayout,
    texture_layout: wgpu::BindGroupLayout,
    /// A 1×1 white texture: what meshes without a texture (or every mesh, with textures off)
    /// sample.
    white_texture: wgpu::BindGroup,
    objects: wgpu::Buffer,
    objects_bind_group: wgpu::BindGroup,
    object_capacity: u64,
    line_buffer: wgpu::Buffer,
    line_capacity: u64,
    meshes: HashMap<MeshId, GpuMesh>,
}

/// The draw pipelines for one sample count.
struct DrawPipelines {
    samples: u32,
    solid: wgpu::RenderPipeline,
    wireframe: wgpu::RenderPipeline,
    points: wgpu::RenderPipeline,
    lines_depth: wgpu::RenderPipeline,
    lines_on_top: wgpu::RenderPipeline,
    /// Translucent ghosts: lit, blended over the scene, depth-tested without writing depth.
    ghost: wgpu::RenderPipeline,
    /// Objects with opacity below 1: lit and textured as opaque ones, blended over the scene,
    /// depth-tested without writing depth.
    translucent: wgpu::RenderPipeline,
    /// `solid` and `translucent` for items drawn without a texture: no texture sample.
    solid_untextured: wgpu::RenderPipeline,
    translucent_untextured: wgpu::RenderPipeline,
    /// `solid` and `solid_untextured` split by facing: every opaque item's front faces are
    /// drawn before any back face, so that a back face hidden behind its own surface (half of
    /// a closed mesh's triangles) is rejected by the depth test before it is shaded. Together
    /// they draw every triangle, as the unculled pipelines do (a surface the deformer folds
    /// keeps its folded faces).
    solid_fronts: wgpu::RenderPipeline,
    solid_backs: wgpu::RenderPipeline,
    solid_untextured_fronts: wgpu::RenderPipeline,
    solid_untextured_backs: wgpu::RenderPipeline,
    /// The background over the whole viewport (colour only: the pass's depth is cleared), for a
    /// frame drawn into a pass that was not cleared for it ([`Renderer::prepare`]).
    fill: wgpu::RenderPipeline,
}

impl DrawPipelines {
    fn new(
        device: &wgpu::Device,
        module: &wgpu::ShaderModule,
        (mesh_layout, line_layout): (&wgpu::PipelineLayout, &wgpu::PipelineLayout),
        color_format: wgpu::TextureFormat,
        samples: u32,
    ) -> Self {
        let two_vec4 = [
            wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x4, offset: 0, shader_location: 0 },
            wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x4, offset: 16, shader_location: 1 },
        ];
        let vertex_layout = wgpu::VertexBufferLayout {
            array_stride: 32,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &two_vec4,
        };
        let uv_attribute =
            [wgpu::VertexAttribute { format: wgpu::VertexFormat::Float32x2, offset: 0, shader_location: 2 }];
        let uv_layout = wgpu::VertexBufferLayout {
            array_stride: 8,
            step_mode: wgpu::VertexStepMode::Vertex,
            attributes: &uv_attribute,
        };
        // Meshes: deformed position and normal (slot 0) and the static texture coordinates
        // (slot 1). Overlay lines: position and colour (slot 0).
        let mesh_buffers = [vertex_layout.clone(), uv_layout];
        // The shaders write linear colour: a target that does not encode sRGB on write gets it
        // encoded by the shaders (`ENCODE_SRGB` in draw.wgsl).
        let encode: &[(&str, f64)] = if color_format.is_srgb() { &[] } else { &[("ENCODE_SRGB", 1.0)] };
        let fragment_options = wgpu::PipelineCompilationOptions { constants: encode, ..Default::default() };
        let pipeline = |label: &str,
                        layout: &wgpu::PipelineLayout,
                        vs: &str,
                        fs: &str,
                        topology: wgpu::PrimitiveTopology,
                        cull_mode: Option<wgpu::Face>,
                        depth_compare: wgpu::CompareFunction,
                        depth_write: bool,
                        blend: Option<wgpu::BlendState>| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(layout),
                vertex: wgpu::VertexState {
                    module,
                    entry_point: Some(vs),
                    compilation_options: Default::default(),
                    buffers: match vs {
                        "vs_mesh" => &mesh_buffers,
                        "vs_fill" => &[],
                        _ => std::slice::from_ref(&vertex_layout),
                    },
                },
                primitive: wgpu::PrimitiveState { topology, cull_mode, ..Default::default() },
                depth_stencil: Some(wgpu::DepthStencilState {
                    format: DEPTH_FORMAT,
                    depth_write_enabled: Some(depth_write),
                    depth_compare: Some(depth_compare),
                    stencil: wgpu::StencilState::default(),
                    bias: wgpu::DepthBiasState::default(),
                }),
                multisample: wgpu::MultisampleState { count: samples, ..Default::default() },
                fragment: Some(wgpu::FragmentState {
                    module,
                    entry_point: Some(fs),
                    compilation_options: fragment_options.clone(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format: color_format,
                        blend,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        use wgpu::CompareFunction::{Always, LessEqual};
        use wgpu::PrimitiveTopology::{LineList, PointList, TriangleList};
        DrawPipelines {
            samples,
            solid: pipeline(
                "keyrig solid",
                mesh_layout,
                "vs_mesh",
                "fs_lit",
                TriangleList,
                None,
                LessEqual,
                true,
                None,
            ),
            wireframe: pipeline(
                "keyrig wireframe",
                mesh_layout,
                "vs_mesh",
                "fs_flat",
                LineList,
                None,
                LessEqual,
                true,
                None,
            ),
            points: pipeline(
                "keyrig points",
                mesh_layout,
                "vs_mesh",
                "fs_flat",
                PointList,
                None,
                LessEqual,
                true,
                None,
            ),
            lines_depth: pipeline(
                "keyrig grid",
                line_layout,
                "vs_line",
                "fs_line",
                LineList,
                None,
                LessEqual,
                false,
                None,
            ),
            lines_on_top: pipeline(
                "keyrig overlays",
                line_layout,
                "vs_line",
                "fs_line",
                LineList,
                None,
                Always,
                false,
                None,
            ),
            ghost: pipeline(
                "keyrig ghosts",
                mesh_layout,
                "vs_mesh",
                "fs_ghost",
                TriangleList,
                None,
                LessEqual,
                false,
                Some(wgpu::BlendState::ALPHA_BLENDING),
            ),
            translucent: pipeline(
                "keyrig translucent objects",
                mesh_layout,
                "vs_mesh",
                "fs_lit",
                TriangleList,
                None,
                LessEqual,
                false,
                Some(wgpu::BlendState::ALPHA_BLENDING),
            ),
            solid_untextured: pipeline(
                "keyrig solid untextured",
                mesh_layout,
                "vs_mesh",
                "fs_lit_untextured",
                TriangleList,
                None,
                LessEqual,
                true,
                None,
            ),
            translucent_untextured: pipeline(
                "keyrig translucent untextured objects",
                mesh_layout,
                "vs_mesh",
                "fs_lit_untextured",
                TriangleList,
                None,
                LessEqual,
                false,
                Some(wgpu::BlendState::ALPHA_BLENDING),
            ),
            solid_fronts: pipeline(
                "keyrig solid, front faces",
                mesh_layout,
                "vs_mesh",
                "fs_lit",
                TriangleList,
                Some(wgpu::Face::Back),
                LessEqual,
                true,
                None,
            ),
            solid_backs: pipeline(
                "keyrig solid, back faces",
                mesh_layout,
                "vs_mesh",
                "fs_lit",
                TriangleList,
                Some(wgpu::Face::Front),
                LessEqual,
                true,
                None,
            ),
            solid_untextured_fronts: pipeline(
                "keyrig solid untextured, front faces",
                mesh_layout,
                "vs_mesh",
                "fs_lit_untextured",
                TriangleList,
                Some(wgpu::Face::Back),
                LessEqual,
                true,
                None,
            ),
            solid_untextured_backs: pipeline(
                "keyrig solid untextured, back faces",
                mesh_layout,
                "vs_mesh",
                "fs_lit_untextured",
                TriangleList,
                Some(wgpu::Face::Front),
                LessEqual,
                true,
                None,
            ),
            fill: pipeline(
                "keyrig background",
                line_layout,
                "vs_fill",
                "fs_fill",
                TriangleList,
                None,
                Always,
                false,
                None,
            ),
        }
    }
}

/// The overlay lines written for a frame ([`Renderer::write_overlay_lines`]): the grid's
/// vertices first, then the skeletons', motion paths' and light gizmos'.
#[derive(Clone, Copy, Debug)]
struct OverlayLines {
    /// The first `grid_vertices` vertices are the grid (drawn depth-tested).
    grid_vertices: u32,
    /// All vertices; those after the grid are drawn on top.
    line_vertices: u64,
}

/// A frame's draws, ready to record into a render pass ([`Renderer::prepare`]): each holds
/// what it binds, so the list outlives the renderer's borrow (an egui paint callback keeps it
/// until egui records its pass).
#[derive(Clone, Debug)]
pub struct FrameDraws {
    globals: wgpu::BindGroup,
    objects: wgpu::BindGroup,
    draws: Vec<Draw>,
}

/// One draw call: a mesh item (with its object slot, texture and texture coordinates) or a
/// run of overlay lines.
#[derive(Clone, Debug)]
struct Draw {
    pipeline: wgpu::RenderPipeline,
    mesh: Option<MeshDrawBindings>,
    /// Vertex slot 0: deformed vertices, or line vertices (none for the background fill).
    vertices: Option<wgpu::Buffer>,
    indices: Option<wgpu::Buffer>,
    /// Indices when `indices` is set, otherwise vertices.
    range: std::ops::Range<u32>,
}

#[derive(Clone, Debug)]
struct MeshDrawBindings {
    object_offset: u32,
    texture: wgpu::BindGroup,
    uvs: wgpu::Buffer,
}

impl FrameDraws {
    /// Records the draws into `pass` (the area must already be cleared or filled).
    pub fn record(&self, pass: &mut wgpu::RenderPass<'_>) {
        pass.set_bind_group(0, &self.globals, &[]);
        for draw in &self.draws {
            pass.set_pipeline(&draw.pipeline);
            if let Some(mesh) = &draw.mesh {
                pass.set_bind_group(1, &self.objects, &[mesh.object_offset]);
                pass.set_bind_group(2, &mesh.texture, &[]);
                pass.set_vertex_buffer(1, mesh.uvs.slice(..));
            }
            if let Some(vertices) = &draw.vertices {
                pass.set_vertex_buffer(0, vertices.slice(..));
            }
            match &draw.indices {
                Some(indices) => {
                    pass.set_index_buffer(indices.slice(..), wgpu::IndexFormat::Uint32);
                    pass.draw_indexed(draw.range.clone(), 0, 0..1);
                }
                None => pass.draw(draw.range.clone(), 0..1),
            }
        }
    }

    /// How many draw calls [`FrameDraws::record`] makes.
    #[must_use]
    pub fn len(&self) -> usize {
        self.draws.len()
    }

    /// Whether the frame draws nothing.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.draws.is_empty()
    }
}

impl Renderer {
    /// Builds the pipelines for viewports of `color_format` (headless uses
    /// `Rgba8UnormSrgb`; the shaders write linear colour, so use an sRGB format) with
    /// [`SAMPLE_COUNT`] samples per pixel.
    #[must_use]
    pub fn new(device: &wgpu::Device, queue: &wgpu::Queue, color_format: wgpu::TextureFormat) -> Self {
        Self::build(device, queue, color_format, SAMPLE_COUNT)
    }

    /// Like [`Renderer::new`] for viewports with `samples` per pixel (one of
    /// [`SUPPORTED_SAMPLE_COUNTS`]; 1 turns anti-aliasing off).
    ///
    /// # Errors
    /// [`RenderError::UnsupportedSampleCount`] for another sample count.
    pub fn with_sample_count(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        color_format: wgpu::TextureFormat,
        samples: u32,
    ) -> Result<Self, RenderError> {
        check_sample_count(samples)?;
        Ok(Self::build(device, queue, color_format, samples))
    }

    /// Samples per pixel of the viewports this renderer draws into.
    #[must_use]
    pub fn sample_count(&self) -> u32 {
        self.pipelines.samples
    }

    /// Rebuilds the draw pipelines for viewports with `samples` per pixel, keeping the uploaded
    /// meshes; draw into a [`Viewport`] with the same count afterwards. Nothing happens when the
    /// count is already `samples`.
    ///
    /// # Errors
    /// [`RenderError::UnsupportedSampleCount`] for a count not in [`SUPPORTED_SAMPLE_COUNTS`].
    pub fn set_sample_count(&mut self, samples: u32) -> Result<(), RenderError> {
        self.set_target(self.color_format, samples)
    }

    /// Rebuilds the draw pipelines for targets of `color_format` with `samples` per pixel,
    /// keeping the uploaded meshes; nothing happens when both are already these. A format that
    /// is not sRGB gets the shaders' linear colour encoded by the shaders themselves (the
    /// editor's window, when the viewport is drawn straight into egui's pass).
    ///
    /// # Errors
    /// [`RenderError::UnsupportedSampleCount`] for a count not in [`SUPPORTED_SAMPLE_COUNTS`].
    pub fn set_target(&mut self, color_format: wgpu::TextureFormat, samples: u32) -> Result<(), RenderError> {
        check_sample_count(samples)?;
        if samples != self.pipelines.samples || color_format != self.color_format {
            self.pipelines = DrawPipelines::new(
                &self.device,
                &self.module,
                (&self.mesh_layout, &self.line_layout),
                color_format,
                samples,
            );
            self.color_format = color_format;
        }
        Ok(())
    }

    fn build(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        color_format: wgpu::TextureFormat,
        samples: u32,
    ) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("keyrig draw.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/draw.wgsl").into()),
        });
        let uniform_layout = |label, dynamic| {
            device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
                label: Some(label),
                entries: &[wgpu::BindGroupLayoutEntry {
                    binding: 0,
                    visibility: wgpu::ShaderStages::VERTEX_FRAGMENT,
                    ty: wgpu::BindingType::Buffer {
                        ty: wgpu::BufferBindingType::Uniform,
                        has_dynamic_offset: dynamic,
                        min_binding_size: None,
                    },
                    count: None,
                }],
            })
        };
        let globals_layout = uniform_layout("keyrig globals", false);
        let object_layout = uniform_layout("keyrig object", true);
        let texture_layout = sampled_texture_layout(device, "keyrig base-colour texture");
        let white = TextureImage::new(1, 1, vec![255u8; 4], keyrig_core::Sampler::default())
            .expect("a 1×1 image has 4 bytes");
        let white_texture = texture_bind_group(device, queue, &texture_layout, &white);
        let globals = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("keyrig globals"),
            size: std::mem::size_of::<GpuGlobals>() as u64,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let globals_bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("keyrig globals"),
            layout: &globals_layout,
            entries: &[wgpu::BindGroupEntry { binding: 0, resource: globals.as_entire_binding() }],
        });
        let mesh_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("keyrig mesh"),
            bind_group_layouts: &[Some(&globals_layout), Some(&object_layout), Some(&texture_layout)],
            immediate_size: 0,
        });
        let line_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("keyrig lines"),
            bind_group_layouts: &[Some(&globals_layout)],
            immediate_size: 0,
        });
        let pipelines =
            DrawPipelines::new(device, &module, (&mesh_layout, &line_layout), color_format, samples);

        let object_capacity = 16;
        let (objects, objects_bind_group) = Self::object_buffer(device, &object_layout, object_capacity);
        let line_capacity = 4096;
        let line_buffer = Self::line_buffer(device, line_capacity);
        Renderer {
            device: device.clone(),
            queue: queue.clone(),
            color_format,
            skinner: GpuSkinner::new(device),
            module,
            mesh_layout,
            line_layout,
            pipelines,
            globals,
            globals_bind_group,
            object_layout,
            texture_layout,
            white_texture,
            objects,
            objects_bind_group,
            object_capacity,
            line_buffer,
            line_capacity,
            meshes: HashMap::new(),
        }
    }

    fn object_buffer(
        device: &wgpu::Device,
        layout: &wgpu::BindGroupLayout,
        capacity: u64,
    ) -> (wgpu::Buffer, wgpu::BindGroup) {
        let buffer = device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("keyrig objects"),
            size: capacity * OBJECT_STRIDE,
            usage: wgpu::BufferUsages::UNIFORM | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        });
        let bind_group = device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some("keyrig objects"),
            layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::Buffer(wgpu::BufferBinding {
                    buffer: &buffer,
                    offset: 0,
                    size: wgpu::BufferSize::new(std::mem::size_of::<GpuObject>() as u64),
                }),
            }],
        });
        (buffer, bind_group)
    }

    fn line_buffer(device: &wgpu::Device, capacity: u64) -> wgpu::Buffer {
        device.create_buffer(&wgpu::BufferDescriptor {
            label: Some("keyrig overlay lines"),
            size: capacity * std::mem::size_of::<LineVertex>() as u64,
            usage: wgpu::BufferUsages::VERTEX | wgpu::BufferUsages::COPY_DST,
            mapped_at_creation: false,
        })
    }

    /// The colour format the pipelines were built for.
    #[must_use]
    pub fn color_format(&self) -> wgpu::TextureFormat {
        self.color_format
    }

    /// The compute pipelines (for benchmarks and tests that skin without drawing).
    #[must_use]
    pub fn skinner(&self) -> &GpuSkinner {
        &self.skinner
    }

    /// Uploads (or replaces) a mesh without texture coordinates. Vertex data stays on the GPU;
    /// frames only send joint data.
    ///
    /// # Errors
    /// Invalid mesh data (lengths, indices, joints, weights, NaN) or a GPU error.
    pub fn upload_mesh(&mut self, id: MeshId, data: &MeshData<'_>) -> Result<(), RenderError> {
        self.upload_mesh_with_uvs(id, data, None)
    }

    /// Uploads (or replaces) a mesh with one texture coordinate per vertex (`None`: all
    /// (0, 0)). A replaced mesh loses its texture; give it one with [`Renderer::set_texture`].
    ///
    /// # Errors
    /// As [`Renderer::upload_mesh`]; [`RenderError::LengthMismatch`] when `uvs` does not have
    /// one entry per vertex, [`RenderError::NonFinite`] for a NaN coordinate.
    pub fn upload_mesh_with_uvs(
        &mut self,
        id: MeshId,
        data: &MeshData<'_>,
        uvs: Option<&[Vec2]>,
    ) -> Result<(), RenderError> {
        let (indices, vertex_count) = match data {
            MeshData::Static { vertices, indices } => (*indices, vertices.len()),
            MeshData::Skinned { skin, indices } => (*indices, skin.positions.len()),
            MeshData::Morph { frames, indices } => (*indices, frames.first().map_or(0, Vec::len)),
        };
        if indices.len() % 3 != 0 {
            return Err(RenderError::BadCount(format!(
                "{} triangle indices is not a multiple of 3",
                indices.len()
            )));
        }
        if let Some((position, &index)) =
            indices.iter().enumerate().find(|(_, &i)| i as usize >= vertex_count)
        {
            return Err(RenderError::IndexOutOfRange { position, index, vertex_count });
        }
        if let Some(uvs) = uvs {
            if uvs.len() != vertex_count {
                return Err(RenderError::LengthMismatch {
                    field: "texture coordinates",
                    expected: vertex_count,
                    actual: uvs.len(),
                });
            }
            if let Some(index) = uvs.iter().position(|uv| !uv.is_finite()) {
                return Err(RenderError::NonFinite { what: "texture coordinate", index });
            }
        }
        let device = self.device.clone();
        let skinner = &self.skinner;
        let mesh = with_error_scope(&device, || -> Result<GpuMesh, RenderError> {
            let deformation = match data {
                MeshData::Static { vertices, .. } => {
                    if vertices.is_empty() {
                        return Err(RenderError::BadCount("a mesh needs at least one vertex".into()));
                    }
                    if let Some(i) =
                        vertices.iter().position(|v| !v.position().is_finite() || !v.normal().is_finite())
                    {
                        return Err(RenderError::NonFinite { what: "static vertex", index: i });
                    }
                    Deformation::Static(crate::skinning::buffer_init(
                        &device,
                        "keyrig static vertices",
                        bytemuck::cast_slice(vertices),
                        wgpu::BufferUsages::VERTEX,
                    ))
                }
                MeshData::Skinned { skin, .. } => Deformation::Skinned(skinner.create_skin(&device, skin)?),
                MeshData::Morph { frames, .. } => Deformation::Morph(skinner.create_morph(&device, frames)?),
            };
            // Index buffers may not be empty; a mesh without triangles still draws as points.
            let edges = overlay::edge_indices(indices);
            let index_buffer = |label, data: &[u32]| {
                let padded: &[u32] = if data.is_empty() { &[0, 0, 0] } else { data };
                crate::skinning::buffer_init(
                    &device,
                    label,
                    bytemuck::cast_slice(padded),
                    wgpu::BufferUsages::INDEX,
                )
            };
            let uv_data: Vec<[f32; 2]> = match uvs {
                Some(uvs) => uvs.iter().map(|uv| uv.to_array()).collect(),
                None => vec![[0.0; 2]; vertex_count.max(1)],
            };
            Ok(GpuMesh {
                deformation,
                uvs: crate::skinning::buffer_init(
                    &device,
                    "keyrig texture coordinates",
                    bytemuck::cast_slice(&uv_data),
                    wgpu::BufferUsages::VERTEX,
                ),
                texture: None,
                vertex_count: vertex_count as u32,
                triangles: index_buffer("keyrig triangles", indices),
                triangle_index_count: indices.len() as u32,
                edges: index_buffer("keyrig edges", &edges),
                edge_index_count: edges.len() as u32,
            })
        })??;
        // Fill the output once (rest pose / first frame) so that the mesh draws sensibly even
        // in a frame that does not deform it.
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("keyrig first skin") });
        match &mesh.deformation {
            Deformation::Static(_) => {}
            // The joint buffer starts with identity poses: M(j) = I gives the rest mesh.
            Deformation::Skinned(skin) => self.skinner.encode(&mut encoder, skin, DeformerKind::Rigid),
            Deformation::Morph(morph) => {
                self.skinner.write_morph(&self.queue, morph, id, 0, 0, 0.0)?;
                self.skinner.encode_morph(&mut encoder, morph);
            }
        }
        self.queue.submit([encoder.finish()]);
        self.meshes.insert(id, mesh);
        Ok(())
    }

    /// Gives mesh `id` a base-colour texture, sampled with the image's sampler (wrap modes,
    /// filters; mipmaps are made here when the sampler uses them), or takes it away (`None`).
    /// The solid style multiplies the draw item's colour by it (when
    /// [`FrameInput::textures`] is on); images larger than the device allows are scaled down.
    ///
    /// # Errors
    /// [`RenderError::UnknownMesh`], or a GPU error.
    pub fn set_texture(&mut self, id: MeshId, image: Option<&TextureImage>) -> Result<(), RenderError> {
        if !self.meshes.contains_key(&id) {
            return Err(RenderError::UnknownMesh(id));
        }
        let bind_group = match image {
            Some(image) => Some(with_error_scope(&self.device, || {
                texture_bind_group(&self.device, &self.queue, &self.texture_layout, image)
            })?),
            None => None,
        };
        if let Some(mesh) = self.meshes.get_mut(&id) {
            mesh.texture = bind_group;
        }
        Ok(())
    }

    /// Whether mesh `id` has a texture.
    #[must_use]
    pub fn has_texture(&self, id: MeshId) -> bool {
        self.meshes.get(&id).is_some_and(|m| m.texture.is_some())
    }

    /// Encodes and submits one frame into `viewport`: compute passes for every deformed item,
    /// then one render pass (meshes, grid, skeletons, motion paths) with MSAA resolve.
    ///
    /// # Errors
    /// An unknown mesh id, joint data that does not fit its mesh, NaN input, or a GPU error.
    pub fn render(&mut self, frame: &FrameInput, viewport: &Viewport) -> Result<FrameStats, RenderError> {
        let device = self.device.clone();
        let command_buffer = with_error_scope(&device, || self.encode(frame, viewport))??;
        self.queue.submit([command_buffer.0]);
        Ok(command_buffer.1)
    }

    /// Like [`Renderer::render`] but returns the command buffer instead of submitting it.
    ///
    /// # Errors
    /// As [`Renderer::render`].
    pub fn encode(
        &mut self,
        frame: &FrameInput,
        viewport: &Viewport,
    ) -> Result<(wgpu::CommandBuffer, FrameStats), RenderError> {
        self.check_viewport(viewport)?;
        let mut encoder = self
            .device
            .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("keyrig frame") });
        let (draws, stats) = self.prepare_in(&mut encoder, frame, viewport.size(), false)?;
        // The render pass, cleared to the background (or to transparent, for a caller that
        // composites the image over a picture of its own).
        let clear = if frame.transparent_background {
            wgpu::Color::TRANSPARENT
        } else {
            let bg = frame.background;
            wgpu::Color { r: f64::from(bg.x), g: f64::from(bg.y), b: f64::from(bg.z), a: 1.0 }
        };
        let mut pass = Self::begin_render_pass(&mut encoder, viewport, clear);
        draws.record(&mut pass);
        drop(pass);
        Ok((encoder.finish(), stats))
    }

    /// Prepares a frame for a render pass the caller owns, `size` pixels wide and high, whose
    /// colour target has the renderer's format and sample count and whose depth attachment is
    /// [`DEPTH_FORMAT`], cleared to 1 where the frame is drawn (egui-wgpu clears the whole
    /// window's depth when its pass begins), with the pass's viewport (and scissor) set to the
    /// frame's rect: submits the frame's uploads and compute passes, and returns the draws to
    /// record into that pass, the first of which fills the rect's colour with the background,
    /// so the rect needs no colour clear. The editor draws its viewport
    /// straight into egui's pass this way (docs/rendering.md, "Embedding in the editor").
    ///
    /// # Errors
    /// As [`Renderer::render`].
    pub fn prepare(
        &mut self,
        frame: &FrameInput,
        size: (u32, u32),
    ) -> Result<(FrameDraws, FrameStats), RenderError> {
        let device = self.device.clone();
        let (command_buffer, draws, stats) = with_error_scope(&device, || {
            let mut encoder = self
                .device
                .create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("keyrig frame") });
            let (draws, stats) = self.prepare_in(&mut encoder, frame, size, true)?;
            Ok::<_, RenderError>((encoder.finish(), draws, stats))
        })??;
        self.queue.submit([command_buffer]);
        Ok((draws, stats))
    }

    /// The steps of a frame before its render pass: the compute passes, the uniforms, the
    /// overlay lines, and the draws.
    fn prepare_in(
        &mut self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInput,
        size: (u32, u32),
        fill: bool,
    ) -> Result<(FrameDraws, FrameStats), RenderError> {
        self.check_frame(frame)?;
        let mut stats = FrameStats::default();

        // 1. Per-frame uploads and compute passes.
        self.encode_deformations(encoder, frame, &mut stats)?;

        // 2. Uniforms.
        self.write_globals(frame, size, &mut stats);
        self.write_objects(frame, &mut stats);

        // 3. Overlay lines: grid (depth-tested) first, then skeletons and paths (on top).
        let lines = self.write_overlay_lines(frame, &mut stats)?;

        // 4. The draws, after the background where the pass was not cleared for the frame.
        let mut draws = FrameDraws {
            globals: self.globals_bind_group.clone(),
            objects: self.objects_bind_group.clone(),
            draws: Vec::with_capacity(frame.items.len() + 3),
        };
        if fill {
            draws.draws.push(Draw {
                pipeline: self.pipelines.fill.clone(),
                mesh: None,
                vertices: None,
                indices: None,
                range: 0..3,
            });
        }
        self.draw_items(&mut draws, frame);
        self.draw_lines(&mut draws, lines);
        stats.draw_calls += draws.draws.len() as u32;
        Ok((draws, stats))
    }

    /// Refuses a viewport of another colour format or sample count than the renderer's.
    fn check_viewport(&self, viewport: &Viewport) -> Result<(), RenderError> {
        if viewport.format != self.color_format {
            return Err(RenderError::Gpu(format!(
                "viewport format {:?} differs from the renderer's {:?}",
                viewport.format, self.color_format
            )));
        }
        if viewport.samples != self.pipelines.samples {
            return Err(RenderError::Gpu(format!(
                "viewport has {} samples per pixel, the renderer's pipelines {}",
                viewport.samples, self.pipelines.samples
            )));
        }
        Ok(())
    }

    /// Refuses a camera that cannot be projected.
    fn check_frame(&self, frame: &FrameInput) -> Result<(), RenderError> {
        if !camera::is_usable(&frame.camera) {
            return Err(RenderError::NonFinite { what: "camera (or distance ≤ 0)", index: 0 });
        }
        if frame.through.is_some_and(|c| !c.is_usable()) {
            return Err(RenderError::NonFinite {
                what: "scene camera (position, rotation, lens or clip planes)",
                index: 0,
            });
        }
        Ok(())
    }

    /// Checks every draw item (a known mesh, a finite transform and colour, a deformation its
    /// mesh has) and, for a skinned or morphing item, writes its joints or morph frames and
    /// records its compute pass.
    fn encode_deformations(
        &self,
        encoder: &mut wgpu::CommandEncoder,
        frame: &FrameInput,
        stats: &mut FrameStats,
    ) -> Result<(), RenderError> {
        for item in &frame.items {
            let mesh = self.meshes.get(&item.mesh).ok_or(RenderError::UnknownMesh(item.mesh))?;
            if !item.world_from_model.is_finite() || !item.colour.is_finite() {
                return Err(RenderError::NonFinite {
                    what: "draw item transform or colour",
                    index: item.mesh as usize,
                });
            }
            match (&item.deform, &mesh.deformation) {
                (Deform::Skin { deformer, joints, bindings, morph }, Deformation::Skinned(skin)) => {
                    stats.joint_bytes += self.skinner.write_joints(&self.queue, skin, item.mesh, joints)?;
                    stats.joint_bytes += self.skinner.write_bindings(
                        &self.queue,
                        skin,
                        item.mesh,
                        bindings.as_ref(),
                        morph.as_ref(),
                    )?;
                    self.skinner.encode(encoder, skin, *deformer);
                    stats.deformed_vertices += u64::from(skin.vertex_count);
                }
                (Deform::Morph { frame_a, frame_b, t }, Deformation::Morph(morph)) => {
                    stats.morph_bytes +=
                        self.skinner.write_morph(&self.queue, morph, item.mesh, *frame_a, *frame_b, *t)?;
                    self.skinner.encode_morph(encoder, morph);
                    stats.deformed_vertices += u64::from(morph.vertex_count);
                }
                (Deform::None, _) => {}
                (Deform::Skin { .. }, _) => {
                    return Err(RenderError::BadCount(format!("mesh {} is not a skinned mesh", item.mesh)))
                }
                (Deform::Morph { .. }, _) => {
                    return Err(RenderError::BadCount(format!("mesh {} is not a morphing mesh", item.mesh)))
                }
            }
        }
        Ok(())
    }

    /// Writes the frame's globals: the camera's projection for the viewport's aspect ratio,
    /// its position, the ambient light and the first [`MAX_LIGHTS`] lights (the others are
    /// counted in [`FrameStats::lights_dropped`]).
    fn write_globals(&self, frame: &FrameInput, (width, height): (u32, u32), stats: &mut FrameStats) {
        let aspect = width as f32 / height as f32;
        let mut lights = [GpuLight::zeroed(); MAX_LIGHTS];
        let mut light_count = 0usize;
        for light in &frame.lights {
            if light_count == MAX_LIGHTS {
                stats.lights_dropped += 1;
                continue;
            }
            lights[light_count] = gpu_light(light);
            light_count += 1;
        }
        let (clip_from_world, eye) = match &frame.through {
            Some(through) => (through.clip_from_world(aspect), through.eye()),
            None => (
                camera::clip_from_world_in(&frame.camera, aspect, frame.depth_range),
                camera::eye_position(&frame.camera),
            ),
        };
        let globals = GpuGlobals {
            clip_from_world: clip_from_world.to_cols_array_2d(),
            camera_position: eye.extend(1.0).to_array(),
            ambient: frame.ambient.extend(0.0).to_array(),
            counts: [light_count as u32, 0, 0, 0],
            lights,
            // Already encoded for a target that does not encode on write, so that the fill's
            // fragments only copy it (`fs_fill`).
            background: if self.color_format.is_srgb() {
                frame.background.extend(1.0).to_array()
            } else {
                let [r, g, b] = frame.background.to_array().map(|c| srgb_encode(c) as f32);
                [r, g, b, 1.0]
            },
        };
        self.queue.write_buffer(&self.globals, 0, bytemuck::bytes_of(&globals));
        stats.uniform_bytes += std::mem::size_of::<GpuGlobals>() as u64;
    }

    /// Writes each draw item's object uniforms (transform, normal matrix, colour, selection,
    /// ghost tint) at its [`OBJECT_STRIDE`] slot, growing the buffer to a power of two when
    /// the items do not fit.
    fn write_objects(&mut self, frame: &FrameInput, stats: &mut FrameStats) {
        let needed = frame.items.len().max(1) as u64;
        if needed > self.object_capacity {
            self.object_capacity = needed.next_power_of_two();
            let (buffer, bind_group) =
                Self::object_buffer(&self.device, &self.object_layout, self.object_capacity);
            self.objects = buffer;
            self.objects_bind_group = bind_group;
        }
        let mut object_bytes = vec![0u8; (frame.items.len() as u64 * OBJECT_STRIDE) as usize];
        for (i, item) in frame.items.iter().enumerate() {
            let normal = Mat4::from_mat3(glam::Mat3::from_mat4(item.world_from_model).inverse().transpose());
            let object = GpuObject {
                world_from_model: item.world_from_model.to_cols_array_2d(),
                normal_from_model: if normal.is_finite() { normal } else { Mat4::IDENTITY }
                    .to_cols_array_2d(),
                colour: item.colour.extend(item.opacity.clamp(0.0, 1.0)).to_array(),
                flags: [if item.selected { 1.0 } else { 0.0 }, 0.0, 0.0, 0.0],
                tint: item.ghost.map_or([0.0; 4], |g| g.tint.extend(g.opacity.clamp(0.0, 1.0)).to_array()),
            };
            let start = i * OBJECT_STRIDE as usize;
            object_bytes[start..start + std::mem::size_of::<GpuObject>()]
                .copy_from_slice(bytemuck::bytes_of(&object));
        }
        if !object_bytes.is_empty() {
            self.queue.write_buffer(&self.objects, 0, &object_bytes);
            stats.uniform_bytes += object_bytes.len() as u64;
        }
    }

    /// Builds and writes the overlay lines: the grid first, then skeletons, motion paths and
    /// light gizmos, growing the line buffer to a power of two when they do not fit.
    ///
    /// # Errors
    /// [`RenderError::NonFinite`] for a line vertex that is not finite.
    fn write_overlay_lines(
        &mut self,
        frame: &FrameInput,
        stats: &mut FrameStats,
    ) -> Result<OverlayLines, RenderError> {
        let mut lines = Lines::default();
        if let Some(spacing) = frame.grid_spacing.filter(|s| s.is_finite() && *s > 0.0) {
            overlay::grid(&mut lines, spacing, 50);
        }
        let grid_vertices = lines.len() as u32;
        // Overlays keep their size on screen: in proportion to the distance looked from (through
        // a scene camera: its distance to the orbit target, the middle of what is being worked on).
        let marker = match &frame.through {
            Some(through) => through.eye().distance(frame.camera.target).max(1e-3) * 0.008,
            None => frame.camera.distance * 0.008,
        };
        for skeleton in &frame.skeletons {
            overlay::skeleton(&mut lines, skeleton, marker);
        }
        for path in &frame.motion_paths {
            overlay::motion_path(&mut lines, path, marker);
        }
        for gizmo in &frame.light_gizmos {
            overlay::light_gizmo(&mut lines, gizmo, marker);
        }
        for gizmo in &frame.camera_gizmos {
            overlay::camera_gizmo(&mut lines, gizmo, marker);
        }
        if lines.vertices.iter().any(|v| !v.position.iter().all(|x| x.is_finite())) {
            return Err(RenderError::NonFinite {
                what: "overlay (skeleton or motion path) position",
                index: 0,
            });
        }
        let line_vertices = lines.len() as u64;
        if line_vertices > self.line_capacity {
            self.line_capacity = line_vertices.next_power_of_two();
            self.line_buffer = Self::line_buffer(&self.device, self.line_capacity);
        }
        if line_vertices > 0 {
            let bytes: &[u8] = bytemuck::cast_slice(&lines.vertices);
            self.queue.write_buffer(&self.line_buffer, 0, bytes);
            stats.overlay_bytes += bytes.len() as u64;
        }
        Ok(OverlayLines { grid_vertices, line_vertices })
    }

    /// Begins the viewport's render pass, clearing colour to `clear` and depth to 1.
    fn begin_render_pass<'e>(
        encoder: &'e mut wgpu::CommandEncoder,
        viewport: &Viewport,
        clear: wgpu::Color,
    ) -> wgpu::RenderPass<'e> {
        // With MSAA the multisampled image is resolved and then discarded; without, the
        // pass draws straight into the colour texture, which must be stored.
        let (view, resolve_target, store) = match &viewport.msaa_view {
            Some(msaa) => (msaa, Some(&viewport.resolved_view), wgpu::StoreOp::Discard),
            None => (&viewport.resolved_view, None, wgpu::StoreOp::Store),
        };
        encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("keyrig viewport"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view,
                depth_slice: None,
                resolve_target,
                ops: wgpu::Operations { load: wgpu::LoadOp::Clear(clear), store },
            })],
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &viewport.depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        })
    }

    /// The draws of the items in the frame's style, opaque items first, then ghosts blended
    /// over them; a mesh without the primitives the style needs (triangles for Solid, edges
    /// for Wireframe) is drawn as points.
    fn draw_items(&self, draws: &mut FrameDraws, frame: &FrameInput) {
        let pipelines = &self.pipelines;
        let pipeline = match frame.style {
            RenderStyle::Solid => &pipelines.solid,
            RenderStyle::Wireframe => &pipelines.wireframe,
            RenderStyle::Points => &pipelines.points,
        };
        // Opaque items first, then translucent items and ghosts blended over them (in the
        // order given).
        let translucent = |item: &DrawItem| item.ghost.is_none() && item.opacity < 1.0;
        let order = frame
            .items
            .iter()
            .enumerate()
            .filter(|(_, item)| item.ghost.is_none() && !translucent(item))
            .chain(frame.items.iter().enumerate().filter(|(_, item)| translucent(item)))
            .chain(frame.items.iter().enumerate().filter(|(_, item)| item.ghost.is_some()));
        // Opaque solid items' back faces, drawn after every opaque front face.
        let mut back_faces = Vec::new();
        for (i, item) in order {
            // Checked in encode_deformations.
            let Some(mesh) = self.meshes.get(&item.mesh) else { continue };
            if item.ghost.is_some() && !back_faces.is_empty() {
                draws.draws.append(&mut back_faces);
            }
            let mesh_draw = |pipeline: &wgpu::RenderPipeline, texture: &wgpu::BindGroup| Draw {
                pipeline: pipeline.clone(),
                mesh: Some(MeshDrawBindings {
                    object_offset: (i as u64 * OBJECT_STRIDE) as u32,
                    texture: texture.clone(),
                    uvs: mesh.uvs.clone(),
                }),
                vertices: Some(mesh.vertex_buffer().clone()),
                indices: None,
                range: 0..mesh.vertex_count,
            };
            if item.ghost.is_some() {
                if mesh.triangle_index_count > 0 {
                    draws.draws.push(Draw {
                        indices: Some(mesh.triangles.clone()),
                        range: 0..mesh.triangle_index_count,
                        ..mesh_draw(&pipelines.ghost, &self.white_texture)
                    });
                }
                continue;
            }
            if translucent(item) && item.opacity <= 0.0 {
                continue;
            }
            let texture = match &mesh.texture {
                Some(texture) if frame.textures => Some(texture),
                _ => None,
            };
            let pipeline = match (frame.style, translucent(item), texture.is_some()) {
                (RenderStyle::Solid, true, true) => &pipelines.translucent,
                (RenderStyle::Solid, true, false) => &pipelines.translucent_untextured,
                (RenderStyle::Solid, false, false) => &pipelines.solid_untextured,
                _ => pipeline,
            };
            let draw = mesh_draw(pipeline, texture.unwrap_or(&self.white_texture));
            if frame.style == RenderStyle::Solid && !translucent(item) && mesh.triangle_index_count > 0 {
                let (fronts, backs) = if texture.is_some() {
                    (&pipelines.solid_fronts, &pipelines.solid_backs)
                } else {
                    (&pipelines.solid_untextured_fronts, &pipelines.solid_untextured_backs)
                };
                let triangles = Draw {
                    indices: Some(mesh.triangles.clone()),
                    range: 0..mesh.triangle_index_count,
                    ..draw
                };
                back_faces.push(Draw { pipeline: backs.clone(), ..triangles.clone() });
                draws.draws.push(Draw { pipeline: fronts.clone(), ..triangles });
                continue;
            }
            if !back_faces.is_empty() && translucent(item) {
                // Every opaque item's back faces before the first translucent item.
                draws.draws.append(&mut back_faces);
            }
            draws.draws.push(match frame.style {
                RenderStyle::Solid if mesh.triangle_index_count > 0 => Draw {
                    indices: Some(mesh.triangles.clone()),
                    range: 0..mesh.triangle_index_count,
                    ..draw
                },
                RenderStyle::Wireframe if mesh.edge_index_count > 0 => {
                    Draw { indices: Some(mesh.edges.clone()), range: 0..mesh.edge_index_count, ..draw }
                }
                RenderStyle::Solid | RenderStyle::Wireframe => {
                    Draw { pipeline: pipelines.points.clone(), ..draw }
                }
                RenderStyle::Points => draw,
            });
        }
        draws.draws.append(&mut back_faces);
    }

    /// The draws of the overlay lines: the grid depth-tested, the rest on top of everything.
    fn draw_lines(&self, draws: &mut FrameDraws, lines: OverlayLines) {
        let OverlayLines { grid_vertices, line_vertices } = lines;
        let line_draw = |pipeline: &wgpu::RenderPipeline, range: std::ops::Range<u32>| Draw {
            pipeline: pipeline.clone(),
            mesh: None,
            vertices: Some(self.line_buffer.clone()),
            indices: None,
            range,
        };
        if grid_vertices > 0 {
            draws.draws.push(line_draw(&self.pipelines.lines_depth, 0..grid_vertices));
        }
        if line_vertices as u32 > grid_vertices {
            draws.draws.push(line_draw(&self.pipelines.lines_on_top, grid_vertices..line_vertices as u32));
        }
    }

    /// Reads back the current deformed vertices of a mesh (the last frame's compute output,
    /// or the static vertices).
    ///
    /// # Errors
    /// [`RenderError::UnknownMesh`], or a GPU error.
    pub fn read_vertices(&self, id: MeshId) -> Result<Vec<SkinnedVertex>, RenderError> {
        let mesh = self.meshes.get(&id).ok_or(RenderError::UnknownMesh(id))?;
        match &mesh.deformation {
            Deformation::Static(_) => {
                Err(RenderError::Gpu(format!("mesh {id} is static; its vertices are the input")))
            }
            Deformation::Skinned(_) | Deformation::Morph(_) => crate::skinning::read_skinned(
                &self.device,
                &self.queue,
                mesh.vertex_buffer(),
                mesh.vertex_count,
            ),
        }
    }
}

/// Linear to sRGB-encoded (IEC 61966-2-1), for a value written to a target that does not
/// encode on write.
fn srgb_encode(linear: f32) -> f64 {
    let x = f64::from(linear.clamp(0.0, 1.0));
    if x <= 0.003_130_8 {
        x * 12.92
    } else {
        1.055 * x.powf(1.0 / 2.4) - 0.055
    }
}

/// The bind group layout of a filterable 2D colour texture (binding 0) and its filtering sampler
/// (binding 1), read by a fragment shader: a mesh's base-colour texture, and the editor's copy
/// of the offscreen viewport into its window.
#[must_use]
pub fn sampled_texture_layout(device: &wgpu::Device, label: &str) -> wgpu::BindGroupLayout {
    device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
        label: Some(label),
        entries: &[
            wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: true },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            },
            wgpu::BindGroupLayoutEntry {
                binding: 1,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Sampler(wgpu::SamplerBindingType::Filtering),
                count: None,
            },
        ],
    })
}

#[cfg(test)]
mod tests {
    use glam::{Mat4, Vec3};
    use keyrig_core::Camera;

    use super::*;
    use crate::{HeadlessRenderer, SkinnedVertex, HEADLESS_FORMAT};

    fn headless() -> HeadlessRenderer {
        HeadlessRenderer::new().unwrap_or_else(|e| panic!("GPU tests need a wgpu adapter: {e}"))
    }

    /// A lit triangle in front of the camera, so the image has edges that MSAA smooths.
    fn triangle_frame(renderer: &mut Renderer) -> FrameInput {
        let vertices = [
            SkinnedVertex::new(Vec3::new(-0.6, -0.5, 0.0), Vec3::Z),
            SkinnedVertex::new(Vec3::new(0.7, -0.4, 0.0), Vec3::Z),
            SkinnedVertex::new(Vec3::new(0.1, 0.6, 0.0), Vec3::Z),
        ];
        renderer
            .upload_mesh(7, &MeshData::Static { vertices: &vertices, indices: &[0, 1, 2] })
            .expect("upload");
        let camera =
            Camera { target: Vec3::ZERO, yaw_deg: 0.0, pitch_deg: 0.0, distance: 2.0, fov_y_deg: 60.0 };
        let mut frame = FrameInput::new(camera);
        frame.ambient = Vec3::splat(0.8);
        frame.grid_spacing = None;
        frame.items.push(DrawItem {
            mesh: 7,
            world_from_model: Mat4::IDENTITY,
            deform: Deform::None,
            colour: Vec3::new(0.9, 0.6, 0.3),
            opacity: 1.0,
            selected: false,
            ghost: None,
        });
        frame
    }

    #[test]
    fn sample_counts_other_than_1_and_4_are_refused_with_a_typed_error() {
        let h = headless();
        let gpu = h.gpu();
        for samples in [0, 2, 3, 8, 16] {
            let renderer = Renderer::with_sample_count(&gpu.device, &gpu.queue, HEADLESS_FORMAT, samples);
            assert!(matches!(renderer, Err(RenderError::UnsupportedSampleCount(n)) if n == samples));
            let viewport = Viewport::with_sample_count(&gpu.device, 8, 8, HEADLESS_FORMAT, samples);
            assert!(matches!(viewport, Err(RenderError::UnsupportedSampleCount(n)) if n == samples));
        }
        let mut renderer = Renderer::new(&gpu.device, &gpu.queue, HEADLESS_FORMAT);
        assert_eq!(renderer.sample_count(), SAMPLE_COUNT);
        assert!(matches!(renderer.set_sample_count(2), Err(RenderError::UnsupportedSampleCount(2))));
        assert_eq!(renderer.sample_count(), SAMPLE_COUNT, "a refused count changes nothing");
    }

    #[test]
    fn a_viewport_with_another_sample_count_is_an_error_not_a_panic() {
        let mut h = headless();
        let frame = triangle_frame(h.renderer_mut());
        let single =
            Viewport::with_sample_count(&h.gpu().device, 32, 32, HEADLESS_FORMAT, 1).expect("viewport");
        assert_eq!(single.sample_count(), 1);
        let err = h.renderer_mut().render(&frame, &single).expect_err("4× pipelines, 1× viewport");
        assert!(err.to_string().contains("samples per pixel"), "{err}");
    }

    #[test]
    fn one_sample_draws_the_same_image_except_along_edges() {
        const SIZE: u32 = 96;
        let mut h = headless();
        let frame = triangle_frame(h.renderer_mut());
        let (msaa, _) = h.render_image(&frame, SIZE, SIZE).expect("4× image");
        h.renderer_mut().set_sample_count(1).expect("1 sample");
        assert_eq!(h.renderer().sample_count(), 1);
        let (single, _) = h.render_image(&frame, SIZE, SIZE).expect("1× image (new viewport)");
        let differing: Vec<(u32, u32)> = msaa
            .enumerate_pixels()
            .filter(|(x, y, p)| p.0.iter().zip(single.get_pixel(*x, *y).0).any(|(a, b)| a.abs_diff(b) > 2))
            .map(|(x, y, _)| (x, y))
            .collect();
        // Interior and background agree; only pixels that an edge crosses differ (the triangle's
        // three edges cross about 150 of the 9216 pixels).
        assert!(!differing.is_empty(), "MSAA should change the edge pixels");
        assert!(differing.len() < 400, "{} of {} pixels differ", differing.len(), SIZE * SIZE);
        // Near the centroid (0.07, −0.1, 0), which projects to about (51, 52).
        let inside = (51, 52);
        assert!(msaa.get_pixel(inside.0, inside.1) != msaa.get_pixel(2, 2), "the triangle is drawn");
        assert!(!differing.contains(&inside), "the triangle's interior is the same");
        assert!(!differing.contains(&(2, 2)), "the background is the same");
        // Back to 4×: the same image as the first.
        h.renderer_mut().set_sample_count(4).expect("4 samples");
        let (again, _) = h.render_image(&frame, SIZE, SIZE).expect("4× again");
        assert_eq!(again, msaa);
    }
}
