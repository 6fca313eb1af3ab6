//! The document's edits as data: each change a panel, menu or command asks of the scene is a
//! [`SceneEdit`] value, applied by [`SceneEdit::apply`] and named by [`SceneEdit::label`] (the
//! undo step's name, read from the scene before the edit). An edit can be logged, compared,
//! tested without a window and used by the command line; the editor queues it with its undo
//! grouping (one step, or one step per drag) and applies it through its document.
//!
//! Edits address items by index (objects, lights, cameras, sound clips, keys) as the scene holds
//! them when the edit is applied; an index that no longer exists leaves the scene unchanged.

use glam::Vec3;
use keyrig_core::channel_id::{set_rotation_keys, set_rotation_mode};
use keyrig_core::{
    AimTarget, Animated, ConstraintKind, Cycles, DeformerSettings, FrameRange, Interpolation, KeyType,
    MeshSource, ObjectConstraint, Projection, RotationMode, Scene, Tcb,
};

use crate::camera_edits::convert_lens;
use crate::channels::{self, ChannelId, ChannelValue};
use crate::cleanup::ReduceTolerance;

/// One key of one channel (index into the channel's track).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct KeyRef {
    pub channel: ChannelId,
    pub index: usize,
}

/// Which of a key's interpolation parameters an edit writes: every field that is `Some` is
/// written to each key, the others keep each key's own value (so a slider moved on a mixed
/// selection changes only what it moved).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct KeyParamChange {
    pub interpolation: Option<Interpolation>,
    pub tension: Option<f32>,
    pub continuity: Option<f32>,
    pub bias: Option<f32>,
    pub clamped: Option<bool>,
}

impl KeyParamChange {
    /// The fields that differ between `before` and `after` (what a key inspector's row moved).
    #[must_use]
    pub fn between(before: (Interpolation, Tcb), after: (Interpolation, Tcb)) -> Self {
        let (b, a) = (before.1, after.1);
        let differs = |x: f32, y: f32| (x != y).then_some(y);
        KeyParamChange {
            interpolation: (before.0 != after.0).then_some(after.0),
            tension: differs(b.tension, a.tension),
            continuity: differs(b.continuity, a.continuity),
            bias: differs(b.bias, a.bias),
            clamped: (b.clamped != a.clamped).then_some(a.clamped),
        }
    }

    /// `old` with this change's fields written over it.
    #[must_use]
    pub fn over(&self, (mode, tcb): (Interpolation, Tcb)) -> (Interpolation, Tcb) {
        (
            self.interpolation.unwrap_or(mode),
            Tcb {
                tension: self.tension.unwrap_or(tcb.tension),
                continuity: self.continuity.unwrap_or(tcb.continuity),
                bias: self.bias.unwrap_or(tcb.bias),
                clamped: self.clamped.unwrap_or(tcb.clamped),
            },
        )
    }

    /// What the change sets, as an undo step names it: "interpolation Linear", "tension 0.50".
    #[must_use]
    pub fn describe(&self) -> String {
        if let Some(mode) = self.interpolation {
            match self.clamped {
                Some(true) if mode == Interpolation::Tcb => "interpolation Tcb, clamped".to_owned(),
                _ => format!("interpolation {mode:?}"),
            }
        } else if let Some(t) = self.tension {
            format!("tension {t:.2}")
        } else if let Some(c) = self.continuity {
            format!("continuity {c:.2}")
        } else if let Some(b) = self.bias {
            format!("bias {b:.2}")
        } else if let Some(c) = self.clamped {
            (if c { "clamped" } else { "unclamped" }).to_owned()
        } else {
            "key".to_owned()
        }
    }
}

/// An attribute that starts being animated (a constant channel the animator can then key).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Animate {
    /// An object's material colour, starting from `from` (the colour it shows now).
    Colour { object: usize, from: Vec3 },
    /// A light's range, starting from `from`.
    LightRange { light: usize, from: f32 },
    /// A spot light's cone (cutoff and inner angle, degrees).
    Cone { light: usize, cutoff_deg: f32, inner_angle_deg: f32 },
    /// An object's deformer (Step keys), starting from `value` (`deformer_value` of the kind).
    Deformer { object: usize, value: f32 },
    /// An object's bones-blending zone (fractions of the parent and child bone).
    BlendZone { object: usize, parent: f32, child: f32 },
}

