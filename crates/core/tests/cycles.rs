//! Cycles (docs/design.md §9): what a track does before its first key and after its last.
//! Table tests with a timeline, the validation errors, and property tests for periodicity,
//! the offset per cycle, ping-pong's mirror symmetry and continuity through the seam.

mod support;

use glam::{DQuat, DVec3, Quat, Vec3};
use keyrig_core::quat::log;
use keyrig_core::{
    Animated, AnimatedTrack, Cycle, Cycles, Interpolation, Key, RawTrack, Scene, Tcb, Track, TrackEnd,
    TrackError,
};
use proptest::prelude::*;
use support::ApproxDist;

fn cycled<T: keyrig_core::TrackValue>(keys: Vec<Key<T>>, before: Cycle, after: Cycle) -> Track<T> {
    Track::with_cycles(&RawTrack::new(keys), Cycles::new(before, after)).expect("valid track")
}

// ---------------------------------------------------------------------------------------------
// Tables.
//
// Linear scalar keys, period P = 2 s, P_n − P_0 = 1:
//
//   value
//     4 |     *
//     2 |    / \__*
//     1 |   *
//       +---+---+---+--> t (s)
//           1   2   3

fn scalar_keys() -> Vec<Key<f32>> {
    vec![
        Key::new(1.0, 1.0).with_interpolation(Interpolation::Linear),
        Key::new(2.0, 4.0).with_interpolation(Interpolation::Linear),
        Key::new(3.0, 2.0).with_interpolation(Interpolation::Linear),
    ]
}

#[test]
fn scalar_cycles_table() {
    // (cycle at both ends, [(time, expected)]). Period 2 s; P_n − P_0 = 1.
    let table: [(Cycle, &[(f64, f32)]); 5] = [
        (Cycle::Hold, &[(-5.0, 1.0), (0.5, 1.0), (1.0, 1.0), (3.0, 2.0), (3.5, 2.0), (100.0, 2.0)]),
        // Slope −2 arriving at the last key, +3 leaving the first.
        (Cycle::Linear, &[(0.0, -2.0), (0.5, -0.5), (1.0, 1.0), (3.0, 2.0), (3.5, 1.0), (5.0, -2.0)]),
        (
            Cycle::Repeat,
            &[
                (-1.0, 1.0),
                (-0.5, 2.5),
                (0.0, 4.0),
                (0.5, 3.0),
                (1.0, 1.0),
                (3.0, 2.0),
                (3.5, 2.5),
                (4.0, 4.0),
                (5.0, 1.0),
                (21.5, 2.5),
            ],
        ),
        (
            Cycle::RepeatOffset,
            &[
                (-1.0, 0.0),
                (0.0, 3.0),
                (0.5, 2.0),
                (1.0, 1.0),
                (3.0, 2.0),
                (3.5, 3.5),
                (4.0, 5.0),
                (5.0, 3.0),
                (21.5, 12.5),
            ],
        ),
        (
            Cycle::PingPong,
            // Mirrored at t = 3 (3.5 is 2.5) and t = 1 (0.5 is 1.5); period 4.
            &[
                (0.5, 2.5),
                (0.0, 4.0),
                (-1.0, 2.0),
                (3.5, 3.0),
                (4.0, 4.0),
                (5.0, 1.0),
                (5.5, 2.5),
                (7.0, 2.0),
            ],
        ),
    ];
    for (cycle, rows) in table {
        let track = cycled(scalar_keys(), cycle, cycle);
        for &(t, expected) in rows {
            let got = track.sample(t);
            assert!((got - expected).abs() < 1e-5, "{cycle:?} at t = {t}: {got}, expected {expected}");
        }
    }
}

#[test]
fn hold_is_the_track_of_old() {
    let keys = scalar_keys();
    let plain = Track::new(&RawTrack::new(keys.clone())).unwrap();
    assert_eq!(Track::with_cycles(&RawTrack::new(keys), Cycles::HOLD).unwrap(), plain);
}

#[test]
fn ends_can_differ() {
    let track = cycled(scalar_keys(), Cycle::Hold, Cycle::Repeat);
    assert_eq!(track.sample(-3.0), 1.0);
    assert!((track.sample(3.5) - 2.5).abs() < 1e-6);
    let track = cycled(scalar_keys(), Cycle::PingPong, Cycle::Hold);
    assert!((track.sample(0.5) - 2.5).abs() < 1e-6);
    assert_eq!(track.sample(9.0), 2.0);
}

