//! Shared test support: `assert_approx_eq!` and named sets of tricky quaternions.
#![allow(dead_code)] // each test binary uses a different part of this module

use glam::{DQuat, DVec3, Quat, Vec3};

/// A distance between two values of the same type, for approximate comparison.
pub trait ApproxDist: std::fmt::Debug {
    /// The largest absolute component difference; for quaternions the distance between the
    /// rotations (`q` and `−q` are the same rotation).
    fn approx_dist(&self, other: &Self) -> f64;
}

impl ApproxDist for f32 {
    fn approx_dist(&self, other: &Self) -> f64 {
        (f64::from(*self) - f64::from(*other)).abs()
    }
}

impl ApproxDist for f64 {
    fn approx_dist(&self, other: &Self) -> f64 {
        (self - other).abs()
    }
}

impl ApproxDist for Vec3 {
    fn approx_dist(&self, other: &Self) -> f64 {
        f64::from((*self - *other).abs().max_element())
    }
}

impl ApproxDist for DVec3 {
    fn approx_dist(&self, other: &Self) -> f64 {
        (*self - *other).abs().max_element()
    }
}

impl ApproxDist for Quat {
    fn approx_dist(&self, other: &Self) -> f64 {
        self.as_dquat().approx_dist(&other.as_dquat())
    }
}

impl ApproxDist for DQuat {
    fn approx_dist(&self, other: &Self) -> f64 {
        let same = (*self - *other).to_array();
        let flipped = (*self + *other).to_array();
        let max = |a: [f64; 4]| a.iter().fold(0.0f64, |m, x| m.max(x.abs()));
        max(same).min(max(flipped))
    }
}

/// `assert_approx_eq!(actual, expected, eps)` or with a context format string after `eps`.
/// Prints both values and their distance on failure.
#[macro_export]
macro_rules! assert_approx_eq {
    ($actual:expr, $expected:expr, $eps:expr $(,)?) => {
        $crate::assert_approx_eq!($actual, $expected, $eps, "")
    };
    ($actual:expr, $expected:expr, $eps:expr, $($ctx:tt)+) => {{
        let (actual, expected) = (&$actual, &$expected);
        let dist = $crate::support::ApproxDist::approx_dist(actual, expected);
        assert!(
            dist <= $eps,
            "assert_approx_eq failed ({}): actual {:?}, expected {:?}, distance {:e} > {:e}",
            format!($($ctx)+),
            actual,
            expected,
            dist,
            $eps
        );
    }};
}

/// A rotation by `degrees` about `axis` (normalized here).
pub fn rot(axis: Vec3, degrees: f32) -> Quat {
    Quat::from_axis_angle(axis.normalize(), degrees.to_radians())
}

/// Named sets of quaternion keys that break naive interpolation code.
pub fn tricky_quaternion_sets() -> Vec<(&'static str, Vec<Quat>)> {
    let q = rot(Vec3::new(1.0, 2.0, 3.0), 40.0);
    let tiny = Quat::from_axis_angle(Vec3::Y, 1e-7);
    vec![
        // The same rotation with opposite signs: must interpolate as a constant.
        ("antipodal", vec![q, -q, q, -q]),
        ("identical", vec![q, q, q, q]),
        // dot = 1 within f32: slerp must not divide by sin(0).
        ("nearly identical", vec![q, q * tiny, q * tiny * tiny, q]),
        // dot = 0 in 4-D: consecutive keys half a turn apart.
        ("180 degrees apart", vec![Quat::IDENTITY, rot(Vec3::X, 180.0), Quat::IDENTITY, rot(Vec3::Z, 180.0)]),
        ("almost 180 degrees apart", vec![Quat::IDENTITY, rot(Vec3::X, 179.999), rot(Vec3::X, 359.99)]),
        ("identity", vec![Quat::IDENTITY, Quat::IDENTITY]),
    ]
}
