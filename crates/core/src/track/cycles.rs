//! Sampling outside the keys: what [`Cycles`] do before the first key and after the last
//! ([`crate::track`] module documentation, "Cycles"; docs/design.md §9), and the check of a
//! track's cycles.

use crate::key::{Cycle, Cycles};

use super::{Segment, Track, TrackError, TrackValue};

/// Which end of a track a [`Cycle`] applies to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TrackEnd {
    /// Before the first key (`Animated::before`).
    Before,
    /// After the last key (`Animated::after`).
    After,
}

impl TrackEnd {
    /// The field's name in the scene file: `before` or `after`.
    #[must_use]
    pub fn field(self) -> &'static str {
        match self {
            TrackEnd::Before => "before",
            TrackEnd::After => "after",
        }
    }
}

impl std::fmt::Display for TrackEnd {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.field())
    }
}

/// Checks the cycles of a track with the given key times: each end other than
/// [`Cycle::Hold`] needs two keys and a positive, finite period. The one place this rule is
/// computed ([`Track::with_cycles`] and [`crate::Scene::problems`] call it).
///
/// # Errors
/// [`TrackError::CycleNeedsTwoKeys`] or [`TrackError::CyclePeriod`], `before` first.
pub fn check_cycles(times: &[f64], cycles: Cycles) -> Result<(), TrackError> {
    for (end, cycle) in [(TrackEnd::Before, cycles.before), (TrackEnd::After, cycles.after)] {
        if cycle.is_hold() {
            continue;
        }
        if times.len() < 2 {
            return Err(TrackError::CycleNeedsTwoKeys { end, cycle });
        }
        let period = times[times.len() - 1] - times[0];
        if !(period.is_finite() && period > 0.0) {
            return Err(TrackError::CyclePeriod { end, cycle });
        }
    }
    Ok(())
}

/// Precomputed for sampling outside the keys.
#[derive(Clone, Debug, PartialEq)]
pub(super) struct Ends<T: TrackValue> {
    /// `t_n − t_0`.
    period: f64,
    /// `1 / period` (a multiplication is cheaper than a division per sample).
    inv_period: f64,
    /// One offset cycle: `P_n − P_0`, or `q_n·q_0⁻¹`.
    delta: T::Delta,
    /// The rate leaving the first key (backwards in time) and arriving at the last.
    rate_before: T::Rate,
    rate_after: T::Rate,
}

impl<T: TrackValue> Ends<T> {
    /// From the validated key times, the keys' f64 values and the segments between them.
    pub(super) fn new(times: &[f64], wide: &[T::Wide], segments: &[Segment<T::Shape>]) -> Self {
        let n = times.len();
        Ends {
            period: times[n - 1] - times[0],
            inv_period: 1.0 / (times[n - 1] - times[0]),
            delta: T::cycle_delta(wide[0], wide[n - 1]),
            rate_before: segments
                .first()
                .map_or(T::zero_rate(), |s| T::end_rate(&s.shape, 0.0, s.inv_duration)),
            rate_after: segments
                .last()
                .map_or(T::zero_rate(), |s| T::end_rate(&s.shape, 1.0, s.inv_duration)),
        }
    }
}

/// Where a time outside the keys is sampled: at `local`, inside the keys, then offset by
/// `cycles` offset cycles (zero unless [`Cycle::RepeatOffset`]); or extrapolated.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(super) enum Outside {
    /// Hold the key.
    Key(usize),
    /// Linear extrapolation from the first (`false`) or last (`true`) key.
    Linear { after: bool },
    /// A time inside the keys; `mirrored` when a ping-pong plays it backwards.
    Cycle { local: f64, cycles: f64, mirrored: bool },
}

impl<T: TrackValue> Track<T> {
    /// With the hold rule at both ends (a cycle's local time may round onto an end key).
    fn sample_held(&self, t: f64) -> T::Wide {
        let last = self.times.len() - 1;
        if t.is_nan() || t <= self.times[0] {
            self.wide[0]
        } else if t >= self.times[last] {
            self.wide[last]
        } else {
            self.sample_inside(t)
        }
    }

    /// Outside the domain with a cycle at that end.
    #[inline]
    pub(super) fn sample_outside(&self, t: f64) -> T::Wide {
        match self.outside(t) {
            Outside::Key(i) => self.wide[i],
            Outside::Linear { after: false } => {
                T::advance(self.wide[0], self.ends.rate_before, t - self.times[0])
            }
            Outside::Linear { after: true } => {
                let last = self.times.len() - 1;
                T::advance(self.wide[last], self.ends.rate_after, t - self.times[last])
            }
            Outside::Cycle { local, cycles, .. } => {
                let value = self.sample_held(local);
                if cycles == 0.0 {
                    value
                } else {
                    T::offset(value, self.ends.delta, cycles)
                }
            }
        }
    }

    /// Where `t`, outside the domain, is sampled ([`crate::track`] module documentation, "Cycles").
    #[inline]
    pub(super) fn outside(&self, t: f64) -> Outside {
        let last = self.times.len() - 1;
        let (t0, period) = (self.times[0], self.ends.period);
        let after = t > self.times[last];
        let held = Outside::Key(if after { last } else { 0 });
        let cycle = if after { self.cycles.after } else { self.cycles.before };
        match cycle {
            Cycle::Hold => held,
            Cycle::Linear => Outside::Linear { after },
            Cycle::Repeat | Cycle::RepeatOffset => {
                let k = floor((t - t0) * self.ends.inv_period);
                if !k.is_finite() {
                    return held;
                }
                let local = t0 + ((t - t0) - k * period);
                let cycles = if cycle == Cycle::RepeatOffset { k } else { 0.0 };
                Outside::Cycle { local, cycles, mirrored: false }
            }
            Cycle::PingPong => {
                let phase = (t - t0).rem_euclid(2.0 * period);
                if !phase.is_finite() {
                    return held;
                }
                if phase <= period {
                    Outside::Cycle { local: t0 + phase, cycles: 0.0, mirrored: false }
                } else {
                    Outside::Cycle { local: t0 + (2.0 * period - phase), cycles: 0.0, mirrored: true }
                }
            }
        }
    }
}

/// `x.floor()` without a libm call on baseline x86-64 (no SSE4.1 `roundsd`): truncate, then
/// step down for negative non-integers. Beyond ±2^52 every f64 is an integer already.
#[inline]
fn floor(x: f64) -> f64 {
    const EXACT: f64 = 4_503_599_627_370_496.0; // 2^52
    if x.abs() < EXACT {
        let k = x as i64 as f64;
        if k > x {
            k - 1.0
        } else {
            k
        }
    } else {
        x
    }
}
