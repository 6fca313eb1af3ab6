//! The transform gizmo driven with the mouse, as an animator would: the pointer is pressed on
//! the gizmo's view ring around the selected joint and dragged a quarter turn along it. With
//! record mode on, each drag writes one key at the current frame; without it the drag is a
//! pose that I keys. The joint's world rotation must turn by the angle dragged, about the
//! camera's view axis (transform-gizmo's view ring), which checks the whole path from pointer
//! events through `joint_rotation_from_world` to the document. Drags of several turns key spin
//! segments (issue 14), Ctrl snaps to 15°, and a ring seen edge-on turns 1° per point.

mod common;

use common::{drag_along, drag_along_with, go_to_frame, harness, on_screen, pointer, press};

use egui::accesskit::Role;
use egui::{Event, Key, Modifiers, PointerButton, Pos2};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use glam::{Affine3A, Quat, Vec3};
use keyrig_edit::channels::{self, ChannelId};
use keyrig_editor::camera::OrbitCamera as _;
use keyrig_editor::camera::Projection;
use keyrig_editor::session::Selected;
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
    let rect = app.viewport_rect().expect("the viewport was laid out");
    let projection = Projection::new(&app.view.camera, rect);
    let at: Vec3 = wrist_world(app).translation.into();
    let screen = projection.project(at).expect("the wrist is in front of the camera");
    assert!(rect.shrink(VIEW_RING_RADIUS + 10.0).contains(screen), "the wrist's gizmo fits in the viewport");
    let forward = (app.view.camera.target - app.view.camera.eye()).normalize();
    (screen, forward)
}

/// Presses on the view ring to the right of the gizmo's centre and drags a quarter turn
/// (counter-clockwise on screen, through the top) along the ring, in 5° steps.
fn drag_quarter_turn(harness: &mut Harness<'_, EditorApp>) {
    drag_around_view_ring(harness, 90.0, Modifiers::NONE);
}

