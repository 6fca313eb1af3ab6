//! Channel ids: the animated values of a scene addressed by index (object, joint, light), as
//! the editor, the scene evaluator and its pose overrides name them, with their values.
//!
//! [`crate::channel::ChannelPath`] names the same values by name for the command line;
//! [`crate::channel::ChannelPath::id`] turns one into the other.

use glam::{EulerRot, Quat, Vec3};

pub mod attribute_id;

use crate::key::Animated;
use crate::object_constraint::{ConstraintKind, ObjectConstraint};
use crate::rotation_mode::RotationMode;
use crate::scene::Scene;
pub use attribute_id::AttributeId;

/// How rotations are printed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RotationFormat {
    /// The unit quaternion x, y, z, w.
    #[default]
    Quat,
    /// Euler angles in degrees, extrinsic X then Y then Z (q = Rz·Ry·Rx, Blender's "XYZ Euler").
    EulerDegrees,
}

/// One animated value of the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
pub enum ChannelId {
    ObjectTranslation(usize),
    ObjectRotation(usize),
    ObjectScale(usize),
    /// Translation of a skeleton's root joint (object index).
    RootTranslation(usize),
    /// A joint's animated local translation (imported characters; keyrig's rigs key rotations).
    JointTranslation {
        object: usize,
        joint: usize,
    },
    JointRotation {
        object: usize,
        joint: usize,
    },
    /// A joint's animated local scale.
    JointScale {
        object: usize,
        joint: usize,
    },
    LightPosition(usize),
    LightDirection(usize),
    LightColour(usize),
    LightIntensity(usize),
    /// The target of a skeleton's IK constraint (object space).
    IkTarget {
        object: usize,
        constraint: usize,
    },
    /// The IK/FK blend of a skeleton's IK constraint (0 = FK, 1 = IK).
    IkBlend {
        object: usize,
        constraint: usize,
    },
    /// Visibility, material, morph weights, deformer, light range and cone
    /// ([`crate::attributes`]).
    Attribute(AttributeId),
    /// A scene camera's position (camera index).
    CameraTranslation(usize),
    /// A scene camera's orientation (unused while it is aimed).
    CameraRotation(usize),
    /// A scene camera's lens: field of view (degrees), focal length (mm) or orthographic
    /// height, as its projection says.
    CameraLens(usize),
    /// The roll (degrees) of an aimed scene camera.
    CameraRoll(usize),
    /// The influence of a scene camera's aim (0 its keyed rotation, 1 the aim).
    CameraAimInfluence(usize),
    /// A scene camera's visibility: 1 shown, 0 hidden (Step keys).
    CameraVisible(usize),
    /// An object's Euler keys (x, y, z in degrees), listed in place of its rotation while it
    /// has them ([`crate::scene::Object::rotation_euler`]).
    ObjectEuler(usize),
    /// A joint's Euler keys, listed in place of its rotation while it has them.
    JointEuler {
        object: usize,
        joint: usize,
    },
    /// A keyed value of an object constraint ([`crate::object_constraint`]): its influence, a
    /// child-of constraint's parent index, a follow-path constraint's offset.
    Constraint {
        object: usize,
        constraint: usize,
        property: ConstraintProperty,
    },
}

/// The keyed values of an object constraint.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, serde::Serialize, serde::Deserialize)]
pub enum ConstraintProperty {
    /// 0 (no effect) to 1 (the constraint's result).
    Influence,
    /// A child-of constraint's parent: an index into its parents (Step keys).
    Parent,
    /// A follow-path constraint's offset along the path, 0 to 1.
    Offset,
}

