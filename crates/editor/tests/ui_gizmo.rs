//! The transform gizmo driven with the mouse, as an animator would: the pointer is pressed on
//! the gizmo's view ring around the selected joint and dragged a quarter turn along it. With
//! record mode on, each drag writes one key at the current frame; without it the drag is a
//! pose that I keys. The joint's world rotation must turn by the angle dragged, about the
//! camera's view axis (transform-gizmo's view ring), which checks the whole path from pointer
//! events through `joint_rotation_from_world` to the document.

mod common;

use common::{go_to_frame, harness, press};

use egui::accesskit::Role;
use egui::{Event, Key, Modifiers, PointerButton, Pos2};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use glam::{Affine3A, Quat, Vec3};
use keyrig_editor::camera::Projection;
use keyrig_editor::channels::{self, ChannelId};
use keyrig_editor::state::Selected;
use keyrig_editor::EditorApp;

/// The wrist of the demo arm: it has no keys in the demo scene.
const WRIST_JOINT: usize = 3;
const WRIST: ChannelId = ChannelId::JointRotation { object: 0, joint: WRIST_JOINT };

/// Screen radius of transform-gizmo's view-axis ring with its default visuals:
/// gizmo_size 75 + stroke_width 4 + 5 points (`outer_circle_radius` in transform-gizmo 0.9).
const VIEW_RING_RADIUS: f32 = 84.0;

/// The wrist's world transform as the editor evaluates it now (keys plus pose overrides).
fn wrist_world(app: &EditorApp) -> Affine3A {
    let pose = app.object_pose_now(0).expect("the demo arm has a pose");
    pose.world_from_object * pose.object_from_joint[WRIST_JOINT]
}

fn rotation_of(a: Affine3A) -> Quat {
    a.to_scale_rotation_translation().1
}

/// Where the wrist is on screen, and the direction the camera looks along (world space).
fn wrist_on_screen(app: &EditorApp) -> (Pos2, Vec3) {
    let rect = app.view.viewport_rect.expect("the viewport was laid out");
    let projection = Projection::new(&app.view.camera, rect);
    let at: Vec3 = wrist_world(app).translation.into();
    let screen = projection.project(at).expect("the wrist is in front of the camera");
    assert!(rect.shrink(VIEW_RING_RADIUS + 10.0).contains(screen), "the wrist's gizmo fits in the viewport");
    let forward = (app.view.camera.target - app.view.camera.eye()).normalize();
    (screen, forward)
}

fn pointer(harness: &mut Harness<'_, EditorApp>, event: Event) {
    harness.event(event);
    harness.run();
}

/// Hovers `path[0]`, presses the primary button there, moves through the rest of `path` one
/// frame per point, releases at the last point and moves away, so the next frame neither
/// hovers nor drags the gizmo.
fn drag_along(harness: &mut Harness<'_, EditorApp>, path: &[Pos2]) {
    let (Some(&start), Some(&end)) = (path.first(), path.last()) else { return };
    let button = |pos: Pos2, pressed: bool| Event::PointerButton {
        pos,
        button: PointerButton::Primary,
        pressed,
        modifiers: Modifiers::NONE,
    };
    pointer(harness, Event::PointerMoved(start));
    pointer(harness, Event::PointerMoved(start));
    pointer(harness, button(start, true));
    for &p in &path[1..] {
        pointer(harness, Event::PointerMoved(p));
    }
    pointer(harness, button(end, false));
    pointer(harness, Event::PointerMoved(end + egui::vec2(0.0, -200.0)));
}

/// Presses on the view ring to the right of the gizmo's centre and drags a quarter turn
/// (counter-clockwise on screen, through the top) along the ring, in 5° steps.
fn drag_quarter_turn(harness: &mut Harness<'_, EditorApp>) {
    let (centre, _) = wrist_on_screen(harness.state());
    let on_ring = |angle_deg: f32| {
        let a = angle_deg.to_radians();
        centre + egui::vec2(a.cos(), -a.sin()) * VIEW_RING_RADIUS
    };
    let path: Vec<Pos2> = (0..=18).map(|step| on_ring(step as f32 * 5.0)).collect();
    drag_along(harness, &path);
}

/// The rotation that takes `before` to `after` in world space: its angle in degrees and axis.
fn world_turn(before: Quat, after: Quat) -> (f32, Vec3) {
    let (axis, angle) = (after * before.inverse()).normalize().to_axis_angle();
    let (axis, angle) =
        if angle > std::f32::consts::PI { (-axis, std::f32::consts::TAU - angle) } else { (axis, angle) };
    (angle.to_degrees(), axis)
}

fn select_wrist(harness: &mut Harness<'_, EditorApp>) {
    harness.get_by_label("wrist").click();
    harness.run();
    assert_eq!(harness.state().selection.item, Some(Selected::Joint { object: 0, joint: WRIST_JOINT }));
}

