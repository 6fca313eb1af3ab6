//! The timeline at the bottom: playback controls (play/pause, loop, fps, range, frame), the
//! dope sheet (a row per object, light, joint and channel with key diamonds you can select,
//! box-select and drag in time) with a scrubber, and the curve view beside it.

use std::collections::BTreeSet;

use egui::{Align2, Color32, FontId, Pos2, Rect, Sense, Stroke, Ui, Vec2};

use crate::app::EditorApp;
use crate::channels::{self, ChannelId};
use crate::commands::Command;
use crate::panels::menu::tool_button;
use crate::session::{KeyRef, Selected};
use crate::widgets::field::{number_field, FieldChange};
use crate::widgets::key_diamond::key_diamond_ui;

const ROW_HEIGHT: f32 = 17.0;
const NAME_WIDTH: f32 = 170.0;
const RULER_HEIGHT: f32 = 20.0;

/// One dope-sheet row.
struct Row {
    label: String,
    indent: usize,
    /// The channel edited on this row; `None` for summary rows (object, light).
    channel: Option<ChannelId>,
    /// Channels whose keys the row shows.
    shows: Vec<ChannelId>,
    item: Option<Selected>,
}

fn rows(app: &EditorApp) -> Vec<Row> {
    let scene = app.doc.scene();
    let mut out = Vec::new();
    let keyed = |id: ChannelId| channels::key_count(scene, id) > 0;
    for (o, object) in scene.objects.iter().enumerate() {
        let all = ChannelId::of_object(scene, o);
        out.push(Row {
            label: object.name.clone(),
            indent: 0,
            channel: None,
            shows: all.clone(),
            item: Some(Selected::Object(o)),
        });
        let selected_object = app.session.selection.item == Some(Selected::Object(o));
        for id in [ChannelId::ObjectTranslation(o), ChannelId::ObjectRotation(o), ChannelId::ObjectScale(o)] {
            if keyed(id) || selected_object {
                out.push(Row {
                    label: id.channel_name().to_owned(),
                    indent: 1,
                    channel: Some(id),
                    shows: vec![id],
                    item: Some(Selected::Object(o)),
                });
            }
        }
        if let Some(skeleton) = &object.skeleton {
            let root = ChannelId::RootTranslation(o);
            if keyed(root) {
                out.push(Row {
                    label: "root translation".to_owned(),
                    indent: 1,
                    channel: Some(root),
                    shows: vec![root],
                    item: Some(Selected::Object(o)),
                });
            }
            for (j, joint) in skeleton.joints.iter().enumerate() {
                let rows = [
                    (
                        ChannelId::JointTranslation { object: o, joint: j },
                        "translation",
                        joint.translation.is_animated(),
                    ),
                    (ChannelId::JointRotation { object: o, joint: j }, "rotation", true),
                    (ChannelId::JointScale { object: o, joint: j }, "scale", joint.scale.is_animated()),
                ];
                for (id, what, shown) in rows {
                    if shown {
                        out.push(Row {
                            label: format!("{} {what}", joint.name),
                            indent: 1,
                            channel: Some(id),
                            shows: vec![id],
                            item: Some(Selected::Joint { object: o, joint: j }),
                        });
                    }
                }
            }
        }
    }
    for (l, light) in scene.lights.iter().enumerate() {
        let all = ChannelId::of_light(l).to_vec();
        out.push(Row {
            label: light.name.clone(),
            indent: 0,
            channel: None,
            shows: all.clone(),
            item: Some(Selected::Light(l)),
        });
        let selected = app.session.selection.item == Some(Selected::Light(l));
        for id in all {
            if keyed(id) || selected {
                out.push(Row {
                    label: id.channel_name().to_owned(),
                    indent: 1,
                    channel: Some(id),
                    shows: vec![id],
                    item: Some(Selected::Light(l)),
                });
            }
        }
    }
    out
}

/// Draws the bottom panel: controls, dope sheet and curves.
pub fn ui(ui: &mut Ui, app: &mut EditorApp) {
    egui::Panel::bottom("timeline").resizable(true).default_size(310.0).show_inside(ui, |ui| {
        controls_ui(ui, app);
        ui.separator();
        let available = ui.available_size();
        let curves_width = (available.x * 0.38).max(200.0);
        ui.horizontal_top(|ui| {
            let sheet_size = Vec2::new((available.x - curves_width - 8.0).max(200.0), available.y);
            let layout = egui::Layout::top_down(egui::Align::Min);
            ui.allocate_ui_with_layout(sheet_size, layout, |ui| dope_sheet_ui(ui, app));
            ui.separator();
            let size = Vec2::new(ui.available_width(), available.y);
            ui.allocate_ui_with_layout(size, layout, |ui| crate::panels::curves::ui(ui, app));
        });
    });
}

