//! The stored form of actions (docs/actions.md): a name and channels by path with their keys.
//! What actions do with a scene is [`crate::action`].

use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::key::Animated;

/// A named set of keyed channels.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Action {
    pub name: String,
    /// The action's channels that are not playing (those of objects it is not active on),
    /// sorted by path. Left out of a scene file while empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub channels: Vec<ActionChannel>,
}

/// One stored channel of an action.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ActionChannel {
    /// The channel path, as `keyrig sample --channel` names it.
    pub path: String,
    pub keys: ActionKeys,
}

/// The keys of a stored channel, by value type: the whole animated value (keys, cycles,
/// mute) as it was when the channel stopped playing.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ActionKeys {
    Vec3(Animated<Vec3>),
    Rotation(Animated<Quat>),
    Scalar(Animated<f32>),
}

impl ActionKeys {
    /// The number of keys.
    #[must_use]
    pub fn len(&self) -> usize {
        match self {
            ActionKeys::Vec3(a) => a.track.len(),
            ActionKeys::Rotation(a) => a.track.len(),
            ActionKeys::Scalar(a) => a.track.len(),
        }
    }

    /// True without keys.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// First and last key times (seconds).
    #[must_use]
    pub fn time_range(&self) -> Option<(f64, f64)> {
        match self {
            ActionKeys::Vec3(a) => a.key_time_range(),
            ActionKeys::Rotation(a) => a.key_time_range(),
            ActionKeys::Scalar(a) => a.key_time_range(),
        }
    }
}

impl<T> Animated<T> {
    /// First and last key times (seconds); `None` without keys.
    #[must_use]
    pub fn key_time_range(&self) -> Option<(f64, f64)> {
        Some((self.track.keys.first()?.time, self.track.keys.last()?.time))
    }
}
