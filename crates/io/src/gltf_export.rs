//! glTF 2.0 export of a keyrig [`Scene`]: meshes, skeletons and skins, object, joint and
//! light animation, KHR_lights_punctual lights; as .glb or as .gltf with the buffer
//! embedded as a `data:` URI.
//!
//! Mapping (docs/design.md §3, §8):
//! - an object becomes a node with its rest TRS; its skeleton's joints become child nodes
//!   (rest transform R(j)); its mesh becomes a separate root node holding the mesh and the
//!   skin, as glTF ignores a skinned mesh node's own transform. Inverse bind matrices are
//!   A(j)⁻¹ of the rest skeleton, so `jointMatrix = F(j)·A(j)⁻¹` equals keyrig's M(j).
//! - **Position tracks** (object translation and scale, root-joint translation, light
//!   position) export exactly: all-Step tracks as STEP, all-Linear as LINEAR, anything
//!   else as CUBICSPLINE with per-second tangents `b_k = S_k / t_d`, `a_{k+1} = D_{k+1} / t_d`
//!   from the validated track. A Step segment inside a spline track holds its value and
//!   jumps within [`STEP_JUMP`] seconds before the next key.
//! - **Rotation tracks** (object rotation, joint rotation `rest · T(j)`, light direction)
//!   export as LINEAR (slerp). All-Linear tracks export key for key (exact); others are
//!   resampled: each segment is split in half until slerp between the emitted keys stays
//!   within [`ExportOptions::rotation_tolerance_deg`] of the keyrig curve (checked at 15 interior points against half the tolerance).
//!   All-Step rotation tracks export as STEP. Every resampled step turns at most
//!   [`MAX_ROTATION_STEP_DEG`] (90°), so glTF's shortest-path slerp between consecutive keys
//!   is unambiguous; spin segments (keys beyond half a turn, [`keyrig_core::Spin`]) are first
//!   cut into pieces of at most [`SPIN_PIECE_DEG`] of their unwrapped angle, so a 720° twist
//!   exports as at least 16 steps and a glTF viewer turns it the whole way, turns included.
//! - **Cycles** (a track's `before`/`after` other than Hold): glTF has no such setting, so the
//!   track is written as LINEAR keys over its keys and the scene's frame range, the repeats
//!   included, resampled between every repeated (or mirrored) key time within the rotation
//!   tolerance or [`CYCLE_POSITION_TOLERANCE`] (Blender mode: its tolerances); a viewer
//!   holds the last written key after the range.
//! - light colour and intensity are written at the start of the frame range (core glTF
//!   cannot animate them).
//! - **Scene cameras** ([`crate::gltf_camera`]) become root nodes holding a glTF camera
//!   (`export_camera`): translation and rotation channels as an object's; an aimed camera's
//!   rotation (glTF has no constraints) is sampled from the scene evaluator at every frame of
//!   the range and resampled like a rotation track; an animated lens is written as a
//!   `KHR_animation_pointer` channel on `/cameras/i/perspective/yfov` (orthographic: `ymag`
//!   and `xmag`): key for key when the map from keyrig's lens is linear (a field of view in
//!   degrees, an orthographic height), else (a focal length) LINEAR keys at every frame of the
//!   range and every key time; its visibility as `KHR_node_visibility`. Every pointer channel,
//!   cameras' and attributes', goes through the one writer `Document::write_pointers`.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Affine3A, Mat4, Quat, Vec2, Vec3};
use keyrig_core::{Animated, AnimatedTrack, Interpolation, LightKind, MeshSource, Scene, Track};
use serde_json::{json, Value};

use crate::model::{ChannelTarget, ImportedModel, ModelPrimitive, PrimitiveMode, WeightsTrack};

/// Duration of the jump that stands in for a Step segment inside a spline track (seconds).
pub const STEP_JUMP: f64 = 1e-3;

/// Largest rotation (degrees) between two consecutive resampled rotation keys: well below the
/// 180° at which glTF's shortest-path slerp would turn the other way or be undefined.
pub const MAX_ROTATION_STEP_DEG: f64 = 90.0;

/// Spin segments are cut into pieces of at most this much of their unwrapped angle (degrees,
/// uniformly in time) before resampling, so that no piece hides a whole turn between the
/// points the resampler checks.
pub const SPIN_PIECE_DEG: f64 = 45.0;

/// Export settings.
#[derive(Clone, Debug)]
pub struct ExportOptions {
    /// Largest angle (degrees) between the exported LINEAR rotation and the keyrig curve.
    pub rotation_tolerance_deg: f64,
    /// Folder that relative `MeshSource::File` paths resolve against (the scene's folder).
    pub base_dir: Option<PathBuf>,
    /// Blender mode: bake every animated channel into LINEAR keys (see [`BakeOptions`]).
    pub bake: Option<BakeOptions>,
}

impl Default for ExportOptions {
    fn default() -> Self {
        ExportOptions { rotation_tolerance_deg: 0.05, base_dir: None, bake: None }
    }
}

/// Blender mode ("bake"): for importers that ignore CUBICSPLINE tangents and blend LINEAR
/// rotation keys component-wise (normalized lerp, not slerp), as Blender 3.4 does.
///
/// Every animated channel that is not all Step is written as LINEAR keys, placed adaptively:
/// each interval between the track's keys is halved until the importer's interpolation
/// between the written keys — linear for translations, scales and morph weights, normalized
/// component-wise lerp for rotations — stays within half the tolerance of keyrig's curve at 15
/// interior points (so within the tolerance between them in practice). All-Step channels stay
/// STEP (Blender reads them as constant keys); a Step segment inside another track holds and
/// jumps within [`STEP_JUMP`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BakeOptions {
    /// Largest distance (scene units, in the node's parent space) between the importer's
    /// translation or scale and keyrig's.
    pub position_tolerance: f64,
    /// Largest angle (degrees) between the importer's rotation and keyrig's; `None` uses
    /// [`ExportOptions::rotation_tolerance_deg`].
    pub rotation_tolerance_deg: Option<f64>,
    /// Largest difference of one morph weight.
    pub weight_tolerance: f64,
}

impl Default for BakeOptions {
    fn default() -> Self {
        BakeOptions { position_tolerance: 1e-4, rotation_tolerance_deg: None, weight_tolerance: 1e-3 }
    }
}

impl BakeOptions {
    /// The rotation tolerance in radians.
    fn rotation_tolerance(&self, options: &ExportOptions) -> f64 {
        self.rotation_tolerance_deg.unwrap_or(options.rotation_tolerance_deg).to_radians()
    }
}

/// Why a scene cannot be exported; `path` names the scene field, as in `keyrig info`.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("{path}: {message}")]
    Scene { path: String, message: String },
    #[error("{path}: cannot load mesh file {file}: {source}")]
    MeshFile { path: String, file: PathBuf, source: Box<MeshFileError> },
    #[error("{path}: cannot write: {source}")]
    Write { path: PathBuf, source: std::io::Error },
}

