//! Table-driven sampling tests: each track's keys are drawn as an ASCII timeline above a table
//! of `(time, expected)` rows that covers times before the first key, at and ±1e-6 around each
//! key, inside segments, and after the last key.

mod support;

use glam::{Quat, Vec3};
use keyrig_core::{Animated, AnimatedTrack, Interpolation, Key, RawTrack, Track, TrackValue};
use support::{rot, tricky_quaternion_sets, ApproxDist};

const E: f64 = 1e-6;

/// Checks every row of `rows` by sampling the track.
fn check_table<T: TrackValue + ApproxDist>(name: &str, track: &Track<T>, rows: &[(f64, T)], eps: f64) {
    for &(t, expected) in rows {
        assert_approx_eq!(track.sample(t), expected, eps, "{name}: sample({t})");
    }
}

#[test]
fn scalar_step_and_linear_segments() {
    //  value
    //   2.0 |        k1━━━━━━━━━━━━━━━━━━━┓        k0: Linear, k1: Step, k2: Linear
    //       |       ╱                     ┃
    //   0.0 k0────╱                       ┃       k3
    //       |                             ┃     ╱
    //  -1.0 |                             k2──╱
    //       +--------+--------+-----------+-----+-------> t (s)
    //      0.0      0.5      1.0          3.0   3.5
    let track = Track::new(&RawTrack::new(vec![
        Key::new(0.0, 0.0f32).with_interpolation(Interpolation::Linear),
        Key::new(1.0, 2.0).with_interpolation(Interpolation::Step),
        Key::new(3.0, -1.0).with_interpolation(Interpolation::Linear),
        Key::new(3.5, 0.0),
    ]))
    .unwrap();
    #[rustfmt::skip]
    let rows = [
        (-1.0,      0.0),            // before the first key: first value
        (-E,        0.0),
        (0.0,       0.0),            // k0
        (E,         2.0 * E as f32), // slope 2 per second
        (0.5,       1.0),
        (1.0 - E,   2.0 - 2.0 * E as f32),
        (1.0,       2.0),            // k1: Step holds its value ...
        (1.0 + E,   2.0),
        (2.0,       2.0),
        (3.0 - E,   2.0),            // ... until just before k2
        (3.0,      -1.0),            // k2
        (3.0 + E,  -1.0 + 2.0 * E as f32),
        (3.25,     -0.5),
        (3.5 - E,  -2.0 * E as f32),
        (3.5,       0.0),            // k3, the last key
        (3.5 + E,   0.0),            // after the last key: last value
        (100.0,     0.0),
    ];
    check_table("scalar", &track, &rows, 2e-7);
    assert_eq!(track.domain(), (0.0, 3.5));
    assert_eq!(track.key_count(), 4);
    assert_eq!(track.key_times(), &[0.0, 1.0, 3.0, 3.5]);
    // Velocity: 2/s on the linear segment, 0 while stepping, 2/s again, 0 outside.
    assert_eq!(track.velocity(0.5), 2.0);
    assert_eq!(track.velocity(2.0), 0.0);
    assert_eq!(track.velocity(3.25), 2.0);
    assert_eq!(track.velocity(-1.0), 0.0);
    assert_eq!(track.velocity(4.0), 0.0);
    assert_eq!(track.velocity_before(1.0), 2.0);
    assert_eq!(track.velocity(1.0), 0.0);
    assert_eq!(track.sample(f64::NAN), 0.0, "NaN time samples the first key");
}

