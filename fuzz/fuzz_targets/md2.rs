//! The MD2 reader on arbitrary bytes: it must return Ok or a located error, never panic,
//! and a model it accepts must play every clip.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(model) = keyrig_io::md2::parse_md2(data) {
        for clip in 0..model.clips.len() {
            let _ = model.sample_clip(clip, 10.0, 0.35, true);
        }
    }
});
