//! FBX import (binary and ASCII, FBX 3000–7700) through [ufbx](https://github.com/ufbx/ufbx),
//! mapped into the same [`ImportedModel`] the glTF importer fills, so that everything after
//! import ([`ImportedModel::to_scene`], `rigid_mesh` / `skinned_mesh`, glTF export, `keyrig
//! deform`) reads an FBX file exactly as it reads a glTF one. docs/interchange.md ("FBX
//! import") says what is read and what is left out.
//!
//! What ufbx is asked to do, so that the model is in keyrig's space and glTF's conventions:
//! - **Units and axes**: metres, +Y up, right-handed, cameras and lights looking down −Z
//!   (`target_unit_meters`, `target_axes`, `target_camera_axes`, `target_light_axes`), by
//!   scaling the geometry and adjusting the root transforms (`SpaceConversion::ModifyGeometry`):
//!   joints keep unit scale. [`FbxImport::keyrig_from_file`] is the map from the file's own
//!   units and axes to the model's.
//! - **Pivots, pre/post rotations, rotation orders, inherit modes**: resolved by ufbx into each
//!   node's local translation/rotation/scale (`ufbx_node.local_transform`); nodes whose
//!   parent's scale must not reach them get ufbx's scale helper nodes
//!   (`InheritModeHandling::Compensate`).
//! - **Geometric transforms** (a mesh's offset from its node that children do not inherit):
//!   baked into the mesh's vertices, or a helper node where an instanced mesh needs one
//!   (`GeometryTransformHandling::ModifyGeometry`).
//! - **Animation**: every animation stack baked by `ufbx_bake_anim` into linear TRS keys (the
//!   layers of the stack evaluated and blended as the file's tool does: additive and override
//!   layers, layer weights, Euler rotation orders), one [`ModelAnimation`] per stack with the
//!   stack's name. keyrig has no animation layers; a stack's layers are merged on import.
//!
//! The file is untrusted: ufbx checks it (its errors become [`FbxError`] with the file and
//! ufbx's description), runs under memory limits proportional to the file's size, and
//! everything read from its result is indexed with checks, its numbers checked finite and its
//! counts bounded ([`MAX_BAKED_KEYS`]).

use std::collections::{HashMap, HashSet};
use std::path::{Path, PathBuf};
use std::sync::Arc;

use glam::{Mat4, Quat, Vec2, Vec3, Vec4};
use keyrig_core::{DeformerKind, Interpolation, Key, RawTrack};

use crate::model::{
    ChannelTarget, ImageData, ImageSource, ImportedModel, ModelAnimation, ModelCamera, ModelChannel,
    ModelLight, ModelLightKind, ModelMesh, ModelNode, ModelPrimitive, ModelProjection, ModelSkin,
    MorphTarget, PrimitiveMode, TextureRef, WeightsTrack,
};

/// The most keys all baked animation stacks of one file may hold together (translation,
/// rotation, scale and morph-weight keys): a file asking for more is refused, not allocated.
pub const MAX_BAKED_KEYS: usize = 20_000_000;

/// The most morph-target displacements one mesh may expand to (blend channels × face corners):
/// FBX stores only the vertices a shape moves, keyrig a displacement for every vertex.
pub const MAX_MORPH_VALUES: usize = 16_000_000;

/// The most bytes a texture file next to the model is read (larger ones are left out).
const MAX_TEXTURE_BYTES: u64 = 256 << 20;

/// Whether `path` names an FBX file (by its extension, any case).
#[must_use]
pub fn is_fbx_path(path: &Path) -> bool {
    path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("fbx"))
}

