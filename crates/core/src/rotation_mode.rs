//! How a rotation channel reads to an animator: as a quaternion, or as Euler angles in one of
//! the six orders. The mode changes what the inspector and the curve editor show and type; the
//! stored keys stay quaternions, interpolated by Squad as before.
//!
//! Orders are named as Blender and Maya name them: **XYZ** turns about X first, then Y, then Z,
//! all about the parent's fixed axes (extrinsic), so the rotation is `R = Rz(z)·Ry(y)·Rx(x)`
//! (glam's `EulerRot::XYZEx`, scipy's `Rotation.from_euler("xyz", …)`). The angles are kept per
//! axis, `(x, y, z)` in degrees, whatever the order.
//!
//! Euler angles of a rotation are not unique: `(a, b, c)` and `(a + 180°, 180° − b, c + 180°)`
//! (first, middle and last axis of the order) are the same rotation, and each angle can gain
//! whole turns. [`EulerOrder::angles_near`] picks the triple nearest a previous one, so that a
//! plain spin about Y reads Y 0 → 360 with X and Z at 0 instead of flipping X and Z to 180° when
//! Y passes 90°; at the gimbal lock (middle angle ±90°), where only the sum or difference of the
//! other two is fixed, it keeps the first angle and solves the last.

use glam::{EulerRot, Quat, Vec3};
use serde::{Deserialize, Serialize};

/// One of the six orders of Euler angles (module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum EulerOrder {
    #[default]
    XYZ,
    XZY,
    YXZ,
    YZX,
    ZXY,
    ZYX,
}

impl EulerOrder {
    pub const ALL: [EulerOrder; 6] = [
        EulerOrder::XYZ,
        EulerOrder::XZY,
        EulerOrder::YXZ,
        EulerOrder::YZX,
        EulerOrder::ZXY,
        EulerOrder::ZYX,
    ];

    /// The axes (0 = X, 1 = Y, 2 = Z) in the order they turn.
    #[must_use]
    pub fn axes(self) -> [usize; 3] {
        match self {
            EulerOrder::XYZ => [0, 1, 2],
            EulerOrder::XZY => [0, 2, 1],
            EulerOrder::YXZ => [1, 0, 2],
            EulerOrder::YZX => [1, 2, 0],
            EulerOrder::ZXY => [2, 0, 1],
            EulerOrder::ZYX => [2, 1, 0],
        }
    }

    /// "XYZ", ….
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            EulerOrder::XYZ => "XYZ",
            EulerOrder::XZY => "XZY",
            EulerOrder::YXZ => "YXZ",
            EulerOrder::YZX => "YZX",
            EulerOrder::ZXY => "ZXY",
            EulerOrder::ZYX => "ZYX",
        }
    }

    /// The formula, for tooltips: "R = Rz·Ry·Rx (X turns first)".
    #[must_use]
    pub fn formula(self) -> String {
        let [a, b, c] = self.axes().map(|i| ["x", "y", "z"][i]);
        format!(
            "R = R{c}·R{b}·R{a}: about {} first, then {}, then {}, about the parent's axes (Blender's and Maya's {} order)",
            a.to_uppercase(),
            b.to_uppercase(),
            c.to_uppercase(),
            self.name()
        )
    }

    /// glam's extrinsic rotation of the same order.
    fn glam(self) -> EulerRot {
        match self {
            EulerOrder::XYZ => EulerRot::XYZEx,
            EulerOrder::XZY => EulerRot::XZYEx,
            EulerOrder::YXZ => EulerRot::YXZEx,
            EulerOrder::YZX => EulerRot::YZXEx,
            EulerOrder::ZXY => EulerRot::ZXYEx,
            EulerOrder::ZYX => EulerRot::ZYXEx,
        }
    }

    /// The rotation of angles `degrees` (x, y, z about their axes).
    #[must_use]
    pub fn to_quat(self, degrees: Vec3) -> Quat {
        let [a, b, c] = self.axes().map(|i| degrees[i].to_radians());
        Quat::from_euler(self.glam(), a, b, c).normalize()
    }

    /// Angles (x, y, z, degrees) of `q`, each in (−180, 180], the middle one in [−90, 90].
    #[must_use]
    pub fn angles(self, q: Quat) -> Vec3 {
        // In f64: the conversion loses precision near the gimbal lock.
        let (a, b, c) = q.as_dquat().to_euler(self.glam());
        let half_turn = |d: f64| if d <= -179.9995 { d + 360.0 } else { d };
        let mut out = Vec3::ZERO;
        for (i, v) in self.axes().into_iter().zip([a, b, c]) {
            out[i] = half_turn(v.to_degrees()) as f32;
        }
        out
    }

    /// Angles (x, y, z, degrees) of `q` nearest `near` (module documentation): of the two
    /// triples of `q`, with whole turns added to each angle, the one whose angles differ least
    /// from `near`'s.
    #[must_use]
    pub fn angles_near(self, q: Quat, near: Vec3) -> Vec3 {
        let [i, j, k] = self.axes();
        let principal = self.angles(q);
        let unwrap = |v: f32, to: f32| v + 360.0 * ((to - v) / 360.0).round();
        let fit = |mut e: Vec3| {
            for axis in 0..3 {
                e[axis] = unwrap(e[axis], near[axis]);
            }
            e
        };
        let cost = |e: Vec3| (e - near).abs().element_sum();
        // Gimbal lock: the middle angle at ±90° fixes only a sum or difference of the others.
        if (90.0 - principal[j].abs()).abs() < 0.05 {
            let mut e = principal;
            e[i] = near[i];
            e[j] = unwrap(principal[j], near[j]);
            // R = R_k(c)·R_j(b)·R_i(a): the last turn is q·R_i(a)⁻¹·R_j(b)⁻¹.
            let axis = |n: usize| Vec3::from_array(std::array::from_fn(|m| if m == n { 1.0 } else { 0.0 }));
            let first = Quat::from_axis_angle(axis(i), e[i].to_radians());
            let middle = Quat::from_axis_angle(axis(j), e[j].to_radians());
            let rest = q * first.inverse() * middle.inverse();
            let c = 2.0 * rest.to_array()[k].atan2(rest.w);
            e[k] = unwrap(c.to_degrees(), near[k]);
            return e;
        }
        let mut other = principal;
        other[i] += 180.0;
        other[j] = 180.0 - other[j];
        other[k] += 180.0;
        let (a, b) = (fit(principal), fit(other));
        if cost(b) < cost(a) {
            b
        } else {
            a
        }
    }
}

