//! Clip tracks and layers in the evaluator (docs/clips.md): each strip's and layer's action
//! as slots of the object's pose channels, and the mix of an object's pose at a time.

use glam::{Quat, Vec3};
use keyrig_core::action::stored_channel_id;
use keyrig_core::channel_id::{channel, ChannelId, ChannelRef};
use keyrig_core::{ActionKeys, ClipTrack, LayerMode, Scene, StripBlend};

use crate::slot::{RotationSlot, Slot};

/// Which pose value of an object a channel sets.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum PoseTarget {
    Translation,
    Scale,
    Root,
    JointTranslation(usize),
    JointScale(usize),
}

/// An object's pose channels as the mix reads and writes them.
#[derive(Clone, Debug, Default)]
pub(crate) struct PoseValues {
    pub(crate) translation: Vec3,
    pub(crate) rotation: Quat,
    pub(crate) scale: Vec3,
    pub(crate) root: Vec3,
    pub(crate) joint_translations: Vec<Vec3>,
    pub(crate) joint_rotations: Vec<Quat>,
    pub(crate) joint_scales: Vec<Vec3>,
}

impl PoseValues {
    fn vec3(&mut self, target: PoseTarget) -> Option<&mut Vec3> {
        match target {
            PoseTarget::Translation => Some(&mut self.translation),
            PoseTarget::Scale => Some(&mut self.scale),
            PoseTarget::Root => Some(&mut self.root),
            PoseTarget::JointTranslation(j) => self.joint_translations.get_mut(j),
            PoseTarget::JointScale(j) => self.joint_scales.get_mut(j),
        }
    }

    fn quat(&mut self, joint: Option<usize>) -> Option<&mut Quat> {
        match joint {
            None => Some(&mut self.rotation),
            Some(j) => self.joint_rotations.get_mut(j),
        }
    }
}

/// The pose channels one action holds for one object, with their values at the strip's
/// first action frame (Combine's reference).
#[derive(Clone, Debug, Default)]
pub(crate) struct ActionSlots {
    vec3: Vec<(PoseTarget, Slot<Vec3>, Vec3)>,
    /// `None`: the object's rotation; `Some(j)`: joint `j`'s.
    rotations: Vec<(Option<usize>, RotationSlot, Quat)>,
}

impl ActionSlots {
    /// The channels of action `name` for object `o`: the object's own keyed channels when it
    /// is the object's active action, else the action's stored channels that name the object.
    pub(crate) fn new(scene: &Scene, o: usize, name: &str) -> Self {
        let mut out = ActionSlots::default();
        let object = &scene.objects[o];
        if object.action.as_deref() == Some(name) {
            for id in scene.keyed_channels_of(o) {
                match channel(scene, id) {
                    Some(ChannelRef::Vec3(a)) => out.push_vec3(scene, id, a),
                    Some(ChannelRef::Rotation(a)) => out.push_quat(scene, id, a),
                    _ => {}
                }
            }
            return out;
        }
        let Some(action) = scene.action_index(name).map(|a| &scene.actions[a]) else { return out };
        for stored in &action.channels {
            let Ok(id) = stored_channel_id(scene, &stored.path) else { continue };
            if keyrig_core::action::channel_object(id) != Some(o) {
                continue;
            }
            match &stored.keys {
                ActionKeys::Vec3(a) => out.push_vec3(scene, id, a),
                ActionKeys::Rotation(a) => out.push_quat(scene, id, a),
                ActionKeys::Scalar(_) => {}
            }
        }
        out
    }

