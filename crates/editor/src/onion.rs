//! Onion skinning: ghosts of the selected object (or of the character whose joint is selected)
//! at other frames, drawn translucent over the viewport — warm before the current frame, cool
//! after it, fading with distance — so spacing can be judged without scrubbing. The ghosts are
//! the scene evaluator's states at those frames (no pose overrides), skinned on the GPU with
//! the object's deformer like the object itself (keyrig-render's `SceneRig::ghost_items`).

use glam::Vec3;
use keyrig_core::{FrameRange, Scene};
use keyrig_render::Ghost;

use keyrig_edit::channels::{self, ChannelId};

/// The most ghosts on each side of the current frame.
pub const MAX_PER_SIDE: u32 = 8;

/// Where ghosts are placed.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Spacing {
    /// Every `n` frames from the current one.
    Frames(u32),
    /// At the object's keys (any of its channels, its joints' included).
    Keys,
}

/// The onion-skin settings of the view (not saved with the scene).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct OnionSkin {
    pub enabled: bool,
    /// Ghosts before and after the current frame (each at most [`MAX_PER_SIDE`]).
    pub before: u32,
    pub after: u32,
    pub spacing: Spacing,
}

impl Default for OnionSkin {
    fn default() -> Self {
        OnionSkin { enabled: false, before: 2, after: 2, spacing: Spacing::Frames(5) }
    }
}

/// The tint of ghosts before the current frame (warm) and after it (cool), linear RGB.
pub const BEFORE_TINT: Vec3 = Vec3::new(1.0, 0.3, 0.2);
pub const AFTER_TINT: Vec3 = Vec3::new(0.2, 0.75, 1.0);

/// One ghost: the frame it shows and how it is drawn.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct GhostFrame {
    pub frame: f64,
    /// −1, −2, … before the current frame; 1, 2, … after it.
    pub offset: i32,
    pub ghost: Ghost,
}

/// The ghosts of `object` around `frame` under `settings`, farthest first (so nearer ghosts
/// are blended over farther ones); frames outside the scene's range are left out.
#[must_use]
pub fn ghost_frames(settings: &OnionSkin, scene: &Scene, object: usize, frame: f64) -> Vec<GhostFrame> {
    if !settings.enabled {
        return Vec::new();
    }
    let (before, after) = (settings.before.min(MAX_PER_SIDE), settings.after.min(MAX_PER_SIDE));
    let range = scene.frame_range;
    let inside = |f: f64| f >= f64::from(range.start) - 1e-9 && f <= f64::from(range.end) + 1e-9;
    let (earlier, later): (Vec<f64>, Vec<f64>) = match settings.spacing {
        Spacing::Frames(step) => {
            let step = f64::from(step.max(1));
            (
                (1..=before).map(|k| frame - step * f64::from(k)).filter(|&f| inside(f)).collect(),
                (1..=after).map(|k| frame + step * f64::from(k)).filter(|&f| inside(f)).collect(),
            )
        }
        Spacing::Keys => {
            let keys = key_frames(scene, object, range);
            (
                keys.iter().rev().copied().filter(|&f| f < frame - 1e-6).take(before as usize).collect(),
                keys.iter().copied().filter(|&f| f > frame + 1e-6).take(after as usize).collect(),
            )
        }
    };
    let mut out = Vec::with_capacity(earlier.len() + later.len());
    let side = |frames: &[f64], sign: i32, tint: Vec3, out: &mut Vec<GhostFrame>| {
        let n = frames.len();
        for (k, &f) in frames.iter().enumerate().rev() {
            // The nearest ghost is the most opaque; the farthest fades to a third of it.
            let fade = if n > 1 { 1.0 - (k as f32 / (n - 1) as f32) * 0.65 } else { 1.0 };
            out.push(GhostFrame {
                frame: f,
                offset: sign * (k as i32 + 1),
                ghost: Ghost { tint, opacity: 0.45 * fade },
            });
        }
    };
    side(&earlier, -1, BEFORE_TINT, &mut out);
    side(&later, 1, AFTER_TINT, &mut out);
    out.sort_by_key(|g| std::cmp::Reverse(g.offset.abs()));
    out
}

/// The distinct frames (sorted) of `object`'s keys inside `range`: its transform, skeleton
/// root and joints.
fn key_frames(scene: &Scene, object: usize, range: FrameRange) -> Vec<f64> {
    let fps = scene.fps.max(1e-9);
    let (from, to) = (f64::from(range.start) / fps, f64::from(range.end) / fps);
    let mut frames: Vec<f64> = ChannelId::of_object(scene, object)
        .into_iter()
        .flat_map(|id| channels::keys_between(scene, id, from - 1e-9, to + 1e-9).times)
        .map(|t| (t * fps * 1e6).round() / 1e6)
        .collect();
    frames.sort_by(f64::total_cmp);
    frames.dedup();
    frames
}

#[cfg(test)]
mod tests {
    use super::*;

    fn settings(before: u32, after: u32, spacing: Spacing) -> OnionSkin {
        OnionSkin { enabled: true, before, after, spacing }
    }

    #[test]
    fn ghosts_every_n_frames_inside_the_range_farthest_first() {
        let scene = keyrig_io::demo::demo_scene();
        let ghosts = ghost_frames(&settings(2, 2, Spacing::Frames(5)), &scene, 0, 30.0);
        let frames: Vec<(f64, i32)> = ghosts.iter().map(|g| (g.frame, g.offset)).collect();
        assert_eq!(frames, [(20.0, -2), (40.0, 2), (25.0, -1), (35.0, 1)]);
        assert!(ghosts.iter().filter(|g| g.offset < 0).all(|g| g.ghost.tint == BEFORE_TINT));
        assert!(ghosts.iter().filter(|g| g.offset > 0).all(|g| g.ghost.tint == AFTER_TINT));
        // Nearer ghosts are more opaque.
        assert!(ghosts[2].ghost.opacity > ghosts[0].ghost.opacity);
        // At the first frame there is nothing before it; off, there are no ghosts.
        let at_start = ghost_frames(&settings(2, 2, Spacing::Frames(5)), &scene, 0, 0.0);
        assert!(at_start.iter().all(|g| g.offset > 0), "{at_start:?}");
        assert!(ghost_frames(&OnionSkin::default(), &scene, 0, 30.0).is_empty());
    }

    #[test]
    fn ghosts_at_keys_use_every_channel_of_the_object() {
        let scene = keyrig_io::demo::demo_scene();
        let keys = key_frames(&scene, 0, scene.frame_range);
        assert!(keys.windows(2).all(|w| w[0] < w[1]), "sorted, distinct: {keys:?}");
        let ghosts = ghost_frames(&settings(3, 1, Spacing::Keys), &scene, 0, 40.0);
        let before: Vec<f64> = ghosts.iter().filter(|g| g.offset < 0).map(|g| g.frame).collect();
        let after: Vec<f64> = ghosts.iter().filter(|g| g.offset > 0).map(|g| g.frame).collect();
        let expected_before: Vec<f64> = keys.iter().rev().copied().filter(|&f| f < 40.0).take(3).collect();
        let mut before_sorted = before.clone();
        before_sorted.sort_by(|a, b| b.total_cmp(a));
        assert_eq!(before_sorted, expected_before);
        assert_eq!(after, keys.iter().copied().filter(|&f| f > 40.0).take(1).collect::<Vec<_>>());
    }
}
