//! Channel paths: how a user names one animated value of a scene, e.g.
//! `object/Arm/joint/elbow/rotation` or `light/Key/intensity` (docs/channels.md).
//!
//! ```text
//! object/<object>/translation        Vec3   the object's translation
//! object/<object>/rotation           Quat   the object's rotation
//! object/<object>/rotation_euler     Vec3   its Euler keys (x, y, z degrees), when it has them
//! object/<object>/scale              Vec3   the object's scale
//! object/<object>/root_translation   Vec3   translation of the skeleton's root joint
//! object/<object>/joint/<joint>/rotation     Quat   the rotation of a joint's local transform T(j)
//! object/<object>/joint/<joint>/rotation_euler  Vec3  its Euler keys, when it has them
//! object/<object>/joint/<joint>/translation  Vec3   the translation of T(j) (imported characters)
//! object/<object>/joint/<joint>/scale        Vec3   the scale of T(j)
//! object/<object>/ik/<constraint>/target     Vec3   an IK constraint's target (object space)
//! object/<object>/ik/<constraint>/blend      f32    an IK constraint's IK/FK blend (0 FK, 1 IK)
//! object/<object>/constraint/<constraint>/influence  f32  an object constraint's influence (0..1)
//! object/<object>/constraint/<constraint>/parent     f32  a child-of constraint's parent index
//! object/<object>/constraint/<constraint>/offset     f32  a follow-path constraint's offset (0..1)
//! light/<light>/position             Vec3
//! light/<light>/direction            Vec3
//! light/<light>/colour               Vec3   linear RGB
//! light/<light>/intensity            f32
//! camera/<camera>/translation        Vec3   a scene camera's position (world space)
//! camera/<camera>/rotation           Quat   its orientation (looks down −Z, +Y up)
//! camera/<camera>/lens               f32    field of view °, focal length mm or ortho height
//! camera/<camera>/roll               f32    an aimed camera's roll about its view axis, °
//! camera/<camera>/aim_influence      f32    an aimed camera's aim influence, 0..1
//! ```
//!
//! [`ChannelPath::parse`] checks the syntax; [`ChannelPath::resolve`] finds the value in a
//! [`Scene`] and validates its track into a [`Channel`] that samples it. Errors name what is
//! unknown and list what exists.

use std::fmt;

use glam::{Quat, Vec3};

use crate::channel_id::attribute_id::{AttributeId, AttributeProperty};
use crate::channel_id::{channel, ChannelId, ChannelKind, ChannelRef, ConstraintProperty};
use crate::key::Animated;
use crate::scene::{Object, Scene};
use crate::track::{AnimatedTrack, TrackError};
use crate::validate::track_error_path;

/// Properties of an object.
pub const OBJECT_PROPERTIES: [&str; 15] = [
    "translation",
    "rotation",
    "rotation_euler",
    "scale",
    "root_translation",
    "joint",
    "ik",
    "constraint",
    "visible",
    "colour",
    "opacity",
    "morph",
    "deformer",
    "blend_parent_fraction",
    "blend_child_fraction",
];
/// Properties of a joint.
pub const JOINT_PROPERTIES: [&str; 4] = ["translation", "rotation", "rotation_euler", "scale"];
/// Properties of an IK constraint.
pub const IK_PROPERTIES: [&str; 2] = ["target", "blend"];
/// Properties of an object constraint (each constraint has the ones its kind keys).
pub const CONSTRAINT_PROPERTIES: [&str; 3] = ["influence", "parent", "offset"];
/// Properties of a light.
pub const LIGHT_PROPERTIES: [&str; 8] =
    ["position", "direction", "colour", "intensity", "visible", "range", "cutoff_deg", "inner_angle_deg"];

/// Properties of a scene camera.
pub const CAMERA_PROPERTIES: [&str; 6] =
    ["translation", "rotation", "lens", "roll", "aim_influence", "visible"];

/// One animated value of a scene camera.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum CameraProperty {
    Translation,
    Rotation,
    Lens,
    Roll,
    AimInfluence,
    Visible,
}

impl CameraProperty {
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            CameraProperty::Translation => "translation",
            CameraProperty::Rotation => "rotation",
            CameraProperty::Lens => "lens",
            CameraProperty::Roll => "roll",
            CameraProperty::AimInfluence => "aim_influence",
            CameraProperty::Visible => "visible",
        }
    }
}

/// One animated value of an object.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum ObjectProperty {
    Translation,
    Rotation,
    /// The Euler keys (x, y, z degrees) of an object that has them.
    RotationEuler,
    Scale,
    RootTranslation,
}

impl ObjectProperty {
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            ObjectProperty::Translation => "translation",
            ObjectProperty::Rotation => "rotation",
            ObjectProperty::RotationEuler => "rotation_euler",
            ObjectProperty::Scale => "scale",
            ObjectProperty::RootTranslation => "root_translation",
        }
    }
}

/// One animated part of a joint's local transform T(j).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum JointProperty {
    Translation,
    Rotation,
    /// The Euler keys (x, y, z degrees) of a joint that has them.
    RotationEuler,
    Scale,
}

impl JointProperty {
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            JointProperty::Translation => "translation",
            JointProperty::Rotation => "rotation",
            JointProperty::RotationEuler => "rotation_euler",
            JointProperty::Scale => "scale",
        }
    }
}

/// One animated value of an IK constraint.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum IkProperty {
    Target,
    Blend,
}

impl IkProperty {
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            IkProperty::Target => "target",
            IkProperty::Blend => "blend",
        }
    }
}

/// One animated value of a light.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum LightProperty {
    Position,
    Direction,
    Colour,
    Intensity,
}

impl LightProperty {
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            LightProperty::Position => "position",
            LightProperty::Direction => "direction",
            LightProperty::Colour => "colour",
            LightProperty::Intensity => "intensity",
        }
    }
}

