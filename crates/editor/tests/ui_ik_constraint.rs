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
use keyrig_editor::channels::{self, ChannelId};
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
