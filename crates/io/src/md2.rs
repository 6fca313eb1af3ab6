//! Quake 2 MD2 import (seed text 001; docs/design.md §8).
//!
//! An MD2 file is a 68-byte header of seventeen little-endian `i32`s followed by arrays the
//! header points at: skin names (64 bytes each), texture coordinates (`i16` s, t in skin
//! pixels), triangles (three vertex and three texture-coordinate indices, `u16`), frames
//! (scale, translation, 16-byte name, then per vertex three `u8` coordinates and an index
//! into the 162-entry normal table) and OpenGL commands (ignored here).
//!
//! Decompression: `position = scale ∘ packed + translate` per frame (component-wise).
//! Texture coordinates are divided by the header's skin size (`u = s / skin_width`,
//! `v = t / skin_height`).
//!
//! The reader trusts nothing: the header is checked (magic `IDP2`, version 8, `ofs_end`
//! equal to the file size), every count is checked against the bytes its array occupies
//! *before* anything is allocated, every offset and array must lie inside the file, every
//! index must be in range and every float finite. Errors carry the byte offset.
//!
//! Frames are grouped into clips by name with the trailing digits stripped (`run1` …
//! `run6` → `run`); [`Md2Model::sample_clip`] plays a clip at a chosen frame rate by
//! linear interpolation between consecutive frames (vertex morphing).

use std::ops::Range;
use std::path::{Path, PathBuf};

use glam::{Vec2, Vec3};

/// Size of the MD2 header in bytes (17 × i32).
pub const HEADER_SIZE: usize = 68;
/// `IDP2` as stored in the first four bytes.
pub const MAGIC: [u8; 4] = *b"IDP2";
/// The only MD2 version.
pub const VERSION: i32 = 8;
/// Bytes of one skin name.
const SKIN_NAME_SIZE: usize = 64;
/// Bytes of one texture coordinate (two i16).
const ST_SIZE: usize = 4;
/// Bytes of one triangle (six u16).
const TRI_SIZE: usize = 12;
/// Bytes of one frame header (scale, translate, 16-byte name).
const FRAME_HEADER_SIZE: usize = 40;
/// Bytes of one packed frame vertex (3 × u8 coordinates + u8 normal index).
const PACKED_VERTEX_SIZE: usize = 4;
/// Bytes of the frame name.
const FRAME_NAME_SIZE: usize = 16;

/// Something wrong with an MD2 file: where (byte offset from the start of the file) and what.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
#[error("byte {offset}: {kind}")]
pub struct Md2Error {
    /// Byte offset of the offending field or array.
    pub offset: usize,
    pub kind: Md2ErrorKind,
}

