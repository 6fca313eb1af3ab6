//! A waveform's per-frame work: the `[min, max]` of every screen column a clip covers, read
//! from its summary (`WaveformSummary::columns`, which the editor's dope sheet draws). The
//! cost is the number of columns, not the track's length: a 10-minute track zoomed out, a
//! 10-minute track zoomed in on one second, and a 10-second track, each 1000 columns wide.
//!
//! `cargo bench -p keyrig-core --bench waveform -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use keyrig_core::{SummaryBuilder, WaveformSummary};

/// `seconds` of 48 kHz stereo noise-like samples, summarised.
fn summary(seconds: usize) -> WaveformSummary {
    let mut builder = SummaryBuilder::new(48_000, 2);
    let chunk: Vec<f32> =
        (0..96_000u32).map(|i| (i.wrapping_mul(2_654_435_761) >> 8) as f32 / 8_388_608.0 - 1.0).collect();
    for _ in 0..seconds {
        builder.push_interleaved(&chunk);
    }
    builder.finish()
}

fn waveform(c: &mut Criterion) {
    const COLUMNS: usize = 1000;
    let long = summary(600);
    let short = summary(10);
    let mut group = c.benchmark_group("waveform columns (1000)");
    for (name, sound, from, span) in [
        ("10-minute track, all of it", &long, 0.0, 600.0),
        ("10-minute track, one second", &long, 300.0, 1.0),
        ("10-second track, all of it", &short, 0.0, 10.0),
    ] {
        let step = span / COLUMNS as f64;
        group.bench_function(name, |b| {
            b.iter(|| black_box(sound).columns(black_box(from), step, COLUMNS).flatten().count());
        });
    }
    group.finish();
}

criterion_group!(benches, waveform);
criterion_main!(benches);