/// Presses on the view ring to the right of the wrist's gizmo and drags `degrees` around it
/// (counter-clockwise on screen when positive, several turns if need be), in 5° steps.
fn drag_around_view_ring(harness: &mut Harness<'_, EditorApp>, degrees: f32, modifiers: Modifiers) {
    let (centre, _) = wrist_on_screen(harness.state());
    let on_ring = |angle_deg: f32| {
        let a = angle_deg.to_radians();
        centre + egui::vec2(a.cos(), -a.sin()) * VIEW_RING_RADIUS
    };
    let steps = (degrees.abs() / 5.0).ceil().max(1.0) as i32;
    let path: Vec<Pos2> = (0..=steps).map(|step| on_ring(degrees * step as f32 / steps as f32)).collect();
    drag_along_with(harness, &path, modifiers);
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
    assert_eq!(
        harness.state().session.selection.item,
        Some(Selected::Joint { object: 0, joint: WRIST_JOINT })
    );
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
    assert!(h.state().session.record);
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
    assert!(!h.state().session.record);
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
    assert_eq!(h.state().session.selection.item, Some(Selected::Light(0)));
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
    assert_eq!(h.state().session.selection.item, Some(Selected::Object(1)));
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
    assert_eq!(h.state().session.selection.item, Some(Selected::Light(0)));
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

/// The wrist's rotation track as the document holds it.
fn wrist_track(app: &EditorApp) -> keyrig_core::RawTrack<Quat> {
    app.doc.scene().objects[0].skeleton.as_ref().expect("the demo arm has a skeleton").joints[WRIST_JOINT]
        .rotation
        .track
        .clone()
}

/// The spin of key `index` of the wrist as (unit axis in the parent frame, degrees): the key's
/// spin axis is in the previous key's frame.
fn wrist_spin(app: &EditorApp, index: usize) -> (Vec3, f64) {
    let track = wrist_track(app);
    match track.keys[index].spin {
        Some(keyrig_core::Spin::Angle { axis, degrees }) => {
            ((track.keys[index - 1].value * axis).normalize(), degrees)
        }
        other => panic!("key {index} should turn with an Angle spin, has {other:?}"),
    }
}

/// The world rotation of the frame the wrist's channel is expressed in (parent · rest), now.
fn wrist_frame(app: &EditorApp) -> Quat {
    let local = app.joint_rotation(0, WRIST_JOINT).expect("the wrist has a rotation");
    (rotation_of(wrist_world(app)) * local.inverse()).normalize()
}

/// Part 2 of issue 14: two and a half turns dragged around the ring in record mode write a key
/// whose segment turns 900° the way the hand went; a drag the other way back 450°.
#[test]
fn dragging_the_ring_several_turns_in_record_mode_keys_the_turns_either_way() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    select_wrist(&mut h);
    press(&mut h, Modifiers::NONE, Key::R);
    go_to_frame(&mut h, 0);
    press(&mut h, Modifiers::NONE, Key::I);

    go_to_frame(&mut h, 30);
    let (_, forward) = wrist_on_screen(h.state());
    // Counter-clockwise on screen is a positive turn about the axis towards the viewer,
    // expressed in the wrist's parent frame.
    let towards_viewer = (wrist_frame(h.state()).inverse() * -forward).normalize();
    drag_around_view_ring(&mut h, 900.0, Modifiers::NONE);
    assert_eq!(key_frames(h.state()), vec![0, 30]);
    let (axis, degrees) = wrist_spin(h.state(), 1);
    let signed = degrees * f64::from(axis.dot(towards_viewer).signum());
    assert!(axis.dot(towards_viewer).abs() > 0.99, "the spin turns about the view axis: {axis:?}");
    assert!((signed - 900.0).abs() < 3.0, "2.5 turns counter-clockwise key a 900° segment, not {signed:.1}°");

    // Played back, the segment turns monotonically the whole way.
    let track = keyrig_core::Track::new(&wrist_track(h.state())).expect("a valid track");
    let fps = h.state().doc.scene().fps;
    let angles: Vec<f64> =
        (0..=30).map(|f| track.spin_degrees(f64::from(f) / fps).expect("inside the spin segment")).collect();
    assert!(angles.windows(2).all(|w| (w[1] - w[0]) * degrees > 0.0), "monotonic: {angles:?}");
    assert!((angles[30] - degrees).abs() < 1e-6);

    // Clockwise one and a quarter turns at frame 50: −450° from the key at frame 30.
    go_to_frame(&mut h, 50);
    let (_, forward) = wrist_on_screen(h.state());
    let towards_viewer = (wrist_frame(h.state()).inverse() * -forward).normalize();
    drag_around_view_ring(&mut h, -450.0, Modifiers::NONE);
    assert_eq!(key_frames(h.state()), vec![0, 30, 50]);
    let (axis, degrees) = wrist_spin(h.state(), 2);
    let signed = degrees * f64::from(axis.dot(towards_viewer).signum());
    assert!(axis.dot(towards_viewer).abs() > 0.99, "{axis:?}");
    assert!((signed + 450.0).abs() < 3.0, "1.25 turns clockwise key a −450° segment, not {signed:.1}°");

    // One undo step per drag.
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(key_frames(h.state()), vec![0, 30]);
}

/// Ctrl snaps the ring's angle to 15° steps (Blender's snapping modifier). (At this frame the
/// press to the right of the view ring grabs the wrist's Z ring, which lies close to it; any
/// ring seen open turns by the angle swept around its centre.)
#[test]
fn ctrl_snaps_the_ring_to_15_degrees() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    select_wrist(&mut h);
    for (dragged, modifiers, expected) in
        [(37.0, Modifiers::CTRL, 30.0), (38.0, Modifiers::CTRL, 45.0), (37.0, Modifiers::NONE, 37.0)]
    {
        let before = rotation_of(wrist_world(h.state()));
        drag_around_view_ring(&mut h, dragged, modifiers);
        let (angle, _) = world_turn(before, rotation_of(wrist_world(h.state())));
        assert!(
            (angle - expected).abs() < 0.3,
            "{dragged}° with {modifiers:?} turns {angle:.2}°, expected {expected}°"
        );
    }
}

