//! Posing a rig as a user does: jumping between keys with the Up and Down arrows, copying a
//! pose with Alt+C and pasting it (Alt+V) at another frame or mirrored (Alt+Shift+V) onto the
//! other side of a rig, and Ctrl+drag box selection of joints in the viewport.

mod common;

use common::{go_to_frame, harness, press};

use egui::{Event, Key, Modifiers, Pos2};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use glam::{Quat, Vec3};
use keyrig_core::{Key as SceneKey, Object, RawTrack, Scene, Skeleton};
use keyrig_edit::channels::{self, ChannelId, ChannelValue};
use keyrig_editor::camera::Projection;
use keyrig_editor::eval::ObjectPose;
use keyrig_editor::session::Selected;
use keyrig_editor::EditorApp;

fn frame(h: &Harness<'_, EditorApp>) -> i32 {
    h.state().session.playback.whole_frame()
}

#[test]
fn up_and_down_jump_to_the_selections_next_and_previous_key() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("elbow").click();
    h.run();
    let scene = h.state().doc.scene();
    let elbow = ChannelId::JointRotation { object: 0, joint: 1 };
    let frames: Vec<i32> =
        channels::key_times(scene, elbow).iter().map(|t| (t * scene.fps).round() as i32).collect();
    assert!(frames.len() >= 3, "{frames:?}");
    go_to_frame(&mut h, 0);
    for &expected in frames.iter().filter(|&&f| f > 0) {
        press(&mut h, Modifiers::NONE, Key::ArrowUp);
        assert_eq!(frame(&h), expected);
    }
    press(&mut h, Modifiers::NONE, Key::ArrowUp);
    assert_eq!(frame(&h), *frames.last().unwrap(), "no key after the last: stays");
    assert!(h.state().status().is_some_and(|s| s.text.starts_with("No key after")));
    press(&mut h, Modifiers::NONE, Key::ArrowDown);
    assert_eq!(frame(&h), frames[frames.len() - 2]);
}

#[test]
fn a_copied_pose_pastes_as_keys_at_another_frame_in_one_undo_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    go_to_frame(&mut h, 30);
    h.get_by_label("Arm").click();
    h.run();
    let at_30: Vec<Option<ChannelValue>> =
        (0..4).map(|joint| h.state().value_now(ChannelId::JointRotation { object: 0, joint })).collect();
    press(&mut h, Modifiers::ALT, Key::C);
    assert!(h.state().status().is_some_and(|s| s.text.starts_with("Copied the pose")));
    press(&mut h, Modifiers::NONE, Key::R);
    go_to_frame(&mut h, 70);
    let steps = h.state().doc.undo_len();
    press(&mut h, Modifiers::ALT, Key::V);
    assert_eq!(h.state().doc.undo_len(), steps + 1, "one step");
    assert_eq!(h.state().doc.undo_label(), Some("paste pose at frame 70"));
    for (joint, before) in at_30.iter().enumerate() {
        let id = ChannelId::JointRotation { object: 0, joint };
        let (Some(ChannelValue::Rotation(a)), Some(ChannelValue::Rotation(b))) =
            (before, h.state().value_now(id))
        else {
            panic!("rotations")
        };
        assert!(a.dot(b).abs() > 1.0 - 1e-6, "joint {joint}: {a:?} → {b:?}");
        let times = channels::key_times(h.state().doc.scene(), id);
        assert!(times.iter().any(|t| (t * 30.0 - 70.0).abs() < 1e-6), "joint {joint} keyed at 70");
    }
}

/// A rig with a spine and two arms named by side.
fn two_armed_scene() -> Scene {
    let joint = |name: &str, parent: Option<usize>, at: Vec3| {
        keyrig_core::Joint::new(name, parent, at, Quat::IDENTITY)
    };
    let mut skeleton = Skeleton {
        joints: vec![
            joint("spine", None, Vec3::Y),
            joint("arm.L", Some(0), Vec3::new(0.3, 0.5, 0.0)),
            joint("arm.R", Some(0), Vec3::new(-0.3, 0.5, 0.0)),
        ],
        root_translation: keyrig_core::Animated::constant(Vec3::ZERO),
        ik_constraints: Vec::new(),
    };
    let mut rig = Object::new("Rig");
    let lift = Quat::from_rotation_z(0.8) * Quat::from_rotation_y(0.3);
    skeleton.joints[1].rotation.track =
        RawTrack::new(vec![SceneKey::new(0.0, lift), SceneKey::new(1.0, Quat::IDENTITY)]);
    rig.skeleton = Some(skeleton);
    Scene { objects: vec![rig], ..Scene::default() }
}

