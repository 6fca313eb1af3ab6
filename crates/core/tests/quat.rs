//! The quaternion helpers where their fallbacks take over: `exp`'s series near zero, `slerp`'s
//! normalized lerp for nearly identical ends and its turn through the perpendicular quaternion
//! for antipodal ends, each against the closed form to f64 precision.

use glam::{DQuat, DVec3, DVec4};
use keyrig_core::quat::{exp, slerp, ANTIPODAL_MARGIN, SLERP_NLERP_ANGLE};

fn distance(a: DQuat, b: DQuat) -> f64 {
    (DVec4::from(a) - DVec4::from(b)).length()
}

#[test]
fn exp_near_zero_is_sin_phi_over_phi_to_the_last_bits() {
    // Below 1e-4 exp uses 1 − φ²/6 + φ⁴/120 for sin φ / φ; libm's sin is the reference.
    let axis = DVec3::new(0.6, 0.0, -0.8);
    for phi in [1e-9, 1e-6, 3e-5, 9.99e-5, 2e-4] {
        let q = exp(axis * phi);
        let sinc = q.x / (axis.x * phi);
        let expected = phi.sin() / phi;
        assert!((sinc - expected).abs() < 1e-15, "φ = {phi}: sin φ / φ = {sinc}, expected {expected}");
        assert!((q.z / (axis.z * phi) - expected).abs() < 1e-15, "φ = {phi}: z");
        assert_eq!(q.y, 0.0);
        assert_eq!(q.w, phi.cos(), "φ = {phi}: w");
    }
}

#[test]
fn slerp_between_nearly_identical_ends_is_the_arc() {
    // 4-D angle 1e-7 (under SLERP_NLERP_ANGLE): the normalized lerp, equal to the arc to ~θ³.
    let a = DQuat::from_axis_angle(DVec3::new(0.0, 0.6, 0.8), 0.3);
    let axis = DVec3::new(1.0, 2.0, 2.0) / 3.0;
    let b = a * DQuat::from_axis_angle(axis, 2e-7);
    assert!(keyrig_core::quat::angle_between(a, b) < SLERP_NLERP_ANGLE);
    for s in [0.0, 0.25, 0.5, 1.0] {
        let expected = a * DQuat::from_axis_angle(axis, 2e-7 * s);
        let got = slerp(a, b, s);
        assert!(distance(got, expected) < 1e-15, "s = {s}: {got:?}, expected {expected:?}");
    }
}

#[test]
fn slerp_between_antipodal_ends_turns_through_the_perpendicular_quaternion() {
    // b = −a: half a turn from a to the perpendicular (−y, x, −w, z), then on to b.
    let a = DQuat::from_xyzw(0.1, 0.7, -0.5, 0.5).normalize();
    let perp = DQuat::from_xyzw(-a.y, a.x, -a.w, a.z);
    let b = -a;
    assert!(keyrig_core::quat::angle_between(a, b) > std::f64::consts::PI - ANTIPODAL_MARGIN);
    let (sin45, cos45) = std::f64::consts::FRAC_PI_4.sin_cos();
    for (s, expected) in [
        (0.0, a),
        (0.25, DQuat::from_vec4(DVec4::from(a) * cos45 + DVec4::from(perp) * sin45)),
        (0.5, perp),
        (0.75, DQuat::from_vec4(DVec4::from(perp) * cos45 + DVec4::from(b) * sin45)),
        (1.0, b),
    ] {
        let got = slerp(a, b, s);
        assert!(distance(got, expected) < 1e-15, "s = {s}: {got:?}, expected {expected:?}");
    }
    assert!(DVec4::from(a).dot(DVec4::from(perp)).abs() < 1e-16, "the turn goes through a perpendicular");
}
