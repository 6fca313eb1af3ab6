//! A sound clip's waveform on a time axis: one vertical bar per screen column, from the
//! smallest to the largest sample the column's stretch of time holds.
//!
//! The bars come from the clip's precomputed min/max summary ([`WaveformSummary::columns`]),
//! which answers each column from the coarsest level whose buckets are no longer than the
//! column (a few lookups), so the cost is the number of visible columns, whatever the length
//! of the track: a 10-minute track zoomed out costs what a ten-second one does
//! (keyrig-core's `benches/waveform.rs`).

use egui::{Color32, Pos2, Rect};
use keyrig_core::{SoundClip, WaveformSummary};

use super::time_axis::TimeAxis;

/// The columns of `clip`'s waveform drawn over `axis` between `left` and `right` (screen
/// points, one column each): `(x, [min, max])` with the samples scaled by the clip's gain and
/// clamped to ±1; columns outside the sound are left out. `fps` turns frames into seconds.
#[must_use]
pub fn waveform_columns(
    summary: &WaveformSummary,
    clip: &SoundClip,
    axis: &TimeAxis,
    fps: f64,
    left: f32,
    right: f32,
) -> Vec<(f32, [f32; 2])> {
    let fps = if fps.is_finite() && fps > 0.0 { fps } else { return Vec::new() };
    let gain = if clip.gain.is_finite() { clip.gain.abs() } else { 0.0 };
    // Only the columns the clip covers are visited.
    let clip_left = axis.x(clip.start_frame);
    let clip_right = axis.x(clip.start_frame + summary.duration() * fps);
    let (from, to) = (left.max(clip_left).floor(), right.min(clip_right).ceil());
    if !(from.is_finite() && to.is_finite()) || to <= from {
        return Vec::new();
    }
    let count = (to - from) as usize;
    let first = (axis.frame(from) - clip.start_frame) / fps;
    let step = axis.frames_per_point() / fps;
    summary
        .columns(first, step, count)
        .enumerate()
        .filter_map(|(c, bounds)| {
            let [lo, hi] = bounds?;
            Some((from + c as f32, [(lo * gain).clamp(-1.0, 1.0), (hi * gain).clamp(-1.0, 1.0)]))
        })
        .collect()
}

/// Paints `columns` ([`waveform_columns`]) into `rect`, full scale at its top and bottom, as
/// one mesh; a bar is at least a line high so silence shows as a line.
pub fn paint_waveform(painter: &egui::Painter, rect: Rect, columns: &[(f32, [f32; 2])], colour: Color32) {
    if columns.is_empty() {
        return;
    }
    let (mid, half) = (rect.center().y, rect.height() * 0.5);
    let mut mesh = egui::Mesh::default();
    mesh.reserve_triangles(columns.len() * 2);
    mesh.reserve_vertices(columns.len() * 4);
    for &(x, [lo, hi]) in columns {
        let top = mid - hi * half;
        let bottom = (mid - lo * half).max(top + 1.0);
        mesh.add_colored_rect(Rect::from_min_max(Pos2::new(x, top), Pos2::new(x + 1.0, bottom)), colour);
    }
    painter.add(egui::Shape::mesh(mesh));
}

#[cfg(test)]
mod tests {
    use super::*;
    use keyrig_core::SummaryBuilder;

    /// One second of silence, then one second of a ±0.5 square wave, at 24 kHz mono.
    fn summary() -> WaveformSummary {
        let mut builder = SummaryBuilder::new(24_000, 1);
        builder.push_interleaved(&[0.0; 24_000]);
        let square: Vec<f32> = (0..24_000).map(|i| if i % 2 == 0 { 0.5 } else { -0.5 }).collect();
        builder.push_interleaved(&square);
        builder.finish()
    }

    #[test]
    fn columns_follow_the_clip_on_the_axis() {
        // 24 fps; frames 0..96 over 96 points: one frame a point. The clip starts at frame 24,
        // so its silence covers frames 24..48 and its square wave frames 48..72.
        let axis = TimeAxis { left: 0.0, right: 96.0, start: 0.0, end: 96.0 };
        let clip = SoundClip::new("a.wav", 24.0);
        let columns = waveform_columns(&summary(), &clip, &axis, 24.0, 0.0, 96.0);
        assert_eq!(columns.first().map(|c| c.0), Some(24.0));
        assert_eq!(columns.last().map(|c| c.0), Some(71.0));
        assert_eq!(columns.len(), 48);
        for &(x, [lo, hi]) in &columns {
            // Frame 47–48 (samples 23 000..24 000) is read from buckets of 512 samples, the
            // last of which (23 552..24 064) holds the step: that column sees both.
            if x < 47.0 {
                assert_eq!([lo, hi], [0.0, 0.0], "x {x}");
            } else if x >= 48.0 {
                assert_eq!([lo, hi], [-0.5, 0.5], "x {x}");
            }
        }
        // Gain scales, and clamps at full scale.
        let loud = SoundClip { gain: 4.0, ..clip.clone() };
        let columns = waveform_columns(&summary(), &loud, &axis, 24.0, 60.0, 64.0);
        assert_eq!(columns, (60..64).map(|x| (x as f32, [-1.0, 1.0])).collect::<Vec<_>>());
        // Only the asked columns; none off the clip; none for a broken fps.
        assert!(waveform_columns(&summary(), &clip, &axis, 24.0, 0.0, 20.0).is_empty());
        assert!(waveform_columns(&summary(), &clip, &axis, 0.0, 0.0, 96.0).is_empty());
        assert!(waveform_columns(&summary(), &clip, &axis, f64::NAN, 0.0, 96.0).is_empty());
    }

    #[test]
    fn a_long_track_zoomed_out_visits_only_the_visible_columns() {
        // Ten minutes at 48 kHz stereo, summarised without keeping the samples.
        let mut builder = SummaryBuilder::new(48_000, 2);
        let chunk: Vec<f32> = (0..96_000).map(|i| ((i / 2) as f32 * 0.01).sin() * 0.25).collect();
        for _ in 0..600 {
            builder.push_interleaved(&chunk);
        }
        let summary = builder.finish();
        let clip = SoundClip::new("long.wav", 0.0);
        let axis = TimeAxis { left: 0.0, right: 800.0, start: 0.0, end: 600.0 * 24.0 };
        let columns = waveform_columns(&summary, &clip, &axis, 24.0, 0.0, 800.0);
        assert_eq!(columns.len(), 800);
        for (_, [lo, hi]) in columns {
            assert!((hi - 0.25).abs() < 1e-3 && (lo + 0.25).abs() < 1e-3, "{lo} {hi}");
        }
    }
}
