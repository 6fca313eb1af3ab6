//! Sound clips in the editor on a machine without a sound device (this one, CI, Xvfb):
//! playback, scrubbing and stepping work as without sound, nothing panics or hangs, and the
//! status bar says once that there is no output device. Where the machine has a device, the
//! same steps check that real-time playback follows the sound's clock.

mod common;

use std::path::Path;
use std::time::{Duration, Instant};

use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;
use keyrig_editor::audio::Availability;

const NO_DEVICE: &str = "No sound output device";

#[test]
fn sound_clips_play_silently_without_a_device_and_it_is_said_once() {
    let dir = tempfile::tempdir().expect("temp dir");
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("../io/tests/fixtures/sound");
    std::fs::copy(fixtures.join("tone.wav"), dir.path().join("tone.wav")).expect("copy");
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo.ron");
    let mut scene = keyrig_io::scene_file::load(&demo).expect("the demo scene");
    scene.sounds.push(keyrig_core::SoundClip::new("tone.wav", 5.0));
    let file = dir.path().join("scene.ron");
    keyrig_io::project::save_scene(&file, &scene).expect("save");

    let mut h = common::harness(dir.path(), Some(file));
    h.state_mut().wait_for_background_work();
    // The device is opened on a thread once the clip's samples are there: wait for its answer.
    let deadline = Instant::now() + Duration::from_secs(20);
    while matches!(h.state().audio_availability(), Availability::Opening | Availability::NotNeeded)
        && Instant::now() < deadline
    {
        h.step();
        std::thread::sleep(Duration::from_millis(20));
    }
    let availability = h.state().audio_availability();
    assert!(
        matches!(availability, Availability::Open | Availability::Unavailable),
        "the sound device neither opened nor failed within 20 s: {availability:?}"
    );
    let said = |h: &egui_kittest::Harness<'_, keyrig_editor::EditorApp>| {
        h.state().status().is_some_and(|s| s.text.contains(NO_DEVICE))
    };
    if availability == Availability::Unavailable {
        assert!(said(&h), "the status bar says there is no device: {:?}", h.state().status());
    }
    // Another message replaces it; whatever follows must not bring it back.
    h.state_mut().info("marker");

    // Real-time playback for a while, stopped, then steps and a scrub.
    h.key_press_modifiers(Modifiers::NONE, Key::Space);
    let start = Instant::now();
    while start.elapsed() < Duration::from_millis(600) {
        h.step();
        std::thread::sleep(Duration::from_millis(15));
    }
    assert!(h.state().session.playback.playing);
    let played_to = h.state().session.playback.frame;
    assert!(played_to > 3.0, "playback moved on: frame {played_to}");
    h.key_press_modifiers(Modifiers::NONE, Key::Space);
    h.step();
    assert!(!h.state().session.playback.playing);
    common::go_to_frame(&mut h, 8);
    common::press(&mut h, Modifiers::NONE, Key::ArrowLeft);
    assert_eq!(h.state().session.playback.whole_frame(), 7);
    assert!(!said(&h), "said once only: {:?}", h.state().status());
    assert_eq!(h.state().audio_availability(), availability, "it is not opened again");
}

/// *↔ View all* shows every sound clip whole, from its first to its last sample, where it lies
/// outside the frame range and the keys.
#[test]
fn view_all_shows_the_sound_clips_whole() {
    let dir = tempfile::tempdir().expect("temp dir");
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("../io/tests/fixtures/sound");
    std::fs::copy(fixtures.join("tone.wav"), dir.path().join("tone.wav")).expect("copy");
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo.ron");
    let mut scene = keyrig_io::scene_file::load(&demo).expect("the demo scene");
    // The demo's range and keys: frames 0–90 at 30 fps. The tone lasts half a second (15
    // frames): one clip from frame −20 and one to frame 100 + 15.
    assert_eq!((scene.frame_range.start, scene.frame_range.end, scene.fps), (0, 90, 30.0));
    scene.sounds.push(keyrig_core::SoundClip::new("tone.wav", -20.0));
    scene.sounds.push(keyrig_core::SoundClip::new("tone.wav", 100.0));
    let file = dir.path().join("scene.ron");
    keyrig_io::project::save_scene(&file, &scene).expect("save");

    let mut h = common::harness(dir.path(), Some(file));
    h.state_mut().wait_for_background_work();
    h.run();
    h.get_by_label("↔ View all").click();
    h.run();
    let view = h.state().dope_sheet_view();
    assert!(view.start <= -20.0 && view.end >= 115.0, "both clips whole: {view:?}");
    assert!(view.start > -30.0 && view.end < 125.0, "and not much more: {view:?}");
}

