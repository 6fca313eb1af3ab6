//! Actions: named sets of keyed channels, several per scene (docs/actions.md).
//!
//! An object plays one action at a time, its *active* action ([`Object::action`]). The keys of
//! the active action are the object's own channels — where the dope sheet, the curve editor,
//! record mode and every key edit already read and write them — so nothing that edits keys
//! needs to know about actions. [`Scene::actions`] lists every action by name and holds, for
//! each, the channels that are *not* playing: those of the objects the action is not active
//! on. Making another action active ([`Scene::assign_action`]) moves the object's keyed
//! channels into its old action and the new action's channels for the object out of it, so
//! every key lives in exactly one place and nothing is lost.
//!
//! Channels are addressed by their channel path (`object/Fox/joint/b_Hip_01/rotation`,
//! [`crate::channel::ChannelPath`]), so an action keeps its keys when objects are added,
//! removed or reordered; renaming an object or a joint renames the paths
//! ([`Scene::rename_in_actions`]).

use crate::channel::ChannelPath;
use crate::channel_id::{channel, channel_mut, ChannelId, ChannelMut, ChannelRef};
use crate::key::Animated;
use crate::scene::Scene;

/// The name a scene's animation gets when it becomes an action without one (a scene file of
/// format version 1–3, a model whose animation has no name): Blender's default.
pub const DEFAULT_ACTION: &str = "Action";

pub use crate::action_keys::{Action, ActionChannel, ActionKeys};

/// Why an action edit was refused.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum ActionError {
    #[error("there is no action {0:?}")]
    Missing(String),
    #[error("there is already an action {0:?}")]
    Taken(String),
    #[error("an action name cannot be empty or contain '/': {0:?}")]
    BadName(String),
    #[error("there is no object {0}")]
    NoObject(usize),
    #[error("object {0:?} has no keys to push down")]
    NoKeys(String),
}

/// What one action holds: its name, how many channels and keys, and the time its keys span.
#[derive(Clone, Debug, PartialEq)]
pub struct ActionSummary {
    pub name: String,
    /// The objects it is active on.
    pub active_on: Vec<String>,
    pub channels: usize,
    pub keys: usize,
    /// First and last key time (seconds); `None` without keys.
    pub time_range: Option<(f64, f64)>,
}

impl Scene {
    /// The index of the action named `name`.
    #[must_use]
    pub fn action_index(&self, name: &str) -> Option<usize> {
        self.actions.iter().position(|a| a.name == name)
    }

    /// The keyed channels of object `o` (the keys of its active action).
    #[must_use]
    pub fn keyed_channels_of(&self, o: usize) -> Vec<ChannelId> {
        let mut ids = ChannelId::of_object(self, o);
        // Both forms of a rotation: quaternion keys left beside constant Euler angles count.
        let partners: Vec<ChannelId> =
            ids.iter().filter_map(|&id| crate::channel_id::euler_partner(id)).collect();
        ids.extend(partners);
        ids.into_iter()
            .filter(|&id| match channel(self, id) {
                Some(ChannelRef::Vec3(a)) => a.is_animated(),
                Some(ChannelRef::Rotation(a)) => a.is_animated(),
                Some(ChannelRef::Scalar(a)) => a.is_animated(),
                None => false,
            })
            .collect()
    }

    /// Takes the keyed channels of object `o` out of the scene (they hold their static values
    /// afterwards), as stored action channels sorted by path.
    pub fn take_keyed_channels(&mut self, o: usize) -> Vec<ActionChannel> {
        let mut out = Vec::new();
        for id in self.keyed_channels_of(o) {
            let Some(path) = ChannelPath::of(self, id).map(|p| p.to_string()) else { continue };
            let keys = match channel_mut(self, id) {
                Some(ChannelMut::Vec3(a)) => {
                    ActionKeys::Vec3(std::mem::replace(a, Animated::constant(a.value)))
                }
                Some(ChannelMut::Rotation(a)) => {
                    ActionKeys::Rotation(std::mem::replace(a, Animated::constant(a.value)))
                }
                Some(ChannelMut::Scalar(a)) => {
                    ActionKeys::Scalar(std::mem::replace(a, Animated::constant(a.value)))
                }
                None => continue,
            };
            out.push(ActionChannel { path, keys });
        }
        out.sort_by(|a, b| a.path.cmp(&b.path));
        out
    }