/// What is wrong with an MD2 file.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Md2ErrorKind {
    #[error("file is {len} bytes, shorter than the {HEADER_SIZE}-byte MD2 header")]
    TooShort { len: usize },
    #[error("magic is {found:?}, expected \"IDP2\"")]
    BadMagic { found: [u8; 4] },
    #[error("version is {found}, expected 8")]
    BadVersion { found: i32 },
    #[error("header says the file is {header} bytes (ofs_end) but it is {actual} bytes")]
    FileSizeMismatch { header: i64, actual: usize },
    #[error("{field} is {value}, must not be negative")]
    Negative { field: &'static str, value: i32 },
    #[error("{field} is {value}, must be positive")]
    NotPositive { field: &'static str, value: i32 },
    #[error("framesize is {found}, expected 40 + 4 × num_xyz = {expected}")]
    FrameSize { found: i64, expected: i64 },
    #[error("{what}: {count} entries of {entry_size} bytes at offset {start} reach past the end of the {file_len}-byte file")]
    ArrayOutOfFile { what: &'static str, start: usize, count: usize, entry_size: usize, file_len: usize },
    #[error("{what} index {index} is out of range (there are {limit})")]
    IndexOutOfRange { what: &'static str, index: usize, limit: usize },
    #[error("{what} is not finite ({value})")]
    NonFinite { what: &'static str, value: f32 },
    #[error("normal index {index} is out of range (the table has 162 entries)")]
    NormalIndex { index: u8 },
    #[error("the model has no {what}")]
    Empty { what: &'static str },
}

/// Errors of [`load_md2_file`]: reading the file or its skin image, or a malformed file.
#[derive(Debug, thiserror::Error)]
pub enum Md2LoadError {
    #[error("{path}: cannot read: {source}")]
    Io { path: PathBuf, source: std::io::Error },
    #[error("{path}: {source}")]
    Format { path: PathBuf, source: Md2Error },
    #[error("{path}: skin image cannot be decoded: {source}")]
    Skin { path: PathBuf, source: image::ImageError },
}

/// Errors of clip playback.
#[derive(Debug, Clone, PartialEq, thiserror::Error)]
pub enum Md2PlaybackError {
    #[error("clip {index} does not exist (the model has {count} clips)")]
    NoSuchClip { index: usize, count: usize },
    #[error("frame rate must be finite and positive, got {0}")]
    BadFps(f64),
    #[error("time must be finite, got {0}")]
    BadTime(f64),
}

/// One decompressed frame: a position and a normal-table index per MD2 vertex (`num_xyz`).
#[derive(Clone, Debug, PartialEq)]
pub struct Md2Frame {
    pub name: String,
    /// Decompressed positions (file axes: Quake's Z up), one per MD2 vertex.
    pub positions: Vec<Vec3>,
    /// Index into [`ANORMS`] per MD2 vertex (checked < 162).
    pub normal_indices: Vec<u8>,
}

impl Md2Frame {
    /// The unit normal of MD2 vertex `i` from the standard table.
    #[must_use]
    pub fn normal(&self, i: usize) -> Vec3 {
        Vec3::from_array(ANORMS[usize::from(self.normal_indices[i])])
    }
}

/// A named run of consecutive frames (`stand`, `run`, …).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Md2Clip {
    pub name: String,
    /// Indices into [`Md2Model::frames`].
    pub frames: Range<usize>,
}

/// A decoded skin image (RGBA8).
#[derive(Clone, Debug, PartialEq)]
pub struct Md2Skin {
    pub path: PathBuf,
    pub width: u32,
    pub height: u32,
    pub rgba: Vec<u8>,
}

/// An imported MD2 model.
///
/// MD2 indexes positions and texture coordinates separately per triangle corner; the
/// importer welds each distinct (position, texcoord) pair into one render vertex. Render
/// vertex `v` takes its position from MD2 vertex `vertex_xyz[v]` of a frame and its texture
/// coordinate from `texcoords[v]`.
#[derive(Clone, Debug, PartialEq)]
pub struct Md2Model {
    /// Skin size from the header, used to normalize texture coordinates.
    pub skin_width: u32,
    pub skin_height: u32,
    /// Skin names stored in the header (often Quake 2 `.pcx` paths; may be empty).
    pub skin_names: Vec<String>,
    /// MD2 vertex (position index) of each render vertex.
    pub vertex_xyz: Vec<u32>,
    /// Normalized texture coordinate of each render vertex (s / width, t / height).
    pub texcoords: Vec<Vec2>,
    /// Triangles as render-vertex indices, three per triangle, in file order, wound
    /// counter-clockwise seen from the front (as glTF and OBJ expect): MD2 stores its
    /// triangles clockwise, so the reader swaps each triangle's second and third corners.
    pub indices: Vec<u32>,
    pub frames: Vec<Md2Frame>,
    pub clips: Vec<Md2Clip>,
    /// The skin image found next to the file, if any (see [`find_skin`]).
    pub skin: Option<Md2Skin>,
}

/// Positions and normals of every render vertex at one moment of a clip.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Md2Pose {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
}

/// A little-endian reader over the file that reports byte offsets.
struct Bytes<'a> {
    data: &'a [u8],
}

impl Bytes<'_> {
    fn i32_at(&self, offset: usize) -> i32 {
        // Callers only read inside ranges checked against `data.len()`.
        let b = &self.data[offset..offset + 4];
        i32::from_le_bytes([b[0], b[1], b[2], b[3]])
    }
    fn u16_at(&self, offset: usize) -> u16 {
        u16::from_le_bytes([self.data[offset], self.data[offset + 1]])
    }
    fn i16_at(&self, offset: usize) -> i16 {
        i16::from_le_bytes([self.data[offset], self.data[offset + 1]])
    }
    fn f32_at(&self, offset: usize) -> f32 {
        f32::from_bits(self.i32_at(offset) as u32)
    }
}

/// The header fields, in file order.
const FIELD_NAMES: [&str; 17] = [
    "ident",
    "version",
    "skinwidth",
    "skinheight",
    "framesize",
    "num_skins",
    "num_xyz",
    "num_st",
    "num_tris",
    "num_glcmds",
    "num_frames",
    "ofs_skins",
    "ofs_st",
    "ofs_tris",
    "ofs_frames",
    "ofs_glcmds",
    "ofs_end",
];

fn err(offset: usize, kind: Md2ErrorKind) -> Md2Error {
    Md2Error { offset, kind }
}

/// Reads header field `i` as a non-negative count or offset.
fn non_negative(bytes: &Bytes<'_>, i: usize) -> Result<usize, Md2Error> {
    let value = bytes.i32_at(4 * i);
    usize::try_from(value).map_err(|_| err(4 * i, Md2ErrorKind::Negative { field: FIELD_NAMES[i], value }))
}

/// Checks that `count` entries of `entry_size` bytes starting at the offset in header field
/// `ofs_field` lie inside the file; returns the start offset. Done before any allocation, so
/// a count can never ask for more memory than the file holds.
fn array_in_file(
    data: &[u8],
    what: &'static str,
    ofs_field: usize,
    start: usize,
    count: usize,
    entry_size: usize,
) -> Result<usize, Md2Error> {
    let end = count.checked_mul(entry_size).and_then(|n| n.checked_add(start));
    match end {
        Some(end) if end <= data.len() => Ok(start),
        _ => Err(err(
            4 * ofs_field,
            Md2ErrorKind::ArrayOutOfFile { what, start, count, entry_size, file_len: data.len() },
        )),
    }
}

/// Parses an MD2 file from memory. No skin image is looked up (see [`load_md2_file`]).
///
/// # Errors
/// An [`Md2Error`] with the byte offset and the problem for every malformed input.
pub fn parse_md2(data: &[u8]) -> Result<Md2Model, Md2Error> {
    if data.len() < HEADER_SIZE {
        return Err(err(0, Md2ErrorKind::TooShort { len: data.len() }));
    }
    let bytes = Bytes { data };
    let magic = [data[0], data[1], data[2], data[3]];
    if magic != MAGIC {
        return Err(err(0, Md2ErrorKind::BadMagic { found: magic }));
    }
    let version = bytes.i32_at(4);
    if version != VERSION {
        return Err(err(4, Md2ErrorKind::BadVersion { found: version }));
    }
    let ofs_end = bytes.i32_at(64);
    if i64::from(ofs_end) != data.len() as i64 {
        return Err(err(
            64,
            Md2ErrorKind::FileSizeMismatch { header: i64::from(ofs_end), actual: data.len() },
        ));
    }
    let skin_width = bytes.i32_at(8);
    let skin_height = bytes.i32_at(12);
    for (i, value) in [(2, skin_width), (3, skin_height)] {
        if value <= 0 {
            return Err(err(4 * i, Md2ErrorKind::NotPositive { field: FIELD_NAMES[i], value }));
        }
    }
    let framesize = non_negative(&bytes, 4)?;
    let num_skins = non_negative(&bytes, 5)?;
    let num_xyz = non_negative(&bytes, 6)?;
    let num_st = non_negative(&bytes, 7)?;
    let num_tris = non_negative(&bytes, 8)?;
    let num_glcmds = non_negative(&bytes, 9)?;
    let num_frames = non_negative(&bytes, 10)?;
    let ofs_skins = non_negative(&bytes, 11)?;
    let ofs_st = non_negative(&bytes, 12)?;
    let ofs_tris = non_negative(&bytes, 13)?;
    let ofs_frames = non_negative(&bytes, 14)?;
    let ofs_glcmds = non_negative(&bytes, 15)?;

    let expected_framesize = FRAME_HEADER_SIZE as i64 + PACKED_VERTEX_SIZE as i64 * num_xyz as i64;
    if framesize as i64 != expected_framesize {
        return Err(err(
            16,
            Md2ErrorKind::FrameSize { found: framesize as i64, expected: expected_framesize },
        ));
    }
    for (field, count, what) in
        [(6, num_xyz, "vertices"), (8, num_tris, "triangles"), (10, num_frames, "frames")]
    {
        if count == 0 {
            return Err(err(4 * field, Md2ErrorKind::Empty { what }));
        }
    }
    array_in_file(data, "skins", 11, ofs_skins, num_skins, SKIN_NAME_SIZE)?;
    array_in_file(data, "texture coordinates", 12, ofs_st, num_st, ST_SIZE)?;
    array_in_file(data, "triangles", 13, ofs_tris, num_tris, TRI_SIZE)?;
    array_in_file(data, "frames", 14, ofs_frames, num_frames, framesize)?;
    array_in_file(data, "GL commands", 15, ofs_glcmds, num_glcmds, 4)?;
    if num_st == 0 {
        return Err(err(28, Md2ErrorKind::Empty { what: "texture coordinates" }));
    }

    let skin_names = (0..num_skins)
        .map(|i| c_string(&data[ofs_skins + i * SKIN_NAME_SIZE..ofs_skins + (i + 1) * SKIN_NAME_SIZE]))
        .collect();

    // Triangles: weld (xyz, st) pairs into render vertices.
    let mut indices = Vec::with_capacity(num_tris * 3);
    let mut vertex_xyz = Vec::new();
    let mut vertex_st: Vec<u16> = Vec::new();
    let mut welded = std::collections::HashMap::new();
    for t in 0..num_tris {
        let base = ofs_tris + t * TRI_SIZE;
        for corner in 0..3 {
            let xyz_offset = base + 2 * corner;
            let st_offset = base + 6 + 2 * corner;
            let xyz = bytes.u16_at(xyz_offset);
            let st = bytes.u16_at(st_offset);
            if usize::from(xyz) >= num_xyz {
                return Err(err(
                    xyz_offset,
                    Md2ErrorKind::IndexOutOfRange { what: "vertex", index: usize::from(xyz), limit: num_xyz },
                ));
            }
            if usize::from(st) >= num_st {
                return Err(err(
                    st_offset,
                    Md2ErrorKind::IndexOutOfRange {
                        what: "texture coordinate",
                        index: usize::from(st),
                        limit: num_st,
                    },
                ));
            }
            let next = vertex_xyz.len() as u32;
            let index = *welded.entry((xyz, st)).or_insert_with(|| {
                vertex_xyz.push(u32::from(xyz));
                vertex_st.push(st);
                next
            });
            indices.push(index);
        }
        // MD2 front faces are clockwise (Quake 2 culls with glFrontFace(GL_CW)); keyrig,
        // glTF and OBJ take counter-clockwise ones.
        let n = indices.len();
        indices.swap(n - 2, n - 1);
    }
    let (width, height) = (skin_width as f32, skin_height as f32);
    let texcoords = vertex_st
        .iter()
        .map(|&st| {
            let offset = ofs_st + usize::from(st) * ST_SIZE;
            Vec2::new(f32::from(bytes.i16_at(offset)) / width, f32::from(bytes.i16_at(offset + 2)) / height)
        })
        .collect();

    let mut frames = Vec::with_capacity(num_frames);
    for f in 0..num_frames {
        let base = ofs_frames + f * framesize;
        let mut scale = [0.0f32; 3];
        let mut translate = [0.0f32; 3];
        for axis in 0..3 {
            for (what, out, offset) in [
                ("frame scale", &mut scale, base + 4 * axis),
                ("frame translation", &mut translate, base + 12 + 4 * axis),
            ] {
                let value = bytes.f32_at(offset);
                if !value.is_finite() {
                    return Err(err(offset, Md2ErrorKind::NonFinite { what, value }));
                }
                out[axis] = value;
            }
        }
        let name = c_string(&data[base + 24..base + 24 + FRAME_NAME_SIZE]);
        let scale = Vec3::from_array(scale);
        let translate = Vec3::from_array(translate);
        let mut positions = Vec::with_capacity(num_xyz);
        let mut normal_indices = Vec::with_capacity(num_xyz);
        for v in 0..num_xyz {
            let offset = base + FRAME_HEADER_SIZE + v * PACKED_VERTEX_SIZE;
            let packed =
                Vec3::new(f32::from(data[offset]), f32::from(data[offset + 1]), f32::from(data[offset + 2]));
            let normal = data[offset + 3];
            if usize::from(normal) >= ANORMS.len() {
                return Err(err(offset + 3, Md2ErrorKind::NormalIndex { index: normal }));
            }
            let position = scale * packed + translate;
            if !position.is_finite() {
                return Err(err(
                    offset,
                    Md2ErrorKind::NonFinite { what: "decompressed position", value: f32::NAN },
                ));
            }
            positions.push(position);
            normal_indices.push(normal);
        }
        frames.push(Md2Frame { name, positions, normal_indices });
    }
    let clips = group_clips(&frames);
    Ok(Md2Model {
        skin_width: skin_width as u32,
        skin_height: skin_height as u32,
        skin_names,
        vertex_xyz,
        texcoords,
        indices,
        frames,
        clips,
        skin: None,
    })
}

/// A NUL-terminated string from a fixed-size field (lossy UTF-8).
fn c_string(field: &[u8]) -> String {
    let end = field.iter().position(|&b| b == 0).unwrap_or(field.len());
    String::from_utf8_lossy(&field[..end]).into_owned()
}

/// The clip name of a frame: its name without trailing digits (`run3` → `run`,
/// `crattak02` → `crattak`). A name made only of digits keeps its name.
#[must_use]
pub fn clip_name(frame_name: &str) -> &str {
    let stripped = frame_name.trim_end_matches(|c: char| c.is_ascii_digit());
    if stripped.is_empty() {
        frame_name
    } else {
        stripped
    }
}

/// Groups consecutive frames whose [`clip_name`]s are equal.
fn group_clips(frames: &[Md2Frame]) -> Vec<Md2Clip> {
    let mut clips: Vec<Md2Clip> = Vec::new();
    for (i, frame) in frames.iter().enumerate() {
        let name = clip_name(&frame.name);
        match clips.last_mut() {
            Some(clip) if clip.name == name => clip.frames.end = i + 1,
            _ => clips.push(Md2Clip { name: name.to_owned(), frames: i..i + 1 }),
        }
    }
    clips
}

impl Md2Model {
    /// Number of render vertices (welded position/texcoord pairs).
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.vertex_xyz.len()
    }

    /// Positions and normals of every render vertex in frame `frame`.
    #[must_use]
    pub fn frame_pose(&self, frame: usize) -> Option<Md2Pose> {
        let f = self.frames.get(frame)?;
        Some(Md2Pose {
            positions: self.vertex_xyz.iter().map(|&x| f.positions[x as usize]).collect(),
            normals: self.vertex_xyz.iter().map(|&x| f.normal(x as usize)).collect(),
        })
    }

    /// The clip named `name`, if any.
    #[must_use]
    pub fn clip_index(&self, name: &str) -> Option<usize> {
        self.clips.iter().position(|c| c.name == name)
    }

    /// Duration of a clip played at `fps` frames per second: `frames / fps` when looping
    /// (the last frame blends back into the first), `(frames − 1) / fps` otherwise.
    #[must_use]
    pub fn clip_duration(&self, clip: usize, fps: f64, looping: bool) -> Option<f64> {
        let n = self.clips.get(clip)?.frames.len() as f64;
        Some(if looping { n / fps } else { (n - 1.0) / fps })
    }

    /// Plays clip `clip` at `fps` frames per second: the pose at `time` seconds.
    ///
    /// Frame position `f = time · fps`; the pose is the linear blend of clip frames
    /// `⌊f⌋` and `⌊f⌋ + 1` with weight `f − ⌊f⌋` (vertex morphing), normals blended and
    /// renormalized. Looping wraps time and blends the last frame into the first; otherwise
    /// time is clamped to the clip. A pure function of its inputs.
    ///
    /// # Errors
    /// Unknown clip, non-finite or non-positive `fps`, non-finite `time`.
    pub fn sample_clip(
        &self,
        clip: usize,
        fps: f64,
        time: f64,
        looping: bool,
    ) -> Result<Md2Pose, Md2PlaybackError> {
        let range = self
            .clips
            .get(clip)
            .ok_or(Md2PlaybackError::NoSuchClip { index: clip, count: self.clips.len() })?
            .frames
            .clone();
        if !(fps.is_finite() && fps > 0.0) {
            return Err(Md2PlaybackError::BadFps(fps));
        }
        if !time.is_finite() {
            return Err(Md2PlaybackError::BadTime(time));
        }
        let n = range.len();
        let f = time * fps;
        if !f.is_finite() {
            return Err(Md2PlaybackError::BadTime(time));
        }
        let (a, b, u) = if looping {
            let f = f.rem_euclid(n as f64);
            let a = (f.floor() as usize).min(n - 1);
            (a, (a + 1) % n, (f - a as f64) as f32)
        } else {
            let f = f.clamp(0.0, (n - 1) as f64);
            let a = (f.floor() as usize).min(n - 1);
            (a, (a + 1).min(n - 1), (f - a as f64) as f32)
        };
        let fa = &self.frames[range.start + a];
        let fb = &self.frames[range.start + b];
        let mut pose = Md2Pose {
            positions: Vec::with_capacity(self.vertex_count()),
            normals: Vec::with_capacity(self.vertex_count()),
        };
        for &x in &self.vertex_xyz {
            let x = x as usize;
            pose.positions.push(fa.positions[x].lerp(fb.positions[x], u));
            pose.normals.push(fa.normal(x).lerp(fb.normal(x), u).normalize_or(fa.normal(x)));
        }
        Ok(pose)
    }
}

