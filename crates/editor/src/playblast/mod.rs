//! Playblasts: a range of frames rendered offscreen and written as one movie (animated GIF,
//! animated PNG, H.264 MP4) or as numbered PNGs, optionally motion-blurred — the one path of
//! `keyrig render --frames` and the editor's File ▸ Render animation (docs/playblast.md).
//!
//! A [`Playblast`] says what to write; [`Playblast::run`] renders each frame through a
//! [`HeadlessRenderer`] from the [`FrameInput`]s a caller's closure builds (the scene at a
//! fractional frame), hands the image to an encoder thread (so encoding one frame overlaps
//! rendering the next), reports [`Progress`] after each frame and stops when the progress
//! callback says so. The movie file is written atomically: it replaces the target only when
//! the last frame is in, and a cancelled or failed render leaves the target as it was.

pub mod encode;

use crate::audio::transport::MixClip;
use encode::MovieSound;

use std::ops::ControlFlow;
use std::path::{Path, PathBuf};
use std::sync::mpsc;
use std::time::{Duration, Instant};

use keyrig_render::accumulate::{subframe_offsets, MAX_SUBFRAMES};
use keyrig_render::image::RgbaImage;
use keyrig_render::{FrameInput, HeadlessRenderer, RenderError};

pub use encode::{numbered_output, write_png, MovieWriter};

/// What a playblast draws beside the scene, as `keyrig render` draws it unless told otherwise:
/// the grid and skeletons, no camera gizmos; seen by `camera` where no scene camera is looked
/// through (`None`: the scene's saved view).
#[must_use]
pub fn playblast_view(camera: Option<keyrig_core::Camera>) -> keyrig_render::ViewOptions {
    keyrig_render::ViewOptions { camera, cameras: false, ..keyrig_render::ViewOptions::default() }
}

/// The frame `frame` of a scene as `keyrig render` and File ▸ Render animation both render it:
/// seen through `through` — the active camera at that frame (markers cut between cameras), one
/// camera, or (`None`) the view in `view.camera` — with the rest of `view`'s options.
///
/// # Errors
/// The scene cannot be turned into a frame at that time.
pub fn scene_frame(
    rig: &keyrig_render::SceneRig,
    view: &keyrig_render::ViewOptions,
    through: Option<crate::view::LookThrough>,
    frame: f64,
) -> Result<FrameInput, keyrig_render::SceneFrameError> {
    let look_through = through.and_then(|t| t.camera_at(rig.scene(), frame));
    rig.frame(rig.time_of_frame(frame), &keyrig_render::ViewOptions { look_through, ..*view })
}

/// Most frames one playblast renders.
pub const MAX_FRAMES: u32 = 100_000;

/// What a playblast writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum MovieFormat {
    /// One PNG per frame (`frame_####.png`).
    PngFrames,
    /// One animated PNG (APNG), lossless, looping.
    Apng,
    /// One animated GIF, 256 colours per frame, looping.
    Gif,
    /// H.264 video in an MP4 file.
    Mp4,
}

impl MovieFormat {
    pub const ALL: [MovieFormat; 4] =
        [MovieFormat::Mp4, MovieFormat::Gif, MovieFormat::Apng, MovieFormat::PngFrames];