/// What went wrong.
#[derive(Debug, thiserror::Error)]
pub enum FbxErrorKind {
    #[error("cannot read: {0}")]
    Io(#[from] std::io::Error),
    /// ufbx refused the file: its error type, description and the extra information some of
    /// its errors carry (ufbx reports no byte offset or line).
    #[error("ufbx: {description} ({error_type}){}", if detail.is_empty() { String::new() } else { format!(": {detail}") })]
    Ufbx { error_type: String, description: String, detail: String },
    /// ufbx could not bake an animation stack.
    #[error("animation stack {stack} ({name:?}): ufbx: {description}")]
    Bake { stack: usize, name: String, description: String },
    /// A number of the file that keyrig needs finite is not.
    #[error("{0} is not finite")]
    NonFinite(String),
    /// The file asks for more than keyrig holds.
    #[error("{what}: {count} is more than the {limit} keyrig reads")]
    TooLarge { what: String, count: usize, limit: usize },
}

/// An FBX import error: the file (when known) and what.
#[derive(Debug, thiserror::Error)]
#[error("{}{kind}", file.as_ref().map(|f| format!("{}: ", f.display())).unwrap_or_default())]
pub struct FbxError {
    pub file: Option<PathBuf>,
    pub kind: FbxErrorKind,
}

impl From<FbxErrorKind> for FbxError {
    fn from(kind: FbxErrorKind) -> Self {
        FbxError { file: None, kind }
    }
}

/// An imported FBX file: the model, and what the mapping did to the file's space.
#[derive(Clone, Debug)]
pub struct FbxImport {
    pub model: ImportedModel,
    /// The file's own units and axes → the model's (metres, +Y up, right-handed): a
    /// rotation, a uniform scale and, for a left-handed file, a mirror. A position the file's
    /// tool reports (an OBJ it exported) maps onto the model's by this matrix.
    pub keyrig_from_file: Mat4,
    /// The file's frame rate (frames per second), for frame ↔ time.
    pub frames_per_second: f64,
    /// The bind-pose world matrix (model space) of each node of the model, where the file's
    /// bind pose lists the node (mesh nodes of skinned meshes, usually).
    pub bind_world: Vec<Option<Mat4>>,
    /// What ufbx warned about and what the mapping left out, one line each.
    pub warnings: Vec<String>,
}

/// A glTF or FBX model file that could not be imported ([`import_model_file`]).
#[derive(Debug, thiserror::Error)]
pub enum ModelImportError {
    #[error(transparent)]
    Gltf(#[from] crate::gltf_import::GltfError),
    #[error(transparent)]
    Fbx(#[from] FbxError),
}

/// The model file at `path` as an [`ImportedModel`]: FBX by its extension
/// ([`is_fbx_path`], [`import_fbx_file`]), else glTF ([`crate::gltf_import::import_gltf_file`]).
/// The one call for code that reads a model wherever it read a glTF one.
///
/// # Errors
/// The importer's error.
pub fn import_model_file(path: &Path) -> Result<ImportedModel, ModelImportError> {
    if is_fbx_path(path) {
        Ok(import_fbx_file(path)?)
    } else {
        Ok(crate::gltf_import::import_gltf_file(path)?)
    }
}

/// Reads and imports the FBX file at `path` (a regular file of at most
/// [`crate::file_io::MAX_MODEL_BYTES`] bytes). Texture files are looked up next to it.
///
/// # Errors
/// The file cannot be read, ufbx refuses it, or it holds what keyrig cannot take (non-finite
/// transforms, more than [`MAX_BAKED_KEYS`] keys); the error names the file.
pub fn import_fbx_file(path: &Path) -> Result<ImportedModel, FbxError> {
    import_fbx(path).map(|i| i.model)
}

/// [`import_fbx_file`], with what the mapping did to the file's space.
///
/// # Errors
/// As [`import_fbx_file`].
pub fn import_fbx(path: &Path) -> Result<FbxImport, FbxError> {
    let with_file = |kind: FbxErrorKind| FbxError { file: Some(path.to_path_buf()), kind };
    let data = crate::file_io::read_regular_file(path, crate::file_io::MAX_MODEL_BYTES)
        .map_err(|e| with_file(FbxErrorKind::Io(e)))?;
    import(&data, Some(path)).map_err(|e| with_file(e.kind))
}

/// Imports an FBX file held in memory. Texture files cannot be looked up (there is no folder):
/// only textures embedded in the file have bytes.
///
/// # Errors
/// As [`import_fbx_file`], without a file name.
pub fn import_fbx_slice(data: &[u8]) -> Result<FbxImport, FbxError> {
    import(data, None)
}

fn memory_limit(file_len: usize) -> usize {
    // ufbx's own structures are a few times the file; compressed arrays may expand up to the
    // limit and no further.
    let cap = usize::try_from(4u64 << 30).unwrap_or(usize::MAX);
    file_len.saturating_mul(64).saturating_add(256 << 20).min(cap)
}

fn allocator(limit: usize) -> ufbx::AllocatorOpts {
    ufbx::AllocatorOpts { memory_limit: limit, ..Default::default() }
}

fn y_up() -> ufbx::CoordinateAxes {
    ufbx::CoordinateAxes {
        right: ufbx::CoordinateAxis::PositiveX,
        up: ufbx::CoordinateAxis::PositiveY,
        front: ufbx::CoordinateAxis::PositiveZ,
    }
}

/// ufbx's error as keyrig reports it: its type and description, and as detail the extra
/// information ufbx gives (an element's name, a byte offset or a count, where it has one), else
/// the innermost step of its parse that failed (a function of ufbx.c and its check).
fn ufbx_error(error: &ufbx::Error) -> FbxErrorKind {
    let mut buf = vec![0u8; 4096];
    let len = ufbx::format_error(&mut buf, error).min(buf.len());
    let text = String::from_utf8_lossy(&buf[..len]);
    // `ufbx_format_error` writes a first line with the description, then the information line
    // (when there is one), then the stack, one `LINE:FUNCTION: CHECK` line per step.
    let is_frame = |l: &str| {
        let t = l.trim_start();
        t.split(':').next().is_some_and(|n| !n.is_empty() && n.bytes().all(|b| b.is_ascii_digit()))
    };
    let mut detail: Vec<String> = text
        .lines()
        .skip(1)
        .filter(|l| !l.trim().is_empty() && !is_frame(l))
        .map(|l| l.trim().to_owned())
        .collect();
    if detail.is_empty() {
        if let Some(frame) = error.stack.iter().take(error.stack_size as usize).next() {
            let function: &str = &frame.function;
            let check: &str = &frame.description;
            detail.push(format!("in {function} (ufbx.c line {}): {check}", frame.source_line));
        }
    }
    FbxErrorKind::Ufbx {
        error_type: format!("{:?}", error.type_),
        description: error.description.to_string(),
        detail: detail.join("; "),
    }
}

fn import(data: &[u8], path: Option<&Path>) -> Result<FbxImport, FbxError> {
    let limit = memory_limit(data.len());
    let name = path.map(|p| p.to_string_lossy().into_owned());
    let opts = ufbx::LoadOpts {
        temp_allocator: allocator(limit),
        result_allocator: allocator(limit),
        file_format: ufbx::FileFormat::Fbx,
        no_format_from_extension: true,
        target_axes: y_up(),
        target_camera_axes: ufbx::CoordinateAxes {
            right: ufbx::CoordinateAxis::PositiveX,
            up: ufbx::CoordinateAxis::PositiveY,
            front: ufbx::CoordinateAxis::PositiveZ,
        },
        target_light_axes: y_up(),
        target_unit_meters: 1.0,
        space_conversion: ufbx::SpaceConversion::ModifyGeometry,
        geometry_transform_handling: ufbx::GeometryTransformHandling::ModifyGeometry,
        inherit_mode_handling: ufbx::InheritModeHandling::Compensate,
        generate_missing_normals: true,
        clean_skin_weights: true,
        filename: match &name {
            Some(n) => ufbx::StringOpt::Ref(n.as_str()),
            None => ufbx::StringOpt::Unset,
        },
        ..Default::default()
    };
    let scene = ufbx::load_memory(data, opts).map_err(|e| FbxError::from(ufbx_error(&e)))?;
    let folder = path.map(crate::file_io::parent_or_dot);
    Mapper::new(&scene, folder.as_deref(), limit).run()
}

fn vec3(v: ufbx::Vec3) -> Vec3 {
    Vec3::new(v.x as f32, v.y as f32, v.z as f32)
}

fn quat(q: ufbx::Quat) -> Quat {
    Quat::from_xyzw(q.x as f32, q.y as f32, q.z as f32, q.w as f32)
}

fn mat4(m: &ufbx::Matrix) -> Mat4 {
    Mat4::from_cols(
        Vec4::new(m.m00 as f32, m.m10 as f32, m.m20 as f32, 0.0),
        Vec4::new(m.m01 as f32, m.m11 as f32, m.m21 as f32, 0.0),
        Vec4::new(m.m02 as f32, m.m12 as f32, m.m22 as f32, 0.0),
        Vec4::new(m.m03 as f32, m.m13 as f32, m.m23 as f32, 1.0),
    )
}

fn finite_or(what: impl FnOnce() -> String, ok: bool) -> Result<(), FbxError> {
    if ok {
        Ok(())
    } else {
        Err(FbxErrorKind::NonFinite(what()).into())
    }
}

/// One ufbx mesh as keyrig reads it: its primitives, and the control point each primitive
/// vertex came from (for weights and blend-shape offsets).
struct MeshOut {
    mesh: ModelMesh,
    /// Per primitive, per vertex: the control point.
    control_points: Vec<Vec<u32>>,
}

struct Mapper<'a> {
    scene: &'a ufbx::Scene,
    folder: Option<&'a Path>,
    limit: usize,
    /// Model node of each ufbx node (by `typed_id`); `None` for the root.
    node_of: Vec<Option<usize>>,
    warnings: Vec<String>,
    keys: usize,
}

impl<'a> Mapper<'a> {
    fn new(scene: &'a ufbx::Scene, folder: Option<&'a Path>, limit: usize) -> Self {
        Mapper { scene, folder, limit, node_of: Vec::new(), warnings: Vec::new(), keys: 0 }
    }

