//! Validated, evaluable keyframe tracks (docs/design.md §3).
//!
//! A [`RawTrack`] is checked once by [`Track::new`] into a [`Track`], which precomputes
//! everything that depends only on the keys (Kochanek–Bartels tangents with the non-uniform
//! spacing factors, Squad control quaternions, sign-consistent unit quaternions). Sampling then
//! only locates the segment (binary search) and evaluates one cubic or one Squad.
//!
//! # Sampling rule
//! * `t` before the first key (or NaN) gives the first key's value; `t` at or after the last key
//!   gives the last key's value (constant extrapolation) — unless the track has a [`Cycle`]
//!   at that end (below).
//! * At a key time `t_i` the result is exactly the key's value (normalized and sign-adjusted for
//!   rotations, see [`Track::key_values`]).
//! * Inside segment i (`t_i < t < t_{i+1}`), the mode of key i decides: Step holds `P_i`;
//!   Linear is `P_i + u (P_{i+1} − P_i)` (slerp for rotations); Tcb is the Hermite segment
//!   `h00·P_i + h10·S_i + h01·P_{i+1} + h11·D_{i+1}` (Squad with TCB for rotations); Hermite uses
//!   the keys' per-second tangents times the segment duration (glTF CUBICSPLINE; for rotations
//!   component-wise Hermite, then normalized). `u = (t − t_i)/(t_{i+1} − t_i)`.
//!
//! # End keys
//! The first and the last key have one neighbour only. keyrig uses `P_{−1} := P_0` and
//! `P_{n+1} := P_n` (for rotations `L(q_{−1}, q_0) = L(q_n, q_{n+1}) = 0`) together with a
//! mirrored spacing (`Δ_{−1} := Δ_0`, `Δ_n := Δ_{n−1}`), so the spacing factor at an end key is 1.
//! With T = C = B = 0 the end tangent is half the chord: `S_0 = (P_1 − P_0)/2`.
//!
//! # Spin keys
//! A rotation key with a [`Spin`] is reached from the previous key by an *unwrapped* chord
//! `L` (half the angle times the axis, any size) instead of the short-way logarithm (docs/design.md
//! §3; docs/interpolation.md). `L` enters the Kochanek–Bartels tangents like any chord, and
//! * Linear: `q(u) = q_i·exp(u·L)·exp(u·e)`,
//! * Tcb: `q(u) = q_i·exp(u·L)·exp(s·((1−u)·A + u·B) + u·e)`, `s = 2u(1−u)`,
//!   `A = (T_i^out − (L+e))/2`, `B = ((L+e) − T_{i+1}^in)/2`,
//!
//! where `e` is the tiny residual (at most [`SPIN_ANGLE_TOLERANCE_DEG`]) between the rotation
//! an [`Spin::Angle`] arrives at and the key's value (zero for [`Spin::Turns`]), so that the
//! segment ends exactly on the key (the tangents use the chord `L + e`). The Tcb form has Squad's values and tangents at both ends
//! (`q_i`, `q_{i+1}`, `T_i^out`, `T_{i+1}^in`) and equals Squad exactly when all rotations share
//! one axis (a twist); Squad's own short-way slerps cannot follow a chord beyond half a turn.
//! A TCB segment next to a spin segment (whose tangents carry that chord) uses the same form,
//! so C = 0 keys stay C¹. Tracks without spins are interpolated exactly as before.
//!
//! # Cycles
//! Outside its keys a track does what its [`Cycles`] say (docs/design.md §9; period `P = t_n − t_0`):
//! * Hold: the end key's value.
//! * Linear: `P_n + (t − t_n)·v_n` with `v_n` the velocity arriving at the last key (leaving
//!   the first, backwards, before it); rotations `q_n·exp((t − t_n)·ω_n)` with `ω_n = q⁻¹·dq/dt`.
//! * Repeat: `t` is moved by whole periods `k = ⌊(t − t_0)/P⌋` into the keys: `sample(t − k·P)`.
//! * RepeatOffset: the same plus `k·(P_n − P_0)`; rotations `M^k·q(t − k·P)` with
//!   `M = q_n·q_0⁻¹` (so relative to the first key each cycle adds `q_0⁻¹·q_n`).
//! * PingPong: the keys forwards, then backwards: `sample(t_0 + φ)` for the phase
//!   `φ = (t − t_0) mod 2P ≤ P`, else `sample(t_0 + 2P − φ)`.
//!
//! TCB and Squad use the keys across the seam as the end keys' neighbours ([`end_chords`]):
//! for Repeat the key before the first is the second-to-last key one period earlier (for
//! RepeatOffset also one offset lower), the key after the last is the second key one period
//! later; for PingPong the neighbour is the mirrored key. So a closed repeating loop
//! (`P_n = P_0`) or any RepeatOffset track with C = 0 keys and equal tension and bias at
//! its first and last key is C¹ through the seam, and a ping-pong with T = C = B = 0 at its
//! end keys turns with zero velocity. Tracks with Hold at both ends are built and sampled
//! exactly as before; [`Track::velocity`] and [`Track::segment_tangents`] describe the keys'
//! own segments only.
//!
//! All arithmetic is done in f64 (values are widened from f32 once, at validation) and the
//! result is rounded to the value type at the end; [`Track::sample_wide`] returns the f64
//! value before rounding.
//!
//! # Modules
//! * this module: the value trait [`TrackValue`], [`Track`] (validation, sampling inside the
//!   keys), [`AnimatedTrack`] and [`TrackError`];
//! * `tangents`: the Kochanek–Bartels tangents and the end keys' neighbours, shared by every
//!   value type;
//! * `vectors`: scalars and vectors (every mode a cubic), their velocity and glTF tangents;
//! * `rotations`: unit quaternions (slerp, Squad, glTF Hermite, spin segments);
//! * `spins`: the rules and the unwrapped chord of a [`Spin`] key, and the
//!   spin segment's formula;
//! * `cycles`: sampling before the first key and after the last ([`Cycles`]), and
//!   [`check_cycles`].

