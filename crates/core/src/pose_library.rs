//! The scene's pose library and its reference image: plain data saved with the scene
//! (docs/scene-format.md), both left out of a scene file while unused.
//!
//! A [`NamedPose`] holds channel values by channel path (`object/Arm/joint/elbow/rotation`,
//! [`crate::channel`]), so a pose finds its joints by name in any scene that has them, and a
//! pose saved from one character applies to a copy of it. A [`ReferenceImage`] names an image
//! file relative to the scene file, as model files are named.

use serde::{Deserialize, Serialize};

use crate::channel_value::ChannelValue;

/// A named pose of the pose library: the values of some channels at the frame it was saved.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct NamedPose {
    pub name: String,
    pub values: Vec<PoseValue>,
}

/// One channel's value in a [`NamedPose`].
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct PoseValue {
    /// The channel's path ([`crate::channel::ChannelPath`]).
    pub channel: String,
    pub value: ChannelValue,
}

/// An image shown behind the scene in the editor's viewport (a drawing or a filmed reference
/// to pose against); not rendered by `keyrig render`.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ReferenceImage {
    /// The image file (PNG, JPEG or BMP), relative to the scene file.
    pub path: String,
    /// How opaque it is drawn, 0 (not seen) to 1.
    #[serde(default = "default_opacity")]
    pub opacity: f32,
}

/// The opacity of a reference image when a scene file does not say.
#[must_use]
pub fn default_opacity() -> f32 {
    0.5
}

impl ReferenceImage {
    /// The image at `path` at the default opacity.
    #[must_use]
    pub fn new(path: impl Into<String>) -> Self {
        ReferenceImage { path: path.into(), opacity: default_opacity() }
    }
}