/// A parsed channel path (names, not yet looked up in a scene).
#[derive(Clone, Debug, PartialEq, Eq, Hash)]
pub enum ChannelPath {
    Object {
        object: String,
        property: ObjectProperty,
    },
    Joint {
        object: String,
        joint: String,
        property: JointProperty,
    },
    Ik {
        object: String,
        constraint: String,
        property: IkProperty,
    },
    /// A keyed value of an object constraint (`object/<o>/constraint/<c>/<property>`).
    Constraint {
        object: String,
        constraint: String,
        property: ConstraintProperty,
    },
    Light {
        light: String,
        property: LightProperty,
    },
    /// An attribute of an object or a light ([`crate::attributes`]): `object/<name>/visible`,
    /// `object/<name>/morph/<target>`, `light/<name>/range`, …
    Attribute {
        light: bool,
        owner: String,
        property: AttributeProperty,
    },
    Camera {
        camera: String,
        property: CameraProperty,
    },
}

impl fmt::Display for ChannelPath {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ChannelPath::Object { object, property } => write!(f, "object/{object}/{}", property.name()),
            ChannelPath::Joint { object, joint, property } => {
                write!(f, "object/{object}/joint/{joint}/{}", property.name())
            }
            ChannelPath::Ik { object, constraint, property } => {
                write!(f, "object/{object}/ik/{constraint}/{}", property.name())
            }
            ChannelPath::Constraint { object, constraint, property } => {
                write!(f, "object/{object}/constraint/{constraint}/{}", property.name())
            }
            ChannelPath::Light { light, property } => write!(f, "light/{light}/{}", property.name()),
            ChannelPath::Attribute { light, owner, property } => {
                write!(f, "{}/{owner}/{}", if *light { "light" } else { "object" }, property.path_name())
            }
            ChannelPath::Camera { camera, property } => write!(f, "camera/{camera}/{}", property.name()),
        }
    }
}

/// Why a channel path cannot be parsed or resolved.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ChannelError {
    #[error(
        "channel path {path:?}: {problem}; expected object/<name>/<property>, \
         object/<name>/joint/<joint>/<property>, light/<name>/<property> or camera/<name>/<property>"
    )]
    Syntax { path: String, problem: String },

    #[error("channel path {path:?}: unknown {owner} property {property:?}; {owner} properties are: {}", expected.join(", "))]
    UnknownProperty { path: String, owner: &'static str, property: String, expected: Vec<&'static str> },

    #[error("channel path {path:?}: no object named {name:?}; {}", listing("objects", available))]
    UnknownObject { path: String, name: String, available: Vec<String> },

    #[error(
        "channel path {path:?}: object {object:?} has no skeleton, so it has no joints, root_translation or IK constraints"
    )]
    NoSkeleton { path: String, object: String },

    #[error(
        "channel path {path:?}: object {object:?} has no joint named {name:?}; {}",
        listing("joints", available)
    )]
    UnknownJoint { path: String, object: String, name: String, available: Vec<String> },

    #[error(
        "channel path {path:?}: object {object:?} has no IK constraint named {name:?}; {}",
        listing("IK constraints", available)
    )]
    UnknownConstraint { path: String, object: String, name: String, available: Vec<String> },

    #[error(
        "channel path {path:?}: object {object:?} has no constraint named {name:?}; {}",
        listing("constraints", available)
    )]
    UnknownObjectConstraint { path: String, object: String, name: String, available: Vec<String> },

    #[error("channel path {path:?}: no light named {name:?}; {}", listing("lights", available))]
    UnknownLight { path: String, name: String, available: Vec<String> },

    #[error("channel path {path:?}: {owner} has no {what} channel{hint}")]
    NotSet { path: String, owner: String, what: String, hint: String },
    #[error("channel path {path:?}: no camera named {name:?}; {}", listing("cameras", available))]
    UnknownCamera { path: String, name: String, available: Vec<String> },

    #[error(
        "channel path {path:?}: camera {camera:?} has no aim constraint, so it has no roll or aim_influence"
    )]
    NoAim { path: String, camera: String },

    /// The channel exists but its keys are invalid.
    #[error("channel {path}: {field}: {source}")]
    InvalidTrack { path: String, field: String, source: TrackError },
}

fn listing(what: &str, names: &[String]) -> String {
    if names.is_empty() {
        format!("the scene has no {what}")
    } else {
        let quoted: Vec<String> = names.iter().map(|n| format!("{n:?}")).collect();
        format!("{what}: {}", quoted.join(", "))
    }
}

