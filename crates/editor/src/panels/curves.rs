//! The curve editor: the selected channels over time, sampled through the same code as the
//! viewport, so it updates live while a key or a T/C/B slider changes. Positions are drawn per
//! component; rotations as XYZ Euler angles in degrees, unwrapped along the curve; each curve
//! has its own colour, named in the legend. Keys are clicked, box-selected and dragged in time
//! (whole frames) and value, one undo step per drag; Delete, Ctrl+C and Ctrl+V work on them as
//! in the dope sheet. The view zooms (wheel; Ctrl+wheel: time only) and pans (Shift+wheel,
//! middle-drag) with rulers of frames and values; the frame ruler scrubs; *Fit* shows
//! everything, F over the curves frames the selected keys (Home stays the first frame).
//! A rotation channel with spin keys also gets its unwrapped turn (white): the twist about the
//! first spin's axis through spin segments ([`crate::twist::unwrapped_twist`], which counts
//! their turns with `Track::spin_degrees`), so a 720° segment climbs to 720 instead of
//! wrapping at ±180°. A channel with cycles (`before`/`after` other than Hold) is drawn over the
//! whole range, its repeats included; the stretches beyond its keys are shaded and named.

use egui::{Align2, Color32, FontId, Pos2, Sense, Shape, Stroke, Ui, Vec2};
use glam::Quat;

use crate::app::EditorApp;
use crate::channels::{self, ChannelId, ChannelValue};
use crate::eval::{euler_degrees, PoseOverrides};
use crate::session::KeyRef;
pub use crate::view::{CurveGesture, CurveView, CurveViewState};
use crate::widgets::publish_painted;
use egui::accesskit::Role;

/// The unwrapped turn of a rotation channel with spin keys (the fourth curve).
const TURN_COLOUR: Color32 = Color32::from_rgb(240, 240, 240);

/// The axis whose unwrapped turn the curve view draws for a rotation channel: the first spin
/// segment's (in its first key's frame); `None` without spin keys.
#[must_use]
pub fn turn_axis(app: &EditorApp, id: ChannelId) -> Option<(keyrig_core::Track<glam::Quat>, glam::DVec3)> {
    let Some(channels::ChannelRef::Rotation(a)) = channels::channel(app.doc.scene(), id) else { return None };
    if a.track.keys.iter().all(|k| k.spin.is_none()) {
        return None;
    }
    let track = keyrig_core::Track::new(&a.track).ok()?;
    let axis = (0..track.key_count()).find_map(|i| track.segment_spin(i))?.0;
    Some((track, axis))
}

/// One component over time: (frame, value) samples.
pub type Curve = Vec<(f64, f32)>;

/// The channels the curve view shows: those of the selected item and of the selected keys.
#[must_use]
pub fn shown_channels(app: &EditorApp) -> Vec<ChannelId> {
    let scene = app.doc.scene();
    let mut ids: Vec<ChannelId> = app.session.selection.channels(scene);
    for k in &app.session.selection.keys {
        if !ids.contains(&k.channel) {
            ids.push(k.channel);
        }
    }
    ids.retain(|&id| channels::key_count(scene, id) > 0);
    ids
}

/// Samples `id` over frames `[start, end]` at `samples` points as one or three curves of
/// numbers (components, or Euler degrees for rotations), and for a rotation with spin keys a
/// fourth: its unwrapped turn in degrees about the first spin's axis ([`turn_axis`]).
#[must_use]
pub fn sample_curves(
    app: &EditorApp,
    id: ChannelId,
    start: f64,
    end: f64,
    samples: usize,
) -> Vec<Vec<(f64, f32)>> {
    let scene = app.doc.scene();
    let fps = scene.fps.max(1e-9);
    let none = PoseOverrides::new();
    let tracks = app.evaluator();
    let n = samples.max(2);
    let mut curves: Vec<Curve> = Vec::new();
    for i in 0..n {
        let frame = start + (end - start) * i as f64 / (n - 1) as f64;
        let values = shown_components(app, tracks.value(id, frame / fps, &none));
        if curves.is_empty() {
            curves = vec![Vec::with_capacity(n); values.len()];
        }
        for (c, v) in values.into_iter().enumerate() {
            let v = if id.kind() == channels::ChannelKind::Rotation {
                // Unwrap Euler angles so a turn past ±180° stays continuous.
                match curves[c].last() {
                    Some(&(_, prev)) => prev + (v - prev + 180.0).rem_euclid(360.0) - 180.0,
                    None => v,
                }
            } else {
                v
            };
            curves[c].push((frame, v));
        }
    }
    let twist_only = app.view.curves.rotation_as_twist;
    if let Some((track, axis)) = turn_axis(app, id).filter(|_| !twist_only) {
        curves.push(
            (0..n)
                .map(|i| {
                    let frame = start + (end - start) * i as f64 / (n - 1) as f64;
                    (frame, crate::twist::unwrapped_twist(&track, axis, frame / fps) as f32)
                })
                .collect(),
        );
    }
    curves
}

