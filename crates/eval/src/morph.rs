//! Vertex-animation playback (MD2 clips): which two stored frames a time shows, and how much
//! of the second. Only frame counts and clip ranges matter here; the vertices live with the
//! consumer (keyrig-render's `MorphMesh` for the GPU, keyrig-io's MD2 model for the CPU).

use std::ops::Range;

use thiserror::Error;

/// What is wrong with morph clips or a request to play them.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MorphError {
    #[error("the mesh has no frames")]
    NoFrames,
    #[error("frame {frame} has {len} vertices, frame 0 has {expected}")]
    FrameLength { frame: usize, len: usize, expected: usize },
    #[error("{count} triangle indices is not a multiple of 3")]
    IndexCount { count: usize },
    #[error("triangle index {index} is out of range (the mesh has {vertices} vertices)")]
    Index { index: u32, vertices: usize },
    #[error("{count} texture coordinates for {vertices} vertices")]
    UvCount { count: usize, vertices: usize },
    #[error("clip `{name}` covers frames {start}..{end}, outside the {frames} frames (or empty)")]
    ClipRange { name: String, start: usize, end: usize, frames: usize },
    #[error("no clip named `{name}` (clips: {available})")]
    NoSuchClip { name: String, available: String },
    #[error("playback rate must be finite and > 0 frames per second, got {0}")]
    BadFps(f64),
    #[error("time must be finite, got {0}")]
    BadTime(f64),
    #[error("{times} key times for {frames} frames, or times that are not finite and increasing, or a period that is not finite and > 0")]
    KeyTimes { times: usize, frames: usize },
}

/// Frames shown at their own times instead of at a rate (a VRML/X3D `CoordinateInterpolator`:
/// frame i at `times[i]` seconds, linear between neighbours, holding before the first and
/// after the last; with a `period` the whole repeats every `period` seconds, a time at a
/// positive multiple of it showing the end of a cycle only at the first, as keyrig's repeating
/// tracks do).
///
/// # Invariants
/// One time per frame, finite and not decreasing (equal times are a jump: the later frame
/// shows from that time on); `period` finite and > 0 ([`MorphClips::with_key_times`]).
#[derive(Clone, Debug)]
pub struct KeyTimes {
    times: Vec<f64>,
    period: Option<f64>,
}

impl PartialEq for KeyTimes {
    fn eq(&self, other: &Self) -> bool {
        self.times.len() == other.times.len()
            && self.times.iter().zip(&other.times).all(|(a, b)| a.to_bits() == b.to_bits())
            && self.period.map(f64::to_bits) == other.period.map(f64::to_bits)
    }
}

impl Eq for KeyTimes {}

impl KeyTimes {
    /// The key times, one per frame.
    #[must_use]
    pub fn times(&self) -> &[f64] {
        &self.times
    }

    /// The repeat period, when the frames loop.
    #[must_use]
    pub fn period(&self) -> Option<f64> {
        self.period
    }

    fn blend(&self, time: f64) -> Result<MorphBlend, MorphError> {
        if !time.is_finite() {
            return Err(MorphError::BadTime(time));
        }
        let local = match self.period {
            Some(p) if time > p => time - (time / p).floor() * p,
            _ => time,
        };
        let times = &self.times;
        let last = times.len() - 1;
        let hold = |i: usize| MorphBlend { frame_a: i as u32, frame_b: i as u32, t: 0.0 };
        if local < times[0] {
            return Ok(hold(0));
        }
        if local >= times[last] {
            return Ok(hold(last));
        }
        // The last key at or before `local` (after a jump: the later of equal keys).
        let next = times.partition_point(|&k| k <= local);
        let a = next - 1;
        let t = ((local - times[a]) / (times[next] - times[a])) as f32;
        Ok(MorphBlend { frame_a: a as u32, frame_b: next as u32, t: t.clamp(0.0, 1.0) })
    }
}

/// A named run of consecutive frames (an MD2 clip: `stand`, `run`, …).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MorphClip {
    pub name: String,
    /// Indices of the stored frames.
    pub frames: Range<usize>,
}

/// Which two frames are blended, and with what weight of the second.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MorphBlend {
    pub frame_a: u32,
    pub frame_b: u32,
    pub t: f32,
}

