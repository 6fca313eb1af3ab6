//! Sound files of a scene's clips: WAV, FLAC, Ogg Vorbis and MP3 decoded with Symphonia into
//! a [`WaveformSummary`] (keyrig-core's min/max summary the editor draws under the timeline).
//!
//! The file is opened like every input ([`crate::file_io::open_regular_file`]: a regular file
//! of at most [`MAX_SOUND_BYTES`]) and decoded packet by packet into the summary, so memory is
//! the summary's (about 1.5 kB a second at 48 kHz), not the decoded sound's. Each packet is
//! summarised from the decoder's own planes in their own sample type (the smallest and largest
//! `i16` of a bucket's run, say, converted to `f32` once), never copied or converted sample by
//! sample: for WAV that is most of the work (`benches/sound.rs`). A packet that does
//! not decode is skipped and counted (as players do), so a damaged stretch does not lose the
//! rest of the track; a file in which no packet decodes is an error.

use std::path::{Path, PathBuf};

use keyrig_core::{SummaryBuilder, WaveformSummary};
use symphonia::core::audio::{AudioBuffer, AudioBufferRef, SampleBuffer, Signal};
use symphonia::core::codecs::{DecoderOptions, CODEC_TYPE_NULL};
use symphonia::core::conv::FromSample;
use symphonia::core::errors::Error as SymphoniaError;
use symphonia::core::formats::FormatOptions;
use symphonia::core::io::MediaSourceStream;
use symphonia::core::meta::MetadataOptions;
use symphonia::core::probe::Hint;
use symphonia::core::sample::{i24, u24, Sample};

/// Largest sound file keyrig reads: 2 GiB (a WAV of about 3 hours at 48 kHz stereo 16-bit).
pub const MAX_SOUND_BYTES: u64 = 2 << 30;

/// Why a sound file could not be read.
#[derive(Debug, thiserror::Error)]
pub enum SoundError {
    #[error("{}: cannot read: {source}", path.display())]
    Read { path: PathBuf, source: std::io::Error },
    #[error("{}: not a sound keyrig reads (WAV, FLAC, Ogg Vorbis, MP3): {message}", path.display())]
    Format { path: PathBuf, message: String },
    #[error("{}: {message} (the packet at sample {timestamp})", path.display())]
    Decode { path: PathBuf, timestamp: u64, message: String },
}

/// A decoded sound file.
#[derive(Clone, Debug)]
pub struct DecodedSound {
    /// The codec, e.g. "flac".
    pub codec: String,
    pub summary: WaveformSummary,
    /// Packets that did not decode and were skipped.
    pub skipped_packets: u64,
    /// The samples, for playing the sound: asked of [`decode_sound_file_for_playback`], and
    /// `None` for a sound longer than it allows.
    pub pcm: Option<SoundPcm>,
}

/// A sound's samples as a player takes them: 16-bit, interleaved.
#[derive(Clone, Debug, PartialEq)]
pub struct SoundPcm {
    pub sample_rate: u32,
    pub channels: u16,
    /// `channels` samples a frame.
    pub samples: Vec<i16>,
}

impl SoundPcm {
    /// Frames (samples per channel).
    #[must_use]
    pub fn frames(&self) -> usize {
        self.samples.len() / usize::from(self.channels.max(1))
    }
}

/// The most frames [`decode_sound_file_for_playback`] keeps by default: 20 minutes at
/// 48 kHz (230 MB of 16-bit stereo).
pub const MAX_PLAYBACK_FRAMES: u64 = 20 * 60 * 48_000;

/// Decodes `path` into its waveform summary.
///
/// # Errors
/// The file cannot be opened or is not a regular file within [`MAX_SOUND_BYTES`], its format
/// is not recognised, it has no audio track, or no packet of it decodes.
pub fn decode_sound_file(path: &Path) -> Result<DecodedSound, SoundError> {
    let read_error = |source| SoundError::Read { path: path.to_path_buf(), source };
    let (file, _) = crate::file_io::open_regular_file(path, MAX_SOUND_BYTES).map_err(read_error)?;
    decode_sound(Box::new(file), path, None)
}

