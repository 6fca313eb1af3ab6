//! The editor's files: opening, saving, importing and exporting through keyrig-io. Errors
//! come back as [`FileError`] for the status bar; nothing here panics on a bad file.
//!
//! - [`meshes`]: the mesh store — meshes of the model files a scene names, loaded once each
//!   (skinned glTF, static glTF, MD2 morph meshes) with their materials.
//! - [`import`]: reading a model as a scene, on a background thread ([`BackgroundImport`]): the
//!   UI keeps drawing, the status bar shows the stage, a fraction where one is known and the
//!   elapsed time, and the result is applied as one undoable edit (or as the new document).
//! - [`placement`]: where an imported model goes — beside what the scene holds, not on top of
//!   it at the origin.
//! - [`recovery`]: the autosave recovery file and the recent-files list.
//! - [`sessions`]: the session (frame, camera, selection, panel sizes) remembered per scene
//!   file in the data folder, restored on reopen.

pub mod import;
pub mod meshes;
pub mod placement;
pub mod recovery;
pub mod sessions;

use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::Quat;
use keyrig_core::Scene;
use keyrig_io::project::load_scene;

pub use import::{
    frame_model_scene, frame_range_end, import_model, rest_world_from_object, BackgroundImport,
    ImportProgress, ImportPurpose, LoadedModel,
};
pub use meshes::{morph_mesh_from_md2, render_meshes, FileMesh, LoadedMesh, MeshStore, RenderMeshes};
pub use recovery::{Recent, Recovery};
pub use sessions::{SavedSession, Sessions};

/// Why a file could not be opened, imported, exported or kept. Clone: the [`MeshStore`]
/// keeps a failed load's error to show it every frame without reading the file again.
#[derive(Clone, Debug, thiserror::Error)]
pub enum FileError {
    #[error(transparent)]
    Scene(Arc<keyrig_io::scene_file::SceneFileError>),
    #[error(transparent)]
    Gltf(Arc<keyrig_io::gltf_import::GltfError>),
    #[error(transparent)]
    Fbx(Arc<keyrig_io::fbx::FbxError>),
    #[error(transparent)]
    Bvh(Arc<keyrig_io::bvh::BvhError>),
    #[error("{}: {source}", path.display())]
    Md2 { path: PathBuf, source: Arc<keyrig_io::md2::Md2Error> },
    #[error("{}: {source}", path.display())]
    Mapping { path: PathBuf, source: Arc<keyrig_io::model::MappingError> },
    #[error("{}: {source}", path.display())]
    SkinnedMesh { path: PathBuf, source: Arc<keyrig_io::model::MappingError> },
    #[error("{}: {source}", path.display())]
    Morph { path: PathBuf, source: keyrig_render::MorphError },
    #[error(transparent)]
    Vrml(Arc<keyrig_io::vrml::VrmlError>),
    #[error("{}: {source}", path.display())]
    VrmlExport { path: PathBuf, source: Arc<keyrig_io::vrml::export::VrmlExportError> },
    #[error("{}: {source}", path.display())]
    VrmlMesh { path: PathBuf, source: Arc<keyrig_io::vrml::map::VrmlMeshError> },
    #[error("{}: {source}", path.display())]
    Export { path: PathBuf, source: Arc<keyrig_io::gltf_export::ExportError> },
    #[error("{}: cannot read: {source}", path.display())]
    Read { path: PathBuf, source: Arc<std::io::Error> },
    #[error("{}: cannot write: {source}", path.display())]
    Write { path: PathBuf, source: Arc<std::io::Error> },
    #[error("{}: cannot create folder: {source}", path.display())]
    Folder { path: PathBuf, source: Arc<std::io::Error> },
    #[error("{}: unknown file type .{extension} (expected .ron, .glb, .gltf, .md2, .wrl, .wrz, .x3d, .x3dv or .iv)", path.display())]
    UnknownType { path: PathBuf, extension: String },
    #[error("{}: no file extension (expected .ron, .glb, .gltf, .md2, .wrl, .wrz, .x3d, .x3dv or .iv)", path.display())]
    NoExtension { path: PathBuf },
    #[error("{}: the editor shows meshes of glTF, MD2, VRML, X3D and Open Inventor files only", path.display())]
    NotAMeshFile { path: PathBuf },
    #[error("{}: no node shows mesh {index}", path.display())]
    NoSuchMesh { path: PathBuf, index: usize },
    #[error("{}: the import stopped unexpectedly", path.display())]
    ImportStopped { path: PathBuf },
    #[error("no data folder for the recovery file")]
    NoDataFolder,
    /// A file of an object of the scene (`at` names the object).
    #[error("{at}: {source}")]
    OfObject { at: String, source: Box<FileError> },
}