    /// Puts a stored channel back into the scene where its path resolves to object `o`;
    /// gives it back when it does not (another object's, or a channel the object lacks).
    fn place_channel(&mut self, o: usize, c: ActionChannel) -> Result<(), ActionChannel> {
        let Ok(id) = stored_channel_id(self, &c.path) else { return Err(c) };
        if channel_object(id) != Some(o) {
            return Err(c);
        }
        // Euler keys and optional attributes exist only while set: make room for them.
        match (id, &c.keys) {
            (ChannelId::ObjectEuler(o), ActionKeys::Vec3(a)) => {
                self.objects[o].rotation_euler = Some(a.clone());
                return Ok(());
            }
            (ChannelId::JointEuler { object, joint }, ActionKeys::Vec3(a)) => {
                if let Some(j) = self.objects[object].skeleton.as_mut().and_then(|s| s.joints.get_mut(joint))
                {
                    j.rotation_euler = Some(a.clone());
                    return Ok(());
                }
                return Err(c);
            }
            (ChannelId::Attribute(attr), _) if channel(self, id).is_none() => {
                let attrs = &mut self.objects[o].attributes;
                match (attr, &c.keys) {
                    (crate::AttributeId::ObjectColour(_), ActionKeys::Vec3(a)) => {
                        attrs.colour = Some(a.clone())
                    }
                    (crate::AttributeId::Deformer(_), ActionKeys::Scalar(a)) => {
                        attrs.deformer = Some(a.clone())
                    }
                    (crate::AttributeId::BlendParent(_), ActionKeys::Scalar(a)) => {
                        attrs.blend_parent_fraction = Some(a.clone());
                    }
                    (crate::AttributeId::BlendChild(_), ActionKeys::Scalar(a)) => {
                        attrs.blend_child_fraction = Some(a.clone());
                    }
                    _ => return Err(c),
                }
                return Ok(());
            }
            _ => {}
        }
        // Quaternion keys play only while the Euler keys are gone.
        match id {
            ChannelId::ObjectRotation(o) => self.objects[o].rotation_euler = None,
            ChannelId::JointRotation { object, joint } => {
                if let Some(j) = self.objects[object].skeleton.as_mut().and_then(|s| s.joints.get_mut(joint))
                {
                    j.rotation_euler = None;
                }
            }
            _ => {}
        }
        match (channel_mut(self, id), &c.keys) {
            (Some(ChannelMut::Vec3(a)), ActionKeys::Vec3(k)) => set_keys(a, k),
            (Some(ChannelMut::Rotation(a)), ActionKeys::Rotation(k)) => set_keys(a, k),
            (Some(ChannelMut::Scalar(a)), ActionKeys::Scalar(k)) => set_keys(a, k),
            _ => return Err(c),
        }
        Ok(())
    }

    /// Makes `action` the active action of object `o` (`None`: no action): the object's keys
    /// go into its old action (a new action named after the object when it had none, so no key
    /// is lost) and the new action's channels for the object come out of it. The scene is
    /// left as it was on an error.
    ///
    /// # Errors
    /// [`ActionError::Missing`] for an unknown action, [`ActionError::NoObject`].
    pub fn assign_action(&mut self, o: usize, action: Option<&str>) -> Result<(), ActionError> {
        let object = self.objects.get(o).ok_or(ActionError::NoObject(o))?;
        if let Some(name) = action {
            if self.action_index(name).is_none() {
                return Err(ActionError::Missing(name.to_owned()));
            }
        }
        if object.action.as_deref() == action {
            return Ok(());
        }
        self.stash_active(o);
        if let Some(name) = action {
            self.play_action(o, name);
        }
        self.objects[o].action = action.map(str::to_owned);
        Ok(())
    }

    /// Moves the keyed channels of object `o` into its active action (made, named after the
    /// object, when it has keys but no action); the object is left with no action.
    fn stash_active(&mut self, o: usize) {
        let stored = self.take_keyed_channels(o);
        let name = match self.objects[o].action.take() {
            Some(name) => name,
            None if stored.is_empty() => return,
            None => self.unused_action_name(&format!("{}Action", self.objects[o].name)),
        };
        let a = match self.action_index(&name) {
            Some(a) => a,
            None => {
                self.actions.push(Action { name, channels: Vec::new() });
                self.actions.len() - 1
            }
        };
        let channels = &mut self.actions[a].channels;
        for c in stored {
            match channels.binary_search_by(|x| x.path.cmp(&c.path)) {
                Ok(i) => channels[i] = c,
                Err(i) => channels.insert(i, c),
            }
        }
    }

