//! The automatic bone map: each joint's place in a humanoid ([`Slot`]) read from its name, with
//! a few structural rules where names alone do not say (docs/retargeting.md, "The bone map").

use glam::Vec3;
use keyrig_core::Skeleton;
use serde::{Deserialize, Serialize};

use crate::mirror::{side_of, words, Side};

/// The side a name marks: `L`, `Left`, `R`, `Right` as [`side_of`] reads them, or the French
/// `gauche`, `droit`, `droite` (the FBX corpus's barbarian).
fn side_in(name: &str) -> Option<Side> {
    side_of(name).or_else(|| {
        words(name).into_iter().find_map(|w| match w.to_lowercase().as_str() {
            "gauche" => Some(Side::Left),
            "droit" | "droite" => Some(Side::Right),
            _ => None,
        })
    })
}

/// A bone of a limb, on one side.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Limb {
    /// The clavicle (`LeftShoulder` in Mixamo, `LeftCollar` in CMU takes).
    Collar,
    UpperArm,
    LowerArm,
    Hand,
    UpperLeg,
    LowerLeg,
    Foot,
    Toe,
}

/// Where a joint sits in a humanoid.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Slot {
    Hips,
    /// The lowest spine joint above the hips.
    Spine,
    /// The highest spine joint (below the neck and the collars).
    Chest,
    Neck,
    Head,
    Left(Limb),
    Right(Limb),
}

impl Slot {
    /// The limb slot on `side`.
    #[must_use]
    pub fn limb(side: Side, limb: Limb) -> Slot {
        match side {
            Side::Left => Slot::Left(limb),
            Side::Right => Slot::Right(limb),
        }
    }

    /// The limb bone, for the slots of a side.
    #[must_use]
    pub fn limb_of(self) -> Option<(Side, Limb)> {
        match self {
            Slot::Left(limb) => Some((Side::Left, limb)),
            Slot::Right(limb) => Some((Side::Right, limb)),
            _ => None,
        }
    }

    /// Whether the slot lies on the body's centre line (hips, spine, neck, head).
    #[must_use]
    pub fn is_central(self) -> bool {
        self.limb_of().is_none()
    }
}

/// What one name says, before the structural rules decide between candidates.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Kind {
    Hips,
    /// `Root`: the hips only when nothing is named hips or pelvis.
    Root,
    Spine,
    Chest,
    Neck,
    Head,
    Collar,
    /// `Shoulder`: the upper arm where the same side also has a collar or clavicle (the CMU
    /// takes' `LeftCollar` / `LeftShoulder`), else the clavicle (Mixamo's `LeftShoulder`).
    Shoulder,
    UpperArm,
    LowerArm,
    Hand,
    UpperLeg,
    LowerLeg,
    Foot,
    Toe,
    /// A numbered `arm` (`arm_joint_L_3`): the side's arm joints in chain order.
    ArmChain,
    /// A numbered `leg` (`leg_joint_L_2`): the side's leg joints in chain order.
    LegChain,
}

/// Words that name no body part: rig prefixes and filler (`mixamorig:`, `Bip01`, `DEF-`,
/// `_joint`, `Skeleton_`).
const FILLER: &[&str] = &[
    "mixamorig",
    "bip",
    "def",
    "org",
    "mch",
    "b",
    "bn",
    "bone",
    "jnt",
    "joint",
    "skeleton",
    "armature",
    "rig",
    "character",
    "j",
    "c",
    "cc",
    "base",
    "bind",
];

/// Words of joints that are never mapped: fingers, helpers, end sites.
const SKIP: &[&str] = &[
    "thumb", "index", "middle", "ring", "pinky", "pinkie", "finger", "fingers", "twist", "roll", "ik",
    "pole", "target", "end", "nub", "top", "site", "ctrl", "control", "hair", "weapon",
];

/// What a name says: the kind of body part and its side.
type Named = (Kind, Option<Side>);

