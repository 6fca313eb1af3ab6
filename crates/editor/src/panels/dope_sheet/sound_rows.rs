//! The scene's sound clips in the dope sheet: one row per clip at the head of the rows,
//! scrolling with them (its name, a mute switch, and its waveform as a bar on the time axis that a drag moves in
//! whole frames, one undo step per drag), and the unmuted clips' waveforms faintly behind the
//! ruler itself, as Maya's time slider shows them.
//!
//! Waveforms are drawn from the clips' min/max summaries ([`crate::sounds::SoundStore`]) one
//! screen column at a time ([`crate::widgets::waveform`]), so a clip costs its visible width.

use egui::accesskit::Role;
use egui::{Align2, Color32, CursorIcon, FontId, PointerButton, Pos2, Rect, Sense, Stroke, Ui, Vec2};
use keyrig_core::SoundClip;

use super::{current_frame_line, marker_lines, shade_outside_range, DopeSheet, Geometry, PAD};
use crate::actions::{Action, Actions, Edit};
use crate::context::FrameCtx;
use crate::sounds::SoundLoad;
use crate::widgets::publish_painted;
use crate::widgets::waveform::{paint_waveform, waveform_columns};
use keyrig_edit::SceneEdit;

/// The height of one clip's row, points.
pub(super) const SOUND_ROW_HEIGHT: f32 = 28.0;

const BAR: Color32 = Color32::from_rgb(34, 58, 52);
const WAVE: Color32 = Color32::from_rgb(110, 205, 165);
const MUTED_WAVE: Color32 = Color32::from_gray(110);

/// A clip being dragged along the time axis.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) struct SoundDrag {
    /// The clip's index in the scene's list.
    clip: usize,
    /// Its start frame when the drag began.
    from: f64,
    /// Whole frames the drag has moved it so far.
    applied: i64,
}

/// How long a clip's bar is drawn while its file decodes or when it cannot be read, seconds.
const UNKNOWN_LENGTH: f64 = 1.0;

/// The clip's frames on the timeline: from its start to its end (its sound's length, or
/// [`UNKNOWN_LENGTH`] while that is not known).
fn clip_frames(ctx: &FrameCtx<'_>, clip: &SoundClip, fps: f64) -> (f64, f64) {
    let seconds = ctx.sounds.summary(ctx.base_dir(), &clip.path).map_or(UNKNOWN_LENGTH, |s| s.duration());
    (clip.start_frame, clip.start_frame + seconds * fps)
}

/// Every clip's frames on the timeline ([`clip_frames`]): what *View all* shows besides the
/// range and the keys.
pub(super) fn clip_spans(ctx: &FrameCtx<'_>) -> Vec<(f64, f64)> {
    let fps = ctx.scene().fps.max(1e-9);
    ctx.scene().sounds.iter().map(|clip| clip_frames(ctx, clip, fps)).collect()
}

impl DopeSheet {
    /// The clips' rows in `strip` (one [`SOUND_ROW_HEIGHT`] each, at the top of the scrolled
    /// rows).
    pub(super) fn sound_rows_ui(
        &mut self,
        ui: &mut Ui,
        ctx: &FrameCtx<'_>,
        actions: &mut Actions,
        strip: Rect,
        geo: &Geometry,
    ) {
        let scene = ctx.scene();
        let visuals = ui.visuals().clone();
        let keys = Rect::from_min_max(
            Pos2::new(geo.keys.0 - PAD, strip.top()),
            Pos2::new(geo.keys.1 + PAD, strip.bottom()),
        );
        let painter = ui.painter_at(strip);
        painter.rect_filled(strip, 0.0, visuals.faint_bg_color.gamma_multiply(0.6));
        shade_outside_range(
            &painter.with_clip_rect(keys),
            scene,
            geo,
            keys,
            visuals.extreme_bg_color.gamma_multiply(0.8),
        );
        for (i, clip) in scene.sounds.iter().enumerate() {
            let top = strip.top() + SOUND_ROW_HEIGHT * i as f32;
            let row = Rect::from_min_max(
                Pos2::new(strip.left(), top),
                Pos2::new(strip.right(), top + SOUND_ROW_HEIGHT),
            );
            self.clip_name_ui(ui, ctx, actions, clip, i, row, geo);
            self.clip_bar_ui(ui, ctx, actions, clip, i, row, geo);
            painter.line_segment(
                [Pos2::new(row.left(), row.bottom() - 0.5), Pos2::new(row.right(), row.bottom() - 0.5)],
                Stroke::new(1.0, visuals.widgets.noninteractive.bg_stroke.color),
            );
        }
        let painter = painter.with_clip_rect(keys);
        marker_lines(&painter, scene, geo, keys);
        current_frame_line(&painter, ctx, geo, keys);
    }

