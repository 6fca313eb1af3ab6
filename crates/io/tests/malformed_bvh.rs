//! Hostile BVH files against the memory bound: the reader's peak allocation stays within 12 ×
//! the file's size + 64 KiB whatever the file declares (a joint of 25 bytes of text is a
//! ~100-byte `BvhJoint`), and the scene made of a file within 40 × + 1 MiB
//! (a keyrig key is ~104 bytes for three values that take as few as
//! six bytes of text). One test, so that no other test allocates while it counts.

use std::alloc::{GlobalAlloc, Layout, System};
use std::sync::atomic::{AtomicUsize, Ordering};

struct Counting;

static LIVE: AtomicUsize = AtomicUsize::new(0);
static PEAK: AtomicUsize = AtomicUsize::new(0);

unsafe impl GlobalAlloc for Counting {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        let p = unsafe { System.alloc(layout) };
        if !p.is_null() {
            let now = LIVE.fetch_add(layout.size(), Ordering::Relaxed) + layout.size();
            PEAK.fetch_max(now, Ordering::Relaxed);
        }
        p
    }

    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        unsafe { System.dealloc(ptr, layout) };
        LIVE.fetch_sub(layout.size(), Ordering::Relaxed);
    }
}

#[global_allocator]
static ALLOCATOR: Counting = Counting;

/// Peak bytes allocated at once while `f` runs, beyond what was live before.
fn peak_of<T>(f: impl FnOnce() -> T) -> (T, usize) {
    let before = LIVE.load(Ordering::Relaxed);
    PEAK.store(before, Ordering::Relaxed);
    let out = f();
    (out, PEAK.load(Ordering::Relaxed).saturating_sub(before))
}

fn corpus() -> String {
    let path =
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/bvh/cmu-bvh11/131_01.bvh");
    std::fs::read_to_string(path).expect("corpus take")
}

/// The hostile files: (what, text).
fn cases() -> Vec<(String, String)> {
    let take = corpus();
    let motion = take.find("MOTION").expect("MOTION");
    let hierarchy = &take[..motion];
    let mut out: Vec<(String, String)> = vec![
        ("the corpus take".into(), take.clone()),
        (
            "a billion frames declared".into(),
            format!("{hierarchy}MOTION\nFrames: 1000000000\nFrame Time: 0.0083333\n0 0 0\n"),
        ),
        ("i32::MAX frames, no channels".into(), {
            "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\n}\nMOTION\nFrames: 2147483647\nFrame Time: 1\n".into()
        }),
    ];
    for cut in [10, 1_000, motion, motion + 40, take.len() / 2, take.len() - 3] {
        out.push((format!("the take cut at byte {cut}"), take[..cut].to_owned()));
    }
    let mut deep =
        String::from("HIERARCHY\nROOT r\n{\nOFFSET 0 0 0\nCHANNELS 3 Zrotation Xrotation Yrotation\n");
    for i in 0..10_000 {
        deep.push_str(&format!("JOINT j{i}\n{{\nOFFSET 0 1 0\nCHANNELS 1 Zrotation\n"));
    }
    deep.push_str(&"}\n".repeat(10_001));
    deep.push_str("MOTION\nFrames: 2\nFrame Time: 0.1\n");
    for _ in 0..2 {
        deep.push_str(&"0 ".repeat(10_003));
        deep.push('\n');
    }
    out.push(("10,000 deep".into(), deep));
    let mut wide = String::from("HIERARCHY\nROOT r\n{\nOFFSET 0 0 0\n");
    for i in 0..20_000 {
        wide.push_str(&format!("JOINT w{i}\n{{\nOFFSET 1 0 0\n}}\n"));
    }
    wide.push_str("}\nMOTION\nFrames: 0\nFrame Time: 0.1\n");
    out.push(("20,000 joints without channels".into(), wide));
    let long = "n".repeat(70_000);
    out.push((
        "70,000-character names".into(),
        format!("HIERARCHY\nROOT {long}\n{{\nOFFSET 0 0 0\nJOINT {long}\n{{\nOFFSET 0 0 0\nEnd Site\n{{\nOFFSET 0 0 0\n}}\n}}\n}}\nMOTION\nFrames: 0\nFrame Time: 1\n"),
    ));
    let mut dense = String::from(
        "HIERARCHY\nROOT r\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation\n}\nMOTION\nFrames: 50000\nFrame Time: 0.01\n",
    );
    dense.push_str(&"0 0 0 0 0 0\n".repeat(50_000));
    out.push(("50,000 frames of the shortest values".into(), dense));
    out.push((
        "a 5 MB value".into(),
        format!("{hierarchy}MOTION\nFrames: 1\nFrame Time: 0.01\n{}\n", "9".repeat(5 << 20)),
    ));
    out
}

#[test]
fn hostile_files_stay_within_the_memory_bound() {
    let mut report = Vec::new();
    for (what, text) in cases() {
        let size = text.len();
        let (parsed, parse_peak) = peak_of(|| keyrig_io::bvh::parse_bvh(&text, None));
        match &parsed {
            Ok(_) => {}
            Err(e) => {
                assert!(e.place.is_some(), "{what}: {e}");
                assert!(e.to_string().len() < 600, "{what}: a long message");
            }
        }
        assert!(parse_peak <= 12 * size + (64 << 10), "{what}: parse peak {parse_peak} for {size} bytes");
        let scene_peak = match parsed {
            Ok(file) => {
                let (scene, peak) = peak_of(|| file.to_scene("x"));
                assert!(scene.problems().is_empty(), "{what}");
                assert!(peak <= 40 * size + (1 << 20), "{what}: scene peak {peak} for {size} bytes");
                Some(peak)
            }
            Err(_) => None,
        };
        report.push(format!(
            "{what}: {size} bytes, parse peak {:.2} × size{}",
            parse_peak as f64 / size as f64,
            scene_peak.map_or(String::from(", refused"), |p| format!(
                ", scene peak {:.2} × size",
                p as f64 / size as f64
            ))
        ));
    }
    println!("{}", report.join("\n"));
}
