//! glTF export: the demo scene passes the Khronos glTF-Validator with zero errors and zero
//! warnings (as .glb and as .gltf), and importing the export samples within tolerance of the original scene —
//! object tracks, joint rotations, and the linear-blend-skinned arm against keyrig-skin.

use std::path::{Path, PathBuf};
use std::process::Command;

#[path = "support/big_gltf.rs"]
mod big_gltf;

use glam::Vec3;
use keyrig_core::{AnimatedTrack, DeformerKind, Interpolation, Key, RawTrack, Scene, Tcb};
use keyrig_io::gltf_export::{export_scene, rotation_angle, ExportOptions};
use keyrig_io::gltf_import::import_gltf_slice;
use keyrig_io::model::{ChannelTarget, ImportedModel};

fn validator_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/validate-gltf")
}

/// Runs the Khronos glTF-Validator on `file` and returns (errors, warnings, full report).
/// Fails with instructions when Node.js or the validator package is missing.
fn validate(file: &Path) -> (u64, u64, String) {
    let dir = validator_dir();
    assert!(
        dir.join("node_modules/gltf-validator").is_dir(),
        "the Khronos glTF-Validator is not installed: install Node.js (18 or newer) and run \
         `npm ci --prefix tools/validate-gltf` in the repository root"
    );
    let output = Command::new("node").arg(dir.join("validate.mjs")).arg(file).output().unwrap_or_else(|e| {
        panic!("cannot run `node` ({e}): install Node.js (18 or newer) and run `npm ci --prefix tools/validate-gltf`")
    });
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&output.stderr);
    let report: serde_json::Value = serde_json::from_str(stdout.trim())
        .unwrap_or_else(|e| panic!("validator output ({e}): {stdout} {stderr}"));
    (
        report["errors"].as_u64().expect("errors count"),
        report["warnings"].as_u64().expect("warnings count"),
        stdout,
    )
}

fn node_named(model: &ImportedModel, name: &str) -> usize {
    model.nodes.iter().position(|n| n.name == name).unwrap_or_else(|| panic!("no node {name}"))
}

fn sample_times(scene: &Scene) -> Vec<f64> {
    let end = f64::from(scene.frame_range.end) / scene.fps;
    (0..=200).map(|i| end * f64::from(i) / 200.0).collect()
}

#[test]
fn demo_scene_export_passes_the_khronos_validator() {
    let scene = keyrig_io::demo::demo_scene();
    let exported = export_scene(&scene, &ExportOptions::default()).expect("export");
    let dir = tempfile::tempdir().expect("tempdir");
    for name in ["demo.glb", "demo.gltf"] {
        let path = dir.path().join(name);
        exported.write(&path).expect("write");
        let (errors, warnings, report) = validate(&path);
        assert_eq!(errors, 0, "{name}: {report}");
        // Zero-weight joints are written as joint 0 (ACCESSOR_JOINTS_USED_ZERO_WEIGHT).
        assert_eq!(warnings, 0, "{name}: {report}");
    }
}

#[test]
fn import_of_the_export_samples_like_the_scene() {
    let scene = keyrig_io::demo::demo_scene();
    let options = ExportOptions::default();
    let model =
        import_gltf_slice(&export_scene(&scene, &options).expect("export").to_glb()).expect("re-import");
    assert_eq!(model.animations.len(), 1);
    let tol = options.rotation_tolerance_deg.to_radians() + 1e-5;
    for object in &scene.objects {
        let node = node_named(&model, &object.name);
        let translation = AnimatedTrack::new(&object.translation).expect("track");
        let rotation = AnimatedTrack::new(&object.rotation).expect("track");
        for t in sample_times(&scene) {
            let pose = model.pose_at(Some(0), t);
            let expected = translation.sample(t);
            assert!((pose.translation[node] - expected).length() < 1e-4, "{} t {t}", object.name);
            let angle = rotation_angle(pose.rotation[node], rotation.sample(t));
            assert!(angle <= tol, "{} rotation t {t}: {} deg", object.name, angle.to_degrees());
        }
        if let Some(skeleton) = &object.skeleton {
            for joint in &skeleton.joints {
                let node = node_named(&model, &joint.name);
                let track = AnimatedTrack::new(&joint.rotation).expect("track");
                for t in sample_times(&scene) {
                    let expected = joint.rest_rotation * track.sample(t);
                    let angle = rotation_angle(model.pose_at(Some(0), t).rotation[node], expected);
                    assert!(angle <= tol, "{} t {t}: {} deg", joint.name, angle.to_degrees());
                }
            }
        }
    }
}

/// glTF has no cycles: the export writes the repeats as keys over the scene's frame range, and
/// the re-imported animation plays the cycle (the waving arm of `assets/cycle.ron`, and a box
/// moving with RepeatOffset after and PingPong before its keys).
#[test]
fn cycles_export_as_keys_over_the_frame_range() {
    use keyrig_core::{Cycle, Cycles};
    let mut scene = keyrig_io::demo::cycle_scene();
    let mut mover = keyrig_core::Object::new("mover");
    mover.translation.track = RawTrack::new(vec![
        Key::new(0.5, Vec3::ZERO),
        Key::new(1.0, Vec3::new(1.0, 0.5, 0.0)).with_tcb(Tcb::new(0.3, 0.0, 0.2)),
        Key::new(1.25, Vec3::new(2.0, 0.0, -1.0)),
    ]);
    mover.translation = mover.translation.with_cycles(Cycles::new(Cycle::PingPong, Cycle::RepeatOffset));
    scene.objects.push(mover);
    let options = ExportOptions::default();
    let model =
        import_gltf_slice(&export_scene(&scene, &options).expect("export").to_glb()).expect("re-import");
    let tol = options.rotation_tolerance_deg.to_radians() + 1e-5;
    let (start, end) = (0.0, f64::from(scene.frame_range.end) / scene.fps);
    let times: Vec<f64> = (0..=480).map(|i| start + (end - start) * f64::from(i) / 480.0).collect();
    let skeleton = scene.objects[0].skeleton.as_ref().expect("arm");
    for joint in &skeleton.joints {
        let node = node_named(&model, &joint.name);
        let track = AnimatedTrack::new(&joint.rotation).expect("track");
        for &t in &times {
            let expected = joint.rest_rotation * track.sample(t);
            let angle = rotation_angle(model.pose_at(Some(0), t).rotation[node], expected);
            assert!(angle <= tol, "{} t {t}: {} deg", joint.name, angle.to_degrees());
        }
    }
    // The elbow waves four times: its keys cover only the first second.
    let elbow = node_named(&model, "elbow");
    let wave = |t: f64| model.pose_at(Some(0), t).rotation[elbow];
    assert!(rotation_angle(wave(0.5), wave(3.5)) < tol, "still waving at 3.5 s");
    let node = node_named(&model, "mover");
    let track = AnimatedTrack::new(&scene.objects[1].translation).expect("track");
    for &t in &times {
        let (got, want) = (model.pose_at(Some(0), t).translation[node], track.sample(t));
        assert!((got - want).length() < 2e-4, "mover t {t}: {got} vs {want}");
    }
    // RepeatOffset: 3 s after the keys the box has moved on by whole cycles.
    assert!(model.pose_at(Some(0), end).translation[node].x > 6.0);
}

#[test]
fn position_tracks_export_exactly_as_cubic_spline() {
    // A TCB track with non-uniform spacing and non-zero T/C/B: the glTF Hermite curve must
    // be the same curve, not an approximation.
    let mut scene = Scene::default();
    let mut object = keyrig_core::Object::new("mover");
    object.translation.track = RawTrack::new(vec![
        Key::new(0.0, Vec3::ZERO),
        Key::new(0.3, Vec3::new(1.0, 2.0, 0.0)).with_tcb(Tcb::new(0.4, -0.3, 0.2)),
        Key::new(1.1, Vec3::new(-1.0, 0.5, 3.0)).with_tcb(Tcb::new(-0.5, 0.5, -0.2)),
        Key::new(1.5, Vec3::new(0.0, 0.0, 1.0)).with_interpolation(Interpolation::Linear),
        Key::new(2.0, Vec3::new(2.0, 0.0, 1.0)),
    ]);
    scene.objects.push(object);
    let model = import_gltf_slice(&export_scene(&scene, &ExportOptions::default()).expect("export").to_glb())
        .expect("re-import");
    let ChannelTarget::Translation(track) = &model.animations[0].channels[0].target else {
        panic!("channel")
    };
    assert!(track.keys.iter().all(|k| k.interpolation == Interpolation::Hermite));
    let original = AnimatedTrack::new(&scene.objects[0].translation).expect("track");
    for i in 0..=400 {
        let t = 2.0 * f64::from(i) / 400.0;
        let got = model.pose_at(Some(0), t).translation[0];
        let want = original.sample(t);
        assert!((got - want).length() < 2e-5, "t {t}: {got} vs {want}");
    }
}

