//! Every check on a model file that an import or an export makes returns a typed error that
//! says where and what: external glTF buffers (`GltfErrorKind`) and the model files a scene's
//! objects come from (`MeshFileError`).

use std::fs;
use std::path::{Path, PathBuf};

use keyrig_core::{MeshSource, Object, Scene};
use keyrig_io::gltf_export::{export_scene, ExportError, ExportOptions, MeshFileError};
use keyrig_io::gltf_import::{import_gltf_file, import_gltf_slice, GltfErrorKind};
use serde_json::{json, Value};

fn md2_corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/md2").join(rel)
}

/// A glTF document whose one buffer is the external file `uri`.
fn with_buffer_uri(uri: &str) -> Vec<u8> {
    serde_json::to_vec(&json!({
        "asset": {"version": "2.0"},
        "buffers": [{"uri": uri, "byteLength": 4}],
    }))
    .expect("JSON")
}

/// Imports a .gltf whose buffer is `uri`, from a folder holding `a.bin`.
fn import_with_uri(uri: &str) -> (GltfErrorKind, String) {
    let dir = tempfile::tempdir().expect("temp dir");
    fs::write(dir.path().join("a.bin"), [0u8; 4]).expect("write bin");
    let path = dir.path().join("m.gltf");
    fs::write(&path, with_buffer_uri(uri)).expect("write gltf");
    let err = import_gltf_file(&path).expect_err(uri);
    let shown = err.to_string();
    assert!(shown.contains("/buffers/0/uri"), "{shown}");
    (err.kind, shown)
}

#[test]
fn external_buffers_are_checked() {
    // The folder's own file loads.
    let dir = tempfile::tempdir().expect("temp dir");
    fs::write(dir.path().join("a b.bin"), [0u8; 4]).expect("write bin");
    fs::write(dir.path().join("m.gltf"), with_buffer_uri("a%20b.bin")).expect("write gltf");
    import_gltf_file(&dir.path().join("m.gltf")).expect("a relative, escaped URI loads");

    let err = import_gltf_slice(&with_buffer_uri("a.bin")).expect_err("no folder");
    assert!(err.to_string().contains("cannot be resolved when importing from memory"), "{err}");

    let (_, shown) = import_with_uri("http://example.com/a.bin");
    assert!(shown.contains("only relative paths and data: URIs are supported"), "{shown}");
    let (_, shown) = import_with_uri("../a.bin");
    assert!(shown.contains("must stay inside the model's folder"), "{shown}");
    for bad in ["a%zz.bin", "a.bin%2"] {
        let (_, shown) = import_with_uri(bad);
        assert!(shown.contains("bad escape in URI"), "{shown}");
    }
    let (_, shown) = import_with_uri("%ff.bin");
    assert!(shown.contains("is not UTF-8"), "{shown}");
    let (kind, shown) = import_with_uri("missing.bin");
    let GltfErrorKind::BufferFile { path, .. } = kind else { panic!("{shown}") };
    assert!(path.ends_with("missing.bin"), "{shown}");
}

/// A scene of one object whose mesh is `source`.
fn scene_with(source: MeshSource) -> Scene {
    let mut object = Object::new("M");
    object.mesh = Some(source);
    Scene { objects: vec![object], ..Scene::default() }
}

/// Exports `scene` with model paths relative to `dir`; the mesh-file error and its text.
fn mesh_file_error(scene: &Scene, dir: &Path) -> (MeshFileError, String) {
    let options = ExportOptions { base_dir: Some(dir.to_path_buf()), ..ExportOptions::default() };
    let Err(err) = export_scene(scene, &options) else { panic!("export must fail") };
    let shown = err.to_string();
    assert!(shown.starts_with("objects[0].mesh: cannot load mesh file "), "{shown}");
    let ExportError::MeshFile { source, .. } = err else { panic!("{shown}") };
    (*source, shown)
}

/// The demo scene exported as .glb, with `edit` applied to its JSON, written as `name`.
fn edited_demo_glb(dir: &Path, name: &str, edit: impl FnOnce(&mut Value)) {
    let mut exported =
        export_scene(&keyrig_io::demo::demo_scene(), &ExportOptions::default()).expect("export");
    edit(&mut exported.json);
    fs::write(dir.join(name), exported.to_glb()).expect("write glb");
}

