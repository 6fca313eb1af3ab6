//! Reading a model (glTF, MD2) as a scene of its own, with its meshes, reporting its stages; on
//! a background thread for the editor ([`BackgroundImport`]), whose finished import the editor
//! applies as one undoable edit or as the new document.

use std::collections::HashMap;
use std::fs;
use std::path::{Path, PathBuf};
use std::sync::{Arc, Mutex};
use std::time::{Duration, Instant};

use glam::Vec3;
use keyrig_core::Scene;

use super::meshes::{
    is_gltf, load_file_mesh, load_gltf_meshes, md2_morph_mesh, vrml_meshes, FileMesh, LoadedMesh, MeshLoad,
};
use super::{extension, md2_rotation, FileError, MD2_SCALE};

/// Reads a model as a scene of its own. glTF (.glb, .gltf) maps onto keyrig through keyrig-io:
/// skinned meshes with their skeleton and every animation as an action, other
/// meshes as objects, KHR lights as lights. An MD2 model becomes one object named after the
/// file, playing every frame at [`keyrig_core::MD2_DEFAULT_FPS`], turned Y-up and scaled to
/// metres ([`md2_rotation`], [`MD2_SCALE`]) and raised so that its first frame stands on the
/// ground; the frame range covers one loop of it. The
/// meshes stay in the file (`MeshSource::File`, with the model's absolute path) and are
/// loaded by [`MeshStore`].
pub fn import_model(path: &Path) -> Result<Scene, FileError> {
    read_model(path, &mut |_, _| {}).map(|read| read.scene)
}

/// A model file as [`read_model`] read it.
pub(super) struct ModelRead {
    pub scene: Scene,
    /// The meshes read on the way (an MD2 file's morph mesh, VRML meshes).
    pub meshes: Vec<LoadedMesh>,
    /// Whether the model brings its own view (a VRML `Viewpoint`).
    pub own_camera: bool,
    /// What the file holds that was not imported, one line per kind.
    pub not_imported: Vec<String>,
    /// The file's own length unit and how it became metres ("glTF lengths are metres").
    pub unit: String,
}

/// Progress of a model read: the stage and, where known, the done fraction.
type ProgressFn<'a> = &'a mut dyn FnMut(&str, Option<f32>);

