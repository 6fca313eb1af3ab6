//! IK posing driven as an animator does it (issue 19, part 1): select the demo arm's wrist,
//! turn on IK posing (Shift+I or the toolbar's IK), press on the handle drawn at the wrist and
//! drag it with real pointer events. The wrist must land where the pointer's view ray meets the
//! plane through the wrist that faces the camera; in record mode the joints of the chain get
//! rotation keys at the current frame and one undo step restores the scene exactly; outside
//! record mode nothing is keyed. Chains the solvers refuse are refused with their message in the
//! status bar.
//!
//! The demo arm is shoulder → elbow → forearm → wrist, 0.400395 m per bone. The default chain of
//! the wrist is two bones up: elbow → forearm → wrist (the forearm joint only twists in the
//! demo, so that chain starts straight and bends the way of the elbow joint's local +Y). A chain
//! of three bones reaches the shoulder and is solved by FABRIK.
//!
//! Tolerances: the wrist is placed by f32 rotations (the solvers round once from f64, docs/ik.md)
//! through four joint transforms, and the pointer's target is found and the wrist projected with
//! f32 matrices, so a few f32 ulps of the arm's 1–3 m coordinates: about 1e-6 m, 1e-3 point on
//! screen at this zoom (about 200 points per metre). Measured: 6e-5 point and 1.3e-7 m. The
//! checks allow 0.01 point on screen and 1e-5 m off the drag plane, ten times the estimate and
//! far below anything an animator could see; a solve that missed by a pixel fails them.

mod common;

use common::{drag_along, go_to_frame, harness, joint_world, on_screen, press, set_value};

use egui::accesskit::Role;
use egui::{Key, Modifiers, Pos2};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use glam::{Quat, Vec3};
use keyrig_core::{Joint, Object, Scene, Skeleton};
use keyrig_edit::channels::{self, ChannelId};
use keyrig_editor::camera::OrbitCamera as _;
use keyrig_editor::session::Selected;
use keyrig_editor::EditorApp;

const SHOULDER: usize = 0;
const ELBOW: usize = 1;
const FOREARM: usize = 2;
const WRIST: usize = 3;

/// The demo's frame 40: no joint has a key there; the elbow is bent 90°, the forearm twisted.
const FRAME: i32 = 40;

/// Screen points allowed between where the wrist lands and where the pointer was released.
const SCREEN_TOLERANCE: f32 = 0.01;
/// Metres the wrist may leave the drag plane.
const PLANE_TOLERANCE: f32 = 1e-5;

fn rotation(joint: usize) -> ChannelId {
    ChannelId::JointRotation { object: 0, joint }
}

fn key_frames(app: &EditorApp, joint: usize) -> Vec<i64> {
    let scene = app.doc.scene();
    channels::key_times(scene, rotation(joint)).iter().map(|t| (t * scene.fps).round() as i64).collect()
}

fn select_joint(h: &mut Harness<'_, EditorApp>, name: &str, joint: usize) {
    h.get_by_label(name).click();
    h.run();
    assert_eq!(h.state().session.selection.item, Some(Selected::Joint { object: 0, joint }));
}

/// The camera's view direction now.
fn forward(app: &EditorApp) -> Vec3 {
    (app.view.camera.target - app.view.camera.eye()).normalize()
}

/// Presses on the wrist's handle and drags it by `by` points in ten steps; returns where the
/// pointer was released.
fn drag_wrist_by(h: &mut Harness<'_, EditorApp>, by: egui::Vec2) -> Pos2 {
    let start = on_screen(h.state(), joint_world(h.state(), 0, WRIST));
    let path: Vec<Pos2> = (0..=10).map(|i| start + by * (i as f32 / 10.0)).collect();
    drag_along(h, &path);
    start + by
}

/// A drag on screen from the wrist towards the elbow's place on screen (`fraction` of the way)
/// and `sideways` points across: a target the two-bone chain can reach.
fn towards_elbow(app: &EditorApp, fraction: f32, sideways: f32) -> egui::Vec2 {
    let wrist = on_screen(app, joint_world(app, 0, WRIST));
    let elbow = on_screen(app, joint_world(app, 0, ELBOW));
    let along = elbow - wrist;
    along * fraction + egui::vec2(-along.y, along.x).normalized() * sideways
}

