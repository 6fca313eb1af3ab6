//! The RON scene loader on arbitrary text (bytes that are not UTF-8 are skipped: the loader
//! takes a `&str`, and reading a file checks UTF-8 first). Every input is also tried with a
//! UTF-8 byte-order mark in front, which the loader strips; an error message never quotes
//! more than keyrig-io's clipped form of a long token.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let origin = std::path::Path::new("fuzz.ron");
        let plain = keyrig_io::scene_file::from_str(text, origin);
        let with_bom = keyrig_io::scene_file::from_str(&format!("\u{FEFF}{text}"), origin);
        if !text.starts_with('\u{FEFF}') {
            assert_eq!(plain.is_ok(), with_bom.is_ok());
        }
        if let Err(e) = plain {
            let message = e.to_string();
            let clipped = keyrig_io::message::clip_long_tokens(&message);
            assert_eq!(keyrig_io::message::clip_long_tokens(&clipped), clipped);
        }
    }
});