#[test]
fn skinned_arm_deforms_like_keyrig_skin_after_export() {
    let scene = keyrig_io::demo::demo_scene();
    let options = ExportOptions::default();
    let model =
        import_gltf_slice(&export_scene(&scene, &options).expect("export").to_glb()).expect("re-import");
    let arm = &scene.objects[0];
    let skeleton = arm.skeleton.as_ref().expect("arm skeleton");
    let mesh_node = node_named(&model, &format!("{}.mesh", arm.name));
    let kind = match arm.mesh {
        Some(keyrig_core::MeshSource::Procedural(kind)) => kind,
        _ => panic!("demo arm is procedural"),
    };
    // keyrig's own linear blend, with the mesh fitted to the scene skeleton as the editor does.
    let mut mesh = keyrig_skin::mesh_for(kind);
    let native = keyrig_skin::scene_skeleton_for(kind).expect("native skeleton");
    let len = |s: &keyrig_core::Skeleton| -> f32 {
        s.joints.iter().filter(|j| j.parent.is_some()).map(|j| j.rest_translation.length()).sum()
    };
    let factor = len(skeleton) / len(&native);
    for p in &mut mesh.positions {
        *p *= factor;
    }
    let rest = keyrig_skin::RestSkeleton::from_scene(skeleton).expect("rest");
    let mesh = mesh.with_skeleton(rest.clone()).expect("fits");
    let bindings =
        mesh.bindings(keyrig_skin::BlendZone::from_settings(&arm.deformer).expect("zone")).expect("bind");
    // The arm's poses from the scene evaluator (object 0), as the editor plays them.
    let eval = keyrig_eval::SceneEvaluator::new(&scene, &std::collections::HashMap::new());
    let pose =
        |t: f64| eval.object_at(0, t, &keyrig_eval::Overrides::new()).and_then(|s| s.pose).expect("pose");
    let object_translation = arm.translation.value;
    let reach: f32 = len(skeleton);
    // Each of the 4 joints may deviate by the rotation tolerance; the tip moves at most
    // Σ tolerance × distance to the tip.
    let bound = 4.0 * (options.rotation_tolerance_deg.to_radians() as f32) * reach + 1e-4;
    for t in sample_times(&scene).into_iter().step_by(10) {
        let palette = keyrig_skin::JointPalette::new(&rest, &pose(t)).expect("palette");
        let ours =
            keyrig_skin::deform_mesh(&mesh, &bindings, &palette, DeformerKind::LinearBlend).expect("deform");
        let gltf = model.deformed_positions(mesh_node, Some(0), t).expect("mesh");
        let worst = ours
            .positions
            .iter()
            .zip(&gltf[0])
            .map(|(a, b)| ((*a + object_translation) - *b).length())
            .fold(0.0, f32::max);
        assert!(worst <= bound, "t {t}: worst vertex {worst} m (bound {bound})");
    }
}

#[test]
fn lights_survive_export_and_import() {
    let scene = keyrig_io::demo::demo_scene();
    let model = import_gltf_slice(&export_scene(&scene, &ExportOptions::default()).expect("export").to_glb())
        .expect("re-import");
    let mapped = model.to_scene("demo.glb", None).expect("scene");
    assert_eq!(mapped.lights.len(), scene.lights.len());
    let t0 = f64::from(scene.frame_range.start) / scene.fps;
    for (a, b) in scene.lights.iter().zip(&mapped.lights) {
        assert_eq!(a.name, b.name);
        assert_eq!(std::mem::discriminant(&a.kind), std::mem::discriminant(&b.kind));
        let position = AnimatedTrack::new(&a.position).expect("track").sample(t0);
        assert!(
            (position - b.position.value).length() < 1e-4,
            "{}: {position} vs {}",
            a.name,
            b.position.value
        );
        let direction = AnimatedTrack::new(&a.direction).expect("track").sample(t0).normalize();
        assert!(direction.angle_between(b.direction.value) < 1e-3, "{}", a.name);
        if let (
            keyrig_core::LightKind::Spot { cutoff_deg, .. },
            keyrig_core::LightKind::Spot { cutoff_deg: c2, .. },
        ) = (a.kind, b.kind)
        {
            assert!((cutoff_deg - c2).abs() < 1e-3);
        }
    }
}

/// The characters scene (the arm, CesiumMan, the Fox and an MD2 model, the last three from
/// their own files) exports to a file the validator accepts: every primitive keeps its normals,
/// joints and weights for all its vertices, each material names its own texture, and the MD2
/// model's morph weights are keyed at the scene range's ends and at every model frame between.
#[test]
fn characters_scene_export_passes_the_khronos_validator() {
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    let scene = keyrig_io::scene_file::load(&assets.join("characters.ron")).expect("assets/characters.ron");
    let options = ExportOptions { base_dir: Some(assets.clone()), ..ExportOptions::default() };
    let exported = export_scene(&scene, &options).expect("export");
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("characters.glb");
    exported.write(&path).expect("write");
    let (errors, warnings, report) = validate(&path);
    assert_eq!(errors, 0, "{report}");
    assert_eq!(warnings, 0, "{report}");

    // Three textured models, three textures, each material its own one.
    let json = &exported.json;
    let textures = json["textures"].as_array().expect("textures");
    assert_eq!(textures.len(), 3, "CesiumMan's, the Fox's and Sydney's skin");
    let mut used: Vec<u64> = json["materials"]
        .as_array()
        .expect("materials")
        .iter()
        .filter_map(|m| m["pbrMetallicRoughness"]["baseColorTexture"]["index"].as_u64())
        .collect();
    used.sort_unstable();
    used.dedup();
    assert_eq!(used, [0, 1, 2]);
    let sources: Vec<u64> = textures.iter().map(|t| t["source"].as_u64().expect("source")).collect();
    assert_eq!(sources, [0, 1, 2]);

    // Sydney (10 model frames per second) in a 30 fps scene of frames 0..=90.
    let model = import_gltf_slice(&exported.to_glb()).expect("re-import");
    let sydney = scene.objects.iter().find(|o| o.name.to_lowercase().contains("sydney")).expect("Sydney");
    let node = node_named(&model, &sydney.name);
    let keys = &weights_of(&model, node).expect("Sydney's morph weights are animated").keys;
    let (t0, t1) =
        (f64::from(scene.frame_range.start) / scene.fps, f64::from(scene.frame_range.end) / scene.fps);
    let mut expected = vec![t0];
    expected.extend((1..30).map(|k| f64::from(k) / 10.0));
    expected.push(t1);
    let times: Vec<f64> = keys.iter().map(|k| k.time).collect();
    assert_eq!(times.len(), expected.len(), "{times:?}");
    for (got, want) in times.iter().zip(&expected) {
        assert!((got - want).abs() < 1e-6, "key at {got}, expected {want}: {times:?}");
    }
    // Between and at the keys, the file's morph plays Sydney as keyrig does (frames a and b of
    // the looping playback, blended by t).
    let md2 = keyrig_io::md2::load_md2_file(&assets.join("models/sydney/sydney.md2")).expect("sydney.md2");
    let playback = md2.playback().expect("playback");
    let track = weights_of(&model, node).expect("weights");
    let primitive = &model.meshes[model.nodes[node].mesh.expect("Sydney's mesh")].primitives[0];
    let size = md2.frames[0].positions.iter().fold(0.0f32, |m, p| m.max(p.abs().max_element()));
    for t in [0.0, 0.05, 0.37, 1.0, 1.23, 2.95, 3.0] {
        let weights = keyrig_io::model::sample_weights(track, t).expect("weights at t");
        let got = ImportedModel::morphed_positions(primitive, &weights);
        let blend = playback.blend_at(None, 10.0, t).expect("blend");
        let want = md2
            .blended_positions(blend.frame_a as usize, blend.frame_b as usize, blend.t)
            .expect("frames of the model");
        assert_eq!(got.len(), want.len(), "t {t}");
        let worst = got.iter().zip(&want).map(|(g, w)| (*g - *w).length()).fold(0.0f32, f32::max);
        assert!(worst < 1e-4 * size, "t {t}: {worst}");
    }
}

