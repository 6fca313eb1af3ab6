//! glTF animation channels that gltf-json 1.4 cannot hold: `KHR_animation_pointer` channels
//! (a JSON pointer instead of a node) and `KHR_node_visibility`.
//!
//! gltf-json requires `node` on every channel target (gltf-rs/gltf issue 439), although glTF 2.0
//! made it optional ("when node isn't defined, the channel SHOULD be ignored") and
//! `KHR_animation_pointer` channels have none. `gltf_import`'s `parse_root` therefore reads a document that
//! gltf-json refuses a second time as plain JSON, sets every channel without `node` aside (their
//! samplers stay), and hands the rest to gltf-json; a file gltf-json accepts is read once, as
//! before. its `read_pointer_channels` then reads the set-aside channels whose pointer names a
//! property keyrig holds, with the same accessor checks as every other channel:
//!
//! | pointer | read as |
//! |---|---|
//! | `/nodes/N/translation`, `rotation`, `scale`, `weights` | a node channel, as the core paths |
//! | `/nodes/N/extensions/KHR_node_visibility/visible` | [`PointerTarget::NodeVisible`] (STEP, 0/1) |
//! | `/materials/M/pbrMetallicRoughness/baseColorFactor` | [`PointerTarget::MaterialBaseColour`] (RGBA) |
//! | `/extensions/KHR_lights_punctual/lights/L/color`, `intensity`, `range` | light channels |
//! | `/extensions/KHR_lights_punctual/lights/L/spot/innerConeAngle`, `outerConeAngle` | cone angles (radians) |
//! | `/cameras/C/perspective/yfov` | [`PointerTarget::CameraYfov`]: the lens (field of view, radians → degrees) |
//! | `/cameras/C/orthographic/ymag` | [`PointerTarget::CameraYmag`]: the lens (view height `2·ymag`) |
//!
//! Skipped with their reason: a camera's `znear` / `zfar` (keyrig's clip planes are not keyed),
//! `xmag` (the width follows the height and the render aspect), `aspectRatio` (the scene's
//! render size).
//!
//! Every other channel is left out and listed in [`crate::model::ImportedModel::skipped_channels`]
//! with why (`keyrig info` prints them).

use glam::{Vec3, Vec4};
use keyrig_core::RawTrack;

/// The extensions read here from the raw JSON rather than by the gltf crate.
pub const READ_FROM_JSON: [&str; 2] = ["KHR_animation_pointer", "KHR_node_visibility"];

/// What a pointer channel animates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PointerTarget {
    /// `KHR_node_visibility`'s `visible` of a node: 1 visible, 0 hidden, STEP keys.
    NodeVisible(usize),
    /// A material's `baseColorFactor` (linear RGBA).
    MaterialBaseColour(usize),
    /// A `KHR_lights_punctual` light's `color` (linear RGB).
    LightColour(usize),
    LightIntensity(usize),
    /// The light's `range` (metres).
    LightRange(usize),
    /// The spot light's `innerConeAngle` (radians).
    LightInnerCone(usize),
    /// The spot light's `outerConeAngle` (radians).
    LightOuterCone(usize),
    /// A perspective camera's `yfov` (radians).
    CameraYfov(usize),
    /// An orthographic camera's `ymag` (half the view's height).
    CameraYmag(usize),
}

/// The keys of a pointer channel, with the file's interpolation (CUBICSPLINE tangents kept).
#[derive(Clone, Debug, PartialEq)]
pub enum PointerKeys {
    Scalar(RawTrack<f32>),
    Vec3(RawTrack<Vec3>),
    Vec4(RawTrack<Vec4>),
}

impl PointerKeys {
    /// The time of the last key.
    #[must_use]
    pub fn last_time(&self) -> Option<f64> {
        match self {
            PointerKeys::Scalar(t) => t.keys.last().map(|k| k.time),
            PointerKeys::Vec3(t) => t.keys.last().map(|k| k.time),
            PointerKeys::Vec4(t) => t.keys.last().map(|k| k.time),
        }
    }
}

/// A `KHR_animation_pointer` channel keyrig holds.
#[derive(Clone, Debug, PartialEq)]
pub struct PointerChannel {
    /// The pointer as the file wrote it.
    pub pointer: String,
    pub target: PointerTarget,
    pub keys: PointerKeys,
}

/// An animation channel the import left out, and why.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct SkippedChannel {
    /// Where the channel is (`/animations/0/channels/2`).
    pub channel: String,
    /// Its `KHR_animation_pointer` pointer, when it has one.
    pub pointer: Option<String>,
    pub reason: String,
}

impl std::fmt::Display for SkippedChannel {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match &self.pointer {
            Some(p) => write!(f, "{} ({p}): {}", self.channel, self.reason),
            None => write!(f, "{}: {}", self.channel, self.reason),
        }
    }
}
