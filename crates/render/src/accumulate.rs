//! Motion blur by accumulation: the average of N renders of one frame at times spread across
//! the shutter, summed on the GPU.
//!
//! "A moving object is rendered in several positions it had during the time period represented
//! by a single frame" (IAnimEd §2; the accumulation buffer of Haeberli and Akeley, *The
//! Accumulation Buffer*, SIGGRAPH 1990). Each sub-frame is rendered into the viewport as usual;
//! a full-screen pass then adds it, weighted 1/N by the pipeline's blend constant, into a
//! 16-bit float sum (`sum += colour · 1/N`). The sum is in linear colour (the sub-frame is
//! read through its sRGB view), so a half-covered pixel is the linear mean of object and
//! background, as a real shutter would see it. A last pass writes the sum into an image of
//! the viewport's format (sRGB-encoded again), which is read back like a plain frame.
//!
//! Precision: a half float holds 11 significant bits, so N ≤ 256 sub-frames of values ≤ 1
//! sum with an error under one step of the 8-bit output.

use crate::RenderError;

/// Format of the running sum: blendable on every wgpu adapter (32-bit float blending is an
/// optional feature).
pub const SUM_FORMAT: wgpu::TextureFormat = wgpu::TextureFormat::Rgba16Float;

/// Most sub-frames one blurred frame may average (see the module's note on precision).
pub const MAX_SUBFRAMES: u32 = 256;

/// The pipelines and textures that average sub-frames of one size and output format.
pub struct Accumulator {
    device: wgpu::Device,
    queue: wgpu::Queue,
    layout: wgpu::BindGroupLayout,
    accumulate: wgpu::RenderPipeline,
    resolve: wgpu::RenderPipeline,
    size: (u32, u32),
    format: wgpu::TextureFormat,
    sum_view: wgpu::TextureView,
    output: wgpu::Texture,
    output_view: wgpu::TextureView,
    /// Sub-frames added since the last [`Accumulator::begin`].
    added: u32,
}

impl Accumulator {
    /// Builds the pipelines and a sum and an output texture of `width`×`height`; the output
    /// has `format` (that of the viewports whose images are added).
    #[must_use]
    pub fn new(
        device: &wgpu::Device,
        queue: &wgpu::Queue,
        width: u32,
        height: u32,
        format: wgpu::TextureFormat,
    ) -> Self {
        let module = device.create_shader_module(wgpu::ShaderModuleDescriptor {
            label: Some("keyrig accumulate.wgsl"),
            source: wgpu::ShaderSource::Wgsl(include_str!("shaders/accumulate.wgsl").into()),
        });
        let layout = device.create_bind_group_layout(&wgpu::BindGroupLayoutDescriptor {
            label: Some("keyrig accumulate source"),
            entries: &[wgpu::BindGroupLayoutEntry {
                binding: 0,
                visibility: wgpu::ShaderStages::FRAGMENT,
                ty: wgpu::BindingType::Texture {
                    sample_type: wgpu::TextureSampleType::Float { filterable: false },
                    view_dimension: wgpu::TextureViewDimension::D2,
                    multisampled: false,
                },
                count: None,
            }],
        });
        let pipeline_layout = device.create_pipeline_layout(&wgpu::PipelineLayoutDescriptor {
            label: Some("keyrig accumulate"),
            bind_group_layouts: &[Some(&layout)],
            immediate_size: 0,
        });
        let pipeline = |label: &str, format: wgpu::TextureFormat, blend: Option<wgpu::BlendState>| {
            device.create_render_pipeline(&wgpu::RenderPipelineDescriptor {
                label: Some(label),
                layout: Some(&pipeline_layout),
                vertex: wgpu::VertexState {
                    module: &module,
                    entry_point: Some("vs_full_screen"),
                    compilation_options: Default::default(),
                    buffers: &[],
                },
                primitive: wgpu::PrimitiveState::default(),
                depth_stencil: None,
                multisample: wgpu::MultisampleState::default(),
                fragment: Some(wgpu::FragmentState {
                    module: &module,
                    entry_point: Some("fs_copy"),
                    compilation_options: Default::default(),
                    targets: &[Some(wgpu::ColorTargetState {
                        format,
                        blend,
                        write_mask: wgpu::ColorWrites::ALL,
                    })],
                }),
                multiview_mask: None,
                cache: None,
            })
        };
        // sum = source · constant + sum · 1.
        let weighted_add = wgpu::BlendComponent {
            src_factor: wgpu::BlendFactor::Constant,
            dst_factor: wgpu::BlendFactor::One,
            operation: wgpu::BlendOperation::Add,
        };
        let accumulate = pipeline(
            "keyrig accumulate",
            SUM_FORMAT,
            Some(wgpu::BlendState { color: weighted_add, alpha: weighted_add }),
        );
        let resolve = pipeline("keyrig accumulate resolve", format, None);
        let texture = |label, format, usage| {
            device.create_texture(&wgpu::TextureDescriptor {
                label: Some(label),
                size: wgpu::Extent3d { width, height, depth_or_array_layers: 1 },
                mip_level_count: 1,
                sample_count: 1,
                dimension: wgpu::TextureDimension::D2,
                format,
                usage,
                view_formats: &[],
            })
        };
        let sum = texture(
            "keyrig motion blur sum",
            SUM_FORMAT,
            wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::TEXTURE_BINDING,
        );
        let output = texture(
            "keyrig motion blur output",
            format,
            wgpu::TextureUsages::RENDER_ATTACHMENT
                | wgpu::TextureUsages::TEXTURE_BINDING
                | wgpu::TextureUsages::COPY_SRC,
        );
        Accumulator {
            device: device.clone(),
            queue: queue.clone(),
            layout,
            accumulate,
            resolve,
            size: (width, height),
            format,
            sum_view: sum.create_view(&Default::default()),
            output_view: output.create_view(&Default::default()),
            output,
            added: 0,
        }
    }

