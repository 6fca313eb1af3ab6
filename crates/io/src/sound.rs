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
//!
//! A long sound (two [`MIN_PART_FRAMES`] or more) is decoded in parts, one per core, each
//! from a seek to just before its start, and the parts joined where the summary's buckets
//! meet: the result is the one-pass decode's, sample for sample, checked at every cut
//! ([`decode_sound_file_on_threads`]); decoding is most of the time for FLAC, MP3 and Vorbis.

use std::ops::Range;
use std::path::{Path, PathBuf};

use keyrig_core::sound::SUMMARY_BUCKET;
use keyrig_core::{SummaryBuilder, WaveformSummary};
use symphonia::core::audio::{AudioBuffer, AudioBufferRef, SampleBuffer, Signal, SignalSpec};
use symphonia::core::codecs::{Decoder, DecoderOptions, CODEC_TYPE_NULL};
use symphonia::core::conv::FromSample;
use symphonia::core::errors::Error as SymphoniaError;
use symphonia::core::formats::{FormatOptions, FormatReader, SeekMode, SeekTo};
use symphonia::core::io::{MediaSource, MediaSourceStream};
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
    /// The parts the sound was decoded in, each on a thread of its own
    /// ([`decode_sound_file_on_threads`]); 1 for one pass.
    pub parts: u32,
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

/// Decodes `path` into its waveform summary: a long sound in parts on the machine's cores
/// ([`decode_sound_file_on_threads`]).
///
/// # Errors
/// The file cannot be opened or is not a regular file within [`MAX_SOUND_BYTES`], its format
/// is not recognised, it has no audio track, or no packet of it decodes.
pub fn decode_sound_file(path: &Path) -> Result<DecodedSound, SoundError> {
    decode_sound_file_on_threads(path, None, default_threads())
}

/// Decodes `path` into its waveform summary and, when it has at most `max_frames` frames, its
/// samples ([`DecodedSound::pcm`]) for playing it: one pass over the file (a long sound's
/// parts each on a core, [`decode_sound_file_on_threads`]).
///
/// # Errors
/// As [`decode_sound_file`].
pub fn decode_sound_file_for_playback(path: &Path, max_frames: u64) -> Result<DecodedSound, SoundError> {
    decode_sound_file_on_threads(path, Some(max_frames), default_threads())
}

/// The threads a sound file is decoded on by default: the machine's cores, at most
/// [`MAX_PARTS`].
fn default_threads() -> usize {
    std::thread::available_parallelism().map_or(1, std::num::NonZeroUsize::get).min(MAX_PARTS)
}

/// The most parts a sound is decoded in at once.
pub const MAX_PARTS: usize = 8;

/// The fewest frames of a part decoded on a thread of its own (about 11 s at 48 kHz): a
/// shorter sound is decoded in one pass, which is quick, without opening it again per part.
pub const MIN_PART_FRAMES: u64 = 1 << 19;

/// Frames decoded before a part's first frame, from which the decoder's state (MP3's bit
/// reservoir, overlap and synthesis filter; Vorbis's overlap) becomes the one-pass decode's.
const PREROLL_FRAMES: u64 = 16_384;

/// Packets a part decodes and throws away before its first frame's packet: after a seek, MP3's
/// first two packets differ from the one-pass decode's and Vorbis's first gives no frames.
const WARMUP_PACKETS: usize = 2;