/// The numbers the curve view draws for a value: a vector's components, a scalar, and a
/// rotation's XYZ Euler angles in degrees — or, with *Twist* chosen, its twist about the bone
/// axis (X) in degrees (wrapped here; the curves unwrap it along time).
fn shown_components(app: &EditorApp, value: Option<ChannelValue>) -> Vec<f32> {
    match value {
        Some(ChannelValue::Vec3(v)) => v.to_array().to_vec(),
        Some(ChannelValue::Rotation(q)) if app.view.curves.rotation_as_twist => {
            vec![crate::twist::twist_degrees(q.as_dquat(), crate::twist::BONE_AXIS.as_dvec3()) as f32]
        }
        Some(ChannelValue::Rotation(q)) => euler_degrees(q).to_array().to_vec(),
        Some(ChannelValue::Scalar(s)) => vec![s],
        None => Vec::new(),
    }
}

/// Width of the value ruler and height of the frame ruler, points.
const VALUE_RULER: f32 = 44.0;
const FRAME_RULER: f32 = 16.0;
/// How close (points) the pointer must be to a key to take it.
const PICK_RADIUS: f32 = 6.0;

/// One colour per shown curve (channel and component), distinct for up to twelve curves.
const PALETTE: [Color32; 12] = [
    Color32::from_rgb(235, 85, 85),
    Color32::from_rgb(95, 205, 95),
    Color32::from_rgb(95, 145, 245),
    Color32::from_rgb(240, 200, 80),
    Color32::from_rgb(215, 110, 230),
    Color32::from_rgb(80, 210, 215),
    Color32::from_rgb(245, 150, 70),
    Color32::from_rgb(160, 230, 120),
    Color32::from_rgb(150, 150, 255),
    Color32::from_rgb(255, 140, 180),
    Color32::from_rgb(190, 170, 120),
    Color32::from_rgb(130, 200, 170),
];

/// The colour of component `c` of the `n`-th shown channel: a channel's X, Y, Z take three
/// neighbouring colours, so two channels never share one (up to four channels).
fn curve_colour(n: usize, c: usize, components: usize) -> Color32 {
    if components == 4 && c == 3 {
        return TURN_COLOUR;
    }
    PALETTE[(n * 3 + c) % PALETTE.len()]
}

/// "X", "Y", "Z" for a vector or Euler angle component, "turn" for the unwrapped twist.
fn component_name(id: ChannelId, c: usize) -> &'static str {
    match (id.kind(), c) {
        (channels::ChannelKind::Scalar, _) => "",
        (_, 0) => "X",
        (_, 1) => "Y",
        (_, 2) => "Z",
        _ => "turn",
    }
}

/// Screen mapping of the plot: frames across, values up.
#[derive(Clone, Copy, Debug)]
struct Plot {
    rect: egui::Rect,
    view: CurveView,
}

impl Plot {
    fn pos(&self, frame: f64, value: f32) -> Pos2 {
        let v = self.view;
        Pos2::new(
            self.rect.left() + ((frame - v.start) / (v.end - v.start).max(1e-9)) as f32 * self.rect.width(),
            self.rect.bottom() - (value - v.low) / (v.high - v.low).max(1e-9) * self.rect.height(),
        )
    }

    fn frame(&self, x: f32) -> f64 {
        let v = self.view;
        v.start + f64::from((x - self.rect.left()) / self.rect.width().max(1.0)) * (v.end - v.start)
    }

    fn frames_per_point(&self) -> f64 {
        (self.view.end - self.view.start) / f64::from(self.rect.width().max(1.0))
    }

    fn values_per_point(&self) -> f32 {
        (self.view.high - self.view.low) / self.rect.height().max(1.0)
    }
}

/// A key on one component's curve.
#[derive(Clone, Copy, Debug, PartialEq)]
struct KeyPoint {
    key: KeyRef,
    component: usize,
    pos: Pos2,
}

/// A Bézier-style handle of a selected Hermite key: a third of the way to the neighbouring key
/// in time, along the key's tangent (value per second) of `component`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Handle {
    key: KeyRef,
    component: usize,
    /// The out-tangent (towards the next key), or the in-tangent (towards the previous one).
    outgoing: bool,
    pos: Pos2,
    /// The key's own point, and the seconds the handle spans (a third of the segment).
    key_pos: Pos2,
    seconds: f64,
}

/// The handles of the selected Hermite keys of position and scalar channels.
fn handles(app: &EditorApp, plot: &Plot) -> Vec<Handle> {
    let scene = app.doc.scene();
    let fps = scene.fps.max(1e-9);
    let mut out = Vec::new();
    for &key in &app.session.selection.keys {
        if key.channel.kind() == channels::ChannelKind::Rotation {
            continue;
        }
        // Per key, not the whole track's times: A can select every key of a long track.
        let time_of = |i: usize| channels::key_params(scene, key.channel, i).map(|p| p.0);
        let (Some(t), Some(value)) = (time_of(key.index), channels::key_value(scene, key.channel, key.index))
        else {
            continue;
        };
        let values: Vec<f32> = match value {
            ChannelValue::Vec3(v) => v.to_array().to_vec(),
            ChannelValue::Scalar(s) => vec![s],
            ChannelValue::Rotation(_) => continue,
        };
        let (inn, outt) = channels::key_tangents(scene, key.channel, key.index);
        let hermite = |i: usize| {
            channels::key_params(scene, key.channel, i)
                .is_some_and(|p| p.1 == keyrig_core::Interpolation::Hermite)
        };
        let mut add = |tangent: Option<Vec<f32>>, neighbour: Option<f64>, outgoing: bool| {
            let (Some(tangent), Some(n)) = (tangent, neighbour) else { return };
            let seconds = (n - t).abs() / 3.0;
            let sign = if outgoing { 1.0 } else { -1.0 };
            for (c, (&v, &m)) in values.iter().zip(&tangent).enumerate() {
                out.push(Handle {
                    key,
                    component: c,
                    outgoing,
                    pos: plot.pos((t + sign * seconds) * fps, v + sign as f32 * m * seconds as f32),
                    key_pos: plot.pos(t * fps, v),
                    seconds,
                });
            }
        };
        if hermite(key.index) {
            add(outt, time_of(key.index + 1), true);
        }
        if key.index > 0 && hermite(key.index - 1) {
            add(inn, time_of(key.index - 1), false);
        }
    }
    out
}

