//! Spins and twists: which [`Spin`] a rotation key needs so that its segment turns the way the
//! hand went ([`spin_toward`]), and the unwrapped twist about a bone axis that the inspector and
//! the curve view show ([`unwrapped_twist`]).
//!
//! Angles are degrees, signed by the right-hand rule about their axis.

use glam::{DQuat, DVec3, Quat, Vec3};
use keyrig_core::{Spin, Track, MAX_SPIN_TURNS};

/// The bone axis of a joint in its own frame: keyrig's skeletons point each bone along the
/// joint's local +X (docs/scene-format.md).
pub const BONE_AXIS: Vec3 = Vec3::X;

/// Wraps degrees into (−180, 180].
#[must_use]
pub fn wrap_degrees(d: f64) -> f64 {
    let w = (d + 180.0).rem_euclid(360.0) - 180.0;
    if w == -180.0 {
        180.0
    } else {
        w
    }
}

/// `wrapped + 360·k` nearest to `target`.
#[must_use]
pub fn nearest_turn(wrapped: f64, target: f64) -> f64 {
    wrapped + 360.0 * ((target - wrapped) / 360.0).round()
}

/// The twist of `q` about `axis` (unit, in `q`'s own frame: `q = swing·R(axis, twist)`) in
/// (−180°, 180°]: `2·atan2(v·axis, w)`, the swing–twist decomposition.
#[must_use]
pub fn twist_degrees(q: DQuat, axis: DVec3) -> f64 {
    wrap_degrees(2.0 * (DVec3::new(q.x, q.y, q.z).dot(axis)).atan2(q.w).to_degrees())
}

/// Turns below this many degrees are left to the short way by [`spin_toward`].
pub const SHORT_WAY_LIMIT_DEGREES: f64 = 179.0;

/// The spin the rotation key `next` needs so that the segment from the key `prev` turns by
/// about `degrees_hint` about `axis_hint` (a direction in `prev`'s frame, as
/// [`Spin::Angle`] takes it), or `None` when the short way already does.
///
/// The key's value decides the rotation; the hint only decides how many whole turns and which
/// way round. The result is `Angle(axis, a + 360·k)` with `a` the signed short-way angle from
/// `prev` to `next` about the short way's axis oriented along the hint (the hint axis itself
/// when it reproduces `next` within a thousandth of a degree, as for a pure twist) and `k` the
/// whole number of turns that brings it nearest to the hint. `None` when that is the short way
/// by a clear margin (under [`SHORT_WAY_LIMIT_DEGREES`]); a turn of about half a turn keeps an
/// explicit spin, because there the short way's direction is decided by rounding.
#[must_use]
pub fn spin_toward(prev: Quat, next: Quat, axis_hint: Vec3, degrees_hint: f64) -> Option<Spin> {
    if !degrees_hint.is_finite() {
        return None;
    }
    let (prev, next) = (prev.as_dquat().normalize(), next.as_dquat().normalize());
    let mut r = prev.conjugate() * next;
    if r.w < 0.0 {
        r = -r;
    }
    let hint = axis_hint.as_dvec3().try_normalize();
    let max_turns = f64::from(MAX_SPIN_TURNS) - 1.0;
    let with_turns = |a: f64| {
        let k = ((degrees_hint - a) / 360.0).round().clamp(-max_turns, max_turns);
        (k, a + 360.0 * k)
    };
    // The hint axis itself, when the rotation is (within 0.001°) a turn about it.
    if let Some(h) = hint {
        let a = twist_degrees(r, h);
        let about_hint = DQuat::from_axis_angle(h, a.to_radians());
        if keyrig_core::quat::angle_between(about_hint, r)
            .min(keyrig_core::quat::angle_between(-about_hint, r))
            < 1e-3_f64.to_radians()
        {
            let (_, degrees) = with_turns(a);
            return (degrees.abs() >= SHORT_WAY_LIMIT_DEGREES)
                .then_some(Spin::Angle { axis: h.as_vec3(), degrees });
        }
    }
    let v = keyrig_core::quat::log(r);
    let half = v.length();
    if half < 1e-9 {
        // Equal rotations: whole turns about the hint's axis.
        let h = hint?;
        let (_, degrees) = with_turns(0.0);
        return (degrees.abs() >= SHORT_WAY_LIMIT_DEGREES)
            .then_some(Spin::Angle { axis: h.as_vec3(), degrees });
    }
    let mut axis = v / half;
    let mut a = 2.0 * half.to_degrees();
    if hint.is_some_and(|h| axis.dot(h) < 0.0) {
        axis = -axis;
        a = -a;
    }
    let (_, degrees) = with_turns(a);
    (degrees.abs() >= SHORT_WAY_LIMIT_DEGREES).then_some(Spin::Angle { axis: axis.as_vec3(), degrees })
}