/// A spot light whose cone angles are not finite (a scene made in code: the scene file refuses
/// them) is refused with the light's path, whichever of the two angles it is.
#[test]
fn spot_lights_need_finite_angles() {
    let base = keyrig_io::demo::demo_scene();
    let spot = base
        .lights
        .iter()
        .position(|l| matches!(l.kind, keyrig_core::LightKind::Spot { .. }))
        .expect("the demo has a spot light");
    for (cutoff, inner) in [(f32::NAN, 10.0), (30.0, f32::INFINITY), (f32::NAN, f32::NAN)] {
        let mut scene = base.clone();
        let keyrig_core::LightKind::Spot { cutoff_deg, inner_angle_deg, .. } = &mut scene.lights[spot].kind
        else {
            unreachable!()
        };
        (*cutoff_deg, *inner_angle_deg) = (cutoff, inner);
        let Err(err) = export_scene(&scene, &ExportOptions::default()) else {
            panic!("cutoff {cutoff}, inner {inner}: exported")
        };
        assert_eq!(err.to_string(), format!("lights[{spot}].kind: spot angles must be finite"));
    }
}

/// The skin's `skeleton` is the arm's root joint (the common root of its joints).
#[test]
fn the_skins_skeleton_is_the_root_joint() {
    let exported = export_scene(&keyrig_io::demo::demo_scene(), &ExportOptions::default()).expect("export");
    let nodes = exported.json["nodes"].as_array().expect("nodes");
    let shoulder = nodes.iter().position(|n| n["name"] == "shoulder").expect("a shoulder node");
    assert_eq!(exported.json["skins"][0]["skeleton"].as_u64(), Some(shoulder as u64));
}

/// An object whose mesh is a morphing glTF model keeps the model's morph targets, default
/// weights and first animation's weights keys (STEP, LINEAR or CUBICSPLINE as in the file).
#[test]
fn morph_weights_of_a_model_file_are_exported() {
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf/AnimatedMorphCube");
    let file = "AnimatedMorphCube.glb";
    let original = keyrig_io::gltf_import::import_gltf_file(&corpus.join(file)).expect("AnimatedMorphCube");
    let mut object = keyrig_core::Object::new("cube");
    object.mesh = Some(keyrig_core::MeshSource::file(file, Some(0)));
    let scene = Scene { objects: vec![object], ..Scene::default() };
    let options = ExportOptions { base_dir: Some(corpus), ..ExportOptions::default() };
    let exported = export_scene(&scene, &options).expect("export");
    let model = import_gltf_slice(&exported.to_glb()).expect("re-import");
    let weights = |m: &ImportedModel| {
        m.animations[0]
            .channels
            .iter()
            .find_map(|c| match &c.target {
                ChannelTarget::Weights(w) => Some(w.clone()),
                _ => None,
            })
            .expect("a weights channel")
    };
    let (got, want) = (weights(&model), weights(&original));
    assert_eq!(got.targets, want.targets);
    assert_eq!(got.keys.len(), want.keys.len());
    for (g, w) in got.keys.iter().zip(&want.keys) {
        assert!((g.time - w.time).abs() < 1e-6, "{} vs {}", g.time, w.time);
        assert_eq!(g.interpolation, w.interpolation);
        assert_eq!(g.value, w.value);
    }
    assert_eq!(
        exported.json["meshes"][0]["primitives"][0]["targets"].as_array().map(Vec::len),
        Some(want.targets)
    );
}

/// An object's rotation is written on its node: its value when it has no keys, and its first
/// key (what a viewer that does not play the animation shows) when it has some.
#[test]
fn static_object_rotations_are_written_on_their_nodes() {
    let mut still = keyrig_core::Object::new("still");
    still.rotation.value = glam::Quat::from_rotation_y(0.7);
    let mut keyed = keyrig_core::Object::new("keyed");
    keyed.rotation.track = RawTrack::new(vec![
        Key::new(0.5, glam::Quat::from_rotation_x(0.4)),
        Key::new(1.5, glam::Quat::from_rotation_x(1.2)),
    ]);
    let scene = Scene { objects: vec![still, keyed], ..Scene::default() };
    let model = import_gltf_slice(&export_scene(&scene, &ExportOptions::default()).expect("export").to_glb())
        .expect("re-import");
    for (name, want) in
        [("still", glam::Quat::from_rotation_y(0.7)), ("keyed", glam::Quat::from_rotation_x(0.4))]
    {
        let got = model.nodes[node_named(&model, name)].rotation;
        assert!(got.angle_between(want) < 1e-6, "{name}: {got} vs {want}");
    }
}

/// Blender mode (LINEAR keys only) writes a joint's translation through its rest transform,
/// `t_rest + q_rest·t(t)`, within the position tolerance of keyrig's curve at every time.
#[test]
fn blender_mode_joint_translations_follow_keyrig_through_the_rest_transform() {
    use keyrig_core::{Animated, Joint, Object, Skeleton};
    use keyrig_io::gltf_export::BakeOptions;
    let rest = glam::Quat::from_rotation_z(0.5);
    let mut root = Joint::new("root", None, Vec3::new(0.0, 1.0, 0.0), rest);
    root.translation = Animated::new(
        Vec3::ZERO,
        RawTrack::new(vec![
            Key::new(0.0, Vec3::ZERO),
            Key::new(1.0, Vec3::new(0.5, 0.0, 0.2)).with_tcb(Tcb::new(0.2, -0.3, 0.1)),
            Key::new(2.0, Vec3::new(0.0, 0.3, 0.0)),
        ]),
    );
    let mut object = Object::new("rig");
    object.skeleton = Some(Skeleton::new(vec![
        root,
        keyrig_core::Joint::new("tip", Some(0), Vec3::X, glam::Quat::IDENTITY),
    ]));
    let scene = Scene { objects: vec![object], ..Scene::default() };
    let bake = BakeOptions::default();
    let options = ExportOptions { bake: Some(bake), ..ExportOptions::default() };
    let exported = export_scene(&scene, &options).expect("export");
    let model = import_gltf_slice(&exported.to_glb()).expect("re-import");
    let node = node_named(&model, "root");
    let joint = &scene.objects[0].skeleton.as_ref().expect("skeleton").joints[0];
    let track = AnimatedTrack::new(&joint.translation).expect("track");
    for i in 0..=80 {
        let t = f64::from(i) / 40.0;
        let want = joint.rest_translation + rest * track.sample(t);
        let got = model.pose_at(Some(0), t).translation[node];
        assert!((got - want).length() as f64 <= bake.position_tolerance + 1e-5, "t {t}: {got} vs {want}");
    }
}

