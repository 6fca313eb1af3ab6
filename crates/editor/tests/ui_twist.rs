//! The inspector's twist field and the curve view on spin keys (issue 14, part 3): the field
//! edits a joint's twist about its bone axis in degrees, counting turns (it reads 720), record
//! mode keys the typed turn as a spin, and the curve view shows the unwrapped turn.

mod common;

use common::{go_to_frame, harness, press, set_value};

use egui::accesskit::Role;
use egui::{Key, Modifiers};
use egui_kittest::kittest::{NodeT, Queryable};
use egui_kittest::Harness;
use keyrig_core::Spin;
use keyrig_edit::channels::{self, ChannelId};
use keyrig_editor::EditorApp;

const WRIST: ChannelId = ChannelId::JointRotation { object: 0, joint: 3 };
const FOREARM: ChannelId = ChannelId::JointRotation { object: 0, joint: 2 };

/// What the twist field shows, read through AccessKit as a screen reader would.
fn twist_field(h: &Harness<'_, EditorApp>) -> f64 {
    h.get_by_role_and_label(Role::SpinButton, "Twist (°)")
        .accesskit_node()
        .numeric_value()
        .expect("the twist field has a value")
}

fn spins(app: &EditorApp, joint: usize) -> Vec<Option<Spin>> {
    let skeleton = app.doc.scene().objects[0].skeleton.as_ref().expect("a skeleton");
    skeleton.joints[joint].rotation.track.keys.iter().map(|k| k.spin).collect()
}

fn twist_ron() -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/twist.ron")
}

#[test]
fn the_twist_field_reads_the_turns_of_twist_ron() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), Some(twist_ron()));
    h.get_by_label("forearm").click();
    h.run();
    for (frame, expected) in [(0, 0.0), (30, 180.0), (60, 360.0)] {
        go_to_frame(&mut h, frame);
        let shown = twist_field(&h);
        assert!((shown - expected).abs() < 0.05, "frame {frame}: the field reads {shown}, not {expected}");
    }
    // The curve view's fourth curve is the unwrapped turn: 0 → 360 without wrapping.
    let curves = h.state().sample_curves(FOREARM, 0.0, 60.0, 61);
    assert_eq!(curves.len(), 4, "X, Y, Z and the unwrapped turn");
    let turn = &curves[3];
    assert!(turn.windows(2).all(|w| w[1].1 >= w[0].1 - 1e-4), "monotonic: {turn:?}");
    assert!(
        (turn[30].1 - 180.0).abs() < 0.05 && (turn[60].1 - 360.0).abs() < 0.05,
        "{:?}",
        (turn[30], turn[60])
    );
}

#[test]
fn typing_720_in_record_mode_keys_two_turns() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("wrist").click();
    h.run();
    press(&mut h, Modifiers::NONE, Key::R);
    go_to_frame(&mut h, 0);
    press(&mut h, Modifiers::NONE, Key::I);
    go_to_frame(&mut h, 40);
    set_value(&mut h, Role::SpinButton, "Twist (°)", 720.0);

    let scene = h.state().doc.scene();
    let frames: Vec<i64> =
        channels::key_times(scene, WRIST).iter().map(|t| (t * scene.fps).round() as i64).collect();
    assert_eq!(frames, vec![0, 40]);
    match spins(h.state(), 3)[1] {
        Some(Spin::Angle { axis, degrees }) => {
            assert!((axis - glam::Vec3::X).length() < 1e-5, "about the bone axis: {axis:?}");
            assert!((degrees - 720.0).abs() < 1e-3, "{degrees}");
        }
        other => panic!("the key at frame 40 should turn two turns, has {other:?}"),
    }
    assert!((twist_field(&h) - 720.0).abs() < 0.05);
    go_to_frame(&mut h, 20);
    assert!((twist_field(&h) - 360.0).abs() < 0.5, "half way: {}", twist_field(&h));

    // Typing −90 at frame 40 makes the segment the short way (no spin).
    go_to_frame(&mut h, 40);
    set_value(&mut h, Role::SpinButton, "Twist (°)", -90.0);
    assert_eq!(spins(h.state(), 3), vec![None, None]);
    assert!((twist_field(&h) + 90.0).abs() < 0.05);

    // The Euler angles name their rotation order: the joint's rotation mode, XYZ by default.
    h.get_by_label("Rotation mode");
    let joint = &h.state().doc.scene().objects[0].skeleton.as_ref().expect("a skeleton").joints[3];
    assert_eq!(joint.rotation_mode.euler(), Some(keyrig_core::EulerOrder::XYZ));
}

/// Issue 42, item 8: the field showed "1 turn" beside 719°. The readout beside it names the
/// whole turns and the rest, so both say the same angle.
#[test]
fn the_turns_beside_the_twist_field_agree_with_its_degrees() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("wrist").click();
    h.run();
    press(&mut h, Modifiers::NONE, Key::R);
    go_to_frame(&mut h, 0);
    press(&mut h, Modifiers::NONE, Key::I);
    go_to_frame(&mut h, 40);
    for (degrees, readout) in [(719.0, "1 turn + 359°"), (720.0, "2 turns"), (400.0, "1 turn + 40°")] {
        set_value(&mut h, Role::SpinButton, "Twist (°)", degrees);
        assert!((twist_field(&h) - degrees).abs() < 0.05, "the field reads {}", twist_field(&h));
        assert!(h.query_by_label(readout).is_some(), "{degrees}°: \"{readout}\" beside the field");
    }
    set_value(&mut h, Role::SpinButton, "Twist (°)", 719.0);
    assert!(h.query_by_label("1 turn").is_none(), "no bare \"1 turn\" beside 719°");
}