fn key_frames(app: &EditorApp) -> Vec<i64> {
    let scene = app.doc.scene();
    channels::key_times(scene, WRIST).iter().map(|t| (t * scene.fps).round() as i64).collect()
}

/// Asserts a quarter turn about the view axis between two world rotations.
fn assert_quarter_turn_about_view_axis(before: Quat, after: Quat, forward: Vec3) {
    let (angle, axis) = world_turn(before, after);
    assert!((angle - 90.0).abs() < 3.0, "a quarter-turn drag turns the joint by {angle:.2}°, not 90°");
    assert!(
        axis.dot(forward).abs() > 0.995,
        "the view ring turns about the view axis {forward:?}; the joint turned about {axis:?}"
    );
}

#[test]
fn dragging_the_gizmo_in_record_mode_keys_the_joint_at_each_frame() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    select_wrist(&mut h);
    h.get_by_label("⏺ Record").click();
    h.run();
    assert!(h.state().record);
    assert!(key_frames(h.state()).is_empty(), "the demo's wrist starts without keys");

    go_to_frame(&mut h, 10);
    let (_, forward) = wrist_on_screen(h.state());
    let before = rotation_of(wrist_world(h.state()));
    let camera_before = h.state().view.camera;
    drag_quarter_turn(&mut h);
    assert_eq!(key_frames(h.state()), vec![10], "record mode writes one key at the current frame");
    assert_eq!(h.state().view.camera, camera_before, "a drag on the gizmo does not orbit the camera");
    let at_10 = rotation_of(wrist_world(h.state()));
    assert_quarter_turn_about_view_axis(before, at_10, forward);

    go_to_frame(&mut h, 20);
    let before_20 = rotation_of(wrist_world(h.state()));
    drag_quarter_turn(&mut h);
    assert_eq!(key_frames(h.state()), vec![10, 20], "a second drag at another frame adds a second key");
    let at_20 = rotation_of(wrist_world(h.state()));
    assert_quarter_turn_about_view_axis(before_20, at_20, forward);

    // The keys hold what was dragged: back at frame 10, the wrist is where the first drag left it.
    go_to_frame(&mut h, 10);
    let (angle, _) = world_turn(at_10, rotation_of(wrist_world(h.state())));
    assert!(angle < 0.05, "the key at frame 10 plays back the dragged rotation (off by {angle}°)");

    // One undo per drag: the second key goes, then the first.
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(key_frames(h.state()), vec![10]);
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert!(key_frames(h.state()).is_empty());
}

#[test]
fn dragging_the_gizmo_without_record_mode_poses_until_i_keys_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    select_wrist(&mut h);
    assert!(!h.state().record);
    go_to_frame(&mut h, 15);
    let (_, forward) = wrist_on_screen(h.state());
    let before = rotation_of(wrist_world(h.state()));
    drag_quarter_turn(&mut h);
    assert!(key_frames(h.state()).is_empty(), "without record mode a drag writes no key");
    let posed = rotation_of(wrist_world(h.state()));
    assert_quarter_turn_about_view_axis(before, posed, forward);

    press(&mut h, Modifiers::NONE, Key::I);
    assert_eq!(key_frames(h.state()), vec![15], "I keys the posed rotation at the current frame");
    let (angle, _) = world_turn(posed, rotation_of(wrist_world(h.state())));
    assert!(angle < 0.05, "the key holds the pose (off by {angle}°)");
}

/// Where a world point is on screen in the editor's viewport now.
fn on_screen(app: &EditorApp, at: Vec3) -> Pos2 {
    let rect = app.view.viewport_rect.expect("the viewport was laid out");
    Projection::new(&app.view.camera, rect).project(at).expect("the point is in front of the camera")
}

/// Presses on the gizmo's centre (transform-gizmo's view-plane translation disc) at `centre`
/// and drags it by `by` screen points, in ten steps.
fn drag_centre(harness: &mut Harness<'_, EditorApp>, centre: Pos2, by: egui::Vec2) {
    let path: Vec<Pos2> = (0..=10).map(|step| centre + by * (step as f32 / 10.0)).collect();
    drag_along(harness, &path);
}

/// Drags the selection's gizmo centre 60 points right and checks that `position` (read from
/// the editor) followed the pointer in the view plane; returns the new position.
fn drag_selection_right(harness: &mut Harness<'_, EditorApp>, position: impl Fn(&EditorApp) -> Vec3) -> Vec3 {
    let before = position(harness.state());
    // Frame the selection first (F), as a user brings what they edit into view (the demo's
    // light sits above the default view).
    press(harness, Modifiers::NONE, Key::F);
    assert!(
        (harness.state().view.camera.target - before).length() < 1e-5,
        "F centres the view on the selection"
    );
    let centre = on_screen(harness.state(), before);
    let camera = harness.state().view.camera;
    let forward = (camera.target - camera.eye()).normalize();
    let by = egui::vec2(60.0, 0.0);
    drag_centre(harness, centre, by);
    assert_eq!(harness.state().view.camera, camera, "a drag on the gizmo does not orbit the camera");
    let after = position(harness.state());
    let moved = after - before;
    assert!(moved.length() > 1e-3, "the drag moved the selection ({before:?} → {after:?})");
    assert!(
        moved.dot(forward).abs() < 1e-3 * moved.length().max(1.0),
        "the view-plane disc moves in the view plane: moved {moved:?}, view axis {forward:?}"
    );
    let landed = on_screen(harness.state(), after);
    assert!(
        (landed - (centre + by)).length() < 1.5,
        "the selection lands under the pointer: at {landed:?}, pointer released at {:?}",
        centre + by
    );
    after
}

