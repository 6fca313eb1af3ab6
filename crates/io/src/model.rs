//! An imported glTF model, kept whole: what the keyrig scene can hold and what it cannot
//! (morph weights, several skins and animations). [`crate::gltf_import`] fills it; [`ImportedModel::to_scene`] maps what fits
//! onto a [`keyrig_core::Scene`].
//!
//! Keys keep the curve of the file exactly: glTF STEP → [`Interpolation::Step`], LINEAR →
//! [`Interpolation::Linear`] (slerp for rotations), CUBICSPLINE → [`Interpolation::Hermite`]
//! with the file's in-tangent `a_k` and out-tangent `b_k` stored per second in
//! [`Key::in_tangent`] / [`Key::out_tangent`]. The sampler here evaluates them as the glTF
//! 2.0 specification (Appendix C) defines:
//! `p(t) = h00·v_k + h10·t_d·b_k + h01·v_{k+1} + h11·t_d·a_{k+1}`, `t_d = t_{k+1} − t_k`,
//! and cubic rotations are normalized after the component-wise Hermite.

use std::sync::Arc;

mod attributes;

use glam::{Mat4, Quat, Vec2, Vec3};
use keyrig_core::{Interpolation, Key, RawTrack};

/// A node of the glTF hierarchy with its rest (file) transform.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelNode {
    pub name: String,
    pub parent: Option<usize>,
    pub children: Vec<usize>,
    pub translation: Vec3,
    pub rotation: Quat,
    pub scale: Vec3,
    pub mesh: Option<usize>,
    pub skin: Option<usize>,
    pub light: Option<usize>,
    /// The camera this node holds (an index of [`ImportedModel::cameras`]).
    pub camera: Option<usize>,
    /// Morph-target weights of this node's mesh instance, when the node overrides them.
    pub weights: Option<Vec<f32>>,
    /// `KHR_node_visibility`: false hides the node and everything below it (true when the
    /// file does not say).
    pub visible: bool,
}

/// How a primitive's indices are to be read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PrimitiveMode {
    /// Triangle list (strips and fans are converted to lists on import).
    Triangles,
    Lines,
    Points,
}

/// One morph target: displacements added to the base attributes.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct MorphTarget {
    pub positions: Option<Arc<[Vec3]>>,
    pub normals: Option<Arc<[Vec3]>>,
}

/// A reference to the base-colour texture of a primitive's material.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureRef {
    pub texture: usize,
    pub image: usize,
    /// Which TEXCOORD_n set it uses.
    pub texcoord_set: u32,
    /// The texture's sampler (wrap modes and filters).
    pub sampler: keyrig_core::Sampler,
}

/// Where an image's bytes are.
#[derive(Clone, Debug, PartialEq)]
pub enum ImageSource {
    /// A URI relative to the glTF file (or a `data:` URI).
    Uri(String),
    /// A buffer view of the file, with its MIME type.
    BufferView { view: usize, mime_type: String },
}

/// The bytes of an image the file holds or references, as stored (PNG or JPEG; not decoded).
#[derive(Clone, Debug, PartialEq)]
pub struct ImageData {
    pub bytes: Arc<[u8]>,
    /// `image/png` or `image/jpeg` (from the file, a `data:` URI or the file name).
    pub mime_type: String,
}

/// One primitive of a mesh, attributes in accessor order.
///
/// Attribute and index arrays are shared (`Arc`): the importer decodes each accessor once,
/// and primitives that use the same accessor hold the same array.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelPrimitive {
    pub mode: PrimitiveMode,
    pub positions: Arc<[Vec3]>,
    pub normals: Option<Arc<[Vec3]>>,
    /// TEXCOORD_0.
    pub texcoords: Option<Arc<[Vec2]>>,
    /// Vertex indices (generated 0..n when the file has none; strips/fans as lists).
    pub indices: Arc<[u32]>,
    /// JOINTS_0, JOINTS_1, …: per vertex four indices into the skin's joint list.
    pub joint_sets: Vec<Arc<[[u16; 4]]>>,
    /// WEIGHTS_0, WEIGHTS_1, …: per vertex four weights, as stored (not renormalized).
    pub weight_sets: Vec<Arc<[[f32; 4]]>>,
    pub morph_targets: Vec<MorphTarget>,
    pub base_colour_factor: [f32; 4],
    pub base_colour_texture: Option<TextureRef>,
    /// Index of the glTF material (`None`: the default material).
    pub material: Option<usize>,
}

/// A mesh: primitives and default morph weights.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelMesh {
    pub name: String,
    /// Shared by meshes whose primitives the file writes identically.
    pub primitives: Arc<Vec<ModelPrimitive>>,
    pub weights: Vec<f32>,
}

/// A skin: joints (node indices) and their inverse bind matrices (identity when absent).
#[derive(Clone, Debug, PartialEq)]
pub struct ModelSkin {
    pub name: String,
    pub joints: Vec<usize>,
    pub inverse_bind_matrices: Vec<Mat4>,
    pub skeleton: Option<usize>,
    /// The deformer the file asks for (FBX's skinning method); `None`: the scene's default
    /// (glTF skins are linear blend).
    pub deformer: Option<keyrig_core::DeformerKind>,
}

/// A KHR_lights_punctual light.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelLight {
    pub name: String,
    pub kind: ModelLightKind,
    pub colour: Vec3,
    pub intensity: f32,
    pub range: Option<f32>,
}

#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ModelLightKind {
    Directional,
    Point,
    /// Cone angles in radians from the light's −Z axis.
    Spot {
        inner_cone_angle: f32,
        outer_cone_angle: f32,
    },
}

/// Morph-target weight keys: each key holds one weight per target.
#[derive(Clone, Debug, PartialEq)]
pub struct WeightsTrack {
    pub targets: usize,
    pub keys: Vec<Key<Vec<f32>>>,
}

/// What an animation channel drives.
#[derive(Clone, Debug, PartialEq)]
pub enum ChannelTarget {
    Translation(RawTrack<Vec3>),
    Rotation(RawTrack<Quat>),
    Scale(RawTrack<Vec3>),
    Weights(WeightsTrack),
}

/// One animated property of one node.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelChannel {
    pub node: usize,
    pub target: ChannelTarget,
}

#[derive(Clone, Debug, PartialEq)]
pub struct ModelAnimation {
    pub name: String,
    pub channels: Vec<ModelChannel>,
    /// `KHR_animation_pointer` channels on properties other than a node's transform and
    /// weights (those are read into `channels`), and `KHR_node_visibility`.
    pub pointers: Vec<crate::gltf_pointer::PointerChannel>,
}