/// The frames of a vertex-animated mesh and its named clips.
///
/// # Invariants
/// At least one frame; every clip a non-empty range of existing frames ([`MorphClips::new`]).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MorphClips {
    frame_count: usize,
    clips: Vec<MorphClip>,
    key_times: Option<KeyTimes>,
}

impl MorphClips {
    /// Clips over `frame_count` stored frames.
    ///
    /// # Errors
    /// No frames, or a clip that is empty or reaches past the last frame.
    pub fn new(frame_count: usize, clips: Vec<MorphClip>) -> Result<Self, MorphError> {
        if frame_count == 0 {
            return Err(MorphError::NoFrames);
        }
        if let Some(clip) = clips.iter().find(|c| c.frames.is_empty() || c.frames.end > frame_count) {
            return Err(MorphError::ClipRange {
                name: clip.name.clone(),
                start: clip.frames.start,
                end: clip.frames.end,
                frames: frame_count,
            });
        }
        Ok(MorphClips { frame_count, clips, key_times: None })
    }

    /// The same frames shown at their own times ([`KeyTimes`]) rather than at a rate: then
    /// [`MorphClips::blend_at`] ignores the clip and the rate.
    ///
    /// # Errors
    /// [`MorphError::KeyTimes`]: not one time per frame, times not finite or decreasing, or a
    /// period that is not finite and > 0.
    pub fn with_key_times(mut self, times: Vec<f64>, period: Option<f64>) -> Result<Self, MorphError> {
        let ok = times.len() == self.frame_count
            && times.iter().all(|t| t.is_finite())
            && times.windows(2).all(|w| w[0] <= w[1])
            && period.is_none_or(|p| p.is_finite() && p > 0.0);
        if !ok {
            return Err(MorphError::KeyTimes { times: times.len(), frames: self.frame_count });
        }
        self.key_times = Some(KeyTimes { times, period });
        Ok(self)
    }

    /// The frames' own times, when they have them.
    #[must_use]
    pub fn key_times(&self) -> Option<&KeyTimes> {
        self.key_times.as_ref()
    }

    /// Number of stored frames.
    #[must_use]
    pub fn frame_count(&self) -> usize {
        self.frame_count
    }

    /// The named clips, in frame order.
    #[must_use]
    pub fn clips(&self) -> &[MorphClip] {
        &self.clips
    }

    /// The frames clip `clip` plays; every frame for `None`.
    ///
    /// # Errors
    /// [`MorphError::NoSuchClip`] listing the clips there are.
    pub fn clip_frames(&self, clip: Option<&str>) -> Result<Range<usize>, MorphError> {
        match clip {
            None => Ok(0..self.frame_count),
            Some(name) => {
                self.clips.iter().find(|c| c.name == name).map(|c| c.frames.clone()).ok_or_else(|| {
                    MorphError::NoSuchClip {
                        name: name.to_owned(),
                        available: self.clips.iter().map(|c| c.name.as_str()).collect::<Vec<_>>().join(", "),
                    }
                })
            }
        }
    }

    /// Seconds one loop of `clip` lasts at `fps`: frames / fps (looping, the last frame morphs
    /// back into the first).
    ///
    /// # Errors
    /// An unknown clip or a rate that is not finite and > 0.
    pub fn clip_duration(&self, clip: Option<&str>, fps: f64) -> Result<f64, MorphError> {
        let frames = self.clip_frames(clip)?;
        if !(fps.is_finite() && fps > 0.0) {
            return Err(MorphError::BadFps(fps));
        }
        Ok(frames.len() as f64 / fps)
    }

