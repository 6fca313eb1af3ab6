//! VRML97 import time against file size: generated .wrl files (`tests/support/big_vrml.rs`)
//! of about 7, 37 and 74 MB — thousands of shapes with crease-angle meshes and animated
//! Transforms — read, expanded, tessellated and mapped onto keyrig objects and tracks
//! (`keyrig_io::vrml::import_vrml_slice`), and the degenerate case of one block. Linear
//! import keeps the throughput (bytes per second) flat across the sizes; the target is a
//! 50 MB file in under 5 s.
//!
//! `cargo bench -p keyrig-io --bench vrml_import -- --warm-up-time 1 --measurement-time 3`

#[path = "../tests/support/big_vrml.rs"]
mod big_vrml;

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};

fn vrml_import(c: &mut Criterion) {
    let mut group = c.benchmark_group("vrml_import");
    group.sample_size(10);
    for blocks in [1usize, 950, 4_750, 9_500] {
        let text = big_vrml::wrl(blocks);
        group.throughput(Throughput::Bytes(text.len() as u64));
        let mb = text.len() as f64 / 1e6;
        group.bench_with_input(
            BenchmarkId::new("wrl_mb", format!("{mb:.1}")),
            text.as_bytes(),
            |b, bytes| {
                b.iter(|| black_box(keyrig_io::vrml::import_vrml_slice(bytes, "big.wrl").expect("import")));
            },
        );
    }
    group.finish();
}

criterion_group!(benches, vrml_import);
criterion_main!(benches);
