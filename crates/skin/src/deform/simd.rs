//! x86-64 kernels that use AVX2 and FMA when the CPU has them (checked at run time; the
//! portable glam paths in the job files run otherwise). Same formulas, fused multiply-adds
//! and 256-bit registers: a 3×4 palette matrix is two registers, (x | y) and (z | t), so
//! blending one influence is two FMAs instead of eight SSE multiplies and adds.

use std::arch::x86_64::*;

use glam::{Affine3A, Vec3, Vec3A, Vec4};

use super::bones_blending::sin_cos_quarter_turn;
use super::BonesBlendVertex;
use crate::dual_quat::DualQuat;
use crate::pose::BonesBlendJoint;

/// Whether this CPU can run the kernels below.
pub(crate) fn available() -> bool {
    is_x86_feature_detected!("avx2") && is_x86_feature_detected!("fma")
}

/// A palette matrix as ((x_axis | y_axis), (z_axis | translation)).
pub(crate) type PackedAffine = [__m256; 2];

/// Packs a palette (O(joints), once per run).
///
/// # Safety
/// The CPU must support AVX2 and FMA ([`available`]).
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn pack_palette(palette: &[Affine3A]) -> Vec<PackedAffine> {
    palette
        .iter()
        .map(|m| {
            [
                _mm256_set_m128(m.matrix3.y_axis.into(), m.matrix3.x_axis.into()),
                _mm256_set_m128(m.translation.into(), m.matrix3.z_axis.into()),
            ]
        })
        .collect()
}

/// Linear blend of one chunk: v' = (Σ wᵢ·M(jᵢ))·v, n' = (Σ wᵢ·M(jᵢ))₃ₓ₃·n.
///
/// # Safety
/// The CPU must support AVX2 and FMA; every joint index must be in `palette` (validated).
#[target_feature(enable = "avx2,fma")]
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn linear_blend_chunk<const N: usize>(
    palette: &[PackedAffine],
    joints: &[[u16; N]],
    weights: &[[f32; N]],
    positions: &[Vec3],
    normals: &[Vec3],
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
) {
    let inputs = joints.iter().zip(weights).zip(positions.iter().zip(normals));
    for (((js, ws), (p, n)), (op, on)) in inputs.zip(out_positions.iter_mut().zip(out_normals.iter_mut())) {
        let m = &palette[js[0] as usize];
        let w = _mm256_set1_ps(ws[0]);
        let mut xy = _mm256_mul_ps(m[0], w);
        let mut zt = _mm256_mul_ps(m[1], w);
        for i in 1..N {
            let m = &palette[js[i] as usize];
            let w = _mm256_set1_ps(ws[i]);
            xy = _mm256_fmadd_ps(m[0], w, xy);
            zt = _mm256_fmadd_ps(m[1], w, zt);
        }
        let (x, y) = (_mm256_castps256_ps128(xy), _mm256_extractf128_ps::<1>(xy));
        let (z, t) = (_mm256_castps256_ps128(zt), _mm256_extractf128_ps::<1>(zt));
        let pos = _mm_fmadd_ps(
            x,
            _mm_set1_ps(p.x),
            _mm_fmadd_ps(y, _mm_set1_ps(p.y), _mm_fmadd_ps(z, _mm_set1_ps(p.z), t)),
        );
        let nrm = _mm_fmadd_ps(
            x,
            _mm_set1_ps(n.x),
            _mm_fmadd_ps(y, _mm_set1_ps(n.y), _mm_mul_ps(z, _mm_set1_ps(n.z))),
        );
        *op = Vec3A::from(pos).into();
        *on = Vec3A::from(nrm).into();
    }
}

/// A dual quaternion as one register (real | dual).
pub(crate) type PackedDualQuat = __m256;

/// # Safety
/// The CPU must support AVX2 and FMA ([`available`]).
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn pack_dual_quaternions(dqs: &[DualQuat]) -> Vec<PackedDualQuat> {
    dqs.iter().map(|q| _mm256_set_m128(Vec4::from(q.dual).into(), Vec4::from(q.real).into())).collect()
}

