//! The editor's files: opening, saving, importing and exporting through keyrig-io, the
//! autosave recovery file and the recent-files list. Errors come back as text for the status
//! bar; nothing here panics on a bad file.

use std::fs;
use std::path::{Path, PathBuf};

use keyrig_core::Scene;

/// How many recent files are remembered.
const RECENT_LIMIT: usize = 10;

/// The platform's data folder for keyrig (`~/.local/share/keyrig` on Linux).
#[must_use]
pub fn default_data_dir() -> Option<PathBuf> {
    directories::ProjectDirs::from("", "", "keyrig").map(|d| d.data_dir().to_path_buf())
}

/// Whether `path` names a scene file (`.ron`) rather than a model.
#[must_use]
pub fn is_scene_file(path: &Path) -> bool {
    extension(path).as_deref() == Some("ron")
}

fn extension(path: &Path) -> Option<String> {
    path.extension().map(|e| e.to_string_lossy().to_ascii_lowercase())
}

/// `path` with `ext` added when it has no extension.
#[must_use]
pub fn with_extension_if_missing(path: PathBuf, ext: &str) -> PathBuf {
    if path.extension().is_some() {
        path
    } else {
        path.with_extension(ext)
    }
}

/// Loads a scene file.
pub fn load_scene(path: &Path) -> Result<Scene, String> {
    keyrig_io::scene_file::load(path).map_err(|e| e.to_string())
}

/// Saves a scene file atomically (keyrig-io keeps the previous file as a backup).
pub fn save_scene(path: &Path, scene: &Scene) -> Result<(), String> {
    keyrig_io::scene_file::save(path, scene).map_err(|e| e.to_string())
}

/// Opens a scene file, or a model as a new scene.
pub fn open_any(path: &Path) -> Result<Scene, String> {
    if is_scene_file(path) {
        load_scene(path)
    } else {
        import_model(path)
    }
}

/// Reads a model as a scene of its own. glTF (.glb, .gltf) maps onto keyrig through keyrig-io:
/// skinned meshes with their skeleton and the first animation's joint rotation tracks, other
/// meshes as objects, KHR lights as lights; the meshes stay in the file
/// (`MeshSource::File`, with the model's absolute path) and are loaded by [`MeshStore`].
pub fn import_model(path: &Path) -> Result<Scene, String> {
    match extension(path).as_deref() {
        Some("glb" | "gltf") => {
            let model = keyrig_io::gltf_import::import_gltf_file(path).map_err(|e| e.to_string())?;
            let absolute = fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
            let animation = (!model.animations.is_empty()).then_some(0);
            model
                .to_scene(&absolute.to_string_lossy(), animation)
                .map_err(|e| format!("{}: {e}", path.display()))
        }
        Some("md2") => Err(format!(
            "{}: MD2 models are vertex animation, which the editor cannot key; play them with \
             `keyrig render` or convert them with `keyrig convert`",
            path.display()
        )),
        Some(other) => Err(format!(
            "{}: unknown file type .{other} (expected .ron, .glb, .gltf or .md2)",
            path.display()
        )),
        None => Err(format!("{}: no file extension (expected .ron, .glb, .gltf or .md2)", path.display())),
    }
}

/// Writes the scene as glTF (.glb, or .gltf with the buffer embedded), resolving mesh files
/// against `base_dir` (the scene's folder).
pub fn export_gltf(path: &Path, scene: &Scene, base_dir: Option<&Path>) -> Result<(), String> {
    let options = keyrig_io::gltf_export::ExportOptions {
        base_dir: base_dir.map(Path::to_path_buf),
        ..keyrig_io::gltf_export::ExportOptions::default()
    };
    let exported = keyrig_io::gltf_export::export_scene(scene, &options)
        .map_err(|e| format!("{}: {e}", path.display()))?;
    exported.write(path).map_err(|e| e.to_string())
}

/// A mesh read from a model file.
#[derive(Clone, Debug)]
pub enum FileMesh {
    /// A skinned mesh, bound to its skin's skeleton.
    Skinned(Box<keyrig_skin::SkinnedMesh>),
    /// A mesh without a skin: positions and triangles in its node's space.
    Static { positions: Vec<glam::Vec3>, indices: Vec<u32> },
}

/// Meshes of model files, loaded once per (file, mesh index).
#[derive(Default)]
pub struct MeshStore {
    meshes: std::collections::HashMap<(PathBuf, Option<usize>), Result<FileMesh, String>>,
}

impl MeshStore {
    /// The mesh `mesh` (the first when `None`) of the model at `path`, resolved against
    /// `base_dir` when relative.
    pub fn get(
        &mut self,
        base_dir: Option<&Path>,
        path: &str,
        mesh: Option<usize>,
    ) -> Result<&FileMesh, String> {
        let full = match base_dir {
            Some(dir) => dir.join(path),
            None => PathBuf::from(path),
        };
        self.meshes
            .entry((full.clone(), mesh))
            .or_insert_with(|| load_file_mesh(&full, mesh))
            .as_ref()
            .map_err(Clone::clone)
    }
}

fn load_file_mesh(path: &Path, mesh: Option<usize>) -> Result<FileMesh, String> {
    if !matches!(extension(path).as_deref(), Some("glb" | "gltf")) {
        return Err(format!("{}: the editor shows meshes of glTF files only", path.display()));
    }
    let model = keyrig_io::gltf_import::import_gltf_file(path).map_err(|e| e.to_string())?;
    let index = mesh.unwrap_or(0);
    let Some(node) = model.nodes.iter().position(|n| n.mesh == Some(index)) else {
        return Err(format!("{}: no node shows mesh {index}", path.display()));
    };
    if model.nodes[node].skin.is_some() {
        return model
            .skinned_mesh(node)
            .map(|m| FileMesh::Skinned(Box::new(m)))
            .map_err(|e| format!("{}: {e}", path.display()));
    }
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    for prim in model.meshes.get(index).map(|m| m.primitives.as_slice()).unwrap_or_default() {
        if prim.mode != keyrig_io::model::PrimitiveMode::Triangles {
            continue;
        }
        let base = positions.len() as u32;
        positions.extend_from_slice(&prim.positions);
        indices.extend(prim.indices.iter().map(|i| i + base));
    }
    Ok(FileMesh::Static { positions, indices })
}

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
    pub fn write(&self, scene: &Scene, origin: Option<&Path>) -> Result<(), String> {
        let (Some(dir), Some(file), Some(origin_file)) = (&self.dir, self.file(), self.origin_file()) else {
            return Err("no data folder for the recovery file".to_owned());
        };
        fs::create_dir_all(dir).map_err(|e| format!("{}: cannot create folder: {e}", dir.display()))?;
        save_scene(&file, scene)?;
        let origin_text = origin.map(|p| p.to_string_lossy().into_owned()).unwrap_or_default();
        fs::write(&origin_file, origin_text)
            .map_err(|e| format!("{}: cannot write: {e}", origin_file.display()))
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
        let text = fs::read_to_string(self.origin_file()?).ok()?;
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
            .and_then(|d| fs::read_to_string(d.join("recent.txt")).ok())
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
                let _ = fs::write(dir.join("recent.txt"), text);
            }
        }
    }
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

    #[test]
    fn unknown_extension_is_an_error_naming_the_file() {
        let err = open_any(Path::new("/tmp/x.txt")).expect_err("txt is not a scene");
        assert!(err.contains("x.txt") && err.contains(".txt"), "{err}");
    }
}
