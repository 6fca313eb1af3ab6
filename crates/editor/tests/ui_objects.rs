//! Managing objects and lights as a user does: the outliner's clicks (with Shift and Ctrl),
//! double-click to rename with typed text, its context menu, and the Delete, Shift+D and
//! Ctrl+R shortcuts. Each step is checked in the document and its undo history.

mod common;

use common::{go_to_frame, harness, press};

use egui::{Event, Key, Modifiers};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use keyrig_edit::channels::{self, ChannelId};
use keyrig_editor::session::Selected;
use keyrig_editor::EditorApp;

fn object_names(h: &Harness<'_, EditorApp>) -> Vec<String> {
    h.state().doc.scene().objects.iter().map(|o| o.name.clone()).collect()
}

fn light_names(h: &Harness<'_, EditorApp>) -> Vec<String> {
    h.state().doc.scene().lights.iter().map(|l| l.name.clone()).collect()
}

fn status_text(h: &Harness<'_, EditorApp>) -> String {
    h.state().status().map(|s| s.text.clone()).unwrap_or_default()
}

/// The outliner's row named `name` (the leftmost widget with that label: the dope sheet
/// names its rows too).
fn outliner_row<'a>(h: &'a Harness<'_, EditorApp>, name: &'a str) -> egui_kittest::Node<'a> {
    h.get_all_by_label(name).min_by(|a, b| a.rect().left().total_cmp(&b.rect().left())).expect("a row")
}

/// Types `text` into the focused field as the window system delivers it (text events), then
/// presses `end` (Enter or Escape).
fn type_and(h: &mut Harness<'_, EditorApp>, text: &str, end: Key) {
    h.key_press_modifiers(Modifiers::COMMAND, Key::A);
    h.run();
    h.event(Event::Text(text.to_owned()));
    h.run();
    press(h, Modifiers::NONE, end);
}

#[test]
fn delete_removes_the_selected_light_or_object_and_undo_brings_it_back() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    assert_eq!(light_names(&h), ["Key", "Sun"]);
    outliner_row(&h, "Key").click();
    h.run();
    assert_eq!(h.state().session.selection.item, Some(Selected::Light(0)));
    press(&mut h, Modifiers::NONE, Key::Delete);
    assert_eq!(light_names(&h), ["Sun"]);
    assert_eq!(status_text(&h), "Deleted Key");
    assert_eq!(h.state().session.selection.item, None);
    assert_eq!(h.state().doc.undo_label(), Some("delete light Key"));

    // The cube through the outliner's context menu.
    outliner_row(&h, "Cube").click_secondary();
    h.run();
    h.get_by_label("Delete").click();
    h.run();
    assert_eq!(object_names(&h), ["Arm"]);

    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(object_names(&h), ["Arm", "Cube"]);
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(light_names(&h), ["Key", "Sun"]);
}

#[test]
fn delete_prefers_selected_keys_and_refuses_a_lone_joint() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let elbow = ChannelId::JointRotation { object: 0, joint: 1 };
    let keys = channels::key_count(h.state().doc.scene(), elbow);
    h.get_by_label("key elbow rotation frame 30").click();
    h.run();
    press(&mut h, Modifiers::NONE, Key::Delete);
    assert_eq!(channels::key_count(h.state().doc.scene(), elbow), keys - 1, "the selected key goes");
    assert_eq!(object_names(&h), ["Arm", "Cube"], "not the object");

    h.get_by_label("elbow").click();
    h.run();
    press(&mut h, Modifiers::NONE, Key::Delete);
    assert!(h.state().status().is_some_and(|s| s.is_error), "{:?}", h.state().status());
    assert!(status_text(&h).contains("elbow is a joint"), "{}", status_text(&h));
    assert_eq!(h.state().doc.scene().objects[0].skeleton.as_ref().map(|s| s.joints.len()), Some(4));
}

#[test]
fn shift_d_duplicates_with_a_new_name_keys_included() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("Arm").click();
    h.run();
    press(&mut h, Modifiers::SHIFT, Key::D);
    assert_eq!(object_names(&h), ["Arm", "Cube", "Arm.001"]);
    assert_eq!(h.state().session.selection.item, Some(Selected::Object(2)));
    let scene = h.state().doc.scene();
    assert_eq!(scene.objects[2].skeleton, scene.objects[0].skeleton, "the copy has the keys");
    press(&mut h, Modifiers::SHIFT, Key::D);
    assert_eq!(object_names(&h)[3], "Arm.002");
    assert!(h.state().doc.scene().problems().is_empty(), "names stay unique");
    press(&mut h, Modifiers::COMMAND, Key::Z);
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(object_names(&h), ["Arm", "Cube"]);
}

