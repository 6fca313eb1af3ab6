//! Number fields commit once: typed text applies on Enter or when focus leaves, as one undo
//! step; Escape cancels; invalid values are refused with a status-bar error; a drag on a value
//! is one undo step. Keys are typed as egui-winit delivers them: a `Key` press followed by the
//! `Text` of the character.

mod common;

use common::{drag, harness};

use egui::accesskit::Role;
use egui::{Event, Key};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use keyrig_edit::channels::{ChannelId, ChannelValue};
use keyrig_editor::session::Selected;
use keyrig_editor::EditorApp;

/// Clicks the number field labelled `label`, types `text` character by character (a frame
/// each) and ends with `finish` (Enter or Escape).
fn type_into(h: &mut Harness<'_, EditorApp>, label: &str, text: &str, finish: Key) {
    h.get_by_role_and_label(Role::SpinButton, label).click();
    h.run();
    for c in text.chars() {
        let s = c.to_string();
        let key = Key::from_name(&s);
        if let Some(key) = key {
            h.key_down(key);
        }
        h.event(Event::Text(s));
        if let Some(key) = key {
            h.key_up(key);
        }
        h.run();
    }
    h.key_press(finish);
    h.run();
}

fn status(h: &Harness<'_, EditorApp>) -> Option<(String, bool)> {
    h.state().status().map(|s| (s.text.clone(), s.is_error))
}

#[test]
fn typing_fps_applies_once_as_one_undo_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    assert_eq!(h.state().doc.scene().fps, 30.0);
    let steps = h.state().doc.undo_len();
    type_into(&mut h, "FPS", "24", Key::Enter);
    assert_eq!(h.state().doc.scene().fps, 24.0);
    assert_eq!(h.state().doc.undo_len(), steps + 1, "one step, not one per keystroke");
    assert!(h.state_mut().doc.undo());
    assert_eq!(h.state().doc.scene().fps, 30.0, "one undo returns to 30, not to 2");
}

#[test]
fn escape_cancels_and_leaves_no_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let steps = h.state().doc.undo_len();
    let range = h.state().doc.scene().frame_range;
    type_into(&mut h, "Start", "10", Key::Escape);
    type_into(&mut h, "FPS", "48", Key::Escape);
    assert_eq!(h.state().doc.scene().frame_range, range);
    assert_eq!(h.state().doc.scene().fps, 30.0);
    assert_eq!(h.state().doc.undo_len(), steps);
    assert!(!h.state().doc.is_dirty());
}

#[test]
fn typing_end_does_not_pass_through_its_prefix() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let end = h.state().doc.scene().frame_range.end;
    h.state_mut().set_frame(end);
    let steps = h.state().doc.undo_len();
    type_into(&mut h, "End", "120", Key::Enter);
    assert_eq!(h.state().doc.scene().frame_range.end, 120);
    assert_eq!(h.state().session.playback.whole_frame(), end, "the playhead did not visit frame 1 or 12");
    assert_eq!(h.state().doc.undo_len(), steps + 1);
    type_into(&mut h, "Start", "100", Key::Enter);
    assert_eq!(h.state().doc.scene().frame_range.start, 100);
    assert_eq!(h.state().doc.undo_len(), steps + 2, "Start 100 is one step, not three");
}

#[test]
fn invalid_values_are_refused_with_a_message() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let steps = h.state().doc.undo_len();
    type_into(&mut h, "FPS", "0", Key::Enter);
    assert_eq!(h.state().doc.scene().fps, 30.0);
    let (text, is_error) = status(&h).expect("a status message");
    assert!(is_error && text.contains("FPS must be between"), "{text}");
    let range = h.state().doc.scene().frame_range;
    type_into(&mut h, "End", &(range.start - 5).to_string(), Key::Enter);
    assert_eq!(h.state().doc.scene().frame_range, range);
    let (text, is_error) = status(&h).expect("a status message");
    assert!(is_error && text.contains("must be after Start"), "{text}");
    assert_eq!(h.state().doc.undo_len(), steps, "refused values leave no step");
}

#[test]
fn typing_the_frame_field_moves_the_playhead_without_a_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let steps = h.state().doc.undo_len();
    type_into(&mut h, "Frame", "45", Key::Enter);
    assert_eq!(h.state().session.playback.whole_frame(), 45);
    assert_eq!(h.state().doc.undo_len(), steps);
}

