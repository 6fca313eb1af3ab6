//! glTF files keep every animation (docs/actions.md): a model's animations come in as actions
//! of their names, and each action goes out as a glTF animation of its name.
//!
//! The Fox (`Survey`, `Walk`, `Run`) is imported as every command imports it
//! (`ImportedModel::to_scene_all`), exported with `export_scene`, and both files are read by
//! the independent evaluator of `reference/` (the `gltf` crate's readers and the
//! specification's samplers): at every frame of each animation the exported skin's vertices
//! must be within 1e-5 of the model's size of the source's. The Khronos validator must report
//! 0 errors and 0 warnings.

mod reference;

use std::path::Path;

use keyrig_io::gltf_export::{export_scene, ExportOptions};
use reference::{corpus, mesh_node, read_reference, size_of, validate, Interpolator};

const TOLERANCE: f64 = 1e-5;
const FPS: f64 = 30.0;

fn skinned_node(doc: &gltf::Document) -> gltf::Node<'_> {
    doc.nodes().find(|n| n.skin().is_some() && n.mesh().is_some()).expect("a skinned mesh node")
}

#[test]
fn the_fox_goes_out_with_survey_walk_and_run() {
    let path = corpus("gltf/Fox/Fox.glb");
    let model = keyrig_io::gltf_import::import_gltf_file(&path).expect("Fox");
    let scene = model.to_scene_all(&path.to_string_lossy()).expect("scene");
    let names: Vec<&str> = scene.actions.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["Survey", "Walk", "Run"]);
    assert_eq!(scene.objects[0].action.as_deref(), Some("Survey"));
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());

    let options =
        ExportOptions { base_dir: path.parent().map(Path::to_path_buf), ..ExportOptions::default() };
    let exported = export_scene(&scene, &options).expect("export");
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("fox.glb");
    std::fs::write(&out, exported.to_glb()).expect("write");

    let (errors, warnings, report) = validate(&out);
    assert_eq!((errors, warnings), (0, 0), "{report}");

    let (src_doc, src_buffers, _) = gltf::import(&path).expect("source");
    let (out_doc, out_buffers, _) = gltf::import(&out).expect("export");
    let out_names: Vec<String> =
        out_doc.animations().map(|a| a.name().unwrap_or_default().to_owned()).collect();
    assert_eq!(out_names, ["Survey", "Walk", "Run"]);
    let (src, back) = (read_reference(&src_doc, &src_buffers), read_reference(&out_doc, &out_buffers));
    let (src_mesh, out_mesh) =
        (mesh_node(&skinned_node(&src_doc), &src_buffers), mesh_node(&skinned_node(&out_doc), &out_buffers));
    for a in src_doc.animations() {
        let name = a.name().unwrap_or_default();
        let b = out_names.iter().position(|n| n == name).expect("the animation is exported");
        let size = size_of(&src_mesh.at(&src, Some(a.index()), 0.0, Interpolator::Spec));
        let frames = (src.duration(a.index()) * FPS).ceil() as usize;
        let mut worst = 0.0f64;
        for frame in 0..=frames {
            let t = (frame as f64 / FPS).min(src.duration(a.index()));
            let want = src_mesh.at(&src, Some(a.index()), t, Interpolator::Spec);
            let got = out_mesh.at(&back, Some(b), t, Interpolator::Spec);
            assert_eq!(want.len(), got.len());
            for (v, (w, g)) in want.iter().zip(&got).enumerate() {
                let error = (*w - *g).length() / size;
                assert!(error <= TOLERANCE, "{name}, frame {frame}, vertex {v}: {g:?} vs {w:?}: {error:.2e}");
                worst = worst.max(error);
            }
        }
        assert!(worst.is_finite() && frames > 10, "{name}: {frames} frames");
        println!("{name}: {} frames, worst {worst:.2e} of the model's size", frames + 1);
    }
}

/// InterpolationTest holds an animation per cube: each becomes an action of its name, each cube
/// plays the one that moves it (so all nine play together), and export writes the nine back.
#[test]
fn interpolation_test_plays_its_nine_animations_together_and_writes_them_back() {
    let path = corpus("gltf/InterpolationTest/InterpolationTest.glb");
    let model = keyrig_io::gltf_import::import_gltf_file(&path).expect("InterpolationTest");
    let scene = model.to_scene_all(&path.to_string_lossy()).expect("scene");
    let wanted: Vec<String> = model.animations.iter().map(|a| a.name.clone()).collect();
    assert_eq!(wanted.len(), 9);
    let names: Vec<String> = scene.actions.iter().map(|a| a.name.clone()).collect();
    assert_eq!(names, wanted);
    // Nine cubes move: each plays its own action, whose keys are the cube's own.
    let moving: Vec<&str> = scene
        .objects
        .iter()
        .enumerate()
        .filter(|(o, _)| !scene.keyed_channels_of(*o).is_empty())
        .map(|(_, x)| x.action.as_deref().expect("an action"))
        .collect();
    assert_eq!(moving.len(), 9, "{moving:?}");
    let mut sorted = moving.clone();
    sorted.sort_unstable();
    sorted.dedup();
    assert_eq!(sorted.len(), 9, "each cube its own action: {moving:?}");
    assert!(scene.actions.iter().all(|a| a.channels.is_empty()), "every action plays");

    let options =
        ExportOptions { base_dir: path.parent().map(Path::to_path_buf), ..ExportOptions::default() };
    let exported = export_scene(&scene, &options).expect("export");
    let back = keyrig_io::gltf_import::import_gltf_slice(&exported.to_glb()).expect("re-import");
    let back_names: Vec<String> = back.animations.iter().map(|a| a.name.clone()).collect();
    assert_eq!(back_names, wanted);
    // Each exported animation moves the node of the same name as the source's.
    for (a, src) in model.animations.iter().enumerate() {
        let src_nodes: Vec<&str> = src.channels.iter().map(|c| model.nodes[c.node].name.as_str()).collect();
        let out_nodes: Vec<&str> =
            back.animations[a].channels.iter().map(|c| back.nodes[c.node].name.as_str()).collect();
        assert_eq!(src_nodes, out_nodes, "{}", src.name);
        let duration = src.duration();
        for i in 0..=20 {
            let t = duration * f64::from(i) / 20.0 * 0.999;
            let (want, got) = (model.pose_at(Some(a), t), back.pose_at(Some(a), t));
            for c in &src.channels {
                let n = back.nodes.iter().position(|x| x.name == model.nodes[c.node].name).expect("node");
                let d = (want.translation[c.node] - got.translation[n]).length()
                    + (want.scale[c.node] - got.scale[n]).length();
                assert!(d < 1e-4, "{} at {t}: {d}", src.name);
                let angle = keyrig_io::gltf_export::rotation_angle(want.rotation[c.node], got.rotation[n]);
                assert!(angle.to_degrees() <= 0.06, "{} at {t}: {angle}", src.name);
            }
        }
    }
}
