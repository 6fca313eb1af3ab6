//! The editor driven as a user would: clicks on labelled widgets, AccessKit value changes and
//! key presses, through egui_kittest. Each test checks the document afterwards.

mod common;

use common::{drag, go_to_frame, harness, press, set_value};

use egui::accesskit::Role;
use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use keyrig_core::{Interpolation, Scene};
use keyrig_edit::channels::{self, ChannelId};
use keyrig_editor::session::Selected;
use keyrig_editor::{Command, EditorApp};

const WRIST: ChannelId = ChannelId::JointRotation { object: 0, joint: 3 };

/// Selects the wrist (unkeyed in the demo), turns record on, and sets its X rotation at two
/// frames: two keys appear, at those frames, with those angles.
fn record_two_wrist_keys(harness: &mut Harness<'_, EditorApp>) {
    harness.get_by_label("wrist").click();
    harness.run();
    assert_eq!(harness.state().session.selection.item, Some(Selected::Joint { object: 0, joint: 3 }));
    harness.get_by_label("⏺ Record").click();
    harness.run();
    assert!(harness.state().session.record, "the Record button turns record mode on");

    go_to_frame(harness, 10);
    set_value(harness, Role::SpinButton, "Rotation (°) X", 45.0);
    go_to_frame(harness, 20);
    set_value(harness, Role::SpinButton, "Rotation (°) X", 90.0);
}

#[test]
fn record_mode_writes_one_key_per_frame_changed() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    assert_eq!(channels::key_count(h.state().doc.scene(), WRIST), 0);
    record_two_wrist_keys(&mut h);

    let scene = h.state().doc.scene();
    let fps = scene.fps;
    let times: Vec<i64> =
        channels::key_times(scene, WRIST).iter().map(|t| (t * fps).round() as i64).collect();
    assert_eq!(times, vec![10, 20]);
    let skeleton = scene.objects[0].skeleton.as_ref().expect("arm skeleton");
    let angles: Vec<f32> = skeleton.joints[3]
        .rotation
        .track
        .keys
        .iter()
        .map(|k| keyrig_editor::eval::euler_degrees(k.value).x)
        .collect();
    assert!((angles[0] - 45.0).abs() < 0.01 && (angles[1] - 90.0).abs() < 0.01, "{angles:?}");
    assert!(h.state().doc.is_dirty());
}

#[test]
fn without_record_mode_a_change_is_a_pose_that_i_keys() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("elbow").click();
    h.run();
    go_to_frame(&mut h, 5);
    let before = h.state().doc.scene().clone();
    set_value(&mut h, Role::SpinButton, "Rotation (°) X", 30.0);
    // The elbow is keyed: the change is a transient pose, not an edit.
    assert_eq!(h.state().doc.scene(), &before);
    let elbow = ChannelId::JointRotation { object: 0, joint: 1 };
    assert!(h.state().session.overrides.contains_key(&elbow));
    press(&mut h, Modifiers::NONE, Key::I);
    let scene = h.state().doc.scene();
    let index = channels::key_at(scene, elbow, 5.0 / scene.fps).expect("I wrote a key at frame 5");
    let key = &scene.objects[0].skeleton.as_ref().expect("skeleton").joints[1].rotation.track.keys[index];
    assert!((keyrig_editor::eval::euler_degrees(key.value).x - 30.0).abs() < 0.01);
    assert!(h.state().session.overrides.is_empty());
}

/// Selects the elbow key at frame 15 by clicking its diamond in the dope sheet.
/// The text the last frame put on the system clipboard (`ctx.copy_text`).
fn copied_text(h: &Harness<'_, EditorApp>) -> Option<String> {
    h.output().platform_output.commands.iter().find_map(|c| match c {
        egui::OutputCommand::CopyText(text) => Some(text.clone()),
        _ => None,
    })
}

fn select_elbow_key_15(h: &mut Harness<'_, EditorApp>) {
    h.get_by_label("key elbow rotation frame 15").click();
    h.run();
    assert_eq!(h.state().session.selection.keys.len(), 1);
}