/// Decodes `path` into its waveform summary and, when it has at most `max_frames` frames, its
/// samples ([`DecodedSound::pcm`]) for playing it: one pass over the file.
///
/// # Errors
/// As [`decode_sound_file`].
pub fn decode_sound_file_for_playback(path: &Path, max_frames: u64) -> Result<DecodedSound, SoundError> {
    let read_error = |source| SoundError::Read { path: path.to_path_buf(), source };
    let (file, _) = crate::file_io::open_regular_file(path, MAX_SOUND_BYTES).map_err(read_error)?;
    decode_sound(Box::new(file), path, Some(max_frames))
}

/// Decodes a sound file's `bytes` (its format found from its content; `name`, whose extension
/// is a hint, names it in errors).
///
/// # Errors
/// As [`decode_sound_file`], but for reading.
pub fn decode_sound_bytes(bytes: Vec<u8>, name: &Path) -> Result<DecodedSound, SoundError> {
    decode_sound(Box::new(std::io::Cursor::new(bytes)), name, Some(MAX_PLAYBACK_FRAMES))
}

/// Refuses a file holding a RIFF/WAVE header within its first 4 KiB (Symphonia's probe finds
/// one anywhere near the start) whose `fmt ` chunk gives a sample rate of 0, which Symphonia
/// 0.5's WAV reader asserts against instead of returning an error; leaves the source at its
/// start. Further in, the panic is caught ([`decode_sound`]).
fn check_wav_rate(source: &mut Box<dyn symphonia::core::io::MediaSource>) -> Result<(), String> {
    use std::io::{Read, Seek, SeekFrom};
    let mut head = Vec::with_capacity(4096);
    let read = source.by_ref().take(4096).read_to_end(&mut head);
    source.seek(SeekFrom::Start(0)).map_err(|e| format!("cannot read it again: {e}"))?;
    read.map_err(|e| e.to_string())?;
    let u32_at = |at: usize| head.get(at..at + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    for riff in (0..head.len().saturating_sub(11)).filter(|&i| &head[i..i + 4] == b"RIFF") {
        if &head[riff + 8..riff + 12] != b"WAVE" {
            continue;
        }
        let mut at = riff + 12;
        while let (Some(id), Some(size)) = (head.get(at..at + 4), u32_at(at + 4)) {
            if id == b"fmt " {
                if u32_at(at + 12) == Some(0) {
                    return Err(format!("the fmt chunk gives a sample rate of 0 (byte {})", at + 12));
                }
                break;
            }
            // Chunks are padded to an even length.
            at = at.saturating_add(8).saturating_add(size as usize).saturating_add(size as usize & 1);
        }
    }
    Ok(())
}

/// Decodes into the summary and, with `keep_frames`, the samples of a sound of at most that
/// many frames. Symphonia asserts on some malformed headers instead of returning an error (a
/// WAV whose sample rate is 0 panics in `TimeBase::new`, found by the `sound` fuzz target): a
/// panic inside it is caught and reported as the file's format error, so a damaged sound file
/// never takes the editor down.
fn decode_sound(
    source: Box<dyn symphonia::core::io::MediaSource>,
    path: &Path,
    keep_frames: Option<u64>,
) -> Result<DecodedSound, SoundError> {
    // Nothing outlives the call but its result: no state is left half-updated by a panic.
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(|| {
        decode_sound_unguarded(source, path, keep_frames)
    }))
    .unwrap_or_else(|panic| {
        let what = panic
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "the decoder stopped".to_owned());
        Err(SoundError::Format { path: path.to_path_buf(), message: format!("malformed: {what}") })
    })
}

