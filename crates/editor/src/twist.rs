//! Twisting: how a drag on a rotation ring becomes an angle ([`RingDrag`]), which
//! [`Spin`] a rotation key needs so that its segment turns the way the hand went
//! ([`spin_toward`]), and the unwrapped twist about a bone axis that the inspector and the curve
//! view show ([`unwrapped_twist`]).
//!
//! Angles are degrees, signed by the right-hand rule about their axis.

use egui::{Pos2, Vec2};
use glam::{DQuat, DVec3, Quat, Vec3};
use keyrig_core::{Spin, Track, MAX_SPIN_TURNS};

/// Rotation snapping increment while the snapping modifier (Ctrl, as in Blender) is held.
pub const SNAP_DEGREES: f64 = 15.0;

/// Degrees per point of pointer travel along a ring seen (nearly) edge-on.
pub const DEGREES_PER_POINT: f64 = 1.0;

/// A ring whose axis makes a cosine below this with the line of sight is seen too edge-on
/// (more than about 70° off its axis) for the angle around its centre to mean anything: a drag
/// along its thin ellipse sweeps almost no angle around the centre at the ellipse's ends and a
/// huge one near the centre. Such rings turn linearly with the drag ([`RingMapping::Along`]).
pub const EDGE_ON_COSINE: f32 = 0.35;

/// A press closer to the ring's centre than this fraction of the ring's screen radius also
/// turns linearly (the angle around the centre changes too fast there).
pub const MIN_AROUND_RADIUS: f32 = 0.35;

/// The bone axis of a joint in its own frame: keyrig's skeletons point each bone along the
/// joint's local +X (docs/scene-format.md).
pub const BONE_AXIS: Vec3 = Vec3::X;

/// How pointer motion maps to the ring's angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RingMapping {
    /// The angle swept by the pointer around the ring's centre on screen, accumulated over
    /// the drag (several turns follow the hand). `sign` is +1 when the axis points towards
    /// the viewer (a counter-clockwise sweep is a positive turn), −1 when away.
    Around { sign: f64 },
    /// [`DEGREES_PER_POINT`] times the pointer's travel along `tangent` (unit, screen points),
    /// the direction in which the ring's near side moves for a positive turn (the far side's
    /// when the press was on the far side of an open ring).
    Along { tangent: Vec2 },
}

/// One drag on a rotation ring, in screen points (y down).
#[derive(Clone, Debug, PartialEq)]
pub struct RingDrag {
    /// The ring's axis, world space, unit.
    pub axis: Vec3,
    /// The ring's centre on screen.
    pub centre: Pos2,
    pub mapping: RingMapping,
    press: Pos2,
    /// Counter-clockwise screen angle of the pointer around the centre, radians.
    last_angle: Option<f32>,
    /// Accumulated turn, degrees, before snapping.
    raw_degrees: f64,
}

/// Counter-clockwise angle of `p` around `centre` on a y-down screen; `None` on the centre.
fn screen_angle(centre: Pos2, p: Pos2) -> Option<f32> {
    let d = p - centre;
    (d.length() > 1.0).then(|| (-d.y).atan2(d.x))
}

impl RingDrag {
    /// A drag pressed at `press` on the ring about `axis` (world) whose centre is at `centre`
    /// on screen with a screen radius of `radius` points. `forward` is the line of sight to
    /// the centre (world, from the eye); `screen_dir(v)` is the screen direction (points, any
    /// length) in which the centre moves along the world direction `v`.
    #[must_use]
    pub fn new(
        axis: Vec3,
        forward: Vec3,
        centre: Pos2,
        press: Pos2,
        radius: f32,
        screen_dir: impl Fn(Vec3) -> Vec2,
    ) -> Self {
        let axis = axis.normalize_or(Vec3::X);
        let forward = forward.normalize_or(Vec3::NEG_Z);
        let cosine = axis.dot(forward);
        let around =
            cosine.abs() >= EDGE_ON_COSINE && (press - centre).length() >= MIN_AROUND_RADIUS * radius;
        let mapping = if around {
            RingMapping::Around { sign: if cosine < 0.0 { 1.0 } else { -1.0 } }
        } else {
            // The ring's point nearest the viewer moves along axis × near for a positive turn.
            let across = forward - axis * cosine;
            let near = (-across).normalize_or(axis.any_orthonormal_vector());
            let mut tangent = screen_dir(axis.cross(near)).normalized();
            // On a ring open enough to tell its sides apart, a press on the far side (away
            // from the near point on screen) drags the far side, which moves the other way.
            let near_on_screen = screen_dir(near);
            if cosine.abs() > 0.1
                && near_on_screen.length() > 1e-6
                && (press - centre).dot(near_on_screen) < 0.0
            {
                tangent = -tangent;
            }
            if !tangent.is_finite() || tangent == Vec2::ZERO {
                tangent = Vec2::X;
            }
            RingMapping::Along { tangent }
        };
        RingDrag { axis, centre, mapping, press, last_angle: screen_angle(centre, press), raw_degrees: 0.0 }
    }

