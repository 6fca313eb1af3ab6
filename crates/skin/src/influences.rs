//! Joint influences (indices and weights per vertex), checked once when a mesh or binding is
//! built and then skinned any number of times.
//!
//! ozz-animation leaves the validity of its runtime data to the step that builds it and checks
//! only buffer sizes per [`SkinningJob`](https://guillaumeblanc.github.io/ozz-animation/) call;
//! keyrig does the same with a type: an [`Influences`] can only be made by [`Influences::new`],
//! which checks every vertex (and names the first bad one), so a job that takes one checks
//! only that the palette holds its largest joint index, O(1), instead of every vertex, O(n).

use crate::deform::validate_influences;
use crate::error::SkinError;

/// `N` joint indices and weights per vertex, valid by construction: every weight finite and
/// ≥ 0, each vertex's weights summing to 1 within [`crate::deform::WEIGHT_SUM_TOLERANCE`], and
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
    /// ([`crate::deform::normalize_weights`]); for importers.
    pub fn normalized(
        joints: Vec<[u16; N]>,
        mut weights: Vec<[f32; N]>,
        joint_count: usize,
    ) -> Result<Self, SkinError> {
        crate::deform::normalize_weights(&mut weights)?;
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