/// Decodes `path` like [`decode_sound_file_for_playback`] (its samples kept when `keep_frames`
/// is given and the sound has at most that many frames), on up to `threads` threads: a sound
/// of at least two [`MIN_PART_FRAMES`] is cut at bucket boundaries of the summary into parts
/// of equal length, each decoded on a thread of its own from a seek to a little before its
/// start (the decoder warmed up over [`WARMUP_PACKETS`] packets), and the parts' summaries
/// and samples joined. The result is the one-pass decode's, sample for sample: each part's
/// packets must follow one another without a gap, and the packet at each cut must decode to
/// the same samples in the parts on both sides of it; a sound for which anything of that does
/// not hold (a damaged packet, a stream whose layout changes, a format that does not seek) is
/// decoded again in one pass.
///
/// # Errors
/// As [`decode_sound_file`].
pub fn decode_sound_file_on_threads(
    path: &Path,
    keep_frames: Option<u64>,
    threads: usize,
) -> Result<DecodedSound, SoundError> {
    let open = || {
        crate::file_io::open_regular_file(path, MAX_SOUND_BYTES)
            .map(|(file, _)| Box::new(file) as Box<dyn MediaSource>)
            .map_err(|source| SoundError::Read { path: path.to_path_buf(), source })
    };
    let source = open()?;
    guarded(path, || {
        let mut opened = open_stream(source, path)?;
        let Some(cuts) = plan_parts(&opened, threads) else {
            return decode_pass(opened, path, keep_frames);
        };
        if let Some(decoded) = decode_parts(&mut opened, path, &cuts, keep_frames) {
            return Ok(decoded);
        }
        decode_pass(open_stream(open()?, path)?, path, keep_frames)
    })
}

/// Decodes a sound file's `bytes` (its format found from its content; `name`, whose extension
/// is a hint, names it in errors).
///
/// # Errors
/// As [`decode_sound_file`], but for reading.
pub fn decode_sound_bytes(bytes: Vec<u8>, name: &Path) -> Result<DecodedSound, SoundError> {
    guarded(name, || {
        decode_pass(
            open_stream(Box::new(std::io::Cursor::new(bytes)), name)?,
            name,
            Some(MAX_PLAYBACK_FRAMES),
        )
    })
}

/// Refuses a file holding a RIFF/WAVE header within its first 4 KiB (Symphonia's probe finds
/// one anywhere near the start) whose `fmt ` chunk gives a sample rate of 0, which Symphonia
/// 0.5's WAV reader asserts against instead of returning an error; leaves the source at its
/// start. Further in, the panic is caught ([`decode_sound`]).
fn check_wav_rate(source: &mut Box<dyn MediaSource>, path: &Path) -> Result<(), SoundError> {
    use std::io::{Read, Seek, SeekFrom};
    let format = |message: String| SoundError::Format { path: path.to_path_buf(), message };
    let mut head = Vec::with_capacity(4096);
    let read = source.by_ref().take(4096).read_to_end(&mut head);
    source.seek(SeekFrom::Start(0)).map_err(|e| format(format!("cannot read it again: {e}")))?;
    read.map_err(|e| format(e.to_string()))?;
    let u32_at = |at: usize| head.get(at..at + 4).map(|b| u32::from_le_bytes([b[0], b[1], b[2], b[3]]));
    for riff in (0..head.len().saturating_sub(11)).filter(|&i| &head[i..i + 4] == b"RIFF") {
        if &head[riff + 8..riff + 12] != b"WAVE" {
            continue;
        }
        let mut at = riff + 12;
        while let (Some(id), Some(size)) = (head.get(at..at + 4), u32_at(at + 4)) {
            if id == b"fmt " {
                if u32_at(at + 12) == Some(0) {
                    return Err(format(format!("the fmt chunk gives a sample rate of 0 (byte {})", at + 12)));
                }
                break;
            }
            // Chunks are padded to an even length.
            at = at.saturating_add(8).saturating_add(size as usize).saturating_add(size as usize & 1);
        }
    }
    Ok(())
}

/// Runs `decode`, a panic inside it reported as the file's format error. Symphonia asserts on
/// some malformed headers instead of returning an error (a WAV whose sample rate is 0 panics
/// in `TimeBase::new`, found by the `sound` fuzz target): so a damaged sound file never takes
/// the editor down.
fn guarded(
    path: &Path,
    decode: impl FnOnce() -> Result<DecodedSound, SoundError>,
) -> Result<DecodedSound, SoundError> {
    // Nothing outlives the call but its result: no state is left half-updated by a panic.
    std::panic::catch_unwind(std::panic::AssertUnwindSafe(decode)).unwrap_or_else(|panic| {
        let what = panic
            .downcast_ref::<&str>()
            .map(|s| (*s).to_owned())
            .or_else(|| panic.downcast_ref::<String>().cloned())
            .unwrap_or_else(|| "the decoder stopped".to_owned());
        Err(SoundError::Format { path: path.to_path_buf(), message: format!("malformed: {what}") })
    })
}