    /// Takes the channels of action `name` that belong to object `o` out of the action and
    /// into the object.
    fn play_action(&mut self, o: usize, name: &str) {
        let Some(a) = self.action_index(name) else { return };
        let channels = std::mem::take(&mut self.actions[a].channels);
        let mut kept = Vec::with_capacity(channels.len());
        for c in channels {
            if let Err(c) = self.place_channel(o, c) {
                kept.push(c);
            }
        }
        self.actions[a].channels = kept;
    }

    /// A name not used by any action: `base`, else `base.001`, `base.002`, …
    #[must_use]
    pub fn unused_action_name(&self, base: &str) -> String {
        if self.action_index(base).is_none() {
            return base.to_owned();
        }
        (1..)
            .map(|n| format!("{base}.{n:03}"))
            .find(|n| self.action_index(n).is_none())
            .unwrap_or_else(|| base.to_owned())
    }

    /// Adds an empty action named `name` and makes it the active action of object `o` (its
    /// keys go into its old action).
    ///
    /// # Errors
    /// [`ActionError::Taken`], [`ActionError::BadName`], [`ActionError::NoObject`].
    pub fn new_action(&mut self, o: usize, name: &str) -> Result<(), ActionError> {
        check_name(name)?;
        if self.action_index(name).is_some() {
            return Err(ActionError::Taken(name.to_owned()));
        }
        if o >= self.objects.len() {
            return Err(ActionError::NoObject(o));
        }
        self.actions.push(Action { name: name.to_owned(), channels: Vec::new() });
        self.assign_action(o, Some(name))
    }

    /// Copies the keys object `o` plays into a new action named `name`, made its active action
    /// (the copied action keeps its keys; Blender's "New" on an assigned action).
    ///
    /// # Errors
    /// As [`Scene::new_action`].
    pub fn duplicate_action(&mut self, o: usize, name: &str) -> Result<(), ActionError> {
        check_name(name)?;
        if self.action_index(name).is_some() {
            return Err(ActionError::Taken(name.to_owned()));
        }
        if o >= self.objects.len() {
            return Err(ActionError::NoObject(o));
        }
        if self.objects[o].action.is_none() {
            // Keys in no action have no action to keep a copy: they become `name`'s (stashing
            // them first would take `<object>Action`, which may be `name` itself).
            self.actions.push(Action { name: name.to_owned(), channels: Vec::new() });
            self.objects[o].action = Some(name.to_owned());
            return Ok(());
        }
        let copy = {
            let mut scratch = self.clone();
            scratch.take_keyed_channels(o)
        };
        self.stash_active(o);
        self.actions.push(Action { name: name.to_owned(), channels: copy });
        self.play_action(o, name);
        self.objects[o].action = Some(name.to_owned());
        Ok(())
    }

    /// Renames action `old` to `new`, and the objects that play it.
    ///
    /// # Errors
    /// [`ActionError::Missing`], [`ActionError::Taken`], [`ActionError::BadName`].
    pub fn rename_action(&mut self, old: &str, new: &str) -> Result<(), ActionError> {
        check_name(new)?;
        let a = self.action_index(old).ok_or_else(|| ActionError::Missing(old.to_owned()))?;
        if old == new {
            return Ok(());
        }
        if self.action_index(new).is_some() {
            return Err(ActionError::Taken(new.to_owned()));
        }
        self.actions[a].name = new.to_owned();
        for object in &mut self.objects {
            if object.action.as_deref() == Some(old) {
                object.action = Some(new.to_owned());
            }
        }
        Ok(())
    }

    /// Deletes action `name` with its keys: the objects that play it lose their keys and are
    /// left with no action.
    ///
    /// # Errors
    /// [`ActionError::Missing`].
    pub fn delete_action(&mut self, name: &str) -> Result<(), ActionError> {
        let a = self.action_index(name).ok_or_else(|| ActionError::Missing(name.to_owned()))?;
        for o in 0..self.objects.len() {
            if self.objects[o].action.as_deref() == Some(name) {
                drop(self.take_keyed_channels(o));
                self.objects[o].action = None;
            }
        }
        self.actions.remove(a);
        Ok(())
    }

