//! The skinned corpus models mapped onto keyrig: scene skeleton (every translation, rotation
//! and scale channel of the joints and the nodes above them, through keyrig-core's validated
//! tracks), keyrig-skin mesh, all four deformers. Linear blend through keyrig-skin agrees with
//! the glTF definition (`ImportedModel::deformed_positions`); every deformer gives finite,
//! bounded results with the same joints and weights. `tests/tests/gltf_reference.rs` checks
//! the same against an evaluation that does not use keyrig-io's importer at all.

use std::path::{Path, PathBuf};

use glam::Vec3;
use keyrig_core::DeformerKind;
use keyrig_io::gltf_import::import_gltf_file;
use keyrig_skin::{deform_mesh, BlendZone, JointPalette};

fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf").join(rel)
}

/// (file, largest linear-blend difference allowed, relative to the model's size). The
/// differences come only from keyrig's f32 arithmetic (tracks are evaluated in f64 and rounded,
/// the palette is f32); the corpus stores at most four influences per vertex, summing to 1.
const SKINNED: [(&str, f32); 5] = [
    ("RiggedSimple/RiggedSimple.glb", 1e-5),
    ("RiggedFigure/RiggedFigure.glb", 1e-5),
    ("CesiumMan/CesiumMan.glb", 1e-5),
    ("SimpleSkin/glTF/SimpleSkin.gltf", 1e-5),
    ("Fox/Fox.glb", 1e-5),
];

#[test]
fn skinned_corpus_models_deform_with_all_four_deformers() {
    for (file, allowed) in SKINNED {
        let model = import_gltf_file(&corpus(file)).expect("import");
        let scene = model.to_scene("model.glb", Some(0)).expect("scene");
        let mesh_node =
            model.nodes.iter().position(|n| n.skin.is_some() && n.mesh.is_some()).expect("skinned node");
        let skin = model.nodes[mesh_node].skin.expect("skin");
        let object = scene
            .objects
            .iter()
            .find(|o| o.name == model.nodes[mesh_node].name)
            .expect("object for the skinned node");
        let skeleton = object.skeleton.as_ref().expect("skeleton");
        // The skin's joints and the nodes above them, up to the scene root.
        assert!(skeleton.joints.len() >= model.skins[skin].joints.len(), "{file}");
        let mesh = model.skinned_mesh(mesh_node).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(mesh.skeleton.len(), skeleton.joints.len(), "{file}");
        // Poses from the scene evaluator, as the editor plays them.
        let o = scene.objects.iter().position(|x| std::ptr::eq(x, object)).expect("index");
        let eval = keyrig_eval::SceneEvaluator::new(&scene, &std::collections::HashMap::new());
        let pose =
            |t: f64| eval.object_at(o, t, &keyrig_eval::Overrides::new()).and_then(|s| s.pose).expect("pose");
        let bindings = mesh.bindings(BlendZone::new(0.25, 0.25).expect("zone")).expect("bindings");
        let (lo, hi) = mesh.positions.iter().fold((Vec3::MAX, Vec3::MIN), |(l, h), p| (l.min(*p), h.max(*p)));
        let size = (hi - lo).length();
        let duration = model.animations[0].duration();
        let mut worst_linear = 0.0f32;
        for step in 0..=8 {
            let t = duration * f64::from(step) / 8.0;
            let palette = JointPalette::new(&mesh.skeleton, &pose(t)).expect("palette");
            let exact = model.deformed_positions(mesh_node, Some(0), t).expect("exact");
            let exact: Vec<Vec3> = exact.into_iter().flatten().collect();
            for kind in DeformerKind::ALL {
                let out = deform_mesh(&mesh, &bindings, &palette, kind)
                    .unwrap_or_else(|e| panic!("{file} {kind:?}: {e}"));
                assert_eq!(out.positions.len(), exact.len());
                // The skinned object sits at the origin: model space is the file's world.
                for (p, e) in out.positions.iter().zip(&exact) {
                    assert!(p.is_finite(), "{file} {kind:?}");
                    // Bounded: no deformer moves a vertex further from its linear-blend
                    // position than the model is large.
                    assert!((*p - *e).length() <= size + 1e-3, "{file} {kind:?} t {t}");
                }
                if kind == DeformerKind::LinearBlend {
                    for (p, e) in out.positions.iter().zip(&exact) {
                        worst_linear = worst_linear.max((*p - *e).length() / size);
                    }
                }
            }
        }
        assert!(
            worst_linear <= allowed,
            "{file}: keyrig-skin linear blend differs by {worst_linear} of the size"
        );
        eprintln!(
            "{file}: keyrig-skin linear blend vs glTF definition: worst {worst_linear:.2e} of the size"
        );
    }
}