impl ChannelPath {
    /// Parses `object/<name>/<property>`, `object/<name>/joint/<joint>/<property>`,
    /// `object/<name>/ik/<constraint>/<property>` or `light/<name>/<property>`. Names cannot contain `/`.
    ///
    /// # Errors
    /// [`ChannelError::Syntax`] or [`ChannelError::UnknownProperty`], naming what is wrong.
    pub fn parse(path: &str) -> Result<Self, ChannelError> {
        let syntax =
            |problem: &str| ChannelError::Syntax { path: path.to_string(), problem: problem.to_string() };
        let parts: Vec<&str> = path.split('/').collect();
        if parts.iter().any(|p| p.is_empty()) {
            return Err(syntax("empty part (check for a leading, trailing or doubled '/')"));
        }
        match parts.as_slice() {
            ["object", object, "joint", joint, property] => {
                let property = match *property {
                    "translation" => JointProperty::Translation,
                    "rotation" => JointProperty::Rotation,
                    "rotation_euler" => JointProperty::RotationEuler,
                    "scale" => JointProperty::Scale,
                    other => {
                        return Err(ChannelError::UnknownProperty {
                            path: path.to_string(),
                            owner: "joint",
                            property: other.to_string(),
                            expected: JOINT_PROPERTIES.to_vec(),
                        })
                    }
                };
                Ok(ChannelPath::Joint {
                    object: (*object).to_string(),
                    joint: (*joint).to_string(),
                    property,
                })
            }
            ["object", _, "joint", ..] => {
                Err(syntax("a joint channel is object/<name>/joint/<joint>/<property>"))
            }
            ["object", object, "ik", constraint, property] => {
                let property = match *property {
                    "target" => IkProperty::Target,
                    "blend" => IkProperty::Blend,
                    other => {
                        return Err(ChannelError::UnknownProperty {
                            path: path.to_string(),
                            owner: "IK constraint",
                            property: other.to_string(),
                            expected: IK_PROPERTIES.to_vec(),
                        })
                    }
                };
                Ok(ChannelPath::Ik {
                    object: (*object).to_string(),
                    constraint: (*constraint).to_string(),
                    property,
                })
            }
            ["object", object, "morph", target] => match target.parse::<usize>() {
                Ok(target) => Ok(ChannelPath::Attribute {
                    light: false,
                    owner: (*object).to_string(),
                    property: AttributeProperty::Morph(target),
                }),
                Err(_) => Err(syntax("a morph-weight channel is object/<name>/morph/<target index>")),
            },
            ["object", _, "morph", ..] => {
                Err(syntax("a morph-weight channel is object/<name>/morph/<target index>"))
            }
            ["object", object, "constraint", constraint, property] => {
                let Some(property) = ConstraintProperty::from_name(property) else {
                    return Err(ChannelError::UnknownProperty {
                        path: path.to_string(),
                        owner: "constraint",
                        property: (*property).to_string(),
                        expected: CONSTRAINT_PROPERTIES.to_vec(),
                    });
                };
                Ok(ChannelPath::Constraint {
                    object: (*object).to_string(),
                    constraint: (*constraint).to_string(),
                    property,
                })
            }
            ["object", _, "constraint", ..] => Err(syntax(
                "an object constraint channel is object/<name>/constraint/<constraint>/<property>",
            )),
            ["object", _, "ik", ..] => {
                Err(syntax("an IK constraint channel is object/<name>/ik/<constraint>/<property>"))
            }
            ["object", object, property] => {
                let property = match *property {
                    "translation" => ObjectProperty::Translation,
                    "rotation" => ObjectProperty::Rotation,
                    "rotation_euler" => ObjectProperty::RotationEuler,
                    "scale" => ObjectProperty::Scale,
                    "root_translation" => ObjectProperty::RootTranslation,
                    other if AttributeProperty::of_object(other).is_some() => {
                        return Ok(ChannelPath::Attribute {
                            light: false,
                            owner: (*object).to_string(),
                            property: AttributeProperty::of_object(other).expect("just matched"),
                        })
                    }
                    other => {
                        return Err(ChannelError::UnknownProperty {
                            path: path.to_string(),
                            owner: "object",
                            property: other.to_string(),
                            expected: OBJECT_PROPERTIES.to_vec(),
                        })
                    }
                };
                Ok(ChannelPath::Object { object: (*object).to_string(), property })
            }
            ["light", light, property] => {
                let property = match *property {
                    "position" => LightProperty::Position,
                    "direction" => LightProperty::Direction,
                    "colour" | "color" => LightProperty::Colour,
                    "intensity" => LightProperty::Intensity,
                    other if AttributeProperty::of_light(other).is_some() => {
                        return Ok(ChannelPath::Attribute {
                            light: true,
                            owner: (*light).to_string(),
                            property: AttributeProperty::of_light(other).expect("just matched"),
                        })
                    }
                    other => {
                        return Err(ChannelError::UnknownProperty {
                            path: path.to_string(),
                            owner: "light",
                            property: other.to_string(),
                            expected: LIGHT_PROPERTIES.to_vec(),
                        })
                    }
                };
                Ok(ChannelPath::Light { light: (*light).to_string(), property })
            }
            ["camera", camera, property] => {
                let property = match *property {
                    "translation" => CameraProperty::Translation,
                    "rotation" => CameraProperty::Rotation,
                    "lens" => CameraProperty::Lens,
                    "roll" => CameraProperty::Roll,
                    "aim_influence" => CameraProperty::AimInfluence,
                    "visible" => CameraProperty::Visible,
                    other => {
                        return Err(ChannelError::UnknownProperty {
                            path: path.to_string(),
                            owner: "camera",
                            property: other.to_string(),
                            expected: CAMERA_PROPERTIES.to_vec(),
                        })
                    }
                };
                Ok(ChannelPath::Camera { camera: (*camera).to_string(), property })
            }
            ["object" | "light" | "camera", _] | ["object" | "light" | "camera"] => {
                Err(syntax("missing property"))
            }
            ["object" | "light" | "camera", ..] => Err(syntax("too many parts")),
            // `split` yields at least one part, so `parts[0]` exists.
            _ => Err(syntax(&format!(
                "unknown kind {:?} (expected \"object\", \"light\" or \"camera\")",
                parts[0]
            ))),
        }
    }

