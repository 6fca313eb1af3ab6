//! Joint influences (indices and weights per vertex) and bones-blending bindings, checked once
//! when a mesh or binding is built and then skinned any number of times.
//!
//! ozz-animation leaves the validity of its runtime data to the step that builds it and checks
//! only buffer sizes per [`SkinningJob`](https://guillaumeblanc.github.io/ozz-animation/) call;
//! keyrig does the same with a type: an [`Influences`] can only be made by [`Influences::new`],
//! which checks every vertex (and names the first bad one), so a job that takes one checks
//! only that the palette holds its largest joint index, O(1), instead of every vertex, O(n).

use std::ops::Deref;

use bytemuck::{Pod, Zeroable};

use crate::deform::parallel::all_chunks;
use crate::error::{check_len, SkinError};

/// Largest allowed |Σw − 1| for a vertex's weights.
pub const WEIGHT_SUM_TOLERANCE: f32 = 1e-3;

/// Checks N-influence joint indices and weights: indices in range, weights finite,
/// non-negative, not all zero and summing to 1 within [`WEIGHT_SUM_TOLERANCE`].
pub fn validate_influences<const N: usize>(
    joints: &[[u16; N]],
    weights: &[[f32; N]],
    joint_count: usize,
) -> Result<(), SkinError> {
    validate_influences_with(joints, weights, joint_count, true)
}

/// [`validate_influences`], on the calling thread or in parallel chunks. A branch-free pass
/// over all vertices answers "all good?" cheaply (it runs every frame); only when it fails does
/// a second pass look for the first bad vertex to report.
pub(crate) fn validate_influences_with<const N: usize>(
    joints: &[[u16; N]],
    weights: &[[f32; N]],
    joint_count: usize,
    parallel: bool,
) -> Result<(), SkinError> {
    check_len("weights", joints.len(), weights.len())?;
    let all_good =
        all_chunks(parallel, joints.len(), |r| influences_pass(&joints[r.clone()], &weights[r], joint_count));
    if all_good {
        Ok(())
    } else {
        first_bad_influence(joints, weights, joint_count)
    }
}

/// True when every vertex passes; written without early exits so that it vectorizes: the
/// largest joint index must be in range, the largest weight bit pattern must be that of a
/// finite non-negative float (≤ 0x7F7F_FFFF: negative numbers have the sign bit set, NaN and
/// infinity an all-ones exponent), and every vertex's sum must be 1 within the tolerance.
pub(crate) fn influences_pass<const N: usize>(
    joints: &[[u16; N]],
    weights: &[[f32; N]],
    joint_count: usize,
) -> bool {
    let mut max_joint = 0u16;
    let mut max_bits = 0u32;
    let mut sums_ok = true;
    for (js, ws) in joints.iter().zip(weights) {
        let mut sum = 0.0f32;
        for i in 0..N {
            max_joint = max_joint.max(js[i]);
            max_bits = max_bits.max(ws[i].to_bits());
            sum += ws[i];
        }
        sums_ok &= (sum - 1.0).abs() <= WEIGHT_SUM_TOLERANCE;
    }
    (max_joint as usize) < joint_count && max_bits <= 0x7F7F_FFFF && sums_ok
}

fn first_bad_influence<const N: usize>(
    joints: &[[u16; N]],
    weights: &[[f32; N]],
    joint_count: usize,
) -> Result<(), SkinError> {
    for (vertex, (js, ws)) in joints.iter().zip(weights).enumerate() {
        let mut sum = 0.0f32;
        for influence in 0..N {
            let joint = js[influence] as usize;
            if joint >= joint_count {
                return Err(SkinError::JointOutOfRange { vertex, influence, joint, joint_count });
            }
            let weight = ws[influence];
            if !weight.is_finite() {
                return Err(SkinError::NonFiniteWeight { vertex, influence, weight });
            }
            if weight < 0.0 {
                return Err(SkinError::NegativeWeight { vertex, influence, weight });
            }
            sum += weight;
        }
        if sum == 0.0 {
            return Err(SkinError::ZeroWeights { vertex });
        }
        if (sum - 1.0).abs() > WEIGHT_SUM_TOLERANCE {
            return Err(SkinError::WeightSum { vertex, sum });
        }
    }
    Ok(())
}

