//! Import time of every corpus FBX file (tests/corpus/fbx): ufbx's parse plus keyrig's mapping
//! into an `ImportedModel` (triangulation, skins, every animation stack baked), from the bytes
//! in memory (`import_fbx_slice`) and from the file (`import_fbx`, reading it and its texture).
//!
//! `cargo bench -p keyrig-io --bench fbx_import -- --warm-up-time 1 --measurement-time 2`
//!
//! The target is under 200 ms a file (docs/benchmarks.md, "FBX import"). The yardstick, timed
//! in the same run: keyrig's glTF import of two corpus models of similar size and content
//! (CesiumMan.glb, a textured skinned character of 491 kB; Fox.glb, 163 kB).

use std::hint::black_box;
use std::path::{Path, PathBuf};

use criterion::{criterion_group, criterion_main, Criterion};
use keyrig_io::fbx::{import_fbx, import_fbx_slice, is_fbx_path};

fn corpus_files() -> Vec<PathBuf> {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/fbx/ufbx");
    let mut files: Vec<PathBuf> = std::fs::read_dir(&dir)
        .expect("tests/corpus/fbx/ufbx")
        .filter_map(|e| e.ok().map(|e| e.path()))
        .filter(|p| is_fbx_path(p))
        .collect();
    files.sort();
    files
}

fn fbx_import(c: &mut Criterion) {
    let mut group = c.benchmark_group("fbx_import");
    for path in corpus_files() {
        let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
        let bytes = std::fs::read(&path).expect("read");
        group.bench_function(format!("slice/{name}"), |b| {
            b.iter(|| import_fbx_slice(black_box(&bytes)).expect("import"));
        });
        group.bench_function(format!("file/{name}"), |b| {
            b.iter(|| import_fbx(black_box(&path)).expect("import"));
        });
    }
    for name in ["CesiumMan/CesiumMan.glb", "Fox/Fox.glb"] {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf").join(name);
        let bytes = std::fs::read(&path).expect("read");
        group.bench_function(format!("yardstick/gltf_slice/{name}"), |b| {
            b.iter(|| keyrig_io::gltf_import::import_gltf_slice(black_box(&bytes)).expect("import"));
        });
    }
    group.finish();
}

criterion_group!(benches, fbx_import);
criterion_main!(benches);
