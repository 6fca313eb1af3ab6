//! Editable key data: what the scene file stores and the editor changes.
//!
//! A [`RawTrack`] is a plain list of [`Key`]s with no invariants. It is checked once into an
//! evaluable track (see [`crate::track`]) whose constructor returns a typed error.

use glam::Vec3;
use std::sync::Arc;

use serde::{Deserialize, Serialize};

/// How the segment that *starts* at a key is interpolated (the mode of key i governs
/// segment i, from key i to key i+1).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Interpolation {
    /// Hold the key's value until the next key (glTF STEP).
    Step,
    /// Straight line (slerp for rotations).
    Linear,
    /// Kochanek–Bartels spline from the key's tension, continuity and bias
    /// (Squad with TCB for rotations).
    #[default]
    Tcb,
    /// Cubic Hermite with the explicit per-second tangents stored in the key
    /// ([`Key::in_tangent`], [`Key::out_tangent`]); what glTF CUBICSPLINE imports as.
    Hermite,
}

/// Tension, continuity and bias of one key, each in [-1, 1] (Kochanek & Bartels 1984).
#[derive(Clone, Copy, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Tcb {
    pub tension: f32,
    pub continuity: f32,
    pub bias: f32,
    /// Clamped (as Blender's auto-clamped handles): at a key that is a peak, a dip or level
    /// with a neighbour the tangent is flat, and elsewhere it is limited so that the segments
    /// on either side of the key do not overshoot it (per component; for rotations per
    /// component of the logarithm). Two keys of equal value then hold that value between them.
    /// Left out of scene files while false.
    #[serde(default, skip_serializing_if = "is_false")]
    pub clamped: bool,
}

fn is_false(b: &bool) -> bool {
    !*b
}

impl Tcb {
    /// T = C = B = 0: Catmull–Rom for positions, Shoemake's squad for rotations.
    pub const ZERO: Tcb = Tcb { tension: 0.0, continuity: 0.0, bias: 0.0, clamped: false };

    #[must_use]
    pub const fn new(tension: f32, continuity: f32, bias: f32) -> Self {
        Tcb { tension, continuity, bias, clamped: false }
    }

    /// The same tension, continuity and bias, clamped or not.
    #[must_use]
    pub const fn with_clamped(self, clamped: bool) -> Self {
        Tcb { clamped, ..self }
    }
}

/// What a key means to the animator (Blender's keyframe types): it changes nothing in how
/// the track plays; the dope sheet draws each type in its own shape and colour so that the
/// story poses, the in-betweens and the holds read apart. Left out of scene files while it is
/// [`KeyType::Keyframe`], the default and what files without the field load as.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum KeyType {
    /// A main pose (a key).
    #[default]
    Keyframe,
    /// An in-between pose that shapes the motion from one key to the next.
    Breakdown,
    /// A pose held with a little motion so that it stays alive.
    MovingHold,
    /// The extreme of a motion (the farthest point of an arc).
    Extreme,
}

impl KeyType {
    /// Every type, in the order menus list them.
    pub const ALL: [KeyType; 4] =
        [KeyType::Keyframe, KeyType::Breakdown, KeyType::MovingHold, KeyType::Extreme];

    /// Whether this is the default type (scene files leave the field out).
    #[must_use]
    pub fn is_keyframe(&self) -> bool {
        *self == KeyType::Keyframe
    }

    /// The type's name as menus and the dope sheet's tooltips say it.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            KeyType::Keyframe => "Keyframe",
            KeyType::Breakdown => "Breakdown",
            KeyType::MovingHold => "Moving hold",
            KeyType::Extreme => "Extreme",
        }
    }
}

/// Most whole turns a [`Spin`] may add or describe (1000 turns, 360 000°). Beyond that a
/// spin is refused as absurd: a segment of a second would turn faster than 60 000 rpm, and
/// `sin`/`cos` of the half-angle would start to lose digits.
pub const MAX_SPIN_TURNS: i32 = 1000;