fn controls_ui(ui: &mut Ui, app: &mut EditorApp) {
    ui.horizontal(|ui| {
        tool_button(ui, app, Command::FirstFrame, "⏮", false);
        tool_button(ui, app, Command::PrevFrame, "⏴", false);
        let playing = app.session.playback.playing;
        tool_button(ui, app, Command::PlayPause, if playing { "⏸ Pause" } else { "▶ Play" }, playing);
        tool_button(ui, app, Command::NextFrame, "⏵", false);
        tool_button(ui, app, Command::LastFrame, "⏭", false);
        let looping = app.session.playback.looping;
        tool_button(ui, app, Command::ToggleLoop, "🔁 Loop", looping);
        ui.checkbox(&mut app.session.playback.every_frame, "Every frame").on_hover_text(
            "Checked: every frame is drawn, even when drawing is slower than the scene's fps \
             (slow motion). Unchecked (the default): real time, dropping frames to keep time.",
        );
        if let Some(t) = app.frame_time.filter(|_| app.session.playback.playing) {
            let fps = app.doc.scene().fps;
            let achieved = app.session.playback.achieved_fps(f64::from(t), fps);
            ui.weak(format!("{achieved:.1}/{fps} fps"))
                .on_hover_text("Scene frames shown per second while playing, against the scene's fps");
        }
        ui.separator();

        let scene = app.doc.scene();
        let (mut start, mut end, mut fps) = (scene.frame_range.start, scene.frame_range.end, scene.fps);
        let (old_start, old_end, old_fps) = (start, end, fps);
        let mut frame = app.session.playback.whole_frame();
        ui.label("Frame");
        let (_, change) = number_field(ui, &mut frame, "Frame", |d| d.range(start..=end));
        if change.any() {
            app.set_frame(frame);
        }
        ui.label("Start");
        let (_, start_change) = number_field(ui, &mut start, "Start", |d| d);
        ui.label("End");
        let (_, end_change) = number_field(ui, &mut end, "End", |d| d);
        ui.label("FPS");
        let (_, fps_change) = number_field(ui, &mut fps, "FPS", |d| d.speed(0.1).max_decimals(3));
        ui.checkbox(&mut app.view.timeline.keep_frames, "Keep key frames").on_hover_text(
            "When the FPS changes: checked, keys stay on their frames (the animation plays \
             faster or slower, as Blender's time stretching); unchecked, keys keep their time \
             in seconds and move to other frames. Either way the frame range follows the keys.",
        );
        if start_change.any() || end_change.any() {
            apply_range(app, (old_start, old_end), (start, end), start_change, end_change);
        }
        match fps_change {
            FieldChange::None => {}
            FieldChange::Dragged => {
                // Computed from the fps at the start of the drag, so the range does not
                // drift by rounding as the drag goes on.
                let origin = *app.view.timeline.fps_drag_origin.get_or_insert((old_fps, old_start, old_end));
                let fps = if fps.is_finite() { fps.clamp(MIN_FPS, MAX_FPS) } else { old_fps };
                let keep_frames = app.view.timeline.keep_frames;
                app.doc.edit_continuous("fps", &fps_label(fps), |s| retime(s, origin, fps, keep_frames));
            }
            FieldChange::Committed => {
                if !(fps.is_finite() && (MIN_FPS..=MAX_FPS).contains(&fps)) {
                    app.error(format!(
                        "FPS must be between {MIN_FPS} and {MAX_FPS} (typed {fps}); it stays {old_fps}"
                    ));
                } else {
                    let keep_frames = app.view.timeline.keep_frames;
                    let origin = (old_fps, old_start, old_end);
                    app.doc.close_group();
                    app.doc.edit(&fps_label(fps), |s| retime(s, origin, fps, keep_frames));
                }
            }
        }
        if !ui.input(|i| i.pointer.any_down()) {
            app.view.timeline.fps_drag_origin = None;
        }
    });
}

/// The lowest and highest scene frame rates the FPS field accepts.
pub const MIN_FPS: f64 = 1.0;
pub const MAX_FPS: f64 = 240.0;
/// The frame range limits of the Start and End fields.
const FRAME_LIMIT: i32 = 100_000;