/// A sound file's stream, probed, with the decoder of its audio track.
struct OpenStream {
    format: Box<dyn FormatReader>,
    decoder: Box<dyn Decoder>,
    track_id: u32,
    /// The codec's short name, e.g. "flac".
    codec: String,
    /// The sample rate and channels the track declares.
    declared: (Option<u32>, Option<u16>),
    /// The frames the track declares.
    frames: Option<u64>,
}

/// A builder for the summary of packets of `spec`: the track's `declared` rate and channels
/// where it gives them.
fn new_builder(declared: (Option<u32>, Option<u16>), spec: SignalSpec) -> SummaryBuilder {
    SummaryBuilder::new(declared.0.unwrap_or(spec.rate), declared.1.unwrap_or_else(|| channels_of(spec)))
}

fn channels_of(spec: SignalSpec) -> u16 {
    u16::try_from(spec.channels.count()).unwrap_or(u16::MAX)
}

fn open_stream(mut source: Box<dyn MediaSource>, path: &Path) -> Result<OpenStream, SoundError> {
    let format_error =
        |e: SymphoniaError| SoundError::Format { path: path.to_path_buf(), message: e.to_string() };
    check_wav_rate(&mut source, path)?;
    let stream = MediaSourceStream::new(source, Default::default());
    let mut hint = Hint::new();
    if let Some(extension) = path.extension().and_then(|e| e.to_str()) {
        hint.with_extension(extension);
    }
    let probed = symphonia::default::get_probe()
        .format(&hint, stream, &FormatOptions::default(), &MetadataOptions::default())
        .map_err(format_error)?;
    let format = probed.format;
    let track =
        format.tracks().iter().find(|t| t.codec_params.codec != CODEC_TYPE_NULL).ok_or_else(|| {
            SoundError::Format { path: path.to_path_buf(), message: "no audio track".into() }
        })?;
    let track_id = track.id;
    let codec = symphonia::default::get_codecs()
        .get_codec(track.codec_params.codec)
        .map_or_else(|| format!("{:?}", track.codec_params.codec), |d| d.short_name.to_owned());
    let decoder = symphonia::default::get_codecs()
        .make(&track.codec_params, &DecoderOptions::default())
        .map_err(format_error)?;
    let declared = (
        track.codec_params.sample_rate,
        track.codec_params.channels.map(|c| u16::try_from(c.count()).unwrap_or(u16::MAX)),
    );
    let frames = track.codec_params.n_frames;
    Ok(OpenStream { format, decoder, track_id, codec, declared, frames })
}