mod cycles;
mod rotations;
mod spins;
mod tangents;
mod vectors;

use std::fmt::Debug;

#[cfg(doc)]
use glam::{DQuat, DVec3, Quat, Vec3};

use crate::key::{Animated, Cycle, Cycles, Interpolation, Key, RawTrack, Tcb};
#[cfg(doc)]
use crate::key::{Spin, SPIN_ANGLE_TOLERANCE_DEG};
#[cfg(doc)]
use tangents::end_chords;

use cycles::Ends;
pub use cycles::{check_cycles, TrackEnd};
pub use rotations::{QuatDelta, QuatShape};
pub(crate) use spins::spin_problem;
pub use spins::{spin_chord, SpinChord, SpinProblem, SpinSegment};
pub use tangents::Vector;
pub use vectors::Cubic;

/// Quaternion keys shorter than this (before normalization) are rejected as zero.
pub const MIN_QUATERNION_NORM: f64 = 1e-6;

/// Which tangent of a key a Hermite segment is missing.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum TangentSide {
    /// `in_tangent`, used by the segment that ends at the key.
    In,
    /// `out_tangent`, used by the segment that starts at the key.
    Out,
}

impl std::fmt::Display for TangentSide {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(match self {
            TangentSide::In => "in_tangent",
            TangentSide::Out => "out_tangent",
        })
    }
}

