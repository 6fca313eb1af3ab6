//! The movie writers of a playblast: numbered PNGs, animated GIF (`gif`), animated PNG (`png`)
//! and H.264 in MP4 (OpenH264 through `openh264`, muxed by `mp4`). Every movie is written into
//! one [`AtomicFile`] that replaces the target only when the last frame is in; a writer dropped
//! before [`MovieWriter::finish`] (an error, a cancel) leaves the target as it was and no
//! temporary file.

use std::io::{self, Write};
use std::path::{Path, PathBuf};

use keyrig_io::file_io::AtomicFile;

use crate::audio::transport::MixClip;
use keyrig_render::image::RgbaImage;

use super::{MovieFormat, PlayblastError};

/// NeuQuant's sampling factor for GIF palettes (1 best, 30 fastest). At 10 (the `gif`
/// crate's example) a 1280×720 frame took 0.54 s, more than twice its render
/// (docs/benchmarks.md); 30 samples every 30th pixel, which still finds a rendered frame's
/// few dozen hues.
const GIF_QUANTIZER_SPEED: i32 = 30;

/// One open movie (or folder of frames), fed frame by frame.
pub enum MovieWriter {
    Frames(FramesWriter),
    Gif(GifWriter),
    Apng(ApngWriter),
    Mp4(Box<Mp4Writer>),
}

impl MovieWriter {
    /// Opens the output of `format` for `frames` frames of `width`×`height` at `fps`.
    ///
    /// # Errors
    /// The size does not fit the format, or the temporary file cannot be created.
    pub fn create(
        format: MovieFormat,
        output: &Path,
        (width, height): (u32, u32),
        frames: u32,
        fps: f64,
    ) -> Result<Self, PlayblastError> {
        let encode = |message: String| PlayblastError::Encode { path: output.to_path_buf(), message };
        Ok(match format {
            MovieFormat::PngFrames => MovieWriter::Frames(FramesWriter { pattern: output.to_path_buf() }),
            MovieFormat::Gif => {
                let (w, h) = match (u16::try_from(width), u16::try_from(height)) {
                    (Ok(w), Ok(h)) => (w, h),
                    _ => {
                        return Err(encode(format!(
                            "GIF images are at most 65535 pixels a side, not {width}×{height}"
                        )))
                    }
                };
                let file = create(output)?;
                let mut encoder = gif::Encoder::new(file, w, h, &[]).map_err(|e| encode(e.to_string()))?;
                encoder.set_repeat(gif::Repeat::Infinite).map_err(|e| encode(e.to_string()))?;
                MovieWriter::Gif(GifWriter {
                    encoder,
                    size: (w, h),
                    fps,
                    written: 0,
                    path: output.to_path_buf(),
                })
            }
            MovieFormat::Apng => {
                let file = SharedFile(std::sync::Arc::new(std::sync::Mutex::new(create(output)?)));
                let mut encoder = png::Encoder::new(file.clone(), width, height);
                encoder.set_color(png::ColorType::Rgba);
                encoder.set_depth(png::BitDepth::Eight);
                encoder.set_compression(png::Compression::Fast);
                encoder.set_source_srgb(png::SrgbRenderingIntent::Perceptual);
                let (num, den) = apng_delay(fps);
                encoder.set_animated(frames, 0).map_err(|e| encode(e.to_string()))?;
                encoder.set_frame_delay(num, den).map_err(|e| encode(e.to_string()))?;
                let writer = encoder.write_header().map_err(|e| encode(e.to_string()))?;
                MovieWriter::Apng(ApngWriter { writer, file, path: output.to_path_buf() })
            }
            MovieFormat::Mp4 => MovieWriter::Mp4(Box::new(Mp4Writer::create(output, (width, height), fps)?)),
        })
    }

    /// Adds the next frame (`number` names it in numbered file names).
    ///
    /// # Errors
    /// The image has another size, or encoding or writing fails.
    pub fn write_frame(&mut self, number: i64, image: &RgbaImage) -> Result<(), PlayblastError> {
        match self {
            MovieWriter::Frames(w) => w.write_frame(number, image),
            MovieWriter::Gif(w) => w.write_frame(image),
            MovieWriter::Apng(w) => w.writer.write_image_data(image.as_raw()).map_err(|e| {
                PlayblastError::Encode { path: w.path.clone(), message: format!("frame {number}: {e}") }
            }),
            MovieWriter::Mp4(w) => w.write_frame(image),
        }
    }

