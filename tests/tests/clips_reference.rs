//! Clip tracks and layers checked against an evaluator written from docs/clips.md alone (not
//! keyrig-eval's mix): the time arithmetic, ramps, weights, blend modes, root motion and layers
//! of `assets/clips.ron` and of random strips, at every frame.
//!
//! The only library code the reference uses is sampling one action's keys: the object plays
//! that action alone (no tracks, no layers) in a copy of the scene and
//! `SceneEvaluator::value` reads a channel at the action time the reference computed.

use std::collections::HashMap;

use glam::{Quat, Vec3};
use keyrig_core::channel_id::{ChannelId, ChannelValue};
use keyrig_core::{
    Action, Animated, ClipTrack, Extrapolation, Interpolation, Joint, Key, Layer, LayerMode, Object,
    RawTrack, Scene, Skeleton, Strip, StripBlend,
};
use keyrig_eval::{Overrides, SceneEvaluator};
use proptest::prelude::*;

/// One action's keys, sampled through the library's key evaluation only.
struct ActionSampler {
    eval: SceneEvaluator,
    keyed: Vec<ChannelId>,
}

/// The pose channels of one object.
#[derive(Clone, Debug)]
struct PoseRef {
    translation: Vec3,
    rotation: Quat,
    scale: Vec3,
    root: Vec3,
    jt: Vec<Vec3>,
    jr: Vec<Quat>,
    js: Vec<Vec3>,
}

/// The channel a keyed id sets, with Euler ids read as their rotation.
fn pose_id(id: ChannelId) -> Option<ChannelId> {
    Some(match id {
        ChannelId::ObjectEuler(o) => ChannelId::ObjectRotation(o),
        ChannelId::JointEuler { object, joint } => ChannelId::JointRotation { object, joint },
        ChannelId::ObjectTranslation(_)
        | ChannelId::ObjectRotation(_)
        | ChannelId::ObjectScale(_)
        | ChannelId::RootTranslation(_)
        | ChannelId::JointTranslation { .. }
        | ChannelId::JointRotation { .. }
        | ChannelId::JointScale { .. } => id,
        _ => return None,
    })
}

struct Reference<'a> {
    scene: &'a Scene,
    /// By (object, action name).
    samplers: HashMap<(usize, String), ActionSampler>,
    /// The scene's own channels (the active actions).
    own: SceneEvaluator,
}

fn unit(q: Quat) -> Quat {
    if q.is_finite() && q.length_squared() > 1e-12 {
        q.normalize()
    } else {
        Quat::IDENTITY
    }
}

impl<'a> Reference<'a> {
    fn new(scene: &'a Scene) -> Self {
        let mut plain = scene.clone();
        plain.layers.clear();
        for o in &mut plain.objects {
            o.clip_tracks.clear();
        }
        let own = SceneEvaluator::new(&plain, &HashMap::new());
        let mut samplers = HashMap::new();
        for o in 0..scene.objects.len() {
            let names: Vec<String> = scene.objects[o]
                .clip_tracks
                .iter()
                .flat_map(|t| t.strips.iter().map(|s| s.action.clone()))
                .chain(scene.layers.iter().map(|l| l.action.clone()))
                .collect();
            for name in names {
                if samplers.contains_key(&(o, name.clone())) {
                    continue;
                }
                let mut alone = plain.clone();
                alone.assign_action(o, Some(&name)).expect("the action exists");
                let keyed = alone.keyed_channels_of(o);
                samplers.insert(
                    (o, name),
                    ActionSampler { eval: SceneEvaluator::new(&alone, &HashMap::new()), keyed },
                );
            }
        }
        Reference { scene, samplers, own }
    }

