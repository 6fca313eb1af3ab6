//! Keying sets: which channels `I` keys (Blender's active keying set, chosen in the toolbar),
//! and in record mode which channels are keyed together with the one a pose change keys (as
//! Blender's "only active keying set" auto-keying and Maya's character sets): *Location*,
//! *Rotation*, *Scale* and *Location, rotation & scale* key those channels of each selected
//! object, joint, light or camera; *Whole character* keys the selected object's transform and
//! every joint of its skeleton (with its IK targets and blends), whichever joint is selected;
//! *Selected channels* (the default) keys every channel of the selection as before — an
//! object's own and, for a character, every joint's — and in record mode only the channel
//! changed.

use keyrig_core::Scene;

use keyrig_render::Selected;

use keyrig_edit::channels::ChannelId;

/// The active keying set (session state: not saved, not undone).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum KeyingSet {
    /// Every channel of the selection (a character's joints with its object).
    #[default]
    Selected,
    Location,
    Rotation,
    Scale,
    LocRotScale,
    /// The selected object's transform and every joint of its skeleton.
    WholeCharacter,
}

/// Which part of a transform a channel is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Part {
    Location,
    Rotation,
    Scale,
}

/// The part of a transform `id` keys: translations and positions, rotations and a light's
/// direction, scales; `None` for everything else (attributes, colours, lenses, IK blends …).
fn part(id: ChannelId) -> Option<Part> {
    match id {
        ChannelId::ObjectTranslation(_)
        | ChannelId::RootTranslation(_)
        | ChannelId::JointTranslation { .. }
        | ChannelId::LightPosition(_)
        | ChannelId::CameraTranslation(_) => Some(Part::Location),
        ChannelId::ObjectRotation(_)
        | ChannelId::ObjectEuler(_)
        | ChannelId::JointRotation { .. }
        | ChannelId::JointEuler { .. }
        | ChannelId::LightDirection(_)
        | ChannelId::CameraRotation(_) => Some(Part::Rotation),
        ChannelId::ObjectScale(_) | ChannelId::JointScale { .. } => Some(Part::Scale),
        _ => None,
    }
}

/// The item a channel belongs to (for a root translation or an IK channel: its object); `None`
/// for attributes.
fn owner(id: ChannelId) -> Option<Selected> {
    (!matches!(id, ChannelId::Attribute(_))).then(|| owner_of(id))
}

/// The scene item a channel belongs to (an object's root translation: the object).
#[must_use]
pub fn owner_of(channel: ChannelId) -> Selected {
    match channel {
        ChannelId::ObjectTranslation(o)
        | ChannelId::ObjectRotation(o)
        | ChannelId::ObjectEuler(o)
        | ChannelId::ObjectScale(o)
        | ChannelId::RootTranslation(o) => Selected::Object(o),
        ChannelId::JointTranslation { object, joint }
        | ChannelId::JointRotation { object, joint }
        | ChannelId::JointEuler { object, joint }
        | ChannelId::JointScale { object, joint } => Selected::Joint { object, joint },
        ChannelId::LightPosition(l)
        | ChannelId::LightDirection(l)
        | ChannelId::LightColour(l)
        | ChannelId::LightIntensity(l) => Selected::Light(l),
        ChannelId::IkTarget { object, .. }
        | ChannelId::IkBlend { object, .. }
        | ChannelId::Constraint { object, .. } => Selected::Object(object),
        ChannelId::Attribute(a) => match a.owner() {
            Ok(o) => Selected::Object(o),
            Err(l) => Selected::Light(l),
        },
        ChannelId::CameraTranslation(c)
        | ChannelId::CameraRotation(c)
        | ChannelId::CameraLens(c)
        | ChannelId::CameraRoll(c)
        | ChannelId::CameraAimInfluence(c)
        | ChannelId::CameraVisible(c) => Selected::Camera(c),
    }
}

/// Every pose channel of object `o`: its transform, its skeleton's root translation, every
/// joint's channels, its IK targets and blends (not its attributes).
fn character(scene: &Scene, o: usize) -> Vec<ChannelId> {
    ChannelId::of_object(scene, o).into_iter().filter(|id| !matches!(id, ChannelId::Attribute(_))).collect()
}

fn push_new(out: &mut Vec<ChannelId>, ids: impl IntoIterator<Item = ChannelId>) {
    for id in ids {
        if !out.contains(&id) {
            out.push(id);
        }
    }
}

impl KeyingSet {
    /// Every keying set, in the order the toolbar lists them.
    pub const ALL: [KeyingSet; 6] = [
        KeyingSet::Selected,
        KeyingSet::Location,
        KeyingSet::Rotation,
        KeyingSet::Scale,
        KeyingSet::LocRotScale,
        KeyingSet::WholeCharacter,
    ];