impl ConstraintProperty {
    /// The name in channel paths (`object/<o>/constraint/<c>/<name>`).
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            ConstraintProperty::Influence => "influence",
            ConstraintProperty::Parent => "parent",
            ConstraintProperty::Offset => "offset",
        }
    }

    /// The property named `name` in a channel path.
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "influence" => ConstraintProperty::Influence,
            "parent" => ConstraintProperty::Parent,
            "offset" => ConstraintProperty::Offset,
            _ => return None,
        })
    }

    /// The field of the constraint that holds the channel, relative to the constraint.
    fn field(self) -> &'static str {
        match self {
            ConstraintProperty::Influence => "influence",
            ConstraintProperty::Parent => "kind.parent",
            ConstraintProperty::Offset => "kind.offset",
        }
    }

    /// The constraint's channel of this property, if it has one.
    #[must_use]
    pub fn of(self, c: &ObjectConstraint) -> Option<&Animated<f32>> {
        match (self, &c.kind) {
            (ConstraintProperty::Influence, _) => Some(&c.influence),
            (ConstraintProperty::Parent, ConstraintKind::ChildOf { parent, .. }) => Some(parent),
            (ConstraintProperty::Offset, ConstraintKind::FollowPath { offset, .. }) => Some(offset),
            _ => None,
        }
    }

    /// [`ConstraintProperty::of`], mutably.
    pub fn of_mut(self, c: &mut ObjectConstraint) -> Option<&mut Animated<f32>> {
        match (self, &mut c.kind) {
            (ConstraintProperty::Influence, _) => Some(&mut c.influence),
            (ConstraintProperty::Parent, ConstraintKind::ChildOf { parent, .. }) => Some(parent),
            (ConstraintProperty::Offset, ConstraintKind::FollowPath { offset, .. }) => Some(offset),
            _ => None,
        }
    }

    /// The properties a constraint has: its influence, then its kind's own.
    #[must_use]
    pub fn of_constraint(c: &ObjectConstraint) -> Vec<ConstraintProperty> {
        let mut out = vec![ConstraintProperty::Influence];
        match c.kind {
            ConstraintKind::ChildOf { .. } => out.push(ConstraintProperty::Parent),
            ConstraintKind::FollowPath { .. } => out.push(ConstraintProperty::Offset),
            _ => {}
        }
        out
    }
}

/// What kind of value a channel holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ChannelKind {
    Vec3,
    Rotation,
    Scalar,
}

impl ChannelId {
    #[must_use]
    pub fn kind(self) -> ChannelKind {
        match self {
            ChannelId::Attribute(a) => a.kind(),
            ChannelId::ObjectRotation(_) | ChannelId::JointRotation { .. } | ChannelId::CameraRotation(_) => {
                ChannelKind::Rotation
            }
            ChannelId::LightIntensity(_)
            | ChannelId::IkBlend { .. }
            | ChannelId::CameraLens(_)
            | ChannelId::CameraRoll(_)
            | ChannelId::CameraAimInfluence(_)
            | ChannelId::CameraVisible(_)
            | ChannelId::Constraint { .. } => ChannelKind::Scalar,
            _ => ChannelKind::Vec3,
        }
    }

