//! The curve editor used with real pointer, wheel and key events: keys dragged in value and in
//! time (one undo step per drag), box selection, scrubbing on the frame ruler, zoom and Fit,
//! F over the curves framing the selected keys, a colour and legend entry per curve.

mod common;

use common::{drag, harness, press};

use egui::{Event, Key, Modifiers, MouseWheelUnit, Pos2};
use egui_kittest::kittest::{NodeT, Queryable};
use egui_kittest::Harness;
use keyrig_edit::channels::{self, ChannelId, ChannelValue};
use keyrig_editor::eval::euler_degrees;
use keyrig_editor::EditorApp;

const ELBOW: ChannelId = ChannelId::JointRotation { object: 0, joint: 1 };

fn elbow_x_at_key(h: &Harness<'_, EditorApp>, index: usize) -> f32 {
    match channels::key_value(h.state().doc.scene(), ELBOW, index) {
        Some(ChannelValue::Rotation(q)) => euler_degrees(q).x,
        other => panic!("a rotation key, got {other:?}"),
    }
}

fn elbow_x_at_key_of(scene: &keyrig_core::Scene, index: usize) -> f32 {
    match channels::key_value(scene, ELBOW, index) {
        Some(ChannelValue::Rotation(q)) => euler_degrees(q).x,
        other => panic!("a rotation key, got {other:?}"),
    }
}

/// A right click in the middle of the curve view, as the mouse gives it: its context menu.
fn open_context_menu(h: &mut Harness<'_, EditorApp>) {
    let plot = h.state().curves_rect().expect("the curve view is laid out");
    h.event(Event::PointerMoved(plot.center()));
    for pressed in [true, false] {
        h.event(Event::PointerButton {
            pos: plot.center(),
            button: egui::PointerButton::Secondary,
            pressed,
            modifiers: Modifiers::NONE,
        });
    }
    h.run();
}

fn frames(h: &Harness<'_, EditorApp>) -> Vec<i64> {
    let scene = h.state().doc.scene();
    channels::key_times(scene, ELBOW).iter().map(|t| (t * scene.fps).round() as i64).collect()
}

/// The demo with the elbow's key at frame 30 selected (dope sheet click): its curves show.
fn with_elbow_key() -> (tempfile::TempDir, Harness<'static, EditorApp>) {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("key elbow rotation frame 30").click();
    h.run();
    (dir, h)
}

#[test]
fn dragging_a_curve_key_changes_its_value_then_its_time_one_undo_step_each() {
    let (_dir, mut h) = with_elbow_key();
    let original = h.state().doc.scene().clone();
    // The key at frame 15 (the elbow bent 45° about −Z).
    let x_before = elbow_x_at_key(&h, 1);
    let key = h.get_by_label("curve key elbow rotation X frame 15").rect().center();
    // Up by 40 points: the X angle grows, the key stays at frame 15.
    drag(&mut h, key, key + egui::vec2(0.0, -40.0));
    let x_after = elbow_x_at_key(&h, 1);
    assert!(x_after > x_before + 1.0, "X {x_before} → {x_after}");
    assert_eq!(frames(&h), [0, 15, 30, 45, 75, 90]);
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(h.state().doc.scene(), &original, "the value drag is one undo step");

    // Sideways by five frames (measured on the curve's own keys): time only.
    let at_30 = h.get_by_label("curve key elbow rotation X frame 30").rect().center();
    let at_45 = h.get_by_label("curve key elbow rotation X frame 45").rect().center();
    let per_frame = (at_45.x - at_30.x) / 15.0;
    drag(&mut h, at_30, at_30 + egui::vec2(per_frame * 5.0, 0.0));
    assert_eq!(frames(&h), [0, 15, 35, 45, 75, 90]);
    assert!(
        (elbow_x_at_key(&h, 2) - elbow_x_at_key_of(&original, 2)).abs() < 1e-3,
        "a level drag leaves the value"
    );
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(h.state().doc.scene(), &original, "the time drag is one undo step");
}

#[test]
fn box_selection_ruler_scrub_zoom_home_and_f() {
    let (_dir, mut h) = with_elbow_key();
    let k15 = h.get_by_label("curve key elbow rotation X frame 15").rect();
    let k45 = h.get_by_label("curve key elbow rotation X frame 45").rect();
    // A box from left of frame 15 to right of frame 45, over the whole height of the keys.
    let top = k15.top().min(k45.top()) - 60.0;
    let bottom = k15.bottom().max(k45.bottom()) + 60.0;
    let plot = h.state().curves_rect().expect("the curve view is laid out");
    let (top, bottom) = (top.max(plot.top() + 8.0), bottom.min(plot.bottom() - 20.0));
    drag(&mut h, Pos2::new(k15.left() - 3.0, top), Pos2::new(k45.right() + 3.0, bottom));
    let selected: Vec<usize> =
        h.state().session.selection.keys.iter().filter(|k| k.channel == ELBOW).map(|k| k.index).collect();
    assert_eq!(selected, [1, 2, 3], "frames 15, 30 and 45");

    // The frame ruler under the plot scrubs.
    let at_45 = k45.center();
    let ruler = Pos2::new(at_45.x, plot.bottom() - 6.0);
    h.event(Event::PointerMoved(ruler));
    for pressed in [true, false] {
        h.event(Event::PointerButton {
            pos: ruler,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: Modifiers::NONE,
        });
    }
    h.run();
    assert_eq!(h.state().session.playback.whole_frame(), 45);

    // The wheel zooms about the pointer; Home fits everything again.
    let centre = plot.center();
    h.event(Event::PointerMoved(centre));
    h.event(Event::MouseWheel {
        unit: MouseWheelUnit::Line,
        delta: egui::vec2(0.0, 3.0),
        modifiers: Modifiers::NONE,
        phase: egui::TouchPhase::Move,
    });
    h.run();
    let zoomed = h.state().panels().curves.view.expect("a zoomed view");
    assert!(zoomed.end - zoomed.start < 90.0, "{zoomed:?}");
    h.get_by_label("Fit").click();
    h.run();
    assert_eq!(h.state().panels().curves.view, None, "Fit shows the range and values");

    // F over the curves frames the selected keys (15–45), not the viewport.
    let camera = h.state().view.camera;
    h.event(Event::PointerMoved(centre));
    press(&mut h, Modifiers::NONE, Key::F);
    let framed = h.state().panels().curves.view.expect("framed");
    assert!(
        framed.start > 5.0 && framed.start < 15.0 && framed.end > 45.0 && framed.end < 60.0,
        "{framed:?}"
    );
    assert_eq!(h.state().view.camera, camera, "the viewport's camera stays");
}

