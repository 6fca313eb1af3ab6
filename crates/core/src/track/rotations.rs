//! Rotations: unit quaternions, interpolated by slerp, Squad, glTF's component-wise Hermite or
//! a spin segment.

use glam::{DQuat, DVec3, DVec4, Quat};

#[cfg(doc)]
use crate::key::Spin;
use crate::key::{Cycles, Interpolation, Key};
use crate::quat::{self, Arc};

use super::cycles::Outside;
use super::spins::{spin_chord, SpinChord, SpinProblem, SpinSegment};
use super::tangents::{end_chords, kb_tangents};
use super::vectors::Cubic;
use super::{Clamped, Track, TrackError, TrackValue, ValueProblem, MIN_QUATERNION_NORM};

/// Segment shapes for unit quaternions.
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum QuatShape {
    Step(DQuat),
    /// Slerp between the (sign-consistent) keys.
    Slerp(Arc),
    /// `squad(u) = slerp(slerp(q_i, q_{i+1}, u), slerp(a_i, b_{i+1}, u), 2u(1−u))`.
    Squad {
        keys: Arc,
        controls: Arc,
    },
    /// glTF CUBICSPLINE rotation: component-wise Hermite, then normalized.
    Hermite(Cubic<DVec4>),
    /// A spin segment, or a TCB segment next to one ([`crate::track`] module documentation, "Spin keys").
    Spin(SpinSegment),
}

/// One [`Cycle::RepeatOffset`] cycle of a rotation track: `M = q_n·q_0⁻¹ = sign·exp(log)`,
/// with `log` the half-angle vector of `±M` with `w ≥ 0`, so `M^k = sign^k·exp(k·log)` exactly
/// continues the quaternions' signs from cycle to cycle.
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct QuatDelta {
    log: DVec3,
    negative: bool,
}

impl TrackValue for Quat {
    type Wide = DQuat;
    type Shape = QuatShape;
    const ROTATION: bool = true;
    type Rate = DVec3;
    type Delta = QuatDelta;

    fn widen(self) -> DQuat {
        self.as_dquat()
    }

    fn narrow(wide: DQuat) -> Quat {
        wide.as_quat()
    }

    fn check(self) -> Result<DQuat, ValueProblem> {
        if !self.is_finite() {
            return Err(ValueProblem::NonFinite);
        }
        let q = self.as_dquat();
        let norm = q.length();
        if norm < MIN_QUATERNION_NORM {
            return Err(ValueProblem::ZeroQuaternion);
        }
        Ok(q * (1.0 / norm))
    }

    fn is_finite_tangent(self) -> bool {
        self.is_finite()
    }