#[test]
fn double_click_renames_with_typed_text_in_one_undo_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let steps = h.state().doc.undo_len();
    h.get_by_label("Cube").click();
    h.run();
    // A double click: two presses and releases within egui's 0.3 s (the harness advances a
    // quarter second per event, so they arrive in one frame, as after a slow frame).
    let cube = h.get_by_label("Cube").rect().center();
    for pressed in [true, false, true, false] {
        h.input_mut().events.push(Event::PointerButton {
            pos: cube,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: Modifiers::NONE,
        });
    }
    h.step();
    h.run();
    assert!(h.state().panels().outliner.renaming().is_some(), "double-click opens the name field");
    type_and(&mut h, "Box", Key::Enter);
    assert_eq!(object_names(&h), ["Arm", "Box"]);
    assert_eq!(h.state().doc.undo_len(), steps + 1, "typing is one step");
    assert_eq!(h.state().doc.undo_label(), Some("rename Cube to Box"));

    // Ctrl+R on a joint; Escape leaves the name alone.
    h.get_by_label("wrist").click();
    h.run();
    press(&mut h, Modifiers::COMMAND, Key::R);
    type_and(&mut h, "hand", Key::Escape);
    assert_eq!(h.state().doc.scene().objects[0].skeleton.as_ref().unwrap().joints[3].name, "wrist");
    assert_eq!(h.state().doc.undo_len(), steps + 1);

    // A taken name is refused with a message, the item keeps its name.
    h.get_by_label("Box").click();
    h.run();
    press(&mut h, Modifiers::COMMAND, Key::R);
    type_and(&mut h, "Arm", Key::Enter);
    assert_eq!(object_names(&h), ["Arm", "Box"]);
    assert!(status_text(&h).contains("the name Arm is taken"), "{}", status_text(&h));
    press(&mut h, Modifiers::COMMAND, Key::R);
    type_and(&mut h, "  ", Key::Enter);
    assert!(status_text(&h).contains("cannot be empty"), "{}", status_text(&h));
    assert_eq!(object_names(&h), ["Arm", "Box"]);
}

#[test]
fn shift_and_ctrl_click_select_several_joints_and_i_keys_them_all() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    go_to_frame(&mut h, 10);
    h.get_by_label("wrist").click();
    h.run();
    h.get_by_label("shoulder").click_modifiers(Modifiers::SHIFT);
    h.run();
    h.get_by_label("elbow").click_modifiers(Modifiers::COMMAND);
    h.run();
    let selection = &h.state().session.selection;
    let joints: Vec<Selected> = selection.items().collect();
    assert_eq!(joints.len(), 3, "{joints:?}");
    assert_eq!(selection.item, Some(Selected::Joint { object: 0, joint: 1 }), "the last clicked is active");
    // Ctrl-click again removes it.
    h.get_by_label("elbow").click_modifiers(Modifiers::COMMAND);
    h.run();
    assert!(!h.state().session.selection.contains(Selected::Joint { object: 0, joint: 1 }));

    let rotation = |h: &Harness<'_, EditorApp>, joint| {
        channels::key_count(h.state().doc.scene(), ChannelId::JointRotation { object: 0, joint })
    };
    let before: Vec<usize> = (0..4).map(|j| rotation(&h, j)).collect();
    press(&mut h, Modifiers::NONE, Key::I);
    assert_eq!(rotation(&h, 3), before[3] + 1, "the wrist is keyed");
    assert_eq!(rotation(&h, 0), before[0] + 1, "the shoulder is keyed");
    assert_eq!(rotation(&h, 1), before[1], "the elbow is not selected");
    // A plain click selects one item again.
    h.get_by_label("elbow").click();
    h.run();
    assert_eq!(h.state().session.selection.items().count(), 1);
}

#[test]
fn i_on_a_character_keys_every_joint_of_its_skeleton() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    go_to_frame(&mut h, 12);
    h.get_by_label("Arm").click();
    h.run();
    press(&mut h, Modifiers::NONE, Key::I);
    let scene = h.state().doc.scene();
    let time = 12.0 / scene.fps;
    for joint in 0..4 {
        let id = ChannelId::JointRotation { object: 0, joint };
        let keyed = channels::key_times(scene, id).iter().any(|t| (t - time).abs() < 1e-9);
        assert!(keyed, "joint {joint} has a key at frame 12");
    }
    assert!(status_text(&h).starts_with("Keyed"), "{}", status_text(&h));
}