    /// Renames the channel paths of every action after object `old` became `new` (`joint`:
    /// `None`), or after joint `joint` of object `old` was renamed to `new`.
    pub fn rename_in_actions(&mut self, object: &str, joint: Option<&str>, new: &str) {
        let (from, to) = match joint {
            None => (format!("object/{object}/"), format!("object/{new}/")),
            Some(j) => (format!("object/{object}/joint/{j}/"), format!("object/{object}/joint/{new}/")),
        };
        for action in &mut self.actions {
            for c in &mut action.channels {
                if let Some(rest) = c.path.strip_prefix(&from) {
                    c.path = format!("{to}{rest}");
                }
            }
            action.channels.sort_by(|a, b| a.path.cmp(&b.path));
        }
    }

    /// Drops the stored keys of object `object` from every action (the object was deleted).
    pub fn forget_in_actions(&mut self, object: &str) {
        let prefix = format!("object/{object}/");
        for action in &mut self.actions {
            action.channels.retain(|c| !c.path.starts_with(&prefix));
        }
    }

    /// Gives every object with keys but no action the action `name` (made when missing): how
    /// the one animation of an older scene file becomes an action.
    pub fn name_unnamed_keys(&mut self, name: &str) {
        let unnamed: Vec<usize> = (0..self.objects.len())
            .filter(|&o| self.objects[o].action.is_none() && !self.keyed_channels_of(o).is_empty())
            .collect();
        if unnamed.is_empty() {
            return;
        }
        if self.action_index(name).is_none() {
            self.actions.push(Action { name: name.to_owned(), channels: Vec::new() });
        }
        for o in unnamed {
            self.objects[o].action = Some(name.to_owned());
        }
    }

    /// The scene playing action `name` on every object that has channels in it (objects it
    /// is already active on included); with `only`, the other objects play no keys at all.
    /// How `keyrig sample --action` and the exporters play one action.
    ///
    /// # Errors
    /// [`ActionError::Missing`].
    pub fn playing_action(&self, name: &str, only: bool) -> Result<Scene, ActionError> {
        let a = self.action_index(name).ok_or_else(|| ActionError::Missing(name.to_owned()))?;
        let mut out = self.clone();
        let owners: Vec<usize> = (0..self.objects.len())
            .filter(|&o| {
                self.objects[o].action.as_deref() == Some(name)
                    || self.actions[a].channels.iter().any(|c| {
                        stored_channel_id(self, &c.path).is_ok_and(|id| channel_object(id) == Some(o))
                    })
            })
            .collect();
        for o in 0..out.objects.len() {
            if owners.contains(&o) {
                out.assign_action(o, Some(name))?;
            } else if only {
                // Its keys go back into its action (or one named after it): it plays none.
                out.assign_action(o, None)?;
            }
        }
        Ok(out)
    }

    /// The problems of the stored channels' paths: each must name an object's channel of the
    /// scene holding the same value type (Euler keys: three angles), and not one of an object
    /// that plays the action (its keys are the object's own). Part of [`Scene::problems`].
    #[must_use]
    pub fn stored_path_problems(&self) -> Vec<crate::scene::Problem> {
        use crate::channel_id::ChannelKind;
        let mut out = Vec::new();
        let mut push = |path: String, message: String| out.push(crate::scene::Problem { path, message });
        for (a, action) in self.actions.iter().enumerate() {
            for (k, c) in action.channels.iter().enumerate() {
                let here = format!("actions[{a}].channels[{k}]");
                let kind = match &c.keys {
                    ActionKeys::Vec3(_) => ChannelKind::Vec3,
                    ActionKeys::Rotation(_) => ChannelKind::Rotation,
                    ActionKeys::Scalar(_) => ChannelKind::Scalar,
                };
                match stored_channel_id(self, &c.path) {
                    Err(e) => push(format!("{here}.path"), e.to_string()),
                    Ok(id) => {
                        let Some(o) = channel_object(id) else {
                            push(
                                format!("{here}.path"),
                                format!(
                                    "{:?} is not an object's channel; actions hold objects' keys",
                                    c.path
                                ),
                            );
                            continue;
                        };
                        let want = match id {
                            ChannelId::ObjectEuler(_) | ChannelId::JointEuler { .. } => ChannelKind::Vec3,
                            _ => id.kind(),
                        };
                        if want != kind {
                            push(
                                format!("{here}.keys"),
                                format!("channel {:?} holds {want:?} values, not {kind:?}", c.path),
                            );
                        } else if self.objects[o].action.as_deref() == Some(action.name.as_str()) {
                            push(
                                format!("{here}.path"),
                                format!(
                                    "object {:?} plays action {:?}: its keys are the object's own channels, \
                                     not stored in the action",
                                    self.objects[o].name, action.name
                                ),
                            );
                        }
                    }
                }
            }
        }
        out
    }

