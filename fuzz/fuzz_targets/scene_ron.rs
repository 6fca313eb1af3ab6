//! The RON scene loader on arbitrary text (bytes that are not UTF-8 are skipped: the loader
//! takes a `&str`, and reading a file checks UTF-8 first).
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(text) = std::str::from_utf8(data) {
        let _ = keyrig_io::scene_file::from_str(text, std::path::Path::new("fuzz.ron"));
    }
});
