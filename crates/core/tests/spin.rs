//! Spin keys (issue 14; docs/design.md §3): rotation segments beyond half a turn.
//!
//! ```text
//!  key 0            key 1                          key 2
//!  0° ─── Linear, Turns(1): 90° + 360° ───▶ 450° ─── TCB, Angle(X, −720°) ───▶ −270°
//! ```

mod support;

use glam::{DQuat, DVec3, Quat, Vec3};
use keyrig_core::quat::log_between;
use keyrig_core::{Interpolation, Key, RawTrack, Spin, SpinProblem, Tcb, Track, TrackError};
use proptest::prelude::*;
use support::ApproxDist;

fn track(keys: Vec<Key<Quat>>) -> Track<Quat> {
    Track::new(&RawTrack::new(keys)).expect("valid keys")
}

fn rot(axis: DVec3, degrees: f64) -> DQuat {
    DQuat::from_axis_angle(axis.normalize(), degrees.to_radians())
}

fn unit_axis() -> impl Strategy<Value = DVec3> {
    (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64)
        .prop_filter("axis", |(x, y, z)| DVec3::new(*x, *y, *z).length() > 0.1)
        .prop_map(|(x, y, z)| DVec3::new(x, y, z).normalize())
}

fn unit_quat() -> impl Strategy<Value = DQuat> {
    (unit_axis(), -180.0..180.0f64).prop_map(|(axis, deg)| rot(axis, deg))
}

/// The signed angle (degrees) of the rotation `q` about `axis`, assuming `q` turns about it:
/// `2·atan2(v·axis, w)`, in (−360°, 360°].
fn angle_about(q: DQuat, axis: DVec3) -> f64 {
    2.0 * DVec3::new(q.x, q.y, q.z).dot(axis).atan2(q.w).to_degrees()
}

/// Right (`dir = 1`) or left (`dir = −1`) body-frame angular velocity by a second-order
/// one-sided difference (as in properties.rs).
fn angular_velocity(track: &Track<Quat>, t: f64, h: f64, dir: f64) -> DVec3 {
    let q0 = track.sample_wide(t);
    let l1 = log_between(q0, track.sample_wide(t + dir * h));
    let l2 = log_between(q0, track.sample_wide(t + dir * 2.0 * h));
    (l1 * 4.0 - l2) * (dir / (2.0 * h))
}

/// A spin on the key after `prev`: whole turns or an angle, plus the key value it arrives at.
#[derive(Clone, Debug)]
enum SpinChoice {
    Turns { short_deg: f64, turns: i32 },
    Angle { degrees: f64 },
    None { short_deg: f64 },
}

fn spin_choice() -> impl Strategy<Value = SpinChoice> {
    prop_oneof![
        (prop_oneof![1.0..170.0f64, -170.0..-1.0f64], -3..=3i32)
            .prop_map(|(short_deg, turns)| SpinChoice::Turns { short_deg, turns }),
        (-1500.0..1500.0f64).prop_map(|degrees| SpinChoice::Angle { degrees }),
        (-90.0..90.0f64).prop_map(|short_deg| SpinChoice::None { short_deg }),
    ]
}