/// A cycled track is written with a key at every repeat of its key times in the range, before
/// its keys as well as after them, so that its corners stay exact.
#[test]
fn cycled_tracks_keep_a_key_at_every_repeat_of_their_keys() {
    use keyrig_core::{Cycle, Cycles};
    let mut object = keyrig_core::Object::new("box");
    let linear = |t: f64, v: Vec3| Key::new(t, v).with_interpolation(Interpolation::Linear);
    object.translation.track = RawTrack::new(vec![
        linear(0.5, Vec3::ZERO),
        linear(1.0, Vec3::new(1.0, 0.0, 0.0)),
        linear(1.3, Vec3::new(1.0, 1.0, 0.0)),
    ]);
    let mut mirrored = object.clone();
    mirrored.name = "mirrored".into();
    mirrored.translation = mirrored.translation.with_cycles(Cycles::new(Cycle::PingPong, Cycle::PingPong));
    object.translation = object.translation.with_cycles(Cycles::new(Cycle::Repeat, Cycle::Repeat));
    let scene = Scene { objects: vec![object, mirrored], ..Scene::default() };
    let model = import_gltf_slice(&export_scene(&scene, &ExportOptions::default()).expect("export").to_glb())
        .expect("re-import");
    let times: Vec<f64> = translation_keys(&model, "box").iter().map(|k| k.0).collect();
    let end = f64::from(scene.frame_range.end) / scene.fps;
    // Where Repeat jumps back to the first key, the keys close in on the jump but stay at least
    // 1e-4 s apart (closer keys would not change what plays).
    for w in times.windows(2) {
        assert!(w[1] - w[0] >= 0.5e-4, "keys at {} and {}: {times:?}", w[0], w[1]);
    }
    // Key times whose repeats no halving of the intervals between other keys lands on.
    let (keys, period) = ([0.5, 1.0, 1.3], 0.8);
    for k in -1..=(end / period).ceil() as i32 {
        for key in keys {
            let t = key + period * f64::from(k);
            if (0.0..=end).contains(&t) {
                assert!(times.iter().any(|&x| (x - t).abs() < 1e-6), "no key at {t}: {times:?}");
            }
        }
    }
    // Ping-pong: the odd cycles play the keys backwards, so their keys sit mirrored in them
    // (1.0 is 0.5 after the start of the cycle, so 0.5 before its end when mirrored).
    let times: Vec<f64> = translation_keys(&model, "mirrored").iter().map(|k| k.0).collect();
    for k in (-1..=(end / period).ceil() as i32).filter(|k| k % 2 != 0) {
        for key in keys {
            let t = 0.5 + period * f64::from(k) + (1.3 - key);
            if (0.0..=end).contains(&t) {
                assert!(times.iter().any(|&x| (x - t).abs() < 1e-6), "no mirrored key at {t}: {times:?}");
            }
        }
    }
}

/// The corpus model whose cubes move, turn and scale with STEP, LINEAR and CUBICSPLINE keys
/// comes back from import → scene → export → import playing as it did, one animation at a time.
#[test]
fn interpolation_test_round_trips_through_a_scene() {
    let file = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/corpus/gltf/InterpolationTest/InterpolationTest.glb");
    let original = keyrig_io::gltf_import::import_gltf_file(&file).expect("InterpolationTest");
    let tolerance = ExportOptions::default().rotation_tolerance_deg.to_radians() + 1e-4;
    let mut cubic = [0, 0];
    for a in 0..original.animations.len() {
        let mut scene = original.to_scene("InterpolationTest.glb", Some(a)).expect("scene");
        let duration = original.animations[a].duration();
        scene.frame_range.end = (duration * scene.fps).ceil() as i32;
        let options =
            ExportOptions { base_dir: file.parent().map(Path::to_path_buf), ..ExportOptions::default() };
        let exported = export_scene(&scene, &options).expect("export");
        let model = import_gltf_slice(&exported.to_glb()).expect("re-import");
        // CUBICSPLINE channels come back as CUBICSPLINE (written exactly, not resampled).
        let interpolation = |m: &ImportedModel, anim: usize, node: usize, rotation: bool| {
            m.animations[anim].channels.iter().find_map(|c| match &c.target {
                ChannelTarget::Rotation(t) if rotation && c.node == node => {
                    t.keys.first().map(|k| k.interpolation)
                }
                ChannelTarget::Translation(t) if !rotation && c.node == node => {
                    t.keys.first().map(|k| k.interpolation)
                }
                _ => None,
            })
        };
        for node in original.animations[a].channels.iter().map(|c| c.node) {
            let name = &original.nodes[node].name;
            let back = node_named(&model, name);
            for rotation in [false, true] {
                if interpolation(&original, a, node, rotation) == Some(Interpolation::Hermite) {
                    assert_eq!(
                        interpolation(&model, 0, back, rotation),
                        Some(Interpolation::Hermite),
                        "{name}"
                    );
                    cubic[usize::from(rotation)] += 1;
                }
            }
            // Just inside the keys: a STEP key's jump is written STEP_JUMP before it.
            for i in 0..=100 {
                let t = duration * f64::from(i) / 100.0 * 0.999;
                let (want, got) = (original.pose_at(Some(a), t), model.pose_at(Some(0), t));
                let label = format!("{} {name} t {t}", original.animations[a].name);
                assert!((want.translation[node] - got.translation[back]).length() < 1e-4, "{label}");
                assert!((want.scale[node] - got.scale[back]).length() < 1e-4, "{label}");
                let angle = rotation_angle(want.rotation[node], got.rotation[back]);
                assert!(angle <= tolerance, "{label}: {}°", angle.to_degrees());
            }
        }
    }
    assert!(cubic[0] > 0 && cubic[1] > 0, "CUBICSPLINE translations and rotations checked: {cubic:?}");
}

/// Outside Blender mode a Step segment among spline ones is written as its key, a copy of it
/// `STEP_JUMP` before the next key, and the next key.
#[test]
fn a_step_segment_in_a_spline_track_holds_until_just_before_the_next_key() {
    use keyrig_io::gltf_export::STEP_JUMP;
    let (a, b, c) = (Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 2.0, 0.0));
    let mut stepped = keyrig_core::Object::new("stepped");
    stepped.translation.track = RawTrack::new(vec![
        Key::new(0.0, a).with_interpolation(Interpolation::Step),
        Key::new(0.75, b).with_tcb(Tcb::new(0.2, 0.0, 0.0)),
        Key::new(2.0, c),
    ]);
    let scene = Scene { objects: vec![stepped], ..Scene::default() };
    let model = import_gltf_slice(&export_scene(&scene, &ExportOptions::default()).expect("export").to_glb())
        .expect("re-import");
    let got = translation_keys(&model, "stepped");
    let want = [(0.0, a), (0.75 - STEP_JUMP, a), (0.75, b), (2.0, c)];
    assert_eq!(got.len(), want.len(), "{got:?}");
    for ((t, v), (u, w)) in got.iter().zip(want) {
        assert!((t - u).abs() < 1e-6 && (*v - w).length() < 1e-6, "{got:?}");
    }
}

/// What `pick` takes from the first channel of the first animation on `node` that it accepts.
fn channel_of<'m, T>(
    model: &'m ImportedModel,
    node: usize,
    pick: impl Fn(&'m ChannelTarget) -> Option<T>,
) -> Option<T> {
    model.animations[0].channels.iter().filter(|c| c.node == node).find_map(|c| pick(&c.target))
}

/// The rotation keys of object `name` in the first animation: (time, value).
fn rotation_keys(model: &ImportedModel, name: &str) -> Vec<(f64, glam::Quat)> {
    channel_of(model, node_named(model, name), |target| match target {
        ChannelTarget::Rotation(track) => Some(track.keys.iter().map(|k| (k.time, k.value)).collect()),
        _ => None,
    })
    .unwrap_or_else(|| panic!("{name}'s rotation is animated"))
}

/// The translation keys of object `name` in the first animation: (time, value).
fn translation_keys(model: &ImportedModel, name: &str) -> Vec<(f64, Vec3)> {
    channel_of(model, node_named(model, name), |target| match target {
        ChannelTarget::Translation(track) => Some(track.keys.iter().map(|k| (k.time, k.value)).collect()),
        _ => None,
    })
    .unwrap_or_else(|| panic!("{name}'s translation is animated"))
}

/// The morph weights track of node `node` in the first animation.
fn weights_of(model: &ImportedModel, node: usize) -> Option<&keyrig_io::model::WeightsTrack> {
    channel_of(model, node, |target| match target {
        ChannelTarget::Weights(w) => Some(w),
        _ => None,
    })
}

