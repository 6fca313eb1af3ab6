//! keyrig-eval: the scene evaluator — the one path from a scene's keys to what is drawn,
//! deformed, sampled and exported at a time (docs/design.md §2).
//!
//! [`SceneEvaluator::new`] validates a [`keyrig_core::Scene`] once: every channel's track
//! (keyrig-core), each skeleton's rest data and each skinned mesh with its deformer bindings
//! (keyrig-skin), each vertex-animated mesh's clips ([`morph`]). [`SceneEvaluator::evaluate`]
//! then answers "the scene at time t": object world transforms, light states, each skeleton's
//! local joint transforms and joint palette (F(j) composed once), morph frames. Pose overrides
//! (values being dragged but not keyed) take part in the same evaluation, so the viewport, the
//! motion path and the curve view all see them.
//!
//! IK constraints are solved after forward kinematics, blended by their IK/FK blend channel;
//! [`bake`] writes their result as rotation keys. Object constraints (aim at, child of, copy
//! location and rotation, follow path; docs/constraints.md) are applied to each object's world
//! transform after its targets are evaluated; [`constraints`] switches a child-of parent and
//! bakes them to keys.
//!
//! Pure: no files, GPU or UI. Model files are loaded by keyrig-io and handed in as
//! [`LoadedMesh`]es.

pub mod bake;
pub mod camera;
mod clips;
pub mod constraints;
mod evaluator;
pub mod merge;
pub mod morph;
mod slot;

pub use bake::{bake_all_ik, bake_ik_constraint, BakeError, Baked};
pub use camera::CameraState;
pub use constraints::{bake_object_constraints, switch_parent, SwitchError};
pub use evaluator::{
    EvalProblem, LightState, LoadedMesh, MorphRig, ObjectLook, ObjectState, Overrides, Rebuilt,
    SceneEvaluator, SceneState, SkinRig,
};
pub use merge::{merge_down, Merged};