/// Keys from `first` turning about per-segment axes; returns the keys and, per segment, the
/// unwrapped angle the track should turn.
fn spin_keys(first: DQuat, steps: &[(DVec3, SpinChoice)], times: &[f64], tcbs: &[Tcb]) -> Vec<Key<Quat>> {
    let mut q = first;
    let mut keys = vec![Key::new(times[0], q.as_quat()).with_tcb(tcbs[0])];
    for (i, (axis, choice)) in steps.iter().enumerate() {
        let (degrees, spin) = match *choice {
            SpinChoice::Turns { short_deg, turns } => (short_deg, Some(Spin::Turns(turns))),
            SpinChoice::Angle { degrees } => (degrees, Some(Spin::Angle { axis: axis.as_vec3(), degrees })),
            SpinChoice::None { short_deg } => (short_deg, None),
        };
        q = (q * rot(*axis, degrees)).normalize();
        let mut key = Key::new(times[i + 1], q.as_quat()).with_tcb(tcbs[i + 1]);
        key.spin = spin;
        keys.push(key);
    }
    keys
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Linear with n extra turns: q_0⁻¹·q(t) stays a rotation about the segment's axis whose
    /// unwrapped angle (summed from small steps, independently of the track's own
    /// bookkeeping) grows monotonically to short + 360°·n.
    #[test]
    fn linear_segment_with_turns_rotates_monotonically_by_the_unwrapped_angle(
        first in unit_quat(),
        axis in unit_axis(),
        short_deg in 1.0..179.0f64,
        turns in prop_oneof![-6..=-1i32, 1..=6i32],
        flip in any::<bool>(),
    ) {
        let end = first * rot(axis, short_deg);
        let end = if flip { -end } else { end };
        let keys = vec![
            Key::new(0.0, first.as_quat()).with_interpolation(Interpolation::Linear),
            Key::new(2.0, end.as_quat()).with_spin(Spin::Turns(turns)),
        ];
        let track = track(keys);
        let total = short_deg + 360.0 * f64::from(turns);
        let (spin_axis, spin_deg) = track.segment_spin(0).expect("a spin segment");
        prop_assert!(spin_axis.approx_dist(&axis) < 1e-5, "{spin_axis:?} vs {axis:?}");
        prop_assert!((spin_deg - total).abs() < 1e-4, "{spin_deg} vs {total}");
        let q0 = track.sample_wide(0.0);
        let steps = 2000;
        let mut unwrapped = 0.0;
        let mut previous = q0;
        for k in 1..=steps {
            let t = 2.0 * f64::from(k) / f64::from(steps);
            let q = track.sample_wide(t);
            let relative = q0.conjugate() * q;
            // About the axis: the vector part is parallel to it.
            let v = DVec3::new(relative.x, relative.y, relative.z);
            prop_assert!(v.cross(axis).length() < 1e-5, "t = {t}: {relative:?} not about {axis:?}");
            let step = angle_about(previous.conjugate() * q, axis);
            let step = if step > 180.0 { step - 360.0 } else if step < -180.0 { step + 360.0 } else { step };
            prop_assert!(step * total.signum() > 0.0, "t = {t}: step {step}° against the turn {total}°");
            unwrapped += step;
            let expected = total * t / 2.0;
            prop_assert!((unwrapped - expected).abs() < 1e-3, "t = {t}: {unwrapped}° vs {expected}°");
            let reported = track.spin_degrees(t).expect("inside a spin segment");
            // The track's own angle comes from the f32 key values: u · (its unwrapped chord).
            let own = spin_deg * t / 2.0;
            prop_assert!((reported - own).abs() < 1e-9, "t = {t}: reported {reported}° vs {own}°");
            previous = q;
        }
        prop_assert!((unwrapped - total).abs() < 1e-3, "{unwrapped} vs {total}");
    }

    /// TCB through spin keys (Turns, Angle and short ones mixed, any axes, uneven spacing)
    /// passes through every key and is C¹ at keys with C = 0.
    #[test]
    fn tcb_through_spin_keys_passes_keys_and_is_c1_at_zero_continuity(
        first in unit_quat(),
        steps in prop::collection::vec((unit_axis(), spin_choice()), 2..6),
        gaps in prop::collection::vec(0.05..2.0f64, 6),
        tcbs in prop::collection::vec((-1.0..=1.0f32, -1.0..=1.0f32), 7),
    ) {
        let times: Vec<f64> = std::iter::once(0.0)
            .chain(gaps.iter().scan(0.0, |t, g| { *t += g; Some(*t) }))
            .collect();
        let tcbs: Vec<Tcb> = tcbs.iter().map(|&(t, b)| Tcb::new(t, 0.0, b)).collect();
        let keys = spin_keys(first, &steps, &times, &tcbs);
        let track = track(keys.clone());
        for (i, k) in keys.iter().enumerate() {
            let sampled = track.sample(k.time);
            prop_assert!(sampled.approx_dist(&k.value.normalize()) <= 2.5e-7, "key {i}: {sampled:?} vs {:?}", k.value);
            // Arriving at the key from inside the segment before it, too (continuity).
            if i > 0 {
                let before = track.sample_wide(k.time - 1e-9 * (k.time - keys[i - 1].time));
                prop_assert!(before.approx_dist(&k.value.as_dquat().normalize()) <= 1e-6, "key {i} from the left: {before:?}");
            }
        }
        // A segment's mean angular speed (rad/s): its unwrapped angle over its duration.
        let mean_speed = |s: usize| {
            let angle = track.segment_spin(s).map_or_else(
                || 2.0 * keys[s].value.as_dquat().dot(keys[s + 1].value.as_dquat()).abs().min(1.0).acos(),
                |(_, degrees)| degrees.abs().to_radians(),
            );
            angle / gaps[s]
        };
        for i in 1..keys.len() - 1 {
            let h = 1e-4 * gaps[i - 1].min(gaps[i]);
            let left = angular_velocity(&track, keys[i].time, h, -1.0);
            let right = angular_velocity(&track, keys[i].time, h, 1.0);
            // The one-sided differences err by h²·q‴ and the f32 key values by ~6e-8 of each
            // segment's rotation: both grow with the neighbouring segments' speed, which can be
            // hundreds of times the speed at the key (a spin of several turns after a key of
            // high tension starts slowly).
            let scale = 1.0 + left.length().max(right.length()) + 0.1 * mean_speed(i - 1).max(mean_speed(i));
            prop_assert!(left.approx_dist(&right) <= 1e-5 * scale, "key {i}: {left:?} vs {right:?}");
        }
    }

    /// A twist about one axis is a scalar TCB curve of its unwrapped angles: with every key
    /// about X, the rotation track's angle equals the scalar track through the cumulative
    /// angles (same times, T/C/B and modes), spin segments and short ones alike. (Short
    /// segments stay within 40° and T/C/B within ±0.3 so that Squad's own short-way slerps
    /// never wrap; spin segments have no such limit.)
    #[test]
    fn twist_about_one_axis_follows_the_scalar_tcb_curve_of_its_angles(
        steps in prop::collection::vec(prop_oneof![
            (-40.0..40.0f64).prop_map(|d| (d, false)),
            (-1000.0..1000.0f64).prop_map(|d| (d, true)),
        ], 1..6),
        gaps in prop::collection::vec(0.5..1.5f64, 6),
        tcbs in prop::collection::vec((-0.3..=0.3f32, -0.3..=0.3f32, -0.3..=0.3f32), 7),
        linear in prop::collection::vec(any::<bool>(), 7),
        fractions in prop::collection::vec(0.0..1.0f64, 20),
    ) {
        let times: Vec<f64> = std::iter::once(0.0)
            .chain(gaps.iter().scan(0.0, |t, g| { *t += g; Some(*t) }))
            .take(steps.len() + 1)
            .collect();
        let mut angles = vec![0.0];
        for (d, _) in &steps {
            angles.push(angles.last().unwrap() + d);
        }
        let mode = |i: usize| if linear[i] { Interpolation::Linear } else { Interpolation::Tcb };
        let tcb = |i: usize| Tcb::new(tcbs[i].0, tcbs[i].1, tcbs[i].2);
        let rotations: Vec<Key<Quat>> = angles
            .iter()
            .enumerate()
            .map(|(i, &a)| {
                let mut k = Key::new(times[i], rot(DVec3::X, a).as_quat()).with_tcb(tcb(i)).with_interpolation(mode(i));
                if i > 0 && steps[i - 1].1 {
                    k.spin = Some(Spin::Angle { axis: Vec3::X, degrees: steps[i - 1].0 });
                }
                k
            })
            .collect();
        let scalar: Vec<Key<f32>> = angles
            .iter()
            .enumerate()
            .map(|(i, &a)| Key::new(times[i], a as f32).with_tcb(tcb(i)).with_interpolation(mode(i)))
            .collect();
        let (rotation, scalar) = (track(rotations), Track::new(&RawTrack::new(scalar)).unwrap());
        let end = *times.last().unwrap();
        for f in &fractions {
            let t = f * end;
            let expected = rot(DVec3::X, scalar.sample_wide(t));
            let got = rotation.sample_wide(t);
            // f32 key values (and f32 angles up to ~5000°): a few 1e-6 of rounding.
            prop_assert!(got.approx_dist(&expected) <= 1e-5, "t = {t}: {got:?} vs {expected:?} ({}°)", scalar.sample_wide(t));
        }
    }

    /// `Turns(0)` is the short way: the same samples, bit for bit, as no spin.
    #[test]
    fn turns_zero_is_the_short_way(first in unit_quat(), axis in unit_axis(), deg in -170.0..170.0f64, fractions in prop::collection::vec(0.0..1.0f64, 10)) {
        let end = (first * rot(axis, deg)).as_quat();
        let plain = track(vec![Key::new(0.0, first.as_quat()), Key::new(1.0, end), Key::new(1.5, first.as_quat())]);
        let zero = track(vec![Key::new(0.0, first.as_quat()), Key::new(1.0, end).with_spin(Spin::Turns(0)), Key::new(1.5, first.as_quat())]);
        for f in &fractions {
            prop_assert_eq!(plain.sample_wide(f * 1.5), zero.sample_wide(f * 1.5));
        }
        prop_assert!(!zero.has_spin());
    }
}

