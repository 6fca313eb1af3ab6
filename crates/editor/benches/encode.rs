//! The playblast encoders' time per 1280×720 frame (`keyrig_editor::playblast::encode`):
//! H.264 in MP4 (OpenH264), animated GIF (NeuQuant at speed 30, LZW) and animated PNG
//! (`Compression::Fast`), each fed frames like a render's — a shaded background with a shape
//! that moves between frames, so the video encoder has motion to code. The movies are never
//! finished (a writer dropped unfinished leaves no file), so only encoding is measured.
//!
//! `cargo bench -p keyrig-editor --bench encode -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;

use criterion::{criterion_group, criterion_main, Criterion};
use keyrig_editor::playblast::encode::MovieWriter;
use keyrig_editor::playblast::MovieFormat;
use keyrig_render::image::RgbaImage;

const SIZE: (u32, u32) = (1280, 720);

/// Frame `n`: a vertical grey gradient with a lit box 40 pixels further right each frame.
fn frame(n: u32) -> RgbaImage {
    let (w, h) = SIZE;
    RgbaImage::from_fn(w, h, |x, y| {
        let shade = 40 + (y * 60 / h) as u8;
        let (bx, by) = (200 + 40 * n, 250);
        if x >= bx && x < bx + 220 && y >= by && y < by + 180 {
            let lit = 150 + ((x - bx) * 80 / 220) as u8;
            image_pixel(lit, lit - 20, lit - 40)
        } else {
            image_pixel(shade, shade, shade + 8)
        }
    })
}

fn image_pixel(r: u8, g: u8, b: u8) -> keyrig_render::image::Rgba<u8> {
    keyrig_render::image::Rgba([r, g, b, 255])
}

fn encoders(c: &mut Criterion) {
    let frames: Vec<RgbaImage> = (0..8).map(frame).collect();
    let dir = tempfile::tempdir().expect("temp dir");
    let mut group = c.benchmark_group("playblast encoder, one 1280x720 frame");
    group.sample_size(10);
    for (name, format, file) in [
        ("mp4", MovieFormat::Mp4, "shot.mp4"),
        ("gif", MovieFormat::Gif, "shot.gif"),
        ("apng", MovieFormat::Apng, "shot.png"),
    ] {
        let mut writer =
            MovieWriter::create(format, &dir.path().join(file), SIZE, 1_000_000, 30.0).expect("the writer");
        let mut n = 0i64;
        group.bench_function(name, |b| {
            b.iter(|| {
                writer.write_frame(n, black_box(&frames[(n % 8) as usize])).expect("encodes");
                n += 1;
            });
        });
    }
    group.finish();
}

criterion_group!(benches, encoders);
criterion_main!(benches);
