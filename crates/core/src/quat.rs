//! Guarded quaternion helpers in f64: logarithm, exponential and slerp that never divide by
//! `sin(0)`.
//!
//! Conventions: a unit quaternion `q = (cos φ, sin φ · n)` rotates by `2φ` about the unit axis
//! `n`. [`log`] returns the *half-angle* vector `φ · n` and [`exp`] is its inverse, so that
//! `exp(log(q)) = q` for every unit `q` (Shoemake 1987; Eberly, "Key Frame Interpolation via
//! Splines and Quaternions").
//!
//! Angles between quaternions are measured with Kahan's formula `θ = 2·atan2(|a − b|, |a + b|)`,
//! which stays accurate near 0 and near π where `acos(a·b)` loses half of its digits.

use glam::{DQuat, DVec3, DVec4};

/// Below this 4-D angle (radians) between two unit quaternions, [`slerp`] falls back to a
/// normalized lerp. The difference between slerp and nlerp is of order θ³ ≈ 1e-18 there, far
/// below f64 resolution of the result, and `sin θ` would be too small to divide by safely.
pub const SLERP_NLERP_ANGLE: f64 = 1e-6;

/// Above `π − ANTIPODAL_MARGIN` two unit quaternions are treated as antipodal: the great arc
/// between them is not unique, and [`slerp`] turns through a fixed perpendicular quaternion.
pub const ANTIPODAL_MARGIN: f64 = 1e-9;

/// Below this norm (of the half-angle vector) [`exp`] uses the Taylor series of `sin φ / φ`.
const EXP_SERIES_BELOW: f64 = 1e-4;

/// `(sin x, cos x)`, accurate to about one ulp; for `|x| < 1e6` several times faster than two
/// libm calls (`f64::sin_cos` calls `sin` and `cos` separately), beyond that it uses libm.
///
/// Cody–Waite reduction by π/2 (two-part constant, exact product for `|k| < 2^20`), then the
/// fdlibm polynomial kernels `__kernel_sin` / `__kernel_cos` on `[−π/4, π/4]` (Sun Microsystems
/// fdlibm 5.3, `k_sin.c`, `k_cos.c`; coefficients copied from there).
#[must_use]
#[inline]
#[allow(clippy::excessive_precision)] // fdlibm's constants, kept digit for digit
pub fn sin_cos(x: f64) -> (f64, f64) {
    // π/2 split into its first 33 bits and the rest (fdlibm e_rem_pio2.c).
    const INV_PIO2: f64 = std::f64::consts::FRAC_2_PI;
    const PIO2_1: f64 = 1.570_796_326_734_125_614_17;
    const PIO2_1T: f64 = 6.077_100_506_506_192_249_32e-11;
    // 1.5·2^52: adding and subtracting it rounds to the nearest integer (SSE2 has no round).
    const ROUND: f64 = 6_755_399_441_055_744.0;
    if x.is_nan() || x.abs() >= 1e6 {
        // Outside the range of the two-part reduction (and NaN): libm.
        return (x.sin(), x.cos());
    }
    let k = (x * INV_PIO2 + ROUND) - ROUND;
    let r = (x - k * PIO2_1) - k * PIO2_1T;
    let z = r * r;
    // __kernel_sin(r, 0, 0)
    const S1: f64 = -1.666_666_666_666_663_243_48e-1;
    const S2: f64 = 8.333_333_333_322_489_461_24e-3;
    const S3: f64 = -1.984_126_982_985_794_931_34e-4;
    const S4: f64 = 2.755_731_370_707_006_767_89e-6;
    const S5: f64 = -2.505_076_025_340_686_341_95e-8;
    const S6: f64 = 1.589_690_995_211_550_102_21e-10;
    let sr = S2 + z * (S3 + z * (S4 + z * (S5 + z * S6)));
    let sin_r = r + z * r * (S1 + z * sr);
    // __kernel_cos(r, 0)
    const C1: f64 = 4.166_666_666_666_660_190_37e-2;
    const C2: f64 = -1.388_888_888_887_410_957_49e-3;
    const C3: f64 = 2.480_158_728_947_672_941_78e-5;
    const C4: f64 = -2.755_731_435_139_066_330_35e-7;
    const C5: f64 = 2.087_572_321_298_174_827_90e-9;
    const C6: f64 = -1.135_964_755_778_819_482_65e-11;
    let cr = z * (C1 + z * (C2 + z * (C3 + z * (C4 + z * (C5 + z * C6)))));
    let hz = 0.5 * z;
    let w = 1.0 - hz;
    let cos_r = w + (((1.0 - w) - hz) + z * cr);
    match (k as i64) & 3 {
        0 => (sin_r, cos_r),
        1 => (cos_r, -sin_r),
        2 => (-sin_r, -cos_r),
        _ => (-cos_r, sin_r),
    }
}