    /// The name column of a clip's row: a mute switch and the file's name (its path, gain and
    /// state as the tooltip).
    #[allow(clippy::too_many_arguments)]
    fn clip_name_ui(
        &mut self,
        ui: &mut Ui,
        ctx: &FrameCtx<'_>,
        actions: &mut Actions,
        clip: &SoundClip,
        i: usize,
        row: Rect,
        geo: &Geometry,
    ) {
        let speaker = Rect::from_min_size(
            Pos2::new(geo.names.0 + 4.0, row.top() + 4.0),
            Vec2::new(22.0, row.height() - 8.0),
        );
        let label = clip.label().to_owned();
        let toggle = ui
            .put(speaker, egui::Button::new(if clip.mute { "🔇" } else { "🔊" }).small().frame(false))
            .on_hover_text(if clip.mute { "Unmute this sound clip" } else { "Mute this sound clip" });
        if toggle.clicked() {
            let mute = !clip.mute;
            actions.edit(Edit::scene(SceneEdit::SoundMute { clip: i, muted: mute }));
        }
        let name = Rect::from_min_max(
            Pos2::new(speaker.right() + 2.0, row.top()),
            Pos2::new(geo.names.1, row.bottom()),
        );
        let visuals = ui.visuals();
        let colour = if clip.mute { visuals.weak_text_color() } else { visuals.text_color() };
        let painter = ui.painter_at(name);
        painter.text(
            Pos2::new(name.left(), name.center().y),
            Align2::LEFT_CENTER,
            format!("♪ {label}"),
            FontId::proportional(12.0),
            colour,
        );
        let state = match ctx.sounds.get(ctx.base_dir(), &clip.path) {
            None | Some(SoundLoad::Loading) => "decoding…".to_owned(),
            Some(SoundLoad::Ready(s)) => {
                format!("{:.2} s, {} Hz, {} channel(s)", s.duration(), s.sample_rate, s.channels)
            }
            Some(SoundLoad::Failed(e)) => e.clone(),
        };
        let tip = format!(
            "Sound clip {}\nstarts at frame {}, gain {}{}\n{state}\nDrag its waveform to move it in time.",
            clip.path,
            clip.start_frame,
            clip.gain,
            if clip.mute { ", muted" } else { "" }
        );
        ui.interact(name, ui.id().with(("sound name", i)), Sense::hover()).on_hover_text(tip);
        publish_painted(
            ui.ctx(),
            ui.id().with(("sound row", i)),
            Role::Row,
            name,
            || format!("dope sheet row ♪ {label}"),
            None,
        );
    }

