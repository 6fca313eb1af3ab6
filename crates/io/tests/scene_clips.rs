//! `assets/clips.ron` (docs/clips.md): the Fox surveys, walks and crossfades into a run with its
//! root continuing while a layer lifts its head, is what `keyrig_io::demo::clips_scene`
//! generates, opens from the repository and plays what it says.
//! Regenerate with `KEYRIG_REGENERATE_DEMO=1 cargo test -p keyrig-io --test scene_clips`.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use keyrig_eval::{LoadedMesh, Overrides, SceneEvaluator};
use keyrig_io::scene_file;

fn assets() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets")
}

#[test]
fn committed_clips_file_equals_generated_scene_and_plays_the_stack() {
    let fox = keyrig_io::gltf_import::import_gltf_file(&assets().join("models/Fox/Fox.glb")).expect("Fox");
    let scene = keyrig_io::demo::clips_scene(&fox).expect("scene");
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    let generated = scene_file::to_string(&scene).expect("serialize");
    let path = assets().join("clips.ron");
    if std::env::var_os("KEYRIG_REGENERATE_DEMO").is_some() {
        std::fs::write(&path, &generated).expect("write assets/clips.ron");
        return;
    }
    let committed = std::fs::read_to_string(&path).expect("read assets/clips.ron");
    assert!(
        committed == generated,
        "assets/clips.ron differs from clips_scene(); regenerate it with \
         KEYRIG_REGENERATE_DEMO=1 cargo test -p keyrig-io --test scene_clips"
    );
    let loaded = scene_file::load(&path).expect("opens");
    assert_eq!(loaded, scene, "reads back to the same scene");

    let node = fox.nodes.iter().position(|n| n.skin.is_some()).expect("skinned node");
    let meshes = HashMap::from([(0, LoadedMesh::Skinned(Arc::new(fox.skinned_mesh(node).expect("mesh"))))]);
    let eval = SceneEvaluator::new(&loaded, &meshes);
    assert!(eval.problems().is_empty(), "{:?}", eval.problems());
    let fps = loaded.fps;
    let at = |f: i32| eval.object_at(0, f64::from(f) / fps, &Overrides::new()).expect("fox");
    // Survey stands; the walk carries the fox on; the run never snaps it back.
    let z = |f: i32| at(f).world_from_object.translation.z;
    assert!(z(0).abs() < 1e-6 && z(100).abs() < 1e-6, "{} {}", z(0), z(100));
    let mut last = z(104);
    for f in 105..=loaded.frame_range.end {
        let now = z(f);
        assert!(now >= last - 1e-5, "the fox moves back at frame {f}: {last} → {now}");
        last = now;
    }
    assert!(last > 4.0, "walked and ran {last} m");
}