    /// The path of channel `id` of `scene` (by the names of its object, joint, constraint,
    /// light or camera): the inverse of [`ChannelPath::id`]. `None` when `id` names nothing
    /// in `scene`.
    #[must_use]
    pub fn of(scene: &Scene, id: ChannelId) -> Option<ChannelPath> {
        let object = |o: usize| scene.objects.get(o).map(|x| x.name.clone());
        let joint = |o: usize, j: usize, property| {
            let x = scene.objects.get(o)?;
            let name = x.skeleton.as_ref()?.joints.get(j)?.name.clone();
            Some(ChannelPath::Joint { object: x.name.clone(), joint: name, property })
        };
        let ik = |o: usize, c: usize, property| {
            let x = scene.objects.get(o)?;
            let name = x.skeleton.as_ref()?.ik_constraints.get(c)?.name.clone();
            Some(ChannelPath::Ik { object: x.name.clone(), constraint: name, property })
        };
        let constraint = |o: usize, c: usize, property| {
            let x = scene.objects.get(o)?;
            let name = x.constraints.get(c)?.name.clone();
            Some(ChannelPath::Constraint { object: x.name.clone(), constraint: name, property })
        };
        let light = |l: usize, property| {
            scene.lights.get(l).map(|x| ChannelPath::Light { light: x.name.clone(), property })
        };
        let camera = |c: usize, property| {
            scene.cameras.get(c).map(|x| ChannelPath::Camera { camera: x.name.clone(), property })
        };
        let on_object = |o: usize, property| object(o).map(|object| ChannelPath::Object { object, property });
        match id {
            ChannelId::ObjectTranslation(o) => on_object(o, ObjectProperty::Translation),
            ChannelId::ObjectRotation(o) => on_object(o, ObjectProperty::Rotation),
            ChannelId::ObjectScale(o) => on_object(o, ObjectProperty::Scale),
            ChannelId::RootTranslation(o) => on_object(o, ObjectProperty::RootTranslation),
            ChannelId::JointTranslation { object, joint: j } => joint(object, j, JointProperty::Translation),
            ChannelId::JointRotation { object, joint: j } => joint(object, j, JointProperty::Rotation),
            ChannelId::JointScale { object, joint: j } => joint(object, j, JointProperty::Scale),
            ChannelId::IkTarget { object, constraint } => ik(object, constraint, IkProperty::Target),
            ChannelId::IkBlend { object, constraint } => ik(object, constraint, IkProperty::Blend),
            ChannelId::LightPosition(l) => light(l, LightProperty::Position),
            ChannelId::LightDirection(l) => light(l, LightProperty::Direction),
            ChannelId::LightColour(l) => light(l, LightProperty::Colour),
            ChannelId::LightIntensity(l) => light(l, LightProperty::Intensity),
            ChannelId::Attribute(a) => Some(ChannelPath::Attribute {
                light: a.owner().is_err(),
                owner: a.owner_name(scene)?,
                property: a.property(),
            }),
            ChannelId::CameraTranslation(c) => camera(c, CameraProperty::Translation),
            ChannelId::CameraRotation(c) => camera(c, CameraProperty::Rotation),
            ChannelId::CameraLens(c) => camera(c, CameraProperty::Lens),
            ChannelId::CameraRoll(c) => camera(c, CameraProperty::Roll),
            ChannelId::CameraAimInfluence(c) => camera(c, CameraProperty::AimInfluence),
            ChannelId::CameraVisible(c) => camera(c, CameraProperty::Visible),
            ChannelId::ObjectEuler(o) => on_object(o, ObjectProperty::RotationEuler),
            ChannelId::JointEuler { object, joint: j } => joint(object, j, JointProperty::RotationEuler),
            ChannelId::Constraint { object, constraint: c, property } => constraint(object, c, property),
        }
    }

    /// The channel's index-based id in `scene`.
    ///
    /// # Errors
    /// [`ChannelError`] naming the unknown object, joint or light and listing those that exist.
    pub fn id(&self, scene: &Scene) -> Result<ChannelId, ChannelError> {
        let path = self.to_string();
        let find_object = |name: &str| -> Result<(usize, &Object), ChannelError> {
            scene.objects.iter().enumerate().find(|(_, o)| o.name == name).ok_or_else(|| {
                ChannelError::UnknownObject {
                    path: path.clone(),
                    name: name.to_string(),
                    available: scene.objects.iter().map(|o| o.name.clone()).collect(),
                }
            })
        };
        let no_skeleton =
            |object: &Object| ChannelError::NoSkeleton { path: path.clone(), object: object.name.clone() };
        let no_euler = |owner: String| {
            ChannelError::NotSet {
            path: path.clone(),
            owner,
            what: "rotation_euler".to_owned(),
            hint: " (its rotation has quaternion keys: sample rotation, or switch it to Euler keys in the editor)"
                .to_owned(),
        }
        };
        Ok(match self {
            ChannelPath::Object { object, property } => {
                let (i, o) = find_object(object)?;
                match property {
                    ObjectProperty::Translation => ChannelId::ObjectTranslation(i),
                    ObjectProperty::Rotation => ChannelId::ObjectRotation(i),
                    ObjectProperty::RotationEuler => {
                        if o.rotation_euler.is_none() {
                            return Err(no_euler(format!("object {:?}", o.name)));
                        }
                        ChannelId::ObjectEuler(i)
                    }
                    ObjectProperty::Scale => ChannelId::ObjectScale(i),
                    ObjectProperty::RootTranslation => {
                        o.skeleton.as_ref().ok_or_else(|| no_skeleton(o))?;
                        ChannelId::RootTranslation(i)
                    }
                }
            }
            ChannelPath::Joint { object, joint, property } => {
                let (i, o) = find_object(object)?;
                let skeleton = o.skeleton.as_ref().ok_or_else(|| no_skeleton(o))?;
                let j = skeleton.joints.iter().position(|j| j.name == *joint).ok_or_else(|| {
                    ChannelError::UnknownJoint {
                        path: path.clone(),
                        object: o.name.clone(),
                        name: joint.clone(),
                        available: skeleton.joints.iter().map(|j| j.name.clone()).collect(),
                    }
                })?;
                match property {
                    JointProperty::Translation => ChannelId::JointTranslation { object: i, joint: j },
                    JointProperty::Rotation => ChannelId::JointRotation { object: i, joint: j },
                    JointProperty::RotationEuler => {
                        if skeleton.joints[j].rotation_euler.is_none() {
                            return Err(no_euler(format!("joint {joint:?} of object {:?}", o.name)));
                        }
                        ChannelId::JointEuler { object: i, joint: j }
                    }
                    JointProperty::Scale => ChannelId::JointScale { object: i, joint: j },
                }
            }
            ChannelPath::Ik { object, constraint, property } => {
                let (i, o) = find_object(object)?;
                let skeleton = o.skeleton.as_ref().ok_or_else(|| no_skeleton(o))?;
                let c =
                    skeleton.ik_constraints.iter().position(|c| c.name == *constraint).ok_or_else(|| {
                        ChannelError::UnknownConstraint {
                            path: path.clone(),
                            object: o.name.clone(),
                            name: constraint.clone(),
                            available: skeleton.ik_constraints.iter().map(|c| c.name.clone()).collect(),
                        }
                    })?;
                match property {
                    IkProperty::Target => ChannelId::IkTarget { object: i, constraint: c },
                    IkProperty::Blend => ChannelId::IkBlend { object: i, constraint: c },
                }
            }
            ChannelPath::Constraint { object, constraint, property } => {
                let (i, o) = find_object(object)?;
                let c = o.constraints.iter().position(|c| c.name == *constraint).ok_or_else(|| {
                    ChannelError::UnknownObjectConstraint {
                        path: path.clone(),
                        object: o.name.clone(),
                        name: constraint.clone(),
                        available: o.constraints.iter().map(|c| c.name.clone()).collect(),
                    }
                })?;
                if property.of(&o.constraints[c]).is_none() {
                    return Err(ChannelError::NotSet {
                        path: path.clone(),
                        owner: format!("constraint {constraint:?} of object {:?}", o.name),
                        what: property.name().to_owned(),
                        hint: format!(" (it is a {} constraint)", o.constraints[c].kind.label()),
                    });
                }
                ChannelId::Constraint { object: i, constraint: c, property: *property }
            }
            ChannelPath::Attribute { light, owner, property } => {
                let id = if *light {
                    let l = scene.lights.iter().position(|l| l.name == *owner).ok_or_else(|| {
                        ChannelError::UnknownLight {
                            path: path.clone(),
                            name: owner.clone(),
                            available: scene.lights.iter().map(|l| l.name.clone()).collect(),
                        }
                    })?;
                    property.light_id(l)
                } else {
                    property.object_id(find_object(owner)?.0)
                };
                let id = id.expect("parse pairs object and light properties with their owner");
                if id.get(scene).is_none() {
                    let hint = match id {
                        AttributeId::MorphWeight { object, .. } => format!(
                            " (it keys {} morph-target weights: morph/0 … morph/{})",
                            scene.objects[object].attributes.morph_weights.len(),
                            scene.objects[object].attributes.morph_weights.len().saturating_sub(1)
                        ),
                        _ => format!("; it is set in the scene file as {}", id.field_path()),
                    };
                    return Err(ChannelError::NotSet {
                        path: path.clone(),
                        owner: format!("{} {owner:?}", if *light { "light" } else { "object" }),
                        what: property.path_name(),
                        hint,
                    });
                }
                ChannelId::Attribute(id)
            }
            ChannelPath::Light { light, property } => {
                let i = scene.lights.iter().position(|l| l.name == *light).ok_or_else(|| {
                    ChannelError::UnknownLight {
                        path: path.clone(),
                        name: light.clone(),
                        available: scene.lights.iter().map(|l| l.name.clone()).collect(),
                    }
                })?;
                match property {
                    LightProperty::Position => ChannelId::LightPosition(i),
                    LightProperty::Direction => ChannelId::LightDirection(i),
                    LightProperty::Colour => ChannelId::LightColour(i),
                    LightProperty::Intensity => ChannelId::LightIntensity(i),
                }
            }
            ChannelPath::Camera { camera, property } => {
                let i = scene.camera_index(camera).ok_or_else(|| ChannelError::UnknownCamera {
                    path: path.clone(),
                    name: camera.clone(),
                    available: scene.cameras.iter().map(|c| c.name.clone()).collect(),
                })?;
                match property {
                    CameraProperty::Translation => ChannelId::CameraTranslation(i),
                    CameraProperty::Rotation => ChannelId::CameraRotation(i),
                    CameraProperty::Lens => ChannelId::CameraLens(i),
                    CameraProperty::Roll => {
                        if scene.cameras[i].aim.is_none() {
                            return Err(ChannelError::NoAim { path: path.clone(), camera: camera.clone() });
                        }
                        ChannelId::CameraRoll(i)
                    }
                    CameraProperty::AimInfluence => {
                        if scene.cameras[i].aim.is_none() {
                            return Err(ChannelError::NoAim { path: path.clone(), camera: camera.clone() });
                        }
                        ChannelId::CameraAimInfluence(i)
                    }
                    CameraProperty::Visible => ChannelId::CameraVisible(i),
                }
            }
        })
    }