    /// Gives the movie a sound track: MP4 only (GIF, APNG and PNGs have none; for them this
    /// does nothing).
    pub fn set_sound(&mut self, sound: MovieSound) {
        if let MovieWriter::Mp4(w) = self {
            w.sound = Some(sound);
        }
    }

    /// Finishes the movie and renames it over the target.
    ///
    /// # Errors
    /// Encoding the last parts or committing the file fails (the target keeps its content).
    pub fn finish(self) -> Result<(), PlayblastError> {
        match self {
            MovieWriter::Frames(_) => Ok(()),
            MovieWriter::Gif(w) => {
                let file = w
                    .encoder
                    .into_inner()
                    .map_err(|e| PlayblastError::Encode { path: w.path.clone(), message: e.to_string() })?;
                commit(file, &w.path)
            }
            MovieWriter::Apng(w) => {
                // `finish` writes IEND and drops the writer's handle; the file is then taken
                // back to commit it.
                let encode = |message: String| PlayblastError::Encode { path: w.path.clone(), message };
                w.writer.finish().map_err(|e| encode(e.to_string()))?;
                let file = w.file.into_inner().map_err(|e| encode(e.to_string()))?;
                commit(file, &w.path)
            }
            MovieWriter::Mp4(w) => w.finish(),
        }
    }
}

fn create(path: &Path) -> Result<AtomicFile, PlayblastError> {
    AtomicFile::create(path).map_err(|source| PlayblastError::Write { path: path.to_path_buf(), source })
}

fn commit(file: AtomicFile, path: &Path) -> Result<(), PlayblastError> {
    file.commit().map_err(|source| PlayblastError::Write { path: path.to_path_buf(), source })
}

/// The numbered PNG files of a range: one atomic write per frame.
pub struct FramesWriter {
    pattern: PathBuf,
}

impl FramesWriter {
    fn write_frame(&mut self, number: i64, image: &RgbaImage) -> Result<(), PlayblastError> {
        let out = numbered_output(&self.pattern, number);
        write_png(&out, image)
    }
}

/// Writes one PNG atomically (the frame of `keyrig render --frame`).
///
/// # Errors
/// The folder cannot be created or the file written.
pub fn write_png(out: &Path, image: &RgbaImage) -> Result<(), PlayblastError> {
    if let Some(parent) = out.parent().filter(|p| !p.as_os_str().is_empty()) {
        std::fs::create_dir_all(parent)
            .map_err(|source| PlayblastError::Write { path: parent.to_path_buf(), source })?;
    }
    keyrig_io::file_io::write_atomic_with(out, |w| {
        use keyrig_render::image::ImageEncoder as _;
        keyrig_render::image::codecs::png::PngEncoder::new(w)
            .write_image(
                image.as_raw(),
                image.width(),
                image.height(),
                keyrig_render::image::ExtendedColorType::Rgba8,
            )
            .map_err(io::Error::other)
    })
    .map_err(|source| PlayblastError::Write { path: out.to_path_buf(), source })
}

/// The output path of frame `frame` of a range of numbered PNGs: `#`s in the name are replaced
/// by the zero-padded frame number (`out/arm_####.png`); in a folder (an existing one, or a
/// path ending in `/`) the files are `frame_0000.png` …; any other name gets `_0000` before its
/// extension (`--format png-frames`).
#[must_use]
pub fn numbered_output(output: &Path, frame: i64) -> PathBuf {
    let text = output.to_string_lossy();
    if let Some(start) = text.find('#') {
        let width = text[start..].chars().take_while(|&c| c == '#').count();
        let number = format!("{frame:0width$}");
        return PathBuf::from(format!("{}{}{}", &text[..start], number, &text[start + width..]));
    }
    if output.is_dir() || text.ends_with('/') {
        return output.join(format!("frame_{frame:04}.png"));
    }
    let stem = output.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_else(|| "frame".into());
    let extension =
        output.extension().map(|e| e.to_string_lossy().into_owned()).unwrap_or_else(|| "png".into());
    output.with_file_name(format!("{stem}_{frame:04}.{extension}"))
}

/// An animated GIF: each frame quantized to its own 256-colour palette (NeuQuant), looping.
pub struct GifWriter {
    encoder: gif::Encoder<AtomicFile>,
    size: (u16, u16),
    fps: f64,
    written: u64,
    path: PathBuf,
}