/// Scales each vertex's weights to sum to 1. Fails on the same bad weights as
/// [`validate_influences`] (non-finite, negative, all zero); use it in importers.
pub fn normalize_weights<const N: usize>(weights: &mut [[f32; N]]) -> Result<(), SkinError> {
    for (vertex, ws) in weights.iter_mut().enumerate() {
        let mut sum = 0.0f32;
        for (influence, &weight) in ws.iter().enumerate() {
            if !weight.is_finite() {
                return Err(SkinError::NonFiniteWeight { vertex, influence, weight });
            }
            if weight < 0.0 {
                return Err(SkinError::NegativeWeight { vertex, influence, weight });
            }
            sum += weight;
        }
        if sum == 0.0 {
            return Err(SkinError::ZeroWeights { vertex });
        }
        for w in ws.iter_mut() {
            *w /= sum;
        }
    }
    Ok(())
}

/// `N` joint indices and weights per vertex, valid by construction: every weight finite and
/// ≥ 0, each vertex's weights summing to 1 within [`WEIGHT_SUM_TOLERANCE`], and
/// every joint index below the joint count it was checked against. Immutable after
/// construction (take it apart with [`Influences::into_parts`] to edit, and build it again).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Influences<const N: usize = 4> {
    joints: Vec<[u16; N]>,
    weights: Vec<[f32; N]>,
    /// One more than the largest joint index (0 without vertices): the fewest palette entries
    /// a job needs.
    joints_needed: usize,
}

impl<const N: usize> Influences<N> {
    /// Checks every vertex's influences against a skeleton of `joint_count` joints.
    ///
    /// # Errors
    /// [`SkinError::LengthMismatch`] when `joints` and `weights` differ in length; otherwise
    /// the first bad vertex: [`SkinError::JointOutOfRange`], [`SkinError::NonFiniteWeight`],
    /// [`SkinError::NegativeWeight`], [`SkinError::ZeroWeights`] or [`SkinError::WeightSum`].
    pub fn new(joints: Vec<[u16; N]>, weights: Vec<[f32; N]>, joint_count: usize) -> Result<Self, SkinError> {
        validate_influences(&joints, &weights, joint_count)?;
        let joints_needed = joints.iter().flatten().max().map_or(0, |&j| j as usize + 1);
        Ok(Influences { joints, weights, joints_needed })
    }

    /// [`Influences::new`] after scaling each vertex's weights to sum to 1
    /// ([`normalize_weights`]); for importers.
    pub fn normalized(
        joints: Vec<[u16; N]>,
        mut weights: Vec<[f32; N]>,
        joint_count: usize,
    ) -> Result<Self, SkinError> {
        normalize_weights(&mut weights)?;
        Self::new(joints, weights, joint_count)
    }

    /// Number of vertices.
    #[must_use]
    pub fn len(&self) -> usize {
        self.joints.len()
    }

    /// Whether there are no vertices.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.joints.is_empty()
    }

    /// The joint indices per vertex.
    #[must_use]
    pub fn joints(&self) -> &[[u16; N]] {
        &self.joints
    }

    /// The weights per vertex.
    #[must_use]
    pub fn weights(&self) -> &[[f32; N]] {
        &self.weights
    }

    /// One more than the largest joint index (0 without vertices): the smallest palette or
    /// skeleton these influences fit.
    #[must_use]
    pub fn joints_needed(&self) -> usize {
        self.joints_needed
    }

    /// The joint indices and weights, to edit and check again.
    #[must_use]
    pub fn into_parts(self) -> (Vec<[u16; N]>, Vec<[f32; N]>) {
        (self.joints, self.weights)
    }

    /// Checks that a palette or skeleton of `joint_count` joints holds every joint index: O(1)
    /// when it does; when it does not, the error names the first vertex that reaches past it.
    pub fn check_joint_count(&self, joint_count: usize) -> Result<(), SkinError> {
        if self.joints_needed <= joint_count {
            return Ok(());
        }
        for (vertex, js) in self.joints.iter().enumerate() {
            if let Some(influence) = js.iter().position(|&j| j as usize >= joint_count) {
                let joint = js[influence] as usize;
                return Err(SkinError::JointOutOfRange { vertex, influence, joint, joint_count });
            }
        }
        unreachable!("joints_needed is one more than the largest joint index")
    }
}

