//! The session: what the animator is doing with the document now — the selection, the
//! playback clock, record mode, IK posing, pose overrides and the key clipboard. None of it is saved
//! with the scene or undone with it.

use std::collections::BTreeSet;

use keyrig_core::Scene;

use keyrig_edit::channels::{ChannelId, ChannelValue, KeyCopy};

use crate::eval::PoseOverrides;
use crate::ik_posing::IkPosing;
pub use crate::keying_sets::owner_of;
use crate::keying_sets::{item_channels, item_exists, KeyingSet};
/// What can be selected in the scene: keyrig-render's one type (object, joint, light).
pub use keyrig_render::Selected;

/// Everything about the current editing session that is not the document or the view.
#[derive(Clone, Debug, Default)]
pub struct Session {
    pub selection: Selection,
    pub playback: Playback,
    /// Record mode: pose changes write keys at the current frame.
    pub record: bool,
    /// Poses set on animated channels outside record mode (dropped when the frame changes).
    pub overrides: PoseOverrides,
    /// Keys copied with Copy or Cut.
    pub clipboard: Vec<KeyCopy>,
    /// A pose copied with Copy pose: channel values at one frame.
    pub pose_clipboard: Vec<(ChannelId, ChannelValue)>,
    /// IK posing: on or off, the chain length per end joint, the pole of each chain's last drag.
    pub ik: IkPosing,
    /// Objects hidden in the viewport (H; Alt+H shows them).
    pub hidden: crate::hidden::Hidden,
    /// What `I` keys, and in record mode what is keyed with a changed channel
    /// ([`crate::keying_sets`]).
    pub keying_set: KeyingSet,
}

impl Session {
    /// A session at the first frame of `range`.
    #[must_use]
    pub fn at_start(range: keyrig_core::FrameRange) -> Self {
        let mut session = Session::default();
        session.playback.go_to(range.start, range.start, range.end);
        session
    }

    /// Current time in seconds for a scene running at `fps`.
    #[must_use]
    pub fn time(&self, fps: f64) -> f64 {
        self.playback.time(fps)
    }

    /// The time of the whole frame keys are written at, seconds.
    #[must_use]
    pub fn key_time(&self, fps: f64) -> f64 {
        f64::from(self.playback.whole_frame()) / fps.max(1e-9)
    }

    /// Whether [`Session::set_frame`] with these arguments would change anything (the clock or
    /// the pose overrides it drops).
    #[must_use]
    pub fn set_frame_changes(&self, frame: i32, range: keyrig_core::FrameRange) -> bool {
        let mut clock = self.playback.clone();
        clock.go_to(frame, range.start, range.end);
        clock != self.playback || !self.overrides.is_empty()
    }

    /// Moves the clock to a whole frame inside `range`; pose overrides are dropped.
    pub fn set_frame(&mut self, frame: i32, range: keyrig_core::FrameRange) {
        self.playback.go_to(frame, range.start, range.end);
        self.overrides.clear();
    }

    /// After `removed` (an object or light) left the scene: nothing is selected, pose
    /// overrides go, and copied keys of later items follow their new index (those of the
    /// removed one are dropped).
    pub fn forget_removed(&mut self, removed: Selected) {
        self.selection = Selection::default();
        self.overrides.clear();
        self.ik.forget_joints();
        self.clipboard.retain_mut(|key| match shifted(key.channel, removed) {
            Some(id) => {
                key.channel = id;
                true
            }
            None => false,
        });
        self.pose_clipboard.retain_mut(|(channel, _)| match shifted(*channel, removed) {
            Some(id) => {
                *channel = id;
                true
            }
            None => false,
        });
    }

    /// The object index the selection belongs to (the joint's object for joints).
    #[must_use]
    pub fn selected_object(&self) -> Option<usize> {
        match self.selection.item {
            Some(Selected::Object(o) | Selected::Joint { object: o, .. }) => Some(o),
            _ => None,
        }
    }
}

pub use keyrig_edit::KeyRef;