    fn push_vec3(&mut self, scene: &Scene, id: ChannelId, a: &keyrig_core::Animated<Vec3>) {
        let target = match id {
            ChannelId::ObjectTranslation(_) => PoseTarget::Translation,
            ChannelId::ObjectScale(_) => PoseTarget::Scale,
            ChannelId::RootTranslation(_) => PoseTarget::Root,
            ChannelId::JointTranslation { joint, .. } => PoseTarget::JointTranslation(joint),
            ChannelId::JointScale { joint, .. } => PoseTarget::JointScale(joint),
            ChannelId::ObjectEuler(o) => {
                let mode = scene.objects[o].rotation_mode;
                let slot =
                    RotationSlot::new(a_quat_placeholder(), Some(a), mode, ChannelId::ObjectRotation(o));
                self.rotations.push((None, slot, Quat::IDENTITY));
                return;
            }
            ChannelId::JointEuler { object, joint } => {
                let Some(j) = scene.objects[object].skeleton.as_ref().and_then(|s| s.joints.get(joint))
                else {
                    return;
                };
                let slot = RotationSlot::new(
                    a_quat_placeholder(),
                    Some(a),
                    j.rotation_mode,
                    ChannelId::JointRotation { object, joint },
                );
                self.rotations.push((Some(joint), slot, Quat::IDENTITY));
                return;
            }
            _ => return,
        };
        self.vec3.push((target, Slot::new(a, id), Vec3::ZERO));
    }

    fn push_quat(&mut self, _scene: &Scene, id: ChannelId, a: &keyrig_core::Animated<Quat>) {
        let joint = match id {
            ChannelId::ObjectRotation(_) => None,
            ChannelId::JointRotation { joint, .. } => Some(joint),
            _ => return,
        };
        let slot = RotationSlot::new(a, None, keyrig_core::RotationMode::Quaternion, id);
        self.rotations.push((joint, slot, Quat::IDENTITY));
    }

    /// Records each channel's value at action time `t0` (seconds): Combine's reference.
    pub(crate) fn set_reference(&mut self, t0: f64) {
        for (_, slot, r) in &mut self.vec3 {
            *r = slot.sample(t0);
        }
        for (_, slot, r) in &mut self.rotations {
            *r = unit(slot.sample(t0));
        }
    }

    fn channel_count(&self) -> usize {
        self.vec3.len() + self.rotations.len()
    }

    /// Blends the channels' values at action time `t` into `pose` with weight `w`; with a
    /// root offset (Replace only), the root's values are the action's moved by it.
    fn blend_into(&self, pose: &mut PoseValues, t: f64, w: f32, mode: Blend, root: Option<&RootOffset>) {
        let moved = root.map(|r| r.moved(self, pose, t));
        for (target, slot, reference) in &self.vec3 {
            let x = match (&moved, *target) {
                (Some(m), PoseTarget::Translation | PoseTarget::JointTranslation(0)) if m.is(*target) => {
                    m.translation
                }
                _ => slot.sample(t),
            };
            let Some(v) = pose.vec3(*target) else { continue };
            let scale = matches!(target, PoseTarget::Scale | PoseTarget::JointScale(_));
            *v = match (mode, scale) {
                (Blend::Replace, _) => v.lerp(x, w),
                (Blend::Relative, false) => *v + (x - *reference) * w,
                (Blend::Relative, true) => *v * (Vec3::ONE + (ratio(x, *reference) - Vec3::ONE) * w),
                (Blend::Additive, false) => *v + x * w,
                (Blend::Additive, true) => *v * (Vec3::ONE + (x - Vec3::ONE) * w),
            };
        }
        for (joint, slot, reference) in &self.rotations {
            let x = match &moved {
                Some(m) if m.joint == *joint => m.rotation,
                _ => unit(slot.sample(t)),
            };
            let Some(q) = pose.quat(*joint) else { continue };
            *q = unit(match mode {
                Blend::Replace => q.slerp(x, w),
                Blend::Relative => *q * Quat::IDENTITY.slerp(reference.inverse() * x, w),
                Blend::Additive => *q * Quat::IDENTITY.slerp(x, w),
            });
        }
        // A root the action does not key still moves with the offset.
        if let Some(m) = moved {
            let target = match m.joint {
                None => PoseTarget::Translation,
                Some(_) => PoseTarget::JointTranslation(0),
            };
            if !self.vec3.iter().any(|(t, _, _)| *t == target) {
                if let Some(v) = pose.vec3(target) {
                    *v = v.lerp(m.translation, w);
                }
            }
            if !self.rotations.iter().any(|(j, _, _)| *j == m.joint) {
                if let Some(q) = pose.quat(m.joint) {
                    *q = unit(q.slerp(m.rotation, w));
                }
            }
        }
    }