/// A rotation that repeats jumps back to its first key at every cycle: the keys close in on
/// the jump but stay at least 1e-4 s apart, and the rotation between them follows keyrig's.
#[test]
fn repeated_rotations_close_in_on_their_jumps_with_keys_1e4_apart() {
    use keyrig_core::{Cycle, Cycles};
    let mut object = keyrig_core::Object::new("turner");
    object.rotation.track = RawTrack::new(vec![
        Key::new(0.5, glam::Quat::IDENTITY).with_interpolation(Interpolation::Linear),
        Key::new(1.25, glam::Quat::from_rotation_y(1.5)),
    ]);
    object.rotation = object.rotation.with_cycles(Cycles::new(Cycle::Repeat, Cycle::Repeat));
    let scene = Scene { objects: vec![object], ..Scene::default() };
    let model = import_gltf_slice(&export_scene(&scene, &ExportOptions::default()).expect("export").to_glb())
        .expect("re-import");
    let times: Vec<f64> = rotation_keys(&model, "turner").iter().map(|k| k.0).collect();
    for w in times.windows(2) {
        assert!(w[1] - w[0] >= 0.5e-4, "keys at {} and {}: {times:?}", w[0], w[1]);
    }
    let track = AnimatedTrack::new(&scene.objects[0].rotation).expect("track");
    let tol = ExportOptions::default().rotation_tolerance_deg.to_radians() + 1e-5;
    for i in 0..=100 {
        // Away from the jumps (at 0.5 + 0.75 k), where both curves are continuous.
        let t = 0.55 + 0.65 * f64::from(i) / 100.0;
        let angle =
            rotation_angle(model.pose_at(Some(0), t).rotation[node_named(&model, "turner")], track.sample(t));
        assert!(angle <= tol, "t {t}: {}°", angle.to_degrees());
    }
}

/// A procedural mesh that cannot be fitted to its object's skeleton (a rest rotation that is
/// not a unit quaternion, and a joint the mesh does not have) is bound to the scene's rest
/// pose: one inverse bind matrix per joint, each the inverse of the joint's rest transform.
#[test]
fn an_unfitted_procedural_mesh_binds_to_the_scenes_rest_pose() {
    let mut scene = keyrig_io::demo::demo_scene();
    let skeleton = scene.objects[0].skeleton.as_mut().expect("the arm");
    let last = skeleton.joints.len() - 1;
    skeleton.joints.push(keyrig_core::Joint::new(
        "finger",
        Some(last),
        Vec3::new(0.1, 0.0, 0.0),
        glam::Quat::from_xyzw(0.0, 0.0, 0.0, 2.0),
    ));
    let exported = export_scene(&scene, &ExportOptions::default()).expect("export");
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("unfitted.glb");
    exported.write(&path).expect("write");
    let (errors, _, report) = validate(&path);
    assert_eq!(errors, 0, "{report}");
    let model = import_gltf_slice(&exported.to_glb()).expect("re-import");
    let skin = &model.skins[0];
    assert_eq!(skin.joints.len(), last + 2);
    assert_eq!(skin.inverse_bind_matrices.len(), last + 2);
    let world = model.world_matrices(&model.rest_pose());
    let arm = world[node_named(&model, &scene.objects[0].name)];
    for (&joint, ibm) in skin.joints.iter().zip(&skin.inverse_bind_matrices) {
        let bind = *ibm * arm.inverse() * world[joint];
        assert!(bind.abs_diff_eq(glam::Mat4::IDENTITY, 1e-4), "{}: {bind}", model.nodes[joint].name);
    }
}

/// Blender mode writes no more keys than the curve needs: a linear track exactly its own keys,
/// a Step segment its start key, a key `STEP_JUMP` before its end holding that value, and the
/// end key.
#[test]
fn blender_mode_writes_linear_and_step_segments_with_the_fewest_keys() {
    use keyrig_io::gltf_export::{BakeOptions, STEP_JUMP};
    let key = |t: f64, v: Vec3, i: Interpolation| Key::new(t, v).with_interpolation(i);
    let (a, b, c) = (Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), Vec3::new(1.0, 2.0, 0.0));
    let mut linear = keyrig_core::Object::new("linear");
    linear.translation.track = RawTrack::new(vec![
        key(0.0, a, Interpolation::Linear),
        key(1.0, b, Interpolation::Linear),
        key(2.0, c, Interpolation::Linear),
    ]);
    let mut stepped = keyrig_core::Object::new("stepped");
    stepped.translation.track = RawTrack::new(vec![
        key(0.0, a, Interpolation::Step),
        key(1.0, b, Interpolation::Linear),
        key(2.0, c, Interpolation::Linear),
    ]);
    let scene = Scene { objects: vec![linear, stepped], ..Scene::default() };
    let options = ExportOptions { bake: Some(BakeOptions::default()), ..ExportOptions::default() };
    let model =
        import_gltf_slice(&export_scene(&scene, &options).expect("export").to_glb()).expect("re-import");
    let close = |got: &[(f64, Vec3)], want: &[(f64, Vec3)]| {
        got.len() == want.len()
            && got.iter().zip(want).all(|((t, v), (u, w))| (t - u).abs() < 1e-6 && (*v - *w).length() < 1e-6)
    };
    let got = translation_keys(&model, "linear");
    assert!(close(&got, &[(0.0, a), (1.0, b), (2.0, c)]), "{got:?}");
    let got = translation_keys(&model, "stepped");
    assert!(close(&got, &[(0.0, a), (1.0 - STEP_JUMP, a), (1.0, b), (2.0, c)]), "{got:?}");
}

/// A rotation track with a Step segment among others is written with the same keys: the
/// held value until `STEP_JUMP` before the next key, then the next key (no keys inside the jump).
#[test]
fn a_step_segment_in_a_rotation_track_is_a_hold_and_one_jump() {
    use keyrig_io::gltf_export::STEP_JUMP;
    let key = |t: f64, angle: f32, i: Interpolation| {
        Key::new(t, glam::Quat::from_rotation_y(angle)).with_interpolation(i)
    };
    let mut object = keyrig_core::Object::new("turner");
    object.rotation.track = RawTrack::new(vec![
        key(0.0, 0.0, Interpolation::Step),
        key(1.0, 0.3, Interpolation::Linear),
        key(2.0, 0.5, Interpolation::Linear),
    ]);
    let scene = Scene { objects: vec![object], ..Scene::default() };
    let model = import_gltf_slice(&export_scene(&scene, &ExportOptions::default()).expect("export").to_glb())
        .expect("re-import");
    let keys: Vec<(f64, f32)> =
        rotation_keys(&model, "turner").iter().map(|&(t, q)| (t, q.to_axis_angle().1)).collect();
    let want = [(0.0, 0.0), (1.0 - STEP_JUMP, 0.0), (1.0, 0.3), (2.0, 0.5)];
    assert_eq!(keys.len(), want.len(), "{keys:?}");
    for ((t, a), (u, b)) in keys.iter().zip(want) {
        assert!((t - u).abs() < 1e-6 && (a - b).abs() < 1e-5, "{keys:?}");
    }
}

/// Outside Blender mode too, a rotation track's Step segment holds its key until exactly
/// `STEP_JUMP` before the next key (a key there, with the held value), and exported rotation
/// keys keep consistent signs even where the track's own keys do not (q and −q are one
/// rotation).
#[test]
fn rotation_steps_hold_until_step_jump_and_keys_keep_their_signs() {
    use keyrig_io::gltf_export::STEP_JUMP;
    let q = |angle: f32| glam::Quat::from_rotation_y(angle);
    let mut object = keyrig_core::Object::new("turner");
    object.rotation.track = RawTrack::new(vec![
        Key::new(0.0, q(0.0)).with_interpolation(Interpolation::Step),
        Key::new(1.0, -q(0.3)).with_interpolation(Interpolation::Linear),
        Key::new(2.0, q(2.5)).with_interpolation(Interpolation::Linear),
        Key::new(3.0, -q(-2.0)),
    ]);
    let scene = Scene { objects: vec![object], ..Scene::default() };
    let exported = export_scene(&scene, &ExportOptions::default()).expect("export");
    let model = import_gltf_slice(&exported.to_glb()).expect("re-import");
    let keys = rotation_keys(&model, "turner");
    let hold = keys
        .iter()
        .find(|k| (k.0 - (1.0 - STEP_JUMP)).abs() < 1e-6)
        .unwrap_or_else(|| panic!("no key at 1 − STEP_JUMP: {keys:?}"));
    assert!(rotation_angle(hold.1, q(0.0)) < 1e-6, "{keys:?}");
    for w in keys.windows(2) {
        assert!(w[0].1.dot(w[1].1) >= 0.0, "keys at {} and {} have opposite signs", w[0].0, w[1].0);
    }
}

