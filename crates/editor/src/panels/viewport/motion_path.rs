//! The editable motion path: with the motion path shown (View ▸ Motion path) and an object or a
//! skeleton's root joint selected, each translation key of it is a handle on the path, drawn
//! over the GPU's path (and in the painter's viewport, which draws no path of its own, as the
//! only sign of it). A drag on a handle moves that key's position in the plane through it that
//! faces the camera: the key's value changes by the move, its time and interpolation stay; one
//! undo step per drag. The key at the current frame is left to the gizmo, which stands on it.

use egui::{Align2, Color32, FontId, Pos2, Rect, Stroke, Ui};
use glam::{Mat3A, Vec3};

use crate::actions::{Action, Actions, Edit};
use crate::camera::{OrbitCamera, Projection};
use crate::context::FrameCtx;
use crate::session::Selected;
use keyrig_edit::channels::{self, ChannelId, ChannelValue};
use keyrig_edit::SceneEdit;

/// A press within this many points of a key's handle grabs it.
pub const KEY_RADIUS: f32 = 7.0;

/// Handles this close to the selection's origin on screen are the gizmo's.
const GIZMO_CLEARANCE: f32 = 14.0;

const GROUP: &str = "motion path key";
const COLOUR: Color32 = Color32::from_rgb(255, 220, 90);

/// A drag of one key of the path.
pub struct KeyDrag {
    id: ChannelId,
    /// The key's time and its value at the press.
    time: f64,
    value: Vec3,
    /// World offset → value offset.
    world_to_value: Mat3A,
    plane_point: Vec3,
    plane_normal: Vec3,
    /// The pointer's point on the plane at the press.
    pressed_at: Vec3,
    moved: bool,
}

/// One key handle: its channel, time, value, world position and the map from a world offset
/// to a value offset.
struct Handle {
    id: ChannelId,
    time: f64,
    value: Vec3,
    world: Vec3,
    at: Pos2,
    world_to_value: Mat3A,
}

/// The translation channel of the selection whose keys the path shows as handles: an object's
/// translation (world space) or a skeleton root's translation (object space).
fn channel(ctx: &FrameCtx<'_>) -> Option<(usize, ChannelId, usize)> {
    let scene = ctx.scene();
    match ctx.session.selection.item? {
        Selected::Object(o) => Some((o, ChannelId::ObjectTranslation(o), 0)),
        Selected::Joint { object, joint } => {
            let skeleton = scene.objects.get(object)?.skeleton.as_ref()?;
            let root = skeleton.joints.get(joint)?.parent.is_none();
            root.then_some((object, ChannelId::RootTranslation(object), joint))
        }
        _ => None,
    }
}

fn handles(ctx: &FrameCtx<'_>, projection: &Projection) -> Vec<Handle> {
    let Some((o, id, root)) = channel(ctx) else { return Vec::new() };
    let scene = ctx.scene();
    let eval = ctx.evaluator();
    let mut out = Vec::new();
    for (i, time) in channels::key_times(scene, id).into_iter().enumerate() {
        let Some(ChannelValue::Vec3(value)) = channels::key_value(scene, id, i) else { continue };
        let Some(state) = eval.object_at(o, time, &ctx.session.overrides) else { continue };
        let (world, world_to_value) = match id {
            ChannelId::RootTranslation(_) => {
                let Some(root) = state.palette.as_ref().map(|p| p.joint_position(root)) else { continue };
                (state.world_from_object.transform_point3(root), state.world_from_object.matrix3.inverse())
            }
            _ => (state.world_from_object.translation.into(), Mat3A::IDENTITY),
        };
        if let Some(at) = projection.project(world) {
            out.push(Handle { id, time, value, world, at, world_to_value });
        }
    }
    out
}

