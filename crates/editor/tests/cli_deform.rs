//! `keyrig deform` end to end: the real binary on a scene written here, the demo scene, a glTF
//! model of the shared corpus, and bad arguments and weights.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use glam::{Quat, Vec3};
use keyrig_core::{
    Animated, DeformerKind, Interpolation, Key, MeshSource, Object, ProceduralMesh, RawTrack, Scene,
};

const KEYRIG: &str = env!("CARGO_BIN_EXE_keyrig");

fn keyrig(args: &[&str]) -> Output {
    Command::new(KEYRIG).args(args).output().expect("run keyrig")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn assert_fails_with(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert!(!o.status.success(), "expected failure, got success");
    assert!(!err.contains("panicked"), "panic:\n{err}");
    for n in needles {
        assert!(err.contains(n), "stderr lacks {n:?}:\n{err}");
    }
}

/// The low-poly arm (centimetres) whose middle joint twists from 0° at t = 0 s through 90° at
/// t = 1 s to 180° at t = 2 s, linear keys.
fn twist_scene(dir: &Path) -> PathBuf {
    let mut scene = Scene::default();
    let mut object = Object::new("Arm");
    object.mesh = Some(MeshSource::Procedural(ProceduralMesh::ArmLowPoly));
    let mut skeleton = keyrig_skin::scene_skeleton_for(ProceduralMesh::ArmLowPoly).unwrap();
    let half = std::f32::consts::FRAC_PI_2;
    skeleton.joints[2].rotation = Animated::new(
        Quat::IDENTITY,
        RawTrack::new(vec![
            Key::new(0.0, Quat::IDENTITY).with_interpolation(Interpolation::Linear),
            Key::new(1.0, Quat::from_rotation_x(half)).with_interpolation(Interpolation::Linear),
            Key::new(2.0, Quat::from_rotation_x(2.0 * half)).with_interpolation(Interpolation::Linear),
        ]),
    );
    object.skeleton = Some(skeleton);
    scene.objects.push(object);
    let path = dir.join("twist.ron");
    keyrig_io::scene_file::save(&path, &scene).unwrap();
    path
}

fn deform_json(file: &Path, when: &[&str], deformer: &str, dir: &Path) -> serde_json::Value {
    let out = dir.join(format!("{deformer}.json"));
    let mut args = vec!["deform", file.to_str().unwrap()];
    args.extend_from_slice(when);
    args.extend_from_slice(&["--deformer", deformer, "-o", out.to_str().unwrap()]);
    let o = keyrig(&args);
    assert!(o.status.success(), "{}", stderr(&o));
    serde_json::from_str(&std::fs::read_to_string(&out).unwrap()).unwrap()
}

fn positions(json: &serde_json::Value, key: &str) -> Vec<Vec3> {
    json[key]
        .as_array()
        .unwrap()
        .iter()
        .map(|p| {
            let c: Vec<f32> = p.as_array().unwrap().iter().map(|x| x.as_f64().unwrap() as f32).collect();
            Vec3::new(c[0], c[1], c[2])
        })
        .collect()
}

/// Mean distance of ring 6 (vertices 36..42, at the middle joint x = 80.079 cm) from the joint.
fn joint_ring_radius(p: &[Vec3]) -> f32 {
    let joint = Vec3::new(80.079, 0.0, 0.0);
    p[36..42].iter().map(|v| v.distance(joint)).sum::<f32>() / 6.0
}

#[test]
fn rest_pose_is_the_mesh_for_every_deformer() {
    let dir = tempfile::tempdir().unwrap();
    let scene = twist_scene(dir.path());
    let mesh = keyrig_skin::mesh_for(ProceduralMesh::ArmLowPoly);
    for kind in DeformerKind::ALL {
        let json = deform_json(&scene, &["--frame", "0"], kind.cli_name(), dir.path());
        assert_eq!(json["vertex_count"], 78);
        assert_eq!(json["deformer"], kind.cli_name());
        let p = positions(&json, "positions");
        let n = positions(&json, "normals");
        for (v, (a, b)) in p.iter().zip(&mesh.positions).enumerate() {
            assert!(a.abs_diff_eq(*b, 1e-3), "{kind:?}: vertex {v} {a} vs {b}");
        }
        for (v, (a, b)) in n.iter().zip(&mesh.normals).enumerate() {
            assert!(a.abs_diff_eq(*b, 1e-4), "{kind:?}: normal {v} {a} vs {b}");
        }
    }
}

#[test]
fn twist_collapses_linear_blend_only() {
    let dir = tempfile::tempdir().unwrap();
    let scene = twist_scene(dir.path());
    let rest = joint_ring_radius(&keyrig_skin::mesh_for(ProceduralMesh::ArmLowPoly).positions);
    // t = 2 s: the 180° twist.
    let linear = joint_ring_radius(&positions(
        &deform_json(&scene, &["--time", "2"], "linear", dir.path()),
        "positions",
    ));
    assert!(linear < 0.05 * rest, "linear blend ring radius {linear} (rest {rest})");
    for deformer in ["bones-blending", "dual-quaternion", "rigid"] {
        let r = joint_ring_radius(&positions(
            &deform_json(&scene, &["--time", "2"], deformer, dir.path()),
            "positions",
        ));
        assert!((r / rest - 1.0).abs() < 1e-3, "{deformer}: ring radius {r} (rest {rest})");
    }
    // --frame uses the scene's 30 fps: frame 30 is t = 1 s, the 90° twist.
    let a = deform_json(&scene, &["--frame", "30"], "linear", dir.path());
    let b = deform_json(&scene, &["--time", "1"], "linear", dir.path());
    assert_eq!(a["positions"], b["positions"]);
    assert_eq!(a["time"], 1.0);
}

#[test]
fn obj_output_has_vertices_normals_and_faces_in_order() {
    let dir = tempfile::tempdir().unwrap();
    let scene = twist_scene(dir.path());
    let out = dir.path().join("arm.obj");
    let o = keyrig(&[
        "deform",
        scene.to_str().unwrap(),
        "--time",
        "1.5",
        "--deformer",
        "dual-quaternion",
        "--object",
        "Arm",
        "-o",
        out.to_str().unwrap(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let text = std::fs::read_to_string(&out).unwrap();
    let count = |prefix: &str| text.lines().filter(|l| l.starts_with(prefix)).count();
    assert_eq!((count("v "), count("vn "), count("f ")), (78, 78, 152));
    assert!(text.lines().any(|l| l == "f 1//1 2//2 8//8"), "first side triangle");
    let json = deform_json(&scene, &["--time", "1.5"], "dual-quaternion", dir.path());
    let first: Vec<f32> = text.lines().find(|l| l.starts_with("v ")).unwrap()[2..]
        .split_whitespace()
        .map(|x| x.parse().unwrap())
        .collect();
    assert!(Vec3::from_slice(&first).abs_diff_eq(positions(&json, "positions")[0], 1e-5));
}

#[test]
fn demo_scene_and_gltf_model_deform() {
    let dir = tempfile::tempdir().unwrap();
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo.ron");
    let json = deform_json(&demo, &["--frame", "45"], "bones-blending", dir.path());
    assert_eq!(json["object"], "Arm");
    assert_eq!(json["vertex_count"], 1250);
    let model =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf/RiggedSimple/RiggedSimple.glb");
    for kind in DeformerKind::ALL {
        let json = deform_json(&model, &["--time", "0.5"], kind.cli_name(), dir.path());
        let p = positions(&json, "positions");
        assert!(!p.is_empty());
        assert!(p.iter().all(|v| v.is_finite() && v.length() < 1e4), "{kind:?}");
    }
}

/// Issue 5: for linear blend, `keyrig deform MODEL.glb --time T` is exactly what the glTF
/// specification defines (joint world transforms × inverse bind matrices, weights as stored),
/// in the file's world axes and accessor order. CesiumMan and Fox animate joint translations
/// (and Fox scales), which keyrig's own pose cannot hold, so they check the exact path.
#[test]
fn gltf_linear_blend_is_the_specification_s_skinning() {
    let dir = tempfile::tempdir().unwrap();
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf");
    for (file, time) in
        [("CesiumMan/CesiumMan.glb", 0.7), ("Fox/Fox.glb", 1.3), ("RiggedFigure/RiggedFigure.glb", 0.4)]
    {
        let path = corpus.join(file);
        let model = keyrig_io::gltf_import::import_gltf_file(&path).unwrap();
        let node = model.nodes.iter().position(|n| n.mesh.is_some() && n.skin.is_some()).unwrap();
        let expected: Vec<Vec3> =
            model.deformed_positions(node, Some(0), time).unwrap().into_iter().flatten().collect();
        let json = deform_json(&path, &["--time", &time.to_string()], "linear", dir.path());
        assert_eq!(json["space"], "gltf-world", "{file}");
        let got = positions(&json, "positions");
        assert_eq!(got.len(), expected.len(), "{file}: vertex count");
        let (min, max) = expected.iter().fold((Vec3::MAX, Vec3::MIN), |(a, b), &p| (a.min(p), b.max(p)));
        let size = (max - min).length();
        let worst = got.iter().zip(&expected).map(|(a, b)| a.distance(*b)).fold(0.0f32, f32::max);
        assert!(worst <= 1e-4 * size, "{file}: off by {worst} (model size {size})");
    }
}

#[test]
fn bad_arguments_and_files_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let scene = twist_scene(dir.path());
    let s = scene.to_str().unwrap();
    let out = dir.path().join("out.json");
    let o = out.to_str().unwrap();
    assert_fails_with(
        &keyrig(&["deform", s, "--time", "1", "--deformer", "squash", "-o", o]),
        &["unknown deformer `squash`"],
    );
    assert_fails_with(&keyrig(&["deform", s, "--deformer", "linear", "-o", o]), &["--frame", "--time"]);
    assert_fails_with(
        &keyrig(&["deform", s, "--time", "1", "--deformer", "linear", "-o", "out.txt"]),
        &["out.txt", ".obj or .json"],
    );
    assert_fails_with(
        &keyrig(&["deform", s, "--time", "1", "--deformer", "linear", "--object", "Leg", "-o", o]),
        &["no object named `Leg`", "Arm"],
    );
    assert_fails_with(
        &keyrig(&["deform", "missing.ron", "--time", "1", "--deformer", "linear", "-o", o]),
        &["missing.ron"],
    );
    assert_fails_with(
        &keyrig(&["deform", s, "--time", "NaN", "--deformer", "linear", "-o", o]),
        &["not a finite number"],
    );
    assert!(!out.exists());
}

/// RiggedSimple.glb with the first vertex's four weights replaced by `weights`.
fn glb_with_weights(dir: &Path, name: &str, weights: [f32; 4]) -> PathBuf {
    let source =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf/RiggedSimple/RiggedSimple.glb");
    let mut data = std::fs::read(source).unwrap();
    let u32_at = |d: &[u8], at: usize| u32::from_le_bytes(d[at..at + 4].try_into().unwrap()) as usize;
    let json_len = u32_at(&data, 12);
    let json: serde_json::Value = serde_json::from_slice(&data[20..20 + json_len]).unwrap();
    let bin_start = 20 + json_len + 8;
    let accessor = &json["accessors"]
        [json["meshes"][0]["primitives"][0]["attributes"]["WEIGHTS_0"].as_u64().unwrap() as usize];
    assert_eq!(accessor["componentType"], 5126, "float weights");
    let view = &json["bufferViews"][accessor["bufferView"].as_u64().unwrap() as usize];
    let offset = bin_start
        + view["byteOffset"].as_u64().unwrap_or(0) as usize
        + accessor["byteOffset"].as_u64().unwrap_or(0) as usize;
    for (i, w) in weights.iter().enumerate() {
        data[offset + 4 * i..offset + 4 * i + 4].copy_from_slice(&w.to_le_bytes());
    }
    let path = dir.join(format!("bad_weight_{name}.glb"));
    std::fs::write(&path, data).unwrap();
    path
}

#[test]
fn bad_weights_in_a_model_are_clear_errors() {
    let dir = tempfile::tempdir().unwrap();
    let out = dir.path().join("out.json");
    let cases: [(&str, [f32; 4], &[&str]); 3] = [
        ("nan", [f32::NAN, 0.5, 0.0, 0.0], &["bad_weight_nan.glb", "WEIGHTS_0", "not finite"]),
        (
            "negative",
            [-5.0, 6.0, 0.0, 0.0],
            &["bad_weight_negative.glb", "vertex 0: weight WEIGHTS_0[0] = -5 is negative"],
        ),
        ("zero", [0.0; 4], &["bad_weight_zero.glb", "vertex 0: all weights are zero"]),
    ];
    for (name, weights, needles) in cases {
        let model = glb_with_weights(dir.path(), name, weights);
        let o = keyrig(&[
            "deform",
            model.to_str().unwrap(),
            "--time",
            "0",
            "--deformer",
            "linear",
            "-o",
            out.to_str().unwrap(),
        ]);
        assert_fails_with(&o, needles);
        assert!(!out.exists());
    }
}

fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus").join(rel)
}

#[test]
fn md2_models_deform_by_morphing_between_frames_as_the_editor_plays_them() {
    let dir = tempfile::tempdir().unwrap();
    let file = corpus("md2/sydney/sydney.md2");
    let md2 = keyrig_io::md2::load_md2_file(&file).unwrap();
    // The editor plays every frame at MD2_DEFAULT_FPS on a 30 fps timeline: frame 5 is
    // 1/6 s, i.e. MD2 frame position 5/30 · 10 ⅔ between frames 1 and 2.
    for frame in ["0", "5", "7.5"] {
        let json = deform_json(&file, &["--frame", frame], "linear", dir.path());
        assert_eq!(json["animation"], "morph");
        assert_eq!(json["space"], "md2");
        let got = positions(&json, "positions");
        let time = frame.parse::<f64>().unwrap() / 30.0;
        let f = time * keyrig_core::MD2_DEFAULT_FPS;
        let (a, u) = (f.floor() as usize, (f - f.floor()) as f32);
        let (pa, pb) = (md2.frame_pose(a).unwrap(), md2.frame_pose(a + 1).unwrap());
        assert_eq!(got.len(), md2.vertex_count());
        for (i, g) in got.iter().enumerate() {
            let want = pa.positions[i].lerp(pb.positions[i], u);
            assert!((*g - want).length() < 1e-4, "frame {frame} vertex {i}: {g} vs {want}");
        }
        let indices: Vec<u32> =
            json["indices"].as_array().unwrap().iter().map(|i| i.as_u64().unwrap() as u32).collect();
        assert_eq!(indices, md2.indices, "triangles as keyrig-io reads them (counter-clockwise)");
    }
    // Outside the editor's frame range (one loop) is an error that states the range.
    let out = dir.path().join("x.json");
    assert_fails_with(
        &keyrig(&[
            "deform",
            file.to_str().unwrap(),
            "--frame",
            "100000",
            "--deformer",
            "linear",
            "-o",
            out.to_str().unwrap(),
        ]),
        &["--frame 100000 is outside the scene's frame range 0..="],
    );
}

#[test]
fn gltf_morph_target_models_deform_as_base_plus_weighted_targets() {
    let dir = tempfile::tempdir().unwrap();
    let file = corpus("gltf/AnimatedMorphCube/AnimatedMorphCube.glb");
    let model = keyrig_io::gltf_import::import_gltf_file(&file).unwrap();
    let node = model.nodes.iter().position(|n| n.mesh.is_some()).unwrap();
    let mut moved = false;
    for time in [0.0, 0.4, 1.0, 1.7] {
        let json = deform_json(&file, &["--time", &time.to_string()], "linear", dir.path());
        assert_eq!(json["animation"], "morph");
        assert_eq!(json["space"], "gltf-world");
        let got = positions(&json, "positions");
        // The glTF reference: p + Σ wᵢ·Δpᵢ with the animation's weights, by the node's world
        // transform.
        let want: Vec<Vec3> = model.deformed_positions(node, Some(0), time).unwrap().concat();
        assert_eq!(got.len(), want.len());
        for (g, w) in got.iter().zip(&want) {
            assert!((*g - *w).length() < 1e-5, "t {time}: {g} vs {w}");
        }
        moved |= got
            .iter()
            .zip(&model.meshes[0].primitives[0].positions[..])
            .any(|(g, p)| (*g - *p).length() > 1e-3);
    }
    assert!(moved, "the targets move the cube at some time");
}

/// Issue 31: a scene's own morph-weight keys morph its glTF object. The scene evaluator gives
/// the weights (`object/<name>/morph/<i>`); the model file only the base and the targets. The
/// scene made from AnimatedMorphCube is given keys of its own: target 0 at 1 and target 1 at 0
/// at t = 0.5 s, which the file's weights channel never reaches; the vertices (in the object's
/// model space) are the file's base plus target 0's displacements.
#[test]
fn a_scene_s_own_morph_weight_keys_morph_its_gltf_object() {
    let dir = tempfile::tempdir().unwrap();
    let file = corpus("gltf/AnimatedMorphCube/AnimatedMorphCube.glb");
    let path = dir.path().join("morph.ron");
    let o = keyrig(&["import", file.to_str().unwrap(), "-o", path.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let mut scene = keyrig_io::scene_file::load(&path).unwrap();
    let weights = &mut scene.objects[0].attributes.morph_weights;
    assert_eq!(weights.len(), 2, "one channel per target");
    for (target, value) in [(0usize, 1.0f32), (1, 0.0)] {
        weights[target] = Animated::new(
            value,
            RawTrack::new(vec![
                Key::new(0.0, value).with_interpolation(Interpolation::Linear),
                Key::new(1.0, value).with_interpolation(Interpolation::Linear),
            ]),
        );
    }
    keyrig_io::scene_file::save(&path, &scene).unwrap();
    let json = deform_json(&path, &["--time", "0.5"], "linear", dir.path());
    assert_eq!(json["animation"], "morph");
    assert_eq!(json["space"], "model");
    let got = positions(&json, "positions");
    let model = keyrig_io::gltf_import::import_gltf_file(&file).unwrap();
    let prim = &model.meshes[0].primitives[0];
    let want = keyrig_io::model::ImportedModel::morphed_positions(prim, &[1.0, 0.0]);
    assert_eq!(got.len(), want.len());
    let mut moved = false;
    for ((g, w), base) in got.iter().zip(&want).zip(&prim.positions[..]) {
        assert!((*g - *w).length() < 1e-6, "{g} vs {w}");
        moved |= (*w - *base).length() > 1e-3;
    }
    assert!(moved, "target 0 moves the cube");
}

/// Issue 29: a scene made from a model (`keyrig import`) deforms like the model file itself
/// where the scene has not changed it: every skinned model of the corpus, every deformer, at a
/// time inside its animation. The scene reads the mesh from the model file (the path it holds
/// is relative to the scene's folder) and poses it with its own keys through the evaluator.
#[test]
fn a_scene_made_from_a_skinned_model_deforms_as_the_model_file_does() {
    let dir = tempfile::tempdir().unwrap();
    let models = [
        ("gltf/RiggedSimple/RiggedSimple.glb", 0.5),
        ("gltf/RiggedSimple/glTF/RiggedSimple.gltf", 0.8),
        ("gltf/RiggedFigure/RiggedFigure.glb", 0.4),
        ("gltf/CesiumMan/CesiumMan.glb", 0.7),
        ("gltf/Fox/Fox.glb", 1.3),
        ("gltf/SimpleSkin/glTF/SimpleSkin.gltf", 2.5),
        ("gltf/SimpleSkin/glTF-Embedded/SimpleSkin.gltf", 1.0),
    ];
    for (n, (model, time)) in models.into_iter().enumerate() {
        let model = corpus(model);
        let scene = dir.path().join(format!("scene{n}.ron"));
        let o = keyrig(&["import", model.to_str().unwrap(), "-o", scene.to_str().unwrap()]);
        assert!(o.status.success(), "{}: {}", model.display(), stderr(&o));
        for deformer in ["linear", "dual-quaternion"] {
            let time = time.to_string();
            let from_model = deform_json(&model, &["--time", &time], deformer, dir.path());
            let from_scene = deform_json(&scene, &["--time", &time], deformer, dir.path());
            assert_eq!(from_scene["object"], from_model["object"], "{}", model.display());
            assert_eq!(from_scene["animation"], "skin");
            let (a, b) = (positions(&from_model, "positions"), positions(&from_scene, "positions"));
            assert_eq!(a.len(), b.len(), "{}: vertex count", model.display());
            let (min, max) = a.iter().fold((Vec3::MAX, Vec3::MIN), |(lo, hi), &p| (lo.min(p), hi.max(p)));
            let size = (max - min).length();
            let worst = a.iter().zip(&b).map(|(p, q)| p.distance(*q)).fold(0.0f32, f32::max);
            assert!(
                worst <= 1e-5 * size,
                "{} {deformer}: the scene's vertices are off by {worst} (model size {size})",
                model.display()
            );
        }
    }
}

/// A scene deforms its imported character with the scene's own keys: a key added in the scene
/// moves the vertices away from the model file's pose.
#[test]
fn a_scene_s_own_keys_pose_its_imported_character() {
    let dir = tempfile::tempdir().unwrap();
    let model = corpus("gltf/RiggedSimple/RiggedSimple.glb");
    let path = dir.path().join("rigged.ron");
    let o = keyrig(&["import", model.to_str().unwrap(), "-o", path.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let before = positions(&deform_json(&path, &["--time", "0.5"], "linear", dir.path()), "positions");
    let mut scene = keyrig_io::scene_file::load(&path).unwrap();
    let object = scene.objects.iter_mut().find(|o| o.skeleton.is_some()).expect("a skinned object");
    let skeleton = object.skeleton.as_mut().unwrap();
    let joint = skeleton.joints.len() - 1;
    skeleton.joints[joint].rotation = Animated::new(
        Quat::IDENTITY,
        RawTrack::new(vec![
            Key::new(0.0, Quat::from_rotation_x(1.2)),
            Key::new(1.0, Quat::from_rotation_x(1.2)),
        ]),
    );
    keyrig_io::scene_file::save(&path, &scene).unwrap();
    let after = positions(&deform_json(&path, &["--time", "0.5"], "linear", dir.path()), "positions");
    let moved = before.iter().zip(&after).filter(|(a, b)| a.distance(**b) > 1e-3).count();
    assert!(moved > before.len() / 10, "the scene's key moved {moved} of {} vertices", before.len());
}