/// A vertex's bones-blending binding: the joint k it blends across and how far (t) it
/// follows k's rotation. A vertex bound rigidly to joint k has t = 1.
#[repr(C)]
#[derive(Clone, Copy, Debug, Default, PartialEq, Pod, Zeroable)]
pub struct BonesBlendVertex {
    pub joint: u32,
    pub t: f32,
}

/// Bones-blending bindings, valid by construction: every joint below the joint count they were
/// checked against, every t in [0, 1], and t < 1 only at joints with a parent. Read them as a
/// slice (`Deref`); immutable after construction ([`BonesBlendBindings::into_inner`] to edit,
/// and build them again).
#[derive(Clone, Debug, Default, PartialEq)]
pub struct BonesBlendBindings {
    bindings: Vec<BonesBlendVertex>,
    /// One more than the largest joint (0 without vertices).
    joints_needed: usize,
    /// The joints some vertex blends across (t < 1), ascending: each needs a parent.
    blended_joints: Vec<u32>,
}

impl BonesBlendBindings {
    /// Checks every vertex's binding against a skeleton's parents (`RestSkeleton::parents`).
    ///
    /// # Errors
    /// The first bad vertex: [`SkinError::JointOutOfRange`] (joint not in the skeleton),
    /// [`SkinError::BadBlendParameter`] (t not in [0, 1], NaN included) or
    /// [`SkinError::RootBlend`] (t < 1 at a joint without a parent).
    pub fn new(bindings: Vec<BonesBlendVertex>, parents: &[Option<usize>]) -> Result<Self, SkinError> {
        let joint_count = parents.len();
        let mut blended = vec![false; joint_count];
        let mut joints_needed = 0;
        for (vertex, b) in bindings.iter().enumerate() {
            let joint = b.joint as usize;
            if joint >= joint_count {
                return Err(SkinError::JointOutOfRange { vertex, influence: 0, joint, joint_count });
            }
            if !(0.0..=1.0).contains(&b.t) {
                return Err(SkinError::BadBlendParameter { vertex, t: b.t });
            }
            if b.t < 1.0 {
                if parents[joint].is_none() {
                    return Err(SkinError::RootBlend { vertex, joint, t: b.t });
                }
                blended[joint] = true;
            }
            joints_needed = joints_needed.max(joint + 1);
        }
        let blended_joints = (0..joint_count as u32).filter(|&j| blended[j as usize]).collect();
        Ok(BonesBlendBindings { bindings, joints_needed, blended_joints })
    }

    /// One more than the largest joint (0 without vertices).
    #[must_use]
    pub fn joints_needed(&self) -> usize {
        self.joints_needed
    }

    /// The bindings, to edit and check again.
    #[must_use]
    pub fn into_inner(self) -> Vec<BonesBlendVertex> {
        self.bindings
    }

    /// Checks that a skeleton with these `parents` (the one a job's palette comes from) holds
    /// every joint and has a parent at every joint blended across: O(joints). On failure the
    /// error names the first vertex concerned.
    pub fn check_joints(&self, parents: &[Option<usize>]) -> Result<(), SkinError> {
        let joint_count = parents.len();
        let fits = self.joints_needed <= joint_count;
        if fits && self.blended_joints.iter().all(|&j| parents[j as usize].is_some()) {
            return Ok(());
        }
        for (vertex, b) in self.bindings.iter().enumerate() {
            let joint = b.joint as usize;
            if joint >= joint_count {
                return Err(SkinError::JointOutOfRange { vertex, influence: 0, joint, joint_count });
            }
            if b.t < 1.0 && parents[joint].is_none() {
                return Err(SkinError::RootBlend { vertex, joint, t: b.t });
            }
        }
        unreachable!("a joint past the skeleton or blended at a root belongs to some vertex")
    }
}