/// Dual quaternion blend of one chunk (see `dual_quaternion.rs` for the formula).
///
/// # Safety
/// The CPU must support AVX2 and FMA; every joint index must be in `dqs` (validated).
#[target_feature(enable = "avx2,fma")]
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn dual_quaternion_chunk<const N: usize>(
    dqs: &[PackedDualQuat],
    joints: &[[u16; N]],
    weights: &[[f32; N]],
    positions: &[Vec3],
    normals: &[Vec3],
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
) {
    let inputs = joints.iter().zip(weights).zip(positions.iter().zip(normals));
    for (((js, ws), (p, n)), (op, on)) in inputs.zip(out_positions.iter_mut().zip(out_normals.iter_mut())) {
        // Pivot: the real part of the largest-weight influence (first on ties).
        let mut pivot = _mm256_castps256_ps128(dqs[js[0] as usize]);
        let mut best = ws[0];
        for i in 1..N {
            let larger = ws[i] > best;
            best = if larger { ws[i] } else { best };
            let mask = _mm_castsi128_ps(_mm_set1_epi32(-(larger as i32)));
            pivot = _mm_blendv_ps(pivot, _mm256_castps256_ps128(dqs[js[i] as usize]), mask);
        }
        let sign_bit = _mm256_set1_ps(-0.0);
        let mut blend = _mm256_setzero_ps();
        for i in 0..N {
            let q = dqs[js[i] as usize];
            // dot(real, pivot) in every lane, then its sign onto the weight.
            let d = _mm_dp_ps::<0xFF>(_mm256_castps256_ps128(q), pivot);
            let sign = _mm256_and_ps(_mm256_set_m128(d, d), sign_bit);
            let w = _mm256_xor_ps(_mm256_set1_ps(ws[i]), sign);
            blend = _mm256_fmadd_ps(q, w, blend);
        }
        let real = _mm256_castps256_ps128(blend);
        let dual = _mm256_extractf128_ps::<1>(blend);
        // 1/|real| by rsqrt and one Newton step (relative error ~1e-7).
        let len2 = _mm_dp_ps::<0xFF>(real, real);
        let r0 = _mm_rsqrt_ps(len2);
        let inv = _mm_mul_ps(
            _mm_mul_ps(_mm_set1_ps(0.5), r0),
            _mm_fnmadd_ps(_mm_mul_ps(len2, r0), r0, _mm_set1_ps(3.0)),
        );
        let real = Vec4::from(_mm_mul_ps(real, inv));
        let dual = Vec4::from(_mm_mul_ps(dual, inv));
        let r = Vec3A::from_vec4(real);
        let d = Vec3A::from_vec4(dual);
        let (rw, dw) = (real.w, dual.w);
        let p = Vec3A::from(*p);
        let n = Vec3A::from(*n);
        let translation = 2.0 * (rw * d - dw * r + r.cross(d));
        *op = (p + 2.0 * r.cross(r.cross(p) + rw * p) + translation).into();
        *on = (n + 2.0 * r.cross(r.cross(n) + rw * n)).into();
    }
}

/// A joint's bones-blending terms B₀, B₁, B₂ (packed like the palette) and θ/2.
pub(crate) struct PackedBonesBlend {
    terms: [PackedAffine; 3],
    half_angle: f32,
}

/// # Safety
/// The CPU must support AVX2 and FMA ([`available`]).
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn pack_bones_blending(joints: &[BonesBlendJoint]) -> Vec<PackedBonesBlend> {
    joints
        .iter()
        .map(|k| PackedBonesBlend {
            terms: k.blend_terms.map(|m| {
                [
                    _mm256_set_m128(m.matrix3.y_axis.into(), m.matrix3.x_axis.into()),
                    _mm256_set_m128(m.translation.into(), m.matrix3.z_axis.into()),
                ]
            }),
            half_angle: k.half_angle,
        })
        .collect()
}

