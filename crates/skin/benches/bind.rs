//! Automatic binding (`keyrig_skin::BindJob`, docs/binding.md) of a generated 50 000-vertex
//! mesh on one thread: a closed tube of radius 1 and length 16 (250 rings of 200 vertices) on
//! a straight chain of 4 and of 16 bones, each method. The bar: < 2 s for 50 000
//! vertices on one core. The job runs on the calling thread only (no rayon).
//!
//! cargo bench -p keyrig-skin --bench bind -- --warm-up-time 1 --measurement-time 5

use criterion::{black_box, criterion_group, criterion_main, Criterion};
use glam::{Quat, Vec3};
use keyrig_skin::{tube_mesh, BindJob, BindMethod, RestJoint, RestSkeleton};

const LENGTH: f32 = 16.0;

fn chain(bones: usize) -> RestSkeleton {
    let step = LENGTH / bones as f32;
    let joints: Vec<RestJoint> = (0..bones)
        .map(|j| {
            let t = if j == 0 { Vec3::ZERO } else { Vec3::X * step };
            RestJoint::new(format!("j{j}"), j.checked_sub(1), t, Quat::IDENTITY)
        })
        .collect();
    RestSkeleton::new(&joints).expect("chain")
}

fn bench_bind(c: &mut Criterion) {
    let (positions, indices) = tube_mesh(250, 200, LENGTH, 1.0);
    assert_eq!(positions.len(), 50_000);
    let mut group = c.benchmark_group("bind/50000");
    group.sample_size(10);
    for bones in [4usize, 16] {
        let skeleton = chain(bones);
        for method in BindMethod::ALL {
            group.bench_function(format!("{}/{bones}-bones/1-thread", method.name()), |b| {
                b.iter(|| {
                    BindJob::new(black_box(&positions), &indices, &skeleton, method).run().expect("bind")
                })
            });
        }
    }
    group.finish();
}

criterion_group!(benches, bench_bind);
criterion_main!(benches);
