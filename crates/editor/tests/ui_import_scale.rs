//! Issue 42, 14: the import scale. The glTF Fox is modelled in centimetres in a file whose unit
//! is metres: imported into the demo scene it arrives about a hundred times the size of the
//! arm, which the status bar says, with the scale that fits; imported with File ▸ Import scale
//! ×0.01 it is the size of the rest, its skinned mesh and its joints scaled alike.

mod common;

use common::{corpus, harness, joint_world};

use egui::accesskit::Role;
use egui_kittest::kittest::Queryable;
use glam::Vec3;
use keyrig_editor::camera::Bounds;

fn size(b: Bounds) -> f32 {
    (b.max - b.min).length()
}

/// The median size (box diagonal) of the demo scene's objects, as the editor draws them.
fn scene_size(app: &keyrig_editor::EditorApp, objects: usize) -> f32 {
    let mut sizes: Vec<f32> = (0..objects).filter_map(|o| app.bounds_of(Some(&[o]))).map(size).collect();
    sizes.sort_by(f32::total_cmp);
    assert!(!sizes.is_empty(), "the demo scene has objects with a size");
    sizes[sizes.len() / 2]
}

/// Imports the Fox into the demo scene at the editor's import scale; returns the harness, the
/// Fox's object index, its drawn size and the position of each of its joints relative to its
/// object's origin.
fn import_fox(h: &mut egui_kittest::Harness<'static, keyrig_editor::EditorApp>) -> (usize, f32, Vec<Vec3>) {
    let fox = h.state().doc.scene().objects.len();
    h.state_mut().import_path(corpus("gltf/Fox/Fox.glb"));
    h.state_mut().wait_for_background_work();
    h.run();
    let app = h.state();
    assert_eq!(app.doc.scene().objects.len(), fox + 1, "the Fox is one skinned object");
    let object = &app.doc.scene().objects[fox];
    let origin = object.translation.value;
    let joints = object.skeleton.as_ref().expect("the Fox has a skeleton").joints.len();
    let bounds = app.bounds_of(Some(&[fox])).expect("the Fox is drawn");
    let relative = (0..joints).map(|j| joint_world(app, fox, j) - origin).collect();
    (fox, size(bounds), relative)
}

#[test]
fn a_fox_a_hundred_times_too_large_is_said_and_imports_at_scale_point_zero_one() {
    let dir = tempfile::tempdir().expect("temp dir");

    // As the file says: glTF metres.
    let mut h = harness(dir.path(), None);
    assert_eq!(h.state().import_scale(), 1.0);
    let (fox, large, joints_large) = import_fox(&mut h);
    let arm = scene_size(h.state(), fox);
    let ratio = large / arm;
    assert!(ratio > 30.0, "the Fox is far larger than the demo's objects: {large} against {arm}");
    let status = h.state().status().cloned().expect("a message");
    assert!(status.is_error, "a model this large is said as a warning: {status:?}");
    assert!(status.text.contains("Fox is about") && status.text.contains("larger"), "{}", status.text);
    assert!(status.text.contains("scale 0.01"), "the scale that fits: {}", status.text);
    assert!(status.text.contains("glTF lengths are metres"), "the file's unit: {}", status.text);
    // Undo takes it out in one step.
    h.key_press_modifiers(egui::Modifiers::COMMAND, egui::Key::Z);
    h.run();
    assert_eq!(h.state().doc.scene().objects.len(), fox);

    // File ▸ Import scale ▸ made in centimetres, then the same import.
    h.get_by_role_and_label(Role::Button, "File").click();
    h.step();
    h.get_by_label("Import scale ⏵").click();
    h.step();
    h.get_by_label("×0.01: made in centimetres").click();
    h.step();
    h.run();
    assert_eq!(h.state().import_scale(), 0.01);
    let (fox, small, joints_small) = import_fox(&mut h);
    assert_eq!(fox, h.state().doc.scene().objects.len() - 1);
    let status = h.state().status().cloned().expect("a message");
    assert!(!status.is_error, "a Fox of the scene's size is not warned about: {status:?}");
    assert!(status.text.contains("scaled ×0.01"), "{}", status.text);
    let ratio = small / arm;
    assert!((0.1..10.0).contains(&ratio), "the Fox is the size of the arm: {small} against {arm}");
    // The skinned mesh as drawn and every joint scale alike: a hundredth, exactly (to f32).
    assert!((small / large - 0.01).abs() < 1e-4, "{small} / {large}");
    assert_eq!(joints_small.len(), joints_large.len());
    for (j, (s, l)) in joints_small.iter().zip(&joints_large).enumerate() {
        assert!((*s - *l * 0.01).length() <= 1e-4 * l.length().max(1.0), "joint {j}: {s} against {l}");
    }
}

#[test]
fn a_bad_import_scale_is_refused_with_a_message() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    for bad in ["0", "-2", "NaN", "two"] {
        assert!(!h.state_mut().set_import_scale(bad), "{bad}");
        let status = h.state().status().cloned().expect("a message");
        assert!(status.is_error && status.text.contains("import scale"), "{bad}: {status:?}");
        assert_eq!(h.state().import_scale(), 1.0, "the scale stays as it was");
    }
    // Typed into the menu's field and taken with Set.
    h.get_by_role_and_label(Role::Button, "File").click();
    h.step();
    h.get_by_label("Import scale ⏵").click();
    h.step();
    h.get_by_role_and_label(Role::TextInput, "Scale ×").click();
    h.step();
    // What a keyboard types into the focused field; the submenu stays open while typing.
    h.event(egui::Event::Text("0.5".to_owned()));
    h.step();
    h.get_by_label("Set").click();
    h.step();
    h.run();
    assert_eq!(h.state().import_scale(), 0.5);
}
