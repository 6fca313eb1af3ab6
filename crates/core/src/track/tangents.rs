//! Kochanek–Bartels tangents, shared by vectors (differences) and rotations (logarithms)
//! (docs/design.md §3), and the end keys' neighbours under [`Cycles`].

use std::fmt::Debug;
use std::ops::{Add, Mul, Sub};

use glam::{DVec3, DVec4};

use crate::key::{Cycle, Cycles, Tcb};

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
pub(super) fn kb_tangents<W: Vector>(
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
pub(super) struct EndChords<W> {
    before: W,
    dt_before: f64,
    after: W,
    dt_after: f64,
}

/// The end keys' neighbours under `cycles` ([`crate::track`] module documentation, "Cycles"): none (a zero
/// chord) for Hold and Linear; for Repeat and RepeatOffset the keys of the previous/next cycle
/// (`d_{−1} = d_{n−1} + g`, `d_n = d_0 + g`, with `g` = `gap()` = `P_0 − P_n` for Repeat and 0
/// for RepeatOffset); for PingPong the mirrored key (`d_{−1} = −d_0`, `d_n = −d_{n−1}`). The
/// first and last key start and end every repeated cycle, so a Repeat at either end sets both;
/// where the two ends disagree, `after` decides.
pub(super) fn end_chords<W: Vector>(
    times: &[f64],
    chords: &[W],
    cycles: Cycles,
    gap: impl Fn() -> W,
) -> EndChords<W> {
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
