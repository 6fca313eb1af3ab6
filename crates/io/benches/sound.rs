//! Sound clip decoding: one minute of 48 kHz stereo pink noise in each format keyrig reads,
//! decoded and summarised by `decode_sound_file` (issue 28's target: a 10-minute track under a
//! second, so a minute under 100 ms) in one pass and in parts, one per core (as keyrig
//! decodes), and the summary alone from samples already in memory.
//!
//! The files are made by FFmpeg (`ffmpeg`, which the playblast tests need too) in a temporary
//! folder before the measurements: the bench stops, saying so, without it.
//!
//! `cargo bench -p keyrig-io --bench sound -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;
use std::path::Path;
use std::process::Command;

use criterion::{criterion_group, criterion_main, Criterion, Throughput};
use keyrig_core::SummaryBuilder;
use keyrig_io::sound::{decode_sound_file, decode_sound_file_on_threads};

const SECONDS: u64 = 60;
const RATE: u64 = 48_000;

/// Makes `name` in `dir` from one minute of pink noise with FFmpeg's encoder `args`.
fn make(dir: &Path, name: &str, args: &[&str]) {
    let source = format!("anoisesrc=color=pink:sample_rate={RATE}:duration={SECONDS}:amplitude=0.5");
    let out = Command::new("ffmpeg")
        .args(["-loglevel", "error", "-y", "-f", "lavfi", "-i", &source, "-ac", "2"])
        .args(args)
        .arg(dir.join(name))
        .output()
        .unwrap_or_else(|e| panic!("benches/sound.rs makes its files with ffmpeg (Debian: ffmpeg): {e}"));
    assert!(out.status.success(), "ffmpeg {name}: {}", String::from_utf8_lossy(&out.stderr));
}

fn decoding(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("temp dir");
    let files = [
        ("wav", vec!["-c:a", "pcm_s16le"]),
        ("flac", vec![]),
        ("mp3", vec!["-c:a", "libmp3lame", "-b:a", "192k"]),
        ("ogg", vec!["-c:a", "libvorbis", "-q:a", "4"]),
    ];
    let mut group = c.benchmark_group("decode and summarise one minute, 48 kHz stereo");
    group.sample_size(10);
    group.throughput(Throughput::Elements(SECONDS * RATE));
    for (extension, args) in &files {
        let name = format!("minute.{extension}");
        make(dir.path(), &name, args);
        let path = dir.path().join(&name);
        let decoded = decode_sound_file(&path).expect("decodes");
        let frames = decoded.summary.frames;
        assert!(frames.abs_diff(SECONDS * RATE) < 4096, "{name}: {frames} frames");
        // One pass, as before parts; then the default: one part per core.
        group.bench_function(format!("{extension}, one pass"), |b| {
            b.iter(|| decode_sound_file_on_threads(black_box(&path), None, 1).expect("decodes"))
        });
        group.bench_function(format!("{extension}, {} parts", decoded.parts), |b| {
            b.iter(|| decode_sound_file(black_box(&path)).expect("decodes"))
        });
    }
    group.finish();

    // The summary alone, of one minute already decoded (interleaved f32, as a player holds it).
    let samples: Vec<f32> = (0..SECONDS * RATE * 2).map(|i| ((i / 2) as f32 * 0.001).sin() * 0.5).collect();
    let mut group = c.benchmark_group("summarise one minute, 48 kHz stereo");
    group.sample_size(10);
    group.throughput(Throughput::Elements(SECONDS * RATE));
    group.bench_function("interleaved f32", |b| {
        b.iter(|| {
            let mut builder = SummaryBuilder::new(48_000, 2);
            for chunk in black_box(&samples).chunks(2304) {
                builder.push_interleaved(chunk);
            }
            builder.finish()
        });
    });
    group.finish();
}

criterion_group!(benches, decoding);
criterion_main!(benches);
