//! Edit ▸ Reduce keys… and Smooth keys… (docs/cleanup.md) on the CMU 131 take: the shortcut
//! opens the window, Apply cleans every keyed channel (nothing selected) as one undo step, and
//! undo brings every key back.

mod common;

use common::{corpus, harness, press};

use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;
use keyrig_edit::cleanup::{key_total, keyed_channels};
use keyrig_editor::EditorApp;

fn keys(app: &EditorApp) -> usize {
    let scene = app.doc.scene();
    key_total(scene, &keyed_channels(scene, None))
}

#[test]
fn reduce_keys_is_one_undo_step_and_undo_restores_the_keys() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), Some(corpus("bvh/cmu-bvh11/131_01.bvh")));
    h.state_mut().wait_for_background_work();
    h.run();
    let before = keys(h.state());
    assert_eq!(before, 31808);
    let original = h.state().doc.scene().clone();

    press(&mut h, Modifiers::COMMAND.plus(Modifiers::ALT), Key::K);
    h.get_by_label("Apply").click();
    h.run();
    let after = keys(h.state());
    assert!(after * 10 <= before, "{after} of {before} keys kept");
    assert!(
        h.state().doc.undo_label().is_some_and(|l| l.starts_with("reduce keys of 32 channels within 0.5°")),
        "{:?}",
        h.state().doc.undo_label()
    );

    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(keys(h.state()), before);
    assert!(*h.state().doc.scene() == original, "undo gives the scene back exactly");
}

#[test]
fn smooth_keys_moves_values_in_one_undo_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), Some(corpus("bvh/cmu-bvh11/131_01.bvh")));
    h.state_mut().wait_for_background_work();
    h.run();
    let original = h.state().doc.scene().clone();

    press(&mut h, Modifiers::COMMAND.plus(Modifiers::SHIFT), Key::K);
    h.get_by_label("Apply").click();
    h.run();
    assert_eq!(keys(h.state()), 31808, "smoothing keeps every key");
    assert!(*h.state().doc.scene() != original, "the values moved");
    assert!(h.state().doc.undo_label().is_some_and(|l| l == "smooth 32 channels below 6 Hz"));
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert!(*h.state().doc.scene() == original);
}