/// Part 3 of issue 14: a ring seen nearly edge-on turned 0° for a 24-point drag along it;
/// it now turns 1° per point along its line on screen, the ring's near side following the
/// pointer.
#[test]
fn a_ring_seen_nearly_edge_on_turns_one_degree_per_point() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    select_wrist(&mut h);
    // Look at the wrist nearly across the arm: its X (bone) ring is a thin ellipse.
    {
        let app = h.state_mut();
        let target: Vec3 = wrist_world(app).translation.into();
        app.view.camera.target = target;
        app.view.camera.yaw_deg = 10.0;
        app.view.camera.pitch_deg = 0.0;
    }
    h.run();
    let app = h.state();
    let world = wrist_world(app);
    let centre_world: Vec3 = world.translation.into();
    let bone = (rotation_of(world) * Vec3::X).normalize();
    let eye = app.view.camera.eye();
    let forward = (centre_world - eye).normalize();
    assert!(bone.dot(forward).abs() < 0.3, "the X ring is seen nearly edge-on: cos {}", bone.dot(forward));
    let rect = app.viewport_rect().expect("laid out");
    let projection = Projection::new(&app.view.camera, rect);
    let centre = projection.project(centre_world).expect("in view");
    // The ring's world radius from its 75-point screen radius.
    let right = forward.cross(Vec3::Y).normalize();
    let points_per_unit =
        (projection.project(centre_world + right * 0.01).expect("in view") - centre).length() / 0.01;
    let radius = 75.0 / points_per_unit;
    // A point of the ring's front half, 40° from its point nearest the viewer.
    let near = -(forward - bone * bone.dot(forward)).normalize();
    let side = bone.cross(near);
    let phi = 40_f32.to_radians();
    let press_at =
        projection.project(centre_world + (near * phi.cos() + side * phi.sin()) * radius).expect("in view");

    let before = rotation_of(world);
    let button = |pos: Pos2, pressed: bool| Event::PointerButton {
        pos,
        button: PointerButton::Primary,
        pressed,
        modifiers: Modifiers::NONE,
    };
    pointer(&mut h, Event::PointerMoved(press_at));
    pointer(&mut h, Event::PointerMoved(press_at));
    pointer(&mut h, button(press_at, true));
    let drag = h.state().ring_drag().cloned().expect("the press grabbed a rotation ring");
    assert!(drag.axis.dot(bone).abs() > 0.999, "the press grabbed the X ring, not {:?}", drag.axis);
    let keyrig_editor::twist::RingMapping::Along { tangent } = drag.mapping else {
        panic!("an edge-on ring turns linearly, got {:?}", drag.mapping)
    };
    let tangent = egui::vec2(tangent.x, tangent.y);
    for step in 1..=6 {
        pointer(&mut h, Event::PointerMoved(press_at + tangent * (4.0 * step as f32)));
    }
    pointer(&mut h, button(press_at + tangent * 24.0, false));
    pointer(&mut h, Event::PointerMoved(press_at + egui::vec2(0.0, -200.0)));

    let after = rotation_of(wrist_world(h.state()));
    let (angle, axis) = world_turn(before, after);
    assert!(axis.dot(bone).abs() > 0.999, "turned about the bone: {axis:?}");
    assert!((angle - 24.0).abs() < 0.2, "a 24-point drag along the edge-on ring turns 24°, not {angle:.2}°");
    // The near side of the ring followed the pointer: it moved along the drag on screen.
    let near_point = centre_world + near * radius;
    let moved = after * before.inverse() * (near_point - centre_world) + centre_world;
    let on_screen_move =
        projection.project(moved).expect("in view") - projection.project(near_point).expect("in view");
    assert!(on_screen_move.dot(tangent) > 0.0, "the near side moves with the pointer: {on_screen_move:?}");
}

