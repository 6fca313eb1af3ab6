//! Dual quaternion skinning (Kavan, Collins, Žára, O'Sullivan, ACM TOG 2008; Blender's
//! "Preserve Volume", Maya's dual-quaternion skinning): blend the unit dual quaternions of the
//! palette, q̂ = Σᵢ ±wᵢ·q̂(jᵢ) with each sign chosen so that q̂(jᵢ)'s real part lies in the
//! same hemisphere as the dominant (largest-weight) influence's, normalize, transform.
//! Normals rotate with the blended real part. Needs a rigid palette
//! ([`crate::pose::JointPalette::dual_quaternions`]).

use glam::{BVec4A, Mat4, Quat, Vec3, Vec3A, Vec4};

use super::{check_buffers, check_len, for_each_chunk, Build, Execution, Job};
use crate::dual_quat::DualQuat;
use crate::error::SkinError;
use crate::influences::Influences;

/// Dual quaternion skinning with `N` influences per vertex. The influences were checked
/// vertex by vertex when they were built ([`Influences::new`]); a run checks only the buffer
/// lengths and that the palette holds their largest joint index.
#[derive(Debug)]
pub struct DualQuatJob<'a, const N: usize = 4> {
    /// The palette M(j) as unit dual quaternions.
    pub dual_quaternions: &'a [DualQuat],
    pub influences: &'a Influences<N>,
    pub positions: &'a [Vec3],
    pub normals: &'a [Vec3],
    pub out_positions: &'a mut [Vec3],
    pub out_normals: &'a mut [Vec3],
}

impl<const N: usize> DualQuatJob<'_, N> {
    /// Checks buffer lengths and that the palette holds every joint index: O(joints), not
    /// O(vertices) (the influences are valid by construction).
    pub fn validate(&self) -> Result<(), SkinError> {
        let n = self.positions.len();
        check_len("influences", n, self.influences.len())?;
        check_buffers(n, self.normals.len(), self.out_positions.len(), self.out_normals.len())?;
        self.influences.check_joint_count(self.dual_quaternions.len())
    }

    /// Validates, then deforms on all cores.
    pub fn run(&mut self) -> Result<(), SkinError> {
        self.run_with(Execution::Parallel)
    }

    /// Validates, then deforms the chosen way.
    pub fn run_with(&mut self, execution: Execution) -> Result<(), SkinError> {
        super::run(self, execution)
    }
}

impl<const N: usize> Job for DualQuatJob<'_, N> {
    fn check(&self, _parallel: bool) -> Result<(), SkinError> {
        self.validate()
    }

    fn reference(&mut self) {
        for v in 0..self.positions.len() {
            let (js, ws) = (&self.influences.joints()[v], &self.influences.weights()[v]);
            let mut dominant = 0;
            for i in 1..N {
                if ws[i] > ws[dominant] {
                    dominant = i;
                }
            }
            let pivot = self.dual_quaternions[js[dominant] as usize].real;
            let mut real = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
            let mut dual = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
            for i in 0..N {
                let q = self.dual_quaternions[js[i] as usize];
                // The weight takes the sign of the dot product (−0.0 included, as the fast
                // paths take it).
                let w = ws[i].copysign(q.real.dot(pivot));
                real += q.real * w;
                dual += q.dual * w;
            }
            let (rotation, translation) = DualQuat { real, dual }.normalize().to_rotation_translation();
            let m = Mat4::from_rotation_translation(rotation, translation);
            self.out_positions[v] = m.transform_point3(self.positions[v]);
            self.out_normals[v] = m.transform_vector3(self.normals[v]);
        }
    }

    fn fast(&mut self, parallel: bool, build: Build) -> Build {
        let dqs = self.dual_quaternions;
        let (joints, weights) = (self.influences.joints(), self.influences.weights());
        let (positions, normals) = (self.positions, self.normals);
        #[cfg(target_arch = "x86_64")]
        if build != Build::Portable {
            // SAFETY: the CPU has AVX2 and FMA (the caller runs only builds that run here);
            // validate() checked that the palette holds every joint index of the influences.
            let packed = unsafe { super::simd::pack_dual_quaternions(dqs) };
            let stream = super::simd::streams_outputs(positions.len(), N);
            let avx512 = build == Build::Avx512Vl;
            for_each_chunk(parallel, self.out_positions, self.out_normals, |start, out_p, out_n| {
                let end = start + out_p.len();
                let (js, ws) = (&joints[start..end], &weights[start..end]);
                let (ps, ns) = (&positions[start..end], &normals[start..end]);
                // SAFETY: as above; the AVX-512VL build only where the CPU has it.
                unsafe {
                    if avx512 {
                        super::simd::dual_quaternion_chunk_avx512_x16(
                            &packed, js, ws, ps, ns, out_p, out_n, stream,
                        )
                    } else {
                        super::simd::dual_quaternion_chunk_soa(&packed, js, ws, ps, ns, out_p, out_n)
                    }
                }
            });
            return if avx512 { Build::Avx512Vl } else { Build::Avx2Fma };
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = build;
        for_each_chunk(parallel, self.out_positions, self.out_normals, |start, out_p, out_n| {
            let end = start + out_p.len();
            let inputs = joints[start..end]
                .iter()
                .zip(&weights[start..end])
                .zip(positions[start..end].iter().zip(&normals[start..end]));
            for (((js, ws), (&p, &n)), (op, on)) in inputs.zip(out_p.iter_mut().zip(out_n.iter_mut())) {
                // Branch-free (random rotations make the signs unpredictable): the pivot is
                // the real part of the largest-weight influence (the first on ties), and each
                // weight takes the sign of its real part's dot product with the pivot.
                let mut pivot = Vec4::from(dqs[js[0] as usize].real);
                let mut best = ws[0];
                for i in 1..N {
                    let larger = ws[i] > best;
                    best = if larger { ws[i] } else { best };
                    pivot = Vec4::select(BVec4A::splat(larger), Vec4::from(dqs[js[i] as usize].real), pivot);
                }
                let mut real = Vec4::ZERO;
                let mut dual = Vec4::ZERO;
                for i in 0..N {
                    let q = &dqs[js[i] as usize];
                    let r = Vec4::from(q.real);
                    let w = Vec4::splat(ws[i]).copysign(Vec4::splat(r.dot(pivot)));
                    real += r * w;
                    dual += Vec4::from(q.dual) * w;
                }
                let inv = real.length_recip();
                let (real, dual) = (real * inv, dual * inv);
                let r = Vec3A::from_vec4(real);
                let d = Vec3A::from_vec4(dual);
                let (rw, dw) = (real.w, dual.w);
                let p = Vec3A::from(p);
                let n = Vec3A::from(n);
                let translation = 2.0 * (rw * d - dw * r + r.cross(d));
                *op = (p + 2.0 * r.cross(r.cross(p) + rw * p) + translation).into();
                *on = (n + 2.0 * r.cross(r.cross(n) + rw * n)).into();
            }
        });
        Build::Portable
    }
}