/// The twist of a rotation track about `axis` (unit, in each key's frame; [`BONE_AXIS`] for a
/// joint) at time `t`, unwrapped: the first key's twist in (−180°, 180°], plus each segment's
/// twist, where a spin segment counts its turns ([`Track::spin_degrees`]) and a short-way
/// segment its change in (−180°, 180°]. Reads 720 after two turns.
#[must_use]
pub fn unwrapped_twist(track: &Track<Quat>, axis: DVec3, t: f64) -> f64 {
    let times = track.key_times();
    let values = track.key_values();
    let twist = |q: Quat| twist_degrees(q.as_dquat(), axis);
    let mut total = twist(values[0]);
    for i in 0..times.len().saturating_sub(1) {
        if t <= times[i] {
            break;
        }
        let spin = track.segment_spin(i).filter(|(s, _)| s.dot(axis).abs() > 0.5);
        let along = |(s, degrees): (DVec3, f64)| degrees * s.dot(axis).signum();
        if t < times[i + 1] {
            let wrapped = wrap_degrees(twist(track.sample(t)) - twist(values[i]));
            let partial = match (spin, track.spin_degrees(t)) {
                (Some((s, _)), Some(d)) => nearest_turn(wrapped, along((s, d))),
                _ => wrapped,
            };
            return total + partial;
        }
        let wrapped = wrap_degrees(twist(values[i + 1]) - twist(values[i]));
        total += match spin {
            Some(s) => nearest_turn(wrapped, along(s)),
            None => wrapped,
        };
    }
    total
}

#[cfg(test)]
mod tests {
    use super::*;
    use keyrig_core::{Interpolation, Key, RawTrack};

    #[test]
    fn wrap_and_nearest_turn() {
        assert_eq!(wrap_degrees(190.0), -170.0);
        assert_eq!(wrap_degrees(-180.0), 180.0);
        assert_eq!(nearest_turn(-170.0, 540.0), 550.0);
        assert_eq!(nearest_turn(10.0, -20.0), 10.0);
    }

    fn about_x(degrees: f64) -> Quat {
        Quat::from_rotation_x(degrees.to_radians() as f32)
    }

    #[test]
    fn spin_toward_follows_the_hint_in_whole_turns() {
        let table: [(f64, f64, Option<f64>); 7] = [
            // (next about X, hint, expected Angle degrees about +X)
            (90.0, 90.0, None),
            (90.0, 450.0, Some(450.0)),
            (90.0, -270.0, Some(-270.0)),
            (0.0, 360.0, Some(360.0)),
            (0.0, -725.0, Some(-720.0)),
            (0.0, 100.0, None),
            (180.0, 180.0 + 1e-3, Some(180.0)),
        ];
        for (next, hint, expected) in table {
            let spin = spin_toward(Quat::IDENTITY, about_x(next), Vec3::X, hint);
            match (spin, expected) {
                (None, None) => {}
                (Some(Spin::Angle { axis, degrees }), Some(e)) => {
                    assert!(
                        (axis - Vec3::X).length() < 1e-6 && (degrees - e).abs() < 1e-3,
                        "{next} {hint}: {spin:?}"
                    );
                }
                _ => panic!("{next}° with hint {hint}: {spin:?}, expected {expected:?}"),
            }
        }
    }

    #[test]
    fn spin_toward_agrees_with_the_key_for_any_axis() {
        let prev = Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.2, 0.5);
        let next = prev * Quat::from_axis_angle(Vec3::new(0.2, 1.0, 0.1).normalize(), 1.0);
        let spin = spin_toward(prev, next, Vec3::Y, 1.0_f64.to_degrees() + 720.0).expect("two extra turns");
        let chord = keyrig_core::track::spin_chord(prev.as_dquat(), next.as_dquat(), spin).expect("agrees");
        let (_, degrees) = (chord.expect("a spin").axis, chord.expect("a spin").degrees);
        assert!((degrees - (1.0_f64.to_degrees() + 720.0)).abs() < 1e-3, "{degrees}");
    }

    #[test]
    fn unwrapped_twist_reads_turns() {
        // 0 → 720° about X (frame 0 → 60 at 30 fps), then back 90° the short way.
        let raw = RawTrack::new(vec![
            Key::new(0.0, Quat::IDENTITY).with_interpolation(Interpolation::Linear),
            Key::new(2.0, Quat::IDENTITY)
                .with_interpolation(Interpolation::Linear)
                .with_spin(Spin::Angle { axis: Vec3::X, degrees: 720.0 }),
            Key::new(3.0, about_x(-90.0)),
        ]);
        let track = Track::new(&raw).expect("valid");
        let x = DVec3::X;
        for (t, expected) in [
            (-1.0, 0.0),
            (0.0, 0.0),
            (0.5, 180.0),
            (1.0, 360.0),
            (1.75, 630.0),
            (2.0, 720.0),
            (3.0, 630.0),
            (9.0, 630.0),
        ] {
            let got = unwrapped_twist(&track, x, t);
            assert!((got - expected).abs() < 1e-2, "t = {t}: {got} vs {expected}");
        }
    }
}
