//! The transform gizmo of the viewport's selection: transform-gizmo's handles driven from the
//! viewport's own response, and the rotation rings of joints and objects turned by the editor
//! itself ([`RingDrag`]). Its state (transform-gizmo's, whether it owns the primary button, a
//! ring drag) belongs to the viewport.

use egui::{Align2, Color32, FontId, Pos2, Rect, Stroke, Ui};
use glam::{Affine3A, DQuat, DVec3, Quat, Vec3};
use transform_gizmo_egui::math::Transform;
use transform_gizmo_egui::{GizmoConfig, GizmoInteraction, GizmoMode, GizmoOrientation, GizmoResult};

use crate::actions::{Actions, Edit};
use crate::camera::{OrbitCamera, Projection};
use crate::context::FrameCtx;
use crate::session::Selected;
use crate::twist::{RingDrag, RingDragState};
use keyrig_edit::channels::{ChannelId, ChannelValue};

use super::targets::{self, Pivot, Target};

/// The undo group of a gizmo drag: its edits are one undo step.
const GROUP: &str = "gizmo";

/// The gizmo's state across frames.
#[derive(Default)]
pub(super) struct GizmoState {
    gizmo: transform_gizmo_egui::Gizmo,
    /// The primary button went down on a gizmo handle: the gizmo owns the drag until release.
    pub(super) drag: bool,
    /// A drag on a rotation ring of a joint or object, turned by the editor itself
    /// ([`RingDrag`]) rather than by transform-gizmo.
    pub(super) ring: Option<RingDragState>,
    /// What the ring drag turns (every selected item, as it stood at the press) and the point
    /// it turns about.
    ring_targets: Vec<Target>,
    ring_centre: Vec3,
    /// Where the selection turns about (the viewport's pivot setting).
    pub(super) pivot: Pivot,
    /// Which handles the gizmo shows (W, E, S: [`GizmoTool`]).
    pub(super) tool: GizmoTool,
}

/// Which handles the gizmo shows, chosen by key as in Maya (W move, E rotate; S scale, as
/// Blender's S, since R is record mode here). Pressing a tool's key again goes back to
/// [`GizmoTool::MoveAndTurn`]. A tool whose handles do not apply to the selection (Move on a
/// joint that can only turn, Scale on anything but objects) shows what does apply, move and
/// turn, so the selection can always be posed.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum GizmoTool {
    /// Move arrows and planes with the rotation rings, as the item allows (the default).
    #[default]
    MoveAndTurn,
    /// Move arrows and planes only (W).
    Move,
    /// Rotation rings only (E).
    Turn,
    /// Scale handles for the selected objects (S).
    Scale,
}