    /// What each action holds, in the scene's order.
    #[must_use]
    pub fn action_summaries(&self) -> Vec<ActionSummary> {
        self.actions
            .iter()
            .map(|action| {
                let mut channels = action.channels.len();
                let mut keys: usize = action.channels.iter().map(|c| c.keys.len()).sum();
                let mut range: Option<(f64, f64)> = None;
                let mut widen = |r: Option<(f64, f64)>| {
                    if let Some((a, b)) = r {
                        range = Some(range.map_or((a, b), |(x, y)| (x.min(a), y.max(b))));
                    }
                };
                for c in &action.channels {
                    widen(c.keys.time_range());
                }
                let mut active_on = Vec::new();
                for (o, object) in self.objects.iter().enumerate() {
                    if object.action.as_deref() != Some(action.name.as_str()) {
                        continue;
                    }
                    active_on.push(object.name.clone());
                    for id in self.keyed_channels_of(o) {
                        channels += 1;
                        let (n, r) = match channel(self, id) {
                            Some(ChannelRef::Vec3(a)) => (a.track.len(), a.key_time_range()),
                            Some(ChannelRef::Rotation(a)) => (a.track.len(), a.key_time_range()),
                            Some(ChannelRef::Scalar(a)) => (a.track.len(), a.key_time_range()),
                            None => (0, None),
                        };
                        keys += n;
                        widen(r);
                    }
                }
                ActionSummary { name: action.name.clone(), active_on, channels, keys, time_range: range }
            })
            .collect()
    }
}

fn set_keys<T: Clone>(a: &mut Animated<T>, stored: &Animated<T>) {
    a.track = stored.track.clone();
    a.before = stored.before;
    a.after = stored.after;
    a.muted = stored.muted;
}

fn check_name(name: &str) -> Result<(), ActionError> {
    if name.trim().is_empty() || name.contains('/') {
        return Err(ActionError::BadName(name.to_owned()));
    }
    Ok(())
}

/// The object a channel belongs to; `None` for lights and cameras.
#[must_use]
pub fn channel_object(id: ChannelId) -> Option<usize> {
    match id {
        ChannelId::ObjectTranslation(o)
        | ChannelId::ObjectRotation(o)
        | ChannelId::ObjectScale(o)
        | ChannelId::ObjectEuler(o)
        | ChannelId::RootTranslation(o)
        | ChannelId::JointTranslation { object: o, .. }
        | ChannelId::JointRotation { object: o, .. }
        | ChannelId::JointScale { object: o, .. }
        | ChannelId::JointEuler { object: o, .. }
        | ChannelId::IkTarget { object: o, .. }
        | ChannelId::IkBlend { object: o, .. }
        | ChannelId::Constraint { object: o, .. } => Some(o),
        ChannelId::Attribute(a) => a.owner().ok(),
        _ => None,
    }
}

/// The channel a stored path names in `scene`. Euler keys (`…/rotation_euler`) name their object
/// or joint even while it plays quaternion keys: the path is then resolved through its rotation.
///
/// # Errors
/// The path does not parse or names nothing in `scene`.
pub fn stored_channel_id(scene: &Scene, path: &str) -> Result<ChannelId, crate::channel::ChannelError> {
    use crate::channel::{JointProperty, ObjectProperty};
    let parsed = ChannelPath::parse(path)?;
    let as_rotation = match &parsed {
        ChannelPath::Object { object, property: ObjectProperty::RotationEuler } => {
            Some(ChannelPath::Object { object: object.clone(), property: ObjectProperty::Rotation })
        }
        ChannelPath::Joint { object, joint, property: JointProperty::RotationEuler } => {
            Some(ChannelPath::Joint {
                object: object.clone(),
                joint: joint.clone(),
                property: JointProperty::Rotation,
            })
        }
        _ => None,
    };
    match as_rotation {
        Some(rotation) => match parsed.id(scene) {
            Ok(id) => Ok(id),
            Err(_) => {
                let id = rotation.id(scene)?;
                Ok(crate::channel_id::euler_partner(id).unwrap_or(id))
            }
        },
        None => parsed.id(scene),
    }
}

