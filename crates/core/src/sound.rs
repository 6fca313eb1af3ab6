//! Sound clips on the timeline, and the min/max summary their waveforms are drawn from.
//!
//! A [`SoundClip`] names a file (relative to the scene's folder, like a model file), the
//! timeline frame its first sample plays at, a gain and a mute switch; the scene saves it.
//! Decoding is keyrig-io's (`keyrig_io::sound`, Symphonia). What the editor draws under the
//! timeline is a [`WaveformSummary`]: the minimum and maximum sample of every
//! [`SUMMARY_BUCKET`] frames, with coarser levels each halving the one before, so that drawing
//! a clip costs one lookup per pixel whatever its length (a 10-minute 48 kHz track is 112 500
//! buckets at the finest level, 900 kB with all levels).

use serde::{Deserialize, Serialize};

/// A sound file placed on the timeline.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct SoundClip {
    /// The sound file (WAV, FLAC, Ogg Vorbis, MP3), relative to the scene file's folder.
    pub path: String,
    /// The timeline frame at which the clip's first sample plays (may be fractional or before
    /// the frame range).
    #[serde(default)]
    pub start_frame: f64,
    /// Linear gain (1: as recorded).
    #[serde(default = "unit_gain", skip_serializing_if = "is_unit_gain")]
    pub gain: f32,
    #[serde(default, skip_serializing_if = "is_false")]
    pub mute: bool,
}

fn unit_gain() -> f32 {
    1.0
}

#[allow(clippy::trivially_copy_pass_by_ref, clippy::float_cmp)] // serde's skip_serializing_if passes a reference
fn is_unit_gain(gain: &f32) -> bool {
    *gain == 1.0
}

#[allow(clippy::trivially_copy_pass_by_ref)]
fn is_false(value: &bool) -> bool {
    !*value
}

impl SoundClip {
    /// A clip of `path` starting at `start_frame`, at unit gain, not muted.
    #[must_use]
    pub fn new(path: impl Into<String>, start_frame: f64) -> Self {
        SoundClip { path: path.into(), start_frame, gain: 1.0, mute: false }
    }

    /// The clip's file name without folders, for labels.
    #[must_use]
    pub fn label(&self) -> &str {
        self.path.rsplit(['/', '\\']).next().unwrap_or(&self.path)
    }
}

/// Frames (samples per channel) summarised by one bucket of a summary's finest level.
pub const SUMMARY_BUCKET: u64 = 256;

/// The minimum and maximum sample over runs of frames, at several resolutions.
#[derive(Clone, Debug, PartialEq)]
pub struct WaveformSummary {
    /// Samples per second of the sound.
    pub sample_rate: u32,
    pub channels: u16,
    /// Frames in the sound (samples per channel).
    pub frames: u64,
    /// `levels[k][i]` is `[min, max]` over every channel of frames
    /// `i · SUMMARY_BUCKET · 2^k .. (i + 1) · SUMMARY_BUCKET · 2^k`.
    pub levels: Vec<Vec<[f32; 2]>>,
}

impl WaveformSummary {
    /// The sound's length in seconds.
    #[must_use]
    pub fn duration(&self) -> f64 {
        if self.sample_rate == 0 {
            0.0
        } else {
            self.frames as f64 / f64::from(self.sample_rate)
        }
    }

    /// `[min, max]` of the samples between `from` and `to` seconds into the sound, read from the
    /// coarsest level whose buckets are no longer than the span (so one call costs a few
    /// lookups); `None` when the span misses the sound.
    #[must_use]
    pub fn range(&self, from: f64, to: f64) -> Option<[f32; 2]> {
        if !(from.is_finite() && to.is_finite())
            || to <= from
            || self.levels.is_empty()
            || self.sample_rate == 0
        {
            return None;
        }
        let rate = f64::from(self.sample_rate);
        let first = (from * rate).max(0.0);
        let last = (to * rate).min(self.frames as f64);
        if last <= first {
            return None;
        }
        let span = last - first;
        let mut level = 0;
        while level + 1 < self.levels.len() && ((SUMMARY_BUCKET << (level + 1)) as f64) <= span {
            level += 1;
        }
        let bucket = (SUMMARY_BUCKET << level) as f64;
        let buckets = &self.levels[level];
        let a = ((first / bucket).floor() as usize).min(buckets.len().saturating_sub(1));
        let b = ((last / bucket).ceil() as usize).clamp(a + 1, buckets.len());
        buckets[a..b].iter().fold(None, |acc: Option<[f32; 2]>, &[lo, hi]| {
            Some(match acc {
                Some([l, h]) => [l.min(lo), h.max(hi)],
                None => [lo, hi],
            })
        })
    }