#[test]
fn moving_a_tcb_slider_changes_the_sampled_value() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    // The elbow key at frame 30 (90°) sits between 45° and 90°: its tangents depend on T, C
    // and B, so the curve between frames 30 and 45 moves with each slider.
    h.get_by_label("key elbow rotation frame 30").click();
    h.run();
    let elbow = ChannelId::JointRotation { object: 0, joint: 1 };
    let sample = |app: &EditorApp| {
        let scene = app.doc.scene();
        match keyrig_editor::eval::channel_value(scene, elbow, 36.0 / scene.fps, &Default::default()) {
            Some(keyrig_edit::channels::ChannelValue::Rotation(q)) => q,
            other => panic!("elbow rotation is a rotation, got {other:?}"),
        }
    };
    let mut previous = sample(h.state());
    for (slider, value) in [("Tension", 0.8), ("Continuity", 0.4), ("Bias", -0.5)] {
        set_value(&mut h, Role::Slider, slider, value);
        let now = sample(h.state());
        assert!(previous.angle_between(now) > 1e-4, "{slider} = {value} moves the curve");
        previous = now;
    }
    let (_, mode, tcb) = channels::key_params(h.state().doc.scene(), elbow, 2).expect("key 2");
    assert_eq!(mode, Interpolation::Tcb);
    assert_eq!((tcb.tension, tcb.continuity, tcb.bias), (0.8, 0.4, -0.5));
}

#[test]
fn undo_and_redo_return_the_document_exactly() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let original: Scene = h.state().doc.scene().clone();
    record_two_wrist_keys(&mut h);
    select_elbow_key_15(&mut h);
    set_value(&mut h, Role::Slider, "Continuity", 0.5);
    press(&mut h, Modifiers::NONE, Key::Delete);
    let edited = h.state().doc.scene().clone();
    assert_ne!(edited, original);

    let mut steps = 0;
    while h.state().doc.undo_label().is_some() {
        press(&mut h, Modifiers::COMMAND, Key::Z);
        steps += 1;
        assert!(steps < 50, "undo terminates");
    }
    assert_eq!(steps, 4, "two keys, one TCB drag, one delete");
    assert_eq!(h.state().doc.scene(), &original);
    for _ in 0..steps {
        press(&mut h, Modifiers::COMMAND | Modifiers::SHIFT, Key::Z);
    }
    assert_eq!(h.state().doc.scene(), &edited);
}

#[test]
fn save_reopen_compare() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("arm.ron");
    keyrig_io::scene_file::save(&path, &keyrig_io::demo::demo_scene()).expect("write the demo scene");
    let mut h = harness(dir.path(), Some(path.clone()));
    assert_eq!(h.state().doc.title(), "keyrig — arm.ron");
    record_two_wrist_keys(&mut h);
    assert_eq!(h.state().doc.title(), "keyrig — arm.ron*");
    press(&mut h, Modifiers::COMMAND, Key::S);
    assert!(!h.state().doc.is_dirty(), "{:?}", h.state().status().cloned());
    assert_eq!(h.state().doc.title(), "keyrig — arm.ron");
    let saved = h.state().doc.scene().clone();

    let reopened = harness(dir.path(), Some(path));
    assert_eq!(reopened.state().doc.scene(), &saved);
    assert!(!reopened.state().doc.is_dirty());
}

#[test]
fn a_bad_file_is_an_error_in_the_status_bar_not_a_panic() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("broken.ron");
    std::fs::write(&path, "(version: 1, scene: (fps: NaN").expect("write");
    let h = harness(dir.path(), Some(path));
    let status = h.state().status().cloned().expect("an error is shown");
    assert!(status.is_error && status.text.contains("broken.ron"), "{status:?}");
    // The editor still opened (on the demo scene).
    assert!(!h.state().doc.scene().objects.is_empty());
}

