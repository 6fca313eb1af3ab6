// Flat fills and the viewport's image, drawn into egui's render pass by paint callbacks.
//
// fs_blit copies the 3D viewport's finished image into egui's render pass, inside the viewport's rect
// (egui sets the viewport transform to that rect before a paint callback). One triangle covers
// the rect; no blending, no colour conversion beyond the texture view's own: a CPU rasterizer
// shades this for a fraction of what egui's own textured-mesh shader costs (docs/rendering.md).

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) uv: vec2<f32>,
};

@vertex
fn vs_blit(@builtin(vertex_index) i: u32) -> VsOut {
    // (0, 0), (2, 0), (0, 2): a triangle whose inside holds the unit square.
    let p = vec2<f32>(f32((i << 1u) & 2u), f32(i & 2u));
    var out: VsOut;
    out.clip = vec4<f32>(p * 2.0 - 1.0, 0.0, 1.0);
    // Clip space y points up, texture v down.
    out.uv = vec2<f32>(p.x, 1.0 - p.y);
    return out;
}

@group(0) @binding(0) var image: texture_2d<f32>;
@group(0) @binding(1) var image_sampler: sampler;

@fragment
fn fs_blit(in: VsOut) -> @location(0) vec4<f32> {
    return vec4<f32>(textureSample(image, image_sampler, in.uv).rgb, 1.0);
}

// The image as premultiplied RGBA (a viewport cleared to transparent black), for a pipeline
// that blends it over what egui drew beneath (the reference image).
@fragment
fn fs_blit_over(in: VsOut) -> @location(0) vec4<f32> {
    return textureSample(image, image_sampler, in.uv);
}

// An opaque fill: the pipeline's blend state multiplies this output by the blend constant
// (source factor: the constant, destination factor: zero), so the pixel becomes the constant.
@fragment
fn fs_flat_fill() -> @location(0) vec4<f32> {
    return vec4<f32>(1.0);
}