/// The kind of body part a name says and its side.
fn kind_of(name: &str) -> Option<Named> {
    let side = side_in(name);
    let all = words(name);
    let numbered = all.iter().any(|w| w.chars().all(|c| c.is_ascii_digit()));
    let lower: Vec<String> = all
        .iter()
        .map(|w| w.to_lowercase())
        .filter(|w| !matches!(w.as_str(), "l" | "r" | "left" | "right" | "gauche" | "droit" | "droite"))
        .filter(|w| !w.chars().all(|c| c.is_ascii_digit()))
        .collect();
    if lower.iter().any(|w| SKIP.contains(&w.as_str())) {
        return None;
    }
    let key: String = lower
        .iter()
        .filter(|w| !FILLER.contains(&w.as_str()))
        .map(String::as_str)
        .collect::<Vec<_>>()
        .concat();
    let sided = side.is_some();
    let kind = match key.as_str() {
        "hips" | "pelvis" | "bassin" => Kind::Hips,
        "hip" if !sided => Kind::Hips,
        "root" if !sided => Kind::Root,
        "spine" | "lowerback" | "back" | "abdomen" | "torso" | "waist" | "torse" => Kind::Spine,
        "chest" | "upperchest" | "thorax" => Kind::Chest,
        "neck" | "lowerneck" | "upperneck" | "cou" => Kind::Neck,
        "head" | "tête" | "tete" => Kind::Head,
        "collar" | "clavicle" | "clav" | "collarbone" => Kind::Collar,
        "shoulder" if sided => Kind::Shoulder,
        "arm" if sided && numbered => Kind::ArmChain,
        "upperarm" | "uparm" | "humerus" | "arm" | "bras" if sided => Kind::UpperArm,
        "forearm" | "lowerarm" | "elbow" | "radius" | "ulna" | "avantbras" if sided => Kind::LowerArm,
        "hand" | "wrist" | "main" if sided => Kind::Hand,
        "leg" if sided && numbered => Kind::LegChain,
        "upleg" | "upperleg" | "thigh" | "femur" | "hip" | "hipjoint" | "cuisse" | "jambe" if sided => {
            Kind::UpperLeg
        }
        "leg" | "lowerleg" | "shin" | "calf" | "knee" | "tibia" | "crus" if sided => Kind::LowerLeg,
        "foot" | "ankle" | "pied" if sided => Kind::Foot,
        "toe" | "toebase" | "toes" | "ball" | "orteil" if sided => Kind::Toe,
        // A plain "arm" joint of a numbered chain (`arm_joint_R` beside `arm_joint_R_2`).
        _ => return None,
    };
    Some((kind, side))
}

