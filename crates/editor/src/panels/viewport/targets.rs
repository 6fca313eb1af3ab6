//! What the gizmo transforms when several joints, objects or lights are selected: each item's
//! place and channels, the pivot they turn about (Blender's pivot point setting), and the edits
//! that turn or move them all in one undo step.
//!
//! - **Median point** (the default): the selection turns as one body about the mean of its
//!   origins. An item with a selected ancestor joint is carried by it and not turned again; an
//!   item that can move (an object, a light, a skeleton's root joint, a joint with translation
//!   keys) swings about the pivot, one that cannot turns in place.
//! - **Individual origins**: each item turns about its own origin by the same angle, so a
//!   selected chain curls (each joint adds its own turn to its parent's), as Blender and Maya do.
//! - **Active element**: as the median point, about the active item's origin.
//!
//! A move (the gizmo's arrows) moves every selected item that can move by the same world
//! offset; items carried by a selected ancestor follow it.

use glam::{Affine3A, Mat3A, Quat, Vec3};
use keyrig_core::LightKind;

use crate::actions::{Actions, Edit};
use crate::context::FrameCtx;
use crate::session::Selected;
use keyrig_edit::channels::{self, ChannelId, ChannelValue, Turn};

/// Where the selection turns about.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Pivot {
    #[default]
    MedianPoint,
    IndividualOrigins,
    ActiveElement,
}

impl Pivot {
    pub const ALL: [Pivot; 3] = [Pivot::MedianPoint, Pivot::IndividualOrigins, Pivot::ActiveElement];

    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            Pivot::MedianPoint => "Median point",
            Pivot::IndividualOrigins => "Individual origins",
            Pivot::ActiveElement => "Active element",
        }
    }

    #[must_use]
    pub fn help(self) -> &'static str {
        match self {
            Pivot::MedianPoint => {
                "The selection turns as one about the mean of its origins; joints carried by a \
                 selected parent follow it"
            }
            Pivot::IndividualOrigins => {
                "Each selected item turns about its own origin; a selected chain curls"
            }
            Pivot::ActiveElement => "The selection turns as one about the active item's origin",
        }
    }
}

/// One selected item the gizmo transforms, as it stood when read.
#[derive(Clone, Debug)]
pub(super) struct Target {
    /// World transform (a light's: its place, aimed along its direction).
    pub world: Affine3A,
    /// The rotation channel and the world rotation of the frame its value is expressed in.
    pub rotation: Option<(ChannelId, Quat)>,
    /// A light's direction channel and its value.
    pub direction: Option<(ChannelId, Vec3)>,
    /// The channel that moves the item, its value, and the linear map from a world offset to
    /// an offset of that value.
    pub translation: Option<(ChannelId, Vec3, Mat3A)>,
    /// A selected ancestor joint carries the item.
    pub carried: bool,
}

impl Target {
    pub fn origin(&self) -> Vec3 {
        self.world.translation.into()
    }
}

/// The selected items the gizmo transforms, the active one first.
pub(super) fn targets(ctx: &FrameCtx<'_>) -> Vec<Target> {
    let items: Vec<Selected> = ctx.session.selection.items().collect();
    let selected_joint = |object: usize, joint: usize| items.contains(&Selected::Joint { object, joint });
    items.iter().filter_map(|&item| target(ctx, item, &selected_joint)).collect()
}

fn target(
    ctx: &FrameCtx<'_>,
    item: Selected,
    selected_joint: &dyn Fn(usize, usize) -> bool,
) -> Option<Target> {
    let scene = ctx.scene();
    match item {
        Selected::Joint { object, joint } => {
            let skeleton = scene.objects.get(object)?.skeleton.as_ref()?;
            let pose = ctx.pose(object)?;
            let j = skeleton.joints.get(joint)?;
            let parent = j.parent.filter(|&p| p < joint);
            let parent_world = match parent {
                Some(p) => pose.world_from_object * *pose.object_from_joint.get(p)?,
                None => pose.world_from_object,
            };
            let (_, parent_rotation, _) = parent_world.to_scale_rotation_translation();
            let world = pose.world_from_object * *pose.object_from_joint.get(joint)?;
            let mut carried = false;
            let mut up = parent;
            while let Some(p) = up {
                if selected_joint(object, p) {
                    carried = true;
                    break;
                }
                up = skeleton.joints[p].parent.filter(|&q| q < p);
            }
            let translation = match parent {
                // The root translation is in the object's space.
                None => {
                    let id = ChannelId::RootTranslation(object);
                    let value = vec3(ctx.value_now(id))?;
                    Some((id, value, pose.world_from_object.matrix3.inverse()))
                }
                Some(_) => {
                    let id = ChannelId::JointTranslation { object, joint };
                    if channels::key_count(scene, id) > 0 {
                        // T(j)'s translation is in the joint's rest frame, F(p)·R(j).
                        let rest = Affine3A::from_rotation_translation(j.rest_rotation, j.rest_translation);
                        let frame = parent_world * rest;
                        vec3(ctx.value_now(id)).map(|value| (id, value, frame.matrix3.inverse()))
                    } else {
                        None
                    }
                }
            };
            Some(Target {
                world,
                rotation: Some((
                    ChannelId::JointRotation { object, joint },
                    parent_rotation * j.rest_rotation,
                )),
                direction: None,
                translation,
                carried,
            })
        }
        Selected::Object(o) => {
            let pose = ctx.pose(o)?;
            let id = ChannelId::ObjectTranslation(o);
            Some(Target {
                world: pose.world_from_object,
                rotation: Some((ChannelId::ObjectRotation(o), Quat::IDENTITY)),
                direction: None,
                translation: vec3(ctx.value_now(id)).map(|v| (id, v, Mat3A::IDENTITY)),
                carried: false,
            })
        }
        Selected::Camera(c) => {
            let state = ctx.scene.state()?.cameras.get(c)?;
            let aimed = scene.cameras.get(c)?.aim.is_some();
            let id = ChannelId::CameraTranslation(c);
            Some(Target {
                world: state.world_from_camera,
                // An aimed camera's rotation follows its target: only its place is dragged.
                rotation: (!aimed).then_some((ChannelId::CameraRotation(c), Quat::IDENTITY)),
                direction: None,
                translation: vec3(ctx.value_now(id)).map(|v| (id, v, Mat3A::IDENTITY)),
                carried: false,
            })
        }
        Selected::Light(l) => {
            let kind = scene.lights.get(l)?.kind;
            let position_id = ChannelId::LightPosition(l);
            let position = vec3(ctx.value_now(position_id))?;
            let direction = match kind {
                LightKind::Point => None,
                LightKind::Directional | LightKind::Spot { .. } => {
                    let id = ChannelId::LightDirection(l);
                    Some((id, vec3(ctx.value_now(id))?))
                }
            };
            let aim = direction.map_or(Quat::IDENTITY, |(_, d)| light_aim(d));
            Some(Target {
                world: Affine3A::from_rotation_translation(aim, position),
                rotation: None,
                direction,
                // A directional light's place only puts its icon.
                translation: (!matches!(kind, LightKind::Directional)).then_some((
                    position_id,
                    position,
                    Mat3A::IDENTITY,
                )),
                carried: false,
            })
        }
    }
}