impl ModelAnimation {
    /// The last key time of any channel (0 when there are none).
    #[must_use]
    pub fn duration(&self) -> f64 {
        self.channels
            .iter()
            .filter_map(|c| match &c.target {
                ChannelTarget::Translation(t) | ChannelTarget::Scale(t) => t.keys.last().map(|k| k.time),
                ChannelTarget::Rotation(t) => t.keys.last().map(|k| k.time),
                ChannelTarget::Weights(w) => w.keys.last().map(|k| k.time),
            })
            .chain(self.pointers.iter().filter_map(|p| p.keys.last_time()))
            .fold(0.0, f64::max)
    }
}

/// A whole imported glTF file.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct ImportedModel {
    pub nodes: Vec<ModelNode>,
    /// Root nodes of the displayed scene (the default scene, else every parentless node).
    pub roots: Vec<usize>,
    pub meshes: Vec<ModelMesh>,
    pub skins: Vec<ModelSkin>,
    pub animations: Vec<ModelAnimation>,
    pub lights: Vec<ModelLight>,
    /// The file's cameras.
    pub cameras: Vec<ModelCamera>,
    pub images: Vec<ImageSource>,
    /// The bytes of each image (same order as `images`) where they could be read: from a
    /// buffer view, a `data:` URI or a file next to the model. `None` for an image that
    /// cannot be read or whose type is neither PNG nor JPEG (export then leaves it out).
    pub image_data: Vec<Option<ImageData>>,
    /// Animation channels the import left out (unknown `KHR_animation_pointer` targets,
    /// channels without a target), each with why.
    pub skipped_channels: Vec<crate::gltf_pointer::SkippedChannel>,
}

/// Local transforms and morph weights of every node at one time.
#[derive(Clone, Debug, PartialEq)]
pub struct NodePose {
    pub translation: Vec<Vec3>,
    pub rotation: Vec<Quat>,
    pub scale: Vec<Vec3>,
    /// Morph weights per node (empty where the node has none).
    pub weights: Vec<Vec<f32>>,
}

impl NodePose {
    /// `parent_from_node` per node.
    #[must_use]
    pub fn local_matrices(&self) -> Vec<Mat4> {
        (0..self.translation.len())
            .map(|i| {
                Mat4::from_scale_rotation_translation(self.scale[i], self.rotation[i], self.translation[i])
            })
            .collect()
    }
}

impl ImportedModel {
    /// The rest pose: every node's file transform, the mesh's or node's default weights.
    #[must_use]
    pub fn rest_pose(&self) -> NodePose {
        NodePose {
            translation: self.nodes.iter().map(|n| n.translation).collect(),
            rotation: self.nodes.iter().map(|n| n.rotation).collect(),
            scale: self.nodes.iter().map(|n| n.scale).collect(),
            weights: self
                .nodes
                .iter()
                .map(|n| {
                    n.weights
                        .clone()
                        .or_else(|| n.mesh.and_then(|m| self.meshes.get(m)).map(|m| m.weights.clone()))
                        .unwrap_or_default()
                })
                .collect(),
        }
    }

    /// The pose at `time` seconds of animation `animation` (the rest pose for properties the
    /// animation does not drive). Times outside the keys hold the first or last value.
    #[must_use]
    pub fn pose_at(&self, animation: Option<usize>, time: f64) -> NodePose {
        let mut pose = self.rest_pose();
        let Some(anim) = animation.and_then(|a| self.animations.get(a)) else { return pose };
        for channel in &anim.channels {
            let n = channel.node;
            if n >= self.nodes.len() {
                continue;
            }
            match &channel.target {
                ChannelTarget::Translation(t) => {
                    if let Some(v) = sample_vec3(t, time) {
                        pose.translation[n] = v;
                    }
                }
                ChannelTarget::Scale(t) => {
                    if let Some(v) = sample_vec3(t, time) {
                        pose.scale[n] = v;
                    }
                }
                ChannelTarget::Rotation(t) => {
                    if let Some(q) = sample_quat(t, time) {
                        pose.rotation[n] = q;
                    }
                }
                ChannelTarget::Weights(w) => {
                    if let Some(v) = sample_weights(w, time) {
                        pose.weights[n] = v;
                    }
                }
            }
        }
        pose
    }

    /// `model_from_node` for every node: parents' matrices times the local one. The
    /// importer guarantees the hierarchy is a forest.
    #[must_use]
    pub fn world_matrices(&self, pose: &NodePose) -> Vec<Mat4> {
        let local = pose.local_matrices();
        let mut world: Vec<Option<Mat4>> = vec![None; self.nodes.len()];
        for start in 0..self.nodes.len() {
            // Walk up to the first node whose world matrix is known, then back down.
            let mut chain = Vec::new();
            let mut cur = Some(start);
            while let Some(c) = cur {
                if world[c].is_some() || chain.len() > self.nodes.len() {
                    break;
                }
                chain.push(c);
                cur = self.nodes[c].parent;
            }
            for &c in chain.iter().rev() {
                let parent = self.nodes[c].parent.and_then(|p| world[p]).unwrap_or(Mat4::IDENTITY);
                world[c] = Some(parent * local[c]);
            }
        }
        world.into_iter().map(|m| m.unwrap_or(Mat4::IDENTITY)).collect()
    }

    /// The joint matrices of skin `skin` as glTF defines them:
    /// `jointMatrix(j) = model_from_node(joint_j) · inverseBindMatrix(j)`. (The skinned mesh
    /// node's own transform is ignored, as the specification requires.)
    #[must_use]
    pub fn joint_matrices(&self, skin: usize, world: &[Mat4]) -> Vec<Mat4> {
        let Some(skin) = self.skins.get(skin) else { return Vec::new() };
        skin.joints
            .iter()
            .enumerate()
            .map(|(j, &node)| {
                world.get(node).copied().unwrap_or(Mat4::IDENTITY)
                    * skin.inverse_bind_matrices.get(j).copied().unwrap_or(Mat4::IDENTITY)
            })
            .collect()
    }

    /// Base positions of a primitive with morph targets applied: `p + Σ w_t · Δp_t`.
    #[must_use]
    pub fn morphed_positions(primitive: &ModelPrimitive, weights: &[f32]) -> Vec<Vec3> {
        let mut out = primitive.positions.to_vec();
        for (target, &w) in primitive.morph_targets.iter().zip(weights) {
            if let Some(d) = &target.positions {
                for (p, d) in out.iter_mut().zip(d.iter()) {
                    *p += w * *d;
                }
            }
        }
        out
    }

