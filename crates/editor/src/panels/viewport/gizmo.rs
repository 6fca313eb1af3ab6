//! The transform gizmo of the viewport's selection: transform-gizmo's handles driven from the
//! viewport's own response, and the rotation rings of joints and objects turned by the editor
//! itself ([`RingDrag`]). Its state (transform-gizmo's, whether it owns the primary button, a
//! ring drag) belongs to the viewport.

use egui::{Align2, Color32, FontId, Pos2, Rect, Stroke, Ui};
use glam::{Affine3A, DQuat, DVec3, Quat, Vec3};
use keyrig_core::LightKind;
use transform_gizmo_egui::math::Transform;
use transform_gizmo_egui::{GizmoConfig, GizmoInteraction, GizmoMode, GizmoOrientation, GizmoResult};

use crate::actions::{Actions, Edit};
use crate::camera::{OrbitCamera, Projection};
use crate::channels::{ChannelId, ChannelValue, Turn};
use crate::context::FrameCtx;
use crate::session::Selected;
use crate::twist::{RingDrag, RingDragState};

/// The undo group of a gizmo drag: its edits are one undo step.
const GROUP: &str = "gizmo";

/// A pose change from the gizmo, part of the drag's undo step.
fn pose_edit(actions: &mut Actions, id: ChannelId, value: ChannelValue) {
    actions.edit(Edit::Pose { id, value, group: GROUP.to_owned() });
}

/// The gizmo's state across frames.
#[derive(Default)]
pub(super) struct GizmoState {
    gizmo: transform_gizmo_egui::Gizmo,
    /// The primary button went down on a gizmo handle: the gizmo owns the drag until release.
    pub(super) drag: bool,
    /// A drag on a rotation ring of a joint or object, turned by the editor itself
    /// ([`RingDrag`]) rather than by transform-gizmo.
    pub(super) ring: Option<RingDragState>,
}