    /// The root's value in this action at time `t`, falling back to `pose`'s where the action
    /// does not key it: `(translation, rotation)` of joint 0 (`joint` `Some(0)`) or the object.
    fn root_at(&self, pose: &PoseValues, joint: Option<usize>, t: f64) -> (Vec3, Quat) {
        let target = match joint {
            None => PoseTarget::Translation,
            Some(_) => PoseTarget::JointTranslation(0),
        };
        let translation = self
            .vec3
            .iter()
            .find(|(p, _, _)| *p == target)
            .map_or_else(|| fallback_translation(pose, joint), |(_, slot, _)| slot.sample(t));
        let rotation = self
            .rotations
            .iter()
            .find(|(j, _, _)| *j == joint)
            .map_or_else(|| fallback_rotation(pose, joint), |(_, slot, _)| unit(slot.sample(t)));
        (translation, rotation)
    }
}

fn fallback_translation(pose: &PoseValues, joint: Option<usize>) -> Vec3 {
    match joint {
        None => pose.translation,
        Some(_) => pose.joint_translations.first().copied().unwrap_or_default(),
    }
}

fn fallback_rotation(pose: &PoseValues, joint: Option<usize>) -> Quat {
    match joint {
        None => pose.rotation,
        Some(_) => pose.joint_rotations.first().copied().unwrap_or_default(),
    }
}

/// A stand-in rotation for a slot built from Euler keys (the quaternion keys are not read).
fn a_quat_placeholder() -> &'static keyrig_core::Animated<Quat> {
    static IDENTITY: std::sync::OnceLock<keyrig_core::Animated<Quat>> = std::sync::OnceLock::new();
    IDENTITY.get_or_init(|| keyrig_core::Animated::constant(Quat::IDENTITY))
}

/// How values meet those below (docs/clips.md, "Blending").
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Blend {
    /// `lerp(a, x, w)`, `slerp(a, x, w)`.
    Replace,
    /// Relative to a reference value `r`: `a + w(x − r)`, `a ⊗ slerp(1, r⁻¹x, w)`,
    /// `a · (1 + w(x/r − 1))`.
    Relative,
    /// The value is itself the difference: `a + w·x`, `a ⊗ slerp(1, x, w)`, `a · (1 + w(x − 1))`.
    Additive,
}

/// A weight clamped to 0..1; 0 for NaN.
fn unit_weight(w: f32) -> f32 {
    if w.is_nan() {
        0.0
    } else {
        w.clamp(0.0, 1.0)
    }
}

fn unit(q: Quat) -> Quat {
    if q.is_finite() && q.length_squared() > 1e-12 {
        q.normalize()
    } else {
        Quat::IDENTITY
    }
}

/// `x / r` per component; 1 where `r` is 0.
fn ratio(x: Vec3, r: Vec3) -> Vec3 {
    Vec3::new(
        if r.x == 0.0 { 1.0 } else { x.x / r.x },
        if r.y == 0.0 { 1.0 } else { x.y / r.y },
        if r.z == 0.0 { 1.0 } else { x.z / r.z },
    )
}

#[derive(Clone, Debug)]
struct StripRig {
    strip: keyrig_core::Strip,
    slots: ActionSlots,
    influence: Slot<f32>,
    /// Root motion continued from the strip before (model-space yaw about +Y, then offset).
    root_offset: Option<RootOffset>,
}

#[derive(Clone, Debug)]
struct TrackRig {
    track: ClipTrack,
    strips: Vec<StripRig>,
}

#[derive(Clone, Debug)]
struct LayerRig {
    slots: ActionSlots,
    weight: Slot<f32>,
    mode: LayerMode,
    plays: bool,
}

/// The clip tracks and layers of one object.
#[derive(Clone, Debug)]
pub(crate) struct ObjectMix {
    tracks: Vec<TrackRig>,
    any_solo: bool,
    layers: Vec<LayerRig>,
    /// What it was built from, to know when to build it again.
    built_from: MixSource,
    plays_active: bool,
}

