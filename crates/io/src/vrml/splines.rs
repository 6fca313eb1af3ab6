//! X3D's non-linear interpolators (ISO/IEC 19775-1 §19.2.4, §19.4.10, §19.4.12, §19.4.13) as
//! keyrig keys: `SplinePositionInterpolator` and `SplineScalarInterpolator` as Hermite keys
//! (always exact), `SquadOrientationInterpolator` as TCB keys where keyrig's Squad is the same
//! curve, else resampled into slerp keys within [`SQUAD_TOLERANCE_DEG`]. [`SquadCurve`] is the
//! X3D evaluation itself, used to check the TCB keys and to resample.
//!
//! **Hermite splines.** One tangent `Tᵢ` per key (`keyVelocity`, normalized to the chord length
//! when `normalizeVelocity`, else Catmull–Rom `(vᵢ₊₁ − vᵢ₋₁)/2`, zero at the ends of an open
//! spline without velocities), per unit of the segment parameter; it leaves key i scaled by
//! `F⁺ᵢ = 2·Δᵢ₋₁/(Δᵢ₋₁+Δᵢ)` and arrives at it scaled by `F⁻ᵢ = 2·Δᵢ/(Δᵢ₋₁+Δᵢ)` (1 at the
//! ends of an open spline). Each segment is a cubic Hermite in the segment parameter, so keyrig
//! Hermite keys whose per-second tangents are those divided by the segment's seconds are the
//! same cubic.
//!
//! **Squad.** `squad(qᵢ, qᵢ₊₁, sᵢ, sᵢ₊₁, u) = slerp(slerp(qᵢ, qᵢ₊₁, u), slerp(sᵢ, sᵢ₊₁, u), 2u(1−u))`
//! with Shoemake's intermediate quaternions `sᵢ = qᵢ·exp(−(log(qᵢ⁻¹qᵢ₊₁) + log(qᵢ⁻¹qᵢ₋₁))/4)`
//! (keys made sign-consistent first, each with a non-negative dot product with the one before).
//! The specification leaves the end keys open; keyrig follows X_ITE (the X3D browser that plays
//! this node): at the ends of an open interpolator `s₀ = q₀` and `sₙ₋₁ = qₙ₋₁`; with `closed`
//! the neighbours wrap (`s₀` and `sₙ₋₁` from `qₙ₋₂`, the end key and `q₁`).
//!
//! keyrig's TCB rotation keys are Squad with `Sᵢ`, `Dᵢ` the Kochanek–Bartels tangents of the
//! chords `dᵢ = log(qᵢ⁻¹qᵢ₊₁)`: `aᵢ = qᵢ·exp((Sᵢ − dᵢ)/2)`. With T = C = B = 0 and equal
//! intervals on both sides (spacing factor 1), `Sᵢ = Dᵢ = (dᵢ₋₁ + dᵢ)/2` gives exactly
//! Shoemake's `sᵢ`; unequal intervals scale keyrig's tangents, and then no T, C, B gives
//! Shoemake's (they would have to be zero and the spacing factor one), so such tracks are
//! resampled. An open end `s₀ = q₀` is `S₀ = d₀`: bias −1 at the first key (+1 at the last)
//! with tension `1 − 1/F` cancelling keyrig's spacing factor `F` there (representable while
//! `F ≥ ½`). Every TCB track is checked against [`SquadCurve`] at 8 points per segment before
//! it is kept.

use glam::{DQuat, Quat, Vec3};
use keyrig_core::quat::{exp, log_between, slerp};
use keyrig_core::{Cycles, Interpolation, Key, RawTrack, Tcb, Track};

/// Largest angle (degrees) between a resampled `SquadOrientationInterpolator` track and the
/// X3D curve it stands for (checked at 8 points per piece).
pub const SQUAD_TOLERANCE_DEG: f64 = 0.01;
/// Shortest piece (fraction of the cycle) resampling cuts a squad into.
const MIN_PIECE: f64 = 1e-6;
/// Largest angle (radians) a TCB track may differ from the X3D squad to count as the same
/// curve: float rounding only (keys are f32).
const SQUAD_EXACT_RAD: f64 = 1e-6;

/// A value a Hermite spline interpolates: `Vec3` (positions) or `f32` (scalars).
pub(super) trait SplineValue: Copy + PartialEq + std::fmt::Debug {
    const ZERO: Self;
    fn sub(self, other: Self) -> Self;
    fn scale(self, f: f32) -> Self;
    fn length(self) -> f32;
    /// Unit length (a sign for scalars), zero stays zero.
    fn unit(self) -> Self;
}

