//! Mirroring a pose across a character's symmetry plane, as Blender's Paste Flipped does, on
//! any rig: joints are paired by the side their names mark (`hand.L`/`hand.R`,
//! `LeftArm`/`RightArm`, `thigh_l`/`thigh_r`, `leg_joint_L_1`/`leg_joint_R_1`) and by mirrored
//! rest positions, and each joint's pose is reflected in the character's (object) space, so that
//! rigs whose left and right joints do not have mirror-image local axes (the common case in
//! glTF files) get a mirror image of the pose.
//!
//! The method. Let `Refl` be the reflection across the plane n·p = d and `M = I − 2nnᵀ` its
//! linear part. A joint frame F = (q, t) (object from joint: rotation q, origin t) seen in the
//! mirror, with its local axes reflected too so that it stays a rotation, is
//! `mirror(F) = Refl ∘ F ∘ M = (q̃, Refl(t))`, where q̃ is the rotation M·q·M (the same angle
//! about the reflected axis −M·v, so q̃ = (2(n·v)n − v, w) for q = (v, w)). For a pair j ↔ k
//! the rest frames B give the fixed correction `C_j = mirror(B(j))⁻¹ · B(k)` (identity when the
//! rig's local axes are mirror images; a half turn about some axis when they are not), and
//! the mirrored pose gives joint k the object-space frame `G(k) = mirror(F(j)) · C_j`: at rest
//! G(k) = B(k), and in any pose k's frame stands to the mirror image of j's as it does at rest.
//! The local values follow from the parents' new frames: with F(j) = F(p)·R(j)·T(j),
//! T(k) = (G(p)·R(k))⁻¹·G(k). Joint scales are copied unchanged (frames are composed without
//! scale).

use glam::{Quat, Vec3};
use keyrig_core::channel_id::{ChannelId, ChannelValue};
use keyrig_core::Scene;

/// The side a joint's name marks.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Side {
    Left,
    Right,
}

/// The words of a name: runs of letters or digits split at separators, at lower-to-upper case
/// changes (`LeftArm` → `Left`, `Arm`), before the last capital of a capital run followed by a
/// lower-case letter (`LArm` → `L`, `Arm`) and between letters and digits.
pub(crate) fn words(name: &str) -> Vec<&str> {
    let mut out = Vec::new();
    let chars: Vec<(usize, char)> = name.char_indices().collect();
    let mut start: Option<usize> = None;
    for (i, &(at, c)) in chars.iter().enumerate() {
        if !c.is_alphanumeric() {
            if let Some(s) = start.take() {
                out.push(&name[s..at]);
            }
            continue;
        }
        if let Some(s) = start {
            let prev = chars[i - 1].1;
            let next = chars.get(i + 1).map(|&(_, c)| c);
            let split = (prev.is_lowercase() && c.is_uppercase())
                || (prev.is_uppercase() && c.is_uppercase() && next.is_some_and(char::is_lowercase))
                || (prev.is_alphabetic() != c.is_alphabetic());
            if split {
                out.push(&name[s..at]);
                start = Some(at);
            }
        } else {
            start = Some(at);
        }
    }
    if let Some(s) = start {
        out.push(&name[s..]);
    }
    out
}

/// The side a joint name marks: a word `L`, `Left` (any case) or `R`, `Right`.
#[must_use]
pub fn side_of(name: &str) -> Option<Side> {
    words(name).into_iter().find_map(|w| match w.to_ascii_lowercase().as_str() {
        "l" | "left" => Some(Side::Left),
        "r" | "right" => Some(Side::Right),
        _ => None,
    })
}

/// The name with its side word swapped (`hand.L` → `hand.R`, `LeftArm` → `RightArm`), when it
/// marks a side.
#[must_use]
pub fn mirrored_name(name: &str) -> Option<String> {
    let words = words(name);
    let word = words.iter().find(|w| side_word(w).is_some())?;
    let at = word.as_ptr() as usize - name.as_ptr() as usize;
    let swapped = side_word(word)?;
    Some(format!("{}{}{}", &name[..at], swapped, &name[at + word.len()..]))
}