#[test]
fn shortcuts_do_what_the_help_window_says() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    press(&mut h, Modifiers::NONE, Key::F12);
    assert!(h.state().view.show_help);
    // Every command is listed with its shortcut text.
    let ctx = h.ctx.clone();
    let window = egui::Rect::from_min_size(egui::Pos2::ZERO, egui::Vec2::from(common::WINDOW));
    for command in Command::ALL {
        let text = command.shortcut_text(&ctx);
        assert!(h.query_all_by_label(&text).next().is_some(), "help lists {text} for {command:?}");
        let explained = h.query_all_by_label(command.tooltip()).next();
        let explained = explained.unwrap_or_else(|| panic!("help explains {command:?}"));
        // Every line of the list is in the 1280×800 window, explanation included.
        assert!(
            window.contains_rect(explained.rect()),
            "{command:?}'s line is cut off: {:?}",
            explained.rect()
        );
    }
    press(&mut h, Modifiers::NONE, Key::Escape);
    assert!(!h.state().view.show_help);

    // Each shortcut runs its command.
    press(&mut h, Modifiers::NONE, Key::R);
    assert!(h.state().session.record);
    press(&mut h, Modifiers::NONE, Key::R);
    assert!(!h.state().session.record);
    let grid = h.state().view.grid;
    press(&mut h, Modifiers::NONE, Key::G);
    assert_eq!(h.state().view.grid, !grid);
    press(&mut h, Modifiers::NONE, Key::End);
    assert_eq!(h.state().session.playback.whole_frame(), h.state().doc.scene().frame_range.end);
    press(&mut h, Modifiers::NONE, Key::Home);
    assert_eq!(h.state().session.playback.whole_frame(), h.state().doc.scene().frame_range.start);
    press(&mut h, Modifiers::NONE, Key::ArrowRight);
    assert_eq!(h.state().session.playback.whole_frame(), 1);
    press(&mut h, Modifiers::NONE, Key::ArrowLeft);
    assert_eq!(h.state().session.playback.whole_frame(), 0);
    for (key, kind) in [
        (Key::Num1, keyrig_core::DeformerKind::Rigid),
        (Key::Num3, keyrig_core::DeformerKind::BonesBlending),
        (Key::Num4, keyrig_core::DeformerKind::DualQuaternion),
        (Key::Num2, keyrig_core::DeformerKind::LinearBlend),
    ] {
        press(&mut h, Modifiers::NONE, key);
        assert_eq!(h.state().doc.scene().objects[0].deformer.kind, kind);
    }
    // Space and Ctrl+P toggle playback (stop again so the harness settles).
    h.key_press(Key::Space);
    h.step();
    assert!(h.state().session.playback.playing);
    h.key_press(Key::Space);
    h.run();
    assert!(!h.state().session.playback.playing);
    h.key_press_modifiers(Modifiers::COMMAND, Key::P);
    h.step();
    assert!(h.state().session.playback.playing);
    h.key_press_modifiers(Modifiers::COMMAND, Key::P);
    h.run();
    assert!(!h.state().session.playback.playing);
    // Ctrl+N on a dirty document asks first; Discard goes ahead.
    assert!(h.state().doc.is_dirty(), "deformer switches are edits");
    press(&mut h, Modifiers::COMMAND, Key::N);
    assert!(h.state().pending().is_some());
    h.get_by_label("Discard changes").click();
    h.run();
    assert!(h.state().doc.scene().objects.is_empty(), "a new, empty scene");
    // Ctrl+Q on a clean document quits at once.
    press(&mut h, Modifiers::COMMAND, Key::Q);
    assert!(h.state().quit_confirmed());
}

