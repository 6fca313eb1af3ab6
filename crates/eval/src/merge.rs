//! Merge down (docs/clips.md, "Merge down"): an object's clip tracks and the scene's layers
//! baked into its active action's keys, one key per frame of the mix, so that one action alone
//! plays what the stack played. What `keyrig export --bake` writes for a scene with clips, and
//! the editor's Merge down.

use std::collections::{BTreeSet, HashMap};

use keyrig_core::channel_id::ChannelId;
use keyrig_core::{Animated, Interpolation, Key, RawTrack, Scene};

use crate::bake::BakeError;
use crate::evaluator::{Overrides, SceneEvaluator};

/// What a merge wrote.
#[derive(Clone, Debug, Default, PartialEq, Eq)]
pub struct Merged {
    /// The objects whose mix became keys.
    pub objects: Vec<usize>,
    /// Channels keyed, over all of them.
    pub channels: usize,
    /// Frames keyed on each channel.
    pub frames: usize,
}

/// The pose channels of object `o` that its active action, its strips' actions or the
/// layers' actions key: those the mix can move.
fn mixed_channels(scene: &Scene, o: usize) -> BTreeSet<ChannelId> {
    let object = &scene.objects[o];
    let names = scene.mixed_action_names(o);
    let pose = |id: ChannelId| match id {
        ChannelId::ObjectEuler(o) => Some(ChannelId::ObjectRotation(o)),
        ChannelId::JointEuler { object, joint } => Some(ChannelId::JointRotation { object, joint }),
        ChannelId::ObjectTranslation(_)
        | ChannelId::ObjectRotation(_)
        | ChannelId::ObjectScale(_)
        | ChannelId::RootTranslation(_)
        | ChannelId::JointTranslation { .. }
        | ChannelId::JointRotation { .. }
        | ChannelId::JointScale { .. } => Some(id),
        _ => None,
    };
    let mut ids: BTreeSet<ChannelId> = scene.keyed_channels_of(o).into_iter().filter_map(pose).collect();
    for name in names {
        if scene.action_index(name).is_none() {
            continue;
        }
        let mut alone = scene.clone();
        if alone.assign_action(o, Some(name)).is_ok() {
            ids.extend(alone.keyed_channels_of(o).into_iter().filter_map(pose));
        }
    }
    // Root motion moves the root even where its action does not key it.
    if object.clip_tracks.iter().flat_map(|t| &t.strips).any(|s| s.continue_root) {
        match object.skeleton.as_ref().and_then(|s| s.joints.first()) {
            Some(j) if j.parent.is_none() => {
                ids.insert(ChannelId::JointTranslation { object: o, joint: 0 });
                ids.insert(ChannelId::JointRotation { object: o, joint: 0 });
            }
            _ => {
                ids.insert(ChannelId::ObjectTranslation(o));
                ids.insert(ChannelId::ObjectRotation(o));
            }
        }
    }
    ids
}

