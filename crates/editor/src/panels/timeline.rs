//! The timeline at the bottom: playback controls (play/pause, loop, fps, range, frame), the
//! dope sheet ([`crate::panels::dope_sheet`]) and the curve view beside it.

use egui::{Ui, Vec2};

use crate::app::EditorApp;
use crate::channels;
use crate::commands::Command;
use crate::panels::menu::tool_button;
use crate::widgets::field::{number_field, FieldChange};

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
            ui.allocate_ui_with_layout(sheet_size, layout, |ui| crate::panels::dope_sheet::ui(ui, app));
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