/// Draws the key handles of the selection's path and runs a drag of one. Returns whether a
/// handle owns the primary button this frame (under the pointer, or dragged).
pub(super) fn ui(
    ui: &Ui,
    ctx: &FrameCtx<'_>,
    actions: &mut Actions,
    drag: &mut Option<KeyDrag>,
    projection: &Projection,
    rect: Rect,
    response: &egui::Response,
) -> bool {
    if !ctx.view.motion_path {
        *drag = None;
        return false;
    }
    let painter = ui.painter().with_clip_rect(rect);
    let (hover, pressed, down, any_down) = ui.input(|i| {
        (i.pointer.hover_pos(), i.pointer.primary_pressed(), i.pointer.primary_down(), i.pointer.any_down())
    });
    if let Some(mut d) = drag.take() {
        if let Some(on_plane) = hover.and_then(|p| projection.on_plane(p, d.plane_point, d.plane_normal)) {
            let value = d.value + d.world_to_value.mul_vec3(on_plane - d.pressed_at);
            if value.is_finite() {
                let (id, time) = (d.id, d.time);
                actions.edit(Edit::continuous(GROUP, SceneEdit::MotionPathKey { channel: id, time, value }));
                d.moved = true;
            }
        }
        for h in handles(ctx, projection) {
            paint(&painter, &h, ctx, h.id == d.id && (h.time - d.time).abs() < 1e-9);
        }
        if down {
            *drag = Some(d);
        } else if d.moved {
            let frame = (d.time * ctx.scene().fps).round();
            actions.push(Action::Info(format!("Moved the key at frame {frame} on the motion path")));
        }
        return true;
    }
    let all = handles(ctx, projection);
    let origin = ctx
        .session
        .selection
        .item
        .and_then(|item| match item {
            Selected::Object(o) => ctx.pose(o).map(|p| Vec3::from(p.world_from_object.translation)),
            Selected::Joint { object, joint } => ctx.pose(object).and_then(|p| {
                Some(Vec3::from((p.world_from_object * *p.object_from_joint.get(joint)?).translation))
            }),
            _ => None,
        })
        .and_then(|w| projection.project(w));
    let free = !any_down || pressed;
    let grabbable = |h: &&Handle| origin.is_none_or(|o| o.distance(h.at) > GIZMO_CLEARANCE);
    let hovered = hover.filter(|&p| free && response.contains_pointer() && rect.contains(p)).and_then(|p| {
        all.iter()
            .filter(grabbable)
            .filter(|h| h.at.distance(p) <= KEY_RADIUS)
            .min_by(|a, b| a.at.distance(p).total_cmp(&b.at.distance(p)))
    });
    for h in &all {
        paint(&painter, h, ctx, hovered.is_some_and(|x| std::ptr::eq(x, h)));
    }
    let Some(h) = hovered else { return false };
    if pressed {
        let camera = &ctx.view.camera;
        let plane_normal = (camera.target - camera.eye()).normalize_or(Vec3::NEG_Z);
        if let Some(pressed_at) = hover.and_then(|p| projection.on_plane(p, h.world, plane_normal)) {
            *drag = Some(KeyDrag {
                id: h.id,
                time: h.time,
                value: h.value,
                world_to_value: h.world_to_value,
                plane_point: h.world,
                plane_normal,
                pressed_at,
                moved: false,
            });
        }
    }
    true
}

/// A key's handle: a ring (filled while hovered or dragged) with its frame number.
fn paint(painter: &egui::Painter, h: &Handle, ctx: &FrameCtx<'_>, active: bool) {
    if active {
        painter.circle_filled(h.at, KEY_RADIUS - 1.0, COLOUR.gamma_multiply(0.5));
    }
    painter.circle_stroke(h.at, KEY_RADIUS - 2.0, Stroke::new(if active { 2.0 } else { 1.2 }, COLOUR));
    let frame = (h.time * ctx.scene().fps).round();
    painter.text(
        h.at + egui::vec2(KEY_RADIUS, -KEY_RADIUS),
        Align2::LEFT_BOTTOM,
        format!("{frame}"),
        FontId::proportional(11.0),
        COLOUR,
    );
}