/// How a rotation channel reads and is typed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum RotationMode {
    /// The unit quaternion (w, x, y, z).
    Quaternion,
    /// Euler angles in degrees in this order.
    Euler(EulerOrder),
}

impl Default for RotationMode {
    /// XYZ Euler angles, as Blender's and Maya's default.
    fn default() -> Self {
        RotationMode::Euler(EulerOrder::XYZ)
    }
}

impl RotationMode {
    /// Every mode an animator can choose, the default's order first.
    pub const ALL: [RotationMode; 7] = [
        RotationMode::Euler(EulerOrder::XYZ),
        RotationMode::Euler(EulerOrder::XZY),
        RotationMode::Euler(EulerOrder::YXZ),
        RotationMode::Euler(EulerOrder::YZX),
        RotationMode::Euler(EulerOrder::ZXY),
        RotationMode::Euler(EulerOrder::ZYX),
        RotationMode::Quaternion,
    ];

    /// The Euler order, `None` for quaternions.
    #[must_use]
    pub fn euler(self) -> Option<EulerOrder> {
        match self {
            RotationMode::Quaternion => None,
            RotationMode::Euler(order) => Some(order),
        }
    }

    /// Whether the mode is the default one (left out of scene files).
    #[must_use]
    pub fn is_default(&self) -> bool {
        *self == RotationMode::default()
    }

