//! The IK handle in the viewport (IK posing, Shift+I). With a joint selected, the chain that
//! ends at it is drawn in orange and a ring, the handle, sits on the joint; the viewport shows it
//! instead of the rotation gizmo. Dragging the handle moves its target in the plane through the
//! joint that faces the camera (as Blender's grab moves in the view plane), and the chain follows
//! ([`crate::ik_posing`]); the solved rotations are applied as gizmo rotations are
//! ([`EditorApp::apply_ik_pose`]: keys in record mode, a pose otherwise, one undo step per drag).
//! A chain the solvers refuse is drawn red with their message; a press on it puts the message in
//! the status bar.

use egui::{Align2, Color32, FontId, Painter, Pos2, Rect, Stroke, Ui};
use glam::Vec3;

use crate::app::EditorApp;
use crate::camera::{OrbitCamera, Projection};
use crate::eval::ObjectPose;
use crate::ik_posing::{IkDrag, IkGrab, PosedChain};
use crate::session::Selected;

/// Radius of the handle's ring, points; a press within it grabs the handle.
pub const HANDLE_RADIUS: f32 = 10.0;

const IK_COLOUR: Color32 = Color32::from_rgb(255, 150, 40);
const ERROR_COLOUR: Color32 = Color32::from_rgb(255, 90, 90);

/// The joint (object, joint) whose IK handle the viewport shows: IK posing is on and a joint is
/// selected.
#[must_use]
pub fn handle_joint(app: &EditorApp) -> Option<(usize, usize)> {
    match (app.session.ik.enabled, app.session.selection.item) {
        (true, Some(Selected::Joint { object, joint })) => Some((object, joint)),
        _ => None,
    }
}

/// Draws the selected joint's chain and IK handle and runs drags of the handle. `None` when the
/// viewport shows no handle (the gizmo's turn); otherwise whether the handle owns the primary
/// button this frame (the pointer is on it, or a drag is under way), so that the camera neither
/// orbits nor picks.
pub fn handle_ui(
    ui: &Ui,
    app: &mut EditorApp,
    projection: &Projection,
    rect: Rect,
    response: &egui::Response,
    poses: &[Option<ObjectPose>],
) -> Option<bool> {
    let Some((object, joint)) = handle_joint(app) else {
        app.ik_grab = None;
        return None;
    };
    app.gizmo_drag = false;
    app.ring_drag = None;
    let painter = ui.painter().with_clip_rect(rect);
    let (hover, pressed, down, any_down) = ui.input(|i| {
        (i.pointer.hover_pos(), i.pointer.primary_pressed(), i.pointer.primary_down(), i.pointer.any_down())
    });
    match app.ik_grab.take() {
        Some(IkGrab::Dragging(drag)) => {
            continue_drag(app, *drag, projection, hover, down, &painter);
            return Some(true);
        }
        Some(IkGrab::Refused) => {
            if down {
                app.ik_grab = Some(IkGrab::Refused);
            }
            return Some(true);
        }
        None => {}
    }
    let pose = poses.get(object).and_then(Option::as_ref)?;
    let end: Vec3 = (pose.world_from_object * *pose.object_from_joint.get(joint)?).translation.into();
    let Some(at) = projection.project(end) else { return Some(false) };
    let bones = app.session.ik.chain_bones(object, joint);
    let chain = PosedChain::new(app.doc.scene(), pose, object, joint, bones);
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
                let camera = &app.view.camera;
                let forward = (camera.target - camera.eye()).normalize_or_zero();
                if let Some(pressed_at) = hover.and_then(|p| projection.on_plane(p, end, forward)) {
                    let pole = chain.pole_for_drag(app.session.ik.pole(&chain));
                    app.ik_grab =
                        Some(IkGrab::Dragging(Box::new(IkDrag::new(chain, pressed_at, forward, pole))));
                }
            }
            Err(e) => {
                app.error(e.to_string());
                app.ik_grab = Some(IkGrab::Refused);
            }
        }
    }
    Some(on_handle)
}

/// One frame of a drag: the target follows the pointer on the drag's plane and the chain is
/// solved for it; on release the pole is kept for the chain's next drag.
fn continue_drag(
    app: &mut EditorApp,
    mut drag: IkDrag,
    projection: &Projection,
    hover: Option<Pos2>,
    down: bool,
    painter: &Painter,
) {
    let on_plane = hover.and_then(|p| projection.on_plane(p, drag.plane_point, drag.plane_normal));
    if let Some(on_plane) = on_plane {
        match drag.drag_to(drag.target_for(on_plane)) {
            Ok(Some(rotations)) => {
                let label = if app.session.record {
                    format!(
                        "IK key {} at frame {}",
                        drag.chain.describe(),
                        app.session.playback.whole_frame()
                    )
                } else {
                    format!("IK pose {}", drag.chain.describe())
                };
                app.apply_ik_pose(&rotations, &label);
            }
            Ok(None) => {}
            Err(e) => {
                app.error(e.to_string());
                if down {
                    app.ik_grab = Some(IkGrab::Refused);
                }
                return;
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
        app.ik_grab = Some(IkGrab::Dragging(Box::new(drag)));
        return;
    }
    app.session.ik.remember_pole(&drag.chain, drag.pole);
    if drag.moved() {
        let turned = drag.chain.names[..drag.chain.bones()].join(", ");
        if app.session.record {
            app.info(format!("IK: keyed {turned} at frame {}", app.session.playback.whole_frame()));
        } else {
            app.info(format!("IK: posed {turned} (press I to key)"));
        }
    }
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