/// `atan2(y, x)` for `y ≥ 0` (an angle in `[0, π]`), accurate to about one ulp and faster than
/// libm's general `atan2`. Reduces to `atan` on `[0, 1]` and evaluates it with fdlibm's
/// `s_atan.c` (Sun Microsystems fdlibm 5.3; constants copied from there).
#[must_use]
#[inline]
#[allow(clippy::excessive_precision)] // fdlibm's constants, kept digit for digit
pub fn atan2_nonneg(y: f64, x: f64) -> f64 {
    use std::f64::consts::{FRAC_PI_2, PI};
    if !(y >= 0.0 && y.is_finite() && x.is_finite()) || (y == 0.0 && x == 0.0) {
        return y.atan2(x);
    }
    let ax = x.abs();
    if y <= ax {
        let r = atan_unit(y / ax);
        if x > 0.0 {
            r
        } else {
            PI - r
        }
    } else {
        let r = atan_unit(ax / y);
        if x >= 0.0 {
            FRAC_PI_2 - r
        } else {
            FRAC_PI_2 + r
        }
    }
}

/// `atan(x)` for `x` in `[0, 1]` (fdlibm `s_atan.c`).
#[inline]
#[allow(clippy::excessive_precision)]
fn atan_unit(x: f64) -> f64 {
    const ATAN_HI: [f64; 2] = [4.636_476_090_008_060_935_15e-1, std::f64::consts::FRAC_PI_4];
    const ATAN_LO: [f64; 2] = [2.269_877_745_296_168_709_24e-17, 3.061_616_997_868_383_017_93e-17];
    const AT: [f64; 11] = [
        3.333_333_333_333_293_180_27e-1,
        -1.999_999_999_987_648_324_76e-1,
        1.428_571_427_250_346_637_11e-1,
        -1.111_111_040_546_235_578_80e-1,
        9.090_887_133_436_506_561_96e-2,
        -7.691_876_205_044_829_994_95e-2,
        6.661_073_137_387_531_206_69e-2,
        -5.833_570_133_790_573_486_45e-2,
        4.976_877_994_615_932_360_17e-2,
        -3.653_157_274_421_691_552_70e-2,
        1.628_582_011_536_578_236_23e-2,
    ];
    let (id, x) = if x < 0.4375 {
        (None, x)
    } else if x < 0.6875 {
        (Some(0), (2.0 * x - 1.0) / (2.0 + x))
    } else {
        (Some(1), (x - 1.0) / (x + 1.0))
    };
    let z = x * x;
    let w = z * z;
    let s1 = z * (AT[0] + w * (AT[2] + w * (AT[4] + w * (AT[6] + w * (AT[8] + w * AT[10])))));
    let s2 = w * (AT[1] + w * (AT[3] + w * (AT[5] + w * (AT[7] + w * AT[9]))));
    match id {
        None => x - x * (s1 + s2),
        Some(i) => ATAN_HI[i] - ((x * (s1 + s2) - ATAN_LO[i]) - x),
    }
}

/// The 4-D angle between two unit quaternions, in `[0, π]` (no shortest-path flip).
#[must_use]
pub fn angle_between(a: DQuat, b: DQuat) -> f64 {
    let a = DVec4::from(a);
    let b = DVec4::from(b);
    2.0 * (a - b).length().atan2((a + b).length())
}