#[test]
fn every_curve_has_its_own_colour_and_a_legend_entry() {
    let (_dir, mut h) = with_elbow_key();
    // Add the shoulder's key at frame 45: two rotation channels, six curves.
    h.get_by_label("key shoulder rotation frame 45").click_modifiers(Modifiers::SHIFT);
    h.run();
    for name in ["elbow rotation X", "elbow rotation Y", "elbow rotation Z", "shoulder rotation X"] {
        assert!(h.query_by_label(name).is_some(), "legend entry {name}");
    }
    assert!(h.query_by_label("Curves: 2 channels").is_some());
}

/// The curve view's context menu sets the interpolation of the selected keys in one undo step;
/// "TCB spline, clamped" keeps the elbow's held 90° (frames 30 and 45) from dipping between
/// its keys.
#[test]
fn the_context_menu_clamps_the_selected_keys() {
    let (_dir, mut h) = with_elbow_key();
    h.get_by_label("key elbow rotation frame 45").click_modifiers(Modifiers::SHIFT);
    h.run();
    let steps = h.state().doc.undo_len();
    open_context_menu(&mut h);
    h.get_by_label("TCB spline, clamped").click();
    h.run();
    let scene = h.state().doc.scene();
    for index in [2, 3] {
        let (_, mode, tcb) = channels::key_params(scene, ELBOW, index).expect("key");
        assert_eq!(mode, keyrig_core::Interpolation::Tcb);
        assert!(tcb.clamped, "key {index} clamped");
    }
    assert_eq!(h.state().doc.undo_len(), steps + 1, "one undo step");
    assert_eq!(h.state().doc.undo_label(), Some("interpolation Tcb, clamped on 2 keys"));
}

/// The curve view's context menu sets the selected keys' type too (the dope sheet's menu):
/// both selected keys become extremes in one undo step, named by what it changed.
#[test]
fn the_context_menu_sets_the_selected_keys_type() {
    let (_dir, mut h) = with_elbow_key();
    h.get_by_label("key elbow rotation frame 45").click_modifiers(Modifiers::SHIFT);
    h.run();
    let steps = h.state().doc.undo_len();
    open_context_menu(&mut h);
    h.get_by_label("Extreme").click();
    h.run();
    let scene = h.state().doc.scene();
    for index in [2, 3] {
        assert_eq!(
            channels::key_type(scene, ELBOW, index),
            Some(keyrig_core::KeyType::Extreme),
            "key {index}"
        );
    }
    assert_eq!(channels::key_type(scene, ELBOW, 1), Some(keyrig_core::KeyType::Keyframe), "not selected");
    assert_eq!(h.state().doc.undo_len(), steps + 1, "one undo step");
    assert_eq!(h.state().doc.undo_label(), Some("key type Extreme on 2 keys"));
}

/// "Hermite handles" turns a TCB key into explicit tangents without changing the curve; its
/// handles then shape the curve, one undo step per drag.
#[test]
fn hermite_handles_keep_the_shape_and_then_shape_the_curve() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let cube = ChannelId::ObjectTranslation(1);
    h.get_by_label("key Cube translation frame 30").click();
    h.run();
    let sample = |h: &Harness<'_, EditorApp>| -> Vec<glam::Vec3> {
        let scene = h.state().doc.scene();
        (0..=90)
            .map(|f| {
                match keyrig_editor::eval::channel_value(
                    scene,
                    cube,
                    f64::from(f) / scene.fps,
                    &Default::default(),
                ) {
                    Some(ChannelValue::Vec3(v)) => v,
                    other => panic!("a position, got {other:?}"),
                }
            })
            .collect()
    };
    let before = sample(&h);
    open_context_menu(&mut h);
    h.get_by_label("Hermite handles (keeps the shape)").click();
    h.run();
    let (_, mode, _) = channels::key_params(h.state().doc.scene(), cube, 1).expect("key");
    assert_eq!(mode, keyrig_core::Interpolation::Hermite);
    let after = sample(&h);
    for (f, (a, b)) in before.iter().zip(&after).enumerate() {
        assert!((*a - *b).length() < 1e-4, "frame {f}: {a} became {b}");
    }

    // Drag the key's outgoing Y handle up: the curve after the key rises, one undo step.
    let steps = h.state().doc.undo_len();
    let handle = h.get_by_label("out handle Cube translation Y key 1").rect().center();
    drag(&mut h, handle, handle + egui::vec2(0.0, -30.0));
    let (_, out) = channels::key_tangents(h.state().doc.scene(), cube, 1);
    assert!(out.is_some(), "the key keeps an out-tangent");
    let shaped = sample(&h);
    let later = (31..45).any(|f| shaped[f].y > after[f].y + 1e-3);
    assert!(later, "the curve after frame 30 rises with the handle");
    assert_eq!(h.state().doc.undo_len(), steps + 1, "one undo step for the handle drag");
}