impl Md2Model {
    /// Frames of `clip` (every frame of the file for `None`), as a scene's
    /// `MeshSource::File { clip, .. }` names them. `None` for an unknown clip name.
    #[must_use]
    pub fn clip_frames(&self, clip: Option<&str>) -> Option<Range<usize>> {
        match clip {
            None => Some(0..self.frames.len()),
            Some(name) => self.clips.iter().find(|c| c.name == name).map(|c| c.frames.clone()),
        }
    }

    /// The model's frames and clips as the scene evaluator plays them (keyrig-eval's
    /// [`keyrig_eval::morph::MorphClips`]: looping, `f = (time · fps) mod n`, frames `⌊f⌋` and
    /// `⌊f⌋ + 1`, weight `f − ⌊f⌋`) — the one playback rule of the editor, `render`, `deform`
    /// and export.
    ///
    /// # Errors
    /// A model without frames, or a clip outside them.
    pub fn playback(&self) -> Result<keyrig_eval::morph::MorphClips, keyrig_eval::morph::MorphError> {
        keyrig_eval::morph::MorphClips::new(
            self.frames.len(),
            self.clips
                .iter()
                .map(|c| keyrig_eval::morph::MorphClip { name: c.name.clone(), frames: c.frames.clone() })
                .collect(),
        )
    }