    /// The name on the command line (`--format`).
    #[must_use]
    pub fn cli_name(self) -> &'static str {
        match self {
            MovieFormat::PngFrames => "png-frames",
            MovieFormat::Apng => "apng",
            MovieFormat::Gif => "gif",
            MovieFormat::Mp4 => "mp4",
        }
    }

    #[must_use]
    pub fn from_cli_name(name: &str) -> Option<Self> {
        Self::ALL.into_iter().find(|f| f.cli_name().eq_ignore_ascii_case(name))
    }

    /// The name in the editor's dialog.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            MovieFormat::PngFrames => "Numbered PNG frames",
            MovieFormat::Apng => "Animated PNG (.png)",
            MovieFormat::Gif => "Animated GIF (.gif)",
            MovieFormat::Mp4 => "H.264 movie (.mp4)",
        }
    }

    /// The extension of the file (or files) it writes.
    #[must_use]
    pub fn extension(self) -> &'static str {
        match self {
            MovieFormat::PngFrames | MovieFormat::Apng => "png",
            MovieFormat::Gif => "gif",
            MovieFormat::Mp4 => "mp4",
        }
    }

    /// What an output path of a range asks for: `#` in the name or a folder → numbered PNGs;
    /// `.mp4`, `.gif`; `.png` or `.apng` → an animated PNG.
    ///
    /// # Errors
    /// [`PlayblastError::UnknownFormat`] for another extension.
    pub fn of_output(output: &Path) -> Result<Self, PlayblastError> {
        let text = output.to_string_lossy();
        let name = output.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        if name.contains('#') || output.is_dir() || text.ends_with('/') {
            return Ok(MovieFormat::PngFrames);
        }
        let extension = output.extension().map(|e| e.to_string_lossy().to_ascii_lowercase());
        match extension.as_deref() {
            Some("mp4") => Ok(MovieFormat::Mp4),
            Some("gif") => Ok(MovieFormat::Gif),
            Some("png" | "apng") => Ok(MovieFormat::Apng),
            _ => Err(PlayblastError::UnknownFormat { path: output.to_path_buf() }),
        }
    }
}

/// Motion blur: each frame is the average of `samples` renders spread evenly across a shutter
/// open for `shutter` of the frame interval, centred on the frame
/// ([`keyrig_render::accumulate`]). One sample is no blur.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MotionBlur {
    pub samples: u32,
    pub shutter: f64,
}

impl MotionBlur {
    /// No blur: one render per frame.
    pub const OFF: MotionBlur = MotionBlur { samples: 1, shutter: DEFAULT_SHUTTER };

    /// The offsets in frames of the sub-frames of frame 0.
    #[must_use]
    pub fn offsets(&self) -> Vec<f64> {
        subframe_offsets(self.samples, self.shutter)
    }

    /// # Errors
    /// No samples, more than [`MAX_SUBFRAMES`], or a shutter outside `0..=1` frames.
    pub fn validate(&self) -> Result<(), PlayblastError> {
        if self.samples == 0 || self.samples > MAX_SUBFRAMES {
            return Err(PlayblastError::Settings(format!(
                "motion blur samples {}: must be between 1 and {MAX_SUBFRAMES}",
                self.samples
            )));
        }
        if !(0.0..=1.0).contains(&self.shutter) {
            return Err(PlayblastError::Settings(format!(
                "shutter {}: must be between 0 and 1 (a fraction of the frame interval)",
                self.shutter
            )));
        }
        Ok(())
    }
}

/// The shutter by default: open for half the frame interval (a film camera's 180° shutter).
pub const DEFAULT_SHUTTER: f64 = 0.5;

/// Why a playblast failed.
#[derive(Debug, thiserror::Error)]
pub enum PlayblastError {
    #[error("{}: unknown movie type (expected .mp4, .gif, .png for an animated PNG, a name with # for numbered PNGs, or a folder)", path.display())]
    UnknownFormat { path: PathBuf },
    #[error("{0}")]
    Settings(String),
    #[error(transparent)]
    Overwrite(#[from] keyrig_io::file_io::OverwriteInputError),
    #[error("frame {frame}: {message}")]
    Frame { frame: f64, message: String },
    #[error("rendering frame {frame}: {source}")]
    Render { frame: f64, source: RenderError },
    #[error("{}: {message}", path.display())]
    Encode { path: PathBuf, message: String },
    #[error("{}: cannot write: {source}", path.display())]
    Write { path: PathBuf, source: std::io::Error },
    #[error("cancelled after {done} of {total} frames; nothing was written over {}", path.display())]
    Cancelled { done: u32, total: u32, path: PathBuf },
    #[error("the encoder thread stopped unexpectedly")]
    EncoderLost,
    #[error("sound clip {path}: {message}")]
    Sound { path: String, message: String },
}

/// Where a playblast is, reported after each frame.
#[derive(Clone, Copy, Debug)]
pub struct Progress {
    pub done: u32,
    pub total: u32,
    pub elapsed: Duration,
}

impl Progress {
    /// The time left at the rate so far (`None` before the first frame).
    #[must_use]
    pub fn remaining(&self) -> Option<Duration> {
        if self.done == 0 {
            return None;
        }
        let per_frame = self.elapsed.as_secs_f64() / f64::from(self.done);
        Some(Duration::from_secs_f64(per_frame * f64::from(self.total.saturating_sub(self.done))))
    }

