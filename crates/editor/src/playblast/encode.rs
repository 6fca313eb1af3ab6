//! The movie writers of a playblast: numbered PNGs, animated GIF (`gif`), animated PNG (`png`)
//! and H.264 in MP4 (OpenH264 through `openh264`, muxed by `mp4`). Every movie is written into
//! one [`AtomicFile`] that replaces the target only when the last frame is in; a writer dropped
//! before [`MovieWriter::finish`] (an error, a cancel) leaves the target as it was and no
//! temporary file.

use std::io::{self, Write};
use std::path::{Path, PathBuf};

use keyrig_io::file_io::AtomicFile;
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
        file.flush().map_err(|source| PlayblastError::Write { path: self.path.clone(), source })?;
        commit(file, &self.path)
    }
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
