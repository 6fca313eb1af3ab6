//! An imported glTF model, kept whole: what the keyrig scene can hold and what it cannot
//! (scale tracks, translation tracks of non-root joints, morph weights, several skins and
//! animations). [`crate::gltf_import`] fills it; [`ImportedModel::to_scene`] maps what fits
//! onto a [`keyrig_core::Scene`].
//!
//! Keys keep the curve of the file exactly: glTF STEP → [`Interpolation::Step`], LINEAR →
//! [`Interpolation::Linear`] (slerp for rotations), CUBICSPLINE → [`Interpolation::Hermite`]
//! with the file's in-tangent `a_k` and out-tangent `b_k` stored per second in
//! [`Key::in_tangent`] / [`Key::out_tangent`]. The sampler here evaluates them as the glTF
//! 2.0 specification (Appendix C) defines:
//! `p(t) = h00·v_k + h10·t_d·b_k + h01·v_{k+1} + h11·t_d·a_{k+1}`, `t_d = t_{k+1} − t_k`,
//! and cubic rotations are normalized after the component-wise Hermite.

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
    /// Morph-target weights of this node's mesh instance, when the node overrides them.
    pub weights: Option<Vec<f32>>,
}

impl ModelNode {
    /// `parent_from_node` = T · R · S.
    #[must_use]
    pub fn local_matrix(&self) -> Mat4 {
        Mat4::from_scale_rotation_translation(self.scale, self.rotation, self.translation)
    }
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
    pub positions: Option<Vec<Vec3>>,
    pub normals: Option<Vec<Vec3>>,
}

/// A reference to the base-colour texture of a primitive's material.
#[derive(Clone, Debug, PartialEq)]
pub struct TextureRef {
    pub texture: usize,
    pub image: usize,
    /// Which TEXCOORD_n set it uses.
    pub texcoord_set: u32,
}

/// Where an image's bytes are.
#[derive(Clone, Debug, PartialEq)]
pub enum ImageSource {
    /// A URI relative to the glTF file (or a `data:` URI).
    Uri(String),
    /// A buffer view of the file, with its MIME type.
    BufferView { view: usize, mime_type: String },
}

/// One primitive of a mesh, attributes in accessor order.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelPrimitive {
    pub mode: PrimitiveMode,
    pub positions: Vec<Vec3>,
    pub normals: Option<Vec<Vec3>>,
    /// TEXCOORD_0.
    pub texcoords: Option<Vec<Vec2>>,
    /// Vertex indices (generated 0..n when the file has none; strips/fans as lists).
    pub indices: Vec<u32>,
    /// JOINTS_0, JOINTS_1, …: per vertex four indices into the skin's joint list.
    pub joint_sets: Vec<Vec<[u16; 4]>>,
    /// WEIGHTS_0, WEIGHTS_1, …: per vertex four weights, as stored (not renormalized).
    pub weight_sets: Vec<Vec<[f32; 4]>>,
    pub morph_targets: Vec<MorphTarget>,
    pub base_colour_factor: [f32; 4],
    pub base_colour_texture: Option<TextureRef>,
}

/// A mesh: primitives and default morph weights.
#[derive(Clone, Debug, PartialEq)]
pub struct ModelMesh {
    pub name: String,
    pub primitives: Vec<ModelPrimitive>,
    pub weights: Vec<f32>,
}