/// One change of the document (docs/ARCHITECTURE.md, "Edits as data").
#[derive(Clone, Debug, PartialEq)]
pub enum SceneEdit {
    /// Writes the changed interpolation parameters to every key of `keys` (the key inspector,
    /// the curve view's interpolation menu).
    KeyParams { keys: Vec<KeyRef>, change: KeyParamChange },
    /// Sets the key type of every key of `keys`.
    KeyType { keys: Vec<KeyRef>, key_type: KeyType },
    /// Gives the segments of `keys` explicit Hermite tangents equal to the curve's now.
    HermiteHandles { keys: Vec<KeyRef> },
    /// Aligns the broken handles of the Hermite keys of `keys`: each component's in- and
    /// out-tangent become their mean, so the next handle drag turns both again.
    AlignHandles { keys: Vec<KeyRef> },
    /// Sets one component of a key's in- or out-tangent (a curve handle drag); with `convert`
    /// the previous key's segment first becomes Hermite. The other handle follows while the two
    /// are aligned, unless `drag` is [`channels::HandleDrag::Free`] (Alt+drag), which breaks them.
    Tangent {
        key: KeyRef,
        outgoing: bool,
        component: usize,
        value: f32,
        convert: bool,
        drag: channels::HandleDrag,
    },
    /// Moves the key of a position `channel` at `time` to `value` (a motion-path key drag).
    MotionPathKey { channel: ChannelId, time: f64, value: Vec3 },
    /// Mutes or unmutes a channel.
    Mute { channel: ChannelId, muted: bool },
    /// Locks or unlocks a channel.
    Lock { channel: ChannelId, locked: bool },
    /// Sets a channel's cycles before and after its keys.
    Cycles { channel: ChannelId, cycles: Cycles },
    /// Sets the rotation mode of a rotation channel; `euler_keys` keys it as Euler angles
    /// (converting the keys), otherwise quaternion keys.
    RotationMode { channel: ChannelId, mode: RotationMode, euler_keys: bool },
    /// Starts animating an attribute.
    Animate(Animate),
    /// Sets an object's deformer settings.
    Deformer { object: usize, settings: DeformerSettings },
    /// The MD2 clip an object's model plays (`None`: every frame).
    ModelClip { object: usize, clip: Option<String> },
    /// The MD2 model's playback rate, frames per second.
    ModelFps { object: usize, fps: f64 },
    /// A camera's projection, converting its lens so the view stays.
    CameraProjection { camera: usize, projection: Projection },
    /// A camera's clip planes.
    CameraClip { camera: usize, near: f32, far: Option<f32> },
    /// What a camera aims at (`None`: its keyed rotation).
    CameraAim { camera: usize, target: Option<AimTarget> },
    /// Appends an object constraint (docs/constraints.md).
    AddConstraint { object: usize, constraint: ObjectConstraint },
    /// Removes an object's constraint `constraint`.
    RemoveConstraint { object: usize, constraint: usize },
    /// Sets the target of an aim-at, copy-location or copy-rotation constraint (other kinds
    /// are left as they are).
    ConstraintTarget { object: usize, constraint: usize, target: AimTarget },
    /// Adds a sound clip.
    AddSound(keyrig_core::SoundClip),
    /// Mutes or unmutes a sound clip.
    SoundMute { clip: usize, muted: bool },
    /// Moves a sound clip to start at `start_frame`.
    SoundStart { clip: usize, start_frame: f64 },
    /// The scene's frame rate; from `origin` (fps, start, end when the change began) so a drag
    /// does not drift; `keep_frames` keeps keys on their frames, else their seconds.
    Retime { origin: (f64, i32, i32), fps: f64, keep_frames: bool },
    /// The scene's frame range.
    FrameRange { start: i32, end: i32 },
    /// The preview range.
    PreviewRange(FrameRange),
    /// The reference image's opacity (clamped to 0..1).
    ReferenceOpacity(f32),
    /// Removes the reference image.
    RemoveReferenceImage,
    /// Makes, copies, renames, deletes or assigns an action (docs/actions.md).
    Action(ActionEdit),
    /// Changes clip tracks, strips or layers (docs/clips.md).
    Clip(ClipEdit),
    /// Reduces the keys of `channels` to within `tolerance` of their curves
    /// ([`crate::cleanup::reduce_keys`], docs/cleanup.md).
    ReduceKeys { channels: Vec<ChannelId>, tolerance: ReduceTolerance },
    /// Smooths `channels` with a Butterworth low-pass at `cutoff_hz`
    /// ([`crate::cleanup::smooth_keys`], docs/cleanup.md).
    SmoothKeys { channels: Vec<ChannelId>, cutoff_hz: f64 },
    /// Puts the action `source`'s object `source_object` plays onto object `object` as a new
    /// action through `map` ([`crate::retarget::retarget`], docs/retargeting.md).
    Retarget {
        source: Box<Scene>,
        source_object: usize,
        object: usize,
        map: crate::retarget::BoneMap,
        options: crate::retarget::RetargetOptions,
    },
}