/// How a rotation key is reached from the previous key when that is not the short way
/// (3ds Max's TCB rotation controller stores every key this way: an axis and an angle
/// relative to the previous key). Only rotation keys may carry one, and never the first key.
///
/// The segment from key i to key i+1 then turns by the *unwrapped* angle-axis `L` below
/// (half the angle times the unit axis, of any size) instead of the short-way logarithm
/// `log(q_i⁻¹·q_{i+1})`; docs/design.md §3 and docs/interpolation.md give the formulas.
///
/// ```text
/// (time: 1.0, value: (0.0, 0.0, 0.0, 1.0), spin: Some(Angle(axis: (1.0, 0.0, 0.0), degrees: 360.0)))
/// (time: 2.0, value: (0.0, 0.0, 0.70710677, 0.70710677), spin: Some(Turns(1)))
/// ```
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub enum Spin {
    /// The short way from the previous key plus `n` whole turns (360° each) about the short
    /// way's axis: `n > 0` keeps turning in the short way's direction (`Turns(1)` from 0° to
    /// 90° about X turns 450°), `n < 0` turns against it (`Turns(-1)` is the long way round,
    /// −270°). `Turns(0)` is the short way, as if there were no spin. The short way must be
    /// between [`SPIN_TURNS_MIN_CHORD_DEG`] and 180° − that (else its axis or direction is
    /// not defined by the two keys: use [`Spin::Angle`]), and |n| ≤ [`MAX_SPIN_TURNS`].
    Turns(i32),
    /// Exactly `degrees` (any size, sign by the right-hand rule) about `axis`, a direction
    /// in the previous key's frame (for a joint: the joint's own axes at the previous key, so
    /// `(1, 0, 0)` is the bone axis of keyrig's arms). The key's `value` must be the rotation
    /// this arrives at, `q_i·(axis, degrees)`, within [`SPIN_ANGLE_TOLERANCE_DEG`]; the track
    /// passes through `value` exactly. The axis must be finite and not zero (it is
    /// normalized) and |degrees| ≤ 360 · [`MAX_SPIN_TURNS`].
    Angle { axis: Vec3, degrees: f64 },
}

/// [`Spin::Turns`] needs the short way between the keys to be at least this many degrees
/// (and at most 180° minus this), so that its axis and direction are defined by the keys'
/// values despite their f32 rounding (about 1e-5° of axis error at this angle).
pub const SPIN_TURNS_MIN_CHORD_DEG: f64 = 0.01;

/// Largest angle between the rotation a [`Spin::Angle`] arrives at and the key's `value`.
pub const SPIN_ANGLE_TOLERANCE_DEG: f64 = 0.01;

/// [`Spin::Angle`] axes shorter than this cannot be normalized and are refused.
pub const MIN_SPIN_AXIS_LENGTH: f32 = 1e-6;

impl Spin {
    /// Whether the numbers are usable on their own: |turns| ≤ [`MAX_SPIN_TURNS`]; for an
    /// angle, finite numbers, an axis at least [`MIN_SPIN_AXIS_LENGTH`] long and
    /// |degrees| ≤ 360 · [`MAX_SPIN_TURNS`].
    #[must_use]
    pub fn is_in_range(self) -> bool {
        let max_degrees = 360.0 * f64::from(MAX_SPIN_TURNS);
        match self {
            Spin::Turns(n) => n.unsigned_abs() <= MAX_SPIN_TURNS.unsigned_abs(),
            Spin::Angle { axis, degrees } => {
                axis.is_finite()
                    && axis.length() >= MIN_SPIN_AXIS_LENGTH
                    && degrees.is_finite()
                    && degrees.abs() <= max_degrees
            }
        }
    }
}

/// One key of a track: a value at a time (seconds) and how to leave it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, bound(deserialize = "T: Deserialize<'de>"))]
pub struct Key<T> {
    /// Time in seconds.
    pub time: f64,
    pub value: T,
    #[serde(default)]
    pub interpolation: Interpolation,
    #[serde(default)]
    pub tcb: Tcb,
    /// Incoming tangent in value units per second; used by [`Interpolation::Hermite`] for the
    /// segment that ends at this key.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub in_tangent: Option<T>,
    /// Outgoing tangent in value units per second; used by [`Interpolation::Hermite`] for the
    /// segment that starts at this key.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub out_tangent: Option<T>,
    /// Rotation keys only: how this key is reached from the previous key when not the short
    /// way (whole extra turns or an explicit angle about an axis). `None`, the default and
    /// what files without the field load as, is the short way.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub spin: Option<Spin>,
    /// What the key means to the animator ([`KeyType`]); playback ignores it. Left out of
    /// scene files while it is a plain keyframe.
    #[serde(default, skip_serializing_if = "KeyType::is_keyframe")]
    pub key_type: KeyType,
}

impl<T> Key<T> {
    /// A TCB key with T = C = B = 0.
    #[must_use]
    pub fn new(time: f64, value: T) -> Self {
        Key {
            time,
            value,
            interpolation: Interpolation::Tcb,
            tcb: Tcb::ZERO,
            in_tangent: None,
            out_tangent: None,
            spin: None,
            key_type: KeyType::Keyframe,
        }
    }

