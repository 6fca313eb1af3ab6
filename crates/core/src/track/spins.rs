//! Spin keys ([`crate::track`] module documentation, "Spin keys"; docs/design.md §3,
//! docs/interpolation.md): the rules of a [`Spin`], the unwrapped chord of a spin segment, and
//! the segment's formula.

use glam::{DQuat, DVec3};

use crate::key::{Spin, MAX_SPIN_TURNS, SPIN_ANGLE_TOLERANCE_DEG, SPIN_TURNS_MIN_CHORD_DEG};
use crate::quat;

#[cfg(doc)]
use super::TrackError;

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

/// `q(u) = q_i·exp(u·L)·exp(2u(1−u)·((1−u)·A + u·B) + u·e)`: Linear spin segments have
/// `A = B = 0`.
#[doc(hidden)]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SpinSegment {
    pub(super) start: DQuat,
    pub(super) chord: DVec3,
    pub(super) a: DVec3,
    pub(super) b: DVec3,
    pub(super) residual: DVec3,
    /// The segment's own spin (axis, degrees) when it ends at a key with a spin; `None` for a
    /// short TCB segment that only borrows the form from a spin neighbour.
    pub(super) spin: Option<(DVec3, f64)>,
}

impl SpinSegment {
    /// `exp(s·((1−u)·A + u·B) + u·e)`, the offset from the unwrapped arc.
    #[inline]
    fn offset(&self, u: f64) -> DVec3 {
        let s = 2.0 * u * (1.0 - u);
        self.a * (s * (1.0 - u)) + self.b * (s * u) + self.residual * u
    }

    #[inline]
    pub(super) fn eval(&self, u: f64) -> DQuat {
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
    pub(super) fn degrees_at(&self, u: f64) -> Option<f64> {
        let (axis, degrees) = self.spin?;
        Some(u * degrees + 2.0 * self.offset(u).dot(axis).to_degrees())
    }
}
