//! IK constraint targets in the viewport: each constraint's target is drawn where it is at the
//! current frame (a crossed diamond with the constraint's name, a dashed line to the chain's end
//! joint), and a drag on it moves the target in the plane through it that faces the camera, as
//! the IK handle moves its target ([`super::ik_handle`]). The move is the target channel's pose
//! ([`Edit::Pose`] on [`ChannelId::IkTarget`]): a key at the current frame in record mode, a pose
//! otherwise; one undo step per drag.

use egui::{Align2, Color32, FontId, Pos2, Rect, Stroke, Ui};
use glam::{Affine3A, Vec3};

use crate::actions::{Action, Actions, Edit};
use crate::camera::{OrbitCamera, Projection};
use crate::context::FrameCtx;
use keyrig_edit::channels::{ChannelId, ChannelValue};

/// A press within this many points of a target grabs it.
pub const TARGET_RADIUS: f32 = 9.0;

/// The undo group of a target drag.
const GROUP: &str = "ik target";

const COLOUR: Color32 = Color32::from_rgb(250, 120, 220);

/// A drag of one target, from the press to the release.
pub struct TargetDrag {
    id: ChannelId,
    name: String,
    object_from_world: Affine3A,
    plane_point: Vec3,
    plane_normal: Vec3,
    /// From the pointer's point on the plane to the target, at the press.
    grip: Vec3,
    moved: bool,
}

/// One constraint's target as drawn this frame.
struct Shown {
    id: ChannelId,
    name: String,
    world: Vec3,
    at: Pos2,
    world_from_object: Affine3A,
}

/// Every IK constraint target of the objects shown, where it is now.
fn shown(ctx: &FrameCtx<'_>, projection: &Projection) -> Vec<(Shown, Option<Pos2>)> {
    let scene = ctx.scene();
    let mut out = Vec::new();
    for (object, o) in scene.objects.iter().enumerate() {
        let Some(skeleton) = &o.skeleton else { continue };
        if skeleton.ik_constraints.is_empty() || ctx.session.hidden.object(scene, object) {
            continue;
        }
        let Some(pose) = ctx.pose(object) else { continue };
        for (c, constraint) in skeleton.ik_constraints.iter().enumerate() {
            let id = ChannelId::IkTarget { object, constraint: c };
            let Some(ChannelValue::Vec3(target)) = ctx.value_now(id) else { continue };
            let world = pose.world_from_object.transform_point3(target);
            let Some(at) = projection.project(world) else { continue };
            let end = pose
                .object_from_joint
                .get(constraint.end)
                .and_then(|f| projection.project((pose.world_from_object * *f).translation.into()));
            out.push((
                Shown {
                    id,
                    name: constraint.name.clone(),
                    world,
                    at,
                    world_from_object: pose.world_from_object,
                },
                end,
            ));
        }
    }
    out
}

/// Draws the targets and runs a drag of one. Returns whether a target owns the primary button
/// this frame (the pointer is on one, or one is being dragged), so that neither the gizmo nor
/// the camera takes it.
pub(super) fn ui(
    ui: &Ui,
    ctx: &FrameCtx<'_>,
    actions: &mut Actions,
    drag: &mut Option<TargetDrag>,
    projection: &Projection,
    rect: Rect,
    response: &egui::Response,
) -> bool {
    let painter = ui.painter().with_clip_rect(rect);
    let targets = shown(ctx, projection);
    let (hover, pressed, down, any_down) = ui.input(|i| {
        (i.pointer.hover_pos(), i.pointer.primary_pressed(), i.pointer.primary_down(), i.pointer.any_down())
    });
    if let Some(mut d) = drag.take() {
        if let Some(on_plane) = hover.and_then(|p| projection.on_plane(p, d.plane_point, d.plane_normal)) {
            let world = on_plane + d.grip;
            let value = d.object_from_world.transform_point3(world);
            if value.is_finite() && ctx.value_now(d.id) != Some(ChannelValue::Vec3(value)) {
                actions.edit(Edit::Pose {
                    id: d.id,
                    value: ChannelValue::Vec3(value),
                    group: GROUP.to_owned(),
                });
                d.moved = true;
            }
        }
        for (t, end) in &targets {
            paint(&painter, t, *end, t.id == d.id);
        }
        if down {
            *drag = Some(d);
        } else if d.moved {
            actions.push(Action::Info(if ctx.session.record {
                format!("{}: target keyed at frame {}", d.name, ctx.session.playback.whole_frame())
            } else {
                format!("{}: target moved", d.name)
            }));
        }
        return true;
    }
    let free = !any_down || pressed;
    let hovered = hover.filter(|&p| free && response.contains_pointer() && rect.contains(p)).and_then(|p| {
        targets
            .iter()
            .map(|(t, _)| t)
            .filter(|t| t.at.distance(p) <= TARGET_RADIUS)
            .min_by(|a, b| a.at.distance(p).total_cmp(&b.at.distance(p)))
    });
    for (t, end) in &targets {
        paint(&painter, t, *end, hovered.is_some_and(|h| h.id == t.id));
    }
    let Some(t) = hovered else { return false };
    if pressed {
        let camera = &ctx.view.camera;
        let plane_normal = (camera.target - camera.eye()).normalize_or(Vec3::NEG_Z);
        if let Some(on_plane) = hover.and_then(|p| projection.on_plane(p, t.world, plane_normal)) {
            *drag = Some(TargetDrag {
                id: t.id,
                name: t.name.clone(),
                object_from_world: t.world_from_object.inverse(),
                plane_point: t.world,
                plane_normal,
                grip: t.world - on_plane,
                moved: false,
            });
        }
    }
    true
}

/// A target: a diamond with a cross, its name, and a dashed line to its chain's end joint.
fn paint(painter: &egui::Painter, t: &Shown, end: Option<Pos2>, active: bool) {
    let stroke = Stroke::new(if active { 2.5 } else { 1.5 }, COLOUR);
    if let Some(end) = end {
        painter.extend(egui::Shape::dashed_line(&[end, t.at], Stroke::new(1.0, COLOUR), 4.0, 4.0));
    }
    let r = TARGET_RADIUS - 2.0;
    let corners = [
        t.at + egui::vec2(0.0, -r),
        t.at + egui::vec2(r, 0.0),
        t.at + egui::vec2(0.0, r),
        t.at + egui::vec2(-r, 0.0),
    ];
    let fill = if active { COLOUR.gamma_multiply(0.5) } else { Color32::TRANSPARENT };
    painter.add(egui::Shape::convex_polygon(corners.to_vec(), fill, stroke));
    painter.line_segment([corners[0], corners[2]], Stroke::new(1.0, COLOUR));
    painter.line_segment([corners[1], corners[3]], Stroke::new(1.0, COLOUR));
    let at = t.at + egui::vec2(TARGET_RADIUS + 3.0, TARGET_RADIUS);
    let font = FontId::proportional(12.0);
    painter.text(at + egui::vec2(1.0, 1.0), Align2::LEFT_TOP, &t.name, font.clone(), Color32::BLACK);
    painter.text(at, Align2::LEFT_TOP, &t.name, font, COLOUR);
}
