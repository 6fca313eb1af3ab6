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
