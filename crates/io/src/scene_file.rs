//! RON scene files: versioned, strictly checked, saved atomically (DESIGN.md §8).
//!
//! A scene file is one RON struct with the format version first and the scene second:
//!
//! ```ron
//! (
//!     version: 1,
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

use crate::scene_locate::{locate, TextPosition};
use crate::scene_ser::CompactKeys;

/// The scene format version this keyrig writes and reads without migration.
pub const CURRENT_VERSION: u32 = 1;

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
struct SceneFileV1 {
    #[allow(dead_code, reason = "checked before this struct is read")]
    version: u32,
    scene: Scene,
}

/// Only the version; every other field is skipped. Read first, so that a newer file with
/// fields this keyrig does not know gets "too new" rather than "unknown field".
#[derive(Deserialize)]
struct VersionHeader {
    version: u32,
}

/// The fixed pretty-printing configuration of scene files. Changing it changes every saved
/// file's bytes.
fn pretty_config() -> ron::ser::PrettyConfig {
    ron::ser::PrettyConfig::new()
        .depth_limit(usize::MAX)
        .new_line("\n")
        .indentor("    ")
        .separator(" ")
        .struct_names(false)
        .separate_tuple_members(false)
        .enumerate_arrays(false)
        .compact_arrays(false)
}

/// Serializes `scene` as a complete scene file (version and scene), pretty-printed with the
/// fixed configuration, ending in a newline. Does not check the scene; [`save`] does.
pub fn to_string(scene: &Scene) -> Result<String, SceneFileError> {
    let doc = SceneFileOut { version: CURRENT_VERSION, scene };
    let mut text = ron::ser::to_string_pretty(&CompactKeys(&doc), pretty_config())
        .map_err(|e| SceneFileError::Serialize { message: e.to_string() })?;
    text.push('\n');
    Ok(text)
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
    let options = ron::Options::default();
    let header: VersionHeader = options.from_str(text).map_err(|e| syntax_error(origin, &e))?;
    let version_at =
        || locate(text, &["version".to_string()])[0].unwrap_or(TextPosition { line: 1, column: 1 });
    if header.version > CURRENT_VERSION {
        let at = version_at();
        return Err(SceneFileError::TooNew {
            path: origin.to_path_buf(),
            line: at.line,
            column: at.column,
            found: header.version,
            supported: CURRENT_VERSION,
        });
    }
    let scene = migrate(header.version, text, origin).map_err(|err| match err {
        MigrationError::Unsupported => {
            let at = version_at();
            SceneFileError::TooOld {
                path: origin.to_path_buf(),
                line: at.line,
                column: at.column,
                found: header.version,
                oldest: OLDEST_SUPPORTED_VERSION,
            }
        }
        MigrationError::File(err) => err,
    })?;
    let problems = scene.problems();
    let located = if problems.is_empty() {
        Vec::new()
    } else {
        let paths: Vec<String> = problems.iter().map(|p| format!("scene.{}", p.path)).collect();
        let positions = locate(text, &paths);
        problems
            .into_iter()
            .zip(positions)
            .map(|(problem, at)| LocatedProblem { problem, position: at.map(|p| (p.line, p.column)) })
            .collect()
    };
    Ok((scene, located))
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
            let doc: SceneFileV1 = ron::Options::default()
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
        code => code.to_string(),
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
    let bytes = fs::read(path).map_err(|source| SceneFileError::Read { path: path.to_path_buf(), source })?;
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
    let mut name = path.file_name().map(|n| n.to_os_string()).unwrap_or_default();
    name.push(".bak");
    path.with_file_name(name)
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
    let text = match fs::read(path) {
        Ok(bytes) => String::from_utf8_lossy(&bytes).into_owned(),
        Err(source) => return Err(SceneFileError::Read { path: path.to_path_buf(), source }),
    };
    // Read only the version, with the lightest parser possible: a newer format may have
    // syntax this keyrig's full reader would reject.
    let version = ron::Options::default()
        .from_str::<VersionHeader>(&text)
        .ok()
        .map(|h| h.version)
        .or_else(|| version_by_scan(&text));
    match version {
        Some(found) if found > CURRENT_VERSION => Err(SceneFileError::RefuseOverwriteNewer {
            path: path.to_path_buf(),
            found,
            supported: CURRENT_VERSION,
        }),
        _ => Ok(()),
    }
}

/// Finds `version: N` near the start of a document that does not parse as a whole.
fn version_by_scan(text: &str) -> Option<u32> {
    let rest = &text[text.find("version")? + "version".len()..];
    let rest = rest.trim_start().strip_prefix(':')?.trim_start();
    let digits: String = rest.chars().take_while(char::is_ascii_digit).collect();
    digits.parse().ok()
}

/// Writes `bytes` to a fresh temporary file beside `path`, syncs it, keeps the old `path`
/// as its backup and renames the temporary file to `path`.
fn write_atomic(path: &Path, bytes: &[u8]) -> Result<(), SceneFileError> {
    let write_err = |source| SceneFileError::Write { path: path.to_path_buf(), source };
    let dir = match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d.to_path_buf(),
        _ => PathBuf::from("."),
    };
    let name = path
        .file_name()
        .ok_or_else(|| write_err(io::Error::new(io::ErrorKind::InvalidInput, "the path has no file name")))?;

    let (tmp_path, mut file) = create_temp(&dir, &name.to_string_lossy()).map_err(write_err)?;
    let result = (|| {
        file.write_all(bytes)?;
        file.flush()?;
        file.sync_all()?;
        drop(file);
        if fs::symlink_metadata(path).is_ok() {
            keep_backup(path).map_err(|e| {
                let bak = backup_path(path);
                io::Error::new(e.kind(), format!("cannot keep the previous file as {}: {e}", bak.display()))
            })?;
        }
        fs::rename(&tmp_path, path)?;
        sync_dir(&dir);
        Ok(())
    })();
    if result.is_err() {
        let _ = fs::remove_file(&tmp_path);
    }
    result.map_err(write_err)
}

/// Creates `.<name>.tmp-<pid>-<n>` in `dir` with `create_new`, so that it never replaces
/// anything.
fn create_temp(dir: &Path, name: &str) -> io::Result<(PathBuf, fs::File)> {
    let pid = std::process::id();
    for n in 0..1000u32 {
        let candidate = dir.join(format!(".{name}.tmp-{pid}-{n}"));
        match fs::OpenOptions::new().write(true).create_new(true).open(&candidate) {
            Ok(file) => return Ok((candidate, file)),
            Err(e) if e.kind() == io::ErrorKind::AlreadyExists => continue,
            Err(e) => return Err(e),
        }
    }
    Err(io::Error::new(io::ErrorKind::AlreadyExists, "no free temporary file name"))
}

/// Makes `<name>.bak` hold the current content of `path` (a hard link when the file system
/// allows it, a copy otherwise). The old backup is replaced.
fn keep_backup(path: &Path) -> io::Result<()> {
    let bak = backup_path(path);
    match fs::remove_file(&bak) {
        Ok(()) => {}
        Err(e) if e.kind() == io::ErrorKind::NotFound => {}
        Err(e) => return Err(e),
    }
    if fs::hard_link(path, &bak).is_err() {
        fs::copy(path, &bak)?;
    }
    Ok(())
}

/// Syncs the directory so that the rename survives a crash (where the platform allows).
fn sync_dir(dir: &Path) {
    #[cfg(unix)]
    if let Ok(d) = fs::File::open(dir) {
        // A failure here does not undo the save; the data itself is already synced.
        let _ = d.sync_all();
    }
    #[cfg(not(unix))]
    let _ = dir;
}