    /// Sets what the key means to the animator ([`KeyType`]).
    #[must_use]
    pub fn with_key_type(mut self, key_type: KeyType) -> Self {
        self.key_type = key_type;
        self
    }

    #[must_use]
    pub fn with_interpolation(mut self, interpolation: Interpolation) -> Self {
        self.interpolation = interpolation;
        self
    }

    #[must_use]
    pub fn with_tcb(mut self, tcb: Tcb) -> Self {
        self.tcb = tcb;
        self
    }

    /// Sets how the key is reached from the previous one (rotation keys only).
    #[must_use]
    pub fn with_spin(mut self, spin: Spin) -> Self {
        self.spin = Some(spin);
        self
    }
}

/// An editable, unvalidated list of keys. Serialized as a plain list.
///
/// The keys are shared copy-on-write ([`Keys`]): cloning a track — an undo snapshot, a copy of
/// the scene — shares them, and the first change to one copy copies that track only.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(transparent, bound(serialize = "T: Serialize", deserialize = "T: Deserialize<'de>"))]
pub struct RawTrack<T> {
    pub keys: Keys<T>,
}

impl<T> Default for RawTrack<T> {
    fn default() -> Self {
        RawTrack { keys: Keys::default() }
    }
}

impl<T> RawTrack<T> {
    #[must_use]
    pub fn new(keys: Vec<Key<T>>) -> Self {
        RawTrack { keys: Keys::from(keys) }
    }

    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.keys.is_empty()
    }

    #[must_use]
    pub fn len(&self) -> usize {
        self.keys.len()
    }
}

/// The keys of a track, shared copy-on-write: reads go straight to the list
/// (`Deref<Target = Vec<Key<T>>>`), and a mutable access (`DerefMut`) first copies the list if
/// another track still shares it ([`Arc::make_mut`]). So a copy of a scene costs one pointer
/// per track, an edit copies only the tracks it changes, and [`Keys::shares_with`] tells whether
/// two tracks are still the same list — which is how the scene evaluator learns what an edit
/// changed without comparing keys.
#[derive(Debug)]
pub struct Keys<T>(Arc<Vec<Key<T>>>);

impl<T> Keys<T> {
    /// True when both are the same shared list (neither was changed since one was cloned from
    /// the other).
    #[must_use]
    pub fn shares_with(&self, other: &Keys<T>) -> bool {
        Arc::ptr_eq(&self.0, &other.0)
    }
}

impl<T> Clone for Keys<T> {
    fn clone(&self) -> Self {
        Keys(Arc::clone(&self.0))
    }
}

impl<T> Default for Keys<T> {
    fn default() -> Self {
        Keys(Arc::new(Vec::new()))
    }
}

impl<T> From<Vec<Key<T>>> for Keys<T> {
    fn from(keys: Vec<Key<T>>) -> Self {
        Keys(Arc::new(keys))
    }
}

impl<T> std::ops::Deref for Keys<T> {
    type Target = Vec<Key<T>>;

    fn deref(&self) -> &Vec<Key<T>> {
        &self.0
    }
}

impl<T: Clone> std::ops::DerefMut for Keys<T> {
    fn deref_mut(&mut self) -> &mut Vec<Key<T>> {
        Arc::make_mut(&mut self.0)
    }
}

impl<T: PartialEq> PartialEq for Keys<T> {
    fn eq(&self, other: &Self) -> bool {
        Arc::ptr_eq(&self.0, &other.0) || *self.0 == *other.0
    }
}

impl<T: Serialize> Serialize for Keys<T> {
    fn serialize<S: serde::Serializer>(&self, serializer: S) -> Result<S::Ok, S::Error> {
        self.0.serialize(serializer)
    }
}

impl<'de, T: Deserialize<'de>> Deserialize<'de> for Keys<T> {
    fn deserialize<D: serde::Deserializer<'de>>(deserializer: D) -> Result<Self, D::Error> {
        Vec::<Key<T>>::deserialize(deserializer).map(Keys::from)
    }
}

/// What a track does before its first key (`before`) or after its last (`after`): a cycle
/// (docs/design.md §9 "Cycles"; docs/interpolation.md gives the formulas). `P = t_n − t_0` is the
/// period, the time from the first key to the last.
///
/// Every behaviour but [`Cycle::Hold`] needs at least two keys (a positive period).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Cycle {
    /// Keep the end key's value (constant extrapolation); what tracks did before cycles.
    #[default]
    Hold,
    /// Continue with the velocity at the end key (for rotations: keep turning at the end
    /// key's angular velocity). A Step end segment has none, so it holds.
    Linear,
    /// Play the keys again and again: the value at `t ± P` is the value at `t`.
    Repeat,
    /// Repeat, each cycle continuing from where the last one ended (a walk): the value at
    /// `t + P` is the value at `t` plus `P_n − P_0`; for rotations `q(t + P) = M·q(t)` with
    /// `M = q_n·q_0⁻¹`, i.e. the turn `q_0⁻¹·q_n` relative to the first key is added once per
    /// cycle.
    RepeatOffset,
    /// Play the keys forwards, then backwards, then forwards…: mirrored at each end key.
    PingPong,
}