impl From<keyrig_io::scene_file::SceneFileError> for FileError {
    fn from(e: keyrig_io::scene_file::SceneFileError) -> Self {
        FileError::Scene(Arc::new(e))
    }
}

impl From<keyrig_io::vrml::VrmlError> for FileError {
    fn from(e: keyrig_io::vrml::VrmlError) -> Self {
        FileError::Vrml(Arc::new(e))
    }
}

impl From<keyrig_io::fbx::ModelImportError> for FileError {
    fn from(e: keyrig_io::fbx::ModelImportError) -> Self {
        match e {
            keyrig_io::fbx::ModelImportError::Gltf(e) => FileError::Gltf(Arc::new(e)),
            keyrig_io::fbx::ModelImportError::Fbx(e) => FileError::Fbx(Arc::new(e)),
        }
    }
}

impl From<keyrig_io::bvh::BvhError> for FileError {
    fn from(e: keyrig_io::bvh::BvhError) -> Self {
        FileError::Bvh(Arc::new(e))
    }
}

impl From<keyrig_io::gltf_import::GltfError> for FileError {
    fn from(e: keyrig_io::gltf_import::GltfError) -> Self {
        FileError::Gltf(Arc::new(e))
    }
}

/// MD2 models are Z-up in Quake units; keyrig scenes are Y-up in metres. An MD2 object gets
/// this rotation (−90° about X: Quake's +Z becomes +Y, its +X stays +X and its +Y becomes −Z)
/// and [`MD2_SCALE`] as its own (editable) transform; the file's vertices are not changed.
/// (keyrig-io's [`keyrig_io::md2::md2_rotation`], which `keyrig_io::md2::md2_scene` uses.)
#[must_use]
pub fn md2_rotation() -> Quat {
    keyrig_io::md2::md2_rotation()
}

/// Metres per Quake unit. Quake 2 player models are about 56 units tall, so one unit as an
/// inch (0.0254 m) makes them about 1.4 m tall, next to a 1.6 m demo arm.
pub const MD2_SCALE: f32 = keyrig_io::md2::MD2_SCALE;

/// The platform's data folder for keyrig (`~/.local/share/keyrig` on Linux).
#[must_use]
pub fn default_data_dir() -> Option<PathBuf> {
    directories::ProjectDirs::from("", "", "keyrig").map(|d| d.data_dir().to_path_buf())
}

/// The extensions of the images a reference image can be (what keyrig-io's `image` reads).
pub const IMAGE_EXTENSIONS: [&str; 4] = ["png", "jpg", "jpeg", "bmp"];

/// Whether `path` names an image (a reference image when dropped on the window).
#[must_use]
pub fn is_image_file(path: &Path) -> bool {
    extension(path).is_some_and(|e| IMAGE_EXTENSIONS.contains(&e.as_str()))
}

/// The sound files keyrig reads (keyrig-io's `sound`, through Symphonia).
pub const SOUND_EXTENSIONS: [&str; 5] = ["wav", "flac", "mp3", "ogg", "oga"];

/// Whether `path` names a sound file (a sound clip when imported or dropped on the window).
#[must_use]
pub fn is_sound_file(path: &Path) -> bool {
    extension(path).is_some_and(|e| SOUND_EXTENSIONS.contains(&e.as_str()))
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

/// Why the file dialog is open.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DialogPurpose {
    Open,
    SaveAs,
    Import,
    /// A sound clip (File ▸ Import sound).
    ImportSound,
    Export,
    /// The reference image behind the scene (View ▸ Reference image).
    ReferenceImage,
}