/// The selected scene items and the selected keys. `item` is the active item (the inspector,
/// the gizmo and framing follow it); `others` are further items selected with Shift or Ctrl.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Selection {
    pub item: Option<Selected>,
    pub others: BTreeSet<Selected>,
    pub keys: BTreeSet<KeyRef>,
}

impl Selection {
    /// Selects `item` alone (a plain click); `None` clears the item selection. Selected keys
    /// of other items are deselected, so the key inspector follows the selection.
    pub fn select_only(&mut self, item: Option<Selected>) {
        self.item = item;
        self.others.clear();
        self.keep_keys_of_items();
    }

    /// Drops selected keys whose channel belongs to no selected item (a character's object
    /// owns the keys of its joints too).
    fn keep_keys_of_items(&mut self) {
        let items: Vec<Selected> = self.items().collect();
        self.keys.retain(|k| {
            let owner = owner_of(k.channel);
            items.iter().any(|&item| {
                item == owner || matches!((item, owner), (Selected::Object(o), Selected::Joint { object, .. }) if o == object)
            })
        });
    }

    /// Shift/Ctrl-click: adds `item` as the active item, or removes it when it was selected.
    pub fn toggle(&mut self, item: Selected) {
        if self.item == Some(item) {
            self.item = self.others.pop_first();
        } else if !self.others.remove(&item) {
            if let Some(active) = self.item.replace(item) {
                self.others.insert(active);
            }
        }
        self.keep_keys_of_items();
    }

    /// Every selected item, the active one first.
    pub fn items(&self) -> impl Iterator<Item = Selected> + '_ {
        self.item.into_iter().chain(self.others.iter().copied().filter(move |o| Some(*o) != self.item))
    }

    /// Whether `item` is selected (active or not).
    #[must_use]
    pub fn contains(&self, item: Selected) -> bool {
        self.item == Some(item) || self.others.contains(&item)
    }

    /// The channels `I` keys with the default keying set: every selected joint's and light's,
    /// and for a selected object its own and (a character) every joint's of its skeleton.
    #[must_use]
    pub fn key_channels(&self, scene: &Scene) -> Vec<ChannelId> {
        KeyingSet::Selected.channels(scene, self.items())
    }

    /// The channels the selected item owns (a joint's rotation, an object's transform, a light's
    /// channels).
    #[must_use]
    pub fn channels(&self, scene: &Scene) -> Vec<ChannelId> {
        self.item.map_or_else(Vec::new, |item| item_channels(item, scene))
    }

    /// Drops selections that no longer exist in `scene` (after undo, open, delete).
    pub fn retain_valid(&mut self, scene: &Scene) {
        self.item = self.item.filter(|&item| item_exists(item, scene));
        self.others.retain(|&item| item_exists(item, scene));
        self.keys.retain(|k| k.index < keyrig_edit::channels::key_count(scene, k.channel));
    }
}

/// The playback clock. The current time is kept in frames (fractional while playing).
#[derive(Clone, Debug, PartialEq)]
pub struct Playback {
    pub frame: f64,
    pub playing: bool,
    pub looping: bool,
    /// Every-frame playback: each drawn frame advances one scene frame, however long it
    /// took (slow motion when drawing is slower than the scene's fps). Off (the default) is
    /// real-time playback: the clock follows the wall clock and drops frames to keep time.
    pub every_frame: bool,
}

impl Default for Playback {
    fn default() -> Self {
        Playback { frame: 0.0, playing: false, looping: true, every_frame: false }
    }
}

impl Playback {
    /// Current time in seconds for a scene running at `fps`.
    #[must_use]
    pub fn time(&self, fps: f64) -> f64 {
        if fps > 0.0 {
            self.frame / fps
        } else {
            0.0
        }
    }

    /// The whole frame the clock is on (what keys are written at).
    #[must_use]
    pub fn whole_frame(&self) -> i32 {
        self.frame.round() as i32
    }