/// "Twist about X" draws a rotation as one curve, its unwrapped twist about the bone axis: the
/// demo forearm's half turn climbs to 180° (Euler X would read the same here, but a twist
/// past a half turn keeps climbing instead of wrapping).
#[test]
fn rotations_can_be_drawn_as_their_twist() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let forearm = ChannelId::JointRotation { object: 0, joint: 2 };
    h.get_by_label("key forearm rotation frame 60").click();
    h.run();
    assert_eq!(h.state().sample_curves(forearm, 0.0, 90.0, 91).len(), 3);
    h.get_by_label("Twist about X").click();
    h.run();
    assert!(h.state().panels().curves.rotation_as_twist);
    assert!(h.query_by_label("forearm rotation twist").is_some(), "the legend names the twist curve");
    let curves = h.state().sample_curves(forearm, 0.0, 90.0, 91);
    assert_eq!(curves.len(), 1, "one curve: the twist");
    let peak = curves[0].iter().map(|&(_, v)| v.abs()).fold(0.0f32, f32::max);
    assert!((peak - 180.0).abs() < 0.5, "the twist peaks at a half turn: {peak}");
    assert!(curves[0].windows(2).all(|w| (w[1].1 - w[0].1).abs() < 20.0), "continuous");
}

/// A over the curves selects every key shown, Alt+A none, as in Blender's graph editor.
#[test]
fn a_and_alt_a_over_the_curves_select_all_and_none() {
    let (_dir, mut h) = with_elbow_key();
    let plot = h.state().curves_rect().expect("laid out");
    h.event(Event::PointerMoved(plot.center()));
    press(&mut h, Modifiers::NONE, Key::A);
    let count = channels::key_count(h.state().doc.scene(), ELBOW);
    assert_eq!(h.state().session.selection.keys.len(), count, "every elbow key");
    h.event(Event::PointerMoved(plot.center()));
    press(&mut h, Modifiers::ALT, Key::A);
    assert!(h.state().session.selection.keys.is_empty());
}

/// What an inspector field shows, read through AccessKit as a screen reader would.
fn field(h: &Harness<'_, EditorApp>, label: &str) -> f64 {
    h.get_by_role_and_label(egui::accesskit::Role::SpinButton, label)
        .accesskit_node()
        .numeric_value()
        .unwrap_or_else(|| panic!("{label} has a value"))
}

/// The demo's Cube spins once about Y (keys at 0°, 120°, 240°, 360°): the inspector and the
/// curves read Y climbing 0 → 360 with X and Z at 0, not X and Z flipping to 180 while Y bounces
/// between ±90 (issue 30). The stored keys and their interpolation stay as they were.
#[test]
fn a_spin_about_y_reads_y_0_to_360_in_the_inspector_and_the_curves() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let keys_before = h.state().doc.scene().objects[1].rotation.clone();
    h.get_by_label("Cube").click();
    h.run();
    for (frame, y) in [(0, 0.0), (20, 80.0), (45, 180.0), (60, 240.0), (75, 300.0), (89, 356.0)] {
        common::go_to_frame(&mut h, frame);
        let (x, got, z) =
            (field(&h, "Rotation (°) X"), field(&h, "Rotation (°) Y"), field(&h, "Rotation (°) Z"));
        assert!((got - y).abs() < 0.05, "frame {frame}: Y reads {got}, not {y}");
        assert!(x.abs() < 0.05 && z.abs() < 0.05, "frame {frame}: X {x}, Z {z} stay 0");
    }
    let curves = h.state().sample_curves(ChannelId::ObjectRotation(1), 0.0, 90.0, 181);
    assert_eq!(curves.len(), 3, "X, Y, Z");
    for (i, &(frame, y)) in curves[1].iter().enumerate() {
        assert!((y - frame as f32 * 4.0).abs() < 0.05, "Y at frame {frame} reads {y}");
        assert!(curves[0][i].1.abs() < 0.05 && curves[2][i].1.abs() < 0.05, "X and Z at frame {frame}");
    }
    assert_eq!(h.state().doc.scene().objects[1].rotation, keys_before, "reading changes no key");
}

/// The rotation mode chosen in the inspector (one undo step) changes what the fields and the
/// curves read: a ZYX order reads the same spin the same way, a quaternion shows W X Y Z.
#[test]
fn the_rotation_mode_changes_what_the_inspector_and_the_curves_read() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("Cube").click();
    h.run();
    common::go_to_frame(&mut h, 60);
    let undo = h.state().doc.undo_len();
    h.get_by_label("Rotation mode").click();
    h.run();
    h.get_by_label("Quaternion (WXYZ)").click();
    h.run();
    assert_eq!(h.state().doc.scene().objects[1].rotation_mode, keyrig_core::RotationMode::Quaternion);
    assert_eq!(h.state().doc.undo_len(), undo + 1);
    // 240° about Y: w = cos 120°, y = sin 120°.
    let (w, y) = (field(&h, "Rotation (°) W"), field(&h, "Rotation (°) Y"));
    let half = 120f64.to_radians();
    assert!((w.abs() - half.cos().abs()).abs() < 1e-3 && (y.abs() - half.sin()).abs() < 1e-3, "w {w} y {y}");
    let curves = h.state().sample_curves(ChannelId::ObjectRotation(1), 0.0, 90.0, 91);
    assert_eq!(curves.len(), 4, "W, X, Y, Z");
    // Continuous: the quaternion stays on one hemisphere, so w runs 1 → −1 smoothly.
    for pair in curves[0].windows(2) {
        assert!(
            (pair[1].1 - pair[0].1).abs() < 0.1,
            "w jumps between frames {} and {}",
            pair[0].0,
            pair[1].0
        );
    }
    h.get_by_label("Rotation mode").click();
    h.run();
    h.get_by_label("ZYX Euler").click();
    h.run();
    let y = field(&h, "Rotation (°) Y");
    assert!((y - 240.0).abs() < 0.05, "ZYX reads the spin as Y 240, got {y}");
    // Typing X = 30 in ZYX order: R = Rx(30)·Ry(240) (X turns last), checked on the matrices.
    common::set_value(&mut h, egui::accesskit::Role::SpinButton, "Rotation (°) X", 30.0);
    let Some(ChannelValue::Rotation(q)) = h.state().value_now(ChannelId::ObjectRotation(1)) else {
        panic!("a rotation")
    };
    let expected =
        glam::Mat3::from_rotation_x(30f32.to_radians()) * glam::Mat3::from_rotation_y(240f32.to_radians());
    let got = glam::Mat3::from_quat(q);
    let diff = (expected - got).to_cols_array().iter().fold(0.0f32, |m, d| m.max(d.abs()));
    assert!(diff < 1e-4, "{expected:?} vs {got:?}");
}

