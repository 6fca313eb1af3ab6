//! The input a user produces, as egui-winit translates it from the window system: the scroll
//! wheel and right/middle/Shift drags over the viewport with a joint selected (the gizmo must
//! not take them), Ctrl+C / Ctrl+V as copy and paste events carrying the system clipboard's
//! text (also between two editor windows), and the save dialog confirmed with Enter on a
//! typed path.

mod common;

use common::{go_to_frame, harness};

use egui::{Event, Key, Modifiers, MouseWheelUnit, PointerButton, Pos2, TouchPhase};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use keyrig_edit::channels::{self, ChannelId};
use keyrig_editor::app::DialogPurpose;
use keyrig_editor::session::Selected;
use keyrig_editor::EditorApp;

const ELBOW: ChannelId = ChannelId::JointRotation { object: 0, joint: 1 };

fn select_elbow(h: &mut Harness<'_, EditorApp>) {
    h.get_by_label("elbow").click();
    h.run();
    assert_eq!(h.state().session.selection.item, Some(Selected::Joint { object: 0, joint: 1 }));
}

/// A point of the viewport away from the selection's gizmo (its lower left).
fn empty_viewport_point(h: &Harness<'_, EditorApp>) -> Pos2 {
    let rect = h.state().viewport_rect().expect("the viewport was laid out");
    rect.left_bottom() + egui::vec2(rect.width() * 0.12, -rect.height() * 0.15)
}

/// Press at `from`, move to `to` in eight steps, release: one frame per event, as winit
/// delivers a drag.
/// `modifiers` are held throughout (winit reports them as they change, before the press).
fn drag_with(
    h: &mut Harness<'_, EditorApp>,
    button: PointerButton,
    modifiers: Modifiers,
    from: Pos2,
    to: Pos2,
) {
    h.input_mut().modifiers = modifiers;
    h.event(Event::PointerMoved(from));
    h.run();
    h.event(Event::PointerButton { pos: from, button, pressed: true, modifiers });
    h.run();
    for i in 1..=8 {
        h.event(Event::PointerMoved(from + (to - from) * (i as f32 / 8.0)));
        h.run();
    }
    h.event(Event::PointerButton { pos: to, button, pressed: false, modifiers });
    h.run();
    h.input_mut().modifiers = Modifiers::NONE;
    h.run();
}

#[test]
fn scroll_and_pan_work_with_a_joint_selected() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    select_elbow(&mut h);
    let at = empty_viewport_point(&h);

    // The wheel zooms in (content moves down: positive y) wherever the pointer is.
    let before = h.state().view.camera;
    h.event(Event::PointerMoved(at));
    h.run();
    for _ in 0..3 {
        h.event(Event::MouseWheel {
            unit: MouseWheelUnit::Line,
            delta: egui::vec2(0.0, 1.0),
            phase: TouchPhase::Move,
            modifiers: Modifiers::NONE,
        });
        h.run();
    }
    let zoomed = h.state().view.camera;
    assert!(
        zoomed.distance < before.distance * 0.95,
        "the wheel zooms: {} → {}",
        before.distance,
        zoomed.distance
    );
    assert_eq!(zoomed.target, before.target);

    // Right, middle and Shift+left drags pan (the target moves, the angles stay).
    for (button, modifiers) in [
        (PointerButton::Secondary, Modifiers::NONE),
        (PointerButton::Middle, Modifiers::NONE),
        (PointerButton::Primary, Modifiers::SHIFT),
    ] {
        let camera = h.state().view.camera;
        let from = empty_viewport_point(&h);
        drag_with(&mut h, button, modifiers, from, from + egui::vec2(60.0, -30.0));
        let after = h.state().view.camera;
        assert!(
            (after.target - camera.target).length() > 1e-3,
            "{button:?} {modifiers:?} drag pans with a joint selected"
        );
        assert_eq!((after.yaw_deg, after.pitch_deg), (camera.yaw_deg, camera.pitch_deg));
        assert_eq!(
            h.state().session.selection.item,
            Some(Selected::Joint { object: 0, joint: 1 }),
            "still selected"
        );
    }

    // A left drag on empty space orbits and writes nothing.
    let camera = h.state().view.camera;
    let keys = channels::key_count(h.state().doc.scene(), ELBOW);
    let from = empty_viewport_point(&h);
    drag_with(&mut h, PointerButton::Primary, Modifiers::NONE, from, from + egui::vec2(80.0, 0.0));
    assert!((h.state().view.camera.yaw_deg - camera.yaw_deg).abs() > 1.0, "left drag orbits");
    assert_eq!(channels::key_count(h.state().doc.scene(), ELBOW), keys);
    assert!(!h.state().doc.is_dirty(), "navigating is not an edit");
}

/// The text the last frame put on the system clipboard (`ctx.copy_text`).
fn copied_text(h: &Harness<'_, EditorApp>) -> Option<String> {
    h.output().platform_output.commands.iter().find_map(|c| match c {
        egui::OutputCommand::CopyText(text) => Some(text.clone()),
        _ => None,
    })
}

