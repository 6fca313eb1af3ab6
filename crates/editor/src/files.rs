//! The editor's files: opening, saving, importing and exporting through keyrig-io, the
//! autosave recovery file and the recent-files list. Errors come back as text for the status
//! bar; nothing here panics on a bad file.
//!
//! Models (glTF, MD2) are read on a background thread ([`BackgroundImport`]): the UI keeps
//! drawing, the status bar shows the stage, a fraction where one is known and the elapsed
//! time, and the result is applied as one undoable edit (or as the new document) when the
//! thread is done.

use std::collections::HashMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use glam::{Mat4, Quat, Vec3};
use keyrig_core::Scene;
use keyrig_io::project::{load_scene, save_scene};
use keyrig_render::{MorphClip, MorphMesh, SkinnedVertex};

/// Why a file could not be opened, imported, exported or kept. Clone: the [`MeshStore`]
/// keeps a failed load's error to show it every frame without reading the file again.
#[derive(Clone, Debug, thiserror::Error)]
pub enum FileError {
    #[error(transparent)]
    Scene(Arc<keyrig_io::scene_file::SceneFileError>),
    #[error(transparent)]
    Gltf(Arc<keyrig_io::gltf_import::GltfError>),
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
    #[error("{at}: `{path}` has no skin; only skinned glTF meshes are drawn")]
    NotSkinned { at: String, path: String },
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

/// Why the file dialog is open.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum DialogPurpose {
    Open,
    SaveAs,
    Import,
    Export,
}