    /// Positions of every render vertex blended between frames `a` and `b` with weight `t` of
    /// `b` (as the renderer's CPU morph: `lerp(a, b, t)`).
    #[must_use]
    pub fn blended_positions(&self, a: usize, b: usize, t: f32) -> Option<Vec<Vec3>> {
        let (fa, fb) = (self.frames.get(a)?, self.frames.get(b)?);
        self.vertex_xyz
            .iter()
            .map(|&x| Some(fa.positions.get(x as usize)?.lerp(*fb.positions.get(x as usize)?, t)))
            .collect()
    }
}

/// MD2 models are Z-up in Quake units; keyrig scenes are Y-up in metres. An MD2 object gets
/// this rotation (−90° about X: Quake's +Z becomes +Y, its +X stays +X and its +Y becomes −Z)
/// and [`MD2_SCALE`] as its own (editable) transform; the file's vertices are not changed.
#[must_use]
pub fn md2_rotation() -> glam::Quat {
    glam::Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2)
}

/// Metres per Quake unit. Quake 2 player models are about 56 units tall, so one unit as an
/// inch (0.0254 m) makes them about 1.4 m tall, next to a 1.6 m demo arm.
pub const MD2_SCALE: f32 = 0.0254;

/// The last frame of a range starting at 0 that shows `seconds` of looping animation at
/// `fps` timeline frames per second (the frame after it is the loop's first again).
#[must_use]
pub fn frame_range_end(seconds: f64, fps: f64) -> i32 {
    let frames = (seconds * fps).round() - 1.0;
    if frames.is_finite() {
        frames.clamp(1.0, 1e6) as i32
    } else {
        60
    }
}

