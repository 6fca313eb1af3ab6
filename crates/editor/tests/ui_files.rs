//! Documents: autosave and the recovery offer, importing a glTF model, exporting glTF,
//! dropping a file on the window, the confirmation before losing changes.

mod common;

use common::{corpus, harness_autosaving};

use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;

#[test]
fn autosave_is_offered_for_recovery_after_a_crash() {
    let dir = tempfile::tempdir().expect("temp dir");
    let edited = {
        let mut h = harness_autosaving(dir.path(), None, 0.2);
        // A change makes the document dirty. No frame runs after it: the autosave timer
        // writes on its own thread while the editor sits idle.
        h.key_press_modifiers(Modifiers::NONE, Key::Num1);
        h.run();
        assert!(h.state().doc.is_dirty());
        let recovery = dir.path().join("recovery.ron");
        assert!(!recovery.exists(), "not before the autosave interval");
        let deadline = std::time::Instant::now() + std::time::Duration::from_secs(20);
        while !recovery.exists() && std::time::Instant::now() < deadline {
            std::thread::sleep(std::time::Duration::from_millis(25));
        }
        assert!(recovery.exists(), "an idle editor autosaves its unsaved changes");
        h.state().doc.scene().clone()
        // Dropped without quitting: as if the editor had crashed.
    };
    let mut h = harness_autosaving(dir.path(), None, 1e9);
    assert!(h.state().recovery_offer().is_some());
    h.get_by_label("Recover").click();
    h.run();
    assert_eq!(h.state().doc.scene(), &edited);
    assert!(h.state().doc.is_dirty(), "a recovered scene still needs saving");

    // Declining removes the autosave.
    let mut again = harness_autosaving(dir.path(), None, 1e9);
    again.get_by_label("Discard autosave").click();
    again.run();
    assert!(again.state().recovery_offer().is_none());
    assert!(!dir.path().join("recovery.ron").exists());
}

#[test]
fn import_a_skinned_gltf_into_the_scene_and_undo_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness_autosaving(dir.path(), None, 1e9);
    let before = h.state().doc.scene().objects.len();
    let model = corpus("gltf/RiggedSimple/RiggedSimple.glb");
    h.state_mut().import_path(model);
    h.state_mut().wait_for_background_work();
    h.run();
    let status = h.state().status().cloned().expect("a message");
    assert!(!status.is_error, "{status:?}");
    let scene = h.state().doc.scene();
    assert!(scene.objects.len() > before);
    let imported = &scene.objects[before];
    assert!(imported.skeleton.is_some(), "the skinned cylinder comes with its skeleton");
    // The viewport skinned it on the CPU (the painter draws it without a GPU).
    assert!(h.state().skin_cache().deformed_positions(before).is_some_and(|p| !p.is_empty()));
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert_eq!(h.state().doc.scene().objects.len(), before);
}

#[test]
fn export_gltf_writes_a_file_and_a_bad_file_reports_an_error() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness_autosaving(dir.path(), None, 1e9);
    let out = dir.path().join("demo.glb");
    h.state_mut().export_to(out.clone());
    h.run();
    assert!(!h.state().status().is_some_and(|s| s.is_error), "{:?}", h.state().status().cloned());
    let bytes = std::fs::read(&out).expect("exported");
    assert_eq!(&bytes[..4], b"glTF");

    let junk = dir.path().join("junk.glb");
    std::fs::write(&junk, b"not a glTF file").expect("write");
    h.state_mut().import_path(junk);
    h.state_mut().wait_for_background_work();
    h.run();
    let status = h.state().status().cloned().expect("an error");
    assert!(status.is_error && status.text.contains("junk.glb"), "{status:?}");
}

#[test]
fn dropping_a_scene_on_a_dirty_document_asks_first() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("other.ron");
    let mut other = keyrig_io::demo::demo_scene();
    other.fps = 24.0;
    keyrig_io::scene_file::save(&path, &other).expect("write a scene");
    let mut h = harness_autosaving(dir.path(), None, 1e9);
    h.key_press_modifiers(Modifiers::NONE, Key::Num4);
    h.run();
    assert!(h.state().doc.is_dirty());
    h.input_mut().dropped_files.push(egui::DroppedFile { path: Some(path.clone()), ..Default::default() });
    h.run();
    assert!(h.state().pending().is_some(), "unsaved changes: the editor asks");
    h.get_by_label("Cancel").click();
    h.run();
    assert_eq!(h.state().doc.scene().fps, 30.0, "cancel keeps the document");
    h.input_mut().dropped_files.push(egui::DroppedFile { path: Some(path), ..Default::default() });
    h.run();
    h.get_by_label("Discard changes").click();
    h.run();
    assert_eq!(h.state().doc.scene(), &other);
    assert_eq!(h.state().doc.title(), "keyrig — other.ron");
}

/// A scene saved in a project folder names the models inside it relative to itself, so the
/// folder can be moved (or shared) and the scene still opens its models.
#[test]
fn a_moved_project_folder_still_opens_its_models() {
    let root = tempfile::tempdir().expect("temp dir");
    let project = root.path().join("project");
    std::fs::create_dir_all(project.join("models")).expect("create folder");
    let model = project.join("models/sydney.md2");
    std::fs::copy(corpus("md2/sydney/sydney.md2"), &model).expect("copy model");
    let outside = root.path().join("outside.md2");
    std::fs::copy(corpus("md2/sydney/sydney.md2"), &outside).expect("copy model");

    let mut h = common::harness(root.path(), None);
    let first = h.state().doc.scene().objects.len();
    h.state_mut().import_path(model);
    h.state_mut().import_path(outside.clone());
    h.state_mut().wait_for_background_work();
    h.run();
    let scene_file = project.join("scene.ron");
    h.state_mut().save_to(scene_file.clone());
    let text = std::fs::read_to_string(&scene_file).expect("read scene");
    assert!(text.contains("path: \"models/sydney.md2\""), "relative below the scene's folder:\n{text}");
    let outside_abs = std::fs::canonicalize(&outside).expect("canonical");
    assert!(
        text.contains(&format!("path: \"{}\"", outside_abs.display())),
        "absolute outside the scene's folder"
    );
    drop(h);

    let moved = root.path().join("moved");
    std::fs::rename(&project, &moved).expect("move the project folder");
    let mut h = common::harness(root.path(), Some(moved.join("scene.ron")));
    h.run();
    assert!(h.state().status().is_none_or(|s| !s.is_error), "{:?}", h.state().status().cloned());
    let Some(keyrig_core::MeshSource::File { path, .. }) = &h.state().doc.scene().objects[first].mesh else {
        panic!("a file mesh")
    };
    assert!(
        std::path::Path::new(path).starts_with(std::fs::canonicalize(&moved).expect("canonical")),
        "{path}"
    );
    assert!(h.state().skin_cache().deformed_positions(first).is_some(), "the moved model loads and morphs");
    assert!(h.state().skin_cache().deformed_positions(first + 1).is_some(), "the outside model loads too");
}
