//! Import time against node count: generated .glb files with a wide and a deep skeleton of
//! N joints (an animation channel on every joint) and with N skinned mesh nodes, for N from
//! 1,000 to 100,000 (the degenerate case: N = 3, the smallest skeleton the generator makes).
//! Linear import keeps time / N flat across the sizes.
//!
//! `import_to_scene` adds the mapping onto a scene (what `keyrig import` and the editor do with
//! a model) for 100,000 skinned mesh nodes and for 100,000 meshes that reuse one accessor.
//!
//! `cargo bench -p keyrig-io --bench import_scale -- --warm-up-time 1 --measurement-time 3`

#[path = "../tests/support/big_gltf.rs"]
mod big_gltf;

use std::hint::black_box;

use big_gltf::Shape;
use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use keyrig_io::gltf_import::import_gltf_slice;

fn import_scale(c: &mut Criterion) {
    let mut group = c.benchmark_group("import_nodes");
    group.sample_size(10);
    for n in [3usize, 1_000, 10_000, 100_000] {
        group.throughput(Throughput::Elements(n as u64));
        for (name, bytes) in [
            ("wide_skeleton", big_gltf::skeleton(n, Shape::Wide)),
            ("deep_skeleton", big_gltf::skeleton(n, Shape::Deep)),
            ("skinned_nodes", big_gltf::many_skinned_nodes(n)),
        ] {
            group.bench_with_input(BenchmarkId::new(name, n), &bytes, |b, bytes| {
                b.iter(|| black_box(import_gltf_slice(bytes).expect("import")));
            });
        }
    }
    group.finish();
    let mut group = c.benchmark_group("import_to_scene");
    group.sample_size(10);
    for (name, bytes) in [
        ("skinned_nodes_100000", big_gltf::many_skinned_nodes(100_000)),
        ("reused_accessor_meshes_100000", big_gltf::reused_accessor_meshes(100_000)),
    ] {
        group.bench_with_input(BenchmarkId::from_parameter(name), &bytes, |b, bytes| {
            b.iter(|| {
                let model = import_gltf_slice(bytes).expect("import");
                black_box(model.to_scene("big.glb", None).expect("scene"))
            });
        });
    }
    group.finish();
}

criterion_group!(benches, import_scale);
criterion_main!(benches);
