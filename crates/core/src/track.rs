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

use std::fmt::Debug;
use std::ops::{Add, Mul, Sub};

use glam::{DQuat, DVec3, DVec4, Quat, Vec3};

use crate::key::{
    Animated, Cycle, Cycles, Interpolation, Key, RawTrack, Spin, Tcb, MAX_SPIN_TURNS,
    SPIN_ANGLE_TOLERANCE_DEG, SPIN_TURNS_MIN_CHORD_DEG,
};
use crate::quat::{self, Arc};

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

/// Why a key's [`Spin`] is refused ([`TrackError::Spin`]).
#[derive(Clone, Copy, Debug, PartialEq, Eq, thiserror::Error)]
pub enum SpinProblem {
    #[error("spin is only meaningful on rotation keys")]
    NotARotation,
    #[error("the first key has no previous key to be reached from, so it cannot have a spin")]
    FirstKey,
    #[error(
        "spin out of range: it must be finite, with a non-zero axis, and at most {MAX_SPIN_TURNS} turns ({} degrees)",
        360 * MAX_SPIN_TURNS
    )]
    OutOfRange,
    #[error(
        "a spin cannot end a Hermite segment (glTF's cubic rotation is component-wise and never \
         turns past half a turn); make the previous key Linear or TCB"
    )]
    AfterHermite,
    #[error(
        "Turns takes its axis and direction from the short way from the previous key, which must \
         be between {SPIN_TURNS_MIN_CHORD_DEG}° and 180° − {SPIN_TURNS_MIN_CHORD_DEG}°; give them \
         with Angle(axis: …, degrees: …)"
    )]
    AmbiguousAxis,
    #[error(
        "Angle arrives at a rotation more than {SPIN_ANGLE_TOLERANCE_DEG}° away from the key's value \
         (value must be the previous key's rotation turned by the angle about the axis)"
    )]
    Disagrees,
}

/// The unwrapped chord of a spin segment from `q_i` to `q_{i+1}`.
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpinChord {
    /// Unit axis in `q_i`'s frame (the given axis for [`Spin::Angle`], the short way's for
    /// [`Spin::Turns`]).
    pub axis: DVec3,
    /// Signed angle about `axis`, degrees.
    pub degrees: f64,
    /// `L = axis · radians(degrees) / 2`.
    pub chord: DVec3,
    /// `e`, with `q_i·exp(L)·exp(e) = ±q_{i+1}`; zero for [`Spin::Turns`].
    pub residual: DVec3,
}

