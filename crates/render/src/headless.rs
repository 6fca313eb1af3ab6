//! Rendering without a window: its own device, an offscreen viewport, pixels read back into an
//! [`image::RgbaImage`].

use crate::accumulate::{Accumulator, MAX_SUBFRAMES};
use crate::gpu::{map_and_read, GpuContext};
use crate::renderer::{FrameInput, FrameStats, MeshData, MeshId, Renderer, Viewport};
use crate::RenderError;

/// Colour format of headless images (8-bit sRGB, what PNG files hold).
pub const HEADLESS_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba8UnormSrgb;

/// A [`Renderer`] on its own device that renders frames to images.
pub struct HeadlessRenderer {
    gpu: GpuContext,
    renderer: Renderer,
    viewport: Option<Viewport>,
    /// Motion blur's sum and pipelines, kept while the size stays.
    accumulator: Option<Accumulator>,
}

impl HeadlessRenderer {
    /// Opens a device (see [`GpuContext::headless`]) and builds the pipelines.
    ///
    /// # Errors
    /// No adapter (with what to install), or the device refused.
    pub fn new() -> Result<Self, RenderError> {
        let gpu = GpuContext::headless()?;
        let renderer = Renderer::new(&gpu.device, &gpu.queue, HEADLESS_FORMAT);
        Ok(HeadlessRenderer { gpu, renderer, viewport: None, accumulator: None })
    }

    /// The device, queue and adapter.
    #[must_use]
    pub fn gpu(&self) -> &GpuContext {
        &self.gpu
    }

    #[must_use]
    pub fn renderer(&self) -> &Renderer {
        &self.renderer
    }

    pub fn renderer_mut(&mut self) -> &mut Renderer {
        &mut self.renderer
    }

    /// See [`Renderer::upload_mesh`].
    ///
    /// # Errors
    /// As [`Renderer::upload_mesh`].
    pub fn upload_mesh(&mut self, id: MeshId, data: &MeshData<'_>) -> Result<(), RenderError> {
        self.renderer.upload_mesh(id, data)
    }

    /// Renders one frame at `width`×`height` and reads it back.
    ///
    /// # Errors
    /// An invalid size, bad frame data, or a GPU error.
    pub fn render_image(
        &mut self,
        frame: &FrameInput,
        width: u32,
        height: u32,
    ) -> Result<(image::RgbaImage, FrameStats), RenderError> {
        let viewport = self.take_viewport(width, height)?;
        let result = self.renderer.render(frame, &viewport).and_then(|stats| {
            let image = read_viewport(&self.gpu.device, &self.gpu.queue, &viewport)?;
            Ok((image, stats))
        });
        self.viewport = Some(viewport);
        result
    }

    /// Renders the average of `subframes` (the scene at several times within one frame's
    /// shutter: motion blur, see [`crate::accumulate`]) at `width`×`height` and reads it back.
    /// Each sub-frame is weighted equally; one sub-frame is [`HeadlessRenderer::render_image`].
    /// The returned statistics add up every sub-frame's.
    ///
    /// # Errors
    /// No sub-frames or more than [`MAX_SUBFRAMES`], and as [`HeadlessRenderer::render_image`].
    pub fn render_image_blurred(
        &mut self,
        subframes: &[FrameInput],
        width: u32,
        height: u32,
    ) -> Result<(image::RgbaImage, FrameStats), RenderError> {
        match subframes.len() {
            0 => return Err(RenderError::Gpu("motion blur: no sub-frames to render".into())),
            1 => return self.render_image(&subframes[0], width, height),
            n if n > MAX_SUBFRAMES as usize => {
                return Err(RenderError::Gpu(format!(
                    "motion blur: {n} sub-frames, more than {MAX_SUBFRAMES}"
                )))
            }
            _ => {}
        }
        let viewport = self.take_viewport(width, height)?;
        let mut accumulator = match self.accumulator.take() {
            Some(a) if a.size_and_format() == ((width, height), HEADLESS_FORMAT) => a,
            _ => Accumulator::new(&self.gpu.device, &self.gpu.queue, width, height, HEADLESS_FORMAT),
        };
        let weight = 1.0 / subframes.len() as f32;
        let mut result = (|| {
            accumulator.begin();
            let mut total = FrameStats::default();
            for frame in subframes {
                let stats = self.renderer.render(frame, &viewport)?;
                total.add(&stats);
                accumulator.add(viewport.color_view(), weight)?;
            }
            let texture = accumulator.resolve()?;
            let image = read_texture(&self.gpu.device, &self.gpu.queue, texture, HEADLESS_FORMAT)?;
            Ok((image, total))
        })();
        if let Err(RenderError::Gpu(message)) = &mut result {
            message.insert_str(0, "motion blur: ");
        }
        self.viewport = Some(viewport);
        self.accumulator = Some(accumulator);
        result
    }

