//! Sound in the editor: the scene's unmuted clips play in real-time playback, in step with the
//! picture (the playback clock follows the audio clock, [`clock`]), and a frame step while
//! stopped — a scrub, an arrow key, a click on the ruler — plays one frame's worth of sound.
//!
//! The device ([`output`], `cpal`) is opened when the scene first has a clip whose samples are
//! decoded, on a thread of its own. Without one (a machine without a sound card, CI, Xvfb) the
//! editor works as before, silently, and the status bar says so once. `core`, `skin` and
//! `eval` know nothing of it.

pub mod clock;
pub mod output;
pub mod transport;

use std::sync::{mpsc, Arc};

use keyrig_core::Scene;

use crate::session::Playback;
use crate::sounds::SoundStore;
use clock::{needs_seek, AudioFollower};
use transport::MixClip;

/// Where the sound device stands.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Availability {
    /// Not asked for yet: the scene has had no clip to play.
    NotNeeded,
    /// Its thread is opening it.
    Opening,
    Open,
    /// There is none (or it failed to open): everything plays silently.
    Unavailable,
}

enum State {
    NotNeeded,
    Opening(mpsc::Receiver<output::Opened>),
    Open(output::Output),
    Unavailable,
}

/// The editor's sound: the device and how the playback follows it.
pub struct Audio {
    state: State,
    follower: AudioFollower,
    /// What the mix was built from: the document's cache key, the fps, and the clips with
    /// samples.
    mix_key: Option<((u64, u64), u64, usize)>,
    /// The whole frame of the last editor frame (a change while stopped plays a burst).
    last_frame: Option<i32>,
}

impl Default for Audio {
    fn default() -> Self {
        Audio { state: State::NotNeeded, follower: AudioFollower::default(), mix_key: None, last_frame: None }
    }
}

impl std::fmt::Debug for Audio {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("Audio").field("availability", &self.availability()).finish()
    }
}

/// The unmuted clips of `scene` whose samples are decoded, placed on the timeline in seconds.
fn mix_of(scene: &Scene, base_dir: Option<&std::path::Path>, sounds: &SoundStore) -> Vec<MixClip> {
    let fps = scene.fps.max(1e-9);
    scene
        .sounds
        .iter()
        .filter(|c| !c.mute && c.gain.is_finite() && c.start_frame.is_finite())
        .filter_map(|c| {
            let pcm = sounds.pcm(base_dir, &c.path)?;
            Some(MixClip { pcm: Arc::clone(pcm), start: c.start_frame / fps, gain: c.gain })
        })
        .collect()
}

impl Audio {
    #[must_use]
    pub fn availability(&self) -> Availability {
        match self.state {
            State::NotNeeded => Availability::NotNeeded,
            State::Opening(_) => Availability::Opening,
            State::Open(_) => Availability::Open,
            State::Unavailable => Availability::Unavailable,
        }
    }

    /// Seconds of sound the device played since the last frame, while the sound plays: what
    /// the playback clock advances by instead of the window's frame time.
    pub fn played_seconds(&mut self) -> Option<f64> {
        let State::Open(out) = &self.state else { return None };
        let transport = out.transport.lock().ok()?;
        if !transport.playing {
            return None;
        }
        Some(self.follower.step(transport.played, transport.rate))
    }

    /// Brings the sound in step with the editor after a frame: opens the device when the scene
    /// first has a clip to play, rebuilds the mix when the clips or the fps changed, starts and
    /// stops with playback, moves the sound to the playhead when they are more than a frame
    /// apart, and plays a frame's burst when the frame changes while stopped. Returns the
    /// message to show once when there turns out to be no device.
    pub fn follow(
        &mut self,
        scene: &Scene,
        doc_key: (u64, u64),
        base_dir: Option<&std::path::Path>,
        sounds: &SoundStore,
        playback: &Playback,
    ) -> Option<String> {
        let frame = playback.whole_frame();
        let stepped = self.last_frame.is_some_and(|last| last != frame);
        self.last_frame = Some(frame);
        let mut notice = None;
        if let State::NotNeeded = self.state {
            if scene.sounds.iter().any(|c| sounds.pcm(base_dir, &c.path).is_some()) {
                self.state = State::Opening(output::open());
            }
        }
        let answer = match &self.state {
            State::Opening(answer) => Some(answer.try_recv()),
            _ => None,
        };
        match answer {
            Some(Ok(Ok(out))) => self.state = State::Open(out),
            Some(Ok(Err(why))) => {
                notice = Some(format!("No sound output device: sound clips play silently ({why})"));
                self.state = State::Unavailable;
            }
            Some(Err(mpsc::TryRecvError::Disconnected)) => {
                notice = Some("No sound output device: sound clips play silently".to_owned());
                self.state = State::Unavailable;
            }
            Some(Err(mpsc::TryRecvError::Empty)) | None => {}
        }
        let State::Open(out) = &self.state else { return notice };
        let Ok(mut transport) = out.transport.lock() else { return notice };
        let fps = scene.fps.max(1e-9);
        let key = (
            doc_key,
            fps.to_bits(),
            scene.sounds.iter().filter(|c| sounds.pcm(base_dir, &c.path).is_some()).count(),
        );
        if self.mix_key != Some(key) {
            transport.mix = Arc::new(mix_of(scene, base_dir, sounds));
            self.mix_key = Some(key);
        }
        let time = playback.frame / fps;
        let real_time = playback.playing && !playback.every_frame;
        if real_time {
            if !transport.playing {
                transport.playing = true;
                transport.burst = 0;
                transport.cursor = time;
                self.follower.reset();
                self.follower.step(transport.played, transport.rate);
            } else if needs_seek(transport.cursor, time, fps) {
                transport.cursor = time;
            }
        } else {
            if transport.playing {
                transport.playing = false;
                self.follower.reset();
            }
            if stepped {
                // One frame of sound from the new frame (a scrub, a step, every-frame playback).
                transport.cursor = time;
                transport.burst = (f64::from(transport.rate) / fps).round() as u64;
            }
        }
        notice
    }

    /// Whether it waits for the device's thread (the editor polls it).
    #[must_use]
    pub fn is_opening(&self) -> bool {
        matches!(self.state, State::Opening(_))
    }
}