/// World rotation and position of joint `joint` of the demo arm now.
fn joint_frame(app: &EditorApp, joint: usize) -> (Quat, Vec3) {
    let pose = app.object_pose_now(0).expect("the demo arm");
    let (_, r, t) = (pose.world_from_object * pose.object_from_joint[joint]).to_scale_rotation_translation();
    (r, t)
}

/// Selects the elbow, Shift-clicks the forearm (the active joint), turns record mode on and
/// drags a quarter turn around the gizmo's view ring, centred at `centre` (world); returns the
/// elbow's and forearm's world rotations before and after, and the view axis.
fn turn_elbow_and_forearm(h: &mut Harness<'_, EditorApp>, pivot: Option<&str>) -> ([(Quat, Quat); 2], Vec3) {
    h.get_by_label("elbow").click();
    h.run();
    h.input_mut().modifiers = Modifiers::SHIFT;
    h.get_by_label("forearm").click();
    h.run();
    h.input_mut().modifiers = Modifiers::NONE;
    h.run();
    let selected: Vec<Selected> = h.state().session.selection.items().collect();
    assert_eq!(selected.len(), 2, "{selected:?}");
    if let Some(pivot) = pivot {
        h.get_by_label("Pivot").click();
        h.run();
        h.get_by_label(pivot).click();
        h.run();
    }
    h.get_by_label("⏺ Record").click();
    h.run();
    go_to_frame(h, 12);
    let before = [joint_frame(h.state(), 1).0, joint_frame(h.state(), 2).0];
    // The gizmo stands at the pivot: the mean of the two origins, or the active (forearm).
    let centre = match pivot {
        None => (joint_frame(h.state(), 1).1 + joint_frame(h.state(), 2).1) * 0.5,
        Some(_) => joint_frame(h.state(), 2).1,
    };
    let centre = on_screen(h.state(), centre);
    let forward = (h.state().view.camera.target - h.state().view.camera.eye()).normalize();
    let steps = 18;
    let path: Vec<Pos2> = (0..=steps)
        .map(|step| {
            let a = (90.0 * step as f32 / steps as f32).to_radians();
            centre + egui::vec2(a.cos(), -a.sin()) * VIEW_RING_RADIUS
        })
        .collect();
    let undo = h.state().doc.undo_len();
    drag_along(h, &path);
    assert_eq!(h.state().doc.undo_len(), undo + 1, "one undo step for the drag");
    let after = [joint_frame(h.state(), 1).0, joint_frame(h.state(), 2).0];
    ([(before[0], after[0]), (before[1], after[1])], forward)
}

#[test]
fn the_gizmo_turns_every_selected_joint_about_the_median_point() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let ([elbow, forearm], forward) = turn_elbow_and_forearm(&mut h, None);
    // The two turn as one body: each by a quarter turn about the view axis.
    assert_quarter_turn_about_view_axis(elbow.0, elbow.1, forward);
    assert_quarter_turn_about_view_axis(forearm.0, forearm.1, forward);
    // The elbow is keyed; the forearm, carried by it, keeps its own rotation.
    let keyed = |joint| {
        let id = ChannelId::JointRotation { object: 0, joint };
        channels::key_times(h.state().doc.scene(), id).iter().any(|t| (t * 30.0 - 12.0).abs() < 1e-6)
    };
    assert!(keyed(1), "the elbow is keyed at frame 12");
    press(&mut h, Modifiers::COMMAND, Key::Z);
    let (a, _) = world_turn(elbow.0, joint_frame(h.state(), 1).0);
    let (b, _) = world_turn(forearm.0, joint_frame(h.state(), 2).0);
    assert!(a < 0.05 && b < 0.05, "one undo takes both turns back ({a}°, {b}°)");
}

