//! `keyrig render --frames A..B -o shot.gif | shot.png | shot.mp4`: playblasts of the demo scene,
//! decoded by decoders other than the encoders that wrote them — the `gif` and `png` crates'
//! decoders, and FFmpeg's `ffprobe` and `ffmpeg` (Debian's `ffmpeg` package; `cargo xtask test`
//! installs it) — for the frame count, the size, the frame delay or rate, and the pictures.
//!
//! Renders on the adapter wgpu finds (lavapipe without a GPU); no adapter fails these tests.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn keyrig(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_keyrig")).args(args).output().expect("run keyrig")
}

fn demo_scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo.ron")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn utf8(path: &Path) -> &str {
    path.to_str().expect("utf-8 path")
}

/// Renders frames `range` of the demo at `size` into `out`, with extra arguments.
fn render(range: &str, size: &str, out: &Path, extra: &[&str]) {
    let demo = demo_scene();
    let mut args = vec!["render", utf8(&demo), "--frames", range, "--size", size, "-o", utf8(out)];
    args.extend_from_slice(extra);
    let result = keyrig(&args);
    assert!(result.status.success(), "keyrig {args:?} failed: {}", stderr(&result));
}

/// One frame of the demo as a PNG, decoded.
fn still(frame: &str, size: &str, dir: &Path) -> keyrig_render::image::RgbaImage {
    let out = dir.join(format!("still_{frame}.png"));
    let demo = demo_scene();
    let result = keyrig(&["render", utf8(&demo), "--frame", frame, "--size", size, "-o", utf8(&out)]);
    assert!(result.status.success(), "{}", stderr(&result));
    keyrig_render::image::open(&out).expect("a PNG").to_rgba8()
}

/// `ffprobe`'s answer for the first video stream: key=value lines.
fn ffprobe(path: &Path, entries: &str) -> String {
    let out = Command::new("ffprobe")
        .args(["-v", "error", "-count_frames", "-select_streams", "v:0", "-show_entries", entries])
        .args(["-of", "default=noprint_wrappers=1", utf8(path)])
        .output()
        .expect("ffprobe (Debian package ffmpeg; `cargo xtask test` installs it)");
    assert!(out.status.success(), "ffprobe {}: {}", path.display(), stderr(&out));
    String::from_utf8(out.stdout).expect("utf-8")
}

fn field<'a>(probe: &'a str, key: &str) -> &'a str {
    probe
        .lines()
        .find_map(|l| l.strip_prefix(key).and_then(|r| r.strip_prefix('=')))
        .unwrap_or_else(|| panic!("no {key} in {probe}"))
}

/// Mean absolute difference per channel (RGB) of two images of one size.
fn mean_difference(a: &keyrig_render::image::RgbaImage, b: &keyrig_render::image::RgbaImage) -> f64 {
    assert_eq!(a.dimensions(), b.dimensions());
    let sum: u64 = a
        .pixels()
        .zip(b.pixels())
        .map(|(p, q)| (0..3).map(|c| u64::from(p.0[c].abs_diff(q.0[c]))).sum::<u64>())
        .sum();
    sum as f64 / (f64::from(a.width() * a.height()) * 3.0)
}

#[test]
fn a_gif_has_every_frame_at_the_scene_rate() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("shot.gif");
    render("0..9", "96x64", &out, &[]);

    let file = std::fs::File::open(&out).expect("the GIF");
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options.read_info(file).expect("a GIF");
    assert_eq!((decoder.width(), decoder.height()), (96, 64));
    let mut delays = Vec::new();
    let mut first = None;
    while let Some(frame) = decoder.read_next_frame().expect("a frame") {
        delays.push(frame.delay);
        if first.is_none() {
            first = Some(frame.buffer.to_vec());
        }
    }
    assert_eq!(delays.len(), 10, "frames 0..=9");
    // 30 fps in whole hundredths: 3, 4, 3, 3, 4, 3 …, 10 frames in 33 hundredths.
    assert!(delays.iter().all(|&d| d == 3 || d == 4), "{delays:?}");
    assert_eq!(delays.iter().map(|&d| u32::from(d)).sum::<u32>(), 33);
    // The first frame is frame 0 in 256 colours.
    let first = keyrig_render::image::RgbaImage::from_raw(96, 64, first.expect("frame 0")).expect("size");
    let difference = mean_difference(&first, &still("0", "96x64", dir.path()));
    assert!(difference < 4.0, "mean difference {difference} from frame 0");

    let probe = ffprobe(&out, "stream=codec_name,width,height,nb_read_frames");
    assert_eq!(field(&probe, "codec_name"), "gif");
    assert_eq!(field(&probe, "nb_read_frames"), "10");
}