#[test]
fn model_files_of_objects_are_checked() {
    let dir = tempfile::tempdir().expect("temp dir");
    let dir = dir.path();

    let (err, shown) = mesh_file_error(&scene_with(MeshSource::file("missing.gltf", None)), dir);
    assert!(matches!(err, MeshFileError::Gltf(_)), "{shown}");
    let (err, shown) = mesh_file_error(&scene_with(MeshSource::file("missing.md2", None)), dir);
    assert!(matches!(err, MeshFileError::Md2(_)), "{shown}");

    edited_demo_glb(dir, "demo.glb", |_| {});
    let (err, shown) = mesh_file_error(&scene_with(MeshSource::file("demo.glb", Some(7))), dir);
    assert!(matches!(err, MeshFileError::NoMesh(7)), "{shown}");
    assert!(shown.ends_with("has no mesh 7"), "{shown}");

    edited_demo_glb(dir, "hidden.glb", |json| {
        for node in json["nodes"].as_array_mut().expect("nodes") {
            if let Some(node) = node.as_object_mut() {
                node.remove("mesh");
                node.remove("skin");
            }
        }
    });
    let (err, shown) = mesh_file_error(&scene_with(MeshSource::file("hidden.glb", Some(0))), dir);
    assert!(matches!(err, MeshFileError::MeshNotShown(0)), "{shown}");

    edited_demo_glb(dir, "points.glb", |json| {
        for mesh in json["meshes"].as_array_mut().expect("meshes") {
            for primitive in mesh["primitives"].as_array_mut().expect("primitives") {
                primitive["mode"] = json!(0);
            }
        }
    });
    let (err, shown) = mesh_file_error(&scene_with(MeshSource::file("points.glb", Some(0))), dir);
    assert!(matches!(err, MeshFileError::NoTriangles(0)), "{shown}");

    // A skinned mesh whose primitives lost their joints and weights: the skin cannot bind it.
    // The scene was made from the file before it lost them (as `keyrig import` makes it).
    let demo = keyrig_io::gltf_import::import_gltf_file(&dir.join("demo.glb")).expect("import demo.glb");
    let scene = demo.to_scene("unweighted.glb", None).expect("scene of demo.glb");
    assert!(scene.objects.iter().any(|o| o.skeleton.is_some()), "the demo's arm has a skeleton");
    edited_demo_glb(dir, "unweighted.glb", |json| {
        for mesh in json["meshes"].as_array_mut().expect("meshes") {
            for primitive in mesh["primitives"].as_array_mut().expect("primitives") {
                let attributes = primitive["attributes"].as_object_mut().expect("attributes");
                attributes.remove("JOINTS_0");
                attributes.remove("WEIGHTS_0");
            }
        }
    });
    let (err, shown) = mesh_file_error(&scene, dir);
    assert!(matches!(err, MeshFileError::Skin(_)), "{shown}");
    assert!(shown.ends_with("a primitive has no JOINTS_0/WEIGHTS_0"), "{shown}");
}

#[test]
fn md2_clips_and_rates_are_checked_on_export() {
    let sydney = md2_corpus("sydney/sydney.md2");
    let dir = sydney.parent().expect("folder");
    let md2 = |clip: Option<&str>, fps: Option<f64>| MeshSource::File {
        path: "sydney.md2".into(),
        mesh: None,
        clip: clip.map(str::to_string),
        fps,
    };

    let (err, shown) = mesh_file_error(&scene_with(md2(Some("fly"), None)), dir);
    let MeshFileError::NoClip { clip, clips } = &err else { panic!("{shown}") };
    assert_eq!(clip, "fly");
    assert!(clips.iter().any(|c| c == "run"), "{shown}");
    assert!(shown.contains("no clip `fly` (clips: "), "{shown}");

    for fps in [0.0, -1.0, f64::NAN] {
        let (err, shown) = mesh_file_error(&scene_with(md2(None, Some(fps))), dir);
        assert!(matches!(err, MeshFileError::BadFps(_)), "{shown}");
    }

    let mut scene = scene_with(md2(None, Some(1000.0)));
    scene.frame_range.end = i32::MAX;
    let (err, shown) = mesh_file_error(&scene, dir);
    assert!(matches!(err, MeshFileError::TooManyFrames), "{shown}");

    // Too many frames counted from a range that starts far before 0, too.
    let mut scene = scene_with(md2(Some("run"), Some(1.0)));
    scene.fps = 1.0;
    scene.frame_range.start = -6_000_000;
    scene.frame_range.end = 6_000_000;
    let (err, shown) = mesh_file_error(&scene, dir);
    assert!(matches!(err, MeshFileError::TooManyFrames), "{shown}");

    let mut scene = scene_with(md2(None, None));
    scene.fps = 0.0;
    let (err, shown) = mesh_file_error(&scene, dir);
    assert!(matches!(err, MeshFileError::FrameRangeNotFinite), "{shown}");
    // One end finite is not enough: a rate so small that the range's end is infinitely far.
    let mut scene = scene_with(md2(None, None));
    (scene.fps, scene.frame_range.start, scene.frame_range.end) = (1e-310, 0, 10);
    let (err, shown) = mesh_file_error(&scene, dir);
    assert!(matches!(err, MeshFileError::FrameRangeNotFinite), "{shown}");
}
