//! Twisting with the pointer: how a drag on a rotation ring becomes an angle ([`RingDrag`]).
//! The spins a turn keys and the unwrapped twist are [`keyrig_edit::spin`]'s.
//!
//! Angles are degrees, signed by the right-hand rule about their axis.

use egui::{Pos2, Vec2};
use glam::{Quat, Vec3};

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

/// How pointer motion maps to the ring's angle.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum RingMapping {
    /// The angle swept by the pointer around the ring's centre on screen, accumulated over
    /// the drag (several turns follow the hand), or the pointer's travel along the ring's
    /// tangent at the press as an arc of the circle through the press, whichever is larger:
    /// a circular drag follows the hand through several turns, and a straight drag along the
    /// ring keeps turning (a drag as long as the circle's circumference is one turn) where the
    /// angle around the centre would stop short of half a turn. `sign` is +1 when the axis
    /// points towards the viewer (a counter-clockwise sweep is a positive turn), −1 when away.
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
    /// [`RingMapping::Around`]: the angle swept around the centre so far, degrees (signed).
    swept_degrees: f64,
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
        RingDrag {
            axis,
            centre,
            mapping,
            press,
            last_angle: screen_angle(centre, press),
            raw_degrees: 0.0,
            swept_degrees: 0.0,
        }
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
                    self.swept_degrees += sign * f64::from(d.to_degrees());
                }
                self.last_angle = Some(angle);
                // The travel along the tangent at the press (counter-clockwise on screen, y
                // down), as an arc of the circle through the press.
                let radial = self.press - self.centre;
                let arc =
                    f64::from((p - self.press).dot(Vec2::new(radial.y, -radial.x)) / radial.length_sq());
                let along = sign * arc.to_degrees();
                self.raw_degrees =
                    if along.abs() > self.swept_degrees.abs() { along } else { self.swept_degrees };
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

/// What the Twist field shows beside `degrees`: the whole turns and the rest, so the two always
/// agree (719° is "1 turn + 359°", 720° "2 turns", −400° "−1 turn − 40°"); `None` under a turn.
/// The degrees are read to the field's two decimals, so 719.999 is two turns, as the field
/// shows 720.
#[must_use]
pub fn turns_readout(degrees: f64) -> Option<String> {
    if !degrees.is_finite() {
        return None;
    }
    let hundredths = (degrees.abs() * 100.0).round();
    let turns = (hundredths / 36_000.0).floor();
    if turns < 1.0 {
        return None;
    }
    let rest = (hundredths - turns * 36_000.0) / 100.0;
    let negative = degrees < 0.0;
    let mut text = format!(
        "{}{turns:.0} turn{}",
        if negative { "\u{2212}" } else { "" },
        if turns >= 2.0 { "s" } else { "" }
    );
    if rest > 0.0 {
        let rest = format!("{rest:.2}");
        let rest = rest.trim_end_matches('0').trim_end_matches('.');
        text.push_str(&format!(" {} {rest}°", if negative { '\u{2212}' } else { '+' }));
    }
    Some(text)
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

    /// Issue 42, item 8: a straight drag along an open ring (from a point of the ring, along
    /// its tangent there) swept at most half a turn around the centre (+165° for 380 points on
    /// a ring 80 points across); it now turns by its length as an arc of the ring, past a turn,
    /// either way and whichever way the axis points.
    #[test]
    fn a_straight_drag_along_an_open_ring_passes_a_turn() {
        let centre = Pos2::new(400.0, 300.0);
        let radius = 80.0;
        for (axis, sign) in [(Vec3::Z, 1.0), (Vec3::NEG_Z, -1.0)] {
            for direction in [1.0_f32, -1.0] {
                let press = circle(centre, radius, 30.0);
                let mut drag = RingDrag::new(axis, Vec3::NEG_Z, centre, press, radius, ortho);
                assert!(matches!(drag.mapping, RingMapping::Around { .. }));
                // Counter-clockwise tangent at 30° on a y-down screen.
                let tangent = circle(centre, radius, 31.0) - circle(centre, radius, 29.0);
                let tangent = tangent.normalized() * direction;
                for step in 1..=76 {
                    drag.drag_to(press + tangent * (5.0 * step as f32));
                }
                // 380 points on a circle of radius 80: 272°.
                let expected = sign * f64::from(direction) * (380.0_f64 / 80.0).to_degrees();
                assert!(
                    (drag.degrees(false) - expected).abs() < 0.5,
                    "{} vs {expected}",
                    drag.degrees(false)
                );
                for step in 77..=140 {
                    drag.drag_to(press + tangent * (5.0 * step as f32));
                }
                assert!(drag.degrees(false).abs() > 360.0, "past a turn: {}", drag.degrees(false));
                assert_eq!(drag.degrees(false).signum(), sign * f64::from(direction));
            }
        }
    }

    /// Issue 42, item 8: the field showed "1 turn" beside 719°; the readout names the rest.
    #[test]
    fn the_turns_readout_agrees_with_the_degrees() {
        assert_eq!(turns_readout(359.0), None);
        assert_eq!(turns_readout(-359.99), None);
        assert_eq!(turns_readout(360.0).as_deref(), Some("1 turn"));
        assert_eq!(turns_readout(719.0).as_deref(), Some("1 turn + 359°"));
        assert_eq!(turns_readout(720.0).as_deref(), Some("2 turns"));
        assert_eq!(turns_readout(719.999).as_deref(), Some("2 turns"));
        assert_eq!(turns_readout(765.5).as_deref(), Some("2 turns + 45.5°"));
        assert_eq!(turns_readout(-400.0).as_deref(), Some("\u{2212}1 turn \u{2212} 40°"));
        assert_eq!(turns_readout(f64::NAN), None);
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
}