#[test]
fn an_animated_png_holds_every_frame_losslessly() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("shot.png");
    render("4..8", "80x48", &out, &[]);

    let decoder = png::Decoder::new(std::io::BufReader::new(std::fs::File::open(&out).expect("the APNG")));
    let mut reader = decoder.read_info().expect("a PNG");
    let control = reader.info().animation_control().expect("an acTL chunk: animated");
    assert_eq!((control.num_frames, control.num_plays), (5, 0));
    let mut frames = Vec::new();
    let mut buffer = vec![0; reader.output_buffer_size().expect("size")];
    for _ in 0..5 {
        let info = reader.next_frame(&mut buffer).expect("a frame");
        assert_eq!((info.width, info.height), (80, 48));
        let fc = reader.info().frame_control().expect("an fcTL chunk");
        assert_eq!((fc.delay_num, fc.delay_den), (1, 30), "1/30 s a frame");
        frames.push(buffer[..info.buffer_size()].to_vec());
    }
    // Lossless: frame 6 of the movie is the PNG of frame 6, byte for byte.
    assert_eq!(frames[2], still("6", "80x48", dir.path()).into_raw());
    assert_ne!(frames[0], frames[4], "the arm moves");

    let probe = ffprobe(&out, "stream=codec_name,nb_read_frames");
    assert_eq!(field(&probe, "codec_name"), "apng");
    assert_eq!(field(&probe, "nb_read_frames"), "5");
}

#[test]
fn an_mp4_is_h264_at_the_scene_rate_and_shows_the_frames() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("shot.mp4");
    render("0..14", "160x96", &out, &[]);

    let probe = ffprobe(
        &out,
        "stream=codec_name,profile,width,height,r_frame_rate,avg_frame_rate,nb_read_frames,duration",
    );
    assert_eq!(field(&probe, "codec_name"), "h264");
    assert_eq!((field(&probe, "width"), field(&probe, "height")), ("160", "96"));
    assert_eq!(field(&probe, "nb_read_frames"), "15");
    assert_eq!(field(&probe, "avg_frame_rate"), "30/1");
    let duration: f64 = field(&probe, "duration").parse().expect("a duration");
    assert!((duration - 0.5).abs() < 1e-3, "15 frames at 30 fps last 0.5 s, not {duration}");

    // FFmpeg's decoder and colour conversion (from the stream's own colour description) give
    // back frame 7 close to the PNG of frame 7.
    let decoded = dir.path().join("decoded_7.png");
    let result = Command::new("ffmpeg")
        .args(["-v", "error", "-i", utf8(&out), "-vf", "select=eq(n\\,7)", "-frames:v", "1"])
        .args(["-pix_fmt", "rgba", utf8(&decoded)])
        .output()
        .expect("ffmpeg");
    assert!(result.status.success(), "ffmpeg: {}", stderr(&result));
    let decoded = keyrig_render::image::open(&decoded).expect("ffmpeg's PNG").to_rgba8();
    let difference = mean_difference(&decoded, &still("7", "160x96", dir.path()));
    assert!(difference < 6.0, "mean difference {difference} per channel from frame 7");
}