/// An MD2 model as a scene of its own, as the editor opens it: one object named `name` whose
/// mesh is `MeshSource::File { path: file }` playing every frame at
/// [`keyrig_core::MD2_DEFAULT_FPS`], turned Y-up and scaled to metres ([`md2_rotation`],
/// [`MD2_SCALE`]) and raised so that its first frame stands on the ground; the frame range
/// covers one loop of it. (No camera framing and no light: the editor adds those.)
#[must_use]
pub fn md2_scene(model: &Md2Model, file: &str, name: &str) -> keyrig_core::Scene {
    let mut scene = keyrig_core::Scene::default();
    let mut object = keyrig_core::Object::new(name);
    object.mesh = Some(keyrig_core::MeshSource::File {
        path: file.to_owned(),
        mesh: None,
        clip: None,
        fps: Some(keyrig_core::MD2_DEFAULT_FPS),
    });
    object.rotation = keyrig_core::Animated::constant(md2_rotation());
    object.scale = keyrig_core::Animated::constant(Vec3::splat(MD2_SCALE));
    // Quake models have their origin near the waist: stand the first frame on the ground (its
    // lowest Quake Z at world height 0).
    let lowest = model
        .frames
        .first()
        .map(|f| model.vertex_xyz.iter().map(|&x| f.positions[x as usize].z).fold(f32::INFINITY, f32::min))
        .unwrap_or(f32::INFINITY);
    if lowest.is_finite() {
        object.translation = keyrig_core::Animated::constant(Vec3::Y * (-lowest * MD2_SCALE));
    }
    scene.objects.push(object);
    let seconds = model.frames.len() as f64 / keyrig_core::MD2_DEFAULT_FPS;
    scene.frame_range.end = frame_range_end(seconds, scene.fps);
    scene
}