    /// The static values (docs/clips.md, "The stack", 1).
    fn base(&self, o: usize) -> PoseRef {
        let object = &self.scene.objects[o];
        let rotation = |a: &Animated<Quat>, e: &Option<Animated<Vec3>>, m: keyrig_core::RotationMode| {
            unit(match e {
                Some(e) => m.euler().unwrap_or_default().to_quat(e.value),
                None => a.value,
            })
        };
        let s = object.skeleton.as_ref();
        PoseRef {
            translation: object.translation.value,
            rotation: rotation(&object.rotation, &object.rotation_euler, object.rotation_mode),
            scale: object.scale.value,
            root: s.map_or(Vec3::ZERO, |s| s.root_translation.value),
            jt: s.map_or(vec![], |s| s.joints.iter().map(|j| j.translation.value).collect()),
            jr: s.map_or(vec![], |s| {
                s.joints.iter().map(|j| rotation(&j.rotation, &j.rotation_euler, j.rotation_mode)).collect()
            }),
            js: s.map_or(vec![], |s| s.joints.iter().map(|j| j.scale.value).collect()),
        }
    }

    /// The strip of `track` at frame `f`, with its action frame and ramp ("Strips and time").
    fn strip_at(track: &ClipTrack, f: f64) -> Option<(usize, f64, f64)> {
        let mut chosen = None;
        for (i, s) in track.strips.iter().enumerate() {
            if s.start <= f {
                chosen = Some(i);
            }
        }
        let i = match chosen {
            Some(i) => {
                let s = &track.strips[i];
                let end = s.start + (s.action_out - s.action_in) * s.repeat / s.speed;
                if f > end && s.extrapolation == Extrapolation::Nothing {
                    return None;
                }
                i
            }
            None if track.strips.first()?.extrapolation == Extrapolation::Hold => 0,
            None => return None,
        };
        let s = &track.strips[i];
        let l = s.action_out - s.action_in;
        let r = s.repeat;
        let length = l * r / s.speed;
        let end = s.start + length;
        let g = f.max(s.start).min(end);
        let u = ((g - s.start) * s.speed).max(0.0).min(l * r);
        let w = if u < l * r { u - l * (u / l).floor() } else { l * r - l * (r.ceil() - 1.0) };
        let frame = if s.reverse { s.action_out - w } else { s.action_in + w };
        let mut ramp: f64 = 1.0;
        if s.blend_in > 0.0 {
            ramp = ramp.min((g - s.start) / s.blend_in);
        }
        if s.blend_out > 0.0 {
            ramp = ramp.min((end - g) / s.blend_out);
        }
        Some((i, frame, ramp.clamp(0.0, 1.0)))
    }

    fn sample(&self, o: usize, action: &str, id: ChannelId, t: f64) -> ChannelValue {
        let sampler = &self.samplers[&(o, action.to_owned())];
        sampler.eval.value(id, t, &Overrides::new()).expect("a keyed channel")
    }

    /// Blends one action's keyed channels at action time `t` into `pose`.
    #[allow(clippy::too_many_arguments)]
    fn blend(
        &self,
        pose: &mut PoseRef,
        o: usize,
        action: &str,
        t: f64,
        w: f32,
        mode: StripBlend,
        reference_time: Option<f64>,
        root: Option<(Quat, Vec3)>,
    ) {
        let keyed = self.samplers[&(o, action.to_owned())].keyed.clone();
        let moved_root = root.map(|(yaw, d)| {
            let (p, q) = self.root_model(o, action, t, pose);
            self.root_channels(o, (yaw * p + d, yaw * q), pose.root)
        });
        let root_id = self.root_ids(o);
        let mut ids: Vec<ChannelId> = keyed.iter().filter_map(|&id| pose_id(id)).collect();
        if moved_root.is_some() {
            for id in [root_id.0, root_id.1] {
                if !ids.contains(&id) {
                    ids.push(id);
                }
            }
        }
        for id in ids {
            let value = match (moved_root, id) {
                (Some((t_root, _)), id) if id == root_id.0 => ChannelValue::Vec3(t_root),
                (Some((_, q_root)), id) if id == root_id.1 => ChannelValue::Rotation(q_root),
                _ => self.sample(o, action, id, t),
            };
            let reference = reference_time.map(|r| self.sample(o, action, id, r));
            let is_scale = matches!(id, ChannelId::ObjectScale(_) | ChannelId::JointScale { .. });
            match (value, slot_of(pose, id)) {
                (ChannelValue::Vec3(x), Slot::V(a)) => {
                    *a = match mode {
                        StripBlend::Replace => *a + (x - *a) * w,
                        StripBlend::Combine => {
                            let Some(ChannelValue::Vec3(r)) = reference else { unreachable!() };
                            if is_scale {
                                let q = Vec3::select(r.cmpeq(Vec3::ZERO), Vec3::ONE, x / r);
                                *a * (Vec3::ONE + (q - Vec3::ONE) * w)
                            } else {
                                *a + (x - r) * w
                            }
                        }
                        StripBlend::Add if is_scale => *a * (Vec3::ONE + (x - Vec3::ONE) * w),
                        StripBlend::Add => *a + x * w,
                    };
                }
                (ChannelValue::Rotation(x), Slot::Q(a)) => {
                    let x = unit(x);
                    *a = unit(match mode {
                        StripBlend::Replace => a.slerp(x, w),
                        StripBlend::Combine => {
                            let Some(ChannelValue::Rotation(r)) = reference else { unreachable!() };
                            *a * Quat::IDENTITY.slerp(unit(r).inverse() * x, w)
                        }
                        StripBlend::Add => *a * Quat::IDENTITY.slerp(x, w),
                    });
                }
                _ => {}
            }
        }
    }