    /// Follows the pointer to `p`.
    pub fn drag_to(&mut self, p: Pos2) {
        match self.mapping {
            RingMapping::Around { sign } => {
                let Some(angle) = screen_angle(self.centre, p) else { return };
                if let Some(last) = self.last_angle {
                    let mut d = angle - last;
                    if d > std::f32::consts::PI {
                        d -= std::f32::consts::TAU;
                    } else if d < -std::f32::consts::PI {
                        d += std::f32::consts::TAU;
                    }
                    self.raw_degrees += sign * f64::from(d.to_degrees());
                }
                self.last_angle = Some(angle);
            }
            RingMapping::Along { tangent } => {
                self.raw_degrees = f64::from((p - self.press).dot(tangent)) * DEGREES_PER_POINT;
            }
        }
    }

    /// The turn so far, degrees about [`RingDrag::axis`]; rounded to [`SNAP_DEGREES`] when
    /// `snap`.
    #[must_use]
    pub fn degrees(&self, snap: bool) -> f64 {
        if snap {
            (self.raw_degrees / SNAP_DEGREES).round() * SNAP_DEGREES
        } else {
            self.raw_degrees
        }
    }
}

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

/// A drag on a rotation ring that the editor turns itself (see [`RingDrag`]).
#[derive(Clone, Debug)]
pub struct RingDragState {
    pub drag: RingDrag,
    /// The rotation channel turned (a joint's or an object's).
    pub channel: keyrig_core::channel_id::ChannelId,
    /// World rotation of the frame the channel's value is expressed in (the parent joint's
    /// world rotation times the joint's rest rotation; identity for an object), so that the
    /// world axis `a` is `frame⁻¹·a` in the channel's frame.
    pub frame: Quat,
    /// Degrees already applied to the channel during this drag.
    pub applied: f64,
}

#[cfg(test)]
mod tests {
    use super::*;
    use keyrig_core::{Interpolation, Key, RawTrack};

    /// Orthographic screen directions for a camera looking down −Z with +Y up.
    fn ortho(v: Vec3) -> Vec2 {
        Vec2::new(v.x, -v.y)
    }

    fn circle(centre: Pos2, radius: f32, ccw_degrees: f32) -> Pos2 {
        let a = ccw_degrees.to_radians();
        centre + egui::vec2(a.cos(), -a.sin()) * radius
    }

    #[test]
    fn around_accumulates_several_turns_either_way() {
        let centre = Pos2::new(400.0, 300.0);
        // Axis towards the viewer (+Z, camera looks down −Z): counter-clockwise is positive.
        for (axis, sign) in [(Vec3::Z, 1.0), (Vec3::NEG_Z, -1.0)] {
            for direction in [1.0_f32, -1.0] {
                let mut drag =
                    RingDrag::new(axis, Vec3::NEG_Z, centre, circle(centre, 80.0, 0.0), 80.0, ortho);
                assert!(matches!(drag.mapping, RingMapping::Around { .. }));
                // Two and a half turns in 10° steps.
                for step in 1..=90 {
                    drag.drag_to(circle(centre, 80.0, direction * step as f32 * 10.0));
                }
                let expected = sign * f64::from(direction) * 900.0;
                assert!(
                    (drag.degrees(false) - expected).abs() < 1e-3,
                    "{} vs {expected}",
                    drag.degrees(false)
                );
            }
        }
    }

    #[test]
    fn snapping_rounds_to_15_degrees() {
        let centre = Pos2::new(0.0, 0.0);
        let mut drag = RingDrag::new(Vec3::Z, Vec3::NEG_Z, centre, circle(centre, 80.0, 0.0), 80.0, ortho);
        drag.drag_to(circle(centre, 80.0, 37.0));
        assert!((drag.degrees(false) - 37.0).abs() < 1e-3);
        assert_eq!(drag.degrees(true), 30.0);
        drag.drag_to(circle(centre, 80.0, 38.0));
        assert_eq!(drag.degrees(true), 45.0);
    }

    /// The edge-on ring: a 24-point drag along it turned it 0°; now 1° per point, with
    /// the ring's near side following the pointer.
    #[test]
    fn an_edge_on_ring_turns_linearly_along_its_screen_line() {
        let centre = Pos2::new(0.0, 0.0);
        // Axis +X, camera down −Z: the ring (YZ plane) is the vertical line x = 0 on screen;
        // its near point is +Z and turns (right-hand about X) towards −Y, down the screen.
        let press = centre + egui::vec2(0.0, -60.0);
        let mut drag = RingDrag::new(Vec3::X, Vec3::NEG_Z, centre, press, 75.0, ortho);
        let RingMapping::Along { tangent } = drag.mapping else { panic!("{:?}", drag.mapping) };
        assert!((tangent - Vec2::new(0.0, 1.0)).length() < 1e-5, "{tangent:?}");
        drag.drag_to(press + egui::vec2(0.0, 24.0));
        assert!((drag.degrees(false) - 24.0).abs() < 1e-4);
        drag.drag_to(press + egui::vec2(3.0, -400.0));
        assert!((drag.degrees(false) + 400.0).abs() < 1e-4);
        // Nearly edge-on (cosine 0.2 < 0.35): still linear, the same way.
        let axis = Vec3::new(0.98, 0.0, 0.2).normalize();
        let drag = RingDrag::new(axis, Vec3::NEG_Z, centre, press, 75.0, ortho);
        assert!(matches!(drag.mapping, RingMapping::Along { tangent } if tangent.y > 0.99));
    }

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