    /// The kept viewport when it has this size and the renderer's sample count, else a new one.
    fn take_viewport(&mut self, width: u32, height: u32) -> Result<Viewport, RenderError> {
        let samples = self.renderer.sample_count();
        match self.viewport.take() {
            Some(v) if v.size() == (width, height) && v.sample_count() == samples => Ok(v),
            _ => Viewport::with_sample_count(&self.gpu.device, width, height, HEADLESS_FORMAT, samples),
        }
    }
}

/// Copies a viewport's resolved colour texture (RGBA8) into an image.
///
/// # Errors
/// [`RenderError::Gpu`] when the format is not 4 bytes per pixel or mapping fails.
pub fn read_viewport(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    viewport: &Viewport,
) -> Result<image::RgbaImage, RenderError> {
    read_texture(device, queue, viewport.color_texture(), viewport.format())
}

/// Copies a single-sample 2D texture of `format` (4 bytes per pixel; BGRA is swapped to RGBA)
/// with `COPY_SRC` usage into an image.
///
/// # Errors
/// [`RenderError::Gpu`] when the format is not 4 bytes per pixel or mapping fails.
pub fn read_texture(
    device: &wgpu::Device,
    queue: &wgpu::Queue,
    texture: &wgpu::Texture,
    format: wgpu::TextureFormat,
) -> Result<image::RgbaImage, RenderError> {
    let (width, height) = (texture.width(), texture.height());
    if format.block_copy_size(None) != Some(4) {
        return Err(RenderError::Gpu(format!("cannot read back a {format:?} texture as RGBA8")));
    }
    let unpadded = width * 4;
    let padded = unpadded.next_multiple_of(wgpu::COPY_BYTES_PER_ROW_ALIGNMENT);
    let staging = device.create_buffer(&wgpu::BufferDescriptor {
        label: Some("keyrig image readback"),
        size: u64::from(padded) * u64::from(height),
        usage: wgpu::BufferUsages::MAP_READ | wgpu::BufferUsages::COPY_DST,
        mapped_at_creation: false,
    });
    let mut encoder =
        device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("keyrig readback") });
    encoder.copy_texture_to_buffer(
        wgpu::TexelCopyTextureInfo {
            texture,
            mip_level: 0,
            origin: wgpu::Origin3d::ZERO,
            aspect: wgpu::TextureAspect::All,
        },
        wgpu::TexelCopyBufferInfo {
            buffer: &staging,
            layout: wgpu::TexelCopyBufferLayout {
                offset: 0,
                bytes_per_row: Some(padded),
                rows_per_image: Some(height),
            },
        },
        wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
    );
    queue.submit([encoder.finish()]);
    let bytes = map_and_read(device, &staging)?;
    let mut pixels = Vec::with_capacity((unpadded * height) as usize);
    for row in bytes.chunks_exact(padded as usize) {
        pixels.extend_from_slice(&row[..unpadded as usize]);
    }
    let mut image = image::RgbaImage::from_raw(width, height, pixels)
        .ok_or_else(|| RenderError::Gpu("readback returned fewer bytes than the image needs".into()))?;
    if matches!(format, wgpu::TextureFormat::Bgra8Unorm | wgpu::TextureFormat::Bgra8UnormSrgb) {
        for p in image.pixels_mut() {
            p.0.swap(0, 2);
        }
    }
    Ok(image)
}
