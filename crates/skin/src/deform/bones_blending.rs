//! Bones blending (Kavan & Žára, "Real Time Skin Deformation with Bones Blending", WSCG 2003;
//! seed text 000). Each vertex is bound to a joint k (between parent bone j = p(k) and child
//! bone k) with a blend parameter t ∈ [0, 1] precomputed in the rest pose
//! (see [`crate::binding`]). At run time
//!
//! v' = F(j)·R(k)·slerp(I, T(k), t)·A(k)⁻¹·v
//!
//! so the vertex follows the parent bone fully and a fraction t of the child's rotation,
//! applied at the shared joint. t = 0 gives M(j)·v, t = 1 gives M(k)·v, and every t keeps the
//! vertex's distance to the joint: a 180° twist does not collapse. (The seed's pseudo-code
//! slerps T(parent) with T(child) and applies it at the parent's pivot; this is the paper's
//! formula instead.) Normals go through the same rotations.

use bytemuck::{Pod, Zeroable};
use std::ops::Range;

use glam::{Mat4, Quat, Vec3};

use super::{all_chunks, check_buffers, check_len, for_each_chunk, Check, Execution};
use crate::error::SkinError;
use crate::pose::JointPalette;

/// A vertex's bones-blending binding: the joint k it blends across and how far (t) it
/// follows k's rotation. A vertex bound rigidly to joint k has t = 1.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BonesBlendVertex {
    pub joint: u32,
    pub t: f32,
}

/// Deforms vertices with bones blending.
#[derive(Debug)]
pub struct BonesBlendJob<'a> {
    /// Must come from the same skeleton the bindings were made for (it carries P(k), T(k)
    /// and A(k)⁻¹ per joint).
    pub palette: &'a JointPalette,
    /// Whether each joint has a parent (t < 1 needs one); `RestSkeleton::parents`.
    pub parents: &'a [Option<usize>],
    pub bindings: &'a [BonesBlendVertex],
    pub positions: &'a [Vec3],
    pub normals: &'a [Vec3],
    pub out_positions: &'a mut [Vec3],
    pub out_normals: &'a mut [Vec3],
}