    /// Short name of the channel ("rotation", "translation", ...).
    #[must_use]
    pub fn channel_name(self) -> &'static str {
        match self {
            ChannelId::ObjectTranslation(_) | ChannelId::JointTranslation { .. } => "translation",
            ChannelId::ObjectRotation(_) | ChannelId::JointRotation { .. } => "rotation",
            ChannelId::ObjectScale(_) | ChannelId::JointScale { .. } => "scale",
            ChannelId::RootTranslation(_) => "root translation",
            ChannelId::LightPosition(_) => "position",
            ChannelId::LightDirection(_) => "direction",
            ChannelId::LightColour(_) => "colour",
            ChannelId::LightIntensity(_) => "intensity",
            ChannelId::IkTarget { .. } => "IK target",
            ChannelId::IkBlend { .. } => "IK blend",
            ChannelId::Attribute(a) => a.channel_name(),
            ChannelId::CameraTranslation(_) => "translation",
            ChannelId::CameraRotation(_) => "rotation",
            ChannelId::CameraLens(_) => "lens",
            ChannelId::CameraRoll(_) => "roll",
            ChannelId::CameraAimInfluence(_) => "aim influence",
            ChannelId::CameraVisible(_) => "visible",
            ChannelId::ObjectEuler(_) | ChannelId::JointEuler { .. } => "rotation (Euler °)",
            ChannelId::Constraint { property, .. } => match property {
                ConstraintProperty::Influence => "influence",
                ConstraintProperty::Parent => "parent",
                ConstraintProperty::Offset => "path offset",
            },
        }
    }

    /// The field path of the channel's `Animated` value in the scene, e.g.
    /// `objects[0].skeleton.joints[2].rotation` (the paths of [`Scene::problems`]).
    #[must_use]
    pub fn field_path(self) -> String {
        match self {
            ChannelId::ObjectTranslation(o) => format!("objects[{o}].translation"),
            ChannelId::ObjectRotation(o) => format!("objects[{o}].rotation"),
            ChannelId::ObjectScale(o) => format!("objects[{o}].scale"),
            ChannelId::RootTranslation(o) => format!("objects[{o}].skeleton.root_translation"),
            ChannelId::JointTranslation { object, joint } => {
                format!("objects[{object}].skeleton.joints[{joint}].translation")
            }
            ChannelId::JointRotation { object, joint } => {
                format!("objects[{object}].skeleton.joints[{joint}].rotation")
            }
            ChannelId::JointScale { object, joint } => {
                format!("objects[{object}].skeleton.joints[{joint}].scale")
            }
            ChannelId::LightPosition(l) => format!("lights[{l}].position"),
            ChannelId::LightDirection(l) => format!("lights[{l}].direction"),
            ChannelId::LightColour(l) => format!("lights[{l}].colour"),
            ChannelId::LightIntensity(l) => format!("lights[{l}].intensity"),
            ChannelId::IkTarget { object, constraint } => {
                format!("objects[{object}].skeleton.ik_constraints[{constraint}].target")
            }
            ChannelId::IkBlend { object, constraint } => {
                format!("objects[{object}].skeleton.ik_constraints[{constraint}].blend")
            }
            ChannelId::Attribute(a) => a.field_path(),
            ChannelId::CameraTranslation(c) => format!("cameras[{c}].translation"),
            ChannelId::CameraRotation(c) => format!("cameras[{c}].rotation"),
            ChannelId::CameraLens(c) => format!("cameras[{c}].lens"),
            ChannelId::CameraRoll(c) => format!("cameras[{c}].aim.roll"),
            ChannelId::CameraAimInfluence(c) => format!("cameras[{c}].aim.influence"),
            ChannelId::CameraVisible(c) => format!("cameras[{c}].visible"),
            ChannelId::ObjectEuler(o) => format!("objects[{o}].rotation_euler"),
            ChannelId::JointEuler { object, joint } => {
                format!("objects[{object}].skeleton.joints[{joint}].rotation_euler")
            }
            ChannelId::Constraint { object, constraint, property } => {
                format!("objects[{object}].constraints[{constraint}].{}", property.field())
            }
        }
    }

    /// "Arm / Elbow rotation": the owner's name and the channel name, for labels.
    #[must_use]
    pub fn label(self, scene: &Scene) -> String {
        format!("{} {}", owner_name(scene, self).unwrap_or_else(|| "?".to_owned()), self.channel_name())
    }

    /// The channels of an object (its transform, skeleton root and joints), in display order.
    /// Every joint has its rotation; its translation and scale are listed only where they are
    /// keyed or not the identity (imported characters), so keyrig's own rigs show one row per
    /// joint. Each IK constraint adds its target and blend after the joints.
    #[must_use]
    pub fn of_object(scene: &Scene, object: usize) -> Vec<ChannelId> {
        let mut out = vec![
            ChannelId::ObjectTranslation(object),
            rotation_or_euler(scene, ChannelId::ObjectRotation(object)),
            ChannelId::ObjectScale(object),
        ];
        if let Some(skeleton) = scene.objects.get(object).and_then(|o| o.skeleton.as_ref()) {
            out.push(ChannelId::RootTranslation(object));
            for (joint, j) in skeleton.joints.iter().enumerate() {
                if j.translation.is_animated() || j.translation.value != Vec3::ZERO {
                    out.push(ChannelId::JointTranslation { object, joint });
                }
                out.push(if j.rotation_euler.is_some() {
                    ChannelId::JointEuler { object, joint }
                } else {
                    ChannelId::JointRotation { object, joint }
                });
                if j.scale.is_animated() || j.scale.value != Vec3::ONE {
                    out.push(ChannelId::JointScale { object, joint });
                }
            }
            for constraint in 0..skeleton.ik_constraints.len() {
                out.push(ChannelId::IkTarget { object, constraint });
                out.push(ChannelId::IkBlend { object, constraint });
            }
        }
        if let Some(o) = scene.objects.get(object) {
            for (constraint, c) in o.constraints.iter().enumerate() {
                out.extend(
                    ConstraintProperty::of_constraint(c).into_iter().map(|property| ChannelId::Constraint {
                        object,
                        constraint,
                        property,
                    }),
                );
            }
        }
        out.extend(AttributeId::of_object(scene, object));
        out
    }

    /// The channels of a light.
    #[must_use]
    pub fn of_light(light: usize) -> [ChannelId; 4] {
        [
            ChannelId::LightPosition(light),
            ChannelId::LightDirection(light),
            ChannelId::LightColour(light),
            ChannelId::LightIntensity(light),
        ]
    }

    /// The channels of a scene camera: translation, rotation, lens, its roll while it is
    /// aimed, and its visibility while keyed or hidden (as an object's: every camera has the
    /// channel, keying it lists it).
    #[must_use]
    pub fn of_camera(scene: &Scene, camera: usize) -> Vec<ChannelId> {
        let mut out = vec![
            ChannelId::CameraTranslation(camera),
            ChannelId::CameraRotation(camera),
            ChannelId::CameraLens(camera),
        ];
        let Some(c) = scene.cameras.get(camera) else { return out };
        if c.aim.is_some() {
            out.push(ChannelId::CameraRoll(camera));
            out.push(ChannelId::CameraAimInfluence(camera));
        }
        if c.visible.is_animated() || c.visible.value != 1.0 {
            out.push(ChannelId::CameraVisible(camera));
        }
        out
    }

    /// True for switches: whole-number values keyed with Step keys (visibility, the deformer).
    #[must_use]
    pub fn is_switch(self) -> bool {
        match self {
            ChannelId::Attribute(a) => a.is_switch(),
            ChannelId::CameraVisible(_)
            | ChannelId::Constraint { property: ConstraintProperty::Parent, .. } => true,
            _ => false,
        }
    }

    /// True for visibility channels (a 0/1 switch shown as a check box).
    #[must_use]
    pub fn is_visibility(self) -> bool {
        matches!(
            self,
            ChannelId::Attribute(AttributeId::ObjectVisible(_) | AttributeId::LightVisible(_))
                | ChannelId::CameraVisible(_)
        )
    }

    /// Every channel of the scene: objects, lights, then cameras.
    #[must_use]
    pub fn all(scene: &Scene) -> Vec<ChannelId> {
        let mut out = Vec::new();
        for o in 0..scene.objects.len() {
            out.extend(ChannelId::of_object(scene, o));
        }
        for l in 0..scene.lights.len() {
            out.extend(ChannelId::of_light(l));
            out.extend(AttributeId::of_light(scene, l));
        }
        for c in 0..scene.cameras.len() {
            out.extend(ChannelId::of_camera(scene, c));
        }
        out
    }
}