    /// Linear blend skinning exactly as glTF defines it:
    /// `v' = Σ_sets Σ_i weight_i · jointMatrix(joint_i) · v`, weights as stored, in
    /// accessor order. Vertices with no weight at all stay where they are.
    #[must_use]
    pub fn linear_blend(
        primitive: &ModelPrimitive,
        positions: &[Vec3],
        joint_matrices: &[Mat4],
    ) -> Vec<Vec3> {
        positions
            .iter()
            .enumerate()
            .map(|(v, &p)| {
                let mut sum = Vec3::ZERO;
                let mut weighted = false;
                for (joints, weights) in primitive.joint_sets.iter().zip(&primitive.weight_sets) {
                    for i in 0..4 {
                        let w = weights[v][i];
                        if w != 0.0 {
                            let m = joint_matrices
                                .get(usize::from(joints[v][i]))
                                .copied()
                                .unwrap_or(Mat4::IDENTITY);
                            sum += w * m.transform_point3(p);
                            weighted = true;
                        }
                    }
                }
                if !weighted {
                    p
                } else {
                    sum
                }
            })
            .collect()
    }

    /// Positions of every primitive of the mesh on `node` at `time` of `animation`, in the
    /// file's axes: morphed, then skinned by linear blend when the node has a skin, else
    /// transformed by the node's world matrix. `None` when the node has no mesh.
    #[must_use]
    pub fn deformed_positions(
        &self,
        node: usize,
        animation: Option<usize>,
        time: f64,
    ) -> Option<Vec<Vec<Vec3>>> {
        let n = self.nodes.get(node)?;
        let mesh = self.meshes.get(n.mesh?)?;
        let pose = self.pose_at(animation, time);
        let world = self.world_matrices(&pose);
        let weights = &pose.weights[node];
        Some(
            mesh.primitives
                .iter()
                .map(|prim| {
                    let morphed = Self::morphed_positions(prim, weights);
                    match n.skin {
                        Some(skin) => Self::linear_blend(prim, &morphed, &self.joint_matrices(skin, &world)),
                        None => morphed.iter().map(|&p| world[node].transform_point3(p)).collect(),
                    }
                })
                .collect(),
        )
    }
}

/// The segment containing `time` and its parameter: (k, u, t_d). Before the first key or
/// after the last, `None` with the index of the key to hold.
fn locate<T>(keys: &[Key<T>], time: f64) -> Result<(usize, f32, f32), usize> {
    let last = keys.len() - 1;
    if keys.len() == 1 || time <= keys[0].time {
        return Err(0);
    }
    if time >= keys[last].time {
        return Err(last);
    }
    // First key with a time greater than `time`; keys are strictly increasing.
    let next = keys.partition_point(|k| k.time <= time);
    let k = next - 1;
    let td = keys[next].time - keys[k].time;
    Ok((k, ((time - keys[k].time) / td) as f32, td as f32))
}

/// Hermite basis (h00, h10, h01, h11) at u.
fn hermite_basis(u: f32) -> [f32; 4] {
    let (u2, u3) = (u * u, u * u * u);
    [2.0 * u3 - 3.0 * u2 + 1.0, u3 - 2.0 * u2 + u, -2.0 * u3 + 3.0 * u2, u3 - u2]
}

/// Samples a translation or scale track as glTF does. `None` for an empty track.
#[must_use]
pub fn sample_vec3(track: &RawTrack<Vec3>, time: f64) -> Option<Vec3> {
    let keys = &track.keys;
    if keys.is_empty() {
        return None;
    }
    Some(match locate(keys, time) {
        Err(i) => keys[i].value,
        Ok((k, u, td)) => {
            let (a, b) = (&keys[k], &keys[k + 1]);
            match a.interpolation {
                Interpolation::Step => a.value,
                Interpolation::Hermite => {
                    let [h00, h10, h01, h11] = hermite_basis(u);
                    h00 * a.value
                        + h10 * td * a.out_tangent.unwrap_or(Vec3::ZERO)
                        + h01 * b.value
                        + h11 * td * b.in_tangent.unwrap_or(Vec3::ZERO)
                }
                Interpolation::Linear | Interpolation::Tcb => a.value.lerp(b.value, u),
            }
        }
    })
}

/// Samples a rotation track as glTF does: slerp (shortest path) for LINEAR, component-wise
/// Hermite then normalize for CUBICSPLINE. `None` for an empty track.
#[must_use]
pub fn sample_quat(track: &RawTrack<Quat>, time: f64) -> Option<Quat> {
    let keys = &track.keys;
    if keys.is_empty() {
        return None;
    }
    Some(match locate(keys, time) {
        Err(i) => keys[i].value,
        Ok((k, u, td)) => {
            let (a, b) = (&keys[k], &keys[k + 1]);
            match a.interpolation {
                Interpolation::Step => a.value,
                Interpolation::Hermite => {
                    let [h00, h10, h01, h11] = hermite_basis(u);
                    let v = h00 * glam::Vec4::from(a.value)
                        + h10
                            * td
                            * glam::Vec4::from(a.out_tangent.unwrap_or(Quat::from_xyzw(0.0, 0.0, 0.0, 0.0)))
                        + h01 * glam::Vec4::from(b.value)
                        + h11
                            * td
                            * glam::Vec4::from(b.in_tangent.unwrap_or(Quat::from_xyzw(0.0, 0.0, 0.0, 0.0)));
                    Quat::from_vec4(v.normalize_or(glam::Vec4::from(a.value)))
                }
                Interpolation::Linear | Interpolation::Tcb => slerp_short(a.value, b.value, u),
            }
        }
    })
}

/// Slerp the short way with a normalized-lerp fallback near parallel inputs.
#[must_use]
pub fn slerp_short(a: Quat, b: Quat, u: f32) -> Quat {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    let dot = a.dot(b).min(1.0);
    if dot > 0.9995 {
        return Quat::from_vec4(glam::Vec4::from(a).lerp(glam::Vec4::from(b), u)).normalize();
    }
    let theta = dot.acos();
    let s = theta.sin();
    let wa = ((1.0 - u) * theta).sin() / s;
    let wb = (u * theta).sin() / s;
    Quat::from_vec4(glam::Vec4::from(a) * wa + glam::Vec4::from(b) * wb).normalize()
}

/// Samples morph weights as glTF does. `None` for an empty track.
#[must_use]
pub fn sample_weights(track: &WeightsTrack, time: f64) -> Option<Vec<f32>> {
    let keys = &track.keys;
    if keys.is_empty() {
        return None;
    }
    Some(match locate(keys, time) {
        Err(i) => keys[i].value.clone(),
        Ok((k, u, td)) => {
            let (a, b) = (&keys[k], &keys[k + 1]);
            match a.interpolation {
                Interpolation::Step => a.value.clone(),
                Interpolation::Hermite => {
                    let [h00, h10, h01, h11] = hermite_basis(u);
                    let zero = vec![0.0; track.targets];
                    let (out_t, in_t) =
                        (a.out_tangent.as_ref().unwrap_or(&zero), b.in_tangent.as_ref().unwrap_or(&zero));
                    (0..track.targets)
                        .map(|i| {
                            h00 * a.value[i] + h10 * td * out_t[i] + h01 * b.value[i] + h11 * td * in_t[i]
                        })
                        .collect()
                }
                Interpolation::Linear | Interpolation::Tcb => {
                    a.value.iter().zip(&b.value).map(|(x, y)| x + (y - x) * u).collect()
                }
            }
        }
    })
}