    /// The ids of the root's translation and rotation ("Root motion").
    fn root_ids(&self, o: usize) -> (ChannelId, ChannelId) {
        match self.rest0(o) {
            Some(_) => (
                ChannelId::JointTranslation { object: o, joint: 0 },
                ChannelId::JointRotation { object: o, joint: 0 },
            ),
            None => (ChannelId::ObjectTranslation(o), ChannelId::ObjectRotation(o)),
        }
    }

    /// Joint 0's rest transform when it is the root: it is a root joint and no action the
    /// object's strips play keys the object's translation (then the object is the root).
    fn rest0(&self, o: usize) -> Option<(Vec3, Quat)> {
        let moves_object =
            self.scene.objects[o].clip_tracks.iter().flat_map(|t| &t.strips).any(|s| {
                self.samplers[&(o, s.action.clone())].keyed.contains(&ChannelId::ObjectTranslation(o))
            });
        let j = self.scene.objects[o].skeleton.as_ref()?.joints.first()?;
        (j.parent.is_none() && !moves_object).then_some((j.rest_translation, j.rest_rotation))
    }

    /// The root in model space in action `action` at time `t`, from `pose` where not keyed.
    fn root_model(&self, o: usize, action: &str, t: f64, pose: &PoseRef) -> (Vec3, Quat) {
        let keyed = &self.samplers[&(o, action.to_owned())].keyed;
        let (ti, ri) = self.root_ids(o);
        let is_keyed = |id: ChannelId| keyed.iter().any(|&k| pose_id(k) == Some(id));
        let tr = if is_keyed(ti) {
            match self.sample(o, action, ti, t) {
                ChannelValue::Vec3(v) => v,
                _ => unreachable!(),
            }
        } else if self.rest0(o).is_some() {
            pose.jt[0]
        } else {
            pose.translation
        };
        let q = if is_keyed(ri) {
            match self.sample(o, action, ri, t) {
                ChannelValue::Rotation(q) => unit(q),
                _ => unreachable!(),
            }
        } else if self.rest0(o).is_some() {
            pose.jr[0]
        } else {
            pose.rotation
        };
        match self.rest0(o) {
            Some((rt, rr)) => (pose.root + rt + rr * tr, rr * q),
            None => (tr, q),
        }
    }

    fn root_channels(&self, o: usize, (p, q): (Vec3, Quat), root: Vec3) -> (Vec3, Quat) {
        match self.rest0(o) {
            Some((rt, rr)) => (rr.inverse() * (p - root - rt), unit(rr.inverse() * q)),
            None => (p, q),
        }
    }