#[test]
fn copy_and_paste_events_move_keys_between_two_editors() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("key elbow rotation frame 15").click();
    h.run();
    h.event(Event::Copy);
    h.step();
    let text = copied_text(&h).expect("Ctrl+C puts the keys on the system clipboard");
    assert!(text.starts_with(channels::CLIPBOARD_HEADER), "{text}");
    h.run();

    // Another editor window (its own clipboard empty) pastes what the system clipboard holds.
    let other_dir = tempfile::tempdir().expect("temp dir");
    let mut other = harness(other_dir.path(), None);
    assert!(other.state().session.clipboard.is_empty());
    go_to_frame(&mut other, 50);
    let before = channels::key_count(other.state().doc.scene(), ELBOW);
    other.event(Event::Paste(text.clone()));
    other.run();
    let scene = other.state().doc.scene();
    assert_eq!(channels::key_count(scene, ELBOW), before + 1);
    let pasted = channels::key_at(scene, ELBOW, 50.0 / scene.fps).expect("a key at frame 50");
    let source = channels::copy_key(h.state().doc.scene(), ELBOW, 1).expect("the copied key");
    let copy = channels::copy_key(scene, ELBOW, pasted).expect("the pasted key");
    assert_eq!((copy.value, copy.interpolation, copy.tcb), (source.value, source.interpolation, source.tcb));

    // Text that is not keyrig keys pastes the editor's own clipboard.
    go_to_frame(&mut h, 60);
    h.event(Event::Paste("hello".to_owned()));
    h.run();
    let scene = h.state().doc.scene();
    assert!(channels::key_at(scene, ELBOW, 60.0 / scene.fps).is_some());

    // Cut copies and deletes.
    let n = channels::key_count(h.state().doc.scene(), ELBOW);
    h.get_by_label("key elbow rotation frame 60").click();
    h.run();
    h.event(Event::Cut);
    h.run();
    assert_eq!(channels::key_count(h.state().doc.scene(), ELBOW), n - 1);
}

#[test]
fn save_as_proposes_a_ron_name_and_takes_a_typed_path_with_enter() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.key_press_modifiers(Modifiers::NONE, Key::Num2);
    h.run();
    h.key_press_modifiers(Modifiers::COMMAND, Key::S);
    h.run();
    assert_eq!(h.state().dialog_purpose(), Some(DialogPurpose::SaveAs), "an untitled scene asks where");
    // The file-name field has the keyboard, "Untitled" selected before ".ron".
    assert!(
        h.query_all_by_value("Untitled.ron").any(|n| n.is_focused()),
        "the proposed name has the keyboard"
    );
    let target = dir.path().join("walk");
    h.event(Event::Text(target.display().to_string()));
    h.run();
    h.key_press(Key::Enter);
    h.run();
    let saved = dir.path().join("walk.ron");
    assert!(saved.exists(), "saved to the typed path with the proposed extension");
    assert_eq!(h.state().doc.path(), Some(saved.as_path()));
    assert!(!h.state().doc.is_dirty());
    assert_eq!(h.state().dialog_purpose(), None);
}

#[test]
fn open_and_import_dialogs_list_only_their_files() {
    use keyrig_editor::files::dialog_filters;
    let names = |p| dialog_filters(p).into_iter().flat_map(|(_, e)| e.iter().copied()).collect::<Vec<_>>();
    assert_eq!(dialog_filters(DialogPurpose::Open)[0].1, &["ron"]);
    assert_eq!(dialog_filters(DialogPurpose::SaveAs)[0].1, &["ron"]);
    assert_eq!(dialog_filters(DialogPurpose::Export)[0].1, &["glb"]);
    assert!(!names(DialogPurpose::Import).contains(&"ron"));

    let dir = tempfile::tempdir().expect("temp dir");
    for file in ["shot.ron", "fox.glb", "ogre.MD2", "notes.txt"] {
        std::fs::write(dir.path().join(file), b"x").expect("write");
    }
    let scene_path = dir.path().join("shot.ron");
    keyrig_io::project::save_scene(&scene_path, &keyrig_io::demo::demo_scene()).expect("save");
    let mut h = harness(dir.path(), Some(scene_path));
    h.key_press_modifiers(Modifiers::COMMAND, Key::I);
    h.run();
    assert_eq!(h.state().dialog_purpose(), Some(DialogPurpose::Import));
    assert!(h.query_by_label_contains("fox.glb").is_some(), "import lists glTF");
    assert!(h.query_by_label_contains("ogre.MD2").is_some(), "and MD2, whatever the case");
    assert!(h.query_by_label_contains("notes.txt").is_none(), "not other files");
    assert!(h.query_by_label_contains("shot.ron").is_none(), "not scenes");
}

/// Issue 42, 11: a file dialog owns the keyboard. With the Open dialog up and its list (not its
/// text field) holding the focus, B, O and the arrow keys change nothing in the editor: the
/// bones stay shown, the onion skin off, the frame where it was.
#[test]
fn a_file_dialog_owns_the_keyboard() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let (bones, onion, frame) =
        (h.state().view.bones, h.state().view.onion.enabled, h.state().session.playback.whole_frame());
    h.key_press_modifiers(Modifiers::COMMAND, Key::O);
    h.run();
    assert_eq!(h.state().dialog_purpose(), Some(DialogPurpose::Open));
    // Nothing has the keyboard: keys are not text for a field.
    h.ctx.memory_mut(|m| {
        if let Some(id) = m.focused() {
            m.surrender_focus(id);
        }
    });
    h.run();
    for key in [Key::B, Key::O, Key::ArrowRight, Key::G] {
        h.key_press(key);
        h.run();
    }
    assert_eq!(h.state().dialog_purpose(), Some(DialogPurpose::Open), "the dialog is still open");
    assert_eq!(h.state().view.bones, bones, "B did not reach the editor");
    assert_eq!(h.state().view.onion.enabled, onion, "O did not reach the editor");
    assert_eq!(h.state().session.playback.whole_frame(), frame, "→ did not step the clock");
}
