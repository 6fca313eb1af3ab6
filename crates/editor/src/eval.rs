//! The editor's view of the scene evaluator (keyrig-eval): pose overrides, an object's state
//! as the panels read it, and the Euler angles the inspector and curve view show.
//!
//! Every panel evaluates through the one [`keyrig_eval::SceneEvaluator`] that
//! [`crate::scene_frame::SceneFrame`] keeps for the document (brought in step when the document
//! or its loaded meshes change): the viewport, the GPU view, the motion path and the curve view
//! see the same values, overrides included.

use glam::{Affine3A, Quat, Vec3};
use keyrig_core::Scene;

use keyrig_edit::channels::{ChannelId, ChannelValue};

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

/// The rotation order of the Euler angles shown for a channel without a rotation mode of its
/// own ([`euler_degrees`]); each object and joint can choose its own
/// ([`keyrig_core::RotationMode`]).
pub const EULER_ORDER: &str = "XYZ";

/// What [`EULER_ORDER`] means, for tooltips.
pub const EULER_ORDER_HELP: &str =
    "Euler angles in the order XYZ, as Blender and Maya name it: R = Rz·Ry·Rx (turn about X \
     first, then Y, then Z, about the parent's axes; glam's EulerRot::XYZEx, scipy's \"xyz\").";

/// A rotation as XYZ Euler angles in degrees, each in (−180, 180] ([`EULER_ORDER`]).
#[must_use]
pub fn euler_degrees(q: Quat) -> Vec3 {
    keyrig_core::EulerOrder::XYZ.angles(q)
}

/// The inverse of [`euler_degrees`].
#[must_use]
pub fn quat_from_euler_degrees(e: Vec3) -> Quat {
    keyrig_core::EulerOrder::XYZ.to_quat(e)
}

/// Most halvings of one step of [`continuous_euler`]'s walk.
const MAX_HALVINGS: u32 = 12;

/// Largest turn between two readings of [`continuous_euler`]'s walk, degrees: small enough
/// that the nearest Euler triple is the continuation.
const WALK_STEP_DEGREES: f32 = 30.0;

/// Euler angles (degrees, `order`) of rotation channel `id` at `time`, continuous from the
/// channel's first key: the walk reads the keyed rotation from the first key to `time` in
/// steps of at most [`WALK_STEP_DEGREES`] (through every turn of a spin segment), each reading
/// the triple nearest the last ([`keyrig_core::EulerOrder::angles_near`]). A spin about Y reads
/// Y 0 → 360 → 720 with X and Z at 0. The value at `time` itself has the overrides; `None`
/// when the channel does not exist.
#[must_use]
pub fn continuous_euler(
    eval: &keyrig_eval::SceneEvaluator,
    scene: &Scene,
    id: ChannelId,
    order: keyrig_core::EulerOrder,
    time: f64,
    overrides: &PoseOverrides,
) -> Option<Vec3> {
    let Some(ChannelValue::Rotation(now)) = eval.value(id, time, overrides) else { return None };
    let keys = match keyrig_edit::channels::channel(scene, id) {
        Some(keyrig_edit::channels::ChannelRef::Rotation(a)) => &a.track.keys,
        _ => return Some(order.angles(now)),
    };
    let none = PoseOverrides::new();
    let rotation = |t: f64| match eval.value(id, t, &none) {
        Some(ChannelValue::Rotation(q)) => q,
        _ => now,
    };
    let Some(first) = keys.first().filter(|k| k.time < time) else { return Some(order.angles(now)) };
    let mut e = order.angles(rotation(first.time));
    let mut q = rotation(first.time);
    // Checkpoints: every key up to `time`, each segment cut into at least 8 pieces per turn
    // its spin makes.
    for (i, key) in keys.iter().enumerate().skip(1) {
        let (t0, t1) = (keys[i - 1].time, key.time.min(time));
        if t1 <= t0 {
            break;
        }
        let turns = match key.spin {
            Some(keyrig_core::Spin::Turns(n)) => f64::from(n.unsigned_abs()) + 1.0,
            Some(keyrig_core::Spin::Angle { degrees, .. }) => degrees.abs() / 360.0 + 1.0,
            None => 1.0,
        };
        let pieces = (8.0 * turns).min(8.0 * f64::from(keyrig_core::MAX_SPIN_TURNS) + 8.0) as usize;
        for p in 1..=pieces {
            let t = t0 + (t1 - t0) * p as f64 / pieces as f64;
            walk(&rotation, order, &mut e, &mut q, t - (t1 - t0) / pieces as f64, t, 0);
        }
        if key.time >= time {
            break;
        }
    }
    if keys.last().is_some_and(|k| k.time < time) {
        let from = keys.last().map_or(time, |k| k.time);
        for p in 1..=8 {
            let t = from + (time - from) * f64::from(p) / 8.0;
            walk(&rotation, order, &mut e, &mut q, t - (time - from) / 8.0, t, 0);
        }
    }
    Some(order.angles_near(now, e))
}

/// One step of [`continuous_euler`]'s walk from `t0` (read as `e`, rotation `q`) to `t1`,
/// halved while it turns more than [`WALK_STEP_DEGREES`].
fn walk(
    rotation: &impl Fn(f64) -> Quat,
    order: keyrig_core::EulerOrder,
    e: &mut Vec3,
    q: &mut Quat,
    t0: f64,
    t1: f64,
    depth: u32,
) {
    let next = rotation(t1);
    if depth < MAX_HALVINGS && q.angle_between(next).to_degrees() > WALK_STEP_DEGREES {
        let mid = 0.5 * (t0 + t1);
        walk(rotation, order, e, q, t0, mid, depth + 1);
        walk(rotation, order, e, q, mid, t1, depth + 1);
        return;
    }
    *e = order.angles_near(next, *e);
    *q = next;
}

/// The twist about the bone axis ([`keyrig_edit::spin::BONE_AXIS`]) of rotation `q` shown for
/// channel `id` at `time`, degrees, unwrapped through the channel's spin keys (720 after two
/// turns); a value off the track (a pose override) reads as its twist nearest the track's.
#[must_use]
pub fn twist_now(scene: &Scene, id: ChannelId, q: Quat, time: f64) -> f64 {
    use keyrig_edit::spin::{nearest_turn, twist_degrees, unwrapped_twist, BONE_AXIS};
    let axis = BONE_AXIS.as_dvec3();
    let wrapped = twist_degrees(q.as_dquat(), axis);
    let track = match keyrig_edit::channels::channel(scene, id) {
        Some(keyrig_edit::channels::ChannelRef::Rotation(a)) if !a.track.is_empty() => {
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
