//! Key reduction of a one-hour, 120 fps, 31-joint take (issue 40, 5: target < 10 s; figures in
//! docs/benchmarks.md, section "Curve clean-up").
//!
//! The take is generated here with the shape a BVH import gives (keyrig_io::bvh): 31 joints
//! with Euler keys (degrees, one Linear key per frame, the CMU files' XYZ order) and the root's
//! translation keys, 432 000 frames each, 13.8 million keys. Each joint turns like a walk: a
//! sum of three harmonics of a 1 Hz stride with per-joint amplitudes and phases, a slow drift
//! of the stride's frequency, and ±0.02° of capture jitter (deterministic); the root bobs and
//! walks forward (metres) with ±0.1 mm of jitter. Reduced within 0.5° and 1 mm, as the CMU test.
//!
//! Rows: `reduce/one_hour_31_joints` (the whole take), `reduce/one_minute_31_joints` (the
//! same motion, one minute, to see the scaling), and the yardstick
//! `reduce/reference_sample_every_frame_one_hour`: every channel's track built and sampled at
//! every frame through `Track::sample`, one pass of keyrig's evaluator over the take.

use std::f64::consts::TAU;
use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BatchSize, Criterion};
use glam::{Quat, Vec3};
use keyrig_core::{
    Animated, EulerOrder, Interpolation, Joint, Key, Object, RawTrack, RotationMode, Scene, Skeleton,
};
use keyrig_edit::cleanup::{keyed_channels, reduce_keys, ReduceTolerance};

const FPS: f64 = 120.0;
const JOINTS: usize = 31;

/// xorshift64*: deterministic jitter without a dependency.
struct Rng(u64);

impl Rng {
    fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

/// A generated take of `seconds` seconds (module documentation).
fn take(seconds: usize) -> Scene {
    let frames = seconds * FPS as usize;
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let key = |t: f64, v: Vec3| Key::new(t, v).with_interpolation(Interpolation::Linear);
    let joints: Vec<Joint> = (0..JOINTS)
        .map(|j| {
            let amplitude =
                [5.0 + 40.0 * rng.next_f64(), 2.0 + 10.0 * rng.next_f64(), 2.0 + 15.0 * rng.next_f64()];
            let phase = [rng.next_f64() * TAU, rng.next_f64() * TAU, rng.next_f64() * TAU];
            let keys: Vec<Key<Vec3>> = (0..frames)
                .map(|f| {
                    let t = f as f64 / FPS;
                    // The stride's phase, its frequency drifting between 0.8 and 1.2 Hz.
                    let stride = 2.0 * std::f64::consts::PI * (t + 0.2 / 0.05 * (0.05 * t).sin() / TAU);
                    let mut v = [0.0f32; 3];
                    for axis in 0..3 {
                        let s = stride + phase[axis];
                        let angle =
                            amplitude[axis] * (s.sin() + 0.3 * (2.0 * s).sin() + 0.1 * (3.0 * s).cos());
                        v[axis] = (angle + 0.04 * (rng.next_f64() - 0.5)) as f32;
                    }
                    key(t, Vec3::from(v))
                })
                .collect();
            let mut joint = Joint::new(format!("joint{j}"), j.checked_sub(1), Vec3::Y * 0.1, Quat::IDENTITY);
            joint.rotation_mode = RotationMode::Euler(EulerOrder::XYZ);
            joint.rotation_euler = Some(Animated::new(keys[0].value, RawTrack::new(keys)));
            joint
        })
        .collect();
    let root: Vec<Key<Vec3>> = (0..frames)
        .map(|f| {
            let t = f as f64 / FPS;
            let mut jitter = || 0.0002 * (rng.next_f64() - 0.5);
            let p = [
                1.2 * t + jitter(),
                0.95 + 0.03 * (4.0 * std::f64::consts::PI * t).sin() + jitter(),
                jitter(),
            ];
            key(t, Vec3::new(p[0] as f32, p[1] as f32, p[2] as f32))
        })
        .collect();
    let mut object = Object::new("Take".to_owned());
    let mut skeleton = Skeleton::new(joints);
    skeleton.root_translation = Animated::new(root[0].value, RawTrack::new(root));
    object.skeleton = Some(skeleton);
    Scene { fps: FPS, objects: vec![object], ..Scene::default() }
}

/// Every channel's track built and sampled at every frame of its keys: the sum of the x
/// components (so nothing is optimised away).
fn sample_every_frame(scene: &Scene, channels: &[keyrig_core::channel_id::ChannelId]) -> f64 {
    let mut sum = 0.0;
    for &id in channels {
        if let Some(keyrig_core::channel_id::ChannelRef::Vec3(a)) =
            keyrig_core::channel_id::channel(scene, id)
        {
            let track = keyrig_core::Track::new(&a.track).expect("valid keys");
            let (first, last) = track.domain();
            let frames = ((last - first) * FPS).round() as usize;
            for f in 0..=frames {
                sum += f64::from(track.sample(first + f as f64 / FPS).x);
            }
        }
    }
    sum
}

fn bench(c: &mut Criterion) {
    let mut group = c.benchmark_group("reduce");
    group.sample_size(10);
    for (name, seconds) in [("one_minute_31_joints", 60), ("one_hour_31_joints", 3600)] {
        let scene = take(seconds);
        let channels = keyed_channels(&scene, None);
        let tolerance = ReduceTolerance { angle_deg: 0.5, distance: 0.001, value: 0.001 };
        {
            let mut once = scene.clone();
            let report = reduce_keys(&mut once, &channels, tolerance).expect("valid tolerances");
            eprintln!(
                "{name}: {} channels, {} keys → {} ({:.1} %), {:.3}° and {:.3} mm at most, {} skipped",
                report.channels,
                report.keys_before,
                report.keys_after,
                100.0 * report.keys_after as f64 / report.keys_before as f64,
                report.max_angle_deg,
                report.max_distance * 1000.0,
                report.skipped.len()
            );
        }
        if seconds == 3600 {
            // The yardstick: one pass over the take through keyrig's evaluator (every channel's
            // track built and sampled at every frame), what any use of the take costs.
            group.bench_function("reference_sample_every_frame_one_hour", |b| {
                b.iter(|| black_box(sample_every_frame(&scene, &channels)));
            });
        }
        group.bench_function(name, |b| {
            b.iter_batched(
                || scene.clone(),
                |mut s| black_box(reduce_keys(&mut s, &channels, tolerance).map(|r| r.keys_after)),
                BatchSize::PerIteration,
            );
        });
    }
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
