//! Retargeting (docs/retargeting.md): an action of one rig played by another.
//!
//! 1. **Bone map** ([`BoneMap`]): pairs of joint names, made from the joints' names
//!    ([`BoneMap::automatic`], through each joint's humanoid [`Slot`]) or read from a file and
//!    edited.
//! 2. **Rest alignment.** Each mapped target joint `j` (source joint `s`) gets a fixed world
//!    rotation `C(j)` that turns its rest bones onto the source's rest bones (the directions to
//!    its mapped children; with several children the centre-line child exactly and the
//!    left–right line as nearly as it can): a target in an A-pose is first brought into the
//!    source's T-pose. Then, per frame, with `W` world rotations,
//!    `W_target(j) = W_source(s) · W_source_rest(s)⁻¹ · C(j) · W_target_rest(j)`, and the local
//!    rotation is `T(j) = (W(parent) · R(j))⁻¹ · W_target(j)`. A mapped bone therefore points
//!    where the source's bone points; unmapped target joints keep their static pose.
//! 3. **Root motion.** The hips' world position follows the source's, scaled by the ratio of
//!    leg lengths `k = L_target / L_source` (rest lengths of the mapped leg bones):
//!    horizontally `p = p_rest + k·(s(t) − s(0))`, vertically
//!    `y = g_target + k·(y_source(t) − g_source)`, `g` the feet's ground height (the target's
//!    rest feet; the source's lowest feet over the take).
//! 4. **Foot contacts.** A source foot is planted where it is within `max_height` leg lengths of
//!    its lowest point and moves slower than `max_speed` leg lengths per second, for at least
//!    `min_seconds`. During each contact the target's foot is held at one point (the mean of
//!    its position there) by the two-bone IK ([`keyrig_core::ik::solve_two_bone`]), bending
//!    towards where the copied knee bends; the hold blends in and out over `blend_seconds`
//!    around the contact (the IK target slides between the copied foot and the planted point)
//!    and the foot keeps its copied world rotation.
//!
//! The result is an ordinary action on the target object: a rotation key per frame on every
//! mapped joint and a translation key per frame on the hips, optionally reduced afterwards
//! ([`crate::cleanup::reduce_keys`]).

pub mod names;

use glam::{Affine3A, Mat3, Quat, Vec3};
use keyrig_core::channel_id::ChannelId;
use keyrig_core::ik::{solve_two_bone, IkChain, Pole};
use keyrig_core::{
    Animated, AnimatedTrack, EulerOrder, Key, Object, RawTrack, RotationMode, Scene, Skeleton,
};
use serde::{Deserialize, Serialize};

pub use names::{skeleton_slots, Limb, Slot};

use crate::cleanup::{reduce_keys, CleanupReport, ReduceTolerance};
use crate::mirror::Side;

/// One pair of the bone map: the source joint whose motion the target joint takes.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub struct BonePair {
    pub source: String,
    pub target: String,
}

/// Which source joint drives which target joint, by name. Each target joint appears at most
/// once; a source joint may drive several target joints.
#[derive(Clone, Debug, Default, PartialEq, Eq, Serialize, Deserialize)]
pub struct BoneMap {
    pub pairs: Vec<BonePair>,
}

impl BoneMap {
    /// The map made from the joints' names: every slot ([`skeleton_slots`]) both skeletons
    /// have, in the target's joint order.
    #[must_use]
    pub fn automatic(source: &Skeleton, target: &Skeleton) -> BoneMap {
        let source_slots = skeleton_slots(source);
        let target_slots = skeleton_slots(target);
        let pairs = target_slots
            .iter()
            .enumerate()
            .filter_map(|(t, slot)| {
                let slot = (*slot)?;
                let s = source_slots.iter().position(|x| *x == Some(slot))?;
                Some(BonePair {
                    source: source.joints[s].name.clone(),
                    target: target.joints[t].name.clone(),
                })
            })
            .collect();
        BoneMap { pairs }
    }

    /// The source joint that drives `target`.
    #[must_use]
    pub fn source_of(&self, target: &str) -> Option<&str> {
        self.pairs.iter().find(|p| p.target == target).map(|p| p.source.as_str())
    }

    /// Makes `source` drive `target` (`None`: `target` is not driven), replacing its pair.
    pub fn set(&mut self, target: &str, source: Option<&str>) {
        self.pairs.retain(|p| p.target != target);
        if let Some(source) = source {
            self.pairs.push(BonePair { source: source.to_owned(), target: target.to_owned() });
        }
    }

    /// The pairs as joint indices (source, target), in the target's joint order.
    ///
    /// # Errors
    /// [`RetargetError::UnknownJoint`] for a name a skeleton does not have,
    /// [`RetargetError::TargetTwice`] for a target joint in two pairs.
    pub fn resolve(
        &self,
        source: &Skeleton,
        target: &Skeleton,
    ) -> Result<Vec<(usize, usize)>, RetargetError> {
        let find = |skeleton: &Skeleton, name: &str, side: &'static str| {
            skeleton
                .joints
                .iter()
                .position(|j| j.name == name)
                .ok_or_else(|| RetargetError::UnknownJoint { side, name: name.to_owned() })
        };
        let mut out = Vec::with_capacity(self.pairs.len());
        for pair in &self.pairs {
            let s = find(source, &pair.source, "source")?;
            let t = find(target, &pair.target, "target")?;
            if out.iter().any(|&(_, u)| u == t) {
                return Err(RetargetError::TargetTwice(pair.target.clone()));
            }
            out.push((s, t));
        }
        out.sort_by_key(|&(_, t)| t);
        Ok(out)
    }

    /// The mapped bones: each mapped target joint with the mapped joints just below it whose
    /// source joints lie just below its source joint in the same way (the bones whose
    /// directions the retargeted action copies; the rest alignment is made from them).
    ///
    /// # Errors
    /// As [`BoneMap::resolve`].
    pub fn bones(&self, source: &Skeleton, target: &Skeleton) -> Result<Vec<MappedBone>, RetargetError> {
        let pairs = self.resolve(source, target)?;
        Ok(mapped_bones(source, target, &pairs))
    }
}