    /// The size and format this accumulator was built for.
    #[must_use]
    pub fn size_and_format(&self) -> ((u32, u32), wgpu::TextureFormat) {
        (self.size, self.format)
    }

    /// Starts a new average: the next [`Accumulator::add`] clears the sum.
    pub fn begin(&mut self) {
        self.added = 0;
    }

    /// Adds `weight` × the image in `source` (a single-sample view of this accumulator's size)
    /// to the sum, submitting the pass at once (so the next sub-frame may reuse the viewport).
    ///
    /// # Errors
    /// [`RenderError::Gpu`] for a weight that is not finite, or a GPU validation error (a
    /// view of another size).
    pub fn add(&mut self, source: &wgpu::TextureView, weight: f32) -> Result<(), RenderError> {
        if !weight.is_finite() {
            return Err(RenderError::Gpu(format!("motion blur weight {weight} is not finite")));
        }
        let load =
            if self.added == 0 { wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT) } else { wgpu::LoadOp::Load };
        let device = self.device.clone();
        let buffer = crate::gpu::with_error_scope(&device, || {
            self.encode_pass(
                "keyrig accumulate",
                &self.accumulate,
                source,
                &self.sum_view,
                load,
                Some(weight),
            )
        })?;
        self.queue.submit([buffer]);
        self.added += 1;
        Ok(())
    }

    /// Writes the sum into the output texture and returns it (to read back).
    ///
    /// # Errors
    /// [`RenderError::Gpu`] when nothing was added, or a GPU validation error.
    pub fn resolve(&mut self) -> Result<&wgpu::Texture, RenderError> {
        if self.added == 0 {
            return Err(RenderError::Gpu("motion blur: no sub-frame was rendered".into()));
        }
        let device = self.device.clone();
        let buffer = crate::gpu::with_error_scope(&device, || {
            let load = wgpu::LoadOp::Clear(wgpu::Color::TRANSPARENT);
            self.encode_pass(
                "keyrig accumulate resolve",
                &self.resolve,
                &self.sum_view,
                &self.output_view,
                load,
                None,
            )
        })?;
        self.queue.submit([buffer]);
        Ok(&self.output)
    }

    fn encode_pass(
        &self,
        label: &str,
        pipeline: &wgpu::RenderPipeline,
        source: &wgpu::TextureView,
        target: &wgpu::TextureView,
        load: wgpu::LoadOp<wgpu::Color>,
        blend_constant: Option<f32>,
    ) -> wgpu::CommandBuffer {
        let bind_group = self.device.create_bind_group(&wgpu::BindGroupDescriptor {
            label: Some(label),
            layout: &self.layout,
            entries: &[wgpu::BindGroupEntry {
                binding: 0,
                resource: wgpu::BindingResource::TextureView(source),
            }],
        });
        let mut encoder =
            self.device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some(label) });
        {
            let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
                label: Some(label),
                color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                    view: target,
                    depth_slice: None,
                    resolve_target: None,
                    ops: wgpu::Operations { load, store: wgpu::StoreOp::Store },
                })],
                depth_stencil_attachment: None,
                timestamp_writes: None,
                occlusion_query_set: None,
                multiview_mask: None,
            });
            pass.set_pipeline(pipeline);
            if let Some(weight) = blend_constant {
                let w = f64::from(weight);
                pass.set_blend_constant(wgpu::Color { r: w, g: w, b: w, a: w });
            }
            pass.set_bind_group(0, &bind_group, &[]);
            pass.draw(0..3, 0..1);
        }
        encoder.finish()
    }
}

/// The offsets, in frames from the frame itself, of `samples` sub-frames spread evenly across
/// a shutter open for `shutter` of the frame interval and centred on the frame (Blender's
/// "Center on Frame"): the first at `−shutter/2`, the last at `+shutter/2`, so the blur
/// covers exactly the motion within the shutter. One sample is the frame itself.
#[must_use]
pub fn subframe_offsets(samples: u32, shutter: f64) -> Vec<f64> {
    if samples <= 1 {
        return vec![0.0];
    }
    let last = f64::from(samples - 1);
    (0..samples).map(|i| shutter * (f64::from(i) / last - 0.5)).collect()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn subframes_span_the_shutter_centred_on_the_frame() {
        assert_eq!(subframe_offsets(1, 0.5), vec![0.0]);
        assert_eq!(subframe_offsets(0, 0.5), vec![0.0]);
        assert_eq!(subframe_offsets(2, 0.5), vec![-0.25, 0.25]);
        assert_eq!(subframe_offsets(5, 1.0), vec![-0.5, -0.25, 0.0, 0.25, 0.5]);
    }
}