impl GifWriter {
    fn write_frame(&mut self, image: &RgbaImage) -> Result<(), PlayblastError> {
        let (w, h) = self.size;
        if image.dimensions() != (u32::from(w), u32::from(h)) {
            return Err(PlayblastError::Encode {
                path: self.path.clone(),
                message: format!("frame of {}×{} in a {w}×{h} movie", image.width(), image.height()),
            });
        }
        // Opaque: a rendered frame has no holes, and a transparent key colour would cost a slot.
        let rgb: Vec<u8> = image.pixels().flat_map(|p| [p.0[0], p.0[1], p.0[2]]).collect();
        let mut frame = gif::Frame::from_rgb_speed(w, h, &rgb, GIF_QUANTIZER_SPEED);
        frame.delay = gif_delay(self.written, self.fps);
        self.written += 1;
        self.encoder
            .write_frame(&frame)
            .map_err(|e| PlayblastError::Encode { path: self.path.clone(), message: e.to_string() })
    }
}

/// The delay of GIF frame `index` in hundredths of a second: whole hundredths, rounded so that
/// frame `n` starts at `round(n · 100 / fps)` and the movie keeps the frame rate over its
/// length (30 fps: 3, 4, 3, 3, 4, 3 …). At least 2: browsers show shorter delays as 10.
#[must_use]
pub fn gif_delay(index: u64, fps: f64) -> u16 {
    let start = |n: u64| (n as f64 * 100.0 / fps).round();
    (start(index + 1) - start(index)).clamp(2.0, f64::from(u16::MAX)) as u16
}

/// The APNG frame delay `num / den` seconds for `fps` (both 16-bit): `1/fps` for a whole rate,
/// else thousandths (23.976 fps: 1000/23976).
#[must_use]
pub fn apng_delay(fps: f64) -> (u16, u16) {
    let whole = fps.round();
    if (fps - whole).abs() < 1e-9 && (1.0..=f64::from(u16::MAX)).contains(&whole) {
        return (1, whole as u16);
    }
    for scale in [1000.0, 100.0, 10.0] {
        let den = (fps * scale).round();
        if (1.0..=f64::from(u16::MAX)).contains(&den) {
            return (scale as u16, den as u16);
        }
    }
    (1, whole.clamp(1.0, f64::from(u16::MAX)) as u16)
}

/// An animated PNG being written.
pub struct ApngWriter {
    writer: png::Writer<SharedFile>,
    file: SharedFile,
    path: PathBuf,
}

/// The file under png's [`png::Writer`], shared so that it can be taken back to commit once
/// the writer has written IEND and dropped its handle (png's writer owns its output and gives
/// no way to take it back).
#[derive(Clone)]
pub struct SharedFile(std::sync::Arc<std::sync::Mutex<AtomicFile>>);

impl Write for SharedFile {
    fn write(&mut self, buf: &[u8]) -> io::Result<usize> {
        self.0.lock().map_err(|_| io::Error::other("a writer panicked"))?.write(buf)
    }

    fn flush(&mut self) -> io::Result<()> {
        self.0.lock().map_err(|_| io::Error::other("a writer panicked"))?.flush()
    }
}

impl SharedFile {
    /// The file, once no other handle is left.
    fn into_inner(self) -> io::Result<AtomicFile> {
        std::sync::Arc::into_inner(self.0)
            .ok_or_else(|| io::Error::other("the file is still in use"))?
            .into_inner()
            .map_err(|_| io::Error::other("a writer panicked"))
    }
}

/// H.264 (Constrained Baseline, OpenH264) in an MP4 file: one IDR frame at the start, then
/// predicted frames; SPS and PPS go into the `avcC` box, each frame's other NAL units into one
/// sample with 4-byte lengths (ISO/IEC 14496-15).
pub struct Mp4Writer {
    encoder: openh264::encoder::Encoder,
    muxer: Option<mp4::Mp4Writer<AtomicFile>>,
    size: (u32, u32),
    /// Samples per second of the track's clock (1000 × fps) and one frame's length in it.
    timescale: u32,
    frame_ticks: u32,
    written: u64,
    path: PathBuf,
    file: Option<AtomicFile>,
    sound: Option<MovieSound>,
}

