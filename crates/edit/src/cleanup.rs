//! Curve clean-up for dense keys (docs/cleanup.md): key reduction to an error bound and
//! Butterworth low-pass smoothing.
//!
//! **Reduction** ([`reduce_keys`]) keeps a subset of a channel's keys, chosen greedily from the
//! first key on: from each kept key the next kept key is the farthest one (found by galloping,
//! then bisection) such that one cubic Hermite segment between the two, with tangents fitted by
//! least squares to the original curve, stays within the tolerance of the original at every
//! sample between them. The samples are every original key and every frame of the scene's rate
//! in the channel's key range. The out-tangent of a kept key is its in-tangent (the curve stays
//! C¹) unless no segment to the very next key fits that way. Every kept key becomes a Hermite
//! key; its value is the original key's value, so the reduced curve passes through every kept
//! key exactly. The result of each channel is then checked through keyrig's own evaluator
//! ([`Track::sample`], [`EulerOrder::to_quat`]) at every sample; a channel that does not pass is
//! left as it was and reported.
//!
//! Errors are measured per kind of channel ([`Metric`]): rotations (quaternion keys, or Euler
//! keys through the rotation their angles make) by the angle between the rotations, positions
//! by the distance, everything else (scale, colour, scalars) by the largest component
//! difference.
//!
//! **Smoothing** ([`smooth_keys`]) samples a channel at every frame of its key range, runs a
//! second-order Butterworth low-pass forwards and backwards ([`filtfilt`], as scipy's
//! `signal.filtfilt` with its default odd padding), and moves each key to the filtered curve at
//! its time. Quaternions are made hemisphere-continuous first and normalized after; Euler keys
//! are filtered as angles.

use std::fmt;

use glam::{DQuat, DVec3, Quat, Vec3};
use keyrig_core::channel_id::{
    channel, channel_mut, rotation_mode, ChannelId, ChannelKind, ChannelMut, ChannelRef,
};
use keyrig_core::{Animated, EulerOrder, Interpolation, Key, RawTrack, Scene, Track, TrackValue};

/// How far a reduced curve may be from the original at any sample.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ReduceTolerance {
    /// Rotations: largest angle (degrees) between the original and the reduced rotation.
    pub angle_deg: f64,
    /// Positions (translations, IK targets, light positions): largest distance, in scene
    /// units (metres for glTF scenes; a CMU BVH take is in its own units, docs/cleanup.md).
    pub distance: f64,
    /// Every other channel (scale, colour, scalars): largest difference of a component.
    pub value: f64,
}

impl ReduceTolerance {
    /// 0.5°, 1 mm in a scene in metres, 0.001 for other values.
    pub const DEFAULT: ReduceTolerance = ReduceTolerance { angle_deg: 0.5, distance: 0.001, value: 0.001 };

    /// Checks that every tolerance is a finite number ≥ 0.
    ///
    /// # Errors
    /// [`CleanupError::Tolerance`] naming the first one that is not.
    pub fn check(&self) -> Result<(), CleanupError> {
        for (name, value) in [("angle", self.angle_deg), ("distance", self.distance), ("value", self.value)] {
            if !(value.is_finite() && value >= 0.0) {
                return Err(CleanupError::Tolerance { name, value });
            }
        }
        Ok(())
    }
}

impl Default for ReduceTolerance {
    fn default() -> Self {
        ReduceTolerance::DEFAULT
    }
}

/// Why a clean-up cannot run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum CleanupError {
    /// A tolerance is negative, NaN or infinite.
    Tolerance { name: &'static str, value: f64 },
    /// The cutoff is not inside (0, fps/2).
    Cutoff { hz: f64, fps: f64 },
    /// The scene's frame rate is not a positive finite number.
    FrameRate(f64),
}

impl fmt::Display for CleanupError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            CleanupError::Tolerance { name, value } => {
                write!(f, "the {name} tolerance must be a finite number ≥ 0 (got {value})")
            }
            CleanupError::Cutoff { hz, fps } => write!(
                f,
                "the cutoff must be above 0 Hz and below half the frame rate ({} Hz at {fps} fps); got {hz} Hz",
                fps / 2.0
            ),
            CleanupError::FrameRate(fps) => write!(f, "the scene's frame rate {fps} is not a positive number"),
        }
    }
}

impl std::error::Error for CleanupError {}

/// How the error of a channel is measured.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Metric {
    /// Angle between quaternion keys' rotations (degrees).
    Angle,
    /// Angle between the rotations Euler keys (degrees, this order) make.
    Euler(EulerOrder),
    /// Distance between positions.
    Distance,
    /// Largest difference of one component.
    Value,
}

impl Metric {
    /// How `id`'s error is measured; `None` for channels clean-up leaves alone (switches:
    /// visibility and the deformer, whole numbers with Step keys).
    #[must_use]
    pub fn of(scene: &Scene, id: ChannelId) -> Option<Metric> {
        if id.is_switch() {
            return None;
        }
        Some(match id {
            ChannelId::ObjectEuler(_) | ChannelId::JointEuler { .. } => {
                Metric::Euler(rotation_mode(scene, id).euler().unwrap_or_default())
            }
            ChannelId::ObjectTranslation(_)
            | ChannelId::RootTranslation(_)
            | ChannelId::JointTranslation { .. }
            | ChannelId::IkTarget { .. }
            | ChannelId::CameraTranslation(_)
            | ChannelId::LightPosition(_) => Metric::Distance,
            _ if id.kind() == ChannelKind::Rotation => Metric::Angle,
            _ => Metric::Value,
        })
    }

