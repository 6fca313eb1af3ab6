//! The editor's view of the scene evaluator (keyrig-eval): pose overrides, an object's state
//! as the panels read it, and the Euler angles the inspector and curve view show.
//!
//! Every panel evaluates through the one [`keyrig_eval::SceneEvaluator`] that
//! [`crate::scene_frame::SceneFrame`] keeps for the document (brought in step when the document
//! or its loaded meshes change): the viewport, the GPU view, the motion path and the curve view
//! see the same values, overrides included.

use glam::{Affine3A, Quat, Vec3};
use keyrig_core::Scene;

use crate::channels::{ChannelId, ChannelValue};

/// Values set by a gizmo or the inspector on a keyed channel without record mode: shown until
/// the frame changes or the pose is keyed with I.
pub type PoseOverrides = keyrig_eval::Overrides;

/// Samples one channel of `scene` at `time` seconds (validating the scene's procedural data
/// once); an override wins. `None` when the channel does not exist. The editor itself samples
/// through its cached evaluator; this is for one-off queries and tests.
#[must_use]
pub fn channel_value(
    scene: &Scene,
    id: ChannelId,
    time: f64,
    overrides: &PoseOverrides,
) -> Option<ChannelValue> {
    keyrig_eval::SceneEvaluator::new(scene, &std::collections::HashMap::new()).value(id, time, overrides)
}

/// An object's evaluated state at one time, as the panels read it.
#[derive(Clone, Debug)]
pub struct ObjectPose {
    /// World from object: T·R·S.
    pub world_from_object: Affine3A,
    /// The skeleton's local joint transforms T(j) and root translation (empty without one).
    pub pose: keyrig_skin::Pose,
    /// Model (object) space transform F(j) of each joint (the palette's, composed once by the
    /// evaluator); empty without a skeleton.
    pub object_from_joint: Vec<Affine3A>,
}

impl ObjectPose {
    /// The panels' view of an evaluated object.
    #[must_use]
    pub fn from_state(state: &keyrig_eval::ObjectState) -> Self {
        let pose = state.pose.clone().unwrap_or_else(|| keyrig_skin::Pose::rest(0));
        let object_from_joint = match (&state.pose, &state.palette) {
            (Some(_), Some(palette)) => palette.model_from_joint.clone(),
            _ => Vec::new(),
        };
        ObjectPose { world_from_object: state.world_from_object, pose, object_from_joint }
    }
}

/// The rotation order of the Euler angles the inspector and the curve view show
/// ([`euler_degrees`]).
pub const EULER_ORDER: &str = "XYZ";

/// What [`EULER_ORDER`] means, for tooltips.
pub const EULER_ORDER_HELP: &str =
    "Euler angles in the order XYZ, intrinsic: R = Rx·Ry·Rz (turn about X, then about \
     the turned Y, then about the turned Z; glam's EulerRot::XYZ). Blender calls the same \
     rotation order ZYX, Maya zyx.";

/// A rotation as XYZ Euler angles in degrees (what the curve view and inspector show), in the
/// order [`EULER_ORDER`].
#[must_use]
pub fn euler_degrees(q: Quat) -> Vec3 {
    let (x, y, z) = q.to_euler(glam::EulerRot::XYZ);
    // Angles in (−180, 180]: a half turn reads 180 as the curve view shows it, not −180
    // (within the f32 noise of the conversion).
    let half_turn = |d: f32| if d <= -179.9995 { d + 360.0 } else { d };
    Vec3::new(half_turn(x.to_degrees()), half_turn(y.to_degrees()), half_turn(z.to_degrees()))
}

/// The inverse of [`euler_degrees`].
#[must_use]
pub fn quat_from_euler_degrees(e: Vec3) -> Quat {
    Quat::from_euler(glam::EulerRot::XYZ, e.x.to_radians(), e.y.to_radians(), e.z.to_radians())
}

/// The twist about the bone axis ([`crate::twist::BONE_AXIS`]) of rotation `q` shown for
/// channel `id` at `time`, degrees, unwrapped through the channel's spin keys (720 after two
/// turns); a value off the track (a pose override) reads as its twist nearest the track's.
#[must_use]
pub fn twist_now(scene: &Scene, id: ChannelId, q: Quat, time: f64) -> f64 {
    use crate::twist::{nearest_turn, twist_degrees, unwrapped_twist, BONE_AXIS};
    let axis = BONE_AXIS.as_dvec3();
    let wrapped = twist_degrees(q.as_dquat(), axis);
    let track = match crate::channels::channel(scene, id) {
        Some(crate::channels::ChannelRef::Rotation(a)) if !a.track.is_empty() => {
            keyrig_core::Track::new(&a.track).ok()
        }
        _ => None,
    };
    match track {
        Some(track) => nearest_turn(wrapped, unwrapped_twist(&track, axis, time)),
        None => wrapped,
    }
}

#[cfg(test)]
mod half_turn_tests {
    use super::*;

    #[test]
    fn a_half_turn_reads_180_not_minus_180() {
        let e = euler_degrees(Quat::from_rotation_x(-std::f32::consts::PI));
        assert!((e.x - 180.0).abs() < 1e-3, "{e:?}");
        let back = quat_from_euler_degrees(e);
        assert!(back.dot(Quat::from_rotation_x(std::f32::consts::PI)).abs() > 1.0 - 1e-6);
        let e = euler_degrees(Quat::from_rotation_x(-1.0));
        assert!((e.x + 1f32.to_degrees()).abs() < 1e-3, "other angles keep their sign: {e:?}");
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn euler_round_trip() {
        let e = Vec3::new(30.0, -20.0, 45.0);
        let back = euler_degrees(quat_from_euler_degrees(e));
        assert!((back - e).length() < 1e-3, "{back:?}");
    }
}