/// What an object's mix depends on: its tracks, the actions they and the layers play, the
/// layers, and the object's active action.
#[derive(Clone, Debug, PartialEq)]
pub(crate) struct MixSource {
    tracks: Vec<ClipTrack>,
    layers: Vec<keyrig_core::Layer>,
    actions: Vec<(String, Vec<keyrig_core::ActionChannel>)>,
    active: Option<String>,
    fps: f64,
}

impl MixSource {
    pub(crate) fn of(scene: &Scene, o: usize) -> Option<Self> {
        let object = &scene.objects[o];
        if object.clip_tracks.is_empty() && scene.layers.is_empty() {
            return None;
        }
        let names = scene.mixed_action_names(o);
        Some(MixSource {
            tracks: object.clip_tracks.clone(),
            layers: scene.layers.clone(),
            actions: names
                .into_iter()
                .filter_map(|n| scene.action_index(n))
                .map(|a| (scene.actions[a].name.clone(), scene.actions[a].channels.clone()))
                .collect(),
            active: object.action.clone(),
            fps: scene.fps,
        })
    }
}

impl ObjectMix {
    /// The mix of object `o`; `None` when it has no clip tracks and the scene no layers.
    pub(crate) fn new(scene: &Scene, o: usize) -> Option<Self> {
        let built_from = MixSource::of(scene, o)?;
        let object = &scene.objects[o];
        let fps = scene.fps;
        let mut all_slots: Vec<Vec<ActionSlots>> = object
            .clip_tracks
            .iter()
            .map(|track| {
                track
                    .strips
                    .iter()
                    .map(|strip| {
                        let mut slots = ActionSlots::new(scene, o, &strip.action);
                        slots.set_reference(strip.action_in / fps);
                        slots
                    })
                    .collect()
            })
            .collect();
        let frame = RootFrame::of(scene, o, &all_slots.iter().flatten().collect::<Vec<_>>());
        let any_solo = object.clip_tracks.iter().any(|t| t.solo);
        let mut tracks: Vec<TrackRig> = Vec::with_capacity(object.clip_tracks.len());
        for (track, track_slots) in object.clip_tracks.iter().zip(&mut all_slots) {
            let mut strips: Vec<StripRig> = Vec::with_capacity(track.strips.len());
            for (strip, slots) in track.strips.iter().zip(track_slots.drain(..)) {
                let influence = Slot::new(&strip.influence, ChannelId::ObjectTranslation(o));
                // The strip before: the one before it on its track, else the one playing at its
                // start on the nearest playing track below.
                let before = strips.last().or_else(|| {
                    tracks.iter().rev().filter(|t| t.track.plays(any_solo)).find_map(|t| {
                        let at = t.track.strip_at(strip.start)?;
                        t.strips.get(at.strip)
                    })
                });
                let root_offset = if strip.continue_root {
                    before.and_then(|before| root_offset(scene, o, frame, before, strip, &slots, fps))
                } else {
                    None
                };
                strips.push(StripRig { strip: strip.clone(), slots, influence, root_offset });
            }
            tracks.push(TrackRig { track: track.clone(), strips });
        }
        let any_layer_solo = scene.layers.iter().any(|l| l.solo);
        let layers = scene
            .layers
            .iter()
            .map(|layer| LayerRig {
                slots: ActionSlots::new(scene, o, &layer.action),
                weight: Slot::new(&layer.weight, ChannelId::ObjectTranslation(o)),
                mode: layer.mode,
                plays: layer.plays(any_layer_solo),
            })
            .filter(|l| l.slots.channel_count() > 0)
            .collect();
        let plays_active = object.action.as_ref().is_some_and(|active| {
            object.clip_tracks.iter().flat_map(|t| &t.strips).any(|s| &s.action == active)
                || scene.layers.iter().any(|l| &l.action == active)
        });
        Some(ObjectMix { plays_active, any_solo, tracks, layers, built_from })
    }

    /// True when the mix was built from what `scene` holds for object `o` now.
    pub(crate) fn is_current(mix: Option<&Self>, scene: &Scene, o: usize) -> bool {
        let source = MixSource::of(scene, o);
        match (mix, source) {
            (None, None) => true,
            (Some(mix), Some(source)) => mix.built_from == source,
            _ => false,
        }
    }