/// A bone both rigs have: from a mapped joint to a mapped joint below it (unmapped joints may
/// lie between), in the source and in the target.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct MappedBone {
    /// Source joints: (from, to).
    pub source: (usize, usize),
    /// Target joints: (from, to).
    pub target: (usize, usize),
}

fn mapped_bones(source: &Skeleton, target: &Skeleton, pairs: &[(usize, usize)]) -> Vec<MappedBone> {
    let nearest_mapped_above = |skeleton: &Skeleton, j: usize, mapped: &dyn Fn(usize) -> bool| {
        let mut at = skeleton.joints[j].parent;
        while let Some(p) = at {
            if mapped(p) {
                return Some(p);
            }
            at = skeleton.joints[p].parent.filter(|&q| q < p);
        }
        None
    };
    let source_mapped = |j: usize| pairs.iter().any(|&(s, _)| s == j);
    let target_mapped = |j: usize| pairs.iter().any(|&(_, t)| t == j);
    let mut out = Vec::new();
    for &(s_child, t_child) in pairs {
        let Some(t_parent) = nearest_mapped_above(target, t_child, &target_mapped) else { continue };
        let Some(&(s_parent, _)) = pairs.iter().find(|&&(_, t)| t == t_parent) else { continue };
        if nearest_mapped_above(source, s_child, &source_mapped) == Some(s_parent) {
            out.push(MappedBone { source: (s_parent, s_child), target: (t_parent, t_child) });
        }
    }
    out
}

/// How foot contacts are found in the source and held on the target.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ContactSettings {
    /// A foot is in contact within this many source leg lengths above its lowest height.
    pub max_height: f64,
    /// … and while it moves (horizontally) slower than this many leg lengths per second.
    pub max_speed: f64,
    /// Shorter contacts are dropped (seconds).
    pub min_seconds: f64,
    /// The hold blends in before a contact and out after it over this time (seconds).
    pub blend_seconds: f64,
}

impl Default for ContactSettings {
    /// 10 % of the leg length above the lowest point, slower than 0.3 leg lengths per second
    /// (a walking stride's swing foot moves at about 3), at least 0.05 s, blended over 0.1 s.
    fn default() -> Self {
        ContactSettings { max_height: 0.05, max_speed: 0.15, min_seconds: 0.05, blend_seconds: 0.1 }
    }
}

/// What [`retarget`] does.
#[derive(Clone, Debug, PartialEq)]
pub struct RetargetOptions {
    /// The new action's name (an existing action is assigned to the target and its keys of
    /// the driven joints replaced).
    pub action: String,
    /// Keys per second; `None`: the source scene's frame rate.
    pub fps: Option<f64>,
    /// Hold planted feet (`None`: copy the legs' rotations only).
    pub contacts: Option<ContactSettings>,
    /// Reduce the keys afterwards within these tolerances.
    pub reduce: Option<ReduceTolerance>,
}

impl RetargetOptions {
    /// Feet held with the default contact settings, keys at the source's rate, not reduced.
    #[must_use]
    pub fn new(action: impl Into<String>) -> Self {
        RetargetOptions {
            action: action.into(),
            fps: None,
            contacts: Some(ContactSettings::default()),
            reduce: None,
        }
    }
}

/// A foot contact found in the source, in the keyed frames of the new action (frame `k` is at
/// `k / fps` seconds).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Contact {
    pub side: Side,
    pub first: usize,
    pub last: usize,
}

/// What [`retarget`] did.
#[derive(Clone, Debug, PartialEq)]
pub struct RetargetReport {
    /// The (source, target) joints driven.
    pub pairs: Vec<(usize, usize)>,
    /// Keyed frames and their rate.
    pub frames: usize,
    pub fps: f64,
    /// `L_target / L_source`, the root motion's scale.
    pub leg_ratio: f32,
    /// Source leg length, in the source's world units.
    pub source_leg: f32,
    /// Target leg length, in the target's world units.
    pub target_leg: f32,
    pub contacts: Vec<Contact>,
    /// Sides whose contacts could not be held: the target's mapped leg is neither two bones
    /// (upper leg, lower leg and foot, each the parent of the next) nor one (upper leg and
    /// foot).
    pub not_held: Vec<Side>,
    /// Frames × feet the IK solved (or a one-bone leg was turned), and of those how many could
    /// not reach their target.
    pub ik_solves: usize,
    pub ik_unreachable: usize,
    /// The key reduction, when asked for.
    pub reduced: Option<CleanupReport>,
}

