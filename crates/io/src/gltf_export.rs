//! glTF 2.0 export of a keyrig [`Scene`]: meshes, skeletons and skins, object, joint and
//! light animation, KHR_lights_punctual lights; as .glb or as .gltf with the buffer
//! embedded as a `data:` URI.
//!
//! Mapping (DESIGN.md §3, §8):
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
//! - light colour and intensity are written at the start of the frame range (core glTF
//!   cannot animate them).

use std::path::{Path, PathBuf};

use glam::{Affine3A, Mat4, Quat, Vec3};
use keyrig_core::{Animated, AnimatedTrack, Interpolation, LightKind, MeshSource, Scene, Track};
use serde_json::{json, Value};

use crate::model::{ImportedModel, PrimitiveMode};

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
}

impl Default for ExportOptions {
    fn default() -> Self {
        ExportOptions { rotation_tolerance_deg: 0.05, base_dir: None }
    }
}

/// Why a scene cannot be exported; `path` names the scene field, as in `keyrig info`.
#[derive(Debug, thiserror::Error)]
pub enum ExportError {
    #[error("{path}: {message}")]
    Scene { path: String, message: String },
    #[error("{path}: cannot load mesh file {file}: {message}")]
    MeshFile { path: String, file: PathBuf, message: String },
    #[error("{path}: cannot write: {source}")]
    Write { path: PathBuf, source: std::io::Error },
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
    width: usize,
}

/// Geometry of one exported mesh.
struct MeshData {
    positions: Vec<Vec3>,
    normals: Option<Vec<Vec3>>,
    indices: Vec<u32>,
    skin: Option<Influences>,
}

/// JOINTS_0 and WEIGHTS_0 of a mesh.
type Influences = (Vec<[u16; 4]>, Vec<[f32; 4]>);