#[test]
fn a_full_turn_with_two_keys() {
    // 0° ─── Angle(X, 360°) ───▶ 360°, both keys the identity.
    let keys = vec![
        Key::new(0.0, Quat::IDENTITY).with_interpolation(Interpolation::Linear),
        Key::new(1.0, Quat::IDENTITY).with_spin(Spin::Angle { axis: Vec3::X, degrees: 360.0 }),
    ];
    let linear = track(keys.clone());
    let tcb = track(keys.into_iter().map(|k| k.with_interpolation(Interpolation::Tcb)).collect());
    for (t, degrees) in [(0.0, 0.0), (0.25, 90.0), (0.5, 180.0), (0.75, 270.0), (1.0, 360.0)] {
        let expected = rot(DVec3::X, degrees);
        assert!(linear.sample_wide(t).approx_dist(&expected) < 1e-12, "t = {t}");
        assert!((linear.spin_degrees(t).unwrap() - degrees).abs() < 1e-9, "t = {t}");
    }
    // TCB with two keys: ease in and out (end tangents half the chord), 180° at the middle.
    assert!(tcb.sample_wide(0.5).approx_dist(&rot(DVec3::X, 180.0)) < 1e-12);
    assert!((tcb.spin_degrees(0.5).unwrap() - 180.0).abs() < 1e-9);
    assert!((tcb.spin_degrees(1.0).unwrap() - 360.0).abs() < 1e-9);
    assert!(tcb.spin_degrees(0.25).unwrap() < 90.0);
    assert_eq!(tcb.spin_degrees(-1.0), Some(0.0));
    assert_eq!(tcb.spin_degrees(2.0), Some(360.0));
}

