//! RON scene files: versioned, strictly checked, saved atomically (docs/design.md §8).
//!
//! A scene file is one RON struct with the format version first and the scene second:
//!
//! ```ron
//! (
//!     version: 4,
//!     scene: (
//!         fps: 30.0,
//!         frame_range: (start: 0, end: 60),
//!         …
//!     ),
//! )
//! ```
//!
//! Loading ([`load`], [`from_str`]):
//! 1. the version is read first; a newer version is refused ([`SceneFileError::TooNew`]), an
//!    older one goes through [`migrate`];
//! 2. the document is deserialized with unknown fields rejected;
//! 3. the scene is checked with [`Scene::problems`] (non-finite numbers, bad joint parents,
//!    unsorted keys, …) and every problem is reported with its field path and the line and
//!    column of that field in the file.
//!
//! Saving ([`save`]) refuses a scene with problems and refuses to overwrite a file written
//! by a newer keyrig; it writes a temporary file in the same folder, syncs it, keeps the
//! previous file as `<name>.ron.bak` and renames the temporary file over the target, so the
//! target is always either the old or the new complete file. The text is pretty RON with a
//! fixed configuration and floats in their shortest round-trip form, so save → load → save
//! gives identical bytes.

use std::fmt;
use std::fs;
use std::io::{self, Write};
use std::path::{Path, PathBuf};

use keyrig_core::{Problem, Scene};
use serde::{Deserialize, Serialize};

use crate::file_io::{read_regular_file, AtomicFile, MAX_SCENE_BYTES};
use crate::scene_locate::{locate, TextPosition};
use crate::scene_text::to_ron;

/// The scene format version this keyrig writes and reads without migration.
pub const CURRENT_VERSION: u32 = 4;

/// Oldest version [`migrate`] can bring up to [`CURRENT_VERSION`].
pub const OLDEST_SUPPORTED_VERSION: u32 = 1;

/// A problem of a loaded scene and where it is in the file (when it could be located).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct LocatedProblem {
    pub problem: Problem,
    /// 1-based line and column of the field's value in the file; `None` for scenes that did
    /// not come from text, or fields the file leaves to their defaults and whose parents
    /// could not be found.
    pub position: Option<(usize, usize)>,
}

impl fmt::Display for LocatedProblem {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self.position {
            Some((line, column)) => write!(f, "{line}:{column}: {}", self.problem),
            None => write!(f, "{}", self.problem),
        }
    }
}

/// Everything that can go wrong reading or writing a scene file. Every variant names the file.
#[derive(Debug, thiserror::Error)]
pub enum SceneFileError {
    #[error("{}: cannot read: {source}", path.display())]
    Read { path: PathBuf, source: io::Error },

    #[error("{}: cannot write: {source}", path.display())]
    Write { path: PathBuf, source: io::Error },

    /// The text is not a well-formed scene document: RON syntax, a wrong type, an unknown or
    /// missing field, a truncated file.
    #[error("{}:{line}:{column}: {message}", path.display())]
    Syntax { path: PathBuf, line: usize, column: usize, message: String },

    /// Written by a newer keyrig; this one cannot read it and will not overwrite it.
    #[error(
        "{}:{line}:{column}: scene format version {found} is newer than this keyrig supports \
         (version {supported}); open it with a newer keyrig",
        path.display()
    )]
    TooNew { path: PathBuf, line: usize, column: usize, found: u32, supported: u32 },

    /// Older than any version a migration exists for.
    #[error(
        "{}:{line}:{column}: scene format version {found} is not supported: the oldest version \
         this keyrig can migrate is {oldest}",
        path.display()
    )]
    TooOld { path: PathBuf, line: usize, column: usize, found: u32, oldest: u32 },

    /// The document parsed but the scene is invalid; all problems are listed.
    #[error("{}: {}", path.display(), ProblemList(problems))]
    Invalid { path: PathBuf, problems: Vec<LocatedProblem> },

    /// `save` found an existing file written by a newer keyrig at the target path.
    #[error(
        "{}: will not overwrite a scene of format version {found}, newer than this keyrig's \
         version {supported}; save under another name",
        path.display()
    )]
    RefuseOverwriteNewer { path: PathBuf, found: u32, supported: u32 },

    #[error("cannot write the scene as RON: {message}")]
    Serialize { message: String },
}

impl SceneFileError {
    /// Line and column of the error in the file, where it has one (for `Invalid`, the first
    /// located problem's).
    #[must_use]
    pub fn position(&self) -> Option<(usize, usize)> {
        match self {
            SceneFileError::Syntax { line, column, .. }
            | SceneFileError::TooNew { line, column, .. }
            | SceneFileError::TooOld { line, column, .. } => Some((*line, *column)),
            SceneFileError::Invalid { problems, .. } => problems.iter().find_map(|p| p.position),
            _ => None,
        }
    }
}

/// Formats a list of problems as "N problems: first; second; …" (at most 10 shown).
struct ProblemList<'a>(&'a [LocatedProblem]);

