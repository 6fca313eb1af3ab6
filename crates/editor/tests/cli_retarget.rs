//! `keyrig retarget` (docs/retargeting.md): the CMU 131 walk onto CesiumMan written as a scene
//! file whose new action plays on the character, the bone map written, edited and given back,
//! and what the command refuses.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use keyrig_edit::retarget::BoneMap;

const KEYRIG: &str = env!("CARGO_BIN_EXE_keyrig");

fn keyrig(args: &[&str]) -> Output {
    Command::new(KEYRIG).args(args).output().expect("run keyrig")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn corpus(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus").join(path)
}

#[test]
fn the_cmu_walk_onto_cesium_man_with_its_map_written_and_read_back() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (take, cesium) = (corpus("bvh/cmu-bvh11/131_01.bvh"), corpus("gltf/CesiumMan/CesiumMan.glb"));
    let out_path = dir.path().join("walk.ron");
    let map_path = dir.path().join("map.ron");
    let out = keyrig(&[
        "retarget",
        take.to_str().unwrap(),
        cesium.to_str().unwrap(),
        "-o",
        out_path.to_str().unwrap(),
        "--write-map",
        map_path.to_str().unwrap(),
        "--reduce",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("action \"131_01\""), "{}", stderr(&out));
    let scene = keyrig_io::scene_file::load(&out_path).expect("the written scene loads");
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    assert_eq!(scene.objects[0].action.as_deref(), Some("131_01"));
    assert!(scene.action_index("animation0").is_some(), "the model's own animation is kept");
    let skeleton = scene.objects[0].skeleton.as_ref().unwrap();
    let head = skeleton.joints.iter().find(|j| j.name == "Skeleton_neck_joint_2").unwrap();
    assert!(head.rotation.is_animated());

    // The map as written, without the head, given back: the head is not driven.
    let text = std::fs::read_to_string(&map_path).expect("the map was written");
    let mut map: BoneMap = ron::from_str(&text).expect("a bone map");
    assert_eq!(map.pairs.len(), 19);
    map.set("Skeleton_neck_joint_2", None);
    let edited = dir.path().join("edited.json");
    std::fs::write(&edited, serde_json::to_string(&map).unwrap()).unwrap();
    let out_path = dir.path().join("no-head.ron");
    let out = keyrig(&[
        "retarget",
        take.to_str().unwrap(),
        cesium.to_str().unwrap(),
        "-o",
        out_path.to_str().unwrap(),
        "--map",
        edited.to_str().unwrap(),
        "--action",
        "Walk",
        "--no-contacts",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let scene = keyrig_io::scene_file::load(&out_path).expect("the written scene loads");
    assert_eq!(scene.objects[0].action.as_deref(), Some("Walk"));
    let skeleton = scene.objects[0].skeleton.as_ref().unwrap();
    let head = skeleton.joints.iter().find(|j| j.name == "Skeleton_neck_joint_2").unwrap();
    assert!(!head.rotation.is_animated());
    let neck = skeleton.joints.iter().find(|j| j.name == "Skeleton_neck_joint_1").unwrap();
    assert_eq!(neck.rotation.track.len(), 994);
}

#[test]
fn retarget_refuses_what_it_cannot_do() {
    let dir = tempfile::tempdir().expect("temp dir");
    let (take, cesium) = (corpus("bvh/cmu-bvh11/131_01.bvh"), corpus("gltf/CesiumMan/CesiumMan.glb"));
    let (take, cesium) = (take.to_str().unwrap(), cesium.to_str().unwrap());
    let glb = dir.path().join("out.glb");
    let out = keyrig(&["retarget", take, cesium, "-o", glb.to_str().unwrap()]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("must end in .ron"), "{}", stderr(&out));

    let map = dir.path().join("map.json");
    std::fs::write(&map, r#"{"pairs": [{"source": "Hips", "target": "NoSuchJoint"}]}"#).unwrap();
    let ron_out = dir.path().join("out.ron");
    let out = keyrig(&[
        "retarget",
        take,
        cesium,
        "-o",
        ron_out.to_str().unwrap(),
        "--map",
        map.to_str().unwrap(),
        "--object",
        "Cesium_Man",
    ]);
    assert!(!out.status.success());
    assert!(stderr(&out).contains("the target skeleton has no joint \"NoSuchJoint\""), "{}", stderr(&out));
    assert!(!ron_out.exists());
}