#[test]
fn paste_mirrored_puts_the_left_arms_pose_on_the_right_arm() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("rig.ron");
    keyrig_io::scene_file::save(&file, &two_armed_scene()).expect("save");
    let mut h = harness(dir.path(), Some(file));
    h.get_by_label("arm.L").click();
    h.run();
    let Some(ChannelValue::Rotation(left)) =
        h.state().value_now(ChannelId::JointRotation { object: 0, joint: 1 })
    else {
        panic!("a rotation")
    };
    press(&mut h, Modifiers::ALT, Key::C);
    press(&mut h, Modifiers::ALT.plus(Modifiers::SHIFT), Key::V);
    let right = h.state().doc.scene().objects[0].skeleton.as_ref().unwrap().joints[2].rotation.value;
    let mirrored = Quat::from_xyzw(left.x, -left.y, -left.z, left.w);
    assert!(right.dot(mirrored).abs() > 1.0 - 1e-6, "the right arm, mirrored: {right:?} vs {mirrored:?}");
    assert_eq!(h.state().doc.undo_label(), Some("paste pose mirrored"));
}

#[test]
fn ctrl_drag_in_the_viewport_box_selects_joints() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let app = h.state();
    let rect = app.viewport_rect().expect("laid out");
    let projection = Projection::new(&app.view.camera, rect);
    let pose: ObjectPose = app.object_pose_now(0).expect("the arm");
    let on_screen: Vec<Pos2> = (0..4)
        .map(|j| {
            let at: Vec3 = (pose.world_from_object * pose.object_from_joint[j]).translation.into();
            projection.project(at).expect("in view")
        })
        .collect();
    // A box around the elbow and the forearm only.
    let inside = [on_screen[1], on_screen[2]];
    let min = Pos2::new(inside[0].x.min(inside[1].x) - 6.0, inside[0].y.min(inside[1].y) - 6.0);
    let max = Pos2::new(inside[0].x.max(inside[1].x) + 6.0, inside[0].y.max(inside[1].y) + 6.0);
    for (j, p) in on_screen.iter().enumerate() {
        let boxed = p.x >= min.x && p.x <= max.x && p.y >= min.y && p.y <= max.y;
        assert_eq!(boxed, j == 1 || j == 2, "the box holds joints 1 and 2 only (joint {j} at {p:?})");
    }
    let camera = h.state().view.camera;
    let ctrl = Modifiers::COMMAND;
    h.input_mut().modifiers = ctrl;
    h.event(Event::PointerMoved(min));
    h.event(Event::PointerButton {
        pos: min,
        button: egui::PointerButton::Primary,
        pressed: true,
        modifiers: ctrl,
    });
    for i in 1..=8 {
        h.event(Event::PointerMoved(min + (max - min) * (i as f32 / 8.0)));
    }
    h.event(Event::PointerButton {
        pos: max,
        button: egui::PointerButton::Primary,
        pressed: false,
        modifiers: ctrl,
    });
    h.run();
    let selected: Vec<Selected> = h.state().session.selection.items().collect();
    assert_eq!(selected.len(), 2, "{selected:?}");
    assert!(selected.contains(&Selected::Joint { object: 0, joint: 1 }));
    assert!(selected.contains(&Selected::Joint { object: 0, joint: 2 }));
    assert_eq!(h.state().view.camera, camera, "a box drag does not orbit");
}

/// World positions of every joint of object 0 now.
fn joint_positions(h: &Harness<'_, EditorApp>) -> (glam::Affine3A, Vec<Vec3>) {
    let pose = h.state().object_pose_now(0).expect("the character");
    let world = pose.world_from_object;
    (world, pose.object_from_joint.iter().map(|f| (world * *f).translation.into()).collect())
}