/// The action edits: each one undo step (docs/actions.md).
#[derive(Clone, Debug, PartialEq)]
pub enum ActionEdit {
    /// Makes `name` (`None`: no action) the active action of `object`.
    Assign { object: usize, name: Option<String> },
    /// A new empty action, made active on `object`.
    New { object: usize, name: String },
    /// A copy of the keys `object` plays, made active under `name`.
    Duplicate { object: usize, name: String },
    /// Renames an action.
    Rename { old: String, new: String },
    /// Deletes an action and its keys.
    Delete { name: String },
}

/// The clip track and layer edits: each one undo step (docs/clips.md).
#[derive(Clone, Debug, PartialEq)]
pub enum ClipEdit {
    /// Pushes `object`'s active action down as a strip on a new top track.
    PushDown { object: usize },
    /// Adds a track on top with one strip playing `action`'s keyed frames from `start`.
    AddStrip { object: usize, action: String, start: f64 },
    /// Replaces a strip (a drag in the clip editor, a field of its menu).
    Strip { object: usize, track: usize, strip: usize, value: keyrig_core::Strip },
    /// Deletes a strip (and its track, when it was the last one there).
    DeleteStrip { object: usize, track: usize, strip: usize },
    /// Mutes or solos a track.
    Track { object: usize, track: usize, mute: bool, solo: bool },
    /// Adds a layer with a new empty action of the same name.
    AddLayer { name: String },
    /// Replaces a layer (its weight, mode, mute or solo).
    Layer { layer: usize, value: keyrig_core::Layer },
    /// Deletes a layer (its action stays).
    DeleteLayer { layer: usize },
    /// Bakes the clip tracks and layers into the active actions over the frame range
    /// (`keyrig_eval::merge_down`).
    MergeDown,
}

impl ClipEdit {
    /// Applies the edit; a refused one changes nothing.
    ///
    /// # Errors
    /// Why the edit was refused, in words for the status bar.
    pub fn apply(&self, scene: &mut Scene) -> Result<(), String> {
        match self {
            ClipEdit::PushDown { object } => scene.push_down(*object).map(drop).map_err(|e| e.to_string()),
            ClipEdit::AddStrip { object, action, start } => {
                if scene.action_index(action).is_none() {
                    return Err(format!("there is no action {action:?}"));
                }
                if *object >= scene.objects.len() {
                    return Err(format!("there is no object {object}"));
                }
                // The frames the action's keys span on this object; without keys, one second.
                let (first, last) = scene.action_frames_on(*object, action).unwrap_or((0.0, scene.fps));
                let last = if last > first { last } else { first + 1.0 };
                scene.push_clip_track(*object, keyrig_core::Strip::new(action.clone(), *start, first, last));
                Ok(())
            }
            ClipEdit::Strip { object, track, strip, value } => {
                let slot = scene
                    .objects
                    .get_mut(*object)
                    .and_then(|o| o.clip_tracks.get_mut(*track))
                    .and_then(|t| t.strips.get_mut(*strip))
                    .ok_or_else(|| format!("there is no strip {strip} on track {track}"))?;
                *slot = value.clone();
                Ok(())
            }
            ClipEdit::DeleteStrip { object, track, strip } => {
                let tracks = scene
                    .objects
                    .get_mut(*object)
                    .map(|o| &mut o.clip_tracks)
                    .ok_or_else(|| format!("there is no object {object}"))?;
                let t = tracks.get_mut(*track).ok_or_else(|| format!("there is no track {track}"))?;
                if *strip >= t.strips.len() {
                    return Err(format!("there is no strip {strip} on track {track}"));
                }
                t.strips.remove(*strip);
                if t.strips.is_empty() {
                    tracks.remove(*track);
                }
                Ok(())
            }
            ClipEdit::Track { object, track, mute, solo } => {
                let t = scene
                    .objects
                    .get_mut(*object)
                    .and_then(|o| o.clip_tracks.get_mut(*track))
                    .ok_or_else(|| format!("there is no track {track}"))?;
                t.mute = *mute;
                t.solo = *solo;
                Ok(())
            }
            ClipEdit::AddLayer { name } => {
                if name.is_empty() || name.contains('/') {
                    return Err(format!("a layer name cannot be empty or contain '/': {name:?}"));
                }
                if scene.layers.iter().any(|l| &l.name == name) {
                    return Err(format!("there is already a layer {name:?}"));
                }
                let action = scene.unused_action_name(name);
                scene.actions.push(keyrig_core::Action { name: action.clone(), channels: Vec::new() });
                scene.layers.push(keyrig_core::Layer::new(name.clone(), action));
                Ok(())
            }
            ClipEdit::Layer { layer, value } => {
                let l = scene.layers.get_mut(*layer).ok_or_else(|| format!("there is no layer {layer}"))?;
                *l = value.clone();
                Ok(())
            }
            ClipEdit::DeleteLayer { layer } => {
                if *layer >= scene.layers.len() {
                    return Err(format!("there is no layer {layer}"));
                }
                scene.layers.remove(*layer);
                Ok(())
            }
            ClipEdit::MergeDown => {
                let (start, end) = (scene.frame_range.start, scene.frame_range.end);
                keyrig_eval::merge_down(scene, start, end).map(drop).map_err(|e| e.to_string())
            }
        }
    }