    /// The root offsets of every track's strips, bottom-up and in strip order.
    fn root_offsets(&self, o: usize) -> Vec<Vec<Option<(Quat, Vec3)>>> {
        let tracks = &self.scene.objects[o].clip_tracks;
        let any_solo = tracks.iter().any(|t| t.solo);
        let mut all: Vec<Vec<Option<(Quat, Vec3)>>> = Vec::new();
        for (k, track) in tracks.iter().enumerate() {
            let mut out = Vec::new();
            for (i, s) in track.strips.iter().enumerate() {
                // The strip before: on this track, else playing at the start below.
                let before = if i > 0 {
                    Some((&track.strips[i - 1], out[i - 1]))
                } else {
                    (0..k).rev().filter(|&b| !tracks[b].mute && (!any_solo || tracks[b].solo)).find_map(|b| {
                        let (j, _, _) = Self::strip_at(&tracks[b], s.start)?;
                        Some((&tracks[b].strips[j], all[b][j]))
                    })
                };
                out.push(match before {
                    Some((before, offset)) if s.continue_root => Some(self.root_offset(o, before, offset, s)),
                    _ => None,
                });
            }
            all.push(out);
        }
        all
    }

    fn root_offset(
        &self,
        o: usize,
        before: &Strip,
        before_offset: Option<(Quat, Vec3)>,
        s: &Strip,
    ) -> (Quat, Vec3) {
        let fps = self.scene.fps;
        let base = self.base(o);
        let heading = |q: Quat| {
            let v = q * Vec3::Z;
            if v.x.hypot(v.z) < 1e-3 {
                let v = q * Vec3::X;
                v.x.atan2(v.z) - std::f32::consts::FRAC_PI_2
            } else {
                v.x.atan2(v.z)
            }
        };
        let tb = before.action_frame(s.start) / fps;
        let (mut p0, mut q0) = self.root_model(o, &before.action, tb, &base);
        if let Some((yaw, d)) = before_offset {
            (p0, q0) = (yaw * p0 + d, yaw * q0);
        }
        let first = if s.reverse { s.action_out } else { s.action_in };
        let (p1, q1) = self.root_model(o, &s.action, first / fps, &base);
        let yaw = Quat::from_rotation_y(heading(q0) - heading(q1));
        let m = yaw * p1;
        (yaw, Vec3::new(p0.x - m.x, 0.0, p0.z - m.z))
    }

    /// Object `o`'s pose channels at time `t` (docs/clips.md, "The stack").
    fn pose(&self, o: usize, t: f64) -> PoseRef {
        let object = &self.scene.objects[o];
        let fps = self.scene.fps;
        let f = t * fps;
        let mut pose = self.base(o);
        let any_solo = object.clip_tracks.iter().any(|t| t.solo);
        let all_offsets = self.root_offsets(o);
        for (k, track) in object.clip_tracks.iter().enumerate() {
            if track.mute || (any_solo && !track.solo) {
                continue;
            }
            let offsets = &all_offsets[k];
            let Some((i, frame, ramp)) = Self::strip_at(track, f) else { continue };
            let s = &track.strips[i];
            let influence = s.influence.sample_reference(t).clamp(0.0, 1.0);
            let w = (ramp as f32 * influence).clamp(0.0, 1.0);
            if w <= 0.0 {
                continue;
            }
            let reference = (s.blend == StripBlend::Combine).then_some(s.action_in / fps);
            let root = offsets[i].filter(|_| s.blend == StripBlend::Replace);
            self.blend(&mut pose, o, &s.action, frame / fps, w, s.blend, reference, root);
        }
        // The active action replaces what it keys.
        for id in self.scene.keyed_channels_of(o).into_iter().filter_map(pose_id) {
            let value = self.own.value(id, t, &Overrides::new()).expect("own channel");
            match (value, slot_of(&mut pose, id)) {
                (ChannelValue::Vec3(x), Slot::V(a)) => *a = x,
                (ChannelValue::Rotation(x), Slot::Q(a)) => *a = unit(x),
                _ => {}
            }
        }
        let any_layer_solo = self.scene.layers.iter().any(|l| l.solo);
        for layer in &self.scene.layers {
            if layer.mute || (any_layer_solo && !layer.solo) {
                continue;
            }
            let w = layer.weight.sample_reference(t).clamp(0.0, 1.0);
            if w <= 0.0 {
                continue;
            }
            let mode = match layer.mode {
                LayerMode::Override => StripBlend::Replace,
                LayerMode::Additive => StripBlend::Add,
            };
            self.blend(&mut pose, o, &layer.action, t, w, mode, None, None);
        }
        pose
    }
}

