//! The BVH reader on arbitrary bytes: it must return a file or a located error, never panic
//! and never allocate more than the input justifies; an accepted file must map onto a valid
//! scene, and a small one must export and read back with the same joints and frames.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let file = match keyrig_io::bvh::parse_bvh_bytes(data, None) {
        Ok(file) => file,
        Err(e) => {
            assert!(e.place.is_some(), "an error without a place: {e}");
            return;
        }
    };
    let scene = file.to_scene("fuzzed");
    let problems = scene.problems();
    assert!(problems.is_empty(), "an accepted file made an invalid scene: {problems:?}");
    // Export plays every frame: only for small takes.
    if file.frames <= 64 && file.joints.len() <= 256 {
        // Sums of values near the limit (an OFFSET plus a position) may not fit a BVH file.
        match keyrig_io::bvh::bvh_text(&scene, 0) {
            Ok(text) => {
                let again = keyrig_io::bvh::parse_bvh(&text, None).expect("the export reads back");
                assert_eq!(again.frames, file.frames.max(1));
                let end_sites = file.joints.iter().filter(|j| j.end_site).count();
                assert!(again.joints.len() >= file.joints.len() - end_sites);
            }
            Err(e) => assert!(matches!(e.kind, keyrig_io::bvh::BvhErrorKind::OutOfRange(_)), "{e}"),
        }
    }
});