    /// The undo label.
    fn label(&self, scene: &Scene) -> String {
        let object =
            |o: usize| scene.objects.get(o).map_or_else(|| format!("object {o}"), |x| x.name.clone());
        match self {
            ClipEdit::PushDown { object: o } => format!("push down the action of {}", object(*o)),
            ClipEdit::AddStrip { object: o, action, start } => {
                format!("add a strip of {action} at frame {start} on {}", object(*o))
            }
            ClipEdit::Strip { object: o, value, .. } => format!(
                "strip {} at frames {:.1}–{:.1} on {}",
                value.action,
                value.start,
                value.end(),
                object(*o)
            ),
            ClipEdit::DeleteStrip { object: o, .. } => format!("delete a strip on {}", object(*o)),
            ClipEdit::Track { object: o, track, mute, solo } => {
                let name = scene
                    .objects
                    .get(*o)
                    .and_then(|x| x.clip_tracks.get(*track))
                    .map_or_else(|| format!("track {track}"), |t| t.name.clone());
                match (mute, solo) {
                    (true, _) => format!("mute track {name}"),
                    (false, true) => format!("solo track {name}"),
                    _ => format!("play track {name}"),
                }
            }
            ClipEdit::AddLayer { name } => format!("add layer {name}"),
            ClipEdit::Layer { value, .. } => {
                format!("layer {} {:?}, weight {}", value.name, value.mode, value.weight.value)
            }
            ClipEdit::DeleteLayer { layer } => format!(
                "delete layer {}",
                scene.layers.get(*layer).map_or_else(|| layer.to_string(), |l| l.name.clone())
            ),
            ClipEdit::MergeDown => "merge down clip tracks and layers".to_owned(),
        }
    }
}

impl ActionEdit {
    /// Applies the edit; a refused one (an unknown or taken name) leaves the scene as it was.
    ///
    /// # Errors
    /// Why the edit was refused.
    pub fn apply(&self, scene: &mut Scene) -> Result<(), keyrig_core::ActionError> {
        match self {
            ActionEdit::Assign { object, name } => scene.assign_action(*object, name.as_deref()),
            ActionEdit::New { object, name } => scene.new_action(*object, name),
            ActionEdit::Duplicate { object, name } => scene.duplicate_action(*object, name),
            ActionEdit::Rename { old, new } => scene.rename_action(old, new),
            ActionEdit::Delete { name } => scene.delete_action(name),
        }
    }
}