#[test]
fn movies_are_written_whole_and_never_over_an_input() {
    let dir = tempfile::tempdir().expect("tempdir");
    // An existing movie is replaced completely and no temporary file is left.
    let out = dir.path().join("shot.gif");
    std::fs::write(&out, b"an older movie").expect("write");
    render("0..2", "32x32", &out, &[]);
    let names: Vec<_> =
        std::fs::read_dir(dir.path()).expect("dir").map(|e| e.expect("entry").file_name()).collect();
    assert_eq!(names, vec![std::ffi::OsString::from("shot.gif")]);
    assert!(std::fs::read(&out).expect("read").starts_with(b"GIF89a"));

    // The scene itself, through --format, is refused before anything is rendered.
    let scene = dir.path().join("scene.ron");
    std::fs::copy(demo_scene(), &scene).expect("copy");
    let before = std::fs::read(&scene).expect("read");
    let result = keyrig(&["render", utf8(&scene), "--frames", "0..2", "--format", "gif", "-o", utf8(&scene)]);
    assert!(!result.status.success());
    assert!(stderr(&result).contains("refusing to overwrite the input file"), "{}", stderr(&result));
    assert_eq!(std::fs::read(&scene).expect("read"), before);

    let demo = demo_scene();
    let cases: [(&[&str], &str); 5] = [
        (&["--frames", "0..2", "-o", "x.avi"], "unknown movie type"),
        (&["--frames", "0..2", "--size", "33x32", "-o", "x.mp4"], "even width and height"),
        (&["--frames", "0..2", "--format", "webm", "-o", "x.mp4"], "--format `webm`"),
        (&["--frame", "3", "--format", "gif", "-o", "x.gif"], "give --frames"),
        (&["--frames", "0..2", "--motion-blur", "0", "-o", "x.gif"], "motion blur samples 0"),
    ];
    for (extra, expected) in cases {
        let mut args = vec!["render", utf8(&demo)];
        args.extend_from_slice(extra);
        let args: Vec<String> = args
            .into_iter()
            .map(|a| if a.starts_with("x.") { utf8(&dir.path().join(a)).to_owned() } else { a.to_owned() })
            .collect();
        let result = Command::new(env!("CARGO_BIN_EXE_keyrig")).args(&args).output().expect("run keyrig");
        assert!(!result.status.success(), "{args:?} should fail");
        let message = stderr(&result);
        assert!(message.contains(expected), "{args:?}: expected `{expected}` in: {message}");
        assert!(!message.contains("panicked"), "{args:?} panicked: {message}");
    }
}

#[test]
fn numbered_frames_stay_as_they_were_and_take_motion_blur() {
    let dir = tempfile::tempdir().expect("tempdir");
    let pattern = dir.path().join("seq").join("arm_###.png");
    render("20..21", "96x64", &pattern, &["--motion-blur", "8"]);
    let blurred =
        keyrig_render::image::open(dir.path().join("seq/arm_020.png")).expect("frame 20").to_rgba8();
    assert!(dir.path().join("seq/arm_021.png").exists());
    // The demo's arm moves at frame 20: the blurred frame differs from the sharp one, but not
    // by much (the same frame, smeared).
    let sharp = still("20", "96x64", dir.path());
    let difference = mean_difference(&blurred, &sharp);
    assert!(difference > 0.0 && difference < 10.0, "mean difference {difference}");
}

