//! Cycles in the inspector: the channel of the selected key gets "Before keys" and "After keys"
//! combo boxes; choosing a behaviour is one undoable edit, and the evaluator (so the viewport,
//! the curve view and `keyrig sample`) repeats the keys from then on.

mod common;

use common::{harness, press};

use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;
use keyrig_core::{Cycle, Cycles};
use keyrig_edit::channels::{self, ChannelId, ChannelValue};
use keyrig_editor::EditorApp;

const CUBE_ROTATION: ChannelId = ChannelId::ObjectRotation(1);

fn cube_rotation_at(app: &EditorApp, seconds: f64) -> glam::Quat {
    let scene = app.doc.scene();
    match keyrig_editor::eval::channel_value(scene, CUBE_ROTATION, seconds, &Default::default()) {
        Some(ChannelValue::Rotation(q)) => q,
        other => panic!("cube rotation is a rotation, got {other:?}"),
    }
}

#[test]
fn choosing_repeat_after_the_keys_is_an_undoable_edit() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    // The demo cube turns once about Y over its 3 s of keys (frames 0–90), then holds.
    h.get_by_label("key Cube rotation frame 30").click();
    h.run();
    assert_eq!(channels::cycles(h.state().doc.scene(), CUBE_ROTATION), Some(Cycles::HOLD));
    let held = cube_rotation_at(h.state(), 4.0);

    h.get_by_label("After keys").scroll_to_me();
    h.run();
    h.get_by_label("After keys").click();
    h.run();
    h.get_by_label("Repeat with offset").click();
    h.run();
    assert_eq!(
        channels::cycles(h.state().doc.scene(), CUBE_ROTATION),
        Some(Cycles::new(Cycle::Hold, Cycle::RepeatOffset))
    );
    assert!(h.state().doc.undo_label().is_some_and(|l| l.contains("Repeat with offset after keys")));
    // One second past the keys the cube turns on (a full turn per cycle: as at 1 s).
    let on = cube_rotation_at(h.state(), 4.0);
    assert!(on.angle_between(held) > 0.1, "the cube keeps turning: {on:?} vs {held:?}");
    assert!(on.angle_between(cube_rotation_at(h.state(), 1.0)) < 1e-4);

    h.get_by_label("Before keys").click();
    h.run();
    h.get_by_label("Ping-pong").click();
    h.run();
    assert_eq!(
        channels::cycles(h.state().doc.scene(), CUBE_ROTATION),
        Some(Cycles::new(Cycle::PingPong, Cycle::RepeatOffset))
    );

    press(&mut h, Modifiers::COMMAND, Key::Z);
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(channels::cycles(h.state().doc.scene(), CUBE_ROTATION), Some(Cycles::HOLD));
    assert!(cube_rotation_at(h.state(), 4.0).angle_between(held) < 1e-6);
}
