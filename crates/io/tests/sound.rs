//! Sound clips' files: WAV, FLAC, Ogg Vorbis and MP3 (made by FFmpeg from one known sine,
//! tests/fixtures/sound/README.md) decode into summaries with the signal's rate, channels,
//! length and peak; hostile files are refused with the path and the reason.

use std::path::{Path, PathBuf};

use keyrig_io::sound::{decode_sound_file, SoundError};

fn fixture(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/sound").join(name)
}

/// FFmpeg's `sine` source (amplitude 1/8) spread from mono over two channels at −3 dB (`-ac 2`:
/// each channel gets the centre × √½).
const PEAK: f32 = 0.125 * std::f32::consts::FRAC_1_SQRT_2;
const RATE: u32 = 22_050;
/// Half a second.
const FRAMES: u64 = 11_025;

#[test]
fn every_format_decodes_to_the_signal_it_holds() {
    // (file, codec, frames tolerance, peak tolerance): lossy codecs pad the ends (MP3's
    // encoder delay and last frame: up to 2 × 1152 + 529 samples; Vorbis's last block, which
    // Symphonia 0.5 does not trim to the stream's end granule: up to 1024) and move the peak
    // a little.
    for (name, codec, frames_slack, peak_slack) in [
        ("tone.wav", "pcm_s16le", 0, 1e-3),
        ("tone.flac", "flac", 0, 1e-3),
        ("tone.ogg", "vorbis", 1024, 0.02),
        ("tone.mp3", "mp3", 2 * 1152 + 529, 0.02),
    ] {
        let sound = decode_sound_file(&fixture(name)).unwrap_or_else(|e| panic!("{name}: {e}"));
        let summary = &sound.summary;
        assert_eq!(sound.codec, codec, "{name}");
        assert_eq!((summary.sample_rate, summary.channels), (RATE, 2), "{name}");
        assert!(summary.frames.abs_diff(FRAMES) <= frames_slack, "{name}: {} frames", summary.frames);
        assert_eq!(sound.skipped_packets, 0, "{name}");
        let [lo, hi] = summary.range(0.0, 1.0).expect("the whole sound");
        assert!((hi - PEAK).abs() <= peak_slack && (lo + PEAK).abs() <= peak_slack, "{name}: {lo}..{hi}");
        // A stretch in the middle: a 440 Hz sine swings fully in every 10 ms.
        let [lo, hi] = summary.range(0.2, 0.21).expect("the middle");
        assert!(hi > PEAK * 0.9 && lo < -PEAK * 0.9, "{name} 0.2..0.21 s: {lo}..{hi}");
        assert_eq!(summary.range(0.6, 0.7), None, "{name}: past the end");
    }
}

#[test]
fn hostile_files_are_refused_with_the_path_and_the_reason() {
    let dir = tempfile::tempdir().expect("tempdir");
    let garbage = dir.path().join("noise.wav");
    std::fs::write(&garbage, b"RIFF\x10\0\0\0WAVEjunkjunkjunk").expect("write");
    let truncated = dir.path().join("cut.flac");
    let flac = std::fs::read(fixture("tone.flac")).expect("read");
    std::fs::write(&truncated, &flac[..60]).expect("write");
    let text = dir.path().join("notes.mp3");
    std::fs::write(&text, "not a sound at all").expect("write");
    for path in [garbage, truncated, text, dir.path().to_path_buf()] {
        let err = decode_sound_file(&path).expect_err("refused");
        let message = err.to_string();
        assert!(message.contains(&*path.to_string_lossy()), "{message}");
    }
    #[cfg(unix)]
    {
        let err = decode_sound_file(Path::new("/dev/zero")).expect_err("a device");
        assert!(
            matches!(err, SoundError::Read { .. }) && err.to_string().contains("character device"),
            "{err}"
        );
    }
}