/// Quaternion logarithm of a unit quaternion: the half-angle vector `φ · n`.
///
/// For `q = ±1` (no rotation, or a full turn) the result is the zero vector. There is no
/// division by `sin φ`: `atan2(|v|, w) / |v|` is finite for every `|v| > 0`.
#[must_use]
pub fn log(q: DQuat) -> DVec3 {
    let v = DVec3::new(q.x, q.y, q.z);
    let s = v.length();
    if s > 0.0 {
        v * (s.atan2(q.w) / s)
    } else {
        DVec3::ZERO
    }
}

/// Quaternion exponential of a half-angle vector: `(cos |v|, sin |v| · v / |v|)`.
#[must_use]
pub fn exp(v: DVec3) -> DQuat {
    let phi = v.length();
    let (sin_phi, cos_phi) = phi.sin_cos();
    // sin φ / φ, with the series 1 − φ²/6 + φ⁴/120 near 0 (error below φ⁶/5040).
    let sinc = if phi < EXP_SERIES_BELOW {
        let p2 = phi * phi;
        1.0 - p2 / 6.0 + p2 * p2 / 120.0
    } else {
        sin_phi / phi
    };
    let xyz = v * sinc;
    DQuat::from_xyzw(xyz.x, xyz.y, xyz.z, cos_phi)
}

/// [`exp`] with keyrig's [`sin_cos`] (one square root and one polynomial `sin_cos` for
/// `|v| < 1e6`): the per-sample exponential of spin segments. Same result as [`exp`] to about
/// one ulp, and the same series near 0.
#[must_use]
#[inline]
pub fn exp_fast(v: DVec3) -> DQuat {
    let phi = v.length();
    if phi < EXP_SERIES_BELOW {
        let p2 = phi * phi;
        let xyz = v * (1.0 - p2 / 6.0 + p2 * p2 / 120.0);
        return DQuat::from_xyzw(xyz.x, xyz.y, xyz.z, 1.0 - p2 / 2.0 + p2 * p2 / 24.0);
    }
    let (sin_phi, cos_phi) = sin_cos(phi);
    let xyz = v * (sin_phi / phi);
    DQuat::from_xyzw(xyz.x, xyz.y, xyz.z, cos_phi)
}

/// `log(a⁻¹ · b)`: the half-angle vector that turns `a` into `b` in `a`'s frame
/// (docs/design.md §3 writes it `L(a, b)`).
#[must_use]
pub fn log_between(a: DQuat, b: DQuat) -> DVec3 {
    log(a.conjugate() * b)
}

/// A precomputed great arc from `from` to `to` (no shortest-path flip), evaluated with one
/// `sin_cos` per sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Arc {
    from: DVec4,
    to: DVec4,
    /// 4-D angle θ between the ends; 0 means "use nlerp".
    angle: f64,
    cos_angle: f64,
    sin_angle: f64,
    inv_sin: f64,
}

impl Arc {
    /// Prepares the arc between two unit quaternions. Antipodal ends are routed through a
    /// perpendicular quaternion by [`slerp`]; [`Arc`] stores them as such a two-leg arc is not
    /// needed by keyrig (callers check with [`angle_between`] first).
    #[must_use]
    pub fn new(from: DQuat, to: DQuat) -> Self {
        let angle = angle_between(from, to);
        let (from, to) = (DVec4::from(from), DVec4::from(to));
        if angle < SLERP_NLERP_ANGLE {
            Arc { from, to, angle: 0.0, cos_angle: 1.0, sin_angle: 0.0, inv_sin: 0.0 }
        } else {
            let (sin_angle, cos_angle) = angle.sin_cos();
            Arc { from, to, angle, cos_angle, sin_angle, inv_sin: 1.0 / sin_angle }
        }
    }

    /// Whether the ends are (nearly) antipodal, so that the arc is not unique.
    #[must_use]
    pub fn is_antipodal(&self) -> bool {
        self.angle > std::f64::consts::PI - ANTIPODAL_MARGIN
    }

