//! Keyed attributes beyond transforms (issue 31, after the IAnimEd thesis §10.2: "more or all
//! possible attributes such as scale, visibility, deformation etc."): an object's visibility,
//! material colour and opacity, morph-target weights and deformer; a light's visibility, range
//! and spot cone; the bones-blending zone (its two fractions, replacing the object's
//! `DeformerSettings` fractions; the evaluator binds the mesh again for each zone it samples).
//!
//! Every attribute is an [`Animated`] value, so it has the keys, interpolation modes, cycles,
//! validation, undo, dope-sheet row and curve of every other channel
//! (`channel_id::attribute_id::AttributeId` names them). Switches are numbers with Step keys: visibility is 1 (shown) or 0 (hidden),
//! the deformer is the index of a `DeformerKind` in `DeformerKind::ALL`.
//!
//! Attributes that replace a static setting are `Option`s: `None` keeps the setting (the mesh's
//! own material colour, the object's [`crate::DeformerSettings`], the light's
//! `LightKind::Spot` angles, no range), `Some` replaces it with the animated value. Their
//! channels exist only while they are `Some`.
//!
//! Everything is left out of a scene file while it is the default, so files without
//! attributes read and save unchanged.

use glam::Vec3;
use serde::{Deserialize, Serialize};

use crate::key::Animated;

fn shown() -> Animated<f32> {
    Animated::constant(1.0)
}

fn is_shown(a: &Animated<f32>) -> bool {
    !a.is_animated() && a.value == 1.0
}

/// An object's keyed attributes (`Object::attributes`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectAttributes {
    /// 1 shown, 0 hidden (Step keys). Left out of the file while always shown.
    #[serde(default = "shown", skip_serializing_if = "is_shown")]
    pub visible: Animated<f32>,
    /// Linear RGB replacing the mesh material's base colour factor (`None`: the mesh's own).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub colour: Option<Animated<Vec3>>,
    /// Opacity in [0, 1], blended over what is behind (1: opaque, as without the attribute).
    #[serde(default = "shown", skip_serializing_if = "is_shown")]
    pub opacity: Animated<f32>,
    /// Weights of the mesh's morph targets (glTF `weights`), by target index; targets beyond
    /// the list keep the mesh's own default weight.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub morph_weights: Vec<Animated<f32>>,
    /// The deformer, as an index into `DeformerKind::ALL` (0 rigid, 1 linear blend, 2 bones
    /// blending, 3 dual quaternion; Step keys), replacing `deformer.kind`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub deformer: Option<Animated<f32>>,
    /// Bones blending: how far the blend zone reaches into the parent bone, as a fraction of its
    /// length in [0, 1], replacing `deformer.blend_parent_fraction`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blend_parent_fraction: Option<Animated<f32>>,
    /// Bones blending: how far the blend zone reaches into the child bone (0..=1), replacing
    /// `deformer.blend_child_fraction`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub blend_child_fraction: Option<Animated<f32>>,
}

impl Default for ObjectAttributes {
    fn default() -> Self {
        ObjectAttributes {
            visible: shown(),
            colour: None,
            opacity: shown(),
            morph_weights: Vec::new(),
            deformer: None,
            blend_parent_fraction: None,
            blend_child_fraction: None,
        }
    }
}

impl ObjectAttributes {
    /// True when nothing is set (what a scene file leaves out).
    #[must_use]
    pub fn is_default(&self) -> bool {
        *self == ObjectAttributes::default()
    }
}

/// A light's keyed attributes (`Light::attributes`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct LightAttributes {
    /// 1 shown (lighting), 0 hidden (Step keys).
    #[serde(default = "shown", skip_serializing_if = "is_shown")]
    pub visible: Animated<f32>,
    /// Distance (> 0) beyond which the light has no effect, with glTF's smooth falloff
    /// `clamp(1 − (d/range)⁴, 0, 1) / d²` (`KHR_lights_punctual`); `None`: unlimited.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub range: Option<Animated<f32>>,
    /// A spot light's cutoff half-angle in degrees, replacing the kind's `cutoff_deg`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub cutoff_deg: Option<Animated<f32>>,
    /// A spot light's inner half-angle in degrees, replacing the kind's `inner_angle_deg`.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub inner_angle_deg: Option<Animated<f32>>,
}

impl Default for LightAttributes {
    fn default() -> Self {
        LightAttributes { visible: shown(), range: None, cutoff_deg: None, inner_angle_deg: None }
    }
}

impl LightAttributes {
    /// True when nothing is set (what a scene file leaves out).
    #[must_use]
    pub fn is_default(&self) -> bool {
        *self == LightAttributes::default()
    }
}

fn cost<T>(a: &Animated<T>, b: Option<&Animated<T>>) -> usize {
    if b.is_some_and(|b| b.track.keys.shares_with(&a.track.keys)) {
        0
    } else {
        a.track.keys.len() * std::mem::size_of::<crate::key::Key<T>>()
    }
}

impl ObjectAttributes {
    /// Bytes of keys in `self` that `other` does not share (`Scene::key_bytes_not_shared_with`).
    #[must_use]
    pub(crate) fn key_bytes_not_shared_with(&self, other: Option<&ObjectAttributes>) -> usize {
        let mut bytes =
            cost(&self.visible, other.map(|o| &o.visible)) + cost(&self.opacity, other.map(|o| &o.opacity));
        if let Some(c) = &self.colour {
            bytes += cost(c, other.and_then(|o| o.colour.as_ref()));
        }
        for (i, w) in self.morph_weights.iter().enumerate() {
            bytes += cost(w, other.and_then(|o| o.morph_weights.get(i)));
        }
        for (mine, theirs) in [
            (&self.deformer, other.and_then(|o| o.deformer.as_ref())),
            (&self.blend_parent_fraction, other.and_then(|o| o.blend_parent_fraction.as_ref())),
            (&self.blend_child_fraction, other.and_then(|o| o.blend_child_fraction.as_ref())),
        ] {
            if let Some(a) = mine {
                bytes += cost(a, theirs);
            }
        }
        bytes
    }
}

impl LightAttributes {
    /// Bytes of keys in `self` that `other` does not share (`Scene::key_bytes_not_shared_with`).
    #[must_use]
    pub(crate) fn key_bytes_not_shared_with(&self, other: Option<&LightAttributes>) -> usize {
        let mut bytes = cost(&self.visible, other.map(|o| &o.visible));
        for (mine, theirs) in [
            (&self.range, other.and_then(|o| o.range.as_ref())),
            (&self.cutoff_deg, other.and_then(|o| o.cutoff_deg.as_ref())),
            (&self.inner_angle_deg, other.and_then(|o| o.inner_angle_deg.as_ref())),
        ] {
            if let Some(a) = mine {
                bytes += cost(a, theirs);
            }
        }
        bytes
    }
}