    fn run(mut self) -> Result<FbxImport, FbxError> {
        let scene = self.scene;
        for w in scene.metadata.warnings.iter() {
            self.warnings.push(format!("ufbx: {}", w.description.as_ref() as &str));
        }
        let mut model = ImportedModel::default();
        self.read_nodes(&mut model)?;
        let bind_world = self.bind_world(&model);
        self.read_cameras_and_lights(&mut model);
        let blend_of_mesh = self.read_meshes(&mut model)?;
        model.animations = self.read_animations(&model, &blend_of_mesh)?;
        let meta = &scene.metadata;
        let rotation = quat(meta.root_rotation);
        let scale = scene.settings.original_unit_meters as f32;
        let scale = if scale.is_finite() && scale > 0.0 { scale } else { 1.0 };
        let mirror = match meta.mirror_axis {
            ufbx::MirrorAxis::X => Vec3::new(-1.0, 1.0, 1.0),
            ufbx::MirrorAxis::Y => Vec3::new(1.0, -1.0, 1.0),
            ufbx::MirrorAxis::Z => Vec3::new(1.0, 1.0, -1.0),
            ufbx::MirrorAxis::None => Vec3::ONE,
        };
        let keyrig_from_file = Mat4::from_scale(mirror)
            * Mat4::from_scale_rotation_translation(Vec3::splat(scale), rotation.normalize(), Vec3::ZERO);
        let fps = scene.settings.frames_per_second;
        Ok(FbxImport {
            model,
            keyrig_from_file: if keyrig_from_file.is_finite() { keyrig_from_file } else { Mat4::IDENTITY },
            frames_per_second: if fps.is_finite() && fps > 0.0 { fps } else { 24.0 },
            bind_world,
            warnings: self.warnings,
        })
    }

    fn model_node(&self, node: &ufbx::Node) -> Option<usize> {
        self.node_of.get(node.element.typed_id as usize).copied().flatten()
    }

    /// Every node but ufbx's root, parents before children (ufbx lists them so), names made
    /// unique (keyrig finds joints and channels by name).
    fn read_nodes(&mut self, model: &mut ImportedModel) -> Result<(), FbxError> {
        let nodes = &self.scene.nodes;
        self.node_of = vec![None; nodes.len()];
        let mut taken: HashSet<String> = HashSet::new();
        let mut suffix: HashMap<String, usize> = HashMap::new();
        for node in nodes.iter() {
            if node.is_root {
                continue;
            }
            let i = model.nodes.len();
            let t = &node.local_transform;
            let (translation, rotation, scale) = (vec3(t.translation), quat(t.rotation), vec3(t.scale));
            let base = node.element.name.to_string();
            finite_or(
                || format!("the transform of node {base:?}"),
                translation.is_finite() && rotation.is_finite() && scale.is_finite(),
            )?;
            let base = if base.is_empty() { format!("node{i}") } else { base };
            let mut name = base.clone();
            // The next suffix to try per name, so that many nodes of one name cost linear time.
            let mut n = suffix.get(&base).copied().unwrap_or(1);
            while !taken.insert(name.clone()) {
                name = format!("{base}.{n:03}");
                n += 1;
            }
            suffix.insert(base, n);
            let parent = node.parent.as_ref().and_then(|p| self.model_node(p));
            if let Some(p) = parent {
                model.nodes[p].children.push(i);
            } else {
                model.roots.push(i);
            }
            if let Some(slot) = self.node_of.get_mut(node.element.typed_id as usize) {
                *slot = Some(i);
            }
            model.nodes.push(ModelNode {
                name,
                parent,
                children: Vec::new(),
                translation,
                rotation: rotation.normalize(),
                scale,
                mesh: None,
                skin: None,
                light: None,
                camera: None,
                weights: None,
                visible: node.visible,
            });
        }
        Ok(())
    }