enum Slot<'p> {
    V(&'p mut Vec3),
    Q(&'p mut Quat),
    None,
}

fn slot_of(pose: &mut PoseRef, id: ChannelId) -> Slot<'_> {
    match id {
        ChannelId::ObjectTranslation(_) => Slot::V(&mut pose.translation),
        ChannelId::ObjectScale(_) => Slot::V(&mut pose.scale),
        ChannelId::ObjectRotation(_) => Slot::Q(&mut pose.rotation),
        ChannelId::RootTranslation(_) => Slot::V(&mut pose.root),
        ChannelId::JointTranslation { joint, .. } => pose.jt.get_mut(joint).map_or(Slot::None, Slot::V),
        ChannelId::JointRotation { joint, .. } => pose.jr.get_mut(joint).map_or(Slot::None, Slot::Q),
        ChannelId::JointScale { joint, .. } => pose.js.get_mut(joint).map_or(Slot::None, Slot::V),
        _ => Slot::None,
    }
}

/// A keyed scalar's value at `t`: its keys, through keyrig-core's key evaluation (what is
/// checked here is the mix, not the keys).
trait SampleReference {
    fn sample_reference(&self, t: f64) -> f32;
}

impl SampleReference for Animated<f32> {
    fn sample_reference(&self, t: f64) -> f32 {
        keyrig_core::AnimatedTrack::new(self).expect("valid keys").sample(t)
    }
}

/// The largest difference between the library's pose and the reference's over `frames`
/// (translations and scales in units, rotations in degrees).
fn compare(scene: &Scene, frames: std::ops::RangeInclusive<i32>) -> (f32, f32, String) {
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    let library = SceneEvaluator::new(scene, &HashMap::new());
    let reference = Reference::new(scene);
    let (mut worst_v, mut worst_deg, mut at) = (0.0f32, 0.0f32, String::new());
    let mut note = |what: &str, f: i32, v: f32, deg: f32| {
        if v > worst_v || deg > worst_deg {
            at = format!("{what} at frame {f}");
        }
        worst_v = worst_v.max(v);
        worst_deg = worst_deg.max(deg);
    };
    // 2·atan2(|v|, |w|) of a⁻¹b: exact near zero, where acos of the dot product is not.
    let angle = |a: Quat, b: Quat| {
        let d = a.inverse() * b;
        (2.0 * d.xyz().length().atan2(d.w.abs())).to_degrees()
    };
    for f in frames {
        let t = f64::from(f) / scene.fps;
        for o in 0..scene.objects.len() {
            let want = reference.pose(o, t);
            let got = library.object_at(o, t, &Overrides::new()).expect("object");
            let (s, r, tr) = got.world_from_object.to_scale_rotation_translation();
            let name = &scene.objects[o].name;
            note(&format!("{name} translation"), f, (tr - want.translation).abs().max_element(), 0.0);
            note(&format!("{name} scale"), f, (s - want.scale).abs().max_element(), 0.0);
            note(&format!("{name} rotation"), f, 0.0, angle(r, want.rotation));
            if let Some(pose) = &got.pose {
                note(
                    &format!("{name} root"),
                    f,
                    (pose.root_translation - want.root).abs().max_element(),
                    0.0,
                );
                for j in 0..want.jt.len() {
                    let v = (pose.local_translations[j] - want.jt[j])
                        .abs()
                        .max_element()
                        .max((pose.local_scales[j] - want.js[j]).abs().max_element());
                    note(&format!("{name} joint {j}"), f, v, angle(pose.local_rotations[j], want.jr[j]));
                }
            }
        }
    }
    (worst_v, worst_deg, at)
}

/// LINEAR scalar keys (influence, weight).
fn linear(keys: &[(f64, f32)]) -> Animated<f32> {
    Animated::new(
        1.0,
        RawTrack::new(
            keys.iter().map(|&(t, v)| Key::new(t, v).with_interpolation(Interpolation::Linear)).collect(),
        ),
    )
}

fn key_vec3(keys: &[(f64, Vec3)]) -> Animated<Vec3> {
    Animated::new(keys[0].1, RawTrack::new(keys.iter().map(|&(t, v)| Key::new(t, v)).collect()))
}

