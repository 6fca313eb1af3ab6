//! The whole glTF import path (GLB container, JSON, validation, accessors, buffers, skins,
//! animations) on arbitrary bytes; an accepted model is also posed and skinned (the glTF
//! reference and, for skinned nodes, keyrig-skin posed by the mapped scene skeleton with all
//! four deformers) and mapped onto a scene. Primitives that share an accessor must share its
//! decoded values (keyrig-io decodes each accessor once).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(model) = keyrig_io::gltf_import::import_gltf_slice(data) {
        let animation = if model.animations.is_empty() { None } else { Some(0) };
        for node in 0..model.nodes.len().min(8) {
            let _ = model.deformed_positions(node, animation, 0.5);
            let skin = model.nodes[node].skin;
            if let (Ok(mesh), Some(skin)) = (model.skinned_mesh(node), skin) {
                let pose = model.scene_skeleton(skin, animation).ok().and_then(|skeleton| {
                    let scene = keyrig_core::Scene {
                        objects: vec![keyrig_core::Object { skeleton: Some(skeleton), ..keyrig_core::Object::new("fuzz") }],
                        ..keyrig_core::Scene::default()
                    };
                    let eval = keyrig_eval::SceneEvaluator::new(&scene, &Default::default());
                    eval.object_at(0, 0.5, &Default::default()).and_then(|s| s.pose)
                });
                let palette = pose.and_then(|p| keyrig_skin::JointPalette::new(&mesh.skeleton, &p).ok());
                if let (Some(palette), Ok(zone)) = (palette, keyrig_skin::BlendZone::new(0.25, 0.25)) {
                    if let Ok(bindings) = mesh.bindings(zone) {
                        for kind in keyrig_core::DeformerKind::ALL {
                            let _ = keyrig_skin::deform_mesh(&mesh, &bindings, &palette, kind);
                        }
                    }
                }
            }
        }
        let _ = model.to_scene("fuzz.glb", animation);
        for mesh in &model.meshes {
            for pair in mesh.primitives.windows(2) {
                if pair[0].positions.as_ptr() != pair[1].positions.as_ptr() {
                    continue;
                }
                assert!(std::sync::Arc::ptr_eq(&pair[0].positions, &pair[1].positions));
            }
        }
    }
});