    fn bind_world(&self, model: &ImportedModel) -> Vec<Option<Mat4>> {
        let mut out = vec![None; model.nodes.len()];
        for pose in self.scene.poses.iter().filter(|p| p.is_bind_pose) {
            for bone in pose.bone_poses.iter() {
                if let Some(n) = self.model_node(&bone.bone_node) {
                    let m = mat4(&bone.bone_to_world);
                    if m.is_finite() && out[n].is_none() {
                        out[n] = Some(m);
                    }
                }
            }
        }
        out
    }

    fn read_cameras_and_lights(&mut self, model: &mut ImportedModel) {
        for node in self.scene.nodes.iter() {
            let Some(n) = self.model_node(node) else { continue };
            if let Some(camera) = &node.camera {
                let near = (camera.near_plane as f32).max(1e-4);
                let far = camera.far_plane as f32;
                let far = (far.is_finite() && far > near).then_some(far);
                let aspect = camera.aspect_ratio as f32;
                let aspect = (aspect.is_finite() && aspect > 0.0).then_some(aspect);
                let projection = match camera.projection_mode {
                    ufbx::ProjectionMode::Perspective => ModelProjection::Perspective {
                        yfov: (camera.field_of_view_deg.y as f32).to_radians().clamp(1e-3, 3.1),
                        aspect_ratio: aspect,
                        znear: near,
                        zfar: far,
                    },
                    ufbx::ProjectionMode::Orthographic => ModelProjection::Orthographic {
                        xmag: (camera.orthographic_size.x as f32 * 0.5).max(1e-6),
                        ymag: (camera.orthographic_size.y as f32 * 0.5).max(1e-6),
                        znear: near,
                        zfar: far.unwrap_or(near * 1e4),
                    },
                };
                let finite = match projection {
                    ModelProjection::Perspective { yfov, znear, .. } => yfov.is_finite() && znear.is_finite(),
                    ModelProjection::Orthographic { xmag, ymag, zfar, .. } => {
                        xmag.is_finite() && ymag.is_finite() && zfar.is_finite()
                    }
                };
                if finite {
                    model.nodes[n].camera = Some(model.cameras.len());
                    model.cameras.push(ModelCamera { name: camera.element.name.to_string(), projection });
                } else {
                    self.warnings
                        .push(format!("camera {:?}: non-finite lens, left out", model.nodes[n].name));
                }
            }
            if let Some(light) = &node.light {
                let kind = match light.type_ {
                    ufbx::LightType::Directional => ModelLightKind::Directional,
                    ufbx::LightType::Spot => ModelLightKind::Spot {
                        inner_cone_angle: (light.inner_angle as f32 * 0.5).to_radians(),
                        outer_cone_angle: (light.outer_angle as f32 * 0.5).to_radians(),
                    },
                    // Area and volume lights light as points in keyrig.
                    _ => ModelLightKind::Point,
                };
                let colour = vec3(light.color);
                let intensity = light.intensity as f32;
                if colour.is_finite() && intensity.is_finite() {
                    model.nodes[n].light = Some(model.lights.len());
                    model.lights.push(ModelLight {
                        name: light.element.name.to_string(),
                        kind,
                        colour,
                        intensity,
                        range: None,
                    });
                }
            }
        }
    }

    /// Meshes (one [`ModelMesh`] per ufbx mesh, shared by its instances), skins (one per
    /// skinned mesh) and the nodes that show them. Returns, per model mesh, its blend channels
    /// (element ids of the channels, in morph-target order).
    fn read_meshes(&mut self, model: &mut ImportedModel) -> Result<Vec<Vec<u32>>, FbxError> {
        let mut mesh_of: HashMap<u32, usize> = HashMap::new();
        let mut skin_of: HashMap<u32, Option<usize>> = HashMap::new();
        let mut blend_channels: Vec<Vec<u32>> = Vec::new();
        for node in self.scene.nodes.iter() {
            let Some(n) = self.model_node(node) else { continue };
            let Some(mesh) = &node.mesh else { continue };
            if node.geometry_transform_helper.is_some() {
                continue; // the helper below shows the mesh
            }
            let id = mesh.element.element_id;
            let m = match mesh_of.get(&id) {
                Some(&m) => m,
                None => {
                    let out = self.read_mesh(mesh, model)?;
                    let Some(mut out) = out else {
                        mesh_of.insert(id, usize::MAX);
                        continue;
                    };
                    let m = model.meshes.len();
                    let skin = self.read_skin(mesh, &mut out, model, n)?;
                    skin_of.insert(id, skin);
                    blend_channels.push(
                        mesh.blend_deformers
                            .iter()
                            .flat_map(|b| b.channels.iter())
                            .filter(|c| c.target_shape.is_some())
                            .map(|c| c.element.element_id)
                            .collect(),
                    );
                    model.meshes.push(out.mesh);
                    mesh_of.insert(id, m);
                    m
                }
            };
            if m == usize::MAX {
                continue;
            }
            model.nodes[n].mesh = Some(m);
            model.nodes[n].skin = skin_of.get(&id).copied().flatten();
        }
        Ok(blend_channels)
    }