impl GizmoTool {
    /// The tool's name in the viewport and the status bar.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            GizmoTool::MoveAndTurn => "Move and turn",
            GizmoTool::Move => "Move",
            GizmoTool::Turn => "Turn",
            GizmoTool::Scale => "Scale",
        }
    }
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
    /// (around the centre, accumulated over several turns, or a straight drag's length as an arc
    /// of the ring, whichever is larger; 1° per point along an edge-on ring; 15° steps with Ctrl) and the turn is keyed with its spin ([`Edit::Turn`]).
    pub(super) fn ui(
        &mut self,
        ui: &mut Ui,
        ctx: &FrameCtx<'_>,
        actions: &mut Actions,
        projection: &Projection,
        rect: Rect,
        response: &egui::Response,
    ) -> bool {
        let items = targets::targets(ctx);
        let Some(active) = items.first() else {
            self.drag = false;
            self.ring = None;
            return false;
        };
        // The gizmo stands at the pivot with the active item's axes.
        let mut world = active.world;
        world.translation = targets::pivot_point(&items, self.pivot).into();
        // Scale mode scales the selected objects (each about its own origin).
        let scaled: Vec<usize> = if self.tool == GizmoTool::Scale {
            ctx.session
                .selection
                .items()
                .filter_map(|item| match item {
                    Selected::Object(o) => Some(o),
                    _ => None,
                })
                .collect()
        } else {
            Vec::new()
        };
        // Point lights have only a place, directional lights only a direction (their icon's
        // place is not used for lighting), spot lights both; joints move where the rig allows
        // (a root, or a joint with translation keys).
        let can_turn = items.iter().any(|t| t.rotation.is_some() || t.direction.is_some());
        let can_move = items.iter().any(|t| t.translation.is_some() && !t.carried);
        // The tool's handles where they apply to the selection, else both.
        let (turns, moves) = match self.tool {
            GizmoTool::Move if can_move => (false, true),
            GizmoTool::Turn if can_turn => (true, false),
            _ => (can_turn, can_move),
        };
        let mut modes = GizmoMode::all_rotate() & GizmoMode::all_translate();
        if !scaled.is_empty() {
            modes = GizmoMode::all_scale();
        } else {
            if turns {
                modes |= GizmoMode::all_rotate();
            }
            if moves {
                modes |= GizmoMode::all_translate();
            }
        }
        if modes.is_empty() {
            self.drag = false;
            self.ring = None;
            return false;
        }
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
            // gizmo only draws its handles where the target now is. Every selected item turns
            // about the pivot ([`targets::turn`]).
            if let Some(p) = hover {
                ring.drag.drag_to(p);
            }
            let degrees = ring.drag.degrees(snap);
            let delta = degrees - ring.applied;
            if delta != 0.0 {
                targets::turn(
                    ctx,
                    actions,
                    &self.ring_targets,
                    self.pivot,
                    self.ring_centre,
                    ring.drag.axis,
                    delta,
                    degrees,
                    GROUP,
                );
                ring.applied = degrees;
            }
            let _ = self.gizmo.update(interaction(false, false, false), &targets);
            paint_gizmo(ui, &self.gizmo, rect);
            paint_ring_drag(ui, rect, &ring, degrees, hover, snap);
            if down {
                self.ring = Some(ring);
            } else {
                self.drag = false;
                self.ring_targets.clear();
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
        let first_rotation = items.iter().find_map(|t| t.rotation);
        let (_, world_rotation, _) = world.to_scale_rotation_translation();
        let picked = match (pressed, &result) {
            (true, Some((GizmoResult::Rotation { axis, is_view_axis, .. }, _))) => {
                let axis = DVec3::from(*axis).as_vec3();
                Some((if *is_view_axis { axis } else { world_rotation * axis }, *is_view_axis))
            }
            // transform-gizmo picks a ring within a few world units of it in the ring's plane,
            // which on a ring seen at a slant is a sliver of screen: a press up to
            // RING_HIT_POINTS from an axis ring's drawn arc takes that ring too.
            (true, None) if !on_handle && free && response.contains_pointer() && turns => hover
                .and_then(|p| near_axis_ring(projection, &world, ctx.view.camera.eye(), p))
                .map(|axis| (axis, false)),
            _ => None,
        };
        if let Some((axis, is_view_axis)) = picked {
            if let Some((channel, frame)) = first_rotation {
                let centre_world: Vec3 = world.translation.into();
                let is_view_axis = &is_view_axis;
                let eye = ctx.view.camera.eye();
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
                    self.ring_centre = centre_world;
                    self.ring_targets = items;
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
        let (old_scale, old_rotation, old_translation) = world.to_scale_rotation_translation();
        if matches!(result, GizmoResult::Scale { .. }) {
            // Every selected object's scale times the handle's factor along each axis.
            let factor = DVec3::from(new.scale).as_vec3() / old_scale;
            if factor.is_finite() {
                for &o in &scaled {
                    if let Some(ChannelValue::Vec3(now)) = ctx.value_now(ChannelId::ObjectScale(o)) {
                        actions.edit(Edit::Pose {
                            id: ChannelId::ObjectScale(o),
                            value: ChannelValue::Vec3(now * factor),
                            group: GROUP.to_owned(),
                        });
                    }
                }
            }
        } else if matches!(result, GizmoResult::Translation { .. }) {
            targets::shift(ctx, actions, &items, new_translation - old_translation, GROUP);
        } else {
            // Only lights turn through transform-gizmo (joints and objects turn on our rings).
            targets::aim_lights(ctx, actions, &items, new_rotation * old_rotation.inverse(), GROUP);
        }
        owns
    }
}

fn to_transform(a: Affine3A) -> Transform {
    let (s, r, t) = a.to_scale_rotation_translation();
    Transform::from_scale_rotation_translation(s.as_dvec3(), r.as_dquat(), t.as_dvec3())
}

/// How far (points) from an axis ring's drawn arc a press still takes the ring.
const RING_HIT_POINTS: f32 = 14.0;

/// The world axis of the axis ring (X, Y or Z of the gizmo's frame `world`) whose drawn arc —
/// the half facing the camera, [`AXIS_RING_RADIUS`] points across at the gizmo's centre — is
/// nearest `pointer`, within [`RING_HIT_POINTS`].
fn near_axis_ring(projection: &Projection, world: &Affine3A, eye: Vec3, pointer: Pos2) -> Option<Vec3> {
    let (_, rotation, centre) = world.to_scale_rotation_translation();
    let centre_screen = projection.project(centre)?;
    let to_eye = (eye - centre).normalize_or_zero();
    // The world radius that projects to the ring's screen radius at the centre's depth.
    let across = to_eye.any_orthonormal_vector();
    let unit = projection.project(centre + across * 0.01 * (eye - centre).length().max(1e-3))?;
    let points_per_world = (unit - centre_screen).length() / (0.01 * (eye - centre).length().max(1e-3));
    if points_per_world <= 0.0 {
        return None;
    }
    let radius = AXIS_RING_RADIUS / points_per_world;
    let mut best: Option<(f32, Vec3)> = None;
    for axis in [Vec3::X, Vec3::Y, Vec3::Z].map(|a| rotation * a) {
        let (u, v) = axis.any_orthonormal_pair();
        let mut previous: Option<Pos2> = None;
        for step in 0..=96 {
            let a = step as f32 / 96.0 * std::f32::consts::TAU;
            let offset = (u * a.cos() + v * a.sin()) * radius;
            // The far half is not drawn.
            let on_arc = offset.dot(to_eye) >= -0.02 * radius;
            let here = projection.project(centre + offset).filter(|_| on_arc);
            if let (Some(a), Some(b)) = (previous, here) {
                let d = distance_to_segment(pointer, a, b);
                if d <= RING_HIT_POINTS && best.is_none_or(|(e, _)| d < e) {
                    best = Some((d, axis));
                }
            }
            previous = here;
        }
    }
    best.map(|(_, axis)| axis)
}

fn distance_to_segment(p: Pos2, a: Pos2, b: Pos2) -> f32 {
    let ab = b - a;
    let t = ((p - a).dot(ab) / ab.length_sq().max(1e-9)).clamp(0.0, 1.0);
    p.distance(a + ab * t)
}

/// Screen radius of transform-gizmo's axis rings with its default visuals (gizmo_size).
const AXIS_RING_RADIUS: f32 = 75.0;
/// Screen radius of its view-axis ring (gizmo_size + stroke width + 5).
const VIEW_RING_RADIUS: f32 = 84.0;

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
    let mut text = format!("{degrees:+.1}°");
    if let Some(turns) = crate::twist::turns_readout(degrees) {
        text.push_str(&format!("  ({turns})"));
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