/// Bones blending of one chunk: v' = (B₀ + sin φ·B₁ + (1 − cos φ)·B₂)·v, φ = t·θ.
///
/// # Safety
/// The CPU must support AVX2 and FMA; every joint index must be in `joints` (validated).
#[target_feature(enable = "avx2,fma")]
pub(crate) unsafe fn bones_blending_chunk(
    joints: &[PackedBonesBlend],
    bindings: &[BonesBlendVertex],
    positions: &[Vec3],
    normals: &[Vec3],
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
) {
    // φ/2 = t·θ/2 for 8 vertices at a time: sin φ = 2·s·c and 1 − cos φ = 2·s² by the same
    // polynomials as the portable path, in 256-bit lanes.
    let mut sin = [0.0f32; 8];
    let mut versin = [0.0f32; 8];
    for start in (0..bindings.len()).step_by(8) {
        let end = (start + 8).min(bindings.len());
        let count = end - start;
        if count == 8 {
            let b = &bindings[start..end];
            let f = |l: usize| b[l].t * joints[b[l].joint as usize].half_angle;
            let x = _mm256_setr_ps(f(0), f(1), f(2), f(3), f(4), f(5), f(6), f(7));
            let (s, c) = sin_cos_quarter_turn_x8(x);
            let two = _mm256_set1_ps(2.0);
            _mm256_storeu_ps(sin.as_mut_ptr(), _mm256_mul_ps(two, _mm256_mul_ps(s, c)));
            _mm256_storeu_ps(versin.as_mut_ptr(), _mm256_mul_ps(two, _mm256_mul_ps(s, s)));
        } else {
            for l in 0..count {
                let b = &bindings[start + l];
                let (s, c) = sin_cos_quarter_turn(b.t * joints[b.joint as usize].half_angle);
                sin[l] = 2.0 * s * c;
                versin[l] = 2.0 * s * s;
            }
        }
        for l in 0..count {
            let v = start + l;
            let (p, n) = (positions[v], normals[v]);
            let k = &joints[bindings[v].joint as usize];
            let sin = _mm256_set1_ps(sin[l]);
            let versin = _mm256_set1_ps(versin[l]);
            let [b0, b1, b2] = &k.terms;
            let xy = _mm256_fmadd_ps(b2[0], versin, _mm256_fmadd_ps(b1[0], sin, b0[0]));
            let zt = _mm256_fmadd_ps(b2[1], versin, _mm256_fmadd_ps(b1[1], sin, b0[1]));
            let (x, y) = (_mm256_castps256_ps128(xy), _mm256_extractf128_ps::<1>(xy));
            let (z, t) = (_mm256_castps256_ps128(zt), _mm256_extractf128_ps::<1>(zt));
            let pos = _mm_fmadd_ps(
                x,
                _mm_set1_ps(p.x),
                _mm_fmadd_ps(y, _mm_set1_ps(p.y), _mm_fmadd_ps(z, _mm_set1_ps(p.z), t)),
            );
            let nrm = _mm_fmadd_ps(
                x,
                _mm_set1_ps(n.x),
                _mm_fmadd_ps(y, _mm_set1_ps(n.y), _mm_mul_ps(z, _mm_set1_ps(n.z))),
            );
            out_positions[v] = Vec3A::from(pos).into();
            out_normals[v] = Vec3A::from(nrm).into();
        }
    }
}