impl Deref for BonesBlendBindings {
    type Target = [BonesBlendVertex];

    fn deref(&self) -> &[BonesBlendVertex] {
        &self.bindings
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn influence_errors_name_vertex_and_influence() {
        let joints = [[0u16, 1], [0, 5]];
        let good = [[0.5f32, 0.5], [1.0, 0.0]];
        assert_eq!(
            validate_influences(&joints, &good, 2),
            Err(SkinError::JointOutOfRange { vertex: 1, influence: 1, joint: 5, joint_count: 2 })
        );
        let joints = [[0u16, 1], [0, 1]];
        assert_eq!(validate_influences(&joints, &good, 2), Ok(()));
        assert!(matches!(
            validate_influences(&joints, &[[0.5, 0.5], [f32::NAN, 1.0]], 2),
            Err(SkinError::NonFiniteWeight { vertex: 1, influence: 0, .. })
        ));
        assert!(matches!(
            validate_influences(&joints, &[[1.5, -0.5], [1.0, 0.0]], 2),
            Err(SkinError::NegativeWeight { vertex: 0, influence: 1, .. })
        ));
        assert_eq!(
            validate_influences(&joints, &[[0.5, 0.5], [0.0, 0.0]], 2),
            Err(SkinError::ZeroWeights { vertex: 1 })
        );
        assert!(matches!(
            validate_influences(&joints, &[[0.5, 0.4], [1.0, 0.0]], 2),
            Err(SkinError::WeightSum { vertex: 0, .. })
        ));
        assert!(matches!(
            validate_influences(&joints, &good[..1], 2),
            Err(SkinError::LengthMismatch { expected: 2, found: 1, .. })
        ));
    }

    #[test]
    fn normalize_scales_to_one() {
        let mut ws = [[2.0f32, 2.0], [0.0, 3.0]];
        normalize_weights(&mut ws).unwrap();
        assert_eq!(ws, [[0.5, 0.5], [0.0, 1.0]]);
        assert_eq!(normalize_weights(&mut [[0.0f32, 0.0]]), Err(SkinError::ZeroWeights { vertex: 0 }));
    }

    /// The branch-free "all good?" pass answers true exactly for valid influences (when it
    /// answers false, the slow pass that names the vertex runs instead: the results would be
    /// the same, only slower, so it is checked on its own).
    #[test]
    fn the_quick_pass_accepts_valid_influences_only() {
        let joints = [[0u16, 1], [1, 2]];
        assert!(influences_pass(&joints, &[[0.5f32, 0.5], [0.9995, 0.0]], 3));
        assert!(influences_pass::<2>(&[], &[], 1));
        assert!(!influences_pass(&joints, &[[0.5f32, 0.5], [0.9985, 0.0]], 3), "sum off by 1.5e-3");
        assert!(!influences_pass(&joints, &[[0.5f32, 0.5], [1.0, 0.0]], 2), "joint 2 of 2");
        assert!(!influences_pass(&joints, &[[1.5f32, -0.5], [1.0, 0.0]], 3), "negative");
        assert!(!influences_pass(&joints, &[[0.5f32, 0.5], [f32::INFINITY, 0.0]], 3), "infinite");
    }

    #[test]
    fn only_valid_influences_are_built_and_errors_name_the_vertex() {
        let joints = vec![[0u16, 1], [0, 3]];
        let good = Influences::new(joints.clone(), vec![[0.5f32, 0.5], [1.0, 0.0]], 4).unwrap();
        assert_eq!((good.len(), good.joints_needed(), good.is_empty()), (2, 4, false));
        assert_eq!(good.check_joint_count(4), Ok(()));
        assert_eq!(
            good.check_joint_count(3),
            Err(SkinError::JointOutOfRange { vertex: 1, influence: 1, joint: 3, joint_count: 3 })
        );
        assert_eq!(
            Influences::new(joints.clone(), vec![[0.5, 0.5], [1.0, 0.0]], 3),
            Err(SkinError::JointOutOfRange { vertex: 1, influence: 1, joint: 3, joint_count: 3 })
        );
        assert!(matches!(
            Influences::new(joints.clone(), vec![[0.5, 0.5], [f32::NAN, 1.0]], 4),
            Err(SkinError::NonFiniteWeight { vertex: 1, influence: 0, .. })
        ));
        assert!(matches!(
            Influences::new(joints.clone(), vec![[0.5, 0.5], [0.9, 0.0]], 4),
            Err(SkinError::WeightSum { vertex: 1, .. })
        ));
        let normalized = Influences::normalized(joints.clone(), vec![[1.0, 1.0], [2.0, 0.0]], 4).unwrap();
        assert_eq!(normalized.weights(), &[[0.5, 0.5], [1.0, 0.0]]);
        assert_eq!(
            Influences::normalized(joints, vec![[1.0, 1.0], [0.0, 0.0]], 4),
            Err(SkinError::ZeroWeights { vertex: 1 })
        );
        let (j, w) = good.into_parts();
        assert_eq!((j.len(), w.len()), (2, 2));
        let empty = Influences::<4>::new(Vec::new(), Vec::new(), 0).unwrap();
        assert_eq!((empty.joints_needed(), empty.is_empty()), (0, true));
        assert_eq!(empty.check_joint_count(0), Ok(()));
    }

    #[test]
    fn only_valid_bones_blending_bindings_are_built_and_errors_name_the_vertex() {
        let parents = [None, Some(0), Some(1)];
        let b = |joint, t| BonesBlendVertex { joint, t };
        let good = BonesBlendBindings::new(vec![b(0, 1.0), b(2, 0.25), b(1, 0.0)], &parents).unwrap();
        assert_eq!((good.len(), good.joints_needed(), good[1]), (3, 3, b(2, 0.25)));
        assert_eq!(good.blended_joints, [1, 2]);
        assert_eq!(good.check_joints(&parents), Ok(()));
        assert_eq!(
            good.check_joints(&parents[..2]),
            Err(SkinError::JointOutOfRange { vertex: 1, influence: 0, joint: 2, joint_count: 2 })
        );
        assert_eq!(
            good.check_joints(&[None, None, Some(1)]),
            Err(SkinError::RootBlend { vertex: 2, joint: 1, t: 0.0 })
        );
        assert_eq!(
            BonesBlendBindings::new(vec![b(0, 1.0), b(3, 1.0)], &parents),
            Err(SkinError::JointOutOfRange { vertex: 1, influence: 0, joint: 3, joint_count: 3 })
        );
        for t in [1.5, -0.25] {
            assert_eq!(
                BonesBlendBindings::new(vec![b(1, 0.5), b(1, t)], &parents),
                Err(SkinError::BadBlendParameter { vertex: 1, t })
            );
        }
        assert!(matches!(
            BonesBlendBindings::new(vec![b(1, f32::NAN)], &parents),
            Err(SkinError::BadBlendParameter { vertex: 0, .. })
        ));
        assert_eq!(
            BonesBlendBindings::new(vec![b(1, 0.5), b(0, 0.5)], &parents),
            Err(SkinError::RootBlend { vertex: 1, joint: 0, t: 0.5 })
        );
        assert_eq!(good.clone().into_inner(), vec![b(0, 1.0), b(2, 0.25), b(1, 0.0)]);
        let empty = BonesBlendBindings::new(Vec::new(), &[]).unwrap();
        assert_eq!((empty.joints_needed(), empty.is_empty()), (0, true));
        assert_eq!(empty.check_joints(&[]), Ok(()));
    }
}