/// Why a [`RawTrack`] (or an [`Animated`] value) cannot be evaluated. `index` is the position
/// of the offending key in the raw key list.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TrackError {
    #[error("track has no keys")]
    Empty,
    #[error("key {index}: time is earlier than the previous key's (keys must be sorted by time)")]
    Unsorted { index: usize },
    #[error("key {index}: same time as the previous key (key times must be distinct)")]
    DuplicateTime { index: usize },
    #[error("key {index}: time is not a finite number")]
    NonFiniteTime { index: usize },
    #[error("key {index}: value is not finite (NaN or infinity)")]
    NonFiniteValue { index: usize },
    #[error("key {index}: rotation quaternion has (nearly) zero length")]
    ZeroQuaternion { index: usize },
    #[error("key {index}: tangent is not finite (NaN or infinity)")]
    NonFiniteTangent { index: usize },
    #[error("key {index}: Hermite interpolation needs the key's {side}")]
    MissingTangent { index: usize, side: TangentSide },
    #[error("key {index}: tension, continuity and bias must be finite and within [-1, 1]")]
    TcbOutOfRange { index: usize },
    #[error("key {index}: {problem}")]
    Spin { index: usize, problem: SpinProblem },
    #[error("static value is not finite (NaN or infinity)")]
    NonFiniteStaticValue,
    #[error("static rotation quaternion has (nearly) zero length")]
    ZeroStaticQuaternion,
    #[error("{cycle} {end} the keys needs at least two keys (a cycle repeats the time from the first key to the last)")]
    CycleNeedsTwoKeys { end: TrackEnd, cycle: Cycle },
    #[error("{cycle} {end} the keys needs a positive, finite period (last key time − first key time)")]
    CyclePeriod { end: TrackEnd, cycle: Cycle },
}

/// What is wrong with one value (before an index is attached).
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ValueProblem {
    NonFinite,
    ZeroQuaternion,
}

mod sealed {
    pub trait Sealed {}
    impl Sealed for f32 {}
    impl Sealed for glam::Vec3 {}
    impl Sealed for glam::Quat {}
}

/// A value type a [`Track`] can interpolate: `f32` (scalars), [`Vec3`] and unit [`Quat`]
/// (rotations). Sealed; the hidden items are keyrig's internals.
pub trait TrackValue: Copy + Debug + PartialEq + sealed::Sealed {
    /// The f64 form all interpolation is done in (`f64`, [`DVec3`], [`DQuat`]).
    type Wide: Copy + Debug + PartialEq;
    #[doc(hidden)]
    type Shape: Clone + Debug + PartialEq;
    /// Whether keys of this type may carry a [`Spin`].
    #[doc(hidden)]
    const ROTATION: bool;
    /// A rate of change per second (for rotations the body-frame half-angle rate `q⁻¹·dq/dt`).
    #[doc(hidden)]
    type Rate: Copy + Debug + PartialEq;
    /// What one cycle of [`Cycle::RepeatOffset`] adds.
    #[doc(hidden)]
    type Delta: Copy + Debug + PartialEq;

    /// Widens to f64 (exact).
    fn widen(self) -> Self::Wide;
    /// Rounds the f64 form to the value type.
    fn narrow(wide: Self::Wide) -> Self;

    /// Checks one key value; returns its f64 form (unit length for rotations).
    #[doc(hidden)]
    fn check(self) -> Result<Self::Wide, ValueProblem>;
    #[doc(hidden)]
    fn is_finite_tangent(self) -> bool;
    /// Builds the n−1 segment shapes; `values` are the checked values, in/out may be adjusted
    /// (sign consistency). Times, values, tangents and the spins' ranges are validated.
    /// `cycles` decide the neighbours of the end keys (module documentation, "Cycles").
    #[doc(hidden)]
    fn build(
        times: &[f64],
        keys: &[Key<Self>],
        values: &mut [Self::Wide],
        cycles: Cycles,
    ) -> Result<Vec<Self::Shape>, TrackError>;
    #[doc(hidden)]
    fn eval(shape: &Self::Shape, u: f64) -> Self::Wide;
    /// The rate of change per second of a segment at `u` (0 or 1).
    #[doc(hidden)]
    fn end_rate(shape: &Self::Shape, u: f64, inv_duration: f64) -> Self::Rate;
    #[doc(hidden)]
    fn zero_rate() -> Self::Rate;
    /// `value` moved on at `rate` for `dt` seconds (linear extrapolation).
    #[doc(hidden)]
    fn advance(value: Self::Wide, rate: Self::Rate, dt: f64) -> Self::Wide;
    /// The change of one [`Cycle::RepeatOffset`] cycle from the first key's value to the last's.
    #[doc(hidden)]
    fn cycle_delta(first: Self::Wide, last: Self::Wide) -> Self::Delta;
    /// `value` offset by `cycles` (a whole number, maybe negative) times `delta`.
    #[doc(hidden)]
    fn offset(value: Self::Wide, delta: Self::Delta, cycles: f64) -> Self::Wide;
}