    /// Done, as a fraction.
    #[must_use]
    pub fn fraction(&self) -> f32 {
        if self.total == 0 {
            1.0
        } else {
            self.done as f32 / self.total as f32
        }
    }
}

/// What a finished playblast did.
#[derive(Clone, Debug)]
pub struct Summary {
    pub frames: u32,
    /// Time spent rendering and reading back (the render thread's busy time).
    pub render_time: Duration,
    /// Time spent encoding and writing (the encoder thread's busy time).
    pub encode_time: Duration,
    /// From the first render to the file committed.
    pub wall_time: Duration,
}

/// The error a caller's frame builder returns (the scene could not be evaluated there).
pub type FrameError = Box<dyn std::error::Error + Send + Sync>;

/// A range of frames to render and where to write them.
#[derive(Clone, Debug)]
pub struct Playblast {
    /// First and last frame (inclusive).
    pub first: i64,
    pub last: i64,
    /// Frame rate of the movie (the scene's).
    pub fps: f64,
    pub size: (u32, u32),
    pub format: MovieFormat,
    pub output: PathBuf,
    pub motion_blur: MotionBlur,
    /// The scene's sound clips, mixed into an MP4's sound track (other formats carry none).
    pub sound: SceneSound,
}

/// A scene's sound clips and the folder their relative paths start from.
#[derive(Clone, Debug, Default)]
pub struct SceneSound {
    pub clips: Vec<keyrig_core::SoundClip>,
    pub base_dir: Option<PathBuf>,
}

impl SceneSound {
    /// The unmuted clips, their files decoded, placed on the timeline in seconds at `fps` (as
    /// the editor plays them, `audio::mix_of`).
    ///
    /// # Errors
    /// A clip's file cannot be decoded, or is longer than the samples kept for playing
    /// ([`keyrig_io::sound::MAX_PLAYBACK_FRAMES`]).
    pub fn mix(&self, fps: f64) -> Result<Vec<MixClip>, PlayblastError> {
        let fps = fps.max(1e-9);
        let mut clips = Vec::new();
        for clip in &self.clips {
            if clip.mute || !clip.gain.is_finite() || !clip.start_frame.is_finite() {
                continue;
            }
            let file = crate::sounds::full_path(self.base_dir.as_deref(), &clip.path);
            let error = |message: String| PlayblastError::Sound { path: clip.path.clone(), message };
            let decoded = keyrig_io::sound::decode_sound_file_for_playback(
                &file,
                keyrig_io::sound::MAX_PLAYBACK_FRAMES,
            )
            .map_err(|e| error(e.to_string()))?;
            let pcm = decoded.pcm.ok_or_else(|| {
                error(format!(
                    "longer than keyrig mixes ({} minutes at 48 kHz)",
                    keyrig_io::sound::MAX_PLAYBACK_FRAMES / 48_000 / 60
                ))
            })?;
            clips.push(MixClip {
                pcm: std::sync::Arc::new(pcm),
                start: clip.start_frame / fps,
                gain: clip.gain,
            });
        }
        Ok(clips)
    }
}

impl Playblast {
    /// Frames in the range.
    #[must_use]
    pub fn frame_count(&self) -> u32 {
        u32::try_from(self.last - self.first + 1).unwrap_or(0)
    }

