//! A scene and the files around it: scene files whose model and sound paths are portable
//! (relative to the scene's folder on disk, absolute in memory), and the files a scene reads.

use std::fs;
use std::path::{Path, PathBuf};

use keyrig_core::{MeshSource, Scene};

use crate::md2;
use crate::scene_file::{self, SceneFileError};

/// Loads a scene file. Model paths relative to the file's folder become absolute in memory,
/// so that the document (and its undo history) does not depend on where it is saved next.
///
/// # Errors
/// The file cannot be read or is not a valid scene ([`SceneFileError`]).
pub fn load_scene(path: &Path) -> Result<Scene, SceneFileError> {
    let mut scene = scene_file::load(path)?;
    let folder = path.parent().map(|p| fs::canonicalize(p).unwrap_or_else(|_| p.to_path_buf()));
    if let Some(folder) = folder {
        map_model_paths(&mut scene, |p| {
            let file = Path::new(p);
            (!file.is_absolute()).then(|| folder.join(file).to_string_lossy().into_owned())
        });
    }
    Ok(scene)
}

/// Saves a scene file atomically (keyrig-io keeps the previous file as a backup). Models that
/// lie below the file's folder are written with paths relative to it (`/`-separated), so the
/// folder can be moved or shared; others keep their absolute paths.
///
/// # Errors
/// The scene cannot be written ([`SceneFileError`]).
pub fn save_scene(path: &Path, scene: &Scene) -> Result<(), SceneFileError> {
    let portable = portable_scene(path, scene);
    scene_file::save(path, &portable)
}

/// `scene` with the model paths below `scene_file`'s folder made relative to it.
#[must_use]
pub fn portable_scene(scene_file: &Path, scene: &Scene) -> Scene {
    let mut out = scene.clone();
    let Some(folder) = scene_file.parent() else { return out };
    let folder = fs::canonicalize(folder).unwrap_or_else(|_| folder.to_path_buf());
    map_model_paths(&mut out, |p| {
        let file = Path::new(p);
        if !file.is_absolute() {
            return None;
        }
        let file = fs::canonicalize(file).unwrap_or_else(|_| file.to_path_buf());
        let relative = file.strip_prefix(&folder).ok()?;
        let parts: Vec<String> =
            relative.components().map(|c| c.as_os_str().to_string_lossy().into_owned()).collect();
        (!parts.is_empty()).then(|| parts.join("/"))
    });
    out
}

/// Replaces each model, sound and reference image file path `p` of the scene by `change(p)`
/// where that is `Some`.
fn map_model_paths(scene: &mut Scene, mut change: impl FnMut(&str) -> Option<String>) {
    for object in &mut scene.objects {
        if let Some(MeshSource::File { path, .. }) = &mut object.mesh {
            if let Some(new) = change(path) {
                *path = new;
            }
        }
    }
    for clip in &mut scene.sounds {
        if let Some(new) = change(&clip.path) {
            clip.path = new;
        }
    }
    if let Some(image) = &mut scene.reference_image {
        if let Some(new) = change(&image.path) {
            image.path = new;
        }
    }
}

/// The files a scene reads: every `MeshSource::File` model (resolved against `base_dir`,
/// the scene's folder) and, for MD2 models, the skin image found beside them; each with a
/// description naming the object.
#[must_use]
pub fn scene_inputs(scene: &Scene, base_dir: Option<&Path>) -> Vec<(PathBuf, String)> {
    let mut out = Vec::new();
    for (i, object) in scene.objects.iter().enumerate() {
        let Some(MeshSource::File { path, .. }) = &object.mesh else { continue };
        let file = match base_dir {
            Some(dir) => dir.join(path),
            None => PathBuf::from(path),
        };
        let here = format!("objects[{i}] (`{}`)", object.name);
        if file.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("md2")) {
            if let Some(skin) = md2::skin_of_file(&file) {
                out.push((skin, format!("the skin image of the MD2 model that {here} uses")));
            }
        }
        out.push((file, format!("the model file that {here} uses")));
    }
    for (i, clip) in scene.sounds.iter().enumerate() {
        let file = match base_dir {
            Some(dir) => dir.join(&clip.path),
            None => PathBuf::from(&clip.path),
        };
        out.push((file, format!("the sound file of sounds[{i}]")));
    }
    if let Some(image) = &scene.reference_image {
        let file = match base_dir {
            Some(dir) => dir.join(&image.path),
            None => PathBuf::from(&image.path),
        };
        out.push((file, "the reference image".to_owned()));
    }
    out
}
