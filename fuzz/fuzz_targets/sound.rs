//! The sound decoder (Symphonia's WAV, FLAC, Ogg Vorbis and MP3 readers behind keyrig-io's
//! summary) on arbitrary bytes: it must return a summary or an error, never panic; a summary
//! must be consistent (every level halves the one before, down to one bucket; its extremes
//! are finite and ordered).
//!
//! keyrig-io catches a panic inside Symphonia and answers with the file's format error
//! (`crates/io/src/sound.rs`, `decode_sound`); libfuzzer-sys's panic hook would abort on that
//! caught panic, so the target puts Rust's default hook back: a panic that reaches the target
//! is still a crash (libfuzzer-sys aborts on it), a caught one is a refused file.
#![no_main]

use libfuzzer_sys::fuzz_target;

static DEFAULT_HOOK: std::sync::Once = std::sync::Once::new();

fuzz_target!(|data: &[u8]| {
    DEFAULT_HOOK.call_once(|| drop(std::panic::take_hook()));
    let name = std::path::Path::new("fuzzed");
    if let Ok(sound) = keyrig_io::sound::decode_sound_bytes(data.to_vec(), name) {
        let summary = &sound.summary;
        for pair in summary.levels.windows(2) {
            assert_eq!(pair[1].len(), pair[0].len().div_ceil(2));
        }
        assert!(summary.levels.last().map_or(true, |top| top.len() == 1));
        for &[lo, hi] in summary.levels.iter().flatten() {
            assert!(lo.is_finite() && hi.is_finite() && lo <= hi, "{lo}..{hi}");
        }
        let _ = summary.range(0.0, summary.duration());
    }
});