    /// Looks the channel up in `scene` and validates its track.
    ///
    /// # Errors
    /// [`ChannelError`] naming the unknown object, joint or light and listing those that
    /// exist, or [`ChannelError::InvalidTrack`] with the field path of the bad key.
    pub fn resolve(&self, scene: &Scene) -> Result<Channel, ChannelError> {
        let id = self.id(scene)?;
        let (path, field) = (self.to_string(), id.field_path());
        let kind = match id {
            ChannelId::LightColour(_) | ChannelId::Attribute(AttributeId::ObjectColour(_)) => {
                ValueKind::Colour
            }
            ChannelId::ObjectEuler(_) | ChannelId::JointEuler { .. } => ValueKind::Angles,
            _ => match id.kind() {
                ChannelKind::Vec3 => ValueKind::Position,
                ChannelKind::Rotation => ValueKind::Rotation,
                ChannelKind::Scalar => ValueKind::Scalar,
            },
        };
        if let (ChannelKind::Rotation, Some((euler, order))) =
            (id.kind(), crate::channel_id::euler_keys(scene, id))
        {
            // A rotation with Euler keys samples its angles and turns them in its order.
            let field = crate::channel_id::euler_partner(id).map_or(field, ChannelId::field_path);
            let mut channel = Channel::build(path, field, euler, kind)?;
            if let Sampler::Vec3(track) = channel.sampler {
                channel.sampler = Sampler::Euler(track, order);
            }
            return Ok(channel);
        }
        match channel(scene, id).expect("the id was just looked up") {
            ChannelRef::Vec3(a) => Channel::build(path, field, a, kind),
            ChannelRef::Rotation(a) => Channel::build(path, field, a, kind),
            ChannelRef::Scalar(a) => Channel::build(path, field, a, kind),
        }
    }
}