/// [`import_model`], with the meshes it read on the way (an MD2 file's morph mesh), so that
/// they need not be read again, reporting its stages to `progress`: glTF is read and parsed
/// by keyrig-io in one step (no fraction); an MD2 file is read in chunks (fraction of its
/// bytes), then parsed (no fraction); a VRML, X3D or Open Inventor file is read, parsed and
/// mapped by keyrig-io in one step, and its meshes built at once. The flag says whether the
/// model brings its own view (a VRML `Viewpoint`), which framing then keeps; the lines say
/// what the file holds that was not imported (VRML, X3D, Inventor); the unit says what the
/// file's lengths are in (glTF: metres; FBX: its own unit, which ufbx converts to metres;
/// VRML, X3D, Inventor: metres by convention; MD2: Quake units scaled to metres).
pub(super) fn read_model(path: &Path, progress: ProgressFn<'_>) -> Result<ModelRead, FileError> {
    let absolute = || fs::canonicalize(path).unwrap_or_else(|_| path.to_path_buf());
    if keyrig_io::vrml::is_vrml_path(path) {
        progress("reading and parsing", None);
        let model = keyrig_io::vrml::import_vrml_file(path)?;
        let file = absolute();
        let scene = model.to_scene(&file.to_string_lossy());
        progress("building meshes", None);
        return Ok(ModelRead {
            scene,
            meshes: vrml_meshes(&file, &model),
            own_camera: !model.views.is_empty(),
            not_imported: model.skipped_lines(),
            unit: "VRML, X3D and Inventor lengths are metres".to_owned(),
        });
    }
    if keyrig_io::bvh::is_bvh_path(path) {
        progress("reading and parsing", None);
        return Ok(ModelRead {
            scene: keyrig_io::bvh::import_scene(path)?,
            meshes: Vec::new(),
            own_camera: false,
            not_imported: Vec::new(),
            unit: "BVH has no unit: its lengths are taken as metres".to_owned(),
        });
    }
    match extension(path).as_deref() {
        Some(ext @ ("glb" | "gltf" | "fbx")) => {
            progress("reading and parsing", None);
            let (model, unit) = if ext == "fbx" {
                let fbx = keyrig_io::fbx::import_fbx(path).map_err(keyrig_io::fbx::ModelImportError::from)?;
                // ufbx scales the file's unit to metres (keyrig_from_file holds the factor).
                let metres = fbx.keyrig_from_file.x_axis.truncate().length();
                let unit = if (metres - 1.0).abs() < 1e-4 {
                    "FBX unit: metres".to_owned()
                } else {
                    format!("FBX unit: {}, converted to metres", super::placement::unit_name(metres))
                };
                (fbx.model, unit)
            } else {
                (keyrig_io::fbx::import_model_file(path)?, "glTF lengths are metres".to_owned())
            };
            let scene = model
                .to_scene_all(&absolute().to_string_lossy())
                .map_err(|e| FileError::Mapping { path: path.to_path_buf(), source: Arc::new(e) })?;
            Ok(ModelRead { scene, meshes: Vec::new(), own_camera: false, not_imported: Vec::new(), unit })
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
            Ok(ModelRead {
                scene,
                meshes: vec![(
                    (PathBuf::from(file), None),
                    Ok((FileMesh::Morph(std::sync::Arc::new(mesh)), None)),
                )],
                own_camera: false,
                not_imported: Vec::new(),
                unit: format!("MD2 Quake units, scaled to metres (×{MD2_SCALE})"),
            })
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

/// The last frame of a range starting at 0 that shows `seconds` of looping animation at
/// `fps` timeline frames per second (the frame after it is the loop's first again).
#[must_use]
pub fn frame_range_end(seconds: f64, fps: f64) -> i32 {
    keyrig_io::md2::frame_range_end(seconds, fps)
}

/// Points a model's new scene's camera at its meshes (rest pose, first MD2 frame), unless the
/// model brought its own view (`own_camera`), and adds a sun when it has no light, as
/// `keyrig render` does for models.
pub(super) fn frame_new_scene(scene: &mut Scene, meshes: &[LoadedMesh], own_camera: bool) {
    if own_camera {
        frame_model_scene(scene, std::iter::empty());
        return;
    }
    let points = rest_points(scene, meshes);
    frame_model_scene(scene, points);
}

use super::placement::rest_points;
pub use super::placement::rest_world_from_object;

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
            attributes: Default::default(),
        });
        scene.ambient = Vec3::splat(0.15);
    }
}

