//! `assets/cycle.ron`, the cycles example of issue 19: the serialized `cycle_scene()`, the arm
//! waving with one wave of elbow keys repeated and the hand in ping-pong.
//!
//! After changing `keyrig_io::demo::cycle_scene`, regenerate the file with
//! `KEYRIG_REGENERATE_DEMO=1 cargo test -p keyrig-io --test scene_cycle`.

use std::path::Path;

use keyrig_core::{AnimatedTrack, Cycle};
use keyrig_io::demo::{cycle_scene, CYCLE_RON, WAVE_SECONDS};
use keyrig_io::scene_file;

#[test]
fn committed_cycle_file_equals_generated_scene() {
    let generated = scene_file::to_string(&cycle_scene()).expect("serialize cycle scene");
    if std::env::var_os("KEYRIG_REGENERATE_DEMO").is_some() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/cycle.ron");
        std::fs::write(&path, &generated).expect("write assets/cycle.ron");
        return;
    }
    assert!(
        CYCLE_RON == generated,
        "assets/cycle.ron differs from keyrig_io::demo::cycle_scene(); regenerate it with \
         KEYRIG_REGENERATE_DEMO=1 cargo test -p keyrig-io --test scene_cycle"
    );
    // The cycles are written readably, after the keys.
    assert!(CYCLE_RON.contains("before: Repeat,\n"), "{CYCLE_RON}");
    assert!(CYCLE_RON.contains("after: Repeat,\n"), "{CYCLE_RON}");
    assert!(CYCLE_RON.contains("after: PingPong,\n"), "{CYCLE_RON}");
}

#[test]
fn cycle_scene_loads_and_waves_every_second() {
    let scene = scene_file::from_str(CYCLE_RON, Path::new("assets/cycle.ron")).expect("cycle.ron loads");
    assert_eq!(scene, cycle_scene());
    assert_eq!(scene.problems(), Vec::new());
    let joints = &scene.objects[0].skeleton.as_ref().expect("a skeleton").joints;
    let elbow = &joints[1].rotation;
    assert_eq!((elbow.before, elbow.after), (Cycle::Repeat, Cycle::Repeat));
    let track = AnimatedTrack::new(elbow).expect("valid");
    // The keys cover one wave; the scene's 4 s play it four times.
    assert_eq!(track.domain(), Some((0.0, WAVE_SECONDS)));
    for t in [0.1, 0.37, 0.5, 0.9] {
        for k in 1..4 {
            let (a, b) = (track.sample(t), track.sample(t + f64::from(k) * WAVE_SECONDS));
            assert!(a.dot(b).abs() > 1.0 - 1e-6, "t = {t}, cycle {k}: {a:?} vs {b:?}");
        }
    }
}