/// A base-colour texture that cannot be drawn ([`ImportedModel::material`]), with the
/// material to draw instead (its colour factor, no texture).
#[derive(Debug, Clone, thiserror::Error)]
#[error("image {image}: {message}")]
pub struct MaterialError {
    pub image: usize,
    pub message: String,
    material: keyrig_core::Material,
}

impl MaterialError {
    /// The material without its texture.
    #[must_use]
    pub fn without_texture(self) -> keyrig_core::Material {
        self.material
    }
}

/// Why an imported model cannot be mapped onto keyrig's scene or skin types.
#[derive(Debug, thiserror::Error)]
pub enum MappingError {
    #[error("node {node}: {message}")]
    Node { node: usize, message: String },
    #[error("skin {skin}: {source}")]
    Skin { skin: usize, source: keyrig_skin::SkinError },
    #[error("mesh {mesh}: {message}")]
    Mesh { mesh: usize, message: String },
    /// Something a scene built from the model needs is not in it (an animation by name).
    #[error("{0}")]
    Missing(String),
}

/// Triangle primitives merged into one vertex list, as a keyrig-skin mesh takes them: positions,
/// normals (computed from the triangles where a primitive has none), TEXCOORD_0 ((0, 0) for the
/// vertices of primitives without one, non-finite ones zeroed) and indices renumbered.
#[derive(Default)]
struct MergedTriangles {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    indices: Vec<u32>,
    uvs: Vec<Vec2>,
    has_uvs: bool,
}

impl MergedTriangles {
    fn push(&mut self, prim: &ModelPrimitive) {
        let base = self.positions.len() as u32;
        self.positions.extend_from_slice(&prim.positions);
        match &prim.texcoords {
            Some(t) if t.len() == prim.positions.len() => {
                self.has_uvs = true;
                self.uvs.extend(t.iter().map(|uv| if uv.is_finite() { *uv } else { Vec2::ZERO }));
            }
            _ => self.uvs.resize(self.positions.len(), Vec2::ZERO),
        }
        match &prim.normals {
            Some(n) => self.normals.extend_from_slice(n),
            None => self.normals.extend(keyrig_skin::mesh::vertex_normals(&prim.positions, &prim.indices)),
        }
        self.indices.extend(prim.indices.iter().map(|&i| base + i));
    }
}

/// The morph targets of `mesh`'s triangle primitives merged as [`MergedTriangles`] merges
/// their vertices: target i of each primitive (zero displacements where a primitive has fewer
/// targets or no positions in it); normal displacements where any primitive has them.
fn merged_morph_targets(mesh: &ModelMesh) -> Vec<keyrig_skin::MorphTarget> {
    let prims: Vec<&ModelPrimitive> =
        mesh.primitives.iter().filter(|p| p.mode == PrimitiveMode::Triangles).collect();
    let count = prims.iter().map(|p| p.morph_targets.len()).max().unwrap_or(0);
    (0..count)
        .map(|t| {
            let any_normals =
                prims.iter().any(|p| p.morph_targets.get(t).is_some_and(|m| m.normals.is_some()));
            let mut positions = Vec::new();
            let mut normals = Vec::new();
            for p in &prims {
                let n = p.positions.len();
                let target = p.morph_targets.get(t);
                match target.and_then(|m| m.positions.as_ref()).filter(|d| d.len() == n) {
                    Some(d) => positions.extend_from_slice(d),
                    None => positions.resize(positions.len() + n, Vec3::ZERO),
                }
                if any_normals {
                    match target.and_then(|m| m.normals.as_ref()).filter(|d| d.len() == n) {
                        Some(d) => normals.extend_from_slice(d),
                        None => normals.resize(normals.len() + n, Vec3::ZERO),
                    }
                }
            }
            keyrig_skin::MorphTarget { positions, normals }
        })
        .collect()
}

/// How a skin maps onto a keyrig skeleton: the skin's joints and every ancestor node of them
/// up to the scene root, parents first, so that the keyrig skeleton's F(j) is exactly the
/// file's global transform of joint j's node (docs/design.md §4; glTF 2.0 §3.7.3). When the nodes
/// have several scene roots, a synthetic identity root joint holds them together.
struct SkeletonMap {
    /// glTF node of keyrig joint k (`None` for the synthetic root).
    nodes: Vec<Option<usize>>,
    /// Index in the glTF skin's joint list of keyrig joint k, for the skin's own joints.
    skin_slot: Vec<Option<usize>>,
    parents: Vec<Option<usize>>,
}

/// The name of the synthetic root joint of a skin whose joints hang under several scene roots.
pub const SYNTHETIC_ROOT_NAME: &str = "(root)";

impl ImportedModel {
    /// `model_from_node` at rest for every node.
    fn rest_world(&self) -> Vec<Mat4> {
        self.world_matrices(&self.rest_pose())
    }

    fn skeleton_map(&self, skin: usize) -> Option<SkeletonMap> {
        let s = self.skins.get(skin)?;
        let count = self.nodes.len();
        // Every joint and its ancestors (the importer guarantees a forest; the walk up stops at
        // the first node already taken, so the whole pass is linear in the node count).
        let mut taken = vec![false; count];
        for &j in &s.joints {
            let mut cur = Some(j);
            let mut steps = 0;
            while let Some(n) = cur.filter(|&n| n < count && !taken[n]) {
                taken[n] = true;
                cur = self.nodes[n].parent;
                steps += 1;
                if steps > count {
                    break;
                }
            }
        }
        // Parents first: breadth-first from the scene roots, keeping the taken nodes.
        let mut order = Vec::new();
        let mut queue: std::collections::VecDeque<usize> =
            (0..count).filter(|&n| self.nodes[n].parent.is_none()).collect();
        while let Some(n) = queue.pop_front() {
            if !taken[n] {
                continue;
            }
            order.push(n);
            queue.extend(self.nodes[n].children.iter().copied().filter(|&c| c < count));
        }
        let roots = order.iter().filter(|&&n| self.nodes[n].parent.is_none()).count();
        let synthetic = roots > 1;
        let mut nodes: Vec<Option<usize>> = Vec::with_capacity(order.len() + usize::from(synthetic));
        if synthetic {
            nodes.push(None);
        }
        nodes.extend(order.iter().map(|&n| Some(n)));
        let mut keyrig_index = vec![usize::MAX; count];
        for (k, n) in nodes.iter().enumerate() {
            if let Some(n) = *n {
                keyrig_index[n] = k;
            }
        }
        let mut slot_of = vec![None; count];
        for (slot, &n) in s.joints.iter().enumerate() {
            if n < count && slot_of[n].is_none() {
                slot_of[n] = Some(slot);
            }
        }
        let parents = nodes
            .iter()
            .map(|n| match n {
                None => None,
                Some(n) => match self.nodes[*n].parent {
                    Some(p) => Some(keyrig_index[p]),
                    None if synthetic => Some(0),
                    None => None,
                },
            })
            .collect();
        let skin_slot = nodes.iter().map(|n| n.and_then(|n| slot_of[n])).collect();
        Some(SkeletonMap { nodes, skin_slot, parents })
    }