fn decode_sound_unguarded(
    mut source: Box<dyn symphonia::core::io::MediaSource>,
    path: &Path,
    keep_frames: Option<u64>,
) -> Result<DecodedSound, SoundError> {
    let format_error =
        |e: SymphoniaError| SoundError::Format { path: path.to_path_buf(), message: e.to_string() };
    check_wav_rate(&mut source)
        .map_err(|message| SoundError::Format { path: path.to_path_buf(), message })?;
    let stream = MediaSourceStream::new(source, Default::default());
    let mut hint = Hint::new();
    if let Some(extension) = path.extension().and_then(|e| e.to_str()) {
        hint.with_extension(extension);
    }
    let probed = symphonia::default::get_probe()
        .format(&hint, stream, &FormatOptions::default(), &MetadataOptions::default())
        .map_err(format_error)?;
    let mut format = probed.format;
    let track =
        format.tracks().iter().find(|t| t.codec_params.codec != CODEC_TYPE_NULL).ok_or_else(|| {
            SoundError::Format { path: path.to_path_buf(), message: "no audio track".into() }
        })?;
    let track_id = track.id;
    let codec = symphonia::default::get_codecs()
        .get_codec(track.codec_params.codec)
        .map_or_else(|| format!("{:?}", track.codec_params.codec), |d| d.short_name.to_owned());
    let mut decoder = symphonia::default::get_codecs()
        .make(&track.codec_params, &DecoderOptions::default())
        .map_err(format_error)?;
    let declared = (track.codec_params.sample_rate, track.codec_params.channels.map(|c| c.count()));

    let mut builder = None;
    // The samples while they are kept, and the buffer that converts a packet's to 16 bits.
    let mut pcm: Option<SoundPcm> = None;
    let mut keeping = keep_frames.is_some();
    let mut packet_samples: Option<SampleBuffer<i16>> = None;
    let (mut skipped, mut decoded, mut last_error) = (0u64, 0u64, None);
    loop {
        let packet = match format.next_packet() {
            Ok(packet) => packet,
            // The end of the stream.
            Err(SymphoniaError::IoError(e)) if e.kind() == std::io::ErrorKind::UnexpectedEof => break,
            Err(SymphoniaError::ResetRequired) => break,
            Err(e) => {
                return Err(SoundError::Decode {
                    path: path.to_path_buf(),
                    timestamp: 0,
                    message: e.to_string(),
                })
            }
        };
        if packet.track_id() != track_id {
            continue;
        }
        match decoder.decode(&packet) {
            Ok(audio) => {
                let spec = *audio.spec();
                let channels = u16::try_from(spec.channels.count()).unwrap_or(u16::MAX);
                let builder = builder.get_or_insert_with(|| {
                    SummaryBuilder::new(
                        declared.0.unwrap_or(spec.rate),
                        declared.1.map_or(channels, |c| c as u16),
                    )
                });
                summarise(builder, &audio);
                decoded += 1;
                if keeping {
                    let pcm = pcm.get_or_insert_with(|| SoundPcm {
                        sample_rate: spec.rate,
                        channels,
                        samples: Vec::new(),
                    });
                    let capacity = audio.capacity() as u64;
                    let buffer = match &mut packet_samples {
                        Some(b) if b.capacity() as u64 >= capacity * u64::from(channels) => b,
                        _ => packet_samples.insert(SampleBuffer::new(capacity, spec)),
                    };
                    buffer.copy_interleaved_ref(audio);
                    let room = keep_frames.unwrap_or(0).saturating_mul(u64::from(channels));
                    if pcm.channels != channels
                        || pcm.sample_rate != spec.rate
                        || (pcm.samples.len() + buffer.samples().len()) as u64 > room
                    {
                        // Longer than allowed, or the stream changed its layout: not kept.
                        keeping = false;
                    } else {
                        pcm.samples.extend_from_slice(buffer.samples());
                    }
                }
                if !keeping {
                    pcm = None;
                }
            }
            Err(SymphoniaError::DecodeError(message)) => {
                skipped += 1;
                last_error = Some((packet.ts(), message.to_owned()));
            }
            Err(e) => {
                return Err(SoundError::Decode {
                    path: path.to_path_buf(),
                    timestamp: packet.ts(),
                    message: e.to_string(),
                })
            }
        }
    }
    match builder {
        Some(builder) if decoded > 0 => {
            Ok(DecodedSound { codec, summary: builder.finish(), skipped_packets: skipped, pcm })
        }
        _ => Err(SoundError::Decode {
            path: path.to_path_buf(),
            timestamp: last_error.as_ref().map_or(0, |(ts, _)| *ts),
            message: match last_error {
                Some((_, message)) => format!("no packet decodes ({skipped} skipped; the last: {message})"),
                None => "the file holds no sound".into(),
            },
        }),
    }
}