fn owner_name(scene: &Scene, id: ChannelId) -> Option<String> {
    Some(match id {
        ChannelId::ObjectTranslation(o)
        | ChannelId::ObjectRotation(o)
        | ChannelId::ObjectEuler(o)
        | ChannelId::ObjectScale(o)
        | ChannelId::RootTranslation(o) => scene.objects.get(o)?.name.clone(),
        ChannelId::JointTranslation { object, joint }
        | ChannelId::JointRotation { object, joint }
        | ChannelId::JointEuler { object, joint }
        | ChannelId::JointScale { object, joint } => {
            scene.objects.get(object)?.skeleton.as_ref()?.joints.get(joint)?.name.clone()
        }
        ChannelId::LightPosition(l)
        | ChannelId::LightDirection(l)
        | ChannelId::LightColour(l)
        | ChannelId::LightIntensity(l) => scene.lights.get(l)?.name.clone(),
        ChannelId::IkTarget { object, constraint } | ChannelId::IkBlend { object, constraint } => {
            scene.objects.get(object)?.skeleton.as_ref()?.ik_constraints.get(constraint)?.name.clone()
        }
        ChannelId::Attribute(a) => a.owner_name(scene)?,
        ChannelId::Constraint { object, constraint, .. } => {
            scene.objects.get(object)?.constraints.get(constraint)?.name.clone()
        }
        ChannelId::CameraTranslation(c)
        | ChannelId::CameraRotation(c)
        | ChannelId::CameraLens(c)
        | ChannelId::CameraRoll(c)
        | ChannelId::CameraAimInfluence(c)
        | ChannelId::CameraVisible(c) => scene.cameras.get(c)?.name.clone(),
    })
}