/// Vertical span (points) of the drawn keys of one curve.
fn key_span(h: &Harness<'_, EditorApp>, curve: &str, frames: &[i32]) -> f32 {
    let ys: Vec<f32> = frames
        .iter()
        .map(|f| h.get_by_label(&format!("curve key {curve} frame {f}")).rect().center().y)
        .collect();
    ys.iter().fold(f32::NEG_INFINITY, |a, &b| a.max(b)) - ys.iter().fold(f32::INFINITY, |a, &b| a.min(b))
}

/// Clicks a widget found by label with `modifiers` held, as the mouse does.
fn click_with(h: &mut Harness<'_, EditorApp>, label: &str, modifiers: Modifiers) {
    let at = h.get_by_label(label).rect().center();
    h.input_mut().modifiers = modifiers;
    h.event(Event::PointerMoved(at));
    for pressed in [true, false] {
        h.event(Event::PointerButton { pos: at, button: egui::PointerButton::Primary, pressed, modifiers });
    }
    h.run();
    h.input_mut().modifiers = Modifiers::NONE;
    h.run();
}

/// The Cube's translation (±1) and rotation (0 … 360) in one view: a legend click hides a
/// curve, Ctrl+click shows one alone and again shows all, Normalize scales each curve to its
/// own −1 … 1 so the small one is no longer a flat line.
#[test]
fn legend_clicks_hide_and_solo_curves_and_normalize_scales_each_curve() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("Cube").click();
    h.run();
    let frames = [0, 30, 60, 75, 90];
    assert!(h.query_by_label("curve key Cube translation X frame 30").is_some());
    click_with(&mut h, "Cube translation X", Modifiers::NONE);
    assert!(h.query_by_label("curve key Cube translation X frame 30").is_none(), "X hidden");
    assert!(h.query_by_label("curve key Cube translation Y frame 30").is_some(), "Y still shown");
    click_with(&mut h, "Cube rotation Y", Modifiers::COMMAND);
    assert!(h.query_by_label("curve key Cube translation Y frame 30").is_none(), "solo hides the others");
    assert!(h.query_by_label("curve key Cube rotation Y frame 30").is_some(), "the soloed curve shows");
    click_with(&mut h, "Cube rotation Y", Modifiers::COMMAND);
    assert!(h.query_by_label("curve key Cube translation X frame 30").is_some(), "Ctrl+click again: all");

    let plot = h.state().curves_rect().expect("laid out").height();
    let flat = key_span(&h, "Cube translation Y", &frames);
    assert!(flat < 0.05 * plot, "next to 0 … 360 the translation is nearly flat: {flat} of {plot}");
    click_with(&mut h, "Normalize", Modifiers::NONE);
    assert!(h.state().panels().curves.normalized);
    let scaled = key_span(&h, "Cube translation Y", &frames);
    assert!(scaled > 0.5 * plot, "normalised, it spans the view: {scaled} of {plot}");
    let spin = key_span(&h, "Cube rotation Y", &[0, 30, 60, 90]);
    assert!(scaled > 0.5 * plot && spin > 0.5 * plot, "both read at full height: {scaled}, {spin}");
}

/// F over the curves frames the selected keys' curves as drawn: the Cube's 0° → 360° spin is
/// framed 0 … 360 (not ±0.001 around the equal quaternions), and one key gets a readable span.
#[test]
fn f_frames_a_spin_by_its_unwrapped_values_and_one_key_with_room() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("key Cube rotation frame 0").click();
    h.run();
    click_with(&mut h, "key Cube rotation frame 90", Modifiers::SHIFT);
    let keys = h.state().session.selection.keys.len();
    assert_eq!(keys, 2, "frames 0 and 90 selected");
    let centre = h.state().curves_rect().expect("laid out").center();
    h.event(Event::PointerMoved(centre));
    press(&mut h, Modifiers::NONE, Key::F);
    let view = h.state().panels().curves.view.expect("framed");
    assert!(view.low <= 0.0 && view.high >= 360.0 && view.high < 450.0, "{view:?}");
    assert!(view.start <= 0.0 && view.end >= 90.0, "{view:?}");

    h.get_by_label("key Cube rotation frame 30").click();
    h.run();
    h.event(Event::PointerMoved(centre));
    press(&mut h, Modifiers::NONE, Key::F);
    let view = h.state().panels().curves.view.expect("framed");
    assert!(view.end - view.start >= 20.0, "one key: at least 20 frames, {view:?}");
    assert!(view.high - view.low >= 30.0, "one key: a tenth of the values at least, {view:?}");
    assert!(view.start < 30.0 && view.end > 30.0);
}