/// In Blender mode a translation's Step segment holds its key until exactly `STEP_JUMP` before
/// the next key (a key there, with the held value), then reaches the next key's value at it.
#[test]
fn blender_mode_steps_hold_until_step_jump() {
    use keyrig_io::gltf_export::{BakeOptions, STEP_JUMP};
    let (a, b) = (Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0));
    let mut stepped = keyrig_core::Object::new("stepped");
    stepped.translation.track = RawTrack::new(vec![
        Key::new(0.0, a).with_interpolation(Interpolation::Step),
        Key::new(0.7, b).with_interpolation(Interpolation::Linear),
        Key::new(2.0, Vec3::new(1.0, 2.0, 0.0)),
    ]);
    let scene = Scene { objects: vec![stepped], ..Scene::default() };
    let options = ExportOptions { bake: Some(BakeOptions::default()), ..ExportOptions::default() };
    let model =
        import_gltf_slice(&export_scene(&scene, &options).expect("export").to_glb()).expect("re-import");
    let keys = translation_keys(&model, "stepped");
    let at = |t: f64| keys.iter().find(|k| (k.0 - t).abs() < 1e-6).map(|k| k.1);
    assert_eq!(at(0.7 - STEP_JUMP), Some(a), "{keys:?}");
    assert_eq!(at(0.7), Some(b), "{keys:?}");
    assert!(keys.iter().all(|k| k.0 > 0.7 - 1e-6 || k.1 == a), "{keys:?}");
}

/// Repeats reach the end of a long range from keys that start late: every corner up to it is a
/// key (keys at 2.5–3 s repeated to 10 s).
#[test]
fn repeats_reach_the_end_of_a_long_range() {
    use keyrig_core::{Cycle, Cycles};
    let linear = |t: f64, v: Vec3| Key::new(t, v).with_interpolation(Interpolation::Linear);
    let mut object = keyrig_core::Object::new("late");
    object.translation.track = RawTrack::new(vec![
        linear(2.5, Vec3::ZERO),
        linear(2.7, Vec3::new(1.0, 0.0, 0.0)),
        linear(3.0, Vec3::new(1.0, 1.0, 0.0)),
    ]);
    object.translation = object.translation.with_cycles(Cycles::new(Cycle::Hold, Cycle::Repeat));
    let mut scene = Scene { objects: vec![object], ..Scene::default() };
    scene.frame_range.end = (10.0 * scene.fps) as i32;
    let model = import_gltf_slice(&export_scene(&scene, &ExportOptions::default()).expect("export").to_glb())
        .expect("re-import");
    let times: Vec<f64> = translation_keys(&model, "late").iter().map(|k| k.0).collect();
    for k in 0..=15 {
        for key in [2.5, 2.7, 3.0] {
            let t = key + 0.5 * f64::from(k);
            if t <= 10.0 {
                assert!(times.iter().any(|&x| (x - t).abs() < 1e-5), "no key at {t}: {times:?}");
            }
        }
    }
}

/// Where a repeating rotation jumps from its last key back to its first, the two may lie in
/// opposite hemispheres (here 286° about Y, then 0°): the exported keys still keep consistent
/// signs, so that component-wise blending (Blender's) takes the short way.
#[test]
fn repeated_rotations_keep_consistent_signs_across_their_jumps() {
    use keyrig_core::{Cycle, Cycles};
    let q = |angle: f32| glam::Quat::from_rotation_y(angle);
    let mut object = keyrig_core::Object::new("turner");
    object.rotation.track = RawTrack::new(vec![
        Key::new(0.5, q(0.0)).with_interpolation(Interpolation::Linear),
        Key::new(1.0, q(2.5)).with_interpolation(Interpolation::Linear),
        Key::new(1.5, q(5.0)),
    ]);
    object.rotation = object.rotation.with_cycles(Cycles::new(Cycle::Hold, Cycle::Repeat));
    let scene = Scene { objects: vec![object], ..Scene::default() };
    let model = import_gltf_slice(&export_scene(&scene, &ExportOptions::default()).expect("export").to_glb())
        .expect("re-import");
    let keys = rotation_keys(&model, "turner");
    assert!(keys.len() > 6, "{keys:?}");
    for w in keys.windows(2) {
        assert!(w[0].1.dot(w[1].1) >= 0.0, "keys at {} and {} have opposite signs", w[0].0, w[1].0);
    }
}

/// Keys of a cycled track exactly 1e-4 s apart (the shortest segment the resampler writes) are
/// both written.
#[test]
fn cycled_keys_1e4_apart_are_both_kept() {
    use keyrig_core::{Cycle, Cycles};
    let linear = |t: f64, v: Vec3| Key::new(t, v).with_interpolation(Interpolation::Linear);
    let mut object = keyrig_core::Object::new("close");
    object.translation.track = RawTrack::new(vec![
        linear(0.0, Vec3::ZERO),
        linear(1e-4, Vec3::new(0.5, 0.0, 0.0)),
        linear(1.0, Vec3::new(1.0, 1.0, 0.0)),
    ]);
    object.translation = object.translation.with_cycles(Cycles::new(Cycle::Hold, Cycle::RepeatOffset));
    let scene = Scene { objects: vec![object], ..Scene::default() };
    let model = import_gltf_slice(&export_scene(&scene, &ExportOptions::default()).expect("export").to_glb())
        .expect("re-import");
    let times: Vec<f64> = translation_keys(&model, "close").iter().map(|k| k.0).collect();
    for t in [0.0, 1e-4, 1.0, 1.0 + 1e-4] {
        assert!(times.iter().any(|&x| (x - t).abs() < 1e-7), "no key at {t}: {times:?}");
    }
}

/// A Step segment shorter than two `STEP_JUMP`s jumps at its middle, in every writer: the
/// cubic translation channel, the resampled rotation and Blender mode's translation.
#[test]
fn a_step_segment_shorter_than_two_jumps_jumps_at_its_middle() {
    use keyrig_io::gltf_export::BakeOptions;
    let (a, b) = (Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0));
    let mut object = keyrig_core::Object::new("quick");
    object.translation.track = RawTrack::new(vec![
        Key::new(0.0, a).with_interpolation(Interpolation::Step),
        Key::new(0.0015, b).with_tcb(Tcb::new(0.2, 0.0, 0.0)),
        Key::new(1.0, Vec3::new(1.0, 2.0, 0.0)),
    ]);
    object.rotation.track = RawTrack::new(vec![
        Key::new(0.0, glam::Quat::IDENTITY).with_interpolation(Interpolation::Step),
        Key::new(0.0015, glam::Quat::from_rotation_y(0.3)).with_interpolation(Interpolation::Linear),
        Key::new(1.0, glam::Quat::from_rotation_y(0.5)),
    ]);
    let scene = Scene { objects: vec![object], ..Scene::default() };
    let hold_at = |keys: Vec<f64>| {
        assert!(keys.iter().any(|&t| (t - 0.00075).abs() < 1e-7), "no key at the middle: {keys:?}");
        assert!(keys.iter().all(|&t| t <= 0.0 || t >= 0.00075 - 1e-7), "a key before the middle: {keys:?}");
    };
    for options in [
        ExportOptions::default(),
        ExportOptions { bake: Some(BakeOptions::default()), ..ExportOptions::default() },
    ] {
        let model =
            import_gltf_slice(&export_scene(&scene, &options).expect("export").to_glb()).expect("re-import");
        hold_at(translation_keys(&model, "quick").iter().map(|k| k.0).collect());
        hold_at(rotation_keys(&model, "quick").iter().map(|k| k.0).collect());
    }
}