/// Exports `scene`.
///
/// # Errors
/// A track that does not validate, a skeleton that does not fit its mesh, a mesh file that
/// cannot be loaded: each with the path of the scene field.
pub fn export_scene(scene: &Scene, options: &ExportOptions) -> Result<ExportedGltf, ExportError> {
    let mut b = Builder::default();
    let mut nodes: Vec<Value> = Vec::new();
    let mut roots: Vec<usize> = Vec::new();
    let mut meshes: Vec<Value> = Vec::new();
    let mut skins: Vec<Value> = Vec::new();
    let mut channels: Vec<Channel> = Vec::new();
    let mut lights: Vec<Value> = Vec::new();
    let tol = options.rotation_tolerance_deg.to_radians();

    for (oi, object) in scene.objects.iter().enumerate() {
        let here = format!("objects[{oi}]");
        let node = nodes.len();
        nodes.push(json!({"name": object.name}));
        roots.push(node);
        set_vec3(
            &mut nodes[node],
            "translation",
            &object.translation,
            Vec3::ZERO,
            &format!("{here}.translation"),
        )?;
        set_vec3(&mut nodes[node], "scale", &object.scale, Vec3::ONE, &format!("{here}.scale"))?;
        set_quat(&mut nodes[node], &object.rotation, Quat::IDENTITY, &format!("{here}.rotation"))?;
        channels.extend(vec3_channel(
            node,
            "translation",
            &object.translation,
            &format!("{here}.translation"),
        )?);
        channels.extend(vec3_channel(node, "scale", &object.scale, &format!("{here}.scale"))?);
        channels.extend(quat_channel(
            node,
            &object.rotation,
            Quat::IDENTITY,
            tol,
            &format!("{here}.rotation"),
        )?);

        // Joints as children of the object node.
        let mut joint_nodes = Vec::new();
        if let Some(skeleton) = &object.skeleton {
            for (ji, joint) in skeleton.joints.iter().enumerate() {
                let jhere = format!("{here}.skeleton.joints[{ji}]");
                let jn = nodes.len();
                let parent = match joint.parent {
                    None => node,
                    Some(p) if p < ji => joint_nodes[p],
                    Some(p) => {
                        return Err(scene_err(
                            format!("{jhere}.parent"),
                            format!("parent {p} is not before the joint"),
                        ))
                    }
                };
                add_child(&mut nodes[parent], jn);
                let rest_rotation = joint.rest_rotation.normalize();
                if !joint.rest_translation.is_finite() || !rest_rotation.is_finite() {
                    return Err(scene_err(&jhere, "rest transform is not finite"));
                }
                let rotation_at_rest =
                    rest_rotation * sample_static(&joint.rotation, &format!("{jhere}.rotation"))?;
                nodes.push(json!({
                    "name": joint.name,
                    "translation": joint.rest_translation.to_array(),
                    "rotation": rotation_at_rest.to_array(),
                }));
                joint_nodes.push(jn);
                channels.extend(quat_channel(
                    jn,
                    &joint.rotation,
                    rest_rotation,
                    tol,
                    &format!("{jhere}.rotation"),
                )?);
                if joint.parent.is_none() {
                    let rt = &skeleton.root_translation;
                    let offset = Animated {
                        value: joint.rest_translation + rt.value,
                        track: keyrig_core::RawTrack::new(
                            rt.track
                                .keys
                                .iter()
                                .map(|k| {
                                    let mut k = k.clone();
                                    k.value += joint.rest_translation;
                                    k
                                })
                                .collect(),
                        ),
                    };
                    if !rt.track.is_empty() || rt.value != Vec3::ZERO {
                        nodes[jn]["translation"] = json!(offset.value.to_array());
                    }
                    channels.extend(vec3_channel(
                        jn,
                        "translation",
                        &offset,
                        &format!("{here}.skeleton.root_translation"),
                    )?);
                }
            }
        }

        // The mesh.
        if let Some(source) = &object.mesh {
            let data = mesh_data(source, object.skeleton.as_ref(), options, &here)?;
            let mesh_index = meshes.len();
            let mut attributes = serde_json::Map::new();
            attributes.insert("POSITION".into(), json!(b.vec3s(&data.positions, Some(ARRAY_BUFFER), true)));
            if let Some(n) = &data.normals {
                let n: Vec<Vec3> = n.iter().map(|v| v.normalize_or(Vec3::Z)).collect();
                attributes.insert("NORMAL".into(), json!(b.vec3s(&n, Some(ARRAY_BUFFER), false)));
            }
            let skinned = match (&data.skin, &object.skeleton) {
                (Some((joints, weights)), Some(skeleton)) if !skeleton.joints.is_empty() => {
                    if let Some(bad) =
                        joints.iter().flatten().find(|&&j| usize::from(j) >= skeleton.joints.len())
                    {
                        return Err(scene_err(
                            format!("{here}.skeleton"),
                            format!(
                                "the mesh uses joint {bad} but the skeleton has {}",
                                skeleton.joints.len()
                            ),
                        ));
                    }
                    // glTF: a joint with zero weight should be joint 0 (the validator warns
                    // ACCESSOR_JOINTS_USED_ZERO_WEIGHT otherwise); it has no effect either way.
                    let joints: Vec<[u16; 4]> = joints
                        .iter()
                        .zip(weights)
                        .map(|(j, w)| std::array::from_fn(|i| if w[i] == 0.0 { 0 } else { j[i] }))
                        .collect();
                    attributes.insert("JOINTS_0".into(), json!(b.joints(&joints)));
                    let w: Vec<f32> = weights.iter().flatten().copied().collect();
                    attributes.insert(
                        "WEIGHTS_0".into(),
                        json!(b.floats(&w, 4, "VEC4", Some(ARRAY_BUFFER), false)),
                    );
                    Some(skeleton)
                }
                _ => None,
            };
            let indices = b.indices(&data.indices);
            meshes.push(json!({
                "name": object.name,
                "primitives": [{"attributes": attributes, "indices": indices, "mode": 4}],
            }));
            match skinned {
                Some(skeleton) => {
                    let ibms = inverse_bind_matrices(skeleton, &here)?;
                    let flat: Vec<f32> = ibms.iter().flat_map(|m| m.to_cols_array()).collect();
                    let acc = b.floats(&flat, 16, "MAT4", None, false);
                    let skin = skins.len();
                    skins.push(json!({"name": object.name, "joints": joint_nodes, "inverseBindMatrices": acc, "skeleton": joint_nodes[0]}));
                    let mesh_node = nodes.len();
                    nodes.push(
                        json!({"name": format!("{}.mesh", object.name), "mesh": mesh_index, "skin": skin}),
                    );
                    roots.push(mesh_node);
                }
                None => nodes[node]["mesh"] = json!(mesh_index),
            }
        }
    }

    for (li, light) in scene.lights.iter().enumerate() {
        let here = format!("lights[{li}]");
        let t0 = f64::from(scene.frame_range.start) / scene.fps;
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
        let light_index = lights.len();
        lights.push(l);
        let node = nodes.len();
        nodes
            .push(json!({"name": light.name, "extensions": {"KHR_lights_punctual": {"light": light_index}}}));
        roots.push(node);
        set_vec3(&mut nodes[node], "translation", &light.position, Vec3::ZERO, &format!("{here}.position"))?;
        channels.extend(vec3_channel(node, "translation", &light.position, &format!("{here}.position"))?);
        // Direction → rotation taking the light's −Z to the direction.
        let dir_here = format!("{here}.direction");
        let dir = AnimatedTrack::new(&light.direction).map_err(|e| scene_err(&dir_here, e.to_string()))?;
        let rest = look_rotation(dir.sample(t0));
        nodes[node]["rotation"] = json!(rest.to_array());
        if let Some(track) = dir.track() {
            let (start, end) = track.domain();
            let sampler = |t: f64| look_rotation(track.sample(t));
            let (times, values) = resample_rotation(&sampler, &[start, end], tol);
            channels.push(linear_quat_channel(node, times, values));
        }
    }

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
    if !lights.is_empty() {
        root["extensionsUsed"] = json!(["KHR_lights_punctual"]);
        root["extensions"] = json!({"KHR_lights_punctual": {"lights": lights}});
    }
    if !channels.is_empty() {
        let mut samplers = Vec::new();
        let mut chans = Vec::new();
        for (i, c) in channels.iter().enumerate() {
            let input = b.floats(&c.times, 1, "SCALAR", None, true);
            let type_ = if c.width == 3 { "VEC3" } else { "VEC4" };
            let output = b.floats(&c.values, c.width, type_, None, false);
            samplers.push(json!({"input": input, "output": output, "interpolation": c.interpolation}));
            chans.push(json!({"sampler": i, "target": {"node": c.node, "path": c.path}}));
        }
        root["animations"] = json!([{"name": "keyrig", "channels": chans, "samplers": samplers}]);
    }
    while !b.bin.len().is_multiple_of(4) {
        b.bin.push(0);
    }
    if !b.bin.is_empty() {
        root["buffers"] = json!([{"byteLength": b.bin.len()}]);
        root["bufferViews"] = json!(b.views);
        root["accessors"] = json!(b.accessors);
    }
    Ok(ExportedGltf { json: root, bin: b.bin })
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

fn set_vec3(
    node: &mut Value,
    field: &str,
    a: &Animated<Vec3>,
    default: Vec3,
    here: &str,
) -> Result<(), ExportError> {
    let v = sample_static(a, here)?;
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

/// A translation/scale channel: exact (STEP, LINEAR or CUBICSPLINE with the track's tangents).
fn vec3_channel(
    node: usize,
    path: &'static str,
    a: &Animated<Vec3>,
    here: &str,
) -> Result<Option<Channel>, ExportError> {
    if a.track.is_empty() {
        return Ok(None);
    }
    let track = Track::new(&a.track).map_err(|e| scene_err(format!("{here}.track"), e.to_string()))?;
    Ok(Some(cubic_or_simple_channel(node, path, &track)))
}

fn cubic_or_simple_channel(node: usize, path: &'static str, track: &Track<Vec3>) -> Channel {
    let times = track.key_times();
    let values = track.key_values();
    let n = times.len();
    let modes: Vec<Interpolation> = (0..n - 1).filter_map(|i| track.segment_interpolation(i)).collect();
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
        let step_next = k + 1 < n && track.segment_interpolation(k) == Some(Interpolation::Step);
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

/// A rotation channel of `rest · T(t)`: key for key when every segment is Linear (or Step),
/// else resampled within `tol` radians.
fn quat_channel(
    node: usize,
    a: &Animated<Quat>,
    rest: Quat,
    tol: f64,
    here: &str,
) -> Result<Option<Channel>, ExportError> {
    if a.track.is_empty() {
        return Ok(None);
    }
    let track = Track::new(&a.track).map_err(|e| scene_err(format!("{here}.track"), e.to_string()))?;
    let times = track.key_times();
    let modes: Vec<Interpolation> =
        (0..times.len() - 1).filter_map(|i| track.segment_interpolation(i)).collect();
    let values: Vec<Quat> = track.key_values().iter().map(|q| (rest * *q).normalize()).collect();
    let spin = track.has_spin();
    if modes.iter().all(|&m| m == Interpolation::Step)
        || (!spin && modes.iter().all(|&m| m == Interpolation::Linear))
    {
        let interpolation = if modes.iter().all(|&m| m == Interpolation::Linear) && !modes.is_empty() {
            "LINEAR"
        } else {
            "STEP"
        };
        return Ok(Some(Channel {
            node,
            path: "rotation",
            interpolation,
            times: times.iter().map(|&t| t as f32).collect(),
            values: values.iter().flat_map(|q| q.to_array()).collect(),
            width: 4,
        }));
    }
    let sampler = |t: f64| (rest * track.sample(t)).normalize();
    let mut breaks: Vec<f64> = times.to_vec();
    // Step segments: hold, then jump just before the next key.
    for (i, m) in modes.iter().enumerate() {
        if *m == Interpolation::Step {
            breaks.push(times[i + 1] - STEP_JUMP.min((times[i + 1] - times[i]) / 2.0));
        }
    }
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
    let (t, v) = resample_rotation(&sampler, &breaks, tol);
    Ok(Some(linear_quat_channel(node, t, v)))
}

fn linear_quat_channel(node: usize, times: Vec<f64>, values: Vec<Quat>) -> Channel {
    // Keep consecutive keys sign-consistent so slerp takes the short way, as keyrig does.
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

/// Resamples `f` on `[breaks]` into LINEAR keys: each interval is halved until its end keys
/// are at most [`MAX_ROTATION_STEP_DEG`] apart and slerp between them stays within `tol / 2`
/// radians of `f` at 15 interior points.
fn resample_rotation(f: &dyn Fn(f64) -> Quat, breaks: &[f64], tol: f64) -> (Vec<f64>, Vec<Quat>) {
    let mut times = vec![breaks[0]];
    let mut values = vec![f(breaks[0])];
    for w in breaks.windows(2) {
        subdivide(f, w[0], w[1], tol, &mut times, &mut values, 0);
    }
    (times, values)
}

fn subdivide(
    f: &dyn Fn(f64) -> Quat,
    t0: f64,
    t1: f64,
    tol: f64,
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
            let lin = crate::model::slerp_short(q0, q1, u as f32);
            rotation_angle(lin, f(t0 + u * (t1 - t0))) <= 0.5 * tol
        });
    if within || t1 - t0 < MIN_SEGMENT || depth > 24 {
        times.push(t1);
        values.push(q1);
    } else {
        let mid = 0.5 * (t0 + t1);
        subdivide(f, t0, mid, tol, times, values, depth + 1);
        subdivide(f, mid, t1, tol, times, values, depth + 1);
    }
}

/// A(j)⁻¹ for every joint: the inverse of the product of rest transforms down the chain.
fn inverse_bind_matrices(skeleton: &keyrig_core::Skeleton, here: &str) -> Result<Vec<Mat4>, ExportError> {
    let mut model_from_joint: Vec<Affine3A> = Vec::with_capacity(skeleton.joints.len());
    for (j, joint) in skeleton.joints.iter().enumerate() {
        let local =
            Affine3A::from_rotation_translation(joint.rest_rotation.normalize(), joint.rest_translation);
        let a = match joint.parent {
            Some(p) if p < j => model_from_joint[p] * local,
            Some(p) => {
                return Err(scene_err(
                    format!("{here}.skeleton.joints[{j}].parent"),
                    format!("parent {p} is not before the joint"),
                ))
            }
            None => local,
        };
        model_from_joint.push(a);
    }
    Ok(model_from_joint.iter().map(|a| Mat4::from(a.inverse())).collect())
}

/// The geometry of an object's mesh: procedural meshes from keyrig-skin (with their
/// weights), glTF files (first mesh or the chosen one; static, no skin) and MD2 files
/// (first frame).
fn mesh_data(
    source: &MeshSource,
    skeleton: Option<&keyrig_core::Skeleton>,
    options: &ExportOptions,
    here: &str,
) -> Result<MeshData, ExportError> {
    match source {
        MeshSource::Procedural(kind) => {
            let mut mesh = keyrig_skin::mesh_for(*kind);
            // Procedural meshes are built in centimetres on their own skeleton; fit them to the
            // object's skeleton as the editor and renderer do. A skeleton that does not build is
            // reported by the skeleton's own export; the mesh then keeps its native size.
            if let Some(rest) = skeleton.and_then(|s| keyrig_skin::RestSkeleton::from_scene(s).ok()) {
                if let Ok(fitted) = mesh.clone().fit_to_skeleton(rest) {
                    mesh = fitted;
                }
            }
            Ok(MeshData {
                positions: mesh.positions,
                normals: Some(mesh.normals),
                indices: mesh.indices,
                skin: Some((mesh.joints, mesh.weights)),
            })
        }
        MeshSource::File { path, mesh, .. } => {
            let file = options.base_dir.as_deref().unwrap_or(Path::new(".")).join(path);
            let err = |message: String| ExportError::MeshFile {
                path: format!("{here}.mesh"),
                file: file.clone(),
                message,
            };
            let is_md2 =
                file.extension().and_then(|e| e.to_str()).is_some_and(|e| e.eq_ignore_ascii_case("md2"));
            if is_md2 {
                let model = crate::md2::load_md2_file(&file).map_err(|e| err(e.to_string()))?;
                let pose = model.frame_pose(0).ok_or_else(|| err("no frames".into()))?;
                return Ok(MeshData {
                    positions: pose.positions,
                    normals: Some(pose.normals),
                    indices: model.indices,
                    skin: None,
                });
            }
            let model = crate::gltf_import::import_gltf_file(&file).map_err(|e| err(e.to_string()))?;
            static_mesh(&model, mesh.unwrap_or(0))
                .ok_or_else(|| err(format!("has no triangle mesh {}", mesh.unwrap_or(0))))
        }
    }
}

/// Sum of the rest offsets of non-root joints: the skeleton's "length".
/// All triangle primitives of mesh `index` merged into one (no skin).
fn static_mesh(model: &ImportedModel, index: usize) -> Option<MeshData> {
    let mesh = model.meshes.get(index)?;
    let mut data =
        MeshData { positions: Vec::new(), normals: Some(Vec::new()), indices: Vec::new(), skin: None };
    for p in mesh.primitives.iter().filter(|p| p.mode == PrimitiveMode::Triangles) {
        let base = data.positions.len() as u32;
        data.positions.extend_from_slice(&p.positions);
        match (&mut data.normals, &p.normals) {
            (Some(n), Some(pn)) => n.extend_from_slice(pn),
            (n, _) => *n = None,
        }
        data.indices.extend(p.indices.iter().map(|i| i + base));
    }
    (!data.positions.is_empty()).then_some(data)
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