/// A Hermite key shows both its handles; dragging the in-handle of a key after a TCB key makes
/// that key Hermite too (keeping its shape) and bends the curve before the key.
#[test]
fn a_hermite_key_shows_and_drags_both_handles() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let cube = ChannelId::ObjectTranslation(1);
    h.get_by_label("key Cube translation frame 30").click();
    h.run();
    open_context_menu(&mut h);
    h.get_by_label("Hermite handles (keeps the shape)").click();
    h.run();
    assert!(h.query_by_label("out handle Cube translation Y key 1").is_some());
    let handle = h.get_by_label("in handle Cube translation Y key 1").rect().center();
    let y_at = |h: &Harness<'_, EditorApp>, f: i32| match h.state().evaluator().value(
        cube,
        f64::from(f) / 30.0,
        &Default::default(),
    ) {
        Some(ChannelValue::Vec3(v)) => v.y,
        other => panic!("{other:?}"),
    };
    let before: Vec<f32> = (0..30).map(|f| y_at(&h, f)).collect();
    drag(&mut h, handle, handle + egui::vec2(0.0, 30.0));
    let (_, mode, _) = channels::key_params(h.state().doc.scene(), cube, 0).expect("key 0");
    assert_eq!(mode, keyrig_core::Interpolation::Hermite, "the previous key became Hermite");
    let after: Vec<f32> = (0..30).map(|f| y_at(&h, f)).collect();
    assert!(before.iter().zip(&after).any(|(a, b)| (a - b).abs() > 1e-3), "the curve before the key bends");
}

/// Issue 42, 9: a Hermite key's handles are aligned (Blender's Aligned): dragging the out-handle
/// turns the in-handle with it, so the curve keeps no kink at the key; Alt+drag moves one
/// handle alone and breaks the pair (Free), after which each handle moves alone.
#[test]
fn hermite_handles_turn_together_unless_broken_with_alt() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let cube = ChannelId::ObjectTranslation(1);
    h.get_by_label("key Cube translation frame 30").click();
    h.run();
    open_context_menu(&mut h);
    h.get_by_label("Hermite handles (keeps the shape)").click();
    h.run();
    let y_tangents = |h: &Harness<'_, EditorApp>| {
        let (inn, out) = channels::key_tangents(h.state().doc.scene(), cube, 1);
        (inn.expect("in-tangent")[1], out.expect("out-tangent")[1])
    };
    let (inn, out) = y_tangents(&h);
    assert!(channels::tangents_aligned(inn, out), "converted without a kink: {inn} {out}");

    let handle = h.get_by_label("out handle Cube translation Y key 1").rect().center();
    drag(&mut h, handle, handle + egui::vec2(0.0, -8.0));
    let (i1, o1) = y_tangents(&h);
    assert!(o1 > out + 1e-3, "the out-handle rose: {out} → {o1}");
    assert_eq!(i1, o1, "the in-handle turned with it: no kink at the key");

    let handle = h.get_by_label("out handle Cube translation Y key 1").rect().center();
    // Alt held from the press to the release, one frame per event.
    let button = |pos: Pos2, pressed: bool| Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: Modifiers::ALT,
    };
    h.input_mut().modifiers = Modifiers::ALT;
    for event in [
        Event::PointerMoved(handle),
        button(handle, true),
        Event::PointerMoved(handle + egui::vec2(0.0, 4.0)),
        Event::PointerMoved(handle + egui::vec2(0.0, 12.0)),
        button(handle + egui::vec2(0.0, 12.0), false),
    ] {
        h.event(event);
        h.step();
    }
    h.input_mut().modifiers = Modifiers::NONE;
    h.event(Event::PointerMoved(handle + egui::vec2(0.0, -200.0)));
    h.run();
    let (i2, o2) = y_tangents(&h);
    assert!(o2 < o1 - 1e-3, "Alt+drag lowered the out-handle: {o1} → {o2}");
    assert_eq!(i2, i1, "…alone: the pair is broken");

    let handle = h.get_by_label("in handle Cube translation Y key 1").rect().center();
    drag(&mut h, handle, handle + egui::vec2(0.0, 8.0));
    let (i3, o3) = y_tangents(&h);
    assert!((i3 - i2).abs() > 1e-3, "the in-handle moved: {i2} → {i3}");
    assert_eq!(o3, o2, "a broken pair's handles move alone");

    // Align handles: one tangent again, their mean, one undo step.
    let steps = h.state().doc.undo_len();
    open_context_menu(&mut h);
    h.get_by_label("Align handles").click();
    h.run();
    let (i4, o4) = y_tangents(&h);
    assert_eq!(i4, o4, "aligned");
    assert!((i4 - (i3 + o3) * 0.5).abs() < 1e-4, "their mean: {i3} {o3} → {i4}");
    assert_eq!(h.state().doc.undo_len(), steps + 1);
}

