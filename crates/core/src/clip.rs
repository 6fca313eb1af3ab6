//! Clip tracks and animation layers (docs/clips.md): how actions play one after another and on
//! top of each other.
//!
//! An object's [`ClipTrack`]s are stacked bottom-up; each holds [`Strip`]s in time order that
//! do not overlap. A strip plays an action from a start frame, trimmed, scaled, repeated and
//! optionally reversed, with blend in/out ramps and an influence that can be keyed. The
//! scene's [`Layer`]s lie above every object's tracks and its active action. This module holds
//! the data and the time arithmetic (which strip plays at a frame, at which action frame and
//! weight); the scene evaluator mixes the values.

use serde::{Deserialize, Serialize};

use crate::key::Animated;

/// How a strip's or a layer's values meet what is below them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum StripBlend {
    /// Mixed with what is below by weight: `lerp`, `slerp`.
    #[default]
    Replace,
    /// Added on top of what is below, relative to the action's value at the strip's first
    /// action frame (`action_in`): the strip adds how far its action moved since then.
    Combine,
    /// Added on top of what is below, relative to the rest pose (zero translation, no
    /// rotation, unit scale): the strip adds its action's values as offsets.
    Add,
}

/// What a strip does outside its frames.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum Extrapolation {
    /// Holds its last pose after its end until the next strip of its track, and its first
    /// pose before its start when it is the first strip of its track.
    Hold,
    /// Holds its last pose after its end until the next strip of its track.
    #[default]
    HoldForward,
    /// Plays only between its start and end.
    Nothing,
}

/// One action placed on a clip track.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Strip {
    /// The action it plays (a name in `Scene::actions`).
    pub action: String,
    /// The timeline frame at which it starts.
    pub start: f64,
    /// The action frames it plays: from `action_in` to `action_out` (the trim).
    pub action_in: f64,
    pub action_out: f64,
    /// Action frames played per timeline frame (> 0).
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub speed: f64,
    /// How many times the trimmed action plays (> 0, may be fractional).
    #[serde(default = "one", skip_serializing_if = "is_one")]
    pub repeat: f64,
    /// Plays from `action_out` back to `action_in`.
    #[serde(default, skip_serializing_if = "is_false")]
    pub reverse: bool,
    /// Timeline frames over which the strip's weight ramps up from its start and down to its
    /// end (together at most the strip's length).
    #[serde(default, skip_serializing_if = "is_zero")]
    pub blend_in: f64,
    #[serde(default, skip_serializing_if = "is_zero")]
    pub blend_out: f64,
    /// The strip's weight in 0..1, keyable (keys at timeline times).
    #[serde(default = "full_influence", skip_serializing_if = "is_full_influence")]
    pub influence: Animated<f32>,
    #[serde(default, skip_serializing_if = "is_replace")]
    pub blend: StripBlend,
    #[serde(default, skip_serializing_if = "is_hold_forward")]
    pub extrapolation: Extrapolation,
    /// Root motion continues (docs/clips.md, "Root motion"): the strip's root joint starts
    /// where the strip before it on the track left the character, in position and heading.
    #[serde(default, skip_serializing_if = "is_false")]
    pub continue_root: bool,
}

/// A track of strips on one object.
#[derive(Clone, Debug, Default, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ClipTrack {
    pub name: String,
    /// A muted track does not play.
    #[serde(default, skip_serializing_if = "is_false")]
    pub mute: bool,
    /// While any of an object's tracks is solo, only its solo tracks play.
    #[serde(default, skip_serializing_if = "is_false")]
    pub solo: bool,
    /// In time order, not overlapping.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub strips: Vec<Strip>,
}

/// How a layer's values meet what is below them.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum LayerMode {
    /// Mixed with what is below by the layer's weight, on the channels the layer keys.
    Override,
    /// The layer's keys are differences added on top of what is below, scaled by its weight:
    /// a translation offset, a rotation applied after, a scale factor.
    #[default]
    Additive,
}

