//! keyrig-skin: the rest skeleton, pose evaluation (joint palettes) and the four skin
//! deformers — rigid, linear blend, bones blending and dual quaternion — with the paper's test
//! meshes and measures. Pure: no file I/O, no GPU, no UI. docs/design.md §4–§6 are the reference;
//! `docs/skinning.md` is the guide.
//!
//! One frame: [`RestSkeleton`] + [`Pose`] → [`JointPalette`] (F(j), M(j) = F(j)·A(j)⁻¹) →
//! a deformer job ([`RigidJob`], [`LinearBlendJob`], [`BonesBlendJob`], [`DualQuatJob`]) or
//! [`deform_mesh`] for a whole [`SkinnedMesh`].

pub mod bind;
pub mod binding;
pub mod deform;
pub mod deformer;
pub mod dual_quat;
pub mod error;
pub mod influences;
pub mod measure;
pub mod mesh;
pub mod paper;
pub mod pose;
pub mod skeleton;

pub use bind::{BindJob, BindMethod, MAX_BOUND_INFLUENCES};
pub use binding::{bind_from_weights, bind_single_weights, smooth_weights, weights_from_bindings, BlendZone};
pub use deform::{BonesBlendJob, DualQuatJob, Execution, LinearBlendJob, RigidJob};
pub use deformer::{deform_mesh, deform_mesh_into, Deformed};
pub use dual_quat::DualQuat;
pub use error::SkinError;
pub use influences::{
    normalize_weights, validate_influences, BonesBlendBindings, BonesBlendVertex, Influences,
    WEIGHT_SUM_TOLERANCE,
};
pub use measure::{enclosed_volume, joint_cross_section, CrossSection};
pub use mesh::{
    mesh_for, scene_skeleton_for, tube_mesh, MeshBindings, MorphTarget, SkinnedMesh, ARM_BONES,
    ARM_JOINT_NAMES, ARM_LENGTH_CM,
};
pub use pose::{BonesBlendJoint, JointPalette, Pose};
pub use skeleton::{RestJoint, RestSkeleton, MAX_JOINTS};