/// The light's local axis that points along its direction (as glTF's lights shine along −Z).
const LIGHT_AXIS: Vec3 = Vec3::NEG_Z;

/// A rotation that takes [`LIGHT_AXIS`] onto the direction `d` (any twist about `d`; only the
/// direction is a channel).
fn light_aim(d: Vec3) -> Quat {
    match d.try_normalize() {
        Some(d) => Quat::from_rotation_arc(LIGHT_AXIS, d),
        None => Quat::IDENTITY,
    }
}

fn vec3(value: Option<ChannelValue>) -> Option<Vec3> {
    match value {
        Some(ChannelValue::Vec3(v)) => Some(v),
        _ => None,
    }
}

/// The point the selection turns about (the active item's origin for individual origins,
/// where the gizmo is drawn).
pub(super) fn pivot_point(targets: &[Target], pivot: Pivot) -> Vec3 {
    match pivot {
        Pivot::MedianPoint if !targets.is_empty() => {
            targets.iter().map(Target::origin).sum::<Vec3>() / targets.len() as f32
        }
        _ => targets.first().map_or(Vec3::ZERO, Target::origin),
    }
}

/// Pushes the edits that turn `targets` (as they stood when the drag started) about the world
/// `axis` through `pivot` at `centre`: `delta` degrees more on the rotation channels (each
/// turned from its value now, so turns past a half turn are kept), and the places and light
/// directions set for the whole `total` of the drag.
#[allow(clippy::too_many_arguments)]
pub(super) fn turn(
    ctx: &FrameCtx<'_>,
    actions: &mut Actions,
    targets: &[Target],
    pivot: Pivot,
    centre: Vec3,
    axis: Vec3,
    delta: f64,
    total: f64,
    group: &str,
) {
    let whole = Quat::from_axis_angle(axis.normalize_or(Vec3::X), total.to_radians() as f32);
    let individual = pivot == Pivot::IndividualOrigins;
    for t in targets {
        if t.carried && !individual {
            continue;
        }
        if let Some((id, frame)) = t.rotation {
            if delta != 0.0 {
                if let Some(ChannelValue::Rotation(from)) = ctx.value_now(id) {
                    let turn = Turn { from, axis: frame.inverse() * axis, degrees: delta };
                    actions.edit(Edit::Turn { id, turn, group: group.to_owned() });
                }
            }
        }
        if let Some((id, d)) = t.direction.filter(|_| total != 0.0) {
            actions.edit(Edit::Pose { id, value: ChannelValue::Vec3(whole * d), group: group.to_owned() });
        }
        if !individual {
            if let Some((id, value, world_to_value)) = t.translation {
                let offset = centre + whole * (t.origin() - centre) - t.origin();
                // A lone item turns about its own origin and stays where it is (no key is made).
                if offset == Vec3::ZERO {
                    continue;
                }
                let value = value + world_to_value.mul_vec3(offset);
                actions.edit(Edit::Pose { id, value: ChannelValue::Vec3(value), group: group.to_owned() });
            }
        }
    }
}

/// Pushes the edits that move every target that can move (and is not carried by a selected
/// joint) by the world offset `offset` from its value now.
pub(super) fn shift(
    ctx: &FrameCtx<'_>,
    actions: &mut Actions,
    targets: &[Target],
    offset: Vec3,
    group: &str,
) {
    for t in targets.iter().filter(|t| !t.carried) {
        if let Some((id, _, world_to_value)) = t.translation {
            if let Some(now) = vec3(ctx.value_now(id)) {
                let value = now + world_to_value.mul_vec3(offset);
                actions.edit(Edit::Pose { id, value: ChannelValue::Vec3(value), group: group.to_owned() });
            }
        }
    }
}

/// Pushes the edits that turn the lights among `targets` (directions only) by `rotation`.
pub(super) fn aim_lights(
    ctx: &FrameCtx<'_>,
    actions: &mut Actions,
    targets: &[Target],
    rotation: Quat,
    group: &str,
) {
    for t in targets {
        if let Some((id, _)) = t.direction {
            if let Some(now) = vec3(ctx.value_now(id)) {
                actions.edit(Edit::Pose {
                    id,
                    value: ChannelValue::Vec3(rotation * now),
                    group: group.to_owned(),
                });
            }
        }
    }
}
