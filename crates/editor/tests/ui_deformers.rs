//! Switching deformers from the keyboard and the menu while the twist plays: the skinned
//! output changes, and the cross-section measure beside the viewport shows the candy wrapper.

mod common;

use common::{harness, press};

use egui::accesskit::Role;
use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use glam::Vec3;
use keyrig_core::DeformerKind;
use keyrig_editor::session::Selected;
use keyrig_editor::EditorApp;

/// The arm's deformed positions (object space) and the forearm's cross-section ratio.
fn skinned(h: &Harness<'_, EditorApp>) -> (Vec<Vec3>, f32) {
    let app = h.state();
    let positions = app.skin_cache().deformed_positions(0).expect("the arm is skinned").to_vec();
    let ratio = app.skin_cache().cross_section(0, 2).expect("measured").expect("a cross-section").ratio();
    (positions, ratio)
}

#[test]
fn switching_deformer_changes_the_skinned_arm_and_the_measure() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("forearm").click();
    h.run();
    assert_eq!(h.state().session.selection.item, Some(Selected::Joint { object: 0, joint: 2 }));
    // Frame 60: the forearm joint is twisted 180° in the demo.
    press(&mut h, Modifiers::NONE, Key::Home);
    for _ in 0..60 {
        press(&mut h, Modifiers::NONE, Key::ArrowRight);
    }

    press(&mut h, Modifiers::NONE, Key::Num2);
    assert_eq!(h.state().doc.scene().objects[0].deformer.kind, DeformerKind::LinearBlend);
    let (linear, linear_ratio) = skinned(&h);
    press(&mut h, Modifiers::NONE, Key::Num3);
    assert_eq!(h.state().doc.scene().objects[0].deformer.kind, DeformerKind::BonesBlending);
    let (bones, bones_ratio) = skinned(&h);
    press(&mut h, Modifiers::NONE, Key::Num4);
    let (dual, dual_ratio) = skinned(&h);
    press(&mut h, Modifiers::NONE, Key::Num1);
    let (rigid, _) = skinned(&h);

    let max_diff = |a: &[Vec3], b: &[Vec3]| a.iter().zip(b).map(|(p, q)| p.distance(*q)).fold(0.0, f32::max);
    for (name, other) in [("bones blending", &bones), ("dual quaternion", &dual), ("rigid", &rigid)] {
        assert!(max_diff(&linear, other) > 0.01, "{name} differs from linear blend");
    }
    // The candy wrapper: linear blending collapses the twisted joint, the others keep it.
    assert!(linear_ratio < 0.5, "linear blend at a 180° twist: {linear_ratio}");
    assert!(bones_ratio > 0.9, "bones blending keeps the cross-section: {bones_ratio}");
    assert!(dual_ratio > 0.5, "dual quaternion keeps more than linear: {dual_ratio}");

    // The measure is shown beside the viewport (in the inspector) as text.
    let shown = format!(
        "Cross-section at forearm: {:.2} × rest",
        h.state().skin_cache().cross_section(0, 2).expect("m").expect("m").ratio()
    );
    assert!(h.query_by_label(&shown).is_some(), "inspector shows {shown}");
}

#[test]
fn the_deformer_menu_switches_while_playing() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.key_press(Key::Space);
    h.step();
    assert!(h.state().session.playback.playing);
    h.get_by_role_and_label(Role::Button, "Deformer").click();
    h.step();
    // A menu item's accessible label is its text followed by its shortcut.
    h.get_by_label("Dual quaternion 4").click();
    h.step();
    h.step();
    assert_eq!(h.state().doc.scene().objects[0].deformer.kind, DeformerKind::DualQuaternion);
    assert!(h.state().session.playback.playing, "playback continues while switching");
    h.key_press(Key::Space);
    h.run();
    assert!(!h.state().session.playback.playing);
}

/// Issue 42, 7: with the deformer keyed (Linear blend, Step keys) while the Arm's setting is
/// Bones blending, the toolbar and the Deformer menu highlight the deformer in effect — the one
/// the viewport's overlay names and the frame is drawn with — not the setting.
#[test]
fn the_toolbar_highlights_the_deformer_in_effect() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut scene = keyrig_io::demo::demo_scene();
    assert_eq!(scene.objects[0].deformer.kind, DeformerKind::BonesBlending);
    let linear = keyrig_core::channel_id::attribute_id::deformer_value(DeformerKind::LinearBlend);
    scene.objects[0].attributes.deformer = Some(keyrig_core::Animated::new(
        linear,
        keyrig_core::RawTrack::new(vec![
            keyrig_core::Key::new(0.0, linear).with_interpolation(keyrig_core::Interpolation::Step),
            keyrig_core::Key::new(3.0, linear).with_interpolation(keyrig_core::Interpolation::Step),
        ]),
    ));
    let path = dir.path().join("keyed.ron");
    keyrig_io::save(&path, &scene).expect("save");
    let mut h = harness(dir.path(), Some(path));
    h.run();
    assert_eq!(h.state().current_deformer(), Some(DeformerKind::LinearBlend), "the keyed deformer in effect");
    // The toolbar and the Deformer menu show what `current_deformer` says (one function).
    h.state_mut().doc.edit("unkey", |s| s.objects[0].attributes.deformer = None);
    h.run();
    assert_eq!(h.state().current_deformer(), Some(DeformerKind::BonesBlending), "the setting without keys");
}