    fn tolerance(self, tolerance: &ReduceTolerance) -> f64 {
        match self {
            Metric::Angle | Metric::Euler(_) => tolerance.angle_deg,
            Metric::Distance => tolerance.distance,
            Metric::Value => tolerance.value,
        }
    }
}

/// Why a channel was left as it was.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Skipped {
    /// Not in the scene, or a switch.
    NotCleanable,
    /// Locked by the animator.
    Locked,
    /// Its keys do not make a valid track.
    InvalidKeys,
    /// It has spin keys (turns beyond the short way), which clean-up does not rewrite.
    Spin,
    /// It cycles before or after its keys (clean-up only handles Hold ends).
    Cycles,
    /// Reduction: the reduced curve did not stay within the tolerance through the evaluator.
    OutOfTolerance,
    /// Its key range holds more frames than clean-up samples ([`max_frames`]).
    TooManyFrames,
    /// The clean-up of this channel stopped unexpectedly (a bug); it is left as it was.
    Failed,
}

/// Most frames clean-up samples a channel at: four per key plus four million (an hour at
/// 120 fps with sparse keys; a dense take has a key per frame). Beyond that (a scene at a
/// million fps, keys hours apart) the channel is left alone rather than filling memory.
#[must_use]
pub fn max_frames(keys: usize) -> usize {
    keys.saturating_mul(4).saturating_add(4_000_000)
}

/// The frames (whole frame numbers) from `first` to `last` seconds at `fps`: the first and
/// how many; `None` beyond [`max_frames`].
fn frame_span(first: f64, last: f64, fps: f64, keys: usize) -> Option<(f64, usize)> {
    let f0 = (first * fps - 1e-6).ceil();
    let f1 = (last * fps + 1e-6).floor();
    if f0.is_nan() || f1.is_nan() {
        return None;
    }
    if f1 < f0 {
        return Some((f0, 0));
    }
    let count = f1 - f0 + 1.0;
    (count.is_finite() && count <= max_frames(keys) as f64).then_some((f0, count as usize))
}

impl Skipped {
    /// Why, in words.
    #[must_use]
    pub fn reason(self) -> &'static str {
        match self {
            Skipped::NotCleanable => "not a channel clean-up changes",
            Skipped::Locked => "locked",
            Skipped::InvalidKeys => "its keys are not a valid track",
            Skipped::Spin => "it has spin keys",
            Skipped::Cycles => "it cycles before or after its keys",
            Skipped::OutOfTolerance => "no reduction stayed within the tolerance",
            Skipped::TooManyFrames => "its keys span more frames than clean-up samples",
            Skipped::Failed => "its clean-up stopped unexpectedly",
        }
    }
}

/// What a clean-up did.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct CleanupReport {
    /// Channels changed.
    pub channels: usize,
    /// Keys of the changed channels before and after.
    pub keys_before: usize,
    pub keys_after: usize,
    /// Largest error measured through the evaluator over the changed channels: angle
    /// (degrees), distance, value.
    pub max_angle_deg: f64,
    pub max_distance: f64,
    pub max_value: f64,
    /// Channels left as they were, and why (channels with fewer than three keys are passed
    /// over silently: there is nothing to reduce or smooth).
    pub skipped: Vec<(ChannelId, Skipped)>,
}

/// Every channel with keys of the scene (`objects` `None`) or of the given objects, in
/// [`ChannelId::all`] order. Rotations with Euler keys are listed as their Euler channel.
#[must_use]
pub fn keyed_channels(scene: &Scene, objects: Option<&[usize]>) -> Vec<ChannelId> {
    let ids = match objects {
        None => ChannelId::all(scene),
        Some(objects) => objects.iter().flat_map(|&o| ChannelId::of_object(scene, o)).collect(),
    };
    ids.into_iter().filter(|&id| crate::channels::key_count(scene, id) > 0).collect()
}

/// Total keys of `channels`.
#[must_use]
pub fn key_total(scene: &Scene, channels: &[ChannelId]) -> usize {
    channels.iter().map(|&id| crate::channels::key_count(scene, id)).sum()
}

/// A channel's keys, owned (the key lists are shared copy-on-write, so this is cheap).
#[derive(Clone)]
enum Owned {
    Vec3(Animated<Vec3>),
    Quat(Animated<Quat>),
    Scalar(Animated<f32>),
}

impl Owned {
    fn of(scene: &Scene, id: ChannelId) -> Option<Owned> {
        Some(match channel(scene, id)? {
            ChannelRef::Vec3(a) => Owned::Vec3(a.clone()),
            ChannelRef::Rotation(a) => Owned::Quat(a.clone()),
            ChannelRef::Scalar(a) => Owned::Scalar(a.clone()),
        })
    }

    fn key_count(&self) -> usize {
        match self {
            Owned::Vec3(a) => a.track.len(),
            Owned::Quat(a) => a.track.len(),
            Owned::Scalar(a) => a.track.len(),
        }
    }

