//! Inverse kinematics solve time (issue 19; figures in docs/benchmarks.md, section "IK solvers").
//!
//! Targets: a two-bone solve ≤ 1 µs, a 10-joint FABRIK solve ≤ 20 µs.
//!
//! Every solve starts from the same pose (the one a drag starts from) and its target is the next
//! of 64 fixed targets, so branches and caches see varied work. Rows:
//! * `two_bone/{reachable,unreachable}`: the demo-like arm (1.0 + 0.8 along X, bent 0.6 rad at
//!   the elbow, under a rotated, moved and scaled parent), targets at 5–95 % of the reach or
//!   beyond it; pole point.
//! * `fabrik/{3,10,32}_joints/{no_pole,pole}`: a chain of equal bones curled 0.15 rad per joint,
//!   targets at 5–95 % of its reach in random directions.
//! * `fabrik/10_joints/near_full_reach`: the degenerate case for FABRIK, targets at 99.9 % of
//!   the reach, where the passes converge slowly and the finish (unbend) closes the gap.
//! * `fabrik/10_joints/drag`: each solve starts from the previous solution and the target
//!   moves 1 mm (of a 1.8 m chain) per solve along a circle, as a drag in the viewport does.

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion};
use glam::{Affine3A, DVec3, Quat, Vec3};
use keyrig_core::ik::{solve_fabrik, solve_two_bone, FabrikSettings, IkChain, IkReport, Pole};

/// xorshift64*: deterministic inputs without a dependency.
struct Rng(u64);

impl Rng {
    fn next_f64(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }

    fn direction(&mut self) -> DVec3 {
        loop {
            let v = DVec3::new(self.next_f64(), self.next_f64(), self.next_f64()) * 2.0 - 1.0;
            let len = v.length();
            if len > 0.1 && len <= 1.0 {
                return v / len;
            }
        }
    }
}

struct Rig {
    world_from_parent: Affine3A,
    translations: Vec<Vec3>,
    rest: Vec<Quat>,
    rotations: Vec<Quat>,
}

impl Rig {
    fn chain(&self) -> IkChain<'_> {
        IkChain {
            world_from_parent: self.world_from_parent,
            translations: &self.translations,
            rest_rotations: &self.rest,
            rotations: &self.rotations,
        }
    }

    fn reach(&self) -> f64 {
        self.translations[1..].iter().map(|t| f64::from(t.length())).sum()
    }

    /// 64 world targets at `lo..hi` of the reach from the root, in random directions.
    fn targets(&self, rng: &mut Rng, lo: f64, hi: f64) -> Vec<Vec3> {
        let world = self.world_from_parent.as_daffine3();
        let root = self.translations[0].as_dvec3();
        (0..64)
            .map(|_| {
                let fraction = lo + (hi - lo) * rng.next_f64();
                let local = root + rng.direction() * fraction * self.reach();
                world.transform_point3(local).as_vec3()
            })
            .collect()
    }
}

fn arm() -> Rig {
    Rig {
        world_from_parent: Affine3A::from_scale_rotation_translation(
            Vec3::splat(1.5),
            Quat::from_rotation_y(0.4),
            Vec3::new(0.2, 1.1, -0.3),
        ),
        translations: vec![Vec3::new(0.1, 0.0, 0.0), Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.8, 0.0, 0.0)],
        rest: vec![Quat::IDENTITY, Quat::from_rotation_x(0.2), Quat::IDENTITY],
        rotations: vec![Quat::from_rotation_z(0.3), Quat::from_rotation_z(-0.6), Quat::IDENTITY],
    }
}

/// `joints` joints, equal bones of 1.8 / (joints − 1), each joint curled 0.15 rad about Z.
fn curled_chain(joints: usize) -> Rig {
    let bone = 1.8 / (joints - 1) as f32;
    Rig {
        world_from_parent: Affine3A::from_rotation_translation(
            Quat::from_rotation_y(0.4),
            Vec3::new(0.2, 1.1, -0.3),
        ),
        translations: std::iter::once(Vec3::ZERO)
            .chain(std::iter::repeat_n(Vec3::new(bone, 0.0, 0.0), joints - 1))
            .collect(),
        rest: vec![Quat::IDENTITY; joints],
        rotations: std::iter::once(Quat::IDENTITY)
            .chain(std::iter::repeat_n(Quat::from_rotation_z(0.15), joints - 1))
            .collect(),
    }
}