#[test]
fn turns_follow_the_short_way_and_negative_turns_go_against_it() {
    let q90 = rot(DVec3::Z, 90.0).as_quat();
    for (turns, total) in [(1, 450.0), (2, 810.0), (-1, -270.0), (-2, -630.0)] {
        let t = track(vec![
            Key::new(0.0, Quat::IDENTITY).with_interpolation(Interpolation::Linear),
            Key::new(1.0, q90).with_spin(Spin::Turns(turns)),
        ]);
        let (axis, degrees) = t.segment_spin(0).unwrap();
        assert!(axis.approx_dist(&DVec3::Z) < 1e-7);
        assert!((degrees - total).abs() < 1e-4, "{turns}: {degrees}");
        assert!(t.sample_wide(0.5).approx_dist(&rot(DVec3::Z, total / 2.0)) < 1e-7, "{turns}");
    }
}

#[test]
fn spin_keys_next_to_short_keys_keep_short_segments_unchanged_elsewhere() {
    // Segments two keys away from a spin are the ordinary Squad: same samples as without.
    let keys: Vec<Key<Quat>> = [0.0, 40.0, 80.0, 120.0, 160.0]
        .iter()
        .enumerate()
        .map(|(i, &d)| Key::new(i as f64, rot(DVec3::Y, d).as_quat()))
        .collect();
    let mut spun = keys.clone();
    spun[4] = Key::new(4.0, rot(DVec3::Y, 160.0).as_quat()).with_spin(Spin::Turns(1));
    let (a, b) = (track(keys), track(spun));
    for t in [0.1, 0.5, 0.9, 1.3, 1.7] {
        assert_eq!(a.sample_wide(t), b.sample_wide(t), "t = {t}");
    }
    assert_ne!(a.sample_wide(3.5), b.sample_wide(3.5));
}

