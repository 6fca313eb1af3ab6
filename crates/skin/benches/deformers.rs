//! Each deformer on 1 000, 100 000 and 1 000 000 vertices with 4 influences (positions and
//! normals), single-threaded and on all cores, beside the memory-bandwidth bound measured in
//! the same run (the real peer, ozz-animation's C++ `SkinningJob`, is timed by
//! `tools/ozz-driver`, interleaved with `examples/deformer_timing.rs`: docs/skinning-vs-ozz.md):
//!
//! - `memcpy`: a plain copy moving as many bytes (read + write) as linear blend does — the
//!   memory-bandwidth bound.
//!
//! Throughput is reported as bytes moved per second: read (positions 12 B, normals 12 B,
//! joints 8 B, weights 16 B; rigid: 2 B joint; bones blending: 8 B binding) plus written
//! (positions and normals, 24 B) per vertex.
//!
//! cargo bench -p keyrig-skin --bench deformers -- --warm-up-time 1 --measurement-time 2

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::Vec3;
use keyrig_skin::{BonesBlendJob, DualQuatJob, Execution, LinearBlendJob, RigidJob};

// The data in ozz's layout is for the example that feeds the C++ driver.
#[allow(dead_code)]
mod support;

use support::data;

fn bench_deformers(c: &mut Criterion) {
    for n in [1_000usize, 100_000, 1_000_000] {
        let d = data(n);
        let mut out_p = vec![Vec3::ZERO; n];
        let mut out_n = vec![Vec3::ZERO; n];
        let mut group = c.benchmark_group(format!("skin/{n}"));
        if n >= 1_000_000 {
            group.sample_size(10);
        }
        let written = 24 * n as u64;
        let lbs_bytes = 48 * n as u64 + written;

        // The bandwidth bound: copy half of LBS's traffic (read it, write it).
        let src = vec![0u8; lbs_bytes as usize / 2];
        let mut dst = vec![0u8; lbs_bytes as usize / 2];
        group.throughput(Throughput::Bytes(lbs_bytes));
        group.bench_function("memcpy", |b| {
            b.iter(|| {
                dst.copy_from_slice(black_box(&src));
                black_box(&mut dst);
            })
        });

        // Checking the 4 joints and weights of every vertex: once, when the influences are
        // built (`Influences::new`), not in every run.
        group.throughput(Throughput::Bytes(24 * n as u64));
        group.bench_function("build_influences/1-thread", |b| {
            b.iter(|| {
                keyrig_skin::Influences::new(black_box(d.joints.clone()), d.weights.clone(), support::JOINTS)
                    .unwrap()
            })
        });
        // The same for bones-blending bindings (`BonesBlendBindings::new`).
        group.throughput(Throughput::Bytes(8 * n as u64));
        let bindings = d.bindings.to_vec();
        group.bench_function("build_bones_blending/1-thread", |b| {
            b.iter(|| {
                keyrig_skin::BonesBlendBindings::new(black_box(bindings.clone()), d.skeleton.parents())
                    .unwrap()
            })
        });
        for (label, execution) in
            [("1-thread", Execution::SingleThreaded), ("all-cores", Execution::Parallel)]
        {
            group.throughput(Throughput::Bytes(26 * n as u64 + written));
            group.bench_function(BenchmarkId::new("rigid", label), |b| {
                b.iter(|| {
                    RigidJob {
                        palette: &d.palette,
                        joints: &d.bones,
                        positions: &d.positions,
                        normals: &d.normals,
                        out_positions: &mut out_p,
                        out_normals: &mut out_n,
                    }
                    .run_with(execution)
                    .unwrap()
                })
            });
            group.throughput(Throughput::Bytes(lbs_bytes));
            group.bench_function(BenchmarkId::new("linear", label), |b| {
                b.iter(|| {
                    LinearBlendJob {
                        palette: &d.palette,
                        influences: &d.influences,
                        positions: &d.positions,
                        normals: &d.normals,
                        out_positions: &mut out_p,
                        out_normals: &mut out_n,
                    }
                    .run_with(execution)
                    .unwrap()
                })
            });
            group.throughput(Throughput::Bytes(32 * n as u64 + written));
            group.bench_function(BenchmarkId::new("bones_blending", label), |b| {
                b.iter(|| {
                    BonesBlendJob {
                        palette: &d.palette,
                        parents: d.skeleton.parents(),
                        bindings: &d.bindings,
                        positions: &d.positions,
                        normals: &d.normals,
                        out_positions: &mut out_p,
                        out_normals: &mut out_n,
                    }
                    .run_with(execution)
                    .unwrap()
                })
            });
            group.throughput(Throughput::Bytes(lbs_bytes));
            group.bench_function(BenchmarkId::new("dual_quaternion", label), |b| {
                b.iter(|| {
                    DualQuatJob {
                        dual_quaternions: &d.dual_quaternions,
                        influences: &d.influences,
                        positions: &d.positions,
                        normals: &d.normals,
                        out_positions: &mut out_p,
                        out_normals: &mut out_n,
                    }
                    .run_with(execution)
                    .unwrap()
                })
            });
        }
        group.finish();
    }
}

criterion_group!(benches, bench_deformers);
criterion_main!(benches);
