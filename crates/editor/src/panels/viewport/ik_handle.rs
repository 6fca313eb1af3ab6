//! The IK handle in the viewport (IK posing, Shift+I). With a joint selected, the chain that
//! ends at it is drawn in orange and a ring, the handle, sits on the joint; the viewport shows it
//! instead of the rotation gizmo. Dragging the handle moves its target in the plane through the
//! joint that faces the camera (as Blender's grab moves in the view plane), and the chain follows
//! ([`crate::ik_posing`]); the solved rotations are applied as gizmo rotations are
//! ([`Edit::IkPose`]: keys in record mode, a pose otherwise, one undo step per drag).
//! A chain the solvers refuse is drawn red with their message; a press on it puts the message in
//! the status bar.

use egui::{Align2, Color32, FontId, Painter, Pos2, Rect, Stroke, Ui};
use glam::Vec3;

use crate::actions::{Action, Actions, Edit, SessionChange};
use crate::camera::{OrbitCamera, Projection};
use crate::context::FrameCtx;
use crate::ik_posing::{IkDrag, IkGrab, PosedChain};
use crate::session::Selected;

/// Radius of the handle's ring, points; a press within it grabs the handle.
pub const HANDLE_RADIUS: f32 = 10.0;

const IK_COLOUR: Color32 = Color32::from_rgb(255, 150, 40);
const ERROR_COLOUR: Color32 = Color32::from_rgb(255, 90, 90);

/// The joint (object, joint) whose IK handle the viewport shows: IK posing is on and a joint is
/// selected.
#[must_use]
pub fn handle_joint(ctx: &FrameCtx<'_>) -> Option<(usize, usize)> {
    match (ctx.session.ik.enabled, ctx.session.selection.item) {
        (true, Some(Selected::Joint { object, joint })) => Some((object, joint)),
        _ => None,
    }
}

/// Draws the selected joint's chain and IK handle and runs drags of the handle. `None` when the
/// viewport shows no handle (the gizmo's turn); otherwise whether the handle owns the primary
/// button this frame (the pointer is on it, or a drag is under way), so that the camera neither
/// orbits nor picks. `grab` is the viewport's press on the handle, kept until release.
pub fn handle_ui(
    ui: &Ui,
    ctx: &FrameCtx<'_>,
    actions: &mut Actions,
    grab: &mut Option<IkGrab>,
    projection: &Projection,
    rect: Rect,
    response: &egui::Response,
) -> Option<bool> {
    let Some((object, joint)) = handle_joint(ctx) else {
        *grab = None;
        return None;
    };
    let painter = ui.painter().with_clip_rect(rect);
    let (hover, pressed, down, any_down) = ui.input(|i| {
        (i.pointer.hover_pos(), i.pointer.primary_pressed(), i.pointer.primary_down(), i.pointer.any_down())
    });
    match grab.take() {
        Some(IkGrab::Dragging(drag)) => {
            *grab = continue_drag(ctx, actions, *drag, projection, hover, down, &painter);
            return Some(true);
        }
        Some(IkGrab::Refused) => {
            if down {
                *grab = Some(IkGrab::Refused);
            }
            return Some(true);
        }
        None => {}
    }
    let pose = ctx.pose(object)?;
    let end: Vec3 = (pose.world_from_object * *pose.object_from_joint.get(joint)?).translation.into();
    let Some(at) = projection.project(end) else { return Some(false) };
    let bones = ctx.session.ik.chain_bones(object, joint);
    let chain = PosedChain::new(ctx.scene(), pose, object, joint, bones);
    let free = !any_down || pressed;
    let on_handle = free
        && response.contains_pointer()
        && hover.is_some_and(|p| rect.contains(p) && p.distance(at) <= HANDLE_RADIUS);
    match &chain {
        Ok(chain) => paint_chain(&painter, projection, &chain.positions(), on_handle),
        Err(e) => {
            painter.circle_stroke(at, HANDLE_RADIUS, Stroke::new(2.0, ERROR_COLOUR));
            label(&painter, at, &e.to_string(), ERROR_COLOUR);
        }
    }
    if pressed && on_handle {
        match chain {
            Ok(chain) => {
                let camera = &ctx.view.camera;
                let forward = (camera.target - camera.eye()).normalize_or_zero();
                if let Some(pressed_at) = hover.and_then(|p| projection.on_plane(p, end, forward)) {
                    let pole = chain.pole_for_drag(ctx.session.ik.pole(&chain));
                    *grab = Some(IkGrab::Dragging(Box::new(IkDrag::new(chain, pressed_at, forward, pole))));
                }
            }
            Err(e) => {
                actions.push(Action::Error(e.to_string()));
                *grab = Some(IkGrab::Refused);
            }
        }
    }
    Some(on_handle)
}