/// Copies the whole character's pose at frame `copy` (outliner click, Alt+C), pastes it
/// mirrored at frame `paste` (Alt+Shift+V), and compares the world positions of the joints with
/// the reflection of the copied ones across the character's plane of symmetry, which the test
/// finds on its own: through the midpoints of the rest positions of the left/right pairs
/// listed here by hand, normal to their mean difference.
fn mirrored_paste_is_a_mirror_image(
    model: &str,
    pairs: &[(&str, &str)],
    centre: &[&str],
    copy: i32,
    paste: i32,
) {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), Some(common::corpus(model)));
    h.state_mut().wait_for_background_work();
    h.run();
    let scene = h.state().doc.scene().clone();
    let skeleton = scene.objects[0].skeleton.as_ref().expect("a skeleton");
    let find =
        |name: &str| skeleton.joints.iter().position(|j| j.name == name).unwrap_or_else(|| panic!("{name}"));
    let rest = keyrig_skin::RestSkeleton::from_scene(skeleton).expect("rest skeleton");
    let (mut sum, mut mids) = (Vec3::ZERO, Vec::new());
    for (left, right) in pairs {
        let (l, r) = (rest.rest_position(find(left)), rest.rest_position(find(right)));
        sum += l - r;
        mids.push((l + r) * 0.5);
    }
    let normal = sum.normalize();
    let offset = mids.iter().map(|m| normal.dot(*m)).sum::<f32>() / mids.len() as f32;
    let reflect = |p: Vec3| p - 2.0 * (normal.dot(p) - offset) * normal;
    let size = {
        let ps: Vec<Vec3> = (0..rest.len()).map(|j| rest.rest_position(j)).collect();
        let lo = ps.iter().fold(Vec3::INFINITY, |a, p| a.min(*p));
        let hi = ps.iter().fold(Vec3::NEG_INFINITY, |a, p| a.max(*p));
        (hi - lo).length()
    };

    h.get_by_label(scene.objects[0].name.as_str()).click();
    h.run();
    go_to_frame(&mut h, copy);
    let (world_copied, copied) = joint_positions(&h);
    press(&mut h, Modifiers::ALT, Key::C);
    go_to_frame(&mut h, paste);
    let (_, before) = joint_positions(&h);
    press(&mut h, Modifiers::ALT.plus(Modifiers::SHIFT), Key::V);
    let status = h.state().status().expect("a message").text.clone();
    assert!(status.contains("mirrored"), "{status}");
    for (left, right) in pairs {
        assert!(
            status.contains(&format!("{left} ↔ {right}")),
            "the status names the pair {left} ↔ {right}: {status}"
        );
    }
    let (world, pasted) = joint_positions(&h);
    let object_space = |w: glam::Affine3A, p: Vec3| -> Vec3 { w.inverse().transform_point3(p) };
    let mut worst: f32 = 0.0;
    let mut check = |from: usize, to: usize| {
        let expected = world.transform_point3(reflect(object_space(world_copied, copied[from])));
        let error = pasted[to].distance(expected);
        worst = worst.max(error / size);
        assert!(
            error < 0.002 * size,
            "{model}: joint {} at {} should be the mirror image of {} at {} (error {error}, size {size})",
            skeleton.joints[to].name,
            pasted[to],
            skeleton.joints[from].name,
            expected
        );
    };
    for (left, right) in pairs {
        check(find(left), find(right));
        check(find(right), find(left));
    }
    for name in centre {
        check(find(name), find(name));
    }
    let moved = before.iter().zip(&pasted).map(|(a, b)| a.distance(*b)).fold(0.0f32, f32::max);
    assert!(moved > 0.05 * size, "{model}: the paste changed the pose (moved {moved} of {size})");
    eprintln!("{model}: worst error {worst:.5} of the size; {status}");
}

#[test]
fn cesium_man_pasted_mirrored_is_the_mirror_image_of_the_copied_walk() {
    mirrored_paste_is_a_mirror_image(
        "gltf/CesiumMan/CesiumMan.glb",
        &[
            ("Skeleton_arm_joint_L__4_", "Skeleton_arm_joint_R"),
            ("Skeleton_arm_joint_L__3_", "Skeleton_arm_joint_R__2_"),
            ("Skeleton_arm_joint_L__2_", "Skeleton_arm_joint_R__3_"),
            ("leg_joint_L_1", "leg_joint_R_1"),
            ("leg_joint_L_2", "leg_joint_R_2"),
            ("leg_joint_L_3", "leg_joint_R_3"),
            ("leg_joint_L_5", "leg_joint_R_5"),
        ],
        &["Skeleton_torso_joint_1", "Skeleton_torso_joint_2", "torso_joint_3", "Skeleton_neck_joint_2"],
        15,
        45,
    );
}

