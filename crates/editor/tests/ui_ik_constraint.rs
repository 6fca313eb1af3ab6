//! IK constraints in the editor (issue 19), with real clicks: the IK posing chain of the demo
//! arm's wrist kept as a constraint ("Keep as IK constraint", its target keyed at the current
//! frame where the wrist is), then baked to rotation keys ("Bake IK to keys"), each one undo
//! step.
//!
//! Tolerance: keeping the constraint re-solves the chain from its keyed pose onto the point the
//! wrist already is at, so the wrist moves by the solver's rounding only (f32 rotations through
//! four joints of a 1.6 m arm: ~1e-7 m); 1e-5 m allows a hundred times that.

mod common;

use common::{go_to_frame, harness, joint_world, press};

use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;
use keyrig_core::Animated;
use keyrig_edit::channels::{self, ChannelId};
use keyrig_editor::session::Selected;

const WRIST: usize = 3;
const FRAME: i32 = 40;

#[test]
fn keep_the_ik_chain_as_a_constraint_then_bake_it_in_one_undo_step_each() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("wrist").click();
    h.run();
    assert_eq!(h.state().session.selection.item, Some(Selected::Joint { object: 0, joint: WRIST }));
    press(&mut h, Modifiers::SHIFT, Key::I);
    go_to_frame(&mut h, FRAME);
    let wrist = joint_world(h.state(), 0, WRIST);
    let before = h.state().doc.scene().clone();
    let steps = h.state().doc.undo_len();

    h.get_by_label("Keep as IK constraint").click();
    h.run();
    let scene = h.state().doc.scene().clone();
    let constraints = &scene.objects[0].skeleton.as_ref().expect("a skeleton").ik_constraints;
    assert_eq!(constraints.len(), 1);
    let c = &constraints[0];
    assert_eq!((c.name.as_str(), c.end, c.bones, c.pole), ("IK wrist", WRIST, 2, None));
    assert_eq!(c.blend, Animated::constant(1.0));
    let target = ChannelId::IkTarget { object: 0, constraint: 0 };
    let frames: Vec<i64> =
        channels::key_times(&scene, target).iter().map(|t| (t * scene.fps).round() as i64).collect();
    assert_eq!(frames, vec![i64::from(FRAME)], "the target is keyed at the current frame");
    assert_eq!(h.state().doc.undo_len(), steps + 1);
    assert!(joint_world(h.state(), 0, WRIST).distance(wrist) < 1e-5, "the wrist stays where it was");
    h.get_by_label("IK constraint: IK wrist");

    // Baking keys elbow and forearm at every frame of the range and turns the constraint off.
    h.get_by_label("Bake IK to keys").click();
    h.run();
    let baked = h.state().doc.scene().clone();
    let skeleton = baked.objects[0].skeleton.as_ref().expect("a skeleton");
    let range = baked.frame_range;
    let frames = (range.end - range.start + 1) as usize;
    assert_eq!(skeleton.joints[1].rotation.track.len(), frames);
    assert_eq!(skeleton.joints[2].rotation.track.len(), frames);
    assert_eq!(skeleton.ik_constraints[0].blend, Animated::constant(0.0));
    assert!(joint_world(h.state(), 0, WRIST).distance(wrist) < 1e-5, "the keys hold the pose");
    assert_eq!(h.state().doc.undo_len(), steps + 2);

    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert!(h.state().doc.scene() == &scene, "one undo takes the bake back");
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert!(h.state().doc.scene() == &before, "and one more the constraint");
}

/// The constraint's target is drawn in the viewport and a drag on it moves it: in record mode a
/// key of the target at the current frame, one undo step, and the chain follows it.
#[test]
fn drag_the_ik_target_in_the_viewport_keys_it_in_one_undo_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("wrist").click();
    h.run();
    press(&mut h, Modifiers::SHIFT, Key::I);
    go_to_frame(&mut h, FRAME);
    h.get_by_label("Keep as IK constraint").click();
    h.run();
    // IK posing off: the gizmo would be shown; the target still comes first under the pointer.
    press(&mut h, Modifiers::SHIFT, Key::I);
    press(&mut h, Modifiers::NONE, Key::R);
    go_to_frame(&mut h, 60);
    let target = ChannelId::IkTarget { object: 0, constraint: 0 };
    let target_world = |h: &egui_kittest::Harness<'_, keyrig_editor::EditorApp>| {
        let Some(channels::ChannelValue::Vec3(v)) = h.state().value_now(target) else { panic!("a target") };
        h.state().object_pose_now(0).expect("a pose").world_from_object.transform_point3(v)
    };
    let before = target_world(&h);
    let steps = h.state().doc.undo_len();
    let from = common::on_screen(h.state(), before);
    let to = from + egui::vec2(-40.0, 30.0);
    let path: Vec<egui::Pos2> = (0..=8).map(|i| from + (to - from) * (i as f32 / 8.0)).collect();
    common::drag_along(&mut h, &path);

    let after = target_world(&h);
    assert!(after.distance(before) > 0.05, "the target moved: {before} → {after}");
    let on_screen = common::on_screen(h.state(), after);
    assert!(
        on_screen.distance(to) < 1.0,
        "it is under the pointer where it was let go: {on_screen:?} vs {to:?}"
    );
    let scene = h.state().doc.scene().clone();
    let frames: Vec<i64> =
        channels::key_times(&scene, target).iter().map(|t| (t * scene.fps).round() as i64).collect();
    assert_eq!(frames, vec![i64::from(FRAME), 60], "keyed at the current frame in record mode");
    assert_eq!(h.state().doc.undo_len(), steps + 1, "one drag, one undo step");
    assert!(
        joint_world(h.state(), 0, WRIST).distance(after) < joint_world(h.state(), 0, WRIST).distance(before),
        "the wrist follows the target"
    );
    assert_eq!(
        h.state().session.selection.item,
        Some(Selected::Joint { object: 0, joint: WRIST }),
        "nothing else picked"
    );
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert!(target_world(&h).distance(before) < 1e-6, "undo puts the target back");
}