/// Mute plays the static value (keys kept); lock refuses a key drag.
#[test]
fn mute_and_lock_per_channel() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("Cube").click();
    h.run();
    common::go_to_frame(&mut h, 60);
    let rotation = ChannelId::ObjectRotation(1);
    let keys = h.state().doc.scene().objects[1].rotation.track.clone();
    click_with(&mut h, "mute Cube rotation", Modifiers::NONE);
    assert!(h.state().doc.scene().objects[1].rotation.muted);
    let Some(ChannelValue::Rotation(q)) = h.state().value_now(rotation) else { panic!("a rotation") };
    assert!(q.angle_between(glam::Quat::IDENTITY) < 1e-5, "muted: the static value, not 240°");
    assert_eq!(h.state().doc.scene().objects[1].rotation.track, keys, "the keys are kept");
    click_with(&mut h, "mute Cube rotation", Modifiers::NONE);
    let Some(ChannelValue::Rotation(q)) = h.state().value_now(rotation) else { panic!("a rotation") };
    assert!(
        (q.angle_between(glam::Quat::IDENTITY).to_degrees() - 120.0).abs() < 0.1,
        "unmuted: 240° about Y"
    );

    click_with(&mut h, "lock Cube translation", Modifiers::NONE);
    let scene = h.state().doc.scene().clone();
    let key = h.get_by_label("curve key Cube translation Y frame 30").rect().center();
    drag(&mut h, key, key + egui::vec2(0.0, -40.0));
    assert_eq!(
        h.state().doc.scene().objects[1].translation.track,
        scene.objects[1].translation.track,
        "a locked channel's keys stay"
    );
}

/// The Cube's key at `index` of `channel` as numbers: translation X Y Z, or its rotation's
/// Euler angles in the Cube's order nearest `near`.
fn cube_key(h: &Harness<'_, EditorApp>, channel: ChannelId, index: usize, near: glam::Vec3) -> glam::Vec3 {
    let scene = h.state().doc.scene();
    match channels::key_value(scene, channel, index) {
        Some(ChannelValue::Vec3(v)) => v,
        Some(ChannelValue::Rotation(q)) => {
            let order = keyrig_core::channel_id::rotation_mode(scene, channel).euler().expect("Euler");
            order.angles_near(q, near)
        }
        other => panic!("a key, got {other:?}"),
    }
}

/// Stacked: the Cube's translation (±1) and its 0 … 360 spin each get a lane of their own with
/// their own scale, sharing the time axis. A drag of a key in either lane changes it by that
/// lane's scale (measured on the lane's own keys), one undo step each.
#[test]
fn the_stacked_view_gives_each_kind_its_lane_and_a_drag_moves_a_key_by_its_lanes_scale() {
    const MOVE: ChannelId = ChannelId::ObjectTranslation(1);
    const TURN: ChannelId = ChannelId::ObjectRotation(1);
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("Cube").click();
    h.run();
    let frames = [0, 30, 60, 75, 90];
    let shared = key_span(&h, "Cube translation Y", &frames);
    let x_at_30_shared = h.get_by_label("curve key Cube translation X frame 30").rect().center().x;
    click_with(&mut h, "Stacked", Modifiers::NONE);
    assert!(h.state().panels().curves.stacked);
    let upper = h.get_by_label("curve lane Translation").rect();
    let lower = h.get_by_label("curve lane Rotation (°)").rect();
    assert!(upper.bottom() <= lower.top() + 1.0, "translation above rotation: {upper:?}, {lower:?}");
    for f in frames {
        for c in ["X", "Y", "Z"] {
            let at = h.get_by_label(&format!("curve key Cube translation {c} frame {f}")).rect().center();
            assert!(upper.contains(at), "translation {c} at frame {f} in its lane: {at:?} not in {upper:?}");
        }
    }
    for f in [0, 30, 60, 90] {
        let at = h.get_by_label(&format!("curve key Cube rotation Y frame {f}")).rect().center();
        assert!(lower.contains(at), "rotation Y at frame {f} in its lane: {at:?} not in {lower:?}");
    }
    let x_at_30 = h.get_by_label("curve key Cube translation X frame 30").rect().center().x;
    assert!((x_at_30 - x_at_30_shared).abs() < 0.5, "the lanes share the time axis");
    let stacked = key_span(&h, "Cube translation Y", &frames);
    assert!(
        stacked > 20.0 * shared && stacked > 0.15 * upper.height(),
        "translation Y reads on its own scale: {stacked} points (shared: {shared})"
    );
    let original = h.state().doc.scene().clone();

    // The second lane: the spin's key at frame 30 (Y 120°), 10 points up. The lane's scale is
    // measured on its keys at frames 0 (0°) and 90 (360°).
    let y0 = h.get_by_label("curve key Cube rotation Y frame 0").rect().center().y;
    let y90 = h.get_by_label("curve key Cube rotation Y frame 90").rect().center().y;
    let degrees_per_point = 360.0 / (y0 - y90);
    let key = h.get_by_label("curve key Cube rotation Y frame 30").rect().center();
    drag(&mut h, key, key + egui::vec2(0.0, -10.0));
    let y = cube_key(&h, TURN, 1, glam::Vec3::new(0.0, 120.0, 0.0)).y;
    let expected = 120.0 + 10.0 * degrees_per_point;
    assert!((y - expected).abs() < 0.03 * (expected - 120.0), "Y {y}, expected {expected}");
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(h.state().doc.scene(), &original, "the drag is one undo step");

    // The first lane: translation X at frame 30 (0.0), 10 points down; the lane's scale from
    // its keys at frames 0 (−0.8) and 60 (0.8).
    let x0 = h.get_by_label("curve key Cube translation X frame 0").rect().center().y;
    let x60 = h.get_by_label("curve key Cube translation X frame 60").rect().center().y;
    let units_per_point = 1.6 / (x0 - x60);
    let key = h.get_by_label("curve key Cube translation X frame 30").rect().center();
    drag(&mut h, key, key + egui::vec2(0.0, 10.0));
    let x = cube_key(&h, MOVE, 1, glam::Vec3::ZERO).x;
    let expected = -10.0 * units_per_point;
    assert!((x - expected).abs() < 0.03 * expected.abs(), "X {x}, expected {expected}");
    assert!(units_per_point < 0.1 * degrees_per_point, "each lane its own scale");
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(h.state().doc.scene(), &original, "the drag is one undo step");
}