/// A WAV whose `fmt ` chunk says 0 samples a second (the `sound` fuzz target's first crash,
/// minimised from its input): Symphonia's WAV reader panics on it (`TimeBase cannot have 0
/// numerator or denominator`); keyrig checks the rate first and answers with the file's format
/// error (a panic inside Symphonia would be caught and reported the same way).
#[test]
fn a_wav_with_a_zero_sample_rate_is_refused_not_a_panic() {
    let bytes: Vec<u8> = vec![
        82, 73, 70, 70, 138, 172, 0, 0, 87, 65, 86, 69, 102, 109, 116, 32, 16, 0, 0, 0, 1, 0, 2, 0, 0, 0, 0,
        0, 0, 0, 0, 20, 4, 0, 16, 0, 76, 73, 83, 84, 26, 0, 0, 0, 73, 78, 70, 76, 97, 118, 99, 54, 48, 46,
        19, 55, 0, 0, 133,
    ];
    let name = Path::new("zero-rate.wav");
    let err = keyrig_io::sound::decode_sound_bytes(bytes.clone(), name).expect_err("refused");
    assert!(matches!(err, SoundError::Format { .. }), "{err}");
    assert!(
        err.to_string().contains("zero-rate.wav") && err.to_string().contains("sample rate of 0"),
        "{err}"
    );
    // The same from a file on disk.
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("zero-rate.wav");
    std::fs::write(&path, &bytes).expect("write");
    let err = decode_sound_file(&path).expect_err("refused");
    assert!(err.to_string().contains(&*path.to_string_lossy()), "{err}");
}

/// The fuzz target's second input of this kind: the RIFF/WAVE header 14 bytes into the file,
/// after junk, where Symphonia's probe still finds it (150 bytes).
#[test]
fn a_zero_rate_wav_header_after_junk_is_refused_too() {
    let bytes: Vec<u8> = vec![
        82, 73, 70, 0, 0, 0, 138, 255, 172, 2, 70, 97, 53, 199, 82, 73, 70, 70, 138, 172, 0, 0, 87, 65, 86,
        69, 102, 109, 116, 32, 16, 0, 0, 0, 1, 0, 1, 0, 0, 0, 0, 0, 14, 79, 1, 0, 4, 0, 16, 0, 76, 73, 83,
        84, 82, 73, 0, 0, 73, 78, 70, 79, 73, 83, 70, 84, 14, 0, 0, 0, 76, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
        0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0,
        0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 99, 118, 102, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 0, 73,
        68, 128,
    ];
    let err = keyrig_io::sound::decode_sound_bytes(bytes, Path::new("junk.wav")).expect_err("refused");
    assert!(matches!(err, SoundError::Format { .. }), "{err}");
    assert!(err.to_string().contains("sample rate of 0 (byte 38)"), "{err}");
}

/// Sound files are portable like models: `project::save_scene` names one below the scene's
/// folder relative to it, `project::load_scene` makes it absolute in memory again, and the
/// scene's inputs name it (so no output replaces it).
#[test]
fn sound_paths_are_relative_to_the_scene_on_disk() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::create_dir(dir.path().join("audio")).expect("folder");
    let sound = dir.path().join("audio/line.wav");
    std::fs::copy(fixture("tone.wav"), &sound).expect("copy");
    let mut scene = keyrig_core::Scene::default();
    scene.sounds.push(keyrig_core::SoundClip::new(sound.to_str().expect("utf-8"), 4.0));
    let file = dir.path().join("shot.ron");
    keyrig_io::project::save_scene(&file, &scene).expect("save");
    let text = std::fs::read_to_string(&file).expect("read");
    assert!(text.contains("path: \"audio/line.wav\""), "{text}");
    let back = keyrig_io::project::load_scene(&file).expect("load");
    let path = PathBuf::from(&back.sounds[0].path);
    assert!(path.is_absolute());
    assert_eq!(std::fs::canonicalize(&path).expect("found"), std::fs::canonicalize(&sound).expect("sound"));
    let inputs =
        keyrig_io::project::scene_inputs(&keyrig_io::scene_file::load(&file).expect("raw"), Some(dir.path()));
    assert!(inputs
        .iter()
        .any(|(p, what)| p == &dir.path().join("audio/line.wav") && what.contains("sounds[0]")));
}

