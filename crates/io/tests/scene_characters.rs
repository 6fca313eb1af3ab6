//! `assets/characters.ron`: the demo with CesiumMan, the Fox and an MD2 model (copies in
//! `assets/models/` with their licence files) is what `keyrig_io::demo::characters_scene`
//! generates, opens from the repository, and every object's mesh is found and evaluates.
//! Regenerate with `KEYRIG_REGENERATE_DEMO=1 cargo test -p keyrig-io --test scene_characters`.

use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use keyrig_core::MeshSource;
use keyrig_eval::{LoadedMesh, SceneEvaluator};
use keyrig_io::scene_file;

fn assets() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets")
}

#[test]
fn committed_characters_file_equals_generated_scene() {
    let models = assets().join("models");
    let cesium =
        keyrig_io::gltf_import::import_gltf_file(&models.join("CesiumMan/CesiumMan.glb")).expect("CesiumMan");
    let fox = keyrig_io::gltf_import::import_gltf_file(&models.join("Fox/Fox.glb")).expect("Fox");
    let sydney = keyrig_io::md2::load_md2_file(&models.join("sydney/sydney.md2")).expect("sydney");
    let scene = keyrig_io::demo::characters_scene(&cesium, &fox, &sydney).expect("scene");
    let generated = scene_file::to_string(&scene).expect("serialize");
    let path = assets().join("characters.ron");
    if std::env::var_os("KEYRIG_REGENERATE_DEMO").is_some() {
        std::fs::write(&path, &generated).expect("write assets/characters.ron");
        return;
    }
    let committed = std::fs::read_to_string(&path).expect("read assets/characters.ron");
    assert!(
        committed == generated,
        "assets/characters.ron differs from characters_scene(); regenerate it with \
         KEYRIG_REGENERATE_DEMO=1 cargo test -p keyrig-io --test scene_characters"
    );

    // Every model file is found beside the scene and the whole scene evaluates.
    let loaded = scene_file::load(&path).expect("opens");
    let mut meshes = HashMap::new();
    for (o, object) in loaded.objects.iter().enumerate() {
        let Some(MeshSource::File { path: file, mesh, .. }) = &object.mesh else { continue };
        let file = assets().join(file);
        let mesh = if file.extension().is_some_and(|e| e == "md2") {
            let model = keyrig_io::md2::load_md2_file(&file).expect("md2");
            assert!(model.skin.is_some(), "the MD2 skin ships beside the model");
            LoadedMesh::Morph(Arc::new(model.playback().expect("clips")))
        } else {
            let model = keyrig_io::gltf_import::import_gltf_file(&file).expect("glTF");
            let node =
                model.nodes.iter().position(|n| n.mesh == *mesh && n.skin.is_some()).expect("skinned node");
            LoadedMesh::Skinned(Arc::new(model.skinned_mesh(node).expect("mesh")))
        };
        meshes.insert(o, mesh);
    }
    assert_eq!(meshes.len(), 3, "CesiumMan, the Fox and Sydney");
    let eval = SceneEvaluator::new(&loaded, &meshes);
    assert!(eval.problems().is_empty(), "{:?}", eval.problems());
    let state = eval.evaluate(1.0, &Default::default());
    // Palettes: the arm, the cube (its rest palette), CesiumMan and the Fox; Sydney morphs.
    assert_eq!(state.objects.iter().filter(|o| o.palette.is_some()).count(), 4);
    assert_eq!(state.objects.iter().filter(|o| matches!(o.morph, Some(Ok(_)))).count(), 1);
}
