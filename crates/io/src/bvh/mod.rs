//! BVH (Biovision Hierarchy) motion capture: read a `.bvh` file into a keyrig
//! [`keyrig_core::Scene`] and write one object's skeleton and animation back as BVH
//! (docs/interchange.md, "BVH motion capture").
//!
//! - [`parse_bvh`] / [`read_bvh_file`] read the text into a [`BvhFile`]: the joint tree
//!   (ROOT, JOINT, End Site, OFFSET, CHANNELS with 0–6 channels in any order) and the MOTION
//!   values, one row of `channel_count` values per frame.
//! - [`BvhFile::to_scene`] maps it onto a scene; [`import_scene`] does both for a path.
//! - [`export_scene`] / [`write_bvh`] write an object with a skeleton.
//!
//! **Rotations.** A joint's rotation channels listed as `Zrotation Xrotation Yrotation` mean
//! the local rotation `R = Rz·Rx·Ry` (column vectors, the matrices multiplied in the order
//! listed: the last listed axis turns first). keyrig's Euler orders name the axis that turns
//! first (`XYZ` is `R = Rz·Ry·Rx`, [`keyrig_core::rotation_mode`]), so the keyrig order is the
//! BVH listing reversed: `Zrotation Xrotation Yrotation` is keyrig's `YXZ`, `Zrotation
//! Yrotation Xrotation` (the CMU files) keyrig's `XYZ`. Each joint keeps its order as its
//! `rotation_mode` and its angles as Euler keys (`rotation_euler`, degrees, one Linear key per
//! frame), so the file's angles are kept exactly, unwrapped or not.
//!
//! **Transforms.** A joint's local transform is `translate(OFFSET + position channels) ·
//! R`; in keyrig that is the joint's rest translation (OFFSET, rest rotation identity) and its
//! animated translation (the position channels, keyed) and rotation. End Sites become tip
//! joints named `<parent>_end` with the End Site's OFFSET and no keys, so every bone has an
//! end to draw to.
//!
//! The file is untrusted: every error names the file, the line and column and the problem
//! ([`BvhError`]); values must be finite and within ±[`MAX_ABS_VALUE`]; the declared frame
//! count is checked against the bytes that follow it before anything is allocated for it; the
//! hierarchy is read without recursion.

mod export;
mod parse;

use std::fmt;
use std::path::{Path, PathBuf};

use glam::{Quat, Vec3};
use keyrig_core::{
    Animated, EulerOrder, Interpolation, Joint, Key, Object, RawTrack, RotationMode, Scene, Skeleton,
};

pub use export::{bvh_text, export_scene, write_bvh, ExportTarget};

/// Largest BVH file keyrig reads: 1 GiB (a one-hour, 120 fps, 31-joint take is about 400 MB).
pub const MAX_BVH_BYTES: u64 = crate::file_io::MAX_MODEL_BYTES;

/// Largest magnitude of any value of the file (OFFSETs, positions, angles in degrees). Beyond
/// it an f32 keeps less than a tenth of a unit (or degree), and no capture is that large: such
/// a value is taken for a broken file.
pub const MAX_ABS_VALUE: f32 = 1.0e6;

/// Shortest frame time read: a microsecond (a million frames per second).
pub const MIN_FRAME_TIME: f64 = 1.0e-6;
/// Longest frame time read: an hour.
pub const MAX_FRAME_TIME: f64 = 3600.0;

/// One channel of a joint.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum BvhChannel {
    Xposition,
    Yposition,
    Zposition,
    Xrotation,
    Yrotation,
    Zrotation,
}

impl BvhChannel {
    /// The channel of a name of the file (case-sensitive, as written by every exporter).
    #[must_use]
    pub fn from_name(name: &str) -> Option<Self> {
        Some(match name {
            "Xposition" => BvhChannel::Xposition,
            "Yposition" => BvhChannel::Yposition,
            "Zposition" => BvhChannel::Zposition,
            "Xrotation" => BvhChannel::Xrotation,
            "Yrotation" => BvhChannel::Yrotation,
            "Zrotation" => BvhChannel::Zrotation,
            _ => return None,
        })
    }

    /// The name as the file writes it.
    #[must_use]
    pub fn name(self) -> &'static str {
        match self {
            BvhChannel::Xposition => "Xposition",
            BvhChannel::Yposition => "Yposition",
            BvhChannel::Zposition => "Zposition",
            BvhChannel::Xrotation => "Xrotation",
            BvhChannel::Yrotation => "Yrotation",
            BvhChannel::Zrotation => "Zrotation",
        }
    }

    /// The axis (0 = X, 1 = Y, 2 = Z) and whether it is a rotation.
    #[must_use]
    pub fn axis(self) -> (usize, bool) {
        match self {
            BvhChannel::Xposition => (0, false),
            BvhChannel::Yposition => (1, false),
            BvhChannel::Zposition => (2, false),
            BvhChannel::Xrotation => (0, true),
            BvhChannel::Yrotation => (1, true),
            BvhChannel::Zrotation => (2, true),
        }
    }
}