#[test]
fn with_individual_origins_a_selected_chain_curls() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let ([elbow, forearm], forward) = turn_elbow_and_forearm(&mut h, Some("Individual origins"));
    assert_eq!(
        h.state().panels().viewport.pivot(),
        keyrig_editor::panels::viewport::Pivot::IndividualOrigins
    );
    assert_quarter_turn_about_view_axis(elbow.0, elbow.1, forward);
    // The forearm turns by its own quarter turn on top of the elbow's: half a turn in all.
    let (angle, axis) = world_turn(forearm.0, forearm.1);
    assert!((angle - 180.0).abs() < 6.0, "the forearm curls by {angle}°, not 180°");
    assert!(axis.dot(forward).abs() > 0.99, "about the view axis: {axis:?}");
}

/// Two objects selected move together by the same offset (one undo step), and a skeleton's
/// root joint moves with the gizmo (its root translation).
#[test]
fn the_gizmo_moves_every_selected_object_and_a_root_joint() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let position = |app: &EditorApp, o: usize| -> Vec3 {
        app.object_pose_now(o).expect("a pose").world_from_object.translation.into()
    };
    h.get_by_label("Arm").click();
    h.run();
    h.input_mut().modifiers = Modifiers::SHIFT;
    h.get_by_label("Cube").click();
    h.run();
    h.input_mut().modifiers = Modifiers::NONE;
    h.run();
    let (arm_before, cube_before) = (position(h.state(), 0), position(h.state(), 1));
    let undo = h.state().doc.undo_len();
    // The gizmo stands at the median point of the two origins.
    let centre = on_screen(h.state(), (arm_before + cube_before) * 0.5);
    drag_centre(&mut h, centre, egui::vec2(50.0, 0.0));
    let (arm_moved, cube_moved) = (position(h.state(), 0) - arm_before, position(h.state(), 1) - cube_before);
    assert!(arm_moved.length() > 1e-3, "the arm moved: {arm_moved:?}");
    assert!(
        (arm_moved - cube_moved).length() < 1e-4,
        "both by the same offset: {arm_moved:?} {cube_moved:?}"
    );
    assert_eq!(h.state().doc.undo_len(), undo + 1, "one undo step");

    h.get_by_label("shoulder").click();
    h.run();
    let shoulder = |app: &EditorApp| common::joint_world(app, 0, 0);
    drag_selection_right(&mut h, shoulder);
    let Some(channels::ChannelValue::Vec3(root)) = h.state().value_now(ChannelId::RootTranslation(0)) else {
        panic!("a root translation")
    };
    assert!(root.length() > 1e-3, "the root translation holds the move: {root:?}");
}