    /// The keyrig skeleton of skin `skin` with every channel of `animation` on its nodes: the
    /// skin's joints and their ancestors up to the scene root, parents first, named as the
    /// nodes. Each joint's rest R(j) is its node's rest translation and rotation; its local
    /// transform T(j) = translate(t′)·rotate(q′)·scale(s) with `t′ = q_rest⁻¹·(t − t_rest)`
    /// and `q′ = q_rest⁻¹·q`, so that R(j)·T(j) is the node's animated `T·R·S` exactly. Keys
    /// are mapped one to one with their interpolation (tangents through the same linear maps,
    /// which is exact for glTF's STEP, LINEAR and CUBICSPLINE): the skeleton's F(j) is the
    /// file's global transform of the node at every time.
    ///
    /// # Errors
    /// No such skin.
    pub fn scene_skeleton(
        &self,
        skin: usize,
        animation: Option<usize>,
    ) -> Result<keyrig_core::Skeleton, MappingError> {
        let map = self
            .skeleton_map(skin)
            .ok_or(MappingError::Node { node: usize::MAX, message: format!("no skin {skin}") })?;
        Ok(self.skeleton_from_map(&map, &self.channels_by_node(animation)))
    }

    /// The channels of `animation`, by the node they drive.
    fn channels_by_node(&self, animation: Option<usize>) -> Vec<Vec<&ChannelTarget>> {
        let mut channels_of: Vec<Vec<&ChannelTarget>> = vec![Vec::new(); self.nodes.len()];
        for channel in animation.and_then(|a| self.animations.get(a)).iter().flat_map(|a| &a.channels) {
            if let Some(list) = channels_of.get_mut(channel.node) {
                list.push(&channel.target);
            }
        }
        channels_of
    }

    /// See [`ImportedModel::scene_skeleton`].
    fn skeleton_from_map(
        &self,
        map: &SkeletonMap,
        channels_of: &[Vec<&ChannelTarget>],
    ) -> keyrig_core::Skeleton {
        let mut joints = Vec::with_capacity(map.nodes.len());
        for (k, n) in map.nodes.iter().enumerate() {
            let Some(n) = *n else {
                joints.push(keyrig_core::Joint::new(SYNTHETIC_ROOT_NAME, None, Vec3::ZERO, Quat::IDENTITY));
                continue;
            };
            let node = &self.nodes[n];
            let q_rest = node.rotation.normalize();
            let q_rest_inv = q_rest.inverse();
            let mut joint =
                keyrig_core::Joint::new(node.name.clone(), map.parents[k], node.translation, q_rest);
            joint.scale = keyrig_core::Animated::constant(node.scale);
            for target in &channels_of[n] {
                match target {
                    ChannelTarget::Rotation(track) => {
                        joint.rotation = animated(
                            joint.rotation,
                            track,
                            |q| (q_rest_inv * q).normalize(),
                            |t| q_rest_inv * t,
                        );
                    }
                    ChannelTarget::Translation(track) => {
                        let rest = node.translation;
                        joint.translation = animated(
                            joint.translation,
                            track,
                            |v| q_rest_inv * (v - rest),
                            |t| q_rest_inv * t,
                        );
                    }
                    ChannelTarget::Scale(track) => joint.scale = animated(joint.scale, track, |v| v, |t| t),
                    ChannelTarget::Weights(_) => {}
                }
            }
            joints.push(joint);
        }
        keyrig_core::Skeleton::new(joints)
    }

    /// Mesh `mesh` without a skin as a keyrig-skin [`keyrig_skin::SkinnedMesh`] bound rigidly to
    /// one root joint at the origin: its triangle primitives merged, in the mesh's own space,
    /// with the file's normals (computed from the triangles where a primitive has none) and
    /// TEXCOORD_0. The renderer, the editor and `keyrig deform` draw and pose it like any skinned
    /// mesh; the object's transform places it.
    ///
    /// # Errors
    /// No such mesh, or keyrig-skin rejects it (no triangles, a non-finite position).
    pub fn rigid_mesh(&self, mesh: usize) -> Result<keyrig_skin::SkinnedMesh, MappingError> {
        let bad = |message: String| MappingError::Mesh { mesh, message };
        let model_mesh = self.meshes.get(mesh).ok_or_else(|| bad("no such mesh".into()))?;
        let mut merged = MergedTriangles::default();
        for prim in model_mesh.primitives.iter().filter(|p| p.mode == PrimitiveMode::Triangles) {
            merged.push(prim);
        }
        let MergedTriangles { positions, normals, indices, uvs, has_uvs } = merged;
        let n = positions.len();
        let skeleton = keyrig_skin::RestSkeleton::new(&[keyrig_skin::RestJoint::new(
            "root",
            None,
            Vec3::ZERO,
            Quat::IDENTITY,
        )])
        .map_err(|e| bad(e.to_string()))?;
        let rigid = keyrig_skin::SkinnedMesh::new(
            positions,
            normals,
            indices,
            vec![[0; 4]; n],
            vec![[1.0, 0.0, 0.0, 0.0]; n],
            Some(vec![0; n]),
            skeleton,
        )
        .map_err(|e| bad(e.to_string()))?
        .with_morph_targets(merged_morph_targets(model_mesh))
        .map_err(|e| bad(e.to_string()))?;
        if has_uvs {
            rigid.with_uvs(uvs).map_err(|e| bad(e.to_string()))
        } else {
            Ok(rigid)
        }
    }