/// A joint of the hierarchy (or an End Site), in the file's order: parents first.
#[derive(Clone, Debug, PartialEq)]
pub struct BvhJoint {
    /// The name after ROOT or JOINT (the rest of its line, trimmed); empty for an End Site.
    pub name: String,
    pub parent: Option<usize>,
    pub offset: Vec3,
    /// The channels in the order listed.
    pub channels: Vec<BvhChannel>,
    /// Column of the joint's first channel in a frame's row.
    pub first_channel: usize,
    /// An End Site (no name, no channels).
    pub end_site: bool,
    /// 1-based line of the joint's keyword.
    pub line: usize,
    channels_read: bool,
}

impl BvhJoint {
    fn new(name: String, parent: Option<usize>, end_site: bool, line: usize) -> Self {
        BvhJoint {
            name,
            parent,
            offset: Vec3::ZERO,
            channels: Vec::new(),
            first_channel: 0,
            end_site,
            line,
            channels_read: false,
        }
    }

    /// The keyrig Euler order of the rotation channels (the listing reversed, module
    /// documentation); axes the joint has no channel for are placed after the listed ones
    /// (their angle is zero, so any place gives the same rotation). `None` without rotation
    /// channels.
    #[must_use]
    pub fn euler_order(&self) -> Option<EulerOrder> {
        let listed: Vec<usize> = self
            .channels
            .iter()
            .filter_map(|c| matches!(c.axis(), (_, true)).then_some(c.axis().0))
            .collect();
        if listed.is_empty() {
            return None;
        }
        // Turn order: the listing reversed, then the missing axes.
        let mut turns: Vec<usize> = listed.iter().rev().copied().collect();
        for axis in 0..3 {
            if !turns.contains(&axis) {
                turns.push(axis);
            }
        }
        EulerOrder::ALL.into_iter().find(|o| o.axes().as_slice() == turns.as_slice())
    }

    /// Whether the joint has position channels.
    #[must_use]
    pub fn has_position(&self) -> bool {
        self.channels.iter().any(|c| !c.axis().1)
    }
}

/// A whole BVH file.
#[derive(Clone, Debug, PartialEq)]
pub struct BvhFile {
    pub joints: Vec<BvhJoint>,
    /// `Frames:`.
    pub frames: usize,
    /// `Frame Time:` in seconds, as written.
    pub frame_time: f64,
    /// The frame rate the scene gets: `1 / frame_time`, or the whole number of frames per
    /// second whose frame time, rounded to the digits the file wrote, is the file's
    /// (`0.0083333` → 120; [`fps_of_frame_time`]).
    pub fps: f64,
    /// Values per frame (the CHANNELS of every joint added up).
    pub channel_count: usize,
    /// `frames × channel_count` values, frame after frame.
    pub values: Vec<f32>,
}

/// Where an error is.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Place {
    /// 1-based line.
    pub line: usize,
    /// 1-based column in characters.
    pub column: usize,
}

/// What is wrong.
#[derive(Debug, thiserror::Error)]
pub enum BvhErrorKind {
    #[error("cannot read: {0}")]
    Read(std::io::Error),
    #[error("not UTF-8 text: {0}")]
    NotUtf8(String),
    #[error("{0}")]
    Syntax(String),
    /// A non-finite or absurd number, a frame time out of range.
    #[error("{0}")]
    Value(String),
    /// The file ends early, or declares more than it holds.
    #[error("truncated: {0}")]
    Truncated(String),
    #[error("{0}")]
    Limit(String),
    #[error("{0}")]
    Unsupported(String),
    /// Export: the object cannot be written (no such object, no skeleton, a bad scene).
    #[error("{0}")]
    Export(String),
    /// Export: a value to write lies beyond ±[`MAX_ABS_VALUE`], which BVH readers (keyrig's
    /// among them) refuse.
    #[error("{0}")]
    OutOfRange(String),
    /// Export: the output would replace an input.
    #[error(transparent)]
    Overwrite(#[from] crate::file_io::OverwriteInputError),
    #[error("cannot write: {0}")]
    Write(std::io::Error),
}

/// A BVH import or export error: the file, where in it, and what.
#[derive(Debug, thiserror::Error)]
pub struct BvhError {
    pub file: Option<PathBuf>,
    pub place: Option<Place>,
    pub kind: BvhErrorKind,
}

impl fmt::Display for BvhError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        if let Some(file) = &self.file {
            write!(f, "{}:", file.display())?;
            if let Some(p) = self.place {
                write!(f, "{}:{}", p.line, p.column)?;
            }
            write!(f, ": ")?;
        } else if let Some(p) = self.place {
            write!(f, "line {}, column {}: ", p.line, p.column)?;
        }
        write!(f, "{}", self.kind)
    }
}