/// Why retargeting cannot run.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum RetargetError {
    #[error("object {0} has no skeleton")]
    NoSkeleton(String),
    #[error("there is no object {0}")]
    NoObject(usize),
    #[error("the {side} skeleton has no joint {name:?}")]
    UnknownJoint { side: &'static str, name: String },
    #[error("target joint {0:?} is driven twice")]
    TargetTwice(String),
    #[error("the bone map drives no joint")]
    EmptyMap,
    #[error("the source has no keys")]
    NoKeys,
    #[error("the source's keys span {seconds} s, too many frames at {fps} fps")]
    TooLong { seconds: f64, fps: f64 },
    #[error("the frame rate {0} is not a positive number")]
    FrameRate(f64),
    #[error("{field}: {message}")]
    Track { field: String, message: String },
    #[error(transparent)]
    Action(#[from] keyrig_core::action::ActionError),
    #[error("key reduction: {0}")]
    Reduce(String),
}

/// A rotation channel ready to sample: quaternion keys, or Euler keys in an order.
enum RotationTrack {
    Quat(AnimatedTrack<Quat>),
    Euler(AnimatedTrack<Vec3>, EulerOrder),
}

impl RotationTrack {
    fn new(
        rotation: &Animated<Quat>,
        euler: Option<&Animated<Vec3>>,
        mode: RotationMode,
        field: &str,
    ) -> Result<Self, RetargetError> {
        let bad = |e: keyrig_core::TrackError| RetargetError::Track {
            field: field.to_owned(),
            message: e.to_string(),
        };
        Ok(match euler {
            Some(angles) => RotationTrack::Euler(
                AnimatedTrack::new(angles).map_err(bad)?,
                mode.euler().unwrap_or(EulerOrder::XYZ),
            ),
            None => RotationTrack::Quat(AnimatedTrack::new(rotation).map_err(bad)?),
        })
    }

    fn sample(&self, t: f64) -> Quat {
        match self {
            RotationTrack::Quat(track) => track.sample(t).normalize(),
            RotationTrack::Euler(track, order) => order.to_quat(track.sample(t)),
        }
    }

    fn domain(&self) -> Option<(f64, f64)> {
        match self {
            RotationTrack::Quat(track) => track.domain(),
            RotationTrack::Euler(track, _) => track.domain(),
        }
    }
}

fn vec_track(animated: &Animated<Vec3>, field: String) -> Result<AnimatedTrack<Vec3>, RetargetError> {
    AnimatedTrack::new(animated).map_err(|e| RetargetError::Track { field, message: e.to_string() })
}

/// An object's skeleton, ready to be posed at any time the way the scene evaluator poses it
/// (without IK constraints): `F(j) = F(p(j))·R(j)·T(j)`, roots shifted by the root translation,
/// all in world space through the object's transform.
struct Rig<'a> {
    skeleton: &'a Skeleton,
    rotations: Vec<RotationTrack>,
    translations: Vec<AnimatedTrack<Vec3>>,
    scales: Vec<AnimatedTrack<Vec3>>,
    root: AnimatedTrack<Vec3>,
    object: (AnimatedTrack<Vec3>, RotationTrack, AnimatedTrack<Vec3>),
}

impl<'a> Rig<'a> {
    fn new(object: &'a Object) -> Result<Self, RetargetError> {
        let skeleton =
            object.skeleton.as_ref().ok_or_else(|| RetargetError::NoSkeleton(object.name.clone()))?;
        let o = &object.name;
        let mut rotations = Vec::new();
        let mut translations = Vec::new();
        let mut scales = Vec::new();
        for joint in &skeleton.joints {
            let at = format!("object/{o}/joint/{}", joint.name);
            rotations.push(RotationTrack::new(
                &joint.rotation,
                joint.rotation_euler.as_ref(),
                joint.rotation_mode,
                &format!("{at}/rotation"),
            )?);
            translations.push(vec_track(&joint.translation, format!("{at}/translation"))?);
            scales.push(vec_track(&joint.scale, format!("{at}/scale"))?);
        }
        Ok(Rig {
            skeleton,
            rotations,
            translations,
            scales,
            root: vec_track(&skeleton.root_translation, format!("object/{o}/root_translation"))?,
            object: (
                vec_track(&object.translation, format!("object/{o}/translation"))?,
                RotationTrack::new(
                    &object.rotation,
                    object.rotation_euler.as_ref(),
                    object.rotation_mode,
                    &format!("object/{o}/rotation"),
                )?,
                vec_track(&object.scale, format!("object/{o}/scale"))?,
            ),
        })
    }

    /// The keyed time range of the skeleton's and the object's channels.
    fn domain(&self) -> Option<(f64, f64)> {
        let (t, r, s) = &self.object;
        self.rotations
            .iter()
            .map(RotationTrack::domain)
            .chain(
                self.translations
                    .iter()
                    .chain(&self.scales)
                    .chain([&self.root, t, s])
                    .map(AnimatedTrack::domain),
            )
            .chain([r.domain()])
            .flatten()
            .reduce(|(a, b), (c, d)| (a.min(c), b.max(d)))
    }

    fn world_from_object(&self, t: f64) -> Affine3A {
        let (tr, r, s) = &self.object;
        Affine3A::from_scale_rotation_translation(s.sample(t), r.sample(t), tr.sample(t))
    }

