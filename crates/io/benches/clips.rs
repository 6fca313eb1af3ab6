//! Evaluating the four-model scene with clip tracks and layers (docs/clips.md, issue 39's
//! speed target): `assets/characters.ron` as it is, then with every keyed object's action
//! pushed down and played by three strips on two tracks (one Combine, blending in) under two
//! layers that key three joints of every character, then with nine strips. The scene as it is
//! is the yardstick of the run; the cost should grow linearly with the strips.
//!
//! ```sh
//! cargo bench -p keyrig-io --bench clips -- --warm-up-time 1 --measurement-time 3
//! ```

use std::collections::HashMap;
use std::hint::black_box;
use std::path::Path;
use std::sync::Arc;

use criterion::{criterion_group, criterion_main, Criterion};
use glam::Quat;
use keyrig_core::{
    Action, ActionChannel, ActionKeys, Animated, ClipTrack, Key, Layer, MeshSource, RawTrack, Scene,
    StripBlend,
};
use keyrig_eval::{LoadedMesh, Overrides, SceneEvaluator};

/// Every keyed object's action pushed down, played by `strips` strips (two thirds on a base
/// track continuing its root, a third Combine strips on a second track), and two layers.
fn with_clips(scene: &mut Scene, strips: usize) {
    let keyed: Vec<usize> =
        (0..scene.objects.len()).filter(|&o| !scene.keyed_channels_of(o).is_empty()).collect();
    for &o in &keyed {
        let t = scene.push_down(o).expect("push down");
        let first = scene.objects[o].clip_tracks[t].strips[0].clone();
        let length = first.length();
        let mut base = vec![first.clone()];
        let mut over = Vec::new();
        for k in 1..strips {
            let mut s = first.clone();
            if k % 3 == 2 {
                s.start = first.start + length * (over.len() as f64 + 0.25);
                s.blend = StripBlend::Combine;
                s.blend_in = length * 0.1;
                s.influence = Animated::constant(0.5);
                s.extrapolation = keyrig_core::Extrapolation::Nothing;
                over.push(s);
            } else {
                s.start = base.last().expect("a strip").end();
                s.continue_root = true;
                base.push(s);
            }
        }
        scene.objects[o].clip_tracks[t].strips = base;
        if !over.is_empty() {
            scene.objects[o].clip_tracks.push(ClipTrack {
                name: "Over".into(),
                strips: over,
                ..ClipTrack::default()
            });
        }
    }
    for l in 0..2 {
        let mut channels = Vec::new();
        for object in &scene.objects {
            let Some(skeleton) = &object.skeleton else { continue };
            for joint in skeleton.joints.iter().skip(1).take(3) {
                let keys = RawTrack::new(vec![
                    Key::new(0.0, Quat::IDENTITY),
                    Key::new(1.0, Quat::from_rotation_x(0.2 + 0.1 * l as f32)),
                    Key::new(2.0, Quat::IDENTITY),
                ]);
                channels.push(ActionChannel {
                    path: format!("object/{}/joint/{}/rotation", object.name, joint.name),
                    keys: ActionKeys::Rotation(Animated::new(Quat::IDENTITY, keys)),
                });
            }
        }
        channels.sort_by(|a, b| a.path.cmp(&b.path));
        let name = format!("Layer {l}");
        scene.actions.push(Action { name: name.clone(), channels });
        scene.layers.push(Layer::new(name.clone(), name));
    }
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
}

fn clips(c: &mut Criterion) {
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    let scene = keyrig_io::scene_file::load(&assets.join("characters.ron")).expect("characters");
    let mut meshes = HashMap::new();
    for (o, object) in scene.objects.iter().enumerate() {
        let Some(MeshSource::File { path, mesh, .. }) = &object.mesh else { continue };
        let file = assets.join(path);
        let loaded = if file.extension().is_some_and(|e| e == "md2") {
            let model = keyrig_io::md2::load_md2_file(&file).expect("md2");
            LoadedMesh::Morph(Arc::new(model.playback().expect("clips")))
        } else {
            let model = keyrig_io::gltf_import::import_gltf_file(&file).expect("glTF");
            let node =
                model.nodes.iter().position(|n| n.mesh == *mesh && n.skin.is_some()).expect("skinned node");
            LoadedMesh::Skinned(Arc::new(model.skinned_mesh(node).expect("mesh")))
        };
        meshes.insert(o, loaded);
    }
    let mut group = c.benchmark_group("clips");
    for (name, strips) in
        [("characters", 0), ("characters+3strips+2layers", 3), ("characters+9strips+2layers", 9)]
    {
        let mut scene = scene.clone();
        if strips > 0 {
            with_clips(&mut scene, strips);
        }
        let eval = SceneEvaluator::new(&scene, &meshes);
        assert!(eval.problems().is_empty(), "{:?}", eval.problems());
        let none = Overrides::new();
        let mut state = eval.evaluate(0.0, &none);
        let fps = scene.fps;
        let mut frame = 0u32;
        group.bench_function(format!("{name}/evaluate"), |b| {
            b.iter(|| {
                frame = (frame + 1) % 240;
                eval.evaluate_into(f64::from(frame) / fps, &none, &mut state);
                black_box(state.objects.len())
            });
        });
    }
    group.finish();
}

criterion_group!(benches, clips);
criterion_main!(benches);