/// Euler keys (issue 30): the Cube's quaternion spin switched to Euler keys in the inspector is
/// one undo step; its keys become Y 0, 120, 240, 360 (X and Z 0) at the same frames and the
/// same rotations; the curve editor draws the three angles; typing Y = 600 in record mode keys
/// 600 (no flip back to 240); a new order converts the keys; the file keeps them; undo goes
/// back to the quaternion keys as they were.
#[test]
fn a_rotation_switched_to_euler_keys_keys_and_draws_its_angles() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("Cube").click();
    h.run();
    common::go_to_frame(&mut h, 60);
    let quaternion_keys = h.state().doc.scene().objects[1].rotation.clone();
    let before: Vec<ChannelValue> = [0.0, 0.25, 0.5, 0.8, 1.0]
        .iter()
        .filter_map(|&t| h.state().evaluator().value(ChannelId::ObjectRotation(1), t, &Default::default()))
        .collect();
    let undo = h.state().doc.undo_len();
    h.get_by_label("Euler keys").click();
    h.run();
    assert_eq!(h.state().doc.undo_len(), undo + 1, "one undo step");
    let scene = h.state().doc.scene();
    let euler = scene.objects[1].rotation_euler.as_ref().expect("Euler keys");
    assert!(!scene.objects[1].rotation.is_animated(), "no quaternion keys left beside them");
    let values: Vec<glam::Vec3> = euler.track.keys.iter().map(|k| k.value).collect();
    for (v, y) in values.iter().zip([0.0, 120.0, 240.0, 360.0]) {
        assert!((*v - glam::Vec3::new(0.0, y, 0.0)).abs().max_element() < 1e-3, "{values:?}");
    }
    // Linear keys about one axis: the same rotation at every time as the slerped quaternions.
    for (t, b) in [0.0, 0.25, 0.5, 0.8, 1.0].iter().zip(&before) {
        let (Some(ChannelValue::Rotation(a)), ChannelValue::Rotation(b)) =
            (h.state().evaluator().value(ChannelId::ObjectRotation(1), *t, &Default::default()), b)
        else {
            panic!("rotations")
        };
        assert!(a.dot(*b).abs() > 1.0 - 1e-6, "t {t}: {a} vs {b}");
    }
    // The inspector types the angles; the curves draw X, Y, Z with Y climbing to 360.
    assert!((field(&h, "Rotation (°) Y") - 240.0).abs() < 1e-3);
    let curves = h.state().sample_curves(ChannelId::ObjectEuler(1), 0.0, 90.0, 91);
    assert_eq!(curves.len(), 3, "X, Y, Z");
    assert!((curves[1][90].1 - 360.0).abs() < 1e-3, "{:?}", curves[1][90]);
    h.get_by_label("curve key Cube rotation (Euler °) Y frame 90");
    // Record mode: 600 is keyed as 600.
    press(&mut h, Modifiers::NONE, Key::R);
    common::set_value(&mut h, egui::accesskit::Role::SpinButton, "Rotation (°) Y", 600.0);
    let euler = h.state().doc.scene().objects[1].rotation_euler.clone().expect("Euler keys");
    let at_60 = euler.track.keys.iter().find(|k| (k.time * 30.0 - 60.0).abs() < 1e-6).expect("a key at 60");
    assert!((at_60.value.y - 600.0).abs() < 1e-3, "{}", at_60.value);
    press(&mut h, Modifiers::NONE, Key::R);
    // ZYX: the keys are converted (the same rotations), Y still climbs.
    h.get_by_label("Rotation mode").click();
    h.run();
    h.get_by_label("ZYX Euler").click();
    h.run();
    let scene = h.state().doc.scene();
    assert_eq!(
        scene.objects[1].rotation_mode,
        keyrig_core::RotationMode::Euler(keyrig_core::EulerOrder::ZYX)
    );
    let zyx = scene.objects[1].rotation_euler.as_ref().expect("still Euler keys");
    for (a, b) in euler.track.keys.iter().zip(zyx.track.keys.iter()) {
        let (qa, qb) =
            (keyrig_core::EulerOrder::XYZ.to_quat(a.value), keyrig_core::EulerOrder::ZYX.to_quat(b.value));
        assert!(
            qa.dot(qb).abs() > 1.0 - 1e-6 && (a.value.y - b.value.y).abs() < 1e-2,
            "{} vs {}",
            a.value,
            b.value
        );
    }
    // The scene file keeps the Euler keys and their order.
    let text = keyrig_io::scene_file::to_string(scene).expect("saves");
    assert!(text.contains("rotation_euler"), "{text}");
    let back = keyrig_io::scene_file::from_str(&text, dir.path()).expect("reads back");
    assert_eq!(&back.objects[1], &scene.objects[1]);
    // Undo three times (order, the key, the switch): the quaternion keys as they were.
    for _ in 0..3 {
        press(&mut h, Modifiers::COMMAND, Key::Z);
    }
    let scene = h.state().doc.scene();
    assert!(scene.objects[1].rotation_euler.is_none());
    assert_eq!(scene.objects[1].rotation, quaternion_keys);
    assert_eq!(h.state().doc.undo_len(), undo);
}