/// An animation layer: an action played above every object's clip tracks and active action.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Layer {
    pub name: String,
    /// The action holding the layer's keys (a name in `Scene::actions`, active on no object).
    pub action: String,
    #[serde(default)]
    pub mode: LayerMode,
    /// The layer's weight in 0..1, keyable.
    #[serde(default = "full_influence", skip_serializing_if = "is_full_influence")]
    pub weight: Animated<f32>,
    #[serde(default, skip_serializing_if = "is_false")]
    pub mute: bool,
    /// While any layer is solo, only solo layers play.
    #[serde(default, skip_serializing_if = "is_false")]
    pub solo: bool,
}

/// Where a strip is at a timeline frame: the action frame it shows and its blend ramp.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StripAt {
    /// The strip's index in its track.
    pub strip: usize,
    /// The action frame shown.
    pub action_frame: f64,
    /// The blend in/out ramp in 0..1 (the keyed influence is applied on top).
    pub ramp: f64,
}

impl Strip {
    /// A strip that plays `action`'s frames `action_in..=action_out` once from `start`.
    #[must_use]
    pub fn new(action: impl Into<String>, start: f64, action_in: f64, action_out: f64) -> Self {
        Strip {
            action: action.into(),
            start,
            action_in,
            action_out,
            speed: 1.0,
            repeat: 1.0,
            reverse: false,
            blend_in: 0.0,
            blend_out: 0.0,
            influence: full_influence(),
            blend: StripBlend::Replace,
            extrapolation: Extrapolation::HoldForward,
            continue_root: false,
        }
    }

    /// Frames of the trimmed action (one repetition, in action frames).
    #[must_use]
    pub fn action_length(&self) -> f64 {
        self.action_out - self.action_in
    }

    /// Timeline frames the strip lasts: `(action_out − action_in) · repeat / speed`.
    #[must_use]
    pub fn length(&self) -> f64 {
        self.action_length() * self.repeat / self.speed
    }

    /// The timeline frame at which it ends.
    #[must_use]
    pub fn end(&self) -> f64 {
        self.start + self.length()
    }

    /// The action frame shown at timeline frame `frame`, clamped to the strip's frames
    /// (docs/clips.md, "Time"): `u = (f − start) · speed` action frames have played; within a
    /// repetition `u mod L` (the last repetition ends on `L`, not 0); reversed, counted back
    /// from `action_out`.
    #[must_use]
    pub fn action_frame(&self, frame: f64) -> f64 {
        let l = self.action_length();
        let total = l * self.repeat;
        // max/min, not clamp: numbers a file got wrong (validation reports them) must not
        // panic here.
        let u = ((frame - self.start) * self.speed).min(total).max(0.0);
        let within = if l <= 0.0 {
            0.0
        } else if u >= total {
            // The end of the last (possibly partial) repetition.
            let r = total - (self.repeat.ceil() - 1.0) * l;
            r.min(l).max(0.0)
        } else {
            u - (u / l).floor() * l
        };
        if self.reverse {
            self.action_out - within
        } else {
            self.action_in + within
        }
    }

    /// The blend ramp at timeline frame `frame`, with `frame` clamped to the strip: rising
    /// linearly over `blend_in` from the start, falling over `blend_out` to the end, 1 between.
    #[must_use]
    pub fn ramp(&self, frame: f64) -> f64 {
        let (start, end) = (self.start, self.end());
        let f = frame.min(end).max(start);
        let mut w: f64 = 1.0;
        if self.blend_in > 0.0 {
            w = w.min((f - start) / self.blend_in);
        }
        if self.blend_out > 0.0 {
            w = w.min((end - f) / self.blend_out);
        }
        w.clamp(0.0, 1.0)
    }

    /// True when its numbers make a strip that can play: finite, `speed` and `repeat` > 0,
    /// `action_out` after `action_in`, blends ≥ 0. The evaluator skips a strip that cannot.
    #[must_use]
    pub fn is_playable(&self) -> bool {
        [self.start, self.action_in, self.action_out, self.speed, self.repeat, self.blend_in, self.blend_out]
            .iter()
            .all(|v| v.is_finite())
            && self.speed > 0.0
            && self.repeat > 0.0
            && self.action_out > self.action_in
            && self.blend_in >= 0.0
            && self.blend_out >= 0.0
            && self.end().is_finite()
    }
}