/// Adds a decoded packet to the summary from its planes, in their own sample type.
fn summarise(builder: &mut SummaryBuilder, audio: &AudioBufferRef<'_>) {
    match audio {
        AudioBufferRef::U8(b) => summarise_planes(builder, b, ordered_extremes),
        AudioBufferRef::U16(b) => summarise_planes(builder, b, ordered_extremes),
        AudioBufferRef::U24(b) => summarise_planes(builder, b, ordered_extremes::<u24>),
        AudioBufferRef::U32(b) => summarise_planes(builder, b, ordered_extremes),
        AudioBufferRef::S8(b) => summarise_planes(builder, b, ordered_extremes),
        AudioBufferRef::S16(b) => summarise_planes(builder, b, ordered_extremes),
        AudioBufferRef::S24(b) => summarise_planes(builder, b, ordered_extremes::<i24>),
        AudioBufferRef::S32(b) => summarise_planes(builder, b, ordered_extremes),
        AudioBufferRef::F32(b) => summarise_planes(builder, b, float_extremes),
        AudioBufferRef::F64(b) => summarise_planes(builder, b, float_extremes),
    }
}

/// Runs of `buffer`'s frames that end where the summary's buckets end, each added as the
/// extremes `extremes` finds over every plane.
fn summarise_planes<S: Sample>(
    builder: &mut SummaryBuilder,
    buffer: &AudioBuffer<S>,
    extremes: impl Fn(&[S]) -> [f32; 2],
) {
    let planes = buffer.planes();
    let planes = planes.planes();
    let frames = buffer.frames();
    let mut at = 0;
    while at < frames {
        let n = usize::try_from(builder.bucket_room()).unwrap_or(usize::MAX).min(frames - at);
        let mut bounds = [f32::INFINITY, f32::NEG_INFINITY];
        for plane in planes.iter() {
            let [lo, hi] = extremes(plane.get(at..at + n).unwrap_or_default());
            bounds = [bounds[0].min(lo), bounds[1].max(hi)];
        }
        builder.push_extremes(n as u64, bounds);
        at += n;
    }
}

/// The smallest and largest of integer samples, found as integers (their order is their
/// value's) and converted to `f32` once each.
fn ordered_extremes<S: Sample + Ord>(samples: &[S]) -> [f32; 2]
where
    f32: FromSample<S>,
{
    match (samples.iter().min(), samples.iter().max()) {
        (Some(&lo), Some(&hi)) => [f32::from_sample(lo), f32::from_sample(hi)],
        _ => [f32::INFINITY, f32::NEG_INFINITY],
    }
}

/// The smallest and largest of floating-point samples, non-finite ones counting as silence.
fn float_extremes<S: Sample>(samples: &[S]) -> [f32; 2]
where
    f32: FromSample<S>,
{
    samples.iter().fold([f32::INFINITY, f32::NEG_INFINITY], |[lo, hi], &s| {
        let s = f32::from_sample(s);
        let s = if s.is_finite() { s } else { 0.0 };
        [lo.min(s), hi.max(s)]
    })
}