/// What each file dialog lists: (filter name, extensions) in the order the drop-down shows
/// them; the first is chosen when the dialog opens.
#[must_use]
pub fn dialog_filters(purpose: DialogPurpose) -> Vec<(&'static str, &'static [&'static str])> {
    const SCENES: (&str, &[&str]) = ("keyrig scenes (.ron)", &["ron"]);
    const MODELS: (&str, &[&str]) = (
        "Models (.glb, .gltf, .fbx, .bvh, .md2, .wrl, .wrz, .x3d, .x3dv, .iv)",
        &["glb", "gltf", "fbx", "bvh", "md2", "wrl", "wrz", "x3d", "x3dv", "x3dz", "x3dvz", "iv"],
    );
    const VRML: (&str, &[&str]) = (
        "VRML, X3D, Open Inventor (.wrl, .wrz, .x3d, .x3dv, .iv)",
        &["wrl", "wrz", "x3d", "x3dv", "x3dz", "x3dvz", "iv"],
    );
    const SOUNDS: (&str, &[&str]) = ("Sounds (.wav, .flac, .mp3, .ogg)", &SOUND_EXTENSIONS);
    match purpose {
        DialogPurpose::Open => vec![
            SCENES,
            MODELS,
            (
                "Scenes and models",
                &[
                    "ron", "glb", "gltf", "fbx", "bvh", "md2", "wrl", "wrz", "x3d", "x3dv", "x3dz", "x3dvz",
                    "iv",
                ],
            ),
        ],
        DialogPurpose::Import => {
            vec![MODELS, SOUNDS, ("glTF (.glb, .gltf)", &["glb", "gltf"]), ("MD2 (.md2)", &["md2"]), VRML]
        }
        DialogPurpose::ImportSound => vec![SOUNDS],
        DialogPurpose::SaveAs => vec![SCENES],
        DialogPurpose::ReferenceImage => vec![("Images (.png, .jpg, .jpeg, .bmp)", &IMAGE_EXTENSIONS)],
        DialogPurpose::Export => vec![
            ("glTF binary (.glb)", &["glb"]),
            ("glTF (.gltf)", &["gltf"]),
            ("VRML97 (.wrl)", &["wrl"]),
            ("X3D (.x3d)", &["x3d"]),
            ("X3D classic (.x3dv)", &["x3dv"]),
            ("Open Inventor (.iv)", &["iv"]),
            ("BVH motion capture (.bvh)", &["bvh"]),
        ],
    }
}

/// The file dialog for `purpose`: filtered to the files that action reads or writes (case
/// does not matter), opening in `folder` when given; save dialogs propose `stem` with the
/// action's extension ("Untitled.ron", "arm.glb"). Enter confirms (egui-file-dialog's
/// submit key and file-name field); a path typed into the file-name field, absolute or
/// relative to the folder shown, or into the path bar (`/` or the ✏ button), is taken as
/// it is.
#[must_use]
pub fn file_dialog(
    purpose: DialogPurpose,
    stem: &str,
    folder: Option<PathBuf>,
    storage: egui_file_dialog::FileDialogStorage,
) -> egui_file_dialog::FileDialog {
    let title = match purpose {
        DialogPurpose::Open => "Open scene or model",
        DialogPurpose::SaveAs => "Save scene as",
        DialogPurpose::Import => "Import model or sound",
        DialogPurpose::ImportSound => "Import sound",
        DialogPurpose::Export => "Export glTF, VRML, X3D or Open Inventor",
        DialogPurpose::ReferenceImage => "Reference image",
    };
    let mut dialog = egui_file_dialog::FileDialog::new()
        .id(egui::Id::new(("keyrig_file_dialog", title)))
        .title(title)
        .storage(storage)
        .default_size([760.0, 460.0])
        // Centred over the window, as the other dialogs are (not docked over the timeline).
        .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
        .show_path_edit_button(true);
    if let Some(folder) = folder {
        dialog = dialog.initial_directory(folder);
        if matches!(purpose, DialogPurpose::SaveAs | DialogPurpose::Export) {
            // The scene's folder, not the one something was last picked in (egui-file-dialog's
            // default): Save As and Export propose a name beside the scene.
            dialog = dialog.opening_mode(egui_file_dialog::OpeningMode::AlwaysInitialDir);
        }
    }
    let filters = dialog_filters(purpose);
    match purpose {
        DialogPurpose::Open
        | DialogPurpose::Import
        | DialogPurpose::ImportSound
        | DialogPurpose::ReferenceImage => {
            for &(name, extensions) in &filters {
                let filter = egui_file_dialog::Filter::new(move |path: &Path| {
                    extension(path).is_some_and(|e| extensions.contains(&e.as_str()))
                });
                dialog = dialog.add_file_filter(name, filter);
            }
            if let Some((first, _)) = filters.first() {
                dialog = dialog.default_file_filter(first);
            }
        }
        DialogPurpose::SaveAs | DialogPurpose::Export => {
            for (name, extensions) in &filters {
                dialog = dialog.add_save_extension(name, extensions[0]);
            }
            if let Some((first, extensions)) = filters.first() {
                dialog = dialog
                    .default_save_extension(first)
                    .default_file_name(&format!("{stem}.{}", extensions[0]));
            }
        }
    }
    dialog
}

/// Opens a scene file, or a model as a new scene (synchronously; the editor's menus use
/// [`BackgroundImport`] for models).
pub fn open_any(path: &Path) -> Result<Scene, FileError> {
    if is_scene_file(path) {
        Ok(load_scene(path)?)
    } else {
        let read = import::read_model(path, &mut |_, _| {})?;
        let mut scene = read.scene;
        let meshes = import::load_meshes_of(&scene, read.meshes, &mut |_| {});
        import::frame_new_scene(&mut scene, &meshes, read.own_camera);
        Ok(scene)
    }
}

/// Writes the scene as glTF (.glb, or .gltf with the buffer embedded) — or, by the path's
/// extension, as VRML97 (.wrl), X3D (.x3d, .x3dv) or Open Inventor (.iv) through
/// `keyrig_io::vrml::export` — resolving mesh files against `base_dir` (the scene's folder).
pub fn export_gltf(path: &Path, scene: &Scene, base_dir: Option<&Path>) -> Result<(), FileError> {
    if keyrig_io::bvh::is_bvh_path(path) {
        // A BVH take: the selected character is not known here; the first with a skeleton.
        let object = scene.objects.iter().position(|o| o.skeleton.is_some()).unwrap_or(0);
        return Ok(keyrig_io::bvh::export_scene(scene, object, path)?);
    }
    if let Some(format) = keyrig_io::vrml::export::ExportFormat::of_path(path) {
        let options = keyrig_io::vrml::export::VrmlExportOptions {
            base_dir: base_dir.map(Path::to_path_buf),
            ..keyrig_io::vrml::export::VrmlExportOptions::default()
        };
        let text = keyrig_io::vrml::export::export_scene(scene, format, &options)
            .map_err(|e| FileError::VrmlExport { path: path.to_path_buf(), source: Arc::new(e) })?;
        return keyrig_io::file_io::write_atomic(path, text.as_bytes())
            .map_err(|e| FileError::Write { path: path.to_path_buf(), source: Arc::new(e) });
    }
    let options = keyrig_io::gltf_export::ExportOptions {
        base_dir: base_dir.map(Path::to_path_buf),
        ..keyrig_io::gltf_export::ExportOptions::default()
    };
    let exported = keyrig_io::gltf_export::export_scene(scene, &options)
        .map_err(|e| FileError::Export { path: path.to_path_buf(), source: Arc::new(e) })?;
    exported.write(path).map_err(|e| FileError::Export { path: path.to_path_buf(), source: Arc::new(e) })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn unknown_extension_is_an_error_naming_the_file() {
        let err = open_any(Path::new("/tmp/x.txt")).expect_err("txt is not a scene");
        assert!(matches!(&err, FileError::UnknownType { extension, .. } if extension == "txt"), "{err:?}");
        let err = err.to_string();
        assert!(err.contains("x.txt") && err.contains(".txt"), "{err}");
    }
}