/// A skin: joints (node indices) and their inverse bind matrices (identity when absent).
#[derive(Clone, Debug, PartialEq)]
pub struct ModelSkin {
    pub name: String,
    pub joints: Vec<usize>,
    pub inverse_bind_matrices: Vec<Mat4>,
    pub skeleton: Option<usize>,
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
    pub images: Vec<ImageSource>,
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
        let mut out = primitive.positions.clone();
        for (target, &w) in primitive.morph_targets.iter().zip(weights) {
            if let Some(d) = &target.positions {
                for (p, d) in out.iter_mut().zip(d) {
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
                let mut total = 0.0;
                for (joints, weights) in primitive.joint_sets.iter().zip(&primitive.weight_sets) {
                    for i in 0..4 {
                        let w = weights[v][i];
                        if w != 0.0 {
                            let m = joint_matrices
                                .get(usize::from(joints[v][i]))
                                .copied()
                                .unwrap_or(Mat4::IDENTITY);
                            sum += w * m.transform_point3(p);
                            total += w;
                        }
                    }
                }
                if total == 0.0 {
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

/// Why an imported model cannot be mapped onto keyrig's scene or skin types.
#[derive(Debug, thiserror::Error)]
pub enum MappingError {
    #[error("node {node}: {message}")]
    Node { node: usize, message: String },
    #[error("skin {skin}: {source}")]
    Skin { skin: usize, source: keyrig_skin::SkinError },
}

/// How a skin's joints map onto a keyrig skeleton: joints reordered parents first, the
/// frame P that the skeleton lives in, and each joint's rest transform relative to its
/// nearest joint ancestor (intermediate nodes folded in, scale dropped).
struct SkeletonMap {
    /// glTF node of keyrig joint k.
    nodes: Vec<usize>,
    /// Index in the glTF skin's joint list of keyrig joint k.
    skin_slot: Vec<usize>,
    parents: Vec<Option<usize>>,
    rest: Vec<(Vec3, Quat)>,
    /// `world_from_skeleton`: rest world transform of the root joint's parent node.
    frame: Mat4,
}

impl ImportedModel {
    /// `model_from_node` at rest for every node.
    fn rest_world(&self) -> Vec<Mat4> {
        self.world_matrices(&self.rest_pose())
    }

    fn skeleton_map(&self, skin: usize) -> Option<SkeletonMap> {
        let s = self.skins.get(skin)?;
        let world = self.rest_world();
        // Nearest joint ancestor and joint depth of every node, parents first (the importer
        // guarantees a forest), in time linear in the node count.
        let mut is_joint = vec![false; self.nodes.len()];
        for &j in &s.joints {
            if let Some(flag) = is_joint.get_mut(j) {
                *flag = true;
            }
        }
        let mut nearest: Vec<Option<usize>> = vec![None; self.nodes.len()];
        let mut depth_of = vec![0usize; self.nodes.len()];
        let mut queue: std::collections::VecDeque<usize> =
            (0..self.nodes.len()).filter(|&n| self.nodes[n].parent.is_none()).collect();
        while let Some(n) = queue.pop_front() {
            if let Some(p) = self.nodes[n].parent {
                nearest[n] = if is_joint[p] { Some(p) } else { nearest[p] };
                depth_of[n] = nearest[n].map_or(0, |a| depth_of[a] + 1);
            }
            queue.extend(self.nodes[n].children.iter().copied().filter(|&c| c < self.nodes.len()));
        }
        let joint_parent = |n: usize| nearest[n];
        let mut order: Vec<usize> = (0..s.joints.len()).collect();
        order.sort_by_key(|&slot| depth_of[s.joints[slot]]);
        let nodes: Vec<usize> = order.iter().map(|&slot| s.joints[slot]).collect();
        let mut keyrig_index = std::collections::HashMap::new();
        for (k, &n) in nodes.iter().enumerate() {
            keyrig_index.entry(n).or_insert(k);
        }
        let roots: Vec<usize> = nodes.iter().copied().filter(|&n| joint_parent(n).is_none()).collect();
        let frame = match roots.as_slice() {
            [root] => self.nodes[*root].parent.map_or(Mat4::IDENTITY, |p| world[p]),
            _ => Mat4::IDENTITY,
        };
        let frame_inv = frame.inverse();
        let mut parents = Vec::with_capacity(nodes.len());
        let mut rest = Vec::with_capacity(nodes.len());
        for &n in &nodes {
            let parent = joint_parent(n).and_then(|p| keyrig_index.get(&p).copied());
            let parent_world = parent.map_or(frame, |p| world[nodes[p]]);
            let rel = if parent.is_none() { frame_inv * world[n] } else { parent_world.inverse() * world[n] };
            let (_, rotation, translation) = rel.to_scale_rotation_translation();
            parents.push(parent);
            rest.push((translation, rotation.normalize()));
        }
        Some(SkeletonMap { nodes, skin_slot: order, parents, rest, frame })
    }

    /// The keyrig skeleton of skin `skin` with the rotation (and root translation) tracks of
    /// `animation`: joints parents first, rest R(j) from the file's node transforms, and
    /// `T(j) = q_rest(j)⁻¹ · q(t)` per key (tangents mapped the same way, which is exact
    /// because left-multiplying by a fixed unit quaternion is linear and norm-preserving).
    /// Joint scale and translation tracks of non-root joints stay in this model only.
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
        let anim = animation.and_then(|a| self.animations.get(a));
        let mut joints = Vec::with_capacity(map.nodes.len());
        let mut root_translation = keyrig_core::Animated::constant(Vec3::ZERO);
        for (k, &n) in map.nodes.iter().enumerate() {
            let node = &self.nodes[n];
            let q_rest_inv = node.rotation.inverse();
            let mut rotation = keyrig_core::Animated::constant(Quat::IDENTITY);
            for channel in anim.iter().flat_map(|a| &a.channels).filter(|c| c.node == n) {
                match &channel.target {
                    ChannelTarget::Rotation(track) => {
                        rotation.track = RawTrack::new(
                            track
                                .keys
                                .iter()
                                .map(|key| Key {
                                    time: key.time,
                                    value: (q_rest_inv * key.value).normalize(),
                                    interpolation: key.interpolation,
                                    tcb: key.tcb,
                                    in_tangent: key.in_tangent.map(|t| q_rest_inv * t),
                                    out_tangent: key.out_tangent.map(|t| q_rest_inv * t),
                                    spin: None,
                                })
                                .collect(),
                        );
                        if let Some(first) = rotation.track.keys.first() {
                            rotation.value = first.value;
                        }
                    }
                    ChannelTarget::Translation(track) if map.parents[k].is_none() => {
                        let rest = node.translation;
                        root_translation = keyrig_core::Animated {
                            value: track.keys.first().map_or(Vec3::ZERO, |key| key.value - rest),
                            track: RawTrack::new(
                                track
                                    .keys
                                    .iter()
                                    .map(|key| {
                                        let mut key = key.clone();
                                        key.value -= rest;
                                        key
                                    })
                                    .collect(),
                            ),
                        };
                    }
                    _ => {}
                }
            }
            joints.push(keyrig_core::Joint {
                name: node.name.clone(),
                parent: map.parents[k],
                rest_translation: map.rest[k].0,
                rest_rotation: map.rest[k].1,
                rotation,
            });
        }
        Ok(keyrig_core::Skeleton { joints, root_translation })
    }

    /// The mesh on `node` as a keyrig-skin [`keyrig_skin::SkinnedMesh`] bound to the skeleton
    /// of [`ImportedModel::scene_skeleton`]: triangle primitives merged, joint indices
    /// renumbered to the parents-first order, the four largest influences kept (of JOINTS_0/1)
    /// and normalized, the file's inverse bind matrices. The palette `F(j)·IBM(j)` then lives
    /// in the skeleton's frame P (see [`ImportedModel::skeleton_frame`]): glTF's world
    /// positions are `P · Σ wᵢ F(jᵢ)·IBM(jᵢ)·v`. Positions are bind-space, as in the file.
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
        let mut renumber = vec![0u16; s.joints.len()];
        for (k, &slot) in map.skin_slot.iter().enumerate() {
            renumber[slot] = k as u16;
        }
        let (mut positions, mut normals, mut indices, mut joints, mut weights) =
            (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
        for prim in self.meshes[mesh].primitives.iter().filter(|p| p.mode == PrimitiveMode::Triangles) {
            if prim.joint_sets.is_empty() {
                return Err(bad("a primitive has no JOINTS_0/WEIGHTS_0"));
            }
            let base = positions.len() as u32;
            positions.extend_from_slice(&prim.positions);
            match &prim.normals {
                Some(nm) => normals.extend_from_slice(nm),
                None => normals.extend(keyrig_skin::mesh::vertex_normals(&prim.positions, &prim.indices)),
            }
            indices.extend(prim.indices.iter().map(|i| i + base));
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
        let rest_joints: Vec<keyrig_skin::RestJoint> = map
            .nodes
            .iter()
            .enumerate()
            .map(|(k, &nd)| {
                keyrig_skin::RestJoint::new(
                    &self.nodes[nd].name,
                    map.parents[k],
                    map.rest[k].0,
                    map.rest[k].1,
                )
            })
            .collect();
        let ibms: Vec<Mat4> = map.skin_slot.iter().map(|&slot| s.inverse_bind_matrices[slot]).collect();
        let skeleton = keyrig_skin::RestSkeleton::with_inverse_bind_matrices(&rest_joints, &ibms)
            .map_err(|source| MappingError::Skin { skin, source })?;
        keyrig_skin::SkinnedMesh::new(positions, normals, indices, joints, weights, None, skeleton)
            .map_err(|source| MappingError::Skin { skin, source })
    }

    /// A keyrig-skin joint palette for the skinned mesh on `node` at `time` of `animation`
    /// that follows the file exactly: `F(j) = P⁻¹ · globalTransform(joint_j)` with every
    /// channel of the animation (translations of any joint and scales included) and
    /// `M(j) = F(j) · IBM(j)`, so rigid, linear blend and dual quaternion through keyrig-skin
    /// reproduce glTF's joint matrices. Bones blending's per-joint rotations come from the
    /// keyrig pose ([`ImportedModel::scene_skeleton`]), which holds rotations and the root
    /// translation only. `skeleton` is the rest skeleton of [`ImportedModel::skinned_mesh`].
    ///
    /// # Errors
    /// The node has no skin, or its tracks or skeleton are rejected by keyrig.
    pub fn exact_joint_palette(
        &self,
        node: usize,
        skeleton: &keyrig_skin::RestSkeleton,
        animation: Option<usize>,
        time: f64,
    ) -> Result<keyrig_skin::JointPalette, MappingError> {
        let bad = |message: String| MappingError::Node { node, message };
        let skin = self.nodes.get(node).and_then(|n| n.skin).ok_or_else(|| bad("has no skin".into()))?;
        let map = self.skeleton_map(skin).ok_or_else(|| bad("skin missing".into()))?;
        let scene_skeleton = self.scene_skeleton(skin, animation)?;
        let sampler = keyrig_skin::ScenePoseSampler::new(&scene_skeleton)
            .map_err(|source| MappingError::Skin { skin, source })?;
        let mut palette = keyrig_skin::JointPalette::new(skeleton, &sampler.sample(time))
            .map_err(|source| MappingError::Skin { skin, source })?;
        let world = self.world_matrices(&self.pose_at(animation, time));
        let frame_inv = map.frame.inverse();
        let s = &self.skins[skin];
        for (k, (&n, &slot)) in map.nodes.iter().zip(&map.skin_slot).enumerate().take(palette.len()) {
            let f = glam::Affine3A::from_mat4(frame_inv * world[n]);
            palette.model_from_joint[k] = f;
            palette.skinning[k] = f * glam::Affine3A::from_mat4(s.inverse_bind_matrices[slot]);
        }
        let uniform = palette.skinning.iter().all(|m| {
            let l = [
                m.matrix3.x_axis.length_squared(),
                m.matrix3.y_axis.length_squared(),
                m.matrix3.z_axis.length_squared(),
            ];
            let max = l[0].max(l[1]).max(l[2]);
            max > 0.0 && l.iter().all(|x| (x - max).abs() <= 1e-4 * max)
        });
        palette.normal_skinning = if uniform {
            None
        } else {
            Some(palette.skinning.iter().map(|m| m.matrix3.inverse().transpose()).collect())
        };
        Ok(palette)
    }

    /// `world_from_skeleton` (P) of skin `skin`: where the keyrig skeleton's model space sits
    /// in the file's world. keyrig-skin's deformed positions times P are glTF world positions.
    #[must_use]
    pub fn skeleton_frame(&self, skin: usize) -> Option<Mat4> {
        self.skeleton_map(skin).map(|m| m.frame)
    }

    /// The model as a keyrig scene, with the tracks of `animation`:
    /// - each skinned mesh node → an object (transform P, the skeleton's frame) with the
    ///   skeleton of [`ImportedModel::scene_skeleton`] and its mesh as
    ///   `MeshSource::File { path: file_name, mesh }`;
    /// - each unskinned mesh node → an object at its rest world transform, with its own
    ///   translation/rotation/scale tracks when it is a root node;
    /// - each KHR_lights_punctual light → a light at its node's rest world position and
    ///   direction (−Z), spot cone angles in degrees.
    ///
    /// What a scene cannot hold stays here: translation tracks of non-root joints, scale
    /// tracks of joints, morph weights, animated lights, the other animations.
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
        if let Some(a) = anim {
            let end = (a.duration() * scene.fps).ceil();
            scene.frame_range.end = if end.is_finite() { end.clamp(1.0, 1e6) as i32 } else { 60 };
        }
        for (i, node) in self.nodes.iter().enumerate() {
            let Some(mesh) = node.mesh else { continue };
            let mut object = keyrig_core::Object::new(node.name.clone());
            object.mesh = Some(keyrig_core::MeshSource::file(file_name, Some(mesh)));
            let placement = match node.skin {
                Some(skin) => {
                    object.skeleton = Some(self.scene_skeleton(skin, animation)?);
                    self.skeleton_frame(skin).unwrap_or(Mat4::IDENTITY)
                }
                None => world[i],
            };
            let (s, r, t) = placement.to_scale_rotation_translation();
            object.translation = keyrig_core::Animated::constant(t);
            object.rotation = keyrig_core::Animated::constant(r.normalize());
            object.scale = keyrig_core::Animated::constant(s);
            if node.skin.is_none() && node.parent.is_none() {
                for channel in anim.iter().flat_map(|a| &a.channels).filter(|c| c.node == i) {
                    match &channel.target {
                        ChannelTarget::Translation(t) => object.translation.track = t.clone(),
                        ChannelTarget::Rotation(t) => object.rotation.track = t.clone(),
                        ChannelTarget::Scale(t) => object.scale.track = t.clone(),
                        ChannelTarget::Weights(_) => {}
                    }
                }
            }
            scene.objects.push(object);
        }
        for (i, node) in self.nodes.iter().enumerate() {
            let Some(light) = node.light.and_then(|l| self.lights.get(l)) else { continue };
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
            scene.lights.push(keyrig_core::Light {
                name: light.name.clone(),
                kind,
                enabled: true,
                position: keyrig_core::Animated::constant(position),
                direction: keyrig_core::Animated::constant(rotation * Vec3::NEG_Z),
                colour: keyrig_core::Animated::constant(light.colour),
                intensity: keyrig_core::Animated::constant(light.intensity),
            });
        }
        Ok(scene)
    }
}