impl GizmoState {
    /// Shows the gizmo and lets it take the primary button when the pointer is on one of its
    /// handles (transform-gizmo's pick test); returns true while it owns the primary button (a
    /// press on a handle, until release), so the camera neither orbits nor picks then.
    ///
    /// transform-gizmo-egui's `interact` puts a click-and-drag widget under the pointer wherever
    /// it is, which takes hover, scroll and every drag from the viewport while anything is
    /// selected; this drives the gizmo with [`Gizmo::update`] instead, from the viewport's own
    /// response.
    ///
    /// The rotation rings of joints and objects are turned by the editor itself: transform-gizmo
    /// maps the pointer to the angle around the ring's centre on screen with no way to change it,
    /// which turns a ring seen edge-on by 0° and a thin ring by large jumps. A press on a ring
    /// asks transform-gizmo which ring it picked; from then on [`RingDrag`] follows the pointer
    /// (around the centre, accumulated over several turns, or 1° per point along an edge-on
    /// ring; 15° steps with Ctrl) and the turn is keyed with its spin ([`Edit::Turn`]).
    pub(super) fn ui(
        &mut self,
        ui: &mut Ui,
        ctx: &FrameCtx<'_>,
        actions: &mut Actions,
        projection: &Projection,
        rect: Rect,
        response: &egui::Response,
    ) -> bool {
        let Some((world, kind)) = gizmo_target(ctx) else {
            self.drag = false;
            self.ring = None;
            return false;
        };
        let modes = match kind {
            GizmoKind::Joint { .. } => GizmoMode::all_rotate(),
            GizmoKind::Object(_) => GizmoMode::all_rotate() | GizmoMode::all_translate(),
            // Point lights have only a place, directional lights only a direction (their icon's
            // place is not used for lighting), spot lights both.
            GizmoKind::Light(_, LightKind::Point) => GizmoMode::all_translate(),
            GizmoKind::Light(_, LightKind::Directional) => GizmoMode::all_rotate(),
            GizmoKind::Light(_, LightKind::Spot { .. }) => {
                GizmoMode::all_rotate() | GizmoMode::all_translate()
            }
            // An aimed camera's rotation follows its target: only its place is dragged.
            GizmoKind::Camera { aimed: true, .. } => GizmoMode::all_translate(),
            GizmoKind::Camera { aimed: false, .. } => GizmoMode::all_rotate() | GizmoMode::all_translate(),
        };
        let to_rows = |m: glam::Mat4| m.as_dmat4().into();
        self.gizmo.update_config(GizmoConfig {
            view_matrix: to_rows(projection.camera_from_world),
            projection_matrix: to_rows(projection.clip_from_camera),
            viewport: transform_gizmo_egui::Rect::from_min_max(
                transform_gizmo_egui::math::Pos2::new(rect.min.x, rect.min.y),
                transform_gizmo_egui::math::Pos2::new(rect.max.x, rect.max.y),
            ),
            modes,
            orientation: GizmoOrientation::Local,
            pixels_per_point: ui.ctx().pixels_per_point(),
            ..Default::default()
        });
        let targets = [to_transform(world)];
        let (hover, pressed, down, any_down, snap) = ui.input(|i| {
            (
                i.pointer.hover_pos(),
                i.pointer.primary_pressed(),
                i.pointer.primary_down(),
                i.pointer.any_down(),
                i.modifiers.ctrl || i.modifiers.command,
            )
        });
        let cursor = hover.unwrap_or_default();
        let interaction = |hovered: bool, drag_started: bool, dragging: bool| GizmoInteraction {
            cursor_pos: (cursor.x, cursor.y),
            hovered,
            drag_started,
            dragging,
        };
        if let Some(mut ring) = self.ring.take() {
            // A rotation ring drag of our own: the angle follows the pointer (RingDrag), the
            // gizmo only draws its handles where the target now is.
            if let Some(p) = hover {
                ring.drag.drag_to(p);
            }
            let degrees = ring.drag.degrees(snap);
            let delta = degrees - ring.applied;
            if delta != 0.0 {
                if let Some(ChannelValue::Rotation(from)) = ctx.value_now(ring.channel) {
                    let axis = ring.frame.inverse() * ring.drag.axis;
                    let turn = Turn { from, axis, degrees: delta };
                    actions.edit(Edit::Turn { id: ring.channel, turn, group: GROUP.to_owned() });
                    ring.applied = degrees;
                }
            }
            let _ = self.gizmo.update(interaction(false, false, false), &targets);
            paint_gizmo(ui, &self.gizmo, rect);
            paint_ring_drag(ui, rect, &ring, degrees, hover, snap);
            if down {
                self.ring = Some(ring);
            } else {
                self.drag = false;
            }
            return true;
        }
        if !self.drag {
            // Place the handles for this frame's target and camera (no input) so that the pick
            // test below sees what is drawn.
            let _ = self.gizmo.update(interaction(false, false, false), &targets);
        }
        // No other drag (orbit, pan) under way, or one starting now.
        let free = !any_down || pressed;
        let on_handle = free
            && response.contains_pointer()
            && hover.is_some_and(|p| rect.contains(p) && self.gizmo.pick_preview((p.x, p.y)));
        if pressed && on_handle {
            self.drag = true;
        }
        let owns = self.drag || on_handle;
        let result = self.gizmo.update(interaction(owns, pressed && self.drag, down && self.drag), &targets);
        if !down {
            self.drag = false;
        }
        // A press on a rotation ring of a joint or object starts a drag of our own (RingDrag):
        // transform-gizmo only tells which ring was picked.
        if let (true, Some((GizmoResult::Rotation { axis, is_view_axis, .. }, _))) = (pressed, &result) {
            if let Some((channel, frame)) = rotation_channel(ctx, kind) {
                let (_, world_rotation, centre_world) = world.to_scale_rotation_translation();
                let axis = DVec3::from(*axis).as_vec3();
                let axis = if *is_view_axis { axis } else { world_rotation * axis };
                let eye = ctx.view.camera.eye();
                let centre_world: Vec3 = centre_world;
                let step = 0.01 * (centre_world - eye).length().max(1e-3);
                let screen_dir = |v: Vec3| match (
                    projection.project(centre_world),
                    projection.project(centre_world + v.normalize_or_zero() * step),
                ) {
                    (Some(a), Some(b)) => b - a,
                    _ => egui::Vec2::ZERO,
                };
                if let (Some(centre), Some(press)) = (projection.project(centre_world), hover) {
                    let radius = if *is_view_axis { VIEW_RING_RADIUS } else { AXIS_RING_RADIUS };
                    let drag = RingDrag::new(axis, centre_world - eye, centre, press, radius, screen_dir);
                    self.ring = Some(RingDragState { drag, channel, frame, applied: 0.0 });
                    // End transform-gizmo's own drag; it draws idle handles from now on.
                    let _ = self.gizmo.update(interaction(false, false, false), &targets);
                    paint_gizmo(ui, &self.gizmo, rect);
                    return true;
                }
            }
        }
        paint_gizmo(ui, &self.gizmo, rect);
        let Some((result, transforms)) = result else { return owns };
        // transform-gizmo reports its drag every frame; a pointer held still changes nothing (what
        // it reports then differs from the pose only by rounding), so nothing is edited.
        let moved = ui.input(|i| i.pointer.delta() != egui::Vec2::ZERO || i.pointer.primary_pressed());
        if !moved {
            return owns;
        }
        let Some(new) = transforms.first() else { return owns };
        let new_rotation: Quat = DQuat::from(new.rotation).as_quat().normalize();
        let new_translation: Vec3 = DVec3::from(new.translation).as_vec3();
        match kind {
            GizmoKind::Joint { object, joint } => {
                // F(j) = F(p)·R(j)·T(j): T = (world_from_parent·R(j))⁻¹ · new world rotation.
                let scene = ctx.scene();
                let Some(skeleton) = scene.objects.get(object).and_then(|o| o.skeleton.as_ref()) else {
                    return owns;
                };
                let Some(pose) = ctx.pose(object) else { return owns };
                let j = &skeleton.joints[joint];
                let parent_world = match j.parent.filter(|&p| p < joint) {
                    Some(p) => pose.world_from_object * pose.object_from_joint[p],
                    None => pose.world_from_object,
                };
                let (_, parent_rotation, _) = parent_world.to_scale_rotation_translation();
                let local = joint_rotation_from_world(parent_rotation, j.rest_rotation, new_rotation);
                pose_edit(
                    actions,
                    ChannelId::JointRotation { object, joint },
                    ChannelValue::Rotation(local.normalize()),
                );
            }
            GizmoKind::Camera { camera: c, .. } => {
                if matches!(result, GizmoResult::Translation { .. }) {
                    pose_edit(actions, ChannelId::CameraTranslation(c), ChannelValue::Vec3(new_translation));
                } else {
                    pose_edit(actions, ChannelId::CameraRotation(c), ChannelValue::Rotation(new_rotation));
                }
            }
            GizmoKind::Object(o) => {
                if matches!(result, GizmoResult::Translation { .. }) {
                    pose_edit(actions, ChannelId::ObjectTranslation(o), ChannelValue::Vec3(new_translation));
                } else {
                    pose_edit(actions, ChannelId::ObjectRotation(o), ChannelValue::Rotation(new_rotation));
                }
            }
            GizmoKind::Light(l, _) => {
                if matches!(result, GizmoResult::Translation { .. }) {
                    pose_edit(actions, ChannelId::LightPosition(l), ChannelValue::Vec3(new_translation));
                } else if let Some(ChannelValue::Vec3(old)) = ctx.value_now(ChannelId::LightDirection(l)) {
                    // Keep the direction's length (it need not be unit), turn it with the gizmo.
                    let length = old.length();
                    let length = if length > 0.0 { length } else { 1.0 };
                    let direction = (new_rotation * LIGHT_AXIS) * length;
                    pose_edit(actions, ChannelId::LightDirection(l), ChannelValue::Vec3(direction));
                }
            }
        }
        owns
    }
}