impl fmt::Display for ProblemList<'_> {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        const SHOWN: usize = 10;
        let n = self.0.len();
        write!(f, "invalid scene, {n} problem{}: ", if n == 1 { "" } else { "s" })?;
        for (i, p) in self.0.iter().take(SHOWN).enumerate() {
            if i > 0 {
                write!(f, "; ")?;
            }
            write!(f, "{p}")?;
        }
        if n > SHOWN {
            write!(f, "; and {} more", n - SHOWN)?;
        }
        Ok(())
    }
}

/// The document as written: version first, then the scene.
#[derive(Serialize)]
struct SceneFileOut<'a> {
    version: u32,
    scene: &'a Scene,
}

/// The current version's document as read, strictly.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneFileCurrent {
    #[allow(dead_code, reason = "checked before this struct is read")]
    version: u32,
    scene: Scene,
}

/// Only the version; every other field is skipped. Used when `version` is not the first
/// field, so that a newer file with fields this keyrig does not know still gets "too new"
/// rather than "unknown field".
#[derive(Deserialize)]
struct VersionHeader {
    version: u32,
}

/// Serializes `scene` as a complete scene file (version and scene) in the fixed layout
/// described in docs/scene-format.md, ending in a newline. Does not check the scene; [`save`] does.
pub fn to_string(scene: &Scene) -> Result<String, SceneFileError> {
    let doc = SceneFileOut { version: CURRENT_VERSION, scene };
    let mut text = to_ron(&doc).map_err(|e| SceneFileError::Serialize { message: e.to_string() })?;
    text.push('\n');
    Ok(text)
}

/// What the one-pass reader saw before it stopped.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Seen {
    /// The first field was `version` with this value, which is not [`CURRENT_VERSION`].
    OtherVersion(u32),
    /// The first field was not `version`.
    VersionNotFirst,
}

#[derive(Deserialize)]
#[serde(field_identifier, rename_all = "lowercase")]
enum EnvelopeField {
    Version,
    Scene,
}

/// Reads a current-version document in one pass: checks that `version` comes first and
/// equals [`CURRENT_VERSION`], then reads the scene. Anything else is recorded in `seen` and
/// left to the slower general path.
struct CurrentVersionReader<'a> {
    seen: &'a std::cell::Cell<Option<Seen>>,
}

impl<'de> serde::de::DeserializeSeed<'de> for CurrentVersionReader<'_> {
    type Value = Scene;

    fn deserialize<D: serde::Deserializer<'de>>(self, deserializer: D) -> Result<Scene, D::Error> {
        deserializer.deserialize_struct("SceneFile", &["version", "scene"], self)
    }
}

impl<'de> serde::de::Visitor<'de> for CurrentVersionReader<'_> {
    type Value = Scene;

    fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        f.write_str("a scene file: (version: …, scene: (…))")
    }

    fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<Scene, A::Error> {
        use serde::de::Error;
        match map.next_key::<EnvelopeField>()? {
            Some(EnvelopeField::Version) => {
                let version: u32 = map.next_value()?;
                if version != CURRENT_VERSION {
                    self.seen.set(Some(Seen::OtherVersion(version)));
                    return Err(A::Error::custom("not the current version"));
                }
            }
            Some(EnvelopeField::Scene) => {
                self.seen.set(Some(Seen::VersionNotFirst));
                return Err(A::Error::custom("version is not the first field"));
            }
            None => return Err(A::Error::missing_field("version")),
        }
        let mut scene = None;
        while let Some(field) = map.next_key::<EnvelopeField>()? {
            match field {
                EnvelopeField::Version => return Err(A::Error::duplicate_field("version")),
                EnvelopeField::Scene if scene.is_some() => return Err(A::Error::duplicate_field("scene")),
                EnvelopeField::Scene => scene = Some(map.next_value::<Scene>()?),
            }
        }
        scene.ok_or_else(|| A::Error::missing_field("scene"))
    }
}

/// Parses a scene file's text and checks the scene. `origin` names the text in errors
/// (usually the file's path). Any problem of the scene is an error; see [`from_str_lenient`]
/// to get the scene together with its problems.
pub fn from_str(text: &str, origin: &Path) -> Result<Scene, SceneFileError> {
    let (scene, problems) = from_str_lenient(text, origin)?;
    if problems.is_empty() {
        Ok(scene)
    } else {
        Err(SceneFileError::Invalid { path: origin.to_path_buf(), problems })
    }
}

/// Parses a scene file's text like [`from_str`] but returns the scene even when it has
/// problems (they are returned beside it, located in the text). Syntax, type and version
/// errors are still errors. `keyrig info` uses this to show what is wrong.
pub fn from_str_lenient(text: &str, origin: &Path) -> Result<(Scene, Vec<LocatedProblem>), SceneFileError> {
    // A byte-order mark (some Windows editors start UTF-8 files with one) is not part of the
    // document; without it, lines and columns are unchanged.
    let text = text.strip_prefix('\u{FEFF}').unwrap_or(text);
    let (scene, version) = match read_current(text) {
        Some(scene) => (scene, CURRENT_VERSION),
        None => read_general(text, origin)?,
    };
    let problems = scene.problems();
    let located = if problems.is_empty() {
        Vec::new()
    } else {
        let paths: Vec<String> = problems.iter().map(|p| format!("scene.{}", p.path)).collect();
        // Read the text again as the document type of its version (`migrate` names them).
        let positions = match version {
            1 => locate::<crate::scene_v1::SceneFileV1>(text, &paths),
            _ => locate::<SceneFileCurrent>(text, &paths),
        };
        problems
            .into_iter()
            .zip(positions)
            .map(|(problem, at)| LocatedProblem { problem, position: at.map(|p| (p.line, p.column)) })
            .collect()
    };
    Ok((scene, located))
}