/// The wrist is under the pointer's release point and in the plane through where it was that
/// faces the camera.
fn assert_wrist_followed(app: &EditorApp, released: Pos2, wrist_before: Vec3, view: Vec3) {
    let wrist = joint_world(app, 0, WRIST);
    let landed = on_screen(app, wrist);
    assert!(
        (landed - released).length() < SCREEN_TOLERANCE,
        "the wrist lands under the pointer: at {landed:?}, released at {released:?}"
    );
    let off_plane = (wrist - wrist_before).dot(view);
    assert!(off_plane.abs() < PLANE_TOLERANCE, "the wrist moves in the view plane (off by {off_plane} m)");
    assert!(wrist.distance(wrist_before) > 0.05, "the drag moved the wrist ({wrist_before:?} → {wrist:?})");
}

#[test]
fn an_ik_drag_in_record_mode_keys_the_chain_at_the_frame_in_one_undo_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    select_joint(&mut h, "wrist", WRIST);
    press(&mut h, Modifiers::SHIFT, Key::I);
    assert!(h.state().session.ik.enabled, "Shift+I turns IK posing on");
    let status = h.state().status().expect("a message").text.clone();
    assert!(status.contains("elbow → forearm → wrist (two-bone solver)"), "{status}");
    assert!(key_frames(h.state(), WRIST).is_empty(), "Shift+I is not I: nothing keyed");
    press(&mut h, Modifiers::NONE, Key::R);
    go_to_frame(&mut h, FRAME);

    let before = h.state().doc.scene().clone();
    let steps = h.state().doc.undo_len();
    let keys_before: Vec<Vec<i64>> = (0..4).map(|j| key_frames(h.state(), j)).collect();
    let wrist_before = joint_world(h.state(), 0, WRIST);
    let (camera, view) = (h.state().view.camera, forward(h.state()));
    let by = towards_elbow(h.state(), 0.35, 20.0);
    let released = drag_wrist_by(&mut h, by);

    assert_eq!(h.state().view.camera, camera, "a drag on the IK handle does not orbit the camera");
    assert!(h.state().ring_drag().is_none(), "the handle replaces the gizmo: no ring was grabbed");
    assert_wrist_followed(h.state(), released, wrist_before, view);
    for joint in [ELBOW, FOREARM] {
        let mut expected = keys_before[joint].clone();
        expected.push(i64::from(FRAME));
        expected.sort_unstable();
        assert_eq!(key_frames(h.state(), joint), expected, "joint {joint} keyed at frame {FRAME}");
    }
    assert_eq!(key_frames(h.state(), SHOULDER), keys_before[SHOULDER], "the shoulder is above the chain");
    assert_eq!(key_frames(h.state(), WRIST), keys_before[WRIST], "the end joint keeps its own rotation");
    assert_eq!(h.state().doc.undo_len(), steps + 1, "the whole drag is one undo step");
    assert_eq!(h.state().doc.undo_label(), Some("IK key elbow → forearm → wrist at frame 40"));

    // The keys hold the pose: away and back, the wrist is where the drag left it.
    let posed = joint_world(h.state(), 0, WRIST);
    go_to_frame(&mut h, 0);
    go_to_frame(&mut h, FRAME);
    assert!(joint_world(h.state(), 0, WRIST).distance(posed) < 1e-5, "the keys play back the pose");

    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert!(h.state().doc.scene() == &before, "one undo restores the scene exactly");
    assert!(joint_world(h.state(), 0, WRIST).distance(wrist_before) < 1e-6);
}

#[test]
fn an_ik_drag_outside_record_mode_poses_the_chain_without_keys_until_i() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    select_joint(&mut h, "wrist", WRIST);
    h.get_by_label("IK").click();
    h.run();
    assert!(h.state().session.ik.enabled, "the toolbar's IK turns IK posing on");
    assert!(!h.state().session.record);
    go_to_frame(&mut h, FRAME);
    let before = h.state().doc.scene().clone();
    let steps = h.state().doc.undo_len();
    let wrist_before = joint_world(h.state(), 0, WRIST);
    let view = forward(h.state());
    let by = towards_elbow(h.state(), 0.3, -25.0);
    let released = drag_wrist_by(&mut h, by);

    assert_wrist_followed(h.state(), released, wrist_before, view);
    assert!(h.state().doc.scene() == &before, "no key and no change to the document");
    assert_eq!(h.state().doc.undo_len(), steps);
    let overrides = &h.state().session.overrides;
    assert!(overrides.contains_key(&rotation(ELBOW)) && overrides.contains_key(&rotation(FOREARM)));
    assert!(h.state().status().is_some_and(|s| s.text == "IK: posed elbow, forearm (press I to key)"));

    // I keys the pose: the selected wrist and, in IK posing, its chain.
    let posed = joint_world(h.state(), 0, WRIST);
    press(&mut h, Modifiers::NONE, Key::I);
    for joint in [ELBOW, FOREARM, WRIST] {
        assert!(key_frames(h.state(), joint).contains(&i64::from(FRAME)), "joint {joint} keyed by I");
    }
    go_to_frame(&mut h, 0);
    go_to_frame(&mut h, FRAME);
    assert!(joint_world(h.state(), 0, WRIST).distance(posed) < 1e-5, "the keys hold the pose");
}

