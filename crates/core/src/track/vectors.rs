//! Scalars and vectors: every mode is a cubic in power form.

use glam::{DVec3, Vec3};

use crate::key::{Cycles, Interpolation, Key};

use super::tangents::{end_chords, kb_tangents, Vector};
use super::{Track, TrackError, TrackValue, ValueProblem};

/// `p(u) = ((c3·u + c2)·u + c1)·u + c0` on u ∈ [0, 1].
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cubic<W> {
    c3: W,
    c2: W,
    c1: W,
    pub(super) c0: W,
}

impl<W: Vector> Cubic<W> {
    fn constant(p0: W) -> Self {
        Cubic { c3: W::ZERO, c2: W::ZERO, c1: W::ZERO, c0: p0 }
    }

    fn linear(p0: W, p1: W) -> Self {
        Cubic { c3: W::ZERO, c2: W::ZERO, c1: p1 - p0, c0: p0 }
    }

    /// Hermite segment `h00·p0 + h10·m0 + h01·p1 + h11·m1` in power form.
    pub(super) fn hermite(p0: W, m0: W, p1: W, m1: W) -> Self {
        Cubic { c3: (p0 - p1) * 2.0 + m0 + m1, c2: (p1 - p0) * 3.0 - m0 * 2.0 - m1, c1: m0, c0: p0 }
    }

    #[inline]
    pub(super) fn eval(&self, u: f64) -> W {
        ((self.c3 * u + self.c2) * u + self.c1) * u + self.c0
    }

    /// dp/du.
    #[inline]
    fn derivative(&self, u: f64) -> W {
        (self.c3 * (3.0 * u) + self.c2 * 2.0) * u + self.c1
    }
}

/// Segment shapes for scalar and vector values.
fn build_cubics<T: TrackValue>(
    times: &[f64],
    keys: &[Key<T>],
    values: &[T::Wide],
    cycles: Cycles,
) -> Vec<Cubic<T::Wide>>
where
    T::Wide: Vector,
{
    let chords: Vec<T::Wide> = values.windows(2).map(|w| w[1] - w[0]).collect();
    let ends = end_chords(times, &chords, cycles, || values[0] - values[values.len() - 1]);
    let tangents = kb_tangents(times, keys.iter().map(|k| k.tcb), &chords, &ends);
    (0..values.len().saturating_sub(1))
        .map(|i| {
            let (p0, p1) = (values[i], values[i + 1]);
            match keys[i].interpolation {
                Interpolation::Step => Cubic::constant(p0),
                Interpolation::Linear => Cubic::linear(p0, p1),
                Interpolation::Tcb => Cubic::hermite(p0, tangents[i].1, p1, tangents[i + 1].0),
                Interpolation::Hermite => {
                    let duration = times[i + 1] - times[i];
                    let m0 = keys[i].out_tangent.map_or(T::Wide::ZERO, T::widen);
                    let m1 = keys[i + 1].in_tangent.map_or(T::Wide::ZERO, T::widen);
                    Cubic::hermite(p0, m0 * duration, p1, m1 * duration)
                }
            }
        })
        .collect()
}

impl TrackValue for f32 {
    type Wide = f64;
    type Shape = Cubic<f64>;
    const ROTATION: bool = false;
    type Rate = f64;
    type Delta = f64;

    fn widen(self) -> f64 {
        f64::from(self)
    }

    fn narrow(wide: f64) -> f32 {
        wide as f32
    }

    fn check(self) -> Result<f64, ValueProblem> {
        if self.is_finite() {
            Ok(f64::from(self))
        } else {
            Err(ValueProblem::NonFinite)
        }
    }

    fn is_finite_tangent(self) -> bool {
        self.is_finite()
    }

    fn build(
        times: &[f64],
        keys: &[Key<f32>],
        values: &mut [f64],
        cycles: Cycles,
    ) -> Result<Vec<Cubic<f64>>, TrackError> {
        Ok(build_cubics(times, keys, values, cycles))
    }

    #[inline]
    fn eval(shape: &Cubic<f64>, u: f64) -> f64 {
        shape.eval(u)
    }

    fn end_rate(shape: &Cubic<f64>, u: f64, inv_duration: f64) -> f64 {
        shape.derivative(u) * inv_duration
    }

    fn zero_rate() -> f64 {
        0.0
    }

    fn advance(value: f64, rate: f64, dt: f64) -> f64 {
        value + rate * dt
    }

    fn cycle_delta(first: f64, last: f64) -> f64 {
        last - first
    }

