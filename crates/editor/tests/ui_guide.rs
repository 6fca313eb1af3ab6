//! The walkthrough of docs/guide.md, performed on the real editor (GPU viewport through
//! eframe's wgpu path): key a twist on the wrist in record mode, shape it with T/C/B, compare
//! deformers; then key a full-turn forearm twist with the twist field on assets/twist.ron and
//! compare the deformers at 180° and 360°. Each step checks the document. With
//! `KEYRIG_WRITE_SCREENSHOTS=1` the tests also write the guide's screenshots to
//! docs/screenshots/.

mod common;

use common::{go_to_frame, gpu_harness, gpu_harness_for, press, set_value};

use egui::accesskit::Role;
use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use keyrig_core::DeformerKind;
use keyrig_edit::channels::{self, ChannelId};
use keyrig_editor::EditorApp;

const SIZE: [f32; 2] = [1280.0, 800.0];
/// Width of the screenshots in docs/ (scaled down from the window).
const SHOT_WIDTH: u32 = 960;
const WRIST: ChannelId = ChannelId::JointRotation { object: 0, joint: 3 };

/// Writes the window as docs/screenshots/<name>.png when asked to.
fn screenshot(h: &mut Harness<'_, EditorApp>, name: &str) {
    if std::env::var_os("KEYRIG_WRITE_SCREENSHOTS").is_none() {
        return;
    }
    let image = h.render().expect("render the editor");
    let height = (image.height() * SHOT_WIDTH) / image.width();
    let small = image::imageops::resize(&image, SHOT_WIDTH, height, image::imageops::FilterType::Triangle);
    let dir = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/screenshots");
    std::fs::create_dir_all(&dir).expect("create docs/screenshots");
    small.save(dir.join(format!("{name}.png"))).expect("write the screenshot");
}

fn wrist_x_degrees_at(h: &Harness<'_, EditorApp>, frame: f64) -> f32 {
    let scene = h.state().doc.scene();
    match keyrig_editor::eval::channel_value(scene, WRIST, frame / scene.fps, &Default::default()) {
        Some(channels::ChannelValue::Rotation(q)) => keyrig_editor::eval::euler_degrees(q).x,
        other => panic!("wrist rotation: {other:?}"),
    }
}

#[test]
fn guide_walkthrough_twist_with_record_mode_and_tcb() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = gpu_harness(dir.path(), SIZE);
    assert!(h.state().gpu().is_some());

    // The editor as it opens (README screenshot), at the demo's twist with bones blending.
    h.get_by_label("forearm").click();
    h.run();
    go_to_frame(&mut h, 55);
    screenshot(&mut h, "editor");

    // 1. Select the wrist and turn on record mode.
    h.get_by_label("wrist").click();
    h.run();
    press(&mut h, Modifiers::NONE, Key::R);
    assert!(h.state().session.record);

    // 2. Key a twist: 0° at frame 0, 90° at 20, 180° at 40, 90° at 60, 0° at 80 (consecutive
    //    keys under 180° apart, so each segment turns the short way the intended direction).
    //    At frame 0 the wrist is already at rest: I keys the current pose.
    go_to_frame(&mut h, 0);
    press(&mut h, Modifiers::NONE, Key::I);
    for (frame, degrees) in [(20, 90.0), (40, 180.0), (60, 90.0), (80, 0.0)] {
        go_to_frame(&mut h, frame);
        set_value(&mut h, Role::SpinButton, "Rotation (°) X", degrees);
    }
    let scene = h.state().doc.scene();
    let frames: Vec<i64> =
        channels::key_times(scene, WRIST).iter().map(|t| (t * scene.fps).round() as i64).collect();
    assert_eq!(frames, vec![0, 20, 40, 60, 80]);
    go_to_frame(&mut h, 30);
    screenshot(&mut h, "guide_record");
    press(&mut h, Modifiers::NONE, Key::R);
    assert!(!h.state().session.record);

    // 3. Shape the key at frame 40 with tension and bias; the curve view follows.
    h.get_by_label("key wrist rotation frame 40").click();
    h.run();
    let before = wrist_x_degrees_at(&h, 46.0);
    set_value(&mut h, Role::Slider, "Tension", -0.6);
    set_value(&mut h, Role::Slider, "Bias", 0.5);
    let after = wrist_x_degrees_at(&h, 46.0);
    assert!((after - before).abs() > 0.5, "T/B moved the curve: {before} → {after}");
    screenshot(&mut h, "guide_tcb");

    // 4. Compare deformers at the demo's 180° forearm twist: linear blend collapses.
    h.get_by_label("forearm").click();
    h.run();
    go_to_frame(&mut h, 60);
    press(&mut h, Modifiers::NONE, Key::Num2);
    let linear = h.state().skin_cache().cross_section(0, 2).expect("measured").expect("section").ratio();
    screenshot(&mut h, "guide_linear_blend");
    press(&mut h, Modifiers::NONE, Key::Num3);
    assert_eq!(h.state().doc.scene().objects[0].deformer.kind, DeformerKind::BonesBlending);
    let bones = h.state().skin_cache().cross_section(0, 2).expect("measured").expect("section").ratio();
    screenshot(&mut h, "guide_bones_blending");
    assert!(linear < 0.5 && bones > 0.9, "linear {linear}, bones blending {bones}");

    // 5. Help lists every shortcut.
    press(&mut h, Modifiers::NONE, Key::F12);
    assert!(h.state().view.show_help);
    screenshot(&mut h, "guide_help");
}

const FOREARM: ChannelId = ChannelId::JointRotation { object: 0, joint: 2 };