#[test]
fn rotation_offset_adds_the_turn_each_cycle() {
    // 0° → 90° about Z in one second: each cycle turns another 90°.
    let z = |deg: f32| Quat::from_rotation_z(deg.to_radians());
    let keys = vec![
        Key::new(0.0, z(0.0)).with_interpolation(Interpolation::Linear),
        Key::new(1.0, z(90.0)).with_interpolation(Interpolation::Linear),
    ];
    let track = cycled(keys, Cycle::RepeatOffset, Cycle::RepeatOffset);
    for (t, deg) in [(1.5, 135.0), (2.0, 180.0), (3.25, 292.5), (-0.5, -45.0), (-2.0, -180.0)] {
        let got = track.sample(t);
        assert!(got.approx_dist(&z(deg)) < 1e-5, "t = {t}: {got:?}, expected {deg}°");
    }
}

#[test]
fn linear_rotation_keeps_turning() {
    let z = |deg: f32| Quat::from_rotation_z(deg.to_radians());
    let keys = vec![
        Key::new(0.0, z(0.0)).with_interpolation(Interpolation::Linear),
        Key::new(1.0, z(30.0)).with_interpolation(Interpolation::Linear),
    ];
    let track = cycled(keys, Cycle::Linear, Cycle::Linear);
    for (t, deg) in [(2.0, 60.0), (4.0, 120.0), (-1.0, -30.0)] {
        let got = track.sample(t);
        assert!(got.approx_dist(&z(deg)) < 1e-5, "t = {t}: {got:?}, expected {deg}°");
    }
}

#[test]
fn a_cycle_needs_two_keys() {
    let one = RawTrack::new(vec![Key::new(0.0, 1.0f32)]);
    assert_eq!(
        Track::with_cycles(&one, Cycles::new(Cycle::Hold, Cycle::Repeat)),
        Err(TrackError::CycleNeedsTwoKeys { end: TrackEnd::After, cycle: Cycle::Repeat })
    );
    let err = Track::with_cycles(&one, Cycles::new(Cycle::PingPong, Cycle::Hold)).unwrap_err();
    assert_eq!(err.to_string(), "Ping-pong before the keys needs at least two keys (a cycle repeats the time from the first key to the last)");
    // Keys spanning more than f64 can hold have no finite period.
    let huge = RawTrack::new(vec![Key::new(-1e308, 0.0f32), Key::new(1e308, 1.0)]);
    assert_eq!(
        Track::with_cycles(&huge, Cycles::new(Cycle::Linear, Cycle::Hold)),
        Err(TrackError::CyclePeriod { end: TrackEnd::Before, cycle: Cycle::Linear })
    );
    // An unanimated value has nothing to repeat: cycles are ignored.
    let constant = Animated::constant(2.0f32).with_cycles(Cycles::new(Cycle::Repeat, Cycle::Repeat));
    assert_eq!(AnimatedTrack::new(&constant).unwrap().sample(5.0), 2.0);
}

#[test]
fn scene_problems_name_the_track_and_end() {
    let mut scene = Scene::default();
    let mut object = keyrig_core::Object::new("Box");
    object.translation = Animated::new(Vec3::ZERO, RawTrack::new(vec![Key::new(0.0, Vec3::ZERO)]))
        .with_cycles(Cycles::new(Cycle::Hold, Cycle::Repeat));
    scene.objects.push(object);
    let problems = scene.problems();
    assert_eq!(problems.len(), 1, "{problems:?}");
    assert_eq!(problems[0].path, "objects[0].translation.after");
    assert!(problems[0].message.contains("Repeat after the keys needs at least two keys"), "{}", problems[0]);
}

// ---------------------------------------------------------------------------------------------
// Properties.

fn times(n: std::ops::Range<usize>) -> impl Strategy<Value = Vec<f64>> {
    (-5.0..5.0f64, prop::collection::vec(0.05..2.0f64, n)).prop_map(|(start, gaps)| {
        let mut t = start;
        gaps.iter()
            .map(|g| {
                let now = t;
                t += g;
                now
            })
            .collect()
    })
}