/// Every channel of `scene`, objects first (translation, rotation, scale, root translation,
/// joints in order), then lights, then cameras.
#[must_use]
pub fn list_channels(scene: &Scene) -> Vec<ChannelPath> {
    let mut out = Vec::new();
    for o in &scene.objects {
        for property in [ObjectProperty::Translation, ObjectProperty::Rotation, ObjectProperty::Scale] {
            out.push(ChannelPath::Object { object: o.name.clone(), property });
            if property == ObjectProperty::Rotation && o.rotation_euler.is_some() {
                out.push(ChannelPath::Object {
                    object: o.name.clone(),
                    property: ObjectProperty::RotationEuler,
                });
            }
        }
        if let Some(skeleton) = &o.skeleton {
            out.push(ChannelPath::Object {
                object: o.name.clone(),
                property: ObjectProperty::RootTranslation,
            });
            for j in &skeleton.joints {
                let joint =
                    |property| ChannelPath::Joint { object: o.name.clone(), joint: j.name.clone(), property };
                if j.translation.is_animated() || j.translation.value != Vec3::ZERO {
                    out.push(joint(JointProperty::Translation));
                }
                out.push(joint(JointProperty::Rotation));
                if j.rotation_euler.is_some() {
                    out.push(joint(JointProperty::RotationEuler));
                }
                if j.scale.is_animated() || j.scale.value != Vec3::ONE {
                    out.push(joint(JointProperty::Scale));
                }
            }
            for c in &skeleton.ik_constraints {
                for property in [IkProperty::Target, IkProperty::Blend] {
                    out.push(ChannelPath::Ik {
                        object: o.name.clone(),
                        constraint: c.name.clone(),
                        property,
                    });
                }
            }
        }
        for c in &o.constraints {
            for property in ConstraintProperty::of_constraint(c) {
                out.push(ChannelPath::Constraint {
                    object: o.name.clone(),
                    constraint: c.name.clone(),
                    property,
                });
            }
        }
    }
    for l in &scene.lights {
        for property in [
            LightProperty::Position,
            LightProperty::Direction,
            LightProperty::Colour,
            LightProperty::Intensity,
        ] {
            out.push(ChannelPath::Light { light: l.name.clone(), property });
        }
    }
    // Attributes after the transforms, so that scenes without them list what they listed.
    for (o, object) in scene.objects.iter().enumerate() {
        for id in AttributeId::of_object(scene, o) {
            if let ChannelId::Attribute(a) = id {
                out.push(ChannelPath::Attribute {
                    light: false,
                    owner: object.name.clone(),
                    property: a.property(),
                });
            }
        }
    }
    for (l, light) in scene.lights.iter().enumerate() {
        for id in AttributeId::of_light(scene, l) {
            if let ChannelId::Attribute(a) = id {
                out.push(ChannelPath::Attribute {
                    light: true,
                    owner: light.name.clone(),
                    property: a.property(),
                });
            }
        }
    }
    for c in &scene.cameras {
        for property in [CameraProperty::Translation, CameraProperty::Rotation, CameraProperty::Lens] {
            out.push(ChannelPath::Camera { camera: c.name.clone(), property });
        }
        if c.aim.is_some() {
            out.push(ChannelPath::Camera { camera: c.name.clone(), property: CameraProperty::Roll });
            out.push(ChannelPath::Camera { camera: c.name.clone(), property: CameraProperty::AimInfluence });
        }
        if c.visible.is_animated() || c.visible.value != 1.0 {
            out.push(ChannelPath::Camera { camera: c.name.clone(), property: CameraProperty::Visible });
        }
    }
    out
}

/// What a channel's values mean; decides the column names.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ValueKind {
    /// f32.
    Scalar,
    /// Vec3 in x, y, z (positions, directions, scales).
    Position,
    /// Vec3 as linear r, g, b.
    Colour,
    /// Unit quaternion.
    Rotation,
    /// Euler angles in degrees (x, y, z), as Euler keys hold them.
    Angles,
}

pub use crate::channel_id::{ChannelValue, RotationFormat};

#[derive(Clone, Debug, PartialEq)]
enum Sampler {
    Scalar(AnimatedTrack<f32>),
    Vec3(AnimatedTrack<Vec3>),
    Quat(AnimatedTrack<Quat>),
    /// A rotation with Euler keys: the angles (degrees) turned in the order.
    Euler(AnimatedTrack<Vec3>, crate::EulerOrder),
}

/// A resolved channel: its validated track and what it is.
#[derive(Clone, Debug, PartialEq)]
pub struct Channel {
    /// The channel path as the user would write it.
    pub path: String,
    /// The field path of its `Animated` value in the scene (`objects[0].rotation`).
    pub field: String,
    pub kind: ValueKind,
    /// Number of keys (0 when not animated).
    pub key_count: usize,
    sampler: Sampler,
}

/// Value types a channel can hold.
trait IntoSampler: Sized + crate::track::TrackValue {
    fn sampler(track: AnimatedTrack<Self>) -> Sampler;
}

impl IntoSampler for f32 {
    fn sampler(track: AnimatedTrack<Self>) -> Sampler {
        Sampler::Scalar(track)
    }
}

impl IntoSampler for Vec3 {
    fn sampler(track: AnimatedTrack<Self>) -> Sampler {
        Sampler::Vec3(track)
    }
}

impl IntoSampler for Quat {
    fn sampler(track: AnimatedTrack<Self>) -> Sampler {
        Sampler::Quat(track)
    }
}

impl Channel {
    fn build<T: IntoSampler>(
        path: String,
        field: String,
        animated: &Animated<T>,
        kind: ValueKind,
    ) -> Result<Self, ChannelError> {
        let track = AnimatedTrack::new(animated).map_err(|source| ChannelError::InvalidTrack {
            path: path.clone(),
            field: track_error_path(&field, &source),
            source,
        })?;
        Ok(Channel { path, field, kind, key_count: animated.track.len(), sampler: T::sampler(track) })
    }

    /// The value at `t` seconds (clamped to the first/last key outside the keyed range).
    #[must_use]
    pub fn sample(&self, t: f64) -> ChannelValue {
        match &self.sampler {
            Sampler::Scalar(s) => ChannelValue::Scalar(s.sample(t)),
            Sampler::Vec3(s) => ChannelValue::Vec3(s.sample(t)),
            Sampler::Quat(s) => ChannelValue::Rotation(s.sample(t)),
            Sampler::Euler(s, order) => ChannelValue::Rotation(order.to_quat(s.sample(t))),
        }
    }

    /// First and last key time; `None` when not animated.
    #[must_use]
    pub fn domain(&self) -> Option<(f64, f64)> {
        match &self.sampler {
            Sampler::Scalar(s) => s.domain(),
            Sampler::Vec3(s) => s.domain(),
            Sampler::Quat(s) => s.domain(),
            Sampler::Euler(s, _) => s.domain(),
        }
    }

