//! sin and cos on a quarter turn, shared by the portable and SIMD bones-blending kernels.

/// sin and cos of x ∈ [0, π/2] by their Taylor polynomials to x¹¹ and x¹²; the truncation
/// error at π/2 is below 6e-8 (the next terms, (π/2)¹³/13! = 5.7e-8 and (π/2)¹⁴/14! = 6.4e-9),
/// i.e. below f32 rounding, and every term kept matters at that precision. Cheaper than libm's
/// range reduction and inlined into the vertex loop.
#[inline(always)]
pub(crate) fn sin_cos_quarter_turn(x: f32) -> (f32, f32) {
    let x2 = x * x;
    let s = x
        * (1.0
            + x2 * (-1.0 / 6.0
                + x2 * (1.0 / 120.0
                    + x2 * (-1.0 / 5040.0 + x2 * (1.0 / 362_880.0 + x2 * (-1.0 / 39_916_800.0))))));
    let c = 1.0
        + x2 * (-0.5
            + x2 * (1.0 / 24.0
                + x2 * (-1.0 / 720.0
                    + x2 * (1.0 / 40_320.0 + x2 * (-1.0 / 3_628_800.0 + x2 * (1.0 / 479_001_600.0))))));
    (s, c)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn polynomial_sin_cos_matches_libm_on_a_quarter_turn() {
        for i in 0..=1000 {
            let x = std::f32::consts::FRAC_PI_2 * i as f32 / 1000.0;
            let (s, c) = sin_cos_quarter_turn(x);
            assert!((s - x.sin()).abs() < 3e-7, "sin({x}): {s} vs {}", x.sin());
            assert!((c - x.cos()).abs() < 3e-7, "cos({x}): {c} vs {}", x.cos());
        }
    }
}
