//! The timeline's playback controls at the bottom of the window: play/pause, loop, every-frame
//! playback, the frame, the frame range and the scene's fps (with "Keep key frames"). The dope
//! sheet and the curve view sit beneath them ([`crate::window`] lays the three out).

use egui::Ui;

use crate::actions::{Action, Actions, Edit, SessionChange};
use crate::commands::Command;
use crate::context::FrameCtx;
use crate::widgets::command_button::tool_button;
use crate::widgets::field::{number_field, FieldChange};
use keyrig_edit::SceneEdit;

/// The playback controls and their own state.
#[derive(Debug, Default)]
pub struct Timeline {
    /// When the FPS changes, keys keep their frames (true) or their times in seconds (false).
    pub keep_frames: bool,
    /// (fps, start, end) when the current FPS drag started.
    fps_drag_origin: Option<(f64, i32, i32)>,
}

impl Timeline {
    /// The controls, on one row.
    pub fn ui(&mut self, ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
        ui.horizontal(|ui| {
            let playback = &ctx.session.playback;
            tool_button(ui, actions, Command::FirstFrame, "⏮", false);
            tool_button(ui, actions, Command::PrevFrame, "⏴", false);
            let playing = playback.playing;
            tool_button(ui, actions, Command::PlayPause, if playing { "⏸ Pause" } else { "▶ Play" }, playing);
            tool_button(ui, actions, Command::NextFrame, "⏵", false);
            tool_button(ui, actions, Command::LastFrame, "⏭", false);
            tool_button(ui, actions, Command::ToggleLoop, "🔁 Loop", playback.looping);
            let mut every_frame = playback.every_frame;
            let response = ui.checkbox(&mut every_frame, "Every frame").on_hover_text(
                "Checked: every frame is drawn, even when drawing is slower than the scene's fps \
                 (slow motion). Unchecked (the default): real time, dropping frames to keep time.",
            );
            if response.changed() {
                actions.session(SessionChange::EveryFrame(every_frame));
            }
            if let Some(t) = ctx.frame_time.filter(|_| playback.playing) {
                let fps = ctx.scene().fps;
                let achieved = playback.achieved_fps(f64::from(t), fps);
                ui.weak(format!("{achieved:.1}/{fps} fps"))
                    .on_hover_text("Scene frames shown per second while playing, against the scene's fps");
            }
            ui.separator();

            let scene = ctx.scene();
            let (mut start, mut end, mut fps) = (scene.frame_range.start, scene.frame_range.end, scene.fps);
            let (old_start, old_end, old_fps) = (start, end, fps);
            let mut frame = playback.whole_frame();
            ui.label("Frame");
            let (_, change) = number_field(ui, &mut frame, "Frame", |d| d.range(start..=end));
            if change.any() {
                ctx.set_frame(actions, frame);
            }
            ui.label("Start");
            let (_, start_change) = number_field(ui, &mut start, "Start", |d| d);
            ui.label("End");
            let (_, end_change) = number_field(ui, &mut end, "End", |d| d);
            ui.label("FPS");
            let (_, fps_change) = number_field(ui, &mut fps, "FPS", |d| d.speed(0.1).max_decimals(3));
            ui.checkbox(&mut self.keep_frames, "Keep key frames").on_hover_text(
                "When the FPS changes: checked, keys stay on their frames (the animation plays \
                 faster or slower, as Blender's time stretching); unchecked, keys keep their time \
                 in seconds and move to other frames. Either way the frame range follows the keys.",
            );
            if start_change.any() || end_change.any() {
                let frame = playback.whole_frame();
                apply_range(actions, frame, (old_start, old_end), (start, end), start_change, end_change);
            }
            let keep_frames = self.keep_frames;
            match fps_change {
                FieldChange::None => {}
                FieldChange::Dragged => {
                    // Computed from the fps at the start of the drag, so the range does not
                    // drift by rounding as the drag goes on.
                    let origin = *self.fps_drag_origin.get_or_insert((old_fps, old_start, old_end));
                    let fps = if fps.is_finite() { fps.clamp(MIN_FPS, MAX_FPS) } else { old_fps };
                    actions.edit(Edit::continuous("fps", SceneEdit::Retime { origin, fps, keep_frames }));
                }
                FieldChange::Committed => {
                    if !(fps.is_finite() && (MIN_FPS..=MAX_FPS).contains(&fps)) {
                        actions.push(Action::Error(format!(
                            "FPS must be between {MIN_FPS} and {MAX_FPS} (typed {fps}); it stays {old_fps}"
                        )));
                    } else {
                        let origin = (old_fps, old_start, old_end);
                        actions.push(Action::CloseGroup);
                        actions.edit(Edit::scene(SceneEdit::Retime { origin, fps, keep_frames }));
                    }
                }
            }
            if !ui.input(|i| i.pointer.any_down()) {
                self.fps_drag_origin = None;
            }
            ui.separator();
            crate::widgets::preview_range::preview_range_ui(ui, ctx, actions);
            markers_ui(ui, ctx, actions);
        });
    }
}

/// The scene's timeline markers as buttons (its name, and the camera it switches to) that go to
/// the marker's frame; the one at the current frame is highlighted. M adds or removes one.
fn markers_ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
    let scene = ctx.scene();
    if scene.markers.is_empty() {
        return;
    }
    ui.separator();
    ui.label("Markers");
    let now = ctx.session.playback.whole_frame();
    for marker in &scene.markers {
        let text = match &marker.camera {
            Some(camera) => format!("▼ {} {} ▸ {camera}", marker.frame, marker.name),
            None => format!("▼ {} {}", marker.frame, marker.name),
        };
        let response = ui
            .selectable_label(marker.frame == now, text)
            .on_hover_text("Go to this marker's frame (M at a marker's frame removes it)");
        if response.clicked() {
            ctx.set_frame(actions, marker.frame);
        }
    }
}

/// The lowest and highest scene frame rates the FPS field accepts.
pub const MIN_FPS: f64 = 1.0;
pub const MAX_FPS: f64 = 240.0;
/// The frame range limits of the Start and End fields.
const FRAME_LIMIT: i32 = 100_000;

/// Applies an edit of the Start or End field: a drag clamps to a valid range (one undo step per
/// drag), a typed value is checked (Start before End) and refused with a status-bar error. The
/// playhead (at `frame`) stays where it was unless the new range leaves it out.
fn apply_range(
    actions: &mut Actions,
    frame: i32,
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
        actions.edit(Edit::continuous("frame range", SceneEdit::FrameRange { start, end }));
    } else if start.abs() > FRAME_LIMIT || end.abs() > FRAME_LIMIT {
        actions.push(Action::Error(format!("Frames must lie between {} and {FRAME_LIMIT}", -FRAME_LIMIT)));
        return;
    } else if start >= end {
        let which = if start_change.any() {
            format!("Start ({start}) must be before End ({end})")
        } else {
            format!("End ({end}) must be after Start ({start})")
        };
        actions.push(Action::Error(format!("{which}; the range stays {}–{}", old.0, old.1)));
        return;
    } else {
        actions.push(Action::CloseGroup);
        actions.edit(Edit::scene(SceneEdit::FrameRange { start, end }));
    }
    if frame < start || frame > end {
        actions.session(SessionChange::SetFrame(frame));
    }
}