    /// The mesh on `node` as a keyrig-skin [`keyrig_skin::SkinnedMesh`] bound to the skeleton
    /// of [`ImportedModel::scene_skeleton`]: triangle primitives merged, joint indices
    /// renumbered to the skeleton's order, the four largest influences kept (of JOINTS_0/1)
    /// and normalized, the file's inverse bind matrices. The skeleton reaches up to the scene
    /// root, so the palette `F(j)·IBM(j)` is glTF's joint matrix and the skinned positions are
    /// glTF's world positions. Positions are bind-space, as in the file.
    ///
    /// # Errors
    /// The node has no mesh or skin, a primitive has no weights, or keyrig-skin rejects it.
    pub fn skinned_mesh(&self, node: usize) -> Result<keyrig_skin::SkinnedMesh, MappingError> {
        let bad = |message: &str| MappingError::Node { node, message: message.into() };
        let n = self.nodes.get(node).ok_or_else(|| bad("no such node"))?;
        let (mesh, skin) =
            (n.mesh.ok_or_else(|| bad("has no mesh"))?, n.skin.ok_or_else(|| bad("has no skin"))?);
        let map = self.skeleton_map(skin).ok_or_else(|| bad("skin missing"))?;
        let s = &self.skins[skin];
        if map.nodes.len() > keyrig_skin::MAX_JOINTS {
            return Err(bad(&format!(
                "its skin and the nodes above it make {} joints; keyrig supports {}",
                map.nodes.len(),
                keyrig_skin::MAX_JOINTS
            )));
        }
        // Vertex joint indices point into the skin's joint list; keyrig's into the skeleton.
        let mut keyrig_of_node = vec![0u16; self.nodes.len()];
        for (k, n) in map.nodes.iter().enumerate() {
            if let Some(n) = *n {
                keyrig_of_node[n] = k as u16;
            }
        }
        let renumber: Vec<u16> =
            s.joints.iter().map(|&n| keyrig_of_node.get(n).copied().unwrap_or(0)).collect();
        let (mut joints, mut weights) = (Vec::new(), Vec::new());
        let mut merged = MergedTriangles::default();
        for prim in self.meshes[mesh].primitives.iter().filter(|p| p.mode == PrimitiveMode::Triangles) {
            if prim.joint_sets.is_empty() {
                return Err(bad("a primitive has no JOINTS_0/WEIGHTS_0"));
            }
            merged.push(prim);
            for v in 0..prim.positions.len() {
                let mut influences: Vec<(u16, f32)> = prim
                    .joint_sets
                    .iter()
                    .zip(&prim.weight_sets)
                    .flat_map(|(j, w)| (0..4).map(move |i| (j[v][i], w[v][i])))
                    .filter(|&(_, w)| w > 0.0)
                    .collect();
                influences.sort_by(|a, b| b.1.total_cmp(&a.1));
                influences.truncate(4);
                let total: f32 = influences.iter().map(|x| x.1).sum();
                let (mut jv, mut wv) = ([0u16; 4], [0.0f32; 4]);
                if total > 0.0 {
                    for (i, (j, w)) in influences.iter().enumerate() {
                        jv[i] = renumber.get(usize::from(*j)).copied().unwrap_or(0);
                        wv[i] = w / total;
                    }
                } else {
                    wv[0] = 1.0;
                }
                joints.push(jv);
                weights.push(wv);
            }
        }
        let MergedTriangles { positions, normals, indices, uvs, has_uvs } = merged;
        let world = self.rest_world();
        let mut rest_joints = Vec::with_capacity(map.nodes.len());
        let mut ibms = Vec::with_capacity(map.nodes.len());
        for (k, (n, slot)) in map.nodes.iter().zip(&map.skin_slot).enumerate() {
            let (name, translation, rotation) = match n {
                Some(n) => (
                    self.nodes[*n].name.as_str(),
                    self.nodes[*n].translation,
                    self.nodes[*n].rotation.normalize(),
                ),
                None => (SYNTHETIC_ROOT_NAME, Vec3::ZERO, Quat::IDENTITY),
            };
            rest_joints.push(keyrig_skin::RestJoint::new(name, map.parents[k], translation, rotation));
            // The skin's joints bind with the file's matrices; the nodes above them (which no
            // vertex is weighted to) with the inverse of their rest world transform.
            ibms.push(match (slot, n) {
                (Some(slot), _) => s.inverse_bind_matrices[*slot],
                (None, Some(n)) => {
                    let inverse = world[*n].inverse();
                    if inverse.is_finite() {
                        inverse
                    } else {
                        Mat4::IDENTITY
                    }
                }
                (None, None) => Mat4::IDENTITY,
            });
        }
        let skeleton = keyrig_skin::RestSkeleton::with_inverse_bind_matrices(&rest_joints, &ibms)
            .map_err(|source| MappingError::Skin { skin, source })?;
        let mesh =
            keyrig_skin::SkinnedMesh::new(positions, normals, indices, joints, weights, None, skeleton)
                .and_then(|m| m.with_morph_targets(merged_morph_targets(&self.meshes[mesh])))
                .map_err(|source| MappingError::Skin { skin, source })?;
        if has_uvs {
            mesh.with_uvs(uvs).map_err(|source| MappingError::Skin { skin, source })
        } else {
            Ok(mesh)
        }
    }

    /// The look of mesh `mesh` as keyrig draws it: the base colour factor and base-colour
    /// texture (decoded, with its sampler) of its first triangle primitive. keyrig draws a mesh
    /// with one material; a mesh whose primitives differ shows the first one's everywhere.
    /// Only TEXCOORD_0 is read ([`ModelPrimitive::texcoords`]), so a texture on another set is
    /// left out. `None` for a mesh without triangles.
    ///
    /// # Errors
    /// [`MaterialError`] when the texture's image bytes are missing or cannot be decoded; the
    /// caller can still draw the mesh with [`MaterialError::without_texture`].
    pub fn material(&self, mesh: usize) -> Result<Option<keyrig_core::Material>, MaterialError> {
        let Some(prim) = self
            .meshes
            .get(mesh)
            .and_then(|m| m.primitives.iter().find(|p| p.mode == PrimitiveMode::Triangles))
        else {
            return Ok(None);
        };
        let base_colour = prim.base_colour_factor.map(|c| if c.is_finite() { c } else { 1.0 });
        let plain = keyrig_core::Material { base_colour, base_colour_texture: None };
        let Some(texture) = &prim.base_colour_texture else { return Ok(Some(plain)) };
        let fail = |message: String| MaterialError { image: texture.image, message, material: plain.clone() };
        if texture.texcoord_set != 0 {
            return Err(fail(format!(
                "uses TEXCOORD_{}; keyrig reads TEXCOORD_0 only",
                texture.texcoord_set
            )));
        }
        if prim.texcoords.is_none() {
            return Err(fail("the primitive has no TEXCOORD_0".into()));
        }
        let Some(Some(data)) = self.image_data.get(texture.image) else {
            return Err(fail("its bytes could not be read".into()));
        };
        let decoded = image::load_from_memory(&data.bytes).map_err(|e| fail(e.to_string()))?.to_rgba8();
        let (width, height) = decoded.dimensions();
        let image = keyrig_core::TextureImage::new(width, height, decoded.into_raw(), texture.sampler)
            .map_err(|e| fail(e.to_string()))?;
        Ok(Some(keyrig_core::Material { base_colour, base_colour_texture: Some(Arc::new(image)) }))
    }