/// The axis ring seen most at a slant in the default view (the thinnest ellipse on screen)
/// takes a press 12 points off its drawn arc, and the drag turns the wrist about that ring's
/// axis (issue 30: two of four such presses missed the ring).
#[test]
fn a_press_12_points_off_a_slanted_ring_still_turns_the_joint() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    select_wrist(&mut h);
    go_to_frame(&mut h, 15);
    let app = h.state();
    let rect = app.viewport_rect().expect("laid out");
    let projection = Projection::new(&app.view.camera, rect);
    let world = wrist_world(app);
    let (_, rotation, centre) = world.to_scale_rotation_translation();
    let eye = app.view.camera.eye();
    let to_eye = (eye - centre).normalize();
    // Screen points per world unit at the wrist's depth, so that a ring of radius r projects to
    // transform-gizmo's 75-point axis rings.
    let side = to_eye.any_orthonormal_vector() * 0.01;
    let centre_screen = projection.project(centre).expect("in view");
    let per_unit = (projection.project(centre + side).expect("in view") - centre_screen).length() / 0.01;
    let radius = 75.0 / per_unit;
    // For each axis ring: the drawn (front) arc's points on screen.
    let arcs: Vec<(Vec3, Vec<Pos2>)> = [Vec3::X, Vec3::Y, Vec3::Z]
        .map(|a| rotation * a)
        .into_iter()
        .map(|axis| {
            let (u, v) = axis.any_orthonormal_pair();
            let points = (0..=180)
                .map(|i| (i as f32 * 2.0).to_radians())
                .map(|a| (u * a.cos() + v * a.sin()) * radius)
                .filter(|o| o.dot(to_eye) >= 0.0)
                .filter_map(|o| projection.project(centre + o))
                .collect();
            (axis, points)
        })
        .collect();
    // The thinnest ellipse: the smallest nearest distance of its arc from the centre.
    let minor =
        |points: &[Pos2]| points.iter().map(|p| p.distance(centre_screen)).fold(f32::INFINITY, f32::min);
    let (axis, arc) = arcs
        .iter()
        .filter(|(_, p)| p.len() > 10)
        .min_by(|a, b| minor(&a.1).total_cmp(&minor(&b.1)))
        .expect("a ring");
    // The point of the arc halfway along it, and 12 points off it, away from the centre.
    let on_arc = arc[arc.len() / 2];
    let outward = (on_arc - centre_screen).normalized();
    let press = on_arc + outward * 12.0;
    let along = (arc[arc.len() / 2 + 3] - arc[arc.len() / 2 - 3]).normalized();
    let path: Vec<Pos2> = (0..=12).map(|i| press + along * (5.0 * i as f32)).collect();
    let before = rotation_of(wrist_world(h.state()));
    drag_along(&mut h, &path);
    let after = rotation_of(wrist_world(h.state()));
    let (angle, turned_about) = world_turn(before, after);
    assert!(angle > 5.0, "the press 12 points off the ring turned the wrist: {angle}°");
    assert!(turned_about.dot(*axis).abs() > 0.99, "about the ring's axis {axis:?}: {turned_about:?}");
}

/// The editable motion path: with the Cube selected, each of its translation keys is a handle
/// on the path; a drag on the key at frame 30 (not the current frame) moves that key's
/// position in the view plane, leaves its time and the other keys alone, and is one undo step.
#[test]
fn dragging_a_key_of_the_motion_path_moves_that_keys_position() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("Cube").click();
    h.run();
    let before = h.state().doc.scene().objects[1].translation.track.clone();
    let key = 1;
    assert!((before.keys[key].time * 30.0 - 30.0).abs() < 1e-9, "the key at frame 30");
    let from = on_screen(h.state(), before.keys[key].value);
    let to = from + egui::vec2(40.0, -25.0);
    let steps = h.state().doc.undo_len();
    let path: Vec<Pos2> = (0..=8).map(|i| from + (to - from) * (i as f32 / 8.0)).collect();
    drag_along(&mut h, &path);

    let after = h.state().doc.scene().objects[1].translation.track.clone();
    let moved = after.keys[key].value;
    assert!(moved.distance(before.keys[key].value) > 0.05, "the key moved: {moved}");
    assert!(on_screen(h.state(), moved).distance(to) < 1.0, "under the pointer where it was let go");
    let forward = (h.state().view.camera.target - h.state().view.camera.eye()).normalize();
    assert!((moved - before.keys[key].value).dot(forward).abs() < 1e-4, "in the view plane");
    assert_eq!(after.keys.len(), before.keys.len());
    for (i, (a, b)) in before.keys.iter().zip(after.keys.iter()).enumerate() {
        assert_eq!(a.time, b.time, "key {i} keeps its time");
        assert_eq!((a.interpolation, a.tcb), (b.interpolation, b.tcb), "key {i} keeps its shape");
        if i != key {
            assert_eq!(a.value, b.value, "key {i} stays");
        }
    }
    assert_eq!(h.state().doc.undo_len(), steps + 1, "one drag, one undo step");
    assert_eq!(h.state().doc.undo_label(), Some("move the key at frame 30 on the motion path"));
    assert_eq!(h.state().session.selection.item, Some(Selected::Object(1)), "the Cube stays selected");
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(h.state().doc.scene().objects[1].translation.track, before);
}