    /// The point at parameter `s` (0 gives `from`, 1 gives `to`).
    #[must_use]
    pub fn eval(&self, s: f64) -> DQuat {
        if self.angle == 0.0 {
            return DQuat::from_vec4((self.from + (self.to - self.from) * s).normalize());
        }
        if self.is_antipodal() {
            return slerp(DQuat::from_vec4(self.from), DQuat::from_vec4(self.to), s);
        }
        // sin((1−s)θ) = sin θ cos sθ − cos θ sin sθ: one sin_cos instead of two sines.
        let (sin_b, cos_b) = sin_cos(s * self.angle);
        let wa = (self.sin_angle * cos_b - self.cos_angle * sin_b) * self.inv_sin;
        let wb = sin_b * self.inv_sin;
        DQuat::from_vec4(self.from * wa + self.to * wb)
    }
}

/// Spherical linear interpolation along the great arc from `a` to `b` (no shortest-path flip:
/// make keys sign-consistent first when the short way is wanted).
///
/// `s = 0` gives `a`, `s = 1` gives `b`. Below [`SLERP_NLERP_ANGLE`] it is a normalized lerp;
/// for antipodal ends (`a ≈ −b`) it turns through the quaternion perpendicular to `a`
/// `(−y, x, −w, z)` (Shoemake's fallback), so the result is always finite and unit length.
#[must_use]
pub fn slerp(a: DQuat, b: DQuat, s: f64) -> DQuat {
    let angle = angle_between(a, b);
    let (va, vb) = (DVec4::from(a), DVec4::from(b));
    if angle < SLERP_NLERP_ANGLE {
        return DQuat::from_vec4((va + (vb - va) * s).normalize());
    }
    if angle > std::f64::consts::PI - ANTIPODAL_MARGIN {
        // Half a turn through the perpendicular quaternion, then on to b (≈ −a).
        let perp = DVec4::new(-a.y, a.x, -a.w, a.z);
        let half = std::f64::consts::FRAC_PI_2;
        return if s <= 0.5 {
            let (sn, cs) = (2.0 * s * half).sin_cos();
            DQuat::from_vec4(va * cs + perp * sn)
        } else {
            let (sn, cs) = ((2.0 * s - 1.0) * half).sin_cos();
            DQuat::from_vec4(perp * cs + vb * sn)
        };
    }
    let inv_sin = 1.0 / angle.sin();
    let wa = ((1.0 - s) * angle).sin() * inv_sin;
    let wb = (s * angle).sin() * inv_sin;
    DQuat::from_vec4(va * wa + vb * wb)
}

