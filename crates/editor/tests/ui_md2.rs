//! MD2 models in the editor: imported (dropped on the window) in the background with the
//! import shown in the status bar, morphing over scene time, clip and rate edited in the
//! inspector and undone, saved and reopened, opened as a new scene; a malformed file is a
//! status-bar error.

mod common;

use common::{corpus, harness};

use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use keyrig_core::MeshSource;
use keyrig_editor::files::ImportPurpose;
use keyrig_editor::session::Selected;
use keyrig_editor::{editor_for, EditorApp, EditorOptions};

/// Object-space positions the viewport morphed for object `o` at `frame`.
fn positions_at(h: &mut Harness<'static, EditorApp>, o: usize, frame: i32) -> Vec<glam::Vec3> {
    h.state_mut().set_frame(frame);
    h.run();
    h.state().skin_cache().deformed_positions(o).expect("the viewport morphed the model").to_vec()
}

#[test]
fn dropped_md2_is_imported_in_the_background_and_morphs_over_time() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let before = h.state().doc.scene().objects.len();
    let model = corpus("md2/sydney/sydney.md2");
    h.input_mut().dropped_files.push(egui::DroppedFile { path: Some(model.clone()), ..Default::default() });
    // The frame that takes the drop starts the import; results are applied from the next
    // frame on, so this frame's status bar shows the running import.
    h.step();
    assert_eq!(h.state().imports().len(), 1);
    assert_eq!(h.state().imports()[0].purpose, ImportPurpose::Import);
    assert!(h.query_by_label_contains("Importing sydney.md2").is_some(), "the status bar shows the import");
    h.state_mut().wait_for_background_work();
    h.run();
    assert!(h.state().imports().is_empty());
    let status = h.state().status().cloned().expect("a message");
    assert!(!status.is_error && status.text.contains("sydney.md2"), "{status:?}");

    let scene = h.state().doc.scene();
    assert_eq!(scene.objects.len(), before + 1);
    let object = &scene.objects[before];
    assert_eq!(object.name, "sydney");
    let Some(MeshSource::File { path, mesh: None, clip: None, fps: Some(fps) }) = &object.mesh else {
        panic!("an MD2 file mesh: {:?}", object.mesh)
    };
    assert!(std::path::Path::new(path).is_absolute() && path.ends_with("sydney.md2"), "{path}");
    assert_eq!(*fps, 10.0);
    assert!(object.skeleton.is_none());

    // Frame 0 and frame 5 (1/6 s, model frame 1.67 at 10 fps) show different vertices.
    let a = positions_at(&mut h, before, 0);
    let b = positions_at(&mut h, before, 5);
    assert_eq!(a.len(), b.len());
    let moved = a.iter().zip(&b).filter(|(p, q)| p.distance(**q) > 1e-3).count();
    assert!(moved > a.len() / 10, "{moved} of {} vertices moved", a.len());
    assert_eq!(positions_at(&mut h, before, 0), a, "the same time gives the same vertices");

    // The model's loop is longer than the demo's 90 frames: the range grew to cover it, and
    // the status bar said so.
    let end = h.state().doc.scene().frame_range.end;
    assert!(end > 90, "range end {end}");
    assert!(status.text.contains(&format!("frame range extended from 0–90 to 0–{end}")), "{status:?}");

    // The import is one undo step, the range's growth with it.
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    assert_eq!(h.state().doc.scene().objects.len(), before);
    assert_eq!(h.state().doc.scene().frame_range.end, 90);
}