impl ClipTrack {
    /// The strip that plays at timeline frame `frame`, with its action frame and ramp
    /// (docs/clips.md, "Which strip plays"): the strip whose frames hold it; else the last
    /// strip that ended before it, held until the next strip starts (Hold, Hold forward); else,
    /// before the first strip, that strip held when its extrapolation is Hold. `None`: no
    /// strip plays.
    #[must_use]
    pub fn strip_at(&self, frame: f64) -> Option<StripAt> {
        let at = |s: usize| {
            let strip = &self.strips[s];
            StripAt { strip: s, action_frame: strip.action_frame(frame), ramp: strip.ramp(frame) }
        };
        // Strips are in time order: the last one that started at or before the frame.
        let started = self.strips.partition_point(|s| s.start <= frame);
        if started == 0 {
            return match self.strips.first() {
                Some(first) if first.extrapolation == Extrapolation::Hold => Some(at(0)),
                _ => None,
            };
        }
        let s = started - 1;
        let strip = &self.strips[s];
        if frame <= strip.end() || strip.extrapolation != Extrapolation::Nothing {
            Some(at(s))
        } else {
            None
        }
    }

    /// Whether the track plays, given whether any track of its object is solo.
    #[must_use]
    pub fn plays(&self, any_solo: bool) -> bool {
        !self.mute && (!any_solo || self.solo)
    }
}

impl Layer {
    /// A layer playing `action`, additive at full weight.
    #[must_use]
    pub fn new(name: impl Into<String>, action: impl Into<String>) -> Self {
        Layer {
            name: name.into(),
            action: action.into(),
            mode: LayerMode::Additive,
            weight: full_influence(),
            mute: false,
            solo: false,
        }
    }

    /// Whether the layer plays, given whether any layer is solo.
    #[must_use]
    pub fn plays(&self, any_solo: bool) -> bool {
        !self.mute && (!any_solo || self.solo)
    }
}

fn one() -> f64 {
    1.0
}

#[allow(clippy::trivially_copy_pass_by_ref)] // serde's skip_serializing_if passes a reference
fn is_one(v: &f64) -> bool {
    *v == 1.0
}

#[allow(clippy::trivially_copy_pass_by_ref)]
fn is_zero(v: &f64) -> bool {
    *v == 0.0
}

#[allow(clippy::trivially_copy_pass_by_ref)]
fn is_false(v: &bool) -> bool {
    !*v
}

#[allow(clippy::trivially_copy_pass_by_ref)]
fn is_replace(v: &StripBlend) -> bool {
    *v == StripBlend::Replace
}

#[allow(clippy::trivially_copy_pass_by_ref)]
fn is_hold_forward(v: &Extrapolation) -> bool {
    *v == Extrapolation::HoldForward
}

fn full_influence() -> Animated<f32> {
    Animated::constant(1.0)
}

fn is_full_influence(a: &Animated<f32>) -> bool {
    *a == full_influence()
}

impl crate::Scene {
    /// Pushes object `o`'s active action down as a strip (Blender's *Push Down*): a new track
    /// on top of its tracks gets a strip playing the action over the frames its keys span, at
    /// those frames, and the object then plays no action (the keys are stored in the action,
    /// nothing is lost). Keys in no action are first named `<object>Action`. Returns the new
    /// track's index.
    ///
    /// # Errors
    /// No such object, or the object has no keys to push down.
    pub fn push_down(&mut self, o: usize) -> Result<usize, crate::ActionError> {
        if o >= self.objects.len() {
            return Err(crate::ActionError::NoObject(o));
        }
        let keyed = self.keyed_channels_of(o);
        let span = keyed
            .iter()
            .filter_map(|&id| key_span(self, id))
            .fold(None, |acc: Option<(f64, f64)>, (a, b)| {
                Some(acc.map_or((a, b), |(x, y)| (x.min(a), y.max(b))))
            });
        let Some((first, last)) = span else {
            return Err(crate::ActionError::NoKeys(self.objects[o].name.clone()));
        };
        if self.objects[o].action.is_none() {
            let name = self.unused_action_name(&format!("{}Action", self.objects[o].name));
            self.duplicate_action(o, &name)?;
        }
        let name = self.objects[o].action.clone().unwrap_or_default();
        self.assign_action(o, None)?;
        let fps = self.fps;
        let (start, end) = (first * fps, last * fps);
        // A single key spans no time: the strip plays one frame of it.
        let end = if end > start { end } else { start + 1.0 };
        let object = &mut self.objects[o];
        let mut n = object.clip_tracks.len() + 1;
        while object.clip_tracks.iter().any(|t| t.name == format!("Track {n}")) {
            n += 1;
        }
        object.clip_tracks.push(ClipTrack {
            name: format!("Track {n}"),
            strips: vec![Strip::new(name, start, start, end)],
            ..ClipTrack::default()
        });
        Ok(object.clip_tracks.len() - 1)
    }
}