#[test]
fn the_key_inspector_follows_the_selection_and_edits_every_selected_key() {
    use egui::accesskit::Role;
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let elbow = ChannelId::JointRotation { object: 0, joint: 1 };
    h.get_by_label("key elbow rotation frame 30").click();
    h.run();
    assert!(h.query_by_label("elbow rotation at frame 30").is_some(), "the inspector shows the key");
    // Another object: its keys are not selected, so the inspector shows none.
    outliner_row(&h, "Cube").click();
    h.run();
    assert!(h.state().session.selection.keys.is_empty());
    assert!(h.query_by_label("elbow rotation at frame 30").is_none(), "no stale key");

    // Two keys with different tension: shown as mixed; a change applies to both, one step.
    h.get_by_label("key elbow rotation frame 30").click();
    h.run();
    common::set_value(&mut h, Role::Slider, "Tension", 0.9);
    h.get_by_label("key elbow rotation frame 15").click_modifiers(Modifiers::SHIFT);
    h.run();
    assert_eq!(h.state().session.selection.keys.len(), 2);
    assert!(h.query_by_label("2 keys selected (editing all)").is_some());
    let steps = h.state().doc.undo_len();
    common::set_value(&mut h, Role::Slider, "Tension (mixed)", -0.25);
    assert_eq!(h.state().doc.undo_len(), steps + 1, "one step for both keys");
    for index in 0..channels::key_count(h.state().doc.scene(), elbow) {
        let (time, _, tcb) = channels::key_params(h.state().doc.scene(), elbow, index).expect("a key");
        let frame = (time * 30.0).round() as i32;
        if frame == 15 || frame == 30 {
            assert_eq!(tcb.tension, -0.25, "key at frame {frame}");
        }
    }
    assert!(h.query_by_label("Tension (mixed)").is_none(), "now equal");
}

/// Shift+D as in Blender: the copy follows the pointer with no button held (in the plane
/// facing the camera, so a move to the right moves it to the camera's right) until a click
/// places it; the copy and its move are one undo step. Escape instead leaves it on the
/// original.
#[test]
fn shift_d_starts_a_move_that_a_click_places_and_escape_cancels() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("Arm").click();
    h.run();
    let rect = h.state().viewport_rect().expect("a viewport");
    let from = rect.center();
    common::pointer(&mut h, Event::PointerMoved(from));
    let steps = h.state().doc.undo_len();
    let original = h.state().doc.scene().objects[0].translation.value;
    press(&mut h, Modifiers::SHIFT, Key::D);
    assert_eq!(object_names(&h), ["Arm", "Cube", "Arm.001"]);
    for i in 1..=5 {
        common::pointer(&mut h, Event::PointerMoved(from + egui::vec2(20.0 * i as f32, 0.0)));
    }
    let moved = h.state().doc.scene().objects[2].translation.value;
    let camera = &h.state().view.camera;
    let right =
        (camera.target - keyrig_editor::camera::OrbitCamera::eye(camera)).cross(glam::Vec3::Y).normalize();
    let offset = moved - original;
    assert!(offset.dot(right) > 0.1, "the copy follows the pointer to the right: {offset:?}");
    assert!(offset.dot(right) > 0.9 * offset.length(), "in the view plane: {offset:?}");
    assert_eq!(h.state().doc.scene().objects[0].translation.value, original, "the original stays");
    // A click places it; the click selects nothing else.
    let at = from + egui::vec2(100.0, 0.0);
    for pressed in [true, false] {
        common::pointer(
            &mut h,
            Event::PointerButton {
                pos: at,
                button: egui::PointerButton::Primary,
                pressed,
                modifiers: Modifiers::NONE,
            },
        );
    }
    common::pointer(&mut h, Event::PointerMoved(at + egui::vec2(30.0, 30.0)));
    assert_eq!(h.state().doc.scene().objects[2].translation.value, moved, "placed where it was clicked");
    assert_eq!(h.state().session.selection.item, Some(Selected::Object(2)));
    assert_eq!(h.state().doc.undo_len(), steps + 1, "the copy and its move are one step");
    assert_eq!(h.state().doc.undo_label(), Some("duplicate as Arm.001"));
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(object_names(&h), ["Arm", "Cube"], "one undo takes the copy and its move back");

    // Escape: the copy stays, on the original.
    h.get_by_label("Arm").click();
    h.run();
    common::pointer(&mut h, Event::PointerMoved(from));
    press(&mut h, Modifiers::SHIFT, Key::D);
    for i in 1..=5 {
        common::pointer(&mut h, Event::PointerMoved(from + egui::vec2(0.0, -15.0 * i as f32)));
    }
    assert_ne!(h.state().doc.scene().objects[2].translation.value, original);
    press(&mut h, Modifiers::NONE, Key::Escape);
    common::pointer(&mut h, Event::PointerMoved(from + egui::vec2(60.0, 0.0)));
    assert_eq!(object_names(&h), ["Arm", "Cube", "Arm.001"]);
    assert_eq!(
        h.state().doc.scene().objects[2].translation.value,
        original,
        "Escape leaves it on the original"
    );
    assert_eq!(h.state().doc.undo_len(), steps + 1);
}