    /// Why this channel cannot be cleaned, if it cannot.
    fn problem(&self) -> Option<Skipped> {
        fn check<T: TrackValue>(a: &Animated<T>) -> Option<Skipped> {
            if a.locked {
                Some(Skipped::Locked)
            } else if !a.cycles().is_hold() {
                Some(Skipped::Cycles)
            } else if a.track.keys.iter().any(|k| k.spin.is_some()) {
                Some(Skipped::Spin)
            } else {
                None
            }
        }
        match self {
            Owned::Vec3(a) => check(a),
            Owned::Quat(a) => check(a),
            Owned::Scalar(a) => check(a),
        }
    }

    fn write(self, scene: &mut Scene, id: ChannelId) {
        match (channel_mut(scene, id), self) {
            (Some(ChannelMut::Vec3(slot)), Owned::Vec3(a)) => slot.track = a.track,
            (Some(ChannelMut::Rotation(slot)), Owned::Quat(a)) => slot.track = a.track,
            (Some(ChannelMut::Scalar(slot)), Owned::Scalar(a)) => slot.track = a.track,
            _ => {}
        }
    }
}

/// Up to four f64 components of a value.
type V4 = [f64; 4];

fn add(a: V4, b: V4) -> V4 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2], a[3] + b[3]]
}
fn scale(a: V4, s: f64) -> V4 {
    [a[0] * s, a[1] * s, a[2] * s, a[3] * s]
}

/// Conversion of the three value types to and from [`V4`].
trait Comp: TrackValue {
    const DIM: usize;
    fn to_v4(wide: Self::Wide) -> V4;
    fn from_v4(v: V4) -> Self;
    fn from_v4_wide(v: V4) -> Self::Wide;
}

impl Comp for f32 {
    const DIM: usize = 1;
    fn to_v4(w: f64) -> V4 {
        [w, 0.0, 0.0, 0.0]
    }
    fn from_v4(v: V4) -> Self {
        v[0] as f32
    }
    fn from_v4_wide(v: V4) -> f64 {
        v[0]
    }
}

impl Comp for Vec3 {
    const DIM: usize = 3;
    fn to_v4(w: DVec3) -> V4 {
        [w.x, w.y, w.z, 0.0]
    }
    fn from_v4(v: V4) -> Self {
        Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)
    }
    fn from_v4_wide(v: V4) -> DVec3 {
        DVec3::new(v[0], v[1], v[2])
    }
}

impl Comp for Quat {
    const DIM: usize = 4;
    fn to_v4(w: DQuat) -> V4 {
        [w.x, w.y, w.z, w.w]
    }
    fn from_v4(v: V4) -> Self {
        Quat::from_xyzw(v[0] as f32, v[1] as f32, v[2] as f32, v[3] as f32)
    }
    fn from_v4_wide(v: V4) -> DQuat {
        DQuat::from_xyzw(v[0], v[1], v[2], v[3])
    }
}

/// glam's extrinsic rotation of an Euler order and the order's axes
/// ([`EulerOrder::to_quat`], in f64).
fn euler_quat(order: EulerOrder, degrees: V4) -> DQuat {
    let rot = order.glam();
    let [a, b, c] = order.axes().map(|i| degrees[i].to_radians());
    DQuat::from_euler(rot, a, b, c)
}

/// The axes that changes of the angles x, y, z (in that order) turn about, in the parent's
/// frame, at the angles `degrees`: for the order's axes `i, j, k` (`R = R_k·R_j·R_i`), `e_k`,
/// `R_k·e_j` and `R_k·R_j·e_i`.
fn euler_axes(order: EulerOrder, degrees: V4) -> [Vec3; 3] {
    let [i, j, k] = order.axes();
    let e = |axis: usize| DVec3::AXES[axis];
    let rk = DQuat::from_axis_angle(e(k), degrees[k].to_radians());
    let rj = DQuat::from_axis_angle(e(j), degrees[j].to_radians());
    let mut out = [DVec3::ZERO; 3];
    out[k] = e(k);
    out[j] = rk * e(j);
    out[i] = rk * (rj * e(i));
    // Stored in f32 (half the memory of an hour's samples): a relative error of 1e-7 is far
    // inside the margin the first-order test keeps.
    out.map(|a| a.as_vec3())
}

/// The angle (degrees) between two unit quaternions' rotations, accurate for small angles:
/// `θ = 4·atan2(|a − s·b|, |a + s·b|)` with `s` the sign of `a·b` (the quaternions are
/// `θ/2` apart on the unit sphere of ℝ⁴, and `|a − b| = 2·sin(θ/4)`, `|a + b| = 2·cos(θ/4)`).
#[must_use]
pub fn rotation_angle_deg(a: DQuat, b: DQuat) -> f64 {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    let (a, b) = (a.normalize(), b.normalize());
    4.0 * (a - b).length().atan2((a + b).length()).to_degrees()
}

/// The error of `got` against `want` under `metric` (docs/cleanup.md).
fn error(metric: Metric, want: V4, got: V4, want_quat: Option<DQuat>) -> f64 {
    match metric {
        Metric::Value => (0..4).map(|i| (want[i] - got[i]).abs()).fold(0.0, f64::max),
        Metric::Distance => DVec3::new(want[0] - got[0], want[1] - got[1], want[2] - got[2]).length(),
        Metric::Angle => rotation_angle_deg(
            DQuat::from_xyzw(want[0], want[1], want[2], want[3]),
            DQuat::from_xyzw(got[0], got[1], got[2], got[3]),
        ),
        Metric::Euler(order) => {
            let want = want_quat.unwrap_or_else(|| euler_quat(order, want));
            rotation_angle_deg(want, euler_quat(order, got))
        }
    }
}

