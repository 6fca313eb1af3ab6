//! The rest skeleton in Kavan's notation (docs/design.md §4, seed text 000):
//!
//! - R(j) = `parent_from_joint[j]`: rest transform of joint j relative to its parent;
//! - A(j) = R(0)…R(p(j))·R(j) = `bind_model_from_joint[j]`: the rest (bind) transform in
//!   model space;
//! - A(j)⁻¹ = `joint_from_bind_model[j]`, precomputed once.
//!
//! Joints are stored parents first (a parent's index is smaller than its children's), which
//! also rules out cycles. A skeleton may have several roots (glTF skins can be forests).

use glam::{Affine3A, Mat4, Quat, Vec3};

use crate::error::SkinError;

/// Joint indices in vertex data are 16-bit, so a skeleton has at most this many joints.
pub const MAX_JOINTS: usize = u16::MAX as usize + 1;

/// Tolerance on the length of a rest rotation quaternion.
const UNIT_TOLERANCE: f32 = 1e-3;

/// One joint as given to [`RestSkeleton::new`]: its parent and R(j).
#[derive(Clone, Debug, PartialEq)]
pub struct RestJoint {
    pub name: String,
    /// Index of the parent joint; `None` for a root. Must be smaller than this joint's index.
    pub parent: Option<usize>,
    /// R(j): maps points in the joint's frame to its parent's frame (model space for a root).
    pub parent_from_joint: Affine3A,
}

impl RestJoint {
    /// A joint whose rest transform is a rotation followed by a translation.
    #[must_use]
    pub fn new(name: impl Into<String>, parent: Option<usize>, translation: Vec3, rotation: Quat) -> Self {
        RestJoint {
            name: name.into(),
            parent,
            parent_from_joint: Affine3A::from_rotation_translation(rotation, translation),
        }
    }
}

/// A validated joint hierarchy with its rest pose: R(j), A(j) and A(j)⁻¹ for every joint.
///
/// # Invariants
/// - at least one joint, at most [`MAX_JOINTS`];
/// - `parents[j] < j` for every non-root joint;
/// - every transform is finite and A(j) is invertible.
#[derive(Clone, Debug, PartialEq)]
pub struct RestSkeleton {
    names: Vec<String>,
    parents: Vec<Option<usize>>,
    children: Vec<Vec<usize>>,
    parent_from_joint: Vec<Affine3A>,
    bind_model_from_joint: Vec<Affine3A>,
    joint_from_bind_model: Vec<Affine3A>,
    bone_lengths: Vec<f32>,
}

impl RestSkeleton {
    /// Builds a skeleton from its joints; A(j) is the product of the rest transforms along the
    /// hierarchy and A(j)⁻¹ its inverse.
    pub fn new(joints: &[RestJoint]) -> Result<Self, SkinError> {
        check_hierarchy(joints)?;
        let mut bind_model_from_joint: Vec<Affine3A> = Vec::with_capacity(joints.len());
        for joint in joints {
            let a = match joint.parent {
                Some(p) => bind_model_from_joint[p] * joint.parent_from_joint,
                None => joint.parent_from_joint,
            };
            bind_model_from_joint.push(a);
        }
        let mut joint_from_bind_model = Vec::with_capacity(joints.len());
        for (j, a) in bind_model_from_joint.iter().enumerate() {
            let det = a.matrix3.determinant();
            if !det.is_finite() || det.abs() < f32::MIN_POSITIVE {
                return Err(SkinError::BadInverseBind { joint: j, name: joints[j].name.clone() });
            }
            joint_from_bind_model.push(a.inverse());
        }
        Ok(Self::assemble(joints, bind_model_from_joint, joint_from_bind_model))
    }

    /// Builds a skeleton the way glTF skins define it: parents and local rest transforms R(j)
    /// as usual, but the inverse bind matrices A(j)⁻¹ given explicitly (they need not equal the
    /// inverse of the rest hierarchy). The palette is then M(j) = F(j)·IBM(j).
    pub fn with_inverse_bind_matrices(
        joints: &[RestJoint],
        joint_from_bind_model: &[Mat4],
    ) -> Result<Self, SkinError> {
        check_hierarchy(joints)?;
        if joint_from_bind_model.len() != joints.len() {
            return Err(SkinError::LengthMismatch {
                what: "inverse bind matrices",
                expected: joints.len(),
                found: joint_from_bind_model.len(),
            });
        }
        let mut inverse = Vec::with_capacity(joints.len());
        let mut forward = Vec::with_capacity(joints.len());
        for (j, m) in joint_from_bind_model.iter().enumerate() {
            let bad = || SkinError::BadInverseBind { joint: j, name: joints[j].name.clone() };
            if !m.is_finite() {
                return Err(bad());
            }
            // glTF requires the fourth row to be (0, 0, 0, 1): an affine transform.
            let row3 = m.row(3);
            if (row3 - glam::Vec4::W).abs().max_element() > 1e-5 {
                return Err(bad());
            }
            let ibm = Affine3A::from_mat4(*m);
            let det = ibm.matrix3.determinant();
            if !det.is_finite() || det.abs() < f32::MIN_POSITIVE {
                return Err(bad());
            }
            let a = ibm.inverse();
            if !a.is_finite() {
                return Err(bad());
            }
            inverse.push(ibm);
            forward.push(a);
        }
        Ok(Self::assemble(joints, forward, inverse))
    }