/// The other side's word in the same case (`L` → `R`, `left` → `right`, `LEFT` → `RIGHT`).
fn side_word(word: &str) -> Option<&'static str> {
    Some(match word {
        "L" => "R",
        "R" => "L",
        "l" => "r",
        "r" => "l",
        "Left" => "Right",
        "Right" => "Left",
        "left" => "right",
        "right" => "left",
        "LEFT" => "RIGHT",
        "RIGHT" => "LEFT",
        _ => return None,
    })
}

/// `q` at unit length, or the identity for a zero or non-finite quaternion.
fn unit_or_identity(q: Quat) -> Quat {
    let length = q.length();
    if length.is_finite() && length > 1e-12 {
        q / length
    } else {
        Quat::IDENTITY
    }
}

/// A rigid transform: rotate, then translate (object from joint).
#[derive(Clone, Copy, Debug, PartialEq)]
struct Rigid {
    rotation: Quat,
    translation: Vec3,
}

impl Rigid {
    const IDENTITY: Rigid = Rigid { rotation: Quat::IDENTITY, translation: Vec3::ZERO };

    fn new(rotation: Quat, translation: Vec3) -> Self {
        Rigid { rotation, translation }
    }

    /// `self ∘ other`.
    fn then(self, other: Rigid) -> Rigid {
        Rigid {
            rotation: (self.rotation * other.rotation).normalize(),
            translation: self.translation + self.rotation * other.translation,
        }
    }

    fn inverse(self) -> Rigid {
        let r = self.rotation.inverse();
        Rigid { rotation: r, translation: -(r * self.translation) }
    }
}

/// A plane of symmetry: the points p with `normal · p = offset`, in the object's space.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SymmetryPlane {
    /// Unit normal, pointing to the character's left side.
    pub normal: Vec3,
    pub offset: f32,
}

impl SymmetryPlane {
    /// The mirror image of a point.
    #[must_use]
    pub fn reflect_point(&self, p: Vec3) -> Vec3 {
        p - 2.0 * (self.normal.dot(p) - self.offset) * self.normal
    }

    /// The mirror image of a direction (a translation).
    #[must_use]
    pub fn reflect_vector(&self, v: Vec3) -> Vec3 {
        v - 2.0 * self.normal.dot(v) * self.normal
    }

    /// The rotation M·q·M seen in the mirror (M the reflection's linear part): the same angle
    /// about the reflected axis −M·v.
    #[must_use]
    pub fn reflect_rotation(&self, q: Quat) -> Quat {
        let v = Vec3::new(q.x, q.y, q.z);
        let m = 2.0 * self.normal.dot(v) * self.normal - v;
        Quat::from_xyzw(m.x, m.y, m.z, q.w)
    }

    /// Signed distance of a point from the plane.
    #[must_use]
    pub fn distance(&self, p: Vec3) -> f32 {
        self.normal.dot(p) - self.offset
    }

    fn reflect_frame(&self, f: Rigid) -> Rigid {
        Rigid::new(self.reflect_rotation(f.rotation), self.reflect_point(f.translation))
    }
}

/// Pairing tolerance: a counterpart's rest position lies within this fraction of the
/// skeleton's extent (its rest positions' bounding-box diagonal) of the mirror image.
const PAIR_TOLERANCE: f32 = 0.05;

/// How the joints of one skeleton mirror: the symmetry plane fitted to its rest pose, each
/// joint's counterpart, and the rest corrections `C_j` (module documentation).
#[derive(Clone, Debug)]
pub struct SkeletonMirror {
    /// The plane, in the object's space.
    pub plane: SymmetryPlane,
    /// The joint that takes joint j's mirrored pose: the other side's joint, j itself for a
    /// joint on the plane, `None` for a joint off the plane without a counterpart.
    pub counterpart: Vec<Option<usize>>,
    names: Vec<String>,
    parents: Vec<Option<usize>>,
    /// R(j): parent from joint at rest.
    rest: Vec<Rigid>,
    /// C_j = mirror(B(j))⁻¹·B(counterpart(j)).
    correction: Vec<Rigid>,
}

