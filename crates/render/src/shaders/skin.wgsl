// keyrig GPU skinning: the four deformers of docs/design.md §5 as compute entry points.
//
// Every entry point reads the rest vertices (uploaded once), the per-joint frame data
// (uploaded every frame) and the static per-joint inverse bind matrices (uploaded once), and
// writes one `SkinnedVertex` (position, normal) per vertex. The draw pass binds the output
// buffer as its vertex buffer.
//
// Layouts (std430, must match `crate::skinning`):
//   SkinVertex    80 bytes: position.xyz, normal.xyz, 4 joints, 4 weights,
//                           rigid joint, bones-blending joint k, bones-blending t
//   JointFrame   240 bytes: M(j), dual quaternion of M(j) (real, dual),
//                           B(k) = F(p(k))·R(k), T(k) as a quaternion (x, y, z, w),
//                           normal matrix of M(j) (inverse-transpose of its 3×3)
//   bind_from_model 64 bytes per joint: A(k)⁻¹ (static)
//   SkinnedVertex 32 bytes: position.xyz 1, normal.xyz 0

struct SkinVertex {
    position: vec4<f32>,
    normal: vec4<f32>,
    joints: vec4<u32>,
    weights: vec4<f32>,
    rigid_joint: u32,
    blend_joint: u32,
    blend_t: f32,
    _pad: u32,
};

struct JointFrame {
    model_from_bind: mat4x4<f32>,
    dq_real: vec4<f32>,
    dq_dual: vec4<f32>,
    blend_base: mat4x4<f32>,
    blend_rotation: vec4<f32>,
    normal_from_bind: mat4x4<f32>,
};

struct SkinnedVertex {
    position: vec4<f32>,
    normal: vec4<f32>,
};

struct SkinParams {
    vertex_count: u32,
    joint_count: u32,
    _pad0: u32,
    _pad1: u32,
};

@group(0) @binding(0) var<uniform> params: SkinParams;
@group(0) @binding(1) var<storage, read> vertices: array<SkinVertex>;
@group(0) @binding(2) var<storage, read> joints: array<JointFrame>;
@group(0) @binding(3) var<storage, read> bind_from_model: array<mat4x4<f32>>;
@group(0) @binding(4) var<storage, read_write> skinned: array<SkinnedVertex>;

fn joint_index(j: u32) -> u32 {
    // Indices are checked on the CPU before upload; the clamp keeps a bad index from ever
    // reading out of bounds.
    return min(j, params.joint_count - 1u);
}

fn write_out(i: u32, p: vec3<f32>, n: vec3<f32>) {
    let len = length(n);
    var unit_n = n;
    if len > 1e-20 {
        unit_n = n / len;
    }
    skinned[i] = SkinnedVertex(vec4<f32>(p, 1.0), vec4<f32>(unit_n, 0.0));
}

// Rotates v by the unit quaternion q = (x, y, z, w).
fn quat_rotate(q: vec4<f32>, v: vec3<f32>) -> vec3<f32> {
    let t = 2.0 * cross(q.xyz, v);
    return v + q.w * t + cross(q.xyz, t);
}

// slerp(I, q, t) for a unit quaternion q, the short way round; falls back to a normalized
// lerp when q is within ~0.0002 rad of the identity (sin θ would vanish).
fn slerp_from_identity(q_in: vec4<f32>, t: f32) -> vec4<f32> {
    var q = q_in;
    if q.w < 0.0 {
        q = -q;
    }
    let cos_theta = clamp(q.w, -1.0, 1.0);
    if cos_theta > 0.9995 {
        return normalize(mix(vec4<f32>(0.0, 0.0, 0.0, 1.0), q, t));
    }
    let theta = acos(cos_theta);
    let sin_theta = sin(theta);
    let a = sin((1.0 - t) * theta) / sin_theta;
    let b = sin(t * theta) / sin_theta;
    return vec4<f32>(0.0, 0.0, 0.0, a) + b * q;
}