/// The curves of the shown channels over `[start, end]`, and the range of their values.
fn curves_over(
    app: &EditorApp,
    ids: &[ChannelId],
    start: f64,
    end: f64,
    samples: usize,
) -> Vec<(ChannelId, Vec<Curve>)> {
    ids.iter().map(|&id| (id, sample_curves(app, id, start, end, samples))).collect()
}

fn value_extent(all: &[(ChannelId, Vec<Curve>)]) -> Option<(f32, f32)> {
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for (_, curves) in all {
        for &(_, v) in curves.iter().flatten() {
            if v.is_finite() {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

/// The view that shows the frame range and every value of `ids` (with a margin).
fn fit_view(app: &EditorApp, ids: &[ChannelId]) -> CurveView {
    let range = app.doc.scene().frame_range;
    let (start, end) = (f64::from(range.start), f64::from(range.end.max(range.start + 1)));
    let all = curves_over(app, ids, start, end, 200);
    let (mut lo, mut hi) = value_extent(&all).unwrap_or((-1.0, 1.0));
    if hi - lo < 1e-3 {
        lo -= 0.5;
        hi += 0.5;
    }
    let pad = (hi - lo) * 0.08;
    CurveView { start, end, low: lo - pad, high: hi + pad }
}

/// The key points of the shown curves in view: each key of each channel on each of its
/// components, at the curve's (unwrapped) value.
fn key_points(app: &EditorApp, plot: &Plot, all: &[(ChannelId, Vec<Curve>)]) -> Vec<KeyPoint> {
    let scene = app.doc.scene();
    let fps = scene.fps.max(1e-9);
    let eval = app.evaluator();
    let none = PoseOverrides::new();
    let mut out = Vec::new();
    let mut last_column = std::collections::HashMap::new();
    for (id, curves) in all {
        let window =
            channels::keys_between(scene, *id, plot.view.start / fps - 1e-9, plot.view.end / fps + 1e-9);
        for (i, time) in window.times.iter().enumerate() {
            let frame = time * fps;
            let raw = shown_components(app, eval.value(*id, *time, &none));
            if raw.is_empty() {
                continue;
            }
            for (c, raw) in raw.into_iter().enumerate() {
                let Some(curve) = curves.get(c) else { continue };
                // The sample nearest the key, to unwrap an Euler angle onto the curve.
                let near = curve
                    .iter()
                    .min_by(|a, b| (a.0 - frame).abs().total_cmp(&(b.0 - frame).abs()))
                    .map_or(raw, |&(_, v)| v);
                let value = if id.kind() == channels::ChannelKind::Rotation {
                    raw + 360.0 * ((near - raw) / 360.0).round()
                } else {
                    raw
                };
                let pos = plot.pos(frame, value);
                // One point per pixel column and component (motion-capture density).
                let column = (pos.x.round() as i32, *id, c);
                if last_column.insert(column, ()).is_some() {
                    continue;
                }
                out.push(KeyPoint {
                    key: KeyRef { channel: *id, index: window.first + i },
                    component: c,
                    pos,
                });
            }
        }
    }
    out
}

/// Lays out the curve view: its header (title, legend, Fit), the plot and its rulers, and
/// handles the pointer: click or box-select keys, drag them in time (whole frames) and value,
/// scrub on the frame ruler, wheel to zoom (Ctrl: time only; Shift: pan), middle-drag to pan.
/// Painting happens at the end of the frame ([`paint_pending`]).
pub fn ui(ui: &mut Ui, app: &mut EditorApp) {
    let ids = shown_channels(app);
    let scene = app.doc.scene();
    ui.horizontal(|ui| {
        let title = match ids.as_slice() {
            [] => "Curves: select an animated object, joint or light".to_owned(),
            [one] => format!("Curves: {}", one.label(scene)),
            many => format!("Curves: {} channels", many.len()),
        };
        ui.label(title);
        let fit = "Show the frame range and every value (F over the curves frames the selected keys)";
        if !ids.is_empty() && ui.small_button("Fit").on_hover_text(fit).clicked() {
            app.view.curves.view = None;
        }
    });
    if !ids.is_empty() {
        legend_ui(ui, app, &ids);
    }
    let size = ui.available_size().max(Vec2::new(100.0, 60.0));
    let (rect, response) = ui.allocate_exact_size(size, Sense::click_and_drag());
    app.view.pending_curves = Some((ui.layer_id(), rect.intersect(ui.clip_rect())));
    app.view.curves_rect = Some(rect);
    if ids.is_empty() {
        return;
    }
    if std::mem::take(&mut app.view.curves.frame_keys) {
        frame_selected_keys(app);
    }
    let view = app.view.curves.view.unwrap_or_else(|| fit_view(app, &ids));
    let plot = Plot { rect: plot_rect(rect), view };
    let samples = (plot.rect.width() / 2.0).clamp(16.0, 800.0) as usize;
    let all = curves_over(app, &ids, view.start, view.end, samples);
    let points = key_points(app, &plot, &all);
    let pick = |pos: Pos2| {
        points
            .iter()
            .map(|p| (p, p.pos.distance(pos)))
            .filter(|(_, d)| *d <= PICK_RADIUS)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(p, _)| *p)
    };
    let additive = ui.input(|i| i.modifiers.shift || i.modifiers.command);
    let on_ruler = |pos: Pos2| pos.y > plot.rect.bottom();
    // Blender's graph editor: A selects every key shown, Alt+A none (over the curves, and not
    // while a text field has the keyboard).
    if response.hovered() && !ui.ctx().text_edit_focused() {
        let (all, none) = ui.input(|i| {
            (
                i.key_pressed(egui::Key::A) && i.modifiers.is_none(),
                i.key_pressed(egui::Key::A) && i.modifiers.alt,
            )
        });
        if all {
            for &id in &ids {
                let count = channels::key_count(app.doc.scene(), id);
                app.session.selection.keys.extend((0..count).map(|index| KeyRef { channel: id, index }));
            }
        } else if none {
            app.session.selection.keys.clear();
        }
    }

    if let Some(pos) = response.interact_pointer_pos().filter(|_| response.clicked()) {
        if on_ruler(pos) {
            app.set_frame(plot.frame(pos.x).round() as i32);
        } else if let Some(point) = pick(pos) {
            select_key(app, point.key, additive);
        } else if !additive {
            app.session.selection.keys.clear();
        }
    }
    let press = ui.input(|i| i.pointer.press_origin());
    let grips = handles(app, &plot);
    let grip_at = |pos: Pos2| {
        grips
            .iter()
            .map(|h| (h, h.pos.distance(pos)))
            .filter(|(_, d)| *d <= PICK_RADIUS)
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(h, _)| *h)
    };
    if let Some(origin) = press.filter(|_| response.drag_started_by(egui::PointerButton::Primary)) {
        app.view.curves.gesture = if on_ruler(origin) {
            Some(CurveGesture::Scrub)
        } else if let Some(grip) = grip_at(origin) {
            Some(CurveGesture::Handle { key: grip.key, component: grip.component, outgoing: grip.outgoing })
        } else if let Some(point) = pick(origin) {
            if !app.session.selection.keys.contains(&point.key) {
                select_key(app, point.key, additive);
            }
            Some(CurveGesture::MoveKeys { frames: 0, value: 0.0, component: point.component })
        } else {
            Some(CurveGesture::Box { start: origin })
        };
    }
    if response.drag_started_by(egui::PointerButton::Middle) {
        app.view.curves.gesture = Some(CurveGesture::Pan { from: view });
    }
    // Only while the pointer drags: the frame of the release reports no movement.
    let delta = response.total_drag_delta().filter(|_| response.dragged());
    match app.view.curves.gesture {
        Some(CurveGesture::Scrub) => {
            if let Some(pos) = response.interact_pointer_pos() {
                app.set_frame(plot.frame(pos.x).round() as i32);
            }
        }
        Some(CurveGesture::MoveKeys { frames, value, component }) if delta.is_some() => {
            let delta = delta.unwrap_or_default();
            // The keys keep the view they were grabbed in, so a drag moves them by what the
            // pointer moved.
            app.view.curves.view.get_or_insert(view);
            let wanted_frames = (f64::from(delta.x) * plot.frames_per_point()).round() as i32;
            let wanted_value = -delta.y * plot.values_per_point();
            let mut applied = (frames, value);
            if wanted_frames != frames
                && crate::panels::dope_sheet::move_selected_keys(
                    app,
                    f64::from(wanted_frames - frames) / scene_fps(app),
                )
            {
                applied.0 = wanted_frames;
            }
            if (wanted_value - value).abs() > f32::EPSILON {
                shift_selected_values(app, component, wanted_value - value);
                applied.1 = wanted_value;
            }
            app.view.curves.gesture =
                Some(CurveGesture::MoveKeys { frames: applied.0, value: applied.1, component });
        }
        Some(CurveGesture::Box { start }) => {
            if response.drag_stopped() {
                if let Some(end) = response.interact_pointer_pos().or(ui.input(|i| i.pointer.latest_pos())) {
                    let area = egui::Rect::from_two_pos(start, end);
                    if !additive {
                        app.session.selection.keys.clear();
                    }
                    for p in points.iter().filter(|p| area.contains(p.pos)) {
                        app.session.selection.keys.insert(p.key);
                    }
                }
            }
        }
        Some(CurveGesture::Pan { from }) if delta.is_some() => {
            let delta = delta.unwrap_or_default();
            let frames = -f64::from(delta.x) * plot.frames_per_point();
            let values = delta.y * plot.values_per_point();
            app.view.curves.view = Some(CurveView {
                start: from.start + frames,
                end: from.end + frames,
                low: from.low + values,
                high: from.high + values,
            });
        }
        Some(CurveGesture::Handle { key, component, outgoing }) if delta.is_some() => {
            // The handle follows the pointer's value; its time stays a third of the segment.
            let grip =
                grips.iter().find(|h| h.key == key && h.component == component && h.outgoing == outgoing);
            if let (Some(grip), Some(pointer)) = (grip, response.interact_pointer_pos()) {
                let value_at = |y: f32| {
                    view.low + (plot.rect.bottom() - y) / plot.rect.height().max(1.0) * (view.high - view.low)
                };
                let rise = value_at(pointer.y) - value_at(grip.key_pos.y);
                let tangent = rise / grip.seconds.max(1e-9) as f32 * if outgoing { 1.0 } else { -1.0 };
                app.doc.edit_continuous("curve handle", "drag tangent handle", |scene| {
                    channels::set_tangent_component(
                        scene,
                        key.channel,
                        key.index,
                        outgoing,
                        component,
                        tangent,
                    );
                });
            }
        }
        Some(CurveGesture::MoveKeys { .. } | CurveGesture::Pan { .. } | CurveGesture::Handle { .. })
        | None => {}
    }
    if response.drag_stopped() {
        if matches!(
            app.view.curves.gesture,
            Some(CurveGesture::MoveKeys { .. } | CurveGesture::Handle { .. })
        ) {
            app.doc.close_group();
        }
        app.view.curves.gesture = None;
    }
    if !ui.input(|i| i.pointer.any_down()) && !response.drag_stopped() {
        app.view.curves.gesture = None;
    }
    if let Some(pointer) = response.hover_pos() {
        zoom_and_pan(ui, app, &plot, pointer);
    }
    response.context_menu(|ui| key_menu_ui(ui, app));
}

/// The curve view's context menu: the interpolation of the selected keys (one undo step), and
/// deleting them.
fn key_menu_ui(ui: &mut Ui, app: &mut EditorApp) {
    use keyrig_core::Interpolation;
    let keys: Vec<KeyRef> = app.session.selection.keys.iter().copied().collect();
    if keys.is_empty() {
        ui.label("Select keys first (click, or drag a box)");
        return;
    }
    ui.label(format!("{} selected key(s)", keys.len()));
    let choices = [
        ("Step", Interpolation::Step, false),
        ("Linear", Interpolation::Linear, false),
        ("TCB spline", Interpolation::Tcb, false),
        ("TCB spline, clamped", Interpolation::Tcb, true),
    ];
    for (label, mode, clamped) in choices {
        if ui.button(label).clicked() {
            app.doc.close_group();
            app.doc.edit(&format!("interpolation {label}"), |scene| {
                for k in &keys {
                    if let Some((_, _, tcb)) = channels::key_params(scene, k.channel, k.index) {
                        channels::set_key_params(scene, k.channel, k.index, mode, tcb.with_clamped(clamped));
                    }
                }
            });
            ui.close();
        }
    }
    let shapeable = keys.iter().any(|k| k.channel.kind() != channels::ChannelKind::Rotation);
    if ui
        .add_enabled(shapeable, egui::Button::new("Hermite handles (keeps the shape)"))
        .on_hover_text("Explicit tangents to drag, equal to the curve's now (positions and scalars)")
        .clicked()
    {
        app.doc.close_group();
        app.doc.edit("interpolation Hermite handles", |scene| {
            let mut by_channel: std::collections::BTreeMap<ChannelId, Vec<usize>> = Default::default();
            for k in &keys {
                by_channel.entry(k.channel).or_default().push(k.index);
            }
            for (id, indices) in by_channel {
                channels::convert_to_hermite(scene, id, &indices);
            }
        });
        ui.close();
    }
    ui.separator();
    if ui.button("Delete keys").clicked() {
        app.delete_selected_keys();
        ui.close();
    }
}

fn scene_fps(app: &EditorApp) -> f64 {
    app.doc.scene().fps.max(1e-9)
}

/// The plot inside the curve view's rect, beside the value ruler and above the frame ruler.
fn plot_rect(rect: egui::Rect) -> egui::Rect {
    egui::Rect::from_min_max(
        Pos2::new(rect.left() + VALUE_RULER, rect.top() + 6.0),
        Pos2::new(rect.right() - 6.0, rect.bottom() - FRAME_RULER),
    )
}

/// A click on a key: selects it alone with its owner, or with Shift/Ctrl adds or removes it.
fn select_key(app: &mut EditorApp, key: KeyRef, additive: bool) {
    let selection = &mut app.session.selection;
    if additive {
        if !selection.keys.remove(&key) {
            selection.keys.insert(key);
        }
    } else {
        selection.keys = std::collections::BTreeSet::from([key]);
    }
}

/// Adds `delta` to component `component` of every selected key (an Euler angle for
/// rotations, degrees) as one continuous edit.
fn shift_selected_values(app: &mut EditorApp, component: usize, delta: f32) {
    let keys: Vec<KeyRef> = app.session.selection.keys.iter().copied().collect();
    let twist = app.view.curves.rotation_as_twist;
    let label =
        if keys.len() == 1 { "move key value".to_owned() } else { format!("move {} key values", keys.len()) };
    app.doc.edit_continuous("curve value", &label, |scene| {
        for k in &keys {
            let Some((time, _, _)) = channels::key_params(scene, k.channel, k.index) else { continue };
            let Some(value) = channels::key_value(scene, k.channel, k.index) else { continue };
            let moved = match value {
                ChannelValue::Vec3(mut v) if component < 3 => {
                    v[component] += delta;
                    ChannelValue::Vec3(v)
                }
                ChannelValue::Scalar(s) if component == 0 => ChannelValue::Scalar(s + delta),
                ChannelValue::Rotation(q) if twist && component == 0 => {
                    // A twist about the bone axis, in the key's own frame.
                    let turn = Quat::from_axis_angle(crate::twist::BONE_AXIS, delta.to_radians());
                    ChannelValue::Rotation((q * turn).normalize())
                }
                ChannelValue::Rotation(q) if component < 3 && !twist => {
                    let mut e = euler_degrees(q);
                    e[component] += delta;
                    ChannelValue::Rotation(crate::eval::quat_from_euler_degrees(e))
                }
                _ => continue,
            };
            channels::set_key(scene, k.channel, time, moved);
        }
    });
}

/// Wheel over the curves zooms both axes about the pointer, Ctrl+wheel the time axis only,
/// Shift+wheel (or a horizontal wheel) pans in time.
fn zoom_and_pan(ui: &Ui, app: &mut EditorApp, plot: &Plot, pointer: Pos2) {
    let (zoom, scroll) = ui.input(|i| (i.zoom_delta(), i.smooth_scroll_delta));
    let mut view = plot.view;
    let anchor_frame = plot.frame(pointer.x);
    let anchor_value =
        view.low + (plot.rect.bottom() - pointer.y) / plot.rect.height().max(1.0) * (view.high - view.low);
    let zoom_time = |view: &mut CurveView, factor: f64| {
        let span = ((view.end - view.start) / factor).max(2.0);
        let t = (anchor_frame - view.start) / (view.end - view.start).max(1e-9);
        view.start = anchor_frame - t * span;
        view.end = view.start + span;
    };
    if (zoom - 1.0).abs() > 1e-4 {
        zoom_time(&mut view, f64::from(zoom));
    }
    if scroll.y.abs() > 0.0 {
        let factor = (scroll.y * 0.004).exp();
        zoom_time(&mut view, f64::from(factor));
        let span = ((view.high - view.low) / factor).max(1e-3);
        let t = (anchor_value - view.low) / (view.high - view.low).max(1e-9);
        view.low = anchor_value - t * span;
        view.high = view.low + span;
    }
    if scroll.x.abs() > 0.0 {
        let shift = -f64::from(scroll.x) * plot.frames_per_point();
        view.start += shift;
        view.end += shift;
    }
    if view != plot.view {
        app.view.curves.view = Some(view);
    }
}

/// The legend: a swatch and name per shown curve.
fn legend_ui(ui: &mut Ui, app: &mut EditorApp, ids: &[ChannelId]) {
    let entries: Vec<(ChannelId, String, usize)> = ids
        .iter()
        .map(|&id| {
            let components = match id.kind() {
                channels::ChannelKind::Scalar => 1,
                channels::ChannelKind::Rotation if app.view.curves.rotation_as_twist => 1,
                _ if turn_axis(app, id).is_some() => 4,
                _ => 3,
            };
            (id, id.label(app.doc.scene()), components)
        })
        .collect();
    ui.horizontal_wrapped(|ui| {
        for (n, (id, label, components)) in entries.iter().enumerate() {
            let (id, components) = (*id, *components);
            for c in 0..components {
                let colour = curve_colour(n, c, components);
                let (swatch, _) = ui.allocate_exact_size(Vec2::new(10.0, 10.0), Sense::hover());
                ui.painter().rect_filled(swatch, 2.0, colour);
                let name = if components == 1 && id.kind() == channels::ChannelKind::Rotation {
                    format!("{label} twist")
                } else {
                    format!("{label} {}", component_name(id, c)).trim_end().to_owned()
                };
                ui.label(egui::RichText::new(name).small());
            }
        }
        if ids.iter().any(|id| id.kind() == channels::ChannelKind::Rotation) {
            let twist = &mut app.view.curves.rotation_as_twist;
            let euler = format!("Euler angles ({})", crate::panels::inspector::EULER_ORDER);
            ui.label(egui::RichText::new("rotations:").small().weak());
            ui.selectable_value(twist, false, egui::RichText::new(euler).small())
                .on_hover_text("Rotations as Euler angles in this order, degrees, unwrapped along the curve");
            ui.selectable_value(twist, true, egui::RichText::new("Twist about X").small()).on_hover_text(
                "Rotations as their twist about the bone axis (X), degrees, unwrapped: a 720° twist climbs to 720",
            );
        }
    });
}

/// Frames the selected keys (all shown keys when none is selected): F over the curve view.
pub fn frame_selected_keys(app: &mut EditorApp) {
    let ids = shown_channels(app);
    if ids.is_empty() {
        return;
    }
    let fit = fit_view(app, &ids);
    let scene = app.doc.scene();
    let fps = scene.fps.max(1e-9);
    let eval = app.evaluator();
    let none = PoseOverrides::new();
    let (mut f0, mut f1, mut v0, mut v1) =
        (f64::INFINITY, f64::NEG_INFINITY, f32::INFINITY, f32::NEG_INFINITY);
    for k in &app.session.selection.keys {
        let Some((time, _, _)) = channels::key_params(scene, k.channel, k.index) else { continue };
        f0 = f0.min(time * fps);
        f1 = f1.max(time * fps);
        for v in shown_components(app, eval.value(k.channel, time, &none)) {
            v0 = v0.min(v);
            v1 = v1.max(v);
        }
    }
    if !f0.is_finite() {
        app.view.curves.view = Some(fit);
        return;
    }
    let (df, dv) = ((f1 - f0).max(4.0) * 0.1, (v1 - v0).max(1e-2) * 0.1);
    app.view.curves.view = Some(CurveView { start: f0 - df, end: f1 + df, low: v0 - dv, high: v1 + dv });
}

/// Labelled ticks about `min_points` apart along a span: the step (1, 2 or 5 × 10ⁿ).
fn nice_step(span: f64, length: f32, min_points: f32) -> f64 {
    let raw = span.abs().max(1e-9) * f64::from(min_points) / f64::from(length.max(1.0));
    let base = 10f64.powf(raw.log10().floor());
    for m in [1.0, 2.0, 5.0, 10.0] {
        if base * m >= raw {
            return base * m;
        }
    }
    base * 10.0
}

/// Paints the curve view laid out by [`ui`] this frame, with the document as the rest of the
/// frame left it (a value dragged in the inspector or the viewport shows at once).
pub fn paint_pending(ctx: &egui::Context, app: &mut EditorApp) {
    let Some((layer, clip)) = app.view.pending_curves.take() else { return };
    // Laid out at `rect` (the plot's geometry, as the pointer saw it), shown within `clip`.
    let rect = app.view.curves_rect.unwrap_or(clip);
    let painter = egui::Painter::new(ctx.clone(), layer, clip);
    let visuals = ctx.global_style().visuals.clone();
    painter.rect_filled(clip, 2.0, visuals.extreme_bg_color);
    let ids = shown_channels(app);
    if ids.is_empty() {
        return;
    }
    let view = app.view.curves.view.unwrap_or_else(|| fit_view(app, &ids));
    let plot = Plot { rect: plot_rect(rect), view };
    let scene = app.doc.scene();
    let fps = scene.fps.max(1e-9);
    let samples = (plot.rect.width() / 2.0).clamp(16.0, 800.0) as usize;
    let all = curves_over(app, &ids, view.start, view.end, samples);
    let weak = visuals.weak_text_color();
    let grid = Stroke::new(1.0, visuals.faint_bg_color);
    let plot_painter = painter.with_clip_rect(plot.rect.intersect(clip));

    // Frames outside the scene's range, shaded.
    let range = scene.frame_range;
    let (a, b) = (plot.pos(f64::from(range.start), 0.0).x, plot.pos(f64::from(range.end), 0.0).x);
    let shade = visuals.faint_bg_color.gamma_multiply(0.7);
    if a > plot.rect.left() {
        plot_painter.rect_filled(
            egui::Rect::from_min_max(plot.rect.min, Pos2::new(a, plot.rect.bottom())),
            0.0,
            shade,
        );
    }
    if b < plot.rect.right() {
        plot_painter.rect_filled(
            egui::Rect::from_min_max(Pos2::new(b, plot.rect.top()), plot.rect.max),
            0.0,
            shade,
        );
    }

    // Rulers: frames under the plot, values beside it, with grid lines.
    let step = nice_step(view.end - view.start, plot.rect.width(), 45.0).max(1.0);
    let mut f = (view.start / step).ceil() * step;
    while f <= view.end {
        let x = plot.pos(f, 0.0).x;
        plot_painter.line_segment([Pos2::new(x, plot.rect.top()), Pos2::new(x, plot.rect.bottom())], grid);
        painter.text(
            Pos2::new(x, plot.rect.bottom() + 2.0),
            Align2::CENTER_TOP,
            format!("{f:.0}"),
            FontId::proportional(9.5),
            weak,
        );
        f += step;
    }
    let vstep = nice_step(f64::from(view.high - view.low), plot.rect.height(), 28.0);
    let mut v = (f64::from(view.low) / vstep).ceil() * vstep;
    while v <= f64::from(view.high) {
        // A tick at zero reads 0, not "-0" (the running sum lands a rounding error below it).
        let tick = if v.abs() < vstep * 1e-6 { 0.0 } else { v };
        let y = plot.pos(view.start, tick as f32).y;
        plot_painter.line_segment([Pos2::new(plot.rect.left(), y), Pos2::new(plot.rect.right(), y)], grid);
        let text = if vstep >= 1.0 {
            format!("{tick:.0}")
        } else {
            format!("{tick:.*}", (-vstep.log10()).ceil() as usize)
        };
        painter.text(
            Pos2::new(plot.rect.left() - 4.0, y),
            Align2::RIGHT_CENTER,
            text,
            FontId::proportional(9.5),
            weak,
        );
        v += vstep;
    }

    // Cycles: the curves go on beyond the keys (sampled like everything else); the stretches
    // outside the keys are shaded and named ("after: Repeat") so the repeats read as repeats.
    for id in &ids {
        let Some(cycles) = channels::cycles(scene, *id).filter(|c| !c.is_hold()) else { continue };
        let window = channels::keys_between(scene, *id, f64::NEG_INFINITY, f64::INFINITY);
        let (Some(&first), Some(&last)) = (window.times.first(), window.times.last()) else { continue };
        let (first, last) =
            ((first * fps).clamp(view.start, view.end), (last * fps).clamp(view.start, view.end));
        for (from, to, cycle, text_at, align) in [
            (view.start, first, cycles.before, first, Align2::RIGHT_TOP),
            (last, view.end, cycles.after, last, Align2::LEFT_TOP),
        ] {
            if cycle.is_hold() || to <= from {
                continue;
            }
            let (x0, x1) = (plot.pos(from, 0.0).x, plot.pos(to, 0.0).x);
            plot_painter.rect_filled(
                egui::Rect::from_min_max(Pos2::new(x0, plot.rect.top()), Pos2::new(x1, plot.rect.bottom())),
                0.0,
                visuals.faint_bg_color.gamma_multiply(0.6),
            );
            let end_name = if align == Align2::LEFT_TOP { "after" } else { "before" };
            plot_painter.text(
                Pos2::new(plot.pos(text_at, 0.0).x, plot.rect.top()),
                align,
                format!("{end_name}: {}", cycle.label()),
                FontId::proportional(10.0),
                weak,
            );
        }
    }

    // Curves and their keys.
    for (n, (_, curves)) in all.iter().enumerate() {
        for (c, curve) in curves.iter().enumerate() {
            let colour = curve_colour(n, c, curves.len());
            let points: Vec<Pos2> = curve.iter().map(|&(f, v)| plot.pos(f, v)).collect();
            plot_painter.add(Shape::line(points, Stroke::new(1.5, colour)));
        }
    }
    let points = key_points(app, &plot, &all);
    for p in &points {
        let n = ids.iter().position(|&id| id == p.key.channel).unwrap_or(0);
        let components = all.get(n).map_or(3, |(_, c)| c.len());
        let colour = curve_colour(n, p.component, components);
        if app.session.selection.keys.contains(&p.key) {
            plot_painter.circle(
                p.pos,
                4.0,
                Color32::from_rgb(255, 200, 60),
                Stroke::new(1.0, Color32::WHITE),
            );
        } else {
            plot_painter.circle_filled(p.pos, 3.0, colour);
        }
    }
    for grip in handles(app, &plot) {
        plot_painter.line_segment([grip.key_pos, grip.pos], Stroke::new(1.0, Color32::from_gray(200)));
        plot_painter.circle(
            grip.pos,
            3.5,
            Color32::from_gray(40),
            Stroke::new(1.5, Color32::from_rgb(255, 200, 60)),
        );
        let side = if grip.outgoing { "out" } else { "in" };
        let r = egui::Rect::from_center_size(grip.pos, Vec2::splat(2.0 * PICK_RADIUS));
        let id =
            egui::Id::new(("curve handle", grip.key.channel, grip.key.index, grip.component, grip.outgoing));
        let label = || {
            let (channel, component) = (grip.key.channel, grip.component);
            format!(
                "{side} handle {} {} key {}",
                channel.label(scene),
                component_name(channel, component),
                grip.key.index
            )
        };
        publish_painted(ctx, id, Role::Button, r, label, None);
    }
    if let Some((_, axis)) = ids.iter().find_map(|&id| turn_axis(app, id)) {
        plot_painter.text(
            Pos2::new(plot.rect.right(), plot.rect.top()),
            Align2::RIGHT_TOP,
            format!(
                "white: turn about ({:.2}, {:.2}, {:.2}) through spin keys, unwrapped",
                axis.x, axis.y, axis.z
            ),
            FontId::proportional(10.0),
            weak,
        );
    }
    // The current frame, and a box selection in progress.
    let x = plot.pos(app.session.playback.frame, 0.0).x;
    if x >= plot.rect.left() && x <= plot.rect.right() {
        painter.line_segment(
            [Pos2::new(x, plot.rect.top()), Pos2::new(x, rect.bottom())],
            Stroke::new(1.5, Color32::from_rgb(90, 170, 255)),
        );
    }
    if let (Some(CurveGesture::Box { start }), Some(now)) =
        (app.view.curves.gesture, ctx.input(|i| i.pointer.latest_pos()))
    {
        plot_painter.rect_stroke(
            egui::Rect::from_two_pos(start, now),
            0.0,
            Stroke::new(1.0, visuals.selection.stroke.color),
            egui::StrokeKind::Inside,
        );
    }
    // Accessibility tools (and UI tests) see each drawn key: "curve key elbow rotation X frame 30".
    for p in &points {
        let r = egui::Rect::from_center_size(p.pos, Vec2::splat(2.0 * PICK_RADIUS));
        let id = egui::Id::new(("curve key", p.key.channel, p.key.index, p.component));
        let label = || {
            let frame = channels::key_params(scene, p.key.channel, p.key.index)
                .map_or(0, |k| (k.0 * fps).round() as i64);
            let (channel, component) = (p.key.channel, p.component);
            format!("curve key {} {} frame {frame}", channel.label(scene), component_name(channel, component))
                .replace("  ", " ")
        };
        publish_painted(ctx, id, Role::Button, r, label, None);
    }
}