/// One segment: from key i (at `start`) to key i+1.
#[derive(Clone, Debug, PartialEq)]
struct Segment<S> {
    start: f64,
    inv_duration: f64,
    interpolation: Interpolation,
    shape: S,
}

/// A validated, evaluable track of `f32`, [`Vec3`] or [`Quat`] keys.
///
/// Build it with [`Track::new`]; sample it with [`Track::sample`] (O(log n) binary search).
///
/// ```
/// use glam::Vec3;
/// use keyrig_core::{Key, RawTrack, Track};
///
/// let raw = RawTrack::new(vec![
///     Key::new(0.0, Vec3::ZERO),
///     Key::new(1.0, Vec3::X),
///     Key::new(3.0, Vec3::new(1.0, 2.0, 0.0)),
/// ]);
/// let track = Track::new(&raw)?;
/// assert_eq!(track.domain(), (0.0, 3.0));
/// assert_eq!(track.sample(1.0), Vec3::X); // passes through keys exactly
/// assert_eq!(track.sample(-5.0), Vec3::ZERO); // clamped before the first key
/// # Ok::<(), keyrig_core::TrackError>(())
/// ```
#[derive(Clone, Debug, PartialEq)]
pub struct Track<T: TrackValue> {
    /// Key times, strictly increasing, at least one.
    times: Vec<f64>,
    /// Key values as given (rotations: normalized and sign-consistent), rounded to `T`.
    values: Vec<T>,
    /// The same values in f64.
    wide: Vec<T::Wide>,
    /// `times.len() − 1` segments.
    segments: Vec<Segment<T::Shape>>,
    /// Before the first key and after the last.
    cycles: Cycles,
    /// What sampling outside the keys needs.
    ends: Ends<T>,
}

impl<T: TrackValue> Track<T> {
    /// Validates `raw` and precomputes its interpolation data.
    ///
    /// # Errors
    /// [`TrackError`] naming the first offending key: no keys, a non-finite time, a time not
    /// after the previous key's, a non-finite value or tangent, a zero quaternion, T/C/B outside
    /// [-1, 1], a Hermite segment whose keys lack the tangents it needs, or a [`Spin`] that
    /// is refused ([`SpinProblem`]: on a non-rotation or the first key, out of range, ending a
    /// Hermite segment, Turns without a defined short way, Angle disagreeing with the value).
    pub fn new(raw: &RawTrack<T>) -> Result<Self, TrackError> {
        Self::with_cycles(raw, Cycles::HOLD)
    }