/// Issue 42, 15: the gizmo's tools by key, as in Maya. With the Cube selected, W leaves only
/// the move handles (a drag around the view ring no longer turns it; a drag of the centre moves
/// it), E only the rings (the same drags: it turns and does not move), S its scale handles; the
/// same key again goes back to move and turn. On a joint that can only turn, W still shows the
/// rings.
#[test]
fn w_e_and_s_choose_the_gizmo_tool() {
    use keyrig_editor::panels::viewport::GizmoTool;
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("Cube").click();
    h.run();
    press(&mut h, Modifiers::NONE, Key::F);
    let tool = |h: &Harness<'_, EditorApp>| h.state().panels().viewport.gizmo_tool();
    assert_eq!(tool(&h), GizmoTool::MoveAndTurn);
    let place = |h: &Harness<'_, EditorApp>| -> Vec3 {
        h.state().object_pose_now(1).expect("the cube").world_from_object.translation.into()
    };
    let turn = |h: &Harness<'_, EditorApp>| -> Quat {
        rotation_of(h.state().object_pose_now(1).expect("the cube").world_from_object)
    };
    // A quarter turn around the Cube's view ring, and a drag of its centre 60 points right.
    let around = |h: &mut Harness<'_, EditorApp>| {
        let centre = on_screen(h.state(), place(h));
        let on_ring =
            |a: f32| centre + egui::vec2(a.to_radians().cos(), -a.to_radians().sin()) * VIEW_RING_RADIUS;
        let path: Vec<Pos2> = (0..=18).map(|i| on_ring(5.0 * i as f32)).collect();
        drag_along(h, &path);
    };
    let across = |h: &mut Harness<'_, EditorApp>| {
        let centre = on_screen(h.state(), place(h));
        drag_centre(h, centre, egui::vec2(60.0, 0.0));
    };

    press(&mut h, Modifiers::NONE, Key::W);
    assert_eq!(tool(&h), GizmoTool::Move);
    assert!(h.query_by_label("Gizmo: move").is_some(), "the status bar says so");
    let (p, q) = (place(&h), turn(&h));
    around(&mut h);
    assert!(turn(&h).angle_between(q) < 1e-4, "W: the view ring does not turn the Cube");
    h.get_by_label("Cube").click();
    h.run();
    press(&mut h, Modifiers::NONE, Key::F);
    let p0 = place(&h);
    across(&mut h);
    assert!((place(&h) - p0).length() > 0.05, "W: the centre moves it ({p:?} → {:?})", place(&h));

    press(&mut h, Modifiers::NONE, Key::E);
    assert_eq!(tool(&h), GizmoTool::Turn);
    press(&mut h, Modifiers::NONE, Key::F);
    let (p, q) = (place(&h), turn(&h));
    across(&mut h);
    assert!((place(&h) - p).length() < 1e-5, "E: the centre does not move the Cube");
    h.get_by_label("Cube").click();
    h.run();
    press(&mut h, Modifiers::NONE, Key::F);
    around(&mut h);
    assert!(turn(&h).angle_between(q).to_degrees() > 45.0, "E: the view ring turns it");

    press(&mut h, Modifiers::NONE, Key::S);
    assert_eq!(tool(&h), GizmoTool::Scale);
    assert!(h.query_by_role_and_label(Role::Button, "Scale").is_some(), "the tool buttons show it");
    press(&mut h, Modifiers::NONE, Key::S);
    assert_eq!(tool(&h), GizmoTool::MoveAndTurn, "S again: move and turn");

    // The wrist can only turn: with W its rings still show and turn it.
    press(&mut h, Modifiers::NONE, Key::W);
    select_wrist(&mut h);
    press(&mut h, Modifiers::NONE, Key::F);
    let before = rotation_of(wrist_world(h.state()));
    drag_quarter_turn(&mut h);
    let (angle, _) = world_turn(before, rotation_of(wrist_world(h.state())));
    assert!((angle - 90.0).abs() < 3.0, "W on a joint that cannot move: the rings turn it {angle}°");
}