    /// The rest skeleton of a scene skeleton (rest translations and rotations of its joints).
    pub fn from_scene(skeleton: &keyrig_core::Skeleton) -> Result<Self, SkinError> {
        // Rest rotations within the tolerance of unit length are normalized (checked below).
        let joints: Vec<RestJoint> = skeleton
            .joints
            .iter()
            .map(|j| {
                let length = j.rest_rotation.length();
                let rotation = if length.is_finite() && length > 0.0 {
                    j.rest_rotation / length
                } else {
                    j.rest_rotation
                };
                RestJoint::new(j.name.clone(), j.parent, j.rest_translation, rotation)
            })
            .collect();
        for (j, (joint, rest)) in skeleton.joints.iter().zip(&joints).enumerate() {
            let length = joint.rest_rotation.length();
            if length.is_finite() && (length - 1.0).abs() > UNIT_TOLERANCE {
                return Err(SkinError::NonUnitRestRotation { joint: j, name: rest.name.clone(), length });
            }
        }
        Self::new(&joints)
    }

    fn assemble(joints: &[RestJoint], forward: Vec<Affine3A>, inverse: Vec<Affine3A>) -> Self {
        let n = joints.len();
        let mut children = vec![Vec::new(); n];
        for (j, joint) in joints.iter().enumerate() {
            if let Some(p) = joint.parent {
                children[p].push(j);
            }
        }
        let parent_from_joint: Vec<Affine3A> = joints.iter().map(|j| j.parent_from_joint).collect();
        // Bone length of a joint: distance to its nearest child; a leaf inherits its parent's
        // length (or 1 model unit for a lone root).
        let mut bone_lengths = vec![0.0f32; n];
        for j in 0..n {
            let nearest = children[j]
                .iter()
                .map(|&c| parent_from_joint[c].translation.length())
                .filter(|l| *l > 0.0)
                .fold(f32::INFINITY, f32::min);
            bone_lengths[j] = if nearest.is_finite() {
                nearest
            } else {
                match joints[j].parent {
                    Some(p) => bone_lengths[p].max(parent_from_joint[j].translation.length()),
                    None => 1.0,
                }
            };
        }
        RestSkeleton {
            names: joints.iter().map(|j| j.name.clone()).collect(),
            parents: joints.iter().map(|j| j.parent).collect(),
            children,
            parent_from_joint,
            bind_model_from_joint: forward,
            joint_from_bind_model: inverse,
            bone_lengths,
        }
    }

    /// Number of joints.
    #[must_use]
    pub fn len(&self) -> usize {
        self.names.len()
    }

    /// Always false: a skeleton has at least one joint.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.names.is_empty()
    }

    #[must_use]
    pub fn names(&self) -> &[String] {
        &self.names
    }

    #[must_use]
    pub fn parents(&self) -> &[Option<usize>] {
        &self.parents
    }

    /// Children of joint `j`, in index order.
    #[must_use]
    pub fn children(&self, j: usize) -> &[usize] {
        &self.children[j]
    }

    /// R(j) for every joint.
    #[must_use]
    pub fn parent_from_joint(&self) -> &[Affine3A] {
        &self.parent_from_joint
    }

    /// A(j) for every joint: the rest (bind) transform in model space.
    #[must_use]
    pub fn bind_model_from_joint(&self) -> &[Affine3A] {
        &self.bind_model_from_joint
    }

    /// A(j)⁻¹ for every joint (glTF's inverse bind matrices).
    #[must_use]
    pub fn joint_from_bind_model(&self) -> &[Affine3A] {
        &self.joint_from_bind_model
    }

    /// Length of the bone that starts at joint j: the distance to its nearest child in the rest
    /// pose; a leaf joint has its parent's bone length.
    #[must_use]
    pub fn bone_lengths(&self) -> &[f32] {
        &self.bone_lengths
    }

    /// Index of the joint with this name.
    #[must_use]
    pub fn find(&self, name: &str) -> Option<usize> {
        self.names.iter().position(|n| n == name)
    }

    /// Rest position of joint j in model space (the origin of A(j)).
    #[must_use]
    pub fn rest_position(&self, j: usize) -> Vec3 {
        self.bind_model_from_joint[j].translation.into()
    }
}