fn key_quat(keys: &[(f64, Quat)]) -> Animated<Quat> {
    Animated::new(Quat::IDENTITY, RawTrack::new(keys.iter().map(|&(t, v)| Key::new(t, v)).collect()))
}

fn skeleton(s: &mut Scene) -> &mut Skeleton {
    s.objects[0].skeleton.as_mut().expect("skeleton")
}

/// A walker: an object with a two-joint skeleton and three actions keyed in it (Idle, Walk,
/// Turn), plus a layer action (Lift) keyed on its second joint; Walk is active.
fn walker() -> Scene {
    let mut scene = Scene { fps: 24.0, ..Scene::default() };
    let mut object = Object::new("Walker");
    let hips = Joint::new("hips", None, Vec3::new(0.0, 1.0, 0.0), Quat::from_rotation_y(0.3));
    let head = Joint::new("head", Some(0), Vec3::new(0.0, 0.5, 0.0), Quat::IDENTITY);
    object.skeleton = Some(Skeleton::new(vec![hips, head]));
    scene.objects.push(object);
    // Idle: breathing.
    skeleton(&mut scene).joints[1].rotation =
        key_quat(&[(0.0, Quat::IDENTITY), (1.0, Quat::from_rotation_x(0.2)), (2.0, Quat::IDENTITY)]);
    skeleton(&mut scene).joints[0].scale =
        key_vec3(&[(0.0, Vec3::ONE), (1.0, Vec3::new(1.0, 1.1, 1.0)), (2.0, Vec3::ONE)]);
    scene.name_unnamed_keys("Idle");
    scene.new_action(0, "Turn").expect("Turn");
    skeleton(&mut scene).joints[0].rotation = key_quat(&[
        (0.0, Quat::from_rotation_y(0.1)),
        (1.0, Quat::from_rotation_y(1.6)),
        (1.5, Quat::from_rotation_y(2.9)),
    ]);
    skeleton(&mut scene).joints[0].translation =
        key_vec3(&[(0.0, Vec3::new(0.0, 0.0, 0.0)), (1.5, Vec3::new(0.5, 0.0, 1.0))]);
    scene.new_action(0, "Lift").expect("Lift");
    skeleton(&mut scene).joints[1].rotation =
        key_quat(&[(0.0, Quat::from_rotation_x(-0.4)), (0.5, Quat::from_rotation_z(0.3))]);
    scene.new_action(0, "Walk").expect("Walk");
    skeleton(&mut scene).joints[0].translation = key_vec3(&[
        (0.0, Vec3::new(0.0, 0.0, 0.0)),
        (0.5, Vec3::new(0.1, 0.05, 0.7)),
        (1.0, Vec3::new(0.0, 0.0, 1.4)),
    ]);
    skeleton(&mut scene).joints[0].rotation = key_quat(&[
        (0.0, Quat::from_rotation_z(0.05)),
        (0.5, Quat::from_rotation_z(-0.05)),
        (1.0, Quat::from_rotation_z(0.05)),
    ]);
    skeleton(&mut scene).joints[1].rotation =
        key_quat(&[(0.0, Quat::IDENTITY), (0.5, Quat::from_rotation_y(0.3)), (1.0, Quat::IDENTITY)]);
    scene.objects[0].translation = key_vec3(&[(0.0, Vec3::ZERO), (1.0, Vec3::new(0.0, 0.0, 2.0))]);
    // The strips play the stored actions; the active one (Walk) plays above them, so it keys
    // nothing here: move its keys into a stored action "Stride" and leave Walk empty.
    scene.duplicate_action(0, "Stride").expect("Stride");
    scene.assign_action(0, Some("Walk")).expect("Walk");
    scene.new_action(0, "Empty").expect("Empty");
    scene
}