/// Issue 42, item 3: Shift+D on an animated object (the demo's Cube, its translation keyed)
/// then a move places the copy with its whole motion: every translation key moves by the
/// offset, so at any other frame the copy plays the original's motion where it was put (the
/// move is not a pose that snaps back). The copy keeps the original's colour: the Cube draws
/// with the renderer's palette colour of its place among the objects, which the copy gets as
/// its colour attribute.
#[test]
fn shift_d_on_an_animated_object_places_its_motion_and_keeps_its_colour() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    assert!(channels::key_count(h.state().doc.scene(), ChannelId::ObjectTranslation(1)) > 2);
    assert!(h.state().doc.scene().objects[1].attributes.colour.is_none());
    let blue = keyrig_render::scene_frame::object_palette_colour(&h.state().evaluator(), 1);
    go_to_frame(&mut h, 10);
    outliner_row(&h, "Cube").click();
    h.run();
    let rect = h.state().viewport_rect().expect("a viewport");
    let from = rect.center();
    common::pointer(&mut h, Event::PointerMoved(from));
    press(&mut h, Modifiers::SHIFT, Key::D);
    assert_eq!(object_names(&h), ["Arm", "Cube", "Cube.001"]);
    for i in 1..=5 {
        common::pointer(&mut h, Event::PointerMoved(from + egui::vec2(24.0 * i as f32, 0.0)));
    }
    let at = from + egui::vec2(120.0, 0.0);
    for pressed in [true, false] {
        common::pointer(
            &mut h,
            Event::PointerButton {
                pos: at,
                button: egui::PointerButton::Primary,
                pressed,
                modifiers: Modifiers::NONE,
            },
        );
    }
    common::pointer(&mut h, Event::PointerMoved(at + egui::vec2(30.0, 30.0)));
    let value =
        |h: &Harness<'_, EditorApp>, o: usize| match h.state().value_now(ChannelId::ObjectTranslation(o)) {
            Some(keyrig_edit::channels::ChannelValue::Vec3(v)) => v,
            other => panic!("a translation: {other:?}"),
        };
    let offset = value(&h, 2) - value(&h, 1);
    assert!(offset.length() > 0.1, "the copy moved at frame 10: {offset:?}");
    // The next frames: the copy stays where it was put, playing the Cube's motion there.
    for frame in [11, 40, 75] {
        go_to_frame(&mut h, frame);
        let now = value(&h, 2) - value(&h, 1);
        assert!((now - offset).length() < 1e-4, "frame {frame}: offset {now:?}, placed {offset:?}");
    }
    assert!(h.state().session.overrides.is_empty(), "the move is in the keys, not a pose");
    let scene = h.state().doc.scene();
    assert_eq!(
        channels::key_count(scene, ChannelId::ObjectTranslation(2)),
        channels::key_count(scene, ChannelId::ObjectTranslation(1)),
        "the copy keeps its keys, moved"
    );
    let rest = scene.objects[2].translation.value - scene.objects[1].translation.value;
    assert!((rest - offset).length() < 1e-4, "its static value (played muted) moved too: {rest:?}");
    assert_eq!(h.state().doc.undo_label(), Some("duplicate as Cube.001"), "one step");
    // Its look: the Cube's palette colour, not the one of the third object.
    let copy_colour = scene.objects[2].attributes.colour.as_ref().map(|c| c.value);
    assert_eq!(copy_colour, Some(blue), "the copy is drawn in the Cube's colour");
    assert_ne!(keyrig_render::scene_frame::object_palette_colour(&h.state().evaluator(), 2), blue);
    assert!(scene.objects[1].attributes.colour.is_none(), "the original is unchanged");
}
