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

use glam::{Mat4, Quat, Vec3};

use super::trig::sin_cos_quarter_turn;
use super::{check_buffers, check_len, for_each_chunk, Build, Execution, Job};
use crate::error::SkinError;
use crate::influences::BonesBlendBindings;
use crate::pose::JointPalette;

/// Deforms vertices with bones blending.
///
/// The bindings were checked vertex by vertex when they were built
/// ([`BonesBlendBindings::new`]); a run checks the buffer lengths, that the palette holds their
/// largest joint and that every joint they blend across (t < 1) has a parent: O(joints).
#[derive(Debug)]
pub struct BonesBlendJob<'a> {
    /// Must come from the same skeleton the bindings were made for (it carries P(k), T(k)
    /// and A(k)⁻¹ per joint).
    pub palette: &'a JointPalette,
    /// Whether each joint has a parent (t < 1 needs one); `RestSkeleton::parents`.
    pub parents: &'a [Option<usize>],
    pub bindings: &'a BonesBlendBindings,
    pub positions: &'a [Vec3],
    pub normals: &'a [Vec3],
    pub out_positions: &'a mut [Vec3],
    pub out_normals: &'a mut [Vec3],
}

impl BonesBlendJob<'_> {
    /// Checks buffer lengths, that the palette and `parents` hold every joint of the bindings
    /// and that every joint blended across has a parent: O(joints), not O(vertices).
    pub fn validate(&self) -> Result<(), SkinError> {
        let n = self.positions.len();
        check_len("bones-blending bindings", n, self.bindings.len())?;
        check_buffers(n, self.normals.len(), self.out_positions.len(), self.out_normals.len())?;
        check_len("joint parents", self.palette.bones_blending.len(), self.parents.len())?;
        self.bindings.check_joints(self.parents)
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

impl Job for BonesBlendJob<'_> {
    fn check(&self, _parallel: bool) -> Result<(), SkinError> {
        self.validate()
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

    fn fast(&mut self, parallel: bool, build: Build) -> Build {
        let joints = &self.palette.bones_blending;
        let (bindings, positions, normals) = (&self.bindings[..], self.positions, self.normals);
        #[cfg(target_arch = "x86_64")]
        if build != Build::Portable {
            // SAFETY: the CPU has AVX2 and FMA (the caller runs only builds that run here);
            // validate() checked every joint index against the palette.
            let packed = unsafe { super::simd::pack_bones_blending(joints) };
            for_each_chunk(parallel, self.out_positions, self.out_normals, |start, out_p, out_n| {
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
            });
            return Build::Avx2Fma;
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = build;
        for_each_chunk(parallel, self.out_positions, self.out_normals, |start, out_p, out_n| {
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
        });
        Build::Portable
    }
}