impl Mp4Writer {
    fn create(path: &Path, (width, height): (u32, u32), fps: f64) -> Result<Self, PlayblastError> {
        let encode = |message: String| PlayblastError::Encode { path: path.to_path_buf(), message };
        if width % 2 != 0 || height % 2 != 0 {
            return Err(encode(format!(
                "H.264 (4:2:0) needs an even width and height, not {width}×{height}; try {}x{}",
                width + width % 2,
                height + height % 2
            )));
        }
        if width > u32::from(u16::MAX) || height > u32::from(u16::MAX) {
            return Err(encode(format!("MP4 video is at most 65535 pixels a side, not {width}×{height}")));
        }
        // Clock: 1000 ticks per frame, so 23.976 fps is exact too.
        let timescale = (fps * 1000.0).round();
        if !(1.0..=f64::from(u32::MAX)).contains(&timescale) {
            return Err(encode(format!("frame rate {fps} cannot be written")));
        }
        use openh264::encoder::{
            ColorPrimaries, EncoderConfig, FrameRate, MatrixCoefficients, RateControlMode,
            TransferCharacteristics, VuiConfig,
        };
        // openh264's RGB → YUV conversion uses BT.601's limited-range matrix; the pixels are
        // sRGB (BT.709 primaries, the sRGB curve). The VUI says exactly that to players.
        let vui = VuiConfig::bt601()
            .color_primaries(ColorPrimaries::Bt709)
            .transfer_characteristics(TransferCharacteristics::Srgb)
            .matrix_coefficients(MatrixCoefficients::Smpte170M);
        let config = EncoderConfig::new()
            .max_frame_rate(FrameRate::from_hz(fps as f32))
            // Constant quality: rate control off, every frame at OpenH264's base quantizer
            // (26, SVC_QUALITY_BASE_QP), whatever the bitrate; and every rendered frame is a
            // frame of the movie (rate control could only meet a bitrate by skipping frames).
            .rate_control_mode(RateControlMode::Off)
            .skip_frames(false)
            .vui(vui);
        let encoder =
            openh264::encoder::Encoder::with_api_config(openh264::OpenH264API::from_source(), config)
                .map_err(|e| encode(format!("starting the H.264 encoder: {e}")))?;
        Ok(Mp4Writer {
            encoder,
            muxer: None,
            size: (width, height),
            timescale: timescale as u32,
            frame_ticks: 1000,
            written: 0,
            path: path.to_path_buf(),
            file: Some(create(path)?),
            sound: None,
        })
    }

    fn error(&self, message: impl std::fmt::Display) -> PlayblastError {
        PlayblastError::Encode { path: self.path.clone(), message: message.to_string() }
    }

    fn write_frame(&mut self, image: &RgbaImage) -> Result<(), PlayblastError> {
        if image.dimensions() != self.size {
            return Err(self.error(format!(
                "frame of {}×{} in a {}×{} movie",
                image.width(),
                image.height(),
                self.size.0,
                self.size.1
            )));
        }
        let (w, h) = (self.size.0 as usize, self.size.1 as usize);
        let yuv = openh264::formats::YUVBuffer::from_rgb_source(openh264::formats::RgbaSliceU8::new(
            image.as_raw(),
            (w, h),
        ));
        let (mut sps, mut pps, mut sample) = (None, None, Vec::new());
        let path = self.path.clone();
        let is_sync = {
            let stream = self.encoder.encode(&yuv).map_err(|e| PlayblastError::Encode {
                path: path.clone(),
                message: format!("encoding: {e}"),
            })?;
            for l in 0..stream.num_layers() {
                let Some(layer) = stream.layer(l) else { continue };
                for n in 0..layer.nal_count() {
                    let Some(nal) = layer.nal_unit(n).map(strip_start_code) else { continue };
                    match nal.first().map(|b| b & 0x1f) {
                        Some(7) => sps = Some(nal.to_vec()),
                        Some(8) => pps = Some(nal.to_vec()),
                        Some(_) => {
                            sample.extend_from_slice(&(nal.len() as u32).to_be_bytes());
                            sample.extend_from_slice(nal);
                        }
                        None => {}
                    }
                }
            }
            matches!(stream.frame_type(), openh264::encoder::FrameType::IDR | openh264::encoder::FrameType::I)
        };
        if self.muxer.is_none() {
            let (Some(sps), Some(pps)) = (sps, pps) else {
                return Err(self.error("the encoder's first frame has no SPS and PPS"));
            };
            self.start_muxer(sps, pps)?;
        }
        if sample.is_empty() {
            return Err(self.error(format!("the encoder skipped frame {}", self.written)));
        }
        let start_time = self.written * u64::from(self.frame_ticks);
        let mp4_sample = mp4::Mp4Sample {
            start_time,
            duration: self.frame_ticks,
            rendering_offset: 0,
            is_sync,
            bytes: mp4::Bytes::from(sample),
        };
        let muxer = self
            .muxer
            .as_mut()
            .ok_or_else(|| PlayblastError::Encode { path: path.clone(), message: "no muxer".into() })?;
        muxer
            .write_sample(1, &mp4_sample)
            .map_err(|e| PlayblastError::Encode { path, message: e.to_string() })?;
        self.written += 1;
        Ok(())
    }