#[test]
fn clip_and_rate_are_edited_in_the_inspector_saved_and_reopened() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let o = h.state().doc.scene().objects.len();
    h.state_mut().import_path(corpus("md2/faerie/faerie.md2"));
    h.state_mut().wait_for_background_work();
    h.run();
    h.state_mut().session.selection.item = Some(Selected::Object(o));
    h.run();
    let mesh_of = |h: &Harness<'static, EditorApp>| h.state().doc.scene().objects[o].mesh.clone();

    // Choose the `run` clip (6 frames): frame 0 now shows the clip's first frame.
    let all_frames = positions_at(&mut h, o, 3);
    h.get_by_label("Clip").click();
    h.run();
    h.get_by_label("run (6 frames)").click();
    h.run();
    let Some(MeshSource::File { clip, .. }) = mesh_of(&h) else { panic!("file mesh") };
    assert_eq!(clip.as_deref(), Some("run"));
    assert_ne!(positions_at(&mut h, o, 3), all_frames, "another clip shows other frames");
    assert!(h.state().doc.undo_label().is_some_and(|l| l.contains("clip run")));

    // The rate: typed into the inspector's field.
    h.get_by_label("Model fps").click();
    h.run();
    h.get_by_label("Model fps").type_text("15");
    h.key_press(Key::Enter);
    h.run();
    let Some(MeshSource::File { fps, .. }) = mesh_of(&h) else { panic!("file mesh") };
    assert_eq!(fps, Some(15.0));

    // Save, reopen, compare.
    let path = dir.path().join("md2.ron");
    h.state_mut().save_to(path.clone());
    h.run();
    let saved = h.state().doc.scene().clone();
    let reopened = harness(dir.path(), Some(path));
    assert_eq!(reopened.state().doc.scene(), &saved);

    // Undo takes back the rate, then the clip.
    h.state_mut().session.selection.item = None;
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    let Some(MeshSource::File { fps, .. }) = mesh_of(&h) else { panic!("file mesh") };
    assert_eq!(fps, Some(10.0));
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
    let Some(MeshSource::File { clip, .. }) = mesh_of(&h) else { panic!("file mesh") };
    assert_eq!(clip, None);
}

#[test]
fn opening_an_md2_makes_a_scene_that_covers_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let model = corpus("md2/dolphin/dolphin.md2");
    // `keyrig edit dolphin.md2`: the editor starts at once and reads the model in the
    // background.
    let mut h = harness(dir.path(), Some(model.clone()));
    h.state_mut().wait_for_background_work();
    h.run();
    let scene = h.state().doc.scene().clone();
    assert_eq!(scene.objects.len(), 1);
    // 59 frames at 10 fps = 5.9 s = 177 frames at 30 fps: 0..=176, then the loop starts again.
    assert_eq!((scene.frame_range.start, scene.frame_range.end), (0, 176));
    // The camera looks at the model (its first frame's bounds), not at the default origin.
    assert_ne!(scene.camera, keyrig_core::Scene::default().camera);
    assert!(scene.camera.distance.is_finite() && scene.camera.distance > 0.0, "{:?}", scene.camera);
    assert!(!scene.lights.is_empty(), "a model opens with a light");
    assert!(h.state().doc.path().is_none(), "a model is not the document's file");

    // No skeleton, so no deformer: the toolbar shows none chosen and the number keys change
    // nothing (no edit, no undo step, still clean) but say why in the status bar.
    assert_eq!(h.state().current_deformer(), None);
    let dirty = h.state().doc.is_dirty();
    let undo = h.state().doc.undo_label().map(str::to_owned);
    h.key_press_modifiers(Modifiers::NONE, Key::Num3);
    h.run();
    assert_eq!(h.state().doc.scene(), &scene);
    assert_eq!((h.state().doc.is_dirty(), h.state().doc.undo_label()), (dirty, undo.as_deref()));
    let status = h.state().status().cloned().expect("a message");
    assert!(status.text.contains("No skinned object"), "{status:?}");

    // File ▸ Open of a model runs in the background and gives the same scene.
    let mut h = harness(dir.path(), None);
    h.state_mut().open_path(model);
    assert_eq!(h.state().imports()[0].purpose, ImportPurpose::Open);
    h.state_mut().wait_for_background_work();
    h.run();
    assert_eq!(h.state().doc.scene(), &scene);
    assert!(h.state().skin_cache().deformed_positions(0).is_some_and(|p| !p.is_empty()));
}