fn fps_label(fps: f64) -> String {
    format!("change fps to {fps}")
}

/// Sets the scene's fps to `fps` from `origin` = (fps, start, end) before the change: with
/// `keep_frames` every key stays on its frame (its time in seconds scales) and the range stays;
/// otherwise keys keep their seconds and the range scales with them.
pub fn retime(scene: &mut keyrig_core::Scene, origin: (f64, i32, i32), fps: f64, keep_frames: bool) {
    let (old_fps, start, end) = origin;
    let current = scene.fps;
    if keep_frames {
        channels::scale_key_times(scene, current / fps);
        scene.frame_range.start = start;
        scene.frame_range.end = end;
    } else {
        let ratio = fps / old_fps;
        let s = (f64::from(start) * ratio).round() as i32;
        let e = ((f64::from(end) * ratio).round() as i32).max(s + 1);
        scene.frame_range.start = s;
        scene.frame_range.end = e;
    }
    scene.fps = fps;
}

/// Applies an edit of the Start or End field: a drag clamps to a valid range (one undo step per
/// drag), a typed value is checked (Start before End) and refused with a status-bar error.
fn apply_range(
    app: &mut EditorApp,
    old: (i32, i32),
    new: (i32, i32),
    start_change: FieldChange,
    end_change: FieldChange,
) {
    let (mut start, mut end) = new;
    let dragged = start_change == FieldChange::Dragged || end_change == FieldChange::Dragged;
    if dragged {
        start = start.clamp(-FRAME_LIMIT, old.1 - 1);
        end = end.clamp(old.0 + 1, FRAME_LIMIT);
        app.doc.edit_continuous("frame range", "change frame range", |s| {
            s.frame_range.start = start;
            s.frame_range.end = end;
        });
    } else if start.abs() > FRAME_LIMIT || end.abs() > FRAME_LIMIT {
        app.error(format!("Frames must lie between {} and {FRAME_LIMIT}", -FRAME_LIMIT));
        return;
    } else if start >= end {
        let which = if start_change.any() {
            format!("Start ({start}) must be before End ({end})")
        } else {
            format!("End ({end}) must be after Start ({start})")
        };
        app.error(format!("{which}; the range stays {}–{}", old.0, old.1));
        return;
    } else {
        app.doc.close_group();
        app.doc.edit(&format!("frame range {start}–{end}"), |s| {
            s.frame_range.start = start;
            s.frame_range.end = end;
        });
    }
    // The playhead stays where it was unless the new range leaves it out.
    let frame = app.session.playback.whole_frame();
    if frame < start || frame > end {
        app.set_frame(frame);
    }
}

fn frame_to_x(frame: f64, start: i32, end: i32, area: Rect) -> f32 {
    let span = f64::from((end - start).max(1));
    area.left() + ((frame - f64::from(start)) / span) as f32 * area.width()
}

fn x_to_frame(x: f32, start: i32, end: i32, area: Rect) -> f64 {
    let span = f64::from((end - start).max(1));
    f64::from(start) + f64::from((x - area.left()) / area.width().max(1.0)) * span
}