/// A borrowed channel of one of the three value types.
pub enum ChannelRef<'a> {
    Vec3(&'a Animated<Vec3>),
    Rotation(&'a Animated<Quat>),
    Scalar(&'a Animated<f32>),
}

/// A mutably borrowed channel.
pub enum ChannelMut<'a> {
    Vec3(&'a mut Animated<Vec3>),
    Rotation(&'a mut Animated<Quat>),
    Scalar(&'a mut Animated<f32>),
}

pub use crate::channel_value::ChannelValue;

impl ChannelValue {
    /// The value as numbers: x, y, z (or r, g, b); a rotation as the unit quaternion x, y, z, w
    /// or as Euler angles in degrees; a scalar alone.
    #[must_use]
    pub fn components(self, rotation: RotationFormat) -> Vec<f64> {
        match self {
            ChannelValue::Scalar(v) => vec![f64::from(v)],
            ChannelValue::Vec3(v) => v.to_array().map(f64::from).to_vec(),
            ChannelValue::Rotation(q) => match rotation {
                RotationFormat::Quat => q.to_array().map(f64::from).to_vec(),
                RotationFormat::EulerDegrees => {
                    let (x, y, z) = q.as_dquat().to_euler(EulerRot::XYZEx);
                    vec![x.to_degrees(), y.to_degrees(), z.to_degrees()]
                }
            },
        }
    }
}

/// Borrows a channel; `None` when the id does not name anything in `scene`.
#[must_use]
pub fn channel(scene: &Scene, id: ChannelId) -> Option<ChannelRef<'_>> {
    Some(match id {
        ChannelId::ObjectTranslation(o) => ChannelRef::Vec3(&scene.objects.get(o)?.translation),
        ChannelId::ObjectRotation(o) => ChannelRef::Rotation(&scene.objects.get(o)?.rotation),
        ChannelId::ObjectScale(o) => ChannelRef::Vec3(&scene.objects.get(o)?.scale),
        ChannelId::RootTranslation(o) => {
            ChannelRef::Vec3(&scene.objects.get(o)?.skeleton.as_ref()?.root_translation)
        }
        ChannelId::JointTranslation { object, joint } => {
            ChannelRef::Vec3(&scene.objects.get(object)?.skeleton.as_ref()?.joints.get(joint)?.translation)
        }
        ChannelId::JointRotation { object, joint } => {
            ChannelRef::Rotation(&scene.objects.get(object)?.skeleton.as_ref()?.joints.get(joint)?.rotation)
        }
        ChannelId::JointScale { object, joint } => {
            ChannelRef::Vec3(&scene.objects.get(object)?.skeleton.as_ref()?.joints.get(joint)?.scale)
        }
        ChannelId::LightPosition(l) => ChannelRef::Vec3(&scene.lights.get(l)?.position),
        ChannelId::LightDirection(l) => ChannelRef::Vec3(&scene.lights.get(l)?.direction),
        ChannelId::LightColour(l) => ChannelRef::Vec3(&scene.lights.get(l)?.colour),
        ChannelId::LightIntensity(l) => ChannelRef::Scalar(&scene.lights.get(l)?.intensity),
        ChannelId::IkTarget { object, constraint } => ChannelRef::Vec3(
            &scene.objects.get(object)?.skeleton.as_ref()?.ik_constraints.get(constraint)?.target,
        ),
        ChannelId::IkBlend { object, constraint } => ChannelRef::Scalar(
            &scene.objects.get(object)?.skeleton.as_ref()?.ik_constraints.get(constraint)?.blend,
        ),
        ChannelId::Attribute(a) => a.get(scene)?,
        ChannelId::CameraTranslation(c) => ChannelRef::Vec3(&scene.cameras.get(c)?.translation),
        ChannelId::CameraRotation(c) => ChannelRef::Rotation(&scene.cameras.get(c)?.rotation),
        ChannelId::CameraLens(c) => ChannelRef::Scalar(&scene.cameras.get(c)?.lens),
        ChannelId::CameraRoll(c) => ChannelRef::Scalar(&scene.cameras.get(c)?.aim.as_ref()?.roll),
        ChannelId::CameraAimInfluence(c) => {
            ChannelRef::Scalar(&scene.cameras.get(c)?.aim.as_ref()?.influence)
        }
        ChannelId::CameraVisible(c) => ChannelRef::Scalar(&scene.cameras.get(c)?.visible),
        ChannelId::ObjectEuler(o) => ChannelRef::Vec3(scene.objects.get(o)?.rotation_euler.as_ref()?),
        ChannelId::JointEuler { object, joint } => ChannelRef::Vec3(
            scene.objects.get(object)?.skeleton.as_ref()?.joints.get(joint)?.rotation_euler.as_ref()?,
        ),
        ChannelId::Constraint { object, constraint, property } => {
            ChannelRef::Scalar(property.of(scene.objects.get(object)?.constraints.get(constraint)?)?)
        }
    })
}

/// Mutably borrows a channel; `None` when the id does not name anything in `scene`.
#[must_use]
pub fn channel_mut(scene: &mut Scene, id: ChannelId) -> Option<ChannelMut<'_>> {
    Some(match id {
        ChannelId::ObjectTranslation(o) => ChannelMut::Vec3(&mut scene.objects.get_mut(o)?.translation),
        ChannelId::ObjectRotation(o) => ChannelMut::Rotation(&mut scene.objects.get_mut(o)?.rotation),
        ChannelId::ObjectScale(o) => ChannelMut::Vec3(&mut scene.objects.get_mut(o)?.scale),
        ChannelId::RootTranslation(o) => {
            ChannelMut::Vec3(&mut scene.objects.get_mut(o)?.skeleton.as_mut()?.root_translation)
        }
        ChannelId::JointTranslation { object, joint } => ChannelMut::Vec3(
            &mut scene.objects.get_mut(object)?.skeleton.as_mut()?.joints.get_mut(joint)?.translation,
        ),
        ChannelId::JointRotation { object, joint } => ChannelMut::Rotation(
            &mut scene.objects.get_mut(object)?.skeleton.as_mut()?.joints.get_mut(joint)?.rotation,
        ),
        ChannelId::JointScale { object, joint } => ChannelMut::Vec3(
            &mut scene.objects.get_mut(object)?.skeleton.as_mut()?.joints.get_mut(joint)?.scale,
        ),
        ChannelId::LightPosition(l) => ChannelMut::Vec3(&mut scene.lights.get_mut(l)?.position),
        ChannelId::LightDirection(l) => ChannelMut::Vec3(&mut scene.lights.get_mut(l)?.direction),
        ChannelId::LightColour(l) => ChannelMut::Vec3(&mut scene.lights.get_mut(l)?.colour),
        ChannelId::LightIntensity(l) => ChannelMut::Scalar(&mut scene.lights.get_mut(l)?.intensity),
        ChannelId::IkTarget { object, constraint } => ChannelMut::Vec3(
            &mut scene.objects.get_mut(object)?.skeleton.as_mut()?.ik_constraints.get_mut(constraint)?.target,
        ),
        ChannelId::IkBlend { object, constraint } => ChannelMut::Scalar(
            &mut scene.objects.get_mut(object)?.skeleton.as_mut()?.ik_constraints.get_mut(constraint)?.blend,
        ),
        ChannelId::Attribute(a) => a.get_mut(scene)?,
        ChannelId::CameraTranslation(c) => ChannelMut::Vec3(&mut scene.cameras.get_mut(c)?.translation),
        ChannelId::CameraRotation(c) => ChannelMut::Rotation(&mut scene.cameras.get_mut(c)?.rotation),
        ChannelId::CameraLens(c) => ChannelMut::Scalar(&mut scene.cameras.get_mut(c)?.lens),
        ChannelId::CameraRoll(c) => ChannelMut::Scalar(&mut scene.cameras.get_mut(c)?.aim.as_mut()?.roll),
        ChannelId::CameraAimInfluence(c) => {
            ChannelMut::Scalar(&mut scene.cameras.get_mut(c)?.aim.as_mut()?.influence)
        }
        ChannelId::CameraVisible(c) => ChannelMut::Scalar(&mut scene.cameras.get_mut(c)?.visible),
        ChannelId::ObjectEuler(o) => ChannelMut::Vec3(scene.objects.get_mut(o)?.rotation_euler.as_mut()?),
        ChannelId::JointEuler { object, joint } => ChannelMut::Vec3(
            scene
                .objects
                .get_mut(object)?
                .skeleton
                .as_mut()?
                .joints
                .get_mut(joint)?
                .rotation_euler
                .as_mut()?,
        ),
        ChannelId::Constraint { object, constraint, property } => ChannelMut::Scalar(
            property.of_mut(scene.objects.get_mut(object)?.constraints.get_mut(constraint)?)?,
        ),
    })
}

/// The rotation mode of a rotation (or Euler-keys) channel's object or joint (the default for
/// other channels).
#[must_use]
pub fn rotation_mode(scene: &Scene, id: ChannelId) -> RotationMode {
    match id {
        ChannelId::ObjectRotation(o) | ChannelId::ObjectEuler(o) => {
            scene.objects.get(o).map(|o| o.rotation_mode)
        }
        ChannelId::JointRotation { object, joint } | ChannelId::JointEuler { object, joint } => scene
            .objects
            .get(object)
            .and_then(|o| o.skeleton.as_ref())
            .and_then(|s| s.joints.get(joint))
            .map(|j| j.rotation_mode),
        _ => None,
    }
    .unwrap_or_default()
}

/// Sets the rotation mode of a rotation channel's object or joint; false when `id` is not one.
/// This only changes how quaternion keys read: a channel with Euler keys changes order through
/// [`crate::rotation_mode::set_rotation_keys`], which converts the keys.
pub fn set_rotation_mode(scene: &mut Scene, id: ChannelId, mode: RotationMode) -> bool {
    let slot = match id {
        ChannelId::ObjectRotation(o) | ChannelId::ObjectEuler(o) => {
            scene.objects.get_mut(o).map(|o| &mut o.rotation_mode)
        }
        ChannelId::JointRotation { object, joint } | ChannelId::JointEuler { object, joint } => scene
            .objects
            .get_mut(object)
            .and_then(|o| o.skeleton.as_mut())
            .and_then(|s| s.joints.get_mut(joint))
            .map(|j| &mut j.rotation_mode),
        _ => None,
    };
    match slot {
        Some(slot) => {
            *slot = mode;
            true
        }
        None => false,
    }
}

/// The Euler-keys channel of a rotation channel's object or joint (and the other way round):
/// `ObjectRotation(o)` ↔ `ObjectEuler(o)`, `JointRotation` ↔ `JointEuler`; `None` for other
/// channels.
#[must_use]
pub fn euler_partner(id: ChannelId) -> Option<ChannelId> {
    Some(match id {
        ChannelId::ObjectRotation(o) => ChannelId::ObjectEuler(o),
        ChannelId::ObjectEuler(o) => ChannelId::ObjectRotation(o),
        ChannelId::JointRotation { object, joint } => ChannelId::JointEuler { object, joint },
        ChannelId::JointEuler { object, joint } => ChannelId::JointRotation { object, joint },
        _ => return None,
    })
}

/// The channel that holds a rotation's keys: the Euler-keys channel when the object or joint
/// has Euler keys, else `id` itself (every other channel too).
#[must_use]
pub fn rotation_or_euler(scene: &Scene, id: ChannelId) -> ChannelId {
    match euler_partner(id) {
        Some(euler @ (ChannelId::ObjectEuler(_) | ChannelId::JointEuler { .. }))
            if channel(scene, euler).is_some() =>
        {
            euler
        }
        _ => id,
    }
}

/// The Euler keys of a rotation or Euler-keys channel's object or joint and their order;
/// `None` when it has none (quaternion keys) or `id` is another channel.
#[must_use]
pub fn euler_keys(scene: &Scene, id: ChannelId) -> Option<(&Animated<Vec3>, crate::EulerOrder)> {
    let euler = match id {
        ChannelId::ObjectEuler(_) | ChannelId::JointEuler { .. } => id,
        _ => euler_partner(id)?,
    };
    let Some(ChannelRef::Vec3(keys)) = channel(scene, euler) else { return None };
    Some((keys, rotation_mode(scene, euler).euler().unwrap_or_default()))
}

/// The rotation, Euler keys and rotation mode of a rotation (or Euler-keys) channel's object
/// or joint.
type RotationParts<'a> = (&'a mut Animated<Quat>, &'a mut Option<Animated<Vec3>>, &'a mut RotationMode);

fn rotation_parts(scene: &mut Scene, id: ChannelId) -> Option<RotationParts<'_>> {
    match id {
        ChannelId::ObjectRotation(o) | ChannelId::ObjectEuler(o) => {
            let o = scene.objects.get_mut(o)?;
            Some((&mut o.rotation, &mut o.rotation_euler, &mut o.rotation_mode))
        }
        ChannelId::JointRotation { object, joint } | ChannelId::JointEuler { object, joint } => {
            let j = scene.objects.get_mut(object)?.skeleton.as_mut()?.joints.get_mut(joint)?;
            Some((&mut j.rotation, &mut j.rotation_euler, &mut j.rotation_mode))
        }
        _ => None,
    }
}