#[test]
fn vec3_catmull_rom_segments() {
    //  keys (T = C = B = 0, uniform spacing: Catmull–Rom with P_-1 := P_0, P_4 := P_3)
    //    k0 (0,0,0)      k1 (1,0,0)      k2 (1,1,0)      k3 (0,1,1)
    //    |---------------|---------------|---------------|
    //   0.0             1.0             2.0             3.0
    //  Tangents (per segment = per second here): S0 = (P1−P0)/2, S_i = D_i = (P_{i+1}−P_{i−1})/2,
    //  D3 = (P3−P2)/2. Segment midpoints: (P_i + P_{i+1})/2 + (S_i − D_{i+1})/8.
    let p = [Vec3::ZERO, Vec3::X, Vec3::new(1.0, 1.0, 0.0), Vec3::new(0.0, 1.0, 1.0)];
    let keys = p.iter().enumerate().map(|(i, &v)| Key::new(i as f64, v)).collect();
    let track = Track::new(&RawTrack::new(keys)).unwrap();
    let e = E as f32;
    #[rustfmt::skip]
    let rows = [
        (-0.5,    p[0]),
        (-E,      p[0]),
        (0.0,     p[0]),
        (E,       Vec3::new(0.5 * e, 0.0, 0.0)),               // leaves k0 at S0 = (0.5, 0, 0)/s
        (0.5,     Vec3::new(0.5, -0.0625, 0.0)),
        (1.0 - E, Vec3::new(1.0 - 0.5 * e, -0.5 * e, 0.0)),    // arrives at k1 at D1 = (0.5, 0.5, 0)/s
        (1.0,     p[1]),
        (1.0 + E, Vec3::new(1.0 + 0.5 * e, 0.5 * e, 0.0)),
        (1.5,     Vec3::new(1.125, 0.5, -0.0625)),
        (2.0,     p[2]),
        (2.0 + E, Vec3::new(1.0 - 0.5 * e, 1.0 + 0.5 * e, 0.5 * e)), // S2 = (−0.5, 0.5, 0.5)/s
        (2.5,     Vec3::new(0.5, 1.0625, 0.5)),
        (3.0 - E, Vec3::new(0.5 * e, 1.0, 1.0 - 0.5 * e)),     // D3 = (−0.5, 0, 0.5)/s
        (3.0,     p[3]),
        (3.0 + E, p[3]),
        (1e9,     p[3]),
    ];
    check_table("vec3", &track, &rows, 2e-7);
    // glTF CUBICSPLINE tangents of segment 1: (S1, D2) per second.
    let (out1, in2) = track.segment_tangents(1).unwrap();
    assert_approx_eq!(out1, Vec3::new(0.5, 0.5, 0.0), 1e-7);
    assert_approx_eq!(in2, Vec3::new(-0.5, 0.5, 0.5), 1e-7);
    assert_eq!(track.segment_tangents(3), None);
}

#[test]
fn quat_linear_and_step_segments() {
    //  rotation about +Z (degrees)
    //   180 |                      k2─────╲           k0: Linear, k1: Step, k2: Linear
    //    90 |          k1━━━━━━━━━┛        ╲
    //     0 k0───────╱                      k3 (270°)
    //       +----------+-----------+--------+------> t (s)
    //      0.0        2.0         3.0      4.0
    let z = |deg: f32| rot(Vec3::Z, deg);
    let track = Track::new(&RawTrack::new(vec![
        Key::new(0.0, z(0.0)).with_interpolation(Interpolation::Linear),
        Key::new(2.0, z(90.0)).with_interpolation(Interpolation::Step),
        Key::new(3.0, z(180.0)).with_interpolation(Interpolation::Linear),
        Key::new(4.0, z(270.0)),
    ]))
    .unwrap();
    let deg_per_s = 45.0 * E as f32;
    #[rustfmt::skip]
    let rows = [
        (-3.0,    z(0.0)),
        (-E,      z(0.0)),
        (0.0,     z(0.0)),
        (E,       z(deg_per_s)),
        (1.0,     z(45.0)),
        (2.0 - E, z(90.0 - deg_per_s)),
        (2.0,     z(90.0)),
        (2.0 + E, z(90.0)),                 // Step holds
        (3.0 - E, z(90.0)),
        (3.0,     z(180.0)),
        (3.0 + E, z(180.0 + 2.0 * deg_per_s)),
        (3.5,     z(225.0)),
        (4.0,     z(270.0)),
        (4.0 + E, z(270.0)),
        (50.0,    z(270.0)),
    ];
    check_table("quat", &track, &rows, 2e-7);
    // k3 = (0, 0, sin 135°, cos 135°) has a positive dot product with k2: not flipped.
    assert_eq!(track.key_values()[3], z(270.0));
}