fn dope_sheet_ui(ui: &mut Ui, app: &mut EditorApp) {
    let rows = rows(app);
    let scene = app.doc.scene();
    let (fps, start, end) = (scene.fps.max(1e-9), scene.frame_range.start, scene.frame_range.end);
    egui::ScrollArea::vertical().id_salt("dope_sheet_scroll").auto_shrink([false, false]).show(ui, |ui| {
        let width = ui.available_width();
        let height = RULER_HEIGHT + ROW_HEIGHT * rows.len() as f32 + 4.0;
        let (outer, background) = ui.allocate_exact_size(Vec2::new(width, height), Sense::click_and_drag());
        let keys_area = Rect::from_min_max(
            Pos2::new(outer.left() + NAME_WIDTH + 8.0, outer.top()),
            Pos2::new(outer.right() - 8.0, outer.bottom()),
        );
        let painter = ui.painter_at(outer);
        let visuals = ui.visuals().clone();
        painter.rect_filled(outer, 0.0, visuals.extreme_bg_color);

        // Ruler and scrubber.
        let ruler = Rect::from_min_max(
            Pos2::new(keys_area.left(), outer.top()),
            Pos2::new(keys_area.right(), outer.top() + RULER_HEIGHT),
        );
        let ruler_response = ui.interact(ruler, ui.id().with("ruler"), Sense::click_and_drag());
        let ruler_response = ruler_response.on_hover_text("Click or drag to scrub");
        if ruler_response.clicked() || ruler_response.dragged() {
            if let Some(p) = ruler_response.interact_pointer_pos() {
                let f = x_to_frame(p.x, start, end, keys_area).round() as i32;
                app.set_frame(f);
            }
        }
        let step = tick_step(end - start, keys_area.width());
        let mut f = start - start.rem_euclid(step);
        while f <= end {
            if f >= start {
                let x = frame_to_x(f64::from(f), start, end, keys_area);
                painter.line_segment(
                    [Pos2::new(x, ruler.bottom() - 5.0), Pos2::new(x, outer.bottom())],
                    Stroke::new(1.0, visuals.faint_bg_color),
                );
                painter.text(
                    Pos2::new(x, ruler.top() + 2.0),
                    Align2::CENTER_TOP,
                    f.to_string(),
                    FontId::proportional(10.0),
                    visuals.weak_text_color(),
                );
            }
            f += step;
        }

        // Rows.
        let mut clicked_item = None;
        let mut diamond_clicked: Option<(KeyRef, bool)> = None;
        let mut drag_started_on: Option<KeyRef> = None;
        let mut dragging_delta: Option<f32> = None;
        let mut drag_stopped = false;
        for (r, row) in rows.iter().enumerate() {
            let top = outer.top() + RULER_HEIGHT + r as f32 * ROW_HEIGHT;
            let row_rect =
                Rect::from_min_max(Pos2::new(outer.left(), top), Pos2::new(outer.right(), top + ROW_HEIGHT));
            let is_selected_item = row.item.is_some() && row.item == app.session.selection.item;
            if is_selected_item {
                painter.rect_filled(row_rect, 0.0, visuals.selection.bg_fill.gamma_multiply(0.35));
            } else if r % 2 == 1 {
                painter.rect_filled(row_rect, 0.0, visuals.faint_bg_color.gamma_multiply(0.5));
            }
            let name_rect = Rect::from_min_size(row_rect.min, Vec2::new(NAME_WIDTH, ROW_HEIGHT));
            let name_response = ui.interact(name_rect, ui.id().with(("row_name", r)), Sense::click());
            if name_response.clicked() {
                clicked_item = row.item;
            }
            let text_color =
                if row.channel.is_none() { visuals.strong_text_color() } else { visuals.text_color() };
            painter.text(
                Pos2::new(name_rect.left() + 6.0 + 12.0 * row.indent as f32, name_rect.center().y),
                Align2::LEFT_CENTER,
                &row.label,
                FontId::proportional(12.0),
                text_color,
            );
            let y = row_rect.center().y;
            for &id in &row.shows {
                for (index, time) in channels::key_times(app.doc.scene(), id).into_iter().enumerate() {
                    let frame = time * fps;
                    let x = frame_to_x(frame, start, end, keys_area);
                    if x < keys_area.left() - 6.0 || x > keys_area.right() + 6.0 {
                        continue;
                    }
                    let key = KeyRef { channel: id, index };
                    let selected = app.session.selection.keys.contains(&key);
                    if row.channel.is_none() {
                        // Summary rows show the keys of their channels, not editable.
                        let c = Pos2::new(x, y);
                        let r = 3.5;
                        painter.add(egui::Shape::convex_polygon(
                            vec![
                                c + Vec2::new(0.0, -r),
                                c + Vec2::new(r, 0.0),
                                c + Vec2::new(0.0, r),
                                c + Vec2::new(-r, 0.0),
                            ],
                            if selected { Color32::from_rgb(255, 200, 60) } else { Color32::from_gray(140) },
                            Stroke::NONE,
                        ));
                        continue;
                    }
                    let label = format!("key {} frame {}", id.label(app.doc.scene()), frame.round() as i64);
                    let response = key_diamond_ui(
                        ui,
                        ui.id().with(("key", id, index)),
                        Pos2::new(x, y),
                        selected,
                        &label,
                    );
                    if response.clicked() {
                        let additive = ui.input(|i| i.modifiers.shift || i.modifiers.command);
                        diamond_clicked = Some((key, additive));
                    }
                    if response.drag_started() {
                        drag_started_on = Some(key);
                    }
                    if response.dragged() {
                        dragging_delta = response.total_drag_delta().map(|d| d.x);
                    }
                    if response.drag_stopped() {
                        drag_stopped = true;
                    }
                }
            }
        }

        // Current-frame line.
        let x = frame_to_x(app.session.playback.frame, start, end, keys_area);
        painter.line_segment(
            [Pos2::new(x, outer.top()), Pos2::new(x, outer.bottom())],
            Stroke::new(2.0, Color32::from_rgb(90, 170, 255)),
        );

        if let Some(item) = clicked_item {
            app.session.selection.select_only(Some(item));
        }
        if let Some((key, additive)) = diamond_clicked {
            if additive {
                if !app.session.selection.keys.remove(&key) {
                    app.session.selection.keys.insert(key);
                }
            } else {
                app.session.selection.keys = BTreeSet::from([key]);
                select_owner(app, key.channel);
            }
        }
        if let Some(key) = drag_started_on {
            if !app.session.selection.keys.contains(&key) {
                app.session.selection.keys = BTreeSet::from([key]);
                select_owner(app, key.channel);
            }
            app.view.timeline.drag_applied = 0;
        }
        if let Some(dx) = dragging_delta {
            let frames_per_point = f64::from((end - start).max(1)) / f64::from(keys_area.width().max(1.0));
            let wanted = (f64::from(dx) * frames_per_point).round() as i32;
            let step = wanted - app.view.timeline.drag_applied;
            if step != 0 && move_selected_keys(app, f64::from(step) / fps) {
                app.view.timeline.drag_applied = wanted;
            }
        }
        if drag_stopped {
            app.doc.close_group();
            app.view.timeline.drag_applied = 0;
        }

        // Box selection on the background.
        if background.drag_started() {
            app.view.timeline.box_start = ui.input(|i| i.pointer.press_origin());
        }
        if let (Some(a), Some(b)) = (app.view.timeline.box_start, ui.input(|i| i.pointer.interact_pos())) {
            let rect = Rect::from_two_pos(a, b);
            painter.rect_stroke(
                rect,
                0.0,
                Stroke::new(1.0, visuals.selection.stroke.color),
                egui::StrokeKind::Inside,
            );
            if background.drag_stopped() {
                let additive = ui.input(|i| i.modifiers.shift || i.modifiers.command);
                if !additive {
                    app.session.selection.keys.clear();
                }
                for (r, row) in rows.iter().enumerate() {
                    let Some(id) = row.channel else { continue };
                    let y = outer.top() + RULER_HEIGHT + (r as f32 + 0.5) * ROW_HEIGHT;
                    for (index, time) in channels::key_times(app.doc.scene(), id).into_iter().enumerate() {
                        let x = frame_to_x(time * fps, start, end, keys_area);
                        if rect.contains(Pos2::new(x, y)) {
                            app.session.selection.keys.insert(KeyRef { channel: id, index });
                        }
                    }
                }
                app.view.timeline.box_start = None;
            }
        }
        if !background.dragged() && !background.drag_stopped() {
            app.view.timeline.box_start = None;
        }
        if background.clicked() {
            app.session.selection.keys.clear();
        }
    });
}

