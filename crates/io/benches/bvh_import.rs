//! BVH import time and memory: a generated take on the CMU 131_01 skeleton (31 joints, 7 End
//! Sites, 96 channels) of one hour at 120 fps (432,000 frames, about 340 MB of text), and the
//! degenerate case of one frame. The file is written into a temporary folder once.
//!
//! Besides criterion's times, the bench prints the memory the imported scene holds against the
//! decoded channel data (one f32 per value), counted by a global allocator: bytes allocated
//! and not freed while the scene lives, and the peak during the import.
//!
//! `cargo bench -p keyrig-io --bench bvh_import`

use std::alloc::{GlobalAlloc, Layout, System};
use std::hint::black_box;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::atomic::{AtomicUsize, Ordering};
use std::time::Instant;

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};

struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let now = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(now, Ordering::Relaxed);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// The hierarchy of the corpus take (everything up to and including `MOTION`).
fn hierarchy() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/bvh/cmu-bvh11/131_01.bvh");
    let text = std::fs::read_to_string(path).expect("the corpus take");
    let end = text.find("MOTION").expect("MOTION") + "MOTION\n".len();
    text[..end].to_owned()
}

/// Writes a take of `frames` frames at 120 fps on the corpus skeleton: every channel a slow
/// sine of its own phase (positions in the skeleton's units, angles within ±90°).
fn write_take(path: &Path, frames: usize) -> usize {
    let hierarchy = hierarchy();
    let channels: usize = hierarchy
        .lines()
        .filter_map(|l| l.trim().strip_prefix("CHANNELS "))
        .map(|l| l.split_whitespace().next().and_then(|n| n.parse::<usize>().ok()).unwrap_or(0))
        .sum();
    let mut out = std::io::BufWriter::new(std::fs::File::create(path).expect("create"));
    write!(out, "{hierarchy}Frames: {frames}\nFrame Time: 0.0083333\n").expect("write");
    let mut row = String::new();
    for f in 0..frames {
        row.clear();
        for c in 0..channels {
            let v = 90.0 * ((f as f64) * 0.01 + c as f64).sin();
            let v = if c < 3 { v / 10.0 } else { v };
            if c > 0 {
                row.push(' ');
            }
            row.push_str(&format!("{v:.4}"));
        }
        row.push('\n');
        out.write_all(row.as_bytes()).expect("write");
    }
    out.flush().expect("flush");
    channels
}

/// CPU seconds this thread has run (user + system): on a machine shared with other builds the
/// wall time of one import overstates what it costs.
fn thread_cpu_seconds() -> f64 {
    // SAFETY: getrusage writes the struct it is given and nothing else.
    let mut usage: libc::rusage = unsafe { std::mem::zeroed() };
    if unsafe { libc::getrusage(libc::RUSAGE_THREAD, &mut usage) } != 0 {
        return f64::NAN;
    }
    let seconds = |t: libc::timeval| t.tv_sec as f64 + t.tv_usec as f64 * 1e-6;
    seconds(usage.ru_utime) + seconds(usage.ru_stime)
}

fn bvh_import(c: &mut Criterion) {
    let dir = std::env::temp_dir().join(format!("keyrig-bench-bvh-{}", std::process::id()));
    std::fs::create_dir_all(&dir).expect("temp dir");
    let mut group = c.benchmark_group("bvh_import");
    group.sample_size(10);
    let cases: [(&str, usize); 2] = [("one_frame", 1), ("one_hour_120fps", 3600 * 120)];
    let mut files: Vec<PathBuf> = Vec::new();
    for (name, frames) in cases {
        let path = dir.join(format!("{name}.bvh"));
        let channels = write_take(&path, frames);
        let bytes = std::fs::metadata(&path).map(|m| m.len()).unwrap_or(0);
        // Memory: what the scene holds after the import, and the peak during it.
        let before = LIVE.load(Ordering::Relaxed);
        PEAK.store(before, Ordering::Relaxed);
        let start = Instant::now();
        let cpu_start = thread_cpu_seconds();
        let file = keyrig_io::bvh::read_bvh_file(&path).expect("read");
        let parsed = start.elapsed();
        let cpu_parsed = thread_cpu_seconds();
        let scene = file.to_scene(name);
        let total = start.elapsed();
        let cpu_total = thread_cpu_seconds();
        drop(file);
        let held = LIVE.load(Ordering::Relaxed) - before;
        let peak = PEAK.load(Ordering::Relaxed) - before;
        let decoded = frames * channels * std::mem::size_of::<f32>();
        let key = std::mem::size_of::<keyrig_core::Key<glam::Vec3>>();
        eprintln!(
            "bvh_import {name}: {frames} frames × {channels} channels, file {:.1} MB; one import: parse {:.2} s \
             ({:.2} s CPU), to_scene {:.2} s ({:.2} s CPU); decoded channel data {:.1} MB; scene holds {:.1} MB ({:.2} × decoded; \
             Key<Vec3> is {key} bytes for 12 bytes of angles); peak during import {:.1} MB ({:.2} × decoded)",
            bytes as f64 / 1e6,
            parsed.as_secs_f64(),
            cpu_parsed - cpu_start,
            (total - parsed).as_secs_f64(),
            cpu_total - cpu_parsed,
            decoded as f64 / 1e6,
            held as f64 / 1e6,
            held as f64 / decoded.max(1) as f64,
            peak as f64 / 1e6,
            peak as f64 / decoded.max(1) as f64,
        );
        drop(scene);
        files.push(path.clone());
        group.throughput(Throughput::Bytes(bytes));
        group.bench_with_input(BenchmarkId::from_parameter(name), &path, |b, path| {
            b.iter(|| black_box(keyrig_io::bvh::import_scene(path).expect("import")));
        });
    }
    group.finish();
    for f in files {
        let _ = std::fs::remove_file(f);
    }
    let _ = std::fs::remove_dir(&dir);
}

criterion_group!(benches, bvh_import);
criterion_main!(benches);