    /// `[min, max]` of each of `count` consecutive spans of `step` seconds, the first starting
    /// `from` seconds into the sound (`None` for a span that misses it): the columns of a
    /// waveform drawn at `step` seconds a column. Each costs one [`WaveformSummary::range`],
    /// so the whole costs `count` lookups whatever the sound's length.
    pub fn columns(&self, from: f64, step: f64, count: usize) -> impl Iterator<Item = Option<[f32; 2]>> + '_ {
        (0..count).map(move |c| {
            let start = from + step * c as f64;
            self.range(start, start + step)
        })
    }
}

/// Builds a [`WaveformSummary`] from interleaved samples pushed in any chunks.
#[derive(Clone, Debug)]
pub struct SummaryBuilder {
    sample_rate: u32,
    channels: u16,
    frames: u64,
    /// Min and max of the bucket being filled, and the frames in it.
    current: [f32; 2],
    in_bucket: u64,
    finest: Vec<[f32; 2]>,
    /// A sample left over from a chunk that ended inside a frame.
    carry: Vec<f32>,
}

impl SummaryBuilder {
    /// A builder for a sound of `channels` channels at `sample_rate` (both at least 1).
    #[must_use]
    pub fn new(sample_rate: u32, channels: u16) -> Self {
        SummaryBuilder {
            sample_rate,
            channels: channels.max(1),
            frames: 0,
            current: [f32::INFINITY, f32::NEG_INFINITY],
            in_bucket: 0,
            finest: Vec::new(),
            carry: Vec::new(),
        }
    }

    /// Adds interleaved samples (non-finite ones count as silence).
    pub fn push_interleaved(&mut self, samples: &[f32]) {
        let channels = usize::from(self.channels);
        let mut samples = samples;
        if !self.carry.is_empty() {
            let need = channels - self.carry.len();
            let take = need.min(samples.len());
            self.carry.extend_from_slice(&samples[..take]);
            samples = &samples[take..];
            if self.carry.len() < channels {
                return;
            }
            let frame = std::mem::take(&mut self.carry);
            self.push_frame(&frame);
        }
        let mut frames = samples.chunks_exact(channels);
        for frame in frames.by_ref() {
            self.push_frame(frame);
        }
        self.carry.extend_from_slice(frames.remainder());
    }

    /// Frames the bucket being filled takes before it is complete (1 to [`SUMMARY_BUCKET`]).
    #[must_use]
    pub fn bucket_room(&self) -> u64 {
        SUMMARY_BUCKET - self.in_bucket
    }

    /// Adds `frames` whole frames whose samples (every channel's) lie between `lo` and `hi`,
    /// as a decoder that found them from its own planes says (non-finite bounds count as
    /// silence). Exact when `frames` is at most [`SummaryBuilder::bucket_room`]; more frames
    /// give every bucket they reach the same bounds. A partial frame left by
    /// [`SummaryBuilder::push_interleaved`] stays where it is.
    pub fn push_extremes(&mut self, frames: u64, [lo, hi]: [f32; 2]) {
        let finite = |s: f32| if s.is_finite() { s } else { 0.0 };
        let (lo, hi) = (finite(lo), finite(hi));
        let mut left = frames;
        while left > 0 {
            let n = left.min(self.bucket_room());
            self.current[0] = self.current[0].min(lo);
            self.current[1] = self.current[1].max(hi);
            self.frames += n;
            self.in_bucket += n;
            left -= n;
            if self.in_bucket == SUMMARY_BUCKET {
                self.finest.push(self.current);
                self.current = [f32::INFINITY, f32::NEG_INFINITY];
                self.in_bucket = 0;
            }
        }
    }