/// Selects the scene item that owns `channel`.
fn select_owner(app: &mut EditorApp, channel: ChannelId) {
    app.session.selection.select_only(Some(crate::session::owner_of(channel)));
}

/// Moves every selected key by `delta` seconds as one continuous edit. Refused (returns false)
/// when a key would land on another key.
pub fn move_selected_keys(app: &mut EditorApp, delta: f64) -> bool {
    let mut by_channel: std::collections::BTreeMap<ChannelId, Vec<usize>> = Default::default();
    for k in &app.session.selection.keys {
        by_channel.entry(k.channel).or_default().push(k.index);
    }
    let mut trial = app.doc.scene().clone();
    let mut new_keys = BTreeSet::new();
    for (id, indices) in &by_channel {
        match channels::move_keys(&mut trial, *id, indices, delta) {
            Some(new_indices) => {
                new_keys.extend(new_indices.into_iter().map(|index| KeyRef { channel: *id, index }))
            }
            None => return false,
        }
    }
    app.doc.edit_continuous("move keys", "move keys", |scene| *scene = trial);
    app.session.selection.keys = new_keys;
    true
}

/// Frames between labelled ticks so that labels are at least ~40 points apart.
fn tick_step(span: i32, width: f32) -> i32 {
    let span = span.max(1) as f32;
    for step in [1, 2, 5, 10, 20, 50, 100, 200, 500, 1000] {
        if width / (span / step as f32) >= 40.0 {
            return step;
        }
    }
    5000
}