/// A linear rotation track is written as its keys (glTF's LINEAR rotations slerp, as keyrig
/// does), even where keys are further apart than the resampler's largest step; a linear
/// track that spins more than half a turn between keys cannot be, and is resampled.
#[test]
fn linear_rotations_are_written_as_their_keys_unless_they_spin() {
    use keyrig_io::gltf_export::MAX_ROTATION_STEP_DEG;
    let linear = |t: f64, q: glam::Quat| Key::new(t, q).with_interpolation(Interpolation::Linear);
    let wide = 170f32.to_radians();
    assert!(f64::from(wide).to_degrees() > MAX_ROTATION_STEP_DEG);
    let mut turner = keyrig_core::Object::new("turner");
    turner.rotation.track = RawTrack::new(vec![
        linear(0.0, glam::Quat::IDENTITY),
        linear(1.0, glam::Quat::from_rotation_y(wide)),
    ]);
    let mut spinner = keyrig_core::Object::new("spinner");
    spinner.rotation.track = RawTrack::new(vec![
        linear(0.0, glam::Quat::IDENTITY),
        linear(1.0, glam::Quat::from_rotation_y(wide)).with_spin(keyrig_core::Spin::Turns(1)),
    ]);
    let scene = Scene { objects: vec![turner, spinner], ..Scene::default() };
    let model = import_gltf_slice(&export_scene(&scene, &ExportOptions::default()).expect("export").to_glb())
        .expect("re-import");
    let keys = rotation_keys(&model, "turner");
    assert_eq!(keys.iter().map(|k| k.0).collect::<Vec<_>>(), [0.0, 1.0], "{keys:?}");
    assert!(rotation_angle(keys[1].1, glam::Quat::from_rotation_y(wide)) < 1e-6);
    let spun = rotation_keys(&model, "spinner");
    assert!(
        spun.len() >= 7,
        "530° (one turn more than the short way) in steps of at most {MAX_ROTATION_STEP_DEG}°: {spun:?}"
    );
}

/// A resampled segment exactly `MIN_SEGMENT` (1e-4 s) long is still halved when it is not
/// within tolerance; its halves are not (rotations, and translations in Blender mode).
#[test]
fn segments_of_the_shortest_length_are_halved_once_more() {
    use keyrig_io::gltf_export::BakeOptions;
    let mut object = keyrig_core::Object::new("flick");
    object.translation.track = RawTrack::new(vec![
        Key::new(0.0, Vec3::ZERO),
        Key::new(1e-4, Vec3::new(1.0, 0.0, 0.0)),
        Key::new(2e-4, Vec3::new(1.0, 2.0, 0.0)),
    ]);
    object.rotation.track = RawTrack::new(vec![
        Key::new(0.0, glam::Quat::IDENTITY),
        Key::new(1e-4, glam::Quat::from_rotation_y(170f32.to_radians())),
        Key::new(2e-4, glam::Quat::from_rotation_x(1.0)),
    ]);
    let scene = Scene { objects: vec![object], ..Scene::default() };
    let options = ExportOptions { bake: Some(BakeOptions::default()), ..ExportOptions::default() };
    let model =
        import_gltf_slice(&export_scene(&scene, &options).expect("export").to_glb()).expect("re-import");
    for times in [
        translation_keys(&model, "flick").iter().map(|k| k.0).collect::<Vec<_>>(),
        rotation_keys(&model, "flick").iter().map(|k| k.0).collect(),
    ] {
        assert!(times.iter().any(|&t| (t - 5e-5).abs() < 1e-9), "no key at 5e-5 s: {times:?}");
        for w in times.windows(2) {
            assert!(w[1] - w[0] > 4.9e-5, "keys at {} and {}: {times:?}", w[0], w[1]);
        }
    }
}

/// An MD2 morph whose scene range starts and ends between two of the model's frames has keys
/// there that blend those two frames as keyrig plays them (not only keys at frame boundaries).
#[test]
fn md2_weights_at_range_ends_between_frames_blend_two_frames() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/md2/sydney");
    let mut object = keyrig_core::Object::new("M");
    object.mesh = Some(keyrig_core::MeshSource::File {
        path: "sydney.md2".into(),
        mesh: None,
        clip: Some("run".into()),
        fps: Some(10.0),
    });
    // 30 scene frames a second, the model at 10: frames 1 and 5 are a third of the way
    // through model frame 0 and two thirds through model frame 1.
    let scene = Scene {
        objects: vec![object],
        fps: 30.0,
        frame_range: keyrig_core::FrameRange { start: 1, end: 5 },
        ..Scene::default()
    };
    let options = ExportOptions { base_dir: Some(dir.clone()), ..ExportOptions::default() };
    let model =
        import_gltf_slice(&export_scene(&scene, &options).expect("export").to_glb()).expect("re-import");
    let node = node_named(&model, "M");
    let track = weights_of(&model, node).expect("weights");
    let md2 = keyrig_io::md2::load_md2_file(&dir.join("sydney.md2")).expect("sydney.md2");
    let run = md2.clip_frames(Some("run")).expect("run");
    let playback = md2.playback().expect("playback");
    for key in [track.keys.first().expect("first key"), track.keys.last().expect("last key")] {
        let blend = playback.blend_at(Some("run"), 10.0, key.time).expect("blend");
        assert!(blend.t > 0.1 && blend.t < 0.9, "t {}: between frames", key.time);
        let mut want = vec![0.0f32; run.len()];
        want[blend.frame_a as usize - run.start] += 1.0 - blend.t;
        want[blend.frame_b as usize - run.start] += blend.t;
        let worst = key.value.iter().zip(&want).map(|(g, w)| (g - w).abs()).fold(0.0f32, f32::max);
        assert!(worst < 1e-6, "t {}: {:?} against {want:?}", key.time, key.value);
    }
    assert!((track.keys[0].time - 1.0 / 30.0).abs() < 1e-6);
    assert!((track.keys.last().expect("last").time - 5.0 / 30.0).abs() < 1e-6);
}

/// A root joint's node carries its rest translation, its turned translation and a static root
/// translation, keyed or not; a joint whose rest translation is not finite is refused.
#[test]
fn a_static_root_translation_is_added_to_the_root_joint() {
    use keyrig_core::{Animated, Joint, Skeleton};
    let turn = glam::Quat::from_rotation_z(std::f32::consts::FRAC_PI_2);
    let object = |name: &str, translation: Animated<Vec3>| {
        let mut joint = Joint::new(format!("{name}_root"), None, Vec3::new(1.0, 0.0, 0.0), turn);
        joint.translation = translation;
        let mut skeleton = Skeleton::new(vec![joint]);
        skeleton.root_translation = Animated::constant(Vec3::new(0.0, 2.0, 0.0));
        let mut object = keyrig_core::Object::new(name);
        object.skeleton = Some(skeleton);
        object
    };
    let mut moving = Animated::constant(Vec3::ZERO);
    moving.track = RawTrack::new(vec![
        Key::new(0.0, Vec3::ZERO).with_interpolation(Interpolation::Linear),
        Key::new(1.0, Vec3::new(1.0, 0.0, 0.0)),
    ]);
    let scene = Scene {
        objects: vec![
            object("still", Animated::constant(Vec3::new(0.5, 0.0, 0.0))),
            object("moving", moving),
        ],
        ..Scene::default()
    };
    let model = import_gltf_slice(&export_scene(&scene, &ExportOptions::default()).expect("export").to_glb())
        .expect("re-import");
    // rest (1, 0, 0) + a quarter turn about z of (0.5, 0, 0) + the root translation (0, 2, 0).
    let still = model.nodes[node_named(&model, "still_root")].translation;
    assert!((still - Vec3::new(1.0, 2.5, 0.0)).length() < 1e-6, "{still}");
    let keys = translation_keys(&model, "moving_root");
    let want = [(0.0, Vec3::new(1.0, 2.0, 0.0)), (1.0, Vec3::new(1.0, 3.0, 0.0))];
    assert_eq!(keys.len(), want.len(), "{keys:?}");
    for ((t, v), (u, w)) in keys.iter().zip(want) {
        assert!((t - u).abs() < 1e-6 && (*v - w).length() < 1e-5, "{keys:?}");
    }

    let mut bad = scene.clone();
    bad.objects[0].skeleton.as_mut().expect("skeleton").joints[0].rest_translation.y = f32::NAN;
    let err = export_scene(&bad, &ExportOptions::default()).expect_err("a NaN rest translation");
    assert!(err.to_string().contains("objects[0].skeleton.joints[0]"), "{err}");
    assert!(err.to_string().contains("rest transform is not finite"), "{err}");
}