    /// A mesh's faces triangulated (ufbx's triangulation), split by material into primitives,
    /// face corners with the same control point, normal and UV shared.
    fn read_mesh(
        &mut self,
        mesh: &ufbx::Mesh,
        model: &mut ImportedModel,
    ) -> Result<Option<MeshOut>, FbxError> {
        let name = mesh.element.name.to_string();
        // Morph targets: per blend channel, its target shape's offsets per control point.
        let channels: Vec<&ufbx::BlendChannel> = mesh
            .blend_deformers
            .iter()
            .flat_map(|b| b.channels.iter())
            .filter(|c| c.target_shape.is_some())
            .map(|c| &**c)
            .collect();
        // Morph targets are dense (a displacement per vertex, as glTF stores them), while an FBX
        // shape lists only the vertices it moves: bound what the expansion allocates.
        let morph_values = channels.len().saturating_mul(mesh.num_indices);
        if morph_values > MAX_MORPH_VALUES {
            return Err(FbxErrorKind::TooLarge {
                what: format!("mesh {name:?}: blend channels × face corners"),
                count: morph_values,
                limit: MAX_MORPH_VALUES,
            }
            .into());
        }
        let mut shape_offsets: Vec<(Vec<Vec3>, Vec<Vec3>, bool)> = Vec::with_capacity(channels.len());
        for channel in &channels {
            let Some(shape) = &channel.target_shape else { continue };
            let mut positions = vec![Vec3::ZERO; mesh.num_vertices];
            let mut normals = vec![Vec3::ZERO; mesh.num_vertices];
            let has_normals = !shape.normal_offsets.is_empty();
            for (k, &v) in shape.offset_vertices.iter().enumerate() {
                let Some(slot) = positions.get_mut(v as usize) else { continue };
                if let Some(&p) = shape.position_offsets.get(k) {
                    *slot = vec3(p);
                }
                if let (Some(slot), Some(&d)) = (normals.get_mut(v as usize), shape.normal_offsets.get(k)) {
                    *slot = vec3(d);
                }
            }
            finite_or(|| format!("a blend shape of mesh {name:?}"), positions.iter().all(|p| p.is_finite()))?;
            shape_offsets.push((positions, normals, has_normals));
        }
        // Faces by material part (all faces in one part when the mesh has no materials).
        let all: Vec<u32> = (0..mesh.faces.len() as u32).collect();
        let parts: Vec<(Option<u32>, &[u32])> = if mesh.material_parts.is_empty() {
            vec![(None, &all)]
        } else {
            mesh.material_parts.iter().map(|p| (Some(p.index), p.face_indices.as_ref())).collect()
        };
        let positions_in = &mesh.vertex_position;
        let normals_in = &mesh.vertex_normal;
        let uvs_in = &mesh.vertex_uv;
        let mut primitives = Vec::new();
        let mut control_points = Vec::new();
        let mut tri = vec![0u32; mesh.max_face_triangles.saturating_mul(3).min(1 << 20)];
        for (material, faces) in parts {
            let mut positions: Vec<Vec3> = Vec::new();
            let mut normals: Vec<Vec3> = Vec::new();
            let mut uvs: Vec<Vec2> = Vec::new();
            let mut points: Vec<u32> = Vec::new();
            let mut indices: Vec<u32> = Vec::new();
            let mut corner: HashMap<(u32, u32, u32), u32> = HashMap::new();
            for &f in faces {
                let Some(&face) = mesh.faces.get(f as usize) else { continue };
                if face.num_indices < 3 || (face.num_indices as usize - 2) * 3 > tri.len() {
                    continue;
                }
                let count = ufbx::triangulate_face(&mut tri, mesh, face) as usize;
                for &ix in tri.iter().take(count * 3) {
                    let ix = ix as usize;
                    let p = positions_in.indices.get(ix).copied().unwrap_or(0);
                    let nrm =
                        if normals_in.exists { normals_in.indices.get(ix).copied().unwrap_or(0) } else { 0 };
                    let uv = if uvs_in.exists { uvs_in.indices.get(ix).copied().unwrap_or(0) } else { 0 };
                    let next = positions.len() as u32;
                    let v = *corner.entry((p, nrm, uv)).or_insert_with(|| {
                        let pos = positions_in.values.get(p as usize).copied().map_or(Vec3::ZERO, vec3);
                        positions.push(pos);
                        let n = normals_in.values.get(nrm as usize).copied().map_or(Vec3::Y, vec3);
                        normals.push(n.try_normalize().unwrap_or(Vec3::Y));
                        let t = uvs_in.values.get(uv as usize).map_or(Vec2::ZERO, |t| {
                            // FBX's V runs up the image, glTF's (and keyrig's) down.
                            Vec2::new(t.x as f32, 1.0 - t.y as f32)
                        });
                        uvs.push(if t.is_finite() { t } else { Vec2::ZERO });
                        points.push(mesh.vertex_indices.get(ix).copied().unwrap_or(0));
                        next
                    });
                    indices.push(v);
                }
            }
            if indices.is_empty() {
                continue;
            }
            finite_or(
                || format!("a vertex position of mesh {name:?}"),
                positions.iter().all(|p| p.is_finite()),
            )?;
            let morph_targets = shape_offsets
                .iter()
                .map(|(dp, dn, has_normals)| MorphTarget {
                    positions: Some(
                        points.iter().map(|&c| dp.get(c as usize).copied().unwrap_or_default()).collect(),
                    ),
                    normals: has_normals.then(|| {
                        points.iter().map(|&c| dn.get(c as usize).copied().unwrap_or_default()).collect()
                    }),
                })
                .collect();
            let material = material.and_then(|m| mesh.materials.get(m as usize));
            let (base_colour_factor, base_colour_texture) = match material {
                Some(m) => self.read_material(m, model),
                None => ([1.0; 4], None),
            };
            primitives.push(ModelPrimitive {
                mode: PrimitiveMode::Triangles,
                positions: positions.into(),
                normals: Some(normals.into()),
                texcoords: uvs_in.exists.then(|| uvs.into()),
                indices: indices.into(),
                joint_sets: Vec::new(),
                weight_sets: Vec::new(),
                morph_targets,
                base_colour_factor,
                base_colour_texture,
                material: None,
            });
            control_points.push(points);
        }
        if primitives.is_empty() {
            self.warnings.push(format!("mesh {name:?} has no triangles (lines or points only), left out"));
            return Ok(None);
        }
        let weights =
            channels.iter().map(|c| c.weight as f32).map(|w| if w.is_finite() { w } else { 0.0 }).collect();
        Ok(Some(MeshOut {
            mesh: ModelMesh { name, primitives: Arc::new(primitives), weights },
            control_points,
        }))
    }

