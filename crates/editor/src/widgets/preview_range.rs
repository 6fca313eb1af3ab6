//! The preview range in the timeline (Blender's preview range): a sub-range of the frame range
//! that playback, Home and End keep to while it is set, so a few frames of a long shot loop on
//! their own. *Preview* (Ctrl+Alt+P) turns it on — over the selected keys, else from the
//! current frame to the range's end — or off; its Start and End fields follow. It is saved
//! with the scene (`Scene::preview_range`) and each change is an undo step; renders and
//! exports keep the whole frame range. The dope sheet tints it on its ruler.

use egui::Ui;
use keyrig_core::{FrameRange, Scene};

use crate::actions::{Actions, Edit};
use crate::commands::Command;
use crate::context::FrameCtx;
use crate::widgets::field::{number_field, FieldChange};
use keyrig_edit::SceneEdit;

/// The colour the preview range is marked with (the dope sheet's ruler, the toggle).
pub const PREVIEW_COLOUR: egui::Color32 = egui::Color32::from_rgb(230, 140, 40);

/// The *Preview* toggle and, while the preview range is set, its Start and End fields.
pub fn preview_range_ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
    let scene = ctx.scene();
    let preview = scene.preview_range;
    let text = egui::RichText::new("Preview");
    let text = if preview.is_some() { text.color(PREVIEW_COLOUR) } else { text };
    let tooltip = format!(
        "{} ({}): playback, Home and End keep to a part of the frame range",
        Command::TogglePreviewRange.tooltip(),
        Command::TogglePreviewRange.shortcut_text(ui.ctx()),
    );
    if ui.selectable_label(preview.is_some(), text).on_hover_text(tooltip).clicked() {
        actions.command(Command::TogglePreviewRange);
    }
    let Some(p) = preview else { return };
    let range = scene.frame_range;
    let (mut start, mut end) = (p.start, p.end);
    let (_, start_change) =
        number_field(ui, &mut start, "Preview start", |d| d.range(range.start..=range.end));
    let (_, end_change) = number_field(ui, &mut end, "Preview end", |d| d.range(range.start..=range.end));
    let changes = [start_change, end_change];
    if !changes.iter().any(|c| c.any()) {
        return;
    }
    // Start after End: the other end follows, so the range is never empty.
    let new = if start_change.any() {
        FrameRange { start, end: end.max(start) }
    } else {
        FrameRange { start: start.min(end), end }
    };
    if changes.contains(&FieldChange::Dragged) {
        actions.edit(Edit::continuous("preview range", SceneEdit::PreviewRange(new)));
    } else {
        actions.push(crate::actions::Action::CloseGroup);
        actions.edit(Edit::scene(SceneEdit::PreviewRange(new)));
    }
}

/// The preview range *Preview* turns on: the frames of the selected keys when they span at
/// least two, else from `frame` to the range's end (the whole range at its end); always inside
/// the frame range.
#[must_use]
pub fn initial_preview(scene: &Scene, key_frames: &[i32], frame: i32) -> FrameRange {
    let range = scene.frame_range;
    let clamp = |f: i32| f.clamp(range.start, range.end);
    if let (Some(&first), Some(&last)) = (key_frames.iter().min(), key_frames.iter().max()) {
        if clamp(first) < clamp(last) {
            return FrameRange { start: clamp(first), end: clamp(last) };
        }
    }
    let start = clamp(frame);
    if start < range.end {
        FrameRange { start, end: range.end }
    } else {
        range
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_first_preview_spans_the_selected_keys_else_the_rest_of_the_range() {
        let scene = Scene { frame_range: FrameRange { start: 0, end: 90 }, ..Scene::default() };
        let range = |start, end| FrameRange { start, end };
        assert_eq!(initial_preview(&scene, &[30, 12, 45], 0), range(12, 45));
        assert_eq!(initial_preview(&scene, &[30, 30], 20), range(20, 90), "keys on one frame");
        assert_eq!(initial_preview(&scene, &[], 20), range(20, 90));
        assert_eq!(initial_preview(&scene, &[-20, 200], 0), range(0, 90), "cut to the range");
        assert_eq!(initial_preview(&scene, &[], 90), range(0, 90), "at the end: all of it");
    }
}