/// [`slerp`] written as a turn from `a` towards the unit direction of `b` orthogonal to `a`:
/// `a·cos(sθ) + e·sin(sθ)`, `e = (b − (a·b)a)/|b − (a·b)a|`, `θ = atan2(|b − (a·b)a|, a·b)`.
/// One square root, one `atan2` and one [`sin_cos`]: the per-sample outer slerp of Squad.
/// Same fallbacks as [`slerp`] near θ = 0 and θ = π.
#[must_use]
#[inline]
pub fn slerp_fast(a: DQuat, b: DQuat, s: f64) -> DQuat {
    let (va, vb) = (DVec4::from(a), DVec4::from(b));
    let d = va.dot(vb);
    let ortho = vb - va * d;
    let sin_angle = ortho.length();
    let angle = atan2_nonneg(sin_angle, d);
    if !(SLERP_NLERP_ANGLE..=std::f64::consts::PI - ANTIPODAL_MARGIN).contains(&angle) {
        return slerp(a, b, s);
    }
    let (sn, cs) = sin_cos(s * angle);
    DQuat::from_vec4(va * cs + ortho * (sn / sin_angle))
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: DQuat, b: DQuat, eps: f64) -> bool {
        (DVec4::from(a) - DVec4::from(b)).length() < eps
    }

    #[test]
    fn log_exp_round_trip_including_zero_and_half_turn() {
        let cases = [
            DQuat::IDENTITY,
            DQuat::from_axis_angle(DVec3::X, 1e-12),
            DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 1.0),
            DQuat::from_axis_angle(DVec3::Y, std::f64::consts::PI),
            DQuat::from_axis_angle(DVec3::Z, 3.0),
        ];
        for q in cases {
            let back = exp(log(q));
            assert!(close(back, q, 1e-14), "{q:?} -> {back:?}");
        }
        assert_eq!(log(DQuat::IDENTITY), DVec3::ZERO);
        assert_eq!(log(-DQuat::IDENTITY), DVec3::ZERO);
        let e = exp(DVec3::ZERO);
        assert_eq!(e, DQuat::IDENTITY);
    }

    #[test]
    fn exp_fast_matches_exp() {
        for v in [
            DVec3::ZERO,
            DVec3::new(1e-9, 0.0, 0.0),
            DVec3::new(3e-5, -2e-5, 1e-5),
            DVec3::new(0.3, 0.4, -0.5),
            DVec3::X * std::f64::consts::PI,
            DVec3::new(1.0, 2.0, 2.0) * 700.0,
        ] {
            assert!(close(exp_fast(v), exp(v), 1e-13), "{v:?}: {:?} vs {:?}", exp_fast(v), exp(v));
        }
    }

    #[test]
    fn slerp_ends_and_midpoint() {
        let a = DQuat::from_axis_angle(DVec3::Z, 0.2);
        let b = DQuat::from_axis_angle(DVec3::Z, 1.4);
        assert!(close(slerp(a, b, 0.0), a, 1e-15));
        assert!(close(slerp(a, b, 1.0), b, 1e-15));
        assert!(close(slerp(a, b, 0.5), DQuat::from_axis_angle(DVec3::Z, 0.8), 1e-15));
        let arc = Arc::new(a, b);
        for s in [0.0, 0.25, 0.5, 0.9, 1.0] {
            assert!(close(arc.eval(s), slerp(a, b, s), 1e-14));
        }
    }

    #[test]
    fn slerp_identical_and_antipodal_inputs_stay_unit() {
        let a = DQuat::from_axis_angle(DVec3::X, 0.7);
        for s in [0.0, 0.3, 0.5, 1.0] {
            let same = slerp(a, a, s);
            assert!(close(same, a, 1e-15));
            let anti = slerp(a, -a, s);
            assert!((anti.length() - 1.0).abs() < 1e-14 && anti.is_finite(), "{anti:?}");
        }
        assert!(close(slerp(a, -a, 1.0), -a, 1e-14));
    }

    #[test]
    fn fast_sin_cos_matches_libm() {
        let mut worst = 0.0f64;
        for i in -20_000..=20_000 {
            let x = f64::from(i) * 1.234_567e-3 + 1e-9;
            let (s, c) = sin_cos(x);
            worst = worst.max((s - x.sin()).abs()).max((c - x.cos()).abs());
        }
        assert!(worst < 5e-16, "worst difference {worst:e}");
        assert_eq!(sin_cos(0.0), (0.0, 1.0));
    }

    #[test]
    fn fast_atan2_matches_libm() {
        let mut worst = 0.0f64;
        for i in 0..=2000 {
            let y = f64::from(i) * 1e-3;
            for x in [-3.0, -1.0, -0.7, -1e-9, 0.0, 1e-12, 0.3, 0.5, 1.0, 2.5] {
                worst = worst.max((atan2_nonneg(y, x) - y.atan2(x)).abs());
            }
        }
        assert!(worst < 5e-16, "worst difference {worst:e}");
        assert_eq!(atan2_nonneg(0.0, 1.0), 0.0);
        assert!(atan2_nonneg(f64::NAN, 1.0).is_nan());
    }

    #[test]
    fn slerp_fast_matches_slerp() {
        let a = DQuat::from_axis_angle(DVec3::new(1.0, 2.0, 3.0).normalize(), 0.4);
        for (b, label) in [
            (DQuat::from_axis_angle(DVec3::Y, 1.9), "wide"),
            (a * DQuat::from_axis_angle(DVec3::X, 1e-8), "nearly identical"),
            (-a * DQuat::from_axis_angle(DVec3::Z, 1e-12), "antipodal"),
            (DQuat::from_axis_angle(DVec3::Y, -2.9), "obtuse"),
        ] {
            for s in [0.0, 0.1, 0.5, 0.77, 1.0] {
                assert!(close(slerp_fast(a, b, s), slerp(a, b, s), 1e-14), "{label} s = {s}");
            }
        }
    }
}
