//! Imported characters move exactly as their glTF file says.
//!
//! For every skinned model of the external corpus (`tests/corpus/gltf/`) and every
//! animation in it, the vertices keyrig shows (glTF import → keyrig scene → keyrig-core's
//! tracks → keyrig-skin's joint palette → linear blend skinning → the object's transform) are
//! compared at every frame (30 fps, the scene's rate) with an independent evaluation of the same
//! file, written here from the glTF 2.0 specification alone:
//!
//! - the file is read with the `gltf` crate's own importer and accessor readers (not keyrig-io's
//!   importer);
//! - samplers follow the specification's Appendix C in f64: STEP holds, LINEAR lerps
//!   translations and scales and slerps rotations the short way, CUBICSPLINE is the Hermite
//!   `h00·v_k + h10·t_d·b_k + h01·v_{k+1} + h11·t_d·a_{k+1}` (rotations normalized after it);
//!   times outside the keys clamp;
//! - node matrices `T·R·S` are composed from the scene root down in f64, joint matrices are
//!   `globalTransform(joint) · inverseBindMatrix`, and a vertex is `Σ wᵢ · jointMatrix(jᵢ) · v`
//!   with the weights of every JOINTS_n/WEIGHTS_n set, normalized to sum 1 (the specification
//!   asks files to store them so).
//!
//! Every vertex must agree within 1e-4 of the model's size (the diagonal of its rest-frame
//! bounding box). docs/interchange.md describes this check. The evaluator is the shared
//! module `reference/` (also used by `export_roundtrip` and `export_bake`).

mod reference;

use glam::DVec3;
use reference::{corpus, mesh_node, read_reference, Interpolator};

const TOLERANCE: f64 = 1e-4;
const FPS: f64 = 30.0;

/// The skinned models of the corpus.
const SKINNED: [&str; 6] = [
    "gltf/RiggedSimple/RiggedSimple.glb",
    "gltf/RiggedSimple/glTF/RiggedSimple.gltf",
    "gltf/RiggedFigure/RiggedFigure.glb",
    "gltf/CesiumMan/CesiumMan.glb",
    "gltf/SimpleSkin/glTF/SimpleSkin.gltf",
    "gltf/Fox/Fox.glb",
];

#[test]
fn imported_characters_match_an_independent_gltf_evaluation_at_every_frame() {
    let mut report = Vec::new();
    for file in SKINNED {
        let path = corpus(file);
        let (doc, buffers, _) = gltf::import(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
        let reference = read_reference(&doc, &buffers);
        let model = keyrig_io::gltf_import::import_gltf_file(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
        let skinned: Vec<gltf::Node<'_>> =
            doc.nodes().filter(|n| n.skin().is_some() && n.mesh().is_some()).collect();
        assert!(!skinned.is_empty(), "{file}: no skinned mesh node");
        for animation in 0..reference.animations.len() {
            let scene =
                model.to_scene("model.glb", Some(animation)).unwrap_or_else(|e| panic!("{file}: {e}"));
            for node in &skinned {
                let gltf_node = mesh_node(node, &buffers);
                let object = scene
                    .objects
                    .iter()
                    .find(|o| o.name == model.nodes[node.index()].name)
                    .unwrap_or_else(|| panic!("{file}: no object for node {}", node.index()));
                let o = scene.objects.iter().position(|x| std::ptr::eq(x, object)).expect("index");
                let mesh = model.skinned_mesh(node.index()).unwrap_or_else(|e| panic!("{file}: {e}"));
                assert_eq!(mesh.positions.len(), gltf_node.positions.len(), "{file}: vertex count");
                // keyrig's one path: the scene evaluator with the object's mesh (the editor's,
                // `render`'s and `deform`'s).
                let loaded = std::collections::HashMap::from([(
                    o,
                    keyrig_eval::LoadedMesh::Skinned(std::sync::Arc::new(mesh.clone())),
                )]);
                let eval = keyrig_eval::SceneEvaluator::new(&scene, &loaded);
                assert!(eval.problems().is_empty(), "{file}: {:?}", eval.problems());
                let skin = eval.skin(o).expect("skinned");
                let rest = gltf_node.at(&reference, Some(animation), 0.0, Interpolator::Spec);
                let (lo, hi) = rest.iter().fold((DVec3::MAX, DVec3::MIN), |(l, h), p| (l.min(*p), h.max(*p)));
                let size = (hi - lo).length();
                let frames = (reference.duration(animation) * FPS).ceil() as usize;
                let mut worst = 0.0f64;
                for frame in 0..=frames {
                    let t = frame as f64 / FPS;
                    let expected = gltf_node.at(&reference, Some(animation), t, Interpolator::Spec);
                    let state = eval.object_at(o, t, &keyrig_eval::Overrides::new()).expect("object");
                    let palette = state.palette.expect("palette");
                    let deformed = keyrig_skin::deform_mesh(
                        &skin.mesh,
                        &skin.bindings,
                        &palette,
                        keyrig_core::DeformerKind::LinearBlend,
                    )
                    .expect("linear blend");
                    let world_from_object = glam::Mat4::from(state.world_from_object);
                    for (v, (got, want)) in deformed.positions.iter().zip(&expected).enumerate() {
                        let got = world_from_object.transform_point3(*got).as_dvec3();
                        let error = (got - *want).length() / size;
                        assert!(
                            error <= TOLERANCE,
                            "{file}, animation {animation}, frame {frame} (t = {t}), vertex {v}: keyrig {got:?}, \
                             glTF {want:?}: {error:.2e} of the model's size {size}"
                        );
                        worst = worst.max(error);
                    }
                }
                report
                    .push(format!("{file} animation {animation}: {} frames, worst {worst:.2e}", frames + 1));
            }
        }
    }
    // Shown with --nocapture; docs/interchange.md quotes these figures.
    println!("{}", report.join("\n"));
}