/// With Euler keys, what turns a rotation keys angles: a two-turn ring turn in record mode adds
/// 720° to Y (the angles follow the hand), a pasted pose keys the Euler channel as the angles
/// nearest the curve's, and no quaternion key appears beside them.
#[test]
fn turns_and_pasted_poses_key_the_euler_angles() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("Cube").click();
    h.run();
    h.get_by_label("Euler keys").click();
    h.run();
    common::go_to_frame(&mut h, 60);
    press(&mut h, Modifiers::NONE, Key::R);
    let Some(ChannelValue::Rotation(from)) = h.state().value_now(ChannelId::ObjectRotation(1)) else {
        panic!()
    };
    let turn = channels::Turn { from, axis: glam::Vec3::Y, degrees: 720.0 };
    h.state_mut().apply_turn(ChannelId::ObjectRotation(1), turn, "ring");
    let y_at = |h: &Harness<'_, EditorApp>, frame: f64| {
        let euler = h.state().doc.scene().objects[1].rotation_euler.clone().expect("Euler keys");
        euler.track.keys.iter().find(|k| (k.time * 30.0 - frame).abs() < 1e-6).map(|k| k.value)
    };
    let v = y_at(&h, 60.0).expect("a key at 60");
    assert!((v.y - 960.0).abs() < 1e-2 && v.x.abs() < 1e-2 && v.z.abs() < 1e-2, "{v}");
    // Copy the pose at 30 (Y 120) and paste it at 45, where the curve reads Y 540: the same
    // rotation is keyed as the angles nearest the curve's there, Y 480 (not a turn back to 120).
    common::go_to_frame(&mut h, 30);
    h.state_mut().copy_pose();
    common::go_to_frame(&mut h, 45);
    h.state_mut().paste_pose(false);
    let v = y_at(&h, 45.0).expect("the pasted pose keyed at 45");
    assert!((v.y - 480.0).abs() < 1e-2 && v.x.abs() < 1e-2 && v.z.abs() < 1e-2, "{v}");
    assert!(!h.state().doc.scene().objects[1].rotation.is_animated());
    assert!(h.state().doc.scene().problems().is_empty());
}

/// Issue 42, 12: with the rotation read as Euler angles (the default XYZ mode, quaternion
/// keys), typing X 360 at a key in record mode keyed the same rotation as 0 with no spin, so
/// the X curve and the field read 0 at the "360° key". The typed angle is a turn about X now:
/// the key gets the spin, and the field and the curve read 360 there, climbing from 0.
#[test]
fn an_euler_angle_typed_a_turn_away_keys_the_turn_and_the_curve_reads_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let wrist = ChannelId::JointRotation { object: 0, joint: 3 };
    h.get_by_label("wrist").click();
    h.run();
    press(&mut h, Modifiers::NONE, Key::R);
    common::go_to_frame(&mut h, 0);
    press(&mut h, Modifiers::NONE, Key::I);
    common::go_to_frame(&mut h, 30);
    common::set_value(&mut h, egui::accesskit::Role::SpinButton, "Rotation (°) X", 360.0);
    press(&mut h, Modifiers::NONE, Key::R);
    let scene = h.state().doc.scene();
    let frames: Vec<i64> =
        channels::key_times(scene, wrist).iter().map(|t| (t * 30.0).round() as i64).collect();
    assert_eq!(frames, [0, 30]);
    common::go_to_frame(&mut h, 20);
    common::go_to_frame(&mut h, 30);
    assert!(
        (field(&h, "Rotation (°) X") - 360.0).abs() < 0.01,
        "the field reads {}",
        field(&h, "Rotation (°) X")
    );
    let curves = h.state().sample_curves(wrist, 0.0, 30.0, 31);
    let x: Vec<f32> = curves[0].iter().map(|p| p.1).collect();
    assert!((x[30] - 360.0).abs() < 0.01, "the X curve reads 360 at the key: {x:?}");
    assert!((x[15] - 180.0).abs() < 1.0 && x.windows(2).all(|w| w[1] >= w[0] - 1e-3), "climbing: {x:?}");
    for c in [1, 2] {
        assert!(curves[c].iter().all(|p| p.1.abs() < 0.01), "Y and Z stay 0: {:?}", curves[c]);
    }
    h.get_by_label("curve key wrist rotation X frame 30");
}

/// Issue 42, 9: the curve view's state leaked between items and documents. A view framed on
/// the elbow's key (F) was kept when the Cube was selected, leaving its 0 → 360 spin off the
/// plot until Fit; now another item is shown fitted. Normalize and hidden curves were kept
/// into the next document; another document starts with every curve shown, not normalised.
#[test]
fn the_curve_view_refits_for_another_item_and_starts_plain_in_another_document() {
    let (dir, mut h) = with_elbow_key();
    let plot = h.state().curves_rect().expect("laid out");
    h.event(Event::PointerMoved(plot.center()));
    press(&mut h, Modifiers::NONE, Key::F);
    let framed = h.state().panels().curves.view.expect("framed on the elbow's key");
    assert!(framed.high < 300.0, "the elbow's values: {framed:?}");
    h.get_by_label("Cube").click();
    h.run();
    let plot = h.state().curves_rect().expect("laid out");
    for frame in [0, 30, 60, 90] {
        let key = h.get_by_label(&format!("curve key Cube rotation Y frame {frame}")).rect().center();
        assert!(plot.contains(key), "frame {frame}: the spin's key at {key:?} is on the plot {plot:?}");
    }

    click_with(&mut h, "Cube translation X", Modifiers::NONE);
    click_with(&mut h, "Normalize", Modifiers::NONE);
    assert!(h.state().panels().curves.normalized);
    assert!(!h.state().panels().curves.hidden.is_empty());
    // Another document: the demo saved and opened again.
    let path = dir.path().join("again.ron");
    let text = keyrig_io::scene_file::to_string(h.state().doc.scene()).expect("saves");
    std::fs::write(&path, text).expect("write the scene");
    h.state_mut().open_path(path);
    h.run();
    h.get_by_label("Cube").click();
    h.run();
    assert!(!h.state().panels().curves.normalized, "Normalize is off in another document");
    assert!(h.state().panels().curves.hidden.is_empty(), "every curve shows");
    assert!(h.query_by_label("curve key Cube translation X frame 30").is_some());
}