    /// Whether this is a rotation channel with spin keys (segments beyond the short way).
    #[must_use]
    pub fn has_spin(&self) -> bool {
        match &self.sampler {
            Sampler::Quat(s) => s.track().is_some_and(crate::track::Track::has_spin),
            _ => false,
        }
    }

    /// The unwrapped angle (degrees) turned since the start of the spin segment at `t`, `None`
    /// outside spin segments and for other channels ([`crate::Track::spin_degrees`]).
    #[must_use]
    pub fn spin_degrees(&self, t: f64) -> Option<f64> {
        match &self.sampler {
            Sampler::Quat(s) => s.track().and_then(|track| track.spin_degrees(t)),
            _ => None,
        }
    }

    /// Column names of [`ChannelValue::components`] for this channel.
    #[must_use]
    pub fn column_names(&self, rotation: RotationFormat) -> &'static [&'static str] {
        match (self.kind, rotation) {
            (ValueKind::Scalar, _) => &["value"],
            (ValueKind::Position, _) => &["x", "y", "z"],
            (ValueKind::Colour, _) => &["r", "g", "b"],
            (ValueKind::Rotation, RotationFormat::Quat) => &["x", "y", "z", "w"],
            (ValueKind::Rotation, RotationFormat::EulerDegrees) | (ValueKind::Angles, _) => {
                &["x_deg", "y_deg", "z_deg"]
            }
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::key::{Key, RawTrack};
    use crate::scene::{Joint, Light, LightKind, Skeleton};

    /// Every listed channel's id names it back by the same path.
    #[test]
    fn paths_of_ids_are_the_inverse_of_id() {
        let scene = scene();
        let paths = list_channels(&scene);
        assert!(paths.len() > 8);
        for path in paths {
            let id = path.id(&scene).expect("listed channels resolve");
            assert_eq!(ChannelPath::of(&scene, id), Some(path));
        }
        assert_eq!(ChannelPath::of(&scene, ChannelId::ObjectScale(9)), None);
    }

    fn scene() -> Scene {
        let mut arm = Object::new("Arm");
        arm.translation.track =
            RawTrack::new(vec![Key::new(0.0, Vec3::ZERO), Key::new(1.0, Vec3::new(2.0, 0.0, 0.0))]);
        arm.skeleton = Some(Skeleton {
            joints: vec![Joint {
                rotation: Animated::new(
                    Quat::IDENTITY,
                    RawTrack::new(vec![
                        Key::new(0.0, Quat::IDENTITY),
                        Key::new(1.0, Quat::from_rotation_x(90f32.to_radians())),
                    ]),
                ),
                ..Joint::new("elbow", None, Vec3::ZERO, Quat::IDENTITY)
            }],
            root_translation: Animated::constant(Vec3::ZERO),
            ik_constraints: Vec::new(),
        });
        let mut scene = Scene::default();
        scene.objects.push(arm);
        scene.objects.push(Object::new("Cube"));
        scene.lights.push(Light {
            name: "Key".into(),
            kind: LightKind::Point,
            enabled: true,
            position: Animated::constant(Vec3::Y),
            direction: Animated::constant(Vec3::NEG_Y),
            colour: Animated::constant(Vec3::ONE),
            intensity: Animated::constant(2.0),
            attributes: Default::default(),
        });
        scene
    }

    #[test]
    fn parse_and_display_round_trip() {
        for text in [
            "object/Arm/translation",
            "object/Arm/rotation",
            "object/Arm/scale",
            "object/Arm/root_translation",
            "object/Arm/joint/elbow/rotation",
            "light/Key/position",
            "light/Key/direction",
            "light/Key/colour",
            "light/Key/intensity",
        ] {
            assert_eq!(ChannelPath::parse(text).map(|p| p.to_string()), Ok(text.to_string()));
        }
        assert_eq!(
            ChannelPath::parse("light/Key/color").map(|p| p.to_string()),
            Ok("light/Key/colour".into())
        );
    }

    #[test]
    fn parse_errors_name_the_problem() {
        let err = |s: &str| ChannelPath::parse(s).unwrap_err().to_string();
        assert!(err("object/Arm/size")
            .contains("unknown object property \"size\"; object properties are: translation"));
        assert!(err("light/Key/rotation")
            .contains("light properties are: position, direction, colour, intensity"));
        assert!(err("object/Arm/joint/elbow/size").contains("unknown joint property \"size\""));
        assert!(err("camera/x/y").contains(
            "unknown camera property \"y\"; camera properties are: translation, rotation, lens, roll, aim_influence, visible"
        ));
        assert!(err("lamp/x/y").contains("unknown kind \"lamp\""));
        assert!(err("object/Arm").contains("missing property"));
        assert!(err("object//rotation").contains("empty part"));
        assert!(err("object/Arm/joint/elbow").contains("object/<name>/joint/<joint>/<property>"));
        assert!(err("").contains("empty part"));
    }

    #[test]
    fn resolve_errors_list_what_exists() {
        let s = scene();
        let err = |p: &str| ChannelPath::parse(p).and_then(|c| c.resolve(&s)).unwrap_err().to_string();
        assert!(err("object/Leg/rotation").contains("no object named \"Leg\"; objects: \"Arm\", \"Cube\""));
        assert!(err("object/Arm/joint/knee/rotation").contains("no joint named \"knee\"; joints: \"elbow\""));
        assert!(err("object/Cube/root_translation").contains("object \"Cube\" has no skeleton"));
        assert!(err("light/Fill/intensity").contains("no light named \"Fill\"; lights: \"Key\""));
    }

    #[test]
    fn samples_and_formats() {
        let s = scene();
        let resolve = |p: &str| ChannelPath::parse(p).and_then(|c| c.resolve(&s)).unwrap();
        let t = resolve("object/Arm/translation");
        assert_eq!(t.key_count, 2);
        assert_eq!(t.field, "objects[0].translation");
        assert_eq!(t.domain(), Some((0.0, 1.0)));
        assert_eq!(t.sample(1.0), ChannelValue::Vec3(Vec3::new(2.0, 0.0, 0.0)));
        assert_eq!(t.column_names(RotationFormat::Quat), ["x", "y", "z"]);

        let r = resolve("object/Arm/joint/elbow/rotation");
        assert_eq!(r.field, "objects[0].skeleton.joints[0].rotation");
        let euler = r.sample(1.0).components(RotationFormat::EulerDegrees);
        assert!(
            (euler[0] - 90.0).abs() < 1e-4 && euler[1].abs() < 1e-4 && euler[2].abs() < 1e-4,
            "{euler:?}"
        );
        assert_eq!(r.sample(0.0).components(RotationFormat::Quat), vec![0.0, 0.0, 0.0, 1.0]);

        let i = resolve("light/Key/intensity");
        assert_eq!(i.key_count, 0);
        assert_eq!(i.domain(), None);
        assert_eq!(i.sample(5.0).components(RotationFormat::Quat), vec![2.0]);
        assert_eq!(resolve("light/Key/colour").column_names(RotationFormat::Quat), ["r", "g", "b"]);
    }

    #[test]
    fn invalid_track_names_the_key() {
        let mut s = scene();
        s.objects[0].translation.track.keys[1].time = -1.0;
        let err = ChannelPath::parse("object/Arm/translation").and_then(|c| c.resolve(&s)).unwrap_err();
        assert!(
            matches!(&err, ChannelError::InvalidTrack { field, .. } if field == "objects[0].translation.track[1].time")
        );
    }

    #[test]
    fn object_constraint_channels_resolve() {
        use crate::object_constraint::{ChildOfParent, ConstraintKind, ObjectConstraint};
        use crate::AimTarget;
        let mut s = Scene::default();
        s.objects.push(Object::new("Hand"));
        let mut prop = Object::new("Prop");
        prop.constraints.push(ObjectConstraint::new(
            "Held",
            ConstraintKind::ChildOf {
                parents: vec![ChildOfParent::new(AimTarget::Object("Hand".into()))],
                parent: Animated::constant(0.0),
            },
        ));
        s.objects.push(prop);
        let resolve = |p: &str| ChannelPath::parse(p).and_then(|c| c.resolve(&s));
        let parent = resolve("object/Prop/constraint/Held/parent").unwrap();
        assert_eq!(parent.field, "objects[1].constraints[0].kind.parent");
        assert_eq!(
            resolve("object/Prop/constraint/Held/influence").unwrap().field,
            "objects[1].constraints[0].influence"
        );
        let err = resolve("object/Prop/constraint/Held/offset").unwrap_err().to_string();
        assert!(err.contains("has no offset channel (it is a Child of constraint)"), "{err}");
        let err = resolve("object/Prop/constraint/Grip/influence").unwrap_err().to_string();
        assert!(err.contains("no constraint named \"Grip\"; constraints: \"Held\""), "{err}");
        let err = ChannelPath::parse("object/Prop/constraint/Held/size").unwrap_err().to_string();
        assert!(err.contains("constraint properties are: influence, parent, offset"), "{err}");
        let id = ChannelId::Constraint {
            object: 1,
            constraint: 0,
            property: crate::channel_id::ConstraintProperty::Parent,
        };
        assert_eq!(
            ChannelPath::of(&s, id).map(|p| p.to_string()).as_deref(),
            Some("object/Prop/constraint/Held/parent")
        );
        assert!(id.is_switch());
        let names: Vec<String> = list_channels(&s).iter().map(ToString::to_string).collect();
        assert!(names.contains(&"object/Prop/constraint/Held/parent".to_owned()), "{names:?}");
    }

    #[test]
    fn camera_channels_resolve() {
        use crate::camera_object::{Aim, AimTarget, SceneCamera};
        let mut s = scene();
        let mut cam = SceneCamera::new("Shot", Vec3::new(0.0, 1.0, 5.0));
        cam.lens.track = RawTrack::new(vec![Key::new(0.0, 40.0), Key::new(2.0, 20.0)]);
        s.cameras.push(cam);
        let resolve = |s: &Scene, p: &str| ChannelPath::parse(p).and_then(|c| c.resolve(s));
        let lens = resolve(&s, "camera/Shot/lens").unwrap();
        assert_eq!((lens.field.as_str(), lens.key_count), ("cameras[0].lens", 2));
        assert_eq!(lens.sample(2.0), ChannelValue::Scalar(20.0));
        assert_eq!(
            resolve(&s, "camera/Shot/translation").unwrap().column_names(RotationFormat::Quat),
            ["x", "y", "z"]
        );
        let err = resolve(&s, "camera/Shot/roll").unwrap_err().to_string();
        assert!(err.contains("camera \"Shot\" has no aim constraint"), "{err}");
        assert!(resolve(&s, "camera/Long/lens").unwrap_err().to_string().contains("cameras: \"Shot\""));
        s.cameras[0].aim = Some(Aim::at(AimTarget::Point(Vec3::ZERO)));
        assert_eq!(resolve(&s, "camera/Shot/roll").unwrap().field, "cameras[0].aim.roll");
        let names: Vec<String> = list_channels(&s).iter().map(ToString::to_string).collect();
        assert_eq!(
            &names[names.len() - 5..],
            [
                "camera/Shot/translation",
                "camera/Shot/rotation",
                "camera/Shot/lens",
                "camera/Shot/roll",
                "camera/Shot/aim_influence"
            ]
        );
        assert_eq!(resolve(&s, "camera/Shot/aim_influence").unwrap().field, "cameras[0].aim.influence");
        for text in
            ["camera/Shot/translation", "camera/Shot/rotation", "camera/Shot/lens", "camera/Shot/roll"]
        {
            assert_eq!(ChannelPath::parse(text).map(|p| p.to_string()), Ok(text.to_string()));
        }
    }

    #[test]
    fn lists_every_channel() {
        let names: Vec<String> = list_channels(&scene()).iter().map(ToString::to_string).collect();
        assert_eq!(names.len(), 3 + 2 + 3 + 4);
        assert!(names.contains(&"object/Arm/joint/elbow/rotation".to_string()));
        assert!(!names.contains(&"object/Cube/root_translation".to_string()));
    }
}