/// The fast path: a current-version document in the strict RON subset of
/// [`crate::scene_text`], read in one pass. `None` when it does not apply or the text has any
/// error; [`read_general`] then reads it (again) with `ron`.
fn read_current(text: &str) -> Option<Scene> {
    let seen = std::cell::Cell::new(None);
    crate::scene_text::from_str_seed(text, CurrentVersionReader { seen: &seen }).ok()
}

/// The general path with `ron`: any RON syntax, versions other than the current one (refused
/// or migrated), and errors located at line and column.
fn read_general(text: &str, origin: &Path) -> Result<(Scene, u32), SceneFileError> {
    let seen = std::cell::Cell::new(None);
    match ron::Options::default().from_str_seed(text, CurrentVersionReader { seen: &seen }) {
        Ok(scene) => Ok((scene, CURRENT_VERSION)),
        Err(err) => match seen.get() {
            None => Err(syntax_error(origin, &err)),
            Some(Seen::OtherVersion(version)) => read_version(version, text, origin),
            Some(Seen::VersionNotFirst) => {
                // Read only the version (skipping everything else), then the document.
                let header: VersionHeader =
                    ron::Options::default().from_str(text).map_err(|e| syntax_error(origin, &e))?;
                read_version(header.version, text, origin)
            }
        },
    }
}

/// Reads a document of `version`: refuses newer versions, migrates older ones. Returns the
/// scene and the version it was read as.
fn read_version(version: u32, text: &str, origin: &Path) -> Result<(Scene, u32), SceneFileError> {
    let version_at = || {
        locate::<VersionHeader>(text, &["version".to_string()])[0]
            .unwrap_or(TextPosition { line: 1, column: 1 })
    };
    if version > CURRENT_VERSION {
        let at = version_at();
        return Err(SceneFileError::TooNew {
            path: origin.to_path_buf(),
            line: at.line,
            column: at.column,
            found: version,
            supported: CURRENT_VERSION,
        });
    }
    let scene = migrate(version, text, origin).map_err(|err| match err {
        MigrationError::Unsupported => {
            let at = version_at();
            SceneFileError::TooOld {
                path: origin.to_path_buf(),
                line: at.line,
                column: at.column,
                found: version,
                oldest: OLDEST_SUPPORTED_VERSION,
            }
        }
        MigrationError::File(err) => err,
    })?;
    Ok((scene, version))
}

/// Why [`migrate`] failed.
#[derive(Debug)]
pub enum MigrationError {
    /// No migration exists from this version.
    Unsupported,
    /// The document of that version is malformed.
    File(SceneFileError),
}

/// The migration hook: reads a document of format `version` (≤ [`CURRENT_VERSION`]) and
/// returns it as a current [`Scene`].
///
/// How to add a version: when the format changes, bump [`CURRENT_VERSION`], freeze the
/// previous document's types in a module `scene_v<N>` (copies of the structs as they were,
/// with `deny_unknown_fields`), implement the conversion from them to the current types, and
/// add an arm here that deserializes the old types and converts them. Keep every older arm:
/// a version-1 file then goes 1 → 2 → … → current. Version 1 is the first published format;
/// there is nothing older to migrate, so anything below it is [`MigrationError::Unsupported`].
pub fn migrate(version: u32, text: &str, origin: &Path) -> Result<Scene, MigrationError> {
    match version {
        1 => {
            let doc: crate::scene_v1::SceneFileV1 = ron::Options::default()
                .from_str(text)
                .map_err(|e| MigrationError::File(syntax_error(origin, &e)))?;
            let mut scene = doc.into_current();
            scene.name_unnamed_keys(keyrig_core::DEFAULT_ACTION);
            Ok(scene)
        }
        // Versions 3 and 4 only added fields that default to "absent" (cameras, markers, new
        // channels; actions), so a version-2 or -3 document reads as the current one. Its one
        // animation becomes the action "Action", active on every object with keys
        // (docs/scene-format.md, "Version 4").
        2 | 3 => {
            let doc: SceneFileCurrent = ron::Options::default()
                .from_str(text)
                .map_err(|e| MigrationError::File(syntax_error(origin, &e)))?;
            let mut scene = doc.scene;
            scene.name_unnamed_keys(keyrig_core::DEFAULT_ACTION);
            Ok(scene)
        }
        CURRENT_VERSION => {
            let doc: SceneFileCurrent = ron::Options::default()
                .from_str(text)
                .map_err(|e| MigrationError::File(syntax_error(origin, &e)))?;
            Ok(doc.scene)
        }
        _ => Err(MigrationError::Unsupported),
    }
}