#[test]
fn the_fox_pasted_mirrored_is_the_mirror_image_of_the_copied_pose() {
    mirrored_paste_is_a_mirror_image(
        "gltf/Fox/Fox.glb",
        &[
            ("b_LeftUpperArm_09", "b_RightUpperArm_06"),
            ("b_LeftForeArm_010", "b_RightForeArm_07"),
            ("b_LeftHand_011", "b_RightHand_08"),
            ("b_LeftLeg01_015", "b_RightLeg01_019"),
            ("b_LeftLeg02_016", "b_RightLeg02_020"),
            ("b_LeftFoot01_017", "b_RightFoot01_021"),
            ("b_LeftFoot02_018", "b_RightFoot02_022"),
        ],
        &["b_Hip_01", "b_Spine01_02", "b_Spine02_03", "b_Neck_04", "b_Head_05", "b_Tail02_013"],
        10,
        40,
    );
}

/// Types `text` into the inspector's Pose name field.
fn type_pose_name(h: &mut Harness<'_, EditorApp>, text: &str) {
    h.get_by_label("Pose name").click();
    h.run();
    h.event(Event::Text(text.to_owned()));
    h.run();
}

/// The pose library: a named pose saved from the left arm at frame 0 is kept in the scene file,
/// applied to the selection at another frame, applied mirrored onto the right arm (the
/// mirrored paste's path), renamed and deleted; each one undo step.
#[test]
fn the_pose_library_saves_applies_mirrors_renames_and_deletes_poses() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("rig.ron");
    keyrig_io::scene_file::save(&file, &two_armed_scene()).expect("save");
    let mut h = harness(dir.path(), Some(file.clone()));
    h.get_by_label("arm.L").click();
    h.run();
    let left_id = ChannelId::JointRotation { object: 0, joint: 1 };
    let Some(ChannelValue::Rotation(lift)) = h.state().value_now(left_id) else { panic!("a rotation") };
    let steps = h.state().doc.undo_len();
    type_pose_name(&mut h, "Lift");
    h.get_by_label("Add pose").click();
    h.run();
    let poses = h.state().doc.scene().poses.clone();
    assert_eq!(poses.len(), 1);
    assert_eq!(poses[0].name, "Lift");
    assert_eq!(poses[0].values[0].channel, "object/Rig/joint/arm.L/rotation");
    assert_eq!(h.state().doc.undo_len(), steps + 1);
    assert_eq!(h.state().doc.undo_label(), Some("add pose Lift to the library"));

    // Saved with the scene, and read back.
    h.state_mut().save_to(file.clone());
    let text = std::fs::read_to_string(&file).expect("saved");
    assert!(text.contains("poses:") && text.contains("\"Lift\""), "{text}");
    assert_eq!(keyrig_io::scene_file::load(&file).expect("reads back").poses, poses);

    // Applied at frame 30, where the arm has turned back: the arm takes the pose again.
    go_to_frame(&mut h, 30);
    let Some(ChannelValue::Rotation(at_30)) = h.state().value_now(left_id) else { panic!("a rotation") };
    assert!(at_30.dot(lift).abs() < 0.99, "the arm moved since frame 0");
    h.get_by_label("Apply").click();
    h.run();
    let Some(ChannelValue::Rotation(applied)) = h.state().value_now(left_id) else { panic!("a rotation") };
    assert!(applied.dot(lift).abs() > 1.0 - 1e-6, "{applied:?} vs {lift:?}");
    assert!(h.state().status().is_some_and(|s| s.text.starts_with("Applied \"Lift\" on 1 channel")));

    // Mirrored onto the right arm, with the whole character selected.
    h.get_by_label("Rig").click();
    h.run();
    let steps = h.state().doc.undo_len();
    h.get_by_label("Apply mirrored").click();
    h.run();
    let right = h.state().doc.scene().objects[0].skeleton.as_ref().unwrap().joints[2].rotation.value;
    let mirrored = Quat::from_xyzw(lift.x, -lift.y, -lift.z, lift.w);
    assert!(right.dot(mirrored).abs() > 1.0 - 1e-6, "the right arm, mirrored: {right:?} vs {mirrored:?}");
    assert_eq!(h.state().doc.undo_len(), steps + 1, "one step");
    assert_eq!(h.state().doc.undo_label(), Some("apply pose Lift mirrored"));

    // Renamed, deleted, and the delete undone.
    type_pose_name(&mut h, "Reach");
    h.get_by_label("Rename").click();
    h.run();
    assert_eq!(h.state().doc.scene().poses[0].name, "Reach");
    assert_eq!(h.state().doc.undo_label(), Some("rename pose Lift to Reach"));
    h.get_by_label("Delete pose").click();
    h.run();
    assert!(h.state().doc.scene().poses.is_empty());
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(h.state().doc.scene().poses[0].name, "Reach");
}