#[test]
fn tracks_layers_and_root_motion_match_the_reference() {
    let mut scene = walker();
    let mut idle = Strip::new("Idle", 0.0, 0.0, 40.0);
    idle.extrapolation = Extrapolation::Hold;
    let mut stride = Strip::new("Stride", 40.0, 0.0, 24.0);
    stride.repeat = 2.5;
    stride.speed = 1.25;
    stride.blend_in = 8.0;
    stride.continue_root = true;
    let mut turn = Strip::new("Turn", 100.0, 6.0, 36.0);
    turn.reverse = true;
    turn.continue_root = true;
    turn.blend_out = 5.0;
    turn.influence = linear(&[(100.0 / 24.0, 0.2), (120.0 / 24.0, 1.0)]);
    let mut breathe = Strip::new("Idle", 10.0, 12.0, 36.0);
    breathe.blend = StripBlend::Combine;
    breathe.extrapolation = Extrapolation::Nothing;
    let mut shake = Strip::new("Turn", 60.0, 0.0, 24.0);
    shake.blend = StripBlend::Add;
    shake.influence = Animated::constant(0.5);
    scene.objects[0].clip_tracks = vec![
        ClipTrack { name: "Base".into(), strips: vec![idle, stride, turn], ..ClipTrack::default() },
        ClipTrack { name: "Over".into(), strips: vec![breathe, shake], ..ClipTrack::default() },
    ];
    let mut lift = Layer::new("Head", "Lift");
    lift.weight = linear(&[(1.0, 0.0), (2.0, 1.0), (3.0, 0.0)]);
    scene.layers = vec![lift];
    let (v, deg, at) = compare(&scene, -10..=160);
    assert!(v < 1e-4 && deg < 0.01, "{v} units, {deg}° ({at})");

    // Root motion: where Turn takes over at full weight, the walker (Stride keys the object's
    // translation, so the object is the root) continues horizontally from where Stride left
    // it, turned to its heading.
    let mut alone = scene.clone();
    alone.layers.clear();
    alone.objects[0].clip_tracks.truncate(1);
    alone.objects[0].clip_tracks[0].strips[2].influence = Animated::constant(1.0);
    let at = |scene: &Scene, f: f64| {
        let eval = SceneEvaluator::new(scene, &HashMap::new());
        eval.object_at(0, f / 24.0, &Overrides::new()).expect("object").world_from_object.translation
    };
    let (before, after) = (at(&alone, 99.999), at(&alone, 100.0));
    assert!(Vec3::from(before - after).with_y(0.0).length() < 1e-3, "{before} → {after}");
    alone.objects[0].clip_tracks[0].strips[2].continue_root = false;
    let after = at(&alone, 100.0);
    assert!(
        Vec3::from(before - after).with_y(0.0).length() > 0.5,
        "without root motion the walker jumps back: {before} → {after}"
    );

    // Override layers, mute and solo.
    scene.layers[0].mode = LayerMode::Override;
    scene.objects[0].clip_tracks[1].solo = true;
    let (v, deg, at) = compare(&scene, 0..=150);
    assert!(v < 1e-4 && deg < 0.01, "{v} units, {deg}° ({at})");
    scene.objects[0].clip_tracks[0].mute = true;
    scene.objects[0].clip_tracks[1].solo = false;
    scene.layers[0].mute = true;
    let (v, deg, at) = compare(&scene, 0..=150);
    assert!(v < 1e-4 && deg < 0.01, "{v} units, {deg}° ({at})");
}

#[test]
fn an_object_without_tracks_plays_its_keys_as_before() {
    let mut scene = walker();
    scene.assign_action(0, Some("Walk")).expect("Walk");
    let (v, deg, at) = compare(&scene, 0..=60);
    assert!(v == 0.0 && deg < 1e-3, "{v} {deg} {at}");
}