    fn build(
        times: &[f64],
        keys: &[Key<Quat>],
        values: &mut [DQuat],
        cycles: Cycles,
    ) -> Result<Vec<QuatShape>, TrackError> {
        // Sign consistency and the chords L(q_i, q_{i+1}): the short-way log, or a spin's
        // unwrapped chord with q_{i+1} given the sign of q_i·exp(L).
        let n = values.len();
        let mut flipped = vec![false; n];
        let mut logs: Vec<DVec3> = Vec::with_capacity(n.saturating_sub(1));
        let mut spins: Vec<Option<SpinChord>> = Vec::with_capacity(n.saturating_sub(1));
        for i in 1..n {
            let spin = match keys[i].spin {
                Some(spin) => {
                    if keys[i - 1].interpolation == Interpolation::Hermite {
                        return Err(TrackError::Spin { index: i, problem: SpinProblem::AfterHermite });
                    }
                    spin_chord(values[i - 1], values[i], spin)
                        .map_err(|problem| TrackError::Spin { index: i, problem })?
                }
                None => None,
            };
            let reference = match &spin {
                Some(spin) => values[i - 1] * quat::exp(spin.chord),
                None => values[i - 1],
            };
            if reference.dot(values[i]) < 0.0 {
                values[i] = -values[i];
                flipped[i] = true;
            }
            // A spin's residual joins its chord here, so that the tangents (and A, B below) are
            // those of the whole segment rotation and C = 0 keys stay C¹ also with a residual.
            logs.push(match &spin {
                Some(spin) => spin.chord + spin.residual,
                None => quat::log_between(values[i - 1], values[i]),
            });
            spins.push(spin);
        }
        // Repeat's gap across the seam, `log(q_n⁻¹·q_0)` the short way (zero when the loop
        // closes, also after whole turns).
        let ends = end_chords(times, &logs, cycles, || {
            let mut r = values[n - 1].conjugate() * values[0];
            if r.w < 0.0 {
                r = -r;
            }
            quat::log(r)
        });
        let tangents = kb_tangents(times, keys.iter().map(|k| k.tcb), &logs, &ends);
        let sign = |i: usize| if flipped[i] { -1.0 } else { 1.0 };
        // With cycles the end segments are neighbours across the seam: a spin at one end
        // puts its chord into the other end's tangent, which only the spin form can follow.
        let seam_spin = n >= 2
            && (cycles.before.is_cyclic() || cycles.after.is_cyclic())
            && spins.iter().any(Option::is_some);
        let is_spin = |i: usize| spins.get(i).is_some_and(Option::is_some);
        Ok((0..n.saturating_sub(1))
            .map(|i| {
                let (q0, q1) = (values[i], values[i + 1]);
                let spin_segment = |a: DVec3, b: DVec3| {
                    let spin = spins[i].as_ref();
                    QuatShape::Spin(SpinSegment {
                        start: q0,
                        chord: spin.map_or(logs[i], |s| s.chord),
                        a,
                        b,
                        residual: spin.map_or(DVec3::ZERO, |s| s.residual),
                        spin: spin.map(|s| (s.axis, s.degrees)),
                    })
                };
                match keys[i].interpolation {
                    Interpolation::Step => QuatShape::Step(q0),
                    Interpolation::Linear if is_spin(i) => spin_segment(DVec3::ZERO, DVec3::ZERO),
                    Interpolation::Linear => QuatShape::Slerp(Arc::new(q0, q1)),
                    Interpolation::Tcb => {
                        let (out_tangent, in_tangent) = (tangents[i].1, tangents[i + 1].0);
                        let at_seam = seam_spin && (i == 0 || i + 2 == n);
                        if is_spin(i) || (i > 0 && is_spin(i - 1)) || is_spin(i + 1) || at_seam {
                            spin_segment((out_tangent - logs[i]) * 0.5, (logs[i] - in_tangent) * 0.5)
                        } else {
                            let a = q0 * quat::exp((out_tangent - logs[i]) * 0.5);
                            let b = q1 * quat::exp((logs[i] - in_tangent) * 0.5);
                            QuatShape::Squad { keys: Arc::new(q0, q1), controls: Arc::new(a, b) }
                        }
                    }
                    Interpolation::Hermite => {
                        let duration = times[i + 1] - times[i];
                        let vec4 = |q: Option<Quat>| q.map_or(DVec4::ZERO, |q| DVec4::from(q.as_dquat()));
                        let m0 = vec4(keys[i].out_tangent) * (sign(i) * duration);
                        let m1 = vec4(keys[i + 1].in_tangent) * (sign(i + 1) * duration);
                        QuatShape::Hermite(Cubic::hermite(DVec4::from(q0), m0, DVec4::from(q1), m1))
                    }
                }
            })
            .collect())
    }

    #[inline]
    fn eval(shape: &QuatShape, u: f64) -> DQuat {
        match shape {
            QuatShape::Step(q) => *q,
            QuatShape::Slerp(arc) => arc.eval(u),
            QuatShape::Squad { keys, controls } => {
                quat::slerp_fast(keys.eval(u), controls.eval(u), 2.0 * u * (1.0 - u))
            }
            QuatShape::Hermite(cubic) => {
                let v = cubic.eval(u);
                let norm = v.length();
                if norm > MIN_QUATERNION_NORM && norm.is_finite() {
                    DQuat::from_vec4(v / norm)
                } else {
                    // The tangents cancel the keys: fall back to the segment's first key.
                    DQuat::from_vec4(cubic.c0)
                }
            }
            QuatShape::Spin(segment) => segment.eval(u),
        }
    }