    fn offset(value: f64, delta: f64, cycles: f64) -> f64 {
        value + delta * cycles
    }
}

impl TrackValue for Vec3 {
    type Wide = DVec3;
    type Shape = Cubic<DVec3>;
    const ROTATION: bool = false;
    type Rate = DVec3;
    type Delta = DVec3;

    fn widen(self) -> DVec3 {
        self.as_dvec3()
    }

    fn narrow(wide: DVec3) -> Vec3 {
        wide.as_vec3()
    }

    fn check(self) -> Result<DVec3, ValueProblem> {
        if self.is_finite() {
            Ok(self.as_dvec3())
        } else {
            Err(ValueProblem::NonFinite)
        }
    }

    fn is_finite_tangent(self) -> bool {
        self.is_finite()
    }

    fn build(
        times: &[f64],
        keys: &[Key<Vec3>],
        values: &mut [DVec3],
        cycles: Cycles,
    ) -> Result<Vec<Cubic<DVec3>>, TrackError> {
        Ok(build_cubics(times, keys, values, cycles))
    }

    #[inline]
    fn eval(shape: &Cubic<DVec3>, u: f64) -> DVec3 {
        shape.eval(u)
    }

    fn end_rate(shape: &Cubic<DVec3>, u: f64, inv_duration: f64) -> DVec3 {
        shape.derivative(u) * inv_duration
    }

    fn zero_rate() -> DVec3 {
        DVec3::ZERO
    }

    fn advance(value: DVec3, rate: DVec3, dt: f64) -> DVec3 {
        value + rate * dt
    }

    fn cycle_delta(first: DVec3, last: DVec3) -> DVec3 {
        last - first
    }

    fn offset(value: DVec3, delta: DVec3, cycles: f64) -> DVec3 {
        value + delta * cycles
    }
}

/// Velocity (derivative with respect to time) and glTF tangents of scalar and vector tracks.
impl<T, W> Track<T>
where
    T: TrackValue<Wide = W, Shape = Cubic<W>>,
    W: Vector,
{
    /// Velocity in value units per second at `t`: the right-hand derivative (at a key, the
    /// velocity leaving it). Zero outside the domain and on Step segments.
    #[must_use]
    pub fn velocity(&self, t: f64) -> T {
        T::narrow(self.velocity_wide(t))
    }

    /// [`Track::velocity`] in f64.
    #[must_use]
    pub fn velocity_wide(&self, t: f64) -> W {
        let last = self.times.len() - 1;
        if t.is_nan() || t < self.times[0] || t >= self.times[last] {
            return W::ZERO;
        }
        let i = self.times.partition_point(|&x| x <= t) - 1;
        self.segment_velocity(i, t)
    }

    /// The left-hand derivative at `t` (at a key, the velocity arriving at it). Zero outside the
    /// domain. With [`Track::velocity`] it shows whether the track is C¹ at a key.
    #[must_use]
    pub fn velocity_before(&self, t: f64) -> T {
        T::narrow(self.velocity_before_wide(t))
    }

    /// [`Track::velocity_before`] in f64.
    #[must_use]
    pub fn velocity_before_wide(&self, t: f64) -> W {
        let last = self.times.len() - 1;
        if t.is_nan() || t <= self.times[0] || t > self.times[last] {
            return W::ZERO;
        }
        let i = self.times.partition_point(|&x| x < t) - 1;
        self.segment_velocity(i, t)
    }

    fn segment_velocity(&self, i: usize, t: f64) -> W {
        let segment = &self.segments[i];
        let u = ((t - segment.start) * segment.inv_duration).clamp(0.0, 1.0);
        segment.shape.derivative(u) * segment.inv_duration
    }

    /// Per-second Hermite tangents of segment `i` as glTF CUBICSPLINE stores them:
    /// `(out-tangent of key i, in-tangent of key i+1)` = `(S_i / t_d, D_{i+1} / t_d)` for TCB
    /// segments, the chord slope for Linear ones. `None` for Step segments (not a cubic that
    /// glTF can express exactly) and past the end.
    #[must_use]
    pub fn segment_tangents(&self, i: usize) -> Option<(T, T)> {
        let segment = self.segments.get(i)?;
        if segment.interpolation == Interpolation::Step {
            return None;
        }
        let shape = &segment.shape;
        Some((
            T::narrow(shape.derivative(0.0) * segment.inv_duration),
            T::narrow(shape.derivative(1.0) * segment.inv_duration),
        ))
    }
}