#[test]
fn copy_paste_and_box_select_keys() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    select_elbow_key_15(&mut h);
    // Ctrl+C and Ctrl+V as egui-winit delivers them: copy and paste events, the paste
    // carrying the system clipboard's text (what the copy put there).
    h.event(egui::Event::Copy);
    h.step();
    let text = copied_text(&h).expect("the copy puts the keys on the system clipboard");
    h.run();
    go_to_frame(&mut h, 40);
    h.event(egui::Event::Paste(text));
    h.run();
    let elbow = ChannelId::JointRotation { object: 0, joint: 1 };
    let scene = h.state().doc.scene();
    assert!(channels::key_at(scene, elbow, 40.0 / scene.fps).is_some(), "pasted at frame 40");
    assert_eq!(channels::key_count(scene, elbow), 7);

    // Drag a box over the whole dope sheet: every key is selected.
    let first = h.get_by_label("key shoulder rotation frame 0").rect();
    let last = h.get_by_label("key Key intensity frame 90").rect();
    let start = first.left_top() - egui::vec2(4.0, 4.0);
    let end = last.right_bottom() + egui::vec2(4.0, 4.0);
    drag(&mut h, start, end);
    let scene = h.state().doc.scene();
    let all: Vec<(ChannelId, usize)> = ChannelId::all(scene)
        .into_iter()
        .flat_map(|id| (0..channels::key_count(scene, id)).map(move |i| (id, i)))
        .collect();
    let missed: Vec<_> = all
        .iter()
        .filter(|(id, i)| {
            !h.state()
                .session
                .selection
                .keys
                .contains(&keyrig_editor::session::KeyRef { channel: *id, index: *i })
        })
        .collect();
    assert!(missed.is_empty(), "box selection missed {missed:?}");
}

#[test]
fn dragging_a_key_diamond_moves_it_in_time_as_one_undo_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let elbow = ChannelId::JointRotation { object: 0, joint: 1 };
    let original = h.state().doc.scene().clone();
    let at_15 = h.get_by_label("key elbow rotation frame 15").rect().center();
    let at_30 = h.get_by_label("key elbow rotation frame 30").rect().center();
    let per_frame = (at_30.x - at_15.x) / 15.0;
    let target = at_15 + egui::vec2(per_frame * 5.0, 0.0);
    drag(&mut h, at_15, target);
    let scene = h.state().doc.scene();
    let frames: Vec<i64> =
        channels::key_times(scene, elbow).iter().map(|t| (t * scene.fps).round() as i64).collect();
    assert_eq!(frames, vec![0, 20, 30, 45, 75, 90]);
    // The moved key stays selected, and the whole drag is one undo step.
    let selected: Vec<_> = h.state().session.selection.keys.iter().copied().collect();
    assert_eq!(selected, vec![keyrig_editor::session::KeyRef { channel: elbow, index: 1 }]);
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(h.state().doc.scene(), &original);
}

/// A double click on a T/C/B slider (two presses and releases within egui's 0.3 s, as the
/// window system sends them) resets it to 0; typing into its number box applies once, on
/// Enter, as one undo step.
#[test]
fn double_click_resets_a_tcb_slider_and_its_number_box_commits_once() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let elbow = ChannelId::JointRotation { object: 0, joint: 1 };
    h.get_by_label("key elbow rotation frame 30").click();
    h.run();
    set_value(&mut h, Role::Slider, "Tension", 0.6);
    assert_eq!(channels::key_params(h.state().doc.scene(), elbow, 2).expect("key").2.tension, 0.6);
    assert_eq!(
        h.state().doc.undo_label(),
        Some("tension 0.60 on elbow rotation key at frame 30"),
        "the undo step says what changed"
    );

    let rail = h.get_by_role_and_label(Role::Slider, "Tension").rect();
    let at = egui::pos2(rail.left() + rail.width() * 0.3, rail.center().y);
    h.event(egui::Event::PointerMoved(at));
    h.run();
    for pressed in [true, false, true, false] {
        h.input_mut().events.push(egui::Event::PointerButton {
            pos: at,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: Modifiers::NONE,
        });
    }
    h.step();
    h.run();
    assert_eq!(
        channels::key_params(h.state().doc.scene(), elbow, 2).expect("key").2.tension,
        0.0,
        "reset to 0"
    );

    // The number box beside the slider: typed text applies on Enter, not per keystroke.
    let steps = h.state().doc.undo_len();
    let boxes: Vec<egui::Rect> = h
        .get_all_by_role(Role::SpinButton)
        .filter(|n| (n.rect().center().y - rail.center().y).abs() < rail.height())
        .map(|n| n.rect())
        .collect();
    let number_box = *boxes.first().expect("the slider's number box");
    h.event(egui::Event::PointerMoved(number_box.center()));
    for pressed in [true, false] {
        h.event(egui::Event::PointerButton {
            pos: number_box.center(),
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: Modifiers::NONE,
        });
    }
    h.run();
    h.key_press_modifiers(Modifiers::COMMAND, Key::A);
    h.run();
    for text in ["0", ".", "3"] {
        h.event(egui::Event::Text(text.to_owned()));
        h.run();
        assert_eq!(
            channels::key_params(h.state().doc.scene(), elbow, 2).expect("key").2.tension,
            0.0,
            "nothing applies while typing"
        );
    }
    press(&mut h, Modifiers::NONE, Key::Enter);
    let tension = channels::key_params(h.state().doc.scene(), elbow, 2).expect("key").2.tension;
    assert!((tension - 0.3).abs() < 1e-6, "Enter applies 0.3, got {tension}");
    assert_eq!(h.state().doc.undo_len(), steps + 1, "one undo step for the typed value");
}

