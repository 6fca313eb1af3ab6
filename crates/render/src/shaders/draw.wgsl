// keyrig mesh drawing: skinned vertices (the compute passes' output) lit by the scene's lights.
//
// Lighting (all in world space, linear RGB, Y up):
//   albedo = object colour × base-colour texture at the vertex's texture coordinate (the
//            texture is sRGB, so the sample is linear; a 1×1 white one when there is none)
//   colour = albedo · (ambient + Σ_lights radiance · max(n·l, 0)) + specular
//   directional: radiance = colour·intensity, l = −direction
//   point:       radiance = colour·intensity / d²
//   spot:        point radiance · cone(θ), cone = 1 inside the inner angle, 0 outside the
//                cut-off, ((cos θ − cos cut) / (cos inner − cos cut))^dropoff in between.
//   range r > 0 (point and spot): radiance · clamp(1 − (d/r)⁴, 0, 1), KHR_lights_punctual's
//                recommended window, so the light ends smoothly at d = r.
//   alpha = the object's opacity (colour.a): the translucent pipeline blends with it.

const MAX_LIGHTS: u32 = 8u;

// Set for a target whose format is not sRGB (the editor's window, when the viewport is drawn
// straight into egui's render pass): the fragment shaders then encode their linear colour with
// the sRGB transfer function (IEC 61966-2-1), as an sRGB target does on write.
override ENCODE_SRGB: bool = false;

// The colour a fragment shader writes: `c` (linear), encoded when the target is not sRGB.
// The curve 1.055·x^(1/2.4) − 0.055 is approximated from three square roots (Ian Taylor's
// fit, as published on chilliant.com, "sRGB Approximations for HLSL"): within a quarter of an
// 8-bit step everywhere, and far cheaper than pow on a CPU rasterizer.
fn target_colour(c: vec4<f32>) -> vec4<f32> {
    if !ENCODE_SRGB {
        return c;
    }
    let x = clamp(c.rgb, vec3<f32>(0.0), vec3<f32>(1.0));
    let s1 = sqrt(x);
    let s2 = sqrt(s1);
    let s3 = sqrt(s2);
    let curve = 0.662002687 * s1 + 0.684122060 * s2 - 0.323583601 * s3 - 0.0225411470 * x;
    return vec4<f32>(select(curve, x * 12.92, x <= vec3<f32>(0.0031308)), c.a);
}
const KIND_DIRECTIONAL: u32 = 0u;
const KIND_POINT: u32 = 1u;
const KIND_SPOT: u32 = 2u;

struct Light {
    // xyz position, w = kind
    position: vec4<f32>,
    // xyz unit direction the light shines in
    direction: vec4<f32>,
    // rgb colour × intensity
    radiance: vec4<f32>,
    // cos(cut-off), cos(inner), dropoff, range (0: none)
    spot: vec4<f32>,
};

struct Globals {
    clip_from_world: mat4x4<f32>,
    camera_position: vec4<f32>,
    ambient: vec4<f32>,
    // x = number of lights
    counts: vec4<u32>,
    lights: array<Light, 8>,
    // linear RGB of the background (the fill of a frame drawn into another pass)
    background: vec4<f32>,
};

struct Object {
    world_from_model: mat4x4<f32>,
    // inverse-transpose of world_from_model's linear part (as a 4×4)
    normal_from_model: mat4x4<f32>,
    colour: vec4<f32>,
    // x = selected (0/1)
    flags: vec4<f32>,
    // a ghost's tint (rgb) and opacity (w)
    tint: vec4<f32>,
};

@group(0) @binding(0) var<uniform> globals: Globals;
@group(1) @binding(0) var<uniform> object: Object;
@group(2) @binding(0) var base_colour_texture: texture_2d<f32>;
@group(2) @binding(1) var base_colour_sampler: sampler;

struct VsOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) world_position: vec3<f32>,
    @location(1) normal: vec3<f32>,
    @location(2) uv: vec2<f32>,
};

@vertex
fn vs_mesh(
    @location(0) position: vec4<f32>,
    @location(1) normal: vec4<f32>,
    @location(2) uv: vec2<f32>,
) -> VsOut {
    let world = object.world_from_model * vec4<f32>(position.xyz, 1.0);
    var out: VsOut;
    out.clip = globals.clip_from_world * world;
    out.world_position = world.xyz;
    out.normal = (object.normal_from_model * vec4<f32>(normal.xyz, 0.0)).xyz;
    out.uv = uv;
    return out;
}

// Untextured items (most of a scene: everything but imported textured models) skip the
// texture sample, about a sixth of a lit pixel's cost on a CPU rasterizer.
@fragment
fn fs_lit(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    // Sampled first, in uniform control flow (implicit derivatives pick the mip level).
    let texel = textureSample(base_colour_texture, base_colour_sampler, in.uv);
    return target_colour(lit(in, front, texel.rgb));
}

@fragment
fn fs_lit_untextured(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    return target_colour(lit(in, front, vec3<f32>(1.0)));
}