/// [`sin_cos_quarter_turn`] in 8 lanes (the same Taylor polynomials, evaluated by Horner's rule
/// with fused multiply-adds).
#[inline]
#[target_feature(enable = "avx2,fma")]
fn sin_cos_quarter_turn_x8(x: __m256) -> (__m256, __m256) {
    let x2 = _mm256_mul_ps(x, x);
    let horner = |coefficients: &[f32]| {
        let mut acc = _mm256_set1_ps(coefficients[0]);
        for &c in &coefficients[1..] {
            acc = _mm256_fmadd_ps(acc, x2, _mm256_set1_ps(c));
        }
        acc
    };
    let s = _mm256_mul_ps(
        x,
        horner(&[
            1.0 / 6_227_020_800.0,
            -1.0 / 39_916_800.0,
            1.0 / 362_880.0,
            -1.0 / 5040.0,
            1.0 / 120.0,
            -1.0 / 6.0,
            1.0,
        ]),
    );
    let c = horner(&[
        -1.0 / 87_178_291_200.0,
        1.0 / 479_001_600.0,
        -1.0 / 3_628_800.0,
        1.0 / 40_320.0,
        -1.0 / 720.0,
        1.0 / 24.0,
        -0.5,
        1.0,
    ]);
    (s, c)
}

/// Writes 8 vertices given as x, y and z registers to 24 floats x₀y₀z₀x₁… at `out`.
///
/// # Safety
/// `out` must be valid for writing 24 floats; the CPU must support AVX2.
#[inline]
#[target_feature(enable = "avx2,fma")]
unsafe fn store_interleaved(out: *mut f32, x: __m256, y: __m256, z: __m256) {
    // Output register r holds floats 8r..8r+8; float f is component f % 3 of vertex f / 3.
    let idx = |r: i32, c: i32| {
        let lane = |i: i32| {
            let f = 8 * r + i;
            if f % 3 == c {
                f / 3
            } else {
                0
            }
        };
        _mm256_setr_epi32(lane(0), lane(1), lane(2), lane(3), lane(4), lane(5), lane(6), lane(7))
    };
    for r in 0..3 {
        let xs = _mm256_permutevar8x32_ps(x, idx(r, 0));
        let ys = _mm256_permutevar8x32_ps(y, idx(r, 1));
        let zs = _mm256_permutevar8x32_ps(z, idx(r, 2));
        // Lane i takes x, y or z by (8r + i) % 3.
        let pick = |c: i32| {
            let m = |i: i32| if (8 * r + i) % 3 == c { -1 } else { 0 };
            _mm256_castsi256_ps(_mm256_setr_epi32(m(0), m(1), m(2), m(3), m(4), m(5), m(6), m(7)))
        };
        let v = _mm256_blendv_ps(_mm256_blendv_ps(zs, ys, pick(1)), xs, pick(0));
        // SAFETY: floats 8r..8r+8 of the 24 the caller provides.
        unsafe { _mm256_storeu_ps(out.add(8 * r as usize), v) };
    }
}

/// Transposes 8 rows of 8 floats (row l = lane l's dual quaternion) into 8 columns
/// (column c = component c of every lane).
#[inline]
#[target_feature(enable = "avx2,fma")]
fn transpose8(r: [__m256; 8]) -> [__m256; 8] {
    let t0 = _mm256_unpacklo_ps(r[0], r[1]);
    let t1 = _mm256_unpackhi_ps(r[0], r[1]);
    let t2 = _mm256_unpacklo_ps(r[2], r[3]);
    let t3 = _mm256_unpackhi_ps(r[2], r[3]);
    let t4 = _mm256_unpacklo_ps(r[4], r[5]);
    let t5 = _mm256_unpackhi_ps(r[4], r[5]);
    let t6 = _mm256_unpacklo_ps(r[6], r[7]);
    let t7 = _mm256_unpackhi_ps(r[6], r[7]);
    let u0 = _mm256_shuffle_ps::<0x44>(t0, t2);
    let u1 = _mm256_shuffle_ps::<0xEE>(t0, t2);
    let u2 = _mm256_shuffle_ps::<0x44>(t1, t3);
    let u3 = _mm256_shuffle_ps::<0xEE>(t1, t3);
    let u4 = _mm256_shuffle_ps::<0x44>(t4, t6);
    let u5 = _mm256_shuffle_ps::<0xEE>(t4, t6);
    let u6 = _mm256_shuffle_ps::<0x44>(t5, t7);
    let u7 = _mm256_shuffle_ps::<0xEE>(t5, t7);
    [
        _mm256_permute2f128_ps::<0x20>(u0, u4),
        _mm256_permute2f128_ps::<0x20>(u1, u5),
        _mm256_permute2f128_ps::<0x20>(u2, u6),
        _mm256_permute2f128_ps::<0x20>(u3, u7),
        _mm256_permute2f128_ps::<0x31>(u0, u4),
        _mm256_permute2f128_ps::<0x31>(u1, u5),
        _mm256_permute2f128_ps::<0x31>(u2, u6),
        _mm256_permute2f128_ps::<0x31>(u3, u7),
    ]
}

