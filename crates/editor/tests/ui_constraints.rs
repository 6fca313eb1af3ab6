//! The inspector's Constraints section (docs/constraints.md), with real clicks: add an aim-at
//! constraint to the demo's Cube, point it at a joint of the arm, key its influence in record
//! mode, and remove it — each one undo step — and the evaluated Cube turns to its target.

mod common;

use common::{go_to_frame, harness, joint_world, press, set_value};

use egui::accesskit::Role;
use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use keyrig_core::channel_id::ConstraintProperty;
use keyrig_core::{AimTarget, ConstraintKind};
use keyrig_edit::channels::{self, ChannelId};
use keyrig_editor::EditorApp;

fn cube_index(h: &Harness<'_, EditorApp>) -> usize {
    h.state().doc.scene().objects.iter().position(|o| o.name == "Cube").expect("the demo's Cube")
}

/// Scrolls the inspector to the widget with `role` and `label` and clicks it.
fn click(h: &mut Harness<'_, EditorApp>, role: Role, label: &str) {
    h.get_by_role_and_label(role, label).scroll_to_me();
    h.run();
    h.get_by_role_and_label(role, label).click();
    h.run();
}

#[test]
fn add_retarget_key_and_remove_a_constraint_one_undo_step_each() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_all_by_label("Cube").next().expect("the Cube in the outliner").click();
    h.run();
    let cube = cube_index(&h);
    let before = h.state().doc.scene().clone();
    let steps = h.state().doc.undo_len();

    // Add: an aim at the first other object (the arm), one undo step.
    click(&mut h, Role::ComboBox, "Add constraint");
    h.get_by_label("Aim at").click();
    h.run();
    let scene = h.state().doc.scene().clone();
    let constraints = &scene.objects[cube].constraints;
    assert_eq!(constraints.len(), 1);
    assert_eq!(constraints[0].name, "Aim at");
    assert!(
        matches!(&constraints[0].kind, ConstraintKind::AimAt { target: AimTarget::Object(o), .. } if o == "Arm")
    );
    assert_eq!(h.state().doc.undo_len(), steps + 1);
    assert_eq!(h.state().doc.undo_label(), Some("add constraint Aim at to Cube"));

    // Retarget: the arm's wrist, from the target combo.
    click(&mut h, Role::ComboBox, "Target of Aim at");
    h.get_by_label("Arm / wrist").click();
    h.run();
    let wrist = AimTarget::Joint { object: "Arm".into(), joint: "wrist".into() };
    let scene = h.state().doc.scene().clone();
    assert!(
        matches!(&scene.objects[cube].constraints[0].kind, ConstraintKind::AimAt { target, .. } if *target == wrist)
    );
    assert_eq!(h.state().doc.undo_len(), steps + 2);
    // The evaluated Cube looks at the wrist: its −Z points there.
    let world = h.state().object_pose_now(cube).expect("the Cube").world_from_object;
    let wrist_at = joint_world(h.state(), 0, 3);
    let look = world.transform_vector3(glam::Vec3::NEG_Z).normalize();
    let to = (wrist_at - glam::Vec3::from(world.translation)).normalize();
    assert!(look.dot(to) > 1.0 - 1e-4, "the Cube looks along {look}, the wrist is along {to}");

    // Key the influence in record mode at frame 10: a key on the influence channel.
    go_to_frame(&mut h, 10);
    press(&mut h, Modifiers::NONE, Key::R);
    h.get_by_role_and_label(Role::Slider, "Influence").scroll_to_me();
    h.run();
    set_value(&mut h, Role::Slider, "Influence", 0.5);
    let influence =
        ChannelId::Constraint { object: cube, constraint: 0, property: ConstraintProperty::Influence };
    let scene = h.state().doc.scene().clone();
    assert_eq!(channels::key_count(&scene, influence), 1, "one influence key");
    assert_eq!(scene.objects[cube].constraints[0].influence.track.keys[0].value, 0.5);
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    press(&mut h, Modifiers::NONE, Key::R);

    // Remove, one undo step; undo brings it back; undo all the way gives the scene as it was.
    let steps_now = h.state().doc.undo_len();
    click(&mut h, Role::Button, "Remove");
    assert!(h.state().doc.scene().objects[cube].constraints.is_empty());
    assert_eq!(h.state().doc.undo_len(), steps_now + 1);
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(h.state().doc.scene(), &scene);
    while h.state().doc.undo_len() > steps {
        press(&mut h, Modifiers::COMMAND, Key::Z);
    }
    assert_eq!(h.state().doc.scene(), &before);
}

/// A child-of constraint switched to another parent at the current frame from the inspector:
/// the Cube does not move at the switch, the parent channel gets its Step keys, one undo step.
#[test]
fn switch_a_child_of_parent_here_without_a_pop() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_all_by_label("Cube").next().expect("the Cube in the outliner").click();
    h.run();
    let cube = cube_index(&h);
    click(&mut h, Role::ComboBox, "Add constraint");
    h.get_by_label("Child of").click();
    h.run();
    go_to_frame(&mut h, 20);
    let world =
        |h: &Harness<'_, EditorApp>| h.state().object_pose_now(cube).expect("the Cube").world_from_object;
    let before = world(&h);
    let steps = h.state().doc.undo_len();
    click(&mut h, Role::ComboBox, "Switch Child of here to");
    h.get_by_label("Arm / wrist").click();
    h.run();
    assert_eq!(h.state().doc.undo_len(), steps + 1);
    assert_eq!(h.state().doc.undo_label(), Some("switch Child of to Arm / wrist"));
    let after = world(&h);
    assert!(after.abs_diff_eq(before, 1e-4), "no pop: {before:?} → {after:?}");
    let scene = h.state().doc.scene().clone();
    let ConstraintKind::ChildOf { parents, parent } = &scene.objects[cube].constraints[0].kind else {
        panic!("a child of")
    };
    assert_eq!(parents.len(), 2);
    let keys: Vec<(i64, f32)> =
        parent.track.keys.iter().map(|k| ((k.time * scene.fps).round() as i64, k.value)).collect();
    assert_eq!(keys, vec![(0, 0.0), (20, 1.0)]);
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert!(world(&h).abs_diff_eq(before, 1e-6), "undo takes the switch back");
}