// Lit colour of a point whose base-colour texel is `texel`.
fn lit(in: VsOut, front: bool, texel: vec3<f32>) -> vec4<f32> {
    var n = normalize(in.normal);
    if !front {
        n = -n;
    }
    let to_eye = normalize(globals.camera_position.xyz - in.world_position);
    let albedo = object.colour.rgb * texel;
    var diffuse = globals.ambient.rgb;
    var specular = vec3<f32>(0.0);
    let count = min(globals.counts.x, MAX_LIGHTS);
    for (var i = 0u; i < count; i = i + 1u) {
        // Fields are read in place (a copy of the whole Light costs a CPU rasterizer dearly).
        let position = globals.lights[i].position;
        let direction = globals.lights[i].direction.xyz;
        let kind = u32(position.w);
        let offset = in.world_position - position.xyz;
        let inv_d = inverseSqrt(max(dot(offset, offset), 1e-8));
        let is_directional = kind == KIND_DIRECTIONAL;
        let l = select(-offset * inv_d, -direction, is_directional);
        // 1/d² for point and spot lights.
        var falloff = select(inv_d * inv_d, 1.0, is_directional);
        if kind == KIND_SPOT {
            let spot = globals.lights[i].spot;
            let cos_theta = dot(offset * inv_d, direction);
            let s = clamp((cos_theta - spot.x) / max(spot.y - spot.x, 1e-6), 0.0, 1.0);
            var cone = select(pow(s, max(spot.z, 0.0)), 1.0, cos_theta >= spot.y);
            cone = select(cone, 0.0, cos_theta <= spot.x);
            falloff = falloff * cone;
        }
        let range = globals.lights[i].spot.w;
        if range > 0.0 {
            let q = (1.0 / inv_d) / range;
            falloff = falloff * clamp(1.0 - q * q * q * q, 0.0, 1.0);
        }
        let radiance = globals.lights[i].radiance.rgb * falloff;
        let n_dot_l = max(dot(n, l), 0.0);
        diffuse = diffuse + radiance * n_dot_l;
        // Blinn-Phong (n·h)^32 by five squarings, only where the light reaches the surface.
        let h = normalize(l + to_eye);
        var s32 = max(dot(n, h), 0.0);
        s32 = s32 * s32;
        s32 = s32 * s32;
        s32 = s32 * s32;
        s32 = s32 * s32;
        s32 = s32 * s32;
        specular = specular + radiance * select(0.0, 0.25 * s32, n_dot_l > 0.0);
    }
    var colour = albedo * diffuse + specular;
    if object.flags.x > 0.5 {
        // Selection: a light orange tint where the surface faces the eye, glowing towards the
        // silhouette; never more than 70 %, so the shading, texture and pose stay visible (a
        // thin, dark figure such as an MD2 model would otherwise turn into a flat silhouette).
        let facing = abs(dot(n, to_eye));
        let rim = (1.0 - facing) * (1.0 - facing);
        colour = mix(colour, vec3<f32>(1.0, 0.45, 0.05), 0.12 + 0.58 * rim);
    }
    return vec4<f32>(colour, object.colour.a);
}

// Onion-skin ghosts: lit without the texture, mixed half-way towards the ghost's tint, and
// blended over the scene with its opacity.
@fragment
fn fs_ghost(in: VsOut, @builtin(front_facing) front: bool) -> @location(0) vec4<f32> {
    var n = normalize(in.normal);
    if !front {
        n = -n;
    }
    let to_eye = normalize(globals.camera_position.xyz - in.world_position);
    var diffuse = globals.ambient.rgb;
    let count = min(globals.counts.x, MAX_LIGHTS);
    for (var i = 0u; i < count; i = i + 1u) {
        let position = globals.lights[i].position;
        let direction = globals.lights[i].direction.xyz;
        let offset = in.world_position - position.xyz;
        let inv_d = inverseSqrt(max(dot(offset, offset), 1e-8));
        let is_directional = u32(position.w) == KIND_DIRECTIONAL;
        let l = select(-offset * inv_d, -direction, is_directional);
        let falloff = select(inv_d * inv_d, 1.0, is_directional);
        diffuse = diffuse + globals.lights[i].radiance.rgb * falloff * max(dot(n, l), 0.0);
    }
    // A rim keeps the ghost's outline readable where it overlaps the current pose.
    let rim = 1.0 - abs(dot(n, to_eye));
    let shaded = object.colour.rgb * clamp(diffuse, vec3<f32>(0.25), vec3<f32>(1.0));
    let colour = mix(shaded, object.tint.rgb, 0.55 + 0.3 * rim);
    return target_colour(vec4<f32>(colour, object.tint.w));
}

// Wireframe and points: the object's colour (orange when selected), unlit.
@fragment
fn fs_flat(in: VsOut) -> @location(0) vec4<f32> {
    if object.flags.x > 0.5 {
        return target_colour(vec4<f32>(1.0, 0.45, 0.05, 1.0));
    }
    return target_colour(vec4<f32>(object.colour.rgb, 1.0));
}

// Overlay lines (grid, bones, motion paths): world-space positions with a colour.
struct LineOut {
    @builtin(position) clip: vec4<f32>,
    @location(0) colour: vec4<f32>,
};

@vertex
fn vs_line(@location(0) position: vec4<f32>, @location(1) colour: vec4<f32>) -> LineOut {
    var out: LineOut;
    out.clip = globals.clip_from_world * vec4<f32>(position.xyz, 1.0);
    out.colour = colour;
    return out;
}

@fragment
fn fs_line(in: LineOut) -> @location(0) vec4<f32> {
    return target_colour(in.colour);
}

// The background over the whole viewport: one triangle that covers it, for a frame drawn into
// a render pass whose colour was not cleared for it (the editor's window); it writes no depth.
@vertex
fn vs_fill(@builtin(vertex_index) index: u32) -> @builtin(position) vec4<f32> {
    let x = f32(index & 1u) * 4.0 - 1.0;
    let y = f32(index >> 1u) * 4.0 - 1.0;
    return vec4<f32>(x, y, 1.0, 1.0);
}

// The background is written as given: `Renderer::write_globals` encodes it beforehand for a
// target that does not encode on write (one value, not a curve per pixel).
@fragment
fn fs_fill() -> @location(0) vec4<f32> {
    return vec4<f32>(globals.background.rgb, 1.0);
}