impl crate::Scene {
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
                .filter(|c| {
                    crate::action::stored_channel_id(self, &c.path)
                        .is_ok_and(|id| crate::action::channel_object(id) == Some(o))
                })
                .filter_map(|c| c.keys.time_range())
                .fold(None, join)
        };
        span.map(|(a, b)| (a * self.fps, b * self.fps))
    }
}

/// First and last key time of channel `id` (seconds).
fn key_span(scene: &crate::Scene, id: crate::channel_id::ChannelId) -> Option<(f64, f64)> {
    use crate::channel_id::{channel, ChannelRef};
    match channel(scene, id)? {
        ChannelRef::Vec3(a) => a.key_time_range(),
        ChannelRef::Rotation(a) => a.key_time_range(),
        ChannelRef::Scalar(a) => a.key_time_range(),
    }
}

/// The problems of the scene's clip tracks and layers, each at its field path
/// (docs/clips.md, "Checks").
pub(crate) fn clip_problems(scene: &crate::Scene, c: &mut crate::validate::Checker) {
    let unit = |c: &mut crate::validate::Checker, path: &str, a: &Animated<f32>| {
        c.animated(path, a);
        let outside = std::iter::once(a.value)
            .chain(a.track.keys.iter().map(|k| k.value))
            .find(|v| !(0.0..=1.0).contains(v));
        if let Some(v) = outside {
            c.push(path, format!("{v} is outside 0..=1"));
        }
    };
    for (o, object) in scene.objects.iter().enumerate() {
        c.unique_names(
            "clip track",
            object
                .clip_tracks
                .iter()
                .enumerate()
                .map(|(t, track)| (format!("objects[{o}].clip_tracks[{t}].name"), track.name.as_str())),
        );
        for (t, track) in object.clip_tracks.iter().enumerate() {
            let mut previous_end: Option<f64> = None;
            for (s, strip) in track.strips.iter().enumerate() {
                let at = |field: &str| format!("objects[{o}].clip_tracks[{t}].strips[{s}].{field}");
                if scene.action_index(&strip.action).is_none() {
                    c.push(at("action"), format!("there is no action {:?} in actions", strip.action));
                }
                let finite = [
                    ("start", strip.start),
                    ("action_in", strip.action_in),
                    ("action_out", strip.action_out),
                    ("speed", strip.speed),
                    ("repeat", strip.repeat),
                    ("blend_in", strip.blend_in),
                    ("blend_out", strip.blend_out),
                ]
                .into_iter()
                .fold(true, |ok, (field, v)| c.f64(&at(field), v) && ok);
                if !finite {
                    continue;
                }
                if strip.action_out <= strip.action_in {
                    c.push(
                        at("action_out"),
                        format!("{} must be after action_in {}", strip.action_out, strip.action_in),
                    );
                }
                for (field, v) in [("speed", strip.speed), ("repeat", strip.repeat)] {
                    if v <= 0.0 {
                        c.push(at(field), format!("{v} must be > 0"));
                    }
                }
                for (field, v) in [("blend_in", strip.blend_in), ("blend_out", strip.blend_out)] {
                    if v < 0.0 {
                        c.push(at(field), format!("{v} must be ≥ 0"));
                    }
                }
                let length = strip.length();
                if length.is_finite()
                    && length > 0.0
                    && strip.blend_in + strip.blend_out > length * (1.0 + 1e-9)
                {
                    c.push(
                        at("blend_out"),
                        format!(
                            "blend in {} and blend out {} are longer than the strip ({length} frames)",
                            strip.blend_in, strip.blend_out
                        ),
                    );
                }
                if let Some(end) = previous_end {
                    if strip.start < end - 1e-9 {
                        c.push(
                            at("start"),
                            format!(
                                "frame {} is before the end of the strip before it (frame {end}): strips \
                                 of a track are in time order and do not overlap",
                                strip.start
                            ),
                        );
                    }
                }
                previous_end = Some(strip.end());
                unit(c, &at("influence"), &strip.influence);
            }
        }
    }
    c.unique_names(
        "layer",
        scene.layers.iter().enumerate().map(|(l, layer)| (format!("layers[{l}].name"), layer.name.as_str())),
    );
    for (l, layer) in scene.layers.iter().enumerate() {
        let path = format!("layers[{l}].action");
        if scene.action_index(&layer.action).is_none() {
            c.push(path, format!("there is no action {:?} in actions", layer.action));
        } else if let Some(o) = scene.objects.iter().position(|o| o.action.as_deref() == Some(&layer.action))
        {
            c.push(
                path,
                format!(
                    "action {:?} is active on object {:?}: a layer's action plays only in the layer",
                    layer.action, scene.objects[o].name
                ),
            );
        }
        unit(c, &format!("layers[{l}].weight"), &layer.weight);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_strip_maps_timeline_frames_to_action_frames() {
        let mut s = Strip::new("Walk", 10.0, 5.0, 25.0);
        assert_eq!(s.length(), 20.0);
        assert_eq!(s.action_frame(10.0), 5.0);
        assert_eq!(s.action_frame(20.0), 15.0);
        assert_eq!(s.action_frame(30.0), 25.0);
        assert_eq!(s.action_frame(40.0), 25.0, "clamped at the end");
        s.speed = 2.0;
        s.repeat = 2.0;
        assert_eq!(s.end(), 30.0);
        assert_eq!(s.action_frame(15.0), 15.0);
        assert_eq!(s.action_frame(19.0), 23.0);
        assert_eq!(s.action_frame(21.0), 7.0, "second repetition");
        assert_eq!(s.action_frame(30.0), 25.0, "the last repetition ends on action_out");
        s.reverse = true;
        assert_eq!(s.action_frame(11.0), 23.0);
        assert_eq!(s.action_frame(30.0), 5.0);
        s.repeat = 1.5;
        s.reverse = false;
        assert_eq!(s.end(), 25.0);
        assert_eq!(s.action_frame(25.0), 15.0, "half a repetition");
    }

    #[test]
    fn ramps_rise_and_fall() {
        let mut s = Strip::new("Run", 0.0, 0.0, 20.0);
        s.blend_in = 10.0;
        s.blend_out = 5.0;
        assert_eq!(s.ramp(-5.0), 0.0);
        assert_eq!(s.ramp(5.0), 0.5);
        assert_eq!(s.ramp(12.0), 1.0);
        assert_eq!(s.ramp(18.0), 0.4);
        assert_eq!(s.ramp(30.0), 0.0);
    }

    #[test]
    fn which_strip_plays() {
        let mut a = Strip::new("A", 0.0, 0.0, 10.0);
        let b = Strip::new("B", 20.0, 0.0, 10.0);
        a.extrapolation = Extrapolation::Nothing;
        let mut track = ClipTrack { name: "t".into(), mute: false, solo: false, strips: vec![a, b] };
        assert_eq!(track.strip_at(-1.0), None);
        assert_eq!(track.strip_at(5.0).map(|s| s.strip), Some(0));
        assert_eq!(track.strip_at(15.0), None, "A plays only over its frames");
        assert_eq!(track.strip_at(25.0).map(|s| (s.strip, s.action_frame)), Some((1, 5.0)));
        assert_eq!(track.strip_at(99.0).map(|s| (s.strip, s.action_frame)), Some((1, 10.0)), "held");
        track.strips[0].extrapolation = Extrapolation::Hold;
        assert_eq!(track.strip_at(-1.0).map(|s| (s.strip, s.action_frame)), Some((0, 0.0)));
        assert_eq!(track.strip_at(15.0).map(|s| (s.strip, s.action_frame)), Some((0, 10.0)));
    }
}