/// The world transform the gizmo edits for the selection, and which channels it drives.
fn gizmo_target(ctx: &FrameCtx<'_>) -> Option<(Affine3A, GizmoKind)> {
    match ctx.session.selection.item? {
        Selected::Joint { object, joint } => {
            let pose = ctx.pose(object)?;
            Some((
                pose.world_from_object * *pose.object_from_joint.get(joint)?,
                GizmoKind::Joint { object, joint },
            ))
        }
        Selected::Object(o) => Some((ctx.pose(o)?.world_from_object, GizmoKind::Object(o))),
        Selected::Camera(c) => {
            let state = ctx.scene.state()?.cameras.get(c)?;
            let aimed = ctx.scene().cameras.get(c)?.aim.is_some();
            Some((state.world_from_camera, GizmoKind::Camera { camera: c, aimed }))
        }
        Selected::Light(l) => {
            let kind = ctx.scene().lights.get(l)?.kind;
            let Some(ChannelValue::Vec3(p)) = ctx.value_now(ChannelId::LightPosition(l)) else { return None };
            let aim = match kind {
                LightKind::Point => Quat::IDENTITY,
                LightKind::Directional | LightKind::Spot { .. } => {
                    let Some(ChannelValue::Vec3(d)) = ctx.value_now(ChannelId::LightDirection(l)) else {
                        return None;
                    };
                    light_aim(d)
                }
            };
            Some((Affine3A::from_rotation_translation(aim, p), GizmoKind::Light(l, kind)))
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

#[derive(Clone, Copy)]
enum GizmoKind {
    Joint { object: usize, joint: usize },
    Object(usize),
    Light(usize, LightKind),
    Camera { camera: usize, aimed: bool },
}

fn to_transform(a: Affine3A) -> Transform {
    let (s, r, t) = a.to_scale_rotation_translation();
    Transform::from_scale_rotation_translation(s.as_dvec3(), r.as_dquat(), t.as_dvec3())
}

/// Screen radius of transform-gizmo's axis rings with its default visuals (gizmo_size).
const AXIS_RING_RADIUS: f32 = 75.0;
/// Screen radius of its view-axis ring (gizmo_size + stroke width + 5).
const VIEW_RING_RADIUS: f32 = 84.0;

/// The rotation channel the gizmo's rings turn for a joint or object, and the world rotation
/// of the frame its value is expressed in.
fn rotation_channel(ctx: &FrameCtx<'_>, kind: GizmoKind) -> Option<(ChannelId, Quat)> {
    match kind {
        GizmoKind::Joint { object, joint } => {
            let skeleton = ctx.scene().objects.get(object)?.skeleton.as_ref()?;
            let pose = ctx.pose(object)?;
            let j = skeleton.joints.get(joint)?;
            let parent_world = match j.parent.filter(|&p| p < joint) {
                Some(p) => pose.world_from_object * *pose.object_from_joint.get(p)?,
                None => pose.world_from_object,
            };
            let (_, parent_rotation, _) = parent_world.to_scale_rotation_translation();
            Some((ChannelId::JointRotation { object, joint }, parent_rotation * j.rest_rotation))
        }
        GizmoKind::Object(o) => Some((ChannelId::ObjectRotation(o), Quat::IDENTITY)),
        GizmoKind::Camera { camera, aimed: false } => {
            Some((ChannelId::CameraRotation(camera), Quat::IDENTITY))
        }
        GizmoKind::Light(..) | GizmoKind::Camera { aimed: true, .. } => None,
    }
}

/// Shows a ring drag: the start and current directions (around the centre) or the line the
/// drag follows (edge-on), and the angle turned, with "snap 15°" while Ctrl is held.
fn paint_ring_drag(
    ui: &Ui,
    rect: Rect,
    ring: &RingDragState,
    degrees: f64,
    pointer: Option<Pos2>,
    snap: bool,
) {
    let painter = ui.painter().with_clip_rect(rect);
    let colour = Color32::from_rgb(255, 215, 90);
    let stroke = Stroke::new(1.5, colour);
    let centre = ring.drag.centre;
    match ring.drag.mapping {
        crate::twist::RingMapping::Around { .. } => {
            if let Some(p) = pointer {
                painter.line_segment([centre, p], stroke);
            }
            painter.circle_filled(centre, 3.0, colour);
        }
        crate::twist::RingMapping::Along { tangent } => {
            let t = egui::vec2(tangent.x, tangent.y) * VIEW_RING_RADIUS;
            let at = pointer.unwrap_or(centre);
            painter.arrow(at - t * 0.5, t, stroke);
        }
    }
    let turns = (degrees.abs() / 360.0).floor();
    let mut text = format!("{degrees:+.1}°");
    if turns >= 1.0 {
        text.push_str(&format!("  ({turns:.0} turn{})", if turns >= 2.0 { "s" } else { "" }));
    }
    if snap {
        text.push_str("  snap 15°");
    }
    let at = pointer.unwrap_or(centre) + egui::vec2(16.0, -18.0);
    painter.text(
        at + egui::vec2(1.0, 1.0),
        Align2::LEFT_BOTTOM,
        &text,
        FontId::proportional(14.0),
        Color32::BLACK,
    );
    painter.text(at, Align2::LEFT_BOTTOM, text, FontId::proportional(14.0), colour);
}

/// Draws the gizmo's triangles (transform-gizmo's draw data, in screen points).
fn paint_gizmo(ui: &Ui, gizmo: &transform_gizmo_egui::Gizmo, rect: Rect) {
    let draw = gizmo.draw();
    let vertices = draw
        .vertices
        .into_iter()
        .zip(draw.colors)
        .map(|(pos, [r, g, b, a])| egui::epaint::Vertex {
            pos: pos.into(),
            uv: Pos2::default(),
            color: egui::Rgba::from_rgba_premultiplied(r, g, b, a).into(),
        })
        .collect();
    ui.painter().with_clip_rect(rect).add(egui::Mesh {
        indices: draw.indices,
        vertices,
        ..Default::default()
    });
}

/// The local rotation T(j) that gives joint j the world rotation `world_rotation`, from
/// F(j) = F(p(j))·R(j)·T(j): T(j) = (rot(F(p(j)))·R(j))⁻¹ · world rotation. For a root,
/// `parent_world_rotation` is the object's rotation.
#[must_use]
pub fn joint_rotation_from_world(
    parent_world_rotation: Quat,
    rest_rotation: Quat,
    world_rotation: Quat,
) -> Quat {
    ((parent_world_rotation * rest_rotation).inverse() * world_rotation).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joint_rotation_from_world_inverts_the_chain() {
        let parent = Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        let rest = Quat::from_rotation_z(0.4);
        let local = Quat::from_euler(glam::EulerRot::XYZ, -0.2, 0.5, 0.9);
        let world = parent * rest * local;
        let back = joint_rotation_from_world(parent, rest, world);
        assert!(back.angle_between(local) < 1e-5, "{back:?} vs {local:?}");
    }
}