#[test]
fn typing_an_inspector_value_is_one_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("wrist").click();
    h.run();
    assert_eq!(h.state().session.selection.item, Some(Selected::Joint { object: 0, joint: 3 }));
    let steps = h.state().doc.undo_len();
    type_into(&mut h, "Rotation (°) X", "12.5", Key::Enter);
    let wrist = ChannelId::JointRotation { object: 0, joint: 3 };
    let Some(ChannelValue::Rotation(q)) = h.state().value_now(wrist) else { panic!("a rotation") };
    let x = keyrig_editor::eval::euler_degrees(q).x;
    assert!((x - 12.5).abs() < 1e-3, "{x}");
    assert_eq!(h.state().doc.undo_len(), steps + 1, "12.5 is one step, not four");
    assert!(h.state_mut().doc.undo());
    let Some(ChannelValue::Rotation(q)) = h.state().value_now(wrist) else { panic!("a rotation") };
    assert!(keyrig_editor::eval::euler_degrees(q).x.abs() < 1e-3, "undo returns to 0, not to 12");
    // Escape leaves the value and the history alone.
    type_into(&mut h, "Rotation (°) X", "7", Key::Escape);
    assert_eq!(h.state().doc.undo_len(), steps);
}

#[test]
fn a_drag_on_a_field_is_one_undo_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let steps = h.state().doc.undo_len();
    let at = h.get_by_role_and_label(Role::SpinButton, "FPS").rect().center();
    drag(&mut h, at, at + egui::vec2(60.0, 0.0));
    let fps = h.state().doc.scene().fps;
    assert!(fps > 31.0, "the drag raised the fps: {fps}");
    assert_eq!(h.state().doc.undo_len(), steps + 1, "one step per drag");
    assert!(h.state_mut().doc.undo());
    assert_eq!(h.state().doc.scene().fps, 30.0);
}

/// Every key of the demo as (channel, frame at the scene's fps).
fn key_frames(h: &Harness<'_, EditorApp>) -> Vec<(ChannelId, f64)> {
    let scene = h.state().doc.scene();
    keyrig_edit::channels::ChannelId::all(scene)
        .into_iter()
        .flat_map(|id| {
            keyrig_edit::channels::key_times(scene, id).into_iter().map(move |t| (id, t * scene.fps))
        })
        .collect()
}

#[test]
fn changing_fps_keeps_key_times_or_frames_and_the_range_follows() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let frames = key_frames(&h);
    assert!(!frames.is_empty());
    let range = h.state().doc.scene().frame_range;
    let steps = h.state().doc.undo_len();
    // Default: keys keep their seconds; at 60 fps they lie on twice the frames, and so does
    // the range.
    type_into(&mut h, "FPS", "60", Key::Enter);
    assert_eq!(h.state().doc.scene().frame_range.end, range.end * 2);
    for ((id, f), (id2, f2)) in frames.iter().zip(key_frames(&h)) {
        assert_eq!(*id, id2);
        assert!((f * 2.0 - f2).abs() < 1e-6, "{f} → {f2}");
    }
    assert_eq!(h.state().doc.undo_len(), steps + 1, "retiming and the range are one step");
    assert!(h.state_mut().doc.undo());
    assert_eq!(h.state().doc.scene().frame_range, range);
    // Keep key frames: the keys stay on their frames and the range stays.
    h.get_by_label("Keep key frames").click();
    h.run();
    type_into(&mut h, "FPS", "60", Key::Enter);
    assert_eq!(h.state().doc.scene().fps, 60.0);
    assert_eq!(h.state().doc.scene().frame_range, range);
    for ((_, f), (_, f2)) in frames.iter().zip(key_frames(&h)) {
        assert!((f - f2).abs() < 1e-6, "{f} → {f2}");
    }
}

/// Transport (beside the fields in the timeline's control row): Play at the last frame with
/// looping off starts from the first frame; every-frame playback advances one frame per drawn
/// frame.
#[test]
fn play_at_the_end_starts_from_the_first_frame() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("🔁 Loop").click();
    h.run();
    assert!(!h.state().session.playback.looping);
    h.key_press(Key::End);
    h.run();
    let range = h.state().doc.scene().frame_range;
    assert_eq!(h.state().session.playback.whole_frame(), range.end);
    h.get_by_label("▶ Play").click();
    h.step();
    assert!(h.state().session.playback.playing);
    assert!(
        h.state().session.playback.frame < f64::from(range.start) + 5.0,
        "{}",
        h.state().session.playback.frame
    );
    h.key_press(Key::Space);
    h.step();
    assert!(!h.state().session.playback.playing);
    h.get_by_label("Every frame").click();
    h.step();
    assert!(h.state().session.playback.every_frame);
    let before = h.state().session.playback.frame;
    h.key_press(Key::Space);
    h.step();
    h.step();
    h.step();
    let advanced = h.state().session.playback.frame - before;
    assert!((1.0..=3.0).contains(&advanced), "one frame per drawn frame: {advanced}");
}