/// Image extensions looked for as skins, in order of preference.
const SKIN_EXTENSIONS: [&str; 4] = ["png", "bmp", "jpg", "jpeg"];

/// Finds the skin image of the MD2 file at `md2_path`, looking in its folder and in a
/// `skins/` folder beside it, in this order:
/// 1. the file names stored in the header (any folder part dropped), with their own
///    extension or with one of png, bmp, jpg, jpeg (Quake 2 stored `.pcx`);
/// 2. the model's own name with those extensions;
/// 3. the only image in the folder (or in `skins/`), when there is exactly one.
#[must_use]
pub fn find_skin(md2_path: &Path, skin_names: &[String]) -> Option<PathBuf> {
    // A bare file name's parent is the empty path, which `read_dir` refuses: use `.`.
    let dir = crate::file_io::parent_or_dot(md2_path);
    let folders = [dir.to_path_buf(), dir.join("skins")];
    let mut stems: Vec<String> = Vec::new();
    for name in skin_names {
        let base = name.rsplit(['/', '\\']).next().unwrap_or(name);
        if base.is_empty() {
            continue;
        }
        for folder in &folders {
            let candidate = folder.join(base);
            if candidate.is_file() && has_image_extension(&candidate) {
                return Some(candidate);
            }
        }
        let stem = Path::new(base).file_stem().and_then(|s| s.to_str()).unwrap_or(base);
        stems.push(stem.to_owned());
    }
    if let Some(stem) = md2_path.file_stem().and_then(|s| s.to_str()) {
        stems.push(stem.to_owned());
    }
    for stem in &stems {
        for folder in &folders {
            for ext in SKIN_EXTENSIONS {
                let candidate = folder.join(format!("{stem}.{ext}"));
                if candidate.is_file() {
                    return Some(candidate);
                }
            }
        }
    }
    for folder in &folders {
        let Ok(entries) = std::fs::read_dir(folder) else { continue };
        let images: Vec<PathBuf> = entries
            .filter_map(|e| e.ok().map(|e| e.path()))
            .filter(|p| p.is_file() && has_image_extension(p))
            .collect();
        if images.len() == 1 {
            return images.into_iter().next();
        }
    }
    None
}

/// The skin image [`load_md2_file`] would load for the MD2 file at `path` (without decoding
/// it); `None` when the file cannot be read or parsed or has no skin beside it.
#[must_use]
pub fn skin_of_file(path: &Path) -> Option<PathBuf> {
    let data = crate::file_io::read_regular_file(path, crate::file_io::MAX_MD2_BYTES).ok()?;
    let model = parse_md2(&data).ok()?;
    find_skin(path, &model.skin_names)
}

fn has_image_extension(path: &Path) -> bool {
    path.extension()
        .and_then(|e| e.to_str())
        .is_some_and(|e| SKIN_EXTENSIONS.iter().any(|s| s.eq_ignore_ascii_case(e)))
}

/// Reads and parses the MD2 file at `path` and loads its skin image when one is found next
/// to it ([`find_skin`]).
///
/// # Errors
/// The file cannot be read, is malformed ([`Md2Error`] with the byte offset), or its skin
/// image exists but cannot be decoded.
pub fn load_md2_file(path: &Path) -> Result<Md2Model, Md2LoadError> {
    let data = crate::file_io::read_regular_file(path, crate::file_io::MAX_MD2_BYTES)
        .map_err(|source| Md2LoadError::Io { path: path.to_path_buf(), source })?;
    let mut model =
        parse_md2(&data).map_err(|source| Md2LoadError::Format { path: path.to_path_buf(), source })?;
    model.skin = load_skin(path, &model.skin_names)?;
    Ok(model)
}

