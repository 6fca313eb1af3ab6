//! How a rotation channel reads to an animator: as a quaternion, or as Euler angles in one of
//! the six orders. The mode changes what the inspector and the curve editor show and type; the
//! stored keys stay quaternions, interpolated by Squad as before.
//!
//! Orders are named as Blender and Maya name them: **XYZ** turns about X first, then Y, then Z,
//! all about the parent's fixed axes (extrinsic), so the rotation is `R = Rz(z)·Ry(y)·Rx(x)`
//! (glam's `EulerRot::XYZEx`, scipy's `Rotation.from_euler("xyz", …)`). The angles are kept per
//! axis, `(x, y, z)` in degrees, whatever the order.
//!
//! Euler angles of a rotation are not unique: `(a, b, c)` and `(a + 180°, 180° − b, c + 180°)`
//! (first, middle and last axis of the order) are the same rotation, and each angle can gain
//! whole turns. [`EulerOrder::angles_near`] picks the triple nearest a previous one, so that a
//! plain spin about Y reads Y 0 → 360 with X and Z at 0 instead of flipping X and Z to 180° when
//! Y passes 90°; at the gimbal lock (middle angle ±90°), where only the sum or difference of the
//! other two is fixed, it keeps the first angle and solves the last.

use glam::{DVec3, EulerRot, Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::key::{Animated, Interpolation, Key, RawTrack, Spin};
use crate::track::{Track, TrackError};

/// One of the six orders of Euler angles (module documentation).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum EulerOrder {
    #[default]
    XYZ,
    XZY,
    YXZ,
    YZX,
    ZXY,
    ZYX,
}

impl EulerOrder {
    pub const ALL: [EulerOrder; 6] = [
        EulerOrder::XYZ,
        EulerOrder::XZY,
        EulerOrder::YXZ,
        EulerOrder::YZX,
        EulerOrder::ZXY,
        EulerOrder::ZYX,
    ];

    /// The axes (0 = X, 1 = Y, 2 = Z) in the order they turn.
    #[must_use]
    pub fn axes(self) -> [usize; 3] {
        match self {
            EulerOrder::XYZ => [0, 1, 2],
            EulerOrder::XZY => [0, 2, 1],
            EulerOrder::YXZ => [1, 0, 2],
            EulerOrder::YZX => [1, 2, 0],
            EulerOrder::ZXY => [2, 0, 1],
            EulerOrder::ZYX => [2, 1, 0],
        }
    }

    /// "XYZ", ….
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            EulerOrder::XYZ => "XYZ",
            EulerOrder::XZY => "XZY",
            EulerOrder::YXZ => "YXZ",
            EulerOrder::YZX => "YZX",
            EulerOrder::ZXY => "ZXY",
            EulerOrder::ZYX => "ZYX",
        }
    }

    /// The formula, for tooltips: "R = Rz·Ry·Rx (X turns first)".
    #[must_use]
    pub fn formula(self) -> String {
        let [a, b, c] = self.axes().map(|i| ["x", "y", "z"][i]);
        format!(
            "R = R{c}·R{b}·R{a}: about {} first, then {}, then {}, about the parent's axes (Blender's and Maya's {} order)",
            a.to_uppercase(),
            b.to_uppercase(),
            c.to_uppercase(),
            self.name()
        )
    }

    /// glam's extrinsic rotation of the same order.
    #[must_use]
    pub fn glam(self) -> EulerRot {
        match self {
            EulerOrder::XYZ => EulerRot::XYZEx,
            EulerOrder::XZY => EulerRot::XZYEx,
            EulerOrder::YXZ => EulerRot::YXZEx,
            EulerOrder::YZX => EulerRot::YZXEx,
            EulerOrder::ZXY => EulerRot::ZXYEx,
            EulerOrder::ZYX => EulerRot::ZYXEx,
        }
    }

    /// The rotation of angles `degrees` (x, y, z about their axes).
    #[must_use]
    pub fn to_quat(self, degrees: Vec3) -> Quat {
        let [a, b, c] = self.axes().map(|i| degrees[i].to_radians());
        Quat::from_euler(self.glam(), a, b, c).normalize()
    }

    /// Angles (x, y, z, degrees) of `q`, each in (−180, 180], the middle one in [−90, 90].
    #[must_use]
    pub fn angles(self, q: Quat) -> Vec3 {
        // In f64: the conversion loses precision near the gimbal lock.
        let (a, b, c) = q.as_dquat().to_euler(self.glam());
        let half_turn = |d: f64| if d <= -179.9995 { d + 360.0 } else { d };
        let mut out = Vec3::ZERO;
        for (i, v) in self.axes().into_iter().zip([a, b, c]) {
            out[i] = half_turn(v.to_degrees()) as f32;
        }
        out
    }

    /// Angles (x, y, z, degrees) of `q` nearest `near` (module documentation): of the two
    /// triples of `q`, with whole turns added to each angle, the one whose angles differ least
    /// from `near`'s.
    #[must_use]
    pub fn angles_near(self, q: Quat, near: Vec3) -> Vec3 {
        let [i, j, k] = self.axes();
        let principal = self.angles(q);
        let unwrap = |v: f32, to: f32| v + 360.0 * ((to - v) / 360.0).round();
        let fit = |mut e: Vec3| {
            for axis in 0..3 {
                e[axis] = unwrap(e[axis], near[axis]);
            }
            e
        };
        let cost = |e: Vec3| (e - near).abs().element_sum();
        // Gimbal lock: the middle angle at ±90° fixes only a sum or difference of the others.
        if (90.0 - principal[j].abs()).abs() < 0.05 {
            let mut e = principal;
            e[i] = near[i];
            e[j] = unwrap(principal[j], near[j]);
            // R = R_k(c)·R_j(b)·R_i(a): the last turn is q·R_i(a)⁻¹·R_j(b)⁻¹.
            let axis = |n: usize| Vec3::from_array(std::array::from_fn(|m| if m == n { 1.0 } else { 0.0 }));
            let first = Quat::from_axis_angle(axis(i), e[i].to_radians());
            let middle = Quat::from_axis_angle(axis(j), e[j].to_radians());
            let rest = q * first.inverse() * middle.inverse();
            let c = 2.0 * rest.to_array()[k].atan2(rest.w);
            e[k] = unwrap(c.to_degrees(), near[k]);
            return e;
        }
        let mut other = principal;
        other[i] += 180.0;
        other[j] = 180.0 - other[j];
        other[k] += 180.0;
        let (a, b) = (fit(principal), fit(other));
        if cost(b) < cost(a) {
            b
        } else {
            a
        }
    }
}

