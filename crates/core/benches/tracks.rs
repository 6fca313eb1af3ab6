//! Sampling throughput of keyrig tracks (docs/design.md §10; figures in docs/benchmarks.md).
//!
//! For 4, 100, 10 000 and 100 000 keys (uneven spacing, random T/C/B):
//! * `vec3_tcb`: Vec3 Kochanek–Bartels track;
//! * `quat_squad`: rotation track, Squad with TCB;
//! * `quat_spin`: the same rotation keys, each reached with one extra whole turn
//!   (`Spin::Turns(1)`), so every segment is a spin segment (unwrapped Squad with TCB);
//! * `quat_slerp_track`: the same rotation keys as a Linear (slerp) keyrig track;
//! * `glam_slerp`: the same keys with a plain `partition_point` + glam `Quat::slerp` (f32), the
//!   cost of "plain slerp between the same keys";
//! * `splines_catmull_rom`: the `splines` crate (v5) Catmull-Rom on the same positions, a peer;
//! * `vec3_tcb_repeat`, `quat_squad_repeat`: the `vec3_tcb` and `quat_squad` keys with
//!   `before: Repeat, after: Repeat` (cycles, issue 19), sampled at the same times moved three
//!   periods later, so every sample goes through the cycle (same values as the plain rows).
//!
//! Access patterns, 4096 samples per iteration, all inside `[t_1, t_{n−2})` (where splines'
//! Catmull-Rom is defined):
//! * `sequential`: playback at 4 samples per key, wrapping around to the start (a loop);
//! * `random`: uniformly random times.
//!
//! Every keyrig row samples with `Track::sample` (binary search), as the product does.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::{Quat, Vec3};
use keyrig_core::{Cycle, Cycles, Interpolation, Key, RawTrack, Spin, Tcb, Track};

const SAMPLES: usize = 4096;
const KEY_COUNTS: [usize; 4] = [4, 100, 10_000, 100_000];

/// xorshift64*: deterministic inputs without a dependency.
struct Rng(u64);

impl Rng {
    fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn range(&mut self, lo: f64, hi: f64) -> f64 {
        lo + (hi - lo) * self.next_f64()
    }
}

struct Keys {
    times: Vec<f64>,
    positions: Vec<Vec3>,
    rotations: Vec<Quat>,
    tcbs: Vec<Tcb>,
}

fn make_keys(n: usize) -> Keys {
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15 ^ n as u64);
    let mut t = 0.0;
    let mut times = Vec::with_capacity(n);
    for _ in 0..n {
        times.push(t);
        t += rng.range(0.02, 0.06);
    }
    let mut v = || rng.range(-1.0, 1.0) as f32;
    let positions = (0..n).map(|_| Vec3::new(v(), v(), v())).collect();
    let mut q = Quat::IDENTITY;
    let rotations = (0..n)
        .map(|_| {
            let axis = Vec3::new(v(), v(), v()).try_normalize().unwrap_or(Vec3::X);
            q = (q * Quat::from_axis_angle(axis, v().abs() * 1.2)).normalize();
            q
        })
        .collect();
    let tcbs = (0..n).map(|_| Tcb::new(v() * 0.5, v() * 0.5, v() * 0.5)).collect();
    Keys { times, positions, rotations, tcbs }
}

fn track<T: keyrig_core::TrackValue>(keys: &Keys, values: &[T], mode: Interpolation) -> Track<T> {
    cycled_track(keys, values, mode, Cycles::HOLD)
}

fn cycled_track<T: keyrig_core::TrackValue>(
    keys: &Keys,
    values: &[T],
    mode: Interpolation,
    cycles: Cycles,
) -> Track<T> {
    let raw = (0..values.len())
        .map(|i| Key::new(keys.times[i], values[i]).with_tcb(keys.tcbs[i]).with_interpolation(mode))
        .collect();
    Track::with_cycles(&RawTrack::new(raw), cycles).expect("bench keys are valid")
}

/// The rotation keys with one extra turn on every key whose short way from the previous key
/// defines an axis (all but a few of the random keys).
fn spin_track(keys: &Keys) -> Track<Quat> {
    let raw = (0..keys.rotations.len())
        .map(|i| {
            let key = Key::new(keys.times[i], keys.rotations[i]).with_tcb(keys.tcbs[i]);
            let chord =
                if i > 0 { keys.rotations[i - 1].angle_between(keys.rotations[i]).to_degrees() } else { 0.0 };
            if (1.0..179.0).contains(&chord) {
                key.with_spin(Spin::Turns(1))
            } else {
                key
            }
        })
        .collect();
    Track::new(&RawTrack::new(raw)).expect("bench keys are valid")
}

/// Sample times: sequential playback (4 per key, looping) and uniformly random.
fn sample_times(keys: &Keys) -> (Vec<f64>, Vec<f64>) {
    let n = keys.times.len();
    let (lo, hi) = (keys.times[1], keys.times[n - 2]);
    let step = (hi - lo) / (n - 3).max(1) as f64 / 4.0;
    let sequential = (0..SAMPLES).map(|i| lo + (i as f64 * step) % (hi - lo)).collect();
    let mut rng = Rng(42);
    let random = (0..SAMPLES).map(|_| rng.range(lo, hi)).collect();
    (sequential, random)
}