/// The forearm's cross-section relative to rest, as the viewport overlay shows it.
fn forearm_section(h: &Harness<'_, EditorApp>) -> f32 {
    h.state().skin_cache().cross_section(0, 2).expect("measured").expect("section").ratio()
}

/// docs/guide.md, "Keying a full-turn twist": assets/twist.ron's forearm turn keyed again with
/// record mode and the twist field, then the deformers at 180° (frame 30) and 360° (frame 60).
#[test]
fn guide_full_turn_twist_with_the_twist_field() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/twist.ron");
    let mut h = gpu_harness_for(dir.path(), SIZE, Some(file));
    let shipped = h.state().doc.scene().clone();
    let sample = |scene: &keyrig_core::Scene, frame: f64| match keyrig_editor::eval::channel_value(
        scene,
        FOREARM,
        frame / scene.fps,
        &Default::default(),
    ) {
        Some(channels::ChannelValue::Rotation(q)) => q,
        other => panic!("forearm rotation: {other:?}"),
    };

    // 1. Select the forearm and delete its two keys (click the first diamond, Shift-click the
    //    second, Delete).
    h.get_by_label("forearm").click();
    h.run();
    h.get_by_label("key forearm rotation frame 0").click();
    h.run();
    h.get_by_label("key forearm rotation frame 60").click_modifiers(Modifiers::SHIFT);
    h.run();
    press(&mut h, Modifiers::NONE, Key::Delete);
    assert_eq!(channels::key_count(h.state().doc.scene(), FOREARM), 0);

    // 2. Record mode; frame 0: key the rest pose with I; frame 60 (End): type 360 in Twist.
    press(&mut h, Modifiers::NONE, Key::R);
    press(&mut h, Modifiers::NONE, Key::Home);
    press(&mut h, Modifiers::NONE, Key::I);
    press(&mut h, Modifiers::NONE, Key::End);
    set_value(&mut h, Role::SpinButton, "Twist (°)", 360.0);
    press(&mut h, Modifiers::NONE, Key::R);
    let scene = h.state().doc.scene();
    let frames: Vec<i64> =
        channels::key_times(scene, FOREARM).iter().map(|t| (t * scene.fps).round() as i64).collect();
    assert_eq!(frames, vec![0, 60]);
    let keys = &scene.objects[0].skeleton.as_ref().expect("skeleton").joints[2].rotation.track.keys;
    match keys[1].spin {
        Some(keyrig_core::Spin::Angle { axis, degrees }) => {
            assert!(axis == glam::Vec3::X && (degrees - 360.0).abs() < 1e-3, "{axis:?} {degrees}");
        }
        other => panic!("the key at frame 60 turns a whole turn, has {other:?}"),
    }
    // The same motion as the shipped file at every frame.
    for frame in 0..=60 {
        let (a, b) = (sample(&shipped, f64::from(frame)), sample(scene, f64::from(frame)));
        assert!(a.angle_between(b) < 1e-3, "frame {frame}: {a:?} vs {b:?}");
    }
    go_to_frame(&mut h, 30);
    screenshot(&mut h, "guide_twist_record");

    // 3. The deformers at 180° (frame 30) and 360° (frame 60).
    press(&mut h, Modifiers::NONE, Key::Num2);
    let linear_180 = forearm_section(&h);
    screenshot(&mut h, "guide_twist_linear_180");
    press(&mut h, Modifiers::NONE, Key::Num3);
    let bones_180 = forearm_section(&h);
    screenshot(&mut h, "guide_twist_bones_180");
    press(&mut h, Modifiers::NONE, Key::Num4);
    assert_eq!(h.state().doc.scene().objects[0].deformer.kind, DeformerKind::DualQuaternion);
    let dq_180 = forearm_section(&h);
    screenshot(&mut h, "guide_twist_dq_180");
    press(&mut h, Modifiers::NONE, Key::End);
    let dq_360 = forearm_section(&h);
    screenshot(&mut h, "guide_twist_dq_360");
    press(&mut h, Modifiers::NONE, Key::Num3);
    let bones_360 = forearm_section(&h);
    screenshot(&mut h, "guide_twist_bones_360");
    press(&mut h, Modifiers::NONE, Key::Num2);
    let linear_360 = forearm_section(&h);
    eprintln!(
        "cross-sections: 180° linear {linear_180:.2} bones {bones_180:.2} dq {dq_180:.2}; \
         360° bones {bones_360:.2} dq {dq_360:.2} linear {linear_360:.2}"
    );
    assert!(linear_180 < 0.5, "linear blend collapses at 180°: {linear_180}");
    assert!(bones_180 > 0.9 && dq_180 > 0.7, "bones {bones_180}, dq {dq_180}");
    assert!(bones_360 > 0.9 && dq_360 > 0.9, "bones {bones_360}, dq {dq_360}");
}

/// docs/guide.md, "Onion skinning": the forearm selected at frame 45, O shows two ghosts of
/// the arm before and two after.
#[test]
fn guide_onion_skin() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = gpu_harness(dir.path(), SIZE);
    h.get_by_label("forearm").click();
    h.run();
    go_to_frame(&mut h, 45);
    let calls =
        |h: &Harness<'_, EditorApp>| h.state().gpu().and_then(|g| g.last_stats).expect("drawn").draw_calls;
    let before = calls(&h);
    press(&mut h, Modifiers::NONE, Key::O);
    assert_eq!(calls(&h), before + 4, "two ghosts before and two after");
    // The guide's picture of this step is taken in the real window (e2e_xdotool.rs).
}
