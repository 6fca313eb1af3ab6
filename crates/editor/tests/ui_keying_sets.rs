//! Keying sets chosen in the toolbar, used with real clicks and key presses: `I` keys the
//! active set's channels (location only, scale only, a whole character from one joint), and in
//! record mode a changed joint is keyed with every joint of its character in one undo step.

mod common;

use common::{go_to_frame, harness, press, set_value};

use egui::accesskit::Role;
use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use keyrig_edit::channels::{self, ChannelId, ChannelValue};
use keyrig_editor::keying_sets::KeyingSet;
use keyrig_editor::EditorApp;

const CUBE: usize = 1;
const ARM: usize = 0;
/// The demo arm's joints: shoulder, elbow, forearm, wrist.
const JOINTS: usize = 4;

/// Chooses `label` in the toolbar's keying-set box, as the mouse does.
fn choose(h: &mut Harness<'_, EditorApp>, label: &str) {
    h.get_by_label("Keying set").click();
    h.run();
    h.get_by_label(label).click();
    h.run();
}

/// Whether channel `id` has a key at `frame`.
fn keyed_at(h: &Harness<'_, EditorApp>, id: ChannelId, frame: i32) -> bool {
    let scene = h.state().doc.scene();
    channels::key_at(scene, id, f64::from(frame) / scene.fps).is_some()
}

#[test]
fn i_keys_only_the_active_sets_channels() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("Cube").click();
    h.run();
    // The box beside *Key* leaves the toolbar's last button in the window.
    let last = h.get_by_label("Elbow").rect();
    assert!(last.right() <= common::WINDOW[0], "the toolbar fits the window: {last:?}");
    choose(&mut h, "Location only");
    assert_eq!(h.state().session.keying_set, KeyingSet::Location);
    go_to_frame(&mut h, 10);
    press(&mut h, Modifiers::NONE, Key::I);
    assert!(keyed_at(&h, ChannelId::ObjectTranslation(CUBE), 10), "location keyed");
    assert!(!keyed_at(&h, ChannelId::ObjectRotation(CUBE), 10), "rotation not keyed");
    assert_eq!(
        channels::key_count(h.state().doc.scene(), ChannelId::ObjectScale(CUBE)),
        0,
        "scale not keyed"
    );

    choose(&mut h, "Scale only");
    go_to_frame(&mut h, 20);
    press(&mut h, Modifiers::NONE, Key::I);
    assert!(keyed_at(&h, ChannelId::ObjectScale(CUBE), 20), "scale keyed");
    assert!(!keyed_at(&h, ChannelId::ObjectTranslation(CUBE), 20), "location not keyed");

    choose(&mut h, "Location, rotation & scale");
    go_to_frame(&mut h, 40);
    press(&mut h, Modifiers::NONE, Key::I);
    for id in
        [ChannelId::ObjectTranslation(CUBE), ChannelId::ObjectRotation(CUBE), ChannelId::ObjectScale(CUBE)]
    {
        assert!(keyed_at(&h, id, 40), "{id:?} keyed at 40");
    }
}

/// With the elbow selected, the default set keys the elbow alone; *Whole character* keys every
/// joint of the arm and the arm's transform, one undo step.
#[test]
fn whole_character_keys_every_joint_from_one_selected_joint() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("elbow").click();
    h.run();
    go_to_frame(&mut h, 10);
    press(&mut h, Modifiers::NONE, Key::I);
    let joint = |joint| ChannelId::JointRotation { object: ARM, joint };
    assert!(keyed_at(&h, joint(1), 10));
    assert!(!keyed_at(&h, joint(3), 10), "the default set keys the selected joint only");

    choose(&mut h, "Whole character");
    go_to_frame(&mut h, 12);
    let undo = h.state().doc.undo_len();
    press(&mut h, Modifiers::NONE, Key::I);
    assert_eq!(h.state().doc.undo_len(), undo + 1, "one undo step");
    for j in 0..JOINTS {
        assert!(keyed_at(&h, joint(j), 12), "joint {j} keyed");
    }
    assert!(keyed_at(&h, ChannelId::ObjectTranslation(ARM), 12), "the arm's transform keyed");
    assert!(!keyed_at(&h, ChannelId::ObjectTranslation(CUBE), 12), "nothing of another object");
}

/// Record mode with *Whole character*: changing the wrist's rotation in the inspector keys
/// every joint of the arm at that frame (the others at their values now), one undo step; with
/// the default set only the wrist is keyed.
#[test]
fn record_mode_keys_the_whole_character_with_a_changed_joint() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("wrist").click();
    h.run();
    h.get_by_label("⏺ Record").click();
    h.run();
    let joint = |joint| ChannelId::JointRotation { object: ARM, joint };

    go_to_frame(&mut h, 8);
    set_value(&mut h, Role::SpinButton, "Rotation (°) X", 20.0);
    assert!(keyed_at(&h, joint(3), 8));
    assert!(!keyed_at(&h, joint(1), 8), "the default set: only the changed joint");

    choose(&mut h, "Whole character");
    go_to_frame(&mut h, 22);
    let before = h.state().doc.scene().clone();
    let elbow_now = h.state().value_now(joint(1));
    let undo = h.state().doc.undo_len();
    set_value(&mut h, Role::SpinButton, "Rotation (°) X", 40.0);
    assert_eq!(h.state().doc.undo_len(), undo + 1, "one undo step");
    for j in 0..JOINTS {
        assert!(keyed_at(&h, joint(j), 22), "joint {j} keyed with the wrist");
    }
    let scene = h.state().doc.scene();
    let index = channels::key_at(scene, joint(1), 22.0 / scene.fps).expect("elbow key");
    match (channels::key_value(scene, joint(1), index), elbow_now) {
        (Some(ChannelValue::Rotation(a)), Some(ChannelValue::Rotation(b))) => {
            assert!(a.dot(b).abs() > 1.0 - 1e-6, "the elbow keyed as it stood: {a:?} vs {b:?}");
        }
        other => panic!("rotations, got {other:?}"),
    }
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(h.state().doc.scene(), &before, "undo takes every key of the change back");
}