    /// [`Track::new`] with `cycles` before the first key and after the last.
    ///
    /// # Errors
    /// See [`Track::new`], and [`check_cycles`]: a behaviour other than [`Cycle::Hold`] needs
    /// two keys and a positive, finite period.
    pub fn with_cycles(raw: &RawTrack<T>, cycles: Cycles) -> Result<Self, TrackError> {
        let keys = &raw.keys[..];
        if keys.is_empty() {
            return Err(TrackError::Empty);
        }
        let mut times = Vec::with_capacity(keys.len());
        let mut wide = Vec::with_capacity(keys.len());
        for (index, key) in keys.iter().enumerate() {
            if !key.time.is_finite() {
                return Err(TrackError::NonFiniteTime { index });
            }
            if let Some(&previous) = times.last() {
                if key.time < previous {
                    return Err(TrackError::Unsorted { index });
                }
                if key.time == previous {
                    return Err(TrackError::DuplicateTime { index });
                }
            }
            times.push(key.time);
            wide.push(key.value.check().map_err(|problem| match problem {
                ValueProblem::NonFinite => TrackError::NonFiniteValue { index },
                ValueProblem::ZeroQuaternion => TrackError::ZeroQuaternion { index },
            })?);
            if !tcb_in_range(key.tcb) {
                return Err(TrackError::TcbOutOfRange { index });
            }
            let tangents = [key.in_tangent, key.out_tangent];
            if tangents.iter().flatten().any(|tangent| !tangent.is_finite_tangent()) {
                return Err(TrackError::NonFiniteTangent { index });
            }
            if let Some(problem) = key.spin.and_then(|spin| spin_problem(spin, index, T::ROTATION)) {
                return Err(TrackError::Spin { index, problem });
            }
        }
        for (index, pair) in keys.windows(2).enumerate() {
            if pair[0].interpolation == Interpolation::Hermite {
                if pair[0].out_tangent.is_none() {
                    return Err(TrackError::MissingTangent { index, side: TangentSide::Out });
                }
                if pair[1].in_tangent.is_none() {
                    return Err(TrackError::MissingTangent { index: index + 1, side: TangentSide::In });
                }
            }
        }
        check_cycles(&times, cycles)?;
        let shapes = T::build(&times, keys, &mut wide, cycles)?;
        let segments: Vec<Segment<T::Shape>> = shapes
            .into_iter()
            .enumerate()
            .map(|(i, shape)| Segment {
                start: times[i],
                inv_duration: 1.0 / (times[i + 1] - times[i]),
                interpolation: keys[i].interpolation,
                shape,
            })
            .collect();
        let values = wide.iter().map(|&w| T::narrow(w)).collect();
        let ends = Ends::new(&times, &wide, &segments);
        Ok(Track { times, values, wide, segments, cycles, ends })
    }

    /// What the track does before its first key and after its last.
    #[must_use]
    pub fn cycles(&self) -> Cycles {
        self.cycles
    }

    /// `(first key time, last key time)`; equal for a single key.
    #[must_use]
    pub fn domain(&self) -> (f64, f64) {
        (self.times[0], self.times[self.times.len() - 1])
    }

    #[must_use]
    pub fn key_count(&self) -> usize {
        self.times.len()
    }

    /// Key times, strictly increasing.
    #[must_use]
    pub fn key_times(&self) -> &[f64] {
        &self.times
    }

    /// Key values as the track interpolates them: as given for scalars and vectors; for
    /// rotations normalized and made sign-consistent (`q_{i+1}` negated where `q_i·q_{i+1} < 0`;
    /// for a key with a [`Spin`], negated where it disagrees in sign with `q_i·exp(L)`).
    #[must_use]
    pub fn key_values(&self) -> &[T] {
        &self.values
    }

    /// The interpolation mode of segment `i` (from key i to key i+1), `None` past the end.
    #[must_use]
    pub fn segment_interpolation(&self, i: usize) -> Option<Interpolation> {
        self.segments.get(i).map(|s| s.interpolation)
    }

    /// The value at time `t` (seconds); outside the domain as [`Track::cycles`] say (by default
    /// held at the first/last key). O(log n) binary search.
    #[must_use]
    #[inline]
    pub fn sample(&self, t: f64) -> T {
        T::narrow(self.sample_wide(t))
    }

    /// [`Track::sample`] in f64, before rounding to the value type.
    #[must_use]
    #[inline]
    pub fn sample_wide(&self, t: f64) -> T::Wide {
        match self.clamp(t) {
            Clamped::Key(i) => self.wide[i],
            Clamped::Inside => self.sample_inside(t),
            Clamped::Outside => self.sample_outside(t),
        }
    }