/// Finds ([`find_skin`]) and decodes the skin image of the MD2 file at `md2_path` whose header
/// names `skin_names`; `None` when there is none beside it.
///
/// # Errors
/// [`Md2LoadError::Skin`] when the image exists but cannot be decoded.
pub fn load_skin(md2_path: &Path, skin_names: &[String]) -> Result<Option<Md2Skin>, Md2LoadError> {
    let Some(skin_path) = find_skin(md2_path, skin_names) else { return Ok(None) };
    let image = image::open(&skin_path)
        .map_err(|source| Md2LoadError::Skin { path: skin_path.clone(), source })?
        .to_rgba8();
    Ok(Some(Md2Skin {
        path: skin_path,
        width: image.width(),
        height: image.height(),
        rgba: image.into_raw(),
    }))
}

impl Md2Skin {
    /// The skin as a material: white base colour times the skin, sampled with
    /// [`keyrig_core::Sampler::default`] (repeat, linear, mipmapped); `None` for an image
    /// without pixels.
    #[must_use]
    pub fn material(&self) -> Option<keyrig_core::Material> {
        let image = keyrig_core::TextureImage::new(
            self.width,
            self.height,
            self.rgba.clone(),
            keyrig_core::Sampler::default(),
        )
        .ok()?;
        Some(keyrig_core::Material {
            base_colour: [1.0; 4],
            base_colour_texture: Some(std::sync::Arc::new(image)),
        })
    }
}

