// Motion blur (accumulate.rs): one full-screen triangle copies a texture pixel for pixel.
//
// Accumulating: the source is a rendered sub-frame (an sRGB texture, so the load returns
// linear colour) and the target a 16-bit float sum; the pipeline's blend adds
// source × constant (the sub-frame's weight 1/N) to what the sum holds.
// Resolving: the source is the sum and the target the sRGB output image (the store encodes).

@group(0) @binding(0) var source: texture_2d<f32>;

@vertex
fn vs_full_screen(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    // (0,0), (2,0), (0,2) in a 0..1 square's units: one triangle covering clip space.
    let x = f32((index << 1u) & 2u);
    let y = f32(index & 2u);
    return vec4<f32>(x * 2.0 - 1.0, 1.0 - y * 2.0, 0.0, 1.0);
}

@fragment
fn fs_copy(@builtin(position) position: vec4<f32>) -> @location(0) vec4<f32> {
    return textureLoad(source, vec2<i32>(position.xy), 0);
}
