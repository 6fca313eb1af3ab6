//! keyrig-edit: editing a [`keyrig_core::Scene`] without a window, for the editor and the
//! command line alike.
//!
//! - [`edit`]: every queued change of the document as a value ([`SceneEdit`]), applied by one
//!   function and named by its undo label (docs/ARCHITECTURE.md, "Edits as data").
//! - [`channels`]: addressing animated values and the key operations on them.
//! - [`cleanup`]: key reduction to an error bound and Butterworth smoothing of dense keys.
//! - [`retarget`]: an action of one rig put onto another (bone map, rest alignment, root
//!   motion, planted feet).
//! - [`spin`]: the spins of turned keys and the unwrapped twist about a bone.
//! - [`mirror`]: left/right names, a skeleton's symmetry plane, mirrored poses.
//! - [`camera_edits`]: scene edits of cameras and markers shared by renaming and deleting.
//! - [`ik`]: IK constraints looked up by their end joint.
//! - [`scene_add`]: empties, primitives, lights and cameras the Add menu makes.

pub mod camera_edits;
pub mod channels;
pub mod cleanup;
pub mod edit;
pub mod ik;
pub mod mirror;
pub mod retarget;
pub mod scene_add;
pub mod spin;

pub use edit::{ClipEdit, KeyParamChange, KeyRef, SceneEdit};