impl SceneEdit {
    /// Applies the edit to `scene`.
    pub fn apply(&self, scene: &mut Scene) {
        match self {
            SceneEdit::KeyParams { keys, change } => {
                for k in keys {
                    if let Some((_, mode, tcb)) = channels::key_params(scene, k.channel, k.index) {
                        let (m, t) = change.over((mode, tcb));
                        channels::set_key_params(scene, k.channel, k.index, m, t);
                    }
                }
            }
            SceneEdit::KeyType { keys, key_type } => {
                for k in keys {
                    channels::set_key_type(scene, k.channel, k.index, *key_type);
                }
            }
            SceneEdit::HermiteHandles { keys } => {
                let mut by_channel: std::collections::BTreeMap<ChannelId, Vec<usize>> = Default::default();
                for k in keys {
                    by_channel.entry(k.channel).or_default().push(k.index);
                }
                for (id, indices) in by_channel {
                    channels::convert_to_hermite(scene, id, &indices);
                }
            }
            SceneEdit::AlignHandles { keys } => {
                for k in keys {
                    channels::align_tangents(scene, k.channel, k.index);
                }
            }
            &SceneEdit::Tangent { key, outgoing, component, value, convert, drag } => {
                if convert && key.index > 0 {
                    channels::convert_to_hermite(scene, key.channel, &[key.index - 1]);
                }
                channels::set_tangent_component(
                    scene,
                    key.channel,
                    key.index,
                    outgoing,
                    component,
                    value,
                    drag,
                );
            }
            &SceneEdit::MotionPathKey { channel, time, value } => {
                channels::set_key(scene, channel, time, ChannelValue::Vec3(value));
            }
            &SceneEdit::Mute { channel, muted } => {
                channels::set_muted(scene, channel, muted);
            }
            &SceneEdit::Lock { channel, locked } => {
                channels::set_locked(scene, channel, locked);
            }
            &SceneEdit::Cycles { channel, cycles } => {
                channels::set_cycles(scene, channel, cycles);
            }
            &SceneEdit::RotationMode { channel, mode, euler_keys } => {
                let euler = euler_keys && mode.euler().is_some();
                let has_euler = keyrig_core::channel_id::has_euler_keys(scene, channel);
                // Invalid keys cannot be converted; the scene then stays as it is.
                if has_euler || euler {
                    let _ = set_rotation_keys(scene, channel, mode, euler);
                } else {
                    set_rotation_mode(scene, channel, mode);
                }
            }
            SceneEdit::Animate(what) => animate(scene, *what),
            &SceneEdit::Deformer { object, settings } => {
                if let Some(obj) = scene.objects.get_mut(object) {
                    obj.deformer = settings;
                }
            }
            SceneEdit::ModelClip { object, clip: chosen } => {
                if let Some(MeshSource::File { clip, .. }) =
                    scene.objects.get_mut(*object).and_then(|x| x.mesh.as_mut())
                {
                    clip.clone_from(chosen);
                }
            }
            &SceneEdit::ModelFps { object, fps: rate } => {
                if let Some(MeshSource::File { fps, .. }) =
                    scene.objects.get_mut(object).and_then(|x| x.mesh.as_mut())
                {
                    *fps = Some(rate);
                }
            }
            &SceneEdit::CameraProjection { camera, projection } => {
                if let Some(c) = scene.cameras.get_mut(camera) {
                    convert_lens(c, projection);
                }
            }
            &SceneEdit::CameraClip { camera, near, far } => {
                if let Some(c) = scene.cameras.get_mut(camera) {
                    (c.near, c.far) = (near, far);
                }
            }
            SceneEdit::CameraAim { camera, target } => {
                if let Some(c) = scene.cameras.get_mut(*camera) {
                    c.aim = match (target.clone(), c.aim.take()) {
                        (None, _) => None,
                        (Some(target), Some(aim)) => Some(keyrig_core::Aim { target, ..aim }),
                        (Some(target), None) => Some(keyrig_core::Aim::at(target)),
                    };
                }
            }
            SceneEdit::AddConstraint { object, constraint } => {
                if let Some(o) = scene.objects.get_mut(*object) {
                    o.constraints.push(constraint.clone());
                }
            }
            &SceneEdit::RemoveConstraint { object, constraint } => {
                if let Some(o) = scene.objects.get_mut(object).filter(|o| constraint < o.constraints.len()) {
                    o.constraints.remove(constraint);
                }
            }
            SceneEdit::ConstraintTarget { object, constraint, target: new } => {
                let c = scene.objects.get_mut(*object).and_then(|o| o.constraints.get_mut(*constraint));
                if let Some(
                    ConstraintKind::AimAt { target, .. }
                    | ConstraintKind::CopyLocation { target }
                    | ConstraintKind::CopyRotation { target },
                ) = c.map(|c| &mut c.kind)
                {
                    target.clone_from(new);
                }
            }
            SceneEdit::AddSound(clip) => scene.sounds.push(clip.clone()),
            &SceneEdit::SoundMute { clip, muted } => {
                if let Some(c) = scene.sounds.get_mut(clip) {
                    c.mute = muted;
                }
            }
            &SceneEdit::SoundStart { clip, start_frame } => {
                if let Some(c) = scene.sounds.get_mut(clip) {
                    c.start_frame = start_frame;
                }
            }
            &SceneEdit::Retime { origin, fps, keep_frames } => retime(scene, origin, fps, keep_frames),
            SceneEdit::Action(edit) => {
                // Checked before it is queued (the inspector refuses taken and unknown names);
                // a refused edit changes nothing.
                let _ = edit.apply(scene);
            }
            SceneEdit::Clip(edit) => {
                // A refused clip edit (a strip that is gone, a taken layer name) changes nothing.
                let _ = edit.apply(scene);
            }
            &SceneEdit::FrameRange { start, end } => {
                scene.frame_range.start = start;
                scene.frame_range.end = end;
            }
            &SceneEdit::PreviewRange(range) => scene.preview_range = Some(range),
            &SceneEdit::ReferenceOpacity(opacity) => {
                if let Some(image) = &mut scene.reference_image {
                    image.opacity = opacity.clamp(0.0, 1.0);
                }
            }
            SceneEdit::RemoveReferenceImage => scene.reference_image = None,
            // A tolerance or cutoff that is refused changes nothing (the commands check first).
            SceneEdit::ReduceKeys { channels, tolerance } => {
                let _ = crate::cleanup::reduce_keys(scene, channels, *tolerance);
            }
            SceneEdit::SmoothKeys { channels, cutoff_hz } => {
                let _ = crate::cleanup::smooth_keys(scene, channels, *cutoff_hz);
            }
            // A refused retargeting leaves the scene as it was (the dialog checks first).
            SceneEdit::Retarget { source, source_object, object, map, options } => {
                let _ = crate::retarget::retarget(source, *source_object, scene, *object, map, options);
            }
        }
    }

