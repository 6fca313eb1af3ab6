//! `assets/ik.ron`, the IK constraint example of issue 19: the serialized `ik_scene()`, the arm's
//! wrist following a target that circles and repeats, the IK/FK blend keyed from 0 to 1.
//!
//! After changing `keyrig_io::demo::ik_scene`, regenerate the file with
//! `KEYRIG_REGENERATE_DEMO=1 cargo test -p keyrig-io --test scene_ik`.

use std::collections::HashMap;
use std::path::Path;

use glam::Vec3;
use keyrig_core::Cycle;
use keyrig_eval::{Overrides, SceneEvaluator};
use keyrig_io::demo::{ik_scene, IK_CIRCLE_SECONDS, IK_RON};
use keyrig_io::scene_file;

#[test]
fn committed_ik_file_equals_generated_scene() {
    let generated = scene_file::to_string(&ik_scene()).expect("serialize the IK scene");
    if std::env::var_os("KEYRIG_REGENERATE_DEMO").is_some() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/ik.ron");
        std::fs::write(&path, &generated).expect("write assets/ik.ron");
        return;
    }
    assert!(
        IK_RON == generated,
        "assets/ik.ron differs from keyrig_io::demo::ik_scene(); regenerate it with \
         KEYRIG_REGENERATE_DEMO=1 cargo test -p keyrig-io --test scene_ik"
    );
    // The constraint is written readably, after the joints.
    for field in ["ik_constraints: [", "name: \"Reach\",", "end: 3,", "bones: 3,", "pole: Some("] {
        assert!(IK_RON.contains(field), "{field} missing from\n{IK_RON}");
    }
}

/// The wrist is on the target at every frame once the blend is 1, and the motion repeats
/// every circle.
#[test]
fn the_wrist_follows_the_repeating_target() {
    let scene = scene_file::from_str(IK_RON, Path::new("assets/ik.ron")).expect("ik.ron loads");
    assert_eq!(scene, ik_scene());
    assert_eq!(scene.problems(), Vec::new());
    let reach = &scene.objects[0].skeleton.as_ref().expect("a skeleton").ik_constraints[0];
    assert_eq!((reach.target.before, reach.target.after), (Cycle::Repeat, Cycle::Repeat));
    let eval = SceneEvaluator::new(&scene, &HashMap::new());
    assert!(eval.problems().is_empty(), "{:?}", eval.problems());
    let none = Overrides::new();
    let wrist_at = |time: f64| -> (Vec3, Vec3) {
        let state = eval.object_at(0, time, &none).expect("the arm");
        let wrist = state.palette.expect("a palette").model_from_joint[3].translation.into();
        let target = match eval.value(
            keyrig_core::channel_id::ChannelId::IkTarget { object: 0, constraint: 0 },
            time,
            &none,
        ) {
            Some(keyrig_core::channel_id::ChannelValue::Vec3(v)) => v,
            other => panic!("target: {other:?}"),
        };
        (wrist, target)
    };
    let length = keyrig_io::demo::ARM_LENGTH * 3.0 / 4.0;
    for frame in 15..=120 {
        let (wrist, target) = wrist_at(f64::from(frame) / scene.fps);
        assert!(wrist.distance(target) <= 1e-5 * length, "frame {frame}: {wrist:?} vs {target:?}");
    }
    for t in [0.6, 0.9, 1.3, 1.95] {
        let (a, _) = wrist_at(t);
        let (b, _) = wrist_at(t + IK_CIRCLE_SECONDS);
        assert!(a.distance(b) < 1e-5, "t = {t}: {a:?} vs {b:?}");
    }
}