    /// `q⁻¹·dq/dt` by one-sided differences of the logarithm over `h` and `h/2` in `u`, combined
    /// by Richardson extrapolation (error O(h²), about 1e-8 of the curvature).
    fn end_rate(shape: &QuatShape, u: f64, inv_duration: f64) -> DVec3 {
        const H: f64 = 1e-4;
        let h = if u > 0.5 { -H } else { H };
        let q = Self::eval(shape, u);
        let slope = |h: f64| quat::log_between(q, Self::eval(shape, u + h)) / h;
        (slope(h / 2.0) * 2.0 - slope(h)) * inv_duration
    }

    fn zero_rate() -> DVec3 {
        DVec3::ZERO
    }

    /// `q·exp(rate·dt)`: turning on at the end key's body-frame angular velocity.
    fn advance(value: DQuat, rate: DVec3, dt: f64) -> DQuat {
        value * quat::exp(rate * dt)
    }

    fn cycle_delta(first: DQuat, last: DQuat) -> QuatDelta {
        let m = last * first.conjugate();
        let negative = m.w < 0.0;
        QuatDelta { log: quat::log(if negative { -m } else { m }), negative }
    }

    /// `M^k·q`.
    fn offset(value: DQuat, delta: QuatDelta, cycles: f64) -> DQuat {
        let power = quat::exp(delta.log * cycles) * value;
        if delta.negative && cycles.rem_euclid(2.0) == 1.0 {
            -power
        } else {
            power
        }
    }
}

/// Spin segments of rotation tracks.
impl Track<Quat> {
    /// Whether any segment ends at a key with a (non-zero) [`Spin`].
    #[must_use]
    pub fn has_spin(&self) -> bool {
        (0..self.segments.len()).any(|i| self.segment_spin(i).is_some())
    }

    /// The spin of segment `i` (from key i to key i+1) when key i+1 has one: the unit axis in
    /// key i's frame and the signed, unwrapped angle about it in degrees (e.g. 360 for a full
    /// turn). `None` for short-way segments and past the end.
    #[must_use]
    pub fn segment_spin(&self, i: usize) -> Option<(DVec3, f64)> {
        match &self.segments.get(i)?.shape {
            QuatShape::Spin(segment) => segment.spin,
            _ => None,
        }
    }

    /// The unwrapped angle (degrees) turned about the spin's axis since the first key of the
    /// spin segment that `t` falls in; `None` outside spin segments. At a key that ends a spin
    /// segment (and after the last key) it is that segment's whole angle, e.g. 360; at a key
    /// that only starts one (and before the first key) 0. Inside a segment it is `u·θ` plus
    /// the TCB offset's component along the axis, the exact angle when every rotation shares
    /// the axis (a twist).
    #[must_use]
    pub fn spin_degrees(&self, t: f64) -> Option<f64> {
        let last = self.times.len() - 1;
        let at_start = |i: usize| self.segment_spin(i).map(|_| 0.0);
        let at_end = |i: usize| self.segment_spin(i).map(|(_, degrees)| degrees);
        let clamped = match self.clamp(t) {
            Clamped::Outside => match self.outside(t) {
                Outside::Cycle { local, .. } => {
                    return self.spin_degrees(local.clamp(self.times[0], self.times[last]))
                }
                Outside::Key(i) => Clamped::Key(i),
                Outside::Linear { .. } => return None,
            },
            clamped => clamped,
        };
        match clamped {
            Clamped::Key(0) => at_start(0),
            Clamped::Key(i) if i == last => at_end(last - 1),
            Clamped::Key(_) => None,
            Clamped::Inside => {
                let i = self.times.partition_point(|&x| x <= t) - 1;
                if t == self.times[i] {
                    return if i > 0 { at_end(i - 1).or_else(|| at_start(i)) } else { at_start(i) };
                }
                match &self.segments[i].shape {
                    QuatShape::Spin(segment) => {
                        let u = ((t - self.segments[i].start) * self.segments[i].inv_duration).min(1.0);
                        segment.degrees_at(u)
                    }
                    _ => None,
                }
            }
            Clamped::Outside => None,
        }
    }
}