/// How a rotation channel reads and is typed.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum RotationMode {
    /// The unit quaternion (w, x, y, z).
    Quaternion,
    /// Euler angles in degrees in this order.
    Euler(EulerOrder),
}

impl Default for RotationMode {
    /// XYZ Euler angles, as Blender's and Maya's default.
    fn default() -> Self {
        RotationMode::Euler(EulerOrder::XYZ)
    }
}

impl RotationMode {
    /// Every mode an animator can choose, the default's order first.
    pub const ALL: [RotationMode; 7] = [
        RotationMode::Euler(EulerOrder::XYZ),
        RotationMode::Euler(EulerOrder::XZY),
        RotationMode::Euler(EulerOrder::YXZ),
        RotationMode::Euler(EulerOrder::YZX),
        RotationMode::Euler(EulerOrder::ZXY),
        RotationMode::Euler(EulerOrder::ZYX),
        RotationMode::Quaternion,
    ];

    /// The Euler order, `None` for quaternions.
    #[must_use]
    pub fn euler(self) -> Option<EulerOrder> {
        match self {
            RotationMode::Quaternion => None,
            RotationMode::Euler(order) => Some(order),
        }
    }

    /// Whether the mode is the default one (left out of scene files).
    #[must_use]
    pub fn is_default(&self) -> bool {
        *self == RotationMode::default()
    }

    /// "XYZ Euler", "Quaternion".
    #[must_use]
    pub fn label(self) -> String {
        match self.euler() {
            Some(order) => format!("{} Euler", order.name()),
            None => "Quaternion (WXYZ)".to_owned(),
        }
    }
}

/// Substeps per key segment when a rotation curve is followed to convert its keys: small
/// enough that consecutive readings of [`EulerOrder::angles_near`] stay on one branch, plus
/// one per 5° of a spin's extra turns.
const FOLLOW_STEPS: usize = 64;

/// How far a segment of `keys` spins beyond the short way, degrees (0 without a spin).
fn spin_extra_degrees(key: &Key<Quat>) -> f64 {
    match key.spin {
        Some(Spin::Turns(n)) => 360.0 * f64::from(n.unsigned_abs()),
        Some(Spin::Angle { degrees, .. }) => degrees.abs(),
        None => 0.0,
    }
}

/// Euler keys (docs/channels.md, "Euler keys") in `order` at the times of `times`' keys, read
/// from the rotation curve `curve`: each key's angles are the ones nearest the previous key's
/// after following the curve through the segment between them ([`EulerOrder::angles_near`]
/// at every substep), so a spin of two turns reads 0 → 720 and no angle flips by 180°. Each
/// key keeps its time, interpolation, TCB and key type; a Hermite key becomes a TCB key (its
/// tangents are quaternions or the other order's angles, not these angles' slopes).
fn euler_keys_along<T>(
    times: &[Key<T>],
    extra_degrees: impl Fn(usize) -> f64,
    curve: impl Fn(f64) -> Quat,
    order: EulerOrder,
    first: Vec3,
) -> Vec<Key<Vec3>> {
    let mut out: Vec<Key<Vec3>> = Vec::with_capacity(times.len());
    let mut e = first;
    for (i, key) in times.iter().enumerate() {
        if i > 0 {
            let t0 = times[i - 1].time;
            let steps = FOLLOW_STEPS + (extra_degrees(i) / 5.0).min(1.0e5) as usize;
            for s in 1..steps {
                let t = t0 + (key.time - t0) * s as f64 / steps as f64;
                e = order.angles_near(curve(t), e);
            }
        }
        e = order.angles_near(curve(key.time), e);
        let interpolation = match key.interpolation {
            Interpolation::Hermite => Interpolation::Tcb,
            other => other,
        };
        out.push(Key {
            time: key.time,
            value: e,
            interpolation,
            tcb: key.tcb,
            in_tangent: None,
            out_tangent: None,
            spin: None,
            key_type: key.key_type,
        });
    }
    out
}

/// Euler keys in `order` of the quaternion keys `rotation` (switching a channel to Euler keys):
/// a key at each of its key times, the angles continuous through spins (module docs of
/// [`euler_keys_along`]). The curve between keys is the angles' own interpolation from then on,
/// not Squad's, so in-between values can differ; the keys themselves are the same rotations.
/// Cycles, mute and lock carry over.
///
/// # Errors
/// The [`TrackError`] of `rotation`'s keys when they are invalid (nothing to follow).
pub fn euler_keys_from_quaternions(
    rotation: &Animated<Quat>,
    order: EulerOrder,
) -> Result<Animated<Vec3>, TrackError> {
    let keys = &rotation.track.keys;
    let value = order.angles(rotation.value.normalize());
    let euler = if keys.is_empty() {
        Vec::new()
    } else {
        let track = Track::new(&rotation.track)?;
        let first = order.angles(keys[0].value.normalize());
        euler_keys_along(keys, |i| spin_extra_degrees(&keys[i]), |t| track.sample(t), order, first)
    };
    Ok(with_flags(value, euler, rotation))
}

