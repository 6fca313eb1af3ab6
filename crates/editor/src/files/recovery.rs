//! The editor's own files in its data folder: the autosave recovery file (`recovery.ron` and
//! `recovery.origin`) and the recent-files list (`recent.txt`).

use std::fs;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use keyrig_core::Scene;
use keyrig_io::project::{load_scene, save_scene};

use super::FileError;

/// How many recent files are remembered.
const RECENT_LIMIT: usize = 10;

/// The autosave recovery file: `recovery.ron` (a scene file) and `recovery.origin` (the path
/// of the document it came from, if any) in the data folder.
#[derive(Clone, Debug)]
pub struct Recovery {
    dir: Option<PathBuf>,
}

impl Recovery {
    #[must_use]
    pub fn new(dir: Option<&Path>) -> Self {
        Recovery { dir: dir.map(Path::to_path_buf) }
    }

    /// Path of the recovery scene file.
    #[must_use]
    pub fn file(&self) -> Option<PathBuf> {
        self.dir.as_ref().map(|d| d.join("recovery.ron"))
    }

    fn origin_file(&self) -> Option<PathBuf> {
        self.dir.as_ref().map(|d| d.join("recovery.origin"))
    }

    /// Writes `scene` as the recovery file.
    pub fn write(&self, scene: &Scene, origin: Option<&Path>) -> Result<(), FileError> {
        let (Some(dir), Some(file), Some(origin_file)) = (&self.dir, self.file(), self.origin_file()) else {
            return Err(FileError::NoDataFolder);
        };
        fs::create_dir_all(dir).map_err(|e| FileError::Folder { path: dir.clone(), source: Arc::new(e) })?;
        save_scene(&file, scene)?;
        let origin_text = origin.map(|p| p.to_string_lossy().into_owned()).unwrap_or_default();
        keyrig_io::file_io::write_atomic(&origin_file, origin_text.as_bytes())
            .map_err(|e| FileError::Write { path: origin_file.clone(), source: Arc::new(e) })
    }

    /// A recovery scene left by a session that did not exit cleanly, if one is readable.
    #[must_use]
    pub fn load_pending(&self) -> Option<Scene> {
        let file = self.file()?;
        if !file.exists() {
            return None;
        }
        load_scene(&file).ok()
    }

    /// The document path the recovery scene was autosaved from.
    #[must_use]
    pub fn origin(&self) -> Option<PathBuf> {
        let text = read_small_text(&self.origin_file()?)?;
        (!text.trim().is_empty()).then(|| PathBuf::from(text.trim()))
    }

    /// Removes the recovery files (after a save, a clean exit, or a declined recovery).
    pub fn clear(&self) {
        for path in [self.file(), self.origin_file()].into_iter().flatten() {
            // A missing file is already what we want; other errors leave a stale file that the
            // next start offers again, which loses nothing.
            let _ = fs::remove_file(&path);
            let _ = fs::remove_file(keyrig_io::scene_file::backup_path(&path));
        }
    }
}

/// The recent-files list, one path per line in `recent.txt` in the data folder.
#[derive(Clone, Debug, Default)]
pub struct Recent {
    dir: Option<PathBuf>,
    pub paths: Vec<PathBuf>,
}

impl Recent {
    /// Reads the list (empty when there is none or it cannot be read).
    #[must_use]
    pub fn load(dir: Option<&Path>) -> Self {
        let paths = dir
            .and_then(|d| read_small_text(&d.join("recent.txt")))
            .map(|text| {
                text.lines().filter(|l| !l.trim().is_empty()).map(PathBuf::from).take(RECENT_LIMIT).collect()
            })
            .unwrap_or_default();
        Recent { dir: dir.map(Path::to_path_buf), paths }
    }

    /// Puts `path` first and writes the list.
    pub fn add(&mut self, path: &Path) {
        let path = fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
        self.paths.retain(|p| p != &path);
        self.paths.insert(0, path);
        self.paths.truncate(RECENT_LIMIT);
        if let Some(dir) = &self.dir {
            let text: String = self.paths.iter().map(|p| format!("{}\n", p.display())).collect();
            // The list is a convenience: failing to write it must not disturb the editing.
            if fs::create_dir_all(dir).is_ok() {
                let _ = keyrig_io::file_io::write_atomic(&dir.join("recent.txt"), text.as_bytes());
            }
        }
    }
}

/// The editor's own small text files (the recent list, the recovery file's origin): a regular
/// file of at most 1 MiB in UTF-8, read through keyrig-io; `None` when missing or not that.
pub(super) fn read_small_text(path: &Path) -> Option<String> {
    let bytes = keyrig_io::file_io::read_regular_file(path, 1 << 20).ok()?;
    String::from_utf8(bytes).ok()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn recent_list_keeps_order_and_survives_reload() {
        let dir = tempfile::tempdir().expect("temp dir");
        let mut recent = Recent::load(Some(dir.path()));
        recent.add(Path::new("/nonexistent/a.ron"));
        recent.add(Path::new("/nonexistent/b.ron"));
        recent.add(Path::new("/nonexistent/a.ron"));
        let again = Recent::load(Some(dir.path()));
        assert_eq!(
            again.paths,
            vec![PathBuf::from("/nonexistent/a.ron"), PathBuf::from("/nonexistent/b.ron")]
        );
    }
}
