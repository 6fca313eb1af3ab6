//! Evaluating the scene at a time for display: channel values (with the editor's transient
//! pose overrides), object transforms and the skeleton's joint transforms.
//!
//! Values come from keyrig-core's validated tracks ([`AnimatedTrack`]), built once per
//! document revision in [`Tracks`] (tangents are computed when keys change, never per frame).
//! Joint transforms follow DESIGN.md §4: `F(j) = F(p(j))·R(j)·T(j)`, with the root's rest
//! translation plus the skeleton's animated root translation.

use std::collections::HashMap;

use glam::{Affine3A, Quat, Vec3};
use keyrig_core::{AnimatedTrack, Scene, TrackError};

use crate::channels::{channel, ChannelId, ChannelRef, ChannelValue};

/// Values set by a gizmo or the inspector on a keyed channel without record mode: shown until
/// the frame changes or the pose is keyed with I.
pub type PoseOverrides = HashMap<ChannelId, ChannelValue>;

/// One validated channel.
#[derive(Clone, Debug)]
enum ChannelTrack {
    Vec3(AnimatedTrack<Vec3>),
    Rotation(AnimatedTrack<Quat>),
    Scalar(AnimatedTrack<f32>),
}

impl ChannelTrack {
    fn new(c: ChannelRef<'_>) -> Result<Self, TrackError> {
        Ok(match c {
            ChannelRef::Vec3(a) => ChannelTrack::Vec3(AnimatedTrack::new(a)?),
            ChannelRef::Rotation(a) => ChannelTrack::Rotation(AnimatedTrack::new(a)?),
            ChannelRef::Scalar(a) => ChannelTrack::Scalar(AnimatedTrack::new(a)?),
        })
    }

    fn sample(&self, t: f64) -> ChannelValue {
        match self {
            ChannelTrack::Vec3(track) => ChannelValue::Vec3(track.sample(t)),
            ChannelTrack::Rotation(track) => ChannelValue::Rotation(track.sample(t)),
            ChannelTrack::Scalar(track) => ChannelValue::Scalar(track.sample(t)),
        }
    }
}

fn static_value(c: ChannelRef<'_>) -> ChannelValue {
    match c {
        ChannelRef::Vec3(a) => ChannelValue::Vec3(a.value),
        ChannelRef::Rotation(a) => ChannelValue::Rotation(a.value),
        ChannelRef::Scalar(a) => ChannelValue::Scalar(a.value),
    }
}

/// The validated tracks of every channel of a scene. A channel whose keys are invalid (e.g.
/// two keys at one time) shows its static value and is listed in [`Tracks::errors`].
#[derive(Clone, Debug, Default)]
pub struct Tracks {
    tracks: HashMap<ChannelId, ChannelTrack>,
    fallbacks: HashMap<ChannelId, ChannelValue>,
    errors: Vec<(ChannelId, TrackError)>,
}

impl Tracks {
    /// Validates every channel of `scene`.
    #[must_use]
    pub fn new(scene: &Scene) -> Self {
        let mut out = Tracks::default();
        for id in ChannelId::all(scene) {
            let Some(c) = channel(scene, id) else { continue };
            let fallback = static_value(ChannelRef::clone_ref(&c));
            match ChannelTrack::new(c) {
                Ok(track) => {
                    out.tracks.insert(id, track);
                }
                Err(e) => {
                    out.fallbacks.insert(id, fallback);
                    out.errors.push((id, e));
                }
            }
        }
        out
    }

    /// Channels whose tracks could not be validated, with the reason.
    #[must_use]
    pub fn errors(&self) -> &[(ChannelId, TrackError)] {
        &self.errors
    }

    /// The value of `id` at `time` seconds; an override wins. `None` when the channel does not
    /// exist.
    #[must_use]
    pub fn value(&self, id: ChannelId, time: f64, overrides: &PoseOverrides) -> Option<ChannelValue> {
        if let Some(v) = overrides.get(&id) {
            return Some(*v);
        }
        match self.tracks.get(&id) {
            Some(track) => Some(track.sample(time)),
            None => self.fallbacks.get(&id).copied(),
        }
    }

    fn vec3(&self, id: ChannelId, time: f64, o: &PoseOverrides, default: Vec3) -> Vec3 {
        match self.value(id, time, o) {
            Some(ChannelValue::Vec3(v)) => v,
            _ => default,
        }
    }

    fn quat(&self, id: ChannelId, time: f64, o: &PoseOverrides) -> Quat {
        match self.value(id, time, o) {
            Some(ChannelValue::Rotation(q)) if q.is_finite() && q.length_squared() > 1e-12 => q.normalize(),
            _ => Quat::IDENTITY,
        }
    }