fn syntax_error(origin: &Path, err: &ron::error::SpannedError) -> SceneFileError {
    let message = match &err.code {
        ron::Error::Eof => "unexpected end of file (is the file truncated?)".to_string(),
        code => crate::message::clip_long_tokens(&code.to_string()).into_owned(),
    };
    SceneFileError::Syntax {
        path: origin.to_path_buf(),
        line: err.span.start.line,
        column: err.span.start.col,
        message,
    }
}

/// Reads and checks the scene file at `path`; see [`from_str`].
pub fn load(path: &Path) -> Result<Scene, SceneFileError> {
    let text = read_text(path)?;
    from_str(&text, path)
}

/// Reads the scene file at `path` and returns the scene with its problems; see
/// [`from_str_lenient`].
pub fn load_lenient(path: &Path) -> Result<(Scene, Vec<LocatedProblem>), SceneFileError> {
    let text = read_text(path)?;
    from_str_lenient(&text, path)
}

fn read_text(path: &Path) -> Result<String, SceneFileError> {
    let bytes = read_regular_file(path, MAX_SCENE_BYTES)
        .map_err(|source| SceneFileError::Read { path: path.to_path_buf(), source })?;
    String::from_utf8(bytes).map_err(|e| {
        let valid = &e.as_bytes()[..e.utf8_error().valid_up_to()];
        let prefix = String::from_utf8_lossy(valid);
        let line = prefix.matches('\n').count() + 1;
        let column = prefix.rsplit('\n').next().map_or(0, |l| l.chars().count()) + 1;
        SceneFileError::Syntax {
            path: path.to_path_buf(),
            line,
            column,
            message: format!("not UTF-8 text (invalid byte at offset {})", valid.len()),
        }
    })
}

/// The backup path of a scene file: `<name>.ron.bak` beside it.
#[must_use]
pub fn backup_path(path: &Path) -> PathBuf {
    crate::file_io::backup_path(path)
}

/// Saves `scene` to `path` atomically, keeping the previous file as `<name>.ron.bak`.
///
/// Refuses (and leaves every file untouched) when the scene has problems, or when `path`
/// holds a scene file of a newer format version. On any error no temporary file is left and
/// `path` still holds its previous content.
pub fn save(path: &Path, scene: &Scene) -> Result<(), SceneFileError> {
    let problems = scene.problems();
    if !problems.is_empty() {
        return Err(SceneFileError::Invalid {
            path: path.to_path_buf(),
            problems: problems
                .into_iter()
                .map(|problem| LocatedProblem { problem, position: None })
                .collect(),
        });
    }
    let text = to_string(scene)?;
    refuse_newer(path)?;
    write_atomic(path, text.as_bytes())
}

/// Errors when `path` exists and declares a format version newer than [`CURRENT_VERSION`].
fn refuse_newer(path: &Path) -> Result<(), SceneFileError> {
    match fs::metadata(path) {
        // Nothing there, or not a file (the write itself will then fail and say why).
        Err(e) if e.kind() == io::ErrorKind::NotFound => return Ok(()),
        Ok(meta) if !meta.is_file() => return Ok(()),
        _ => {}
    }
    let text = match read_regular_file(path, MAX_SCENE_BYTES) {
        Ok(bytes) => String::from_utf8_lossy(&bytes).into_owned(),
        Err(source) => return Err(SceneFileError::Read { path: path.to_path_buf(), source }),
    };
    // Read only the version: a newer format may have syntax this keyrig's reader would reject,
    // and parsing a whole large file just for its first field would be slow.
    let version = peek_version(&text).or_else(|| version_by_scan(&text));
    match version {
        Some(found) if found > CURRENT_VERSION => Err(SceneFileError::RefuseOverwriteNewer {
            path: path.to_path_buf(),
            found,
            supported: CURRENT_VERSION,
        }),
        _ => Ok(()),
    }
}

/// Reads the document's first field when it is `version`, and stops there.
fn peek_version(text: &str) -> Option<u32> {
    struct FirstField<'a>(&'a std::cell::Cell<Option<u32>>);

    impl<'de> serde::de::DeserializeSeed<'de> for FirstField<'_> {
        type Value = ();
        fn deserialize<D: serde::Deserializer<'de>>(self, deserializer: D) -> Result<(), D::Error> {
            deserializer.deserialize_struct("SceneFile", &["version", "scene"], self)
        }
    }

    impl<'de> serde::de::Visitor<'de> for FirstField<'_> {
        type Value = ();
        fn expecting(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
            f.write_str("a scene file")
        }
        fn visit_map<A: serde::de::MapAccess<'de>>(self, mut map: A) -> Result<(), A::Error> {
            if let Some(EnvelopeField::Version) = map.next_key::<EnvelopeField>()? {
                self.0.set(Some(map.next_value::<u32>()?));
            }
            // Stop reading: the rest does not matter here.
            Err(serde::de::Error::custom("stop"))
        }
    }

    let found = std::cell::Cell::new(None);
    let _ = ron::Options::default().from_str_seed(text, FirstField(&found));
    found.get()
}

