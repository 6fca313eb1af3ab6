//! Preparing one frame without rasterizing it — scene evaluation (every channel, object and
//! light), joint palettes (F(j) composed once), morph frames and the joint data handed to the
//! GPU in its layout — and an edit of one key followed by the same, as the editor does it:
//! the document edit with its undo snapshot, the evaluator brought in step, the draw rig
//! rebuilt around it (vertex buffers are not sent again: no mesh changed).
//!
//! Scenes: `assets/demo.ron`, `assets/characters.ron` (the demo with CesiumMan, the Fox
//! and an MD2 model) and `assets/cameras.ron` (the twisting arm seen by two aimed scene
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
    for name in ["demo", "characters", "cameras"] {
        let path = assets.join(format!("{name}.ron"));
        let scene = keyrig_io::scene_file::load(&path).expect("scene");
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
                    keyrig_editor::channels::set_key(s, elbow, 1.0, ChannelValue::Rotation(q));
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

criterion_group!(benches, frame_prep);
criterion_main!(benches);
