//! Object constraints in the viewport (docs/constraints.md): a dotted line from each
//! constrained object to what its constraints read now — an aim's, a copy's target, a child-of
//! constraint's parent in effect — with the constraint's name, and a follow path's polyline.
//! Drawn only; targets are picked in the inspector.

use egui::{Align2, Color32, FontId, Pos2, Stroke};
use glam::Vec3;
use keyrig_core::channel_id::ConstraintProperty;
use keyrig_core::{AimTarget, ConstraintKind};

use crate::camera::Projection;
use crate::context::FrameCtx;
use keyrig_edit::channels::{ChannelId, ChannelValue};

const COLOUR: Color32 = Color32::from_rgb(120, 220, 250);

/// Where `target` is now in world space, from the evaluated poses.
fn target_world(ctx: &FrameCtx<'_>, target: &AimTarget) -> Option<Vec3> {
    let scene = ctx.scene();
    match target {
        AimTarget::Point(p) => Some(*p),
        AimTarget::Object(name) => {
            let o = scene.objects.iter().position(|x| &x.name == name)?;
            Some(ctx.pose(o)?.world_from_object.translation.into())
        }
        AimTarget::Joint { object, joint } => {
            let o = scene.objects.iter().position(|x| &x.name == object)?;
            let j = scene.objects[o].skeleton.as_ref()?.joints.iter().position(|x| &x.name == joint)?;
            let pose = ctx.pose(o)?;
            Some((pose.world_from_object * *pose.object_from_joint.get(j)?).translation.into())
        }
    }
}

/// Draws every shown object's constraint lines.
pub(super) fn paint(painter: &egui::Painter, projection: &Projection, ctx: &FrameCtx<'_>) {
    let scene = ctx.scene();
    let font = FontId::proportional(11.0);
    for (o, object) in scene.objects.iter().enumerate() {
        if object.constraints.is_empty() || ctx.session.hidden.object(scene, o) {
            continue;
        }
        let Some(pose) = ctx.pose(o) else { continue };
        let Some(from) = projection.project(pose.world_from_object.translation.into()) else { continue };
        for (c, constraint) in object.constraints.iter().enumerate() {
            let target = match &constraint.kind {
                ConstraintKind::AimAt { target, .. }
                | ConstraintKind::CopyLocation { target }
                | ConstraintKind::CopyRotation { target } => Some(target.clone()),
                ConstraintKind::ChildOf { parents, .. } => {
                    let id = ChannelId::Constraint {
                        object: o,
                        constraint: c,
                        property: ConstraintProperty::Parent,
                    };
                    match ctx.value_now(id) {
                        Some(ChannelValue::Scalar(v)) if v.round() >= 0.0 => {
                            parents.get(v.round() as usize).map(|p| p.target.clone())
                        }
                        _ => None,
                    }
                }
                ConstraintKind::FollowPath { points, space, .. } => {
                    let space = match space {
                        Some(name) => scene
                            .objects
                            .iter()
                            .position(|x| &x.name == name)
                            .and_then(|s| ctx.pose(s))
                            .map(|p| p.world_from_object),
                        None => Some(glam::Affine3A::IDENTITY),
                    };
                    if let Some(space) = space {
                        let line: Vec<Pos2> = points
                            .iter()
                            .filter_map(|p| projection.project(space.transform_point3(*p)))
                            .collect();
                        if line.len() == points.len() {
                            painter.add(egui::Shape::line(line, Stroke::new(1.0, COLOUR)));
                        }
                    }
                    None
                }
            };
            let Some(to) = target.and_then(|t| target_world(ctx, &t)).and_then(|w| projection.project(w))
            else {
                continue;
            };
            painter.extend(egui::Shape::dotted_line(&[from, to], COLOUR, 6.0, 1.0));
            let mid = from + (to - from) * 0.5;
            painter.text(mid, Align2::LEFT_BOTTOM, &constraint.name, font.clone(), COLOUR);
        }
    }
}
