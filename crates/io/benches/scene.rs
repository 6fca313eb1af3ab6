//! Scene file speed: serializing, saving, parsing and loading a scene with 100 000 keys
//! (issue 2 target: load and save each under 200 ms), and a scene with 100 actions of 1,000
//! keys each (issue 39 target: load and save each under 200 ms).
//!
//! `cargo bench -p keyrig-io --bench scene -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use glam::{Quat, Vec3};
use keyrig_core::{Key, RawTrack, Scene, Tcb};
use keyrig_io::demo::demo_scene;
use keyrig_io::scene_file;

/// The demo scene with its tracks grown to `total` keys: 80 % joint rotations, 10 % object
/// translations, 10 % light intensities, at 120 keys per second. With `varied_tcb` every key
/// has its own T/C/B (the file's worst case: three more numbers per key); without, all keys
/// are plain Catmull–Rom / Squad keys whose T/C/B the file leaves out.
fn scene_with_keys(total: usize, varied_tcb: bool) -> Scene {
    let mut scene = demo_scene();
    let time = |i: usize| i as f64 / 120.0;
    let tcb = |i: usize| {
        if varied_tcb {
            Tcb::new(((i % 7) as f32 - 3.0) / 4.0, ((i % 5) as f32 - 2.0) / 3.0, ((i % 3) as f32 - 1.0) / 2.0)
        } else {
            Tcb::ZERO
        }
    };
    let per_joint = total * 8 / 10 / 4;
    let skeleton = scene.objects[0].skeleton.as_mut().expect("demo arm has a skeleton");
    for (j, joint) in skeleton.joints.iter_mut().enumerate() {
        joint.rotation.track = RawTrack::new(
            (0..per_joint)
                .map(|i| {
                    let angle = (i as f32 * 0.37 + j as f32).sin() * 1.5;
                    Key::new(time(i), Quat::from_axis_angle(Vec3::new(1.0, 0.3, -0.2).normalize(), angle))
                        .with_tcb(tcb(i))
                })
                .collect(),
        );
    }
    let rest = total - 4 * per_joint;
    scene.objects[1].translation.track = RawTrack::new(
        (0..rest / 2)
            .map(|i| {
                let s = i as f32 * 0.01;
                Key::new(time(i), Vec3::new(s.sin(), s.cos() * 0.5, (s * 3.0).sin() * 0.1)).with_tcb(tcb(i))
            })
            .collect(),
    );
    scene.lights[0].intensity.track = RawTrack::new(
        (0..rest - rest / 2).map(|i| Key::new(time(i), 1.0 + (i as f32 * 0.1).sin())).collect(),
    );
    scene.frame_range.end = (time(per_joint) * scene.fps) as i32;
    scene
}

fn key_count(scene: &Scene) -> usize {
    let objects: usize = scene
        .objects
        .iter()
        .map(|o| {
            o.translation.track.len()
                + o.rotation.track.len()
                + o.scale.track.len()
                + o.skeleton.as_ref().map_or(0, |s| {
                    s.root_translation.track.len()
                        + s.joints.iter().map(|j| j.rotation.track.len()).sum::<usize>()
                })
        })
        .sum();
    let lights: usize = scene
        .lights
        .iter()
        .map(|l| {
            l.position.track.len() + l.direction.track.len() + l.colour.track.len() + l.intensity.track.len()
        })
        .sum();
    objects + lights
}

fn bench_variant(c: &mut Criterion, name: &str, varied_tcb: bool) {
    let scene = scene_with_keys(100_000, varied_tcb);
    let keys = key_count(&scene);
    assert!((100_000..100_100).contains(&keys), "{keys} keys");
    assert!(scene.problems().is_empty(), "bench scene must be valid");
    let text = scene_file::to_string(&scene).expect("serialize");
    eprintln!("{name}: {keys} keys, {} bytes of RON", text.len());
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("big.ron");
    scene_file::save(&path, &scene).expect("save");

    let mut group = c.benchmark_group(name);
    group.sample_size(10);
    group.throughput(Throughput::Elements(keys as u64));
    group.bench_function("to_string", |b| {
        b.iter(|| scene_file::to_string(black_box(&scene)).expect("serialize"))
    });
    group.bench_function("save", |b| {
        b.iter(|| scene_file::save(black_box(&path), black_box(&scene)).expect("save"))
    });
    group.bench_function("from_str", |b| {
        b.iter(|| scene_file::from_str(black_box(&text), black_box(&path)).expect("parse"))
    });
    group.bench_function("load", |b| b.iter(|| scene_file::load(black_box(&path)).expect("load")));
    group.bench_function("problems", |b| b.iter(|| black_box(&scene).problems()));
    group.finish();
}

/// The demo with its keys as the action "Wave" and 100 more actions, each storing 250 rotation
/// keys on each of the arm's four joints (1,000 keys per action, 100,000 in all), as a
/// character with many clips is saved (docs/actions.md).
fn scene_with_actions() -> Scene {
    let mut scene = demo_scene();
    scene.name_unnamed_keys("Wave");
    let joints: Vec<String> = scene.objects[0]
        .skeleton
        .as_ref()
        .expect("demo arm has a skeleton")
        .joints
        .iter()
        .map(|j| j.name.clone())
        .collect();
    for a in 0..100 {
        let channels = joints
            .iter()
            .enumerate()
            .map(|(j, name)| keyrig_core::ActionChannel {
                path: format!("object/Arm/joint/{name}/rotation"),
                keys: keyrig_core::ActionKeys::Rotation(keyrig_core::Animated::new(
                    Quat::IDENTITY,
                    RawTrack::new(
                        (0..250)
                            .map(|i| {
                                let angle = (i as f32 * 0.37 + j as f32 + a as f32).sin() * 1.5;
                                Key::new(
                                    i as f64 / 30.0,
                                    Quat::from_axis_angle(Vec3::new(1.0, 0.3, -0.2).normalize(), angle),
                                )
                            })
                            .collect(),
                    ),
                )),
            })
            .collect();
        scene.actions.push(keyrig_core::Action { name: format!("Clip{a:03}"), channels });
    }
    scene
}

fn bench_actions(c: &mut Criterion) {
    let scene = scene_with_actions();
    assert!(scene.problems().is_empty(), "bench scene must be valid: {:?}", &scene.problems()[..1]);
    let keys: usize = scene.actions.iter().flat_map(|a| &a.channels).map(|c| c.keys.len()).sum();
    assert_eq!(keys, 100_000);
    let text = scene_file::to_string(&scene).expect("serialize");
    eprintln!("scene_100_actions: {keys} stored keys, {} bytes of RON", text.len());
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("actions.ron");
    scene_file::save(&path, &scene).expect("save");
    let mut group = c.benchmark_group("scene_100_actions_1000_keys");
    group.sample_size(10);
    group.throughput(Throughput::Elements(keys as u64));
    group.bench_function("save", |b| {
        b.iter(|| scene_file::save(black_box(&path), black_box(&scene)).expect("save"))
    });
    group.bench_function("load", |b| b.iter(|| scene_file::load(black_box(&path)).expect("load")));
    group.finish();
}

fn bench(c: &mut Criterion) {
    bench_variant(c, "scene_100k_keys_default_tcb", false);
    bench_variant(c, "scene_100k_keys_varied_tcb", true);
    bench_actions(c);
}

criterion_group!(benches, bench);
criterion_main!(benches);