/// What is wrong with the model file an object's mesh comes from ([`ExportError::MeshFile`]).
#[derive(Debug, thiserror::Error)]
pub enum MeshFileError {
    #[error(transparent)]
    Gltf(#[from] crate::gltf_import::GltfError),
    #[error(transparent)]
    Md2(#[from] crate::md2::Md2LoadError),
    #[error(transparent)]
    Fbx(#[from] crate::fbx::FbxError),
    #[error(transparent)]
    Vrml(#[from] crate::vrml::VrmlError),
    #[error(transparent)]
    VrmlMesh(#[from] crate::vrml::map::VrmlMeshError),
    #[error("mesh {0} morphs by a CoordinateInterpolator, which glTF export does not write yet")]
    VrmlMorph(usize),
    #[error("has no mesh {0}")]
    NoMesh(usize),
    #[error("no node shows mesh {0}")]
    MeshNotShown(usize),
    #[error("mesh {0} has no triangles")]
    NoTriangles(usize),
    #[error(transparent)]
    Skin(#[from] crate::model::MappingError),
    #[error("no clip `{clip}` (clips: {})", clips.join(", "))]
    NoClip { clip: String, clips: Vec<String> },
    #[error("the model has no frames")]
    NoFrames,
    #[error("{0} is not a frame rate")]
    BadFps(f64),
    #[error("frame {0} is missing")]
    FrameMissing(usize),
    #[error("the scene's frame range is not finite")]
    FrameRangeNotFinite,
    #[error("the scene's frame range holds more than 10 million model frames")]
    TooManyFrames,
    #[error(transparent)]
    Playback(#[from] keyrig_eval::morph::MorphError),
    #[error("skin image size does not match its pixels")]
    SkinSize,
    #[error("skin image: {0}")]
    SkinImage(#[from] image::ImageError),
}

fn scene_err(path: impl Into<String>, message: impl Into<String>) -> ExportError {
    ExportError::Scene { path: path.into(), message: message.into() }
}

/// A glTF document and its single binary buffer, ready to be written.
#[derive(Clone, Debug, PartialEq)]
pub struct ExportedGltf {
    pub json: Value,
    pub bin: Vec<u8>,
}

impl ExportedGltf {
    /// The binary container (.glb).
    #[must_use]
    pub fn to_glb(&self) -> Vec<u8> {
        let mut json = self.json.clone();
        if let Some(buffer) = json.pointer_mut("/buffers/0") {
            if let Some(obj) = buffer.as_object_mut() {
                obj.remove("uri");
            }
        }
        let mut j = serde_json::to_vec(&json).unwrap_or_default();
        while !j.len().is_multiple_of(4) {
            j.push(b' ');
        }
        let mut b = self.bin.clone();
        while !b.len().is_multiple_of(4) {
            b.push(0);
        }
        let total = 12 + 8 + j.len() + if b.is_empty() { 0 } else { 8 + b.len() };
        let mut out = Vec::with_capacity(total);
        out.extend_from_slice(b"glTF");
        out.extend_from_slice(&2u32.to_le_bytes());
        out.extend_from_slice(&(total as u32).to_le_bytes());
        out.extend_from_slice(&(j.len() as u32).to_le_bytes());
        out.extend_from_slice(b"JSON");
        out.extend_from_slice(&j);
        if !b.is_empty() {
            out.extend_from_slice(&(b.len() as u32).to_le_bytes());
            out.extend_from_slice(b"BIN\0");
            out.extend_from_slice(&b);
        }
        out
    }

    /// A self-contained .gltf text with the buffer as a base64 `data:` URI.
    #[must_use]
    pub fn to_gltf_embedded(&self) -> String {
        let mut json = self.json.clone();
        if let Some(obj) = json.pointer_mut("/buffers/0").and_then(Value::as_object_mut) {
            obj.insert(
                "uri".into(),
                Value::String(format!("data:application/octet-stream;base64,{}", base64_encode(&self.bin))),
            );
        }
        serde_json::to_string_pretty(&json).unwrap_or_default()
    }

    /// Writes .glb or .gltf by the extension of `path` (.gltf → embedded text, else GLB),
    /// atomically ([`crate::file_io::write_atomic`]): `path` holds either its previous
    /// content or the whole new file, whatever happens during the write.
    ///
    /// # Errors
    /// The file cannot be written.
    pub fn write(&self, path: &Path) -> Result<(), ExportError> {
        let is_text =
            path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("gltf"));
        let bytes = if is_text { self.to_gltf_embedded().into_bytes() } else { self.to_glb() };
        crate::file_io::write_atomic(path, &bytes)
            .map_err(|source| ExportError::Write { path: path.to_path_buf(), source })
    }
}

/// Standard base64 with padding (RFC 4648).
#[must_use]
pub fn base64_encode(data: &[u8]) -> String {
    const ALPHABET: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::with_capacity(data.len().div_ceil(3) * 4);
    for chunk in data.chunks(3) {
        let b = [chunk[0], chunk.get(1).copied().unwrap_or(0), chunk.get(2).copied().unwrap_or(0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(ALPHABET[((n >> (18 - 6 * i)) & 63) as usize] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

const ARRAY_BUFFER: u32 = 34962;
const ELEMENT_ARRAY_BUFFER: u32 = 34963;
const FLOAT: u32 = 5126;
const UNSIGNED_SHORT: u32 = 5123;
const UNSIGNED_INT: u32 = 5125;

/// Accumulates the binary buffer, buffer views and accessors.
#[derive(Default)]
struct Builder {
    bin: Vec<u8>,
    views: Vec<Value>,
    accessors: Vec<Value>,
}

impl Builder {
    fn view(&mut self, bytes: &[u8], target: Option<u32>) -> usize {
        while !self.bin.len().is_multiple_of(4) {
            self.bin.push(0);
        }
        let mut v = json!({"buffer": 0, "byteOffset": self.bin.len(), "byteLength": bytes.len()});
        if let Some(t) = target {
            v["target"] = json!(t);
        }
        self.bin.extend_from_slice(bytes);
        self.views.push(v);
        self.views.len() - 1
    }

    fn accessor(
        &mut self,
        view: usize,
        component: u32,
        count: usize,
        type_: &str,
        minmax: Option<(Vec<f32>, Vec<f32>)>,
    ) -> usize {
        let mut a = json!({"bufferView": view, "componentType": component, "count": count, "type": type_});
        if let Some((min, max)) = minmax {
            a["min"] = json!(min);
            a["max"] = json!(max);
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }

    fn floats(
        &mut self,
        values: &[f32],
        width: usize,
        type_: &str,
        target: Option<u32>,
        with_minmax: bool,
    ) -> usize {
        let bytes: Vec<u8> = values.iter().flat_map(|f| f.to_le_bytes()).collect();
        let view = self.view(&bytes, target);
        let count = values.len() / width;
        let minmax = with_minmax.then(|| {
            let mut min = vec![f32::INFINITY; width];
            let mut max = vec![f32::NEG_INFINITY; width];
            for chunk in values.chunks(width) {
                for (i, &v) in chunk.iter().enumerate() {
                    min[i] = min[i].min(v);
                    max[i] = max[i].max(v);
                }
            }
            (min, max)
        });
        self.accessor(view, FLOAT, count, type_, minmax)
    }

    fn vec3s(&mut self, v: &[Vec3], target: Option<u32>, with_minmax: bool) -> usize {
        let flat: Vec<f32> = v.iter().flat_map(|p| p.to_array()).collect();
        self.floats(&flat, 3, "VEC3", target, with_minmax)
    }

    fn indices(&mut self, idx: &[u32]) -> usize {
        let bytes: Vec<u8> = idx.iter().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(ELEMENT_ARRAY_BUFFER));
        self.accessor(view, UNSIGNED_INT, idx.len(), "SCALAR", None)
    }

    fn joints(&mut self, j: &[[u16; 4]]) -> usize {
        let bytes: Vec<u8> = j.iter().flatten().flat_map(|i| i.to_le_bytes()).collect();
        let view = self.view(&bytes, Some(ARRAY_BUFFER));
        self.accessor(view, UNSIGNED_SHORT, j.len(), "VEC4", None)
    }
}

/// One animation channel before it is written: node, path, interpolation, times, values.
struct Channel {
    node: usize,
    path: &'static str,
    interpolation: &'static str,
    times: Vec<f32>,
    /// Flattened outputs (3 per key for CUBICSPLINE: in-tangent, value, out-tangent).
    values: Vec<f32>,
    /// Components per output element: 3 (VEC3), 4 (VEC4) or 1 (SCALAR: morph weights).
    width: usize,
}

/// The material of one exported primitive: base colour factor and texture.
#[derive(Clone, Debug, PartialEq)]
struct MaterialData {
    base_colour: [f32; 4],
    /// Index into the document's textures.
    texture: Option<usize>,
}

/// One exported primitive (triangles).
struct PrimitiveData {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    texcoords: Option<Vec<Vec2>>,
    indices: Vec<u32>,
    skin: Option<Influences>,
    /// Morph targets: position and (optional) normal displacements.
    targets: Vec<(Vec<Vec3>, Option<Vec<Vec3>>)>,
    material: Option<MaterialData>,
}

/// JOINTS_0 and WEIGHTS_0 of a mesh.
type Influences = (Vec<[u16; 4]>, Vec<[f32; 4]>);

/// A model file an object's mesh comes from, loaded once per export.
enum LoadedFile {
    Gltf(Box<ImportedModel>),
    Md2(Box<crate::md2::Md2Model>),
    Vrml(Box<crate::vrml::VrmlModel>),
}

/// Loads the model file at `path` (glTF by default, MD2 by its extension), through the same
/// readers as the editor: [`crate::gltf_import::import_gltf_file`] and
/// [`crate::md2::load_md2_file`] (which also finds the skin image).
fn load_file(path: &Path) -> Result<LoadedFile, MeshFileError> {
    let is_md2 = path.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("md2"));
    if crate::vrml::is_vrml_path(path) {
        return Ok(LoadedFile::Vrml(Box::new(crate::vrml::import_vrml_file(path)?)));
    }
    if crate::fbx::is_fbx_path(path) {
        return Ok(LoadedFile::Gltf(Box::new(crate::fbx::import_fbx_file(path)?)));
    }
    Ok(if is_md2 {
        LoadedFile::Md2(Box::new(crate::md2::load_md2_file(path)?))
    } else {
        LoadedFile::Gltf(Box::new(crate::gltf_import::import_gltf_file(path)?))
    })
}

mod attributes;

/// Everything a document accumulates besides the buffer.
#[derive(Default)]
struct Document {
    /// `KHR_animation_pointer` channels (written after `channels`).
    pointers: Vec<attributes::PointerChannel>,
    /// A node has `KHR_node_visibility`.
    node_visibility: bool,
    /// A channel is a `KHR_animation_pointer` one.
    animation_pointer: bool,
    b: Builder,
    nodes: Vec<Value>,
    roots: Vec<usize>,
    meshes: Vec<Value>,
    skins: Vec<Value>,
    channels: Vec<Channel>,
    /// The `cameras` entries (their lens channels are in `pointers`).
    cameras: Vec<Value>,
    images: Vec<Value>,
    textures: Vec<Value>,
    materials: Vec<Value>,
    /// (source file, image index) → texture index, so that a shared image is written once.
    texture_of: HashMap<(PathBuf, usize), usize>,
}

impl Document {
    /// A texture of the image bytes (PNG or JPEG), with a linear, repeating sampler.
    fn texture(&mut self, key: (PathBuf, usize), bytes: &[u8], mime_type: &str) -> usize {
        if let Some(&t) = self.texture_of.get(&key) {
            return t;
        }
        let view = self.b.view(bytes, None);
        self.images.push(json!({"bufferView": view, "mimeType": mime_type}));
        self.textures.push(json!({"sampler": 0, "source": self.images.len() - 1}));
        let t = self.textures.len() - 1;
        self.texture_of.insert(key, t);
        t
    }

    fn material(&mut self, m: &MaterialData) -> usize {
        let mut pbr = json!({"metallicFactor": 0.0, "roughnessFactor": 1.0});
        if m.base_colour != [1.0; 4] {
            pbr["baseColorFactor"] = json!(m.base_colour);
        }
        if let Some(t) = m.texture {
            pbr["baseColorTexture"] = json!({"index": t});
        }
        let value = json!({"pbrMetallicRoughness": pbr});
        if let Some(i) = self.materials.iter().position(|x| *x == value) {
            return i;
        }
        self.materials.push(value);
        self.materials.len() - 1
    }

    /// Writes a mesh of `primitives` and returns its index.
    fn mesh(&mut self, name: &str, primitives: &[PrimitiveData], weights: Option<&[f32]>) -> usize {
        let mut prims = Vec::with_capacity(primitives.len());
        for p in primitives {
            let b = &mut self.b;
            let mut attributes = serde_json::Map::new();
            attributes.insert("POSITION".into(), json!(b.vec3s(&p.positions, Some(ARRAY_BUFFER), true)));
            if let Some(n) = &p.normals {
                let n: Vec<Vec3> = n.iter().map(|v| v.normalize_or(Vec3::Z)).collect();
                attributes.insert("NORMAL".into(), json!(b.vec3s(&n, Some(ARRAY_BUFFER), false)));
            }
            if let Some(uv) = &p.texcoords {
                let flat: Vec<f32> = uv.iter().flat_map(|t| t.to_array()).collect();
                attributes.insert(
                    "TEXCOORD_0".into(),
                    json!(b.floats(&flat, 2, "VEC2", Some(ARRAY_BUFFER), false)),
                );
            }
            if let Some((joints, weights)) = &p.skin {
                // glTF: a joint with zero weight should be joint 0 (the validator warns
                // ACCESSOR_JOINTS_USED_ZERO_WEIGHT otherwise); it has no effect either way.
                let joints: Vec<[u16; 4]> = joints
                    .iter()
                    .zip(weights)
                    .map(|(j, w)| std::array::from_fn(|i| if w[i] == 0.0 { 0 } else { j[i] }))
                    .collect();
                attributes.insert("JOINTS_0".into(), json!(b.joints(&joints)));
                let w: Vec<f32> = weights.iter().flatten().copied().collect();
                attributes
                    .insert("WEIGHTS_0".into(), json!(b.floats(&w, 4, "VEC4", Some(ARRAY_BUFFER), false)));
            }
            let indices = b.indices(&p.indices);
            let mut prim = json!({"attributes": attributes, "indices": indices, "mode": 4});
            if !p.targets.is_empty() {
                let targets: Vec<Value> = p
                    .targets
                    .iter()
                    .map(|(dp, dn)| {
                        let mut t = json!({"POSITION": b.vec3s(dp, Some(ARRAY_BUFFER), true)});
                        if let (Some(dn), true) = (dn, p.normals.is_some()) {
                            t["NORMAL"] = json!(b.vec3s(dn, Some(ARRAY_BUFFER), false));
                        }
                        t
                    })
                    .collect();
                prim["targets"] = json!(targets);
            }
            if let Some(m) = &p.material {
                prim["material"] = json!(self.material(m));
            }
            prims.push(prim);
        }
        let mut mesh = json!({"name": name, "primitives": prims});
        if let Some(w) = weights {
            mesh["weights"] = json!(w);
        }
        self.meshes.push(mesh);
        self.meshes.len() - 1
    }
}

/// Exports `scene`.
///
/// Every object is written with its transform and animation, its skeleton (joint nodes with
/// every channel: translation, rotation, scale), and its mesh:
/// - procedural meshes from keyrig-skin, fitted to the object's skeleton, with their skin;
/// - glTF model meshes (`MeshSource::File` of a .glb/.gltf) loaded from the file: a skinned
///   mesh as keyrig deforms it ([`ImportedModel::skinned_mesh`]: the four largest influences,
///   normalized, joints renumbered to the object's skeleton, the file's inverse bind matrices
///   as `RestSkeleton::joint_from_bind_model`), one glTF primitive per triangle primitive of
///   the file with its texture coordinates and material (base colour factor and texture); an
///   unskinned mesh with its morph targets and the morph weights of the file's first
///   animation (as `keyrig deform` plays them);
/// - MD2 meshes as morph-target animation: the object's clip (or every frame), one target per
///   frame, weights keyed at every frame boundary over the scene's frame range so that the
///   LINEAR weights reproduce keyrig's looping playback, the skin image as base-colour texture.
///
/// glTF has no IK: IK constraints are baked first (`keyrig_eval::bake_all_ik` over the scene's
/// frame range, a rotation key per frame on each chain joint), so the file shows the solved
/// chains as keyrig evaluates them at every frame. Object constraints (aim at, child of, copy,
/// follow path) are baked likewise (`keyrig_eval::bake_object_constraints`): a constrained
/// object's node gets LINEAR keys of its evaluated transform at every frame.
///
/// # Errors
/// A track that does not validate, a skeleton that does not fit its mesh, a mesh file that
/// cannot be loaded: each with the path of the scene field.
pub fn export_scene(scene: &Scene, options: &ExportOptions) -> Result<ExportedGltf, ExportError> {
    // glTF has no clip tracks or layers: baked, their mix becomes each moved object's active
    // action (docs/clips.md, "Merge down"); otherwise each action is written as it is.
    let merged;
    let scene = if options.bake.is_some()
        && (!scene.layers.is_empty() || scene.objects.iter().any(|o| !o.clip_tracks.is_empty()))
    {
        let mut copy = scene.clone();
        keyrig_eval::merge_down(&mut copy, scene.frame_range.start, scene.frame_range.end)
            .map_err(|e| scene_err("clip_tracks", e.to_string()))?;
        merged = copy;
        &merged
    } else {
        scene
    };
    let mut files: HashMap<PathBuf, LoadedFile> = HashMap::new();
    let (mut doc, lights) = write_document(scene, options, &mut files)?;
    if scene.actions.is_empty() {
        let channels = std::mem::take(&mut doc.channels);
        let pointers = std::mem::take(&mut doc.pointers);
        return Ok(doc.into_gltf(lights, vec![("keyrig".to_owned(), channels, pointers)]));
    }
    // Each action is an animation of its name (docs/actions.md, "Export"), written from the
    // scene playing that action alone; the node tree, meshes and rest values are the scene's.
    // Keys that belong to no action, if any, are the animation "keyrig".
    doc.channels.clear();
    doc.pointers.clear();
    let mut animations = Vec::new();
    for action in &scene.actions {
        let mut playing = scene
            .playing_action(&action.name, true)
            .map_err(|e| scene_err(format!("actions[{}]", action.name), e.to_string()))?;
        // Lights' and cameras' keys are in no action: they go to "keyrig" below.
        for id in keyrig_core::channel_id::ChannelId::all(&playing) {
            if keyrig_core::action::channel_object(id).is_none() {
                match keyrig_core::channel_id::channel_mut(&mut playing, id) {
                    Some(keyrig_core::channel_id::ChannelMut::Vec3(a)) => *a = Animated::constant(a.value),
                    Some(keyrig_core::channel_id::ChannelMut::Rotation(a)) => {
                        *a = Animated::constant(a.value)
                    }
                    Some(keyrig_core::channel_id::ChannelMut::Scalar(a)) => *a = Animated::constant(a.value),
                    None => {}
                }
            }
        }
        let (mut one, _) = write_document(&playing, options, &mut files)?;
        let (channels, pointers) = (std::mem::take(&mut one.channels), std::mem::take(&mut one.pointers));
        doc.node_visibility |= one.node_visibility;
        animations.push((action.name.clone(), channels, pointers));
    }
    let mut unnamed = scene.clone();
    for o in 0..unnamed.objects.len() {
        if unnamed.objects[o].action.is_some() {
            drop(unnamed.take_keyed_channels(o));
        }
    }
    let (mut rest, _) = write_document(&unnamed, options, &mut files)?;
    animations.push((
        "keyrig".to_owned(),
        std::mem::take(&mut rest.channels),
        std::mem::take(&mut rest.pointers),
    ));
    Ok(doc.into_gltf(lights, animations))
}

/// The glTF document of `scene` playing the keys it plays, and its KHR_lights_punctual
/// lights (the body of [`export_scene`]); mesh files are loaded once into `files`.
fn write_document(
    scene: &Scene,
    options: &ExportOptions,
    files: &mut HashMap<PathBuf, LoadedFile>,
) -> Result<(Document, Vec<Value>), ExportError> {
    // Constraints without effect are left alone, so a scene without IK is written as it is.
    let mut baked = scene.clone();
    keyrig_eval::bake_all_ik(&mut baked, scene.frame_range.start, scene.frame_range.end)
        .map_err(|e| scene_err("ik_constraints", e.to_string()))?;
    // Nor object constraints: each constrained object's evaluated transform becomes LINEAR keys
    // at every frame (docs/constraints.md, "Baking and export").
    keyrig_eval::bake_object_constraints(&mut baked, scene.frame_range.start, scene.frame_range.end)
        .map_err(|e| scene_err("constraints", e.to_string()))?;
    // glTF rotations are quaternions: Euler keys become quaternion keys that follow them within
    // a tenth of the tolerance (docs/channels.md, "Euler keys"), resampled below like any.
    let range =
        (f64::from(scene.frame_range.start) / scene.fps, f64::from(scene.frame_range.end) / scene.fps);
    let converted = match baked
        .with_quaternion_keys(range, options.rotation_tolerance_deg / 10.0)
        .map_err(|(path, e)| scene_err(&path, e.to_string()))?
    {
        std::borrow::Cow::Owned(converted) => Some(converted),
        std::borrow::Cow::Borrowed(_) => None,
    };
    if let Some(converted) = converted {
        baked = converted;
    }
    let scene = &baked;
    let mut doc = Document::default();
    // Tracks with cycles are written as keys over the scene's frame range.
    let range =
        (f64::from(scene.frame_range.start) / scene.fps, f64::from(scene.frame_range.end) / scene.fps);
    for (oi, object) in scene.objects.iter().enumerate() {
        export_object(&mut doc, files, scene, object, options, range, &format!("objects[{oi}]"))?;
    }
    let t0 = f64::from(scene.frame_range.start) / scene.fps;
    let mut lights: Vec<Value> = Vec::new();
    for (li, light) in scene.lights.iter().enumerate() {
        let here = format!("lights[{li}]");
        let light_index = lights.len();
        let mut entry = punctual_light(light, t0, &here)?;
        attributes::light(&mut doc, light, light_index, &mut entry, t0, options, range, &here)?;
        lights.push(entry);
        let node = doc.nodes.len();
        light_node(&mut doc, light, light_index, t0, options, range, &here)?;
        attributes::visibility(
            &mut doc,
            node,
            &light.attributes.visible,
            t0,
            &format!("{here}.attributes.visible"),
        )?;
    }
    if !scene.cameras.is_empty() {
        let eval = keyrig_eval::SceneEvaluator::new(scene, &HashMap::new());
        for c in 0..scene.cameras.len() {
            export_camera(&mut doc, scene, &eval, c, options, range)?;
        }
    }
    Ok((doc, lights))
}

/// Writes `object` (at the scene path `here`): its node with its transform and channels
/// ([`object_node`]), its skeleton's joints ([`export_joints`]) and its mesh, procedural
/// ([`procedural_mesh`]) or from a model file, which is loaded once per export into `files`.
fn export_object(
    doc: &mut Document,
    files: &mut HashMap<PathBuf, LoadedFile>,
    scene: &Scene,
    object: &keyrig_core::Object,
    options: &ExportOptions,
    range: (f64, f64),
    here: &str,
) -> Result<(), ExportError> {
    let node = object_node(doc, object, options, range, here)?;
    attributes::visibility(
        doc,
        node,
        &object.attributes.visible,
        range.0,
        &format!("{here}.attributes.visible"),
    )?;
    export_mesh(doc, files, scene, object, node, options, range, here)?;
    // The object's own material with its colour and opacity: on its node's mesh or a skinned
    // mesh node below it.
    let mut with_mesh = vec![node];
    if let Some(children) = doc.nodes[node]["children"].as_array() {
        with_mesh.extend(children.iter().filter_map(Value::as_u64).map(|c| c as usize));
    }
    with_mesh.retain(|&n| doc.nodes[n].get("mesh").is_some());
    attributes::material(doc, &with_mesh, &object.attributes, range.0, options, range, here)
}

/// Writes the skeleton and mesh of `object` (whose node is `node`).
#[allow(clippy::too_many_arguments)]
fn export_mesh(
    doc: &mut Document,
    files: &mut HashMap<PathBuf, LoadedFile>,
    scene: &Scene,
    object: &keyrig_core::Object,
    node: usize,
    options: &ExportOptions,
    range: (f64, f64),
    here: &str,
) -> Result<(), ExportError> {
    let joint_nodes = match &object.skeleton {
        Some(skeleton) => export_joints(doc, node, skeleton, options, range, here)?,
        None => Vec::new(),
    };

    let Some(source) = &object.mesh else { return Ok(()) };
    let mesh_here = format!("{here}.mesh");
    match source {
        MeshSource::Procedural(kind) => procedural_mesh(doc, object, *kind, node, &joint_nodes, here)?,
        MeshSource::File { path, mesh, clip, fps } => {
            let file = options.base_dir.as_deref().unwrap_or(Path::new(".")).join(path);
            let err = |source: MeshFileError| ExportError::MeshFile {
                path: mesh_here.clone(),
                file: file.clone(),
                source: Box::new(source),
            };
            if !files.contains_key(&file) {
                let loaded = load_file(&file).map_err(err)?;
                files.insert(file.clone(), loaded);
            }
            match &files[&file] {
                LoadedFile::Md2(model) => {
                    let fps = fps.unwrap_or(keyrig_core::MD2_DEFAULT_FPS);
                    md2_object(doc, scene, model, &file, clip.as_deref(), fps, node, &object.name)
                        .map_err(err)?;
                }
                LoadedFile::Vrml(model) => {
                    let index = mesh.unwrap_or(0);
                    if model.meshes.get(index).is_some_and(|m| m.morph.is_some()) {
                        return Err(err(MeshFileError::VrmlMorph(index)));
                    }
                    let mesh = model.skinned_mesh(index).map_err(|e| err(e.into()))?;
                    let colour = model.meshes[index].material.base_colour;
                    let skinned = !joint_nodes.is_empty() && joint_nodes.len() == mesh.skeleton.len();
                    let prim = PrimitiveData {
                        positions: mesh.positions.clone(),
                        normals: Some(mesh.normals.clone()),
                        texcoords: mesh.uvs.clone(),
                        indices: mesh.indices.clone(),
                        skin: skinned
                            .then(|| (mesh.influences.joints().to_vec(), mesh.influences.weights().to_vec())),
                        targets: Vec::new(),
                        material: Some(MaterialData { base_colour: colour, texture: None }),
                    };
                    if skinned {
                        let ibms = ibms_of(&mesh.skeleton);
                        skinned_mesh_node(doc, &object.name, &[prim], &ibms, &joint_nodes, node);
                    } else {
                        let m = doc.mesh(&object.name, &[prim], None);
                        doc.nodes[node]["mesh"] = json!(m);
                    }
                }
                LoadedFile::Gltf(model) => {
                    let index = mesh.unwrap_or(0);
                    gltf_object(doc, model, &file, index, node, object, &joint_nodes, options, range, here)?;
                }
            }
        }
    }
    Ok(())
}

/// Writes the root node of `object` with its rest translation, scale and rotation and their
/// channels; returns the node.
fn object_node(
    doc: &mut Document,
    object: &keyrig_core::Object,
    options: &ExportOptions,
    range: (f64, f64),
    here: &str,
) -> Result<usize, ExportError> {
    let node = doc.nodes.len();
    doc.nodes.push(json!({"name": object.name}));
    doc.roots.push(node);
    let identity = (Quat::IDENTITY, Vec3::ZERO);
    set_vec3(
        &mut doc.nodes[node],
        "translation",
        &object.translation,
        identity,
        Vec3::ZERO,
        &format!("{here}.translation"),
    )?;
    set_vec3(&mut doc.nodes[node], "scale", &object.scale, identity, Vec3::ONE, &format!("{here}.scale"))?;
    set_quat(&mut doc.nodes[node], &object.rotation, Quat::IDENTITY, &format!("{here}.rotation"))?;
    doc.channels.extend(vec3_channel(
        node,
        "translation",
        &object.translation,
        identity,
        options,
        range,
        &format!("{here}.translation"),
    )?);
    doc.channels.extend(vec3_channel(
        node,
        "scale",
        &object.scale,
        identity,
        options,
        range,
        &format!("{here}.scale"),
    )?);
    doc.channels.extend(quat_channel(
        node,
        &object.rotation,
        Quat::IDENTITY,
        options,
        range,
        &format!("{here}.rotation"),
    )?);
    Ok(node)
}

/// Writes the procedural mesh `kind` of `object` (node `node`), fitted to the object's
/// skeleton and skinned to its joints `joint_nodes` when it has any.
fn procedural_mesh(
    doc: &mut Document,
    object: &keyrig_core::Object,
    kind: keyrig_core::ProceduralMesh,
    node: usize,
    joint_nodes: &[usize],
    here: &str,
) -> Result<(), ExportError> {
    let mut mesh = keyrig_skin::mesh_for(kind);
    // Procedural meshes are built in centimetres on their own skeleton; fit them to
    // the object's skeleton as the editor and renderer do. A skeleton that does not
    // build is reported by the skeleton's own export; the mesh then keeps its
    // native size.
    let rest = object.skeleton.as_ref().and_then(|s| keyrig_skin::RestSkeleton::from_scene(s).ok());
    if let Some(rest) = rest {
        if let Ok(fitted) = mesh.clone().fit_to_skeleton(rest) {
            mesh = fitted;
        }
    }
    let skinned = !joint_nodes.is_empty();
    let prim = PrimitiveData {
        positions: mesh.positions.clone(),
        normals: Some(mesh.normals.clone()),
        texcoords: None,
        indices: mesh.indices.clone(),
        skin: skinned.then(|| (mesh.influences.joints().to_vec(), mesh.influences.weights().to_vec())),
        targets: Vec::new(),
        material: None,
    };
    if skinned {
        check_joints(&prim, joint_nodes.len(), &format!("{here}.skeleton"))?;
        if mesh.skeleton.len() != joint_nodes.len() {
            // The fit failed (a skeleton that does not build): bind to the scene's rest.
            let ibms = inverse_bind_matrices(object.skeleton.as_ref().expect("skeleton"));
            skinned_mesh_node(doc, &object.name, &[prim], &ibms, joint_nodes, node);
        } else {
            let ibms = ibms_of(&mesh.skeleton);
            skinned_mesh_node(doc, &object.name, &[prim], &ibms, joint_nodes, node);
        }
    } else {
        let m = doc.mesh(&object.name, &[prim], None);
        doc.nodes[node]["mesh"] = json!(m);
    }
    Ok(())
}

/// The KHR_lights_punctual entry of `light` (at the scene path `here`): its kind, and its
/// colour and intensity at `t0`, the start of the frame range (core glTF cannot animate them).
fn punctual_light(light: &keyrig_core::Light, t0: f64, here: &str) -> Result<Value, ExportError> {
    let colour = sample_at(&light.colour, t0, &format!("{here}.colour"))?;
    let intensity = sample_at(&light.intensity, t0, &format!("{here}.intensity"))?;
    let mut l = json!({"name": light.name, "color": colour.max(Vec3::ZERO).to_array(), "intensity": intensity.max(0.0)});
    match light.kind {
        LightKind::Directional => l["type"] = json!("directional"),
        LightKind::Point => l["type"] = json!("point"),
        LightKind::Spot { cutoff_deg, inner_angle_deg, .. } => {
            if !(cutoff_deg.is_finite() && inner_angle_deg.is_finite()) {
                return Err(scene_err(format!("{here}.kind"), "spot angles must be finite"));
            }
            let outer = cutoff_deg.to_radians().clamp(1e-4, std::f32::consts::FRAC_PI_2);
            let inner = inner_angle_deg.to_radians().clamp(0.0, outer - 1e-4);
            l["type"] = json!("spot");
            l["spot"] = json!({"innerConeAngle": inner, "outerConeAngle": outer});
        }
    }
    Ok(l)
}

/// Writes the root node of `light` (entry `light_index` of KHR_lights_punctual) with its
/// position and its direction as a rotation ([`light_direction`]), and their channels.
fn light_node(
    doc: &mut Document,
    light: &keyrig_core::Light,
    light_index: usize,
    t0: f64,
    options: &ExportOptions,
    range: (f64, f64),
    here: &str,
) -> Result<(), ExportError> {
    let node = doc.nodes.len();
    doc.nodes
        .push(json!({"name": light.name, "extensions": {"KHR_lights_punctual": {"light": light_index}}}));
    doc.roots.push(node);
    let identity = (Quat::IDENTITY, Vec3::ZERO);
    set_vec3(
        &mut doc.nodes[node],
        "translation",
        &light.position,
        identity,
        Vec3::ZERO,
        &format!("{here}.position"),
    )?;
    doc.channels.extend(vec3_channel(
        node,
        "translation",
        &light.position,
        identity,
        options,
        range,
        &format!("{here}.position"),
    )?);
    light_direction(doc, node, light, t0, options, range, here)
}

/// The rotation of the light node `node`: the one taking the light's −Z to its direction, at
/// `t0` as the node's rest rotation and, when the direction is animated, as a LINEAR channel
/// resampled like the other rotations.
fn light_direction(
    doc: &mut Document,
    node: usize,
    light: &keyrig_core::Light,
    t0: f64,
    options: &ExportOptions,
    range: (f64, f64),
    here: &str,
) -> Result<(), ExportError> {
    // Direction → rotation taking the light's −Z to the direction.
    let dir_here = format!("{here}.direction");
    let dir = AnimatedTrack::new(&light.direction).map_err(|e| scene_err(&dir_here, e.to_string()))?;
    let rest = look_rotation(dir.sample(t0));
    doc.nodes[node]["rotation"] = json!(rest.to_array());
    if let Some(track) = dir.track() {
        // Key times are breaks, and a Step segment is a hold and one jump, as for the
        // other rotations.
        let (breaks, jumps) = if track.cycles().is_hold() {
            step_breaks(track.key_times(), |i| track.segment_interpolation(i))
        } else {
            (cycle_breaks(track, range), Vec::new())
        };
        let sampler = |t: f64| look_rotation(track.sample(t));
        let tol = options.rotation_tolerance_deg.to_radians();
        let (times, values) = match &options.bake {
            Some(bake) => {
                resample_rotation(&sampler, &breaks, &jumps, bake.rotation_tolerance(options), nlerp)
            }
            None => resample_rotation(&sampler, &breaks, &jumps, tol, crate::model::slerp_short),
        };
        doc.channels.push(linear_quat_channel(node, times, values));
    }
    Ok(())
}

impl Document {
    /// The glTF JSON and binary buffer of everything written, with the KHR_lights_punctual
    /// `lights`: the node tree, meshes, skins, materials and textures, the `animations`
    /// (each a name, its node channels and its pointer channels; those without channels are
    /// left out, their accessors after the meshes'), and the buffer padded to a multiple of 4
    /// bytes.
    fn into_gltf(
        mut self,
        lights: Vec<Value>,
        animations: Vec<(String, Vec<Channel>, Vec<attributes::PointerChannel>)>,
    ) -> ExportedGltf {
        // Camera lenses and the attributes animate through KHR_animation_pointer channels,
        // written by the one writer (`write_pointers`) after the node channels of each
        // animation.
        let mut written = Vec::new();
        for (name, channels, pointers) in animations {
            if channels.is_empty() && pointers.is_empty() {
                continue;
            }
            let mut animation = Self::animation(&mut self.b, &name, &channels);
            let (mut samplers, mut chans) = (Vec::new(), Vec::new());
            if let (Some(Value::Array(s)), Some(Value::Array(c))) = (
                animation.get_mut("samplers").map(std::mem::take),
                animation.get_mut("channels").map(std::mem::take),
            ) {
                (samplers, chans) = (s, c);
            }
            self.pointers = pointers;
            self.write_pointers(&mut samplers, &mut chans);
            animation["samplers"] = json!(samplers);
            animation["channels"] = json!(chans);
            written.push(animation);
        }
        let mut used: Vec<&str> = Vec::new();
        if !lights.is_empty() {
            used.push("KHR_lights_punctual");
        }
        if self.animation_pointer {
            used.push("KHR_animation_pointer");
        }
        if self.node_visibility {
            used.push("KHR_node_visibility");
        }
        let Document { mut b, nodes, roots, meshes, skins, cameras, images, textures, materials, .. } = self;
        let mut root = json!({
            "asset": {"version": "2.0", "generator": concat!("keyrig ", env!("CARGO_PKG_VERSION"))},
            "scene": 0,
            "scenes": [{"name": "keyrig scene", "nodes": roots}],
            "nodes": nodes,
        });
        if !meshes.is_empty() {
            root["meshes"] = json!(meshes);
        }
        if !skins.is_empty() {
            root["skins"] = json!(skins);
        }
        if !materials.is_empty() {
            root["materials"] = json!(materials);
        }
        if !images.is_empty() {
            root["images"] = json!(images);
            root["textures"] = json!(textures);
            root["samplers"] =
                json!([{"magFilter": 9729, "minFilter": 9987, "wrapS": 10497, "wrapT": 10497}]);
        }
        if !used.is_empty() {
            // Used, never required: a viewer without these extensions shows the rest values.
            root["extensionsUsed"] = json!(used);
        }
        if !lights.is_empty() {
            root["extensions"] = json!({"KHR_lights_punctual": {"lights": lights}});
        }
        if !cameras.is_empty() {
            root["cameras"] = json!(cameras);
        }
        if !written.is_empty() {
            root["animations"] = json!(written);
        }
        while !b.bin.len().is_multiple_of(4) {
            b.bin.push(0);
        }
        if !b.bin.is_empty() {
            root["buffers"] = json!([{"byteLength": b.bin.len()}]);
            root["bufferViews"] = json!(b.views);
            root["accessors"] = json!(b.accessors);
        }
        ExportedGltf { json: root, bin: b.bin }
    }

    /// The animation `name` of `channels`: a sampler of each channel, its times and values
    /// written to `b`, and the channel targeting its node and path.
    fn animation(b: &mut Builder, name: &str, channels: &[Channel]) -> Value {
        let mut samplers = Vec::new();
        let mut chans = Vec::new();
        for (i, c) in channels.iter().enumerate() {
            let input = b.floats(&c.times, 1, "SCALAR", None, true);
            let type_ = match c.width {
                3 => "VEC3",
                4 => "VEC4",
                _ => "SCALAR",
            };
            let width = if c.width == 3 || c.width == 4 { c.width } else { 1 };
            let output = b.floats(&c.values, width, type_, None, false);
            samplers.push(json!({"input": input, "output": output, "interpolation": c.interpolation}));
            chans.push(json!({"sampler": i, "target": {"node": c.node, "path": c.path}}));
        }
        json!({"name": name, "channels": chans, "samplers": samplers})
    }
}

/// Writes scene camera `c` ([`crate::gltf_camera`]): a root node holding the camera, its
/// translation channel, its rotation channel (an aimed camera's sampled from `eval` at every
/// frame), its lens as KHR_animation_pointer channels ([`attributes::camera_lens`]) and its
/// visibility as KHR_node_visibility ([`attributes::visibility`]).
fn export_camera(
    doc: &mut Document,
    scene: &Scene,
    eval: &keyrig_eval::SceneEvaluator,
    c: usize,
    options: &ExportOptions,
    range: (f64, f64),
) -> Result<(), ExportError> {
    let camera = &scene.cameras[c];
    let here = format!("cameras[{c}]");
    let t0 = range.0;
    let aspect = scene.render_size.map(keyrig_core::RenderSize::aspect);
    let lens_track =
        AnimatedTrack::new(&camera.lens).map_err(|e| scene_err(format!("{here}.lens"), e.to_string()))?;
    let camera_index = doc.cameras.len();
    doc.cameras.push(crate::gltf_camera::camera_json(camera, lens_track.sample(t0), aspect));
    let node = doc.nodes.len();
    doc.nodes.push(json!({"name": camera.name, "camera": camera_index}));
    doc.roots.push(node);
    let identity = (Quat::IDENTITY, Vec3::ZERO);
    let translation_here = format!("{here}.translation");
    set_vec3(
        &mut doc.nodes[node],
        "translation",
        &camera.translation,
        identity,
        Vec3::ZERO,
        &translation_here,
    )?;
    doc.channels.extend(vec3_channel(
        node,
        "translation",
        &camera.translation,
        identity,
        options,
        range,
        &translation_here,
    )?);
    let frames: Vec<f64> =
        (scene.frame_range.start..=scene.frame_range.end).map(|f| f64::from(f) / scene.fps).collect();
    let no_overrides = keyrig_eval::Overrides::new();
    if camera.aim.is_some() {
        let rotation_at = |t: f64| {
            eval.camera_at(c, t, &no_overrides)
                .map_or(Quat::IDENTITY, |s| Quat::from_mat3a(&s.world_from_camera.matrix3).normalize())
        };
        doc.nodes[node]["rotation"] = json!(rotation_at(t0).to_array());
        let tol = options.rotation_tolerance_deg.to_radians();
        let (times, values) = match &options.bake {
            Some(bake) => {
                resample_rotation(&rotation_at, &frames, &[], bake.rotation_tolerance(options), nlerp)
            }
            None => resample_rotation(&rotation_at, &frames, &[], tol, crate::model::slerp_short),
        };
        if frames.len() > 1 {
            doc.channels.push(linear_quat_channel(node, times, values));
        }
    } else {
        let rotation_here = format!("{here}.rotation");
        set_quat(&mut doc.nodes[node], &camera.rotation, Quat::IDENTITY, &rotation_here)?;
        doc.channels.extend(quat_channel(
            node,
            &camera.rotation,
            Quat::IDENTITY,
            options,
            range,
            &rotation_here,
        )?);
    }
    attributes::camera_lens(doc, camera, camera_index, &lens_track, aspect, &frames, options, range, &here)?;
    attributes::visibility(doc, node, &camera.visible, t0, &format!("{here}.visible"))?;
    Ok(())
}

/// Writes the joints of `skeleton` as nodes below the object node `object_node` and their
/// channels, returning the node of each joint.
///
/// A joint's node carries R(j)·T(j) as glTF's `T·R·S`: translation `t_rest + q_rest·t(t)`,
/// rotation `q_rest·q(t)`, scale `s(t)` — exact, as `translate(t_rest)·rotate(q_rest)·
/// translate(t)·rotate(q)·scale(s)` is that TRS. A root joint adds the skeleton's root
/// translation: folded into its translation when at most one of the two is animated, else
/// written on a node of its own between the object and the joint.
fn export_joints(
    doc: &mut Document,
    object_node: usize,
    skeleton: &keyrig_core::Skeleton,
    options: &ExportOptions,
    range: (f64, f64),
    here: &str,
) -> Result<Vec<usize>, ExportError> {
    let mut joint_nodes: Vec<usize> = Vec::with_capacity(skeleton.joints.len());
    let rt = &skeleton.root_translation;
    let rt_here = format!("{here}.skeleton.root_translation");
    let rt_value = sample_static(rt, &rt_here)?;
    for (ji, joint) in skeleton.joints.iter().enumerate() {
        let jhere = format!("{here}.skeleton.joints[{ji}]");
        let mut parent = match joint.parent {
            None => object_node,
            Some(p) if p < ji => joint_nodes[p],
            Some(p) => {
                return Err(scene_err(
                    format!("{jhere}.parent"),
                    format!("parent {p} is not before the joint"),
                ))
            }
        };
        let rest_rotation = joint.rest_rotation.normalize();
        if !joint.rest_translation.is_finite() || !rest_rotation.is_finite() {
            return Err(scene_err(&jhere, "rest transform is not finite"));
        }
        let is_root = joint.parent.is_none();
        let both_animated = is_root && rt.is_animated() && joint.translation.is_animated();
        if both_animated {
            let helper = doc.nodes.len();
            doc.nodes.push(json!({"name": format!("{}.root_translation", joint.name)}));
            add_child(&mut doc.nodes[parent], helper);
            let identity = (Quat::IDENTITY, Vec3::ZERO);
            set_vec3(&mut doc.nodes[helper], "translation", rt, identity, Vec3::ZERO, &rt_here)?;
            doc.channels.extend(vec3_channel(helper, "translation", rt, identity, options, range, &rt_here)?);
            parent = helper;
        }
        let jn = doc.nodes.len();
        add_child(&mut doc.nodes[parent], jn);
        doc.nodes.push(json!({"name": joint.name}));
        joint_nodes.push(jn);
        let rotation_at_rest = rest_rotation * sample_static(&joint.rotation, &format!("{jhere}.rotation"))?;
        doc.nodes[jn]["rotation"] = json!(rotation_at_rest.normalize().to_array());
        doc.channels.extend(quat_channel(
            jn,
            &joint.rotation,
            rest_rotation,
            options,
            range,
            &format!("{jhere}.rotation"),
        )?);
        set_vec3(
            &mut doc.nodes[jn],
            "scale",
            &joint.scale,
            (Quat::IDENTITY, Vec3::ZERO),
            Vec3::ONE,
            &format!("{jhere}.scale"),
        )?;
        doc.channels.extend(vec3_channel(
            jn,
            "scale",
            &joint.scale,
            (Quat::IDENTITY, Vec3::ZERO),
            options,
            range,
            &format!("{jhere}.scale"),
        )?);
        // Translation: t_rest + q_rest·t(t) (+ the root translation).
        let t_here = format!("{jhere}.translation");
        let t_value = sample_static(&joint.translation, &t_here)?;
        let root_shift = if is_root && !both_animated { rt_value } else { Vec3::ZERO };
        let static_translation = joint.rest_translation + rest_rotation * t_value + root_shift;
        if static_translation != Vec3::ZERO {
            doc.nodes[jn]["translation"] = json!(static_translation.to_array());
        }
        if joint.translation.is_animated() {
            let map = (rest_rotation, joint.rest_translation + root_shift);
            doc.channels.extend(vec3_channel(
                jn,
                "translation",
                &joint.translation,
                map,
                options,
                range,
                &t_here,
            )?);
        } else if is_root && rt.is_animated() {
            let map = (Quat::IDENTITY, joint.rest_translation + rest_rotation * t_value);
            doc.channels.extend(vec3_channel(jn, "translation", rt, map, options, range, &rt_here)?);
        }
    }
    Ok(joint_nodes)
}

/// A(j)⁻¹ of a rest skeleton as matrices.
fn ibms_of(skeleton: &keyrig_skin::RestSkeleton) -> Vec<Mat4> {
    skeleton.joint_from_bind_model().iter().map(|a| Mat4::from(*a)).collect()
}

/// Refuses vertex joints the skeleton does not have.
fn check_joints(prim: &PrimitiveData, joint_count: usize, here: &str) -> Result<(), ExportError> {
    if let Some((joints, weights)) = &prim.skin {
        for (j, w) in joints.iter().zip(weights) {
            for i in 0..4 {
                if w[i] != 0.0 && usize::from(j[i]) >= joint_count {
                    return Err(scene_err(
                        here,
                        format!("the mesh uses joint {} but the skeleton has {joint_count}", j[i]),
                    ));
                }
            }
        }
    }
    Ok(())
}

/// Writes a skinned mesh: the mesh on a root node of its own (glTF ignores a skinned mesh
/// node's transform, and the validator warns when it is not a root) with a skin of
/// `joint_nodes` and `ibms`.
fn skinned_mesh_node(
    doc: &mut Document,
    name: &str,
    primitives: &[PrimitiveData],
    ibms: &[Mat4],
    joint_nodes: &[usize],
    object_node: usize,
) {
    let mesh_index = doc.mesh(name, primitives, None);
    let flat: Vec<f32> = ibms.iter().flat_map(|m| m.to_cols_array()).collect();
    let acc = doc.b.floats(&flat, 16, "MAT4", None, false);
    let skin = doc.skins.len();
    let mut s = json!({"name": name, "joints": joint_nodes, "inverseBindMatrices": acc});
    // `skeleton`: the common root of the joints (the only root joint, else the object node).
    let roots: Vec<usize> = joint_nodes
        .iter()
        .copied()
        .filter(|&n| !joint_nodes.iter().any(|&p| has_child(&doc.nodes[p], n)))
        .collect();
    s["skeleton"] = json!(if roots.len() == 1 && has_child(&doc.nodes[object_node], roots[0]) {
        roots[0]
    } else {
        object_node
    });
    doc.skins.push(s);
    let mesh_node = doc.nodes.len();
    doc.nodes.push(json!({"name": format!("{name}.mesh"), "mesh": mesh_index, "skin": skin}));
    doc.roots.push(mesh_node);
}

fn has_child(node: &Value, child: usize) -> bool {
    node.get("children")
        .and_then(Value::as_array)
        .is_some_and(|c| c.iter().any(|x| x.as_u64() == Some(child as u64)))
}

/// The material of a glTF primitive, with its base-colour texture written to `doc` when the
/// image's bytes are known and it uses TEXCOORD_0.
fn gltf_material(doc: &mut Document, model: &ImportedModel, file: &Path, p: &ModelPrimitive) -> MaterialData {
    let texture = p.base_colour_texture.as_ref().and_then(|t| {
        if t.texcoord_set != 0 || p.texcoords.is_none() {
            return None;
        }
        let data = model.image_data.get(t.image)?.as_ref()?;
        Some(doc.texture((file.to_path_buf(), t.image), &data.bytes, &data.mime_type))
    });
    MaterialData { base_colour: p.base_colour_factor, texture }
}

/// An object whose mesh is mesh `index` of the glTF model `model` (see [`export_scene`]).
#[allow(clippy::too_many_arguments)]
fn gltf_object(
    doc: &mut Document,
    model: &ImportedModel,
    file: &Path,
    index: usize,
    node: usize,
    object: &keyrig_core::Object,
    joint_nodes: &[usize],
    options: &ExportOptions,
    range: (f64, f64),
    here: &str,
) -> Result<(), ExportError> {
    let file_err = |source: MeshFileError| ExportError::MeshFile {
        path: format!("{here}.mesh"),
        file: file.to_path_buf(),
        source: Box::new(source),
    };
    let Some(source_mesh) = model.meshes.get(index) else {
        return Err(file_err(MeshFileError::NoMesh(index)));
    };
    let Some(model_node) = model.nodes.iter().position(|n| n.mesh == Some(index)) else {
        return Err(file_err(MeshFileError::MeshNotShown(index)));
    };
    let triangles: Vec<&ModelPrimitive> =
        source_mesh.primitives.iter().filter(|p| p.mode == PrimitiveMode::Triangles).collect();
    if triangles.is_empty() {
        return Err(file_err(MeshFileError::NoTriangles(index)));
    }
    if model.nodes[model_node].skin.is_some() && !joint_nodes.is_empty() {
        // As keyrig deforms it: keyrig-skin's mesh, split back into the file's primitives.
        let skinned = model.skinned_mesh(model_node).map_err(|e| file_err(e.into()))?;
        if skinned.skeleton.len() != joint_nodes.len() {
            return Err(scene_err(
                format!("{here}.skeleton"),
                format!(
                    "{} joints, but the mesh from the model file is bound to {}",
                    joint_nodes.len(),
                    skinned.skeleton.len()
                ),
            ));
        }
        let mut prims = Vec::with_capacity(triangles.len());
        let (mut vbase, mut ibase) = (0usize, 0usize);
        for p in &triangles {
            let (nv, ni) = (p.positions.len(), p.indices.len());
            let material = gltf_material(doc, model, file, p);
            prims.push(PrimitiveData {
                positions: skinned.positions[vbase..vbase + nv].to_vec(),
                normals: Some(skinned.normals[vbase..vbase + nv].to_vec()),
                texcoords: p.texcoords.as_ref().map(|t| t.to_vec()),
                indices: skinned.indices[ibase..ibase + ni].iter().map(|&i| i - vbase as u32).collect(),
                skin: Some((
                    skinned.influences.joints()[vbase..vbase + nv].to_vec(),
                    skinned.influences.weights()[vbase..vbase + nv].to_vec(),
                )),
                targets: Vec::new(),
                material: Some(material),
            });
            vbase += nv;
            ibase += ni;
        }
        let ibms = ibms_of(&skinned.skeleton);
        skinned_mesh_node(doc, &object.name, &prims, &ibms, joint_nodes, node);
        return Ok(());
    }
    // Unskinned (or an object without a skeleton): the mesh on the object node, in the node's
    // own space, with its morph targets.
    let mut prims = Vec::with_capacity(triangles.len());
    let targets = triangles.iter().map(|p| p.morph_targets.len()).max().unwrap_or(0);
    for p in &triangles {
        let material = gltf_material(doc, model, file, p);
        let n = p.positions.len();
        let morph: Vec<(Vec<Vec3>, Option<Vec<Vec3>>)> = (0..targets)
            .map(|t| {
                let target = p.morph_targets.get(t);
                let dp = target
                    .and_then(|t| t.positions.as_ref())
                    .map_or_else(|| vec![Vec3::ZERO; n], |d| d.to_vec());
                let dn = p.normals.as_ref().map(|_| {
                    target
                        .and_then(|t| t.normals.as_ref())
                        .map_or_else(|| vec![Vec3::ZERO; n], |d| d.to_vec())
                });
                (dp, dn)
            })
            .collect();
        prims.push(PrimitiveData {
            positions: p.positions.to_vec(),
            normals: p.normals.as_ref().map(|n| n.to_vec()),
            texcoords: p.texcoords.as_ref().map(|t| t.to_vec()),
            indices: p.indices.to_vec(),
            skin: None,
            targets: morph,
            material: Some(material),
        });
    }
    let keyed = &object.attributes.morph_weights;
    let default_weights = (targets > 0).then(|| {
        let w = model.nodes[model_node].weights.clone().unwrap_or_else(|| source_mesh.weights.clone());
        // The scene's weights (their values at the start of the range), else the file's.
        (0..targets)
            .map(|i| match keyed.get(i) {
                Some(k) => AnimatedTrack::new(k).map_or(k.value, |t| t.sample(range.0)),
                None => w.get(i).copied().unwrap_or(0.0),
            })
            .collect::<Vec<f32>>()
    });
    let m = doc.mesh(&object.name, &prims, default_weights.as_deref());
    doc.nodes[node]["mesh"] = json!(m);
    if targets > 0 && !keyed.is_empty() {
        // The scene's morph-weight channels (targets it does not key keep their default).
        let mut all: Vec<Animated<f32>> = keyed.iter().take(targets).cloned().collect();
        let defaults = default_weights.clone().unwrap_or_default();
        all.extend((all.len()..targets).map(|i| Animated::constant(defaults.get(i).copied().unwrap_or(0.0))));
        if let Some(w) = attributes::weights_track(&all, range, &format!("{here}.attributes.morph_weights"))?
        {
            doc.channels.push(weights_channel(node, &w, options));
        }
    } else if targets > 0 {
        // The morph weights of the file's first animation, as `keyrig deform` plays them.
        let weights =
            model.animations.first().into_iter().flat_map(|a| &a.channels).find_map(|c| match &c.target {
                ChannelTarget::Weights(w)
                    if c.node == model_node && w.targets == targets && !w.keys.is_empty() =>
                {
                    Some(w)
                }
                _ => None,
            });
        if let Some(w) = weights {
            doc.channels.push(weights_channel(node, w, options));
        }
    }
    Ok(())
}

/// A morph-weight channel of a glTF weights track: STEP, LINEAR or CUBICSPLINE as in the file
/// (exact), or in Blender mode LINEAR keys within the weight tolerance.
fn weights_channel(node: usize, w: &WeightsTrack, options: &ExportOptions) -> Channel {
    let interpolation = w.keys[0].interpolation;
    let times: Vec<f32> = w.keys.iter().map(|k| k.time as f32).collect();
    let channel = |interpolation: &'static str, times: Vec<f32>, values: Vec<f32>| Channel {
        node,
        path: "weights",
        interpolation,
        times,
        values,
        width: 1,
    };
    match (interpolation, &options.bake) {
        (Interpolation::Step, _) => {
            channel("STEP", times, w.keys.iter().flat_map(|k| k.value.clone()).collect())
        }
        (Interpolation::Linear | Interpolation::Tcb, _) => {
            channel("LINEAR", times, w.keys.iter().flat_map(|k| k.value.clone()).collect())
        }
        (Interpolation::Hermite, None) => {
            let zero = vec![0.0f32; w.targets];
            let mut values = Vec::with_capacity(w.keys.len() * 3 * w.targets);
            for k in &w.keys {
                values.extend_from_slice(k.in_tangent.as_ref().unwrap_or(&zero));
                values.extend_from_slice(&k.value);
                values.extend_from_slice(k.out_tangent.as_ref().unwrap_or(&zero));
            }
            channel("CUBICSPLINE", times, values)
        }
        (Interpolation::Hermite, Some(bake)) => {
            let f = |t: f64| -> Vec<f64> {
                crate::model::sample_weights(w, t).unwrap_or_default().iter().map(|&x| f64::from(x)).collect()
            };
            let breaks: Vec<f64> = w.keys.iter().map(|k| k.time).collect();
            let (t, v) = resample_linear(&f, &breaks, &[], bake.weight_tolerance, max_abs);
            channel(
                "LINEAR",
                t.iter().map(|&t| t as f32).collect(),
                v.iter().flatten().map(|&x| x as f32).collect(),
            )
        }
    }
}

/// An MD2 object: frames of `clip` as morph targets of the object node's mesh, the weights
/// keyed so that glTF's LINEAR weights are keyrig's looping playback at `fps` over the
/// scene's frame range, the skin image as base-colour texture.
#[allow(clippy::too_many_arguments)]
fn md2_object(
    doc: &mut Document,
    scene: &Scene,
    model: &crate::md2::Md2Model,
    file: &Path,
    clip: Option<&str>,
    fps: f64,
    node: usize,
    name: &str,
) -> Result<(), MeshFileError> {
    let frames = model.clip_frames(clip).ok_or_else(|| MeshFileError::NoClip {
        clip: clip.unwrap_or_default().to_string(),
        clips: model.clips.iter().map(|c| c.name.clone()).collect(),
    })?;
    if frames.is_empty() {
        return Err(MeshFileError::NoFrames);
    }
    if !(fps.is_finite() && fps > 0.0) {
        return Err(MeshFileError::BadFps(fps));
    }
    let base = model.frame_pose(frames.start).ok_or(MeshFileError::FrameMissing(frames.start))?;
    let mut targets = Vec::with_capacity(frames.len());
    for f in frames.clone() {
        let pose = model.frame_pose(f).ok_or(MeshFileError::FrameMissing(f))?;
        let dp: Vec<Vec3> = pose.positions.iter().zip(&base.positions).map(|(p, q)| *p - *q).collect();
        let dn: Vec<Vec3> = pose.normals.iter().zip(&base.normals).map(|(p, q)| *p - *q).collect();
        targets.push((dp, Some(dn)));
    }
    let texture = match &model.skin {
        Some(skin) => {
            let mut png = Vec::new();
            image::RgbaImage::from_raw(skin.width, skin.height, skin.rgba.clone())
                .ok_or(MeshFileError::SkinSize)?
                .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)?;
            Some(doc.texture((file.to_path_buf(), 0), &png, "image/png"))
        }
        None => None,
    };
    let prim = PrimitiveData {
        positions: base.positions,
        normals: Some(base.normals),
        texcoords: Some(model.texcoords.clone()),
        indices: model.indices.clone(),
        skin: None,
        targets,
        material: Some(MaterialData { base_colour: [1.0; 4], texture }),
    };
    let n = frames.len();
    let m = doc.mesh(name, &[prim], Some(&vec![0.0; n]));
    doc.nodes[node]["mesh"] = json!(m);
    // Keys at the scene range's ends and at every frame boundary between them.
    let (t0, t1) =
        (f64::from(scene.frame_range.start) / scene.fps, f64::from(scene.frame_range.end) / scene.fps);
    if !(t0.is_finite() && t1.is_finite()) {
        return Err(MeshFileError::FrameRangeNotFinite);
    }
    let mut times = vec![t0];
    let (k0, k1) = ((t0 * fps).floor() as i64, (t1 * fps).ceil() as i64);
    if k1 - k0 > 10_000_000 {
        return Err(MeshFileError::TooManyFrames);
    }
    times.extend((k0..=k1).map(|k| k as f64 / fps).filter(|&t| t > t0 && t < t1));
    if t1 > t0 {
        times.push(t1);
    }
    let playback = model.playback()?;
    let mut weights = vec![0.0f32; times.len() * n];
    for (i, &t) in times.iter().enumerate() {
        let blend = playback.blend_at(clip, fps, t)?;
        let (a, b) = (blend.frame_a as usize, blend.frame_b as usize);
        weights[i * n + (a - frames.start)] += 1.0 - blend.t;
        weights[i * n + (b - frames.start)] += blend.t;
    }
    doc.channels.push(Channel {
        node,
        path: "weights",
        interpolation: "LINEAR",
        times: times.iter().map(|&t| t as f32).collect(),
        values: weights,
        width: 1,
    });
    Ok(())
}

fn add_child(node: &mut Value, child: usize) {
    match node.get_mut("children").and_then(Value::as_array_mut) {
        Some(children) => children.push(json!(child)),
        None => node["children"] = json!([child]),
    }
}

/// The rotation taking −Z (a glTF light's direction) to `dir`.
fn look_rotation(dir: Vec3) -> Quat {
    match dir.try_normalize() {
        Some(d) => Quat::from_rotation_arc(Vec3::NEG_Z, d),
        None => Quat::IDENTITY,
    }
}

fn sample_static<T: keyrig_core::TrackValue>(a: &Animated<T>, here: &str) -> Result<T, ExportError> {
    Ok(AnimatedTrack::new(a)
        .map_err(|e| scene_err(here, e.to_string()))?
        .sample(a.track.keys.first().map_or(0.0, |k| k.time)))
}

fn sample_at<T: keyrig_core::TrackValue>(a: &Animated<T>, t: f64, here: &str) -> Result<T, ExportError> {
    Ok(AnimatedTrack::new(a).map_err(|e| scene_err(here, e.to_string()))?.sample(t))
}

/// A rigid map `v ↦ rotation·v + offset` applied to a Vec3 track (tangents: `rotation·v`).
type Vec3Map = (Quat, Vec3);

fn set_vec3(
    node: &mut Value,
    field: &str,
    a: &Animated<Vec3>,
    map: Vec3Map,
    default: Vec3,
    here: &str,
) -> Result<(), ExportError> {
    let v = map.0 * sample_static(a, here)? + map.1;
    if v != default {
        node[field] = json!(v.to_array());
    }
    Ok(())
}

fn set_quat(node: &mut Value, a: &Animated<Quat>, rest: Quat, here: &str) -> Result<(), ExportError> {
    let q = (rest * sample_static(a, here)?).normalize();
    if q != Quat::IDENTITY {
        node["rotation"] = json!(q.to_array());
    }
    Ok(())
}

/// A translation/scale channel of `map(track)`: exact (STEP, LINEAR or CUBICSPLINE with the
/// track's tangents), or in Blender mode LINEAR keys within the position tolerance.
fn vec3_channel(
    node: usize,
    path: &'static str,
    a: &Animated<Vec3>,
    map: Vec3Map,
    options: &ExportOptions,
    range: (f64, f64),
    here: &str,
) -> Result<Option<Channel>, ExportError> {
    if a.track.is_empty() {
        return Ok(None);
    }
    let (rotation, offset) = map;
    if !a.cycles().is_hold() {
        let track = Track::with_cycles(&a.track, a.cycles()).map_err(|e| scene_err(here, e.to_string()))?;
        let f = |t: f64| -> Vec<f64> {
            (rotation * track.sample(t) + offset).to_array().iter().map(|&x| f64::from(x)).collect()
        };
        let tolerance = options.bake.map_or(CYCLE_POSITION_TOLERANCE, |b| b.position_tolerance);
        let (t, v) = resample_linear(&f, &cycle_breaks(&track, range), &[], tolerance, euclidean);
        return Ok(Some(Channel {
            node,
            path,
            interpolation: "LINEAR",
            times: t.iter().map(|&t| t as f32).collect(),
            values: v.iter().flatten().map(|&x| x as f32).collect(),
            width: 3,
        }));
    }
    let track = Track::new(&a.track).map_err(|e| scene_err(format!("{here}.track"), e.to_string()))?;
    if let Some(bake) = &options.bake {
        let all_step = segment_modes(&track).iter().all(|&m| m == Interpolation::Step);
        if !all_step {
            let f = |t: f64| -> Vec<f64> {
                (rotation * track.sample(t) + offset).to_array().iter().map(|&x| f64::from(x)).collect()
            };
            let (breaks, jumps) = step_breaks(track.key_times(), |i| track.segment_interpolation(i));
            let (t, v) = resample_linear(&f, &breaks, &jumps, bake.position_tolerance, euclidean);
            return Ok(Some(Channel {
                node,
                path,
                interpolation: "LINEAR",
                times: t.iter().map(|&t| t as f32).collect(),
                values: v.iter().flatten().map(|&x| x as f32).collect(),
                width: 3,
            }));
        }
    }
    let mut channel = cubic_or_simple_channel(node, path, &track);
    let cubic = channel.interpolation == "CUBICSPLINE";
    for (i, v) in channel.values.chunks_exact_mut(3).enumerate() {
        let x = Vec3::from_slice(v);
        // CUBICSPLINE elements are (in-tangent, value, out-tangent): tangents only rotate.
        let y = if cubic && i % 3 != 1 { rotation * x } else { rotation * x + offset };
        v.copy_from_slice(&y.to_array());
    }
    Ok(Some(channel))
}

/// Largest distance (scene units) between the LINEAR keys a translation or scale track with
/// cycles is written as and keyrig's curve, outside Blender mode.
pub const CYCLE_POSITION_TOLERANCE: f64 = 1e-4;

/// The times a track with cycles is resampled between: its key times and their repeats (for
/// ping-pong, their mirror images) over the keys and the scene's `range`, with the range's ends.
/// glTF has no cycles: the exported keys play the repeats up to the end of the range and hold
/// after it.
fn cycle_breaks<T: keyrig_core::TrackValue>(track: &Track<T>, range: (f64, f64)) -> Vec<f64> {
    let times = track.key_times();
    let (t0, tn) = track.domain();
    let (start, end) = (range.0.min(t0), range.1.max(tn));
    let period = tn - t0;
    let mut breaks = vec![start, end];
    breaks.extend_from_slice(times);
    if period > 0.0 && start.is_finite() && end.is_finite() {
        let first = ((start - t0) / period).floor() as i64;
        let last = ((end - t0) / period).ceil() as i64;
        // At most a million repeats: a longer range than that is not worth writing out.
        if last - first <= 1_000_000 {
            for k in first..=last {
                let shift = k as f64 * period;
                for &t in times {
                    // Repeats: t + k·P; ping-pong's odd cycles are mirrored, its even ones repeat.
                    breaks.push(t + shift);
                    breaks.push(t0 + shift + (tn - t));
                }
            }
        }
    }
    breaks.retain(|&t| (start..=end).contains(&t));
    breaks.sort_by(f64::total_cmp);
    // Repeated key times differ from each other by rounding only: keep one (f32 key times
    // must increase). The range's end stays: a break just before it gives way.
    breaks.dedup_by(|later, earlier| *later - *earlier < MIN_SEGMENT);
    if let Some(last) = breaks.last_mut() {
        *last = end;
    }
    breaks
}

/// Key times plus, for every Step segment, a break just before its end key (hold, then jump
/// within [`STEP_JUMP`]); and the jumps' start times, whose segments are written as they are
/// (a jump is no curve that more keys would follow closer).
fn step_breaks(times: &[f64], mode: impl Fn(usize) -> Option<Interpolation>) -> (Vec<f64>, Vec<f64>) {
    let mut breaks: Vec<f64> = times.to_vec();
    let mut jumps = Vec::new();
    for i in 0..times.len().saturating_sub(1) {
        if mode(i) == Some(Interpolation::Step) {
            let jump = times[i + 1] - STEP_JUMP.min((times[i + 1] - times[i]) / 2.0);
            breaks.push(jump);
            jumps.push(jump);
        }
    }
    breaks.sort_by(f64::total_cmp);
    breaks.dedup();
    (breaks, jumps)
}

/// Whether the segment from break `t0` is a Step segment's jump (`jumps` ascending).
fn is_jump(jumps: &[f64], t0: f64) -> bool {
    jumps.binary_search_by(|j| j.total_cmp(&t0)).is_ok()
}

fn euclidean(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt()
}

fn max_abs(a: &[f64], b: &[f64]) -> f64 {
    a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
}

/// Resamples `f` on `[breaks]` into LINEAR keys: each interval is halved until linear
/// interpolation between its end keys stays within `tol / 2` (by `distance`) of `f` at 15
/// interior points; an interval that starts at one of `jumps` is written as it is.
fn resample_linear(
    f: &dyn Fn(f64) -> Vec<f64>,
    breaks: &[f64],
    jumps: &[f64],
    tol: f64,
    distance: fn(&[f64], &[f64]) -> f64,
) -> (Vec<f64>, Vec<Vec<f64>>) {
    fn go(
        f: &dyn Fn(f64) -> Vec<f64>,
        (t0, t1): (f64, f64),
        (v0, v1): (&[f64], Vec<f64>),
        tol: f64,
        distance: fn(&[f64], &[f64]) -> f64,
        out: &mut (Vec<f64>, Vec<Vec<f64>>),
        depth: u32,
    ) {
        let within = (1..16).all(|i| {
            let u = f64::from(i) / 16.0;
            let lin: Vec<f64> = v0.iter().zip(&v1).map(|(a, b)| a + u * (b - a)).collect();
            distance(&lin, &f(t0 + u * (t1 - t0))) <= 0.5 * tol
        });
        if within || t1 - t0 < MIN_SEGMENT || depth > 24 {
            out.0.push(t1);
            out.1.push(v1);
        } else {
            let mid = 0.5 * (t0 + t1);
            let vm = f(mid);
            go(f, (t0, mid), (v0, vm.clone()), tol, distance, out, depth + 1);
            let v_mid = out.1.last().cloned().unwrap_or(vm);
            go(f, (mid, t1), (&v_mid, v1), tol, distance, out, depth + 1);
        }
    }
    let mut out = (vec![breaks[0]], vec![f(breaks[0])]);
    for w in breaks.windows(2) {
        if is_jump(jumps, w[0]) {
            out.0.push(w[1]);
            out.1.push(f(w[1]));
            continue;
        }
        let v0 = out.1.last().cloned().unwrap_or_default();
        go(f, (w[0], w[1]), (&v0, f(w[1])), tol, distance, &mut out, 0);
    }
    out
}

/// The interpolation of each segment of `track`, in order.
fn segment_modes<T: keyrig_core::TrackValue>(track: &Track<T>) -> Vec<Interpolation> {
    (0..).map_while(|i| track.segment_interpolation(i)).collect()
}

fn cubic_or_simple_channel(node: usize, path: &'static str, track: &Track<Vec3>) -> Channel {
    let times = track.key_times();
    let values = track.key_values();
    let n = times.len();
    let modes = segment_modes(track);
    let simple = |interpolation: &'static str| Channel {
        node,
        path,
        interpolation,
        times: times.iter().map(|&t| t as f32).collect(),
        values: values.iter().flat_map(|v| v.to_array()).collect(),
        width: 3,
    };
    if modes.iter().all(|&m| m == Interpolation::Step) {
        return simple("STEP");
    }
    if modes.iter().all(|&m| m == Interpolation::Linear) {
        return simple("LINEAR");
    }
    // CUBICSPLINE: per key (in-tangent a_k, value v_k, out-tangent b_k), per second.
    let mut out_times: Vec<f32> = Vec::new();
    let mut out: Vec<[Vec3; 3]> = Vec::new();
    for k in 0..n {
        let in_tangent =
            if k == 0 { Vec3::ZERO } else { track.segment_tangents(k - 1).map_or(Vec3::ZERO, |t| t.1) };
        let out_tangent = track.segment_tangents(k).map_or(Vec3::ZERO, |t| t.0);
        // Only segments have an interpolation: the last key has none.
        let step_next = track.segment_interpolation(k) == Some(Interpolation::Step);
        out_times.push(times[k] as f32);
        out.push([in_tangent, values[k], out_tangent]);
        if step_next {
            // Hold v_k until just before the next key, then jump.
            let hold = (times[k + 1] - STEP_JUMP.min((times[k + 1] - times[k]) / 2.0)) as f32;
            if hold > *out_times.last().unwrap_or(&f32::NEG_INFINITY) && hold < times[k + 1] as f32 {
                out_times.push(hold);
                out.push([Vec3::ZERO, values[k], Vec3::ZERO]);
            }
        }
    }
    Channel {
        node,
        path,
        interpolation: "CUBICSPLINE",
        times: out_times,
        values: out.iter().flat_map(|k| k.iter().flat_map(|v| v.to_array())).collect(),
        width: 3,
    }
}

/// A rotation channel of `rest · T(t)`:
/// - all Step: STEP; all Linear without spins: LINEAR key for key (exact);
/// - all Hermite (glTF CUBICSPLINE keys, e.g. of an imported model): CUBICSPLINE with the
///   keys' tangents (exact: keyrig's Hermite rotation is glTF's component-wise Hermite, and
///   left-multiplying by `rest` is linear; keys and tangents are written with the signs
///   keyrig's sign-consistent track uses);
/// - otherwise resampled as LINEAR keys within the rotation tolerance.
///
/// In Blender mode every channel that is not all Step is resampled, checked against the
/// component-wise interpolation (nlerp) Blender uses.
fn quat_channel(
    node: usize,
    a: &Animated<Quat>,
    rest: Quat,
    options: &ExportOptions,
    range: (f64, f64),
    here: &str,
) -> Result<Option<Channel>, ExportError> {
    if a.track.is_empty() {
        return Ok(None);
    }
    if !a.cycles().is_hold() {
        let track = Track::with_cycles(&a.track, a.cycles()).map_err(|e| scene_err(here, e.to_string()))?;
        let sampler = |t: f64| (rest * track.sample(t)).normalize();
        let breaks = cycle_breaks(&track, range);
        let (t, v) = match &options.bake {
            Some(bake) => resample_rotation(&sampler, &breaks, &[], bake.rotation_tolerance(options), nlerp),
            None => resample_rotation(
                &sampler,
                &breaks,
                &[],
                options.rotation_tolerance_deg.to_radians(),
                crate::model::slerp_short,
            ),
        };
        return Ok(Some(linear_quat_channel(node, t, v)));
    }
    let track = Track::new(&a.track).map_err(|e| scene_err(format!("{here}.track"), e.to_string()))?;
    let times = track.key_times();
    let modes = segment_modes(&track);
    let values: Vec<Quat> = track.key_values().iter().map(|q| (rest * *q).normalize()).collect();
    let spin = track.has_spin();
    let all = |m: Interpolation| modes.iter().all(|&x| x == m);
    let simple = |interpolation: &'static str| Channel {
        node,
        path: "rotation",
        interpolation,
        times: times.iter().map(|&t| t as f32).collect(),
        values: values.iter().flat_map(|q| q.to_array()).collect(),
        width: 4,
    };
    if all(Interpolation::Step) {
        return Ok(Some(simple("STEP")));
    }
    if options.bake.is_none() && !spin && all(Interpolation::Linear) {
        return Ok(Some(simple("LINEAR")));
    }
    if options.bake.is_none() && !spin && all(Interpolation::Hermite) && a.track.keys.len() == times.len() {
        let mut flat = Vec::with_capacity(values.len() * 12);
        let zero = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
        for (k, key) in a.track.keys.iter().enumerate() {
            // The track flipped this key when its stored value points the other way.
            let sign = if track.key_values()[k].dot(key.value) < 0.0 { -1.0 } else { 1.0 };
            let tangent = |t: Option<Quat>| -> Quat {
                let t = t.unwrap_or(zero);
                rest * Quat::from_vec4(glam::Vec4::from(t) * sign)
            };
            let (in_t, out_t) = (tangent(key.in_tangent), tangent(key.out_tangent));
            flat.extend_from_slice(&in_t.to_array());
            flat.extend_from_slice(&values[k].to_array());
            flat.extend_from_slice(&out_t.to_array());
        }
        return Ok(Some(Channel {
            node,
            path: "rotation",
            interpolation: "CUBICSPLINE",
            times: times.iter().map(|&t| t as f32).collect(),
            values: flat,
            width: 4,
        }));
    }
    let sampler = |t: f64| (rest * track.sample(t)).normalize();
    let (mut breaks, jumps) = step_breaks(times, |i| track.segment_interpolation(i));
    // Spin segments: pieces of at most SPIN_PIECE_DEG of the unwrapped angle.
    for i in 0..modes.len() {
        if let (Some((_, degrees)), true) = (track.segment_spin(i), modes[i] != Interpolation::Step) {
            let pieces = (degrees.abs() / SPIN_PIECE_DEG).ceil().max(1.0) as usize;
            let (t0, t1) = (times[i], times[i + 1]);
            breaks.extend((1..pieces).map(|k| t0 + (t1 - t0) * k as f64 / pieces as f64));
        }
    }
    breaks.sort_by(f64::total_cmp);
    breaks.dedup();
    let (t, v) = match &options.bake {
        Some(bake) => resample_rotation(&sampler, &breaks, &jumps, bake.rotation_tolerance(options), nlerp),
        None => resample_rotation(
            &sampler,
            &breaks,
            &jumps,
            options.rotation_tolerance_deg.to_radians(),
            crate::model::slerp_short,
        ),
    };
    Ok(Some(linear_quat_channel(node, t, v)))
}

fn linear_quat_channel(node: usize, times: Vec<f64>, values: Vec<Quat>) -> Channel {
    // Keep consecutive keys sign-consistent so slerp takes the short way, as keyrig does (and
    // so that component-wise blending, as Blender does, does not pass through zero).
    let mut flat = Vec::with_capacity(values.len() * 4);
    let mut prev = Quat::IDENTITY;
    for (i, q) in values.iter().enumerate() {
        let q = if i > 0 && prev.dot(*q) < 0.0 { -*q } else { *q };
        flat.extend_from_slice(&q.to_array());
        prev = q;
    }
    Channel {
        node,
        path: "rotation",
        interpolation: "LINEAR",
        times: times.iter().map(|&t| t as f32).collect(),
        values: flat,
        width: 4,
    }
}

/// Component-wise interpolation of two quaternions (the second sign-aligned to the first),
/// then normalized: how importers that do not slerp (Blender 3.4) blend LINEAR rotation keys.
#[must_use]
pub fn nlerp(a: Quat, b: Quat, u: f32) -> Quat {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    Quat::from_vec4(glam::Vec4::from(a).lerp(glam::Vec4::from(b), u)).normalize()
}

/// Angle between two rotations (radians), computed in f64 as `2·atan2(|v|, |w|)` of the
/// relative rotation `a⁻¹·b`, which stays accurate for tiny angles (unlike `acos` of a dot).
#[must_use]
pub fn rotation_angle(a: Quat, b: Quat) -> f64 {
    let a = glam::DQuat::from_xyzw(f64::from(a.x), f64::from(a.y), f64::from(a.z), f64::from(a.w));
    let b = glam::DQuat::from_xyzw(f64::from(b.x), f64::from(b.y), f64::from(b.z), f64::from(b.w));
    let d = a.conjugate() * b;
    2.0 * glam::DVec3::new(d.x, d.y, d.z).length().atan2(d.w.abs())
}

/// Minimum duration of a resampled segment (seconds); stops runaway subdivision.
const MIN_SEGMENT: f64 = 1e-4;

/// How an importer blends two LINEAR rotation keys: slerp (the glTF specification) or nlerp.
type QuatLerp = fn(Quat, Quat, f32) -> Quat;

/// Resamples `f` on `[breaks]` into LINEAR keys: each interval is halved until its end keys
/// are at most [`MAX_ROTATION_STEP_DEG`] apart and `lerp` between them stays within `tol / 2`
/// radians of `f` at 15 interior points.
fn resample_rotation(
    f: &dyn Fn(f64) -> Quat,
    breaks: &[f64],
    jumps: &[f64],
    tol: f64,
    lerp: QuatLerp,
) -> (Vec<f64>, Vec<Quat>) {
    let mut times = vec![breaks[0]];
    let mut values = vec![f(breaks[0])];
    for w in breaks.windows(2) {
        if is_jump(jumps, w[0]) {
            times.push(w[1]);
            values.push(f(w[1]));
            continue;
        }
        subdivide(f, w[0], w[1], tol, lerp, &mut times, &mut values, 0);
    }
    (times, values)
}

#[allow(clippy::too_many_arguments)]
fn subdivide(
    f: &dyn Fn(f64) -> Quat,
    t0: f64,
    t1: f64,
    tol: f64,
    lerp: QuatLerp,
    times: &mut Vec<f64>,
    values: &mut Vec<Quat>,
    depth: u32,
) {
    let (q0, q1) = (f(t0), f(t1));
    // Check at 15 interior points against half the tolerance, so that the curve between
    // the checked points (and f32 key times) stays within the full tolerance.
    let within = rotation_angle(q0, q1) <= MAX_ROTATION_STEP_DEG.to_radians()
        && (1..16).all(|i| {
            let u = f64::from(i) / 16.0;
            let lin = lerp(q0, q1, u as f32);
            rotation_angle(lin, f(t0 + u * (t1 - t0))) <= 0.5 * tol
        });
    if within || t1 - t0 < MIN_SEGMENT || depth > 24 {
        times.push(t1);
        values.push(q1);
    } else {
        let mid = 0.5 * (t0 + t1);
        subdivide(f, t0, mid, tol, lerp, times, values, depth + 1);
        subdivide(f, mid, t1, tol, lerp, times, values, depth + 1);
    }
}

/// A(j)⁻¹ for every joint: the inverse of the product of rest transforms down the chain.
/// Parents come before their joints ([`export_joints`] refuses the skeleton otherwise).
fn inverse_bind_matrices(skeleton: &keyrig_core::Skeleton) -> Vec<Mat4> {
    let mut model_from_joint: Vec<Affine3A> = Vec::with_capacity(skeleton.joints.len());
    for joint in &skeleton.joints {
        let local =
            Affine3A::from_rotation_translation(joint.rest_rotation.normalize(), joint.rest_translation);
        let parent = joint.parent.and_then(|p| model_from_joint.get(p));
        model_from_joint.push(parent.map_or(local, |parent| *parent * local));
    }
    model_from_joint.iter().map(|a| Mat4::from(a.inverse())).collect()
}

/// Frame rates [`export_md2`] accepts. Key times are `k / fps` in f32 seconds: far above
/// 1000 fps consecutive keys of a long clip would no longer be distinct, far below 0.01
/// they would leave f32's exact integer range.
pub const MD2_FPS_RANGE: std::ops::RangeInclusive<f64> = 0.01..=1000.0;

/// Options of [`export_md2`].
#[derive(Clone, Copy, Debug)]
pub struct Md2ExportOptions {
    /// Playback rate of the clips (Quake 2 played its models at 10 frames per second).
    pub fps: f64,
}

impl Default for Md2ExportOptions {
    fn default() -> Self {
        Md2ExportOptions { fps: 10.0 }
    }
}

/// Converts an MD2 model to glTF morph-target animation.
///
/// The mesh's base shape is frame 0; every frame is a morph target (position and normal
/// displacements from frame 0). Each clip becomes an animation that drives the weights
/// LINEARly, one-hot per frame at `k / fps`, with a closing key that blends the last frame
/// back into the first — exactly [`crate::md2::Md2Model::sample_clip`] with looping.
/// Quake's Z-up axes become glTF's Y-up by a −90° rotation about X on the root node. The skin
/// image, when loaded, is embedded as PNG and used as the base-colour texture.
///
/// # Errors
/// A non-positive or non-finite frame rate, or a skin image that cannot be encoded.
pub fn export_md2(
    model: &crate::md2::Md2Model,
    options: Md2ExportOptions,
) -> Result<ExportedGltf, ExportError> {
    if !(options.fps.is_finite() && MD2_FPS_RANGE.contains(&options.fps)) {
        return Err(scene_err(
            "fps",
            format!(
                "{} is not a frame rate between {} and {} frames per second",
                options.fps,
                MD2_FPS_RANGE.start(),
                MD2_FPS_RANGE.end()
            ),
        ));
    }
    let mut b = Builder::default();
    let base = model.frame_pose(0).ok_or_else(|| scene_err("frames", "the model has no frames"))?;
    let mut attributes = serde_json::Map::new();
    attributes.insert("POSITION".into(), json!(b.vec3s(&base.positions, Some(ARRAY_BUFFER), true)));
    attributes.insert("NORMAL".into(), json!(b.vec3s(&base.normals, Some(ARRAY_BUFFER), false)));
    let uv: Vec<f32> = model.texcoords.iter().flat_map(|t| t.to_array()).collect();
    attributes.insert("TEXCOORD_0".into(), json!(b.floats(&uv, 2, "VEC2", Some(ARRAY_BUFFER), false)));
    let indices = b.indices(&model.indices);
    let mut targets = Vec::with_capacity(model.frames.len());
    for f in 0..model.frames.len() {
        let pose = model.frame_pose(f).ok_or_else(|| scene_err("frames", "frame vanished"))?;
        let dp: Vec<Vec3> = pose.positions.iter().zip(&base.positions).map(|(p, q)| *p - *q).collect();
        let dn: Vec<Vec3> = pose.normals.iter().zip(&base.normals).map(|(p, q)| *p - *q).collect();
        targets.push(json!({
            "POSITION": b.vec3s(&dp, Some(ARRAY_BUFFER), true),
            "NORMAL": b.vec3s(&dn, Some(ARRAY_BUFFER), false),
        }));
    }
    let mut primitive = json!({"attributes": attributes, "indices": indices, "mode": 4, "targets": targets});
    let mut root = json!({
        "asset": {"version": "2.0", "generator": concat!("keyrig ", env!("CARGO_PKG_VERSION"), " (MD2 conversion)")},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{
            "name": "md2",
            "mesh": 0,
            "rotation": Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2).to_array(),
        }],
    });
    if let Some(skin) = &model.skin {
        let mut png = Vec::new();
        image::RgbaImage::from_raw(skin.width, skin.height, skin.rgba.clone())
            .ok_or_else(|| scene_err("skin", "image size does not match its pixels"))?
            .write_to(&mut std::io::Cursor::new(&mut png), image::ImageFormat::Png)
            .map_err(|e| scene_err("skin", e.to_string()))?;
        let view = b.view(&png, None);
        root["images"] = json!([{"bufferView": view, "mimeType": "image/png"}]);
        root["samplers"] = json!([{"magFilter": 9729, "minFilter": 9729}]);
        root["textures"] = json!([{"sampler": 0, "source": 0}]);
        root["materials"] = json!([{
            "name": "skin",
            "pbrMetallicRoughness": {"baseColorTexture": {"index": 0}, "metallicFactor": 0.0, "roughnessFactor": 1.0},
        }]);
        primitive["material"] = json!(0);
    }
    let n_targets = model.frames.len();
    root["meshes"] = json!([{
        "name": "md2",
        "primitives": [primitive],
        "weights": vec![0.0f32; n_targets],
        "extras": {"targetNames": model.frames.iter().map(|f| f.name.clone()).collect::<Vec<_>>()},
    }]);
    let mut animations = Vec::new();
    for clip in &model.clips {
        let frames: Vec<usize> = clip.frames.clone().chain(std::iter::once(clip.frames.start)).collect();
        let times: Vec<f32> = (0..frames.len()).map(|k| (k as f64 / options.fps) as f32).collect();
        let mut weights = vec![0.0f32; frames.len() * n_targets];
        for (k, &f) in frames.iter().enumerate() {
            weights[k * n_targets + f] = 1.0;
        }
        let input = b.floats(&times, 1, "SCALAR", None, true);
        let output = b.floats(&weights, 1, "SCALAR", None, false);
        animations.push(json!({
            "name": clip.name,
            "samplers": [{"input": input, "output": output, "interpolation": "LINEAR"}],
            "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
        }));
    }
    root["animations"] = json!(animations);
    root["buffers"] = json!([{"byteLength": b.bin.len()}]);
    root["bufferViews"] = json!(b.views);
    root["accessors"] = json!(b.accessors);
    Ok(ExportedGltf { json: root, bin: b.bin })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::md2::{Md2Clip, Md2Frame, Md2Model, Md2Skin};

    /// One triangle, one frame.
    fn triangle_model() -> Md2Model {
        Md2Model {
            skin_width: 2,
            skin_height: 2,
            skin_names: Vec::new(),
            vertex_xyz: vec![0, 1, 2],
            texcoords: vec![Vec2::ZERO, Vec2::X, Vec2::Y],
            indices: vec![0, 1, 2],
            frames: vec![Md2Frame {
                name: "stand1".into(),
                positions: vec![Vec3::ZERO, Vec3::X, Vec3::Y],
                normal_indices: vec![0, 0, 0],
            }],
            clips: vec![Md2Clip { name: "stand".into(), frames: 0..1 }],
            skin: None,
        }
    }

    fn export_object(model: &Md2Model, clip: Option<&str>) -> Result<Document, MeshFileError> {
        let mut doc = Document::default();
        doc.nodes.push(json!({"name": "model"}));
        md2_object(&mut doc, &Scene::default(), model, Path::new("model.md2"), clip, 10.0, 0, "model")?;
        Ok(doc)
    }

    /// `Md2Model`'s fields are public, so a model built or changed in memory can disagree with
    /// itself; exporting it is refused with the reason, never a panic or a broken file.
    #[test]
    fn an_md2_model_that_disagrees_with_itself_is_refused() {
        let model = triangle_model();
        let doc = export_object(&model, Some("stand")).expect("a consistent model exports");
        assert_eq!(doc.meshes.len(), 1);

        let clip_past_the_frames =
            Md2Model { clips: vec![Md2Clip { name: "run".into(), frames: 0..3 }], ..model.clone() };
        match export_object(&clip_past_the_frames, Some("run")) {
            Err(e @ MeshFileError::FrameMissing(1)) => assert_eq!(e.to_string(), "frame 1 is missing"),
            other => panic!("expected frame 1 missing, got {:?}", other.map(|_| ())),
        }
        let clip_of_no_frame =
            Md2Model { clips: vec![Md2Clip { name: "run".into(), frames: 5..6 }], ..model.clone() };
        assert!(matches!(export_object(&clip_of_no_frame, Some("run")), Err(MeshFileError::FrameMissing(5))));

        let short_skin = Md2Skin { path: "model.png".into(), width: 2, height: 2, rgba: vec![255; 15] };
        let skin_of_wrong_size = Md2Model { skin: Some(short_skin), ..model.clone() };
        match export_object(&skin_of_wrong_size, None) {
            Err(e @ MeshFileError::SkinSize) => {
                assert_eq!(e.to_string(), "skin image size does not match its pixels");
            }
            other => panic!("expected a skin size error, got {:?}", other.map(|_| ())),
        }
        let whole_skin = Md2Skin { path: "model.png".into(), width: 2, height: 2, rgba: vec![255; 16] };
        let doc = export_object(&Md2Model { skin: Some(whole_skin), ..model }, None).expect("a 2×2 skin");
        assert_eq!(doc.textures.len(), 1);
    }
}