#[test]
fn a_malformed_md2_is_a_status_bar_error() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut bytes = std::fs::read(corpus("md2/dolphin/dolphin.md2")).expect("corpus file");
    // num_frames (header field 10, bytes 40..44) far beyond what the file holds.
    bytes[40..44].copy_from_slice(&100_000i32.to_le_bytes());
    let bad = dir.path().join("broken.md2");
    std::fs::write(&bad, &bytes).expect("write");
    let truncated = dir.path().join("short.md2");
    std::fs::write(&truncated, b"IDP2\x08\x00\x00\x00").expect("write");

    let mut h = harness(dir.path(), None);
    let before = h.state().doc.scene().clone();
    for (file, needle) in [(&bad, "broken.md2"), (&truncated, "short.md2")] {
        h.state_mut().import_path(file.clone());
        h.state_mut().wait_for_background_work();
        h.run();
        let status = h.state().status().cloned().expect("an error");
        assert!(
            status.is_error && status.text.contains(needle) && status.text.contains("byte"),
            "{status:?}"
        );
        assert!(h.query_by_label_contains(needle).is_some(), "shown in the status bar");
        assert_eq!(h.state().doc.scene(), &before, "nothing imported");
    }
}

/// `keyrig render scene.ron` plays the scene's MD2 object too (keyrig-render's GPU morph pass,
/// on lavapipe without a GPU): the model opened and saved by the editor renders, and two
/// frames of it differ.
#[test]
fn keyrig_render_plays_a_saved_scene_with_an_md2_object() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.state_mut().open_path(corpus("md2/sydney/sydney.md2"));
    h.state_mut().wait_for_background_work();
    h.run();
    let scene_file = dir.path().join("sydney.ron");
    h.state_mut().save_to(scene_file.clone());
    let render = |frame: &str| {
        let out = dir.path().join(format!("frame{frame}.png"));
        let result = std::process::Command::new(env!("CARGO_BIN_EXE_keyrig"))
            .args(["render", scene_file.to_str().expect("utf-8"), "--frame", frame, "--size", "240x180"])
            .arg("-o")
            .arg(&out)
            .output()
            .expect("run keyrig");
        assert!(result.status.success(), "{}", String::from_utf8_lossy(&result.stderr));
        image::open(&out).expect("a PNG").to_rgba8()
    };
    let (a, b) = (render("0"), render("12"));
    let differing = a.pixels().zip(b.pixels()).filter(|(p, q)| p != q).count();
    assert!(differing > 100, "only {differing} pixels changed between frames 0 and 12");
}

/// The editor's GPU viewport (keyrig-render on the device kittest's wgpu renderer gives it;
/// lavapipe without a GPU) morphs an imported MD2 model: no viewport error, and each frame
/// sends the morph parameters of one morphing mesh.
#[test]
fn an_imported_md2_morphs_in_the_gpu_viewport() {
    let temp = tempfile::tempdir().expect("temp dir");
    let dir = temp.path().to_path_buf();
    let mut h = Harness::builder().wgpu().with_size(egui::vec2(960.0, 600.0)).build_eframe(move |cc| {
        let mut app =
            editor_for(None, EditorOptions { data_dir: Some(dir.clone()), autosave_seconds: Some(1e9) });
        if let Some(rs) = &cc.wgpu_render_state {
            app.attach_gpu(rs);
        }
        app
    });
    h.run();
    assert!(h.state().gpu().is_some(), "kittest's wgpu renderer gives the editor a device");
    h.state_mut().import_path(corpus("md2/ratamahatta/ratamahatta.md2"));
    h.state_mut().wait_for_background_work();
    for frame in [0, 7] {
        h.state_mut().set_frame(frame);
        h.run();
        assert!(!h.state().status().is_some_and(|s| s.is_error), "{:?}", h.state().status().cloned());
        assert_eq!(h.state().viewport_errors(), Vec::<String>::new());
        let stats = h.state().gpu().and_then(|g| g.last_stats).expect("a GPU frame");
        assert_eq!(stats.morph_bytes, 16, "one morphing mesh: {stats:?}");
    }
}