impl Cycle {
    /// Every behaviour, in the order the inspector lists them.
    pub const ALL: [Cycle; 5] =
        [Cycle::Hold, Cycle::Linear, Cycle::Repeat, Cycle::RepeatOffset, Cycle::PingPong];

    /// `Hold`, the default (left out of scene files).
    #[must_use]
    pub fn is_hold(&self) -> bool {
        *self == Cycle::Hold
    }

    /// Whether the keys are played again ([`Cycle::Repeat`], [`Cycle::RepeatOffset`],
    /// [`Cycle::PingPong`]).
    #[must_use]
    pub fn is_cyclic(self) -> bool {
        matches!(self, Cycle::Repeat | Cycle::RepeatOffset | Cycle::PingPong)
    }

    /// The name shown in the editor ("Repeat with offset").
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            Cycle::Hold => "Hold",
            Cycle::Linear => "Linear",
            Cycle::Repeat => "Repeat",
            Cycle::RepeatOffset => "Repeat with offset",
            Cycle::PingPong => "Ping-pong",
        }
    }
}

impl std::fmt::Display for Cycle {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(self.label())
    }
}

/// What a track does outside its keys: `before` the first key and `after` the last.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub struct Cycles {
    pub before: Cycle,
    pub after: Cycle,
}

impl Cycles {
    /// Hold at both ends.
    pub const HOLD: Cycles = Cycles { before: Cycle::Hold, after: Cycle::Hold };

    #[must_use]
    pub const fn new(before: Cycle, after: Cycle) -> Self {
        Cycles { before, after }
    }

    /// Both ends [`Cycle::Hold`].
    #[must_use]
    pub fn is_hold(self) -> bool {
        self.before.is_hold() && self.after.is_hold()
    }
}

/// A value that may be animated: the static `value` (the pose) is used while `track` has no
/// keys; once it has keys, the sampled track wins, with `before` and `after` ([`Cycle`])
/// deciding what happens outside its keys. Both are left out of the file when
/// [`Cycle::Hold`], so scenes without cycles read and write as before:
///
/// ```text
/// rotation: (value: (0.0, 0.0, 0.0, 1.0), track: [ … ], after: Repeat)
/// ```
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, bound(deserialize = "T: Deserialize<'de>"))]
pub struct Animated<T> {
    pub value: T,
    #[serde(default = "RawTrack::default", skip_serializing_if = "RawTrack::is_empty")]
    pub track: RawTrack<T>,
    /// Before the first key.
    #[serde(default, skip_serializing_if = "Cycle::is_hold")]
    pub before: Cycle,
    /// After the last key.
    #[serde(default, skip_serializing_if = "Cycle::is_hold")]
    pub after: Cycle,
    /// Muted (Blender's mute): the channel plays its static `value` and ignores its keys,
    /// which are kept. Left out of a scene file when false.
    #[serde(default, skip_serializing_if = "is_false")]
    pub muted: bool,
    /// Locked: the editor refuses to change the channel's keys and value. Left out of a scene
    /// file when false.
    #[serde(default, skip_serializing_if = "is_false")]
    pub locked: bool,
}

impl<T> Animated<T> {
    /// A constant, not animated.
    #[must_use]
    pub fn constant(value: T) -> Self {
        Animated::new(value, RawTrack::default())
    }

    /// The static `value` and a `track`, holding outside its keys.
    #[must_use]
    pub fn new(value: T, track: RawTrack<T>) -> Self {
        Animated { value, track, before: Cycle::Hold, after: Cycle::Hold, muted: false, locked: false }
    }

    /// The same with the given behaviour before the first key and after the last.
    #[must_use]
    pub fn with_cycles(mut self, cycles: Cycles) -> Self {
        self.before = cycles.before;
        self.after = cycles.after;
        self
    }

    /// `before` and `after` together.
    #[must_use]
    pub fn cycles(&self) -> Cycles {
        Cycles { before: self.before, after: self.after }
    }

    #[must_use]
    pub fn is_animated(&self) -> bool {
        !self.track.is_empty()
    }
}
