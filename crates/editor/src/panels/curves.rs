//! The curve view: the selected channels over the frame range, sampled through the same code
//! as the viewport, so it updates live while a key or a T/C/B slider changes. Positions are
//! drawn per component; rotations as XYZ Euler angles in degrees, unwrapped along the curve.
//! A rotation channel with spin keys also gets its unwrapped turn (white): the twist about the
//! first spin's axis through spin segments ([`crate::twist::unwrapped_twist`], which counts
//! their turns with `Track::spin_degrees`), so a 720° segment climbs to 720 instead of
//! wrapping at ±180°. A channel with cycles (`before`/`after` other than Hold) is drawn over the
//! whole range, its repeats included; the stretches beyond its keys are shaded and named.

use egui::{Align2, Color32, FontId, Pos2, Sense, Shape, Stroke, Ui, Vec2};

use crate::app::EditorApp;
use crate::channels::{self, ChannelId, ChannelValue};
use crate::eval::{euler_degrees, PoseOverrides};

const COMPONENT_COLOURS: [Color32; 3] =
    [Color32::from_rgb(230, 80, 80), Color32::from_rgb(90, 200, 90), Color32::from_rgb(90, 140, 240)];

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
        let values: Vec<f32> = match tracks.value(id, frame / fps, &none) {
            Some(ChannelValue::Vec3(v)) => v.to_array().to_vec(),
            Some(ChannelValue::Rotation(q)) => euler_degrees(q).to_array().to_vec(),
            Some(ChannelValue::Scalar(s)) => vec![s],
            None => Vec::new(),
        };
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
    if let Some((track, axis)) = turn_axis(app, id) {
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

pub fn ui(ui: &mut Ui, app: &mut EditorApp) {
    let ids = shown_channels(app);
    let title = match ids.as_slice() {
        [] => "Curves: select an animated object, joint or light".to_owned(),
        [one] => format!("Curves: {}", one.label(app.doc.scene())),
        many => format!("Curves: {} channels", many.len()),
    };
    ui.label(title);
    let size = ui.available_size().max(Vec2::new(100.0, 60.0));
    let (rect, _response) = ui.allocate_exact_size(size, Sense::hover());
    // Painted at the end of the frame, after the inspector and the viewport had their say.
    app.view.pending_curves = Some((ui.layer_id(), rect.intersect(ui.clip_rect())));
}

/// Paints the curve view laid out by [`ui`] this frame, with the document as the rest of the
/// frame left it (a value dragged in the inspector or the viewport shows at once).
pub fn paint_pending(ctx: &egui::Context, app: &mut EditorApp) {
    let Some((layer, rect)) = app.view.pending_curves.take() else { return };
    let painter = egui::Painter::new(ctx.clone(), layer, rect);
    let visuals = ctx.global_style().visuals.clone();
    painter.rect_filled(rect, 2.0, visuals.extreme_bg_color);
    let ids = shown_channels(app);
    if ids.is_empty() {
        return;
    }
    let scene = app.doc.scene();
    let (start, end) = (
        f64::from(scene.frame_range.start),
        f64::from(scene.frame_range.end.max(scene.frame_range.start + 1)),
    );
    let samples = (rect.width() / 2.0).clamp(16.0, 800.0) as usize;
    let all: Vec<(ChannelId, Vec<Curve>)> =
        ids.iter().map(|&id| (id, sample_curves(app, id, start, end, samples))).collect();
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for (_, curves) in &all {
        for curve in curves {
            for &(_, v) in curve {
                if v.is_finite() {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
        }
    }
    if !(lo.is_finite() && hi.is_finite()) {
        return;
    }
    if hi - lo < 1e-3 {
        lo -= 0.5;
        hi += 0.5;
    }
    let pad = (hi - lo) * 0.08;
    let (lo, hi) = (lo - pad, hi + pad);
    let plot = rect.shrink2(Vec2::new(28.0, 8.0));
    let to_screen = |frame: f64, v: f32| {
        Pos2::new(
            plot.left() + ((frame - start) / (end - start)) as f32 * plot.width(),
            plot.bottom() - (v - lo) / (hi - lo) * plot.height(),
        )
    };
    // Zero line and value labels.
    if lo < 0.0 && hi > 0.0 {
        let y = to_screen(start, 0.0).y;
        painter.line_segment(
            [Pos2::new(plot.left(), y), Pos2::new(plot.right(), y)],
            Stroke::new(1.0, visuals.faint_bg_color),
        );
    }
    for v in [lo + pad, hi - pad] {
        painter.text(
            Pos2::new(rect.left() + 2.0, to_screen(start, v).y),
            Align2::LEFT_CENTER,
            format!("{v:.1}"),
            FontId::proportional(9.0),
            visuals.weak_text_color(),
        );
    }
    let fps = scene.fps.max(1e-9);
    // Cycles: the curves go on beyond the keys (sampled like everything else); the stretches
    // outside the keys are shaded and named ("after: Repeat") so the repeats read as repeats.
    for id in &ids {
        let Some(cycles) = channels::cycles(scene, *id).filter(|c| !c.is_hold()) else { continue };
        let times = channels::key_times(scene, *id);
        let (Some(&first), Some(&last)) = (times.first(), times.last()) else { continue };
        let (first, last) = ((first * fps).clamp(start, end), (last * fps).clamp(start, end));
        for (from, to, cycle, text_at, align) in [
            (start, first, cycles.before, first, Align2::RIGHT_TOP),
            (last, end, cycles.after, last, Align2::LEFT_TOP),
        ] {
            if cycle.is_hold() || to <= from {
                continue;
            }
            let (a, b) = (to_screen(from, hi), to_screen(to, lo));
            painter.rect_filled(
                egui::Rect::from_min_max(Pos2::new(a.x, plot.top()), Pos2::new(b.x, plot.bottom())),
                0.0,
                visuals.faint_bg_color.gamma_multiply(0.6),
            );
            let end_name = if align == Align2::LEFT_TOP { "after" } else { "before" };
            let text = format!("{end_name}: {}", cycle.label());
            painter.text(
                Pos2::new(to_screen(text_at, lo).x, plot.top()),
                align,
                text,
                FontId::proportional(10.0),
                visuals.weak_text_color(),
            );
        }
    }
    for (id, curves) in &all {
        for (c, curve) in curves.iter().enumerate() {
            let colour = match (curves.len(), c) {
                (1, _) => Color32::from_rgb(230, 200, 90),
                (_, 3) => TURN_COLOUR,
                _ => COMPONENT_COLOURS[c % 3],
            };
            let points: Vec<Pos2> = curve.iter().map(|&(f, v)| to_screen(f, v)).collect();
            painter.add(Shape::line(points, Stroke::new(1.5, colour)));
            // Key markers: the curve's value at each key time in view, one per pixel column
            // (a motion-capture track has more keys than the view has pixels).
            let mut last_column = None;
            for time in channels::keys_between(scene, *id, start / fps, end / fps).times {
                let frame = time * fps;
                let i = (((frame - start) / (end - start)) * (curve.len() - 1) as f64).round() as usize;
                if let Some(&(_, v)) = curve.get(i) {
                    let at = to_screen(frame, v);
                    let column = at.x.round() as i32;
                    if last_column != Some(column) {
                        last_column = Some(column);
                        painter.circle_filled(at, 3.0, colour);
                    }
                }
            }
        }
    }
    if let Some((_, axis)) = ids.iter().find_map(|&id| turn_axis(app, id)) {
        painter.text(
            Pos2::new(plot.right(), plot.top()),
            Align2::RIGHT_TOP,
            format!(
                "white: turn about ({:.2}, {:.2}, {:.2}) through spin keys, unwrapped; X/Y/Z: Euler {}",
                axis.x,
                axis.y,
                axis.z,
                crate::panels::inspector::EULER_ORDER
            ),
            FontId::proportional(10.0),
            visuals.weak_text_color(),
        );
    }
    let x = to_screen(app.session.playback.frame, lo).x;
    painter.line_segment(
        [Pos2::new(x, plot.top()), Pos2::new(x, plot.bottom())],
        Stroke::new(1.5, Color32::from_rgb(90, 170, 255)),
    );
}