    fn start_muxer(&mut self, sps: Vec<u8>, pps: Vec<u8>) -> Result<(), PlayblastError> {
        let file = self.file.take().ok_or_else(|| self.error("the file is gone"))?;
        let brand = |s: &str| s.parse::<mp4::FourCC>().map_err(|e| self.error(e));
        let config = mp4::Mp4Config {
            major_brand: brand("isom")?,
            minor_version: 512,
            compatible_brands: vec![brand("isom")?, brand("iso2")?, brand("avc1")?, brand("mp41")?],
            timescale: self.timescale,
        };
        let mut muxer = mp4::Mp4Writer::write_start(file, &config).map_err(|e| self.error(e))?;
        muxer
            .add_track(&mp4::TrackConfig {
                track_type: mp4::TrackType::Video,
                timescale: self.timescale,
                language: "und".into(),
                media_conf: mp4::MediaConfig::AvcConfig(mp4::AvcConfig {
                    width: self.size.0 as u16,
                    height: self.size.1 as u16,
                    seq_param_set: sps,
                    pic_param_set: pps,
                }),
            })
            .map_err(|e| self.error(e))?;
        self.muxer = Some(muxer);
        Ok(())
    }

    fn finish(mut self) -> Result<(), PlayblastError> {
        let mut muxer = self.muxer.take().ok_or_else(|| self.error("no frame was written"))?;
        muxer.write_end().map_err(|e| self.error(e))?;
        let mut file = muxer.into_writer();
        if let Some(sound) = &self.sound {
            add_sound_track(&mut file, sound)
                .map_err(|e| self.error(format!("writing the sound track: {e}")))?;
        }
        file.flush().map_err(|source| PlayblastError::Write { path: self.path.clone(), source })?;
        commit(file, &self.path)
    }
}

/// The sound an MP4 carries: the scene's unmuted clips placed on the timeline, mixed from the
/// movie's first frame for its length.
#[derive(Clone, Debug)]
pub struct MovieSound {
    pub clips: Vec<MixClip>,
    /// The timeline second of the movie's first frame.
    pub from: f64,
    /// The movie's length in seconds.
    pub seconds: f64,
}

/// The sound track's frames a second and channels: 16-bit little-endian PCM (`sowt`).
pub const SOUND_RATE: u32 = 48_000;
pub const SOUND_CHANNELS: u16 = 2;
/// Frames a chunk of the sound track (one second).
const SOUND_CHUNK: u64 = SOUND_RATE as u64;