    /// The base colour (factor and texture) of a material: ufbx's PBR view of it (which maps
    /// Lambert/Phong diffuse colour × factor too).
    fn read_material(
        &mut self,
        material: &ufbx::Material,
        model: &mut ImportedModel,
    ) -> ([f32; 4], Option<TextureRef>) {
        let colour = &material.pbr.base_color;
        let mut c = if colour.has_value {
            [colour.value_vec4.x as f32, colour.value_vec4.y as f32, colour.value_vec4.z as f32, 1.0]
        } else {
            [1.0; 4]
        };
        let factor = &material.pbr.base_factor;
        if factor.has_value {
            let f = factor.value_vec4.x as f32;
            for x in c.iter_mut().take(3) {
                *x *= f;
            }
        }
        let c = c.map(|x| if x.is_finite() { x.clamp(0.0, 1e3) } else { 1.0 });
        let texture = colour.texture.as_ref().or(material.fbx.diffuse_color.texture.as_ref());
        let texture = texture.and_then(|t| self.read_texture(t, model));
        (c, texture)
    }

    fn read_texture(&mut self, texture: &ufbx::Texture, model: &mut ImportedModel) -> Option<TextureRef> {
        let relative = texture.relative_filename.to_string();
        let absolute = texture.filename.to_string();
        let uri = if relative.is_empty() { absolute.clone() } else { relative.clone() };
        if uri.is_empty() && texture.content.is_empty() {
            return None;
        }
        let image = match model.images.iter().position(|i| *i == ImageSource::Uri(uri.clone())) {
            Some(i) => i,
            None => {
                let bytes: Option<Vec<u8>> = if !texture.content.is_empty() {
                    Some(texture.content.to_vec())
                } else {
                    self.texture_file(&relative, &absolute)
                };
                let data = bytes.and_then(|b| {
                    let mime = if b.starts_with(b"\x89PNG") {
                        "image/png"
                    } else if b.starts_with(&[0xFF, 0xD8]) {
                        "image/jpeg"
                    } else {
                        return None;
                    };
                    Some(ImageData { bytes: b.into(), mime_type: mime.into() })
                });
                if data.is_none() {
                    self.warnings.push(format!("texture {uri:?}: no PNG or JPEG bytes found"));
                }
                model.images.push(ImageSource::Uri(uri));
                model.image_data.push(data);
                model.images.len() - 1
            }
        };
        let wrap = |w: ufbx::WrapMode| match w {
            ufbx::WrapMode::Repeat => keyrig_core::WrapMode::Repeat,
            ufbx::WrapMode::Clamp => keyrig_core::WrapMode::ClampToEdge,
        };
        let sampler = keyrig_core::Sampler {
            wrap_u: wrap(texture.wrap_u),
            wrap_v: wrap(texture.wrap_v),
            ..Default::default()
        };
        Some(TextureRef { texture: image, image, texcoord_set: 0, sampler })
    }

    /// A texture's bytes from a file next to the model: its relative path (inside the model's
    /// folder: no `..`, not absolute), else the file name of its absolute path in that folder.
    fn texture_file(&self, relative: &str, absolute: &str) -> Option<Vec<u8>> {
        let folder = self.folder?;
        let inside = |p: &Path| p.components().all(|c| matches!(c, std::path::Component::Normal(_)));
        let rel = Path::new(relative);
        let candidates = [
            (!relative.is_empty() && inside(rel)).then(|| folder.join(rel)),
            Path::new(&absolute.replace('\\', "/")).file_name().map(|n| folder.join(n)),
            Path::new(&relative.replace('\\', "/")).file_name().map(|n| folder.join(n)),
        ];
        candidates
            .into_iter()
            .flatten()
            .find_map(|p| crate::file_io::read_regular_file(&p, MAX_TEXTURE_BYTES).ok())
    }

