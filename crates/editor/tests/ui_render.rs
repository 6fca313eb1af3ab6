//! File ▸ Render animation: the dialog renders the open scene on its own thread into the
//! movie it names (here an animated GIF, decoded by the `gif` crate), shows its progress, and
//! the editor keeps working meanwhile; Cancel leaves no movie.

mod common;

use common::{harness, press, set_value};
use egui::accesskit::Role;
use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;

/// Runs frames; while a render runs the editor repaints every 100 ms to show its progress,
/// more often than the harness's step limit allows, which is not a failure here.
fn step(h: &mut egui_kittest::Harness<'_, keyrig_editor::EditorApp>) {
    let _ = h.try_run();
}

/// The demo scene saved in `dir`, so that the dialog's output lands beside it.
fn scene_in(dir: &std::path::Path) -> std::path::PathBuf {
    let path = dir.join("arm.ron");
    keyrig_io::save(&path, &keyrig_io::demo::demo_scene()).expect("save");
    path
}

#[test]
fn the_dialog_renders_a_movie_while_the_editor_keeps_working() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut h = harness(dir.path(), Some(scene_in(dir.path())));
    press(&mut h, Modifiers::COMMAND | Modifiers::SHIFT, Key::R);
    assert!(h.state().view.show_render, "Ctrl+Shift+R opens the dialog");
    set_value(&mut h, Role::SpinButton, "Width", 64.0);
    set_value(&mut h, Role::SpinButton, "Height", 48.0);
    set_value(&mut h, Role::SpinButton, "First frame", 10.0);
    set_value(&mut h, Role::SpinButton, "Last frame", 17.0);
    h.get_by_role_and_label(Role::ComboBox, "Format").click();
    h.run();
    h.get_by_label("Animated GIF (.gif)").click();
    h.run();
    h.get_by_label("Render").click();
    step(&mut h);
    assert!(h.state().rendering(), "the render runs on its own thread");
    // The editor answers while it renders: the next frame key moves the clock.
    let before = h.state().session.playback.whole_frame();
    h.key_press_modifiers(Modifiers::NONE, Key::ArrowRight);
    step(&mut h);
    assert_eq!(h.state().session.playback.whole_frame(), before + 1);

    h.state_mut().wait_for_render();
    h.run();
    let status = h.state().status().cloned().expect("a message");
    assert!(!status.is_error && status.text.contains("Rendered 8 frames"), "{status:?}");
    let movie = dir.path().join("arm.gif");
    let mut options = gif::DecodeOptions::new();
    options.set_color_output(gif::ColorOutput::RGBA);
    let mut decoder = options.read_info(std::fs::File::open(&movie).expect("the movie")).expect("a GIF");
    assert_eq!((decoder.width(), decoder.height()), (64, 48));
    let mut frames = 0;
    while decoder.read_next_frame().expect("a frame").is_some() {
        frames += 1;
    }
    assert_eq!(frames, 8, "frames 10..=17");
}

#[test]
fn cancelling_writes_no_movie() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut h = harness(dir.path(), Some(scene_in(dir.path())));
    press(&mut h, Modifiers::COMMAND | Modifiers::SHIFT, Key::R);
    set_value(&mut h, Role::SpinButton, "Width", 64.0);
    set_value(&mut h, Role::SpinButton, "Height", 48.0);
    h.get_by_label("Render").click();
    step(&mut h);
    h.get_by_label("Cancel").click();
    step(&mut h);
    h.state_mut().wait_for_render();
    h.run();
    let status = h.state().status().cloned().expect("a message");
    assert!(status.is_error && status.text.contains("cancelled"), "{status:?}");
    assert!(!dir.path().join("arm.mp4").exists(), "a cancelled render leaves no movie");
    let left: Vec<_> = std::fs::read_dir(dir.path())
        .expect("dir")
        .filter_map(|e| e.ok().map(|e| e.file_name().to_string_lossy().into_owned()))
        .filter(|n| n.contains("arm.mp4"))
        .collect();
    assert!(left.is_empty(), "temporary files left: {left:?}");
}

/// Issue 42, 2: the dialog renders what `keyrig render --frames` renders — the scene's render
/// size (960×540 in `assets/cameras.ron`), through the active camera with the marker's cut at
/// frame 30 — pixel for pixel, frames 28 to 32 on both sides of the cut.
#[test]
fn the_dialog_renders_what_keyrig_render_renders() {
    let dir = tempfile::tempdir().expect("tempdir");
    let asset = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/cameras.ron");
    let path = dir.path().join("shot.ron");
    keyrig_io::project::save_scene(&path, &keyrig_io::project::load_scene(&asset).expect("load"))
        .expect("save");
    let mut h = harness(dir.path(), Some(path.clone()));
    press(&mut h, Modifiers::COMMAND | Modifiers::SHIFT, Key::R);
    set_value(&mut h, Role::SpinButton, "First frame", 28.0);
    set_value(&mut h, Role::SpinButton, "Last frame", 32.0);
    h.get_by_role_and_label(Role::ComboBox, "Format").click();
    h.run();
    h.get_by_label("Numbered PNG frames").click();
    h.run();
    h.get_by_label("Render").click();
    step(&mut h);
    h.state_mut().wait_for_render();
    h.run();
    let status = h.state().status().cloned().expect("a message");
    assert!(!status.is_error && status.text.contains("Rendered 5 frames"), "{status:?}");

    let cli = dir.path().join("cli");
    std::fs::create_dir(&cli).expect("a folder");
    let out = std::process::Command::new(env!("CARGO_BIN_EXE_keyrig"))
        .args(["render", path.to_str().expect("utf-8"), "--frames", "28..32", "-o"])
        .arg(cli.join("frame_####.png"))
        .output()
        .expect("keyrig render");
    assert!(out.status.success(), "{}", String::from_utf8_lossy(&out.stderr));
    for frame in 28..=32 {
        let name = format!("frame_{frame:04}.png");
        let editor =
            image::open(dir.path().join("shot_frames").join(&name)).expect("the dialog's frame").to_rgba8();
        let command = image::open(cli.join(&name)).expect("keyrig render's frame").to_rgba8();
        assert_eq!(editor.dimensions(), (960, 540), "{name}: the scene's render size");
        assert_eq!(editor.dimensions(), command.dimensions());
        let differ = editor
            .pixels()
            .zip(command.pixels())
            .filter(|(a, b)| a.0.iter().zip(b.0).any(|(x, y)| x.abs_diff(y) > 2))
            .count();
        assert!(differ == 0, "{name}: {differ} pixels differ from keyrig render's");
    }
}