/// Adds `sound`, mixed, as a second track of the finished MP4 in `file`, whose `moov` box the
/// muxer wrote last: its samples go into a second `mdat` box where that `moov` was, followed by
/// the `moov` box with the sound's `trak` added (and `mvhd`'s next track ID moved on). The
/// track is uncompressed 16-bit stereo PCM at 48 kHz in a QuickTime `sowt` sample entry,
/// one-second chunks.
///
/// # Errors
/// The file cannot be read back or written, or is not laid out as the muxer writes.
fn add_sound_track<F: io::Read + Write + io::Seek>(file: &mut F, sound: &MovieSound) -> io::Result<()> {
    use io::SeekFrom;
    let bad = |what: &str| io::Error::new(io::ErrorKind::InvalidData, what.to_owned());
    let end = file.seek(SeekFrom::End(0))?;
    // The top-level boxes, to the `moov`.
    let mut at = 0u64;
    let moov_at = loop {
        if at.saturating_add(8) > end {
            return Err(bad("no moov box"));
        }
        file.seek(SeekFrom::Start(at))?;
        let mut head = [0u8; 16];
        file.read_exact(&mut head[..8])?;
        let mut size = u64::from(u32::from_be_bytes([head[0], head[1], head[2], head[3]]));
        if size == 1 {
            file.read_exact(&mut head[8..])?;
            size = u64::from_be_bytes([
                head[8], head[9], head[10], head[11], head[12], head[13], head[14], head[15],
            ]);
        } else if size == 0 {
            size = end - at;
        }
        if &head[4..8] == b"moov" {
            if at + size != end || size < 8 {
                return Err(bad("the moov box is not the file's last"));
            }
            break at;
        }
        if size < 8 {
            return Err(bad("a box shorter than its header"));
        }
        at += size;
    };
    let mut moov = vec![0u8; usize::try_from(end - moov_at).map_err(|_| bad("moov too large"))?];
    file.seek(SeekFrom::Start(moov_at))?;
    file.read_exact(&mut moov)?;
    if u32::from_be_bytes([moov[0], moov[1], moov[2], moov[3]]) == 1 {
        return Err(bad("a moov box with a 64-bit size"));
    }
    let mut children = moov[8..].to_vec();
    // mvhd: the movie's timescale, and the next track ID (its last 4 bytes), which the sound
    // track takes.
    let (mut timescale, mut track_id) = (None, 0u32);
    let mut c = 0;
    while c + 8 <= children.len() {
        let size =
            u32::from_be_bytes([children[c], children[c + 1], children[c + 2], children[c + 3]]) as usize;
        if size < 8 || c + size > children.len() {
            return Err(bad("a malformed box in moov"));
        }
        if &children[c + 4..c + 8] == b"mvhd" && size >= 32 {
            let body = c + 8;
            let at = if children[body] == 1 { body + 20 } else { body + 12 };
            let word = |i: usize| {
                u32::from_be_bytes([children[i], children[i + 1], children[i + 2], children[i + 3]])
            };
            timescale = Some(word(at));
            let next = c + size - 4;
            track_id = word(next);
            children[next..next + 4].copy_from_slice(&(track_id + 1).to_be_bytes());
        }
        c += size;
    }
    let timescale = timescale.ok_or_else(|| bad("no mvhd box"))?;

    // The samples, mixed a chunk at a time, in an `mdat` where the `moov` was.
    let frames = (sound.seconds * f64::from(SOUND_RATE)).round().max(0.0) as u64;
    let bytes_per_frame = u64::from(SOUND_CHANNELS) * 2;
    let data = frames * bytes_per_frame;
    file.seek(SeekFrom::Start(moov_at))?;
    let header = if data + 8 <= u64::from(u32::MAX) {
        file.write_all(&((data + 8) as u32).to_be_bytes())?;
        file.write_all(b"mdat")?;
        8
    } else {
        file.write_all(&1u32.to_be_bytes())?;
        file.write_all(b"mdat")?;
        file.write_all(&(data + 16).to_be_bytes())?;
        16
    };
    let first_chunk = moov_at + header;
    let channels = usize::from(SOUND_CHANNELS);
    let mut block = vec![0f32; SOUND_CHUNK as usize * channels];
    let mut out = Vec::with_capacity(block.len() * 2);
    let mut done = 0u64;
    while done < frames {
        let n = (frames - done).min(SOUND_CHUNK) as usize;
        let block = &mut block[..n * channels];
        block.fill(0.0);
        let from = sound.from + done as f64 / f64::from(SOUND_RATE);
        crate::audio::transport::mix_into(&sound.clips, block, channels, SOUND_RATE, from);
        out.clear();
        for &s in block.iter() {
            out.extend_from_slice(&((s * 32767.0).round() as i16).to_le_bytes());
        }
        file.write_all(&out)?;
        done += n as u64;
    }

    // The `trak`.
    let chunks = frames.div_ceil(SOUND_CHUNK).max(1);
    let duration = frames * u64::from(timescale) / u64::from(SOUND_RATE);
    let trak = sound_trak(track_id, frames, duration, first_chunk, chunks, bytes_per_frame);
    let moov_size = 8 + children.len() + trak.len();
    let moov_size = u32::try_from(moov_size).map_err(|_| bad("moov too large"))?;
    file.write_all(&moov_size.to_be_bytes())?;
    file.write_all(b"moov")?;
    file.write_all(&children)?;
    file.write_all(&trak)?;
    Ok(())
}

/// A box: its size, its type, `body`.
fn mp4_box(kind: &[u8; 4], body: &[u8]) -> Vec<u8> {
    let mut b = Vec::with_capacity(body.len() + 8);
    b.extend_from_slice(&((body.len() + 8) as u32).to_be_bytes());
    b.extend_from_slice(kind);
    b.extend_from_slice(body);
    b
}