fn check_hierarchy(joints: &[RestJoint]) -> Result<(), SkinError> {
    if joints.is_empty() {
        return Err(SkinError::EmptySkeleton);
    }
    if joints.len() > MAX_JOINTS {
        return Err(SkinError::TooManyJoints { count: joints.len(), max: MAX_JOINTS });
    }
    for (j, joint) in joints.iter().enumerate() {
        if let Some(p) = joint.parent {
            if p >= joints.len() {
                return Err(SkinError::ParentOutOfRange {
                    joint: j,
                    name: joint.name.clone(),
                    parent: p,
                    count: joints.len(),
                });
            }
            if p >= j {
                return Err(SkinError::ParentNotBefore { joint: j, name: joint.name.clone(), parent: p });
            }
        }
        if !joint.parent_from_joint.is_finite() {
            return Err(SkinError::NonFiniteRest { joint: j, name: joint.name.clone() });
        }
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn chain(n: usize) -> Vec<RestJoint> {
        (0..n)
            .map(|j| {
                RestJoint::new(
                    format!("j{j}"),
                    j.checked_sub(1),
                    Vec3::new(if j == 0 { 0.0 } else { 2.0 }, 0.0, 0.0),
                    Quat::IDENTITY,
                )
            })
            .collect()
    }

    #[test]
    fn bind_transforms_compose_along_the_chain() {
        let skeleton = RestSkeleton::new(&chain(4)).unwrap();
        assert_eq!(skeleton.rest_position(3), Vec3::new(6.0, 0.0, 0.0));
        for j in 0..4 {
            let product = skeleton.bind_model_from_joint()[j] * skeleton.joint_from_bind_model()[j];
            assert!(product.abs_diff_eq(Affine3A::IDENTITY, 1e-6));
        }
        assert_eq!(skeleton.children(1), &[2]);
        assert_eq!(skeleton.names(), &["j0", "j1", "j2", "j3"]);
        assert_eq!(skeleton.bone_lengths(), &[2.0, 2.0, 2.0, 2.0]);
    }

    #[test]
    fn invalid_hierarchies_are_typed_errors() {
        assert_eq!(RestSkeleton::new(&[]), Err(SkinError::EmptySkeleton));
        let many: Vec<RestJoint> = (0..=MAX_JOINTS)
            .map(|j| RestJoint::new("j", j.checked_sub(1), Vec3::X, Quat::IDENTITY))
            .collect();
        assert_eq!(
            RestSkeleton::new(&many),
            Err(SkinError::TooManyJoints { count: MAX_JOINTS + 1, max: MAX_JOINTS })
        );
        let mut joints = chain(3);
        joints[1].parent = Some(1);
        assert!(matches!(
            RestSkeleton::new(&joints),
            Err(SkinError::ParentNotBefore { joint: 1, parent: 1, .. })
        ));
        let mut joints = chain(3);
        joints[1].parent = Some(2);
        assert!(matches!(
            RestSkeleton::new(&joints),
            Err(SkinError::ParentNotBefore { joint: 1, parent: 2, .. })
        ));
        let mut joints = chain(3);
        joints[2].parent = Some(7);
        assert!(matches!(
            RestSkeleton::new(&joints),
            Err(SkinError::ParentOutOfRange { joint: 2, parent: 7, .. })
        ));
        let mut joints = chain(3);
        joints[2].parent_from_joint.translation.x = f32::NAN;
        assert!(matches!(RestSkeleton::new(&joints), Err(SkinError::NonFiniteRest { joint: 2, .. })));
        let mut joints = chain(3);
        joints[0].parent_from_joint = Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0));
        assert!(matches!(RestSkeleton::new(&joints), Err(SkinError::BadInverseBind { joint: 0, .. })));
    }

    #[test]
    fn explicit_inverse_bind_matrices_are_kept() {
        let joints = chain(2);
        let ibm = [Mat4::IDENTITY, Mat4::from_translation(Vec3::new(-5.0, 0.0, 0.0))];
        let skeleton = RestSkeleton::with_inverse_bind_matrices(&joints, &ibm).unwrap();
        assert_eq!(skeleton.rest_position(1), Vec3::new(5.0, 0.0, 0.0));
        assert!(matches!(
            RestSkeleton::with_inverse_bind_matrices(&joints, &ibm[..1]),
            Err(SkinError::LengthMismatch { expected: 2, found: 1, .. })
        ));
        let singular = [Mat4::IDENTITY, Mat4::ZERO];
        assert!(matches!(
            RestSkeleton::with_inverse_bind_matrices(&joints, &singular),
            Err(SkinError::BadInverseBind { joint: 1, .. })
        ));
        // Non-finite, not affine (fourth row), singular 3×3 part: each refused, naming the joint.
        let mut not_finite = ibm;
        not_finite[1].w_axis.x = f32::NAN;
        let mut not_affine = ibm;
        not_affine[0].x_axis.w = 0.5;
        let mut flat = ibm;
        flat[1].z_axis = glam::Vec4::ZERO;
        for (bad, joint) in [(not_finite, 1), (not_affine, 0), (flat, 1)] {
            assert!(matches!(
                RestSkeleton::with_inverse_bind_matrices(&joints, &bad),
                Err(SkinError::BadInverseBind { joint: j, .. }) if j == joint
            ));
        }
        // The hierarchy is checked first.
        let mut orphan = chain(2);
        orphan[1].parent = Some(5);
        assert!(matches!(
            RestSkeleton::with_inverse_bind_matrices(&orphan, &ibm),
            Err(SkinError::ParentOutOfRange { joint: 1, parent: 5, .. })
        ));
    }
}