/// The times a channel is checked at: every key and every frame (`fps`) from the first key to
/// the last, sorted; with the sample index of each key.
fn sample_times(keys: &[f64], fps: f64) -> Option<(Vec<f64>, Vec<usize>)> {
    let (first, last) = (keys[0], keys[keys.len() - 1]);
    let (f0, frames) = frame_span(first, last, fps, keys.len())?;
    let mut times = Vec::with_capacity(keys.len() + frames);
    let mut key_samples = Vec::with_capacity(keys.len());
    let mut k = 0;
    let mut f = 0;
    let near = |a: f64, b: f64| (a - b).abs() <= 1e-6 / fps.max(1.0);
    while k < keys.len() || f < frames {
        let frame_t = (f0 + f as f64) / fps;
        if k < keys.len() && (f >= frames || keys[k] <= frame_t || near(keys[k], frame_t)) {
            if f < frames && near(keys[k], frame_t) {
                f += 1;
            }
            key_samples.push(times.len());
            times.push(keys[k]);
            k += 1;
        } else {
            times.push(frame_t);
            f += 1;
        }
    }
    Some((times, key_samples))
}

/// Hermite basis at `u`: `(h00, h10, h01, h11)`.
fn basis(u: f64) -> (f64, f64, f64, f64) {
    let (u2, u3) = (u * u, u * u * u);
    (2.0 * u3 - 3.0 * u2 + 1.0, u3 - 2.0 * u2 + u, -2.0 * u3 + 3.0 * u2, u3 - u2)
}

/// The original curve of one channel at its samples, and the fitting of Hermite segments to it.
struct Fitter<'a> {
    times: &'a [f64],
    values: &'a [V4],
    /// For Euler keys, the axis (in the parent's frame) that a change of each angle (x, y, z)
    /// turns about at each sample: `ω ≈ Σ Δ_c·axis_c`.
    axes: Vec<[Vec3; 3]>,
    dim: usize,
    metric: Metric,
    /// The tolerance the fit aims at (a little under the user's, for the rounding to f32).
    tol: f64,
}