/// A full box: a box whose body starts with a version and 24 bits of flags.
fn mp4_full_box(kind: &[u8; 4], version: u8, flags: u32, body: &[u8]) -> Vec<u8> {
    let mut full = Vec::with_capacity(body.len() + 4);
    full.extend_from_slice(&((u32::from(version) << 24) | (flags & 0x00ff_ffff)).to_be_bytes());
    full.extend_from_slice(body);
    mp4_box(kind, &full)
}

/// The sound track's `trak` (ISO/IEC 14496-12): `frames` PCM frames of [`SOUND_CHANNELS`]
/// 16-bit channels at [`SOUND_RATE`], one sample each, in `chunks` chunks of
/// [`SOUND_CHUNK`] frames (the last one shorter) from `first_chunk` on; `duration` in the
/// movie's timescale.
fn sound_trak(
    track_id: u32,
    frames: u64,
    duration: u64,
    first_chunk: u64,
    chunks: u64,
    bytes_per_frame: u64,
) -> Vec<u8> {
    let be32 = |v: u32| v.to_be_bytes();
    let long = duration > u64::from(u32::MAX) || frames > u64::from(u32::MAX);
    // tkhd: enabled, in the movie and its preview; volume 1.0; the identity matrix.
    let mut tkhd = Vec::new();
    if long {
        tkhd.extend_from_slice(&[0; 16]);
        tkhd.extend_from_slice(&be32(track_id));
        tkhd.extend_from_slice(&[0; 4]);
        tkhd.extend_from_slice(&duration.to_be_bytes());
    } else {
        tkhd.extend_from_slice(&[0; 8]);
        tkhd.extend_from_slice(&be32(track_id));
        tkhd.extend_from_slice(&[0; 4]);
        tkhd.extend_from_slice(&be32(duration as u32));
    }
    tkhd.extend_from_slice(&[0; 8]);
    tkhd.extend_from_slice(&[0, 0, 0, 1, 0x01, 0x00, 0, 0]);
    for m in [0x0001_0000u32, 0, 0, 0, 0x0001_0000, 0, 0, 0, 0x4000_0000] {
        tkhd.extend_from_slice(&be32(m));
    }
    tkhd.extend_from_slice(&[0; 8]);
    let tkhd = mp4_full_box(b"tkhd", u8::from(long), 7, &tkhd);
    // mdhd: the track's clock is the sample rate; language "und".
    let mut mdhd = Vec::new();
    if long {
        mdhd.extend_from_slice(&[0; 16]);
        mdhd.extend_from_slice(&be32(SOUND_RATE));
        mdhd.extend_from_slice(&frames.to_be_bytes());
    } else {
        mdhd.extend_from_slice(&[0; 8]);
        mdhd.extend_from_slice(&be32(SOUND_RATE));
        mdhd.extend_from_slice(&be32(frames as u32));
    }
    mdhd.extend_from_slice(&[0x55, 0xc4, 0, 0]);
    let mdhd = mp4_full_box(b"mdhd", u8::from(long), 0, &mdhd);
    let mut hdlr = vec![0; 4];
    hdlr.extend_from_slice(b"soun");
    hdlr.extend_from_slice(&[0; 12]);
    hdlr.extend_from_slice(b"SoundHandler\0");
    let hdlr = mp4_full_box(b"hdlr", 0, 0, &hdlr);
    let smhd = mp4_full_box(b"smhd", 0, 0, &[0; 4]);
    let url = mp4_full_box(b"url ", 0, 1, &[]);
    let dref = mp4_full_box(b"dref", 0, 0, &[be32(1).as_slice(), &url].concat());
    let dinf = mp4_box(b"dinf", &dref);
    // stsd: one `sowt` entry (QuickTime's sound sample description, version 0) with its
    // channel layout.
    let mut sowt = vec![0; 6];
    sowt.extend_from_slice(&1u16.to_be_bytes());
    sowt.extend_from_slice(&[0; 8]);
    sowt.extend_from_slice(&SOUND_CHANNELS.to_be_bytes());
    sowt.extend_from_slice(&16u16.to_be_bytes());
    sowt.extend_from_slice(&[0; 4]);
    sowt.extend_from_slice(&be32(SOUND_RATE << 16));
    // chan: the channels are left and right (kAudioChannelLayoutTag_Stereo), so that players
    // need not guess.
    sowt.extend_from_slice(&mp4_full_box(b"chan", 0, 0, &[be32(0x0065_0002), be32(0), be32(0)].concat()));
    let stsd = mp4_full_box(b"stsd", 0, 0, &[be32(1).as_slice(), &mp4_box(b"sowt", &sowt)].concat());
    // Every sample (frame) lasts one tick of the track's clock.
    let frames32 = u32::try_from(frames).unwrap_or(u32::MAX);
    let stts = mp4_full_box(b"stts", 0, 0, &[be32(1), be32(frames32), be32(1)].concat());
    let last = frames - (chunks - 1) * SOUND_CHUNK;
    let mut stsc = Vec::new();
    if chunks > 1 && last != SOUND_CHUNK {
        stsc.extend_from_slice(&[be32(2), be32(1), be32(SOUND_CHUNK as u32), be32(1)].concat());
        stsc.extend_from_slice(&[be32(chunks as u32), be32(last as u32), be32(1)].concat());
    } else {
        let per = if chunks > 1 { SOUND_CHUNK } else { last };
        stsc.extend_from_slice(&[be32(1), be32(1), be32(per as u32), be32(1)].concat());
    }
    let stsc = mp4_full_box(b"stsc", 0, 0, &stsc);
    let stsz = mp4_full_box(b"stsz", 0, 0, &[be32(bytes_per_frame as u32), be32(frames32)].concat());
    let offsets = (0..chunks).map(|k| first_chunk + k * SOUND_CHUNK * bytes_per_frame);
    let stco = if first_chunk + frames * bytes_per_frame <= u64::from(u32::MAX) {
        let mut b = be32(chunks as u32).to_vec();
        offsets.for_each(|o| b.extend_from_slice(&be32(o as u32)));
        mp4_full_box(b"stco", 0, 0, &b)
    } else {
        let mut b = be32(chunks as u32).to_vec();
        offsets.for_each(|o| b.extend_from_slice(&o.to_be_bytes()));
        mp4_full_box(b"co64", 0, 0, &b)
    };
    let stbl = mp4_box(b"stbl", &[stsd, stts, stsc, stsz, stco].concat());
    let minf = mp4_box(b"minf", &[smhd, dinf, stbl].concat());
    let mdia = mp4_box(b"mdia", &[mdhd, hdlr, minf].concat());
    mp4_box(b"trak", &[tkhd, mdia].concat())
}

