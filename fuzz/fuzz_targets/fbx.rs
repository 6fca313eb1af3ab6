//! FBX import on arbitrary bytes: ufbx parses them (its own checks and memory limits), keyrig
//! maps what ufbx returns into an `ImportedModel` (`keyrig_io::fbx`). An accepted model is
//! then mapped onto a scene, evaluated and skinned with all four deformers, as the glTF target
//! does: the mapping must give the downstream code nothing it refuses with a panic.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let Ok(import) = keyrig_io::fbx::import_fbx_slice(data) else { return };
    let model = import.model;
    let animation = if model.animations.is_empty() { None } else { Some(0) };
    for node in 0..model.nodes.len().min(8) {
        let _ = model.deformed_positions(node, animation, 0.5);
        if let Some(mesh) = model.nodes[node].mesh {
            let _ = model.rigid_mesh(mesh);
            let _ = model.material(mesh);
        }
        let skin = model.nodes[node].skin;
        if let (Ok(mesh), Some(skin)) = (model.skinned_mesh(node), skin) {
            let pose = model.scene_skeleton(skin, animation).ok().and_then(|skeleton| {
                let scene = keyrig_core::Scene {
                    objects: vec![keyrig_core::Object {
                        skeleton: Some(skeleton),
                        ..keyrig_core::Object::new("fuzz")
                    }],
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
    if let Ok(scene) = model.to_scene("fuzz.fbx", animation) {
        let eval = keyrig_eval::SceneEvaluator::new(&scene, &Default::default());
        for o in 0..scene.objects.len().min(8) {
            let _ = eval.object_at(o, 0.5, &Default::default());
        }
    }
    // Every primitive's attributes and indices agree.
    for mesh in &model.meshes {
        for p in mesh.primitives.iter() {
            let n = p.positions.len();
            assert!(p.indices.iter().all(|&i| (i as usize) < n));
            assert!(p.normals.as_ref().is_none_or(|x| x.len() == n));
            assert!(p.texcoords.as_ref().is_none_or(|x| x.len() == n));
            assert!(p.joint_sets.iter().all(|x| x.len() == n));
            assert!(p.morph_targets.iter().all(|t| t.positions.as_ref().is_none_or(|x| x.len() == n)));
        }
    }
});