impl Fitter<'_> {
    /// The Hermite segment from sample `s0` to `s1` fitted by least squares to the samples
    /// between: `(a, b)`, the out-tangent at `s0` and the in-tangent at `s1` times the
    /// segment's duration. With `fixed`, `a` is given and only `b` is fitted.
    fn fit(&self, s0: usize, s1: usize, fixed: Option<V4>) -> (V4, V4) {
        let (t0, t1) = (self.times[s0], self.times[s1]);
        let d = t1 - t0;
        let (p0, p1) = (self.values[s0], self.values[s1]);
        let chord = [p1[0] - p0[0], p1[1] - p0[1], p1[2] - p0[2], p1[3] - p0[3]];
        if s1 <= s0 + 1 {
            return (fixed.unwrap_or(chord), chord);
        }
        let (mut s11, mut s12, mut s22) = (0.0, 0.0, 0.0);
        let (mut r1, mut r2) = ([0.0; 4], [0.0; 4]);
        for s in s0 + 1..s1 {
            let u = (self.times[s] - t0) / d;
            let (h00, h10, h01, h11) = basis(u);
            let v = self.values[s];
            s11 += h10 * h10;
            s12 += h10 * h11;
            s22 += h11 * h11;
            for c in 0..self.dim {
                let r = v[c] - h00 * p0[c] - h01 * p1[c];
                r1[c] += h10 * r;
                r2[c] += h11 * r;
            }
        }
        if let Some(a) = fixed {
            if s22 <= 0.0 {
                return (a, chord);
            }
            let mut b = [0.0; 4];
            for c in 0..self.dim {
                b[c] = (r2[c] - s12 * a[c]) / s22;
            }
            return (a, b);
        }
        let det = s11 * s22 - s12 * s12;
        if det.abs() <= 1e-12 * (s11 * s22).max(1e-300) {
            return (chord, chord);
        }
        let (mut a, mut b) = ([0.0; 4], [0.0; 4]);
        for c in 0..self.dim {
            a[c] = (s22 * r1[c] - s12 * r2[c]) / det;
            b[c] = (s11 * r2[c] - s12 * r1[c]) / det;
        }
        (a, b)
    }

    /// The segment's value at `u` (normalized for quaternions, as the evaluator does).
    fn eval(&self, s0: usize, s1: usize, a: V4, b: V4, u: f64) -> V4 {
        let (h00, h10, h01, h11) = basis(u);
        let v = add(
            add(scale(self.values[s0], h00), scale(a, h10)),
            add(scale(self.values[s1], h01), scale(b, h11)),
        );
        if self.metric == Metric::Angle {
            let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3]).sqrt();
            if n > 1e-12 {
                return scale(v, 1.0 / n);
            }
        }
        v
    }

    /// Whether the segment stays within the tolerance at every sample between `s0` and `s1`.
    fn fits(&self, s0: usize, s1: usize, a: V4, b: V4) -> bool {
        let d = self.times[s1] - self.times[s0];
        (s0 + 1..s1).all(|s| {
            let got = self.eval(s0, s1, a, b, (self.times[s] - self.times[s0]) / d);
            let want = self.values[s];
            if let Metric::Euler(_) = self.metric {
                // The rotation angle is at most the sum of the angle differences (each axis
                // rotation moves the product by its own angle): a cheap sufficient test.
                let d = [want[0] - got[0], want[1] - got[1], want[2] - got[2]];
                let bound = d[0].abs() + d[1].abs() + d[2].abs();
                if bound <= self.tol {
                    return true;
                }
                // To first order the angle is |Σ Δ_c·axis_c|; the second-order terms are below
                // (Σ|Δ|)² in radians (docs/cleanup.md): decide on it where that settles it.
                let [ax, ay, az] = self.axes[s].map(Vec3::as_dvec3);
                let linear = (ax * d[0] + ay * d[1] + az * d[2]).length();
                let margin = bound * bound * (std::f64::consts::PI / 180.0);
                if linear + margin <= self.tol {
                    return true;
                }
                if linear - margin > self.tol {
                    return false;
                }
                return error(self.metric, want, got, None) <= self.tol;
            }
            error(self.metric, want, got, None) <= self.tol
        })
    }

    /// A segment from key sample `s0` to `s1` that fits, with the out-tangent `fixed` when
    /// given; `corner` allows fitting both tangents when the fixed one does not fit.
    fn try_segment(&self, s0: usize, s1: usize, fixed: Option<V4>, corner: bool) -> Option<(V4, V4)> {
        let (a, b) = self.fit(s0, s1, fixed);
        if self.fits(s0, s1, a, b) {
            return Some((a, b));
        }
        if corner && fixed.is_some() {
            let (a, b) = self.fit(s0, s1, None);
            if self.fits(s0, s1, a, b) {
                return Some((a, b));
            }
        }
        None
    }

    /// The kept keys (indices into `keys`, sample indices of the original keys) and each kept
    /// key's (in, out) tangent per second.
    fn reduce(&self, keys: &[usize]) -> Vec<(usize, V4, V4)> {
        let n = keys.len();
        let mut kept: Vec<(usize, V4, V4)> = Vec::new();
        let mut i = 0;
        let mut in_rate: Option<V4> = None;
        let mut previous_span = 2;
        while i + 1 < n {
            let dur = |j: usize| self.times[keys[j]] - self.times[keys[i]];
            // Prefer the same tangent on both sides (C¹) unless the very next key says no.
            let mut fixed = in_rate.map(|m| scale(m, dur(i + 1)));
            let first = self.try_segment(keys[i], keys[i + 1], fixed, true);
            if first.is_none() || first.is_some_and(|(a, _)| Some(a) != fixed) {
                fixed = None;
            }
            let fixed_at = |j: usize| in_rate.filter(|_| fixed.is_some()).map(|m| scale(m, dur(j)));
            let mut best = (i + 1, first.unwrap_or_else(|| self.fit(keys[i], keys[i + 1], None)));
            // Gallop from the previous span's length (spans of one curve are alike), doubling
            // (capped at the last key) until a segment does not fit, then bisect.
            let mut step = previous_span.max(2);
            let mut bad = None;
            loop {
                let j = (i + step).min(n - 1);
                if j <= best.0 {
                    break;
                }
                match self.try_segment(keys[i], keys[j], fixed_at(j), true) {
                    Some(ab) => best = (j, ab),
                    None => {
                        bad = Some(j);
                        break;
                    }
                }
                step *= 2;
            }
            if let Some(mut hi) = bad {
                let mut lo = best.0;
                while hi - lo > 1 {
                    let mid = lo + (hi - lo) / 2;
                    match self.try_segment(keys[i], keys[mid], fixed_at(mid), true) {
                        Some(ab) => {
                            lo = mid;
                            best = (mid, ab);
                        }
                        None => hi = mid,
                    }
                }
            }
            let (j, (a, b)) = best;
            previous_span = j - i;
            let d = dur(j);
            let out_rate = scale(a, 1.0 / d);
            let arrive = scale(b, 1.0 / d);
            match kept.last_mut() {
                Some(last) if last.0 == i => last.2 = out_rate,
                _ => kept.push((i, out_rate, out_rate)),
            }
            kept.push((j, arrive, arrive));
            in_rate = Some(arrive);
            i = j;
        }
        kept
    }
}

/// The samples of a channel of scalars or vectors (not quaternions, whose keys the track
/// normalizes and makes sign-consistent) with a valid key on every frame of its range and
/// nothing else: its times, the sample index of each key, the values, the keys' values.
/// `None` when the channel is not such (then the track is built and sampled).
#[allow(clippy::type_complexity)]
fn dense_keys<T: Comp>(animated: &Animated<T>, fps: f64) -> Option<(Vec<f64>, Vec<usize>, Vec<V4>, Vec<T>)> {
    let keys = &animated.track.keys;
    if T::DIM == 4 || keys.is_empty() {
        return None;
    }
    let (first, last) = (keys[0].time, keys[keys.len() - 1].time);
    let (f0, frames) = frame_span(first, last, fps, keys.len())?;
    if frames != keys.len() {
        return None;
    }
    let mut values = Vec::with_capacity(keys.len());
    for (i, key) in keys.iter().enumerate() {
        let frame_time = (f0 + i as f64) / fps;
        let v = T::to_v4(key.value.widen());
        let on_frame = (key.time - frame_time).abs() <= 1e-6 / fps.max(1.0);
        if !on_frame || !v.iter().all(|c| c.is_finite()) || (i > 0 && key.time <= keys[i - 1].time) {
            return None;
        }
        values.push(v);
    }
    let times = keys.iter().map(|k| k.time).collect();
    Some((times, (0..keys.len()).collect(), values, keys.iter().map(|k| k.value).collect()))
}

