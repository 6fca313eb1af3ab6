//! Clamped TCB keys (`Tcb::clamped`, as Blender's auto-clamped handles): two keys of equal value
//! hold it between them instead of dipping, every segment between clamped keys stays within its
//! keys' values, rotations ease into equal keys too, and scene files without the field read as
//! before.

use glam::{Quat, Vec3};
use keyrig_core::{Key, RawTrack, Tcb, Track};
use proptest::prelude::*;

/// The issue's example: a rise to −16.8, held at −16.8 for a second, then a fall. Unclamped,
/// Catmull–Rom tangents dip below −16.8 between the two equal keys.
fn held_value(clamped: bool) -> Track<f32> {
    let tcb = Tcb::ZERO.with_clamped(clamped);
    Track::new(&RawTrack::new(vec![
        Key::new(0.0, -40.0f32).with_tcb(tcb),
        Key::new(1.0, -16.8).with_tcb(tcb),
        Key::new(2.0, -16.8).with_tcb(tcb),
        Key::new(3.0, 10.0).with_tcb(tcb),
    ]))
    .expect("a valid track")
}

#[test]
fn two_equal_clamped_keys_hold_their_value_between_them() {
    let dip =
        (0..=100).map(|i| held_value(false).sample(1.0 + f64::from(i) / 100.0)).fold(f32::MAX, f32::min);
    assert!(dip < -17.0, "unclamped TCB dips between equal keys: {dip}");
    for i in 0..=100 {
        let t = 1.0 + f64::from(i) / 100.0;
        let v = held_value(true).sample(t);
        assert!((v + 16.8).abs() < 1e-4, "clamped: {v} at {t}");
    }
}

proptest! {
    /// Between two clamped keys a scalar curve never leaves the range of the two keys' values,
    /// whatever the spacing and the tension, continuity and bias.
    #[test]
    fn clamped_segments_stay_within_their_keys(
        steps in prop::collection::vec((0.05f64..3.0, -100.0f32..100.0), 3..9),
        tcb in (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0),
    ) {
        let tcb = Tcb::new(tcb.0, tcb.1, tcb.2).with_clamped(true);
        let mut time = 0.0;
        let keys: Vec<Key<f32>> = steps
            .iter()
            .map(|&(dt, v)| {
                time += dt;
                Key::new(time, v).with_tcb(tcb)
            })
            .collect();
        let track = Track::new(&RawTrack::new(keys.clone())).expect("a valid track");
        for w in keys.windows(2) {
            let (lo, hi) = (w[0].value.min(w[1].value), w[0].value.max(w[1].value));
            let slack = 1e-4 * (1.0 + hi.abs().max(lo.abs()));
            for i in 0..=50 {
                let t = w[0].time + (w[1].time - w[0].time) * f64::from(i) / 50.0;
                let v = track.sample(t);
                prop_assert!(v >= lo - slack && v <= hi + slack, "{v} outside [{lo}, {hi}] at {t}");
            }
        }
    }
}

#[test]
fn vectors_clamp_each_component_and_rotations_ease_into_equal_keys() {
    let tcb = Tcb::ZERO.with_clamped(true);
    let track = Track::new(&RawTrack::new(vec![
        Key::new(0.0, Vec3::new(0.0, 5.0, 0.0)).with_tcb(tcb),
        Key::new(1.0, Vec3::new(2.0, 1.0, 0.0)).with_tcb(tcb),
        Key::new(2.0, Vec3::new(2.0, 0.0, 0.0)).with_tcb(tcb),
        Key::new(3.0, Vec3::new(0.0, -3.0, 0.0)).with_tcb(tcb),
    ]))
    .expect("a valid track");
    for i in 0..=20 {
        let v = track.sample(1.0 + f64::from(i) / 20.0);
        assert!((v.x - 2.0).abs() < 1e-5, "x holds at 2: {v}");
        assert!(v.y <= 1.0 + 1e-5 && v.y >= -1e-5, "y stays between its keys: {v}");
    }

    let bent = Quat::from_rotation_z(1.2);
    let rotations = Track::new(&RawTrack::new(vec![
        Key::new(0.0, Quat::IDENTITY).with_tcb(tcb),
        Key::new(1.0, bent).with_tcb(tcb),
        Key::new(2.0, bent).with_tcb(tcb),
        Key::new(3.0, Quat::IDENTITY).with_tcb(tcb),
    ]))
    .expect("a valid track");
    for i in 0..=20 {
        let q = rotations.sample(1.0 + f64::from(i) / 20.0);
        assert!(q.angle_between(bent) < 1e-4, "the rotation holds between equal keys: {q}");
    }
}

#[test]
fn scene_text_leaves_the_field_out_while_false_and_reads_it_back() {
    let plain = Tcb::new(0.5, 0.0, 0.0);
    let text = serde_json::to_string(&plain).expect("serialize");
    assert!(!text.contains("clamped"), "{text}");
    let old: Tcb = serde_json::from_str(r#"{"tension":0.5,"continuity":0.0,"bias":0.0}"#).expect("old text");
    assert_eq!(old, plain);
    let clamped = plain.with_clamped(true);
    let back: Tcb = serde_json::from_str(&serde_json::to_string(&clamped).expect("serialize")).expect("read");
    assert_eq!(back, clamped);
}
