// keyrig MD2 vertex morphing on the GPU (seed text 001): lerp two frames' positions and
// normals. Output layout is the skinning output (`SkinnedVertex`, 32 bytes) so the draw pass
// treats morphed and skinned meshes alike.

struct SkinnedVertex {
    position: vec4<f32>,
    normal: vec4<f32>,
};

// MD2 vertex morphing: lerp between two frames' positions and normals.
struct MorphParams {
    vertex_count: u32,
    frame_a: u32,
    frame_b: u32,
    t: f32,
};

@group(0) @binding(0) var<uniform> morph_params: MorphParams;
// All frames, frame-major: frames[f * vertex_count + i].
@group(0) @binding(1) var<storage, read> frames: array<SkinnedVertex>;
@group(0) @binding(2) var<storage, read_write> morphed: array<SkinnedVertex>;

@compute @workgroup_size(64)
fn morph(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    let count = morph_params.vertex_count;
    if i >= count {
        return;
    }
    let a = frames[morph_params.frame_a * count + i];
    let b = frames[morph_params.frame_b * count + i];
    let t = morph_params.t;
    let p = mix(a.position.xyz, b.position.xyz, t);
    var n = mix(a.normal.xyz, b.normal.xyz, t);
    let len = length(n);
    if len > 1e-20 {
        n = n / len;
    }
    morphed[i] = SkinnedVertex(vec4<f32>(p, 1.0), vec4<f32>(n, 0.0));
}