/// Decodes the whole stream in one pass into the summary and, with `keep_frames`, the samples
/// of a sound of at most that many frames.
fn decode_pass(
    mut stream: OpenStream,
    path: &Path,
    keep_frames: Option<u64>,
) -> Result<DecodedSound, SoundError> {
    let mut builder = None;
    // The samples while they are kept, and the buffer that converts a packet's to 16 bits.
    let mut pcm: Option<SoundPcm> = None;
    let mut keeping = keep_frames.is_some();
    let mut packet_samples: Option<SampleBuffer<i16>> = None;
    let (mut skipped, mut decoded, mut last_error) = (0u64, 0u64, None);
    loop {
        let packet = match stream.format.next_packet() {
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
        if packet.track_id() != stream.track_id {
            continue;
        }
        match stream.decoder.decode(&packet) {
            Ok(audio) => {
                let spec = *audio.spec();
                let channels = channels_of(spec);
                if builder.is_none() {
                    builder = Some(new_builder(stream.declared, spec));
                }
                if let Some(builder) = builder.as_mut() {
                    summarise(builder, &audio, 0..audio.frames());
                }
                decoded += 1;
                if keeping {
                    let pcm = pcm.get_or_insert_with(|| SoundPcm {
                        sample_rate: spec.rate,
                        channels,
                        samples: Vec::new(),
                    });
                    let buffer = interleaved_i16(&mut packet_samples, audio);
                    let room = keep_frames.unwrap_or(0).saturating_mul(u64::from(channels));
                    if pcm.channels != channels
                        || pcm.sample_rate != spec.rate
                        || (pcm.samples.len() + buffer.len()) as u64 > room
                    {
                        // Longer than allowed, or the stream changed its layout: not kept.
                        keeping = false;
                    } else {
                        pcm.samples.extend_from_slice(buffer);
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
        Some(builder) if decoded > 0 => Ok(DecodedSound {
            codec: stream.codec,
            summary: builder.finish(),
            skipped_packets: skipped,
            pcm,
            parts: 1,
        }),
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

/// A packet's samples, interleaved and converted to 16 bits in `buffer` (made or grown to fit).
fn interleaved_i16<'b>(buffer: &'b mut Option<SampleBuffer<i16>>, audio: AudioBufferRef<'_>) -> &'b [i16] {
    let spec = *audio.spec();
    let capacity = audio.capacity() as u64;
    if buffer.as_ref().is_some_and(|b| (b.capacity() as u64) < capacity * spec.channels.count() as u64) {
        *buffer = None;
    }
    let buffer = buffer.get_or_insert_with(|| SampleBuffer::new(capacity, spec));
    buffer.copy_interleaved_ref(audio);
    buffer.samples()
}

/// Where a sound is cut into parts decoded on threads of their own: the first frame of each
/// part after the first, on the summary's bucket boundaries; `None` for a sound decoded in one
/// pass (one thread, a length the track does not declare, or too short for two parts).
fn plan_parts(stream: &OpenStream, threads: usize) -> Option<Vec<u64>> {
    let frames = stream.frames?;
    let parts = (frames / MIN_PART_FRAMES).min(threads.min(MAX_PARTS) as u64);
    (parts >= 2).then(|| (1..parts).map(|k| frames * k / parts / SUMMARY_BUCKET * SUMMARY_BUCKET).collect())
}

/// One part of a sound, decoded.
struct Part {
    builder: SummaryBuilder,
    spec: SignalSpec,
    /// The part's samples, interleaved 16-bit, when they are kept.
    samples: Option<Vec<i16>>,
    /// The packet holding the part's first frame (`None` for the first part), and the packet
    /// holding the frame after its last (`None` for the last part): the same packet, decoded
    /// by the parts on both sides of a cut, must be the same.
    head: Option<PacketPrint>,
    tail: Option<PacketPrint>,
}

/// A decoded packet's timestamp, frames and a hash of its samples.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
struct PacketPrint {
    ts: u64,
    frames: usize,
    hash: u64,
}

impl PacketPrint {
    fn of(ts: u64, audio: &AudioBufferRef<'_>) -> Self {
        use std::hash::{Hash, Hasher};
        let mut buffer = SampleBuffer::<f32>::new(audio.capacity() as u64, *audio.spec());
        buffer.copy_planar_ref(audio.clone());
        let mut hasher = std::collections::hash_map::DefaultHasher::new();
        for sample in buffer.samples() {
            sample.to_bits().hash(&mut hasher);
        }
        PacketPrint { ts, frames: audio.frames(), hash: hasher.finish() }
    }
}

/// Decodes the parts of `stream` cut at `cuts` (the first part from `stream`, which must be at
/// its start, each other part on a thread of its own from the file opened again) and joins
/// them; `None` where the parts do not join into the one-pass decode
/// ([`decode_sound_file_on_threads`]).
fn decode_parts(
    stream: &mut OpenStream,
    path: &Path,
    cuts: &[u64],
    keep_frames: Option<u64>,
) -> Option<DecodedSound> {
    // The samples are kept when the sound may be short enough; whether it is, its length says.
    let keep =
        keep_frames.is_some_and(|k| stream.frames.is_some_and(|f| f <= k.saturating_add(MIN_PART_FRAMES)));
    let bounds: Vec<(u64, Option<u64>)> = std::iter::once(0)
        .chain(cuts.iter().copied())
        .zip(cuts.iter().copied().map(Some).chain(std::iter::once(None)))
        .collect();
    let parts: Vec<Option<Part>> = std::thread::scope(|scope| {
        let others: Vec<_> = bounds[1..]
            .iter()
            .map(|&(from, to)| {
                scope.spawn(move || {
                    let (file, _) = crate::file_io::open_regular_file(path, MAX_SOUND_BYTES).ok()?;
                    let mut stream = open_stream(Box::new(file), path).ok()?;
                    decode_part(&mut stream, from, to, keep)
                })
            })
            .collect();
        let first = decode_part(stream, bounds[0].0, bounds[0].1, keep);
        std::iter::once(first).chain(others.into_iter().map(|h| h.join().ok().flatten())).collect()
    });
    let mut parts = parts.into_iter().collect::<Option<Vec<Part>>>()?.into_iter();
    let mut joined = parts.next()?;
    for part in parts {
        if joined.tail.is_none() || joined.tail != part.head || part.spec != joined.spec {
            return None;
        }
        if !joined.builder.append(part.builder) {
            return None;
        }
        joined.samples = match (joined.samples, part.samples) {
            (Some(mut a), Some(b)) => {
                a.extend_from_slice(&b);
                Some(a)
            }
            _ => None,
        };
        joined.tail = part.tail;
    }
    let summary = joined.builder.finish();
    let pcm = match keep_frames {
        None => None,
        // Longer than kept: as the one pass.
        Some(k) if summary.frames > k => None,
        // Short enough to keep: kept (where the parts did not keep them, the track declared
        // more frames than it holds, and the one pass keeps them).
        Some(_) => Some(SoundPcm {
            sample_rate: joined.spec.rate,
            channels: channels_of(joined.spec),
            samples: joined.samples?,
        }),
    };
    Some(DecodedSound {
        codec: stream.codec.clone(),
        summary,
        skipped_packets: 0,
        pcm,
        parts: u32::try_from(cuts.len() + 1).unwrap_or(u32::MAX),
    })
}

/// Decodes frames `from..to` (`to`: the end of the stream when `None`) of `stream`, which is
/// at its start: seeking to a little before `from` when it is not 0. `None` where a packet
/// does not decode, the stream changes its layout, a packet's timestamp does not follow from
/// the one before, or too few packets come before `from` to warm the decoder up.
fn decode_part(stream: &mut OpenStream, from: u64, to: Option<u64>, keep: bool) -> Option<Part> {
    let (track_id, declared) = (stream.track_id, stream.declared);
    if from > 0 {
        let ts = from.saturating_sub(PREROLL_FRAMES);
        stream.format.seek(SeekMode::Accurate, SeekTo::TimeStamp { ts, track_id }).ok()?;
        stream.decoder.reset();
    }
    let stop = to.unwrap_or(u64::MAX);
    // The next frame the part needs, the timestamp the next packet must have (not known for
    // the first packet after a seek), and the packets decoded.
    let mut next = from;
    let mut expected_ts = (from == 0).then_some(0);
    let mut packets = 0;
    let mut part: Option<Part> = None;
    let mut packet_samples: Option<SampleBuffer<i16>> = None;
    loop {
        let packet = match stream.format.next_packet() {
            Ok(packet) => packet,
            Err(SymphoniaError::IoError(e)) if e.kind() == std::io::ErrorKind::UnexpectedEof => break,
            Err(_) => return None,
        };
        if packet.track_id() != track_id {
            continue;
        }
        let audio = match stream.decoder.decode(&packet) {
            Ok(audio) => audio,
            // After a seek, before the part's first frame: warm up again from the next packet.
            Err(SymphoniaError::DecodeError(_)) if from > 0 && part.is_none() => {
                (packets, expected_ts) = (0, None);
                continue;
            }
            Err(_) => return None,
        };
        let (ts, frames) = (packet.ts(), audio.frames());
        let end = ts.checked_add(frames as u64)?;
        if expected_ts.is_some_and(|e| e != ts) {
            return None;
        }
        packets += 1;
        // After a seek, the first packet's length is its own; the next ones follow it.
        expected_ts = (from == 0 || packets > 1).then_some(end);
        if let Some(part) = part.as_mut().filter(|_| next >= stop) {
            // The packet holding the frame after the part's last.
            if end > stop {
                part.tail = Some(PacketPrint::of(ts, &audio));
                break;
            }
            continue;
        }
        if end <= next {
            continue;
        }
        if ts > next || (from > 0 && part.is_none() && packets <= WARMUP_PACKETS) {
            // A gap, or the decoder not warmed up yet.
            return None;
        }
        let spec = *audio.spec();
        if part.is_none() {
            part = Some(Part {
                builder: new_builder(declared, spec),
                spec,
                samples: keep.then(Vec::new),
                head: (from > 0).then(|| PacketPrint::of(ts, &audio)),
                tail: None,
            });
        }
        let part = part.as_mut()?;
        if part.spec != spec {
            return None;
        }
        let first = usize::try_from(next - ts).ok()?;
        let last = usize::try_from(end.min(stop) - ts).ok()?;
        summarise(&mut part.builder, &audio, first..last);
        if let Some(samples) = part.samples.as_mut() {
            let channels = spec.channels.count();
            let packet = interleaved_i16(&mut packet_samples, audio.clone());
            samples.extend_from_slice(packet.get(first * channels..last * channels)?);
        }
        next = ts + last as u64;
        if next >= stop && end > stop {
            part.tail = Some(PacketPrint::of(ts, &audio));
            break;
        }
    }
    // The part must reach its end (the stream's, for the last part).
    let part = part?;
    (to.is_none() || part.tail.is_some()).then_some(part)
}

/// Adds a decoded packet to the summary from its planes, in their own sample type.
fn summarise(builder: &mut SummaryBuilder, audio: &AudioBufferRef<'_>, frames: Range<usize>) {
    match audio {
        AudioBufferRef::U8(b) => summarise_planes(builder, b, frames, ordered_extremes),
        AudioBufferRef::U16(b) => summarise_planes(builder, b, frames, ordered_extremes),
        AudioBufferRef::U24(b) => summarise_planes(builder, b, frames, ordered_extremes::<u24>),
        AudioBufferRef::U32(b) => summarise_planes(builder, b, frames, ordered_extremes),
        AudioBufferRef::S8(b) => summarise_planes(builder, b, frames, ordered_extremes),
        AudioBufferRef::S16(b) => summarise_planes(builder, b, frames, ordered_extremes),
        AudioBufferRef::S24(b) => summarise_planes(builder, b, frames, ordered_extremes::<i24>),
        AudioBufferRef::S32(b) => summarise_planes(builder, b, frames, ordered_extremes),
        AudioBufferRef::F32(b) => summarise_planes(builder, b, frames, float_extremes),
        AudioBufferRef::F64(b) => summarise_planes(builder, b, frames, float_extremes),
    }
}

/// Runs of `buffer`'s `frames` that end where the summary's buckets end, each added as the
/// extremes `extremes` finds over every plane.
fn summarise_planes<S: Sample>(
    builder: &mut SummaryBuilder,
    buffer: &AudioBuffer<S>,
    frames: Range<usize>,
    extremes: impl Fn(&[S]) -> [f32; 2],
) {
    let planes = buffer.planes();
    let planes = planes.planes();
    let (mut at, frames) = (frames.start, frames.end.min(buffer.frames()));
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