#[test]
fn squad_passes_through_keys_and_is_clamped() {
    //  k0 ──── k1 ──────── k2 ── k3     Squad with varied T/C/B, uneven spacing
    //  0.0     0.4         1.9   2.0
    let keys = vec![
        Key::new(0.0, rot(Vec3::X, 10.0)),
        Key::new(0.4, rot(Vec3::new(1.0, 1.0, 0.0), 70.0)).with_tcb(keyrig_core::Tcb::new(0.5, -0.3, 0.2)),
        Key::new(1.9, rot(Vec3::Y, 140.0)).with_tcb(keyrig_core::Tcb::new(-0.5, 0.0, -0.8)),
        Key::new(2.0, rot(Vec3::Z, 30.0)),
    ];
    let track = Track::new(&RawTrack::new(keys.clone())).unwrap();
    let mut rows =
        vec![(-1.0, keys[0].value), (-E, keys[0].value), (2.0 + E, keys[3].value), (7.0, keys[3].value)];
    rows.extend(keys.iter().map(|k| (k.time, k.value)));
    check_table("squad", &track, &rows, 1e-7);
    // Around the keys the track moves continuously (no jump at ±1e-6).
    for k in &keys[1..3] {
        let (before, at, after) = (track.sample(k.time - E), track.sample(k.time), track.sample(k.time + E));
        assert!(before.approx_dist(&at) < 1e-4 && after.approx_dist(&at) < 1e-4, "jump at {}", k.time);
    }
}

#[test]
fn single_key_track_is_constant() {
    //  k0 at 1.0 only: the domain is a point; every time gives k0.
    let track = Track::new(&RawTrack::new(vec![Key::new(1.0, Vec3::new(1.0, 2.0, 3.0))])).unwrap();
    let rows =
        [(-1.0, Vec3::new(1.0, 2.0, 3.0)), (1.0, Vec3::new(1.0, 2.0, 3.0)), (2.0, Vec3::new(1.0, 2.0, 3.0))];
    check_table("single", &track, &rows, 0.0);
    assert_eq!(track.domain(), (1.0, 1.0));
    assert_eq!(track.velocity(1.0), Vec3::ZERO);
    assert_eq!(track.segment_interpolation(0), None);
}

#[test]
fn hermite_keys_use_per_second_tangents_times_segment_duration() {
    //  k0 (0) ───────────── k1 (1)      Hermite, out-tangent of k0 = 3/s, in-tangent of k1 = 0/s
    //  0.0                  2.0         segment duration 2 s: m0 = 6, m1 = 0
    //  p(u) = h10·6 + h01·1 = 6(u³ − 2u² + u) + (3u² − 2u³) = 4u³ − 9u² + 6u
    let mut k0 = Key::new(0.0, 0.0f32).with_interpolation(Interpolation::Hermite);
    k0.out_tangent = Some(3.0);
    let mut k1 = Key::new(2.0, 1.0f32);
    k1.in_tangent = Some(0.0);
    let track = Track::new(&RawTrack::new(vec![k0, k1])).unwrap();
    let p = |u: f32| 4.0 * u * u * u - 9.0 * u * u + 6.0 * u;
    let rows = [(0.0, 0.0), (0.5, p(0.25)), (1.0, p(0.5)), (1.5, p(0.75)), (2.0, 1.0), (3.0, 1.0)];
    check_table("hermite", &track, &rows, 2e-7);
    assert_approx_eq!(track.velocity(0.0), 3.0f32, 1e-6);
    assert_approx_eq!(track.velocity_before(2.0), 0.0f32, 1e-6);
    assert_eq!(track.segment_tangents(0), Some((3.0, 0.0)));
}

#[test]
fn hermite_rotation_is_component_wise_then_normalized() {
    // With zero tangents the Hermite blend is smoothstep-weighted nlerp.
    let (a, b) = (rot(Vec3::Z, 0.0), rot(Vec3::Z, 90.0));
    let mut k0 = Key::new(0.0, a).with_interpolation(Interpolation::Hermite);
    k0.out_tangent = Some(Quat::from_xyzw(0.0, 0.0, 0.0, 0.0));
    let mut k1 = Key::new(1.0, b);
    k1.in_tangent = Some(Quat::from_xyzw(0.0, 0.0, 0.0, 0.0));
    let track = Track::new(&RawTrack::new(vec![k0, k1])).unwrap();
    for u in [0.1f32, 0.5, 0.8] {
        let s = u * u * (3.0 - 2.0 * u);
        let expected = (a * (1.0 - s) + b * s).normalize();
        assert_approx_eq!(track.sample(f64::from(u)), expected, 1e-6, "u = {u}");
    }
}