impl SplineValue for Vec3 {
    const ZERO: Self = Vec3::ZERO;
    fn sub(self, other: Self) -> Self {
        self - other
    }
    fn scale(self, f: f32) -> Self {
        self * f
    }
    fn length(self) -> f32 {
        Vec3::length(self)
    }
    fn unit(self) -> Self {
        self.normalize_or_zero()
    }
}

impl SplineValue for f32 {
    const ZERO: Self = 0.0;
    fn sub(self, other: Self) -> Self {
        self - other
    }
    fn scale(self, f: f32) -> Self {
        self * f
    }
    fn length(self) -> f32 {
        self.abs()
    }
    fn unit(self) -> Self {
        if self == 0.0 {
            0.0
        } else {
            self.signum()
        }
    }
}

/// The fields of a spline interpolator besides its keys.
pub(super) struct SplineFields<'a, T> {
    pub closed: bool,
    pub velocity: &'a [T],
    pub normalize: bool,
}

/// X3D `SplinePositionInterpolator` / `SplineScalarInterpolator` as Hermite keys over a cycle
/// of `cycle` seconds: keys at `fractions[i]·cycle`, with Linear hold keys at 0 and `cycle`
/// when the keys do not reach them. `fractions` must increase strictly.
pub(super) fn spline_keys<T: SplineValue>(
    fractions: &[f64],
    values: &[T],
    fields: &SplineFields<'_, T>,
    cycle: f64,
) -> Vec<Key<T>> {
    let n = fractions.len().min(values.len());
    if n == 0 {
        return Vec::new();
    }
    let closed = fields.closed && n > 2 && values[0] == values[n - 1];
    let velocity = fields.velocity;
    let chord: f32 = values[..n].windows(2).map(|w| w[1].sub(w[0]).length()).sum();
    let given = |v: T| if fields.normalize { v.unit().scale(chord) } else { v };
    let tangent = |i: usize| -> T {
        if velocity.len() == n {
            return given(velocity[i]);
        }
        if velocity.len() == 2 && (i == 0 || i == n - 1) && !closed {
            return given(velocity[usize::from(i != 0)]);
        }
        if closed && (i == 0 || i == n - 1) {
            return values[1].sub(values[n - 2]).scale(0.5);
        }
        if i == 0 || i == n - 1 {
            return T::ZERO;
        }
        values[i + 1].sub(values[i - 1]).scale(0.5)
    };
    let span = |i: usize| -> (f64, f64) {
        let before = if i > 0 {
            fractions[i] - fractions[i - 1]
        } else if closed {
            fractions[n - 1] - fractions[n - 2]
        } else {
            0.0
        };
        let after = if i + 1 < n {
            fractions[i + 1] - fractions[i]
        } else if closed {
            fractions[1] - fractions[0]
        } else {
            0.0
        };
        (before, after)
    };
    let mut keys = Vec::with_capacity(n + 2);
    if fractions[0] > 0.0 {
        keys.push(Key::new(0.0, values[0]).with_interpolation(Interpolation::Linear));
    }
    for i in 0..n {
        let (before, after) = span(i);
        let total = before + after;
        let (f_out, f_in) = if ((i == 0 || i == n - 1) && !closed) || total <= 0.0 {
            (1.0, 1.0)
        } else {
            (2.0 * before / total, 2.0 * after / total)
        };
        let t = tangent(i);
        // Per segment parameter → per second: divide by the segment's length in seconds.
        let out = if after > 0.0 { t.scale((f_out / (after * cycle)) as f32) } else { T::ZERO };
        let inn = if before > 0.0 { t.scale((f_in / (before * cycle)) as f32) } else { T::ZERO };
        let mut key = Key::new(fractions[i] * cycle, values[i]).with_interpolation(Interpolation::Hermite);
        key.out_tangent = Some(out);
        key.in_tangent = Some(inn);
        keys.push(key);
    }
    if fractions[n - 1] < 1.0 {
        if let Some(last) = keys.last_mut() {
            last.interpolation = Interpolation::Linear;
        }
        keys.push(Key::new(cycle, values[n - 1]).with_interpolation(Interpolation::Linear));
    }
    keys
}

