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
        Ok(MorphClips { frame_count, clips })
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

    /// The frames to blend at `time` seconds when `clip` plays at `fps`, looping:
    /// f = (time · fps) mod n over the clip's n frames; frames ⌊f⌋ and ⌊f⌋ + 1 (the clip's
    /// first after its last) with weight t = f − ⌊f⌋. A pure function of its inputs.
    ///
    /// # Errors
    /// An unknown clip, a rate that is not finite and > 0, a time that is not finite.
    pub fn blend_at(&self, clip: Option<&str>, fps: f64, time: f64) -> Result<MorphBlend, MorphError> {
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
}
