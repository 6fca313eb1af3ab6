//! `keyrig clean` (docs/cleanup.md): the CMU 131 take reduced within 0.5° and 1 mm (0.0177 of
//! its units) to a scene file with at most a tenth of its keys, smoothing, and what the command
//! refuses (nothing to do, bad tolerances and cutoffs, writing over the input).

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

use keyrig_edit::cleanup::{key_total, keyed_channels};

const KEYRIG: &str = env!("CARGO_BIN_EXE_keyrig");

fn keyrig(args: &[&str]) -> Output {
    Command::new(KEYRIG).args(args).output().expect("run keyrig")
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn take() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/bvh/cmu-bvh11/131_01.bvh")
}

#[test]
fn the_cmu_take_reduced_and_smoothed_to_a_scene_file() {
    let dir = tempfile::tempdir().expect("temp dir");
    let take = take();
    let out_path = dir.path().join("walk.ron");
    let out = keyrig(&[
        "clean",
        take.to_str().unwrap(),
        "-o",
        out_path.to_str().unwrap(),
        "--reduce-angle",
        "0.5",
        "--reduce-distance",
        "0.0177",
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    assert!(stderr(&out).contains("reduced 32 channels from 31808 to"), "{}", stderr(&out));
    let original = keyrig_io::bvh::import_scene(&take).unwrap();
    let cleaned = keyrig_io::scene_file::load(&out_path).expect("the written scene loads");
    let before = key_total(&original, &keyed_channels(&original, None));
    let after = key_total(&cleaned, &keyed_channels(&cleaned, None));
    assert_eq!(before, 31808);
    assert!(after * 10 <= before, "{after} of {before}");
    assert!(cleaned.problems().is_empty(), "{:?}", cleaned.problems());

    // Smoothing alone keeps every key; the values move.
    let smooth_path = dir.path().join("smooth.ron");
    let out =
        keyrig(&["clean", take.to_str().unwrap(), "-o", smooth_path.to_str().unwrap(), "--smooth-hz", "6"]);
    assert!(out.status.success(), "{}", stderr(&out));
    let smoothed = keyrig_io::scene_file::load(&smooth_path).unwrap();
    assert_eq!(key_total(&smoothed, &keyed_channels(&smoothed, None)), before);
    assert!(smoothed.objects[0] != original.objects[0]);
}

#[test]
fn clean_refuses_what_it_cannot_do() {
    let dir = tempfile::tempdir().expect("temp dir");
    let take = take();
    let out_path = dir.path().join("walk.ron");
    let (t, o) = (take.to_str().unwrap(), out_path.to_str().unwrap());
    let fails = |args: &[&str], needle: &str| {
        let out = keyrig(args);
        assert!(!out.status.success(), "{args:?} succeeded");
        assert!(stderr(&out).contains(needle), "{args:?}: {}", stderr(&out));
    };
    fails(&["clean", t, "-o", o], "nothing to do");
    fails(&["clean", t, "-o", o, "--reduce-angle", "NaN"], "angle tolerance");
    fails(&["clean", t, "-o", o, "--reduce-distance", "-1"], "distance tolerance");
    fails(&["clean", t, "-o", o, "--smooth-hz", "60"], "half the frame rate");
    fails(&["clean", t, "-o", o, "--smooth-hz", "0"], "cutoff");
    fails(&["clean", t, "-o", &format!("{}/walk.glb", dir.path().display()), "--reduce"], ".ron");
    fails(&["clean", t, "-o", o, "--reduce", "--object", "Nobody"], "no object is named");
    assert!(!out_path.exists(), "nothing written by a refused command");
    // Never over the input.
    let scene = dir.path().join("scene.ron");
    assert!(keyrig(&["import", t, "-o", scene.to_str().unwrap()]).status.success());
    let before = std::fs::read(&scene).unwrap();
    fails(&["clean", scene.to_str().unwrap(), "-o", scene.to_str().unwrap(), "--reduce"], "input");
    assert_eq!(std::fs::read(&scene).unwrap(), before);
}