    /// World from joint for every joint at `t`; `rest`: with every T(j) the identity.
    fn world(&self, t: f64, rest: bool, out: &mut Vec<Affine3A>) {
        out.clear();
        let object = self.world_from_object(t);
        let root = object * Affine3A::from_translation(self.root.sample(t));
        for (j, joint) in self.skeleton.joints.iter().enumerate() {
            let parent = match joint.parent.filter(|&p| p < out.len()) {
                Some(p) => out[p],
                None => root,
            };
            let r = Affine3A::from_rotation_translation(joint.rest_rotation, joint.rest_translation);
            let local = if rest {
                Affine3A::IDENTITY
            } else {
                Affine3A::from_scale_rotation_translation(
                    self.scales[j].sample(t),
                    self.rotations[j].sample(t),
                    self.translations[j].sample(t),
                )
            };
            out.push(parent * r * local);
        }
    }
}

/// The bones a joint is aimed by: one bone exactly, or with several, the centre-line bone
/// (else the longest) exactly and the line between a left and a right bone as nearly as it can
/// (else another bone).
#[derive(Clone, Copy, Debug)]
struct Aim {
    primary: MappedBone,
    secondary: Option<(MappedBone, Option<MappedBone>)>,
}

impl Aim {
    fn of(j: usize, bones: &[MappedBone], slots: &[Option<Slot>]) -> Option<Aim> {
        let children: Vec<MappedBone> = bones.iter().copied().filter(|b| b.target.0 == j).collect();
        let slot = |b: &MappedBone| slots[b.target.1];
        let primary = children
            .iter()
            .copied()
            .find(|b| slot(b).is_some_and(Slot::is_central))
            .or_else(|| children.first().copied())?;
        let side_pair = children.iter().find_map(|l| {
            let (Side::Left, limb) = slot(l)?.limb_of()? else { return None };
            let r = children.iter().find(|r| slot(r) == Some(Slot::Right(limb)))?;
            Some((*l, Some(*r)))
        });
        let secondary = side_pair.or_else(|| children.iter().find(|b| **b != primary).map(|b| (*b, None)));
        Some(Aim { primary, secondary })
    }

    /// The rotation that turns the bones as `from` gives them onto the bones as `to` gives them.
    fn rotation(&self, from: impl Fn(MappedBone) -> Vec3, to: impl Fn(MappedBone) -> Vec3) -> Option<Quat> {
        let (uf, ut) = (from(self.primary).try_normalize()?, to(self.primary).try_normalize()?);
        let second =
            |f: &dyn Fn(MappedBone) -> Vec3| self.secondary.map(|(a, b)| f(a) - b.map_or(Vec3::ZERO, f));
        let aligned = match (second(&from), second(&to)) {
            (Some(vf), Some(vt)) => frame_alignment(uf, vf, ut, vt),
            _ => None,
        };
        Some(aligned.unwrap_or_else(|| Quat::from_rotation_arc(uf, ut)))
    }
}

/// The rotation part of an affine map (its scale divided out).
fn rotation_of(a: &Affine3A) -> Quat {
    a.to_scale_rotation_translation().1.normalize()
}

fn position_of(a: &Affine3A) -> Vec3 {
    Vec3::from(a.translation)
}

/// The rotation that takes the orthonormal frame of (`u_from`, `v_from`) to that of
/// (`u_to`, `v_to`): `u_from` exactly onto `u_to`, the plane of the pair onto the other's.
fn frame_alignment(u_from: Vec3, v_from: Vec3, u_to: Vec3, v_to: Vec3) -> Option<Quat> {
    let frame = |u: Vec3, v: Vec3| -> Option<Mat3> {
        let a = u.try_normalize()?;
        let c = a.cross(v).try_normalize()?;
        Some(Mat3::from_cols(a, c.cross(a), c))
    };
    let (from, to) = (frame(u_from, v_from)?, frame(u_to, v_to)?);
    Some(Quat::from_mat3(&(to * from.transpose())).normalize())
}

/// The most frames one retargeting keys (a day at 120 fps), so that keys hours apart at a
/// million frames per second are refused rather than filling memory with poses.
const MAX_FRAMES: usize = 10_368_000;

/// The world up direction both rigs are read in (glTF's and BVH's +Y).
const UP: Vec3 = Vec3::Y;

