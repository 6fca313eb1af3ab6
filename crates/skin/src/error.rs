//! The one error type of keyrig-skin: every problem names the joint or vertex it concerns.

use thiserror::Error;

/// What is wrong with a skeleton, a pose or a deformer job's inputs.
#[derive(Clone, Debug, PartialEq, Error)]
pub enum SkinError {
    #[error("the skeleton has no joints")]
    EmptySkeleton,
    #[error("the skeleton has {count} joints; at most {max} are supported (joint indices are 16-bit)")]
    TooManyJoints { count: usize, max: usize },
    #[error(
        "joint {joint} (`{name}`): parent index {parent} is out of range (the skeleton has {count} joints)"
    )]
    ParentOutOfRange { joint: usize, name: String, parent: usize, count: usize },
    #[error(
        "joint {joint} (`{name}`): parent index {parent} is not smaller than the joint's own index \
         (joints must be stored parents first; this also rules out cycles)"
    )]
    ParentNotBefore { joint: usize, name: String, parent: usize },
    #[error("joint {joint} (`{name}`): the rest transform has a non-finite component")]
    NonFiniteRest { joint: usize, name: String },
    #[error("joint {joint} (`{name}`): the rest rotation is not a unit quaternion (length {length})")]
    NonUnitRestRotation { joint: usize, name: String, length: f32 },
    #[error("joint {joint} (`{name}`): the inverse bind matrix is non-finite or not invertible")]
    BadInverseBind { joint: usize, name: String },
    #[error("{what}: expected {expected} entries, found {found}")]
    LengthMismatch { what: &'static str, expected: usize, found: usize },
    #[error("pose: joint {joint} has a non-finite or zero-length rotation")]
    BadPoseRotation { joint: usize },
    #[error("pose: joint {joint}'s translation or scale is not finite")]
    BadPoseTransform { joint: usize },
    #[error("pose: the root translation is not finite")]
    BadRootTranslation,
    #[error("vertex {vertex}: the {what} is not finite")]
    NonFiniteVertex { vertex: usize, what: &'static str },
    #[error("vertex {vertex}, influence {influence}: joint index {joint} is out of range (the skeleton has {joint_count} joints)")]
    JointOutOfRange { vertex: usize, influence: usize, joint: usize, joint_count: usize },
    #[error("vertex {vertex}, influence {influence}: weight {weight} is not finite")]
    NonFiniteWeight { vertex: usize, influence: usize, weight: f32 },
    #[error("vertex {vertex}, influence {influence}: weight {weight} is negative")]
    NegativeWeight { vertex: usize, influence: usize, weight: f32 },
    #[error("vertex {vertex}: all weights are zero")]
    ZeroWeights { vertex: usize },
    #[error("vertex {vertex}: the weights sum to {sum}, expected 1 (normalize them first)")]
    WeightSum { vertex: usize, sum: f32 },
    #[error("vertex {vertex}: bones-blending parameter t = {t} is not in [0, 1]")]
    BadBlendParameter { vertex: usize, t: f32 },
    #[error("vertex {vertex}: bones-blending joint {joint} is a root joint but t = {t} < 1 (a root has no parent bone to blend with)")]
    RootBlend { vertex: usize, joint: usize, t: f32 },
    #[error(
        "bones-blending zone: parent fraction {parent_fraction} and child fraction {child_fraction} must be finite and in [0, 1]"
    )]
    BadBlendZone { parent_fraction: f32, child_fraction: f32 },
    #[error(
        "joint {joint}: the skinning transform M(j) has scale {scale} (not rigid); dual quaternion skinning needs rigid transforms"
    )]
    NonRigidTransform { joint: usize, scale: f32 },
    #[error("joint {joint}: the skinning transform is not finite")]
    NonFiniteTransform { joint: usize },
    #[error("joint {joint} is out of range (the skeleton has {joint_count} joints)")]
    NoSuchJoint { joint: usize, joint_count: usize },
    #[error("triangle {triangle}: vertex index {index} is out of range ({vertex_count} vertices)")]
    TriangleIndexOutOfRange { triangle: usize, index: u32, vertex_count: usize },
    #[error("binding: no joint is marked deforming, so no vertex could be bound")]
    NoDeformingJoint,
}

/// [`SkinError::LengthMismatch`] unless `found == expected`.
pub(crate) fn check_len(what: &'static str, expected: usize, found: usize) -> Result<(), SkinError> {
    if expected == found {
        Ok(())
    } else {
        Err(SkinError::LengthMismatch { what, expected, found })
    }
}