    /// True when a strip plays the object's active action (its slots read the object's own
    /// channels, so an edit of those rebuilds the mix).
    pub(crate) fn plays_active(&self) -> bool {
        self.plays_active
    }

    pub(crate) fn channel_count(&self) -> usize {
        self.tracks.iter().flat_map(|t| &t.strips).map(|s| s.slots.channel_count()).sum::<usize>()
            + self.layers.iter().map(|l| l.slots.channel_count()).sum::<usize>()
    }

    /// Blends the strips playing at `time` seconds into `pose` (the channels' static values).
    pub(crate) fn strips_into(&self, pose: &mut PoseValues, time: f64) {
        let fps = self.built_from.fps;
        let frame = time * fps;
        for track in &self.tracks {
            if !track.track.plays(self.any_solo) {
                continue;
            }
            let Some(at) = track.track.strip_at(frame) else { continue };
            let rig = &track.strips[at.strip];
            if !rig.strip.is_playable() {
                continue;
            }
            let w = unit_weight(at.ramp as f32 * unit_weight(rig.influence.sample(time)));
            if w <= 0.0 {
                continue;
            }
            let mode = match rig.strip.blend {
                StripBlend::Replace => Blend::Replace,
                StripBlend::Combine => Blend::Relative,
                StripBlend::Add => Blend::Additive,
            };
            let root = rig.root_offset.as_ref().filter(|_| mode == Blend::Replace);
            rig.slots.blend_into(pose, at.action_frame / fps, w, mode, root);
        }
    }

    /// Blends the layers playing at `time` seconds into `pose`.
    pub(crate) fn layers_into(&self, pose: &mut PoseValues, time: f64) {
        for layer in self.layers.iter().filter(|l| l.plays) {
            let w = unit_weight(layer.weight.sample(time));
            if w <= 0.0 {
                continue;
            }
            let mode = match layer.mode {
                LayerMode::Override => Blend::Replace,
                LayerMode::Additive => Blend::Additive,
            };
            layer.slots.blend_into(pose, time, w, mode, None);
        }
    }
}

/// A root value moved by a strip's root offset, in the channel's own terms.
struct MovedRoot {
    joint: Option<usize>,
    translation: Vec3,
    rotation: Quat,
}

impl MovedRoot {
    fn is(&self, target: PoseTarget) -> bool {
        match self.joint {
            None => target == PoseTarget::Translation,
            Some(_) => target == PoseTarget::JointTranslation(0),
        }
    }
}

/// Where the root is: joint 0 of a skeleton (with its rest transform and the skeleton's root
/// translation), or the object itself.
#[derive(Clone, Copy, Debug)]
enum RootFrame {
    Object,
    Joint { rest_translation: Vec3, rest_rotation: Quat },
}

/// A strip's root motion continued (docs/clips.md, "Root motion"): the root's model-space
/// position `p` and rotation `q` become `yaw·p + offset` and `yaw·q`.
#[derive(Clone, Copy, Debug)]
pub(crate) struct RootOffset {
    frame: RootFrame,
    yaw: Quat,
    offset: Vec3,
}

impl RootFrame {
    /// The object itself when an action its strips play keys its translation, else joint 0
    /// of its skeleton (when it is a root), else the object.
    fn of(scene: &Scene, o: usize, strips: &[&ActionSlots]) -> Self {
        let moves_object =
            strips.iter().any(|slots| slots.vec3.iter().any(|(t, _, _)| *t == PoseTarget::Translation));
        match scene.objects[o].skeleton.as_ref().and_then(|s| s.joints.first()) {
            Some(j) if j.parent.is_none() && !moves_object => {
                RootFrame::Joint { rest_translation: j.rest_translation, rest_rotation: j.rest_rotation }
            }
            _ => RootFrame::Object,
        }
    }

    fn joint(self) -> Option<usize> {
        match self {
            RootFrame::Object => None,
            RootFrame::Joint { .. } => Some(0),
        }
    }