/// The same Euler keys read in another order (changing the order of a channel with Euler
/// keys): the rotation at each key is kept, the angles follow the old curve so they stay
/// continuous.
///
/// # Errors
/// The [`TrackError`] of `euler`'s keys when they are invalid.
pub fn reorder_euler_keys(
    euler: &Animated<Vec3>,
    from: EulerOrder,
    to: EulerOrder,
) -> Result<Animated<Vec3>, TrackError> {
    let keys = &euler.track.keys;
    let value = to.angles_near(from.to_quat(euler.value), euler.value);
    let out = if keys.is_empty() {
        Vec::new()
    } else {
        let track = Track::new(&euler.track)?;
        let first = to.angles_near(from.to_quat(keys[0].value), keys[0].value);
        euler_keys_along(
            keys,
            |i| f64::from((keys[i].value - keys[i - 1].value).abs().max_element()),
            |t| from.to_quat(track.sample(t)),
            to,
            first,
        )
    };
    Ok(with_flags(value, out, euler))
}

/// Quaternion keys of Euler keys (switching a channel back): a key at each key time with the
/// same rotation, interpolation, TCB and key type, and, where the angles turn more than half
/// a turn between two keys, the [`Spin::Angle`] that turns as far (about the axis the angles'
/// path turns about, in the previous key's frame), so a Y spin 0 → 720 stays two turns.
///
/// # Errors
/// The [`TrackError`] of `euler`'s keys when they are invalid.
pub fn quaternion_keys_from_euler(
    euler: &Animated<Vec3>,
    order: EulerOrder,
) -> Result<Animated<Quat>, TrackError> {
    let keys = &euler.track.keys;
    if !keys.is_empty() {
        Track::new(&euler.track)?;
    }
    let mut out: Vec<Key<Quat>> = Vec::with_capacity(keys.len());
    for (i, key) in keys.iter().enumerate() {
        let q = order.to_quat(key.value);
        let spin = if i == 0 { None } else { path_spin(keys[i - 1].value, key.value, order) };
        let interpolation = match key.interpolation {
            Interpolation::Hermite => Interpolation::Tcb,
            other => other,
        };
        out.push(Key {
            time: key.time,
            value: q,
            interpolation,
            tcb: key.tcb,
            in_tangent: None,
            out_tangent: None,
            spin,
            key_type: key.key_type,
        });
    }
    Ok(with_flags(order.to_quat(euler.value), out, euler))
}

/// The spin from angles `a` to `b` when the straight path between them turns more than half
/// a turn (else `None`, the short way): [`Spin::Angle`] about the short way's axis (or the
/// path's, when the keys are the same rotation) by the short angle plus the whole turns
/// nearest the path's.
fn path_spin(a: Vec3, b: Vec3, order: EulerOrder) -> Option<Spin> {
    let q0 = order.to_quat(a).as_dquat();
    let steps = 256;
    // The path's turn in q0's frame: the sum of each small step's rotation vector.
    let mut total = DVec3::ZERO;
    let mut prev = glam::DQuat::IDENTITY;
    for s in 1..=steps {
        let e = a.lerp(b, s as f32 / steps as f32);
        let r = q0.inverse() * order.to_quat(e).as_dquat();
        // `to_quat` is continuous in the angles, so consecutive steps stay near the identity
        // (w > 0) and each is the small turn it looks.
        total += (r * prev.inverse()).to_scaled_axis();
        prev = r;
    }
    if total.length().to_degrees() < 180.0 {
        return None;
    }
    let r = (q0.inverse() * order.to_quat(b).as_dquat()).normalize();
    let r = if r.w < 0.0 { -r } else { r };
    let (short_axis, short) = r.to_axis_angle();
    // The short way's axis, unless the keys are the same rotation (glam gives no axis below
    // about 1e-6°): then the path's.
    let (mut axis, mut short) =
        if short > 0.0 { (short_axis, short.to_degrees()) } else { (total.normalize(), 0.0) };
    if axis.dot(total) < 0.0 {
        axis = -axis;
        short = -short;
    }
    let along = axis.dot(total).to_degrees();
    let degrees = short + 360.0 * ((along - short) / 360.0).round();
    Some(Spin::Angle { axis: axis.as_vec3(), degrees })
}