/// The X3D `SquadOrientationInterpolator` curve (module documentation), in f64.
#[derive(Clone, Debug)]
pub struct SquadCurve {
    fractions: Vec<f64>,
    keys: Vec<DQuat>,
    controls: Vec<DQuat>,
}

/// Shoemake's intermediate quaternion at `q` between `before` and `after`.
fn intermediate(before: DQuat, q: DQuat, after: DQuat) -> DQuat {
    let before = if before.dot(q) < 0.0 { -before } else { before };
    let after = if after.dot(q) < 0.0 { -after } else { after };
    q * exp((log_between(q, after) + log_between(q, before)) * -0.25)
}

impl SquadCurve {
    /// The curve through `values` at `fractions` (strictly increasing, at least one).
    #[must_use]
    pub fn new(fractions: &[f64], values: &[Quat], closed: bool) -> Self {
        let n = fractions.len().min(values.len());
        let mut keys: Vec<DQuat> = Vec::with_capacity(n);
        for v in &values[..n] {
            let q = v.as_dquat().normalize();
            keys.push(match keys.last() {
                Some(prev) if prev.dot(q) < 0.0 => -q,
                _ => q,
            });
        }
        let controls = (0..n)
            .map(|i| {
                if i > 0 && i + 1 < n {
                    intermediate(keys[i - 1], keys[i], keys[i + 1])
                } else if closed && n > 2 {
                    intermediate(keys[n - 2], keys[i], keys[1])
                } else {
                    keys[i]
                }
            })
            .collect();
        SquadCurve { fractions: fractions[..n].to_vec(), keys, controls }
    }

    /// The rotation at fraction `f` (the end keys outside them).
    #[must_use]
    pub fn eval(&self, f: f64) -> DQuat {
        let n = self.fractions.len();
        if n == 0 {
            return DQuat::IDENTITY;
        }
        if f.is_nan() || f <= self.fractions[0] {
            return self.keys[0];
        }
        if f >= self.fractions[n - 1] {
            return self.keys[n - 1];
        }
        let i = self.fractions.partition_point(|&k| k <= f) - 1;
        let u = (f - self.fractions[i]) / (self.fractions[i + 1] - self.fractions[i]);
        let on_keys = slerp(self.keys[i], self.keys[i + 1], u);
        let on_controls = slerp(self.controls[i], self.controls[i + 1], u);
        slerp(on_keys, on_controls, 2.0 * u * (1.0 - u))
    }
}

/// The rotation angle (radians) between two unit quaternions (either sign).
#[must_use]
pub fn rotation_angle(a: DQuat, b: DQuat) -> f64 {
    // 4·atan2(|a − b|, |a + b|) with b turned to a's sign: exact near 0, where acos of a dot
    // product of f32-rounded quaternions loses half its digits.
    let b = if a.dot(b) < 0.0 { -b } else { b };
    let (a, b) = (glam::DVec4::from(a), glam::DVec4::from(b));
    4.0 * (a - b).length().atan2((a + b).length())
}