/// Puts the action the source object plays onto the target object as a new action, through
/// `map` (module documentation). The source is sampled at every frame of its keys' range; the
/// target gets one key per frame from time 0.
///
/// # Errors
/// [`RetargetError`]: an object without a skeleton, a map naming joints the skeletons do not
/// have or driving nothing, a source without keys or with too many frames, a bad frame rate,
/// an invalid channel, a bad action name, a bad reduction tolerance. The target scene is
/// unchanged on an error.
pub fn retarget(
    source: &Scene,
    source_object: usize,
    target: &mut Scene,
    target_object: usize,
    map: &BoneMap,
    options: &RetargetOptions,
) -> Result<RetargetReport, RetargetError> {
    let src_object = source.objects.get(source_object).ok_or(RetargetError::NoObject(source_object))?;
    let src = Rig::new(src_object)?;
    let src_skeleton = src.skeleton;
    let tgt_skeleton =
        target.objects.get(target_object).ok_or(RetargetError::NoObject(target_object))?.skeleton.as_ref();
    let tgt_skeleton =
        tgt_skeleton.ok_or_else(|| RetargetError::NoSkeleton(target.objects[target_object].name.clone()))?;
    let pairs = map.resolve(src_skeleton, tgt_skeleton)?;
    if pairs.is_empty() {
        return Err(RetargetError::EmptyMap);
    }
    let fps = options.fps.unwrap_or(source.fps);
    if !(fps.is_finite() && fps > 0.0) {
        return Err(RetargetError::FrameRate(fps));
    }
    if let Some(tolerance) = options.reduce {
        tolerance.check().map_err(|e| RetargetError::Reduce(e.to_string()))?;
        if !(target.fps.is_finite() && target.fps > 0.0) {
            return Err(RetargetError::FrameRate(target.fps));
        }
    }
    let (t0, t1) = src.domain().ok_or(RetargetError::NoKeys)?;
    let span = ((t1 - t0) * fps).round();
    if !(span.is_finite() && span < MAX_FRAMES as f64) {
        return Err(RetargetError::TooLong { seconds: t1 - t0, fps });
    }
    let frames = span.max(0.0) as usize + 1;
    // Checked before the target changes: its channels must validate too.
    Rig::new(&target.objects[target_object])?;

    // The target plays the new action from here on: its old keys are stored, and what it
    // holds without keys (the static values) is what the new keys are built on.
    match target.action_index(&options.action) {
        Some(_) => target.assign_action(target_object, Some(&options.action))?,
        None => target.new_action(target_object, &options.action)?,
    }
    let tgt_object = &target.objects[target_object];
    let tgt_skeleton =
        tgt_object.skeleton.as_ref().ok_or_else(|| RetargetError::NoSkeleton(tgt_object.name.clone()))?;
    let n = tgt_skeleton.joints.len();
    let tgt_rig = Rig::new(tgt_object)?;

    // Rest poses in world space.
    let mut src_rest = Vec::new();
    src.world(t0, true, &mut src_rest);
    let mut tgt_rest = Vec::new();
    tgt_rig.world(0.0, true, &mut tgt_rest);

    let target_slots = skeleton_slots(tgt_skeleton);
    let source_of = |t: usize| pairs.iter().find(|&&(_, u)| u == t).map(|&(s, _)| s);
    let slot_joint = |slot: Slot| (0..n).find(|&j| target_slots[j] == Some(slot) && source_of(j).is_some());
    // The hips: the mapped joint named so, else the mapped joint nearest the root.
    let depth = |j: usize| {
        let (mut d, mut at) = (0, tgt_skeleton.joints[j].parent);
        while let Some(p) = at {
            d += 1;
            at = tgt_skeleton.joints[p].parent.filter(|&q| q < p);
        }
        d
    };
    let hips = slot_joint(Slot::Hips)
        .or_else(|| pairs.iter().map(|&(_, t)| t).min_by_key(|&t| depth(t)))
        .ok_or(RetargetError::EmptyMap)?;
    let src_hips = source_of(hips).ok_or(RetargetError::EmptyMap)?;

    // Rest alignment C(j) from the mapped bones.
    let bones = mapped_bones(src_skeleton, tgt_skeleton, &pairs);
    let aims: Vec<Option<Aim>> = (0..n).map(|j| Aim::of(j, &bones, &target_slots)).collect();
    let rest_direction =
        |rest: &[Affine3A], (from, to): (usize, usize)| position_of(&rest[to]) - position_of(&rest[from]);
    let mut align: Vec<Option<Quat>> = aims
        .iter()
        .map(|aim| {
            aim.as_ref()?
                .rotation(|b| rest_direction(&tgt_rest, b.target), |b| rest_direction(&src_rest, b.source))
        })
        .collect();
    // Each aimed bone in its joint's frame at rest (the target's own offsets).
    // Each aimed bone in its joint's frame, with the unmapped joints along it in their static
    // pose (as the evaluator will pose them).
    let mut tgt_static = Vec::new();
    tgt_rig.world(0.0, false, &mut tgt_static);
    let local_offset = |b: MappedBone| {
        rotation_of(&tgt_static[b.target.0]).inverse() * rest_direction(&tgt_static, b.target)
    };
    // A joint without mapped bones below it turns as the nearest aligned joint above it.
    for j in 0..n {
        if align[j].is_none() && source_of(j).is_some() {
            let mut at = tgt_skeleton.joints[j].parent;
            while let Some(p) = at {
                if let Some(a) = align[p] {
                    align[j] = Some(a);
                    break;
                }
                at = tgt_skeleton.joints[p].parent.filter(|&q| q < p);
            }
        }
    }

    // Legs: lengths, ground heights and the two-bone chains.
    let leg = |side: Side| -> Vec<usize> {
        [Limb::UpperLeg, Limb::LowerLeg, Limb::Foot]
            .into_iter()
            .filter_map(|l| slot_joint(Slot::limb(side, l)))
            .collect()
    };
    let chain_length = |chain: &[usize], rest: &[Affine3A], map: &dyn Fn(usize) -> usize| -> f32 {
        chain.windows(2).map(|w| position_of(&rest[map(w[1])]).distance(position_of(&rest[map(w[0])]))).sum()
    };
    let (mut source_leg, mut target_leg, mut legs) = (0.0f32, 0.0f32, 0);
    for side in [Side::Left, Side::Right] {
        let chain = leg(side);
        if chain.len() >= 2 {
            target_leg += chain_length(&chain, &tgt_rest, &|t| t);
            source_leg += chain_length(&chain, &src_rest, &|t| source_of(t).unwrap_or(src_hips));
            legs += 1;
        }
    }
    if legs > 0 {
        source_leg /= legs as f32;
        target_leg /= legs as f32;
    } else {
        // No legs: the hips' rest height above the lowest joint.
        let lowest = |rest: &[Affine3A]| rest.iter().map(|a| position_of(a).dot(UP)).fold(f32::MAX, f32::min);
        source_leg = position_of(&src_rest[src_hips]).dot(UP) - lowest(&src_rest);
        target_leg = position_of(&tgt_rest[hips]).dot(UP) - lowest(&tgt_rest);
    }
    let leg_ratio = if source_leg > 0.0 && target_leg > 0.0 { target_leg / source_leg } else { 1.0 };
    let feet: Vec<(Side, usize)> = [Side::Left, Side::Right]
        .into_iter()
        .filter_map(|side| Some((side, slot_joint(Slot::limb(side, Limb::Foot))?)))
        .collect();

    // Pass 1: the source at every frame, the copied rotations and the scaled root motion.
    let mut src_world: Vec<Vec<Affine3A>> = Vec::with_capacity(frames);
    let mut scratch = Vec::new();
    for k in 0..frames {
        src.world(t0 + k as f64 / fps, false, &mut scratch);
        src_world.push(scratch.clone());
    }
    let src_foot_heights: Vec<f32> = feet
        .iter()
        .filter_map(|&(_, f)| source_of(f))
        .flat_map(|s| src_world.iter().map(move |w| position_of(&w[s]).dot(UP)))
        .collect();
    let src_ground = src_foot_heights.iter().copied().reduce(f32::min).unwrap_or_else(|| {
        src_world.iter().flatten().map(|a| position_of(a).dot(UP)).fold(f32::MAX, f32::min)
    });
    let tgt_ground = if feet.is_empty() {
        tgt_rest.iter().map(|a| position_of(a).dot(UP)).fold(f32::MAX, f32::min)
    } else {
        feet.iter().map(|&(_, f)| position_of(&tgt_rest[f]).dot(UP)).fold(f32::MAX, f32::min)
    };
    let hips_rest = position_of(&tgt_rest[hips]);
    let src_hips_start = position_of(&src_world[0][src_hips]);
    let horizontal = |v: Vec3| v - UP * v.dot(UP);

    let world_from_object = tgt_rig.world_from_object(0.0);
    let root_shift = world_from_object * Affine3A::from_translation(tgt_skeleton.root_translation.value);
    let static_rotation = |j: usize| tgt_rig.rotations[j].sample(0.0);
    let static_translation = |j: usize| tgt_skeleton.joints[j].translation.value;
    let static_scale = |j: usize| tgt_skeleton.joints[j].scale.value;
    let compose = |parent: Affine3A, j: usize, q: Quat, t: Vec3| {
        let joint = &tgt_skeleton.joints[j];
        parent
            * Affine3A::from_rotation_translation(joint.rest_rotation, joint.rest_translation)
            * Affine3A::from_scale_rotation_translation(static_scale(j), q, t)
    };
    let parent_of = |world: &[Affine3A], j: usize| match tgt_skeleton.joints[j].parent.filter(|&p| p < j) {
        Some(p) => world[p],
        None => root_shift,
    };

    let mut locals: Vec<Vec<Quat>> = Vec::with_capacity(frames);
    let mut hips_translations: Vec<Vec3> = Vec::with_capacity(frames);
    let mut tgt_world: Vec<Vec<Affine3A>> = Vec::with_capacity(frames);
    for sw in &src_world {
        let mut local = vec![Quat::IDENTITY; n];
        let mut world: Vec<Affine3A> = Vec::with_capacity(n);
        let mut hips_t = static_translation(hips);
        for j in 0..n {
            let parent = parent_of(&world, j);
            let joint = &tgt_skeleton.joints[j];
            let q = match (source_of(j), align[j]) {
                (Some(s), Some(c)) => {
                    let copied = rotation_of(&sw[s])
                        * rotation_of(&src_rest[s]).inverse()
                        * c
                        * rotation_of(&tgt_rest[j]);
                    // Where unmapped source joints lie along a bone (CMU's `lowerneck`, `Chest`),
                    // the copy alone misses their turn: aim the bones at the source's.
                    let aim = aims[j].as_ref().and_then(|aim| {
                        aim.rotation(|b| copied * local_offset(b), |b| rest_direction(sw, b.source))
                    });
                    let wanted = aim.unwrap_or(Quat::IDENTITY) * copied;
                    ((rotation_of(&parent) * joint.rest_rotation).inverse() * wanted).normalize()
                }
                (Some(s), None) => {
                    // Nothing aligned above (a lone joint): copy the world rotation change.
                    let wanted =
                        rotation_of(&sw[s]) * rotation_of(&src_rest[s]).inverse() * rotation_of(&tgt_rest[j]);
                    ((rotation_of(&parent) * joint.rest_rotation).inverse() * wanted).normalize()
                }
                _ => static_rotation(j),
            };
            let t = if j == hips {
                let s = position_of(&sw[src_hips]);
                let mut p = hips_rest - UP * hips_rest.dot(UP) + horizontal(s - src_hips_start) * leg_ratio;
                p += UP * (tgt_ground + (s.dot(UP) - src_ground) * leg_ratio);
                let x = parent.inverse().transform_point3(p);
                hips_t = joint.rest_rotation.inverse() * (x - joint.rest_translation);
                hips_t
            } else {
                static_translation(j)
            };
            local[j] = q;
            world.push(compose(parent, j, q, t));
        }
        locals.push(local);
        hips_translations.push(hips_t);
        tgt_world.push(world);
    }

    // Contacts, found in the source.
    let mut contacts = Vec::new();
    let mut not_held = Vec::new();
    let (mut ik_solves, mut ik_unreachable) = (0, 0);
    if let Some(settings) = options.contacts {
        for &(side, foot) in &feet {
            let Some(src_foot) = source_of(foot) else { continue };
            let found = find_contacts(&src_world, src_foot, source_leg, fps, &settings);
            let chain = leg(side);
            let linked = chain.windows(2).all(|w| tgt_skeleton.joints[w[1]].parent == Some(w[0]));
            let two_bone = linked && chain.len() == 3;
            // A leg of one bone (no knee) is turned about its root towards the planted point.
            let one_bone = linked && chain.len() == 2;
            if !two_bone && !one_bone {
                if !found.is_empty() {
                    not_held.push(side);
                }
                contacts.extend(found.into_iter().map(|(first, last)| Contact { side, first, last }));
                continue;
            }
            // The planted point of each contact and, per frame, the nearest contact's weight.
            let plants: Vec<Vec3> = found
                .iter()
                .map(|&(a, b)| {
                    (a..=b).map(|k| position_of(&tgt_world[k][foot])).sum::<Vec3>() / (b - a + 1) as f32
                })
                .collect();
            let blend = (settings.blend_seconds * fps).round().max(0.0) as usize;
            for k in 0..frames {
                let mut best: Option<(f32, Vec3)> = None;
                for (&(a, b), &plant) in found.iter().zip(&plants) {
                    let distance = if k < a { a - k } else { k.saturating_sub(b) };
                    if distance > blend {
                        continue;
                    }
                    let w = if distance == 0 {
                        1.0
                    } else {
                        let x = 1.0 - distance as f32 / (blend + 1) as f32;
                        x * x * (3.0 - 2.0 * x)
                    };
                    if best.is_none_or(|(bw, _)| w > bw) {
                        best = Some((w, plant));
                    }
                }
                let Some((w, plant)) = best else { continue };
                let (upper, lower) = (chain[0], chain[1]);
                let world = &mut tgt_world[k];
                let local = &mut locals[k];
                let parent = parent_of(world, upper);
                let fk_foot = position_of(&world[foot]);
                let goal = fk_foot.lerp(plant, w);
                let foot_world = rotation_of(&world[foot]);
                let keep_foot = |world: &mut [Affine3A], local: &mut [Quat], above: usize| {
                    let joint = &tgt_skeleton.joints[foot];
                    local[foot] = ((rotation_of(&world[above]) * joint.rest_rotation).inverse() * foot_world)
                        .normalize();
                    world[foot] = compose(world[above], foot, local[foot], static_translation(foot));
                };
                if one_bone {
                    // The leg cannot change its length: the foot goes to the planted point's
                    // place on the ground plane (below the hip at the leg's length), or as
                    // near it as the leg reaches.
                    let hip = position_of(&world[upper]);
                    let length = fk_foot.distance(hip);
                    let across = horizontal(goal - hip);
                    let goal = if across.length() < length {
                        hip + across - UP * (length * length - across.length_squared()).sqrt()
                    } else {
                        goal
                    };
                    let (Some(from), Some(to)) =
                        ((fk_foot - hip).try_normalize(), (goal - hip).try_normalize())
                    else {
                        continue;
                    };
                    let turned = Quat::from_rotation_arc(from, to) * rotation_of(&world[upper]);
                    let joint = &tgt_skeleton.joints[upper];
                    local[upper] =
                        ((rotation_of(&parent) * joint.rest_rotation).inverse() * turned).normalize();
                    world[upper] = compose(parent, upper, local[upper], static_translation(upper));
                    keep_foot(world, local, upper);
                    ik_solves += 1;
                    if horizontal(position_of(&world[foot]) - goal).length() > 1e-3 * target_leg {
                        ik_unreachable += 1;
                    }
                    continue;
                }
                let (hip, knee) = (position_of(&world[upper]), position_of(&world[lower]));
                let axis = (fk_foot - hip).normalize_or_zero();
                let bend = (knee - hip) - axis * (knee - hip).dot(axis);
                let forward = rotation_of(&world[hips])
                    * rotation_of(&tgt_rest[hips]).inverse()
                    * rest_forward(&tgt_rest, &target_slots);
                let direction = if bend.length() > 1e-3 * target_leg { bend.normalize() } else { forward };
                let pole = Pole::Point(knee + direction * target_leg);
                let joints = [upper, lower, foot];
                let translations = joints.map(|j| {
                    let joint = &tgt_skeleton.joints[j];
                    joint.rest_translation + joint.rest_rotation * static_translation(j)
                });
                let rest_rotations = joints.map(|j| tgt_skeleton.joints[j].rest_rotation);
                let rotations = joints.map(|j| local[j]);
                let chain = IkChain {
                    world_from_parent: parent,
                    translations: &translations,
                    rest_rotations: &rest_rotations,
                    rotations: &rotations,
                };
                let mut out = [Quat::IDENTITY; 3];
                let Ok(report) = solve_two_bone(&chain, goal, pole, &mut out) else { continue };
                ik_solves += 1;
                if !report.reachable {
                    ik_unreachable += 1;
                }
                local[upper] = out[0];
                local[lower] = out[1];
                world[upper] = compose(parent, upper, out[0], static_translation(upper));
                world[lower] = compose(world[upper], lower, out[1], static_translation(lower));
                keep_foot(world, local, lower);
            }
            contacts.extend(found.into_iter().map(|(first, last)| Contact { side, first, last }));
        }
    }

    // Keys.
    let time = |k: usize| k as f64 / fps;
    let object = &mut target.objects[target_object];
    let skeleton = object.skeleton.as_mut().ok_or_else(|| RetargetError::NoSkeleton(object.name.clone()))?;
    let mut channels = Vec::new();
    for &(_, j) in &pairs {
        let mut previous = Quat::IDENTITY;
        let keys: Vec<Key<Quat>> = (0..frames)
            .map(|k| {
                let mut q = locals[k][j];
                if q.dot(previous) < 0.0 {
                    q = -q;
                }
                previous = q;
                Key::new(time(k), q)
            })
            .collect();
        let joint = &mut skeleton.joints[j];
        joint.rotation = Animated::new(keys[0].value, RawTrack::new(keys));
        if joint.rotation_euler.take().is_some() {
            joint.rotation_mode = RotationMode::Quaternion;
        }
        channels.push(ChannelId::JointRotation { object: target_object, joint: j });
    }
    let keys: Vec<Key<Vec3>> =
        hips_translations.iter().enumerate().map(|(k, &t)| Key::new(time(k), t)).collect();
    skeleton.joints[hips].translation = Animated::new(keys[0].value, RawTrack::new(keys));
    channels.push(ChannelId::JointTranslation { object: target_object, joint: hips });
    let end = (time(frames - 1) * target.fps).ceil();
    if end.is_finite() && end > f64::from(target.frame_range.end) && end < f64::from(i32::MAX) {
        target.frame_range.end = end as i32;
    }
    target.frame_range.start = target.frame_range.start.min(0);
    let reduced = match options.reduce {
        Some(tolerance) => Some(
            reduce_keys(target, &channels, tolerance).map_err(|e| RetargetError::Reduce(e.to_string()))?,
        ),
        None => None,
    };
    contacts.sort_by_key(|c| c.first);
    Ok(RetargetReport {
        pairs,
        frames,
        fps,
        leg_ratio,
        source_leg,
        target_leg,
        contacts,
        not_held,
        ik_solves,
        ik_unreachable,
        reduced,
    })
}