    /// The undo step's name for this edit, read from `scene` as it is before the edit.
    #[must_use]
    pub fn label(&self, scene: &Scene) -> String {
        let object =
            |o: usize| scene.objects.get(o).map_or_else(|| format!("object {o}"), |x| x.name.clone());
        let camera =
            |c: usize| scene.cameras.get(c).map_or_else(|| format!("camera {c}"), |x| x.name.clone());
        let sound = |c: usize| scene.sounds.get(c).map_or_else(|| format!("{c}"), |x| x.label().to_owned());
        match self {
            SceneEdit::KeyParams { keys, change } => {
                format!("{} on {}", change.describe(), keys_named(scene, keys))
            }
            SceneEdit::KeyType { keys, key_type } => {
                format!("key type {} on {}", key_type.label(), keys_named(scene, keys))
            }
            SceneEdit::HermiteHandles { keys } => format!("Hermite handles on {}", keys_named(scene, keys)),
            SceneEdit::AlignHandles { keys } => format!("align handles on {}", keys_named(scene, keys)),
            SceneEdit::Tangent { key, outgoing, .. } => {
                let side = if *outgoing { "out" } else { "in" };
                format!("drag {side} handle of {} key {}", key.channel.label(scene), key.index)
            }
            SceneEdit::MotionPathKey { time, .. } => {
                format!("move the key at frame {} on the motion path", (time * scene.fps).round())
            }
            SceneEdit::Mute { channel, muted } => {
                format!("{} {}", if *muted { "mute" } else { "unmute" }, channel.label(scene))
            }
            SceneEdit::Lock { channel, locked } => {
                format!("{} {}", if *locked { "lock" } else { "unlock" }, channel.label(scene))
            }
            SceneEdit::Cycles { channel, cycles } => {
                let old = channels::cycles(scene, *channel).unwrap_or_default();
                let (end, cycle) = if cycles.before != old.before {
                    ("before", cycles.before)
                } else {
                    ("after", cycles.after)
                };
                format!("{}: {} {end} keys", channel.label(scene), cycle.label())
            }
            SceneEdit::RotationMode { channel, mode, euler_keys } => {
                let name = channel.label(scene);
                let had_euler = keyrig_core::channel_id::has_euler_keys(scene, *channel);
                let euler = *euler_keys && mode.euler().is_some();
                match (had_euler, euler) {
                    (false, true) => format!("Euler keys ({}) for {name}", mode.label()),
                    (true, false) => format!("quaternion keys for {name}"),
                    (true, true) => format!("Euler keys of {name} to {}", mode.label()),
                    (false, false) => format!("rotation mode {} of {name}", mode.label()),
                }
            }
            SceneEdit::Animate(what) => match what {
                Animate::Colour { .. } => "animate colour",
                Animate::LightRange { .. } => "light range",
                Animate::Cone { .. } => "animate cone",
                Animate::Deformer { .. } => "animate deformer",
                Animate::BlendZone { .. } => "animate blend zone",
            }
            .to_owned(),
            SceneEdit::Deformer { settings, .. } => format!("deformer {}", settings.kind.label()),
            SceneEdit::ModelClip { object: o, clip } => {
                format!("{} clip {}", object(*o), clip.as_deref().unwrap_or("all frames"))
            }
            SceneEdit::ModelFps { object: o, .. } => format!("{} model fps", object(*o)),
            SceneEdit::CameraProjection { camera: c, .. } => format!("{} projection", camera(*c)),
            SceneEdit::CameraClip { camera: c, .. } => format!("{} clip planes", camera(*c)),
            SceneEdit::CameraAim { .. } => "camera aim".to_owned(),
            SceneEdit::AddConstraint { object: o, constraint } => {
                format!("add constraint {} to {}", constraint.name, object(*o))
            }
            SceneEdit::RemoveConstraint { object: o, constraint } => format!(
                "remove constraint {} from {}",
                scene
                    .objects
                    .get(*o)
                    .and_then(|x| x.constraints.get(*constraint))
                    .map_or("?", |c| c.name.as_str()),
                object(*o)
            ),
            SceneEdit::ConstraintTarget { object: o, constraint, target } => format!(
                "{} target {}",
                scene
                    .objects
                    .get(*o)
                    .and_then(|x| x.constraints.get(*constraint))
                    .map_or("?", |c| c.name.as_str()),
                target_label(target)
            ),
            SceneEdit::AddSound(clip) => {
                format!("add sound clip {} at frame {}", clip.label(), clip.start_frame)
            }
            SceneEdit::SoundMute { clip, muted } => {
                format!("{} sound clip {}", if *muted { "mute" } else { "unmute" }, sound(*clip))
            }
            SceneEdit::SoundStart { clip, start_frame } => {
                format!("move sound clip {} to frame {start_frame}", sound(*clip))
            }
            SceneEdit::Retime { fps, .. } => format!("change fps to {fps}"),
            SceneEdit::Action(edit) => match edit {
                ActionEdit::Assign { object: o, name: Some(name) } => {
                    format!("play action {name} on {}", object(*o))
                }
                ActionEdit::Assign { object: o, name: None } => format!("no action on {}", object(*o)),
                ActionEdit::New { object: o, name } => format!("new action {name} on {}", object(*o)),
                ActionEdit::Duplicate { object: o, name } => {
                    format!("duplicate action as {name} on {}", object(*o))
                }
                ActionEdit::Rename { old, new } => format!("rename action {old} to {new}"),
                ActionEdit::Delete { name } => format!("delete action {name}"),
            },
            SceneEdit::Clip(edit) => edit.label(scene),
            SceneEdit::FrameRange { start, end } => format!("frame range {start}–{end}"),
            SceneEdit::PreviewRange(r) => format!("preview range {}–{}", r.start, r.end),
            SceneEdit::ReferenceOpacity(_) => "reference image opacity".to_owned(),
            SceneEdit::RemoveReferenceImage => "remove the reference image".to_owned(),
            SceneEdit::ReduceKeys { channels, tolerance } => format!(
                "reduce keys of {} within {}°, {} (distance), {} (value)",
                channels_named(scene, channels),
                tolerance.angle_deg,
                tolerance.distance,
                tolerance.value
            ),
            SceneEdit::SmoothKeys { channels, cutoff_hz } => {
                format!("smooth {} below {cutoff_hz} Hz", channels_named(scene, channels))
            }
            SceneEdit::Retarget { options, object: o, .. } => {
                format!("retarget {} onto {}", options.action, object(*o))
            }
        }
    }
}

