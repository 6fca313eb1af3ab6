//! The inspector's Action section (docs/actions.md): assign, new, duplicate, rename and delete
//! an object's action, each one undo step, refused names refused, saved with the scene.

mod common;

use common::{harness, press};

use egui::accesskit::Role;
use egui::{Event, Key, Modifiers};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use keyrig_editor::EditorApp;

/// The demo with its keys as the action "Wave", and the Cube playing the empty action "Still".
fn scene() -> keyrig_core::Scene {
    let mut scene = keyrig_io::demo::demo_scene();
    scene.name_unnamed_keys("Wave");
    let cube = scene.objects.iter().position(|o| o.name == "Cube").expect("the demo's Cube");
    scene.new_action(cube, "Still").expect("new action");
    scene
}

fn cube<'a>(h: &'a Harness<'_, EditorApp>) -> &'a keyrig_core::Object {
    h.state().doc.scene().objects.iter().find(|o| o.name == "Cube").expect("Cube")
}

/// Scrolls the inspector to the widget labelled `label` (the Action section is its last) and
/// clicks it.
fn click(h: &mut Harness<'_, EditorApp>, label: &str) {
    h.get_by_label(label).scroll_to_me();
    h.run();
    h.get_by_label(label).click();
    h.run();
}

fn type_action_name(h: &mut Harness<'_, EditorApp>, text: &str) {
    click(h, "Action name");
    h.get_by_label("Action name").click();
    h.run();
    h.event(Event::Text(text.to_owned()));
    h.run();
}

#[test]
fn the_inspector_assigns_makes_renames_and_deletes_actions() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("actions.ron");
    keyrig_io::scene_file::save(&file, &scene()).expect("save");
    let mut h = harness(dir.path(), Some(file.clone()));
    h.get_all_by_label("Cube").next().expect("the Cube in the outliner").click();
    h.run();
    assert_eq!(cube(&h).action.as_deref(), Some("Still"));
    assert!(!cube(&h).translation.is_animated());
    let steps = h.state().doc.undo_len();

    // Assign Wave from the combo box: the Cube's keys come back, one undo step.
    h.get_by_role_and_label(Role::ComboBox, "Action").scroll_to_me();
    h.run();
    h.get_by_role_and_label(Role::ComboBox, "Action").click();
    h.run();
    h.get_by_label("Wave").click();
    h.run();
    assert_eq!(cube(&h).action.as_deref(), Some("Wave"));
    assert_eq!(cube(&h).translation.track.len(), 5, "the demo Cube's five position keys");
    assert_eq!(h.state().doc.undo_len(), steps + 1);
    assert_eq!(h.state().doc.undo_label(), Some("play action Wave on Cube"));
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(cube(&h).action.as_deref(), Some("Still"));
    assert!(!cube(&h).translation.is_animated(), "undo puts the keys back in Wave");
    press(&mut h, Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    assert_eq!(cube(&h).action.as_deref(), Some("Wave"));

    // Duplicate under a new name: the copy plays, Wave keeps its keys.
    type_action_name(&mut h, "Bounce");
    click(&mut h, "Duplicate action");
    assert_eq!(cube(&h).action.as_deref(), Some("Bounce"));
    assert_eq!(cube(&h).translation.track.len(), 5);
    let scene = h.state().doc.scene();
    let wave = &scene.actions[scene.action_index("Wave").expect("Wave")];
    assert!(wave.channels.iter().any(|c| c.path == "object/Cube/translation"), "Wave keeps the Cube's keys");

    // A taken name is refused: nothing changes, the status says why.
    let steps = h.state().doc.undo_len();
    type_action_name(&mut h, "Wave");
    click(&mut h, "New action");
    assert_eq!(h.state().doc.undo_len(), steps, "refused");
    assert!(
        h.state().status().is_some_and(|s| s.text.contains("already an action")),
        "{:?}",
        h.state().status().map(|s| s.text.clone())
    );

    // Rename the active action (the refused name replaced in the field); then delete it.
    click(&mut h, "Action name");
    press(&mut h, Modifiers::COMMAND, Key::A);
    h.event(Event::Text("Hop".to_owned()));
    h.run();
    click(&mut h, "Rename action");
    assert_eq!(cube(&h).action.as_deref(), Some("Hop"), "{:?}", h.state().doc.scene().actions);
    assert_eq!(h.state().doc.undo_label(), Some("rename action Bounce to Hop"));
    click(&mut h, "Delete action");
    assert_eq!(cube(&h).action, None);
    assert!(!cube(&h).translation.is_animated());
    assert!(h.state().doc.scene().action_index("Hop").is_none());

    // Saved and read back as it is.
    h.state_mut().save_to(file.clone());
    let back = keyrig_io::scene_file::load(&file).expect("reads back");
    assert_eq!(&back, h.state().doc.scene());
    assert!(back.problems().is_empty());
}