impl SkeletonMirror {
    /// Pairs the joints of `skeleton`: by the side their names mark and by mirrored rest
    /// positions, across the plane fitted to the pairs (the object's YZ plane through the
    /// joints' centre when no name marks a side).
    #[must_use]
    pub fn new(skeleton: &keyrig_core::Skeleton) -> Self {
        let n = skeleton.joints.len();
        let parents: Vec<Option<usize>> =
            skeleton.joints.iter().enumerate().map(|(j, joint)| joint.parent.filter(|&p| p < j)).collect();
        let rest: Vec<Rigid> = skeleton
            .joints
            .iter()
            .map(|joint| {
                let q = unit_or_identity(joint.rest_rotation);
                let t = if joint.rest_translation.is_finite() { joint.rest_translation } else { Vec3::ZERO };
                Rigid::new(q, t)
            })
            .collect();
        let names: Vec<String> = skeleton.joints.iter().map(|j| j.name.clone()).collect();
        let mut mirror = SkeletonMirror {
            plane: SymmetryPlane { normal: Vec3::X, offset: 0.0 },
            counterpart: vec![None; n],
            names,
            parents,
            rest,
            correction: vec![Rigid::IDENTITY; n],
        };
        let bind = mirror.frames(&vec![Rigid::IDENTITY; n], Vec3::ZERO);
        let positions: Vec<Vec3> = bind.iter().map(|f| f.translation).collect();
        let sides: Vec<Option<Side>> = mirror.names.iter().map(|name| side_of(name)).collect();
        let depth: Vec<usize> = {
            let mut d = vec![0; n];
            for j in 0..n {
                d[j] = mirror.parents[j].map_or(0, |p| d[p] + 1);
            }
            d
        };
        let (min, max) = positions
            .iter()
            .fold((Vec3::splat(f32::INFINITY), Vec3::splat(f32::NEG_INFINITY)), |(lo, hi), &p| {
                (lo.min(p), hi.max(p))
            });
        let extent = if n > 0 { (max - min).length() } else { 0.0 };
        let tolerance = (PAIR_TOLERANCE * extent).max(1e-6);
        let first = initial_plane(&positions, &sides);
        let pairing =
            |plane: &SymmetryPlane| pair_joints(plane, &positions, &sides, &mirror.names, &depth, tolerance);
        let counterpart = pairing(&first);
        let plane = fit_plane(&positions, &sides, &counterpart, first);
        mirror.counterpart = pairing(&plane);
        mirror.plane = plane;
        for j in 0..n {
            if let Some(k) = mirror.counterpart[j] {
                mirror.correction[j] = plane.reflect_frame(bind[j]).inverse().then(bind[k]);
            }
        }
        mirror
    }

    /// Object-space frames of every joint for local transforms `local` (rotation, translation
    /// of T(j)) and a root translation: F(j) = F(p)·R(j)·T(j).
    fn frames(&self, local: &[Rigid], root_translation: Vec3) -> Vec<Rigid> {
        let mut out: Vec<Rigid> = Vec::with_capacity(local.len());
        for (j, t) in local.iter().enumerate() {
            let parent = match self.parents[j] {
                Some(p) => out[p],
                None => Rigid::new(Quat::IDENTITY, root_translation),
            };
            out.push(parent.then(self.rest[j]).then(*t));
        }
        out
    }

    /// The pairs of joints on either side (each pair once, the left joint first where names
    /// tell).
    #[must_use]
    pub fn pairs(&self) -> Vec<(usize, usize)> {
        (0..self.counterpart.len())
            .filter_map(|j| self.counterpart[j].filter(|&k| k > j).map(|k| (j, k)))
            .map(|(j, k)| if side_of(&self.names[k]) == Some(Side::Left) { (k, j) } else { (j, k) })
            .collect()
    }

    /// The joints on the plane, which mirror onto themselves.
    #[must_use]
    pub fn on_plane(&self) -> Vec<usize> {
        (0..self.counterpart.len()).filter(|&j| self.counterpart[j] == Some(j)).collect()
    }