/// Issue 42, 15: the undo history (Ctrl+Alt+Z) lists the start, every step and the steps
/// undone; a click on a row goes back to the state after it, a click on an undone (greyed) row
/// forward again, and the list follows.
#[test]
fn the_undo_history_lists_the_steps_and_a_click_goes_back_or_forward_to_one() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    // Two steps: a key on the wrist, then one on the elbow, at frame 10 in record mode.
    let elbow = ChannelId::JointRotation { object: 0, joint: 1 };
    let elbow_keys = channels::key_count(h.state().doc.scene(), elbow);
    h.get_by_label("wrist").click();
    h.run();
    press(&mut h, Modifiers::NONE, Key::R);
    go_to_frame(&mut h, 10);
    set_value(&mut h, Role::SpinButton, "Rotation (°) X", 45.0);
    h.get_by_label("elbow").click();
    h.run();
    set_value(&mut h, Role::SpinButton, "Rotation (°) X", 30.0);
    assert_eq!(h.state().doc.undo_len(), 2);
    let labels: Vec<String> = h.state().doc.undo_labels().map(str::to_owned).collect();
    assert_eq!(labels, ["key wrist rotation", "key elbow rotation"]);
    let keys = |h: &Harness<'_, EditorApp>| {
        let scene = h.state().doc.scene();
        (channels::key_count(scene, WRIST), channels::key_count(scene, elbow) - elbow_keys)
    };
    assert_eq!(keys(&h), (1, 1));
    assert!(h.query_by_label("Start of the history").is_none(), "closed at first");
    press(&mut h, Modifiers::COMMAND | Modifiers::ALT, Key::Z);
    assert!(h.state().view.show_undo_history, "Ctrl+Alt+Z opens it (and undoes nothing)");
    assert_eq!(h.state().doc.undo_len(), 2);
    assert!(h.query_by_label("Start of the history").is_some());
    for label in &labels {
        assert!(h.query_by_label(label).is_some(), "the step \"{label}\" is listed");
    }
    // Back to the start: both keys go.
    h.get_by_label("Start of the history").click();
    h.run();
    assert_eq!(h.state().doc.undo_len(), 0);
    assert_eq!(keys(&h), (0, 0), "back to no new key");
    // Forward to the first step: one key, and the second step is still there to redo.
    h.get_by_label(&labels[0]).click();
    h.run();
    assert_eq!(h.state().doc.undo_len(), 1);
    assert_eq!(keys(&h), (1, 0), "the wrist's key only");
    assert_eq!(h.state().doc.redo_labels().collect::<Vec<_>>(), [labels[1].as_str()]);
    h.get_by_label(&labels[1]).click();
    h.run();
    assert_eq!(h.state().doc.undo_len(), 2);
    assert_eq!(keys(&h), (1, 1), "both again");
    // The window closes with the same key.
    press(&mut h, Modifiers::COMMAND | Modifiers::ALT, Key::Z);
    assert!(!h.state().view.show_undo_history);
    assert!(h.query_by_label("Start of the history").is_none());
}