/// Bakes what the clip tracks and layers play into the active action of every object they
/// move, over frames `start..=end`: each channel the mix can move gets a LINEAR key at every
/// frame (Euler keys become quaternion keys), then the objects' clip tracks and the scene's
/// layers are removed. An object without an active action gets one named
/// `<object>Merged` (or `.001` after it when taken). IK constraints are left to play on top.
///
/// # Errors
/// An empty range or a scene without a positive fps.
pub fn merge_down(scene: &mut Scene, start: i32, end: i32) -> Result<Merged, BakeError> {
    if start > end {
        return Err(BakeError::EmptyRange { start, end });
    }
    if !(scene.fps.is_finite() && scene.fps > 0.0) {
        return Err(BakeError::BadFps(scene.fps));
    }
    let moved: Vec<usize> = (0..scene.objects.len())
        .filter(|&o| !scene.objects[o].clip_tracks.is_empty() || !scene.layers.is_empty())
        .collect();
    let eval = SceneEvaluator::new(scene, &HashMap::new());
    let fps = scene.fps;
    let mut merged = Merged { frames: (end - start) as usize + 1, ..Merged::default() };
    let none = Overrides::new();
    for &o in &moved {
        let ids = mixed_channels(scene, o);
        if ids.is_empty() {
            continue;
        }
        let mut poses = Vec::with_capacity(merged.frames);
        for f in start..=end {
            let t = f64::from(f) / fps;
            let state =
                eval.object_at_solving(o, t, &none, 0).ok_or(BakeError::NoPose { object: o, frame: f })?;
            poses.push((t, state));
        }
        if scene.objects[o].action.is_none() {
            let name = scene.unused_action_name(&format!("{}Merged", scene.objects[o].name));
            // Keys in no action go into the new one; nothing is lost.
            let _ = scene.duplicate_action(o, &name);
        }
        let object = &mut scene.objects[o];
        for &id in &ids {
            match id {
                ChannelId::ObjectTranslation(_)
                | ChannelId::ObjectRotation(_)
                | ChannelId::ObjectScale(_) => {
                    let keys =
                        poses.iter().map(|(t, s)| (*t, s.world_from_object.to_scale_rotation_translation()));
                    match id {
                        ChannelId::ObjectTranslation(_) => {
                            object.translation =
                                animated(object.translation.value, keys.map(|(t, (_, _, p))| linear(t, p)))
                        }
                        ChannelId::ObjectScale(_) => {
                            object.scale =
                                animated(object.scale.value, keys.map(|(t, (s, _, _))| linear(t, s)))
                        }
                        _ => {
                            object.rotation_euler = None;
                            object.rotation =
                                animated(object.rotation.value, keys.map(|(t, (_, q, _))| linear(t, q)));
                        }
                    }
                }
                ChannelId::RootTranslation(_) => {
                    let Some(skeleton) = object.skeleton.as_mut() else { continue };
                    let keys =
                        poses.iter().filter_map(|(t, s)| Some(linear(*t, s.pose.as_ref()?.root_translation)));
                    skeleton.root_translation = animated(skeleton.root_translation.value, keys);
                }
                ChannelId::JointTranslation { joint, .. }
                | ChannelId::JointRotation { joint, .. }
                | ChannelId::JointScale { joint, .. } => {
                    let Some(j) = object.skeleton.as_mut().and_then(|s| s.joints.get_mut(joint)) else {
                        continue;
                    };
                    let pose = |s: &crate::ObjectState| s.pose.clone();
                    let values = poses.iter().filter_map(|(t, s)| Some((*t, pose(s)?)));
                    match id {
                        ChannelId::JointTranslation { .. } => {
                            j.translation = animated(
                                j.translation.value,
                                values
                                    .filter_map(|(t, p)| Some(linear(t, *p.local_translations.get(joint)?))),
                            );
                        }
                        ChannelId::JointScale { .. } => {
                            j.scale = animated(
                                j.scale.value,
                                values.filter_map(|(t, p)| Some(linear(t, *p.local_scales.get(joint)?))),
                            );
                        }
                        _ => {
                            j.rotation_euler = None;
                            j.rotation = animated(
                                j.rotation.value,
                                values.filter_map(|(t, p)| Some(linear(t, *p.local_rotations.get(joint)?))),
                            );
                        }
                    }
                }
                _ => {}
            }
        }
        object.clip_tracks.clear();
        merged.objects.push(o);
        merged.channels += ids.len();
    }
    scene.layers.clear();
    Ok(merged)
}

/// A LINEAR key.
fn linear<T>(t: f64, v: T) -> Key<T> {
    Key::new(t, v).with_interpolation(Interpolation::Linear)
}

fn animated<T>(value: T, keys: impl Iterator<Item = Key<T>>) -> Animated<T> {
    Animated::new(value, RawTrack::new(keys.collect()))
}