/// What each file dialog lists: (filter name, extensions) in the order the drop-down shows
/// them; the first is chosen when the dialog opens.
#[must_use]
pub fn dialog_filters(purpose: DialogPurpose) -> Vec<(&'static str, &'static [&'static str])> {
    const SCENES: (&str, &[&str]) = ("keyrig scenes (.ron)", &["ron"]);
    const MODELS: (&str, &[&str]) = (
        "Models (.glb, .gltf, .md2, .wrl, .wrz, .x3d, .x3dv, .iv)",
        &["glb", "gltf", "md2", "wrl", "wrz", "x3d", "x3dv", "x3dz", "x3dvz", "iv"],
    );
    const VRML: (&str, &[&str]) = (
        "VRML, X3D, Open Inventor (.wrl, .wrz, .x3d, .x3dv, .iv)",
        &["wrl", "wrz", "x3d", "x3dv", "x3dz", "x3dvz", "iv"],
    );
    match purpose {
        DialogPurpose::Open => vec![
            SCENES,
            MODELS,
            (
                "Scenes and models",
                &["ron", "glb", "gltf", "md2", "wrl", "wrz", "x3d", "x3dv", "x3dz", "x3dvz", "iv"],
            ),
        ],
        DialogPurpose::Import => {
            vec![MODELS, ("glTF (.glb, .gltf)", &["glb", "gltf"]), ("MD2 (.md2)", &["md2"]), VRML]
        }
        DialogPurpose::SaveAs => vec![SCENES],
        DialogPurpose::Export => vec![
            ("glTF binary (.glb)", &["glb"]),
            ("glTF (.gltf)", &["gltf"]),
            ("VRML97 (.wrl)", &["wrl"]),
            ("X3D (.x3d)", &["x3d"]),
            ("X3D classic (.x3dv)", &["x3dv"]),
            ("Open Inventor (.iv)", &["iv"]),
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
        DialogPurpose::Import => "Import model",
        DialogPurpose::Export => "Export glTF, VRML, X3D or Open Inventor",
    };
    let mut dialog = egui_file_dialog::FileDialog::new()
        .id(egui::Id::new(("keyrig_file_dialog", title)))
        .title(title)
        .storage(storage)
        .default_size([760.0, 460.0])
        .show_path_edit_button(true);
    if let Some(folder) = folder {
        dialog = dialog.initial_directory(folder);
    }
    let filters = dialog_filters(purpose);
    match purpose {
        DialogPurpose::Open | DialogPurpose::Import => {
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
        let (mut scene, read, own_camera, _) = read_model(path, &mut |_, _| {})?;
        let meshes = load_meshes_of(&scene, read, &mut |_| {});
        frame_new_scene(&mut scene, &meshes, own_camera);
        Ok(scene)
    }
}

/// Reads a model as a scene of its own. glTF (.glb, .gltf) maps onto keyrig through keyrig-io:
/// skinned meshes with their skeleton and the first animation's joint rotation tracks, other
/// meshes as objects, KHR lights as lights. An MD2 model becomes one object named after the
/// file, playing every frame at [`keyrig_core::MD2_DEFAULT_FPS`], turned Y-up and scaled to
/// metres ([`md2_rotation`], [`MD2_SCALE`]) and raised so that its first frame stands on the
/// ground; the frame range covers one loop of it. The
/// meshes stay in the file (`MeshSource::File`, with the model's absolute path) and are
/// loaded by [`MeshStore`].
pub fn import_model(path: &Path) -> Result<Scene, FileError> {
    read_model(path, &mut |_, _| {}).map(|(scene, _, _, _)| scene)
}

/// Progress of a model read: the stage and, where known, the done fraction.
type ProgressFn<'a> = &'a mut dyn FnMut(&str, Option<f32>);

/// [`import_model`], with the meshes it read on the way (an MD2 file's morph mesh), so that
/// they need not be read again, reporting its stages to `progress`: glTF is read and parsed
/// by keyrig-io in one step (no fraction); an MD2 file is read in chunks (fraction of its
/// bytes), then parsed (no fraction); a VRML, X3D or Open Inventor file is read, parsed and
/// mapped by keyrig-io in one step, and its meshes built at once. The flag says whether the
/// model brings its own view (a VRML `Viewpoint`), which framing then keeps; the lines say
/// what the file holds that was not imported (VRML, X3D, Inventor).
fn read_model(
    path: &Path,
    progress: ProgressFn<'_>,
) -> Result<(Scene, Vec<LoadedMesh>, bool, Vec<String>), FileError> {
    let absolute = || fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    if keyrig_io::vrml::is_vrml_path(path) {
        progress("reading and parsing", None);
        let model = keyrig_io::vrml::import_vrml_file(path)?;
        let file = absolute();
        let scene = model.to_scene(&file.to_string_lossy());
        progress("building meshes", None);
        return Ok((scene, vrml_meshes(&file, &model), !model.views.is_empty(), model.skipped_lines()));
    }
    match extension(path).as_deref() {
        Some("glb" | "gltf") => {
            progress("reading and parsing", None);
            let model = keyrig_io::gltf_import::import_gltf_file(path)?;
            let animation = (!model.animations.is_empty()).then_some(0);
            let scene = model
                .to_scene(&absolute().to_string_lossy(), animation)
                .map_err(|e| FileError::Mapping { path: path.to_path_buf(), source: Arc::new(e) })?;
            Ok((scene, Vec::new(), false, Vec::new()))
        }
        Some("md2") => {
            let data = read_with_progress(path, &mut |f| progress("reading", Some(f)))?;
            progress("parsing", None);
            let mesh = md2_morph_mesh(path, &data)?;
            let mut scene = Scene::default();
            let name =
                path.file_stem().map_or_else(|| "MD2".to_owned(), |s| s.to_string_lossy().into_owned());
            let mut object = keyrig_core::Object::new(name);
            let file = absolute().to_string_lossy().into_owned();
            object.mesh = Some(keyrig_core::MeshSource::File {
                path: file.clone(),
                mesh: None,
                clip: None,
                fps: Some(keyrig_core::MD2_DEFAULT_FPS),
            });
            object.rotation = keyrig_core::Animated::constant(md2_rotation());
            object.scale = keyrig_core::Animated::constant(Vec3::splat(MD2_SCALE));
            // Quake models have their origin near the waist: stand the first frame on the
            // ground (its lowest Quake Z at world height 0).
            let lowest = mesh.frames()[0].iter().map(|v| v.position().z).fold(f32::INFINITY, f32::min);
            if lowest.is_finite() {
                object.translation = keyrig_core::Animated::constant(Vec3::Y * (-lowest * MD2_SCALE));
            }
            scene.objects.push(object);
            let seconds = mesh
                .clip_duration(None, keyrig_core::MD2_DEFAULT_FPS)
                .map_err(|source| FileError::Morph { path: path.to_path_buf(), source })?;
            scene.frame_range.end = frame_range_end(seconds, scene.fps);
            Ok((
                scene,
                vec![((PathBuf::from(file), None), Ok((FileMesh::Morph(std::sync::Arc::new(mesh)), None)))],
                false,
                Vec::new(),
            ))
        }
        Some(other) => Err(FileError::UnknownType { path: path.to_path_buf(), extension: other.to_owned() }),
        None => Err(FileError::NoExtension { path: path.to_path_buf() }),
    }
}

/// Bytes per read of [`read_with_progress`].
const READ_CHUNK: usize = 256 * 1024;

/// Reads a whole file in chunks, reporting the fraction of its bytes read after each.
fn read_with_progress(path: &Path, progress: &mut dyn FnMut(f32)) -> Result<Vec<u8>, FileError> {
    use std::io::Read as _;
    let cannot = |e: std::io::Error| FileError::Read { path: path.to_path_buf(), source: Arc::new(e) };
    // A regular file within the MD2 size limit (never a FIFO or a device), checked before
    // reading; the reads below stop at the limit too.
    let limit = keyrig_io::file_io::MAX_MD2_BYTES;
    let (mut file, len) = keyrig_io::file_io::open_regular_file(path, limit).map_err(cannot)?;
    let mut data = Vec::with_capacity(usize::try_from(len).unwrap_or(0));
    let mut chunk = vec![0u8; READ_CHUNK];
    loop {
        let n = file.read(&mut chunk).map_err(cannot)?;
        if n == 0 {
            break;
        }
        data.extend_from_slice(&chunk[..n]);
        if data.len() as u64 > limit {
            return Err(cannot(std::io::Error::new(
                std::io::ErrorKind::InvalidData,
                format!("the file grew past the limit of {limit} bytes while it was read"),
            )));
        }
        progress(if len > 0 { (data.len() as f64 / len as f64).min(1.0) as f32 } else { 1.0 });
    }
    Ok(data)
}

/// The morph mesh of the MD2 file `path` whose bytes are `data`, textured with its skin
/// when one is found beside it ([`keyrig_io::md2::load_skin`]; a skin that cannot be decoded
/// leaves the model untextured rather than unreadable).
fn md2_morph_mesh(path: &Path, data: &[u8]) -> Result<MorphMesh, FileError> {
    let mut model = keyrig_io::md2::parse_md2(data)
        .map_err(|e| FileError::Md2 { path: path.to_path_buf(), source: Arc::new(e) })?;
    model.skin = keyrig_io::md2::load_skin(path, &model.skin_names).ok().flatten();
    morph_mesh_from_md2(&model).map_err(|source| FileError::Morph { path: path.to_path_buf(), source })
}

/// The last frame of a range starting at 0 that shows `seconds` of looping animation at
/// `fps` timeline frames per second (the frame after it is the loop's first again).
#[must_use]
pub fn frame_range_end(seconds: f64, fps: f64) -> i32 {
    keyrig_io::md2::frame_range_end(seconds, fps)
}

/// A keyrig morph mesh from an MD2 model: every frame's positions and normals per render
/// vertex (in the file's Z-up Quake units), its clips, texture coordinates and, when the
/// model's skin was loaded ([`keyrig_io::md2::Md2Model::skin`]), the skin as its material.
///
/// # Errors
/// A model without frames (keyrig-io's reader refuses those already).
pub fn morph_mesh_from_md2(model: &keyrig_io::md2::Md2Model) -> Result<MorphMesh, keyrig_render::MorphError> {
    let frames: Vec<Vec<SkinnedVertex>> = (0..model.frames.len())
        .filter_map(|f| model.frame_pose(f))
        .map(|pose| {
            pose.positions.iter().zip(&pose.normals).map(|(&p, &n)| SkinnedVertex::new(p, n)).collect()
        })
        .collect();
    let clips =
        model.clips.iter().map(|c| MorphClip { name: c.name.clone(), frames: c.frames.clone() }).collect();
    let material = model.skin.as_ref().and_then(keyrig_io::md2::Md2Skin::material).map(std::sync::Arc::new);
    MorphMesh::new(frames, model.indices.clone(), clips)
        .and_then(|m| m.with_look(model.texcoords.clone(), material))
}

/// Every mesh of a VRML/X3D/Inventor model, keyed as [`MeshStore`] keys them (`path`, mesh
/// index): rigid skinned meshes, or morph meshes playing their `CoordinateInterpolator`'s keys
/// at their own times; each with its material.
#[must_use]
pub fn vrml_meshes(path: &Path, model: &keyrig_io::vrml::VrmlModel) -> Vec<LoadedMesh> {
    (0..model.meshes.len())
        .map(|i| {
            let mesh = &model.meshes[i];
            let material = mesh.material.clone();
            let loaded = match &mesh.morph {
                Some(morph) => {
                    let frames: Vec<Vec<SkinnedVertex>> = morph
                        .frames
                        .iter()
                        .map(|f| {
                            f.positions
                                .iter()
                                .zip(&f.normals)
                                .map(|(&p, &n)| SkinnedVertex::new(p, n))
                                .collect()
                        })
                        .collect();
                    let uvs = mesh.uvs.clone();
                    MorphMesh::new(frames, mesh.indices.clone(), Vec::new())
                        .and_then(|m| m.with_key_times(morph.times.clone(), morph.period))
                        .and_then(|m| match uvs {
                            Some(uvs) => m.with_look(uvs, Some(std::sync::Arc::new(material.clone()))),
                            None => Ok(m),
                        })
                        .map(|m| (FileMesh::Morph(std::sync::Arc::new(m)), Some(material)))
                        .map_err(|source| FileError::Morph { path: path.to_path_buf(), source })
                }
                None => model
                    .skinned_mesh(i)
                    .map(|m| (FileMesh::Skinned(std::sync::Arc::new(m)), Some(material)))
                    .map_err(|e| FileError::VrmlMesh { path: path.to_path_buf(), source: Arc::new(e) }),
            };
            ((path.to_path_buf(), Some(i)), loaded)
        })
        .collect()
}

/// Points a model's new scene's camera at its meshes (rest pose, first MD2 frame), unless the
/// model brought its own view (`own_camera`), and adds a sun when it has no light, as
/// `keyrig render` does for models.
fn frame_new_scene(scene: &mut Scene, meshes: &[LoadedMesh], own_camera: bool) {
    if own_camera {
        frame_model_scene(scene, std::iter::empty());
        return;
    }
    let mut points = Vec::new();
    for object in &scene.objects {
        let Some(keyrig_core::MeshSource::File { path, mesh, .. }) = &object.mesh else { continue };
        let Some((_, Ok((data, _)))) = meshes.iter().find(|((p, m), _)| p == Path::new(path) && m == mesh)
        else {
            continue;
        };
        let world = rest_world_from_object(object);
        points.extend(data.rest_positions().into_iter().map(|p| world.transform_point3(p)));
    }
    frame_model_scene(scene, points);
}

/// An object's world transform from its un-animated translation, rotation and scale.
#[must_use]
pub fn rest_world_from_object(object: &keyrig_core::Object) -> Mat4 {
    Mat4::from_scale_rotation_translation(
        object.scale.value,
        object.rotation.value.normalize(),
        object.translation.value,
    )
}

/// What a model opened on its own needs (model files carry no keyrig camera, often no light):
/// the camera looks at the bounds of `points` (world space) from above and to the side, and a
/// sun is added when the scene has no light.
pub fn frame_model_scene(scene: &mut Scene, points: impl IntoIterator<Item = Vec3>) {
    let bounds = points.into_iter().fold((Vec3::MAX, Vec3::MIN), |b, p| (b.0.min(p), b.1.max(p)));
    if bounds.0.cmple(bounds.1).all() {
        let radius = ((bounds.1 - bounds.0).length() * 0.5).max(1e-3);
        scene.camera = keyrig_core::Camera {
            target: (bounds.0 + bounds.1) * 0.5,
            yaw_deg: 30.0,
            pitch_deg: 15.0,
            distance: radius * 2.8,
            fov_y_deg: 45.0,
        };
    }
    if scene.lights.is_empty() {
        scene.lights.push(keyrig_core::Light {
            name: "Sun".into(),
            kind: keyrig_core::LightKind::Directional,
            enabled: true,
            position: keyrig_core::Animated::constant(Vec3::new(0.0, 3.0, 0.0)),
            direction: keyrig_core::Animated::constant(Vec3::new(-0.4, -1.0, -0.6)),
            colour: keyrig_core::Animated::constant(Vec3::ONE),
            intensity: keyrig_core::Animated::constant(0.9),
        });
        scene.ambient = Vec3::splat(0.15);
    }
}

/// Loads the mesh of every object of `scene` whose mesh is a file (once per file and mesh
/// index) that is not among `read` already, calling `progress` with (done, total) before the
/// first and after each.
fn load_meshes_of(
    scene: &Scene,
    read: Vec<LoadedMesh>,
    progress: &mut dyn FnMut((usize, usize)),
) -> Vec<LoadedMesh> {
    let mut wanted: Vec<(PathBuf, Option<usize>)> = Vec::new();
    for object in &scene.objects {
        if let Some(keyrig_core::MeshSource::File { path, mesh, .. }) = &object.mesh {
            let key = (PathBuf::from(path), *mesh);
            if !wanted.contains(&key) && !read.iter().any(|(k, _)| *k == key) {
                wanted.push(key);
            }
        }
    }
    let total = wanted.len();
    if total > 0 {
        progress((0, total));
    }
    let mut meshes = read;
    let mut vrml_files: HashMap<PathBuf, Vec<LoadedMesh>> = HashMap::new();
    for (i, (path, mesh)) in wanted.into_iter().enumerate() {
        let loaded = if keyrig_io::vrml::is_vrml_path(&path) {
            // A VRML file is read once for all of its meshes.
            let all =
                vrml_files.entry(path.clone()).or_insert_with(|| {
                    match keyrig_io::vrml::import_vrml_file(&path) {
                        Ok(model) => vrml_meshes(&path, &model),
                        Err(e) => vec![((path.clone(), mesh), Err(FileError::Vrml(Arc::new(e))))],
                    }
                });
            all.iter().find(|((_, m), _)| *m == mesh).map(|(_, l)| l.clone()).unwrap_or_else(|| {
                all.first().map_or(
                    Err(FileError::NoSuchMesh { path: path.clone(), index: mesh.unwrap_or(0) }),
                    |(_, l)| l.clone(),
                )
            })
        } else {
            load_file_mesh(&path, mesh)
        };
        progress((i + 1, total));
        meshes.push(((path, mesh), loaded));
    }
    meshes
}

/// A model file's mesh as [`MeshStore`] keys it (full path, mesh index) and how loading it
/// went: the mesh and, for glTF, its material (an MD2 mesh carries its skin itself).
pub type LoadedMesh =
    ((PathBuf, Option<usize>), Result<(FileMesh, Option<keyrig_core::Material>), FileError>);

/// Whether a model import replaces the document or adds to it.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImportPurpose {
    /// Open the model as a new scene (File ▸ Open, `keyrig edit model`).
    Open,
    /// Add the model's objects and lights to the scene as one undoable edit (File ▸ Import,
    /// a dropped model).
    Import,
}

/// Where a background import is.
#[derive(Clone, Debug, PartialEq)]
pub struct ImportProgress {
    /// What is being done (`reading and parsing`, `loading meshes`, …).
    pub stage: String,
    /// Done fraction where it is known (meshes loaded of meshes to load); `None` while a
    /// single step whose length is unknown runs (reading and parsing the file).
    pub fraction: Option<f32>,
}

/// A model read on a background thread: the scene it maps to and its meshes, ready for the
/// [`MeshStore`].
pub struct LoadedModel {
    pub scene: Scene,
    pub meshes: Vec<LoadedMesh>,
    /// What the file holds that was not imported, one line per kind (VRML, X3D, Inventor).
    pub not_imported: Vec<String>,
}

/// A model import running on its own thread.
pub struct BackgroundImport {
    pub path: PathBuf,
    pub purpose: ImportPurpose,
    started: Instant,
    progress: Arc<Mutex<ImportProgress>>,
    handle: std::thread::JoinHandle<Result<LoadedModel, FileError>>,
}

impl BackgroundImport {
    /// Starts reading the model at `path` on a new thread.
    #[must_use]
    pub fn start(path: PathBuf, purpose: ImportPurpose) -> Self {
        let progress = Arc::new(Mutex::new(ImportProgress { stage: "reading".to_owned(), fraction: None }));
        let shared = Arc::clone(&progress);
        let file = path.clone();
        let handle = std::thread::spawn(move || {
            let set = |stage: &str, fraction: Option<f32>| {
                if let Ok(mut p) = shared.lock() {
                    *p = ImportProgress { stage: stage.to_owned(), fraction };
                }
            };
            let (mut scene, read, own_camera, not_imported) =
                read_model(&file, &mut |stage, fraction| set(stage, fraction))?;
            let meshes = load_meshes_of(&scene, read, &mut |(done, total)| {
                set("loading meshes", Some(done as f32 / total.max(1) as f32));
            });
            if purpose == ImportPurpose::Open {
                frame_new_scene(&mut scene, &meshes, own_camera);
            }
            Ok(LoadedModel { scene, meshes, not_imported })
        });
        BackgroundImport { path, purpose, started: Instant::now(), progress, handle }
    }

    /// The stage and fraction now.
    #[must_use]
    pub fn progress(&self) -> ImportProgress {
        self.progress.lock().map_or_else(
            |_| ImportProgress { stage: "reading and parsing".to_owned(), fraction: None },
            |p| p.clone(),
        )
    }

    /// Time since the import started.
    #[must_use]
    pub fn elapsed(&self) -> Duration {
        self.started.elapsed()
    }

    /// Whether the thread is done (then [`BackgroundImport::finish`] does not block).
    #[must_use]
    pub fn is_finished(&self) -> bool {
        self.handle.is_finished()
    }

    /// The result, waiting for the thread if it still runs.
    ///
    /// # Errors
    /// The model could not be read, or its thread stopped ([`FileError::ImportStopped`]).
    pub fn finish(self) -> Result<LoadedModel, FileError> {
        let path = self.path.clone();
        self.handle.join().unwrap_or(Err(FileError::ImportStopped { path }))
    }
}

/// Writes the scene as glTF (.glb, or .gltf with the buffer embedded) — or, by the path's
/// extension, as VRML97 (.wrl), X3D (.x3d, .x3dv) or Open Inventor (.iv) through
/// `keyrig_io::vrml::export` — resolving mesh files against `base_dir` (the scene's folder).
pub fn export_gltf(path: &Path, scene: &Scene, base_dir: Option<&Path>) -> Result<(), FileError> {
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

/// A mesh read from a model file.
#[derive(Clone, Debug)]
pub enum FileMesh {
    /// A skinned mesh, bound to its skin's skeleton.
    Skinned(std::sync::Arc<keyrig_skin::SkinnedMesh>),
    /// A mesh without a skin: positions and triangles in its node's space.
    Static { positions: Vec<glam::Vec3>, indices: Vec<u32> },
    /// A vertex-animated mesh (MD2): every frame, its triangles and clips.
    Morph(std::sync::Arc<MorphMesh>),
}

impl FileMesh {
    /// Positions at rest (the skinned mesh's bind pose, a morph mesh's first frame).
    #[must_use]
    pub fn rest_positions(&self) -> Vec<Vec3> {
        match self {
            FileMesh::Skinned(m) => m.positions.clone(),
            FileMesh::Static { positions, .. } => positions.clone(),
            FileMesh::Morph(m) => m.frames()[0].iter().map(SkinnedVertex::position).collect(),
        }
    }
}

/// Meshes of model files, loaded once per (file, mesh index).
#[derive(Default)]
pub struct MeshStore {
    meshes: HashMap<(PathBuf, Option<usize>), Result<FileMesh, FileError>>,
    /// Materials of glTF meshes (a morph mesh holds its own).
    materials: HashMap<(PathBuf, Option<usize>), std::sync::Arc<keyrig_core::Material>>,
    /// Counts loads and inserts, so that whatever was built from the store (the scene
    /// evaluator) knows when to be rebuilt.
    generation: u64,
}

impl MeshStore {
    /// The mesh `mesh` (the first when `None`) of the model at `path`, resolved against
    /// `base_dir` when relative.
    pub fn get(
        &mut self,
        base_dir: Option<&Path>,
        path: &str,
        mesh: Option<usize>,
    ) -> Result<&FileMesh, FileError> {
        let key = (full_path(base_dir, path), mesh);
        if !self.meshes.contains_key(&key) && keyrig_io::vrml::is_vrml_path(&key.0) {
            // One read of the file gives every mesh of it.
            match keyrig_io::vrml::import_vrml_file(&key.0) {
                Ok(model) => {
                    for ((p, m), loaded) in vrml_meshes(&key.0, &model) {
                        self.insert(p, m, loaded);
                    }
                    if !self.meshes.contains_key(&key) {
                        self.generation += 1;
                        self.meshes.insert(
                            key.clone(),
                            Err(FileError::NoSuchMesh { path: key.0.clone(), index: mesh.unwrap_or(0) }),
                        );
                    }
                }
                Err(e) => {
                    self.generation += 1;
                    self.meshes.insert(key.clone(), Err(FileError::Vrml(Arc::new(e))));
                }
            }
        }
        if !self.meshes.contains_key(&key) {
            self.generation += 1;
            let loaded = load_file_mesh(&key.0, mesh).map(|(loaded, material)| {
                if let Some(material) = material {
                    self.materials.insert(key.clone(), std::sync::Arc::new(material));
                }
                loaded
            });
            self.meshes.insert(key.clone(), loaded);
        }
        self.meshes[&key].as_ref().map_err(Clone::clone)
    }

    /// The material of a loaded mesh (a glTF mesh's base colour and texture, an MD2 skin).
    #[must_use]
    pub fn material(
        &self,
        base_dir: Option<&Path>,
        path: &str,
        mesh: Option<usize>,
    ) -> Option<std::sync::Arc<keyrig_core::Material>> {
        let key = (full_path(base_dir, path), mesh);
        if let Some(material) = self.materials.get(&key) {
            return Some(std::sync::Arc::clone(material));
        }
        match self.meshes.get(&key)? {
            Ok(FileMesh::Morph(m)) => m.material().cloned(),
            _ => None,
        }
    }

    /// Materials of the loaded meshes of `scene`'s model-file objects, by object index.
    #[must_use]
    pub fn materials_for(
        &self,
        base_dir: Option<&Path>,
        scene: &keyrig_core::Scene,
    ) -> HashMap<usize, std::sync::Arc<keyrig_core::Material>> {
        let mut out = HashMap::new();
        for (o, object) in scene.objects.iter().enumerate() {
            if let Some(keyrig_core::MeshSource::File { path, mesh, .. }) = &object.mesh {
                if let Some(material) = self.material(base_dir, path, *mesh) {
                    out.insert(o, material);
                }
            }
        }
        out
    }

    /// The mesh if it was loaded already (nothing is read).
    #[must_use]
    pub fn peek(&self, base_dir: Option<&Path>, path: &str, mesh: Option<usize>) -> Option<&FileMesh> {
        self.meshes.get(&(full_path(base_dir, path), mesh))?.as_ref().ok()
    }

    /// Stores a mesh (and its material) loaded elsewhere (by a background import) under its
    /// full path.
    pub fn insert(
        &mut self,
        path: PathBuf,
        mesh: Option<usize>,
        loaded: Result<(FileMesh, Option<keyrig_core::Material>), FileError>,
    ) {
        self.generation += 1;
        let key = (path, mesh);
        let loaded = loaded.map(|(loaded, material)| {
            match material {
                Some(material) => self.materials.insert(key.clone(), std::sync::Arc::new(material)),
                None => self.materials.remove(&key),
            };
            loaded
        });
        self.meshes.insert(key, loaded);
    }

    /// How many meshes were loaded or stored so far.
    #[must_use]
    pub fn generation(&self) -> u64 {
        self.generation
    }

    /// What the scene evaluator needs of the loaded meshes of `scene`'s model-file objects,
    /// by object index (meshes not loaded yet are left out).
    #[must_use]
    pub fn loaded_for(
        &self,
        base_dir: Option<&Path>,
        scene: &keyrig_core::Scene,
    ) -> HashMap<usize, keyrig_eval::LoadedMesh> {
        let mut out = HashMap::new();
        for (o, object) in scene.objects.iter().enumerate() {
            if let Some(keyrig_core::MeshSource::File { path, mesh, .. }) = &object.mesh {
                let loaded = match self.peek(base_dir, path, *mesh) {
                    Some(FileMesh::Skinned(m)) => keyrig_eval::LoadedMesh::Skinned(std::sync::Arc::clone(m)),
                    Some(FileMesh::Morph(m)) => {
                        keyrig_eval::LoadedMesh::Morph(std::sync::Arc::clone(m.playback()))
                    }
                    Some(FileMesh::Static { .. }) => keyrig_eval::LoadedMesh::Static,
                    None => continue,
                };
                out.insert(o, loaded);
            }
        }
        out
    }
}

fn full_path(base_dir: Option<&Path>, path: &str) -> PathBuf {
    match base_dir {
        Some(dir) => dir.join(path),
        None => PathBuf::from(path),
    }
}

/// A model file's mesh and, for glTF, its material ([`keyrig_io::model::ImportedModel::material`];
/// a texture that cannot be decoded leaves the base colour alone). An MD2 mesh carries its
/// skin itself.
fn load_file_mesh(
    path: &Path,
    mesh: Option<usize>,
) -> Result<(FileMesh, Option<keyrig_core::Material>), FileError> {
    match extension(path).as_deref() {
        Some("glb" | "gltf") => {}
        Some("md2") => {
            let data = keyrig_io::file_io::read_regular_file(path, keyrig_io::file_io::MAX_MD2_BYTES)
                .map_err(|e| FileError::Read { path: path.to_path_buf(), source: Arc::new(e) })?;
            return md2_morph_mesh(path, &data).map(|m| (FileMesh::Morph(std::sync::Arc::new(m)), None));
        }
        _ => return Err(FileError::NotAMeshFile { path: path.to_path_buf() }),
    }
    let model = keyrig_io::gltf_import::import_gltf_file(path)?;
    let index = mesh.unwrap_or(0);
    let Some(node) = model.nodes.iter().position(|n| n.mesh == Some(index)) else {
        return Err(FileError::NoSuchMesh { path: path.to_path_buf(), index });
    };
    let material = model.material(index).unwrap_or_else(|e| Some(e.without_texture()));
    if model.nodes[node].skin.is_some() {
        return model
            .skinned_mesh(node)
            .map(|m| (FileMesh::Skinned(std::sync::Arc::new(m)), material))
            .map_err(|e| FileError::SkinnedMesh { path: path.to_path_buf(), source: Arc::new(e) });
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
    Ok((FileMesh::Static { positions, indices }, material))
}

/// Skinned and vertex-animated (MD2) meshes of every object of `scene` whose mesh is a model
/// file, by object index, for [`keyrig_render::SceneRig::with_loaded`]; relative paths
/// resolve against `base_dir` (the scene's folder). `keyrig render scene.ron` and the
/// editor's loading share this.
///
/// # Errors
/// A file that cannot be read, or a glTF mesh without a skin (keyrig-render draws file
/// meshes skinned or morphed), naming the object.
pub fn render_meshes(scene: &Scene, base_dir: Option<&Path>) -> Result<RenderMeshes, FileError> {
    let mut store = MeshStore::default();
    let (mut skinned, mut morphs) = (HashMap::new(), HashMap::new());
    for (o, object) in scene.objects.iter().enumerate() {
        let Some(keyrig_core::MeshSource::File { path, mesh, .. }) = &object.mesh else { continue };
        let at = || format!("objects[{o}] ({})", object.name);
        match store
            .get(base_dir, path, *mesh)
            .map_err(|e| FileError::OfObject { at: at(), source: Box::new(e) })?
        {
            FileMesh::Skinned(m) => {
                skinned.insert(o, (**m).clone());
            }
            FileMesh::Morph(m) => {
                morphs.insert(o, (**m).clone());
            }
            FileMesh::Static { .. } => return Err(FileError::NotSkinned { at: at(), path: path.clone() }),
        }
    }
    let materials = store.materials_for(base_dir, scene);
    Ok(RenderMeshes { skinned, morphs, materials })
}

/// The file meshes of a scene as keyrig-render takes them, by object index.
#[derive(Default)]
pub struct RenderMeshes {
    pub skinned: HashMap<usize, keyrig_skin::SkinnedMesh>,
    pub morphs: HashMap<usize, MorphMesh>,
    /// Materials of the skinned meshes (morph meshes carry theirs), for
    /// [`keyrig_render::SceneRig::with_materials`].
    pub materials: HashMap<usize, std::sync::Arc<keyrig_core::Material>>,
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
fn read_small_text(path: &Path) -> Option<String> {
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

    #[test]
    fn reading_reports_the_fraction_of_bytes_read() {
        let dir = tempfile::tempdir().expect("temp dir");
        let path = dir.path().join("big.md2");
        let bytes: Vec<u8> = (0..READ_CHUNK * 2 + 1000).map(|i| (i % 251) as u8).collect();
        fs::write(&path, &bytes).expect("write");
        let mut fractions = Vec::new();
        let data = read_with_progress(&path, &mut |f| fractions.push(f)).expect("read");
        assert_eq!(data, bytes);
        assert_eq!(fractions.len(), 3, "{fractions:?}");
        assert!(fractions.windows(2).all(|w| w[0] < w[1]), "{fractions:?}");
        assert_eq!(fractions.last(), Some(&1.0));
        let err = read_with_progress(&dir.path().join("missing.md2"), &mut |_| {}).expect_err("no file");
        assert!(matches!(err, FileError::Read { .. }), "{err:?}");
        let err = err.to_string();
        assert!(err.contains("missing.md2") && err.contains("cannot read"), "{err}");
    }

    #[test]
    fn unknown_extension_is_an_error_naming_the_file() {
        let err = open_any(Path::new("/tmp/x.txt")).expect_err("txt is not a scene");
        assert!(matches!(&err, FileError::UnknownType { extension, .. } if extension == "txt"), "{err:?}");
        let err = err.to_string();
        assert!(err.contains("x.txt") && err.contains(".txt"), "{err}");
    }
}