/// Loads the mesh of every object of `scene` whose mesh is a file (once per file and mesh
/// index) that is not among `read` already, calling `progress` with (done, total) before the
/// first and after each.
pub(super) fn load_meshes_of(
    scene: &Scene,
    read: Vec<LoadedMesh>,
    progress: &mut dyn FnMut((usize, usize)),
) -> Vec<LoadedMesh> {
    let mut seen: std::collections::HashSet<(PathBuf, Option<usize>)> =
        read.iter().map(|(key, _)| key.clone()).collect();
    let mut wanted: Vec<(PathBuf, Option<usize>)> = Vec::new();
    for object in &scene.objects {
        if let Some(keyrig_core::MeshSource::File { path, mesh, .. }) = &object.mesh {
            let key = (PathBuf::from(path), *mesh);
            if seen.insert(key.clone()) {
                wanted.push(key);
            }
        }
    }
    let total = wanted.len();
    if total > 0 {
        progress((0, total));
    }
    let mut meshes = read;
    // A glTF file is imported once for all the meshes wanted of it (once per mesh made a file
    // of 100,000 meshes take hours).
    let mut files: HashMap<PathBuf, Result<Vec<MeshLoad>, FileError>> = HashMap::new();
    let mut vrml_files: HashMap<PathBuf, Result<HashMap<Option<usize>, MeshLoad>, FileError>> =
        HashMap::new();
    for (i, (path, mesh)) in wanted.into_iter().enumerate() {
        let loaded = if keyrig_io::vrml::is_vrml_path(&path) {
            // A VRML file is read once for all of its meshes, found by key.
            let all =
                vrml_files.entry(path.clone()).or_insert_with(|| {
                    match keyrig_io::vrml::import_vrml_file(&path) {
                        Ok(model) => {
                            Ok(vrml_meshes(&path, &model).into_iter().map(|((_, m), l)| (m, l)).collect())
                        }
                        Err(e) => Err(FileError::Vrml(Arc::new(e))),
                    }
                });
            match all {
                Ok(all) => all.get(&mesh).cloned().unwrap_or_else(|| {
                    Err(FileError::NoSuchMesh { path: path.clone(), index: mesh.unwrap_or(0) })
                }),
                Err(e) => Err(e.clone()),
            }
        } else if is_gltf(&path) {
            let all = files.entry(path.clone()).or_insert_with(|| load_gltf_meshes(&path));
            match all {
                Ok(all) => all.get(mesh.unwrap_or(0)).cloned().unwrap_or_else(|| {
                    Err(FileError::NoSuchMesh { path: path.clone(), index: mesh.unwrap_or(0) })
                }),
                Err(e) => Err(e.clone()),
            }
        } else {
            load_file_mesh(&path, mesh)
        };
        progress((i + 1, total));
        meshes.push(((path, mesh), loaded));
    }
    meshes
}

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
    /// The file's own length unit and how it became metres ("glTF lengths are metres").
    pub unit: String,
}

/// A model import running on its own thread.
pub struct BackgroundImport {
    pub path: PathBuf,
    pub purpose: ImportPurpose,
    /// The import scale applied to the model ([`super::placement::scale_by`]); 1 keeps the
    /// file's unit.
    pub scale: f32,
    started: Instant,
    progress: Arc<Mutex<ImportProgress>>,
    handle: std::thread::JoinHandle<Result<LoadedModel, FileError>>,
}

impl BackgroundImport {
    /// Starts reading the model at `path` on a new thread, scaled by `scale` (a checked import
    /// scale, [`super::placement::check_import_scale`]; 1 keeps the file's unit).
    #[must_use]
    pub fn start(path: PathBuf, purpose: ImportPurpose, scale: f32) -> Self {
        let progress = Arc::new(Mutex::new(ImportProgress { stage: "reading".to_owned(), fraction: None }));
        let shared = Arc::clone(&progress);
        let file = path.clone();
        let handle = std::thread::spawn(move || {
            let set = |stage: &str, fraction: Option<f32>| {
                if let Ok(mut p) = shared.lock() {
                    *p = ImportProgress { stage: stage.to_owned(), fraction };
                }
            };
            let ModelRead { mut scene, meshes, own_camera, not_imported, unit } =
                read_model(&file, &mut |stage, fraction| set(stage, fraction))?;
            let meshes = load_meshes_of(&scene, meshes, &mut |(done, total)| {
                set("loading meshes", Some(done as f32 / total.max(1) as f32));
            });
            if purpose == ImportPurpose::Open {
                frame_new_scene(&mut scene, &meshes, own_camera);
            }
            super::placement::scale_by(&mut scene, scale);
            Ok(LoadedModel { scene, meshes, not_imported, unit })
        });
        BackgroundImport { path, purpose, scale, started: Instant::now(), progress, handle }
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

#[cfg(test)]
mod tests {
    use super::*;

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
}