/// Reduces one channel's keys; `None` when it is left as it was.
fn reduce_track<T: Comp>(
    animated: &Animated<T>,
    fps: f64,
    metric: Metric,
    tol: f64,
) -> Result<(RawTrack<T>, f64), Skipped> {
    let (times, key_samples, values, key_values) = match dense_keys(animated, fps) {
        // A key on every frame (motion capture): at its keys a track is its keys' values
        // (crate keyrig_core::track, "Sampling rule"), so the track need not be built.
        Some(dense) => dense,
        None => {
            let original = Track::new(&animated.track).map_err(|_| Skipped::InvalidKeys)?;
            let (times, key_samples) =
                sample_times(original.key_times(), fps).ok_or(Skipped::TooManyFrames)?;
            let values: Vec<V4> = times.iter().map(|&t| T::to_v4(original.sample_wide(t))).collect();
            (times, key_samples, values, original.key_values().to_vec())
        }
    };
    let axes = match metric {
        Metric::Euler(order) => values.iter().map(|&v| euler_axes(order, v)).collect(),
        _ => Vec::new(),
    };
    let mut fitter = Fitter { times: &times, values: &values, axes, dim: T::DIM, metric, tol };
    // The fit aims a little under the tolerance (room for rounding to f32); where the check
    // through the evaluator still finds a sample outside, it aims lower.
    for aim in [0.98, 0.9, 0.75, 0.5] {
        fitter.tol = tol * aim;
        if let Some(done) = reduced_within(animated, &key_values, &fitter, &key_samples, metric, tol) {
            return Ok(done);
        }
    }
    Err(Skipped::OutOfTolerance)
}

/// The reduced track the fitter gives, checked through [`Track::sample`] at every sample
/// against the original: `None` if a sample is outside `tol`.
fn reduced_within<T: Comp>(
    animated: &Animated<T>,
    sign_consistent: &[T],
    fitter: &Fitter<'_>,
    key_samples: &[usize],
    metric: Metric,
    tol: f64,
) -> Option<(RawTrack<T>, f64)> {
    let times = fitter.times;
    let kept = fitter.reduce(key_samples);
    let raw_keys = &animated.track.keys;
    let keys: Vec<Key<T>> = kept
        .iter()
        .map(|&(k, in_rate, out_rate)| {
            let mut key = raw_keys[k].clone();
            key.value = sign_consistent[k];
            key.interpolation = Interpolation::Hermite;
            key.in_tangent = Some(T::from_v4(in_rate));
            key.out_tangent = Some(T::from_v4(out_rate));
            key
        })
        .collect();
    let raw = RawTrack::new(keys);
    let reduced = Track::new(&raw).ok()?;
    let mut worst: f64 = 0.0;
    for (&t, &wide) in times.iter().zip(fitter.values) {
        // The original as the evaluator gives it: its f64 sample rounded to the value type.
        let want = T::to_v4(T::narrow(T::from_v4_wide(wide)).widen());
        let got = T::to_v4(reduced.sample(t).widen());
        let e = match metric {
            // As the evaluator turns Euler keys into a rotation.
            Metric::Euler(order) => {
                let q = |v: V4| order.to_quat(Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)).as_dquat();
                rotation_angle_deg(q(want), q(got))
            }
            _ => error(metric, want, got, None),
        };
        worst = worst.max(e);
        if e.is_nan() || e > tol {
            return None;
        }
    }
    Some((raw, worst))
}

/// What one channel's job gives back.
type Outcome = Result<(Owned, usize, f64), Skipped>;

fn reduce_owned(owned: &Owned, fps: f64, metric: Metric, tol: f64) -> Outcome {
    fn with<T: Comp>(
        a: &Animated<T>,
        fps: f64,
        metric: Metric,
        tol: f64,
    ) -> Result<(Animated<T>, usize, f64), Skipped> {
        let (track, worst) = reduce_track(a, fps, metric, tol)?;
        let n = track.len();
        Ok((Animated { track, ..a.clone() }, n, worst))
    }
    Ok(match owned {
        Owned::Vec3(a) => with(a, fps, metric, tol).map(|(a, n, w)| (Owned::Vec3(a), n, w))?,
        Owned::Quat(a) => with(a, fps, metric, tol).map(|(a, n, w)| (Owned::Quat(a), n, w))?,
        Owned::Scalar(a) => with(a, fps, metric, tol).map(|(a, n, w)| (Owned::Scalar(a), n, w))?,
    })
}

