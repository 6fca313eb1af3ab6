//! The mesh store: the meshes of the model files a scene names, loaded once per (file, mesh
//! index) — a skinned glTF mesh bound to its skin's skeleton, a static glTF mesh, an MD2 model
//! as a morph mesh — with their materials (a glTF base colour and texture, an MD2 skin). The
//! editor's frame preparation and `keyrig render` read meshes through it.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::Vec3;
use keyrig_core::Scene;
use keyrig_render::{MorphClip, MorphMesh, SkinnedVertex};

use super::{extension, FileError};

/// The morph mesh of the MD2 file `path` whose bytes are `data`, textured with its skin
/// when one is found beside it ([`keyrig_io::md2::load_skin`]; a skin that cannot be decoded
/// leaves the model untextured rather than unreadable).
pub(super) fn md2_morph_mesh(path: &Path, data: &[u8]) -> Result<MorphMesh, FileError> {
    let mut model = keyrig_io::md2::parse_md2(data)
        .map_err(|e| FileError::Md2 { path: path.to_path_buf(), source: Arc::new(e) })?;
    model.skin = keyrig_io::md2::load_skin(path, &model.skin_names).ok().flatten();
    morph_mesh_from_md2(&model).map_err(|source| FileError::Morph { path: path.to_path_buf(), source })
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

/// A model file's mesh as [`MeshStore`] keys it (full path, mesh index) and how loading it
/// went: the mesh and, for glTF, its material (an MD2 mesh carries its skin itself).
pub type LoadedMesh =
    ((PathBuf, Option<usize>), Result<(FileMesh, Option<keyrig_core::Material>), FileError>);

/// How loading one mesh of a model file went: the mesh and, for glTF, its material.
pub(super) type MeshLoad = Result<(FileMesh, Option<keyrig_core::Material>), FileError>;

pub(super) fn is_gltf(path: &Path) -> bool {
    matches!(extension(path).as_deref(), Some("glb" | "gltf" | "fbx"))
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

/// A mesh read from a model file.
#[derive(Clone, Debug)]
pub enum FileMesh {
    /// A skinned mesh, bound to its skin's skeleton (a glTF mesh without a skin: bound rigidly
    /// to one root joint, [`keyrig_io::model::ImportedModel::rigid_mesh`]).
    Skinned(std::sync::Arc<keyrig_skin::SkinnedMesh>),
    /// A vertex-animated mesh (MD2): every frame, its triangles and clips.
    Morph(std::sync::Arc<MorphMesh>),
}

impl FileMesh {
    /// Positions at rest (the skinned mesh's bind pose, a morph mesh's first frame).
    #[must_use]
    pub fn rest_positions(&self) -> Vec<Vec3> {
        match self {
            FileMesh::Skinned(m) => m.positions.clone(),
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
            self.generation += 1;
            match keyrig_io::vrml::import_vrml_file(&key.0) {
                Ok(model) => {
                    for (k, loaded) in vrml_meshes(&key.0, &model) {
                        self.keep(k, loaded);
                    }
                    if !self.meshes.contains_key(&key) {
                        let index = mesh.unwrap_or(0);
                        self.keep(key.clone(), Err(FileError::NoSuchMesh { path: key.0.clone(), index }));
                    }
                }
                Err(e) => self.keep(key.clone(), Err(FileError::Vrml(Arc::new(e)))),
            }
        }
        if !self.meshes.contains_key(&key) {
            self.generation += 1;
            if is_gltf(&key.0) {
                // Every mesh of the file from one import: a scene that shows many meshes of one
                // file reads it once.
                match load_gltf_meshes(&key.0) {
                    Ok(all) => {
                        for (index, loaded) in all.into_iter().enumerate() {
                            if index == 0 {
                                self.keep((key.0.clone(), None), loaded.clone());
                            }
                            self.keep((key.0.clone(), Some(index)), loaded);
                        }
                        if !self.meshes.contains_key(&key) {
                            let index = mesh.unwrap_or(0);
                            self.keep(key.clone(), Err(FileError::NoSuchMesh { path: key.0.clone(), index }));
                        }
                    }
                    Err(e) => self.keep(key.clone(), Err(e)),
                }
            } else {
                let loaded = load_file_mesh(&key.0, mesh);
                self.keep(key.clone(), loaded);
            }
        }
        self.meshes[&key].as_ref().map_err(Clone::clone)
    }

    /// Stores how loading one mesh went, its material apart.
    fn keep(&mut self, key: (PathBuf, Option<usize>), loaded: MeshLoad) {
        let loaded = loaded.map(|(loaded, material)| {
            if let Some(material) = material {
                self.materials.insert(key.clone(), std::sync::Arc::new(material));
            }
            loaded
        });
        self.meshes.insert(key, loaded);
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
pub(super) fn load_file_mesh(
    path: &Path,
    mesh: Option<usize>,
) -> Result<(FileMesh, Option<keyrig_core::Material>), FileError> {
    match extension(path).as_deref() {
        Some("glb" | "gltf" | "fbx") => {}
        Some("md2") => {
            let data = keyrig_io::file_io::read_regular_file(path, keyrig_io::file_io::MAX_MD2_BYTES)
                .map_err(|e| FileError::Read { path: path.to_path_buf(), source: Arc::new(e) })?;
            return md2_morph_mesh(path, &data).map(|m| (FileMesh::Morph(std::sync::Arc::new(m)), None));
        }
        _ => return Err(FileError::NotAMeshFile { path: path.to_path_buf() }),
    }
    let model = keyrig_io::fbx::import_model_file(path)?;
    let index = mesh.unwrap_or(0);
    let node = model.nodes.iter().position(|n| n.mesh == Some(index));
    gltf_mesh(&model, path, index, node)
}

/// Every mesh of the glTF file at `path` by mesh index, from one import: a file of many meshes
/// is read once, not once per mesh.
pub(super) fn load_gltf_meshes(path: &Path) -> Result<Vec<MeshLoad>, FileError> {
    let model = keyrig_io::fbx::import_model_file(path)?;
    let mut node_of_mesh = vec![None; model.meshes.len()];
    for (n, node) in model.nodes.iter().enumerate() {
        if let Some(slot) = node.mesh.and_then(|m| node_of_mesh.get_mut(m)) {
            slot.get_or_insert(n);
        }
    }
    // Meshes without a skin that show the same accessors (a file that reuses one mesh's data in
    // many meshes) share one rigid mesh: memory follows the file's data, not its mesh count.
    let mut rigid: HashMap<Vec<[usize; 5]>, std::sync::Arc<keyrig_skin::SkinnedMesh>> = HashMap::new();
    let mut out = Vec::with_capacity(node_of_mesh.len());
    for (index, node) in node_of_mesh.into_iter().enumerate() {
        let unskinned = node.is_some_and(|n| model.nodes[n].skin.is_none());
        let key = unskinned.then(|| accessors_of(&model.meshes[index]));
        if let Some(shared) = key.as_ref().and_then(|k| rigid.get(k)) {
            let material = model.material(index).unwrap_or_else(|e| Some(e.without_texture()));
            out.push(Ok((FileMesh::Skinned(std::sync::Arc::clone(shared)), material)));
            continue;
        }
        let loaded = gltf_mesh(&model, path, index, node);
        if let (Some(key), Ok((FileMesh::Skinned(mesh), _))) = (key, &loaded) {
            rigid.insert(key, std::sync::Arc::clone(mesh));
        }
        out.push(loaded);
    }
    Ok(out)
}

/// The decoded data a mesh's triangle primitives show (by address: keyrig-io decodes each
/// accessor once, so equal addresses are the same accessor).
fn accessors_of(mesh: &keyrig_io::model::ModelMesh) -> Vec<[usize; 5]> {
    fn address<T>(data: Option<&std::sync::Arc<[T]>>) -> usize {
        data.map_or(0, |d| d.as_ptr() as usize)
    }
    mesh.primitives
        .iter()
        .filter(|p| p.mode == keyrig_io::model::PrimitiveMode::Triangles)
        .map(|p| {
            [
                address(Some(&p.positions)),
                address(p.normals.as_ref()),
                address(p.texcoords.as_ref()),
                address(Some(&p.indices)),
                p.positions.len(),
            ]
        })
        .collect()
}

/// Mesh `index` of a glTF model as the first node that shows it (`node`) uses it: skinned by
/// that node's skin, or bound rigidly to one root joint when the node has none (drawn and
/// posed like any skinned mesh, placed by its object); with the mesh's material.
fn gltf_mesh(
    model: &keyrig_io::model::ImportedModel,
    path: &Path,
    index: usize,
    node: Option<usize>,
) -> MeshLoad {
    let Some(node) = node else {
        return Err(FileError::NoSuchMesh { path: path.to_path_buf(), index });
    };
    let material = model.material(index).unwrap_or_else(|e| Some(e.without_texture()));
    let skinned =
        if model.nodes[node].skin.is_some() { model.skinned_mesh(node) } else { model.rigid_mesh(index) };
    skinned
        .map(|m| (FileMesh::Skinned(std::sync::Arc::new(m)), material))
        .map_err(|e| FileError::SkinnedMesh { path: path.to_path_buf(), source: Arc::new(e) })
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
