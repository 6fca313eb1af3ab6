//! Scene cameras and markers in the editor, as a user works with them (issue 31): selecting a
//! camera in the outliner, keying its fields in record mode (its visibility with a Step key),
//! looking through it (0) and
//! leaving by orbiting, setting it to the view (Ctrl+Alt+0), adding one (Ctrl+Shift+C),
//! markers (M, Ctrl+B), and deleting a camera bound to a marker.

mod common;

use common::{go_to_frame, harness, press, set_value};

use egui::accesskit::Role;
use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use keyrig_edit::channels::{self, ChannelId, ChannelValue};
use keyrig_editor::session::Selected;
use keyrig_editor::EditorApp;

fn cameras_ron() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/cameras.ron")
}

/// The outliner's row named `name` (the leftmost widget with that label: the dope sheet names
/// its rows too).
fn outliner_row<'a>(h: &'a Harness<'_, EditorApp>, name: &'a str) -> egui_kittest::Node<'a> {
    h.get_all_by_label(name).min_by(|a, b| a.rect().left().total_cmp(&b.rect().left())).expect("a row")
}

fn select_camera(h: &mut Harness<'_, EditorApp>, name: &str) {
    outliner_row(h, name).click();
    h.run();
}

#[test]
fn a_camera_is_selected_keyed_and_looked_through() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), Some(cameras_ron()));
    select_camera(&mut h, "Dolly");
    assert_eq!(h.state().session.selection.item, Some(Selected::Camera(0)));
    assert!(h.query_by_label("Camera: Dolly").is_some(), "the inspector shows the camera");

    // Record mode: the inspector's fields key the camera's channels at the current frame.
    go_to_frame(&mut h, 15);
    press(&mut h, Modifiers::NONE, Key::R);
    let translation = ChannelId::CameraTranslation(0);
    let lens = ChannelId::CameraLens(0);
    assert_eq!(channels::key_count(h.state().doc.scene(), translation), 2);
    set_value(&mut h, Role::SpinButton, "Translation X", 1.25);
    set_value(&mut h, Role::SpinButton, "Focal length (mm)", 35.0);
    let scene = h.state().doc.scene();
    assert_eq!(channels::key_count(scene, translation), 3);
    assert_eq!(channels::key_count(scene, lens), 3);
    let time = 15.0 / scene.fps;
    assert!(matches!(h.state().value_now(lens), Some(ChannelValue::Scalar(v)) if (v - 35.0).abs() < 1e-4));
    let key = scene.cameras[0].translation.track.keys.iter().find(|k| (k.time - time).abs() < 1e-9);
    assert_eq!(key.map(|k| k.value.x), Some(1.25));
    // The Visible check box keys the camera's visibility with a Step key; the channel is then
    // listed (its dope-sheet row and curve), and the evaluated camera is hidden.
    let visible = ChannelId::CameraVisible(0);
    assert!(!ChannelId::of_camera(h.state().doc.scene(), 0).contains(&visible), "not listed while shown");
    h.get_by_label("Visible").click();
    h.run();
    let scene = h.state().doc.scene();
    let keys = &scene.cameras[0].visible.track.keys;
    assert_eq!(keys.len(), 1);
    assert_eq!((keys[0].value, keys[0].interpolation), (0.0, keyrig_core::Interpolation::Step));
    assert!((keys[0].time - time).abs() < 1e-9);
    assert!(ChannelId::of_camera(scene, 0).contains(&visible), "listed once keyed");
    assert!(matches!(h.state().value_now(visible), Some(ChannelValue::Scalar(v)) if v == 0.0));
    assert_eq!(scene.problems(), Vec::new());
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert!(h.state().doc.scene().cameras[0].visible.track.keys.is_empty(), "one undo step");
    press(&mut h, Modifiers::NONE, Key::R);

    // 0 looks through the selected camera; 0 again, or orbiting, returns to the view.
    press(&mut h, Modifiers::NONE, Key::Num0);
    assert_eq!(h.state().view.look_through, Some(keyrig_editor::view::LookThrough::Camera(0)));
    press(&mut h, Modifiers::NONE, Key::Num0);
    assert_eq!(h.state().view.look_through, None);
    press(&mut h, Modifiers::NONE, Key::Num0);
    let centre = h.state().viewport_rect().expect("laid out").center();
    common::drag(&mut h, centre, centre + egui::vec2(60.0, 10.0));
    assert_eq!(h.state().view.look_through, None, "orbiting leaves the camera's view");
}

#[test]
fn cameras_are_added_set_to_the_view_and_bound_to_markers() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), Some(cameras_ron()));
    press(&mut h, Modifiers::COMMAND | Modifiers::SHIFT, Key::C);
    let scene = h.state().doc.scene();
    assert_eq!(scene.cameras.len(), 3);
    assert_eq!(scene.cameras[2].name, "Camera");
    assert_eq!(h.state().session.selection.item, Some(Selected::Camera(2)));
    let eye = keyrig_render::camera::eye_position(&h.state().view.camera);
    assert!(scene.cameras[2].translation.value.abs_diff_eq(eye, 1e-5));

    // Move the view, then set the camera to it: it stands at the new eye, looking at the target.
    let mut view = h.state().view.camera;
    view.yaw_deg += 50.0;
    h.state_mut().view.camera = view;
    press(&mut h, Modifiers::COMMAND | Modifiers::ALT, Key::Num0);
    let eye = keyrig_render::camera::eye_position(&view);
    let camera = h.state().doc.scene().cameras[2].clone();
    assert!(camera.translation.value.abs_diff_eq(eye, 1e-5));
    let forward = camera.rotation.value * glam::Vec3::NEG_Z;
    assert!(forward.abs_diff_eq((view.target - eye).normalize(), 1e-5), "{forward}");

    // M adds a marker at the frame and removes it again; Ctrl+B binds the selected camera.
    go_to_frame(&mut h, 5);
    press(&mut h, Modifiers::NONE, Key::M);
    assert_eq!(h.state().doc.scene().markers.len(), 2);
    assert_eq!(h.state().doc.scene().markers[0].frame, 5);
    press(&mut h, Modifiers::NONE, Key::M);
    assert_eq!(h.state().doc.scene().markers.len(), 1);
    press(&mut h, Modifiers::COMMAND, Key::B);
    let scene = h.state().doc.scene();
    assert_eq!(scene.markers[0].camera.as_deref(), Some("Camera"));
    assert_eq!(scene.active_camera_at(5.0), Some(2));
    assert!(h.query_by_label("▼ 5 Camera ▸ Camera").is_some(), "the timeline shows the marker");

    // Deleting the camera unbinds its marker: the scene stays valid; undo restores both.
    press(&mut h, Modifiers::NONE, Key::Delete);
    let scene = h.state().doc.scene();
    assert_eq!(scene.cameras.len(), 2);
    assert_eq!(scene.markers[0].camera, None);
    assert_eq!(scene.problems(), Vec::new());
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(h.state().doc.scene().markers[0].camera.as_deref(), Some("Camera"));
}