impl BvhError {
    fn whole(file: Option<&Path>, kind: BvhErrorKind) -> Self {
        BvhError { file: file.map(Path::to_path_buf), place: None, kind }
    }
}

/// Whether `path` names a BVH file (extension `.bvh`, any case).
#[must_use]
pub fn is_bvh_path(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("bvh"))
}

/// The scene frame rate of a frame time written as `written`: the whole number `n` of frames
/// per second when `1/n`, rounded to as many decimals as the file wrote, is the file's value
/// (`0.0083333` → 120, `.033333` → 30: exporters print `1/n` to a few digits), else
/// `1 / frame_time` (`0.0333667` → 29.97…).
#[must_use]
pub fn fps_of_frame_time(frame_time: f64, written: &str) -> f64 {
    let fps = 1.0 / frame_time;
    let n = fps.round();
    if n < 1.0 {
        return fps;
    }
    let mantissa = written.split(['e', 'E']).next().unwrap_or("");
    let has_exponent = mantissa.len() != written.len();
    let decimals = mantissa.split_once('.').map_or(0, |(_, d)| d.len()).min(17) as i32;
    let tolerance = if has_exponent { 1e-6 * frame_time } else { 0.5 * 10f64.powi(-decimals) };
    if (1.0 / n - frame_time).abs() <= tolerance.max(1e-15 * frame_time) {
        n
    } else {
        fps
    }
}

/// Reads BVH text (`file` names it in errors).
///
/// # Errors
/// The text is not a valid BVH file ([`BvhError`] with the line and column).
pub fn parse_bvh(text: &str, file: Option<&Path>) -> Result<BvhFile, BvhError> {
    parse::parse(text, file)
}

/// Reads BVH bytes: UTF-8 text (a byte-order mark allowed), then [`parse_bvh`].
///
/// # Errors
/// Not UTF-8, or not a valid BVH file.
pub fn parse_bvh_bytes(bytes: &[u8], file: Option<&Path>) -> Result<BvhFile, BvhError> {
    let text = std::str::from_utf8(bytes).map_err(|e| {
        let at = e.valid_up_to();
        let before = String::from_utf8_lossy(&bytes[..at]);
        let line = before.matches('\n').count() + 1;
        let column = before.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        BvhError {
            file: file.map(Path::to_path_buf),
            place: Some(Place { line, column }),
            kind: BvhErrorKind::NotUtf8(format!("byte 0x{:02x} does not begin a UTF-8 character", bytes[at])),
        }
    })?;
    parse_bvh(text, file)
}

/// Reads the BVH file at `path` (a regular file of at most [`MAX_BVH_BYTES`]).
///
/// # Errors
/// The file cannot be read or is not a valid BVH file.
pub fn read_bvh_file(path: &Path) -> Result<BvhFile, BvhError> {
    let bytes = crate::file_io::read_regular_file(path, MAX_BVH_BYTES)
        .map_err(|e| BvhError::whole(Some(path), BvhErrorKind::Read(e)))?;
    parse_bvh_bytes(&bytes, Some(path))
}

/// Reads the BVH file at `path` and maps it onto a scene ([`BvhFile::to_scene`]), the object
/// named after the file.
///
/// # Errors
/// As [`read_bvh_file`].
pub fn import_scene(path: &Path) -> Result<Scene, BvhError> {
    let file = read_bvh_file(path)?;
    let name = path.file_stem().map(|s| s.to_string_lossy().into_owned()).unwrap_or_default();
    Ok(file.to_scene(&name))
}

/// A name keyrig accepts (not empty, no `/`), unique among `taken`.
fn scene_name(wanted: &str, fallback: &str, taken: &mut std::collections::HashSet<String>) -> String {
    let base = if wanted.is_empty() { fallback.to_owned() } else { wanted.replace('/', "_") };
    let mut name = base.clone();
    let mut n = 2usize;
    while taken.contains(&name) {
        name = format!("{base}.{n}");
        n += 1;
    }
    taken.insert(name.clone());
    name
}

/// Suffix of the tip joints End Sites become: `<parent>_end`.
pub const END_SITE_SUFFIX: &str = "_end";

impl BvhFile {
    /// The value of frame `frame`, column `column`.
    #[must_use]
    pub fn value(&self, frame: usize, column: usize) -> f32 {
        self.values[frame * self.channel_count + column]
    }