    /// The set's name in the toolbar.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            KeyingSet::Selected => "Selected channels",
            KeyingSet::Location => "Location only",
            KeyingSet::Rotation => "Rotation only",
            KeyingSet::Scale => "Scale only",
            KeyingSet::LocRotScale => "Location, rotation & scale",
            KeyingSet::WholeCharacter => "Whole character",
        }
    }

    /// What `I` keys with this set, for the toolbar's tooltip.
    #[must_use]
    pub fn description(self) -> &'static str {
        match self {
            KeyingSet::Selected => {
                "Every channel of the selection: an object's own and, for a character, every joint's"
            }
            KeyingSet::Location => {
                "The translation (position) of each selected object, joint, light or camera"
            }
            KeyingSet::Rotation => {
                "The rotation (a light's direction) of each selected object, joint, light or camera"
            }
            KeyingSet::Scale => "The scale of each selected object or joint",
            KeyingSet::LocRotScale => "Translation, rotation and scale of each selected item",
            KeyingSet::WholeCharacter => {
                "The selected object's transform and every joint of its skeleton, whichever joint is selected"
            }
        }
    }

    /// Whether the set keys channels of `part`.
    fn takes(self, part: Part) -> bool {
        match self {
            KeyingSet::Location => part == Part::Location,
            KeyingSet::Rotation => part == Part::Rotation,
            KeyingSet::Scale => part == Part::Scale,
            KeyingSet::LocRotScale => true,
            KeyingSet::Selected | KeyingSet::WholeCharacter => false,
        }
    }

    /// The channels `I` keys with this set and the selected `items`.
    #[must_use]
    pub fn channels(self, scene: &Scene, items: impl IntoIterator<Item = Selected>) -> Vec<ChannelId> {
        let mut out = Vec::new();
        for item in items {
            match self {
                KeyingSet::Selected => match item {
                    Selected::Object(o) if o < scene.objects.len() => {
                        push_new(&mut out, ChannelId::of_object(scene, o));
                    }
                    other => push_new(&mut out, item_channels(other, scene)),
                },
                KeyingSet::WholeCharacter => match item {
                    Selected::Object(o) | Selected::Joint { object: o, .. } if o < scene.objects.len() => {
                        push_new(&mut out, character(scene, o));
                    }
                    other => push_new(&mut out, item_channels(other, scene)),
                },
                _ => push_new(
                    &mut out,
                    item_channels(item, scene)
                        .into_iter()
                        .filter(|&id| part(id).is_some_and(|p| self.takes(p))),
                ),
            }
        }
        out
    }

    /// In record mode, the channels keyed together with `id` when a pose change keys it: the
    /// set's channels of the item `id` belongs to (its whole character for *Whole
    /// character*), `id` left out; none for *Selected channels*.
    #[must_use]
    pub fn companions(self, scene: &Scene, id: ChannelId) -> Vec<ChannelId> {
        let Some(item) = owner(id) else { return Vec::new() };
        let ids = match (self, item) {
            (KeyingSet::Selected, _) => Vec::new(),
            (KeyingSet::WholeCharacter, Selected::Object(o) | Selected::Joint { object: o, .. }) => {
                character(scene, o)
            }
            (KeyingSet::WholeCharacter, other) => item_channels(other, scene),
            (set, item) => item_channels(item, scene)
                .into_iter()
                .filter(|&c| part(c).is_some_and(|p| set.takes(p)))
                .collect(),
        };
        ids.into_iter().filter(|&c| c != id).collect()
    }
}

/// Whether `item` exists in `scene`.
pub(crate) fn item_exists(item: Selected, scene: &Scene) -> bool {
    match item {
        Selected::Object(o) => o < scene.objects.len(),
        Selected::Joint { object, joint } => scene
            .objects
            .get(object)
            .and_then(|o| o.skeleton.as_ref())
            .is_some_and(|s| joint < s.joints.len()),
        Selected::Light(l) => l < scene.lights.len(),
        Selected::Camera(c) => c < scene.cameras.len(),
    }
}

/// The channels `item` owns: an object's transform, a joint's channels (rotation, and
/// translation and scale where used), a light's; none when it does not exist.
pub(crate) fn item_channels(item: Selected, scene: &Scene) -> Vec<ChannelId> {
    if !item_exists(item, scene) {
        return Vec::new();
    }
    match item {
        Selected::Object(o) => {
            vec![
                ChannelId::ObjectTranslation(o),
                keyrig_core::channel_id::rotation_or_euler(scene, ChannelId::ObjectRotation(o)),
                ChannelId::ObjectScale(o),
            ]
        }
        Selected::Joint { object, joint } => ChannelId::of_object(scene, object)
            .into_iter()
            .filter(|id| {
                matches!(id, ChannelId::JointTranslation { joint: j, .. }
                    | ChannelId::JointRotation { joint: j, .. }
                    | ChannelId::JointEuler { joint: j, .. }
                    | ChannelId::JointScale { joint: j, .. } if *j == joint)
            })
            .collect(),
        Selected::Light(l) => ChannelId::of_light(l).to_vec(),
        Selected::Camera(c) => ChannelId::of_camera(scene, c),
    }
}