/// Whether a rotation channel's object or joint has Euler keys.
#[must_use]
pub fn has_euler_keys(scene: &Scene, id: ChannelId) -> bool {
    euler_keys(scene, id).is_some()
}

/// Sets the rotation mode of a rotation (or Euler-keys) channel's object or joint, with Euler
/// keys when `euler` is true and `mode` is an Euler order, else with quaternion keys, and
/// converts its keys (docs/channels.md, "Euler keys"):
/// * quaternion → Euler keys: [`crate::rotation_mode::euler_keys_from_quaternions`];
/// * Euler keys in another order: [`crate::rotation_mode::reorder_euler_keys`];
/// * Euler → quaternion keys: [`crate::rotation_mode::quaternion_keys_from_euler`];
/// * quaternion keys in another mode: only the mode changes (what the inspector shows).
///
/// Returns false (and changes nothing) when `id` is not a rotation of an object or joint or
/// the rotation is locked.
///
/// # Errors
/// The [`crate::TrackError`] of keys that are invalid (nothing changes).
pub fn set_rotation_keys(
    scene: &mut Scene,
    id: ChannelId,
    mode: RotationMode,
    euler: bool,
) -> Result<bool, crate::TrackError> {
    use crate::rotation_mode::{euler_keys_from_quaternions, quaternion_keys_from_euler, reorder_euler_keys};
    let Some((rotation, keys, current)) = rotation_parts(scene, id) else { return Ok(false) };
    if rotation.locked || keys.as_ref().is_some_and(|k| k.locked) {
        return Ok(false);
    }
    let from = current.euler().unwrap_or_default();
    match (keys.as_ref(), mode.euler().filter(|_| euler)) {
        (None, None) => {}
        (None, Some(order)) => {
            let new = euler_keys_from_quaternions(rotation, order)?;
            *rotation = Animated::constant(order.to_quat(new.value));
            *keys = Some(new);
        }
        (Some(old), Some(order)) => {
            if order != from {
                *keys = Some(reorder_euler_keys(old, from, order)?);
            }
        }
        (Some(old), None) => {
            *rotation = quaternion_keys_from_euler(old, from)?;
            *keys = None;
        }
    }
    *current = mode;
    Ok(true)
}