/// Finds `version: N` near the start of a document that does not parse as a whole.
fn version_by_scan(text: &str) -> Option<u32> {
    let rest = &text[text.find("version")? + "version".len()..];
    let rest = rest.trim_start().strip_prefix(':')?.trim_start();
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    digits.parse().ok()
}

/// Writes `bytes` through keyrig-io's one atomic writer ([`crate::file_io::AtomicFile`]),
/// keeping the previous `path` as its backup.
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), SceneFileError> {
    let write_err = |source| SceneFileError::Write { path: path.to_path_buf(), source };
    let mut file = AtomicFile::create(path).map_err(write_err)?.keep_backup(true);
    file.write_all(bytes).map_err(write_err)?;
    file.commit().map_err(write_err)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::demo::{demo_scene, DEMO_RON};
    use keyrig_core::MeshSource;
    use proptest::prelude::*;

    fn with_ron(text: &str) -> Option<Scene> {
        let seen = std::cell::Cell::new(None);
        ron::Options::default().from_str_seed(text, CurrentVersionReader { seen: &seen }).ok()
    }

    #[test]
    fn fast_path_reads_what_the_writer_writes() {
        assert_eq!(read_current(DEMO_RON), Some(demo_scene()));
        let mut scene = demo_scene();
        scene.objects[0].name = "tab\there \"quoted\" back\\slash\nnew line ünïcode".into();
        let text = to_string(&scene).unwrap();
        assert_eq!(read_current(&text), Some(scene));
        // Spin keys (Turns(-n), Angle(axis, degrees)) are inside the fast subset as well.
        let twist = crate::demo::TWIST_RON;
        assert_eq!(read_current(twist), Some(crate::demo::twist_scene()));
        let turns = twist
            .replace("spin: Some(Angle(axis: (1.0, 0.0, 0.0), degrees: 360.0))", "spin: Some(Turns(-3))");
        assert!(turns.contains("Turns(-3)"));
        assert_eq!(read_current(&turns), with_ron(&turns));
        assert!(read_current(&turns).is_some());
    }

    /// Cameras (each projection, an aim at a joint with a keyed roll, an infinite far plane),
    /// markers, the active camera and the render size: written, read by both readers to the
    /// same scene; a scene without them writes none of these fields.
    #[test]
    fn cameras_and_markers_round_trip() {
        use keyrig_core::{
            Aim, AimTarget, Animated, Key, Marker, Projection, RawTrack, RenderSize, SceneCamera,
        };
        let plain = to_string(&demo_scene()).unwrap();
        for field in ["cameras:", "markers:", "active_camera:", "render_size:"] {
            assert!(!plain.contains(field), "{field}");
        }
        let mut scene = demo_scene();
        let mut dolly = SceneCamera::new("Dolly", glam::Vec3::new(0.0, 1.0, 6.0));
        dolly.projection = Projection::FocalLength { sensor_height_mm: 24.0 };
        dolly.lens = Animated::new(35.0, RawTrack::new(vec![Key::new(0.0, 35.0), Key::new(1.0, 70.0)]));
        dolly.far = None;
        dolly.aim = Some(Aim {
            up: glam::Vec3::Y,
            roll: Animated::new(0.0, RawTrack::new(vec![Key::new(0.0, 0.0), Key::new(1.0, 15.0)])),
            target: AimTarget::Joint { object: scene.objects[0].name.clone(), joint: "elbow".into() },
            influence: Animated::constant(1.0),
        });
        let mut top = SceneCamera::new("Top", glam::Vec3::new(0.0, 10.0, 0.0));
        top.projection = Projection::Orthographic;
        top.lens.value = 4.0;
        top.aim = Some(Aim::at(AimTarget::Point(glam::Vec3::ZERO)));
        scene.cameras = vec![dolly, top];
        scene.active_camera = Some("Dolly".into());
        scene.markers = vec![Marker { name: "cut".into(), frame: 30, camera: Some("Top".into()) }];
        scene.render_size = Some(RenderSize { width: 960, height: 540 });
        let text = to_string(&scene).unwrap();
        assert!(text.contains("projection: FocalLength(sensor_height_mm: 24.0)"), "{text}");
        assert_eq!(read_current(&text).as_ref(), Some(&scene));
        assert_eq!(with_ron(&text).as_ref(), Some(&scene));
        assert_eq!(to_string(&read_current(&text).unwrap()).unwrap(), text);
    }

    /// Texts in and outside the fast subset: whenever the fast path accepts, `ron` reads the
    /// same scene; where it gives up, the general path still reads what `ron` accepts.
    #[test]
    fn fast_path_never_disagrees_with_ron() {
        let base = "fps: 30.0, frame_range: (start: 0, end: 1)";
        let texts = [
            format!("(version: 4, scene: ({base}))"),
            format!("(version: 4, scene: ({base},),)"),
            format!("(version: 4, scene: ({base}, ambient: (1, 2e3, -0.0)))"),
            format!("(version: 4, scene: ({base}, ambient: (3.4028235e+38, 1e-45, -2.5E-3)))"),
            format!("// c\n(/* a /* nested */ */ version: 4, scene: ({base}))\n// end"),
            format!("SceneFile(version: 4, scene: Scene({base}))"),
            format!("(version: 4, scene: ({base}, ambient: (1.0f32, 2.0, 3.0)))"),
            format!("(version: 4, scene: ({base}, ambient: (1_0.0, 2.0, 3.0)))"),
            format!("(version: 4, scene: ({base}, ambient: (-NaN, +inf, NaN)))"),
            format!("(version: 4, scene: ({base}, objects: [(name: \"\\u{{41}}\", translation: (value: (0.0, 0.0, 0.0)), rotation: (value: (0.0, 0.0, 0.0, 1.0)), scale: (value: (1.0, 1.0, 1.0)))]))"),
            format!("(version: 4, scene: ({base}, objects: [(name: r#\"raw\"#, translation: (value: (0.0, 0.0, 0.0)), rotation: (value: (0.0, 0.0, 0.0, 1.0)), scale: (value: (1.0, 1.0, 1.0)))]))"),
            format!("(version: 4, scene: ({base}, ambient: (1.0, 2.0)))"),
            format!("(version: 4, scene: ({base}, ambient: (1.0, 2.0, 3.0, 4.0)))"),
            format!("(version: 4, scene: ({base}) extra)"),
            format!("(version: 4, scene: ({base}))) "),
            format!("(version: 4 scene: ({base}))"),
            "(version: 4, scene: (fps: 30, frame_range: (start: 0.0, end: 1)))".to_string(),
            format!("(version: 4, scene: ({base}, lights: [(name: \"L\", kind: Spot(cutoff_deg: 1.0, inner_angle_deg: 1.0, dropoff: 1.0), position: (value: (0.0, 0.0, 0.0)), direction: (value: (0.0, -1.0, 0.0)), colour: (value: (1.0, 1.0, 1.0)), intensity: (value: 1.0))]))"),
            format!("(version: 4, scene: ({base}, lights: [(name: \"L\", kind: Point(), position: (value: (0.0, 0.0, 0.0)), direction: (value: (0.0, -1.0, 0.0)), colour: (value: (1.0, 1.0, 1.0)), intensity: (value: 1.0))]))"),
            "(version: 4, scene: (fps: 30.0, frame_range: (start: 0, end: 1), unknown: 3))".to_string(),
            "(version: 4, scene: (fps: 1e400, frame_range: (start: 0, end: 4294967296)))".to_string(),
            // Model file meshes with and without the MD2 clip and rate (texts[21..]).
            md2_object_text(base, "path: \"a.md2\""),
            md2_object_text(base, "path: \"a.md2\", clip: Some(\"run\"), fps: Some(10.0)"),
            md2_object_text(base, "path: \"a.md2\", fps: Some(12), clip: Some(\"run\"), mesh: Some(0)"),
            md2_object_text(base, "path: \"a.md2\", clip: None, fps: None"),
            md2_object_text(base, "path: \"a.md2\", fps: Some(-inf)"),
            md2_object_text(base, "path: \"a.md2\", fps: 10.0"),
            md2_object_text(base, "path: \"a.md2\", clip: \"run\""),
            md2_object_text(base, "path: \"a.md2\", clip: Some(run)"),
            md2_object_text(base, "path: \"a.md2\", clip: Some(\"run\"), clip: Some(\"jump\")"),
            md2_object_text(base, "path: \"a.md2\", speed: Some(1.0)"),
            md2_object_text(base, "path: \"a.md2\", fps: Some(1e400)"),
        ];
        for text in &texts {
            let fast = read_current(text);
            let ron = with_ron(text);
            if let Some(fast) = fast {
                assert_eq!(format!("{:?}", Some(fast)), format!("{ron:?}"), "{text}");
            }
            let general = read_general(text, Path::new("t.ron")).ok().map(|(scene, _)| scene);
            assert_eq!(format!("{general:?}"), format!("{ron:?}"), "{text}");
        }
        // The plain forms are taken by the fast path.
        assert!(read_current(&texts[0]).is_some());
        assert!(read_current(&texts[3]).is_some());
        assert!(read_current(&texts[4]).is_some());
        assert!(read_current(&texts[17]).is_some());
        for text in &texts[21..24] {
            assert!(read_current(text).is_some(), "{text}");
        }
        let Some(MeshSource::File { clip, fps, mesh, .. }) =
            &read_current(&texts[23]).expect("read").objects[0].mesh
        else {
            panic!("a file mesh")
        };
        assert_eq!((clip.as_deref(), *fps, *mesh), (Some("run"), Some(12.0), Some(0)));
    }

    /// A scene (`base` fields) with one object whose mesh is `File(<fields>)`.
    fn md2_object_text(base: &str, fields: &str) -> String {
        format!(
            "(version: 4, scene: ({base}, objects: [(name: \"M\", translation: (value: (0.0, 0.0, 0.0)), \
             rotation: (value: (0.0, 0.0, 0.0, 1.0)), scale: (value: (1.0, 1.0, 1.0)), mesh: Some(File({fields})))]))"
        )
    }

    /// A scene with an MD2 object: its clip and rate survive a save and load, the bytes are
    /// stable, objects without them write no `clip`/`fps` (version-1 files keep their bytes),
    /// and invalid rates are refused with the field's path.
    #[test]
    fn md2_clip_and_fps_round_trip() {
        let mut scene = demo_scene();
        let mut object = keyrig_core::Object::new("Sydney");
        object.mesh = Some(MeshSource::File {
            path: "/models/sydney.md2".into(),
            mesh: None,
            clip: Some("run".into()),
            fps: Some(12.5),
        });
        scene.objects.push(object);
        let text = to_string(&scene).unwrap();
        assert!(
            text.contains(
                "mesh: Some(File(path: \"/models/sydney.md2\", clip: Some(\"run\"), fps: Some(12.5)))"
            ),
            "{text}"
        );
        assert_eq!(read_current(&text), Some(scene.clone()));
        assert_eq!(with_ron(&text), Some(scene.clone()));
        assert_eq!(to_string(&from_str(&text, Path::new("s.ron")).unwrap()).unwrap(), text);

        // Without clip and rate nothing new is written.
        scene.objects.last_mut().unwrap().mesh = Some(MeshSource::file("/models/sydney.md2", None));
        let plain = to_string(&scene).unwrap();
        assert!(plain.contains("mesh: Some(File(path: \"/models/sydney.md2\"))"), "{plain}");
        assert!(!plain.contains("clip") && !plain.contains("fps: Some"), "{plain}");
        assert_eq!(to_string(&demo_scene()).unwrap(), DEMO_RON, "the demo file keeps its bytes");

        let bad = text.replace("fps: Some(12.5)", "fps: Some(0.0)");
        let err = from_str(&bad, Path::new("bad.ron")).expect_err("fps 0");
        let message = err.to_string();
        assert!(message.contains("objects[2].mesh.fps") && message.contains("> 0"), "{message}");
        assert!(err.position().is_some(), "{message}");
    }

    /// Mutations of a file with an MD2 object around its clip and rate: the fast path agrees
    /// with `ron` whenever it accepts, and loading never panics.
    #[test]
    fn mutated_md2_fields_agree_with_ron() {
        let mut scene = Scene::default();
        let mut object = keyrig_core::Object::new("M");
        object.mesh = Some(MeshSource::File {
            path: "m.md2".into(),
            mesh: Some(0),
            clip: Some("crattak".into()),
            fps: Some(9.5),
        });
        scene.objects.push(object);
        let text = to_string(&scene).unwrap();
        let start = text.find("mesh:").expect("mesh field");
        let end = start + text[start..].find('\n').expect("line end");
        let mut accepted = 0;
        for i in (start..end).filter(|&i| text.is_char_boundary(i)) {
            for replacement in ["", ",", ")", "(", "\"", "1", "-", "x", "NaN", "None", "Some("] {
                let next = i + text[i..].chars().next().map_or(0, char::len_utf8);
                let mutated = format!("{}{}{}", &text[..i], replacement, &text[next..]);
                let result = std::panic::catch_unwind(|| {
                    (
                        read_current(&mutated),
                        with_ron(&mutated),
                        from_str_lenient(&mutated, Path::new("m.ron")),
                    )
                });
                let Ok((fast, ron, loaded)) = result else {
                    panic!("panic on mutation at byte {i}:\n{mutated}")
                };
                if let Some(fast) = fast {
                    accepted += 1;
                    assert_eq!(format!("{:?}", Some(fast)), format!("{ron:?}"), "byte {i}:\n{mutated}");
                }
                if let Err(err) = loaded {
                    assert!(err.position().is_some(), "byte {i}: {err}");
                }
            }
        }
        assert!(accepted > 0, "some mutations (inside the strings and numbers) stay valid");
    }

    /// Floats of every kind: any bit pattern (NaN and infinities included), `-0.0`, the
    /// smallest subnormal and largest finite values, and ordinary ones.
    fn tricky_f32() -> impl Strategy<Value = f32> + Clone {
        prop_oneof![
            any::<f32>(),
            Just(-0.0f32),
            Just(1e-45f32),
            Just(f32::MIN_POSITIVE),
            Just(f32::MAX),
            Just(f32::NAN),
            Just(f32::NEG_INFINITY),
            -1e6f32..1e6,
        ]
    }

    fn tricky_f64() -> impl Strategy<Value = f64> + Clone {
        prop_oneof![any::<f64>(), Just(-0.0f64), Just(5e-324f64), Just(f64::MAX), 0.0f64..100.0]
    }

    fn tricky_vec3() -> impl Strategy<Value = glam::Vec3> + Clone {
        (tricky_f32(), tricky_f32(), tricky_f32()).prop_map(|(x, y, z)| glam::Vec3::new(x, y, z))
    }

    /// The demo scene with a generated name (any Unicode, quotes, backslashes, control
    /// characters), frame rate, light intensity and a generated track of keys.
    fn generated_scene() -> impl Strategy<Value = Scene> {
        let name = prop_oneof!["\\PC{0,12}", "[\"\\\\\n\r\t\u{1}\u{7f}é😀 a]{0,8}"];
        let key = (tricky_f64(), tricky_vec3(), (tricky_f32(), tricky_f32(), tricky_f32()), 0..4usize);
        (name, tricky_f64(), tricky_f32(), prop::collection::vec(key, 0..5)).prop_map(
            |(name, fps, intensity, keys)| {
                use keyrig_core::{Interpolation, Key, RawTrack, Tcb};
                let mut scene = demo_scene();
                scene.fps = fps;
                scene.objects[1].name = name;
                scene.lights[0].intensity.value = intensity;
                scene.objects[1].translation.track = RawTrack::new(
                    keys.into_iter()
                        .map(|(time, value, (t, c, b), mode)| {
                            let interpolation = [
                                Interpolation::Step,
                                Interpolation::Linear,
                                Interpolation::Tcb,
                                Interpolation::Hermite,
                            ][mode];
                            Key::new(time, value)
                                .with_tcb(Tcb::new(t, c, b))
                                .with_interpolation(interpolation)
                        })
                        .collect(),
                );
                scene
            },
        )
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// The hand-written reader and writer (`scene_text`) against `ron` on generated
        /// scenes: `ron` reads the writer's text back to the scene bit for bit; the fast
        /// reader takes that text (unless it holds a `\u{…}` escape) and reads what `ron`
        /// reads; on `ron`'s own pretty output of the scene it reads what `ron` reads or
        /// gives up; and loading refuses a scene with a NaN or infinity, at its place.
        #[test]
        fn hand_written_text_agrees_with_ron_on_generated_scenes(scene in generated_scene()) {
            let text = to_string(&scene).unwrap();
            let by_ron = with_ron(&text);
            prop_assert_eq!(format!("{by_ron:?}"), format!("{:?}", Some(&scene)), "{}", text);
            let fast = read_current(&text);
            prop_assert!(fast.is_some() || text.contains("\\u{"), "{}", text);
            if let Some(fast) = fast {
                prop_assert_eq!(format!("{:?}", Some(fast)), format!("{by_ron:?}"));
            }

            let doc = SceneFileOut { version: CURRENT_VERSION, scene: &scene };
            let ron_text = ron::ser::to_string_pretty(&doc, ron::ser::PrettyConfig::default()).unwrap();
            let by_ron = with_ron(&ron_text);
            if let Some(fast) = read_current(&ron_text) {
                prop_assert_eq!(format!("{:?}", Some(fast)), format!("{by_ron:?}"), "{}", ron_text);
            }

            match from_str(&text, Path::new("g.ron")) {
                Ok(loaded) => {
                    prop_assert!(scene.problems().is_empty());
                    prop_assert_eq!(format!("{loaded:?}"), format!("{scene:?}"));
                }
                Err(SceneFileError::Invalid { problems, .. }) => {
                    prop_assert!(!scene.problems().is_empty());
                    prop_assert!(problems[0].position.is_some(), "{:?}", problems);
                }
                Err(err) => prop_assert!(false, "{}", err),
            }
        }
    }

    /// Deterministic mutations of the demo file (a character replaced, deleted or doubled):
    /// the fast path never accepts a text that `ron` rejects or reads differently, and
    /// loading never panics and always locates its error.
    #[test]
    fn mutated_demo_files_agree_with_ron_and_never_panic() {
        const REPLACEMENTS: [&str; 16] =
            [",", ")", "(", "]", " ", "1", "e", "-", "\"", "\\", "/", "*", "x", ":", "NaN", "1e999"];
        let demo = DEMO_RON;
        let positions: Vec<usize> =
            (0..demo.len()).step_by(11).filter(|&i| demo.is_char_boundary(i)).collect();
        let mut accepted = 0;
        let mut checked = 0;
        for (n, &i) in positions.iter().enumerate() {
            let next = demo[i..].chars().next().map_or(i, |c| i + c.len_utf8());
            let mutations = [
                format!("{}{}{}", &demo[..i], REPLACEMENTS[n % REPLACEMENTS.len()], &demo[next..]),
                format!("{}{}", &demo[..i], &demo[next..]),
                format!("{}{}", &demo[..next], &demo[i..]),
            ];
            for text in &mutations {
                checked += 1;
                let result = std::panic::catch_unwind(|| {
                    let fast = read_current(text);
                    let ron = with_ron(text);
                    (fast, ron, from_str_lenient(text, Path::new("m.ron")))
                });
                let Ok((fast, ron, loaded)) = result else {
                    panic!("panic on mutation at byte {i}:\n{text}")
                };
                if let Some(fast) = fast {
                    accepted += 1;
                    assert_eq!(format!("{:?}", Some(fast)), format!("{ron:?}"), "byte {i}:\n{text}");
                }
                if let Err(err) = loaded {
                    assert!(err.position().is_some(), "byte {i}: {err}");
                }
            }
        }
        // Some mutations (inside strings, numbers, whitespace) still give valid files.
        assert!(accepted > 0 && checked > 2000, "{accepted} of {checked}");
    }
}