// Clip tracks built from actions (docs/clips.md): here, not in `clip`, so that `clip` does not
// import `action` (no module import cycle).
impl Scene {
    /// Pushes object `o`'s active action down as a strip (Blender's *Push Down*): a new track
    /// on top of its tracks gets a strip playing the action over the frames its keys span, at
    /// those frames, and the object then plays no action (the keys are stored in the action,
    /// nothing is lost). Keys in no action are first named `<object>Action`. Returns the new
    /// track's index.
    ///
    /// # Errors
    /// No such object, or the object has no keys to push down.
    pub fn push_down(&mut self, o: usize) -> Result<usize, ActionError> {
        if o >= self.objects.len() {
            return Err(ActionError::NoObject(o));
        }
        if self.keyed_channels_of(o).is_empty() {
            return Err(ActionError::NoKeys(self.objects[o].name.clone()));
        }
        if self.objects[o].action.is_none() {
            let name = self.unused_action_name(&format!("{}Action", self.objects[o].name));
            self.duplicate_action(o, &name)?;
        }
        let name = self.objects[o].action.clone().unwrap_or_default();
        let (start, end) = self.action_frames_on(o, &name).unwrap_or((0.0, 0.0));
        self.assign_action(o, None)?;
        // A single key spans no time: the strip plays one frame of it.
        let end = if end > start { end } else { start + 1.0 };
        Ok(self.push_clip_track(o, crate::clip::Strip::new(name, start, start, end)))
    }

    /// Adds a track named `Track N` (the first free N) on top of object `o`'s tracks, holding
    /// `strip`; returns its index. `o` must be an object of the scene.
    pub fn push_clip_track(&mut self, o: usize, strip: crate::clip::Strip) -> usize {
        let tracks = &mut self.objects[o].clip_tracks;
        let mut n = tracks.len() + 1;
        while tracks.iter().any(|t| t.name == format!("Track {n}")) {
            n += 1;
        }
        tracks.push(crate::clip::ClipTrack {
            name: format!("Track {n}"),
            strips: vec![strip],
            ..crate::clip::ClipTrack::default()
        });
        tracks.len() - 1
    }

    /// The names of the actions object `o`'s strips and the scene's layers play, sorted, each
    /// once: what its clip mix reads.
    #[must_use]
    pub fn mixed_action_names(&self, o: usize) -> Vec<&str> {
        let mut names: Vec<&str> = self.objects[o]
            .clip_tracks
            .iter()
            .flat_map(|t| t.strips.iter().map(|s| s.action.as_str()))
            .chain(self.layers.iter().map(|l| l.action.as_str()))
            .collect();
        names.sort_unstable();
        names.dedup();
        names
    }
}

impl Scene {
    /// The frames action `name`'s keys for object `o` span (its keyed channels when it is the
    /// object's active action, else its stored channels that name the object); `None` without
    /// keys there.
    #[must_use]
    pub fn action_frames_on(&self, o: usize, name: &str) -> Option<(f64, f64)> {
        let object = self.objects.get(o)?;
        let join = |acc: Option<(f64, f64)>, (a, b): (f64, f64)| {
            Some(acc.map_or((a, b), |(x, y)| (x.min(a), y.max(b))))
        };
        let span = if object.action.as_deref() == Some(name) {
            self.keyed_channels_of(o).into_iter().filter_map(|id| key_span(self, id)).fold(None, join)
        } else {
            let action = &self.actions[self.action_index(name)?];
            action
                .channels
                .iter()
                .filter(|c| stored_channel_id(self, &c.path).is_ok_and(|id| channel_object(id) == Some(o)))
                .filter_map(|c| c.keys.time_range())
                .fold(None, join)
        };
        span.map(|(a, b)| (a * self.fps, b * self.fps))
    }
}

/// First and last key time of channel `id` (seconds).
fn key_span(scene: &Scene, id: crate::channel_id::ChannelId) -> Option<(f64, f64)> {
    use crate::channel_id::{channel, ChannelRef};
    match channel(scene, id)? {
        ChannelRef::Vec3(a) => a.key_time_range(),
        ChannelRef::Rotation(a) => a.key_time_range(),
        ChannelRef::Scalar(a) => a.key_time_range(),
    }
}