/// Channels as an undo step names them: "Hips rotation (Euler °)", "32 channels".
#[must_use]
pub fn channels_named(scene: &Scene, channels: &[ChannelId]) -> String {
    match channels {
        [one] => one.label(scene),
        _ => format!("{} channels", channels.len()),
    }
}

/// Keys as an undo step names them: "elbow rotation key at frame 30", "3 keys".
#[must_use]
pub fn keys_named(scene: &Scene, keys: &[KeyRef]) -> String {
    match keys {
        [k] => {
            let frame = channels::key_params(scene, k.channel, k.index)
                .map_or(0, |p| (p.0 * scene.fps).round() as i64);
            format!("{} key at frame {frame}", k.channel.label(scene))
        }
        many => format!("{} keys", many.len()),
    }
}

fn animate(scene: &mut Scene, what: Animate) {
    match what {
        Animate::Colour { object, from } => {
            if let Some(obj) = scene.objects.get_mut(object) {
                obj.attributes.colour = Some(Animated::constant(from));
            }
        }
        Animate::LightRange { light, from } => {
            if let Some(l) = scene.lights.get_mut(light) {
                l.attributes.range = Some(Animated::constant(from));
            }
        }
        Animate::Cone { light, cutoff_deg, inner_angle_deg } => {
            if let Some(l) = scene.lights.get_mut(light) {
                l.attributes.cutoff_deg = Some(Animated::constant(cutoff_deg));
                l.attributes.inner_angle_deg = Some(Animated::constant(inner_angle_deg));
            }
        }
        Animate::Deformer { object, value } => {
            if let Some(obj) = scene.objects.get_mut(object) {
                obj.attributes.deformer = Some(Animated::constant(value));
            }
        }
        Animate::BlendZone { object, parent, child } => {
            if let Some(obj) = scene.objects.get_mut(object) {
                obj.attributes.blend_parent_fraction = Some(Animated::constant(parent));
                obj.attributes.blend_child_fraction = Some(Animated::constant(child));
            }
        }
    }
}

