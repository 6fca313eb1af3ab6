//! Sound files of a scene's clips: WAV, FLAC, Ogg Vorbis and MP3 decoded with Symphonia into
//! a [`WaveformSummary`] (keyrig-core's min/max summary the editor draws under the timeline).
//!
//! The file is opened like every input ([`crate::file_io::open_regular_file`]: a regular file
//! of at most [`MAX_SOUND_BYTES`]) and decoded packet by packet into the summary, so memory is
//! the summary's (about 1.5 kB a second at 48 kHz), not the decoded sound's. A packet that does
//! not decode is skipped and counted (as players do), so a damaged stretch does not lose the
//! rest of the track; a file in which no packet decodes is an error.

use std::path::{Path, PathBuf};

use keyrig_core::{SummaryBuilder, WaveformSummary};
use symphonia::core::audio::SampleBuffer;
use symphonia::core::codecs::{DecoderOptions, CODEC_TYPE_NULL};
use symphonia::core::errors::Error as SymphoniaError;
use symphonia::core::formats::FormatOptions;
use symphonia::core::io::MediaSourceStream;
use symphonia::core::meta::MetadataOptions;
use symphonia::core::probe::Hint;

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
}

/// Decodes `path` into its waveform summary.
///
/// # Errors
/// The file cannot be opened or is not a regular file within [`MAX_SOUND_BYTES`], its format
/// is not recognised, it has no audio track, or no packet of it decodes.
pub fn decode_sound_file(path: &Path) -> Result<DecodedSound, SoundError> {
    let read_error = |source| SoundError::Read { path: path.to_path_buf(), source };
    let format_error =
        |e: SymphoniaError| SoundError::Format { path: path.to_path_buf(), message: e.to_string() };
    let (file, _) = crate::file_io::open_regular_file(path, MAX_SOUND_BYTES).map_err(read_error)?;
    let stream = MediaSourceStream::new(Box::new(file), Default::default());
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
    let mut buffer: Option<SampleBuffer<f32>> = None;
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
                let capacity = audio.capacity() as u64;
                let buf = match &mut buffer {
                    Some(b) if b.capacity() as u64 >= capacity * spec.channels.count() as u64 => b,
                    _ => buffer.insert(SampleBuffer::new(capacity, spec)),
                };
                buf.copy_interleaved_ref(audio);
                builder.push_interleaved(buf.samples());
                decoded += 1;
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
            Ok(DecodedSound { codec, summary: builder.finish(), skipped_packets: skipped })
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
