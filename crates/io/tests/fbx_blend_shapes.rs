//! Blend shapes: a hand-written FBX (tests/fixtures/fbx/blend_shape_triangle.fbx: one triangle,
//! one blend channel moving vertex 2 by (0, 0, 1), its weight keyed linearly from 0 % at 0 s to
//! 100 % at 1 s) becomes a morph target and a weights channel of the animation.

use std::path::Path;

use glam::Vec3;
use keyrig_io::fbx::import_fbx_file;
use keyrig_io::model::ChannelTarget;

#[test]
fn blend_channels_become_morph_targets_with_animated_weights() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/fbx/blend_shape_triangle.fbx");
    let model = import_fbx_file(&path).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(model.meshes.len(), 1);
    let prim = &model.meshes[0].primitives[0];
    assert_eq!(prim.positions.len(), 3);
    assert_eq!(prim.morph_targets.len(), 1);
    let offsets = prim.morph_targets[0].positions.as_ref().expect("position offsets");
    // The vertex at (0, 1, 0) moves by (0, 0, 1); the others stay.
    for (p, d) in prim.positions.iter().zip(offsets.iter()) {
        let expected = if p.abs_diff_eq(Vec3::Y, 1e-6) { Vec3::Z } else { Vec3::ZERO };
        assert!(d.abs_diff_eq(expected, 1e-6), "{p} moves by {d}");
    }
    assert_eq!(model.meshes[0].weights, vec![0.0]);
    assert_eq!(model.animations.len(), 1);
    assert_eq!(model.animations[0].name, "Lift");
    let weights = model.animations[0]
        .channels
        .iter()
        .find_map(|c| match &c.target {
            ChannelTarget::Weights(w) => Some(w),
            _ => None,
        })
        .expect("weights channel");
    assert_eq!(weights.targets, 1);
    let node = model.nodes.iter().position(|n| n.mesh.is_some()).expect("mesh node");
    for (t, w) in [(0.0, 0.0), (0.5, 0.5), (1.0, 1.0)] {
        let pose = model.pose_at(Some(0), t);
        assert!((pose.weights[node][0] - w).abs() < 0.02, "t {t}: {:?}", pose.weights[node]);
        let moved = model.deformed_positions(node, Some(0), t).expect("positions").concat();
        let top = moved.iter().find(|p| (p.y - 1.0).abs() < 1e-6).expect("vertex 2");
        assert!((top.z - w).abs() < 0.02, "t {t}: {top}");
    }
    // Through the scene: the object's morph weights channel and keyrig-skin's morphed mesh.
    let scene = model.to_scene("blend.fbx", Some(0)).expect("scene");
    let eval = keyrig_eval::SceneEvaluator::new(&scene, &Default::default());
    let state = eval.object_at(0, 0.5, &keyrig_eval::Overrides::new()).expect("state");
    let mesh = model.rigid_mesh(0).expect("mesh");
    let weights = state.look.morph_weights.clone();
    assert_eq!(weights.len(), 1);
    let (positions, _) = mesh.morphed(&weights).expect("morphed");
    let top = positions.iter().find(|p| (p.y - 1.0).abs() < 1e-6).expect("vertex 2");
    assert!((top.z - 0.5).abs() < 0.02, "{top}");
}

/// Hostile variants of the same file: absurd counts, key times and values get a typed error or
/// a bounded model, never a panic or an allocation the file does not justify.
#[test]
fn hostile_variants_give_errors_or_bounded_models() {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/fbx/blend_shape_triangle.fbx");
    let text = std::fs::read_to_string(&path).expect("fixture");
    let variants = [
        // An array that says it holds a billion values.
        text.replace("Vertices: *9 {", "Vertices: *1000000000 {"),
        // A key a million years away (FBX ticks: 46186158000 a second).
        text.replace("a: 0,46186158000", "a: 0,9000000000000000000"),
        // Non-finite and huge values.
        text.replace("a: 0,0,0,1,0,0,0,1,0", "a: 0,0,0,1e308,0,0,0,inf,0"),
        text.replace("a: 0,100\n", "a: 0,1e300\n"),
        // An index far outside the vertices.
        text.replace("a: 0,1,-3", "a: 0,1,-4000000000"),
        text.replace("Indexes: *1 {\n\t\t\ta: 2", "Indexes: *1 {\n\t\t\ta: 4000000000"),
        // A connection loop: the model its own parent.
        text.replace("C: \"OO\",2000,0", "C: \"OO\",2000,2000"),
    ];
    for (i, variant) in variants.iter().enumerate() {
        assert_ne!(variant, &text, "variant {i} changes the file");
        match keyrig_io::fbx::import_fbx_slice(variant.as_bytes()) {
            Ok(import) => {
                let model = import.model;
                let keys: usize = model
                    .animations
                    .iter()
                    .flat_map(|a| &a.channels)
                    .map(|c| match &c.target {
                        ChannelTarget::Translation(t) | ChannelTarget::Scale(t) => t.keys.len(),
                        ChannelTarget::Rotation(t) => t.keys.len(),
                        ChannelTarget::Weights(w) => w.keys.len(),
                    })
                    .sum();
                assert!(keys <= keyrig_io::fbx::MAX_BAKED_KEYS, "variant {i}");
                for mesh in &model.meshes {
                    for p in mesh.primitives.iter() {
                        assert!(p.indices.iter().all(|&x| (x as usize) < p.positions.len()), "variant {i}");
                    }
                }
                let _ = model.to_scene("hostile.fbx", (!model.animations.is_empty()).then_some(0));
                eprintln!("variant {i}: imported ({} meshes, {keys} keys)", model.meshes.len());
            }
            Err(e) => eprintln!("variant {i}: {e}"),
        }
    }
}
