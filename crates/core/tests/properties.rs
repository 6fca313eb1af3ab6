//! Property tests for every interpolation invariant of docs/design.md §3.

mod support;

use glam::{DQuat, DVec3, Quat, Vec3};
use keyrig_core::quat::{exp, log_between, slerp};
use keyrig_core::{Interpolation, Key, RawTrack, Tcb, Track, TrackError};
use proptest::prelude::*;
use support::ApproxDist;

// ---------------------------------------------------------------------------------------------
// Strategies.

/// Strictly increasing times with uneven gaps (ratios up to 3000 between neighbours).
fn times(n: std::ops::Range<usize>) -> impl Strategy<Value = Vec<f64>> {
    (-5.0..5.0f64, prop::collection::vec(1e-3..3.0f64, n)).prop_map(|(start, gaps)| {
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

fn tcb() -> impl Strategy<Value = Tcb> {
    (-1.0..=1.0f32, -1.0..=1.0f32, -1.0..=1.0f32).prop_map(|(t, c, b)| Tcb::new(t, c, b))
}

fn tcb_c0() -> impl Strategy<Value = Tcb> {
    (-1.0..=1.0f32, -1.0..=1.0f32).prop_map(|(t, b)| Tcb::new(t, 0.0, b))
}

fn mode() -> impl Strategy<Value = Interpolation> {
    prop_oneof![
        Just(Interpolation::Step),
        Just(Interpolation::Linear),
        Just(Interpolation::Tcb),
        Just(Interpolation::Hermite)
    ]
}

fn vec3() -> impl Strategy<Value = Vec3> {
    (-10.0..10.0f32, -10.0..10.0f32, -10.0..10.0f32).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn unit_quat() -> impl Strategy<Value = Quat> {
    (vec3(), -std::f32::consts::PI..std::f32::consts::PI)
        .prop_filter("axis", |(axis, _)| axis.length() > 1e-2)
        .prop_map(|(axis, angle)| Quat::from_axis_angle(axis.normalize(), angle))
}

/// Rotation keys whose consecutive keys are at most `max_deg` apart, with a random sign each.
fn chained_quats(n: std::ops::Range<usize>, max_deg: f32) -> impl Strategy<Value = Vec<Quat>> {
    (unit_quat(), prop::collection::vec((vec3(), 0.0..max_deg, any::<bool>()), n)).prop_map(
        |(first, steps)| {
            let mut q = first;
            steps
                .iter()
                .map(|(axis, deg, negate)| {
                    let axis = axis.try_normalize().unwrap_or(Vec3::X);
                    let key = if *negate { -q } else { q };
                    q = (q * Quat::from_axis_angle(axis, deg.to_radians())).normalize();
                    key
                })
                .collect()
        },
    )
}

/// A Vec3 track with random modes, T/C/B and (for Hermite keys) tangents.
fn vec3_keys() -> impl Strategy<Value = Vec<Key<Vec3>>> {
    times(2..12).prop_flat_map(|ts| {
        let n = ts.len();
        (Just(ts), prop::collection::vec((vec3(), mode(), tcb(), vec3(), vec3()), n)).prop_map(
            |(ts, rest)| {
                ts.iter()
                    .zip(rest)
                    .map(|(&t, (v, m, tcb, tin, tout))| {
                        let mut k = Key::new(t, v).with_interpolation(m).with_tcb(tcb);
                        k.in_tangent = Some(tin);
                        k.out_tangent = Some(tout);
                        k
                    })
                    .collect()
            },
        )
    })
}

/// A rotation track with random modes, T/C/B and tangents.
fn quat_keys(max_deg: f32) -> impl Strategy<Value = Vec<Key<Quat>>> {
    times(2..10).prop_flat_map(move |ts| {
        let n = ts.len();
        (Just(ts), chained_quats(n..n + 1, max_deg), prop::collection::vec((mode(), tcb(), unit_quat()), n))
            .prop_map(|(ts, qs, rest)| {
                ts.iter()
                    .zip(qs)
                    .zip(rest)
                    .map(|((&t, q), (m, tcb, tangent))| {
                        let mut k = Key::new(t, q).with_interpolation(m).with_tcb(tcb);
                        k.in_tangent = Some(tangent * 0.5);
                        k.out_tangent = Some(tangent * -0.5);
                        k
                    })
                    .collect()
            })
    })
}

/// Times to sample a track at: inside, outside and at its keys.
fn probe_times(key_times: &[f64], fractions: &[f64]) -> Vec<f64> {
    let (first, last) = (key_times[0], key_times[key_times.len() - 1]);
    let mut ts: Vec<f64> = fractions.iter().map(|f| first - 1.0 + f * (last - first + 2.0)).collect();
    ts.extend_from_slice(key_times);
    ts
}

fn track<T: keyrig_core::TrackValue>(keys: Vec<Key<T>>) -> Track<T> {
    Track::new(&RawTrack::new(keys)).expect("generated keys are valid")
}

// ---------------------------------------------------------------------------------------------
// Reference formulas written out independently of the implementation.

/// Uniform Catmull–Rom in matrix form, with P_{-1} := P_0 and P_{n+1} := P_n.
fn catmull_rom(p: &[DVec3], i: usize, u: f64) -> DVec3 {
    let at = |j: isize| p[j.clamp(0, p.len() as isize - 1) as usize];
    let i = i as isize;
    let (p0, p1, p2, p3) = (at(i - 1), at(i), at(i + 1), at(i + 2));
    0.5 * (2.0 * p1
        + (p2 - p0) * u
        + (2.0 * p0 - 5.0 * p1 + 4.0 * p2 - p3) * (u * u)
        + (-p0 + 3.0 * p1 - 3.0 * p2 + p3) * (u * u * u))
}

/// Shoemake's squad (1987) with s_i = q_i·exp(−(log(q_i⁻¹q_{i+1}) + log(q_i⁻¹q_{i−1}))/4) and
/// q_{−1} := q_0, q_{n+1} := q_n. `q` must be sign-consistent.
fn shoemake_squad(q: &[DQuat], i: usize, u: f64) -> DQuat {
    let at = |j: isize| q[j.clamp(0, q.len() as isize - 1) as usize];
    let s = |j: isize| at(j) * exp(-(log_between(at(j), at(j + 1)) + log_between(at(j), at(j - 1))) * 0.25);
    let i = i as isize;
    let (qi, qn) = (at(i), at(i + 1));
    slerp(slerp(qi, qn, u), slerp(s(i), s(i + 1), u), 2.0 * u * (1.0 - u))
}

fn sign_consistent(quats: &[Quat]) -> Vec<DQuat> {
    let mut out: Vec<DQuat> = quats.iter().map(|q| q.as_dquat().normalize()).collect();
    for i in 1..out.len() {
        if out[i - 1].dot(out[i]) < 0.0 {
            out[i] = -out[i];
        }
    }
    out
}

/// Right (`dir = 1`) or left (`dir = −1`) body-frame angular velocity (half-angle per second)
/// at `t`, by a second-order one-sided difference of `log(q(t)⁻¹ q(t ± h))`.
fn angular_velocity(track: &Track<Quat>, t: f64, h: f64, dir: f64) -> DVec3 {
    let q0 = track.sample_wide(t);
    let l1 = log_between(q0, track.sample_wide(t + dir * h));
    let l2 = log_between(q0, track.sample_wide(t + dir * 2.0 * h));
    (l1 * 4.0 - l2) * (dir / (2.0 * h))
}

// ---------------------------------------------------------------------------------------------

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    #[test]
    fn vec3_tracks_pass_through_every_key_exactly(keys in vec3_keys()) {
        let track = track(keys.clone());
        for k in &keys {
            prop_assert_eq!(track.sample(k.time), k.value);
        }
        let values: Vec<Vec3> = keys.iter().map(|k| k.value).collect();
        prop_assert_eq!(track.key_values(), values.as_slice());
    }

    #[test]
    fn rotation_tracks_pass_through_every_key(keys in quat_keys(170.0)) {
        let track = track(keys.clone());
        for (i, k) in keys.iter().enumerate() {
            let sampled = track.sample(k.time);
            prop_assert_eq!(sampled, track.key_values()[i]);
            prop_assert!(sampled.approx_dist(&k.value.normalize()) <= 2.5e-7, "key {}: {:?} vs {:?}", i, sampled, k.value);
        }
    }

    #[test]
    fn rotations_are_unit_everywhere(keys in quat_keys(179.0), fractions in prop::collection::vec(0.0..1.0f64, 40)) {
        let track = track(keys.clone());
        for t in probe_times(track.key_times(), &fractions) {
            let q = track.sample(t);
            prop_assert!(q.is_finite() && (q.length() - 1.0).abs() < 1e-6, "t = {}: {:?}", t, q);
            let wide = track.sample_wide(t);
            prop_assert!((wide.length() - 1.0).abs() < 1e-12, "t = {}: |q| = {}", t, wide.length());
        }
    }

    #[test]
    fn vec3_tcb_is_c1_at_keys_with_zero_continuity(
        ts in times(3..10),
        values in prop::collection::vec(vec3(), 10),
        tcbs in prop::collection::vec(tcb_c0(), 10),
    ) {
        let keys = ts.iter().enumerate().map(|(i, &t)| Key::new(t, values[i]).with_tcb(tcbs[i])).collect();
        let track = track(keys);
        for &t in &ts[1..ts.len() - 1] {
            let (left, right) = (track.velocity_before_wide(t), track.velocity_wide(t));
            let scale = 1.0 + left.abs().max_element();
            prop_assert!(left.approx_dist(&right) <= 1e-9 * scale, "t = {}: {:?} vs {:?}", t, left, right);
        }
    }

    #[test]
    fn scalar_tcb_is_c1_at_keys_with_zero_continuity(
        ts in times(3..10),
        values in prop::collection::vec(-10.0..10.0f32, 10),
        tcbs in prop::collection::vec(tcb_c0(), 10),
    ) {
        let keys = ts.iter().enumerate().map(|(i, &t)| Key::new(t, values[i]).with_tcb(tcbs[i])).collect();
        let track = track(keys);
        for &t in &ts[1..ts.len() - 1] {
            let (left, right) = (track.velocity_before_wide(t), track.velocity_wide(t));
            prop_assert!((left - right).abs() <= 1e-9 * (1.0 + left.abs()), "t = {}: {} vs {}", t, left, right);
        }
    }

    #[test]
    fn squad_is_c1_at_keys_with_zero_continuity(
        gaps in prop::collection::vec(0.05..2.0f64, 3..8),
        tcbs in prop::collection::vec(tcb_c0(), 8),
        quats in chained_quats(8..9, 90.0),
    ) {
        let mut t = 0.0;
        let keys: Vec<Key<Quat>> = std::iter::once(0.0)
            .chain(gaps.iter().map(|g| { t += g; t }))
            .enumerate()
            .map(|(i, t)| Key::new(t, quats[i]).with_tcb(tcbs[i]))
            .collect();
        let track = track(keys.clone());
        for i in 1..keys.len() - 1 {
            let h = 1e-4 * gaps[i - 1].min(gaps[i]);
            let left = angular_velocity(&track, keys[i].time, h, -1.0);
            let right = angular_velocity(&track, keys[i].time, h, 1.0);
            let scale = 1.0 + left.length().max(right.length());
            prop_assert!(left.approx_dist(&right) <= 1e-5 * scale, "key {}: {:?} vs {:?}", i, left, right);
        }
    }

    #[test]
    fn vec3_velocity_matches_finite_differences(keys in vec3_keys(), fractions in prop::collection::vec(0.02..0.98f64, 8)) {
        let track = track(keys);
        let ts = track.key_times().to_vec();
        for w in ts.windows(2) {
            for f in &fractions {
                let (t, h) = (w[0] + f * (w[1] - w[0]), 1e-5 * (w[1] - w[0]));
                let numeric = (track.sample_wide(t + h) - track.sample_wide(t - h)) / (2.0 * h);
                let analytic = track.velocity_wide(t);
                let scale = 1.0 + numeric.abs().max_element();
                prop_assert!(numeric.approx_dist(&analytic) <= 1e-5 * scale, "t = {}: {:?} vs {:?}", t, numeric, analytic);
            }
        }
    }

    #[test]
    fn zero_tcb_on_uniform_keys_is_catmull_rom(
        values in prop::collection::vec(vec3(), 2..10),
        dt in 0.01..5.0f64,
        start in -3.0..3.0f64,
        us in prop::collection::vec(0.0..1.0f64, 5),
    ) {
        let keys = values.iter().enumerate().map(|(i, &v)| Key::new(start + i as f64 * dt, v)).collect();
        let track = track(keys);
        let p: Vec<DVec3> = values.iter().map(|v| v.as_dvec3()).collect();
        for i in 0..p.len() - 1 {
            for &u in &us {
                let t = start + (i as f64 + u) * dt;
                if t >= start + (i + 1) as f64 * dt { continue; }
                let expected = catmull_rom(&p, i, (t - (start + i as f64 * dt)) / dt);
                prop_assert!(track.sample_wide(t).approx_dist(&expected) <= 1e-11, "segment {} u {}", i, u);
            }
        }
    }

    #[test]
    fn zero_tcb_on_uniform_rotation_keys_is_shoemake_squad(
        quats in chained_quats(2..9, 150.0),
        dt in 0.01..5.0f64,
        us in prop::collection::vec(0.0..1.0f64, 5),
    ) {
        let keys = quats.iter().enumerate().map(|(i, &q)| Key::new(i as f64 * dt, q)).collect();
        let track = track(keys);
        let q = sign_consistent(&quats);
        for i in 0..q.len() - 1 {
            for &u in &us {
                let t = (i as f64 + u) * dt;
                let u = (t - i as f64 * dt) / dt;
                let expected = shoemake_squad(&q, i, u);
                prop_assert!(track.sample_wide(t).approx_dist(&expected) <= 1e-12, "segment {} u {}", i, u);
            }
        }
    }

    #[test]
    fn negated_rotation_keys_give_the_same_rotations(
        keys in quat_keys(170.0),
        flips in prop::collection::vec(any::<bool>(), 10),
        fractions in prop::collection::vec(0.0..1.0f64, 30),
    ) {
        // Hermite keys carry tangents that belong to their sign; leave them out here.
        let keys: Vec<Key<Quat>> = keys
            .into_iter()
            .map(|k| if k.interpolation == Interpolation::Hermite { k.with_interpolation(Interpolation::Tcb) } else { k })
            .collect();
        let negated: Vec<Key<Quat>> = keys
            .iter()
            .zip(&flips)
            .map(|(k, &flip)| { let mut k = k.clone(); if flip { k.value = -k.value; } k })
            .collect();
        let (a, b) = (track(keys), track(negated));
        for t in probe_times(a.key_times(), &fractions) {
            prop_assert!(a.sample_wide(t).approx_dist(&b.sample_wide(t)) <= 1e-12, "t = {}", t);
            prop_assert!(a.sample(t).approx_dist(&b.sample(t)) <= 1e-6, "t = {}", t);
        }
    }

    #[test]
    fn identical_or_nearly_coincident_keys_give_finite_output(
        value in vec3(),
        q in unit_quat(),
        modes in prop::collection::vec((mode(), tcb()), 6),
        spacing in prop_oneof![Just(1e-7), Just(1e-9), 1e-7..1.0f64],
        jitter in prop::collection::vec(vec3(), 6),
        fractions in prop::collection::vec(0.0..1.0f64, 30),
    ) {
        let make = |i: usize, v: Vec3| {
            let mut k = Key::new(1.0 + i as f64 * spacing, v).with_interpolation(modes[i].0).with_tcb(modes[i].1);
            k.in_tangent = Some(Vec3::ZERO);
            k.out_tangent = Some(Vec3::ZERO);
            k
        };
        // All keys equal: the track is that constant (Hermite with zero tangents included).
        let same = track((0..6).map(|i| make(i, value)).collect());
        // Keys 1e-7 apart with different values: finite, bounded overshoot.
        let apart = track((0..6).map(|i| make(i, jitter[i])).collect());
        let rotations = track(
            (0..6)
                .map(|i| {
                    let mut k = Key::new(1.0 + i as f64 * spacing, q).with_interpolation(modes[i].0).with_tcb(modes[i].1);
                    k.in_tangent = Some(Quat::from_xyzw(0.0, 0.0, 0.0, 0.0));
                    k.out_tangent = Some(Quat::from_xyzw(0.0, 0.0, 0.0, 0.0));
                    k
                })
                .collect(),
        );
        for t in probe_times(same.key_times(), &fractions) {
            prop_assert!(same.sample(t).approx_dist(&value) <= 1e-5, "t = {}", t);
            let v = apart.sample(t);
            prop_assert!(v.is_finite() && v.abs().max_element() < 200.0, "t = {}: {:?}", t, v);
            prop_assert!(apart.velocity(t).is_finite(), "t = {}", t);
            let r = rotations.sample(t);
            prop_assert!(r.approx_dist(&q) <= 1e-6 && (r.length() - 1.0).abs() < 1e-6, "t = {}: {:?}", t, r);
        }
    }

    #[test]
    fn duplicate_times_and_nan_values_are_named(keys in vec3_keys(), pick in any::<prop::sample::Index>()) {
        let i = 1 + pick.index(keys.len() - 1);
        let mut dup = keys.clone();
        dup[i].time = dup[i - 1].time;
        prop_assert_eq!(Track::new(&RawTrack::new(dup)).unwrap_err(), TrackError::DuplicateTime { index: i });

        let mut nan = keys.clone();
        nan[i].value.z = f32::NAN;
        prop_assert_eq!(Track::new(&RawTrack::new(nan)).unwrap_err(), TrackError::NonFiniteValue { index: i });

        let mut nan_time = keys;
        nan_time[i].time = f64::NAN;
        prop_assert_eq!(Track::new(&RawTrack::new(nan_time)).unwrap_err(), TrackError::NonFiniteTime { index: i });
    }

}