    /// The joints that could not be paired: off the plane with no joint at their mirror image.
    #[must_use]
    pub fn unpaired(&self) -> Vec<usize> {
        (0..self.counterpart.len()).filter(|&j| self.counterpart[j].is_none()).collect()
    }

    /// The mirror image of pose `source` on channels `channels` (joint rotations, translations
    /// and scales and the root translation of this skeleton), put on the joints' counterparts
    /// over pose `current`: each pasted joint k of a pair j ↔ k gets the local values that give
    /// it the object-space frame `mirror(F(j))·C_j` under its parents' new frames. Returns the
    /// counterparts' channels (`object`'s) and values; channels of unpaired joints are left
    /// out. Both poses must be of this skeleton.
    #[must_use]
    pub fn mirror_channels(
        &self,
        object: usize,
        source: &keyrig_skin::Pose,
        current: &keyrig_skin::Pose,
        channels: &[ChannelId],
    ) -> Vec<(ChannelId, ChannelValue)> {
        let n = self.counterpart.len();
        if source.len() != n || current.len() != n {
            return Vec::new();
        }
        let local = |pose: &keyrig_skin::Pose| -> Vec<Rigid> {
            (0..n)
                .map(|j| {
                    let q = unit_or_identity(pose.local_rotations[j]);
                    Rigid::new(q, pose.local_translations[j])
                })
                .collect()
        };
        let source_frames = self.frames(&local(source), source.root_translation);
        // For each target joint, the source joint whose rotation / translation / scale it takes.
        let (mut rotation_from, mut translation_from, mut scale_from) =
            (vec![None; n], vec![None; n], vec![None; n]);
        let mut root = current.root_translation;
        for &id in channels {
            match id {
                ChannelId::JointRotation { object: o, joint } if o == object && joint < n => {
                    if let Some(k) = self.counterpart[joint] {
                        rotation_from[k] = Some(joint);
                    }
                }
                ChannelId::JointTranslation { object: o, joint } if o == object && joint < n => {
                    if let Some(k) = self.counterpart[joint] {
                        translation_from[k] = Some(joint);
                    }
                }
                ChannelId::JointScale { object: o, joint } if o == object && joint < n => {
                    if let Some(k) = self.counterpart[joint] {
                        scale_from[k] = Some(joint);
                    }
                }
                ChannelId::RootTranslation(o) if o == object => {
                    root = self.plane.reflect_vector(source.root_translation);
                }
                _ => {}
            }
        }
        let mut new = local(current);
        let mut frames: Vec<Rigid> = Vec::with_capacity(n);
        for k in 0..n {
            let parent = match self.parents[k] {
                Some(p) => frames[p],
                None => Rigid::new(Quat::IDENTITY, root),
            };
            let base = parent.then(self.rest[k]);
            let target = |j: usize| self.plane.reflect_frame(source_frames[j]).then(self.correction[j]);
            if let Some(j) = rotation_from[k] {
                let q = (base.rotation.inverse() * target(j).rotation).normalize();
                // The sign nearest the current value, so that keys stay on one hemisphere.
                new[k].rotation = if q.dot(new[k].rotation) < 0.0 { -q } else { q };
            }
            if let Some(j) = translation_from[k] {
                new[k].translation = base.inverse().then(target(j)).translation;
            }
            frames.push(base.then(new[k]));
        }
        let mut out = Vec::new();
        if channels.contains(&ChannelId::RootTranslation(object)) {
            out.push((ChannelId::RootTranslation(object), ChannelValue::Vec3(root)));
        }
        for k in 0..n {
            if rotation_from[k].is_some() {
                out.push((
                    ChannelId::JointRotation { object, joint: k },
                    ChannelValue::Rotation(new[k].rotation),
                ));
            }
            if translation_from[k].is_some() {
                out.push((
                    ChannelId::JointTranslation { object, joint: k },
                    ChannelValue::Vec3(new[k].translation),
                ));
            }
            if let Some(j) = scale_from[k] {
                out.push((
                    ChannelId::JointScale { object, joint: k },
                    ChannelValue::Vec3(source.local_scales[j]),
                ));
            }
        }
        out
    }

