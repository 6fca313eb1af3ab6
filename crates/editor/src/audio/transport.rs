//! What the sound output plays, shared by the editor's frame and the device's callback: the
//! clips' samples placed on the timeline (the mix), where on the timeline the next output
//! frame is (the cursor), whether it is playing, what is left of a scrub burst, and how many
//! frames it has played (the audio clock the playback clock follows).
//!
//! Pure: no device. The device's callback calls [`Transport::render`]; tests call it with a
//! simulated device.

use std::sync::Arc;

use keyrig_io::sound::SoundPcm;

/// One clip as the mix plays it.
#[derive(Clone, Debug)]
pub struct MixClip {
    pub pcm: Arc<SoundPcm>,
    /// The timeline second its first sample plays at.
    pub start: f64,
    /// Linear gain.
    pub gain: f32,
}

/// The sound output's state.
#[derive(Clone, Debug)]
pub struct Transport {
    /// The output's frames a second and channels.
    pub rate: u32,
    pub channels: u16,
    /// The unmuted clips.
    pub mix: Arc<Vec<MixClip>>,
    /// The timeline second of the next output frame.
    pub cursor: f64,
    pub playing: bool,
    /// Output frames left of a scrub burst (played while not playing).
    pub burst: u64,
    /// Output frames rendered while playing: the audio clock.
    pub played: u64,
}

impl Transport {
    /// A silent transport for an output of `rate` frames a second and `channels` channels.
    #[must_use]
    pub fn new(rate: u32, channels: u16) -> Self {
        Transport {
            rate: rate.max(1),
            channels: channels.max(1),
            mix: Arc::new(Vec::new()),
            cursor: 0.0,
            playing: false,
            burst: 0,
            played: 0,
        }
    }

    /// Fills `out` (interleaved, [`Transport::channels`] a frame) with what plays next: the mix
    /// from the cursor while playing or bursting, silence otherwise; moves the cursor and, while
    /// playing, the audio clock.
    pub fn render(&mut self, out: &mut [f32]) {
        let channels = usize::from(self.channels);
        let frames = out.len() / channels;
        out.fill(0.0);
        let sounding =
            if self.playing { frames } else { frames.min(usize::try_from(self.burst).unwrap_or(usize::MAX)) };
        if sounding > 0 {
            mix_into(&self.mix, &mut out[..sounding * channels], channels, self.rate, self.cursor);
            self.cursor += sounding as f64 / f64::from(self.rate);
        }
        if self.playing {
            self.played += frames as u64;
        } else {
            self.burst -= sounding as u64;
        }
    }
}

/// Adds `clips` played from timeline second `from` into `out` (interleaved, `channels` a frame,
/// `rate` frames a second), each resampled by linear interpolation between its samples, a
/// mono clip on every channel; the sum is clamped to ±1.
pub fn mix_into(clips: &[MixClip], out: &mut [f32], channels: usize, rate: u32, from: f64) {
    let channels = channels.max(1);
    let frames = out.len() / channels;
    for clip in clips {
        let pcm = &clip.pcm;
        let (source_channels, source_frames) = (usize::from(pcm.channels.max(1)), pcm.frames());
        if source_frames < 2 || pcm.sample_rate == 0 {
            continue;
        }
        let step = f64::from(pcm.sample_rate) / f64::from(rate.max(1));
        let scale = clip.gain / 32768.0;
        let first = (from - clip.start) * f64::from(pcm.sample_rate);
        for f in 0..frames {
            let at = first + f as f64 * step;
            if at < 0.0 {
                continue;
            }
            let i = at as usize;
            if i + 1 >= source_frames {
                break;
            }
            let t = (at - i as f64) as f32;
            for c in 0..channels {
                let sc = c.min(source_channels - 1);
                let a = f32::from(pcm.samples[i * source_channels + sc]);
                let b = f32::from(pcm.samples[(i + 1) * source_channels + sc]);
                out[f * channels + c] += (a + (b - a) * t) * scale;
            }
        }
    }
    for s in out.iter_mut() {
        *s = s.clamp(-1.0, 1.0);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// A mono ramp at 1000 Hz: sample i is i × 10 (so its value says where it was read).
    fn ramp(frames: usize) -> Arc<SoundPcm> {
        Arc::new(SoundPcm {
            sample_rate: 1000,
            channels: 1,
            samples: (0..frames).map(|i| (i * 10) as i16).collect(),
        })
    }

    #[test]
    fn the_mix_places_resamples_and_sums_clips() {
        // The ramp starts at timeline second 1; an output at 2000 Hz reads it at half steps.
        let clips = vec![MixClip { pcm: ramp(1000), start: 1.0, gain: 1.0 }];
        let mut out = vec![0.0; 8];
        mix_into(&clips, &mut out, 2, 2000, 1.1);
        // Frames at source positions 100, 100.5, 101, 101.5, on both channels.
        let expect: Vec<f32> =
            [1000.0, 1005.0, 1010.0, 1015.0].iter().flat_map(|v| [v / 32768.0, v / 32768.0]).collect();
        for (a, b) in out.iter().zip(&expect) {
            assert!((a - b).abs() < 1e-6, "{out:?} vs {expect:?}");
        }
        // Before the clip and after its end: silence; two clips add; gain scales; the sum clamps.
        let mut out = vec![0.0; 4];
        mix_into(&clips, &mut out, 1, 1000, 0.0);
        assert_eq!(out, vec![0.0; 4]);
        mix_into(&clips, &mut out, 1, 1000, 5.0);
        assert_eq!(out, vec![0.0; 4]);
        let loud = vec![
            MixClip { pcm: ramp(1000), start: 0.0, gain: 0.5 },
            MixClip { pcm: ramp(1000), start: 0.0, gain: 1.0 },
        ];
        mix_into(&loud, &mut out, 1, 1000, 0.1);
        assert!((out[0] - 1.5 * 1000.0 / 32768.0).abs() < 1e-6, "{out:?}");
        let huge = vec![MixClip { pcm: ramp(1000), start: 0.0, gain: 100.0 }];
        mix_into(&huge, &mut out, 1, 1000, 0.5);
        assert_eq!(out, vec![1.0; 4]);
    }

    #[test]
    fn bursts_play_once_and_only_playing_moves_the_clock() {
        let mut transport = Transport::new(1000, 1);
        transport.mix = Arc::new(vec![MixClip { pcm: ramp(1000), start: 0.0, gain: 1.0 }]);
        let mut out = vec![9.0; 64];
        transport.render(&mut out);
        assert_eq!(out, vec![0.0; 64], "stopped: silence");
        // A burst of 40 frames from second 0.2 sounds over two callbacks, then stops.
        (transport.cursor, transport.burst) = (0.2, 40);
        transport.render(&mut out[..32]);
        assert!((out[0] - 2000.0 / 32768.0).abs() < 1e-6);
        assert_eq!(transport.burst, 8);
        transport.render(&mut out[..32]);
        assert!(out[7] > 0.0 && out[8..32].iter().all(|&s| s == 0.0), "{out:?}");
        assert_eq!((transport.burst, transport.played), (0, 0));
        // Playing moves the cursor and counts frames.
        transport.playing = true;
        transport.render(&mut out);
        assert_eq!(transport.played, 64);
        assert!((transport.cursor - (0.24 + 0.064)).abs() < 1e-9, "{}", transport.cursor);
    }
}