/// Sets the scene's frame rate to `fps` from `origin` (the fps, start and end when the change
/// began): with `keep_frames` keys stay on their frames (their times scale) and the range stays;
/// otherwise keys keep their seconds and the range's frames scale with the rate.
pub fn retime(scene: &mut Scene, origin: (f64, i32, i32), fps: f64, keep_frames: bool) {
    let (old_fps, start, end) = origin;
    let current = scene.fps;
    if keep_frames {
        channels::scale_key_times(scene, current / fps);
        scene.frame_range.start = start;
        scene.frame_range.end = end;
    } else {
        let ratio = fps / old_fps;
        let s = (f64::from(start) * ratio).round() as i32;
        let e = ((f64::from(end) * ratio).round() as i32).max(s + 1);
        scene.frame_range.start = s;
        scene.frame_range.end = e;
    }
    scene.fps = fps;
}

/// A target as the editor shows it: `Cube`, `Arm / wrist`, `point (1.00, 0.00, 2.00)`.
#[must_use]
pub fn target_label(target: &AimTarget) -> String {
    match target {
        AimTarget::Object(o) => o.clone(),
        AimTarget::Joint { object, joint } => format!("{object} / {joint}"),
        AimTarget::Point(p) => format!("point ({:.2}, {:.2}, {:.2})", p.x, p.y, p.z),
    }
}

/// A new constraint of the kind labelled `kind` (an [`ConstraintKind::label`]) for object
/// `object`, named after its kind and unique among the object's constraints, aimed at `target`
/// (a follow path: a straight path 2 units along +X from where the object is, in world space;
/// a child of: `target` as its only parent, in effect from the start, with no offset, so the
/// object's own transform is read in the parent's frame). `None` for an unknown kind or object.
#[must_use]
pub fn new_constraint(
    scene: &Scene,
    object: usize,
    kind: &str,
    target: AimTarget,
) -> Option<ObjectConstraint> {
    let o = scene.objects.get(object)?;
    let at = o.translation.value;
    let kind = match kind {
        "Aim at" => ConstraintKind::AimAt { target, axis: keyrig_core::AimAxis::NegZ, up: Vec3::Y },
        "Copy location" => ConstraintKind::CopyLocation { target },
        "Copy rotation" => ConstraintKind::CopyRotation { target },
        "Child of" => ConstraintKind::ChildOf {
            parents: vec![keyrig_core::ChildOfParent::new(target)],
            parent: Animated::constant(0.0),
        },
        "Follow path" => ConstraintKind::FollowPath {
            points: vec![at, at + Vec3::new(2.0, 0.0, 0.0)],
            space: None,
            offset: Animated::constant(0.0),
            axis: None,
        },
        _ => return None,
    };
    let base = kind.label();
    let taken = |name: &str| o.constraints.iter().any(|c| c.name == name);
    let name = std::iter::once(base.to_owned())
        .chain((2..).map(|i| format!("{base} {i}")))
        .find(|n| !taken(n))
        .expect("an unbounded list of names");
    Some(ObjectConstraint::new(name, kind))
}

/// The kinds [`new_constraint`] makes, as the editor lists them.
pub const CONSTRAINT_KINDS: [&str; 5] =
    ["Aim at", "Copy location", "Copy rotation", "Child of", "Follow path"];