/// Each joint's slot, `None` where the joint has no place in the map (fingers, helpers,
/// extra spine joints, joints of another character).
///
/// Names first (module `names`, docs/retargeting.md); then, among several candidates for one
/// slot, joints that sit on their parent (a zero rest offset, as the CMU takes' `LHipJoint` and
/// `lowerneck`) give way to those that do not, and the one nearest the root wins — but the
/// chest is the highest spine joint. With nothing named hips, the hips are the joint where the
/// legs branch; limb joints must lie below the hips (the FBX barbarian's loose `pied
/// gauche.001` helpers do not).
#[must_use]
pub fn skeleton_slots(skeleton: &Skeleton) -> Vec<Option<Slot>> {
    let joints = &skeleton.joints;
    let n = joints.len();
    let kinds: Vec<Option<Named>> = joints.iter().map(|j| kind_of(&j.name)).collect();
    let extent = skeleton_extent(skeleton);
    let on_parent =
        |j: usize| joints[j].parent.is_some() && joints[j].rest_translation.length() <= 1e-4 * extent;
    let is_below = |j: usize, ancestor: usize| {
        let mut at = joints[j].parent;
        while let Some(p) = at {
            if p == ancestor {
                return true;
            }
            at = joints[p].parent.filter(|&q| q < p);
        }
        false
    };
    // Candidates per slot, in joint order (parents first).
    let mut candidates: Vec<(Slot, usize)> = Vec::new();
    for side in [Side::Left, Side::Right] {
        let of_side = |k: Kind| -> Vec<usize> {
            (0..n).filter(|&j| kinds[j].is_some_and(|(kind, s)| kind == k && s == Some(side))).collect()
        };
        let has_collar = !of_side(Kind::Collar).is_empty();
        for (kind, limb) in [
            (Kind::Collar, Limb::Collar),
            (Kind::UpperArm, Limb::UpperArm),
            (Kind::LowerArm, Limb::LowerArm),
            (Kind::Hand, Limb::Hand),
            (Kind::UpperLeg, Limb::UpperLeg),
            (Kind::LowerLeg, Limb::LowerLeg),
            (Kind::Foot, Limb::Foot),
            (Kind::Toe, Limb::Toe),
        ] {
            candidates.extend(of_side(kind).into_iter().map(|j| (Slot::limb(side, limb), j)));
        }
        let shoulder = if has_collar { Limb::UpperArm } else { Limb::Collar };
        candidates.extend(of_side(Kind::Shoulder).into_iter().map(|j| (Slot::limb(side, shoulder), j)));
        // Numbered chains: the side's arm (or leg) joints in chain order.
        let arm_chain = of_side(Kind::ArmChain);
        if !arm_chain.is_empty() {
            let mut chain = arm_chain;
            chain.extend(of_side(Kind::UpperArm));
            chain.sort_unstable();
            candidates.retain(|&(slot, j)| !(chain.contains(&j) && slot.limb_of().is_some()));
            let limbs: &[Limb] = match chain.len() {
                2 => &[Limb::UpperArm, Limb::LowerArm],
                3 => &[Limb::UpperArm, Limb::LowerArm, Limb::Hand],
                _ => &[Limb::Collar, Limb::UpperArm, Limb::LowerArm, Limb::Hand],
            };
            candidates.extend(chain.iter().zip(limbs).map(|(&j, &limb)| (Slot::limb(side, limb), j)));
        }
        let leg_chain = of_side(Kind::LegChain);
        if leg_chain.len() >= 2 {
            let limbs = [Limb::UpperLeg, Limb::LowerLeg, Limb::Foot, Limb::Toe];
            candidates.extend(leg_chain.iter().zip(limbs).map(|(&j, limb)| (Slot::limb(side, limb), j)));
        }
    }
    let central =
        |k: Kind| -> Vec<usize> { (0..n).filter(|&j| kinds[j].is_some_and(|(kind, _)| kind == k)).collect() };
    let mut spine = central(Kind::Spine);
    let mut chest = central(Kind::Chest);
    let mut neck = central(Kind::Neck);
    let mut head = central(Kind::Head);

    // The hips: named, else where the upper legs branch, else a joint named root.
    let pick_first = |list: &[usize]| -> Option<usize> {
        list.iter().copied().find(|&j| !on_parent(j)).or_else(|| list.first().copied())
    };
    let upper_leg = |side| {
        let list: Vec<usize> = candidates
            .iter()
            .filter(|&&(s, _)| s == Slot::limb(side, Limb::UpperLeg))
            .map(|&(_, j)| j)
            .collect();
        pick_first(&list)
    };
    let hips = pick_first(&central(Kind::Hips))
        .or_else(|| {
            let (l, r) = (upper_leg(Side::Left)?, upper_leg(Side::Right)?);
            (0..n).rev().find(|&a| is_below(l, a) && is_below(r, a))
        })
        .or_else(|| pick_first(&central(Kind::Root)));
    if let Some(h) = hips {
        candidates.retain(|&(_, j)| is_below(j, h));
        for list in [&mut spine, &mut chest, &mut neck, &mut head] {
            list.retain(|&j| j != h && is_below(j, h));
        }
    }
    // Several spine joints and none named chest: the last is the chest (Mixamo's Spine2).
    if chest.is_empty() && spine.len() >= 2 {
        chest.push(spine.pop().unwrap_or_default());
    }
    if head.is_empty() && neck.len() >= 2 {
        head.push(neck.pop().unwrap_or_default());
    }

    let mut slots = vec![None; n];
    if let Some(h) = hips {
        slots[h] = Some(Slot::Hips);
    }
    let mut place = |slot: Slot, j: Option<usize>| {
        if let Some(j) = j {
            if slots[j].is_none() {
                slots[j] = Some(slot);
            }
        }
    };
    place(Slot::Spine, pick_first(&spine));
    place(Slot::Chest, chest.iter().rev().copied().find(|&j| !on_parent(j)).or(chest.last().copied()));
    place(Slot::Neck, pick_first(&neck));
    place(Slot::Head, pick_first(&head));
    for side in [Side::Left, Side::Right] {
        for limb in [
            Limb::Collar,
            Limb::UpperArm,
            Limb::LowerArm,
            Limb::Hand,
            Limb::UpperLeg,
            Limb::LowerLeg,
            Limb::Foot,
            Limb::Toe,
        ] {
            let slot = Slot::limb(side, limb);
            let list: Vec<usize> = candidates.iter().filter(|&&(s, _)| s == slot).map(|&(_, j)| j).collect();
            let mut sorted = list;
            sorted.sort_unstable();
            sorted.dedup();
            place(slot, pick_first(&sorted));
        }
    }
    slots
}

