//! The command line at the size users bring: a glTF file of 100,000 meshes that reuse one
//! accessor, and one of 100,000 skinned mesh nodes, through `keyrig info` and `keyrig import`
//! and back through `info` on the scene. Nothing is timed: each step searched a list per
//! object before (`info` found each channel's object by name, the import loaded the model file
//! once per mesh and framed the scene by searching the loaded meshes per object), which made
//! the reused-accessor file take hours; a quadratic step would make this test run for minutes.
//! `cargo bench -p keyrig-io --bench import_scale` measures the import's speed.

#[path = "../../io/tests/support/big_gltf.rs"]
mod big_gltf;

use std::path::Path;
use std::process::Command;

fn keyrig(args: &[&str]) -> String {
    let out = Command::new(env!("CARGO_BIN_EXE_keyrig")).args(args).output().expect("run keyrig");
    assert!(out.status.success(), "keyrig {args:?}: {}", String::from_utf8_lossy(&out.stderr));
    String::from_utf8_lossy(&out.stdout).into_owned()
}

fn info_objects(file: &Path) -> String {
    let text = keyrig(&["info", file.to_str().expect("utf-8")]);
    text.lines().find(|l| l.starts_with("objects:")).expect("an objects line").to_owned()
}

#[test]
fn a_hundred_thousand_meshes_or_skinned_nodes_import_and_summarize() {
    let dir = tempfile::tempdir().expect("temp dir");
    for (name, bytes) in [
        ("reused.glb", big_gltf::reused_accessor_meshes(100_000)),
        ("skinned.glb", big_gltf::many_skinned_nodes(100_000)),
    ] {
        let model = dir.path().join(name);
        std::fs::write(&model, bytes).expect("write the model");
        assert_eq!(info_objects(&model), "objects:  100000", "{name}");
        let scene = dir.path().join(format!("{name}.ron"));
        keyrig(&["import", model.to_str().expect("utf-8"), "-o", scene.to_str().expect("utf-8")]);
        assert_eq!(info_objects(&scene), "objects:  100000", "{name} as a scene");
    }
}