    /// Appends `later`, the summary of the frames that follow this builder's, as if they had
    /// been pushed here (a sound summarised in parts, each on a thread of its own). Exact only
    /// where this builder ends on a bucket boundary, so that `later`'s buckets are this
    /// builder's next ones: otherwise nothing is appended and `false` is returned.
    #[must_use]
    pub fn append(&mut self, later: SummaryBuilder) -> bool {
        if self.in_bucket != 0 || !self.carry.is_empty() {
            return false;
        }
        self.finest.extend(later.finest);
        self.frames += later.frames;
        self.current = later.current;
        self.in_bucket = later.in_bucket;
        self.carry = later.carry;
        true
    }

    fn push_frame(&mut self, frame: &[f32]) {
        for &s in frame {
            let s = if s.is_finite() { s } else { 0.0 };
            self.current[0] = self.current[0].min(s);
            self.current[1] = self.current[1].max(s);
        }
        self.frames += 1;
        self.in_bucket += 1;
        if self.in_bucket == SUMMARY_BUCKET {
            self.finest.push(self.current);
            self.current = [f32::INFINITY, f32::NEG_INFINITY];
            self.in_bucket = 0;
        }
    }

    /// The summary: the finest level, then levels halving it down to one bucket.
    #[must_use]
    pub fn finish(mut self) -> WaveformSummary {
        if self.in_bucket > 0 {
            self.finest.push(self.current);
        }
        let mut levels = vec![self.finest];
        while levels.last().is_some_and(|l| l.len() > 1) {
            let coarser = levels
                .last()
                .map(|l| {
                    l.chunks(2)
                        .map(|pair| {
                            pair.iter().fold([f32::INFINITY, f32::NEG_INFINITY], |[lo, hi], &[a, b]| {
                                [lo.min(a), hi.max(b)]
                            })
                        })
                        .collect()
                })
                .unwrap_or_default();
            levels.push(coarser);
        }
        if levels.first().is_some_and(Vec::is_empty) {
            levels.clear();
        }
        WaveformSummary {
            sample_rate: self.sample_rate,
            channels: self.channels,
            frames: self.frames,
            levels,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A 1 kHz sine at 48 kHz, stereo, the right channel at half amplitude.
    fn sine(seconds: f64) -> Vec<f32> {
        let n = (seconds * 48_000.0) as usize;
        (0..n)
            .flat_map(|i| {
                let s = (2.0 * std::f64::consts::PI * 1000.0 * i as f64 / 48_000.0).sin() as f32;
                [s, 0.5 * s]
            })
            .collect()
    }

    #[test]
    fn a_summary_holds_the_extremes_at_every_level() {
        let samples = sine(2.0);
        let mut builder = SummaryBuilder::new(48_000, 2);
        // Odd chunk sizes split frames between pushes.
        for chunk in samples.chunks(1001) {
            builder.push_interleaved(chunk);
        }
        let summary = builder.finish();
        assert_eq!(summary.frames, 96_000);
        assert!((summary.duration() - 2.0).abs() < 1e-12);
        assert_eq!(summary.levels[0].len(), 96_000usize.div_ceil(256));
        assert_eq!(summary.levels.last().map(Vec::len), Some(1));
        let [lo, hi] = summary.levels.last().expect("top")[0];
        assert!((hi - 1.0).abs() < 1e-6 && (lo + 1.0).abs() < 1e-6, "{lo} {hi}");
        // Any span of a full period or more sees ±1.
        for (from, to) in [(0.0, 0.001), (0.5, 1.7), (1.999, 2.0), (0.0, 10.0)] {
            let [lo, hi] = summary.range(from, to).expect("in the sound");
            assert!(hi > 0.99 && lo < -0.99, "{from}..{to}: {lo}..{hi}");
        }
        assert_eq!(summary.range(2.5, 3.0), None);
        // Columns of half a second from -0.5 s: before the sound, four of it, after it.
        let columns: Vec<_> = summary.columns(-0.5, 0.5, 6).collect();
        assert_eq!(columns.len(), 6);
        assert_eq!((columns[0], columns[5]), (None, None));
        for column in &columns[1..5] {
            let [lo, hi] = column.expect("in the sound");
            assert!(hi > 0.99 && lo < -0.99, "{lo}..{hi}");
        }
        assert_eq!(summary.range(1.0, 1.0), None);
        assert_eq!(summary.range(f64::NAN, 1.0), None);
    }

    #[test]
    fn a_sound_summarised_in_parts_is_the_sound_summarised_whole() {
        let samples = sine(0.5);
        let mut whole = SummaryBuilder::new(48_000, 2);
        whole.push_interleaved(&samples);
        // Parts that start on bucket boundaries (the last one ends inside a bucket).
        let cut = 2 * 256 * 37;
        let mut first = SummaryBuilder::new(48_000, 2);
        first.push_interleaved(&samples[..cut]);
        let mut second = SummaryBuilder::new(48_000, 2);
        second.push_interleaved(&samples[cut..]);
        assert!(first.append(second));
        assert_eq!(first.finish(), whole.finish());
        // A part that ends inside a bucket takes nothing after it.
        let mut ragged = SummaryBuilder::new(48_000, 2);
        ragged.push_interleaved(&samples[..2 * 300]);
        assert!(!ragged.append(SummaryBuilder::new(48_000, 2)));
        assert_eq!(ragged.finish().frames, 300);
    }

    #[test]
    fn extremes_pushed_per_bucket_give_the_summary_of_the_samples() {
        let samples = sine(0.5);
        let mut by_samples = SummaryBuilder::new(48_000, 2);
        by_samples.push_interleaved(&samples);
        // The same sound as a decoder's planes give it: runs that end at bucket ends.
        let mut by_extremes = SummaryBuilder::new(48_000, 2);
        let mut at = 0;
        let frames = samples.len() / 2;
        while at < frames {
            let n = (by_extremes.bucket_room() as usize).min(frames - at).min(100);
            let run = &samples[2 * at..2 * (at + n)];
            let lo = run.iter().copied().fold(f32::INFINITY, f32::min);
            let hi = run.iter().copied().fold(f32::NEG_INFINITY, f32::max);
            by_extremes.push_extremes(n as u64, [lo, hi]);
            at += n;
        }
        assert_eq!(by_extremes.finish(), by_samples.finish());
        // More frames than the bucket takes: every bucket reached gets the bounds.
        let mut builder = SummaryBuilder::new(1000, 1);
        builder.push_extremes(10, [-0.25, 0.5]);
        assert_eq!(builder.bucket_room(), SUMMARY_BUCKET - 10);
        builder.push_extremes(SUMMARY_BUCKET * 2, [f32::NEG_INFINITY, f32::NAN]);
        let summary = builder.finish();
        assert_eq!(summary.frames, 10 + 2 * SUMMARY_BUCKET);
        assert_eq!(summary.levels[0], vec![[-0.25, 0.5], [0.0, 0.0], [0.0, 0.0]]);
    }

    #[test]
    fn silence_and_empty_sounds() {
        let mut builder = SummaryBuilder::new(8000, 1);
        builder.push_interleaved(&[0.0; 300]);
        builder.push_interleaved(&[f32::NAN]);
        let summary = builder.finish();
        assert_eq!(summary.frames, 301);
        assert_eq!(summary.range(0.0, 1.0), Some([0.0, 0.0]));
        let empty = SummaryBuilder::new(8000, 1).finish();
        assert!(empty.levels.is_empty());
        assert_eq!(empty.range(0.0, 1.0), None);
    }

    #[test]
    fn clips_read_with_defaults() {
        let clip = SoundClip::new("sound/line.wav", 12.0);
        assert_eq!(clip.label(), "line.wav");
        assert!((clip.gain - 1.0).abs() < f32::EPSILON && !clip.mute);
    }
}
