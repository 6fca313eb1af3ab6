//! x86-64 kernels that use AVX2 and FMA when the CPU has them (checked at run time; the
//! portable glam paths in the job files run otherwise). Same formulas, fused multiply-adds
//! and 256-bit registers: a 3×4 palette matrix is two registers, (x | y) and (z | t), so
//! blending one influence is two FMAs instead of eight SSE multiplies and adds.

use std::arch::x86_64::*;

use glam::{Affine3A, Vec3, Vec3A, Vec4};

use crate::dual_quat::DualQuat;

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