/// The 162 unit normals MD2 vertices index (Quake 2's `anorms.h`, the vertices of a
/// subdivided icosahedron), in Quake's axes.
pub const ANORMS: [[f32; 3]; 162] = [
    [-0.525731, 0.000000, 0.850651],
    [-0.442863, 0.238856, 0.864188],
    [-0.295242, 0.000000, 0.955423],
    [-0.309017, 0.500000, 0.809017],
    [-0.162460, 0.262866, 0.951056],
    [0.000000, 0.000000, 1.000000],
    [0.000000, 0.850651, 0.525731],
    [-0.147621, 0.716567, 0.681718],
    [0.147621, 0.716567, 0.681718],
    [0.000000, 0.525731, 0.850651],
    [0.309017, 0.500000, 0.809017],
    [0.525731, 0.000000, 0.850651],
    [0.295242, 0.000000, 0.955423],
    [0.442863, 0.238856, 0.864188],
    [0.162460, 0.262866, 0.951056],
    [-0.681718, 0.147621, 0.716567],
    [-0.809017, 0.309017, 0.500000],
    [-0.587785, 0.425325, 0.688191],
    [-0.850651, 0.525731, 0.000000],
    [-0.864188, 0.442863, 0.238856],
    [-0.716567, 0.681718, 0.147621],
    [-0.688191, 0.587785, 0.425325],
    [-0.500000, 0.809017, 0.309017],
    [-0.238856, 0.864188, 0.442863],
    [-0.425325, 0.688191, 0.587785],
    [-0.716567, 0.681718, -0.147621],
    [-0.500000, 0.809017, -0.309017],
    [-0.525731, 0.850651, 0.000000],
    [0.000000, 0.850651, -0.525731],
    [-0.238856, 0.864188, -0.442863],
    [0.000000, 0.955423, -0.295242],
    [-0.262866, 0.951056, -0.162460],
    [0.000000, 1.000000, 0.000000],
    [0.000000, 0.955423, 0.295242],
    [-0.262866, 0.951056, 0.162460],
    [0.238856, 0.864188, 0.442863],
    [0.262866, 0.951056, 0.162460],
    [0.500000, 0.809017, 0.309017],
    [0.238856, 0.864188, -0.442863],
    [0.262866, 0.951056, -0.162460],
    [0.500000, 0.809017, -0.309017],
    [0.850651, 0.525731, 0.000000],
    [0.716567, 0.681718, 0.147621],
    [0.716567, 0.681718, -0.147621],
    [0.525731, 0.850651, 0.000000],
    [0.425325, 0.688191, 0.587785],
    [0.864188, 0.442863, 0.238856],
    [0.688191, 0.587785, 0.425325],
    [0.809017, 0.309017, 0.500000],
    [0.681718, 0.147621, 0.716567],
    [0.587785, 0.425325, 0.688191],
    [0.955423, 0.295242, 0.000000],
    [1.000000, 0.000000, 0.000000],
    [0.951056, 0.162460, 0.262866],
    [0.850651, -0.525731, 0.000000],
    [0.955423, -0.295242, 0.000000],
    [0.864188, -0.442863, 0.238856],
    [0.951056, -0.162460, 0.262866],
    [0.809017, -0.309017, 0.500000],
    [0.681718, -0.147621, 0.716567],
    [0.850651, 0.000000, 0.525731],
    [0.864188, 0.442863, -0.238856],
    [0.809017, 0.309017, -0.500000],
    [0.951056, 0.162460, -0.262866],
    [0.525731, 0.000000, -0.850651],
    [0.681718, 0.147621, -0.716567],
    [0.681718, -0.147621, -0.716567],
    [0.850651, 0.000000, -0.525731],
    [0.809017, -0.309017, -0.500000],
    [0.864188, -0.442863, -0.238856],
    [0.951056, -0.162460, -0.262866],
    [0.147621, 0.716567, -0.681718],
    [0.309017, 0.500000, -0.809017],
    [0.425325, 0.688191, -0.587785],
    [0.442863, 0.238856, -0.864188],
    [0.587785, 0.425325, -0.688191],
    [0.688191, 0.587785, -0.425325],
    [-0.147621, 0.716567, -0.681718],
    [-0.309017, 0.500000, -0.809017],
    [0.000000, 0.525731, -0.850651],
    [-0.525731, 0.000000, -0.850651],
    [-0.442863, 0.238856, -0.864188],
    [-0.295242, 0.000000, -0.955423],
    [-0.162460, 0.262866, -0.951056],
    [0.000000, 0.000000, -1.000000],
    [0.295242, 0.000000, -0.955423],
    [0.162460, 0.262866, -0.951056],
    [-0.442863, -0.238856, -0.864188],
    [-0.309017, -0.500000, -0.809017],
    [-0.162460, -0.262866, -0.951056],
    [0.000000, -0.850651, -0.525731],
    [-0.147621, -0.716567, -0.681718],
    [0.147621, -0.716567, -0.681718],
    [0.000000, -0.525731, -0.850651],
    [0.309017, -0.500000, -0.809017],
    [0.442863, -0.238856, -0.864188],
    [0.162460, -0.262866, -0.951056],
    [0.238856, -0.864188, -0.442863],
    [0.500000, -0.809017, -0.309017],
    [0.425325, -0.688191, -0.587785],
    [0.716567, -0.681718, -0.147621],
    [0.688191, -0.587785, -0.425325],
    [0.587785, -0.425325, -0.688191],
    [0.000000, -0.955423, -0.295242],
    [0.000000, -1.000000, 0.000000],
    [0.262866, -0.951056, -0.162460],
    [0.000000, -0.850651, 0.525731],
    [0.000000, -0.955423, 0.295242],
    [0.238856, -0.864188, 0.442863],
    [0.262866, -0.951056, 0.162460],
    [0.500000, -0.809017, 0.309017],
    [0.716567, -0.681718, 0.147621],
    [0.525731, -0.850651, 0.000000],
    [-0.238856, -0.864188, -0.442863],
    [-0.500000, -0.809017, -0.309017],
    [-0.262866, -0.951056, -0.162460],
    [-0.850651, -0.525731, 0.000000],
    [-0.716567, -0.681718, -0.147621],
    [-0.716567, -0.681718, 0.147621],
    [-0.525731, -0.850651, 0.000000],
    [-0.500000, -0.809017, 0.309017],
    [-0.238856, -0.864188, 0.442863],
    [-0.262866, -0.951056, 0.162460],
    [-0.864188, -0.442863, 0.238856],
    [-0.809017, -0.309017, 0.500000],
    [-0.688191, -0.587785, 0.425325],
    [-0.681718, -0.147621, 0.716567],
    [-0.442863, -0.238856, 0.864188],
    [-0.587785, -0.425325, 0.688191],
    [-0.309017, -0.500000, 0.809017],
    [-0.147621, -0.716567, 0.681718],
    [-0.425325, -0.688191, 0.587785],
    [-0.162460, -0.262866, 0.951056],
    [0.442863, -0.238856, 0.864188],
    [0.162460, -0.262866, 0.951056],
    [0.309017, -0.500000, 0.809017],
    [0.147621, -0.716567, 0.681718],
    [0.000000, -0.525731, 0.850651],
    [0.425325, -0.688191, 0.587785],
    [0.587785, -0.425325, 0.688191],
    [0.688191, -0.587785, 0.425325],
    [-0.955423, 0.295242, 0.000000],
    [-0.951056, 0.162460, 0.262866],
    [-1.000000, 0.000000, 0.000000],
    [-0.850651, 0.000000, 0.525731],
    [-0.955423, -0.295242, 0.000000],
    [-0.951056, -0.162460, 0.262866],
    [-0.864188, 0.442863, -0.238856],
    [-0.951056, 0.162460, -0.262866],
    [-0.809017, 0.309017, -0.500000],
    [-0.864188, -0.442863, -0.238856],
    [-0.951056, -0.162460, -0.262866],
    [-0.809017, -0.309017, -0.500000],
    [-0.681718, 0.147621, -0.716567],
    [-0.681718, -0.147621, -0.716567],
    [-0.850651, 0.000000, -0.525731],
    [-0.688191, 0.587785, -0.425325],
    [-0.587785, 0.425325, -0.688191],
    [-0.425325, 0.688191, -0.587785],
    [-0.425325, -0.688191, -0.587785],
    [-0.587785, -0.425325, -0.688191],
    [-0.688191, -0.587785, -0.425325],
];

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn clip_names_strip_trailing_digits() {
        assert_eq!(clip_name("run12"), "run");
        assert_eq!(clip_name("crattak02"), "crattak");
        assert_eq!(clip_name("stand"), "stand");
        assert_eq!(clip_name("007"), "007");
    }

    #[test]
    fn anorms_are_unit() {
        for (i, n) in ANORMS.iter().enumerate() {
            let len = Vec3::from_array(*n).length();
            assert!((len - 1.0).abs() < 1e-5, "entry {i} has length {len}");
        }
    }
}