#[test]
fn tricky_quaternion_sets_give_unit_finite_rotations_in_every_mode() {
    for (name, quats) in tricky_quaternion_sets() {
        for mode in [Interpolation::Linear, Interpolation::Tcb, Interpolation::Step] {
            let keys = quats
                .iter()
                .enumerate()
                .map(|(i, &q)| Key::new(i as f64 * 0.5, q).with_interpolation(mode))
                .collect();
            let track = Track::new(&RawTrack::new(keys)).unwrap();
            for j in 0..=200 {
                let t = j as f64 * (quats.len() as f64 * 0.5) / 200.0 - 0.1;
                let q = track.sample(t);
                assert!(q.is_finite(), "{name} {mode:?} t = {t}: {q:?}");
                assert!((q.length() - 1.0).abs() < 1e-6, "{name} {mode:?} t = {t}: |q| = {}", q.length());
            }
            for (i, &q) in quats.iter().enumerate() {
                assert_approx_eq!(track.sample(i as f64 * 0.5), q, 1e-7, "{name} {mode:?} key {i}");
            }
        }
    }
}

#[test]
fn antipodal_and_identical_keys_interpolate_as_a_constant() {
    let sets = tricky_quaternion_sets();
    for name in ["antipodal", "identical"] {
        let quats = &sets.iter().find(|(n, _)| *n == name).unwrap().1;
        let keys = quats.iter().enumerate().map(|(i, &q)| Key::new(i as f64, q)).collect();
        let track = Track::new(&RawTrack::new(keys)).unwrap();
        for j in 0..=30 {
            let t = j as f64 * 0.1;
            assert_approx_eq!(track.sample(t), quats[0], 1e-7, "{name} at t = {t}");
        }
    }
}

#[test]
fn half_turn_keys_slerp_through_the_quarter_turn() {
    //  k0 identity ───── k1 180° about X     dot = 0: no flip, 90° about X halfway
    //  (k1 written exactly: rot(X, 180°) in f32 has w = −4.4e-8, which flips it to −X.)
    let track = Track::new(&RawTrack::new(vec![
        Key::new(0.0, Quat::IDENTITY).with_interpolation(Interpolation::Linear),
        Key::new(1.0, Quat::from_xyzw(1.0, 0.0, 0.0, 0.0)),
    ]))
    .unwrap();
    assert_approx_eq!(track.sample(0.5), rot(Vec3::X, 90.0), 1e-7);
    assert_approx_eq!(track.sample(0.25), rot(Vec3::X, 45.0), 1e-7);
}

#[test]
fn animated_track_is_constant_without_keys_and_keyed_with_them() {
    let constant = AnimatedTrack::new(&Animated::constant(Vec3::new(1.0, 2.0, 3.0))).unwrap();
    assert!(!constant.is_animated());
    assert_eq!(constant.domain(), None);
    assert_eq!(constant.sample(123.0), Vec3::new(1.0, 2.0, 3.0));
    assert_eq!(constant.sample(-4.0), Vec3::new(1.0, 2.0, 3.0));

    // A non-normalized static rotation is normalized.
    let rotation = AnimatedTrack::new(&Animated::constant(Quat::from_xyzw(0.0, 0.0, 0.0, 2.0))).unwrap();
    assert_eq!(rotation.sample(0.0), Quat::IDENTITY);

    let mut animated = Animated::constant(0.0f32);
    animated.track =
        RawTrack::new(vec![Key::new(0.0, 1.0).with_interpolation(Interpolation::Linear), Key::new(2.0, 3.0)]);
    let keyed = AnimatedTrack::new(&animated).unwrap();
    assert!(keyed.is_animated());
    assert_eq!(keyed.domain(), Some((0.0, 2.0)));
    assert_eq!(keyed.sample(1.0), 2.0);
    assert_eq!([keyed.sample(0.5), keyed.sample(1.5), keyed.sample(0.0)], [1.5, 2.5, 1.0]);
    assert_eq!(keyed.track().map(Track::key_count), Some(2));
}

#[test]
fn long_track_finds_the_right_segment_everywhere() {
    // 1000 Linear keys: at each key its value, a third into each segment a third of the way
    // to the next key (binary search over many segments).
    let value = |i: usize| Vec3::splat((i as f32 * 0.37).sin());
    let keys = (0..1000)
        .map(|i| Key::new(i as f64 * 0.1, value(i)).with_interpolation(Interpolation::Linear))
        .collect();
    let track = Track::new(&RawTrack::new(keys)).unwrap();
    for i in 0..999 {
        let t = i as f64 * 0.1;
        assert_eq!(track.sample(t), value(i), "key {i}");
        let expected = value(i) + (value(i + 1) - value(i)) / 3.0;
        assert_approx_eq!(track.sample(t + 0.1 / 3.0), expected, 1e-5, "a third into segment {i}");
    }
    assert_eq!(track.sample(99.9), value(999));
}