    /// Strictly inside the domain.
    #[inline]
    fn sample_inside(&self, t: f64) -> T::Wide {
        let i = self.times.partition_point(|&x| x <= t) - 1;
        self.eval_segment(i, t)
    }

    /// At or outside the ends of the open domain: the key whose value holds (at the end keys
    /// themselves, for NaN, and outside them when the cycle there is [`Cycle::Hold`]); inside:
    /// needs a segment; outside with another cycle: see [`Track::outside`].
    #[inline]
    fn clamp(&self, t: f64) -> Clamped {
        let last = self.times.len() - 1;
        if t.is_nan() || t <= self.times[0] {
            if t < self.times[0] && !self.cycles.before.is_hold() {
                Clamped::Outside
            } else {
                Clamped::Key(0)
            }
        } else if t >= self.times[last] {
            if t > self.times[last] && !self.cycles.after.is_hold() {
                Clamped::Outside
            } else {
                Clamped::Key(last)
            }
        } else {
            Clamped::Inside
        }
    }

    /// Segment `i` at `t` with `t_i <= t < t_{i+1}`.
    #[inline]
    fn eval_segment(&self, i: usize, t: f64) -> T::Wide {
        let segment = &self.segments[i];
        if t == segment.start {
            return self.wide[i];
        }
        let u = ((t - segment.start) * segment.inv_duration).min(1.0);
        T::eval(&segment.shape, u)
    }
}

enum Clamped {
    Key(usize),
    Inside,
    Outside,
}

fn tcb_in_range(tcb: Tcb) -> bool {
    [tcb.tension, tcb.continuity, tcb.bias].iter().all(|x| x.is_finite() && (-1.0..=1.0).contains(x))
}

// ---------------------------------------------------------------------------------------------
// Animated values.

/// The validated form of an [`Animated`] value: the static value while the track has no keys,
/// else the evaluable [`Track`].
#[derive(Clone, Debug, PartialEq)]
pub enum AnimatedTrack<T: TrackValue> {
    Constant(T),
    Keyed(Track<T>),
}

impl<T: TrackValue> AnimatedTrack<T> {
    /// Validates the static value (finite; non-zero and normalized for rotations) or the track.
    ///
    /// # Errors
    /// [`TrackError::NonFiniteStaticValue`] / [`TrackError::ZeroStaticQuaternion`] for a bad
    /// static value of an unanimated property, else the errors of [`Track::with_cycles`]
    /// (cycles on an unanimated value are ignored: it has nothing to repeat).
    pub fn new(animated: &Animated<T>) -> Result<Self, TrackError> {
        // A muted channel plays its static value.
        if animated.track.is_empty() || animated.muted {
            let wide = animated.value.check().map_err(|problem| match problem {
                ValueProblem::NonFinite => TrackError::NonFiniteStaticValue,
                ValueProblem::ZeroQuaternion => TrackError::ZeroStaticQuaternion,
            })?;
            Ok(AnimatedTrack::Constant(T::narrow(wide)))
        } else {
            Track::with_cycles(&animated.track, animated.cycles()).map(AnimatedTrack::Keyed)
        }
    }

    /// The value at `t` (seconds).
    #[must_use]
    #[inline]
    pub fn sample(&self, t: f64) -> T {
        match self {
            AnimatedTrack::Constant(value) => *value,
            AnimatedTrack::Keyed(track) => track.sample(t),
        }
    }

    /// The keyed track, if animated.
    #[must_use]
    pub fn track(&self) -> Option<&Track<T>> {
        match self {
            AnimatedTrack::Constant(_) => None,
            AnimatedTrack::Keyed(track) => Some(track),
        }
    }

    #[must_use]
    pub fn is_animated(&self) -> bool {
        matches!(self, AnimatedTrack::Keyed(_))
    }

    /// The keyed time range, `None` when constant.
    #[must_use]
    pub fn domain(&self) -> Option<(f64, f64)> {
        self.track().map(Track::domain)
    }
}