#[test]
fn bad_spins_are_refused_naming_the_key() {
    let q = |d: f64| rot(DVec3::X, d).as_quat();
    let err = |keys: Vec<Key<Quat>>| Track::new(&RawTrack::new(keys)).unwrap_err();
    let spin_err = |index, problem| TrackError::Spin { index, problem };
    let angle = |degrees: f64| Spin::Angle { axis: Vec3::X, degrees };
    let two = |spin: Spin, second: Quat| vec![Key::new(0.0, q(0.0)), Key::new(1.0, second).with_spin(spin)];
    assert_eq!(err(two(angle(f64::NAN), q(0.0))), spin_err(1, SpinProblem::OutOfRange));
    assert_eq!(err(two(angle(f64::INFINITY), q(0.0))), spin_err(1, SpinProblem::OutOfRange));
    assert_eq!(err(two(angle(360_000.0 + 360.0), q(0.0))), spin_err(1, SpinProblem::OutOfRange));
    assert_eq!(err(two(Spin::Turns(1001), q(10.0))), spin_err(1, SpinProblem::OutOfRange));
    assert_eq!(err(two(Spin::Turns(i32::MIN), q(10.0))), spin_err(1, SpinProblem::OutOfRange));
    assert_eq!(
        err(two(Spin::Angle { axis: Vec3::ZERO, degrees: 360.0 }, q(0.0))),
        spin_err(1, SpinProblem::OutOfRange)
    );
    assert!(Track::new(&RawTrack::new(two(Spin::Turns(1000), q(10.0)))).is_ok());
    assert!(Track::new(&RawTrack::new(two(angle(-360_000.0), q(0.0)))).is_ok());
    // Turns needs a short way to take its axis from.
    assert_eq!(err(two(Spin::Turns(1), q(0.0))), spin_err(1, SpinProblem::AmbiguousAxis));
    assert_eq!(err(two(Spin::Turns(1), q(180.0))), spin_err(1, SpinProblem::AmbiguousAxis));
    // Angle must arrive at the key's value.
    assert_eq!(err(two(angle(90.0), q(45.0))), spin_err(1, SpinProblem::Disagrees));
    assert_eq!(err(two(angle(360.0), q(0.1))), spin_err(1, SpinProblem::Disagrees));
    assert!(Track::new(&RawTrack::new(two(angle(450.0), q(90.0)))).is_ok());
    // Not on the first key, not after a Hermite segment, not on scalars or vectors.
    let first = vec![Key::new(0.0, q(0.0)).with_spin(Spin::Turns(1)), Key::new(1.0, q(10.0))];
    assert_eq!(err(first), spin_err(0, SpinProblem::FirstKey));
    let mut hermite = two(Spin::Turns(1), q(10.0));
    hermite[0] = hermite[0].clone().with_interpolation(Interpolation::Hermite);
    hermite[0].out_tangent = Some(Quat::IDENTITY);
    hermite[1].in_tangent = Some(Quat::IDENTITY);
    assert_eq!(err(hermite), spin_err(1, SpinProblem::AfterHermite));
    let vector = vec![Key::new(0.0, Vec3::ZERO), Key::new(1.0, Vec3::X).with_spin(Spin::Turns(1))];
    assert_eq!(Track::new(&RawTrack::new(vector)).unwrap_err(), spin_err(1, SpinProblem::NotARotation));
    let scalar = vec![Key::new(0.0, 0.0f32), Key::new(1.0, 1.0).with_spin(Spin::Turns(1))];
    assert_eq!(Track::new(&RawTrack::new(scalar)).unwrap_err(), spin_err(1, SpinProblem::NotARotation));
    let message = spin_err(3, SpinProblem::OutOfRange).to_string();
    assert!(message.starts_with("key 3: spin out of range"), "{message}");
    assert!(message.contains("1000 turns (360000 degrees)"), "{message}");
}

#[test]
fn scene_problems_name_the_spin_field() {
    use keyrig_core::{Object, Scene};
    let mut scene = Scene::default();
    let mut o = Object::new("Arm");
    o.rotation.track = RawTrack::new(vec![
        Key::new(0.0, Quat::IDENTITY),
        Key::new(1.0, Quat::IDENTITY).with_spin(Spin::Turns(2)),
        Key::new(2.0, Quat::IDENTITY).with_spin(Spin::Angle { axis: Vec3::X, degrees: f64::NAN }),
        Key::new(3.0, Quat::IDENTITY).with_spin(Spin::Angle { axis: Vec3::Y, degrees: -720.0 }),
    ]);
    o.translation.track =
        RawTrack::new(vec![Key::new(0.0, Vec3::ZERO), Key::new(1.0, Vec3::X).with_spin(Spin::Turns(1))]);
    scene.objects.push(o);
    let problems: Vec<String> = scene.problems().iter().map(ToString::to_string).collect();
    assert_eq!(problems.len(), 3, "{problems:#?}");
    assert!(problems[0]
        .starts_with("objects[0].translation.track[1].spin: spin is only meaningful on rotation keys"));
    assert!(problems[1].starts_with("objects[0].rotation.track[2].spin: spin out of range"));
    assert!(
        problems[2].starts_with("objects[0].rotation.track[1].spin: Turns takes its axis"),
        "{}",
        problems[2]
    );
}