    /// The model as a keyrig scene with every animation as an action of its name
    /// (docs/actions.md, "Imported animations"): the scene of [`ImportedModel::to_scene`] with
    /// the first animation, whose keys become the first action; each other animation's keys
    /// are stored in an action of its own. Each object plays the first animation that moves it
    /// (as Blender's glTF importer assigns them), so a file with an animation per object plays
    /// them all together; the frame range covers the longest action that plays.
    ///
    /// # Errors
    /// A skin that cannot be mapped.
    pub fn to_scene_all(&self, file_name: &str) -> Result<keyrig_core::Scene, MappingError> {
        if self.animations.is_empty() {
            return self.to_scene(file_name, None);
        }
        let mut names: Vec<String> = Vec::with_capacity(self.animations.len());
        for a in &self.animations {
            let base = if a.name.is_empty() {
                keyrig_core::DEFAULT_ACTION.to_owned()
            } else {
                a.name.replace('/', "_")
            };
            let mut name = base.clone();
            let mut n = 0;
            while names.contains(&name) {
                n += 1;
                name = format!("{base}.{n:03}");
            }
            names.push(name);
        }
        let mut scene = self.to_scene(file_name, Some(0))?;
        scene.name_unnamed_keys(&names[0]);
        for (i, name) in names.iter().enumerate().skip(1) {
            let mut other = self.to_scene(file_name, Some(i))?;
            let mut channels = Vec::new();
            for o in 0..other.objects.len() {
                channels.extend(other.take_keyed_channels(o));
            }
            channels.sort_by(|a, b| a.path.cmp(&b.path));
            scene.actions.push(keyrig_core::Action { name: name.clone(), channels });
            // An object the earlier animations leave still plays this one.
            for o in 0..scene.objects.len() {
                if scene.objects[o].action.is_none() {
                    let _ = scene.assign_action(o, Some(name));
                    if scene.keyed_channels_of(o).is_empty() {
                        let _ = scene.assign_action(o, None);
                    } else {
                        let end = (self.animations[i].duration() * scene.fps).ceil();
                        if end.is_finite() {
                            scene.frame_range.end = scene.frame_range.end.max(end.clamp(1.0, 1e6) as i32);
                        }
                    }
                }
            }
        }
        Ok(scene)
    }

    /// The model as a keyrig scene, with the tracks of `animation`:
    /// - each skinned mesh node → an object at the origin (glTF ignores a skinned mesh node's
    ///   own transform) with the skeleton of [`ImportedModel::scene_skeleton`], which holds
    ///   every channel of the skin's joints and of the nodes above them, and its mesh as
    ///   `MeshSource::File { path: file_name, mesh }`;
    /// - each unskinned mesh node → an object at its rest world transform, with its own
    ///   translation/rotation/scale tracks when it is a root node;
    /// - each KHR_lights_punctual light → a light at its node's rest world position and
    ///   direction (−Z), spot cone angles in degrees;
    /// - each node holding a camera → a scene camera (`add_scene_cameras`).
    ///
    /// What the scene does not take from the file: the animation of unskinned nodes below other
    /// nodes, the pointer channels listed in [`ImportedModel::skipped_channels`], and the other
    /// animations.
    ///
    /// # Errors
    /// A skin that cannot be mapped.
    pub fn to_scene(
        &self,
        file_name: &str,
        animation: Option<usize>,
    ) -> Result<keyrig_core::Scene, MappingError> {
        let mut scene = keyrig_core::Scene::default();
        let world = self.rest_world();
        let anim = animation.and_then(|a| self.animations.get(a));
        // One skeleton per skin, however many mesh nodes share it: linear in the node count.
        let channels_of = self.channels_by_node(animation);
        let mut skeletons: std::collections::HashMap<usize, keyrig_core::Skeleton> =
            std::collections::HashMap::new();
        if let Some(a) = anim {
            let end = (a.duration() * scene.fps).ceil();
            scene.frame_range.end = if end.is_finite() { end.clamp(1.0, 1e6) as i32 } else { 60 };
        }
        for (i, node) in self.nodes.iter().enumerate() {
            let Some(mesh) = node.mesh else { continue };
            let mut object = keyrig_core::Object::new(node.name.clone());
            object.mesh = Some(keyrig_core::MeshSource::file(file_name, Some(mesh)));
            // A skeleton reaches up to the scene root, so a skinned object sits at the origin.
            let placement = match node.skin {
                Some(skin) => {
                    let skeleton = match skeletons.entry(skin) {
                        std::collections::hash_map::Entry::Occupied(e) => e.get().clone(),
                        std::collections::hash_map::Entry::Vacant(e) => {
                            let map = self
                                .skeleton_map(skin)
                                .ok_or(MappingError::Node { node: i, message: format!("no skin {skin}") })?;
                            e.insert(self.skeleton_from_map(&map, &channels_of)).clone()
                        }
                    };
                    object.skeleton = Some(skeleton);
                    if let Some(kind) = self.skins.get(skin).and_then(|s| s.deformer) {
                        object.deformer.kind = kind;
                    }
                    Mat4::IDENTITY
                }
                None => world[i],
            };
            let (s, r, t) = placement.to_scale_rotation_translation();
            object.translation = keyrig_core::Animated::constant(t);
            object.rotation = keyrig_core::Animated::constant(r.normalize());
            object.scale = keyrig_core::Animated::constant(s);
            if node.skin.is_none() && node.parent.is_none() {
                for target in &channels_of[i] {
                    match target {
                        ChannelTarget::Translation(t) => object.translation.track = t.clone(),
                        ChannelTarget::Rotation(t) => object.rotation.track = t.clone(),
                        ChannelTarget::Scale(t) => object.scale.track = t.clone(),
                        ChannelTarget::Weights(_) => {}
                    }
                }
            }
            attributes::object_attributes(self, anim, i, &channels_of[i], &mut object);
            scene.objects.push(object);
        }
        let mut uses = vec![0usize; self.lights.len()];
        for l in self.nodes.iter().filter_map(|n| n.light) {
            if let Some(u) = uses.get_mut(l) {
                *u += 1;
            }
        }
        for (i, node) in self.nodes.iter().enumerate() {
            let Some(light) = node.light.and_then(|l| self.lights.get(l)) else { continue };
            let light_index = node.light.unwrap_or_default();
            // A light several nodes place is named by its nodes, so each scene light has a name.
            let name = if uses[light_index] > 1 { node.name.clone() } else { light.name.clone() };
            let (_, rotation, position) = world[i].to_scale_rotation_translation();
            let kind = match light.kind {
                ModelLightKind::Directional => keyrig_core::LightKind::Directional,
                ModelLightKind::Point => keyrig_core::LightKind::Point,
                ModelLightKind::Spot { inner_cone_angle, outer_cone_angle } => keyrig_core::LightKind::Spot {
                    cutoff_deg: outer_cone_angle.to_degrees(),
                    inner_angle_deg: inner_cone_angle.to_degrees(),
                    dropoff: 1.0,
                },
            };
            let mut scene_light = keyrig_core::Light {
                name,
                kind,
                enabled: true,
                position: keyrig_core::Animated::constant(position),
                direction: keyrig_core::Animated::constant(rotation * Vec3::NEG_Z),
                colour: keyrig_core::Animated::constant(light.colour),
                intensity: keyrig_core::Animated::constant(light.intensity),
                attributes: Default::default(),
            };
            attributes::light_attributes(self, anim, i, light_index, &mut scene_light);
            scene.lights.push(scene_light);
        }
        add_scene_cameras(self, &world, &channels_of, anim, &mut scene);
        Ok(scene)
    }
}