    /// The root's model-space position and rotation from its channel values.
    fn model_of(self, root_shift: Vec3, (t, q): (Vec3, Quat)) -> (Vec3, Quat) {
        match self {
            RootFrame::Object => (t, q),
            RootFrame::Joint { rest_translation, rest_rotation } => {
                (root_shift + rest_translation + rest_rotation * t, rest_rotation * q)
            }
        }
    }

    /// The channel values that put the root at model-space `(p, q)`.
    fn channels_of(self, root_shift: Vec3, (p, q): (Vec3, Quat)) -> (Vec3, Quat) {
        match self {
            RootFrame::Object => (p, q),
            RootFrame::Joint { rest_translation, rest_rotation } => {
                let r = rest_rotation.inverse();
                (r * (p - root_shift - rest_translation), unit(r * q))
            }
        }
    }
}

impl RootOffset {
    fn moved(&self, slots: &ActionSlots, pose: &PoseValues, t: f64) -> MovedRoot {
        let joint = self.frame.joint();
        let (p, q) = self.frame.model_of(pose.root, slots.root_at(pose, joint, t));
        let (translation, rotation) =
            self.frame.channels_of(pose.root, (self.yaw * p + self.offset, self.yaw * q));
        MovedRoot { joint, translation, rotation }
    }
}

/// The heading of rotation `q` about +Y (radians): where it turns +Z, seen from above (+X when
/// +Z turns vertical).
fn heading(q: Quat) -> f32 {
    let mut v = q * Vec3::Z;
    if v.x.hypot(v.z) < 1e-3 {
        v = q * Vec3::X;
        return v.x.atan2(v.z) - std::f32::consts::FRAC_PI_2;
    }
    v.x.atan2(v.z)
}

/// The static values of object `o`'s pose channels: the pose below every strip.
pub(crate) fn base_pose(scene: &Scene, o: usize, pose: &mut PoseValues) {
    let object = &scene.objects[o];
    pose.translation = object.translation.value;
    pose.rotation = unit(match &object.rotation_euler {
        Some(e) => object.rotation_mode.euler().unwrap_or_default().to_quat(e.value),
        None => object.rotation.value,
    });
    pose.scale = object.scale.value;
    pose.joint_translations.clear();
    pose.joint_rotations.clear();
    pose.joint_scales.clear();
    pose.root = Vec3::ZERO;
    if let Some(s) = &object.skeleton {
        pose.root = s.root_translation.value;
        for j in &s.joints {
            pose.joint_translations.push(j.translation.value);
            pose.joint_rotations.push(unit(match &j.rotation_euler {
                Some(e) => j.rotation_mode.euler().unwrap_or_default().to_quat(e.value),
                None => j.rotation.value,
            }));
            pose.joint_scales.push(j.scale.value);
        }
    }
}

/// The offset that makes `strip` (its action's channels `slots`) start where `before` left
/// the root: horizontal position and heading matched at `strip.start`.
fn root_offset(
    scene: &Scene,
    o: usize,
    frame: RootFrame,
    before: &StripRig,
    strip: &keyrig_core::Strip,
    slots: &ActionSlots,
    fps: f64,
) -> Option<RootOffset> {
    let joint = frame.joint();
    let mut base = PoseValues::default();
    base_pose(scene, o, &mut base);
    // Where the strip before leaves the root (its own offset applied).
    let t_before = before.strip.action_frame(strip.start) / fps;
    let (p_before, q_before) = match &before.root_offset {
        Some(offset) => {
            let m = offset.moved(&before.slots, &base, t_before);
            frame.model_of(base.root, (m.translation, m.rotation))
        }
        None => frame.model_of(base.root, before.slots.root_at(&base, joint, t_before)),
    };
    let t_start = strip.action_frame(strip.start) / fps;
    let (p_start, q_start) = frame.model_of(base.root, slots.root_at(&base, joint, t_start));
    let turn = heading(q_before) - heading(q_start);
    if !turn.is_finite() {
        return None;
    }
    let yaw = Quat::from_rotation_y(turn);
    let moved = yaw * p_start;
    let offset = Vec3::new(p_before.x - moved.x, 0.0, p_before.z - moved.z);
    offset.is_finite().then_some(RootOffset { frame, yaw, offset })
}
