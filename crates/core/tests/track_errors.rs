//! One invalid track per error class: each names the offending key.

use glam::{Quat, Vec3};
use keyrig_core::{
    Animated, AnimatedTrack, Interpolation, Key, RawTrack, TangentSide, Tcb, Track, TrackError,
};

fn vec3_keys() -> Vec<Key<Vec3>> {
    (0..4).map(|i| Key::new(f64::from(i), Vec3::splat(i as f32))).collect()
}

fn err<T: keyrig_core::TrackValue>(keys: Vec<Key<T>>) -> TrackError {
    Track::new(&RawTrack::new(keys)).expect_err("track must be rejected")
}

#[test]
fn empty_track() {
    assert_eq!(err::<f32>(vec![]), TrackError::Empty);
    assert_eq!(TrackError::Empty.to_string(), "track has no keys");
}

#[test]
fn time_errors_name_the_key() {
    let mut keys = vec3_keys();
    keys[2].time = 0.5;
    assert_eq!(err(keys), TrackError::Unsorted { index: 2 });

    let mut keys = vec3_keys();
    keys[3].time = 2.0;
    let e = err(keys);
    assert_eq!(e, TrackError::DuplicateTime { index: 3 });
    assert!(e.to_string().starts_with("key 3:"), "{e}");

    for bad in [f64::NAN, f64::INFINITY, f64::NEG_INFINITY] {
        let mut keys = vec3_keys();
        keys[1].time = bad;
        assert_eq!(err(keys), TrackError::NonFiniteTime { index: 1 });
    }
}

#[test]
fn value_errors_name_the_key() {
    let mut keys = vec3_keys();
    keys[0].value.y = f32::NAN;
    assert_eq!(err(keys), TrackError::NonFiniteValue { index: 0 });

    let scalar = vec![Key::new(0.0, 1.0f32), Key::new(1.0, f32::INFINITY)];
    assert_eq!(err(scalar), TrackError::NonFiniteValue { index: 1 });

    let rotations = vec![Key::new(0.0, Quat::IDENTITY), Key::new(1.0, Quat::from_xyzw(0.0, 0.0, 0.0, 0.0))];
    assert_eq!(err(rotations), TrackError::ZeroQuaternion { index: 1 });

    let rotations = vec![Key::new(0.0, Quat::from_xyzw(f32::NAN, 0.0, 0.0, 1.0))];
    assert_eq!(err(rotations), TrackError::NonFiniteValue { index: 0 });
}

#[test]
fn tcb_out_of_range_or_not_finite() {
    for tcb in [Tcb::new(1.5, 0.0, 0.0), Tcb::new(0.0, -1.01, 0.0), Tcb::new(0.0, 0.0, f32::NAN)] {
        let mut keys = vec3_keys();
        keys[2].tcb = tcb;
        assert_eq!(err(keys), TrackError::TcbOutOfRange { index: 2 }, "{tcb:?}");
    }
    // The limits themselves are allowed.
    let mut keys = vec3_keys();
    keys[1].tcb = Tcb::new(1.0, -1.0, 1.0);
    assert!(Track::new(&RawTrack::new(keys)).is_ok());
}

#[test]
fn hermite_tangents_missing_or_not_finite() {
    let mut keys = vec3_keys();
    keys[1].interpolation = Interpolation::Hermite;
    assert_eq!(err(keys.clone()), TrackError::MissingTangent { index: 1, side: TangentSide::Out });
    keys[1].out_tangent = Some(Vec3::X);
    let e = err(keys.clone());
    assert_eq!(e, TrackError::MissingTangent { index: 2, side: TangentSide::In });
    assert_eq!(e.to_string(), "key 2: Hermite interpolation needs the key's in_tangent");
    keys[2].in_tangent = Some(Vec3::new(0.0, f32::NAN, 0.0));
    assert_eq!(err(keys.clone()), TrackError::NonFiniteTangent { index: 2 });
    keys[2].in_tangent = Some(Vec3::Y);
    assert!(Track::new(&RawTrack::new(keys.clone())).is_ok());

    // A Hermite last key needs no tangents: it starts no segment.
    let mut keys = vec3_keys();
    keys[3].interpolation = Interpolation::Hermite;
    assert!(Track::new(&RawTrack::new(keys)).is_ok());
}

#[test]
fn first_problem_in_key_order_is_reported() {
    let mut keys = vec3_keys();
    keys[3].value.x = f32::NAN;
    keys[1].time = 5.0; // key 2 (time 2.0) is then unsorted
    assert_eq!(err(keys), TrackError::Unsorted { index: 2 });
}

#[test]
fn animated_static_value_errors() {
    let nan = Animated::constant(Vec3::new(f32::NAN, 0.0, 0.0));
    assert_eq!(AnimatedTrack::new(&nan), Err(TrackError::NonFiniteStaticValue));
    let zero = Animated::constant(Quat::from_xyzw(0.0, 0.0, 0.0, 0.0));
    assert_eq!(AnimatedTrack::new(&zero), Err(TrackError::ZeroStaticQuaternion));
    let mut keyed = Animated::constant(0.0f32);
    keyed.track = RawTrack::new(vec![Key::new(1.0, 0.0), Key::new(1.0, 1.0)]);
    assert_eq!(AnimatedTrack::new(&keyed), Err(TrackError::DuplicateTime { index: 1 }));
}
