//! The playback clock following the audio clock: while the sound plays, each editor frame
//! advances the playhead by the seconds of sound the device played since the frame before
//! (the count of frames its callback rendered, over its rate), not by the window's frame time,
//! so picture and sound cannot drift apart however the two clocks differ. The cursor of the
//! sound is moved to the playhead only when they differ by more than a frame: a loop's wrap,
//! a click on the ruler, a change of the FPS or of the frame range.

/// Turns the audio clock's frame count into seconds played since the last frame.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct AudioFollower {
    /// The count at the last frame.
    last: Option<u64>,
}

impl AudioFollower {
    /// Seconds of sound played since the last call (0 on the first), given the device's
    /// count of played frames and its rate.
    pub fn step(&mut self, played: u64, rate: u32) -> f64 {
        let seconds = match self.last {
            Some(last) => played.saturating_sub(last) as f64 / f64::from(rate.max(1)),
            None => 0.0,
        };
        self.last = Some(played);
        seconds
    }

    /// Forgets the count (playback stopped: the next start counts from there).
    pub fn reset(&mut self) {
        self.last = None;
    }
}

/// Whether the sound's cursor at `cursor` seconds must move to the playhead at `time`: they
/// differ by more than one frame at `fps`.
#[must_use]
pub fn needs_seek(cursor: f64, time: f64, fps: f64) -> bool {
    (cursor - time).abs() > 1.0 / fps.max(1e-9)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::audio::transport::Transport;
    use crate::session::Playback;

    /// A minute of playback at 24 fps with a simulated sound device whose clock runs 0.3 %
    /// fast against the wall clock (as cheap sound cards do), rendering 512-frame buffers at
    /// 48 kHz, while the editor draws frames at an uneven 50–70 Hz. Following the audio clock,
    /// picture and sound stay within a frame; following the wall clock, as the editor does
    /// without sound, they drift apart by several frames.
    #[test]
    fn the_playhead_follows_the_audio_clock_within_a_frame_over_a_minute() {
        let fps = 24.0;
        let (rate, buffer) = (48_000u32, 512usize);
        let device_speed = 1.003;
        let mut transport = Transport::new(rate, 2);
        transport.playing = true;
        let mut out = vec![0.0f32; buffer * 2];
        let mut follower = AudioFollower::default();
        let mut playback = Playback { playing: true, looping: false, ..Playback::default() };
        let mut wall_playback = playback.clone();
        // The device renders a buffer whenever its clock has consumed the last one.
        let (mut wall, mut device_due) = (0.0f64, 0.0f64);
        let mut seed = 1u32;
        let mut worst = 0.0f64;
        follower.step(transport.played, rate);
        while wall < 60.0 {
            seed = seed.wrapping_mul(1_664_525).wrapping_add(1_013_904_223);
            let dt = 1.0 / (50.0 + f64::from(seed >> 24) / 255.0 * 20.0);
            wall += dt;
            while device_due <= wall {
                transport.render(&mut out);
                device_due += buffer as f64 / f64::from(rate) / device_speed;
            }
            playback.advance(follower.step(transport.played, rate), fps, 0, 100_000);
            wall_playback.advance(dt, fps, 0, 100_000);
            if needs_seek(transport.cursor, playback.frame / fps, fps) {
                transport.cursor = playback.frame / fps;
            }
            // The sound heard now: the cursor less the buffer still queued in the device.
            let heard = transport.cursor - buffer as f64 / f64::from(rate);
            worst = worst.max((heard - playback.frame / fps).abs() * fps);
        }
        assert!(worst < 1.0, "picture and sound apart by {worst:.3} frames");
        let heard = transport.cursor * fps;
        let wall_drift = (wall_playback.frame - heard).abs();
        assert!(wall_drift > 3.0, "the wall clock alone drifts: {wall_drift:.2} frames");
    }

    #[test]
    fn seeks_only_past_a_frame() {
        assert!(!needs_seek(1.0, 1.0 + 0.9 / 24.0, 24.0));
        assert!(needs_seek(1.0, 1.0 + 1.1 / 24.0, 24.0));
        assert!(needs_seek(4.0, 0.0, 30.0), "a loop's wrap");
        let mut follower = AudioFollower::default();
        assert_eq!(follower.step(1000, 1000), 0.0);
        assert_eq!(follower.step(1500, 1000), 0.5);
        follower.reset();
        assert_eq!(follower.step(9000, 1000), 0.0);
    }
}