    /// Says which joints pair, which lie on the plane and which could not be paired.
    #[must_use]
    pub fn describe(&self) -> String {
        let name = |j: usize| self.names[j].as_str();
        let pairs: Vec<String> =
            self.pairs().into_iter().map(|(a, b)| format!("{} ↔ {}", name(a), name(b))).collect();
        let mut text = format!(
            "{} pair(s): {}; {} on the plane",
            pairs.len(),
            if pairs.is_empty() { "none".to_owned() } else { pairs.join(", ") },
            self.on_plane().len()
        );
        let unpaired = self.unpaired();
        if !unpaired.is_empty() {
            let names: Vec<&str> = unpaired.into_iter().map(name).collect();
            text.push_str(&format!("; could not pair {}", names.join(", ")));
        }
        text
    }
}

/// A first plane: across the mean positions of the joints named left and right, or the
/// object's YZ plane through the joints' centre when no name marks a side.
fn initial_plane(positions: &[Vec3], sides: &[Option<Side>]) -> SymmetryPlane {
    let mean = |side: Side| {
        let (sum, count) = positions
            .iter()
            .zip(sides)
            .filter(|(_, s)| **s == Some(side))
            .fold((Vec3::ZERO, 0usize), |(sum, count), (p, _)| (sum + *p, count + 1));
        (count > 0).then(|| sum / count as f32)
    };
    if let (Some(left), Some(right)) = (mean(Side::Left), mean(Side::Right)) {
        if let Some(normal) = (left - right).try_normalize() {
            return SymmetryPlane { normal, offset: normal.dot(0.5 * (left + right)) };
        }
    }
    let centre = if positions.is_empty() {
        Vec3::ZERO
    } else {
        positions.iter().copied().sum::<Vec3>() / positions.len() as f32
    };
    SymmetryPlane { normal: Vec3::X, offset: centre.x }
}

/// The plane that best separates the pairs found: its normal the mean of the vectors from
/// each pair's right (or lower-side) joint to its left one, through the pairs' midpoints.
/// `fallback` when there are no pairs.
fn fit_plane(
    positions: &[Vec3],
    sides: &[Option<Side>],
    counterpart: &[Option<usize>],
    fallback: SymmetryPlane,
) -> SymmetryPlane {
    let mut sum = Vec3::ZERO;
    let mut mids = Vec::new();
    for (j, k) in counterpart.iter().enumerate().filter_map(|(j, k)| k.filter(|&k| k > j).map(|k| (j, k))) {
        let mut d = positions[j] - positions[k];
        let left_is_k = sides[k] == Some(Side::Left) || (sides[j].is_none() && d.dot(fallback.normal) < 0.0);
        if left_is_k {
            d = -d;
        }
        sum += d;
        mids.push(0.5 * (positions[j] + positions[k]));
    }
    match sum.try_normalize() {
        Some(normal) if !mids.is_empty() => {
            let offset = mids.iter().map(|m| normal.dot(*m)).sum::<f32>() / mids.len() as f32;
            SymmetryPlane { normal, offset }
        }
        _ => fallback,
    }
}

/// Each joint's counterpart across `plane`: a joint named by side takes the nearest joint of
/// the other side at its mirror image (the joint its name swaps to first, when near), an
/// unnamed joint on the plane itself, else the nearest unnamed joint at its mirror image;
/// pairs must choose each other.
fn pair_joints(
    plane: &SymmetryPlane,
    positions: &[Vec3],
    sides: &[Option<Side>],
    names: &[String],
    depth: &[usize],
    tolerance: f32,
) -> Vec<Option<usize>> {
    let n = positions.len();
    let by_name: std::collections::HashMap<&str, usize> =
        names.iter().enumerate().map(|(j, name)| (name.as_str(), j)).collect();
    let best = |j: usize| -> Option<usize> {
        if sides[j].is_none() && plane.distance(positions[j]).abs() <= 0.5 * tolerance {
            return Some(j);
        }
        let image = plane.reflect_point(positions[j]);
        let swapped = mirrored_name(&names[j]).and_then(|name| by_name.get(name.as_str()).copied());
        let compatible = |k: usize| match (sides[j], sides[k]) {
            (Some(a), Some(b)) => a != b,
            (None, None) => k != j,
            _ => false,
        };
        (0..n)
            .filter(|&k| compatible(k))
            .filter_map(|k| {
                let distance = positions[k].distance(image);
                if distance > tolerance {
                    return None;
                }
                // Names and the hierarchy break ties between joints at one place.
                let name_bonus = if swapped == Some(k) { 0.5 * tolerance } else { 0.0 };
                let depth_penalty = 0.1 * tolerance * depth[j].abs_diff(depth[k]) as f32;
                Some((k, distance - name_bonus + depth_penalty))
            })
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(k, _)| k)
    };
    let chosen: Vec<Option<usize>> = (0..n).map(best).collect();
    (0..n).map(|j| chosen[j].filter(|&k| k == j || chosen[k] == Some(j))).collect()
}

