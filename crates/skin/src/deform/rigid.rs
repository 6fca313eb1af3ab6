//! Rigid skinning ("basic skeletal animation", seed text 000): one joint per vertex,
//! v' = M(j)·v, n' = N(j)·n with N(j) the inverse-transpose of M(j)'s linear part.

use std::ops::Range;

use glam::{Mat3, Mat4, Vec3, Vec3A};

use super::{all_chunks, check_buffers, check_len, for_each_chunk, Build, Execution, Job};
use crate::error::SkinError;
use crate::pose::JointPalette;

/// Deforms each vertex rigidly with the single joint it is bound to.
#[derive(Debug)]
pub struct RigidJob<'a> {
    pub palette: &'a JointPalette,
    /// The joint of each vertex.
    pub joints: &'a [u16],
    pub positions: &'a [Vec3],
    pub normals: &'a [Vec3],
    pub out_positions: &'a mut [Vec3],
    pub out_normals: &'a mut [Vec3],
}

impl RigidJob<'_> {
    /// Checks buffer lengths and that every joint index is in the palette.
    pub fn validate(&self) -> Result<(), SkinError> {
        self.validate_with(true)
    }

    fn validate_with(&self, parallel: bool) -> Result<(), SkinError> {
        self.check_lengths()?;
        let joint_count = self.palette.len();
        // A branch-free pass answers "all good?"; only when it fails does the loop below look
        // for the first bad vertex.
        if all_chunks(parallel, self.positions.len(), Self::quick_check(self.joints, self.palette.len())) {
            return Ok(());
        }
        for (vertex, &j) in self.joints.iter().enumerate() {
            if j as usize >= joint_count {
                return Err(SkinError::JointOutOfRange {
                    vertex,
                    influence: 0,
                    joint: j as usize,
                    joint_count,
                });
            }
        }
        Ok(())
    }

    fn check_lengths(&self) -> Result<(), SkinError> {
        let n = self.positions.len();
        check_len("joints", n, self.joints.len())?;
        check_buffers(n, self.normals.len(), self.out_positions.len(), self.out_normals.len())
    }

    /// Whether every joint index in a range is in the palette: the largest one, found without
    /// branches (it vectorizes).
    fn quick_check(joints: &[u16], joint_count: usize) -> impl Fn(Range<usize>) -> bool + Sync + '_ {
        move |r: Range<usize>| usize::from(joints[r].iter().fold(0u16, |m, &j| m.max(j))) < joint_count
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

impl Job for RigidJob<'_> {
    /// Rigid joints are a plain slice, not a validated type: every index is checked, in
    /// parallel chunks for a parallel run.
    fn check(&self, parallel: bool) -> Result<(), SkinError> {
        self.validate_with(parallel)
    }

    fn reference(&mut self) {
        for v in 0..self.positions.len() {
            let j = self.joints[v] as usize;
            let m = Mat4::from(self.palette.skinning[j]);
            self.out_positions[v] = m.transform_point3(self.positions[v]);
            let n = match &self.palette.normal_skinning {
                Some(normals) => Mat3::from(normals[j]),
                None => Mat3::from_mat4(m).inverse().transpose(),
            };
            self.out_normals[v] = n * self.normals[v];
        }
    }

    fn fast(&mut self, parallel: bool, build: Build) -> Build {
        let palette = &self.palette.skinning;
        let normal_palette = self.palette.normal_skinning.as_deref();
        let joints = self.joints;
        let positions = self.positions;
        let normals = self.normals;
        #[cfg(target_arch = "x86_64")]
        if build != Build::Portable {
            for_each_chunk(parallel, self.out_positions, self.out_normals, |start, out_p, out_n| {
                let end = start + out_p.len();
                // SAFETY: the CPU has AVX2 and FMA (the caller runs only builds that run here);
                // validate() checked every joint index against the palette; the slices are one
                // chunk of buffers whose lengths were checked equal.
                unsafe {
                    super::simd::rigid_chunk(
                        palette,
                        normal_palette,
                        &joints[start..end],
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
            let inputs = joints[start..end].iter().zip(&positions[start..end]).zip(&normals[start..end]);
            for (((&j, &p), &n), (op, on)) in inputs.zip(out_p.iter_mut().zip(out_n.iter_mut())) {
                let m = &palette[j as usize];
                *op = m.transform_point3a(Vec3A::from(p)).into();
                let nm = match normal_palette {
                    Some(normals) => normals[j as usize] * Vec3A::from(n),
                    None => m.matrix3 * Vec3A::from(n),
                };
                *on = nm.into();
            }
        });
        Build::Portable
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The branch-free pass accepts exactly the ranges whose joints are all in the palette
    /// (when it refuses, the slow pass that names the vertex runs instead: the result would be
    /// the same, only slower, so it is checked on its own).
    #[test]
    fn the_quick_check_accepts_in_range_joints_only() {
        let joints = [0u16, 2, 1, 3];
        assert!(RigidJob::quick_check(&joints, 4)(0..4));
        assert!(RigidJob::quick_check(&joints, 3)(0..3));
        assert!(!RigidJob::quick_check(&joints, 3)(0..4));
        assert!(!RigidJob::quick_check(&joints, 3)(3..4));
    }
}