    /// The frames to blend at `time` seconds: at their own times when the frames have them
    /// ([`MorphClips::with_key_times`]); else when `clip` plays at `fps`, looping:
    /// f = (time · fps) mod n over the clip's n frames; frames ⌊f⌋ and ⌊f⌋ + 1 (the clip's
    /// first after its last) with weight t = f − ⌊f⌋. A pure function of its inputs.
    ///
    /// # Errors
    /// An unknown clip, a rate that is not finite and > 0, a time that is not finite.
    pub fn blend_at(&self, clip: Option<&str>, fps: f64, time: f64) -> Result<MorphBlend, MorphError> {
        if let Some(keys) = &self.key_times {
            return keys.blend(time);
        }
        let frames = self.clip_frames(clip)?;
        if !(fps.is_finite() && fps > 0.0) {
            return Err(MorphError::BadFps(fps));
        }
        let f = time * fps;
        if !f.is_finite() {
            return Err(MorphError::BadTime(time));
        }
        let n = frames.len();
        let f = f.rem_euclid(n as f64);
        let a = (f.floor() as usize).min(n - 1);
        let b = (a + 1) % n;
        let t = ((f - a as f64) as f32).clamp(0.0, 1.0);
        Ok(MorphBlend { frame_a: (frames.start + a) as u32, frame_b: (frames.start + b) as u32, t })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn blends_loop_over_the_clip() {
        let clips = MorphClips::new(10, vec![MorphClip { name: "run".into(), frames: 4..8 }]).unwrap();
        let b = clips.blend_at(Some("run"), 10.0, 0.25).unwrap();
        assert_eq!((b.frame_a, b.frame_b), (6, 7));
        assert!((b.t - 0.5).abs() < 1e-6);
        // The last frame morphs back into the first.
        let b = clips.blend_at(Some("run"), 10.0, 0.35).unwrap();
        assert_eq!((b.frame_a, b.frame_b), (7, 4));
        assert!(matches!(clips.blend_at(Some("walk"), 10.0, 0.0), Err(MorphError::NoSuchClip { .. })));
        assert!(matches!(clips.blend_at(None, 0.0, 0.0), Err(MorphError::BadFps(_))));
        assert!(matches!(clips.blend_at(None, 10.0, f64::NAN), Err(MorphError::BadTime(_))));
        assert_eq!(clips.clip_duration(Some("run"), 10.0), Ok(0.4));
        assert!(matches!(MorphClips::new(0, vec![]), Err(MorphError::NoFrames)));
        assert!(matches!(
            MorphClips::new(3, vec![MorphClip { name: "x".into(), frames: 2..5 }]),
            Err(MorphError::ClipRange { .. })
        ));
    }

    /// Key times: linear between keys, held outside them, equal keys a jump, repeating with
    /// the period (a time at a positive multiple of it shows the cycle's end only at the
    /// first multiple, as repeating tracks do).
    ///
    /// ```text
    /// frames   0     1       2 3
    /// times    0.5   1.0     2.0 (2.0)      period 4
    /// ```
    #[test]
    fn key_times_blend_like_a_coordinate_interpolator() {
        let clips =
            MorphClips::new(4, vec![]).unwrap().with_key_times(vec![0.5, 1.0, 2.0, 2.0], Some(4.0)).unwrap();
        let at = |t: f64| {
            let b = clips.blend_at(Some("ignored"), 10.0, t).unwrap();
            (b.frame_a, b.frame_b, b.t)
        };
        assert_eq!(at(0.0), (0, 0, 0.0));
        assert_eq!(at(0.5), (0, 1, 0.0));
        assert_eq!(at(0.75), (0, 1, 0.5));
        assert_eq!(at(1.5), (1, 2, 0.5));
        assert_eq!(at(1.999_999), (1, 2, 0.999_999));
        assert_eq!(at(2.0), (3, 3, 0.0), "the later of equal keys from its time on");
        assert_eq!(at(4.0), (3, 3, 0.0), "the first cycle's end");
        assert_eq!(at(4.75), (0, 1, 0.5), "the second cycle");
        assert_eq!(at(8.0), (0, 0, 0.0), "a later multiple starts the next cycle");
        assert!(matches!(
            MorphClips::new(2, vec![]).unwrap().with_key_times(vec![1.0, 0.0], None),
            Err(MorphError::KeyTimes { .. })
        ));
        assert!(matches!(
            MorphClips::new(2, vec![]).unwrap().with_key_times(vec![0.0], None),
            Err(MorphError::KeyTimes { .. })
        ));
        assert!(matches!(
            MorphClips::new(2, vec![]).unwrap().with_key_times(vec![0.0, 1.0], Some(0.0)),
            Err(MorphError::KeyTimes { .. })
        ));
        assert!(matches!(clips.blend_at(None, 10.0, f64::NAN), Err(MorphError::BadTime(_))));
    }
}