/// Quaternion keys that follow Euler keys within `tolerance_deg` over `range` (seconds) and
/// their own keys, for formats that have no Euler keys (glTF, VRML, X3D): LINEAR keys (slerp)
/// at every Euler key time, with segments halved until the slerp between two keys is within
/// the tolerance of the Euler curve at a quarter, half and three quarters of the way and turns
/// less than 90°; STEP keys where the Euler keys step. Cycles are played out over `range` (the
/// result holds outside it); a muted channel gives its static value.
///
/// # Errors
/// The [`TrackError`] of `euler`'s keys when they are invalid.
pub fn quaternion_keys_following(
    euler: &Animated<Vec3>,
    order: EulerOrder,
    range: (f64, f64),
    tolerance_deg: f64,
) -> Result<Animated<Quat>, TrackError> {
    let static_value = order.to_quat(euler.value);
    if euler.track.is_empty() || euler.muted {
        return Ok(Animated::constant(static_value));
    }
    let track = crate::track::AnimatedTrack::new(euler)?;
    let keys = &euler.track.keys;
    let (first, last) = (keys[0].time, keys[keys.len() - 1].time);
    let cycles = euler.before != crate::key::Cycle::Hold || euler.after != crate::key::Cycle::Hold;
    let (from, to) = if cycles { (first.min(range.0), last.max(range.1)) } else { (first, last) };
    // Breakpoints: the key times inside [from, to], and where cycles play the keys again their
    // times in each cycle (mirrored in a ping-pong's backward cycles, whose steps are left to the
    // halving below: a backward Step holds the value before the key, not after it).
    // The range's ends first: a key at the same time, pushed later, gives the step.
    let mut times: Vec<(f64, bool)> = vec![(from, false), (to, false)];
    let period = last - first;
    let mut push = |t: f64, step: bool| {
        if t >= from - 1e-9 && t <= to + 1e-9 {
            times.push((t, step));
        }
    };
    let (before, after) = if period > 0.0 {
        (((first - from) / period).ceil() as i64, ((to - last) / period).ceil() as i64)
    } else {
        (0, 0)
    };
    for n in -before.min(100_000)..=after.min(100_000) {
        let cycle = if n < 0 { euler.before } else { euler.after };
        if n != 0 && !cycle.is_cyclic() {
            continue;
        }
        let start = first + n as f64 * period;
        for k in keys.iter() {
            if cycle == crate::key::Cycle::PingPong && n % 2 != 0 {
                push(start + (last - k.time), false);
            } else {
                push(start + (k.time - first), k.interpolation == Interpolation::Step);
            }
        }
    }
    // Of equal times the last pushed says whether a step starts there: a cycle's first key
    // (the segment after a cycle's end is the next cycle's first).
    times.sort_by(|a, b| a.0.total_cmp(&b.0));
    times.dedup_by(|b, a| {
        let same = (a.0 - b.0).abs() < 1e-9;
        if same {
            a.1 = b.1;
        }
        same
    });
    let q = |t: f64| order.to_quat(track.sample(t)).as_dquat();
    let tolerance = tolerance_deg.to_radians();
    let mut out: Vec<Key<Quat>> = Vec::new();
    // Rotation keys interpolate the short way whatever their signs.
    let push = |out: &mut Vec<Key<Quat>>, t: f64, value: glam::DQuat, step: bool| {
        let value = value.normalize();
        let interpolation = if step { Interpolation::Step } else { Interpolation::Linear };
        out.push(Key::new(t, value.as_quat()).with_interpolation(interpolation));
    };
    for w in times.windows(2) {
        let ((a, step), (b, _)) = (w[0], w[1]);
        match out.last_mut() {
            // The previous piece ended here: this key starts the next segment.
            Some(k) if (k.time - a).abs() <= 1e-12 => {
                if step {
                    k.interpolation = Interpolation::Step;
                }
            }
            _ => push(&mut out, a, q(a), step),
        }
        if step {
            continue;
        }
        // Halve [a, b] until each piece's slerp follows the curve.
        let mut stack = vec![(a, b, 0u32)];
        let mut pieces: Vec<f64> = Vec::new();
        while let Some((lo, hi, depth)) = stack.pop() {
            // `angle` and glam's slerp take the short way whatever the signs.
            let (qa, qb) = (q(lo), q(hi));
            let fits = angle(qa, qb) < std::f64::consts::FRAC_PI_2
                && [0.25, 0.5, 0.75]
                    .iter()
                    .all(|&u| angle(qa.slerp(qb, u), q(lo + (hi - lo) * u)) <= tolerance);
            if fits || depth >= 20 {
                pieces.push(hi);
            } else {
                let mid = 0.5 * (lo + hi);
                // Right half first on the stack so the left half is handled first.
                stack.push((mid, hi, depth + 1));
                stack.push((lo, mid, depth + 1));
            }
        }
        for t in pieces {
            push(&mut out, t, q(t), false);
        }
    }
    // A Step segment pushes nothing for its end: the last breakpoint needs its key then.
    if let Some(&(end, _)) = times.last() {
        if out.last().is_none_or(|k| (k.time - end).abs() > 1e-12) {
            push(&mut out, end, q(end), false);
        }
    }
    let mut animated = Animated::new(static_value, RawTrack::new(out));
    animated.locked = euler.locked;
    Ok(animated)
}

/// The angle between two rotations (radians): twice the 4-D angle of `a` and `±b` on one
/// hemisphere ([`crate::quat::angle_between`], accurate for tiny angles, unlike glam's
/// `angle_between`, an approximate `acos` of the dot product good to about 0.02°).
fn angle(a: glam::DQuat, b: glam::DQuat) -> f64 {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    2.0 * crate::quat::angle_between(a, b)
}