    /// A clip's bar on the time axis with its waveform; a drag on it moves the clip.
    #[allow(clippy::too_many_arguments)]
    fn clip_bar_ui(
        &mut self,
        ui: &mut Ui,
        ctx: &FrameCtx<'_>,
        actions: &mut Actions,
        clip: &SoundClip,
        i: usize,
        row: Rect,
        geo: &Geometry,
    ) {
        let keys = Rect::from_min_max(
            Pos2::new(geo.keys.0 - PAD, row.top()),
            Pos2::new(geo.keys.1 + PAD, row.bottom()),
        );
        let (first, last) = clip_frames(ctx, clip, geo.fps);
        let bar = Rect::from_min_max(
            Pos2::new(geo.x(first).max(keys.left() - 2.0), row.top() + 2.0),
            Pos2::new(geo.x(last).min(keys.right() + 2.0), row.bottom() - 3.0),
        );
        let painter = ui.painter_at(keys);
        let visible = bar.width() > 0.0;
        if visible {
            painter.rect_filled(bar, 2.0, BAR);
        }
        match ctx.sounds.get(ctx.base_dir(), &clip.path) {
            Some(SoundLoad::Ready(summary)) if visible => {
                let columns = waveform_columns(summary, clip, &geo.axis(), geo.fps, bar.left(), bar.right());
                paint_waveform(
                    &painter,
                    bar.shrink2(Vec2::new(0.0, 1.0)),
                    &columns,
                    if clip.mute { MUTED_WAVE } else { WAVE },
                );
            }
            Some(SoundLoad::Failed(_)) if visible => {
                painter.text(
                    bar.left_center() + Vec2::new(4.0, 0.0),
                    Align2::LEFT_CENTER,
                    "cannot read",
                    FontId::proportional(10.0),
                    Color32::from_rgb(240, 110, 100),
                );
            }
            None | Some(SoundLoad::Loading) if visible => {
                painter.text(
                    bar.left_center() + Vec2::new(4.0, 0.0),
                    Align2::LEFT_CENTER,
                    "decoding…",
                    FontId::proportional(10.0),
                    ui.visuals().weak_text_color(),
                );
            }
            _ => {}
        }
        if visible {
            let label = clip.label().to_owned();
            let frame = clip.start_frame;
            publish_painted(
                ui.ctx(),
                ui.id().with(("sound clip", i)),
                Role::Button,
                bar,
                || format!("sound clip {label} frame {frame}"),
                None,
            );
        }

        // Dragging the bar moves the clip by whole frames; the whole drag is one undo step.
        let response = ui.interact(bar.intersect(keys), ui.id().with(("sound bar", i)), Sense::drag());
        let response = response.on_hover_cursor(CursorIcon::Grab);
        if response.drag_started_by(PointerButton::Primary) {
            self.sound_drag = Some(SoundDrag { clip: i, from: clip.start_frame, applied: 0 });
        }
        let Some(drag) = self.sound_drag.filter(|d| d.clip == i) else { return };
        if let Some(delta) = response.total_drag_delta() {
            let frames = (f64::from(delta.x) * geo.frames_per_point()).round() as i64;
            if frames != drag.applied {
                let start = drag.from + frames as f64;
                actions.edit(Edit::continuous(
                    format!("move sound clip {i}"),
                    SceneEdit::SoundStart { clip: i, start_frame: start },
                ));
                self.sound_drag = Some(SoundDrag { applied: frames, ..drag });
            }
        }
        if response.drag_stopped() || !ui.input(|input| input.pointer.any_down()) {
            actions.push(Action::CloseGroup);
            self.sound_drag = None;
        }
    }
}

/// The unmuted clips' waveforms, faint, behind the frame ruler.
pub(super) fn ruler_waveforms(painter: &egui::Painter, ctx: &FrameCtx<'_>, geo: &Geometry, ruler: Rect) {
    let colour = WAVE.gamma_multiply(0.3);
    let (left, right) = (ruler.left().max(geo.keys.0 - PAD), ruler.right());
    for clip in ctx.scene().sounds.iter().filter(|c| !c.mute) {
        if let Some(summary) = ctx.sounds.summary(ctx.base_dir(), &clip.path) {
            let columns = waveform_columns(summary, clip, &geo.axis(), geo.fps, left, right);
            paint_waveform(painter, ruler.shrink2(Vec2::new(0.0, 2.0)), &columns, colour);
        }
    }
}