fn strip_strategy() -> impl Strategy<Value = (Strip, f64)> {
    (
        prop::sample::select(vec!["Idle", "Stride", "Turn"]),
        0.0..20.0f64,
        0.0..20.0f64,
        4.0..30.0f64,
        0.25..3.0f64,
        0.5..3.0f64,
        any::<bool>(),
        (0.0..1.0f64, 0.0..1.0f64),
        prop::sample::select(vec![StripBlend::Replace, StripBlend::Combine, StripBlend::Add]),
        prop::sample::select(vec![Extrapolation::Hold, Extrapolation::HoldForward, Extrapolation::Nothing]),
        (0.0..=1.0f32, any::<bool>()),
        any::<bool>(),
    )
        .prop_map(
            |(
                action,
                gap,
                action_in,
                len,
                speed,
                repeat,
                reverse,
                (bi, bo),
                blend,
                extrapolation,
                (inf, keyed),
                root,
            )| {
                let mut s = Strip::new(action, 0.0, action_in, action_in + len);
                s.speed = speed;
                s.repeat = repeat;
                s.reverse = reverse;
                let length = s.length();
                s.blend_in = bi * length * 0.5;
                s.blend_out = bo * length * 0.5;
                s.blend = blend;
                s.extrapolation = extrapolation;
                s.influence =
                    if keyed { linear(&[(0.5, inf), (4.0, 1.0 - inf)]) } else { Animated::constant(inf) };
                s.continue_root = root;
                (s, gap)
            },
        )
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 48, .. ProptestConfig::default() })]
    #[test]
    fn random_strips_match_the_reference(
        tracks in prop::collection::vec((prop::collection::vec(strip_strategy(), 1..4), any::<bool>(), any::<bool>()), 1..4),
        layer in prop::option::of((prop::sample::select(vec![LayerMode::Override, LayerMode::Additive]), 0.0..=1.0f32)),
    ) {
        let mut scene = walker();
        for (k, (strips, mute, solo)) in tracks.into_iter().enumerate() {
            let mut start = -5.0;
            let mut placed = Vec::new();
            for (mut s, gap) in strips {
                s.start = start + gap;
                start = s.end();
                placed.push(s);
            }
            scene.objects[0].clip_tracks.push(ClipTrack { name: format!("T{k}"), mute, solo, strips: placed });
        }
        if let Some((mode, weight)) = layer {
            let mut l = Layer::new("L", "Lift");
            l.mode = mode;
            l.weight = Animated::constant(weight);
            scene.layers.push(l);
        }
        let (v, deg, at) = compare(&scene, -8..=130);
        prop_assert!(v < 1e-3 && deg < 0.05, "{} units, {}° ({})", v, deg, at);
    }
}

#[test]
fn actions_used_by_the_tests_exist() {
    let scene = walker();
    for name in ["Idle", "Stride", "Turn", "Lift", "Walk", "Empty"] {
        assert!(scene.action_index(name).is_some(), "{name}");
    }
    let _: &Action = &scene.actions[0];
}

#[test]
fn merge_down_keys_what_the_stack_played() {
    let mut scene = walker();
    let mut idle = Strip::new("Idle", 0.0, 0.0, 40.0);
    idle.extrapolation = Extrapolation::Hold;
    let mut stride = Strip::new("Stride", 30.0, 0.0, 24.0);
    stride.blend_in = 10.0;
    stride.repeat = 2.0;
    stride.continue_root = true;
    scene.objects[0].clip_tracks = vec![
        ClipTrack { name: "Idle".into(), strips: vec![idle], ..ClipTrack::default() },
        ClipTrack { name: "Walk".into(), strips: vec![stride], ..ClipTrack::default() },
    ];
    scene.layers = vec![Layer::new("Head", "Lift")];
    scene.frame_range = keyrig_core::FrameRange { start: 0, end: 90 };
    let before = SceneEvaluator::new(&scene, &HashMap::new());
    let mut merged = scene.clone();
    let report = keyrig_eval::merge_down(&mut merged, 0, 90).expect("merge");
    assert_eq!(report.objects, vec![0]);
    assert_eq!(report.frames, 91);
    assert!(merged.layers.is_empty() && merged.objects[0].clip_tracks.is_empty());
    assert!(merged.problems().is_empty(), "{:?}", merged.problems());
    let after = SceneEvaluator::new(&merged, &HashMap::new());
    for f in 0..=90 {
        let t = f64::from(f) / 24.0;
        let a = before.object_at(0, t, &Overrides::new()).expect("before");
        let b = after.object_at(0, t, &Overrides::new()).expect("after");
        let (pa, pb) = (a.palette.expect("palette"), b.palette.expect("palette"));
        for (j, (x, y)) in pa.model_from_joint.iter().zip(&pb.model_from_joint).enumerate() {
            assert!(x.abs_diff_eq(*y, 1e-5), "frame {f} joint {j}: {x:?} vs {y:?}");
        }
        assert!(a.world_from_object.abs_diff_eq(b.world_from_object, 1e-5), "frame {f}");
    }
}