/// The sound clips' rows head the dope sheet's rows and scroll with them: a wheel over a
/// sheet of many rows moves the clip's bar up with the rows.
#[test]
fn sound_rows_scroll_with_the_rows() {
    let dir = tempfile::tempdir().expect("temp dir");
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("../io/tests/fixtures/sound");
    std::fs::copy(fixtures.join("tone.wav"), dir.path().join("tone.wav")).expect("copy");
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo.ron");
    let mut scene = keyrig_io::scene_file::load(&demo).expect("the demo scene");
    // Forty more objects: more rows than the sheet shows.
    for i in 0..40 {
        let mut extra = scene.objects[0].clone();
        extra.name = format!("Extra{i}");
        scene.objects.push(extra);
    }
    scene.sounds.push(keyrig_core::SoundClip::new("tone.wav", 5.0));
    let file = dir.path().join("scene.ron");
    keyrig_io::project::save_scene(&file, &scene).expect("save");

    let mut h = common::harness(dir.path(), Some(file));
    h.state_mut().wait_for_background_work();
    h.run();
    let bar = h.get_by_label("sound clip tone.wav frame 5").rect();
    // The clip's own row ("♪ tone.wav") and the channel rows under it.
    let top_of = |h: &egui_kittest::Harness<'_, keyrig_editor::EditorApp>, label: &str| {
        h.query_by_label(label).map(|n| n.rect().top())
    };
    let cube = top_of(&h, "dope sheet row Cube").expect("the Cube's row");
    let first_channel = top_of(&h, "dope sheet row Arm").expect("the first object's row");
    let sound_row = h.get_by_label("dope sheet row ♪ tone.wav").rect();
    assert!(
        sound_row.bottom() <= first_channel + 0.5 && bar.bottom() <= first_channel,
        "the clip's row heads the rows: {sound_row:?}, the bar {bar:?}, the rows from {first_channel}"
    );
    h.event(egui::Event::PointerMoved(bar.center()));
    h.event(egui::Event::MouseWheel {
        unit: egui::MouseWheelUnit::Point,
        delta: egui::vec2(0.0, -20.0),
        modifiers: Modifiers::NONE,
        phase: egui::TouchPhase::Move,
    });
    for _ in 0..10 {
        h.run();
    }
    let scrolled = cube - top_of(&h, "dope sheet row Cube").expect("the Cube's row");
    assert!(scrolled > 5.0, "the rows scrolled: {scrolled}");
    let moved = bar.top() - h.get_by_label("sound clip tone.wav frame 5").rect().top();
    assert!((moved - scrolled).abs() < 0.5, "the clip's bar moved {moved} with the rows' {scrolled}");
}

/// Issue 42, 13: a sound file dropped on the window, or picked with Ctrl+I (File ▸ Import…, whose
/// dialog lists sounds) or File ▸ Import sound, becomes a sound clip at the current frame — one
/// undo step each — and the dope sheet shows its row.
#[test]
fn a_sound_file_is_imported_at_the_current_frame() {
    let dir = tempfile::tempdir().expect("temp dir");
    let fixtures = Path::new(env!("CARGO_MANIFEST_DIR")).join("../io/tests/fixtures/sound");
    let wav = dir.path().join("tone.wav");
    std::fs::copy(fixtures.join("tone.wav"), &wav).expect("copy");
    let mut h = common::harness(dir.path(), None);
    common::go_to_frame(&mut h, 12);
    let steps = h.state().doc.undo_len();
    h.input_mut().dropped_files.push(egui::DroppedFile { path: Some(wav.clone()), ..Default::default() });
    h.run();
    let sounds = &h.state().doc.scene().sounds;
    assert_eq!(sounds.len(), 1, "the dropped sound is a clip");
    assert_eq!(Path::new(&sounds[0].path), wav.as_path());
    assert_eq!(sounds[0].start_frame, 12.0);
    assert_eq!(h.state().doc.undo_len(), steps + 1);
    assert_eq!(h.state().doc.undo_label(), Some("add sound clip tone.wav at frame 12"));
    h.state_mut().wait_for_background_work();
    h.run();
    assert!(h.query_by_label("dope sheet row ♪ tone.wav").is_some(), "its row in the dope sheet");

    // Ctrl+I's dialog lists sounds beside models; File ▸ Import sound lists only sounds.
    let names = |purpose| {
        keyrig_editor::files::dialog_filters(purpose)
            .iter()
            .flat_map(|f| f.1.iter().copied())
            .collect::<Vec<_>>()
    };
    for ext in ["wav", "flac", "mp3", "ogg"] {
        assert!(names(keyrig_editor::files::DialogPurpose::Import).contains(&ext), "{ext}");
        assert!(names(keyrig_editor::files::DialogPurpose::ImportSound).contains(&ext), "{ext}");
    }
    common::go_to_frame(&mut h, 30);
    h.state_mut().import_path(wav.clone());
    h.run();
    assert_eq!(h.state().doc.scene().sounds.iter().map(|c| c.start_frame).collect::<Vec<_>>(), [12.0, 30.0]);
    press_undo(&mut h);
    assert_eq!(h.state().doc.scene().sounds.len(), 1, "one undo step");
}

fn press_undo(h: &mut egui_kittest::Harness<'_, keyrig_editor::EditorApp>) {
    h.key_press_modifiers(Modifiers::COMMAND, Key::Z);
    h.run();
}