/// X3D `SquadOrientationInterpolator` keys over a cycle of `cycle` seconds played with
/// `cycles` (keys at `fractions[i]·cycle`, hold keys at 0 and `cycle` as for the other
/// interpolators): TCB keys when keyrig's Squad is the same curve, else slerp keys within
/// [`SQUAD_TOLERANCE_DEG`]. Returns the keys and whether they are exact. `fractions` must
/// increase strictly.
pub(super) fn squad_keys(
    fractions: &[f64],
    values: &[Quat],
    closed: bool,
    cycle: f64,
    cycles: Cycles,
) -> (Vec<Key<Quat>>, bool) {
    let n = fractions.len().min(values.len());
    if n == 0 {
        return (Vec::new(), true);
    }
    let curve = SquadCurve::new(fractions, values, closed);
    let value = |i: usize| curve.keys[i].as_quat();
    let lead = fractions[0] > 0.0;
    let trail = fractions[n - 1] < 1.0;
    let looping = cycles.after.is_cyclic();
    let span = |a: f64, b: f64| (b - a) * cycle;
    // keyrig's spacing factors at the end keys (crate::track's end chords).
    let first_interval = if lead {
        span(0.0, fractions[0])
    } else {
        span(fractions[0], fractions.get(1).copied().unwrap_or(1.0))
    };
    let last_interval = if trail {
        span(fractions[n - 1], 1.0)
    } else if n > 1 {
        span(fractions[n - 2], fractions[n - 1])
    } else {
        span(0.0, fractions[0])
    };
    let mut keys = Vec::with_capacity(n + 2);
    if lead {
        keys.push(Key::new(0.0, value(0)).with_interpolation(Interpolation::Linear));
    }
    for i in 0..n {
        let mut key = Key::new(fractions[i] * cycle, value(i)).with_interpolation(Interpolation::Tcb);
        let open_end = !(closed && n > 2) && n > 1 && (i == 0 || i == n - 1);
        if open_end {
            let inside = if i == 0 {
                span(fractions[0], fractions[1])
            } else {
                span(fractions[n - 2], fractions[n - 1])
            };
            let outside = match (i == 0, lead, trail, looping) {
                (true, true, _, _) => span(0.0, fractions[0]),
                (true, false, _, true) => last_interval,
                (false, _, true, _) => span(fractions[n - 1], 1.0),
                (false, _, false, true) => first_interval,
                _ => inside,
            };
            // F = 2·inside/(inside + outside) scales the tangent towards the neighbour inside.
            let factor = 2.0 * inside / (inside + outside);
            let tension = (1.0 - 1.0 / factor) as f32;
            key.tcb = Tcb { tension, continuity: 0.0, bias: if i == 0 { -1.0 } else { 1.0 }, clamped: false };
        }
        keys.push(key);
    }
    if trail {
        if let Some(last) = keys.last_mut() {
            last.interpolation = Interpolation::Linear;
        }
        keys.push(Key::new(cycle, value(n - 1)).with_interpolation(Interpolation::Linear));
    }
    let exact = Track::with_cycles(&RawTrack::new(keys.clone()), cycles).is_ok_and(|track| {
        fractions[..n].windows(2).all(|w| {
            (1..8).all(|k| {
                let f = w[0] + (w[1] - w[0]) * f64::from(k) / 8.0;
                rotation_angle(track.sample_wide(f * cycle), curve.eval(f)) <= SQUAD_EXACT_RAD
            })
        })
    });
    if exact {
        return (keys, true);
    }
    (resample_squad(&curve, cycle), false)
}

/// Slerp keys following `curve` within [`SQUAD_TOLERANCE_DEG`]: each segment is halved until
/// the slerp between a piece's ends stays within the tolerance of the curve at 7 points (down
/// to 1/4096 of the segment and 10⁻⁶ of the cycle, which 30 fps playback cannot tell apart).
fn resample_squad(curve: &SquadCurve, cycle: f64) -> Vec<Key<Quat>> {
    let tolerance = SQUAD_TOLERANCE_DEG.to_radians();
    let fr = &curve.fractions;
    let n = fr.len();
    let linear =
        |f: f64| Key::new(f * cycle, curve.eval(f).as_quat()).with_interpolation(Interpolation::Linear);
    let mut keys = Vec::new();
    if fr[0] > 0.0 {
        keys.push(linear(0.0));
    }
    for w in fr.windows(2) {
        let (a, b) = (w[0], w[1]);
        let mut done = vec![a];
        let mut pieces = vec![(a, b)];
        while let Some((f0, f1)) = pieces.pop() {
            let (q0, q1) = (curve.eval(f0), curve.eval(f1));
            let fits = (1..8).all(|k| {
                let s = f64::from(k) / 8.0;
                rotation_angle(slerp(q0, q1, s), curve.eval(f0 + (f1 - f0) * s)) <= tolerance
            });
            // Bounded: at most 4096 pieces a segment, none shorter than 10⁻⁶ of the cycle
            // (so at most a million pieces besides the keys, whatever the file holds).
            if fits || f1 - f0 <= ((b - a) / 4096.0).max(MIN_PIECE) {
                done.push(f1);
            } else {
                let m = 0.5 * (f0 + f1);
                pieces.push((m, f1));
                pieces.push((f0, m));
            }
        }
        done.pop();
        keys.extend(done.into_iter().map(linear));
    }
    keys.push(linear(fr[n - 1]));
    if fr[n - 1] < 1.0 {
        keys.push(linear(1.0));
    }
    keys
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn intermediate_of_a_straight_turn_is_the_key() {
        // Keys evenly along one axis: Shoemake's intermediate quaternion is the key itself.
        let q = |a: f64| DQuat::from_axis_angle(glam::DVec3::Z, a);
        let s = intermediate(q(0.0), q(0.5), q(1.0));
        assert!(rotation_angle(s, q(0.5)) < 1e-12);
    }
}