// 1. Rigid: v' = M(j)·v with the vertex's single joint.
@compute @workgroup_size(64)
fn skin_rigid(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= params.vertex_count {
        return;
    }
    let v = vertices[i];
    let jf = joints[joint_index(v.rigid_joint)];
    let p = (jf.model_from_bind * vec4<f32>(v.position.xyz, 1.0)).xyz;
    let n = (jf.normal_from_bind * vec4<f32>(v.normal.xyz, 0.0)).xyz;
    write_out(i, p, n);
}

// 2. Linear blend: v' = Σ wᵢ·M(jᵢ)·v (normals by the blended normal matrices, renormalized).
@compute @workgroup_size(64)
fn skin_linear(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= params.vertex_count {
        return;
    }
    let v = vertices[i];
    var m = mat4x4<f32>(vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0), vec4<f32>(0.0));
    var nm = m;
    for (var k = 0u; k < 4u; k = k + 1u) {
        let w = v.weights[k];
        if w != 0.0 {
            let jf = joints[joint_index(v.joints[k])];
            m = m + jf.model_from_bind * w;
            nm = nm + jf.normal_from_bind * w;
        }
    }
    let p = (m * vec4<f32>(v.position.xyz, 1.0)).xyz;
    let n = (nm * vec4<f32>(v.normal.xyz, 0.0)).xyz;
    write_out(i, p, n);
}

// 3. Bones blending (Kavan & Žára 2003):
//    v' = F(j)·R(k)·slerp(I, T(k), t)·A(k)⁻¹·v, with F(j)·R(k) = blend_base of joint k.
@compute @workgroup_size(64)
fn skin_bones_blending(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= params.vertex_count {
        return;
    }
    let v = vertices[i];
    let k = joint_index(v.blend_joint);
    let jf = joints[k];
    let a_inv = bind_from_model[k];
    let q = slerp_from_identity(jf.blend_rotation, v.blend_t);
    let local_p = quat_rotate(q, (a_inv * vec4<f32>(v.position.xyz, 1.0)).xyz);
    let local_n = quat_rotate(q, (a_inv * vec4<f32>(v.normal.xyz, 0.0)).xyz);
    let p = (jf.blend_base * vec4<f32>(local_p, 1.0)).xyz;
    let n = (jf.blend_base * vec4<f32>(local_n, 0.0)).xyz;
    write_out(i, p, n);
}

// 4. Dual quaternion (Kavan et al. 2008): blend the joints' unit dual quaternions with signs
//    aligned to the dominant influence, normalize, transform.
@compute @workgroup_size(64)
fn skin_dual_quaternion(@builtin(global_invocation_id) gid: vec3<u32>) {
    let i = gid.x;
    if i >= params.vertex_count {
        return;
    }
    let v = vertices[i];
    // Dominant influence: the largest weight (first one on ties).
    var dominant = 0u;
    for (var k = 1u; k < 4u; k = k + 1u) {
        if v.weights[k] > v.weights[dominant] {
            dominant = k;
        }
    }
    let pivot = joints[joint_index(v.joints[dominant])].dq_real;
    var real = vec4<f32>(0.0);
    var dual = vec4<f32>(0.0);
    for (var k = 0u; k < 4u; k = k + 1u) {
        let w = v.weights[k];
        if w != 0.0 {
            let jf = joints[joint_index(v.joints[k])];
            var s = w;
            if dot(jf.dq_real, pivot) < 0.0 {
                s = -w;
            }
            real = real + s * jf.dq_real;
            dual = dual + s * jf.dq_dual;
        }
    }
    let len = length(real);
    var p = v.position.xyz;
    var n = v.normal.xyz;
    if len > 1e-20 {
        real = real / len;
        dual = dual / len;
        // translation t = 2·(dual·conj(real)).xyz
        let t = 2.0 * (real.w * dual.xyz - dual.w * real.xyz + cross(real.xyz, dual.xyz));
        p = quat_rotate(real, p) + t;
        n = quat_rotate(real, n);
    }
    write_out(i, p, n);
}