    /// "XYZ Euler", "Quaternion".
    #[must_use]
    pub fn label(self) -> String {
        match self.euler() {
            Some(order) => format!("{} Euler", order.name()),
            None => "Quaternion (WXYZ)".to_owned(),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat3;

    /// Quaternions and their Euler angles from scipy 1.17 (`Rotation.from_quat(q)
    /// .as_euler(order, degrees=True)` with lower-case, extrinsic orders), per axis.
    #[allow(clippy::type_complexity)]
    fn scipy_reference() -> Vec<(Quat, [(EulerOrder, Vec3); 6])> {
        vec![
            (
                glam::DQuat::from_xyzw(0.102597835, 0.718184846, -0.307793506, 0.615587011).as_quat(),
                [
                    (EulerOrder::XYZ, Vec3::new(-99.46232, 71.32828, -133.66778)),
                    (EulerOrder::XZY, Vec3::new(35.75389, 103.13402, -13.39005)),
                    (EulerOrder::YXZ, Vec3::new(-18.40848, 93.17983, -33.69007)),
                    (EulerOrder::YZX, Vec3::new(-21.80141, 105.06849, -31.75686)),
                    (EulerOrder::ZXY, Vec3::new(34.64019, 93.66779, -16.34817)),
                    (EulerOrder::ZYX, Vec3::new(95.29008, 55.19031, -112.78241)),
                ],
            ),
            (
                glam::DQuat::from_xyzw(0.515710623, -0.206284249, 0.412568499, 0.721994872).as_quat(),
                [
                    (EulerOrder::XYZ, Vec3::new(56.30993, -46.33626, 33.69007)),
                    (EulerOrder::XZY, Vec3::new(82.05653, -51.54629, 22.51831)),
                    (EulerOrder::YXZ, Vec3::new(35.06239, -62.10273, 81.02737)),
                    (EulerOrder::YZX, Vec3::new(77.47119, 12.52881, 53.95067)),
                    (EulerOrder::ZXY, Vec3::new(66.19062, 18.43495, 71.56505)),
                    (EulerOrder::ZYX, Vec3::new(67.28559, 7.33437, 54.6052)),
                ],
            ),
            (
                glam::DQuat::from_xyzw(-0.307793506, 0.102597835, 0.923380517, 0.205195670).as_quat(),
                [
                    (EulerOrder::XYZ, Vec3::new(4.57392, 37.62757, 156.50143)),
                    (EulerOrder::XZY, Vec3::new(-160.55997, 139.95027, 18.40848)),
                    (EulerOrder::YXZ, Vec3::new(3.62109, 37.71598, 153.70521)),
                    (EulerOrder::YZX, Vec3::new(175.9623, -144.0715, 26.23828)),
                    (EulerOrder::ZXY, Vec3::new(-18.40848, -33.69007, 160.55997)),
                    (EulerOrder::ZYX, Vec3::new(-21.80141, -31.75686, 148.67131)),
                ],
            ),
        ]
    }

    fn same_rotation(a: Quat, b: Quat) -> bool {
        a.dot(b).abs() > 1.0 - 1e-6
    }

    #[test]
    fn angles_match_scipy_in_every_order() {
        for (q, rows) in scipy_reference() {
            for (order, expected) in rows {
                let got = order.angles(q);
                assert!(
                    (got - expected).abs().max_element() < 2e-3,
                    "{order:?} of {q}: {got} vs scipy {expected}"
                );
                assert!(same_rotation(order.to_quat(expected), q), "{order:?}: scipy's angles give back q");
            }
        }
    }

    /// Rx, Ry, Rz written out by hand (right-handed, column vectors).
    fn hand_matrix(axis: usize, degrees: f32) -> Mat3 {
        let (s, c) = degrees.to_radians().sin_cos();
        match axis {
            0 => Mat3::from_cols(Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, c, s), Vec3::new(0.0, -s, c)),
            1 => Mat3::from_cols(Vec3::new(c, 0.0, -s), Vec3::new(0.0, 1.0, 0.0), Vec3::new(s, 0.0, c)),
            _ => Mat3::from_cols(Vec3::new(c, s, 0.0), Vec3::new(-s, c, 0.0), Vec3::new(0.0, 0.0, 1.0)),
        }
    }

    #[test]
    fn to_quat_is_the_product_of_hand_written_matrices_first_axis_on_the_right() {
        let angles = Vec3::new(23.0, -61.0, 142.0);
        for order in EulerOrder::ALL {
            let [i, j, k] = order.axes();
            let expected = hand_matrix(k, angles[k]) * hand_matrix(j, angles[j]) * hand_matrix(i, angles[i]);
            let got = Mat3::from_quat(order.to_quat(angles));
            let diff = (expected - got).to_cols_array().iter().fold(0.0f32, |m, d| m.max(d.abs()));
            assert!(diff < 1e-5, "{order:?}: {expected:?} vs {got:?}");
            let back = order.angles(order.to_quat(angles));
            assert!(same_rotation(order.to_quat(back), order.to_quat(angles)), "{order:?} round trip");
        }
    }

    #[test]
    fn a_plain_spin_reads_as_one_angle_climbing_in_every_order() {
        for order in EulerOrder::ALL {
            for axis in 0..3 {
                let unit = Vec3::from_array(std::array::from_fn(|m| if m == axis { 1.0 } else { 0.0 }));
                let mut e = Vec3::ZERO;
                for step in 0..=720 {
                    let degrees = step as f32 * 0.5;
                    let q = Quat::from_axis_angle(unit, degrees.to_radians());
                    e = order.angles_near(q, e);
                    let mut expected = Vec3::ZERO;
                    expected[axis] = degrees;
                    assert!(
                        (e - expected).abs().max_element() < 0.02,
                        "{order:?}, spin about axis {axis} at {degrees}°: read {e}"
                    );
                }
            }
        }
    }

    #[test]
    fn nearest_angles_are_the_same_rotation_and_continuous_on_a_tumble() {
        // A tumble about a tilted axis passes near every gimbal lock; consecutive readings stay
        // close and always give back the rotation.
        let axis = Vec3::new(0.3, 1.0, -0.4).normalize();
        for order in EulerOrder::ALL {
            let mut e = order.angles(Quat::IDENTITY);
            for step in 1..=720 {
                let q = Quat::from_axis_angle(axis, (step as f32 * 0.5).to_radians())
                    * Quat::from_rotation_x(0.4);
                let next = order.angles_near(q, e);
                assert!(same_rotation(order.to_quat(next), q), "{order:?} step {step}: {next} is not q");
                if step > 1 {
                    assert!((next - e).abs().max_element() < 12.0, "{order:?} step {step}: {e} → {next}");
                }
                e = next;
            }
        }
    }
}
