//! The sound decoder (Symphonia's WAV, FLAC, Ogg Vorbis and MP3 readers behind keyrig-io's
//! summary) on arbitrary bytes: it must return a summary or an error, never panic; a summary
//! must be consistent (every level halves the one before, down to one bucket; its extremes
//! are finite and ordered).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
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
