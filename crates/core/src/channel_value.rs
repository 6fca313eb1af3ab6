//! A value of any channel type ([`ChannelValue`]), apart from the channels themselves
//! ([`crate::channel_id`]) so that plain scene data (a pose of the pose library,
//! [`crate::pose_library`]) can hold one.

use glam::{Quat, Vec3};

/// A value of any channel type (a sample, the clipboard, pose overrides, a library pose).
#[derive(Clone, Copy, Debug, PartialEq, serde::Serialize, serde::Deserialize)]
pub enum ChannelValue {
    Vec3(Vec3),
    Rotation(Quat),
    Scalar(f32),
}