    /// Advances by `dt` seconds at `fps`, looping or stopping at the end of `[start, end]`.
    pub fn advance(&mut self, dt: f64, fps: f64, start: i32, end: i32) {
        if !(self.playing && dt.is_finite() && fps.is_finite() && fps > 0.0) {
            return;
        }
        let (start, end) = (f64::from(start), f64::from(end.max(start)));
        self.frame += if self.every_frame { 1.0 } else { dt * fps };
        if self.frame > end {
            if self.looping && end > start {
                self.frame = start + (self.frame - start) % (end - start);
            } else {
                self.frame = end;
                self.playing = false;
            }
        }
        if self.frame < start {
            self.frame = start;
        }
    }

    /// Starts or stops playback; starting at (or past) the end with looping off starts from
    /// `start`, as a player's Play at the end of a clip does.
    pub fn toggle_play(&mut self, start: i32, end: i32) {
        if !self.playing && !self.looping && self.frame >= f64::from(end) {
            self.frame = f64::from(start);
        }
        self.playing = !self.playing;
    }

    /// Scene frames shown per second while playing, given the smoothed seconds between drawn
    /// frames: every drawn frame in every-frame mode, at most the scene's fps in real time.
    #[must_use]
    pub fn achieved_fps(&self, frame_time: f64, fps: f64) -> f64 {
        let drawn = 1.0 / frame_time.max(1e-6);
        if self.every_frame {
            drawn
        } else {
            drawn.min(fps)
        }
    }

    /// Jumps to a whole frame, clamped to `[start, end]`.
    pub fn go_to(&mut self, frame: i32, start: i32, end: i32) {
        self.frame = f64::from(frame.clamp(start, end.max(start)));
    }
}