/// One frame of a drag: the target follows the pointer on the drag's plane and the chain is
/// solved for it; on release the pole is kept for the chain's next drag. Returns the grab that
/// goes on (none once released).
fn continue_drag(
    ctx: &FrameCtx<'_>,
    actions: &mut Actions,
    mut drag: IkDrag,
    projection: &Projection,
    hover: Option<Pos2>,
    down: bool,
    painter: &Painter,
) -> Option<IkGrab> {
    let on_plane = hover.and_then(|p| projection.on_plane(p, drag.plane_point, drag.plane_normal));
    if let Some(on_plane) = on_plane {
        match drag.drag_to(drag.target_for(on_plane)) {
            Ok(Some(rotations)) => {
                let label = if ctx.session.record {
                    format!(
                        "IK key {} at frame {}",
                        drag.chain.describe(),
                        ctx.session.playback.whole_frame()
                    )
                } else {
                    format!("IK pose {}", drag.chain.describe())
                };
                actions.edit(Edit::IkPose { rotations, label });
            }
            Ok(None) => {}
            Err(e) => {
                actions.push(Action::Error(e.to_string()));
                return down.then_some(IkGrab::Refused);
            }
        }
    }
    let positions = drag.solved_positions();
    paint_chain(painter, projection, &positions, true);
    if let (Some((target, report)), Some(end)) = (drag.last, positions.last()) {
        if !report.reachable {
            if let (Some(a), Some(b)) = (projection.project(*end), projection.project(target)) {
                painter.extend(egui::Shape::dashed_line(&[a, b], Stroke::new(1.5, IK_COLOUR), 4.0, 4.0));
                painter.circle_stroke(b, 4.0, Stroke::new(1.5, IK_COLOUR));
                label(painter, b, "out of reach", IK_COLOUR);
            }
        }
    }
    if down {
        return Some(IkGrab::Dragging(Box::new(drag)));
    }
    if drag.moved() {
        let turned = drag.chain.names[..drag.chain.bones()].join(", ");
        actions.push(Action::Info(if ctx.session.record {
            format!("IK: keyed {turned} at frame {}", ctx.session.playback.whole_frame())
        } else {
            format!("IK: posed {turned} (press I to key)")
        }));
    }
    actions.session(SessionChange::RememberPole { chain: Box::new(drag.chain), pole: drag.pole });
    None
}

/// The chain's bones in the IK colour and the handle (a ring, filled while hovered or dragged) on
/// its end joint; `positions` are world positions, root first.
fn paint_chain(painter: &Painter, projection: &Projection, positions: &[Vec3], active: bool) {
    for pair in positions.windows(2) {
        if let Some(segment) = projection.project_segment(pair[0], pair[1]) {
            painter.line_segment(segment, Stroke::new(3.0, IK_COLOUR));
        }
    }
    let Some(at) = positions.last().and_then(|p| projection.project(*p)) else { return };
    if active {
        painter.circle_filled(at, HANDLE_RADIUS, IK_COLOUR.gamma_multiply(0.45));
    }
    painter.circle_stroke(at, HANDLE_RADIUS, Stroke::new(2.0, IK_COLOUR));
    painter.circle_filled(at, 2.5, IK_COLOUR);
    label(painter, at, "IK", IK_COLOUR);
}

/// Text beside the handle, with a shadow so it reads over the mesh.
fn label(painter: &Painter, at: Pos2, text: &str, colour: Color32) {
    let at = at + egui::vec2(HANDLE_RADIUS + 4.0, -HANDLE_RADIUS - 2.0);
    let font = FontId::proportional(13.0);
    painter.text(at + egui::vec2(1.0, 1.0), Align2::LEFT_BOTTOM, text, font.clone(), Color32::BLACK);
    painter.text(at, Align2::LEFT_BOTTOM, text, font, colour);
}
