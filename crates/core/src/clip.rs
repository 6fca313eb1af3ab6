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
