//! Import time of every corpus model (glTF and MD2), export time of the demo scene, and the
//! peak memory of each import compared with the file size.
//!
//! `cargo bench -p keyrig-io --bench import -- --warm-up-time 1 --measurement-time 2`
//!
//! Peak memory is measured once per model, before the timings, with a counting global
//! allocator (the bytes allocated at once during the import, above what was allocated
//! before it), and printed as a table. The counting costs a few nanoseconds per
//! allocation, included in the timings.

#[path = "../tests/support/big_gltf.rs"]
mod big_gltf;

use std::alloc::{GlobalAlloc, Layout, System};
use std::hint::black_box;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicIsize, Ordering};

use criterion::{criterion_group, criterion_main, Criterion};
use keyrig_io::gltf_export::{export_md2, export_scene, ExportOptions, Md2ExportOptions};
use keyrig_io::gltf_import::{import_gltf_file, import_gltf_slice};
use keyrig_io::md2::{load_md2_file, parse_md2};

struct Counting;

static CURRENT: AtomicIsize = AtomicIsize::new(0);
static PEAK: AtomicIsize = AtomicIsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let now = CURRENT.fetch_add(layout.size() as isize, Ordering::Relaxed) + layout.size() as isize;
        PEAK.fetch_max(now, Ordering::Relaxed);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        CURRENT.fetch_sub(layout.size() as isize, Ordering::Relaxed);
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        let delta = new_size as isize - layout.size() as isize;
        let now = CURRENT.fetch_add(delta, Ordering::Relaxed) + delta;
        PEAK.fetch_max(now, Ordering::Relaxed);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

#[global_allocator]
static ALLOC: Counting = Counting;

fn peak_of(f: impl FnOnce()) -> usize {
    let start = CURRENT.load(Ordering::Relaxed);
    PEAK.store(start, Ordering::Relaxed);
    f();
    (PEAK.load(Ordering::Relaxed) - start).max(0) as usize
}

fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus").join(rel)
}

const GLTF: [&str; 9] = [
    "gltf/RiggedSimple/RiggedSimple.glb",
    "gltf/RiggedSimple/glTF/RiggedSimple.gltf",
    "gltf/RiggedFigure/RiggedFigure.glb",
    "gltf/CesiumMan/CesiumMan.glb",
    "gltf/SimpleSkin/glTF/SimpleSkin.gltf",
    "gltf/SimpleSkin/glTF-Embedded/SimpleSkin.gltf",
    "gltf/Fox/Fox.glb",
    "gltf/InterpolationTest/InterpolationTest.glb",
    "gltf/AnimatedMorphCube/AnimatedMorphCube.glb",
];

const MD2: [&str; 5] = [
    "md2/ratamahatta/ratamahatta.md2",
    "md2/ratamahatta/weapon.md2",
    "md2/sydney/sydney.md2",
    "md2/faerie/faerie.md2",
    "md2/dolphin/dolphin.md2",
];

/// glTF files with external buffers are imported from their path (their buffers are files).
fn has_external_buffers(rel: &str) -> bool {
    rel.ends_with(".gltf") && !rel.contains("Embedded")
}

fn memory_table() {
    println!("\npeak memory of one import (bytes allocated at once) vs. file bytes read:");
    println!("| file | bytes read | peak bytes | peak / bytes |");
    println!("|---|---:|---:|---:|");
    for rel in GLTF {
        let path = corpus(rel);
        let (read, peak) = if has_external_buffers(rel) {
            let dir = path.parent().expect("dir");
            let total: u64 = std::fs::read_dir(dir)
                .expect("dir")
                .filter_map(|e| e.ok())
                .filter(|e| e.path().extension().is_some_and(|x| x == "bin" || x == "gltf"))
                .map(|e| e.metadata().map_or(0, |m| m.len()))
                .sum();
            (total as usize, peak_of(|| drop(black_box(import_gltf_file(&path).expect("import")))))
        } else {
            let data = std::fs::read(&path).expect("read");
            (data.len(), peak_of(|| drop(black_box(import_gltf_slice(&data).expect("import")))))
        };
        println!("| {rel} | {read} | {peak} | {:.2} |", peak as f64 / read as f64);
    }
    for rel in MD2 {
        let data = std::fs::read(corpus(rel)).expect("read");
        let peak = peak_of(|| drop(black_box(parse_md2(&data).expect("parse"))));
        println!("| {rel} (parse) | {} | {peak} | {:.2} |", data.len(), peak as f64 / data.len() as f64);
    }
    // Issue 29's case: 100,000 meshes and nodes reusing one accessor (almost all JSON).
    let data = big_gltf::reused_accessor_meshes(100_000);
    let peak = peak_of(|| drop(black_box(import_gltf_slice(&data).expect("import"))));
    let name = "generated: 100,000 meshes reusing one accessor";
    println!("| {name} | {} | {peak} | {:.2} |", data.len(), peak as f64 / data.len() as f64);
    println!();
}

fn bench(c: &mut Criterion) {
    memory_table();
    let mut group = c.benchmark_group("import");
    for rel in GLTF {
        let path = corpus(rel);
        if has_external_buffers(rel) {
            group.bench_function(rel, |b| b.iter(|| import_gltf_file(black_box(&path)).expect("import")));
        } else {
            let data = std::fs::read(&path).expect("read");
            group.bench_function(rel, |b| b.iter(|| import_gltf_slice(black_box(&data)).expect("import")));
        }
    }
    for rel in MD2 {
        let data = std::fs::read(corpus(rel)).expect("read");
        group.bench_function(format!("{rel} (parse)"), |b| {
            b.iter(|| parse_md2(black_box(&data)).expect("parse"))
        });
        let path = corpus(rel);
        group.bench_function(format!("{rel} (file + skin)"), |b| {
            b.iter(|| load_md2_file(black_box(&path)).expect("load"))
        });
    }
    group.finish();

    let mut group = c.benchmark_group("export");
    let scene = keyrig_io::demo::demo_scene();
    group.bench_function("demo scene to .glb", |b| {
        b.iter(|| export_scene(black_box(&scene), &ExportOptions::default()).expect("export").to_glb())
    });
    let rat = load_md2_file(&corpus("md2/ratamahatta/ratamahatta.md2")).expect("md2");
    group.bench_function("ratamahatta.md2 to .glb", |b| {
        b.iter(|| export_md2(black_box(&rat), Md2ExportOptions::default()).expect("export").to_glb())
    });
    group.finish();
}

criterion_group!(benches, bench);
criterion_main!(benches);