#[test]
fn samples_for_playback_are_the_files_own() {
    use keyrig_io::sound::decode_sound_file_for_playback;
    // The WAV's samples are 16-bit already: kept as they are in the file (its last
    // 4 × FRAMES bytes: the data chunk, interleaved little-endian, after FFmpeg's header).
    let bytes = std::fs::read(fixture("tone.wav")).expect("read");
    let data = bytes.len() - 4 * FRAMES as usize;
    let in_file: Vec<i16> = bytes[data..].chunks_exact(2).map(|b| i16::from_le_bytes([b[0], b[1]])).collect();
    let sound = decode_sound_file_for_playback(&fixture("tone.wav"), FRAMES).expect("decodes");
    let pcm = sound.pcm.expect("kept");
    assert_eq!((pcm.sample_rate, pcm.channels, pcm.frames() as u64), (RATE, 2, FRAMES));
    assert_eq!(pcm.samples, in_file);
    // Every format gives its sound's samples (within the lossy codecs' padding).
    for name in ["tone.flac", "tone.ogg", "tone.mp3"] {
        let sound = decode_sound_file_for_playback(&fixture(name), 2 * FRAMES).expect("decodes");
        let pcm = sound.pcm.unwrap_or_else(|| panic!("{name}: kept"));
        assert_eq!(pcm.frames() as u64, sound.summary.frames, "{name}");
        let peak = pcm.samples.iter().map(|s| s.unsigned_abs()).max().unwrap_or(0);
        assert!((f32::from(peak) / 32768.0 - PEAK).abs() < 0.02, "{name}: peak {peak}");
    }
    // Longer than allowed: the summary, without the samples.
    let sound = decode_sound_file_for_playback(&fixture("tone.flac"), FRAMES / 2).expect("decodes");
    assert!(sound.pcm.is_none());
    assert_eq!(sound.summary.frames, FRAMES);
    assert!(decode_sound_file(&fixture("tone.flac")).expect("decodes").pcm.is_none());
}

/// A long sound decoded in parts, each on a thread of its own from a seek, is the one-pass
/// decode sample for sample, in every format (FFmpeg makes 45.3 s of 48 kHz stereo noise, a
/// different noise in each channel: long enough for four parts of
/// [`keyrig_io::sound::MIN_PART_FRAMES`], with the last summary bucket a partial one).
#[test]
fn a_long_sound_decoded_in_parts_is_the_one_pass_decode_sample_for_sample() {
    use keyrig_io::sound::decode_sound_file_on_threads;
    use std::process::Command;
    let dir = tempfile::tempdir().expect("tempdir");
    for (name, args) in [
        ("noise.wav", &["-c:a", "pcm_s16le"][..]),
        ("noise.flac", &[][..]),
        ("noise.mp3", &["-c:a", "libmp3lame", "-b:a", "128k"][..]),
        ("noise.ogg", &["-c:a", "libvorbis", "-q:a", "3"][..]),
    ] {
        let path = dir.path().join(name);
        let noise = |seed: u32| {
            format!("anoisesrc=color=pink:sample_rate=48000:duration=45.3:amplitude=0.5:seed={seed}")
        };
        let out = Command::new("ffmpeg")
            .args([
                "-loglevel",
                "error",
                "-y",
                "-f",
                "lavfi",
                "-i",
                &noise(1),
                "-f",
                "lavfi",
                "-i",
                &noise(2),
            ])
            .args(["-filter_complex", "amerge=inputs=2"])
            .args(args)
            .arg(&path)
            .output()
            .unwrap_or_else(|e| panic!("this test makes its sounds with ffmpeg (Debian: ffmpeg): {e}"));
        assert!(out.status.success(), "ffmpeg {name}: {}", String::from_utf8_lossy(&out.stderr));

        let whole = decode_sound_file_on_threads(&path, Some(u64::MAX), 1).expect("decodes");
        let parts = decode_sound_file_on_threads(&path, Some(u64::MAX), 4).expect("decodes");
        assert_eq!((whole.parts, parts.parts), (1, 4), "{name}: decoded in four parts");
        assert_eq!(parts.codec, whole.codec, "{name}");
        let (a, b) = (whole.pcm.expect("kept"), parts.pcm.expect("kept"));
        assert_eq!(
            (b.sample_rate, b.channels, b.frames()),
            (a.sample_rate, a.channels, a.frames()),
            "{name}"
        );
        assert!(a.frames() > 45 * 48_000, "{name}: {} frames", a.frames());
        // Not silence: both channels swing, each its own way.
        assert!(a.samples.iter().step_by(2).zip(a.samples.iter().skip(1).step_by(2)).any(|(l, r)| l != r));
        assert!(
            a.samples == b.samples,
            "{name}: the samples differ at {:?}",
            a.samples.iter().zip(&b.samples).position(|(x, y)| x != y)
        );
        assert_eq!(parts.summary, whole.summary, "{name}");
        // The summary alone, and a sound longer than the samples kept: as in one pass.
        let summary = decode_sound_file_on_threads(&path, None, 4).expect("decodes");
        assert_eq!((summary.parts, summary.pcm.is_none()), (4, true), "{name}");
        assert_eq!(summary.summary, whole.summary, "{name}");
        let short = decode_sound_file_on_threads(&path, Some(48_000), 3).expect("decodes");
        assert_eq!((short.parts, short.pcm.is_none()), (3, true), "{name}");
        assert_eq!(short.summary, whole.summary, "{name}");
    }
}