/// A skinned mesh of several primitives from a model file is written back as its primitives,
/// each with its own vertices; shown by an object without a skeleton, the same mesh is written
/// unskinned, and without morph weights (it has no targets).
#[test]
fn a_skinned_model_files_primitives_keep_their_own_vertices() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::write(dir.path().join("two.glb"), big_gltf::two_primitive_skin()).expect("write");
    let file = keyrig_io::gltf_import::import_gltf_file(&dir.path().join("two.glb")).expect("import");
    let skinned = file.to_scene("two.glb", None).expect("scene");
    let options = ExportOptions { base_dir: Some(dir.path().to_path_buf()), ..ExportOptions::default() };
    let mut unskinned = skinned.clone();
    for object in &mut unskinned.objects {
        object.skeleton = None;
    }
    let want = [
        [Vec3::new(0.0, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, 1.0, 0.0)],
        [Vec3::new(2.0, 0.0, 0.0), Vec3::new(3.0, 0.0, 0.0), Vec3::new(2.0, 1.0, 0.0)],
    ];
    for (scene, skin) in [(&skinned, true), (&unskinned, false)] {
        let exported = export_scene(scene, &options).expect("export");
        let model = import_gltf_slice(&exported.to_glb()).expect("re-import");
        let shown = model.nodes.iter().find(|n| n.mesh.is_some()).expect("a node shows the mesh");
        assert_eq!(shown.skin.is_some(), skin);
        let mesh = &model.meshes[shown.mesh.expect("mesh")];
        assert_eq!(mesh.primitives.len(), 2);
        for (primitive, want) in mesh.primitives.iter().zip(&want) {
            assert_eq!(&primitive.positions[..], want, "skinned: {skin}");
            assert_eq!(&primitive.indices[..], [0, 1, 2], "skinned: {skin}");
        }
        assert!(exported.json["meshes"]
            .as_array()
            .expect("meshes")
            .iter()
            .all(|m| m.get("weights").is_none()));
    }
}

/// A light's direction keyed with a Step segment is written as the other rotations are: the
/// held direction until `STEP_JUMP` before the next key, then that key, with no keys closing in
/// on the jump.
#[test]
fn a_light_directions_step_is_a_hold_and_one_jump() {
    use keyrig_io::gltf_export::STEP_JUMP;
    let mut scene = keyrig_io::demo::demo_scene();
    scene.objects.clear();
    scene.lights.truncate(1);
    let name = scene.lights[0].name.clone();
    let (a, b) = (Vec3::new(0.0, -1.0, 0.0), Vec3::new(1.0, -1.0, 0.0));
    scene.lights[0].direction.track = RawTrack::new(vec![
        Key::new(0.0, a).with_interpolation(Interpolation::Step),
        Key::new(1.0, b).with_interpolation(Interpolation::Linear),
        Key::new(2.0, b),
    ]);
    let model = import_gltf_slice(&export_scene(&scene, &ExportOptions::default()).expect("export").to_glb())
        .expect("re-import");
    let keys = rotation_keys(&model, &name);
    let times: Vec<f64> = keys.iter().map(|k| k.0).collect();
    assert!(
        times.iter().all(|&t| t == 0.0 || (t - (1.0 - STEP_JUMP)).abs() < 1e-6 || t >= 1.0 - 1e-6),
        "{times:?}"
    );
    let hold =
        keys.iter().find(|k| (k.0 - (1.0 - STEP_JUMP)).abs() < 1e-6).unwrap_or_else(|| panic!("{times:?}"));
    let down = hold.1 * Vec3::NEG_Z;
    assert!(down.angle_between(a) < 1e-5, "held {down}");
    assert!(keys.len() <= 4, "{times:?}");
}

/// A repeated track whose repeats put a key just before the end of the scene's range (within
/// 1e-4 s) still ends at the range's end.
#[test]
fn a_repeat_just_before_the_range_end_keeps_the_end() {
    use keyrig_core::{Cycle, Cycles};
    let linear = |t: f64, v: Vec3| Key::new(t, v).with_interpolation(Interpolation::Linear);
    let mut object = keyrig_core::Object::new("mover");
    object.translation.track = RawTrack::new(vec![
        linear(0.0, Vec3::ZERO),
        linear(0.49995, Vec3::new(1.0, 0.0, 0.0)),
        linear(1.0, Vec3::new(1.0, 1.0, 0.0)),
    ]);
    object.translation = object.translation.with_cycles(Cycles::new(Cycle::Repeat, Cycle::Repeat));
    // 45 frames at 30 per second: the range ends at 1.5 s, 0.05 ms after the repeat of 0.49995.
    let scene = Scene {
        objects: vec![object],
        fps: 30.0,
        frame_range: keyrig_core::FrameRange { start: 0, end: 45 },
        ..Scene::default()
    };
    let model = import_gltf_slice(&export_scene(&scene, &ExportOptions::default()).expect("export").to_glb())
        .expect("re-import");
    let keys = translation_keys(&model, "mover");
    let (t, v) = *keys.last().expect("keys");
    assert!((t - 1.5).abs() < 1e-6, "the last key is at {t}: {keys:?}");
    let want = AnimatedTrack::new(&scene.objects[0].translation).expect("track").sample(1.5);
    assert!((v - want).length() < 1e-4, "{v} against {want}");
}

/// Euler keys (issue 30) export as quaternion keys that follow them: the demo's Cube keyed on
/// all three angles (Y past a turn) and the arm's elbow switched to Euler keys in ZXY order;
/// the re-imported file turns like keyrig's channels (`object/Cube/rotation`, sampled through
/// the Euler keys) within 1.1 × the tolerance (the quaternion keys follow within a tenth, the
/// exporter's resampling within the tolerance), and it passes the validator.
#[test]
fn euler_keys_export_as_rotations_that_follow_them() {
    use keyrig_core::channel::ChannelPath;
    use keyrig_core::channel_id::{set_rotation_keys, ChannelId};
    let mut scene = keyrig_io::demo::demo_scene();
    let cube = scene.objects.iter().position(|o| o.name == "Cube").expect("the demo's cube");
    assert!(set_rotation_keys(
        &mut scene,
        ChannelId::ObjectRotation(cube),
        keyrig_core::RotationMode::Euler(keyrig_core::EulerOrder::XYZ),
        true
    )
    .unwrap());
    let euler = scene.objects[cube].rotation_euler.as_mut().expect("Euler keys");
    euler.track.keys[1].value.x = 60.0;
    euler.track.keys[2].value.z = -45.0;
    euler.track.keys[3].value.y = 500.0;
    assert!(set_rotation_keys(
        &mut scene,
        ChannelId::JointRotation { object: 0, joint: 1 },
        keyrig_core::RotationMode::Euler(keyrig_core::EulerOrder::ZXY),
        true
    )
    .unwrap());
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    let options = ExportOptions::default();
    let exported = export_scene(&scene, &options).expect("export");
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("euler.glb");
    exported.write(&path).expect("write");
    let (errors, warnings, report) = validate(&path);
    assert_eq!((errors, warnings), (0, 0), "{report}");
    let model = import_gltf_slice(&exported.to_glb()).expect("re-import");
    let tol = 1.1 * options.rotation_tolerance_deg.to_radians() + 1e-5;
    let cube_rotation = ChannelPath::parse("object/Cube/rotation").unwrap().resolve(&scene).unwrap();
    let elbow_name = scene.objects[0].skeleton.as_ref().unwrap().joints[1].name.clone();
    let elbow_rest = scene.objects[0].skeleton.as_ref().unwrap().joints[1].rest_rotation;
    let elbow = ChannelPath::parse(&format!("object/{}/joint/{elbow_name}/rotation", scene.objects[0].name))
        .unwrap()
        .resolve(&scene)
        .unwrap();
    let (cube_node, elbow_node) = (node_named(&model, "Cube"), node_named(&model, &elbow_name));
    for t in sample_times(&scene) {
        let pose = model.pose_at(Some(0), t);
        let keyrig_core::channel::ChannelValue::Rotation(want) = cube_rotation.sample(t) else { panic!() };
        let angle = rotation_angle(pose.rotation[cube_node], want);
        assert!(angle <= tol, "Cube t {t}: {} deg", angle.to_degrees());
        let keyrig_core::channel::ChannelValue::Rotation(want) = elbow.sample(t) else { panic!() };
        let angle = rotation_angle(pose.rotation[elbow_node], elbow_rest * want);
        assert!(angle <= tol, "elbow t {t}: {} deg", angle.to_degrees());
    }
    // The Cube really turns past a turn about Y between frames 60 and 90 (260° more).
    let euler = scene.objects[cube].rotation_euler.as_ref().unwrap();
    assert!((euler.track.keys[3].value.y - euler.track.keys[2].value.y - 260.0).abs() < 1e-3);
}