/// A track mapped key by key: values through `value`, tangents through `tangent` (the linear
/// part of the same map); the static value is the first key's. `fallback` stays when the
/// track has no keys.
fn animated<T: Copy>(
    fallback: keyrig_core::Animated<T>,
    track: &RawTrack<T>,
    value: impl Fn(T) -> T,
    tangent: impl Fn(T) -> T,
) -> keyrig_core::Animated<T> {
    let keys: Vec<Key<T>> = track
        .keys
        .iter()
        .map(|key| Key {
            time: key.time,
            value: value(key.value),
            interpolation: key.interpolation,
            tcb: key.tcb,
            in_tangent: key.in_tangent.map(&tangent),
            out_tangent: key.out_tangent.map(&tangent),
            spin: None,
            key_type: key.key_type,
        })
        .collect();
    match keys.first() {
        Some(first) => keyrig_core::Animated::new(first.value, RawTrack::new(keys)),
        None => fallback,
    }
}

/// A glTF camera.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelCamera {
    pub name: String,
    pub projection: ModelProjection,
}

/// A glTF camera's projection, as the file gives it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum ModelProjection {
    Perspective { yfov: f32, aspect_ratio: Option<f32>, znear: f32, zfar: Option<f32> },
    Orthographic { xmag: f32, ymag: f32, znear: f32, zfar: f32 },
}

impl ModelProjection {
    /// Width over height, when the file says.
    #[must_use]
    pub fn aspect_ratio(self) -> Option<f32> {
        match self {
            ModelProjection::Perspective { aspect_ratio, .. } => aspect_ratio,
            ModelProjection::Orthographic { xmag, ymag, .. } => Some(xmag / ymag),
        }
    }
}

/// Adds a scene camera for each node of `model` that holds a camera, named after the node (or
/// its camera), unique among the scene's cameras: at the node's rest world position and
/// rotation (a camera looks down its node's −Z with +Y up in glTF as in keyrig; the node's
/// scale does not apply), keyed by the node's own translation and rotation channels when it is
/// a root node. A perspective camera's `yfov` (radians) becomes a field of view in degrees, an
/// orthographic camera's `ymag` (half the view's height) a view height of `2·ymag`. The first
/// camera with an aspect ratio (`aspectRatio`, or `xmag / ymag`) sets the scene's render size
/// (720 pixels tall). Its visibility and its keyed `yfov` / `ymag` (`KHR_node_visibility`,
/// `KHR_animation_pointer`) come from `attributes::camera_attributes`.
fn add_scene_cameras(
    model: &ImportedModel,
    world: &[Mat4],
    channels_of: &[Vec<&ChannelTarget>],
    anim: Option<&ModelAnimation>,
    scene: &mut keyrig_core::Scene,
) {
    for (i, node) in model.nodes.iter().enumerate() {
        let Some(camera) = node.camera.and_then(|c| model.cameras.get(c)) else { continue };
        let camera_index = node.camera.unwrap_or_default();
        let (_, rotation, translation) = world[i].to_scale_rotation_translation();
        // The node's name, unless the file left it out (then the camera's).
        let base = if node.name == format!("node{i}") { camera.name.clone() } else { node.name.clone() };
        let name = if scene.camera_index(&base).is_some() {
            (1..).map(|n| format!("{base}.{n:03}")).find(|n| scene.camera_index(n).is_none()).unwrap_or(base)
        } else {
            base
        };
        let mut out = keyrig_core::SceneCamera::new(name, translation);
        out.rotation = keyrig_core::Animated::constant(rotation.normalize());
        match camera.projection {
            ModelProjection::Perspective { yfov, znear, zfar, .. } => {
                out.projection = keyrig_core::Projection::Perspective;
                out.lens = keyrig_core::Animated::constant(yfov.to_degrees());
                (out.near, out.far) = (znear, zfar);
            }
            ModelProjection::Orthographic { ymag, znear, zfar, .. } => {
                out.projection = keyrig_core::Projection::Orthographic;
                out.lens = keyrig_core::Animated::constant(2.0 * ymag);
                // keyrig's near plane is > 0; glTF allows an orthographic znear of 0.
                (out.near, out.far) = (znear.max(1e-4).min(zfar * 0.5), Some(zfar));
            }
        }
        if node.parent.is_none() {
            for target in &channels_of[i] {
                match target {
                    ChannelTarget::Translation(t) => out.translation.track = t.clone(),
                    ChannelTarget::Rotation(t) => out.rotation.track = t.clone(),
                    ChannelTarget::Scale(_) | ChannelTarget::Weights(_) => {}
                }
            }
        }
        attributes::camera_attributes(model, anim, i, camera_index, &mut out);
        if scene.render_size.is_none() {
            if let Some(aspect) = camera.projection.aspect_ratio().filter(|a| a.is_finite() && *a > 0.0) {
                let width = (720.0 * aspect).round().clamp(1.0, f32::from(u16::MAX)) as u32;
                scene.render_size = Some(keyrig_core::RenderSize {
                    width: width.min(keyrig_core::RenderSize::MAX_SIDE),
                    height: 720,
                });
            }
        }
        scene.cameras.push(out);
    }
}
