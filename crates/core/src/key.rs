//! Editable key data: what the scene file stores and the editor changes.
//!
//! A [`RawTrack`] is a plain list of [`Key`]s with no invariants. It is checked once into an
//! evaluable track (see [`crate::track`]) whose constructor returns a typed error.

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
}

impl Tcb {
    /// T = C = B = 0: Catmull–Rom for positions, Shoemake's squad for rotations.
    pub const ZERO: Tcb = Tcb { tension: 0.0, continuity: 0.0, bias: 0.0 };

    #[must_use]
    pub const fn new(tension: f32, continuity: f32, bias: f32) -> Self {
        Tcb { tension, continuity, bias }
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
        }
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
}

/// An editable, unvalidated list of keys. Serialized as a plain list.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(transparent)]
pub struct RawTrack<T> {
    pub keys: Vec<Key<T>>,
}

impl<T> Default for RawTrack<T> {
    fn default() -> Self {
        RawTrack { keys: Vec::new() }
    }
}

impl<T> RawTrack<T> {
    #[must_use]
    pub fn new(keys: Vec<Key<T>>) -> Self {
        RawTrack { keys }
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

/// A value that may be animated: the static `value` (the pose) is used while `track` has no
/// keys; once it has keys, the sampled track wins.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields, bound(deserialize = "T: Deserialize<'de>"))]
pub struct Animated<T> {
    pub value: T,
    #[serde(default = "RawTrack::default", skip_serializing_if = "RawTrack::is_empty")]
    pub track: RawTrack<T>,
}

impl<T> Animated<T> {
    /// A constant, not animated.
    #[must_use]
    pub fn constant(value: T) -> Self {
        Animated { value, track: RawTrack::default() }
    }

    #[must_use]
    pub fn is_animated(&self) -> bool {
        !self.track.is_empty()
    }
}