/// The chord of a spin from the unit quaternion `prev` to the unit quaternion `next` (either
/// sign; the result does not depend on the signs). `None` for the short way (`Turns(0)`).
/// The one place the rules of [`Spin`] are computed: the track builder and
/// [`crate::Scene::problems`] both call it.
///
/// # Errors
/// [`SpinProblem::OutOfRange`], [`SpinProblem::AmbiguousAxis`] or [`SpinProblem::Disagrees`].
#[doc(hidden)]
pub fn spin_chord(prev: DQuat, next: DQuat, spin: Spin) -> Result<Option<SpinChord>, SpinProblem> {
    if !spin.is_in_range() {
        return Err(SpinProblem::OutOfRange);
    }
    match spin {
        Spin::Turns(0) => Ok(None),
        Spin::Turns(turns) => {
            // The short way: r = q_i⁻¹·q_{i+1} with w ≥ 0 (w is the dot product of the keys).
            let mut r = prev.conjugate() * next;
            if r.w < 0.0 {
                r = -r;
            }
            let short = quat::log(r);
            let half = short.length();
            let degrees = 2.0 * half.to_degrees();
            if !(SPIN_TURNS_MIN_CHORD_DEG..=180.0 - SPIN_TURNS_MIN_CHORD_DEG).contains(&degrees) {
                return Err(SpinProblem::AmbiguousAxis);
            }
            let axis = short / half;
            let degrees = degrees + 360.0 * f64::from(turns);
            Ok(Some(SpinChord {
                axis,
                degrees,
                chord: axis * (degrees.to_radians() / 2.0),
                residual: DVec3::ZERO,
            }))
        }
        Spin::Angle { axis, degrees } => {
            let axis = axis.as_dvec3().normalize();
            let chord = axis * (degrees.to_radians() / 2.0);
            let mut m = (prev * quat::exp(chord)).conjugate() * next;
            if m.w < 0.0 {
                m = -m;
            }
            let residual = quat::log(m);
            if 2.0 * residual.length().to_degrees() > SPIN_ANGLE_TOLERANCE_DEG {
                return Err(SpinProblem::Disagrees);
            }
            Ok(Some(SpinChord { axis, degrees, chord, residual }))
        }
    }
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

/// Precomputed for sampling outside the keys.
#[derive(Clone, Debug, PartialEq)]
struct Ends<T: TrackValue> {
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

/// Where a time outside the keys is sampled: at `local`, inside the keys, then offset by
/// `cycles` offset cycles (zero unless [`Cycle::RepeatOffset`]); or extrapolated.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Outside {
    /// Hold the key.
    Key(usize),
    /// Linear extrapolation from the first (`false`) or last (`true`) key.
    Linear { after: bool },
    /// A time inside the keys; `mirrored` when a ping-pong plays it backwards.
    Cycle { local: f64, cycles: f64, mirrored: bool },
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
        let n = times.len();
        let ends = Ends {
            period: times[n - 1] - times[0],
            inv_period: 1.0 / (times[n - 1] - times[0]),
            delta: T::cycle_delta(wide[0], wide[n - 1]),
            rate_before: segments
                .first()
                .map_or(T::zero_rate(), |s| T::end_rate(&s.shape, 0.0, s.inv_duration)),
            rate_after: segments
                .last()
                .map_or(T::zero_rate(), |s| T::end_rate(&s.shape, 1.0, s.inv_duration)),
        };
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
    fn sample_outside(&self, t: f64) -> T::Wide {
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

    /// Where `t`, outside the domain, is sampled (module documentation, "Cycles").
    #[inline]
    fn outside(&self, t: f64) -> Outside {
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

/// What is wrong with `spin` on key `index` of a track (of rotations when `rotation`), judged
/// from the key alone (the track validator and `Scene::problems` share this rule).
pub(crate) fn spin_problem(spin: crate::key::Spin, index: usize, rotation: bool) -> Option<SpinProblem> {
    if !rotation {
        Some(SpinProblem::NotARotation)
    } else if index == 0 {
        Some(SpinProblem::FirstKey)
    } else if !spin.is_in_range() {
        Some(SpinProblem::OutOfRange)
    } else {
        None
    }
}

fn tcb_in_range(tcb: Tcb) -> bool {
    [tcb.tension, tcb.continuity, tcb.bias].iter().all(|x| x.is_finite() && (-1.0..=1.0).contains(x))
}

// ---------------------------------------------------------------------------------------------
// Kochanek–Bartels tangents, shared by vectors (differences) and rotations (logarithms).

/// A value that tangents are linear combinations of.
#[doc(hidden)]
pub trait Vector:
    Copy + Debug + PartialEq + Add<Output = Self> + Sub<Output = Self> + Mul<f64, Output = Self>
{
    const ZERO: Self;

    /// Applies `f` to every component.
    #[must_use]
    fn map3(self, other_a: Self, other_b: Self, f: impl Fn(f64, f64, f64) -> f64) -> Self;
}

impl Vector for f64 {
    const ZERO: Self = 0.0;

    fn map3(self, a: Self, b: Self, f: impl Fn(f64, f64, f64) -> f64) -> Self {
        f(self, a, b)
    }
}
impl Vector for DVec3 {
    const ZERO: Self = DVec3::ZERO;

    fn map3(self, a: Self, b: Self, f: impl Fn(f64, f64, f64) -> f64) -> Self {
        DVec3::new(f(self.x, a.x, b.x), f(self.y, a.y, b.y), f(self.z, a.z, b.z))
    }
}
impl Vector for DVec4 {
    const ZERO: Self = DVec4::ZERO;

    fn map3(self, a: Self, b: Self, f: impl Fn(f64, f64, f64) -> f64) -> Self {
        DVec4::new(f(self.x, a.x, b.x), f(self.y, a.y, b.y), f(self.z, a.z, b.z), f(self.w, a.w, b.w))
    }
}

/// A clamped key's tangent component `m` (value per segment) for the chord `d` of the segment
/// it shapes, given the chords `d_prev` and `d_next` on either side of the key: flat at a peak,
/// a dip or a level neighbour (the chords do not share a strict sign), else of the chord's sign
/// and at most three times it — inside the box where a cubic Hermite segment stays monotone
/// (Fritsch & Carlson 1980), so it cannot overshoot its keys.
fn clamp_tangent(m: f64, d: f64, d_prev: f64, d_next: f64) -> f64 {
    if d_prev * d_next <= 0.0 {
        return 0.0;
    }
    if d > 0.0 {
        m.clamp(0.0, 3.0 * d)
    } else {
        m.clamp(3.0 * d, 0.0)
    }
}

/// The Kochanek–Bartels tangents of every key: `(D_i, S_i)` (incoming, outgoing), in value units
/// per segment (not per second), with the non-uniform spacing factors.
///
/// `chords[j]` is the difference from key j to key j+1 (`P_{j+1} − P_j`, or `L(q_j, q_{j+1})`).
/// docs/design.md §3:
/// `S_i = 2Δ_i/(Δ_{i−1}+Δ_i) · [(1−T)(1+B)(1+C)/2 · d_{i−1} + (1−T)(1−B)(1−C)/2 · d_i]`,
/// `D_i = 2Δ_{i−1}/(Δ_{i−1}+Δ_i) · [(1−T)(1+B)(1−C)/2 · d_{i−1} + (1−T)(1−B)(1+C)/2 · d_i]`,
/// with `d_{−1}`, `d_n`, `Δ_{−1}`, `Δ_n` at the ends from [`end_chords`] (without cycles
/// `d_{−1} = d_n = 0`, `Δ_{−1} = Δ_0`, `Δ_n = Δ_{n−1}`).
fn kb_tangents<W: Vector>(
    times: &[f64],
    tcbs: impl Iterator<Item = Tcb>,
    chords: &[W],
    ends: &EndChords<W>,
) -> Vec<(W, W)> {
    let n = times.len();
    tcbs.enumerate()
        .map(|(i, tcb)| {
            if n < 2 {
                return (W::ZERO, W::ZERO);
            }
            let d_prev = if i > 0 { chords[i - 1] } else { ends.before };
            let d_next = if i + 1 < n { chords[i] } else { ends.after };
            let dt_prev = if i > 0 { times[i] - times[i - 1] } else { ends.dt_before };
            let dt_next = if i + 1 < n { times[i + 1] - times[i] } else { ends.dt_after };
            let (t, c, b) = (f64::from(tcb.tension), f64::from(tcb.continuity), f64::from(tcb.bias));
            let out = d_prev * ((1.0 - t) * (1.0 + b) * (1.0 + c) / 2.0)
                + d_next * ((1.0 - t) * (1.0 - b) * (1.0 - c) / 2.0);
            let inc = d_prev * ((1.0 - t) * (1.0 + b) * (1.0 - c) / 2.0)
                + d_next * ((1.0 - t) * (1.0 - b) * (1.0 + c) / 2.0);
            let sum = dt_prev + dt_next;
            let (inc, out) = (inc * (2.0 * dt_prev / sum), out * (2.0 * dt_next / sum));
            if tcb.clamped {
                // The incoming tangent shapes the segment from the previous key (chord
                // d_prev), the outgoing one the segment to the next (chord d_next).
                let inc = inc.map3(d_prev, d_next, |m, a, b| clamp_tangent(m, a, a, b));
                let out = out.map3(d_prev, d_next, |m, a, b| clamp_tangent(m, b, a, b));
                return (inc, out);
            }
            (inc, out)
        })
        .collect()
}

/// The chords to the neighbours of the end keys: `d_{−1}` (from the key before the first key)
/// and `d_n` (from the last key to the key after it), with their spacings.
#[derive(Clone, Copy, Debug)]
struct EndChords<W> {
    before: W,
    dt_before: f64,
    after: W,
    dt_after: f64,
}

/// The end keys' neighbours under `cycles` (module documentation, "Cycles"): none (a zero
/// chord) for Hold and Linear; for Repeat and RepeatOffset the keys of the previous/next cycle
/// (`d_{−1} = d_{n−1} + g`, `d_n = d_0 + g`, with `g` = `gap()` = `P_0 − P_n` for Repeat and 0
/// for RepeatOffset); for PingPong the mirrored key (`d_{−1} = −d_0`, `d_n = −d_{n−1}`). The
/// first and last key start and end every repeated cycle, so a Repeat at either end sets both;
/// where the two ends disagree, `after` decides.
fn end_chords<W: Vector>(times: &[f64], chords: &[W], cycles: Cycles, gap: impl Fn() -> W) -> EndChords<W> {
    let n = times.len();
    if n < 2 {
        return EndChords { before: W::ZERO, dt_before: 0.0, after: W::ZERO, dt_after: 0.0 };
    }
    let (first, last) = (chords[0], chords[n - 2]);
    let (dt_first, dt_last) = (times[1] - times[0], times[n - 1] - times[n - 2]);
    let repeats = |c: Cycle| matches!(c, Cycle::Repeat | Cycle::RepeatOffset);
    let gap_of = |c: Cycle| if c == Cycle::Repeat { gap() } else { W::ZERO };
    let before_source = if repeats(cycles.after) {
        Some(cycles.after)
    } else {
        Some(cycles.before).filter(|c| c.is_cyclic())
    };
    let after_source = if cycles.after.is_cyclic() {
        Some(cycles.after)
    } else {
        Some(cycles.before).filter(|&c| repeats(c))
    };
    let (before, dt_before) = match before_source {
        None => (W::ZERO, dt_first),
        Some(Cycle::PingPong) => (first * -1.0, dt_first),
        Some(c) => (last + gap_of(c), dt_last),
    };
    let (after, dt_after) = match after_source {
        None => (W::ZERO, dt_last),
        Some(Cycle::PingPong) => (last * -1.0, dt_last),
        Some(c) => (first + gap_of(c), dt_first),
    };
    EndChords { before, dt_before, after, dt_after }
}

// ---------------------------------------------------------------------------------------------
// Scalars and vectors: every mode is a cubic in power form.

/// `p(u) = ((c3·u + c2)·u + c1)·u + c0` on u ∈ [0, 1].
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Cubic<W> {
    c3: W,
    c2: W,
    c1: W,
    c0: W,
}

impl<W: Vector> Cubic<W> {
    fn constant(p0: W) -> Self {
        Cubic { c3: W::ZERO, c2: W::ZERO, c1: W::ZERO, c0: p0 }
    }

    fn linear(p0: W, p1: W) -> Self {
        Cubic { c3: W::ZERO, c2: W::ZERO, c1: p1 - p0, c0: p0 }
    }

    /// Hermite segment `h00·p0 + h10·m0 + h01·p1 + h11·m1` in power form.
    fn hermite(p0: W, m0: W, p1: W, m1: W) -> Self {
        Cubic { c3: (p0 - p1) * 2.0 + m0 + m1, c2: (p1 - p0) * 3.0 - m0 * 2.0 - m1, c1: m0, c0: p0 }
    }

    #[inline]
    fn eval(&self, u: f64) -> W {
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

// ---------------------------------------------------------------------------------------------
// Rotations.

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
    /// A spin segment, or a TCB segment next to one (module documentation, "Spin keys").
    Spin(SpinSegment),
}

/// `q(u) = q_i·exp(u·L)·exp(2u(1−u)·((1−u)·A + u·B) + u·e)`: Linear spin segments have
/// `A = B = 0`.
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpinSegment {
    start: DQuat,
    chord: DVec3,
    a: DVec3,
    b: DVec3,
    residual: DVec3,
    /// The segment's own spin (axis, degrees) when it ends at a key with a spin; `None` for a
    /// short TCB segment that only borrows the form from a spin neighbour.
    spin: Option<(DVec3, f64)>,
}

impl SpinSegment {
    /// `exp(s·((1−u)·A + u·B) + u·e)`, the offset from the unwrapped arc.
    #[inline]
    fn offset(&self, u: f64) -> DVec3 {
        let s = 2.0 * u * (1.0 - u);
        self.a * (s * (1.0 - u)) + self.b * (s * u) + self.residual * u
    }

    #[inline]
    fn eval(&self, u: f64) -> DQuat {
        let arc = self.start * quat::exp_fast(self.chord * u);
        let offset = self.offset(u);
        if offset == DVec3::ZERO {
            arc
        } else {
            arc * quat::exp_fast(offset)
        }
    }

    /// Degrees turned about the spin's axis since the segment's first key: `u·θ` plus twice
    /// the offset's component along the axis (exact when every rotation shares the axis).
    fn degrees_at(&self, u: f64) -> Option<f64> {
        let (axis, degrees) = self.spin?;
        Some(u * degrees + 2.0 * self.offset(u).dot(axis).to_degrees())
    }
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
        if animated.track.is_empty() {
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