/// Where channel `id` is after `removed` left the scene: `None` when it belonged to it, one
/// index lower when it belonged to a later item of the same kind, unchanged otherwise.
#[must_use]
pub fn shifted(id: ChannelId, removed: Selected) -> Option<ChannelId> {
    let shift = |i: usize, gone: usize| match i.cmp(&gone) {
        std::cmp::Ordering::Less => Some(i),
        std::cmp::Ordering::Equal => None,
        std::cmp::Ordering::Greater => Some(i - 1),
    };
    use ChannelId as C;
    Some(match (id, removed) {
        (C::ObjectTranslation(o), Selected::Object(r)) => C::ObjectTranslation(shift(o, r)?),
        (C::ObjectRotation(o), Selected::Object(r)) => C::ObjectRotation(shift(o, r)?),
        (C::ObjectEuler(o), Selected::Object(r)) => C::ObjectEuler(shift(o, r)?),
        (C::ObjectScale(o), Selected::Object(r)) => C::ObjectScale(shift(o, r)?),
        (C::RootTranslation(o), Selected::Object(r)) => C::RootTranslation(shift(o, r)?),
        (C::JointTranslation { object, joint }, Selected::Object(r)) => {
            C::JointTranslation { object: shift(object, r)?, joint }
        }
        (C::JointRotation { object, joint }, Selected::Object(r)) => {
            C::JointRotation { object: shift(object, r)?, joint }
        }
        (C::JointEuler { object, joint }, Selected::Object(r)) => {
            C::JointEuler { object: shift(object, r)?, joint }
        }
        (C::JointScale { object, joint }, Selected::Object(r)) => {
            C::JointScale { object: shift(object, r)?, joint }
        }
        (C::LightPosition(l), Selected::Light(r)) => C::LightPosition(shift(l, r)?),
        (C::LightDirection(l), Selected::Light(r)) => C::LightDirection(shift(l, r)?),
        (C::LightColour(l), Selected::Light(r)) => C::LightColour(shift(l, r)?),
        (C::LightIntensity(l), Selected::Light(r)) => C::LightIntensity(shift(l, r)?),
        (C::IkTarget { object, constraint }, Selected::Object(r)) => {
            C::IkTarget { object: shift(object, r)?, constraint }
        }
        (C::IkBlend { object, constraint }, Selected::Object(r)) => {
            C::IkBlend { object: shift(object, r)?, constraint }
        }
        (C::Constraint { object, constraint, property }, Selected::Object(r)) => {
            C::Constraint { object: shift(object, r)?, constraint, property }
        }
        (C::Attribute(a), Selected::Object(r)) if a.owner().is_ok() => {
            C::Attribute(a.with_owner(shift(a.owner().ok()?, r)?))
        }
        (C::Attribute(a), Selected::Light(r)) if a.owner().is_err() => {
            C::Attribute(a.with_owner(shift(a.owner().err()?, r)?))
        }
        (C::CameraTranslation(c), Selected::Camera(r)) => C::CameraTranslation(shift(c, r)?),
        (C::CameraRotation(c), Selected::Camera(r)) => C::CameraRotation(shift(c, r)?),
        (C::CameraLens(c), Selected::Camera(r)) => C::CameraLens(shift(c, r)?),
        (C::CameraRoll(c), Selected::Camera(r)) => C::CameraRoll(shift(c, r)?),
        (C::CameraAimInfluence(c), Selected::Camera(r)) => C::CameraAimInfluence(shift(c, r)?),
        (C::CameraVisible(c), Selected::Camera(r)) => C::CameraVisible(shift(c, r)?),
        (id, _) => id,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn channels_follow_a_removed_item() {
        let elbow = |object| ChannelId::JointRotation { object, joint: 1 };
        assert_eq!(shifted(elbow(0), Selected::Object(1)), Some(elbow(0)));
        assert_eq!(shifted(elbow(1), Selected::Object(1)), None);
        assert_eq!(shifted(elbow(2), Selected::Object(1)), Some(elbow(1)));
        assert_eq!(shifted(ChannelId::LightColour(3), Selected::Object(0)), Some(ChannelId::LightColour(3)));
        assert_eq!(shifted(ChannelId::LightColour(3), Selected::Light(1)), Some(ChannelId::LightColour(2)));
        assert_eq!(shifted(ChannelId::LightIntensity(1), Selected::Light(1)), None);
        assert_eq!(shifted(ChannelId::ObjectScale(4), Selected::Light(0)), Some(ChannelId::ObjectScale(4)));
    }

    #[test]
    fn playback_loops_and_stops() {
        let mut p = Playback { frame: 9.0, playing: true, looping: true, every_frame: false };
        p.advance(0.1, 30.0, 0, 10);
        assert!((p.frame - 2.0).abs() < 1e-9, "{}", p.frame);
        let mut p = Playback { frame: 9.0, playing: true, looping: false, every_frame: false };
        p.advance(0.1, 30.0, 0, 10);
        assert_eq!(p.frame, 10.0);
        assert!(!p.playing);
        // Play at the end with looping off starts from the first frame.
        p.toggle_play(0, 10);
        assert!(p.playing);
        assert_eq!(p.frame, 0.0);
        // With looping on, Play at the end stays (the next step wraps).
        let mut p = Playback { frame: 10.0, playing: false, looping: true, every_frame: false };
        p.toggle_play(0, 10);
        assert_eq!(p.frame, 10.0);
    }

    #[test]
    fn real_time_drops_frames_and_every_frame_does_not() {
        // A slow draw (0.1 s) at 30 fps: real time jumps 3 frames, every-frame mode 1.
        let mut p = Playback { frame: 0.0, playing: true, looping: true, every_frame: false };
        p.advance(0.1, 30.0, 0, 100);
        assert!((p.frame - 3.0).abs() < 1e-9);
        assert!((p.achieved_fps(0.1, 30.0) - 10.0).abs() < 1e-9);
        assert!((p.achieved_fps(0.01, 30.0) - 30.0).abs() < 1e-9, "never above the scene's fps");
        p.every_frame = true;
        p.advance(0.1, 30.0, 0, 100);
        assert!((p.frame - 4.0).abs() < 1e-9);
        assert!((p.achieved_fps(0.01, 30.0) - 100.0).abs() < 1e-6);
    }
}