    /// A joint's (x, y, z) of its position (`rotation` false) or rotation channels at a frame;
    /// axes without a channel are 0.
    #[must_use]
    pub fn joint_values(&self, joint: usize, frame: usize, rotation: bool) -> Vec3 {
        let j = &self.joints[joint];
        let mut v = Vec3::ZERO;
        for (k, c) in j.channels.iter().enumerate() {
            let (axis, is_rotation) = c.axis();
            if is_rotation == rotation {
                v[axis] = self.value(frame, j.first_channel + k);
            }
        }
        v
    }

    /// The scene of this file: one object named `name` (the file's stem; `"BVH"` when empty)
    /// holding the skeleton, no mesh; fps from the frame time ([`BvhFile::fps`]); frames 0 to
    /// `frames − 1`.
    ///
    /// Each joint: rest translation = OFFSET, rest rotation identity; rotation channels →
    /// `rotation_mode` Euler in the order they make (module documentation) with Euler keys in
    /// degrees, one Linear key per frame at `frame / fps` seconds; position channels →
    /// translation keys (Linear, added to the rest translation). End Sites → tip joints
    /// `<parent>_end`. Names are made valid and unique (`/` → `_`, an empty name `joint<i>`, a
    /// repeated name gets `.2`, `.3`, …).
    #[must_use]
    pub fn to_scene(&self, name: &str) -> Scene {
        let (mut rotations, mut positions) = self.tracks();
        let mut taken = std::collections::HashSet::new();
        let mut joints = Vec::with_capacity(self.joints.len());
        for (i, j) in self.joints.iter().enumerate() {
            let wanted = if j.end_site {
                format!("{}{END_SITE_SUFFIX}", j.parent.map_or("", |p| joints_name(&joints, p)))
            } else {
                j.name.clone()
            };
            let name = scene_name(&wanted, &format!("joint{i}"), &mut taken);
            let mut joint = Joint::new(name, j.parent, j.offset, Quat::IDENTITY);
            if let Some(order) = j.euler_order() {
                joint.rotation_mode = RotationMode::Euler(order);
                if let Some(euler) = rotations[i].take().map(animated) {
                    joint.rotation = Animated::constant(order.to_quat(euler.value));
                    joint.rotation_euler = Some(euler);
                }
            }
            if let Some(translation) = positions[i].take().map(animated) {
                joint.translation = translation;
            }
            joints.push(joint);
        }
        let mut object = Object::new(scene_name(name, "BVH", &mut std::collections::HashSet::new()));
        object.skeleton = Some(Skeleton::new(joints));
        let last = self.frames.saturating_sub(1).min(i32::MAX as usize) as i32;
        Scene {
            fps: self.fps,
            frame_range: keyrig_core::FrameRange { start: 0, end: last },
            objects: vec![object],
            ..Scene::default()
        }
    }

    /// Per joint, one Linear key per frame of its rotation channels and of its position
    /// channels (`None` for a joint without such channels, or without frames). One pass over
    /// the frames, each row read once (reading a joint's columns frame after frame for each
    /// joint in turn went over the whole data once per track).
    #[allow(clippy::type_complexity)]
    fn tracks(&self) -> (Vec<Option<Vec<Key<Vec3>>>>, Vec<Option<Vec<Key<Vec3>>>>) {
        let with = |wanted: bool| (wanted && self.frames > 0).then(|| Vec::with_capacity(self.frames));
        let mut rotations: Vec<Option<Vec<Key<Vec3>>>> =
            self.joints.iter().map(|j| with(j.euler_order().is_some())).collect();
        let mut positions: Vec<Option<Vec<Key<Vec3>>>> =
            self.joints.iter().map(|j| with(j.has_position())).collect();
        let key = |time: f64, value: Vec3| Key::new(time, value).with_interpolation(Interpolation::Linear);
        // Without channels there is nothing to read per frame (and `Frames:` may say 2³¹ − 1).
        let frames = if self.channel_count == 0 { 0 } else { self.frames };
        for frame in 0..frames {
            let time = frame as f64 / self.fps;
            for (i, (r, p)) in rotations.iter_mut().zip(positions.iter_mut()).enumerate() {
                if let Some(keys) = r {
                    keys.push(key(time, self.joint_values(i, frame, true)));
                }
                if let Some(keys) = p {
                    keys.push(key(time, self.joint_values(i, frame, false)));
                }
            }
        }
        (rotations, positions)
    }
}

/// Keys as an animated value whose static value is the first key's.
fn animated(keys: Vec<Key<Vec3>>) -> Animated<Vec3> {
    let first = keys.first().map_or(Vec3::ZERO, |k| k.value);
    Animated::new(first, RawTrack::new(keys))
}

fn joints_name(joints: &[Joint], j: usize) -> &str {
    joints.get(j).map_or("", |j| j.name.as_str())
}

#[cfg(test)]
mod tests;