impl BonesBlendJob<'_> {
    /// Checks buffer lengths, joint indices, t ∈ [0, 1] and that t < 1 only at joints with a
    /// parent.
    pub fn validate(&self) -> Result<(), SkinError> {
        self.validate_with(true)
    }

    fn validate_with(&self, parallel: bool) -> Result<(), SkinError> {
        self.check_lengths()?;
        let joint_count = self.palette.bones_blending.len();
        // A branch-light pass answers "all good?"; the loop below finds the first bad vertex.
        if all_chunks(
            parallel,
            self.positions.len(),
            Self::quick_check(self.bindings, self.parents, self.palette.bones_blending.len()),
        ) {
            return Ok(());
        }
        for (vertex, b) in self.bindings.iter().enumerate() {
            let joint = b.joint as usize;
            if joint >= joint_count {
                return Err(SkinError::JointOutOfRange { vertex, influence: 0, joint, joint_count });
            }
            if !(0.0..=1.0).contains(&b.t) {
                return Err(SkinError::BadBlendParameter { vertex, t: b.t });
            }
            if b.t < 1.0 && self.parents[joint].is_none() {
                return Err(SkinError::RootBlend { vertex, joint, t: b.t });
            }
        }
        Ok(())
    }

    fn check_lengths(&self) -> Result<(), SkinError> {
        let n = self.positions.len();
        check_len("bones-blending bindings", n, self.bindings.len())?;
        check_buffers(n, self.normals.len(), self.out_positions.len(), self.out_normals.len())?;
        check_len("joint parents", self.palette.bones_blending.len(), self.parents.len())
    }

    /// Whether every binding in a range is valid (joint in range, t ∈ [0, 1], t < 1 only where
    /// the joint has a parent), without early exits.
    fn quick_check<'a>(
        bindings: &'a [BonesBlendVertex],
        parents: &'a [Option<usize>],
        joint_count: usize,
    ) -> impl Fn(Range<usize>) -> bool + Sync + 'a {
        move |r: Range<usize>| {
            bindings[r].iter().fold(true, |ok, b| {
                let joint = b.joint as usize;
                let has_parent = parents.get(joint).is_some_and(|p| p.is_some());
                ok & (joint < joint_count) & (b.t >= 0.0) & ((b.t < 1.0) & has_parent | (b.t == 1.0))
            })
        }
    }

    /// Validates, then deforms on all cores.
    pub fn run(&mut self) -> Result<(), SkinError> {
        self.run_with(Execution::Parallel)
    }

    /// Validates, then deforms the chosen way.
    pub fn run_with(&mut self, execution: Execution) -> Result<(), SkinError> {
        if execution.parallel() {
            // The quick per-chunk check runs in the same dispatch as the kernel (see
            // `for_each_chunk`); when it fails nothing was written, and the full validation
            // below names the error.
            self.check_lengths()?;
            if self.fast(execution, true) {
                return Ok(());
            }
        }
        self.validate_with(false)?;
        match execution {
            Execution::Reference => self.reference(),
            Execution::SingleThreaded | Execution::Parallel | Execution::Portable => {
                self.fast(execution, false);
            }
        }
        Ok(())
    }

    fn reference(&mut self) {
        for v in 0..self.positions.len() {
            let b = self.bindings[v];
            let k = &self.palette.bones_blending[b.joint as usize];
            // F(j)·R(k) is P(k); slerp from the identity to T(k) by t.
            let blended = Quat::IDENTITY.slerp(k.rotation, b.t);
            let m = Mat4::from(k.posed_from_joint_rest)
                * Mat4::from_quat(blended)
                * Mat4::from(k.joint_from_bind_model);
            self.out_positions[v] = m.transform_point3(self.positions[v]);
            self.out_normals[v] = m.transform_vector3(self.normals[v]);
        }
    }

    /// The fast path; with `check`, only if every chunk passes the quick check (returns
    /// whether it ran).
    fn fast(&mut self, execution: Execution, check: bool) -> bool {
        let parallel = execution.parallel();
        let joints = &self.palette.bones_blending;
        let (bindings, positions, normals) = (self.bindings, self.positions, self.normals);
        let quick_check = Self::quick_check(self.bindings, self.parents, self.palette.bones_blending.len());
        let check: Option<Check> = check.then_some(&quick_check);
        #[cfg(target_arch = "x86_64")]
        if execution.simd() {
            // SAFETY: the CPU has AVX2 and FMA (checked above); validate() checked every joint
            // index against the palette.
            let packed = unsafe { super::simd::pack_bones_blending(joints) };
            return for_each_chunk(
                parallel,
                check,
                self.out_positions,
                self.out_normals,
                |start, out_p, out_n| {
                    let end = start + out_p.len();
                    // SAFETY: as above.
                    unsafe {
                        super::simd::bones_blending_chunk(
                            &packed,
                            &bindings[start..end],
                            &positions[start..end],
                            &normals[start..end],
                            out_p,
                            out_n,
                        )
                    }
                },
            );
        }
        for_each_chunk(parallel, check, self.out_positions, self.out_normals, |start, out_p, out_n| {
            let end = start + out_p.len();
            let inputs =
                bindings[start..end].iter().zip(positions[start..end].iter().zip(&normals[start..end]));
            for ((b, (&p, &n)), (op, on)) in inputs.zip(out_p.iter_mut().zip(out_n.iter_mut())) {
                let k = &joints[b.joint as usize];
                // sin φ = 2·sin(φ/2)·cos(φ/2), 1 − cos φ = 2·sin²(φ/2), φ/2 = t·θ/2 ∈ [0, π/2].
                let (s, c) = sin_cos_quarter_turn(b.t * k.half_angle);
                let (sin, versin) = (2.0 * s * c, 2.0 * s * s);
                let [b0, b1, b2] = &k.blend_terms;
                let x = b0.matrix3.x_axis + b1.matrix3.x_axis * sin + b2.matrix3.x_axis * versin;
                let y = b0.matrix3.y_axis + b1.matrix3.y_axis * sin + b2.matrix3.y_axis * versin;
                let z = b0.matrix3.z_axis + b1.matrix3.z_axis * sin + b2.matrix3.z_axis * versin;
                let t = b0.translation + b1.translation * sin + b2.translation * versin;
                *op = (x * p.x + y * p.y + z * p.z + t).into();
                *on = (x * n.x + y * n.y + z * n.z).into();
            }
        })
    }
}

/// sin and cos of x ∈ [0, π/2] by their Taylor polynomials to x¹³ and x¹⁴; the truncation
/// error at π/2 is below 6e-8 (the next terms, (π/2)¹⁵/15! and (π/2)¹⁶/16!), i.e. below
/// f32 rounding. Cheaper than libm's range reduction and inlined into the vertex loop.
#[inline(always)]
pub(crate) fn sin_cos_quarter_turn(x: f32) -> (f32, f32) {
    let x2 = x * x;
    let s = x
        * (1.0
            + x2 * (-1.0 / 6.0
                + x2 * (1.0 / 120.0
                    + x2 * (-1.0 / 5040.0
                        + x2 * (1.0 / 362_880.0
                            + x2 * (-1.0 / 39_916_800.0 + x2 * (1.0 / 6_227_020_800.0)))))));
    let c = 1.0
        + x2 * (-0.5
            + x2 * (1.0 / 24.0
                + x2 * (-1.0 / 720.0
                    + x2 * (1.0 / 40_320.0
                        + x2 * (-1.0 / 3_628_800.0
                            + x2 * (1.0 / 479_001_600.0 + x2 * (-1.0 / 87_178_291_200.0)))))));
    (s, c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polynomial_sin_cos_matches_libm_on_a_quarter_turn() {
        for i in 0..=1000 {
            let x = std::f32::consts::FRAC_PI_2 * i as f32 / 1000.0;
            let (s, c) = sin_cos_quarter_turn(x);
            assert!((s - x.sin()).abs() < 3e-7, "sin({x}): {s} vs {}", x.sin());
            assert!((c - x.cos()).abs() < 3e-7, "cos({x}): {c} vs {}", x.cos());
        }
    }
}
