//! Round trip: every model of the external corpus, imported as keyrig imports it (glTF →
//! `ImportedModel::to_scene`, once per animation; MD2 → `keyrig_io::md2::md2_scene`), saved and
//! loaded again as a scene file, exported with `export_scene`, then read back by the
//! independent glTF evaluator of `reference/` (the `gltf` crate's readers and the
//! specification's samplers, not keyrig-io's importer). At every frame of the scene's range
//! the exported file's deformed vertices must equal what keyrig shows, within 1e-4 of the
//! model's size:
//!
//! - skinned glTF objects: the scene evaluator (`SceneEvaluator::object_at`) → `JointPalette` on the mesh of
//!   `ImportedModel::skinned_mesh` → linear blend → the object's transform;
//! - unskinned glTF objects: the mesh morphed with the file's first animation's weights (as
//!   `keyrig deform` does), placed by the object's transform tracks;
//! - MD2 objects: the looping morph blend between frames (keyrig-eval's `MorphClips::blend_at`, the editor's
//!   `MorphMesh::blend_at`), placed by the object's transform.
//!
//! The Khronos glTF-Validator must report 0 errors and 0 warnings on every exported file.

mod reference;

use std::path::Path;

use glam::{DVec3, Mat4, Vec3};
use keyrig_core::{AnimatedTrack, MeshSource, Object, Scene};
use keyrig_io::gltf_export::{export_scene, ExportOptions};
use keyrig_io::model::{ChannelTarget, ImportedModel, PrimitiveMode};
use reference::{corpus, mesh_node, read_reference, size_of, validate, Interpolator};

const TOLERANCE: f64 = 1e-4;

const GLTF: [&str; 8] = [
    "gltf/RiggedSimple/RiggedSimple.glb",
    "gltf/RiggedSimple/glTF/RiggedSimple.gltf",
    "gltf/RiggedFigure/RiggedFigure.glb",
    "gltf/CesiumMan/CesiumMan.glb",
    "gltf/SimpleSkin/glTF/SimpleSkin.gltf",
    "gltf/Fox/Fox.glb",
    "gltf/InterpolationTest/InterpolationTest.glb",
    "gltf/AnimatedMorphCube/AnimatedMorphCube.glb",
];

const MD2: [&str; 5] = [
    "md2/ratamahatta/ratamahatta.md2",
    "md2/ratamahatta/weapon.md2",
    "md2/sydney/sydney.md2",
    "md2/faerie/faerie.md2",
    "md2/dolphin/dolphin.md2",
];

/// The object's world transform at `t` through keyrig-core's tracks.
fn object_world(object: &Object, t: f64) -> Mat4 {
    let s = AnimatedTrack::new(&object.scale).expect("scale").sample(t);
    let r = AnimatedTrack::new(&object.rotation).expect("rotation").sample(t);
    let p = AnimatedTrack::new(&object.translation).expect("translation").sample(t);
    Mat4::from_scale_rotation_translation(s, r, p)
}

/// What keyrig shows of one object over time.
enum Shown {
    /// The object alone, through the scene evaluator with its mesh.
    Skinned {
        eval: Box<keyrig_eval::SceneEvaluator>,
    },
    Morphed {
        model: Box<ImportedModel>,
        node: usize,
        mesh: usize,
    },
    Md2 {
        model: Box<keyrig_io::md2::Md2Model>,
        clip: Option<String>,
        fps: f64,
    },
}

impl Shown {
    fn of(object: &Object) -> Shown {
        let Some(MeshSource::File { path, mesh, clip, fps }) = &object.mesh else {
            panic!("not a file mesh")
        };
        if path.ends_with(".md2") {
            let model = keyrig_io::md2::load_md2_file(Path::new(path)).expect("md2");
            return Shown::Md2 {
                model: Box::new(model),
                clip: clip.clone(),
                fps: fps.unwrap_or(keyrig_core::MD2_DEFAULT_FPS),
            };
        }
        let model = keyrig_io::gltf_import::import_gltf_file(Path::new(path)).expect("glTF");
        let index = mesh.unwrap_or(0);
        let node = model.nodes.iter().position(|n| n.mesh == Some(index)).expect("node of the mesh");
        if model.nodes[node].skin.is_some() {
            let mesh = model.skinned_mesh(node).expect("skinned mesh");
            let alone = keyrig_core::Scene { objects: vec![object.clone()], ..keyrig_core::Scene::default() };
            let loaded = std::collections::HashMap::from([(
                0,
                keyrig_eval::LoadedMesh::Skinned(std::sync::Arc::new(mesh)),
            )]);
            let eval = keyrig_eval::SceneEvaluator::new(&alone, &loaded);
            assert!(eval.problems().is_empty(), "{:?}", eval.problems());
            Shown::Skinned { eval: Box::new(eval) }
        } else {
            Shown::Morphed { model: Box::new(model), node, mesh: index }
        }
    }