/// Plain slerp between the keys around `t`: binary search, then glam's f32 `Quat::slerp`.
fn glam_slerp(times: &[f64], rotations: &[Quat], t: f64) -> Quat {
    let i = times.partition_point(|&x| x <= t).clamp(1, times.len() - 1) - 1;
    let u = ((t - times[i]) / (times[i + 1] - times[i])) as f32;
    rotations[i].slerp(rotations[i + 1], u)
}

fn bench_tracks(c: &mut Criterion) {
    for &n in &KEY_COUNTS {
        let keys = make_keys(n);
        let (sequential, random) = sample_times(&keys);
        let vec3_tcb = track(&keys, &keys.positions, Interpolation::Tcb);
        let quat_squad = track(&keys, &keys.rotations, Interpolation::Tcb);
        let quat_slerp = track(&keys, &keys.rotations, Interpolation::Linear);
        let quat_spin = spin_track(&keys);
        let repeat = Cycles::new(Cycle::Repeat, Cycle::Repeat);
        let vec3_repeat = cycled_track(&keys, &keys.positions, Interpolation::Tcb, repeat);
        let quat_repeat = cycled_track(&keys, &keys.rotations, Interpolation::Tcb, repeat);
        let (t0, tn) = vec3_repeat.domain();
        let later = 3.0 * (tn - t0);
        // glam's slerp takes the short way itself; give it the sign-consistent keys keyrig uses.
        let consistent: Vec<Quat> = quat_slerp.key_values().to_vec();
        let spline = splines::Spline::from_vec(
            (0..n)
                .map(|i| {
                    let p = keys.positions[i];
                    splines::Key::new(
                        keys.times[i] as f32,
                        glam030::Vec3::new(p.x, p.y, p.z),
                        splines::Interpolation::CatmullRom,
                    )
                })
                .collect(),
        );

        let mut group = c.benchmark_group(format!("tracks/{n}_keys"));
        group.throughput(Throughput::Elements(SAMPLES as u64));
        for (pattern, times) in [("sequential", &sequential), ("random", &random)] {
            group.bench_with_input(BenchmarkId::new("vec3_tcb", pattern), times, |b, times| {
                b.iter(|| {
                    let mut acc = Vec3::ZERO;
                    times.iter().for_each(|&t| acc += vec3_tcb.sample(black_box(t)));
                    acc
                })
            });
            let repeated: Vec<f64> = times.iter().map(|t| t + later).collect();
            group.bench_with_input(BenchmarkId::new("vec3_tcb_repeat", pattern), &repeated, |b, times| {
                b.iter(|| {
                    let mut acc = Vec3::ZERO;
                    times.iter().for_each(|&t| acc += vec3_repeat.sample(black_box(t)));
                    acc
                })
            });
            group.bench_with_input(BenchmarkId::new("quat_squad_repeat", pattern), &repeated, |b, times| {
                b.iter(|| {
                    let mut acc = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
                    times.iter().for_each(|&t| acc += quat_repeat.sample(black_box(t)));
                    acc
                })
            });
            group.bench_with_input(BenchmarkId::new("quat_squad", pattern), times, |b, times| {
                b.iter(|| {
                    let mut acc = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
                    times.iter().for_each(|&t| acc += quat_squad.sample(black_box(t)));
                    acc
                })
            });
            group.bench_with_input(BenchmarkId::new("quat_spin", pattern), times, |b, times| {
                b.iter(|| {
                    let mut acc = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
                    times.iter().for_each(|&t| acc += quat_spin.sample(black_box(t)));
                    acc
                })
            });
            group.bench_with_input(BenchmarkId::new("quat_slerp_track", pattern), times, |b, times| {
                b.iter(|| {
                    let mut acc = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
                    times.iter().for_each(|&t| acc += quat_slerp.sample(black_box(t)));
                    acc
                })
            });
            group.bench_with_input(BenchmarkId::new("glam_slerp", pattern), times, |b, times| {
                b.iter(|| {
                    let mut acc = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
                    let times_in = quat_slerp.key_times();
                    times.iter().for_each(|&t| acc += glam_slerp(times_in, &consistent, black_box(t)));
                    acc
                })
            });
            group.bench_with_input(BenchmarkId::new("splines_catmull_rom", pattern), times, |b, times| {
                b.iter(|| {
                    let mut acc = glam030::Vec3::ZERO;
                    times.iter().for_each(|&t| acc += spline.sample(black_box(t as f32)).unwrap_or_default());
                    acc
                })
            });
        }
        group.finish();
    }
}

fn bench_build(c: &mut Criterion) {
    // Validation cost (tangents, Squad controls), paid once per edit, not per frame.
    let mut group = c.benchmark_group("tracks/build");
    for &n in &[100usize, 100_000] {
        let keys = make_keys(n);
        let vec3_raw = RawTrack::new((0..n).map(|i| Key::new(keys.times[i], keys.positions[i])).collect());
        let quat_raw = RawTrack::new((0..n).map(|i| Key::new(keys.times[i], keys.rotations[i])).collect());
        group.throughput(Throughput::Elements(n as u64));
        group.bench_with_input(BenchmarkId::new("vec3_tcb", n), &vec3_raw, |b, raw| {
            b.iter(|| Track::new(raw))
        });
        group.bench_with_input(BenchmarkId::new("quat_squad", n), &quat_raw, |b, raw| {
            b.iter(|| Track::new(raw))
        });
    }
    group.finish();
}

criterion_group!(benches, bench_tracks, bench_build);
criterion_main!(benches);