    /// # Errors
    /// An empty or too long range, a frame rate that is not positive, or bad motion blur.
    pub fn validate(&self) -> Result<(), PlayblastError> {
        if self.last < self.first {
            return Err(PlayblastError::Settings(format!(
                "frames {}..{}: the range is empty",
                self.first, self.last
            )));
        }
        if self.last - self.first >= i64::from(MAX_FRAMES) {
            return Err(PlayblastError::Settings(format!(
                "frames {}..{}: more than {MAX_FRAMES} frames",
                self.first, self.last
            )));
        }
        if !(self.fps.is_finite() && self.fps > 0.0) {
            return Err(PlayblastError::Settings(format!("frame rate {}: must be positive", self.fps)));
        }
        if self.size.0 == 0 || self.size.1 == 0 {
            return Err(PlayblastError::Settings(format!(
                "size {}×{}: must not be empty",
                self.size.0, self.size.1
            )));
        }
        self.motion_blur.validate()
    }

    /// Refuses an output that would replace one of `inputs` (for numbered PNGs, any of them).
    ///
    /// # Errors
    /// [`PlayblastError::Overwrite`].
    pub fn check_outputs(&self, inputs: &[(PathBuf, String)]) -> Result<(), PlayblastError> {
        match self.format {
            MovieFormat::PngFrames => {
                for frame in self.first..=self.last {
                    keyrig_io::file_io::refuse_overwriting(&numbered_output(&self.output, frame), inputs)?;
                }
            }
            _ => keyrig_io::file_io::refuse_overwriting(&self.output, inputs)?,
        }
        Ok(())
    }