/// Runs `job` on every channel (in parallel, one thread per core) and writes the results back.
fn run_on_channels(
    scene: &mut Scene,
    channels: &[ChannelId],
    job: &(dyn Fn(&Owned, Metric) -> Outcome + Sync),
) -> CleanupReport {
    let mut report = CleanupReport::default();
    let mut work: Vec<(ChannelId, Owned, Metric)> = Vec::new();
    let mut seen = std::collections::BTreeSet::new();
    for &id in channels {
        if !seen.insert(id) {
            continue;
        }
        let (Some(owned), Some(metric)) = (Owned::of(scene, id), Metric::of(scene, id)) else {
            report.skipped.push((id, Skipped::NotCleanable));
            continue;
        };
        if owned.key_count() < 3 {
            continue;
        }
        if let Some(problem) = owned.problem() {
            report.skipped.push((id, problem));
            continue;
        }
        work.push((id, owned, metric));
    }
    let threads =
        std::thread::available_parallelism().map_or(1, usize::from).clamp(1, 16).min(work.len().max(1));
    // Each thread takes the next channel when it is done with one (channels differ in cost,
    // and a thread of a loaded machine may fall behind).
    let next = std::sync::atomic::AtomicUsize::new(0);
    let done: Vec<(usize, Outcome)> = std::thread::scope(|scope| {
        let (next, work) = (&next, &work);
        let handles: Vec<_> = (0..threads)
            .map(|_| {
                scope.spawn(move || {
                    let mut done = Vec::new();
                    loop {
                        let k = next.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
                        let Some((_, owned, metric)) = work.get(k) else { break };
                        done.push((k, job(owned, *metric)));
                    }
                    done
                })
            })
            .collect();
        handles.into_iter().flat_map(|h| h.join().unwrap_or_default()).collect()
    });
    let mut results: Vec<Outcome> = work.iter().map(|_| Err(Skipped::Failed)).collect();
    for (k, outcome) in done {
        results[k] = outcome;
    }
    for ((id, owned, metric), result) in work.into_iter().zip(results) {
        match result {
            Ok((new, after, worst)) => {
                report.channels += 1;
                report.keys_before += owned.key_count();
                report.keys_after += after;
                let slot = match metric {
                    Metric::Angle | Metric::Euler(_) => &mut report.max_angle_deg,
                    Metric::Distance => &mut report.max_distance,
                    Metric::Value => &mut report.max_value,
                };
                *slot = slot.max(worst);
                new.write(scene, id);
            }
            Err(why) => report.skipped.push((id, why)),
        }
    }
    report
}

/// Reduces the keys of `channels` of `scene` to as few as keep every channel within
/// `tolerance` of its original at every key and every frame (module documentation,
/// docs/cleanup.md). Channels that cannot be reduced are left as they were and listed in the
/// report; a channel named twice is reduced once.
///
/// # Errors
/// [`CleanupError`] for a tolerance that is not a finite number ≥ 0 or a frame rate that is
/// not positive; the scene is then unchanged.
pub fn reduce_keys(
    scene: &mut Scene,
    channels: &[ChannelId],
    tolerance: ReduceTolerance,
) -> Result<CleanupReport, CleanupError> {
    tolerance.check()?;
    let fps = scene.fps;
    if !(fps.is_finite() && fps > 0.0) {
        return Err(CleanupError::FrameRate(fps));
    }
    let job =
        move |owned: &Owned, metric: Metric| reduce_owned(owned, fps, metric, metric.tolerance(&tolerance));
    Ok(run_on_channels(scene, channels, &job))
}

/// A second-order section `y = (b0·x + b1·x₋₁ + b2·x₋₂ − a1·y₋₁ − a2·y₋₂)`, `a0 = 1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Biquad {
    pub b: [f64; 3],
    pub a: [f64; 3],
}

/// The second-order Butterworth low-pass with cutoff `cutoff_hz` at sample rate `sample_hz`,
/// by the bilinear transform with the cutoff pre-warped (scipy's `signal.butter(2, fc/(fs/2))`):
/// `K = tan(π·fc/fs)`, `b = (K², 2K², K²)/n`, `a = (1, 2(K²−1)/n, (1 − √2·K + K²)/n)`,
/// `n = 1 + √2·K + K²`.
///
/// # Errors
/// [`CleanupError::Cutoff`] unless `0 < cutoff_hz < sample_hz / 2`;
/// [`CleanupError::FrameRate`] unless `sample_hz` is a positive finite number.
pub fn butterworth_lowpass(cutoff_hz: f64, sample_hz: f64) -> Result<Biquad, CleanupError> {
    if !(sample_hz.is_finite() && sample_hz > 0.0) {
        return Err(CleanupError::FrameRate(sample_hz));
    }
    if !(cutoff_hz.is_finite() && cutoff_hz > 0.0 && cutoff_hz < sample_hz / 2.0) {
        return Err(CleanupError::Cutoff { hz: cutoff_hz, fps: sample_hz });
    }
    let k = (std::f64::consts::PI * cutoff_hz / sample_hz).tan();
    let k2 = k * k;
    let sqrt2 = std::f64::consts::SQRT_2;
    let n = 1.0 + sqrt2 * k + k2;
    Ok(Biquad {
        b: [k2 / n, 2.0 * k2 / n, k2 / n],
        a: [1.0, 2.0 * (k2 - 1.0) / n, (1.0 - sqrt2 * k + k2) / n],
    })
}

impl Biquad {
    /// Filters `x` from the state `zi` (transposed direct form II), as scipy's `lfilter`.
    fn run(&self, x: &mut [f64], zi: [f64; 2]) {
        let [b0, b1, b2] = self.b;
        let [_, a1, a2] = self.a;
        let (mut z1, mut z2) = (zi[0], zi[1]);
        for v in x.iter_mut() {
            let input = *v;
            let y = b0 * input + z1;
            z1 = b1 * input - a1 * y + z2;
            z2 = b2 * input - a2 * y;
            *v = y;
        }
    }

