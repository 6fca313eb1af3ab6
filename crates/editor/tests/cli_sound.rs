//! Sound clips in a scene: saved with paths relative to the scene, read back unchanged, and
//! listed by `keyrig info` with what their files hold (codec, rate, channels, length) — a file
//! that does not decode is a problem that names the clip.

use std::path::Path;
use std::process::Command;

use keyrig_core::SoundClip;

fn fixture(name: &str) -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../io/tests/fixtures/sound").join(name)
}

#[test]
fn info_lists_a_scenes_sound_clips() {
    let dir = tempfile::tempdir().expect("tempdir");
    std::fs::create_dir(dir.path().join("audio")).expect("folder");
    std::fs::copy(fixture("tone.flac"), dir.path().join("audio/line.flac")).expect("copy");
    let mut scene = keyrig_io::demo::demo_scene();
    scene.sounds.push(SoundClip::new("audio/line.flac", 12.0));
    scene.sounds.push(SoundClip { gain: 0.5, mute: true, ..SoundClip::new("audio/missing.wav", -3.0) });
    let path = dir.path().join("shot.ron");
    keyrig_io::save(&path, &scene).expect("save");
    // Saved and read back as it was; a clip at unit gain and not muted saves neither field.
    assert_eq!(keyrig_io::load(&path).expect("load"), scene);
    let text = std::fs::read_to_string(&path).expect("read");
    assert!(text.contains("path: \"audio/line.flac\""), "{text}");
    assert_eq!(text.matches("gain:").count(), 1, "{text}");

    let out = Command::new(env!("CARGO_BIN_EXE_keyrig"))
        .args(["info", path.to_str().expect("utf-8")])
        .output()
        .expect("run");
    let stdout = String::from_utf8_lossy(&out.stdout);
    assert!(stdout.contains("sounds:   2"), "{stdout}");
    assert!(
        stdout.contains("\"audio/line.flac\": from frame 12, gain 1, flac 22050 Hz 2 channels, 0.500 s"),
        "{stdout}"
    );
    assert!(
        stdout.contains("\"audio/missing.wav\": from frame -3, gain 0.5, muted, cannot be read"),
        "{stdout}"
    );
    // The missing file is a problem, so info fails.
    assert!(!out.status.success());
    assert!(stdout.contains("sounds[1].path") && stdout.contains("missing.wav"), "{stdout}");

    let out = Command::new(env!("CARGO_BIN_EXE_keyrig"))
        .args(["info", path.to_str().expect("utf-8"), "--format", "json"])
        .output()
        .expect("run");
    let doc: serde_json::Value = serde_json::from_slice(&out.stdout).expect("JSON");
    assert_eq!(doc["sounds"][0]["sample_rate"], 22050);
    assert_eq!(doc["sounds"][0]["duration_s"], 0.5);
    assert_eq!(doc["sounds"][1]["mute"], true);
    assert!(doc["sounds"][1]["codec"].is_null());
}