    /// The first skin deformer of `mesh` as a glTF-style skin: its clusters' bone nodes are the
    /// joints, each with `geometry_to_bone` as inverse bind matrix, so that
    /// `model_from_joint · geometry_to_bone · v` is ufbx's (the FBX SDK's) skinned position and
    /// the mesh node's own transform is not applied (as glTF). Per vertex the four largest
    /// weights, normalised. Vertices without weights follow the mesh node (an extra joint,
    /// identity inverse bind matrix), as in the FBX SDK. The skin's method becomes
    /// [`ModelSkin::deformer`].
    fn read_skin(
        &mut self,
        mesh: &ufbx::Mesh,
        out: &mut MeshOut,
        model: &mut ImportedModel,
        mesh_node: usize,
    ) -> Result<Option<usize>, FbxError> {
        let Some(skin) = mesh.skin_deformers.first() else { return Ok(None) };
        if mesh.skin_deformers.len() > 1 {
            self.warnings.push(format!(
                "mesh {:?} has {} skin deformers; keyrig reads the first",
                out.mesh.name,
                mesh.skin_deformers.len()
            ));
        }
        let mut joints: Vec<usize> = Vec::new();
        let mut ibms: Vec<Mat4> = Vec::new();
        let mut slot_of_cluster: Vec<Option<u16>> = Vec::with_capacity(skin.clusters.len());
        for cluster in skin.clusters.iter() {
            let node = cluster.bone_node.as_ref().and_then(|b| self.model_node(b));
            let ibm = mat4(&cluster.geometry_to_bone);
            match node {
                Some(n) if ibm.is_finite() && joints.len() < usize::from(u16::MAX) => {
                    slot_of_cluster.push(Some(joints.len() as u16));
                    joints.push(n);
                    ibms.push(ibm);
                }
                _ => slot_of_cluster.push(None),
            }
        }
        let mut unweighted = false;
        let mut joint_sets = Vec::with_capacity(out.control_points.len());
        let mut weight_sets = Vec::with_capacity(out.control_points.len());
        let rest_slot = joints.len().min(usize::from(u16::MAX)) as u16;
        for points in &out.control_points {
            let mut js = Vec::with_capacity(points.len());
            let mut ws = Vec::with_capacity(points.len());
            for &c in points {
                let mut influences: Vec<(u16, f32)> = Vec::new();
                if let Some(v) = skin.vertices.get(c as usize) {
                    let begin = v.weight_begin as usize;
                    let end = begin.saturating_add(v.num_weights as usize).min(skin.weights.len());
                    for w in skin.weights.get(begin..end).unwrap_or(&[]) {
                        let slot = slot_of_cluster.get(w.cluster_index as usize).copied().flatten();
                        let weight = w.weight as f32;
                        if let Some(slot) = slot.filter(|_| weight.is_finite() && weight > 0.0) {
                            influences.push((slot, weight));
                        }
                    }
                }
                influences.sort_by(|a, b| b.1.total_cmp(&a.1));
                influences.truncate(4);
                let total: f32 = influences.iter().map(|x| x.1).sum();
                let (mut j, mut w) = ([0u16; 4], [0.0f32; 4]);
                if total > 0.0 && total.is_finite() {
                    for (i, (slot, weight)) in influences.iter().enumerate() {
                        j[i] = *slot;
                        w[i] = weight / total;
                    }
                } else {
                    unweighted = true;
                    j[0] = rest_slot;
                    w[0] = 1.0;
                }
                js.push(j);
                ws.push(w);
            }
            joint_sets.push(js);
            weight_sets.push(ws);
        }
        if unweighted {
            joints.push(mesh_node);
            ibms.push(Mat4::IDENTITY);
        }
        if joints.is_empty() {
            return Ok(None);
        }
        // Attach the weights to this mesh's primitives.
        let prims: Vec<ModelPrimitive> = out
            .mesh
            .primitives
            .iter()
            .zip(joint_sets.into_iter().zip(weight_sets))
            .map(|(p, (j, w))| ModelPrimitive {
                joint_sets: vec![j.into()],
                weight_sets: vec![w.into()],
                ..p.clone()
            })
            .collect();
        out.mesh.primitives = Arc::new(prims);
        let deformer = match skin.skinning_method {
            ufbx::SkinningMethod::Rigid => DeformerKind::Rigid,
            ufbx::SkinningMethod::DualQuaternion => DeformerKind::DualQuaternion,
            // keyrig has no per-vertex blend of the two: linear blend.
            ufbx::SkinningMethod::Linear | ufbx::SkinningMethod::BlendedDqLinear => DeformerKind::LinearBlend,
        };
        model.skins.push(ModelSkin {
            name: skin.element.name.to_string(),
            joints,
            inverse_bind_matrices: ibms,
            skeleton: None,
            deformer: Some(deformer),
        });
        Ok(Some(model.skins.len() - 1))
    }

    /// The file's frame rate when it is a usable one (1 to 1000 per second), else 30.
    fn resample_rate(&self) -> f64 {
        let fps = self.scene.settings.frames_per_second;
        if (1.0..=1000.0).contains(&fps) {
            fps
        } else {
            30.0
        }
    }

    fn count_keys(&mut self, n: usize) -> Result<(), FbxError> {
        self.keys = self.keys.saturating_add(n);
        if self.keys > MAX_BAKED_KEYS {
            return Err(FbxErrorKind::TooLarge {
                what: "baked animation keys".into(),
                count: self.keys,
                limit: MAX_BAKED_KEYS,
            }
            .into());
        }
        Ok(())
    }

    /// Baked keys as a linear track (times strictly increasing: a key at or before the one
    /// before it is dropped). `None` for a channel that holds its rest value throughout.
    fn track<T: Copy>(
        &mut self,
        keys: impl ExactSizeIterator<Item = (f64, T)>,
        constant: bool,
        rest: T,
        same: impl Fn(T, T) -> bool,
        finite: impl Fn(T) -> bool,
        what: impl Fn() -> String,
    ) -> Result<Option<RawTrack<T>>, FbxError> {
        self.count_keys(keys.len())?;
        let mut out: Vec<Key<T>> = Vec::with_capacity(keys.len());
        for (time, value) in keys {
            finite_or(&what, time.is_finite() && finite(value))?;
            if out.last().is_some_and(|k| k.time >= time) {
                continue;
            }
            out.push(Key::new(time, value).with_interpolation(Interpolation::Linear));
        }
        if out.is_empty() || (constant && same(out[0].value, rest)) {
            return Ok(None);
        }
        if constant {
            out.truncate(1);
        }
        Ok(Some(RawTrack::new(out)))
    }

