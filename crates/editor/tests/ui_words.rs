//! Words the editor shows: Edit ▸ Undo and Redo name the step they revert or repeat.

mod common;

use common::harness;

use egui::accesskit::Role;
use egui_kittest::kittest::Queryable;

#[test]
fn undo_and_redo_in_the_menu_name_their_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.run();
    h.state_mut().set_deformer(keyrig_core::DeformerKind::Rigid);
    h.run();
    let step = h.state().doc.undo_label().expect("an undo step").to_owned();
    h.get_by_role_and_label(Role::Button, "Edit").click();
    h.step();
    h.step();
    // A menu item's accessible label is its text followed by its shortcut.
    assert!(h.query_by_label_contains(&format!("Undo {step}")).is_some(), "Undo names `{step}`");
    assert!(h.query_by_label_contains(&format!("Redo {step}")).is_none(), "nothing to redo yet");
    // After undoing, Redo names the step.
    h.key_press(egui::Key::Escape);
    h.run();
    assert!(h.state_mut().doc.undo());
    h.run();
    h.get_by_role_and_label(Role::Button, "Edit").click();
    h.step();
    h.step();
    assert!(h.query_by_label_contains(&format!("Redo {step}")).is_some(), "Redo names `{step}`");
}