#[test]
fn dragging_the_gizmo_translates_lights_and_objects_and_records_keys() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("⏺ Record").click();
    h.run();
    go_to_frame(&mut h, 12);

    // The spot light "Key": its position track gets a key at frame 12 holding the dragged place.
    // "Key" also names the light's dope-sheet row; the outliner's entry is a toggle.
    h.get_by_role_and_label(Role::Button, "Key").click();
    h.run();
    assert_eq!(h.state().selection.item, Some(Selected::Light(0)));
    let light = ChannelId::LightPosition(0);
    let keys_before = channels::key_count(h.state().doc.scene(), light);
    let light_position = |app: &EditorApp| match app.value_now(ChannelId::LightPosition(0)) {
        Some(channels::ChannelValue::Vec3(p)) => p,
        other => panic!("the light's position is a Vec3 channel, got {other:?}"),
    };
    let moved_light = drag_selection_right(&mut h, light_position);
    let scene = h.state().doc.scene();
    let frames: Vec<i64> =
        channels::key_times(scene, light).iter().map(|t| (t * scene.fps).round() as i64).collect();
    assert_eq!(channels::key_count(scene, light), keys_before + 1, "one key added: {frames:?}");
    assert!(frames.contains(&12), "the new key is at frame 12: {frames:?}");

    // The object "Cube": translation keyed the same way.
    h.get_by_label("Cube").click();
    h.run();
    assert_eq!(h.state().selection.item, Some(Selected::Object(1)));
    let cube = ChannelId::ObjectTranslation(1);
    let cube_keys_before = channels::key_count(h.state().doc.scene(), cube);
    let cube_position = |app: &EditorApp| -> Vec3 {
        app.object_pose_now(1).expect("the cube has a pose").world_from_object.translation.into()
    };
    drag_selection_right(&mut h, cube_position);
    assert_eq!(channels::key_count(h.state().doc.scene(), cube), cube_keys_before + 1);

    // Scrubbing away and back plays the keyed light position.
    go_to_frame(&mut h, 30);
    go_to_frame(&mut h, 12);
    assert!((light_position(h.state()) - moved_light).length() < 1e-4, "the key holds the dragged position");
}

/// A spot light's rotate ring turns its direction (keeping its length) and record mode keys
/// the direction channel; its position stays.
#[test]
fn dragging_a_spot_lights_view_ring_turns_its_direction() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("⏺ Record").click();
    h.run();
    go_to_frame(&mut h, 8);
    h.get_by_role_and_label(Role::Button, "Key").click();
    h.run();
    assert_eq!(h.state().selection.item, Some(Selected::Light(0)));
    let vec3 = |app: &EditorApp, id: ChannelId| match app.value_now(id) {
        Some(channels::ChannelValue::Vec3(v)) => v,
        other => panic!("{id:?} is a Vec3 channel, got {other:?}"),
    };
    let (position, direction) = (ChannelId::LightPosition(0), ChannelId::LightDirection(0));
    let place = vec3(h.state(), position);
    press(&mut h, Modifiers::NONE, Key::F);
    let before = vec3(h.state(), direction);
    let keys_before = channels::key_count(h.state().doc.scene(), direction);
    let camera = h.state().view.camera;
    let forward = (camera.target - camera.eye()).normalize();
    let centre = on_screen(h.state(), place);
    let path: Vec<Pos2> = (0..=18)
        .map(|step| {
            let a = (step as f32 * 5.0).to_radians();
            centre + egui::vec2(a.cos(), -a.sin()) * VIEW_RING_RADIUS
        })
        .collect();
    drag_along(&mut h, &path);

    let after = vec3(h.state(), direction);
    assert!((after.length() - before.length()).abs() < 1e-4, "the direction keeps its length");
    let miss = |sign: f32| {
        let expected = Quat::from_axis_angle(forward, sign * std::f32::consts::FRAC_PI_2) * before;
        expected.angle_between(after).to_degrees()
    };
    let miss = miss(1.0).min(miss(-1.0));
    assert!(
        miss < 3.0,
        "a quarter turn on the view ring turns the direction 90° about the view axis (off by {miss:.2}°)"
    );
    assert!((vec3(h.state(), position) - place).length() < 1e-5, "turning does not move the light");
    assert_eq!(
        channels::key_count(h.state().doc.scene(), direction),
        keys_before + 1,
        "record mode keys the direction"
    );
}