/// The direction a rig faces at rest, in world space: `(left hip − right hip) × up` (a
/// character facing +Z with its left at +X gives +Z); +Z without both upper legs.
fn rest_forward(rest: &[Affine3A], slots: &[Option<Slot>]) -> Vec3 {
    let find = |slot: Slot| slots.iter().position(|s| *s == Some(slot));
    match (find(Slot::Left(Limb::UpperLeg)), find(Slot::Right(Limb::UpperLeg))) {
        (Some(l), Some(r)) => {
            let side = position_of(&rest[l]) - position_of(&rest[r]);
            side.cross(UP).try_normalize().unwrap_or(Vec3::Z)
        }
        _ => Vec3::Z,
    }
}

/// The contacts of one source joint: runs of frames where it is within `max_height` leg
/// lengths of its lowest height and moves horizontally slower than `max_speed` leg lengths per
/// second (central differences), at least `min_seconds` long; gaps of up to 2 frames inside a
/// contact are closed.
fn find_contacts(
    world: &[Vec<Affine3A>],
    joint: usize,
    leg: f32,
    fps: f64,
    settings: &ContactSettings,
) -> Vec<(usize, usize)> {
    let positions: Vec<Vec3> = world.iter().map(|w| position_of(&w[joint])).collect();
    let n = positions.len();
    if n < 2 || leg <= 0.0 {
        return Vec::new();
    }
    let lowest = positions.iter().map(|p| p.dot(UP)).fold(f32::MAX, f32::min);
    let leg = f64::from(leg);
    let planted: Vec<bool> = (0..n)
        .map(|k| {
            let (a, b) = (k.saturating_sub(1), (k + 1).min(n - 1));
            let d = positions[b] - positions[a];
            let d = d - UP * d.dot(UP);
            let speed = f64::from(d.length()) * fps / (b - a) as f64;
            let height = f64::from(positions[k].dot(UP) - lowest);
            height <= settings.max_height * leg && speed <= settings.max_speed * leg
        })
        .collect();
    let mut runs: Vec<(usize, usize)> = Vec::new();
    let mut k = 0;
    while k < n {
        if !planted[k] {
            k += 1;
            continue;
        }
        let start = k;
        while k < n && planted[k] {
            k += 1;
        }
        match runs.last_mut() {
            Some(last) if start - last.1 <= 3 => last.1 = k - 1,
            _ => runs.push((start, k - 1)),
        }
    }
    let min_frames = (settings.min_seconds * fps).ceil() as usize;
    runs.retain(|&(a, b)| b - a + 1 >= min_frames.max(2));
    runs
}
