//! Preparing one frame without rasterizing it — scene evaluation (every channel, object and
//! light), joint palettes (F(j) composed once), morph frames and the joint data handed to the
//! GPU in its layout — and an edit of one key followed by the same, as the editor does it:
//! the document edit with its undo snapshot, the evaluator brought in step, the draw rig
//! rebuilt around it (vertex buffers are not sent again: no mesh changed).
//!
//! Scenes: `assets/demo.ron`, `assets/characters.ron` (the demo with CesiumMan, the Fox
//! and an MD2 model), `characters+attributes`: the characters scene with keyed attributes on
//! every object and light (visibility, opacity, colour, a keyed deformer; light visibility,
//! range and spot cone), `characters+euler`: every rotation of the characters scene switched
//! to Euler keys, and `assets/cameras.ron` (the twisting arm seen by two aimed scene
//! cameras). docs/benchmarks.md records the figures.
//!
//! Run: `cargo bench -p keyrig-editor --bench frame_prep`

use std::hint::black_box;
use std::path::Path;
use std::sync::Arc;

use criterion::{criterion_group, criterion_main, Criterion};
use keyrig_core::channel_id::{ChannelId, ChannelValue};
use keyrig_eval::{Overrides, SceneEvaluator};
use keyrig_render::{Deform, SceneRig, ViewOptions};

/// The frame's GPU joint data: what `Renderer::render` writes to the palette buffers.
fn gpu_bytes(frame: &keyrig_render::FrameInput) -> usize {
    frame
        .items
        .iter()
        .map(|item| match &item.deform {
            Deform::Skin { joints, .. } => {
                joints.iter().map(|j| std::mem::size_of_val(&black_box(j.to_gpu()))).sum::<usize>()
            }
            _ => 0,
        })
        .sum()
}

fn frame_prep(c: &mut Criterion) {
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    let mut group = c.benchmark_group("frame_prep");
    for name in ["demo", "characters", "characters+attributes", "characters+euler", "cameras"] {
        let file = name.trim_end_matches("+attributes").trim_end_matches("+euler");
        let path = assets.join(format!("{file}.ron"));
        let mut scene = keyrig_io::scene_file::load(&path).expect("scene");
        if name.ends_with("+attributes") {
            with_attributes(&mut scene);
        }
        if name.ends_with("+euler") {
            with_euler_keys(&mut scene);
        }
        let meshes = keyrig_editor::files::render_meshes(&scene, Some(&assets)).expect("meshes");
        let rig = SceneRig::with_loaded(&scene, &meshes.skinned, &meshes.morphs).expect("rig");
        let view = ViewOptions::default();
        let none = Overrides::new();
        let fps = scene.fps;
        let mut frame = 0u32;
        group.bench_function(format!("{name}/evaluate_and_prepare"), |b| {
            b.iter(|| {
                frame = (frame + 1) % 90;
                let state = rig.evaluator().evaluate(f64::from(frame) / fps, &none);
                let input = rig.frame_from_state(&state, &view).expect("frame");
                black_box(gpu_bytes(&input))
            });
        });

        // The editor's path for one key edit: Document::edit (undo snapshot, change check),
        // SceneEvaluator::update, a new rig around the evaluator, then the frame.
        let mut doc = keyrig_editor::document::Document::new(scene.clone(), None);
        let loaded: std::collections::HashMap<usize, keyrig_eval::LoadedMesh> = meshes
            .skinned
            .iter()
            .map(|(&o, m)| (o, keyrig_eval::LoadedMesh::Skinned(Arc::new(m.clone()))))
            .chain(
                meshes
                    .morphs
                    .iter()
                    .map(|(&o, m)| (o, keyrig_eval::LoadedMesh::Morph(Arc::clone(m.playback())))),
            )
            .collect();
        let mut eval = Arc::new(SceneEvaluator::new(doc.scene(), &loaded));
        let morphs = meshes.morphs.iter().map(|(&o, m)| (o, Arc::new(m.clone()))).collect();
        let elbow = ChannelId::JointRotation { object: 0, joint: 1 };
        let mut turn = 0.0f32;
        group.bench_function(format!("{name}/edit_key_then_prepare"), |b| {
            b.iter(|| {
                turn = (turn + 0.01) % 1.0;
                let q = glam::Quat::from_rotation_z(turn);
                doc.edit("bench key", |s| {
                    keyrig_edit::channels::set_key(s, elbow, 1.0, ChannelValue::Rotation(q));
                });
                Arc::make_mut(&mut eval).update(doc.scene(), &loaded);
                let rig = SceneRig::with_evaluator(doc.scene(), Arc::clone(&eval), &morphs);
                let state = eval.evaluate(f64::from(frame) / fps, &none);
                let input = rig.frame_from_state(&state, &view).expect("frame");
                black_box(gpu_bytes(&input))
            });
        });
    }
    group.finish();
}

/// Every object's and joint's rotation switched to Euler keys (XYZ), as the inspector's box
/// does: the evaluator turns three angle tracks into each rotation.
fn with_euler_keys(scene: &mut keyrig_core::Scene) {
    use keyrig_core::channel_id::{set_rotation_keys, ChannelId};
    let xyz = keyrig_core::RotationMode::Euler(keyrig_core::EulerOrder::XYZ);
    for o in 0..scene.objects.len() {
        assert!(set_rotation_keys(scene, ChannelId::ObjectRotation(o), xyz, true).expect("valid keys"));
        let joints = scene.objects[o].skeleton.as_ref().map_or(0, |s| s.joints.len());
        for joint in 0..joints {
            let id = ChannelId::JointRotation { object: o, joint };
            assert!(set_rotation_keys(scene, id, xyz, true).expect("valid keys"));
        }
    }
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
}

/// Keys every attribute a frame evaluates on every object and light.
fn with_attributes(scene: &mut keyrig_core::Scene) {
    use keyrig_core::{Animated, Interpolation, Key, RawTrack};
    let linear = |a: f32, b: f32| {
        Animated::new(a, RawTrack::new(vec![Key::new(0.0, a), Key::new(1.5, b), Key::new(3.0, a)]))
    };
    let step = |values: &[f32]| {
        let keys = values
            .iter()
            .enumerate()
            .map(|(i, &v)| Key::new(i as f64, v).with_interpolation(Interpolation::Step))
            .collect();
        Animated::new(values[0], RawTrack::new(keys))
    };
    for object in &mut scene.objects {
        let a = &mut object.attributes;
        a.visible = step(&[1.0, 1.0, 0.0, 1.0]);
        a.opacity = linear(1.0, 0.3);
        let colour = Animated::new(
            glam::Vec3::ONE,
            RawTrack::new(vec![
                Key::new(0.0, glam::Vec3::ONE),
                Key::new(3.0, glam::Vec3::new(1.0, 0.2, 0.1)),
            ]),
        );
        a.colour = Some(colour);
        if object.skeleton.is_some() {
            a.deformer = Some(step(&[1.0, 2.0, 3.0, 1.0]));
        }
    }
    for light in &mut scene.lights {
        light.attributes.visible = step(&[1.0, 0.0, 1.0]);
        light.attributes.range = Some(linear(10.0, 4.0));
        if let keyrig_core::LightKind::Spot { cutoff_deg, inner_angle_deg, .. } = light.kind {
            light.attributes.cutoff_deg = Some(linear(cutoff_deg, cutoff_deg * 0.5));
            light.attributes.inner_angle_deg = Some(linear(inner_angle_deg, inner_angle_deg * 0.5));
        }
    }
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
}

criterion_group!(benches, frame_prep);
criterion_main!(benches);