    /// Renders the range and writes it (see the module documentation). `frame_input` builds
    /// the frame at a (fractional) frame number; `progress` is called after each frame and
    /// stops the render by returning [`ControlFlow::Break`].
    ///
    /// # Errors
    /// Bad settings, a frame that cannot be built or rendered, an encoding or write error, or
    /// [`PlayblastError::Cancelled`]. In every case the target keeps its previous content
    /// (numbered PNGs already written stay).
    pub fn run(
        &self,
        headless: &mut HeadlessRenderer,
        frame_input: &mut dyn FnMut(f64) -> Result<FrameInput, FrameError>,
        progress: &mut dyn FnMut(&Progress) -> ControlFlow<()>,
    ) -> Result<Summary, PlayblastError> {
        self.validate()?;
        let total = self.frame_count();
        if self.format != MovieFormat::PngFrames {
            if let Some(parent) = self.output.parent().filter(|p| !p.as_os_str().is_empty()) {
                std::fs::create_dir_all(parent)
                    .map_err(|source| PlayblastError::Write { path: parent.to_path_buf(), source })?;
            }
        }
        let mut writer = MovieWriter::create(self.format, &self.output, self.size, total, self.fps)?;
        if self.format == MovieFormat::Mp4 && self.sound.clips.iter().any(|c| !c.mute) {
            writer.set_sound(MovieSound {
                clips: self.sound.mix(self.fps)?,
                from: self.first as f64 / self.fps,
                seconds: f64::from(total) / self.fps,
            });
        }
        let offsets = self.motion_blur.offsets();
        let started = Instant::now();
        let (sender, receiver) = mpsc::sync_channel::<(i64, RgbaImage)>(2);
        std::thread::scope(|scope| {
            let encoder = scope.spawn(move || {
                let mut writer = writer;
                let mut busy = Duration::ZERO;
                for (number, image) in receiver {
                    let t = Instant::now();
                    writer.write_frame(number, &image)?;
                    busy += t.elapsed();
                }
                Ok::<_, PlayblastError>((writer, busy))
            });
            let mut render_time = Duration::ZERO;
            let mut done = 0;
            let mut outcome = Ok(());
            for number in self.first..=self.last {
                let t = Instant::now();
                let image = match render_blurred(headless, frame_input, number as f64, &offsets, self.size) {
                    Ok(image) => image,
                    Err(e) => {
                        outcome = Err(e);
                        break;
                    }
                };
                render_time += t.elapsed();
                if sender.send((number, image)).is_err() {
                    // The encoder stopped: its error is reported below.
                    break;
                }
                done += 1;
                let report = Progress { done, total, elapsed: started.elapsed() };
                if progress(&report).is_break() && done < total {
                    outcome = Err(PlayblastError::Cancelled { done, total, path: self.output.clone() });
                    break;
                }
            }
            drop(sender);
            let (writer, encode_time) = encoder.join().map_err(|_| PlayblastError::EncoderLost)??;
            outcome?;
            if done < total {
                return Err(PlayblastError::EncoderLost);
            }
            let t = Instant::now();
            writer.finish()?;
            Ok(Summary {
                frames: done,
                render_time,
                encode_time: encode_time + t.elapsed(),
                wall_time: started.elapsed(),
            })
        })
    }
}

/// Renders `frame` as the average of the sub-frames at `frame + offset` for each offset (one
/// offset of 0: a plain frame).
///
/// # Errors
/// A sub-frame cannot be built or rendered.
pub fn render_blurred(
    headless: &mut HeadlessRenderer,
    frame_input: &mut dyn FnMut(f64) -> Result<FrameInput, FrameError>,
    frame: f64,
    offsets: &[f64],
    (width, height): (u32, u32),
) -> Result<RgbaImage, PlayblastError> {
    let mut inputs = Vec::with_capacity(offsets.len());
    for offset in offsets {
        let at = frame + offset;
        inputs
            .push(frame_input(at).map_err(|e| PlayblastError::Frame { frame: at, message: e.to_string() })?);
    }
    let (image, _) = headless
        .render_image_blurred(&inputs, width, height)
        .map_err(|source| PlayblastError::Render { frame, source })?;
    Ok(image)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn outputs_name_their_format() {
        let of = |p: &str| MovieFormat::of_output(Path::new(p));
        assert_eq!(of("shot.mp4").unwrap(), MovieFormat::Mp4);
        assert_eq!(of("shot.GIF").unwrap(), MovieFormat::Gif);
        assert_eq!(of("shot.png").unwrap(), MovieFormat::Apng);
        assert_eq!(of("out/frame_####.png").unwrap(), MovieFormat::PngFrames);
        assert_eq!(of("out/").unwrap(), MovieFormat::PngFrames);
        let err = of("shot.avi").unwrap_err().to_string();
        assert!(err.contains("shot.avi") && err.contains(".mp4"), "{err}");
    }

    #[test]
    fn bad_settings_are_refused_with_the_value() {
        let blast = Playblast {
            first: 5,
            last: 4,
            fps: 30.0,
            size: (64, 64),
            format: MovieFormat::Gif,
            output: PathBuf::from("a.gif"),
            motion_blur: MotionBlur::OFF,
            sound: SceneSound::default(),
        };
        assert!(blast.validate().unwrap_err().to_string().contains("empty"));
        let blur = MotionBlur { samples: 0, shutter: 0.5 };
        assert!(blur.validate().unwrap_err().to_string().contains("samples 0"));
        let blur = MotionBlur { samples: 4, shutter: 1.5 };
        assert!(blur.validate().unwrap_err().to_string().contains("shutter 1.5"));
    }

    #[test]
    fn time_left_follows_the_rate_so_far() {
        let p = Progress { done: 10, total: 40, elapsed: Duration::from_secs(5) };
        assert_eq!(p.remaining(), Some(Duration::from_secs(15)));
        assert_eq!(Progress { done: 0, total: 4, elapsed: Duration::ZERO }.remaining(), None);
    }
}