/// The diagonal of the rest joint positions' bounding box (1 for a skeleton without extent).
fn skeleton_extent(skeleton: &Skeleton) -> f32 {
    let mut positions: Vec<Vec3> = Vec::with_capacity(skeleton.joints.len());
    for joint in &skeleton.joints {
        let p = match joint.parent.filter(|&p| p < positions.len()) {
            Some(p) => positions[p] + joint.rest_translation,
            None => joint.rest_translation,
        };
        positions.push(p);
    }
    let (lo, hi) = positions
        .iter()
        .fold((Vec3::splat(f32::MAX), Vec3::splat(f32::MIN)), |(lo, hi), &p| (lo.min(p), hi.max(p)));
    let d = (hi - lo).length();
    if d.is_finite() && d > 0.0 {
        d
    } else {
        1.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn names_of_the_common_rigs() {
        let cases: &[(&str, Option<Named>)] = &[
            ("mixamorig:LeftUpLeg", Some((Kind::UpperLeg, Some(Side::Left)))),
            ("mixamorig:RightLeg", Some((Kind::LowerLeg, Some(Side::Right)))),
            ("mixamorig:LeftToeBase", Some((Kind::Toe, Some(Side::Left)))),
            ("mixamorig:Spine2", Some((Kind::Spine, None))),
            ("mixamorig:LeftHandIndex1", None),
            ("Bip01 L Thigh", Some((Kind::UpperLeg, Some(Side::Left)))),
            ("Bip01 R Calf", Some((Kind::LowerLeg, Some(Side::Right)))),
            ("Bip01 Pelvis", Some((Kind::Hips, None))),
            ("thigh.L", Some((Kind::UpperLeg, Some(Side::Left)))),
            ("shin.R", Some((Kind::LowerLeg, Some(Side::Right)))),
            ("upper_arm.L", Some((Kind::UpperArm, Some(Side::Left)))),
            ("forearm_r", Some((Kind::LowerArm, Some(Side::Right)))),
            ("LeftKnee", Some((Kind::LowerLeg, Some(Side::Left)))),
            ("LeftCollar", Some((Kind::Collar, Some(Side::Left)))),
            ("LeftShoulder", Some((Kind::Shoulder, Some(Side::Left)))),
            ("LHipJoint", Some((Kind::UpperLeg, Some(Side::Left)))),
            ("Head_end", None),
            ("leg_joint_L_3", Some((Kind::LegChain, Some(Side::Left)))),
            ("Skeleton_arm_joint_R__2_", Some((Kind::ArmChain, Some(Side::Right)))),
            ("Skeleton_arm_joint_R", Some((Kind::UpperArm, Some(Side::Right)))),
            ("pied gauche", Some((Kind::Foot, Some(Side::Left)))),
        ];
        for (name, expected) in cases {
            assert_eq!(kind_of(name), *expected, "{name}");
        }
    }
}