/// `value` and `keys` with `from`'s cycles, mute and lock.
fn with_flags<T, U>(value: U, keys: Vec<Key<U>>, from: &Animated<T>) -> Animated<U> {
    Animated {
        value,
        track: RawTrack::new(keys),
        before: from.before,
        after: from.after,
        muted: from.muted,
        locked: from.locked,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Mat3;

    /// Quaternions and their Euler angles from scipy 1.17 (`Rotation.from_quat(q)
    /// .as_euler(order, degrees=True)` with lower-case, extrinsic orders), per axis.
    #[allow(clippy::type_complexity)]
    fn scipy_reference() -> Vec<(Quat, [(EulerOrder, Vec3); 6])> {
        vec![
            (
                glam::DQuat::from_xyzw(0.102597835, 0.718184846, -0.307793506, 0.615587011).as_quat(),
                [
                    (EulerOrder::XYZ, Vec3::new(-99.46232, 71.32828, -133.66778)),
                    (EulerOrder::XZY, Vec3::new(35.75389, 103.13402, -13.39005)),
                    (EulerOrder::YXZ, Vec3::new(-18.40848, 93.17983, -33.69007)),
                    (EulerOrder::YZX, Vec3::new(-21.80141, 105.06849, -31.75686)),
                    (EulerOrder::ZXY, Vec3::new(34.64019, 93.66779, -16.34817)),
                    (EulerOrder::ZYX, Vec3::new(95.29008, 55.19031, -112.78241)),
                ],
            ),
            (
                glam::DQuat::from_xyzw(0.515710623, -0.206284249, 0.412568499, 0.721994872).as_quat(),
                [
                    (EulerOrder::XYZ, Vec3::new(56.30993, -46.33626, 33.69007)),
                    (EulerOrder::XZY, Vec3::new(82.05653, -51.54629, 22.51831)),
                    (EulerOrder::YXZ, Vec3::new(35.06239, -62.10273, 81.02737)),
                    (EulerOrder::YZX, Vec3::new(77.47119, 12.52881, 53.95067)),
                    (EulerOrder::ZXY, Vec3::new(66.19062, 18.43495, 71.56505)),
                    (EulerOrder::ZYX, Vec3::new(67.28559, 7.33437, 54.6052)),
                ],
            ),
            (
                glam::DQuat::from_xyzw(-0.307793506, 0.102597835, 0.923380517, 0.205195670).as_quat(),
                [
                    (EulerOrder::XYZ, Vec3::new(4.57392, 37.62757, 156.50143)),
                    (EulerOrder::XZY, Vec3::new(-160.55997, 139.95027, 18.40848)),
                    (EulerOrder::YXZ, Vec3::new(3.62109, 37.71598, 153.70521)),
                    (EulerOrder::YZX, Vec3::new(175.9623, -144.0715, 26.23828)),
                    (EulerOrder::ZXY, Vec3::new(-18.40848, -33.69007, 160.55997)),
                    (EulerOrder::ZYX, Vec3::new(-21.80141, -31.75686, 148.67131)),
                ],
            ),
        ]
    }

    fn same_rotation(a: Quat, b: Quat) -> bool {
        a.dot(b).abs() > 1.0 - 1e-6
    }

    #[test]
    fn angles_match_scipy_in_every_order() {
        for (q, rows) in scipy_reference() {
            for (order, expected) in rows {
                let got = order.angles(q);
                assert!(
                    (got - expected).abs().max_element() < 2e-3,
                    "{order:?} of {q}: {got} vs scipy {expected}"
                );
                assert!(same_rotation(order.to_quat(expected), q), "{order:?}: scipy's angles give back q");
            }
        }
    }

    /// Rx, Ry, Rz written out by hand (right-handed, column vectors).
    fn hand_matrix(axis: usize, degrees: f32) -> Mat3 {
        let (s, c) = degrees.to_radians().sin_cos();
        match axis {
            0 => Mat3::from_cols(Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.0, c, s), Vec3::new(0.0, -s, c)),
            1 => Mat3::from_cols(Vec3::new(c, 0.0, -s), Vec3::new(0.0, 1.0, 0.0), Vec3::new(s, 0.0, c)),
            _ => Mat3::from_cols(Vec3::new(c, s, 0.0), Vec3::new(-s, c, 0.0), Vec3::new(0.0, 0.0, 1.0)),
        }
    }

    #[test]
    fn to_quat_is_the_product_of_hand_written_matrices_first_axis_on_the_right() {
        let angles = Vec3::new(23.0, -61.0, 142.0);
        for order in EulerOrder::ALL {
            let [i, j, k] = order.axes();
            let expected = hand_matrix(k, angles[k]) * hand_matrix(j, angles[j]) * hand_matrix(i, angles[i]);
            let got = Mat3::from_quat(order.to_quat(angles));
            let diff = (expected - got).to_cols_array().iter().fold(0.0f32, |m, d| m.max(d.abs()));
            assert!(diff < 1e-5, "{order:?}: {expected:?} vs {got:?}");
            let back = order.angles(order.to_quat(angles));
            assert!(same_rotation(order.to_quat(back), order.to_quat(angles)), "{order:?} round trip");
        }
    }

    #[test]
    fn a_plain_spin_reads_as_one_angle_climbing_in_every_order() {
        for order in EulerOrder::ALL {
            for axis in 0..3 {
                let unit = Vec3::from_array(std::array::from_fn(|m| if m == axis { 1.0 } else { 0.0 }));
                let mut e = Vec3::ZERO;
                for step in 0..=720 {
                    let degrees = step as f32 * 0.5;
                    let q = Quat::from_axis_angle(unit, degrees.to_radians());
                    e = order.angles_near(q, e);
                    let mut expected = Vec3::ZERO;
                    expected[axis] = degrees;
                    assert!(
                        (e - expected).abs().max_element() < 0.02,
                        "{order:?}, spin about axis {axis} at {degrees}°: read {e}"
                    );
                }
            }
        }
    }

    #[test]
    fn nearest_angles_are_the_same_rotation_and_continuous_on_a_tumble() {
        // A tumble about a tilted axis passes near every gimbal lock; consecutive readings stay
        // close and always give back the rotation.
        let axis = Vec3::new(0.3, 1.0, -0.4).normalize();
        for order in EulerOrder::ALL {
            let mut e = order.angles(Quat::IDENTITY);
            for step in 1..=720 {
                let q = Quat::from_axis_angle(axis, (step as f32 * 0.5).to_radians())
                    * Quat::from_rotation_x(0.4);
                let next = order.angles_near(q, e);
                assert!(same_rotation(order.to_quat(next), q), "{order:?} step {step}: {next} is not q");
                if step > 1 {
                    assert!((next - e).abs().max_element() < 12.0, "{order:?} step {step}: {e} → {next}");
                }
                e = next;
            }
        }
    }

    fn deg(axis: Vec3, degrees: f32) -> Quat {
        Quat::from_axis_angle(axis, degrees.to_radians())
    }

    /// Quaternion keys 0° → 460° about Y (a spin of one turn past the short way) → 460° again
    /// with X turned 30° first.
    fn spinning() -> Animated<Quat> {
        let keys = vec![
            Key::new(0.0, Quat::IDENTITY).with_interpolation(Interpolation::Linear),
            Key::new(1.0, deg(Vec3::Y, 100.0))
                .with_interpolation(Interpolation::Linear)
                .with_spin(Spin::Angle { axis: Vec3::Y, degrees: 460.0 }),
            Key::new(2.0, deg(Vec3::Y, 100.0) * deg(Vec3::X, 30.0))
                .with_tcb(crate::key::Tcb::new(0.5, 0.0, 0.0)),
        ];
        Animated::new(Quat::IDENTITY, RawTrack::new(keys))
    }

    #[test]
    fn quaternion_keys_become_euler_keys_that_follow_their_spins() {
        let euler = euler_keys_from_quaternions(&spinning(), EulerOrder::XYZ).expect("valid keys");
        let keys = &euler.track.keys;
        assert_eq!(keys.len(), 3);
        assert!((keys[0].value - Vec3::ZERO).abs().max_element() < 1e-3, "{}", keys[0].value);
        // The spin turned 460° about Y: Y reads 460, not 100.
        assert!((keys[1].value - Vec3::new(0.0, 460.0, 0.0)).abs().max_element() < 1e-2, "{}", keys[1].value);
        // Each key is the same rotation as before, with its time, interpolation and TCB.
        for (e, q) in keys.iter().zip(spinning().track.keys.iter()) {
            assert!(same_rotation(EulerOrder::XYZ.to_quat(e.value), q.value), "{} vs {}", e.value, q.value);
            assert_eq!((e.time, e.interpolation, e.tcb), (q.time, q.interpolation, q.tcb));
            assert!(e.spin.is_none());
        }
        // The third key's angles are the ones nearest (0, 460, 0): X 30 (X turns first in XYZ).
        let third = keys[2].value;
        assert!(
            (third.y - 460.0).abs() < 1e-2 && (third.x - 30.0).abs() < 1e-2 && third.z.abs() < 1e-2,
            "{third}"
        );
    }

    #[test]
    fn euler_keys_go_back_to_quaternion_keys_with_the_turns_they_make() {
        let euler = euler_keys_from_quaternions(&spinning(), EulerOrder::XYZ).expect("valid keys");
        let back = quaternion_keys_from_euler(&euler, EulerOrder::XYZ).expect("valid keys");
        let track = Track::new(&back.track).expect("the spins agree with the keys");
        let keys = &back.track.keys;
        assert!(keys[0].spin.is_none());
        // 0 → 460 about Y: a spin of 460° about +Y (one turn past the short 100°).
        match keys[1].spin {
            Some(Spin::Angle { axis, degrees }) => {
                assert!(
                    axis.normalize().dot(Vec3::Y) > 0.9999 && (degrees - 460.0).abs() < 0.05,
                    "{axis} {degrees}"
                );
            }
            other => panic!("expected a 460° spin, got {other:?}"),
        }
        // 460 → 460 with X 0 → 30: the short way, no spin.
        assert!(keys[2].spin.is_none(), "{:?}", keys[2].spin);
        // Halfway through the spin segment the quaternion track has turned 230° about Y.
        assert!(same_rotation(track.sample(0.5), deg(Vec3::Y, 230.0)), "{}", track.sample(0.5));
    }

    #[test]
    fn a_new_order_keeps_each_key_rotation_and_stays_continuous() {
        let euler = euler_keys_from_quaternions(&spinning(), EulerOrder::XYZ).expect("valid keys");
        let zyx = reorder_euler_keys(&euler, EulerOrder::XYZ, EulerOrder::ZYX).expect("valid keys");
        for (a, b) in euler.track.keys.iter().zip(zyx.track.keys.iter()) {
            assert!(same_rotation(EulerOrder::XYZ.to_quat(a.value), EulerOrder::ZYX.to_quat(b.value)));
        }
        // The spin about Y reads 460 in ZYX too.
        assert!((zyx.track.keys[1].value.y - 460.0).abs() < 1e-2, "{}", zyx.track.keys[1].value);
    }

    /// Linear Euler keys (0, 0, 0) → (40, 270, 0) in XYZ: halfway the rotation is the hand-written
    /// Ry(135)·Rx(20), which slerp between the keys would not give (the short way is −90° about Y).
    #[test]
    fn quaternion_keys_for_exporters_follow_the_euler_curve_within_the_tolerance() {
        let euler = Animated::new(
            Vec3::ZERO,
            RawTrack::new(vec![
                Key::new(0.0, Vec3::ZERO).with_interpolation(Interpolation::Linear),
                Key::new(1.0, Vec3::new(40.0, 270.0, 0.0)).with_interpolation(Interpolation::Step),
                Key::new(1.5, Vec3::new(0.0, 0.0, 90.0)),
                Key::new(2.5, Vec3::new(10.0, -20.0, 400.0)),
            ]),
        );
        let order = EulerOrder::XYZ;
        let tolerance = 0.01;
        let quats = quaternion_keys_following(&euler, order, (0.0, 2.5), tolerance).expect("valid keys");
        // Halving stops as soon as a piece fits: 189 keys for 0.01° here. More would only make
        // exported files bigger.
        assert!(quats.track.len() <= 200, "{} keys", quats.track.len());
        let track = Track::new(&quats.track).expect("valid quaternion keys");
        let curve = crate::track::AnimatedTrack::new(&euler).expect("valid keys");
        for t in [0.0, 0.01, 0.025, 0.03, 0.5, 0.99] {
            let linear = Vec3::new(40.0, 270.0, 0.0) * t as f32;
            assert!(
                (curve.sample(t) - linear).abs().max_element() < 1e-3,
                "t {t}: {} vs {linear}",
                curve.sample(t)
            );
        }
        for i in 0..=500 {
            let t = 2.5 * f64::from(i) / 500.0;
            let want = order.to_quat(curve.sample(t));
            let got = track.sample(t);
            // In f64: an f32 angle between nearly equal rotations is only good to about 0.04°.
            let angle = angle(want.as_dquat(), got.as_dquat()).to_degrees();
            if angle > tolerance * 1.01 + 1e-3 {
                let near: Vec<_> = quats
                    .track
                    .keys
                    .iter()
                    .filter(|k| (k.time - t).abs() < 0.1)
                    .map(|k| (k.time, k.interpolation))
                    .collect();
                panic!("t {t}: {angle}° off; keys near: {near:?}");
            }
        }
        let half = hand_matrix(1, 135.0) * hand_matrix(0, 20.0);
        let got = Mat3::from_quat(track.sample(0.5));
        let diff = (half - got).to_cols_array().iter().fold(0.0f32, |m, d| m.max(d.abs()));
        assert!(diff < 1e-3, "{half:?} vs {got:?}");
        // The step holds its key's rotation until the next key.
        assert!(same_rotation(track.sample(1.4), order.to_quat(Vec3::new(40.0, 270.0, 0.0))));
    }

    /// A spin of a thousand turns late in the timeline (keys at 1000 s and 1001 s): the angles
    /// follow every turn (Y 90 + 360 000), and so does a new order of those Euler keys.
    #[test]
    fn a_thousand_turns_late_in_the_timeline_are_followed() {
        let keys = vec![
            Key::new(1000.0, Quat::IDENTITY),
            Key::new(1001.0, deg(Vec3::Y, 90.0)).with_spin(Spin::Turns(1000)),
        ];
        let euler =
            euler_keys_from_quaternions(&Animated::new(Quat::IDENTITY, RawTrack::new(keys)), EulerOrder::XYZ)
                .expect("valid keys");
        let last = euler.track.keys[1].value;
        assert!((last.y - 360_090.0).abs() < 0.5 && last.x.abs() < 0.01 && last.z.abs() < 0.01, "{last}");
        let shifted = Animated::new(
            Vec3::ZERO,
            RawTrack::new(vec![
                Key::new(1000.0, Vec3::new(0.0, 3600.0, 0.0)),
                Key::new(1001.0, Vec3::new(0.0, 363_690.0, 0.0)),
            ]),
        );
        let zyx = reorder_euler_keys(&shifted, EulerOrder::XYZ, EulerOrder::ZYX).expect("valid keys");
        assert!((zyx.track.keys[0].value.y - 3600.0).abs() < 0.01, "{}", zyx.track.keys[0].value);
        assert!((zyx.track.keys[1].value.y - 363_690.0).abs() < 0.5, "{}", zyx.track.keys[1].value);
    }

    /// Euler keys back to quaternion keys: a path of more than half a turn gets the spin that
    /// turns as far about +Y, whether the short way goes the other way (270: short −90), the
    /// keys are the same rotation (360, 720: q and −q, q and q), nearly so (360.5, 719.7: a
    /// short way under a degree) or two turns are added (820);
    /// under half a turn there is none. Each track validates and turns halfway by half the
    /// angle.
    #[test]
    fn paths_past_half_a_turn_become_spins_that_turn_as_far() {
        for (y, spin) in [
            (100.0, None),
            (270.0, Some(270.0)),
            (360.0, Some(360.0)),
            (360.5, Some(360.5)),
            (-0.3 + 720.0, Some(719.7)),
            (720.0, Some(720.0)),
            (820.0, Some(820.0)),
        ] {
            let euler = Animated::new(
                Vec3::ZERO,
                RawTrack::new(vec![
                    Key::new(0.0, Vec3::ZERO).with_interpolation(Interpolation::Linear),
                    Key::new(1.0, Vec3::new(0.0, y, 0.0)),
                ]),
            );
            let back = quaternion_keys_from_euler(&euler, EulerOrder::XYZ).expect("valid keys");
            match (back.track.keys[1].spin, spin) {
                (None, None) => {}
                (Some(Spin::Angle { axis, degrees }), Some(want)) => {
                    let along = f64::from(axis.normalize().dot(Vec3::Y));
                    assert!(
                        (degrees * along - want).abs() < 0.05 && along.abs() > 0.9999,
                        "{y}: {axis} {degrees}"
                    );
                }
                (got, want) => panic!("{y}: spin {got:?}, expected {want:?}"),
            }
            let track = Track::new(&back.track).expect("the spin agrees with the keys");
            let half = y / 2.0;
            assert!(same_rotation(track.sample(0.5), deg(Vec3::Y, half)), "{y}: {}", track.sample(0.5));
        }
    }

    #[test]
    fn invalid_euler_keys_are_refused_and_muted_or_unkeyed_ones_hold_their_value() {
        let bad = Animated::new(
            Vec3::ZERO,
            RawTrack::new(vec![Key::new(1.0, Vec3::ZERO), Key::new(f64::NAN, Vec3::X)]),
        );
        assert!(quaternion_keys_from_euler(&bad, EulerOrder::XYZ).is_err());
        assert!(reorder_euler_keys(&bad, EulerOrder::XYZ, EulerOrder::YXZ).is_err());
        assert!(quaternion_keys_following(&bad, EulerOrder::XYZ, (0.0, 1.0), 0.05).is_err());
        let value = Vec3::new(10.0, 20.0, 30.0);
        let keyed =
            Animated::new(value, RawTrack::new(vec![Key::new(0.0, Vec3::ZERO), Key::new(1.0, Vec3::Y)]));
        let muted = Animated { muted: true, ..keyed };
        for a in [muted, Animated::constant(value)] {
            let q = quaternion_keys_following(&a, EulerOrder::ZXY, (0.0, 1.0), 0.05).expect("valid");
            assert!(!q.is_animated());
            assert!(same_rotation(q.value, EulerOrder::ZXY.to_quat(value)));
        }
    }

    /// Cycles are played out over the range: Repeat before the keys, RepeatOffset after them
    /// (each cycle adds the last key's angles minus the first's), a Step key among them, a
    /// period of 0.75 s. Every repeat of a key time inside the range is a key of the result (a
    /// Step one steps), nothing lies outside the range, and the curve is followed within the
    /// tolerance everywhere but within a hundred-thousandth of a second of where a cycle starts
    /// again and the curve jumps (there the keys close in on the jump to a millionth of a
    /// second). A cycle on one side alone also plays out over the whole range (the other side
    /// holds); without cycles the keys span only the Euler keys.
    #[test]
    fn cycles_are_played_out_over_the_range() {
        use crate::key::{Cycle, Cycles};
        let keys = Animated::new(
            Vec3::ZERO,
            RawTrack::new(vec![
                Key::new(0.5, Vec3::ZERO).with_interpolation(Interpolation::Linear),
                Key::new(0.9, Vec3::new(30.0, 80.0, 0.0)).with_interpolation(Interpolation::Step),
                Key::new(1.05, Vec3::new(0.0, 100.0, -20.0)),
                Key::new(1.25, Vec3::new(0.0, 120.0, 0.0)),
            ]),
        );
        let range = (-2.6, 4.7);
        let tolerance = 0.02;
        let cases = [
            (Cycles { before: Cycle::Repeat, after: Cycle::RepeatOffset }, (range.0, range.1)),
            (Cycles { before: Cycle::Hold, after: Cycle::Repeat }, (range.0, range.1)),
            (Cycles { before: Cycle::PingPong, after: Cycle::Hold }, (range.0, range.1)),
            (Cycles { before: Cycle::Linear, after: Cycle::PingPong }, (range.0, range.1)),
            (Cycles::HOLD, (0.5, 1.25)),
        ];
        for (cycles, span) in cases {
            let euler = keys.clone().with_cycles(cycles);
            let quats =
                quaternion_keys_following(&euler, EulerOrder::XYZ, range, tolerance).expect("valid keys");
            let times: Vec<f64> = quats.track.keys.iter().map(|k| k.time).collect();
            assert_eq!((times[0], times[times.len() - 1]), span, "{cycles:?}: the span, no more");
            for n in -5..=5 {
                let cycle = if n < 0 { cycles.before } else { cycles.after };
                if n != 0 && !cycle.is_cyclic() {
                    continue;
                }
                // A ping-pong's backward cycles play the keys mirrored.
                let backward = cycle == Cycle::PingPong && n % 2 != 0;
                for k in euler.track.keys.iter() {
                    let start = 0.5 + 0.75 * f64::from(n);
                    let t = if backward { start + (1.25 - k.time) } else { start + (k.time - 0.5) };
                    if t < range.0 || t > range.1 {
                        continue;
                    }
                    let key = quats.track.keys.iter().find(|q| (q.time - t).abs() < 1e-9);
                    let key =
                        key.unwrap_or_else(|| panic!("{cycles:?}: no key at the repeat {t}: {times:?}"));
                    if !backward && (t - 4.7).abs() > 1e-9 {
                        let step = k.interpolation == Interpolation::Step;
                        assert_eq!(key.interpolation == Interpolation::Step, step, "{cycles:?} at {t}");
                    }
                }
            }
            let track = Track::new(&quats.track).expect("valid");
            let curve = crate::track::AnimatedTrack::new(&euler).expect("valid");
            // Where a cycle starts again the curve jumps (its ends differ): the keys close in on
            // the jump to a millionth of a second, so the samples keep clear of it.
            let jump = |t: f64| {
                let k = ((t - 0.5) / 0.75).round();
                cycles != Cycles::HOLD && (t - (0.5 + 0.75 * k)).abs() < 1e-5
            };
            for i in 0..=600 {
                let t = span.0 + (span.1 - span.0) * f64::from(i) / 600.0;
                if jump(t) {
                    continue;
                }
                let (want, got) = (EulerOrder::XYZ.to_quat(curve.sample(t)), track.sample(t));
                let off = angle(want.as_dquat(), got.as_dquat()).to_degrees();
                assert!(off <= tolerance * 1.01 + 1e-3, "{cycles:?} t {t}: {off}°");
            }
        }
    }
}
