//! Curve clean-up (docs/cleanup.md): key reduction of the CMU 131 walk within 0.5° and 1 mm,
//! checked independently through the scene evaluator at every frame; the Butterworth filter
//! against its analytic magnitude and against scipy's numbers; and the edge cases.

use std::path::Path;

use glam::{DQuat, Quat, Vec3};
use keyrig_core::{Animated, Interpolation, Key, Object, RawTrack, Scene};
use keyrig_edit::channels::{self, ChannelId, ChannelValue};
use keyrig_edit::cleanup::{
    butterworth_lowpass, filtfilt, keyed_channels, key_total, reduce_keys, smooth_keys, CleanupError,
    ReduceTolerance, Skipped,
};
use keyrig_edit::SceneEdit;
use keyrig_eval::{Overrides, SceneEvaluator};

/// Metres per unit of the CMU BVH files converted by cgspeed (the corpus take): the CMU
/// skeletons are in units of 1/0.45 inch (mocap.cs.cmu.edu FAQ: "(1.0/0.45)*2.54/100"), which
/// the take's hips height of about 16.9 units (0.95 m) agrees with.
const CMU_METRES_PER_UNIT: f64 = (1.0 / 0.45) * 2.54 / 100.0;

fn cmu_take() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/bvh/cmu-bvh11/131_01.bvh");
    keyrig_io::bvh::import_scene(&path).expect("the corpus take reads")
}

/// The angle (degrees) between two rotations, computed here from the quaternions.
fn angle_deg(a: Quat, b: Quat) -> f64 {
    let (a, b) = (a.as_dquat().normalize(), b.as_dquat().normalize());
    let d = a.dot(b).abs().min(1.0);
    // acos is ill-conditioned near 1: use the half-angle sine of the difference instead.
    let b = if a.dot(b) < 0.0 { -b } else { b };
    let s = (a - b).length() / 2.0; // = sin(θ/4)·… exactly: |a − b| = 2·sin(θ/4)
    let from_chord = 4.0 * s.asin();
    assert!((from_chord - 2.0 * d.acos()).abs() < 1e-3, "the two formulas agree");
    from_chord.to_degrees()
}

/// Largest differences between two scenes' joint channels, through the scene evaluator at
/// every frame of the range: (rotation angle in degrees, translation distance in scene units).
fn max_deviation(original: &Scene, reduced: &Scene) -> (f64, f64) {
    let none = Overrides::default();
    let a = SceneEvaluator::new(original, &Default::default());
    let b = SceneEvaluator::new(reduced, &Default::default());
    let joints = original.objects[0].skeleton.as_ref().unwrap().joints.len();
    let (mut angle, mut distance) = (0.0f64, 0.0f64);
    for frame in original.frame_range.start..=original.frame_range.end {
        let t = f64::from(frame) / original.fps;
        for joint in 0..joints {
            let rotation = ChannelId::JointRotation { object: 0, joint };
            let (Some(ChannelValue::Rotation(qa)), Some(ChannelValue::Rotation(qb))) =
                (a.value(rotation, t, &none), b.value(rotation, t, &none))
            else {
                panic!("joint {joint} has a rotation")
            };
            angle = angle.max(angle_deg(qa, qb));
            let translation = ChannelId::JointTranslation { object: 0, joint };
            let (Some(ChannelValue::Vec3(pa)), Some(ChannelValue::Vec3(pb))) =
                (a.value(translation, t, &none), b.value(translation, t, &none))
            else {
                panic!("joint {joint} has a translation")
            };
            distance = distance.max(f64::from((pa - pb).length()));
        }
    }
    (angle, distance)
}

#[test]
fn cmu_walk_reduced_within_half_a_degree_and_a_millimetre_keeps_a_tenth_of_its_keys() {
    let original = cmu_take();
    assert_eq!(original.fps.round(), 120.0);
    let channels = keyed_channels(&original, None);
    // 31 joints with rotation keys, and the hips' position.
    assert_eq!(channels.len(), 32);
    let before = key_total(&original, &channels);
    assert_eq!(before, 32 * 994);
    let millimetre = 0.001 / CMU_METRES_PER_UNIT;
    let tolerance = ReduceTolerance { angle_deg: 0.5, distance: millimetre, value: millimetre };
    let mut reduced = original.clone();
    let report = reduce_keys(&mut reduced, &channels, tolerance).unwrap();
    let after = key_total(&reduced, &channels);
    eprintln!("CMU 131_01: {before} keys → {after} ({:.1} %), report {report:?}", 100.0 * after as f64 / before as f64);
    assert!(report.skipped.is_empty(), "{:?}", report.skipped);
    assert_eq!((report.keys_before, report.keys_after), (before, after));
    assert!(after * 10 <= before, "{after} of {before} keys kept");
    let (angle, distance) = max_deviation(&original, &reduced);
    eprintln!("through the evaluator: {angle:.4}° and {:.4} mm at most", distance * CMU_METRES_PER_UNIT * 1000.0);
    assert!(angle <= 0.5, "{angle}°");
    assert!(distance <= millimetre, "{distance} units");
    assert!(report.max_angle_deg <= 0.5 && report.max_distance <= millimetre);
    // The evaluator's numbers and the report's agree (the same samples: every frame).
    assert!((report.max_angle_deg - angle).abs() < 1e-3, "{} vs {angle}", report.max_angle_deg);
}