/// A chain of three bones (chosen in the inspector) reaches the shoulder and is solved by
/// FABRIK; record mode keys shoulder, elbow and forearm.
#[test]
fn a_longer_chain_set_in_the_inspector_drags_with_fabrik() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    select_joint(&mut h, "wrist", WRIST);
    press(&mut h, Modifiers::SHIFT, Key::I);
    set_value(&mut h, Role::SpinButton, "IK chain (bones)", 3.0);
    assert_eq!(h.state().session.ik.chain_bones(0, WRIST), 3);
    h.get_by_label("shoulder → elbow → forearm → wrist · FABRIK");
    press(&mut h, Modifiers::NONE, Key::R);
    go_to_frame(&mut h, FRAME);
    let before = h.state().doc.scene().clone();
    let wrist_before = joint_world(h.state(), 0, WRIST);
    let view = forward(h.state());
    let shoulder = on_screen(h.state(), joint_world(h.state(), 0, SHOULDER));
    let wrist = on_screen(h.state(), joint_world(h.state(), 0, WRIST));
    let released = drag_wrist_by(&mut h, (shoulder - wrist) * 0.3 + egui::vec2(0.0, -30.0));

    assert_wrist_followed(h.state(), released, wrist_before, view);
    for joint in [SHOULDER, ELBOW, FOREARM] {
        assert!(key_frames(h.state(), joint).contains(&i64::from(FRAME)), "joint {joint} keyed");
    }
    assert!(!key_frames(h.state(), WRIST).contains(&i64::from(FRAME)));
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert!(h.state().doc.scene() == &before, "one undo restores the scene exactly");
}

/// Which way the elbow → forearm → wrist chain bends: the forearm joint's offset from the
/// elbow → wrist line, unit.
fn bend_side(app: &EditorApp) -> Vec3 {
    let (elbow, forearm, wrist) =
        (joint_world(app, 0, ELBOW), joint_world(app, 0, FOREARM), joint_world(app, 0, WRIST));
    let axis = (wrist - elbow).normalize();
    let offset = forearm - elbow;
    (offset - axis * offset.dot(axis)).normalize()
}

/// The bend side is the pose's, and it is kept from drag to drag. At frame 0 the demo arm is
/// straight along +X; the forearm is first bent 40° about +Z with the inspector, so the forearm
/// joint sits below the elbow → wrist line (−Y), the opposite of the side a chain that never
/// bent takes (its root's +Y). A drag keeps that side; a drag out of reach leaves the chain
/// straight; the next drag back in bends it to the same side again (the stored pole), not to
/// +Y.
#[test]
fn consecutive_drags_keep_the_bend_side() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    go_to_frame(&mut h, 0);
    select_joint(&mut h, "forearm", FOREARM);
    set_value(&mut h, Role::SpinButton, "Rotation (°) Z", 40.0);
    assert!(bend_side(h.state()).dot(Vec3::NEG_Y) > 0.9, "bent down: {:?}", bend_side(h.state()));
    select_joint(&mut h, "wrist", WRIST);
    press(&mut h, Modifiers::SHIFT, Key::I);

    let inward = towards_elbow(h.state(), 0.2, 0.0);
    let start = on_screen(h.state(), joint_world(h.state(), 0, WRIST));
    drag_wrist_by(&mut h, inward);
    let bent = bend_side(h.state());
    assert!(bent.dot(Vec3::NEG_Y) > 0.9, "the drag keeps the pose's bend side: {bent:?}");

    // Out of reach: the chain ends straight, pointing at the pointer.
    drag_wrist_by(&mut h, -inward * 4.0);
    let (elbow, forearm, wrist) = (
        joint_world(h.state(), 0, ELBOW),
        joint_world(h.state(), 0, FOREARM),
        joint_world(h.state(), 0, WRIST),
    );
    let straightness = (forearm - elbow).normalize().dot((wrist - forearm).normalize());
    assert!(straightness > 1.0 - 1e-5, "out of reach the chain is straight: cos {straightness}");

    // Back to the first place: the same bend side.
    let here = on_screen(h.state(), joint_world(h.state(), 0, WRIST));
    drag_wrist_by(&mut h, (start + inward) - here);
    let again = bend_side(h.state());
    assert!(again.dot(bent) > 0.99, "the forearm joint bends to the same side: {bent:?} vs {again:?}");
}