    /// One [`ModelAnimation`] per animation stack, named as the stack: ufbx bakes the stack
    /// (its layers blended) into linear keys of each node's local translation, rotation
    /// (resampled: FBX interpolates Euler angles) and scale, and of each blend channel's weight.
    fn read_animations(
        &mut self,
        model: &ImportedModel,
        blend_of_mesh: &[Vec<u32>],
    ) -> Result<Vec<ModelAnimation>, FbxError> {
        let scene = self.scene;
        let mut out = Vec::new();
        for (s, stack) in scene.anim_stacks.iter().enumerate() {
            let name = stack.element.name.to_string();
            let name = if name.is_empty() { format!("stack{s}") } else { name };
            // Curves are sampled at the file's frame rate, so every frame the file's tool shows is
            // a key (ufbx's default, 30 per second, falls between a 24 fps file's frames).
            let opts = ufbx::BakeOpts {
                temp_allocator: allocator(self.limit),
                result_allocator: allocator(self.limit),
                resample_rate: self.resample_rate(),
                ..Default::default()
            };
            let baked = ufbx::bake_anim(scene, &stack.anim, opts).map_err(|e| {
                let description = match ufbx_error(&e) {
                    FbxErrorKind::Ufbx { description, detail, .. } => format!("{description}: {detail}"),
                    other => other.to_string(),
                };
                FbxError::from(FbxErrorKind::Bake { stack: s, name: name.clone(), description })
            })?;
            let mut channels = Vec::new();
            for bn in baked.nodes.iter() {
                let Some(n) = self.node_of.get(bn.typed_id as usize).copied().flatten() else { continue };
                let node = &model.nodes[n];
                let what = |c: &str| {
                    let (stack, node) = (name.clone(), node.name.clone());
                    let c = c.to_owned();
                    move || format!("animation {stack:?}: a {c} key of node {node:?}")
                };
                let near = |a: Vec3, b: Vec3| a.abs_diff_eq(b, 1e-6);
                let t = self.track(
                    bn.translation_keys.iter().map(|k| (k.time, vec3(k.value))),
                    bn.constant_translation,
                    node.translation,
                    near,
                    Vec3::is_finite,
                    what("translation"),
                )?;
                let r = self.track(
                    bn.rotation_keys.iter().map(|k| (k.time, quat(k.value).normalize())),
                    bn.constant_rotation,
                    node.rotation,
                    |a: Quat, b: Quat| a.dot(b).abs() > 1.0 - 1e-7,
                    Quat::is_finite,
                    what("rotation"),
                )?;
                let sc = self.track(
                    bn.scale_keys.iter().map(|k| (k.time, vec3(k.value))),
                    bn.constant_scale,
                    node.scale,
                    near,
                    Vec3::is_finite,
                    what("scale"),
                )?;
                channels.extend(t.map(|t| ModelChannel { node: n, target: ChannelTarget::Translation(t) }));
                channels.extend(r.map(|r| ModelChannel { node: n, target: ChannelTarget::Rotation(r) }));
                channels.extend(sc.map(|s| ModelChannel { node: n, target: ChannelTarget::Scale(s) }));
            }
            // Blend channel weights ("DeformPercent", 0..100 in the file).
            let percent: HashMap<u32, &[ufbx::BakedVec3]> = baked
                .elements
                .iter()
                .filter_map(|e| {
                    let p = e.props.iter().find(|p| (p.name.as_ref() as &str) == "DeformPercent")?;
                    Some((e.element_id, p.keys.as_ref()))
                })
                .collect();
            for (m, blend) in blend_of_mesh.iter().enumerate() {
                if !blend.iter().any(|c| percent.contains_key(c)) {
                    continue;
                }
                let mut times: Vec<f64> = blend
                    .iter()
                    .filter_map(|c| percent.get(c))
                    .flat_map(|keys| keys.iter().map(|k| k.time))
                    .filter(|t| t.is_finite())
                    .collect();
                times.sort_by(f64::total_cmp);
                times.dedup();
                self.count_keys(times.len().saturating_mul(blend.len()))?;
                let rest = model.meshes.get(m).map(|x| x.weights.clone()).unwrap_or_default();
                let keys: Vec<Key<Vec<f32>>> = times
                    .iter()
                    .map(|&t| {
                        let value = blend
                            .iter()
                            .enumerate()
                            .map(|(i, c)| match percent.get(c) {
                                Some(keys) => {
                                    let w = (ufbx::evaluate_baked_vec3(keys, t).x * 0.01) as f32;
                                    if w.is_finite() {
                                        w
                                    } else {
                                        0.0
                                    }
                                }
                                None => rest.get(i).copied().unwrap_or(0.0),
                            })
                            .collect();
                        Key::new(t, value).with_interpolation(Interpolation::Linear)
                    })
                    .collect();
                if keys.is_empty() {
                    continue;
                }
                for (n, node) in model.nodes.iter().enumerate() {
                    if node.mesh == Some(m) {
                        self.count_keys(keys.len().saturating_mul(blend.len()))?;
                        channels.push(ModelChannel {
                            node: n,
                            target: ChannelTarget::Weights(WeightsTrack {
                                targets: blend.len(),
                                keys: keys.clone(),
                            }),
                        });
                    }
                }
            }
            out.push(ModelAnimation { name, channels, pointers: Vec::new() });
        }
        Ok(out)
    }
}