/// A NAL unit without its Annex B start code (`00 00 01` or `00 00 00 01`).
fn strip_start_code(nal: &[u8]) -> &[u8] {
    if let Some(rest) = nal.strip_prefix(&[0, 0, 0, 1]) {
        rest
    } else if let Some(rest) = nal.strip_prefix(&[0, 0, 1]) {
        rest
    } else {
        nal
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn gif_delays_keep_the_frame_rate_in_whole_hundredths() {
        let delays: Vec<u16> = (0..6).map(|i| gif_delay(i, 30.0)).collect();
        assert_eq!(delays, vec![3, 4, 3, 3, 4, 3]);
        let total: u64 = (0..300).map(|i| u64::from(gif_delay(i, 30.0))).sum();
        assert_eq!(total, 1000, "300 frames at 30 fps last 10 s");
        assert!((0..100).all(|i| gif_delay(i, 25.0) == 4));
        assert_eq!(gif_delay(0, 120.0), 2, "browsers slow delays under 2 hundredths down to 10");
    }

    #[test]
    fn apng_delays_are_the_frame_interval() {
        assert_eq!(apng_delay(30.0), (1, 30));
        assert_eq!(apng_delay(24.0), (1, 24));
        assert_eq!(apng_delay(23.976), (1000, 23976));
        assert_eq!(apng_delay(29.97), (1000, 29970));
    }

    #[test]
    fn start_codes_are_stripped() {
        assert_eq!(strip_start_code(&[0, 0, 0, 1, 0x67, 1]), &[0x67, 1]);
        assert_eq!(strip_start_code(&[0, 0, 1, 0x68]), &[0x68]);
        assert_eq!(strip_start_code(&[0x65]), &[0x65]);
    }

    #[test]
    fn range_outputs_are_numbered() {
        assert_eq!(numbered_output(Path::new("out/a_###.png"), 7), PathBuf::from("out/a_007.png"));
        assert_eq!(numbered_output(Path::new("out/a.png"), 12), PathBuf::from("out/a_0012.png"));
        assert_eq!(numbered_output(Path::new("out/"), 3), PathBuf::from("out/frame_0003.png"));
    }
}