fn vec3() -> impl Strategy<Value = Vec3> {
    (-10.0..10.0f32, -10.0..10.0f32, -10.0..10.0f32).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn tcb_c0() -> impl Strategy<Value = Tcb> {
    (-0.9..=0.9f32, -0.9..=0.9f32).prop_map(|(t, b)| Tcb::new(t, 0.0, b))
}

fn mode() -> impl Strategy<Value = Interpolation> {
    prop_oneof![Just(Interpolation::Step), Just(Interpolation::Linear), Just(Interpolation::Tcb)]
}

fn unit_quat() -> impl Strategy<Value = Quat> {
    (vec3(), -std::f32::consts::PI..std::f32::consts::PI)
        .prop_filter("axis", |(axis, _)| axis.length() > 1e-2)
        .prop_map(|(axis, angle)| Quat::from_axis_angle(axis.normalize(), angle))
}

/// Rotation keys at most 90° apart from one to the next.
fn chained_quats(n: usize) -> impl Strategy<Value = Vec<Quat>> {
    (unit_quat(), prop::collection::vec((vec3(), 0.0..90.0f32), n)).prop_map(|(first, steps)| {
        let mut q = first;
        steps
            .iter()
            .map(|(axis, deg)| {
                let key = q;
                q = (q * Quat::from_axis_angle(axis.try_normalize().unwrap_or(Vec3::X), deg.to_radians()))
                    .normalize();
                key
            })
            .collect()
    })
}

fn repeating() -> impl Strategy<Value = Cycle> {
    prop_oneof![Just(Cycle::Repeat), Just(Cycle::RepeatOffset)]
}

/// Times spread over several periods on both sides of the keys.
fn probe(track_times: &[f64], fractions: &[f64]) -> Vec<f64> {
    let (t0, tn) = (track_times[0], track_times[track_times.len() - 1]);
    let period = tn - t0;
    fractions.iter().map(|f| t0 + (f * 8.0 - 4.0) * period).collect()
}

/// `q⁻¹·dq/dt` at `t` from one side (`dir` = ±1), by Richardson extrapolation, insensitive to the
/// sign of the quaternions.
fn angular_velocity(track: &Track<Quat>, t: f64, h: f64, dir: f64) -> DVec3 {
    let q0 = track.sample_wide(t);
    let between = |q: DQuat| {
        let mut r = q0.conjugate() * q;
        if r.w < 0.0 {
            r = -r;
        }
        log(r)
    };
    let l1 = between(track.sample_wide(t + dir * h));
    let l2 = between(track.sample_wide(t + dir * 2.0 * h));
    (l1 * 4.0 - l2) * (dir / (2.0 * h))
}

/// One-sided derivative of a Vec3 track by Richardson extrapolation.
fn vec3_velocity(track: &Track<Vec3>, t: f64, h: f64, dir: f64) -> DVec3 {
    let p0 = track.sample_wide(t);
    let d1 = track.sample_wide(t + dir * h) - p0;
    let d2 = track.sample_wide(t + dir * 2.0 * h) - p0;
    (d1 * 4.0 - d2) * (dir / (2.0 * h))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn vec3_repeat_is_periodic(
        ts in times(2..8), values in prop::collection::vec((vec3(), mode(), tcb_c0()), 8),
        cycle in repeating(), fractions in prop::collection::vec(0.0..1.0f64, 16),
    ) {
        let keys: Vec<Key<Vec3>> = ts.iter().zip(&values)
            .map(|(&t, &(v, m, tcb))| Key::new(t, v).with_interpolation(m).with_tcb(tcb)).collect();
        let track = cycled(keys.clone(), cycle, cycle);
        let period = ts[ts.len() - 1] - ts[0];
        let delta = if cycle == Cycle::RepeatOffset { keys[keys.len() - 1].value - keys[0].value } else { Vec3::ZERO };
        for t in probe(&ts, &fractions) {
            let (now, next) = (track.sample(t), track.sample(t + period));
            let scale = 1.0 + f64::from(now.abs().max_element());
            prop_assert!(next.approx_dist(&(now + delta)) <= 1e-4 * scale, "t = {}: {:?} then {:?}", t, now, next);
        }
    }

    #[test]
    fn scalar_repeat_is_periodic(
        ts in times(2..8), values in prop::collection::vec((-10.0..10.0f32, mode(), tcb_c0()), 8),
        cycle in repeating(), fractions in prop::collection::vec(0.0..1.0f64, 16),
    ) {
        let keys: Vec<Key<f32>> = ts.iter().zip(&values)
            .map(|(&t, &(v, m, tcb))| Key::new(t, v).with_interpolation(m).with_tcb(tcb)).collect();
        let track = cycled(keys.clone(), cycle, cycle);
        let period = ts[ts.len() - 1] - ts[0];
        let delta = if cycle == Cycle::RepeatOffset { keys[keys.len() - 1].value - keys[0].value } else { 0.0 };
        for t in probe(&ts, &fractions) {
            let (now, next) = (track.sample(t), track.sample(t + period));
            prop_assert!((next - (now + delta)).abs() <= 1e-4 * (1.0 + now.abs()), "t = {}: {} then {}", t, now, next);
        }
    }

    #[test]
    fn rotation_repeat_is_periodic(
        ts in times(2..8), quats in chained_quats(8), modes in prop::collection::vec((mode(), tcb_c0()), 8),
        cycle in repeating(), fractions in prop::collection::vec(0.0..1.0f64, 16),
    ) {
        let keys: Vec<Key<Quat>> = ts.iter().enumerate()
            .map(|(i, &t)| Key::new(t, quats[i]).with_interpolation(modes[i].0).with_tcb(modes[i].1)).collect();
        let track = cycled(keys, cycle, cycle);
        let period = ts[ts.len() - 1] - ts[0];
        let values = track.key_values();
        let m = if cycle == Cycle::RepeatOffset {
            values[values.len() - 1].as_dquat() * values[0].as_dquat().conjugate()
        } else {
            DQuat::IDENTITY
        };
        for t in probe(&ts, &fractions) {
            let (now, next) = (track.sample_wide(t), track.sample_wide(t + period));
            prop_assert!(next.approx_dist(&(m * now)) <= 1e-6, "t = {}: {:?} then {:?}", t, now, next);
        }
    }

    #[test]
    fn ping_pong_mirrors_at_both_ends(
        ts in times(2..8), values in prop::collection::vec((vec3(), mode(), tcb_c0()), 8),
        quats in chained_quats(8), fractions in prop::collection::vec(0.0..1.0f64, 8),
    ) {
        let keys: Vec<Key<Vec3>> = ts.iter().zip(&values)
            .map(|(&t, &(v, m, tcb))| Key::new(t, v).with_interpolation(m).with_tcb(tcb)).collect();
        let rotations: Vec<Key<Quat>> = ts.iter().zip(&values).enumerate()
            .map(|(i, (&t, &(_, m, tcb)))| Key::new(t, quats[i]).with_interpolation(m).with_tcb(tcb)).collect();
        let track = cycled(keys, Cycle::PingPong, Cycle::PingPong);
        let spin = cycled(rotations, Cycle::PingPong, Cycle::PingPong);
        let (t0, tn) = (ts[0], ts[ts.len() - 1]);
        let period = tn - t0;
        for f in &fractions {
            let x = f * period;
            for (a, b) in [(tn + x, tn - x), (t0 - x, t0 + x), (tn + x + 2.0 * period, tn - x)] {
                let (pa, pb) = (track.sample(a), track.sample(b));
                prop_assert!(pa.approx_dist(&pb) <= 1e-4 * (1.0 + f64::from(pb.abs().max_element())), "{} vs {}: {:?} {:?}", a, b, pa, pb);
                let (qa, qb) = (spin.sample_wide(a), spin.sample_wide(b));
                prop_assert!(qa.approx_dist(&qb) <= 1e-6, "{} vs {}: {:?} {:?}", a, b, qa, qb);
            }
        }
    }

    /// A RepeatOffset track, and a Repeat track whose last key equals its first, of C = 0 TCB
    /// keys (equal tension and bias at both ends) is continuous and C¹ through the seams.
    #[test]
    fn vec3_seam_is_c1(
        ts in times(3..8), values in prop::collection::vec((vec3(), tcb_c0()), 8), cycle in repeating(),
    ) {
        let n = ts.len();
        let mut keys: Vec<Key<Vec3>> = ts.iter().zip(&values).map(|(&t, &(v, tcb))| Key::new(t, v).with_tcb(tcb)).collect();
        keys[n - 1].tcb = keys[0].tcb;
        if cycle == Cycle::Repeat {
            keys[n - 1].value = keys[0].value;
        }
        let track = cycled(keys, cycle, cycle);
        let h = 1e-4 * (ts[1] - ts[0]).min(ts[n - 1] - ts[n - 2]);
        for seam in [ts[0], ts[n - 1], ts[n - 1] + (ts[n - 1] - ts[0])] {
            let (before, after) = (track.sample_wide(seam - 1e-9), track.sample_wide(seam + 1e-9));
            let scale = 1.0 + before.abs().max_element();
            prop_assert!(before.approx_dist(&after) <= 1e-6 * scale, "seam {}: {:?} {:?}", seam, before, after);
            let (left, right) = (vec3_velocity(&track, seam, h, -1.0), vec3_velocity(&track, seam, h, 1.0));
            let scale = 1.0 + left.abs().max_element().max(right.abs().max_element());
            prop_assert!(left.approx_dist(&right) <= 1e-4 * scale, "seam {}: {:?} vs {:?}", seam, left, right);
        }
    }

    #[test]
    fn scalar_seam_is_c1(
        ts in times(3..8), values in prop::collection::vec((-10.0..10.0f32, tcb_c0()), 8), cycle in repeating(),
    ) {
        let n = ts.len();
        let mut keys: Vec<Key<Vec3>> = ts.iter().zip(&values).map(|(&t, &(v, tcb))| Key::new(t, Vec3::splat(v)).with_tcb(tcb)).collect();
        keys[n - 1].tcb = keys[0].tcb;
        if cycle == Cycle::Repeat {
            keys[n - 1].value = keys[0].value;
        }
        // The same keys as a scalar track.
        let scalars: Vec<Key<f32>> = keys.iter().map(|k| Key::new(k.time, k.value.x).with_tcb(k.tcb)).collect();
        let track = cycled(scalars, cycle, cycle);
        let h = 1e-4 * (ts[1] - ts[0]).min(ts[n - 1] - ts[n - 2]);
        for seam in [ts[0], ts[n - 1]] {
            let velocity = |dir: f64| {
                let p0 = track.sample_wide(seam);
                ((track.sample_wide(seam + dir * h) - p0) * 4.0 - (track.sample_wide(seam + dir * 2.0 * h) - p0)) * (dir / (2.0 * h))
            };
            let (left, right) = (velocity(-1.0), velocity(1.0));
            prop_assert!((left - right).abs() <= 1e-4 * (1.0 + left.abs().max(right.abs())), "seam {}: {} vs {}", seam, left, right);
        }
    }

    #[test]
    fn rotation_seam_is_c1(
        ts in times(3..8), quats in chained_quats(8), tcbs in prop::collection::vec(tcb_c0(), 8), cycle in repeating(),
    ) {
        let n = ts.len();
        let mut keys: Vec<Key<Quat>> = ts.iter().enumerate().map(|(i, &t)| Key::new(t, quats[i]).with_tcb(tcbs[i])).collect();
        keys[n - 1].tcb = keys[0].tcb;
        if cycle == Cycle::Repeat {
            // Close the loop (the last key 90° or less from the one before it).
            keys[n - 1].value = -keys[0].value;
            let prev = keys[n - 2].value.as_dquat();
            prop_assume!(prev.dot(keys[0].value.as_dquat()).abs() > 0.3);
        }
        let track = cycled(keys, cycle, cycle);
        let h = 1e-4 * (ts[1] - ts[0]).min(ts[n - 1] - ts[n - 2]);
        for seam in [ts[0], ts[n - 1]] {
            let (before, after) = (track.sample_wide(seam - 1e-9), track.sample_wide(seam + 1e-9));
            prop_assert!(before.approx_dist(&after) <= 1e-6, "seam {}: {:?} {:?}", seam, before, after);
            let (left, right) = (angular_velocity(&track, seam, h, -1.0), angular_velocity(&track, seam, h, 1.0));
            let scale = 1.0 + left.length().max(right.length());
            prop_assert!(left.approx_dist(&right) <= 1e-4 * scale, "seam {}: {:?} vs {:?}", seam, left, right);
        }
    }

    /// Linear extrapolation leaves the end keys with their velocity.
    #[test]
    fn linear_is_c1_at_the_ends(ts in times(2..8), values in prop::collection::vec((vec3(), tcb_c0()), 8), quats in chained_quats(8)) {
        let n = ts.len();
        let keys: Vec<Key<Vec3>> = ts.iter().zip(&values).map(|(&t, &(v, tcb))| Key::new(t, v).with_tcb(tcb)).collect();
        let rotations: Vec<Key<Quat>> = ts.iter().zip(&values).enumerate().map(|(i, (&t, &(_, tcb)))| Key::new(t, quats[i]).with_tcb(tcb)).collect();
        let track = cycled(keys, Cycle::Linear, Cycle::Linear);
        let spin = cycled(rotations, Cycle::Linear, Cycle::Linear);
        let h = 1e-4 * (ts[1] - ts[0]).min(ts[n - 1] - ts[n - 2]);
        for end in [ts[0], ts[n - 1]] {
            let (left, right) = (vec3_velocity(&track, end, h, -1.0), vec3_velocity(&track, end, h, 1.0));
            let scale = 1.0 + left.abs().max_element().max(right.abs().max_element());
            prop_assert!(left.approx_dist(&right) <= 1e-4 * scale, "end {}: {:?} vs {:?}", end, left, right);
            let (left, right) = (angular_velocity(&spin, end, h, -1.0), angular_velocity(&spin, end, h, 1.0));
            let scale = 1.0 + left.length().max(right.length());
            prop_assert!(left.approx_dist(&right) <= 1e-4 * scale, "end {}: {:?} vs {:?}", end, left, right);
        }
    }
}