/// The elbow has one joint above it: no two-bone chain ends there. Turning IK posing on says
/// so in the status bar, and a press on its handle repeats it without changing anything.
#[test]
fn a_joint_without_two_joints_above_it_is_refused_in_the_status_bar() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    select_joint(&mut h, "elbow", ELBOW);
    press(&mut h, Modifiers::SHIFT, Key::I);
    let expected = "IK on elbow: an IK chain needs at least 2 bones (3 joints); this one has 2 joint(s)";
    let status = h.state().status().expect("a message").clone();
    assert!(status.is_error && status.text == expected, "{status:?}");
    let before = h.state().doc.scene().clone();
    let camera = h.state().view.camera;
    let elbow = on_screen(h.state(), joint_world(h.state(), 0, ELBOW));
    drag_along(&mut h, &[elbow, elbow + egui::vec2(60.0, -40.0)]);
    let again = h.state().status().expect("the press explains").clone();
    assert!(again.is_error && again.text == expected && again.at > status.at, "{again:?}");
    assert!(h.state().doc.scene() == &before);
    assert_eq!(h.state().view.camera, camera, "the press on the handle does not orbit");
}

/// A rig whose "hand" joint sits exactly on its parent "palm": a zero-length bone.
fn zero_bone_scene() -> Scene {
    let joints = vec![
        Joint::new("upper", None, Vec3::ZERO, Quat::IDENTITY),
        Joint::new("palm", Some(0), Vec3::new(0.5, 0.0, 0.0), Quat::IDENTITY),
        Joint::new("hand", Some(1), Vec3::ZERO, Quat::IDENTITY),
    ];
    let mut rig = Object::new("Rig");
    rig.skeleton = Some(Skeleton::new(joints));
    Scene { objects: vec![rig], ..Scene::default() }
}

#[test]
fn a_zero_length_bone_is_refused_with_the_solvers_message() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("rig.ron");
    keyrig_io::scene_file::save(&file, &zero_bone_scene()).expect("save");
    let mut h = harness(dir.path(), Some(file));
    select_joint(&mut h, "hand", 2);
    press(&mut h, Modifiers::SHIFT, Key::I);
    let status = h.state().status().expect("a message").clone();
    assert!(status.is_error, "{status:?}");
    assert_eq!(
        status.text,
        "IK chain upper → palm → hand: IK chain joint 2 sits on its parent joint 1: a zero-length bone \
         has no direction to aim"
    );
    let before = h.state().doc.scene().clone();
    press(&mut h, Modifiers::NONE, Key::R);
    let hand = on_screen(h.state(), joint_world(h.state(), 0, 2));
    drag_along(&mut h, &[hand, hand + egui::vec2(-40.0, 30.0)]);
    assert!(h.state().status().is_some_and(|s| s.is_error && s.text.contains("zero-length")));
    assert!(h.state().doc.scene() == &before, "nothing is keyed");
}

/// The shortcut list (F12) and the Edit menu list IK posing with Shift+I.
#[test]
fn ik_posing_is_in_the_shortcut_list() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    press(&mut h, Modifiers::NONE, Key::F12);
    assert!(h.state().view.show_help);
    h.get_by_label("IK posing");
    h.get_by_label("Shift+I");
}

/// Typing a capital I in a name field types it: Shift+I waits while a text field has the
/// keyboard.
#[test]
fn a_capital_i_typed_in_a_name_field_does_not_toggle_ik_posing() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    select_joint(&mut h, "wrist", WRIST);
    press(&mut h, Modifiers::COMMAND, Key::R);
    assert!(h.state().panels().outliner.renaming().is_some(), "Ctrl+R opens the name field");
    h.key_press_modifiers(Modifiers::COMMAND, Key::A);
    h.run();
    h.input_mut().modifiers = Modifiers::SHIFT;
    h.event(egui::Event::Key {
        key: Key::I,
        physical_key: None,
        pressed: true,
        repeat: false,
        modifiers: Modifiers::SHIFT,
    });
    h.event(egui::Event::Text("I".to_owned()));
    h.run();
    h.input_mut().modifiers = Modifiers::NONE;
    assert!(!h.state().session.ik.enabled, "Shift+I in a text field types I");
    press(&mut h, Modifiers::NONE, Key::Enter);
    let scene = h.state().doc.scene();
    assert_eq!(scene.objects[0].skeleton.as_ref().expect("the arm").joints[WRIST].name, "I");
}