/// The MP4 of a scene with sound clips carries their mix as a second track, which FFmpeg
/// decodes: 16-bit stereo PCM at 48 kHz lasting the movie, silent until the clip's start
/// frame, then the clip's 440 Hz tone (tests/fixtures/sound: half a second at 22,050 Hz,
/// amplitude ⅛ spread over two channels) for its half second at its gain, then silent again.
/// A muted clip is not heard.
#[test]
fn an_mp4_carries_the_scenes_sound_clips_mixed() {
    let dir = tempfile::tempdir().expect("tempdir");
    let fixture =
        |name: &str| Path::new(env!("CARGO_MANIFEST_DIR")).join("../io/tests/fixtures/sound").join(name);
    std::fs::create_dir(dir.path().join("audio")).expect("folder");
    std::fs::copy(fixture("tone.flac"), dir.path().join("audio/line.flac")).expect("copy");
    std::fs::copy(fixture("tone.wav"), dir.path().join("audio/muted.wav")).expect("copy");
    let mut scene = keyrig_io::demo::demo_scene();
    assert_eq!(scene.fps, 30.0);
    // Frame 10 of a render from frame 2: 8 frames, 0.2667 s, into the movie; gain 0.5.
    scene
        .sounds
        .push(keyrig_core::SoundClip { gain: 0.5, ..keyrig_core::SoundClip::new("audio/line.flac", 10.0) });
    scene
        .sounds
        .push(keyrig_core::SoundClip { mute: true, ..keyrig_core::SoundClip::new("audio/muted.wav", 2.0) });
    let scene_path = dir.path().join("shot.ron");
    keyrig_io::save(&scene_path, &scene).expect("save");
    let out = dir.path().join("shot.mp4");
    let result =
        keyrig(&["render", utf8(&scene_path), "--frames", "2..31", "--size", "96x64", "-o", utf8(&out)]);
    assert!(result.status.success(), "{}", stderr(&result));

    let probe = Command::new("ffprobe")
        .args([
            "-v",
            "error",
            "-select_streams",
            "a:0",
            "-show_entries",
            "stream=codec_name,sample_rate,channels,channel_layout,duration",
        ])
        .args(["-of", "default=noprint_wrappers=1", utf8(&out)])
        .output()
        .expect("ffprobe");
    let probe = String::from_utf8_lossy(&probe.stdout).into_owned();
    assert_eq!(field(&probe, "codec_name"), "pcm_s16le", "{probe}");
    assert_eq!((field(&probe, "sample_rate"), field(&probe, "channels")), ("48000", "2"), "{probe}");
    assert_eq!(field(&probe, "channel_layout"), "stereo", "the track says left and right: {probe}");
    let duration: f64 = field(&probe, "duration").parse().expect("seconds");
    assert!((duration - 1.0).abs() < 1e-3, "30 frames at 30 fps: {duration} s");
    // The video is still there.
    assert_eq!(field(&ffprobe(&out, "stream=nb_read_frames"), "nb_read_frames"), "30");

    let pcm = Command::new("ffmpeg")
        .args(["-v", "error", "-i", utf8(&out), "-map", "0:a", "-f", "s16le", "-c:a", "pcm_s16le", "-"])
        .output()
        .expect("ffmpeg");
    assert!(pcm.status.success(), "{}", stderr(&pcm));
    let samples: Vec<f64> =
        pcm.stdout.chunks_exact(2).map(|b| f64::from(i16::from_le_bytes([b[0], b[1]])) / 32767.0).collect();
    assert_eq!(samples.len(), 2 * 48_000, "one second of stereo");
    let left: Vec<f64> = samples.iter().step_by(2).copied().collect();
    let right: Vec<f64> = samples.iter().skip(1).step_by(2).copied().collect();
    assert_eq!(left, right, "the same tone on both channels");
    // Where the tone sounds: from the clip's start frame for half a second.
    let loud: Vec<usize> = (0..left.len()).filter(|&i| left[i].abs() > 0.005).collect();
    let (start, end) = (8.0 / 30.0 * 48_000.0, (8.0 / 30.0 + 0.5) * 48_000.0);
    let (first, last) = (*loud.first().expect("sound") as f64, *loud.last().expect("sound") as f64);
    assert!(
        (first - start).abs() <= 8.0 && (last - end).abs() <= 8.0,
        "the tone at {first}..{last}, not {start}..{end}"
    );
    // Its samples: the tone at half gain, in phase from the clip's start (correlation and
    // level against 0.5 × ⅛ × √½ × sin(2π · 440 · t)).
    let peak = 0.5 * 0.125 * std::f64::consts::FRAC_1_SQRT_2;
    let span = start.ceil() as usize + 100..end.floor() as usize - 100;
    let expect: Vec<f64> = span
        .clone()
        .map(|i| peak * (2.0 * std::f64::consts::PI * 440.0 * (i as f64 - start) / 48_000.0).sin())
        .collect();
    let got = &left[span];
    let dot = |a: &[f64], b: &[f64]| a.iter().zip(b).map(|(x, y)| x * y).sum::<f64>();
    let correlation = dot(got, &expect) / (dot(got, got).sqrt() * dot(&expect, &expect).sqrt());
    assert!(correlation > 0.999, "correlation {correlation}");
    let rms = |a: &[f64]| (dot(a, a) / a.len() as f64).sqrt();
    assert!((rms(got) / rms(&expect) - 1.0).abs() < 0.02, "level {} of {}", rms(got), rms(&expect));
}