/// Dual quaternion skinning of one chunk, 8 vertices at a time in structure-of-arrays form
/// (each register holds one component of 8 vertices), the remainder one at a time with
/// [`dual_quaternion_chunk`]. Same formula and sign rule.
///
/// # Safety
/// The CPU must support AVX2 and FMA; every joint index must be in `dqs` (validated).
#[target_feature(enable = "avx2,fma")]
#[allow(clippy::too_many_arguments)]
pub(crate) unsafe fn dual_quaternion_chunk_soa<const N: usize>(
    dqs: &[PackedDualQuat],
    joints: &[[u16; N]],
    weights: &[[f32; N]],
    positions: &[Vec3],
    normals: &[Vec3],
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
) {
    let full = out_positions.len() / 8 * 8;
    let sign_bit = _mm256_set1_ps(-0.0);
    // Gather offsets (in floats) of one component of 8 consecutive Vec3s / [f32; N]s.
    let stride3 = _mm256_setr_epi32(0, 3, 6, 9, 12, 15, 18, 21);
    let n = N as i32;
    let stride_n = _mm256_setr_epi32(0, n, 2 * n, 3 * n, 4 * n, 5 * n, 6 * n, 7 * n);
    for base in (0..full).step_by(8) {
        let js = &joints[base..base + 8];
        let ws = &weights[base..base + 8];
        // Components of every influence, and the weights, in SoA form.
        let mut comps = [[_mm256_setzero_ps(); 8]; N];
        let mut wv = [_mm256_setzero_ps(); N];
        for i in 0..N {
            comps[i] = transpose8(std::array::from_fn(|l| dqs[js[l][i] as usize]));
            // SAFETY: lane l reads ws[l][i], inside the 8·N floats of `ws`.
            wv[i] = unsafe { _mm256_i32gather_ps::<4>(ws.as_ptr().cast::<f32>().add(i), stride_n) };
        }
        // Pivot: the real part of each lane's largest-weight influence (first on ties).
        let mut best = wv[0];
        let mut pivot = [comps[0][0], comps[0][1], comps[0][2], comps[0][3]];
        for i in 1..N {
            let larger = _mm256_cmp_ps::<_CMP_GT_OQ>(wv[i], best);
            best = _mm256_blendv_ps(best, wv[i], larger);
            for c in 0..4 {
                pivot[c] = _mm256_blendv_ps(pivot[c], comps[i][c], larger);
            }
        }
        let mut q = [_mm256_setzero_ps(); 8];
        for i in 0..N {
            let r = &comps[i];
            let dot = _mm256_fmadd_ps(
                r[3],
                pivot[3],
                _mm256_fmadd_ps(
                    r[2],
                    pivot[2],
                    _mm256_fmadd_ps(r[1], pivot[1], _mm256_mul_ps(r[0], pivot[0])),
                ),
            );
            let w = _mm256_xor_ps(wv[i], _mm256_and_ps(dot, sign_bit));
            for c in 0..8 {
                q[c] = _mm256_fmadd_ps(r[c], w, q[c]);
            }
        }
        // Normalize by the real part's length (rsqrt and one Newton step).
        let len2 = _mm256_fmadd_ps(
            q[3],
            q[3],
            _mm256_fmadd_ps(q[2], q[2], _mm256_fmadd_ps(q[1], q[1], _mm256_mul_ps(q[0], q[0]))),
        );
        let r0 = _mm256_rsqrt_ps(len2);
        let inv = _mm256_mul_ps(
            _mm256_mul_ps(_mm256_set1_ps(0.5), r0),
            _mm256_fnmadd_ps(_mm256_mul_ps(len2, r0), r0, _mm256_set1_ps(3.0)),
        );
        let [rx, ry, rz, rw, dx, dy, dz, dw] = q.map(|v| _mm256_mul_ps(v, inv));
        // v + 2·r⃗ × (r⃗ × v + w·v): the rotation of v.
        let rotate = |vx: __m256, vy: __m256, vz: __m256| {
            let cx = _mm256_fmadd_ps(rw, vx, _mm256_fmsub_ps(ry, vz, _mm256_mul_ps(rz, vy)));
            let cy = _mm256_fmadd_ps(rw, vy, _mm256_fmsub_ps(rz, vx, _mm256_mul_ps(rx, vz)));
            let cz = _mm256_fmadd_ps(rw, vz, _mm256_fmsub_ps(rx, vy, _mm256_mul_ps(ry, vx)));
            let two = _mm256_set1_ps(2.0);
            (
                _mm256_fmadd_ps(two, _mm256_fmsub_ps(ry, cz, _mm256_mul_ps(rz, cy)), vx),
                _mm256_fmadd_ps(two, _mm256_fmsub_ps(rz, cx, _mm256_mul_ps(rx, cz)), vy),
                _mm256_fmadd_ps(two, _mm256_fmsub_ps(rx, cy, _mm256_mul_ps(ry, cx)), vz),
            )
        };
        // Translation 2·(w_r·d⃗ − w_d·r⃗ + r⃗ × d⃗).
        let two = _mm256_set1_ps(2.0);
        let tx = _mm256_mul_ps(
            two,
            _mm256_fmadd_ps(rw, dx, _mm256_fnmadd_ps(dw, rx, _mm256_fmsub_ps(ry, dz, _mm256_mul_ps(rz, dy)))),
        );
        let ty = _mm256_mul_ps(
            two,
            _mm256_fmadd_ps(rw, dy, _mm256_fnmadd_ps(dw, ry, _mm256_fmsub_ps(rz, dx, _mm256_mul_ps(rx, dz)))),
        );
        let tz = _mm256_mul_ps(
            two,
            _mm256_fmadd_ps(rw, dz, _mm256_fnmadd_ps(dw, rz, _mm256_fmsub_ps(rx, dy, _mm256_mul_ps(ry, dx)))),
        );
        // SAFETY (both): lane l reads component c of vertex l, inside the 8 Vec3s (24 floats).
        let ps = positions[base..base + 8].as_ptr().cast::<f32>();
        let comp = |at: *const f32, c: usize| unsafe { _mm256_i32gather_ps::<4>(at.add(c), stride3) };
        let (px, py, pz) = rotate(comp(ps, 0), comp(ps, 1), comp(ps, 2));
        let ns = normals[base..base + 8].as_ptr().cast::<f32>();
        let (nx, ny, nz) = rotate(comp(ns, 0), comp(ns, 1), comp(ns, 2));
        let (px, py, pz) = (_mm256_add_ps(px, tx), _mm256_add_ps(py, ty), _mm256_add_ps(pz, tz));
        // SAFETY (both): 8 Vec3s are 24 contiguous floats of the output slices.
        unsafe {
            store_interleaved(out_positions[base..base + 8].as_mut_ptr().cast::<f32>(), px, py, pz);
            store_interleaved(out_normals[base..base + 8].as_mut_ptr().cast::<f32>(), nx, ny, nz);
        }
    }
    dual_quaternion_chunk(
        dqs,
        &joints[full..],
        &weights[full..],
        &positions[full..],
        &normals[full..],
        &mut out_positions[full..],
        &mut out_normals[full..],
    );
}