/// A mirrored paste: the values to set and what was paired.
#[derive(Clone, Debug, PartialEq)]
pub struct MirroredPaste {
    pub values: Vec<(ChannelId, ChannelValue)>,
    /// Per character: which joints paired, which lie on the plane, which could not be paired.
    pub report: String,
}

/// The copied pose `clipboard` mirrored across each character's symmetry plane
/// ([`SkeletonMirror`]): joint channels go to the counterparts with mirrored values, the root
/// translation is reflected, an object's own transform is pasted as it was (the character's
/// space is its own), IK channels are left out. `current_pose(object)` is the object's pose
/// now (what the copied channels are laid over).
#[must_use]
pub fn mirror_clipboard(
    scene: &Scene,
    clipboard: &[(ChannelId, ChannelValue)],
    current_pose: impl Fn(usize) -> Option<keyrig_skin::Pose>,
) -> MirroredPaste {
    let mut values = Vec::new();
    let mut reports = Vec::new();
    let mut objects: Vec<usize> = Vec::new();
    let mut left_out = 0;
    for &(id, value) in clipboard {
        match id {
            ChannelId::JointRotation { object, .. }
            | ChannelId::JointTranslation { object, .. }
            | ChannelId::JointScale { object, .. }
            | ChannelId::RootTranslation(object) => {
                if !objects.contains(&object) {
                    objects.push(object);
                }
            }
            ChannelId::IkTarget { .. } | ChannelId::IkBlend { .. } => left_out += 1,
            _ => values.push((id, value)),
        }
    }
    for object in objects {
        let Some(skeleton) = scene.objects.get(object).and_then(|o| o.skeleton.as_ref()) else { continue };
        let Some(current) = current_pose(object).filter(|p| p.len() == skeleton.joints.len()) else {
            continue;
        };
        let mut source = current.clone();
        let mut channels = Vec::new();
        for &(id, value) in clipboard {
            match (id, value) {
                (ChannelId::JointRotation { object: o, joint }, ChannelValue::Rotation(q)) if o == object => {
                    if let Some(r) = source.local_rotations.get_mut(joint) {
                        *r = q;
                        channels.push(id);
                    }
                }
                (ChannelId::JointTranslation { object: o, joint }, ChannelValue::Vec3(v)) if o == object => {
                    if let Some(t) = source.local_translations.get_mut(joint) {
                        *t = v;
                        channels.push(id);
                    }
                }
                (ChannelId::JointScale { object: o, joint }, ChannelValue::Vec3(v)) if o == object => {
                    if let Some(s) = source.local_scales.get_mut(joint) {
                        *s = v;
                        channels.push(id);
                    }
                }
                (ChannelId::RootTranslation(o), ChannelValue::Vec3(v)) if o == object => {
                    source.root_translation = v;
                    channels.push(id);
                }
                _ => {}
            }
        }
        let mirror = SkeletonMirror::new(skeleton);
        values.extend(mirror.mirror_channels(object, &source, &current, &channels));
        reports.push(format!("{}: {}", scene.objects[object].name, mirror.describe()));
    }
    if left_out > 0 {
        reports.push(format!("{left_out} IK channel(s) left out"));
    }
    MirroredPaste { values, report: reports.join(". ") }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::{Affine3A, Mat3};

    #[test]
    fn side_markers_swap_and_others_have_none() {
        for (a, b) in [
            ("hand.L", "hand.R"),
            ("thigh_r", "thigh_l"),
            ("L_clavicle", "R_clavicle"),
            ("mixamorig:LeftArm", "mixamorig:RightArm"),
            ("right_foot", "left_foot"),
            ("leg_joint_L_1", "leg_joint_R_1"),
            ("b_LeftUpperArm_09", "b_RightUpperArm_09"),
            ("Skeleton_arm_joint_L__4_", "Skeleton_arm_joint_R__4_"),
        ] {
            assert_eq!(mirrored_name(a).as_deref(), Some(b), "{a}");
            assert_eq!(mirrored_name(b).as_deref(), Some(a), "{b}");
        }
        assert_eq!(side_of("b_LeftUpperArm_09"), Some(Side::Left));
        assert_eq!(side_of("Skeleton_arm_joint_R"), Some(Side::Right));
        for name in ["spine", "Leg", "Rib", "torso_joint_3", "LR"] {
            assert_eq!(side_of(name), None, "{name}");
            assert_eq!(mirrored_name(name), None, "{name}");
        }
    }

    #[test]
    fn a_reflected_rotation_is_m_r_m_for_any_plane() {
        // M = I − 2nnᵀ; the rotation seen in the mirror is M·R·M, checked on the matrices.
        let q = Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        for normal in [Vec3::X, Vec3::new(0.3, -0.5, 0.8).normalize()] {
            let plane = SymmetryPlane { normal, offset: 0.4 };
            let m = Mat3::IDENTITY
                - 2.0 * Mat3::from_cols(normal * normal.x, normal * normal.y, normal * normal.z);
            let expected = m * Mat3::from_quat(q) * m;
            let got = Mat3::from_quat(plane.reflect_rotation(q));
            let diff = (expected - got).to_cols_array().iter().fold(0.0f32, |a, d| a.max(d.abs()));
            assert!(diff < 1e-5, "{normal}: {expected:?} vs {got:?}");
            let p = Vec3::new(1.0, 2.0, -3.0);
            let r = plane.reflect_point(p);
            assert!(
                (plane.distance(r) + plane.distance(p)).abs() < 1e-5 && (r - p).cross(normal).length() < 1e-5
            );
        }
    }

    /// A spine with two arms of two bones whose rest positions are mirror images across X = 0
    /// but whose local axes are not: the right arm's joints have arbitrary rest rotations.
    fn lopsided_rig() -> keyrig_core::Skeleton {
        let left_rotation = Quat::from_euler(glam::EulerRot::XYZ, 0.2, 0.1, -1.2);
        let right_rotation = Quat::from_euler(glam::EulerRot::XYZ, 2.5, -0.9, 0.4);
        let hand_left = Vec3::new(0.5, 0.1, 0.05);
        // The right hand's rest offset in the right arm's frame such that its position is the
        // mirror image of the left hand's.
        let mirror = Vec3::new(-1.0, 1.0, 1.0);
        let hand_right = right_rotation.inverse() * ((left_rotation * hand_left) * mirror);
        let joint = |name: &str, parent, at, q| keyrig_core::Joint::new(name, parent, at, q);
        keyrig_core::Skeleton::new(vec![
            joint("spine", None, Vec3::new(0.0, 1.0, 0.0), Quat::from_rotation_y(0.3)),
            joint(
                "arm.L",
                Some(0),
                Quat::from_rotation_y(-0.3) * Vec3::new(0.2, 0.5, 0.0),
                Quat::from_rotation_y(-0.3) * left_rotation,
            ),
            joint("hand.L", Some(1), hand_left, Quat::from_rotation_x(0.7)),
            joint(
                "arm.R",
                Some(0),
                Quat::from_rotation_y(-0.3) * Vec3::new(-0.2, 0.5, 0.0),
                Quat::from_rotation_y(-0.3) * right_rotation,
            ),
            joint("hand.R", Some(3), hand_right, Quat::from_rotation_z(-1.3)),
        ])
    }

    /// Object-space joint positions of a pose, composed with glam's affine matrices (not the
    /// module's own rigid frames).
    fn positions(skeleton: &keyrig_core::Skeleton, pose: &keyrig_skin::Pose) -> Vec<Vec3> {
        let mut frames: Vec<Affine3A> = Vec::new();
        for (j, joint) in skeleton.joints.iter().enumerate() {
            let parent =
                joint.parent.map_or(Affine3A::from_translation(pose.root_translation), |p| frames[p]);
            let rest = Affine3A::from_rotation_translation(joint.rest_rotation, joint.rest_translation);
            let local =
                Affine3A::from_rotation_translation(pose.local_rotations[j], pose.local_translations[j]);
            frames.push(parent * rest * local);
        }
        frames.iter().map(|f| f.translation.into()).collect()
    }

    #[test]
    fn a_rig_with_unmirrored_axes_gets_a_mirror_image_of_the_pose() {
        let skeleton = lopsided_rig();
        let mirror = SkeletonMirror::new(&skeleton);
        assert_eq!(mirror.counterpart, vec![Some(0), Some(3), Some(4), Some(1), Some(2)]);
        assert!((mirror.plane.normal - Vec3::X).length() < 1e-5, "{:?}", mirror.plane);
        assert!(mirror.plane.offset.abs() < 1e-5);
        let mut source = keyrig_skin::Pose::rest(5);
        source.local_rotations[0] = Quat::from_rotation_z(0.25);
        source.local_rotations[1] = Quat::from_euler(glam::EulerRot::XYZ, 0.4, -0.8, 0.3);
        source.local_rotations[2] = Quat::from_rotation_y(1.1);
        source.root_translation = Vec3::new(0.3, 0.1, -0.2);
        let channels: Vec<ChannelId> = (0..5)
            .map(|joint| ChannelId::JointRotation { object: 0, joint })
            .chain([ChannelId::RootTranslation(0)])
            .collect();
        let current = keyrig_skin::Pose::rest(5);
        let mut mirrored = current.clone();
        for (id, value) in mirror.mirror_channels(0, &source, &current, &channels) {
            match (id, value) {
                (ChannelId::JointRotation { joint, .. }, ChannelValue::Rotation(q)) => {
                    mirrored.local_rotations[joint] = q
                }
                (ChannelId::RootTranslation(_), ChannelValue::Vec3(v)) => mirrored.root_translation = v,
                other => panic!("unexpected {other:?}"),
            }
        }
        let before = positions(&skeleton, &source);
        let after = positions(&skeleton, &mirrored);
        let reflect = |p: Vec3| Vec3::new(-p.x, p.y, p.z);
        for (j, k) in [(0, 0), (1, 3), (2, 4), (3, 1), (4, 2)] {
            assert!(
                (after[k] - reflect(before[j])).length() < 1e-4,
                "joint {k} at {} is the mirror image of joint {j} at {}",
                after[k],
                before[j]
            );
        }
        // The old way (flipping each local rotation's y and z) puts the right hand elsewhere.
        let mut naive = current.clone();
        for j in 0..5 {
            let q = source.local_rotations[j];
            let k = [0, 3, 4, 1, 2][j];
            naive.local_rotations[k] = Quat::from_xyzw(q.x, -q.y, -q.z, q.w);
        }
        naive.root_translation = reflect(source.root_translation);
        assert!((positions(&skeleton, &naive)[4] - reflect(before[2])).length() > 0.1);
    }

    #[test]
    fn an_unnamed_joint_off_the_plane_without_a_partner_is_reported() {
        let mut skeleton = lopsided_rig();
        skeleton.joints.push(keyrig_core::Joint::new(
            "prop",
            Some(0),
            Vec3::new(0.6, 0.0, 0.0),
            Quat::IDENTITY,
        ));
        let mirror = SkeletonMirror::new(&skeleton);
        assert_eq!(mirror.unpaired(), vec![5]);
        assert_eq!(mirror.pairs(), vec![(1, 3), (2, 4)]);
        let text = mirror.describe();
        assert!(text.contains("arm.L ↔ arm.R") && text.contains("could not pair prop"), "{text}");
    }
}