/// A skeleton without constraints writes no `ik_constraints` field (every older file saves
/// byte-for-byte as before); the blend may be left out of a file (it is then 1, fully IK), and
/// the fast reader and `ron` read a constraint to the same value.
#[test]
fn constraints_are_written_only_when_present() {
    let mut scene = ik_scene();
    let text = scene_file::to_string(&scene).expect("serializes");
    let reach = &scene.objects[0].skeleton.as_ref().expect("a skeleton").ik_constraints[0];
    let short = text.replace(
        "                            blend: (\n                                value: 0.0,\n                                track: [\n                                    (time: 0.0, value: 0.0, interpolation: Linear),\n                                    (time: 0.5, value: 1.0),\n                                ],\n                            ),\n",
        "",
    );
    assert_ne!(short, text);
    let read = scene_file::from_str(&short, Path::new("short.ron")).expect("reads without a blend");
    let read_reach = &read.objects[0].skeleton.as_ref().expect("a skeleton").ik_constraints[0];
    assert_eq!(read_reach.blend, keyrig_core::Animated::constant(1.0));
    assert_eq!(read_reach.target, reach.target);
    scene.objects[0].skeleton.as_mut().expect("a skeleton").ik_constraints.clear();
    let plain = scene_file::to_string(&scene).expect("serializes");
    assert!(!plain.contains("ik_constraints"), "{plain}");
}

/// glTF has no IK: export bakes the constraint, so the exported joint rotations at every frame
/// are the solved ones (rest rotation · solved local rotation), read straight from the file's
/// JSON and binary buffer.
#[test]
fn export_writes_the_solved_rotations_at_every_frame() {
    use keyrig_io::gltf_export::{export_scene, ExportOptions, ExportedGltf};
    let scene = ik_scene();
    let gltf = export_scene(&scene, &ExportOptions::default()).expect("export the IK scene");

    let floats = |gltf: &ExportedGltf, index: usize| -> Vec<f32> {
        let accessor = &gltf.json["accessors"][index];
        let width = match accessor["type"].as_str().expect("type") {
            "SCALAR" => 1,
            "VEC3" => 3,
            "VEC4" => 4,
            other => panic!("type {other}"),
        };
        let count = accessor["count"].as_u64().expect("count") as usize;
        let view = &gltf.json["bufferViews"][accessor["bufferView"].as_u64().expect("view") as usize];
        let start = view["byteOffset"].as_u64().unwrap_or(0) as usize
            + accessor["byteOffset"].as_u64().unwrap_or(0) as usize;
        (0..count * width)
            .map(|i| {
                f32::from_le_bytes(gltf.bin[start + 4 * i..start + 4 * i + 4].try_into().expect("4 bytes"))
            })
            .collect()
    };
    let eval = SceneEvaluator::new(&scene, &HashMap::new());
    let skeleton = scene.objects[0].skeleton.as_ref().expect("a skeleton");
    let nodes = gltf.json["nodes"].as_array().expect("nodes");
    let animation = &gltf.json["animations"][0];
    let mut checked = 0;
    // The chain's joints (shoulder, elbow, forearm): the constraint turns them.
    for j in 0..3 {
        let name = &skeleton.joints[j].name;
        let node =
            nodes.iter().position(|n| n["name"] == name.as_str()).unwrap_or_else(|| panic!("node {name}"));
        let channel = animation["channels"]
            .as_array()
            .expect("channels")
            .iter()
            .find(|c| c["target"]["node"] == node && c["target"]["path"] == "rotation")
            .unwrap_or_else(|| panic!("no rotation channel for {name}"));
        let sampler = &animation["samplers"][channel["sampler"].as_u64().expect("sampler") as usize];
        let times = floats(&gltf, sampler["input"].as_u64().expect("input") as usize);
        let values = floats(&gltf, sampler["output"].as_u64().expect("output") as usize);
        for frame in scene.frame_range.start..=scene.frame_range.end {
            let t = f64::from(frame) / scene.fps;
            let Some(k) = times.iter().position(|&kt| (f64::from(kt) - t).abs() < 1e-4) else {
                panic!("{name}: no exported key at frame {frame}")
            };
            let q = &values[4 * k..4 * k + 4];
            let exported = glam::Quat::from_xyzw(q[0], q[1], q[2], q[3]).normalize();
            let state = eval.object_at(0, t, &Overrides::new()).expect("the arm");
            let solved = state.pose.as_ref().expect("a pose").local_rotations[j];
            let want = (skeleton.joints[j].rest_rotation * solved).normalize();
            let angle = 2.0 * f64::from(exported.dot(want).abs().min(1.0)).acos();
            assert!(
                angle < 2e-4,
                "{name} at frame {frame}: exported {exported:?}, solved {want:?} ({angle} rad)"
            );
            checked += 1;
        }
    }
    assert_eq!(checked, 3 * (scene.frame_range.end - scene.frame_range.start + 1) as usize);
}