    /// World positions at `t`.
    fn at(&self, object: &Object, t: f64) -> Vec<DVec3> {
        let local: Vec<Vec3> = match self {
            Shown::Skinned { eval } => {
                let skin = eval.skin(0).expect("skinned");
                let palette = eval
                    .object_at(0, t, &keyrig_eval::Overrides::new())
                    .and_then(|s| s.palette)
                    .expect("palette");
                keyrig_skin::deform_mesh(
                    &skin.mesh,
                    &skin.bindings,
                    &palette,
                    keyrig_core::DeformerKind::LinearBlend,
                )
                .expect("linear blend")
                .positions
            }
            Shown::Morphed { model, node, mesh } => {
                let weights = model
                    .animations
                    .first()
                    .into_iter()
                    .flat_map(|a| &a.channels)
                    .find_map(|c| match &c.target {
                        ChannelTarget::Weights(w) if c.node == *node => {
                            keyrig_io::model::sample_weights(w, t)
                        }
                        _ => None,
                    })
                    .unwrap_or_else(|| model.rest_pose().weights[*node].clone());
                model.meshes[*mesh]
                    .primitives
                    .iter()
                    .filter(|p| p.mode == PrimitiveMode::Triangles)
                    .flat_map(|p| ImportedModel::morphed_positions(p, &weights))
                    .collect()
            }
            Shown::Md2 { model, clip, fps } => {
                let blend =
                    model.playback().expect("clips").blend_at(clip.as_deref(), *fps, t).expect("blend");
                model
                    .blended_positions(blend.frame_a as usize, blend.frame_b as usize, blend.t)
                    .expect("frames")
            }
        };
        let world = object_world(object, t);
        local.iter().map(|&p| world.transform_point3(p).as_dvec3()).collect()
    }
}

/// Exports `scene` (after a save and load as a scene file), validates the file and compares it
/// with keyrig at every frame; returns a line for the report.
fn round_trip(label: &str, scene: &Scene, dir: &Path) -> String {
    let scene_path = dir.join("scene.ron");
    keyrig_io::scene_file::save(&scene_path, scene).unwrap_or_else(|e| panic!("{label}: save: {e}"));
    let scene = keyrig_io::scene_file::load(&scene_path).unwrap_or_else(|e| panic!("{label}: load: {e}"));
    let exported =
        export_scene(&scene, &ExportOptions::default()).unwrap_or_else(|e| panic!("{label}: export: {e}"));
    let out = dir.join("out.glb");
    exported.write(&out).expect("write");
    let bytes = std::fs::metadata(&out).expect("metadata").len();
    let (errors, warnings, report) = validate(&out);
    assert_eq!((errors, warnings), (0, 0), "{label}: validator: {report}");

    let (doc, buffers, _) = gltf::import(&out).unwrap_or_else(|e| panic!("{label}: {e}"));
    let reference = read_reference(&doc, &buffers);
    let animation = (!reference.animations.is_empty()).then_some(0);
    let mut worst = 0.0f64;
    let mut vertices = 0;
    let frames: Vec<i32> = (scene.frame_range.start..=scene.frame_range.end).collect();
    for (k, object) in scene.objects.iter().filter(|o| o.mesh.is_some()).enumerate() {
        let node = doc.nodes().find(|n| n.mesh().is_some_and(|m| m.index() == k)).expect("mesh node");
        let exported = mesh_node(&node, &buffers);
        let shown = Shown::of(object);
        let size = size_of(&shown.at(object, f64::from(scene.frame_range.start) / scene.fps));
        vertices += exported.positions.len();
        for &frame in &frames {
            let t = f64::from(frame) / scene.fps;
            let want = shown.at(object, t);
            let got = exported.at(&reference, animation, t, Interpolator::Spec);
            assert_eq!(want.len(), got.len(), "{label}: object `{}`: vertex count", object.name);
            for (v, (w, g)) in want.iter().zip(&got).enumerate() {
                let error = (*w - *g).length() / size;
                assert!(
                    error <= TOLERANCE,
                    "{label}: object `{}`, frame {frame} (t = {t}), vertex {v}: keyrig {w:?}, exported {g:?}: \
                     {error:.2e} of the size {size}",
                    object.name
                );
                worst = worst.max(error);
            }
        }
    }
    format!(
        "{label}: {} objects, {vertices} vertices, {} frames, {bytes} bytes, worst {worst:.2e}",
        scene.objects.iter().filter(|o| o.mesh.is_some()).count(),
        frames.len()
    )
}

#[test]
fn every_corpus_model_exports_as_keyrig_shows_it() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut report = Vec::new();
    for file in GLTF {
        let path = corpus(file).canonicalize().expect("corpus file");
        let model = keyrig_io::gltf_import::import_gltf_file(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
        let animations: Vec<Option<usize>> = if model.animations.is_empty() {
            vec![None]
        } else {
            (0..model.animations.len()).map(Some).collect()
        };
        for animation in animations {
            let scene =
                model.to_scene(&path.to_string_lossy(), animation).unwrap_or_else(|e| panic!("{file}: {e}"));
            report.push(round_trip(&format!("{file} animation {animation:?}"), &scene, dir.path()));
        }
    }
    for file in MD2 {
        let path = corpus(file).canonicalize().expect("corpus file");
        let model = keyrig_io::md2::load_md2_file(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
        let scene = keyrig_io::md2::md2_scene(&model, &path.to_string_lossy(), "md2");
        report.push(round_trip(file, &scene, dir.path()));
    }
    // Shown with --nocapture; docs/interchange.md quotes these figures.
    println!("{}", report.join("\n"));
}