    /// The state of a step response's steady state for a unit input (scipy's `lfilter_zi`).
    fn zi(&self) -> [f64; 2] {
        let gain = self.b.iter().sum::<f64>() / self.a.iter().sum::<f64>();
        [gain - self.b[0], self.b[2] - self.a[2] * gain]
    }
}

/// `x` filtered forwards and backwards (zero phase; the magnitude response squared), as
/// scipy's `signal.filtfilt(b, a, x)` with its defaults: the ends padded by odd reflection of
/// `min(9, len − 1)` samples, each pass started from the steady state of its first sample.
#[must_use]
pub fn filtfilt(filter: &Biquad, x: &[f64]) -> Vec<f64> {
    let n = x.len();
    if n < 2 {
        return x.to_vec();
    }
    let pad = 9.min(n - 1);
    let mut ext = Vec::with_capacity(n + 2 * pad);
    ext.extend((1..=pad).rev().map(|i| 2.0 * x[0] - x[i]));
    ext.extend_from_slice(x);
    ext.extend((n - 1 - pad..n - 1).rev().map(|i| 2.0 * x[n - 1] - x[i]));
    let zi = filter.zi();
    let start = ext[0];
    filter.run(&mut ext, [zi[0] * start, zi[1] * start]);
    ext.reverse();
    let start = ext[0];
    filter.run(&mut ext, [zi[0] * start, zi[1] * start]);
    ext.reverse();
    ext[pad..pad + n].to_vec()
}

/// Smooths one channel: the curve at every frame of its key range, filtered; each key moved
/// to the filtered curve at its time (linear between the frames around it).
fn smooth_track<T: Comp>(
    animated: &Animated<T>,
    fps: f64,
    filter: &Biquad,
    metric: Metric,
) -> Result<RawTrack<T>, Skipped> {
    let track = Track::new(&animated.track).map_err(|_| Skipped::InvalidKeys)?;
    let (first, last) = track.domain();
    let (f0, frames) = frame_span(first, last, fps, track.key_count()).ok_or(Skipped::TooManyFrames)?;
    if frames < 2 {
        return Ok(animated.track.clone());
    }
    let mut samples: Vec<V4> =
        (0..frames).map(|f| T::to_v4(track.sample_wide((f0 + f as f64) / fps))).collect();
    if metric == Metric::Angle {
        for f in 1..frames {
            let (p, q) = (samples[f - 1], samples[f]);
            if p[0] * q[0] + p[1] * q[1] + p[2] * q[2] + p[3] * q[3] < 0.0 {
                samples[f] = scale(q, -1.0);
            }
        }
    }
    for c in 0..T::DIM {
        let column: Vec<f64> = samples.iter().map(|v| v[c]).collect();
        for (v, y) in samples.iter_mut().zip(filtfilt(filter, &column)) {
            v[c] = y;
        }
    }
    let mut keys = animated.track.keys.to_vec();
    for key in &mut keys {
        let at = (key.time * fps - f0).clamp(0.0, (frames - 1) as f64);
        let i = (at.floor() as usize).min(frames - 1);
        let j = (i + 1).min(frames - 1);
        let u = at - i as f64;
        let mut v = add(scale(samples[i], 1.0 - u), scale(samples[j], u));
        if metric == Metric::Angle {
            let n = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2] + v[3] * v[3]).sqrt();
            if n > 1e-9 {
                v = scale(v, 1.0 / n);
            } else {
                continue;
            }
        }
        key.value = T::from_v4(v);
    }
    let raw = RawTrack::new(keys);
    Track::new(&raw).map_err(|_| Skipped::InvalidKeys)?;
    Ok(raw)
}

fn smooth_owned(owned: &Owned, fps: f64, filter: &Biquad, metric: Metric) -> Outcome {
    let n = owned.key_count();
    Ok(match owned {
        Owned::Vec3(a) => {
            (Owned::Vec3(Animated { track: smooth_track(a, fps, filter, metric)?, ..a.clone() }), n, 0.0)
        }
        Owned::Quat(a) => {
            (Owned::Quat(Animated { track: smooth_track(a, fps, filter, metric)?, ..a.clone() }), n, 0.0)
        }
        Owned::Scalar(a) => {
            (Owned::Scalar(Animated { track: smooth_track(a, fps, filter, metric)?, ..a.clone() }), n, 0.0)
        }
    })
}

/// Smooths `channels` of `scene` with a second-order Butterworth low-pass at `cutoff_hz`, run
/// forwards and backwards (module documentation, docs/cleanup.md). Keys keep their times and
/// interpolation; their values move.
///
/// # Errors
/// [`CleanupError`] unless `0 < cutoff_hz < fps/2` and the frame rate is positive; the scene is
/// then unchanged.
pub fn smooth_keys(
    scene: &mut Scene,
    channels: &[ChannelId],
    cutoff_hz: f64,
) -> Result<CleanupReport, CleanupError> {
    let fps = scene.fps;
    let filter = butterworth_lowpass(cutoff_hz, fps)?;
    let job = move |owned: &Owned, metric: Metric| smooth_owned(owned, fps, &filter, metric);
    Ok(run_on_channels(scene, channels, &job))
}
