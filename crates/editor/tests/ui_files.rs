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

/// A model imported into a scene brings its actions (docs/actions.md); imported twice, the
/// second copy's object and actions get names of their own, and the scene stays valid.
#[test]
fn an_imported_model_brings_its_actions_and_twice_stays_valid() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness_autosaving(dir.path(), None, 1e9);
    for _ in 0..2 {
        h.state_mut().import_path(corpus("gltf/Fox/Fox.glb"));
        h.state_mut().wait_for_background_work();
        h.run();
    }
    let scene = h.state().doc.scene();
    let names: Vec<&str> = scene.actions.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["Survey", "Walk", "Run", "Survey.001", "Walk.001", "Run.001"]);
    let foxes: Vec<(&str, Option<&str>)> = scene
        .objects
        .iter()
        .filter(|o| o.name.starts_with("fox"))
        .map(|o| (o.name.as_str(), o.action.as_deref()))
        .collect();
    assert_eq!(foxes, [("fox", Some("Survey")), ("fox.001", Some("Survey.001"))]);
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    // The second fox walks with its own Walk.
    let mut walking = scene.clone();
    let second = walking.objects.iter().position(|o| o.name == "fox.001").expect("fox.001");
    walking.assign_action(second, Some("Walk.001")).expect("Walk.001");
    assert_eq!(walking.keyed_channels_of(second).len(), 21);
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

/// Reopening a saved scene restores the session it was left with: the current frame, the
/// viewport's camera, the selection and the panel sizes. They are kept in the data folder
/// (`sessions.json`), not in the scene file, which stays as it was saved.
#[test]
fn reopening_a_scene_restores_frame_camera_selection_and_panel_sizes() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("shot.ron");
    let outliner_width = |h: &egui_kittest::Harness<'_, keyrig_editor::EditorApp>| {
        egui::containers::panel::PanelState::load(&h.ctx, egui::Id::new("outliner")).expect("laid out").rect
    };
    let (frame, camera, width) = {
        let mut h = common::harness(dir.path(), None);
        h.state_mut().save_to(file.clone());
        h.run();
        let saved = std::fs::read(&file).expect("saved");
        h.get_by_label("elbow").click();
        h.run();
        common::go_to_frame(&mut h, 25);
        // Orbit from empty space at the viewport's top left, then widen the outliner by its edge.
        let rect = h.state().viewport_rect().expect("a viewport");
        let start = rect.left_top() + egui::vec2(40.0, 60.0);
        common::drag(&mut h, start, start + egui::vec2(80.0, 20.0));
        let edge = outliner_width(&h);
        // Just inside the edge: the viewport, laid out after the outliner, takes the points
        // from the edge on. The pointer rests there a frame before the press, as a hand's does.
        let grip = egui::pos2(edge.right() - 3.0, edge.center().y);
        common::pointer(&mut h, egui::Event::PointerMoved(grip));
        common::drag(&mut h, grip, grip + egui::vec2(70.0, 0.0));
        let width = outliner_width(&h).width();
        assert!(width > edge.width() + 40.0, "the outliner widened: {} → {width}", edge.width());
        let camera = h.state().view.camera;
        assert_ne!(camera, h.state().doc.scene().camera, "the view was orbited");
        // Leaving the file (File ▸ New) remembers its session; the file itself is unchanged.
        h.state_mut().perform(keyrig_editor::app::PendingAction::New);
        h.run();
        assert_eq!(std::fs::read(&file).expect("still there"), saved, "the scene file is not touched");
        (h.state().session.playback.whole_frame(), camera, width)
    };
    assert_eq!(frame, 0, "a new scene starts at its first frame");
    assert!(dir.path().join("sessions.json").exists());

    let mut h = common::harness(dir.path(), Some(file.clone()));
    h.run();
    assert_eq!(h.state().session.playback.whole_frame(), 25);
    assert_eq!(h.state().view.camera, camera);
    assert_eq!(
        h.state().session.selection.item,
        Some(keyrig_editor::session::Selected::Joint { object: 0, joint: 1 }),
        "the elbow is selected again"
    );
    assert!((outliner_width(&h).width() - width).abs() < 2.0, "{} vs {width}", outliner_width(&h).width());
    assert!(!h.state().doc.is_dirty(), "restoring the session is no edit");
}

/// A PNG dropped on the window becomes the reference image behind the scene (one undo step),
/// drawn in the viewport; its opacity is the inspector's slider; the scene file names it
/// relative to its folder, as models; an image that cannot be read is refused with its name in
/// the status bar, and a scene whose image is missing opens with the error over the viewport.
#[test]
fn a_dropped_image_is_the_reference_image_saved_relative_to_the_scene() {
    let dir = tempfile::tempdir().expect("temp dir");
    let png = dir.path().join("ref.png");
    image::RgbaImage::from_pixel(4, 2, image::Rgba([200, 100, 50, 255])).save(&png).expect("png");
    let file = dir.path().join("shot.ron");
    keyrig_io::project::save_scene(&file, &keyrig_io::demo::demo_scene()).expect("save");
    let mut h = common::harness(dir.path(), Some(file.clone()));
    let steps = h.state().doc.undo_len();
    h.input_mut().dropped_files.push(egui::DroppedFile { path: Some(png.clone()), ..Default::default() });
    h.run();
    let reference = h.state().doc.scene().reference_image.clone().expect("a reference image");
    assert_eq!(std::path::PathBuf::from(&reference.path), std::path::absolute(&png).expect("absolute"));
    assert_eq!(reference.opacity, 0.5);
    assert_eq!(h.state().doc.undo_len(), steps + 1);
    assert_eq!(h.state().doc.undo_label(), Some("reference image ref.png"));
    h.run();
    assert_eq!(h.state().panels().viewport.reference_image_size(), Some([4, 2]), "drawn behind the scene");
    assert!(h.state().viewport_errors().is_empty(), "{:?}", h.state().viewport_errors());

    common::set_value(&mut h, egui::accesskit::Role::Slider, "Reference opacity", 0.25);
    assert_eq!(h.state().doc.scene().reference_image.as_ref().map(|r| r.opacity), Some(0.25));
    h.state_mut().save_to(file.clone());
    let text = std::fs::read_to_string(&file).expect("saved");
    let at = text.find("reference_image: Some((").expect("the reference image is saved");
    let saved = &text[at..];
    assert!(saved.contains("path: \"ref.png\",") && saved.contains("opacity: 0.25,"), "{saved}");

    // A file that is no image is refused; the scene keeps its image.
    let junk = dir.path().join("junk.png");
    std::fs::write(&junk, b"not a picture").expect("write");
    h.input_mut().dropped_files.push(egui::DroppedFile { path: Some(junk), ..Default::default() });
    h.run();
    let status = h.state().status().cloned().expect("a message");
    assert!(status.is_error && status.text.contains("junk.png"), "{status:?}");
    assert!(h.state().doc.scene().reference_image.as_ref().is_some_and(|r| r.path.ends_with("ref.png")));

    h.get_by_label("Remove reference image").click();
    h.run();
    assert!(h.state().doc.scene().reference_image.is_none());
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert!(h.state().doc.scene().reference_image.is_some(), "undo brings it back");

    // Reopened without its image: an error over the viewport, the scene drawn as without one.
    std::fs::remove_file(&png).expect("remove");
    let mut again = common::harness(dir.path(), Some(file));
    again.run();
    let errors = again.state().viewport_errors().to_vec();
    assert!(errors.iter().any(|e| e.contains("ref.png") && e.contains("cannot read")), "{errors:?}");
    assert_eq!(again.state().panels().viewport.reference_image_size(), None);
}