    /// Evaluates object `index` of `scene` (the scene these tracks were built from).
    #[must_use]
    pub fn object_pose(
        &self,
        scene: &Scene,
        index: usize,
        time: f64,
        overrides: &PoseOverrides,
    ) -> Option<ObjectPose> {
        let object = scene.objects.get(index)?;
        let translation = self.vec3(ChannelId::ObjectTranslation(index), time, overrides, Vec3::ZERO);
        let rotation = self.quat(ChannelId::ObjectRotation(index), time, overrides);
        let scale = self.vec3(ChannelId::ObjectScale(index), time, overrides, Vec3::ONE);
        let world_from_object = Affine3A::from_scale_rotation_translation(scale, rotation, translation);
        let mut pose = keyrig_skin::Pose::rest(0);
        let mut object_from_joint: Vec<Affine3A> = Vec::new();
        if let Some(skeleton) = &object.skeleton {
            pose.root_translation = self.vec3(ChannelId::RootTranslation(index), time, overrides, Vec3::ZERO);
            for (j, joint) in skeleton.joints.iter().enumerate() {
                let t = self.quat(ChannelId::JointRotation { object: index, joint: j }, time, overrides);
                let translation = self.vec3(
                    ChannelId::JointTranslation { object: index, joint: j },
                    time,
                    overrides,
                    joint.translation.value,
                );
                let scale = self.vec3(
                    ChannelId::JointScale { object: index, joint: j },
                    time,
                    overrides,
                    joint.scale.value,
                );
                pose.local_translations.push(translation);
                pose.local_rotations.push(t);
                pose.local_scales.push(scale);
                let parent = joint.parent.filter(|&p| p < j).map(|p| object_from_joint[p]);
                let rest_translation = if parent.is_none() {
                    joint.rest_translation + pose.root_translation
                } else {
                    joint.rest_translation
                };
                let rest_rotation = if joint.rest_rotation.length_squared() > 1e-12 {
                    joint.rest_rotation.normalize()
                } else {
                    Quat::IDENTITY
                };
                let parent_from_joint = Affine3A::from_rotation_translation(rest_rotation, rest_translation)
                    * Affine3A::from_scale_rotation_translation(scale, t, translation);
                object_from_joint.push(match parent {
                    Some(p) => p * parent_from_joint,
                    None => parent_from_joint,
                });
            }
        }
        Some(ObjectPose { world_from_object, pose, object_from_joint })
    }
}
/// Samples one channel of `scene` at `time` seconds (validating just that channel); an
/// override wins. `None` when the channel does not exist. The editor itself samples through a
/// cached [`Tracks`]; this is for one-off queries and tests.
#[must_use]
pub fn channel_value(
    scene: &Scene,
    id: ChannelId,
    time: f64,
    overrides: &PoseOverrides,
) -> Option<ChannelValue> {
    if let Some(v) = overrides.get(&id) {
        return Some(*v);
    }
    let c = channel(scene, id)?;
    let fallback = static_value(ChannelRef::clone_ref(&c));
    Some(ChannelTrack::new(c).map_or(fallback, |t| t.sample(time)))
}

/// An object's evaluated state at one time.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectPose {
    /// World from object: T·R·S.
    pub world_from_object: Affine3A,
    /// The skeleton's local joint transforms T(j) and root translation (empty without one).
    pub pose: keyrig_skin::Pose,
    /// Model (object) space transform F(j) of each joint.
    pub object_from_joint: Vec<Affine3A>,
}

/// A rotation as XYZ Euler angles in degrees (what the curve view and inspector show).
#[must_use]
pub fn euler_degrees(q: Quat) -> Vec3 {
    let (x, y, z) = q.to_euler(glam::EulerRot::XYZ);
    Vec3::new(x.to_degrees(), y.to_degrees(), z.to_degrees())
}

/// The inverse of [`euler_degrees`].
#[must_use]
pub fn quat_from_euler_degrees(e: Vec3) -> Quat {
    Quat::from_euler(glam::EulerRot::XYZ, e.x.to_radians(), e.y.to_radians(), e.z.to_radians())
}

#[cfg(test)]
mod tests {
    use super::*;
    use keyrig_core::{Animated, Joint, Object, Skeleton};

    #[test]
    fn joint_transforms_chain_rest_and_rotation() {
        let mut scene = Scene::default();
        let mut arm = Object::new("Arm");
        let joint = |name: &str, parent, x| Joint::new(name, parent, Vec3::new(x, 0.0, 0.0), Quat::IDENTITY);
        let mut skeleton = Skeleton {
            joints: vec![joint("a", None, 0.0), joint("b", Some(0), 1.0)],
            root_translation: Animated::constant(Vec3::ZERO),
        };
        skeleton.joints[0].rotation.value = Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
        arm.skeleton = Some(skeleton);
        scene.objects.push(arm);
        let pose = Tracks::new(&scene).object_pose(&scene, 0, 0.0, &PoseOverrides::new()).expect("object 0");
        let b = pose.object_from_joint[1].translation;
        assert!((Vec3::from(b) - Vec3::Y).length() < 1e-6, "{b:?}");
    }

    #[test]
    fn euler_round_trip() {
        let e = Vec3::new(30.0, -20.0, 45.0);
        let back = euler_degrees(quat_from_euler_degrees(e));
        assert!((back - e).length() < 1e-3, "{back:?}");
    }
}