/// Checks, outside the timing, that every reachable target of a row is reached.
fn check_reached(name: &str, rig: &Rig, targets: &[Vec3], solve: impl Fn(&IkChain<'_>, Vec3) -> IkReport) {
    for target in targets {
        let report = solve(&rig.chain(), *target);
        assert!(!report.reachable || report.distance < 1e-5 * rig.reach(), "{name}: {target} {report:?}");
    }
}

fn bench_two_bone(c: &mut Criterion) {
    let mut group = c.benchmark_group("ik/two_bone");
    let rig = arm();
    let mut rng = Rng(0x9E37_79B9_7F4A_7C15);
    let pole = Pole::Point(Vec3::new(0.5, 3.0, 1.0));
    for (name, lo, hi) in [("reachable", 0.05, 0.95), ("unreachable", 1.05, 2.0)] {
        let targets = rig.targets(&mut rng, lo, hi);
        check_reached(name, &rig, &targets, |chain, target| {
            solve_two_bone(chain, target, pole, &mut [Quat::IDENTITY; 3]).expect("valid chain")
        });
        group.bench_with_input(BenchmarkId::from_parameter(name), &targets, |b, targets| {
            let chain = rig.chain();
            let mut out = [Quat::IDENTITY; 3];
            let mut k = 0;
            b.iter(|| {
                k = (k + 1) % targets.len();
                let report =
                    solve_two_bone(&chain, black_box(targets[k]), pole, &mut out).expect("valid chain");
                black_box((report, &out));
            });
        });
    }
    group.finish();
}

fn bench_fabrik(c: &mut Criterion) {
    let mut group = c.benchmark_group("ik/fabrik");
    let settings = FabrikSettings::default();
    let mut rng = Rng(0xD1B5_4A32_D192_ED03);
    for joints in [3, 10, 32] {
        let rig = curled_chain(joints);
        let targets = rig.targets(&mut rng, 0.05, 0.95);
        for (name, pole) in [("no_pole", None), ("pole", Some(Pole::Point(Vec3::new(0.9, 3.0, -0.3))))] {
            check_reached(name, &rig, &targets, |chain, target| {
                solve_fabrik(chain, target, pole, &settings, &mut vec![Quat::IDENTITY; joints])
                    .expect("valid chain")
            });
            group.bench_with_input(
                BenchmarkId::new(format!("{joints}_joints"), name),
                &targets,
                |b, targets| {
                    let chain = rig.chain();
                    let mut out = vec![Quat::IDENTITY; joints];
                    let mut k = 0;
                    b.iter(|| {
                        k = (k + 1) % targets.len();
                        let report = solve_fabrik(&chain, black_box(targets[k]), pole, &settings, &mut out)
                            .expect("valid chain");
                        black_box((report, &out));
                    });
                },
            );
        }
    }

    let rig = curled_chain(10);
    let near = rig.targets(&mut rng, 0.999, 0.999);
    check_reached("near_full_reach", &rig, &near, |chain, target| {
        solve_fabrik(chain, target, None, &settings, &mut [Quat::IDENTITY; 10]).expect("valid chain")
    });
    group.bench_with_input(BenchmarkId::new("10_joints", "near_full_reach"), &near, |b, targets| {
        let chain = rig.chain();
        let mut out = vec![Quat::IDENTITY; 10];
        let mut k = 0;
        b.iter(|| {
            k = (k + 1) % targets.len();
            let report =
                solve_fabrik(&chain, black_box(targets[k]), None, &settings, &mut out).expect("valid chain");
            black_box((report, &out));
        });
    });

    // A drag: the target walks a circle of radius 0.5 (1 mm steps), each solve from the last.
    let world = rig.world_from_parent.as_daffine3();
    let path: Vec<Vec3> = (0..3142)
        .map(|k| {
            let angle = k as f64 * 0.002;
            world.transform_point3(DVec3::new(1.2, 0.5 * angle.cos(), 0.5 * angle.sin())).as_vec3()
        })
        .collect();
    let pole = Some(Pole::Point(Vec3::new(0.9, 3.0, -0.3)));
    group.bench_with_input(BenchmarkId::new("10_joints", "drag"), &path, |b, path| {
        let mut rotations = rig.rotations.clone();
        let mut out = vec![Quat::IDENTITY; 10];
        let mut k = 0;
        b.iter(|| {
            k = (k + 1) % path.len();
            let chain = IkChain { rotations: &rotations, ..rig.chain() };
            let report =
                solve_fabrik(&chain, black_box(path[k]), pole, &settings, &mut out).expect("valid chain");
            black_box(report);
            rotations.copy_from_slice(&out);
        });
    });
    group.finish();
}

criterion_group!(benches, bench_two_bone, bench_fabrik);
criterion_main!(benches);
