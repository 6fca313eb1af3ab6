//! Mirroring a pose between the sides of a rig: joint names that mark a side (`hand.L` and
//! `hand.R`, `LeftArm` and `RightArm`, `thigh_l` and `thigh_r`) and values flipped across the
//! X axis, as Blender's Paste Flipped does. A rig whose joints' local axes are not mirror
//! images of each other gets mirrored names but not a mirrored look.

use glam::{Quat, Vec3};
use keyrig_core::channel_id::{ChannelId, ChannelValue};
use keyrig_core::Scene;

/// Pairs of side markers, tried in order. Suffixes with a separator, then whole words.
const SUFFIXES: [(&str, &str); 4] = [(".L", ".R"), (".l", ".r"), ("_L", "_R"), ("_l", "_r")];
const PREFIXES: [(&str, &str); 2] = [("L_", "R_"), ("l_", "r_")];
const WORDS: [(&str, &str); 3] = [("Left", "Right"), ("left", "right"), ("LEFT", "RIGHT")];

/// The name of the other side's joint, when `name` marks a side.
#[must_use]
pub fn mirrored_name(name: &str) -> Option<String> {
    for (a, b) in SUFFIXES {
        if let Some(stem) = name.strip_suffix(a) {
            return Some(format!("{stem}{b}"));
        }
        if let Some(stem) = name.strip_suffix(b) {
            return Some(format!("{stem}{a}"));
        }
    }
    for (a, b) in PREFIXES {
        if let Some(rest) = name.strip_prefix(a) {
            return Some(format!("{b}{rest}"));
        }
        if let Some(rest) = name.strip_prefix(b) {
            return Some(format!("{a}{rest}"));
        }
    }
    for (a, b) in WORDS {
        if name.contains(a) {
            return Some(name.replacen(a, b, 1));
        }
        if name.contains(b) {
            return Some(name.replacen(b, a, 1));
        }
    }
    None
}

/// The channel of the other side's joint in the same skeleton; the channel itself for a joint
/// without a side (a spine) or without a counterpart, and for objects and lights.
#[must_use]
pub fn mirror_channel(scene: &Scene, id: ChannelId) -> ChannelId {
    let (object, joint) = match id {
        ChannelId::JointTranslation { object, joint }
        | ChannelId::JointRotation { object, joint }
        | ChannelId::JointScale { object, joint } => (object, joint),
        _ => return id,
    };
    let Some(skeleton) = scene.objects.get(object).and_then(|o| o.skeleton.as_ref()) else { return id };
    let Some(other) = skeleton
        .joints
        .get(joint)
        .and_then(|j| mirrored_name(&j.name))
        .and_then(|name| skeleton.joints.iter().position(|j| j.name == name))
    else {
        return id;
    };
    match id {
        ChannelId::JointTranslation { .. } => ChannelId::JointTranslation { object, joint: other },
        ChannelId::JointRotation { .. } => ChannelId::JointRotation { object, joint: other },
        _ => ChannelId::JointScale { object, joint: other },
    }
}

/// A value of channel `id` mirrored across the X axis (the YZ plane): a translation's x
/// changes sign; a rotation keeps its x component and negates y and z (the same turn seen
/// in the mirror); scales and scalars stay.
#[must_use]
pub fn mirror_value(id: ChannelId, value: ChannelValue) -> ChannelValue {
    let is_scale = matches!(id, ChannelId::JointScale { .. } | ChannelId::ObjectScale(_));
    match value {
        ChannelValue::Vec3(v) if !is_scale => ChannelValue::Vec3(Vec3::new(-v.x, v.y, v.z)),
        ChannelValue::Rotation(q) => ChannelValue::Rotation(Quat::from_xyzw(q.x, -q.y, -q.z, q.w)),
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn side_markers_swap_and_others_have_none() {
        for (a, b) in [
            ("hand.L", "hand.R"),
            ("thigh_r", "thigh_l"),
            ("L_clavicle", "R_clavicle"),
            ("mixamorig:LeftArm", "mixamorig:RightArm"),
            ("right_foot", "left_foot"),
        ] {
            assert_eq!(mirrored_name(a).as_deref(), Some(b), "{a}");
            assert_eq!(mirrored_name(b).as_deref(), Some(a), "{b}");
        }
        assert_eq!(mirrored_name("spine"), None);
        assert_eq!(mirrored_name("Leg"), None, "a capital L alone is not a side");
    }

    #[test]
    fn a_mirrored_rotation_is_the_mirror_image_of_the_turn() {
        // Mirroring across the YZ plane is M = diag(−1, 1, 1); the mirrored rotation is
        // M·R·M, checked on the matrices.
        let q = Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        let ChannelValue::Rotation(m) =
            mirror_value(ChannelId::JointRotation { object: 0, joint: 0 }, ChannelValue::Rotation(q))
        else {
            panic!("a rotation")
        };
        let mirror = glam::Mat3::from_diagonal(Vec3::new(-1.0, 1.0, 1.0));
        let expected = mirror * glam::Mat3::from_quat(q) * mirror;
        let got = glam::Mat3::from_quat(m);
        assert!((expected - got).to_cols_array().iter().all(|d| d.abs() < 1e-6), "{expected:?} {got:?}");
        let scale = ChannelValue::Vec3(Vec3::new(2.0, 1.0, 1.0));
        assert_eq!(mirror_value(ChannelId::JointScale { object: 0, joint: 0 }, scale), scale);
        assert_eq!(
            mirror_value(ChannelId::JointTranslation { object: 0, joint: 0 }, ChannelValue::Vec3(Vec3::X)),
            ChannelValue::Vec3(Vec3::NEG_X)
        );
    }
}
