//! Skinned meshes and the meshes keyrig generates in code (docs/design.md §6).
//!
//! Units: **centimetres**, as in the paper (seed text 000, chapter V). The arms lie along +X
//! from the origin; their 4 bones are joints `shoulder`, `elbow`, `forearm` and `wrist`
//! ([`ARM_JOINT_NAMES`]) at x = 0, L, 2L, 3L with L = 160.158 / 4 = 40.0395 cm.

use glam::{Quat, Vec2, Vec3};
use keyrig_core::{Joint, ProceduralMesh, Skeleton};

use crate::binding::{bind_from_weights, bind_single_weights, smooth_weights, BlendZone};
use crate::error::SkinError;
use crate::influences::{BonesBlendBindings, Influences};
use crate::skeleton::RestSkeleton;

/// Length of the paper's arms along X, in centimetres.
pub const ARM_LENGTH_CM: f32 = 160.158;
/// Number of bones (joints) of each arm.
pub const ARM_BONES: usize = 4;
/// Names of the arm's joints, root first (the demo scene's arm uses the same names).
pub const ARM_JOINT_NAMES: [&str; ARM_BONES] = ["shoulder", "elbow", "forearm", "wrist"];

/// A triangle mesh bound to a rest skeleton, in bind model space.
///
/// # Invariants (checked by [`SkinnedMesh::new`])
/// - `positions`, `normals`, `influences` (and `bones` and `uvs` when present) have one
///   entry per vertex; every position and normal is finite;
/// - `indices` holds whole triangles of in-range vertex indices;
/// - every joint index is in the skeleton; weights are ≥ 0 and sum to 1 ([`Influences`] holds
///   only such weights, checked once when it is built).
#[derive(Clone, Debug, PartialEq)]
pub struct SkinnedMesh {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    /// Triangle list, counter-clockwise seen from outside.
    pub indices: Vec<u32>,
    /// Up to 4 joints and weights per vertex (unused ones: joint 0, weight 0), validated.
    pub influences: Influences,
    /// The single joint of each vertex for single-weight meshes (the paper's arms); `None`
    /// for meshes that come with multi-weights only.
    pub bones: Option<Vec<u16>>,
    pub skeleton: RestSkeleton,
    /// Texture coordinates per vertex (glTF TEXCOORD_0: (0, 0) is the image's top-left
    /// corner), for drawing only; the deformers ignore them. `None`: the mesh has none.
    pub uvs: Option<Vec<Vec2>>,
    /// Morph targets (glTF), each with one displacement per vertex: the mesh deformed is
    /// `positions + Σ wᵢ·Δᵢ` for the weights of the frame ([`SkinnedMesh::morphed`]) before
    /// it is skinned. Empty for a mesh without targets.
    pub morph_targets: Vec<MorphTarget>,
}

/// One morph target of a [`SkinnedMesh`]: a position displacement per vertex, and a normal
/// displacement per vertex or none.
#[derive(Clone, Debug, PartialEq)]
pub struct MorphTarget {
    pub positions: Vec<Vec3>,
    /// Empty when the target does not move normals.
    pub normals: Vec<Vec3>,
}

/// Per-vertex data the deformers need besides the weights, computed once per mesh and blend
/// zone (not per frame).
#[derive(Clone, Debug, PartialEq)]
pub struct MeshBindings {
    /// The rigid deformer's joint per vertex: the single weight, or the dominant influence.
    pub rigid: Vec<u16>,
    /// Bones-blending (joint, t) per vertex, checked against the mesh's skeleton.
    pub bones_blending: BonesBlendBindings,
}

impl SkinnedMesh {
    /// Checks and assembles a mesh.
    #[allow(clippy::too_many_arguments)]
    pub fn new(
        positions: Vec<Vec3>,
        normals: Vec<Vec3>,
        indices: Vec<u32>,
        joints: Vec<[u16; 4]>,
        weights: Vec<[f32; 4]>,
        bones: Option<Vec<u16>>,
        skeleton: RestSkeleton,
    ) -> Result<Self, SkinError> {
        let influences = Influences::new(joints, weights, skeleton.len())?;
        let mesh = SkinnedMesh {
            positions,
            normals,
            indices,
            influences,
            bones,
            skeleton,
            uvs: None,
            morph_targets: Vec::new(),
        };
        mesh.validate()?;
        Ok(mesh)
    }

    /// The mesh with texture coordinates, one per vertex.
    ///
    /// # Errors
    /// [`SkinError::LengthMismatch`] when `uvs` does not have one entry per vertex.
    pub fn with_uvs(mut self, uvs: Vec<Vec2>) -> Result<Self, SkinError> {
        if uvs.len() != self.positions.len() {
            return Err(SkinError::LengthMismatch {
                what: "texture coordinates",
                expected: self.positions.len(),
                found: uvs.len(),
            });
        }
        self.uvs = Some(uvs);
        Ok(self)
    }

    /// The mesh with morph targets.
    ///
    /// # Errors
    /// [`SkinError::LengthMismatch`] when a target does not have one displacement per vertex
    /// (normals: one per vertex or none); [`SkinError::NonFiniteVertex`] for a displacement
    /// that is not finite.
    pub fn with_morph_targets(mut self, targets: Vec<MorphTarget>) -> Result<Self, SkinError> {
        let n = self.positions.len();
        for target in &targets {
            if target.positions.len() != n {
                return Err(SkinError::LengthMismatch {
                    what: "morph target positions",
                    expected: n,
                    found: target.positions.len(),
                });
            }
            if !target.normals.is_empty() && target.normals.len() != n {
                return Err(SkinError::LengthMismatch {
                    what: "morph target normals",
                    expected: n,
                    found: target.normals.len(),
                });
            }
            let bad = target.positions.iter().chain(&target.normals).position(|d| !d.is_finite());
            if let Some(v) = bad {
                return Err(SkinError::NonFiniteVertex {
                    vertex: v % n.max(1),
                    what: "morph target displacement",
                });
            }
        }
        self.morph_targets = targets;
        Ok(self)
    }

    /// Positions and unit normals morphed by `weights` (one per target; missing ones 0):
    /// `p + Σ wᵢ·Δpᵢ`, `normalize(n + Σ wᵢ·Δnᵢ)`, as glTF defines morphing. `None` when no
    /// target has a non-zero finite weight (the mesh is drawn as it is).
    #[must_use]
    pub fn morphed(&self, weights: &[f32]) -> Option<(Vec<Vec3>, Vec<Vec3>)> {
        let active: Vec<(&MorphTarget, f32)> = self
            .morph_targets
            .iter()
            .zip(weights)
            .filter(|(_, w)| w.is_finite() && **w != 0.0)
            .map(|(t, &w)| (t, w))
            .collect();
        if active.is_empty() {
            return None;
        }
        let mut positions = self.positions.clone();
        let mut normals = self.normals.clone();
        for (target, w) in active {
            for (p, d) in positions.iter_mut().zip(&target.positions) {
                *p += w * *d;
            }
            for (n, d) in normals.iter_mut().zip(&target.normals) {
                *n += w * *d;
            }
        }
        for n in &mut normals {
            *n = n.normalize_or_zero();
        }
        Some((positions, normals))
    }

    /// A single-weight mesh with smooth 4-influence weights derived across each joint
    /// ([`crate::binding::smooth_weights`]).
    pub fn from_single_weights(
        positions: Vec<Vec3>,
        normals: Vec<Vec3>,
        indices: Vec<u32>,
        bones: Vec<u16>,
        skeleton: RestSkeleton,
        zone: BlendZone,
    ) -> Result<Self, SkinError> {
        let (joints, weights) = smooth_weights(&skeleton, &positions, &bones, zone)?;
        Self::new(positions, normals, indices, joints, weights, Some(bones), skeleton)
    }

    /// Checks the invariants listed on the type.
    pub fn validate(&self) -> Result<(), SkinError> {
        let n = self.positions.len();
        let len = |what, found| {
            if found == n {
                Ok(())
            } else {
                Err(SkinError::LengthMismatch { what, expected: n, found })
            }
        };
        len("normals", self.normals.len())?;
        len("influences", self.influences.len())?;
        if let Some(uvs) = &self.uvs {
            len("texture coordinates", uvs.len())?;
        }
        if let Some(bones) = &self.bones {
            len("single-weight joints", bones.len())?;
            let joint_count = self.skeleton.len();
            if let Some((vertex, &b)) = bones.iter().enumerate().find(|(_, &b)| b as usize >= joint_count) {
                return Err(SkinError::JointOutOfRange {
                    vertex,
                    influence: 0,
                    joint: b as usize,
                    joint_count,
                });
            }
        }
        for (vertex, (p, nm)) in self.positions.iter().zip(&self.normals).enumerate() {
            if !p.is_finite() {
                return Err(SkinError::NonFiniteVertex { vertex, what: "position" });
            }
            if !nm.is_finite() {
                return Err(SkinError::NonFiniteVertex { vertex, what: "normal" });
            }
        }
        if !self.indices.len().is_multiple_of(3) {
            return Err(SkinError::LengthMismatch {
                what: "triangle indices (a multiple of 3)",
                expected: self.indices.len() / 3 * 3,
                found: self.indices.len(),
            });
        }
        if let Some((i, &index)) = self.indices.iter().enumerate().find(|(_, &i)| i as usize >= n) {
            return Err(SkinError::TriangleIndexOutOfRange { triangle: i / 3, index, vertex_count: n });
        }
        self.influences.check_joint_count(self.skeleton.len())
    }

    /// Replaces the rest skeleton (e.g. by the scene object's own, possibly edited, one),
    /// keeping the weights; fails if a joint index no longer exists.
    pub fn with_skeleton(mut self, skeleton: RestSkeleton) -> Result<Self, SkinError> {
        self.skeleton = skeleton;
        self.validate()?;
        Ok(self)
    }

    /// Scales the mesh to `skeleton`, a skeleton of the same shape in other units (e.g. the
    /// paper's arms, built in centimetres, on a scene skeleton in metres), and binds it to it.
    ///
    /// The factor is the ratio of the summed parent-to-joint distances (the chain's length);
    /// positions are scaled only when both skeletons have the same number of joints and a
    /// non-zero length. Normals are unchanged by a uniform scale.
    pub fn fit_to_skeleton(mut self, skeleton: RestSkeleton) -> Result<Self, SkinError> {
        let chain_length = |s: &RestSkeleton| -> f32 {
            s.parents()
                .iter()
                .zip(s.parent_from_joint())
                .filter(|(parent, _)| parent.is_some())
                .map(|(_, a)| a.translation.length())
                .sum()
        };
        let (own, target) = (chain_length(&self.skeleton), chain_length(&skeleton));
        if self.skeleton.len() == skeleton.len() && own > 0.0 && target > 0.0 {
            let factor = target / own;
            if (factor - 1.0).abs() > 1e-6 {
                for p in &mut self.positions {
                    *p *= factor;
                }
            }
        }
        self.with_skeleton(skeleton)
    }

    /// Number of vertices.
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.positions.len()
    }

    /// The rigid and bones-blending bindings for a blend zone: from the single weights when the
    /// mesh has them (nearest joint of the vertex's bone), else from the two dominant
    /// influences.
    pub fn bindings(&self, zone: BlendZone) -> Result<MeshBindings, SkinError> {
        match &self.bones {
            Some(bones) => Ok(MeshBindings {
                rigid: bones.clone(),
                bones_blending: BonesBlendBindings::new(
                    bind_single_weights(&self.skeleton, &self.positions, bones, zone)?,
                    self.skeleton.parents(),
                )?,
            }),
            None => Ok(MeshBindings {
                rigid: (self.influences.joints().iter().zip(self.influences.weights()))
                    .map(|(js, ws)| js[dominant(ws)])
                    .collect(),
                bones_blending: BonesBlendBindings::new(
                    bind_from_weights(&self.skeleton, self.influences.joints(), self.influences.weights())?,
                    self.skeleton.parents(),
                )?,
            }),
        }
    }
}

fn dominant(ws: &[f32; 4]) -> usize {
    (1..4).fold(0, |best, i| if ws[i] > ws[best] { i } else { best })
}

/// Area-weighted vertex normals of a triangle list (unit length; zero for unused vertices).
#[must_use]
pub fn vertex_normals(positions: &[Vec3], indices: &[u32]) -> Vec<Vec3> {
    let mut normals = vec![Vec3::ZERO; positions.len()];
    for tri in indices.chunks_exact(3) {
        let [a, b, c] = [tri[0] as usize, tri[1] as usize, tri[2] as usize];
        if a >= positions.len() || b >= positions.len() || c >= positions.len() {
            continue;
        }
        let n = (positions[b] - positions[a]).cross(positions[c] - positions[a]);
        normals[a] += n;
        normals[b] += n;
        normals[c] += n;
    }
    normals.iter().map(|n| n.normalize_or_zero()).collect()
}

/// A closed circular tube of `radius` along +X from 0 to `length`: `rings` evenly spaced rings
/// of `sides` vertices, capped at both ends, counter-clockwise from outside. Returns positions
/// and the triangle list (for the binding tests and benchmarks).
#[must_use]
pub fn tube_mesh(rings: usize, sides: usize, length: f32, radius: f32) -> (Vec<Vec3>, Vec<u32>) {
    let (mut positions, mut indices) = (Vec::new(), Vec::new());
    let step = length / (rings.max(2) - 1) as f32;
    let angle = move |k: usize| std::f32::consts::TAU * k as f32 / sides as f32;
    tube(
        rings.max(2),
        sides.max(3),
        |i| Vec3::X * (i as f32 * step),
        |k| {
            let (s, c) = angle(k).sin_cos();
            (radius * c, radius * s)
        },
        &mut positions,
        &mut indices,
    );
    (positions, indices)
}

/// A closed tube: `rings` rings of `sides` vertices each, ring i at `centre(i)` with the
/// cross-section `section(k)` (in the ring's YZ plane), both ends capped by a fan without an
/// extra vertex. Returns positions and indices; (rings − 1)·sides·2 + 2·(sides − 2) triangles.
fn tube(
    rings: usize,
    sides: usize,
    centre: impl Fn(usize) -> Vec3,
    section: impl Fn(usize) -> (f32, f32),
    positions: &mut Vec<Vec3>,
    indices: &mut Vec<u32>,
) {
    let base = positions.len() as u32;
    for i in 0..rings {
        let c = centre(i);
        for k in 0..sides {
            let (y, z) = section(k);
            positions.push(c + Vec3::new(0.0, y, z));
        }
    }
    let at = |i: usize, k: usize| base + (i * sides + k % sides) as u32;
    for i in 0..rings - 1 {
        for k in 0..sides {
            let (a, b, c, d) = (at(i, k), at(i, k + 1), at(i + 1, k + 1), at(i + 1, k));
            indices.extend_from_slice(&[a, b, c, a, c, d]);
        }
    }
    for k in 1..sides - 1 {
        // First cap faces −X, last cap +X.
        indices.extend_from_slice(&[at(0, 0), at(0, k + 1), at(0, k)]);
        indices.extend_from_slice(&[at(rings - 1, 0), at(rings - 1, k), at(rings - 1, k + 1)]);
    }
}

/// An elliptical cross-section of `sides` vertices at angles 2πk/sides whose bounding box is
/// exactly `extent_y` × `extent_z`.
fn ellipse(sides: usize, extent_y: f32, extent_z: f32) -> impl Fn(usize) -> (f32, f32) {
    let angle = move |k: usize| std::f32::consts::TAU * k as f32 / sides as f32;
    let (mut cmin, mut cmax, mut smin, mut smax) = (f32::MAX, f32::MIN, f32::MAX, f32::MIN);
    for k in 0..sides {
        let (s, c) = angle(k).sin_cos();
        cmin = cmin.min(c);
        cmax = cmax.max(c);
        smin = smin.min(s);
        smax = smax.max(s);
    }
    let a = extent_y / (cmax - cmin);
    let b = extent_z / (smax - smin);
    move |k| {
        let (s, c) = angle(k).sin_cos();
        (a * c, b * s)
    }
}

/// The arm skeleton of the paper's test as a scene skeleton: 4 un-animated joints along +X.
#[must_use]
pub fn arm_scene_skeleton() -> Skeleton {
    let bone = ARM_LENGTH_CM / ARM_BONES as f32;
    let joints = (0..ARM_BONES)
        .map(|j| {
            let rest_translation = if j == 0 { Vec3::ZERO } else { Vec3::new(bone, 0.0, 0.0) };
            Joint::new(ARM_JOINT_NAMES[j], j.checked_sub(1), rest_translation, Quat::IDENTITY)
        })
        .collect();
    Skeleton::new(joints)
}

/// Palm length (cm) of the hand and the finger geometry.
const PALM_LENGTH: f32 = 9.0;
const FINGER_OFFSETS_Z: [f32; 3] = [-2.7, 0.0, 2.7];
const PHALANX_LENGTH: f32 = 4.0;

/// The hand's scene skeleton: `palm` (root) with three fingers of two phalanges each, so the
/// palm's end is a joint with three children.
#[must_use]
pub fn hand_scene_skeleton() -> Skeleton {
    let mut joints = vec![Joint::new("palm", None, Vec3::ZERO, Quat::IDENTITY)];
    for (f, z) in FINGER_OFFSETS_Z.iter().enumerate() {
        let base = joints.len();
        joints.push(Joint::new(
            format!("finger{f}.0"),
            Some(0),
            Vec3::new(PALM_LENGTH, 0.0, *z),
            Quat::IDENTITY,
        ));
        joints.push(Joint::new(
            format!("finger{f}.1"),
            Some(base),
            Vec3::new(PHALANX_LENGTH, 0.0, 0.0),
            Quat::IDENTITY,
        ));
    }
    Skeleton::new(joints)
}

/// The rest skeleton of a procedural mesh as a scene skeleton, for building scenes; `None` for
/// the cube, which has no skeleton.
#[must_use]
pub fn scene_skeleton_for(kind: ProceduralMesh) -> Option<Skeleton> {
    match kind {
        ProceduralMesh::ArmLowPoly | ProceduralMesh::ArmHighPoly => Some(arm_scene_skeleton()),
        ProceduralMesh::Hand => Some(hand_scene_skeleton()),
        ProceduralMesh::Cube | ProceduralMesh::Sphere | ProceduralMesh::Plane => None,
    }
}

fn arm(rings: usize, sides: usize, extent_y: f32, extent_z: f32) -> SkinnedMesh {
    let mut positions = Vec::with_capacity(rings * sides);
    let mut indices = Vec::new();
    let spacing = ARM_LENGTH_CM / (rings - 1) as f32;
    tube(
        rings,
        sides,
        |i| Vec3::new(i as f32 * spacing, 0.0, 0.0),
        ellipse(sides, extent_y, extent_z),
        &mut positions,
        &mut indices,
    );
    // Ring i lies on bone ⌊4i/(rings − 1)⌋ (a ring exactly at a joint belongs to the child bone).
    let bones: Vec<u16> = (0..rings)
        .flat_map(|i| std::iter::repeat_n(((ARM_BONES * i) / (rings - 1)).min(ARM_BONES - 1) as u16, sides))
        .collect();
    let normals = vertex_normals(&positions, &indices);
    let skeleton =
        RestSkeleton::from_scene(&arm_scene_skeleton()).expect("the arm skeleton is valid by construction");
    SkinnedMesh::from_single_weights(positions, normals, indices, bones, skeleton, BlendZone::default())
        .expect("the arm mesh is valid by construction")
}

fn hand() -> SkinnedMesh {
    let mut positions = Vec::new();
    let mut indices = Vec::new();
    let mut bones = Vec::new();
    let palm_rings = 7;
    tube(
        palm_rings,
        12,
        |i| Vec3::new(PALM_LENGTH * i as f32 / (palm_rings - 1) as f32, 0.0, 0.0),
        ellipse(12, 3.0, 8.4),
        &mut positions,
        &mut indices,
    );
    bones.resize(positions.len(), 0u16);
    let finger_rings = 9;
    let finger_start = PALM_LENGTH - 1.0;
    let finger_length = 1.0 + 2.0 * PHALANX_LENGTH;
    for (f, z) in FINGER_OFFSETS_Z.iter().enumerate() {
        let first = positions.len();
        tube(
            finger_rings,
            8,
            |i| Vec3::new(finger_start + finger_length * i as f32 / (finger_rings - 1) as f32, 0.0, *z),
            ellipse(8, 1.6, 1.8),
            &mut positions,
            &mut indices,
        );
        let (j0, j1) = (1 + 2 * f as u16, 2 + 2 * f as u16);
        bones.extend(positions[first..].iter().map(|p| {
            if p.x < PALM_LENGTH {
                0
            } else if p.x < PALM_LENGTH + PHALANX_LENGTH {
                j0
            } else {
                j1
            }
        }));
    }
    let normals = vertex_normals(&positions, &indices);
    let skeleton =
        RestSkeleton::from_scene(&hand_scene_skeleton()).expect("the hand skeleton is valid by construction");
    SkinnedMesh::from_single_weights(positions, normals, indices, bones, skeleton, BlendZone::default())
        .expect("the hand mesh is valid by construction")
}

fn cube() -> SkinnedMesh {
    let mut positions = Vec::with_capacity(24);
    let mut normals = Vec::with_capacity(24);
    let mut indices = Vec::with_capacity(36);
    for axis in 0..3 {
        for n in [-Vec3::AXES[axis], Vec3::AXES[axis]] {
            // (n, u, v) right-handed: the corners below go counter-clockwise seen from outside.
            let u = Vec3::AXES[(axis + 1) % 3];
            let v = n.cross(u);
            let base = positions.len() as u32;
            for corner in [-u - v, u - v, u + v, v - u] {
                positions.push(0.5 * (n + corner));
                normals.push(n);
            }
            indices.extend_from_slice(&[base, base + 1, base + 2, base, base + 2, base + 3]);
        }
    }
    let skeleton =
        RestSkeleton::new(&[crate::skeleton::RestJoint::new("root", None, Vec3::ZERO, Quat::IDENTITY)])
            .expect("a one-joint skeleton is valid");
    let n = positions.len();
    SkinnedMesh::new(
        positions,
        normals,
        indices,
        vec![[0; 4]; n],
        vec![[1.0, 0.0, 0.0, 0.0]; n],
        Some(vec![0; n]),
        skeleton,
    )
    .expect("the cube is valid by construction")
}

/// Builds a procedural mesh with its rest skeleton (the arms and the hand: single weights plus
/// smooth derived weights for the default blend zone; the cube: one root joint).
#[must_use]
pub fn mesh_for(kind: ProceduralMesh) -> SkinnedMesh {
    match kind {
        // 13 rings × 6 = 78 vertices, 152 triangles, 50.178 × 40.12 cm.
        ProceduralMesh::ArmLowPoly => arm(13, 6, 50.178, 40.12),
        // 50 rings × 25 = 1250 vertices, 2496 triangles, 43.744 × 40.12 cm.
        ProceduralMesh::ArmHighPoly => arm(50, 25, 43.744, 40.12),
        ProceduralMesh::Hand => hand(),
        ProceduralMesh::Cube => cube(),
        ProceduralMesh::Sphere => sphere(16, 32),
        ProceduralMesh::Plane => plane(),
    }
}

/// A mesh bound rigidly to one root joint at the origin (the cube, the sphere, the plane).
fn rigid(positions: Vec<Vec3>, normals: Vec<Vec3>, indices: Vec<u32>) -> SkinnedMesh {
    let skeleton =
        RestSkeleton::new(&[crate::skeleton::RestJoint::new("root", None, Vec3::ZERO, Quat::IDENTITY)])
            .expect("a one-joint skeleton is valid");
    let n = positions.len();
    SkinnedMesh::new(
        positions,
        normals,
        indices,
        vec![[0; 4]; n],
        vec![[1.0, 0.0, 0.0, 0.0]; n],
        Some(vec![0; n]),
        skeleton,
    )
    .expect("a rigid primitive is valid by construction")
}

/// A UV sphere of radius 0.5: a vertex at each pole and `rings` rings of `segments` vertices
/// between them (at polar angles π·i/(rings + 1)), normals pointing out; triangles wind
/// counter-clockwise seen from outside.
fn sphere(rings: usize, segments: usize) -> SkinnedMesh {
    use std::f32::consts::{PI, TAU};
    let mut normals = vec![Vec3::Y];
    for i in 1..=rings {
        let polar = PI * i as f32 / (rings + 1) as f32;
        for s in 0..segments {
            let azimuth = TAU * s as f32 / segments as f32;
            normals.push(Vec3::new(polar.sin() * azimuth.cos(), polar.cos(), -polar.sin() * azimuth.sin()));
        }
    }
    normals.push(-Vec3::Y);
    let positions: Vec<Vec3> = normals.iter().map(|n| *n * 0.5).collect();
    let (top, bottom) = (0u32, (normals.len() - 1) as u32);
    let at = |ring: usize, s: usize| (1 + ring * segments + s % segments) as u32;
    let mut indices = Vec::with_capacity(6 * rings * segments);
    for s in 0..segments {
        indices.extend_from_slice(&[top, at(0, s), at(0, s + 1)]);
        indices.extend_from_slice(&[bottom, at(rings - 1, s + 1), at(rings - 1, s)]);
    }
    for r in 0..rings - 1 {
        for s in 0..segments {
            let (a, b, c, d) = (at(r, s), at(r, s + 1), at(r + 1, s), at(r + 1, s + 1));
            indices.extend_from_slice(&[a, c, d, a, d, b]);
        }
    }
    rigid(positions, normals, indices)
}

/// A 1 × 1 square in the XZ plane, facing +Y.
fn plane() -> SkinnedMesh {
    let positions = vec![
        Vec3::new(-0.5, 0.0, 0.5),
        Vec3::new(0.5, 0.0, 0.5),
        Vec3::new(0.5, 0.0, -0.5),
        Vec3::new(-0.5, 0.0, -0.5),
    ];
    rigid(positions, vec![Vec3::Y; 4], vec![0, 1, 2, 0, 2, 3])
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Each triangle of a closed primitive faces outward: its counter-clockwise normal points
    /// away from the centre; the sphere's vertices lie on radius 0.5 with outward unit normals,
    /// and the plane faces +Y.
    #[test]
    fn sphere_and_plane_have_their_shapes_and_face_out() {
        let sphere = mesh_for(ProceduralMesh::Sphere);
        assert_eq!(sphere.positions.len(), 2 + 16 * 32);
        assert_eq!(sphere.indices.len(), 3 * (2 * 32 + 2 * 32 * 15));
        for (p, n) in sphere.positions.iter().zip(&sphere.normals) {
            assert!((p.length() - 0.5).abs() < 1e-5 && (n.length() - 1.0).abs() < 1e-5);
            assert!(p.normalize().dot(*n) > 0.9999);
        }
        for t in sphere.indices.chunks(3) {
            let [a, b, c] = [0, 1, 2].map(|i| sphere.positions[t[i] as usize]);
            let facing = (b - a).cross(c - a);
            assert!(facing.dot((a + b + c) / 3.0) > 0.0, "triangle {t:?} faces in");
        }
        let plane = mesh_for(ProceduralMesh::Plane);
        let [a, b, c] = [0, 1, 2].map(|i| plane.positions[plane.indices[i] as usize]);
        assert!((b - a).cross(c - a).normalize().dot(Vec3::Y) > 0.9999, "the plane faces +Y");
        assert!(plane.positions.iter().all(|p| p.y == 0.0 && p.x.abs() == 0.5 && p.z.abs() == 0.5));
        assert!(scene_skeleton_for(ProceduralMesh::Sphere).is_none());
    }

    /// The hand: a palm tube of 7 rings of 12 vertices along x ∈ [0, 9] and three finger tubes
    /// of 9 rings of 8 vertices from x = 8 (1 cm inside the palm) to x = 17; finger vertices
    /// inside the palm follow the palm (joint 0), the next 4 cm the finger's first joint, the
    /// rest its second. The cube: 24 vertices on the faces of [−0.5, 0.5]³ with their faces'
    /// normals.
    #[test]
    fn hand_and_cube_have_their_shapes() {
        let hand = mesh_for(ProceduralMesh::Hand);
        assert_eq!(hand.vertex_count(), 7 * 12 + 3 * 9 * 8);
        let xs = hand.positions.iter().map(|p| p.x);
        let (min, max) = xs.fold((f32::MAX, f32::MIN), |(lo, hi), x| (lo.min(x), hi.max(x)));
        assert!(min.abs() < 1e-5 && (max - 17.0).abs() < 1e-5, "x from {min} to {max}");
        let bones = hand.bones.as_ref().unwrap();
        let count = |j: u16| bones.iter().filter(|&&b| b == j).count();
        assert_eq!(count(0), 7 * 12 + 3 * 8);
        for j in 1..=6 {
            assert_eq!(count(j), 4 * 8, "joint {j}");
        }
        let cube = mesh_for(ProceduralMesh::Cube);
        assert_eq!((cube.vertex_count(), cube.indices.len()), (24, 36));
        for (p, n) in cube.positions.iter().zip(&cube.normals) {
            assert_eq!(n.abs().max_element(), 1.0, "{n}");
            assert_eq!(n.length(), 1.0, "{n}");
            assert_eq!(p.dot(*n), 0.5, "{p} on the face of {n}");
            assert_eq!(p.abs(), Vec3::splat(0.5), "{p} is a corner");
        }
        // Four different corners on each face.
        for (i, (p, n)) in cube.positions.iter().zip(&cube.normals).enumerate() {
            for (q, m) in cube.positions.iter().zip(&cube.normals).skip(i + 1) {
                assert!(p != q || n != m, "corner {p} twice on the face of {n}");
            }
        }
    }

    /// Normals are the area-weighted sums of the adjacent triangles' normals, normalized; a
    /// triangle with an index past the positions is skipped and an unused vertex gets zero.
    #[test]
    fn vertex_normals_weight_triangles_by_area() {
        // Away from the origin: normals do not depend on where the mesh lies.
        let positions = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::new(0.0, 0.0, -2.0), Vec3::ONE]
            .map(|p| p + Vec3::new(1.0, 2.0, 3.0));
        // (0, 1, 2): normal +Z, twice its area 1; (0, 3, 1): normal −Y, twice its area 2.
        let normals = vertex_normals(&positions, &[0, 1, 2, 0, 3, 1, 0, 1, 9]);
        let shared = Vec3::new(0.0, -2.0, 1.0).normalize();
        let expected = [shared, shared, Vec3::Z, Vec3::NEG_Y, Vec3::ZERO];
        for (v, (n, e)) in normals.iter().zip(expected).enumerate() {
            assert!((*n - e).length() < 1e-6, "vertex {v}: {n} vs {e}");
        }
        assert_eq!(normals.len(), 5);
    }

    /// Every invariant of a mesh is checked, and each error names what and where.
    #[test]
    fn bad_meshes_are_typed_errors() {
        let cube = mesh_for(ProceduralMesh::Cube);
        let n = cube.vertex_count();
        let (joints, weights) = (cube.influences.joints().to_vec(), cube.influences.weights().to_vec());
        let build = |edit: &dyn Fn(&mut SkinnedMesh)| {
            let mut mesh = cube.clone();
            edit(&mut mesh);
            mesh.validate()
        };
        assert_eq!(build(&|_| {}), Ok(()));
        let length = |what, found| Err(SkinError::LengthMismatch { what, expected: n, found });
        assert_eq!(build(&|m| m.normals.truncate(n - 1)), length("normals", n - 1));
        assert_eq!(
            build(
                &|m| m.influences = Influences::new(joints[1..].to_vec(), weights[1..].to_vec(), 1).unwrap()
            ),
            length("influences", n - 1)
        );
        assert_eq!(build(&|m| m.uvs = Some(vec![Vec2::ZERO; 2])), length("texture coordinates", 2));
        assert_eq!(build(&|m| m.bones = Some(vec![0; 3])), length("single-weight joints", 3));
        assert_eq!(
            build(&|m| m.bones.as_mut().unwrap()[5] = 1),
            Err(SkinError::JointOutOfRange { vertex: 5, influence: 0, joint: 1, joint_count: 1 })
        );
        assert_eq!(
            build(&|m| m.positions[4].y = f32::NAN),
            Err(SkinError::NonFiniteVertex { vertex: 4, what: "position" })
        );
        assert_eq!(
            build(&|m| m.normals[6].z = f32::INFINITY),
            Err(SkinError::NonFiniteVertex { vertex: 6, what: "normal" })
        );
        assert_eq!(
            build(&|m| m.indices.push(0)),
            Err(SkinError::LengthMismatch {
                what: "triangle indices (a multiple of 3)",
                expected: 36,
                found: 37
            })
        );
        assert_eq!(
            build(&|m| m.indices[7] = n as u32),
            Err(SkinError::TriangleIndexOutOfRange { triangle: 2, index: n as u32, vertex_count: n })
        );
        // The same checks when a mesh is made or given texture coordinates or a skeleton.
        assert_eq!(
            cube.clone().with_uvs(vec![Vec2::ZERO; n + 1]).map(|_| ()),
            length("texture coordinates", n + 1)
        );
        assert_eq!(
            cube.clone().with_uvs(vec![Vec2::ONE; n]).map(|m| m.uvs.map(|uvs| uvs.len())),
            Ok(Some(n))
        );
        let two = RestSkeleton::new(&[
            crate::skeleton::RestJoint::new("root", None, Vec3::ZERO, Quat::IDENTITY),
            crate::skeleton::RestJoint::new("tip", Some(0), Vec3::X, Quat::IDENTITY),
        ])
        .unwrap();
        let mut on_two = cube.clone().with_skeleton(two.clone()).unwrap();
        on_two.bones = Some(vec![1; n]);
        assert_eq!(
            on_two.with_skeleton(cube.skeleton.clone()).map(|_| ()),
            Err(SkinError::JointOutOfRange { vertex: 0, influence: 0, joint: 1, joint_count: 1 })
        );
        assert_eq!(
            SkinnedMesh::new(
                cube.positions.clone(),
                cube.normals[1..].to_vec(),
                cube.indices.clone(),
                joints,
                weights,
                None,
                two
            )
            .map(|_| ()),
            length("normals", n - 1)
        );
    }

    fn extent(mesh: &SkinnedMesh) -> Vec3 {
        let min = mesh.positions.iter().fold(Vec3::MAX, |a, &b| a.min(b));
        let max = mesh.positions.iter().fold(Vec3::MIN, |a, &b| a.max(b));
        max - min
    }

    /// A scene skeleton's rest rotations must be unit quaternions (within the tolerance, then
    /// normalized); the error names the joint and the length.
    #[test]
    fn scene_skeletons_need_unit_rest_rotations() {
        let mut scene = arm_scene_skeleton();
        scene.joints[2].rest_rotation = Quat::from_xyzw(0.0, 0.0, 0.0, 2.0);
        assert_eq!(
            RestSkeleton::from_scene(&scene),
            Err(SkinError::NonUnitRestRotation { joint: 2, name: ARM_JOINT_NAMES[2].into(), length: 2.0 })
        );
        // Within the tolerance (1e-3), the rotation is normalized.
        scene.joints[2].rest_rotation = Quat::from_xyzw(0.0, 0.6, 0.0, 0.8) * 1.0005;
        let rest = RestSkeleton::from_scene(&scene).unwrap();
        let det = rest.parent_from_joint()[2].matrix3.determinant();
        assert!((det - 1.0).abs() < 1e-5, "determinant {det}");
    }

    #[test]
    fn fit_to_skeleton_scales_to_a_metre_skeleton_and_binds_it() {
        let native = mesh_for(ProceduralMesh::ArmLowPoly);
        let mut metres = arm_scene_skeleton();
        for joint in &mut metres.joints {
            joint.rest_translation *= 0.01;
        }
        let rest = RestSkeleton::from_scene(&metres).unwrap();
        let fitted = native.clone().fit_to_skeleton(rest.clone()).unwrap();
        assert_eq!(fitted.skeleton, rest);
        for (a, b) in native.positions.iter().zip(&fitted.positions) {
            assert!((*a * 0.01 - *b).length() < 1e-5, "{a} * 0.01 != {b}");
        }
        assert_eq!(fitted.normals, native.normals);
        // A skeleton of the same length keeps the positions bit for bit.
        let same = native.clone().fit_to_skeleton(native.skeleton.clone()).unwrap();
        assert_eq!(same.positions, native.positions);
        // A skeleton of another shape keeps the size but must still hold every joint index.
        let hand = RestSkeleton::from_scene(&hand_scene_skeleton()).unwrap();
        let on_hand = native.clone().fit_to_skeleton(hand).unwrap();
        assert_eq!(on_hand.positions, native.positions);
    }

    #[test]
    fn arms_match_the_paper() {
        let low = mesh_for(ProceduralMesh::ArmLowPoly);
        assert_eq!(low.vertex_count(), 78);
        assert_eq!(low.indices.len() / 3, 152);
        assert!(extent(&low).abs_diff_eq(Vec3::new(160.158, 50.178, 40.12), 1e-3), "{}", extent(&low));
        let high = mesh_for(ProceduralMesh::ArmHighPoly);
        assert_eq!(high.vertex_count(), 1250);
        assert_eq!(high.indices.len() / 3, 2496);
        assert!(extent(&high).abs_diff_eq(Vec3::new(160.158, 43.744, 40.12), 1e-3), "{}", extent(&high));
        assert_eq!(high.skeleton.len(), 4);
        assert!((high.skeleton.rest_position(3).x - 3.0 * 40.0395).abs() < 1e-3);
    }

    #[test]
    fn procedural_meshes_are_closed_and_outward() {
        // (The cube has split vertices per face for its hard normals; its volume is checked below.)
        for kind in [
            ProceduralMesh::ArmLowPoly,
            ProceduralMesh::ArmHighPoly,
            ProceduralMesh::Hand,
            ProceduralMesh::Sphere,
        ] {
            let mesh = mesh_for(kind);
            mesh.validate().unwrap();
            // Every edge is used once in each direction.
            let mut edges = std::collections::HashMap::new();
            for t in mesh.indices.chunks_exact(3) {
                for (a, b) in [(t[0], t[1]), (t[1], t[2]), (t[2], t[0])] {
                    *edges.entry((a, b)).or_insert(0) += 1;
                }
            }
            for (&(a, b), &count) in &edges {
                assert_eq!(count, 1, "{kind:?}: edge {a}->{b}");
                assert_eq!(edges.get(&(b, a)), Some(&1), "{kind:?}: edge {b}->{a} missing");
            }
            let volume = crate::measure::enclosed_volume(&mesh.positions, &mesh.indices).unwrap();
            assert!(volume > 0.0, "{kind:?}: volume {volume}");
        }
        let cube = mesh_for(ProceduralMesh::Cube);
        assert!(
            (crate::measure::enclosed_volume(&cube.positions, &cube.indices).unwrap() - 1.0).abs() < 1e-6
        );
    }

    #[test]
    fn hand_palm_end_is_a_branching_joint() {
        let hand = mesh_for(ProceduralMesh::Hand);
        assert_eq!(hand.skeleton.children(0), &[1, 3, 5]);
        let bindings = hand.bindings(BlendZone::default()).unwrap();
        // Palm vertices at the far end bind to the finger base nearest to them.
        for (v, p) in hand.positions.iter().enumerate() {
            if hand.bones.as_ref().unwrap()[v] == 0 && p.x > PALM_LENGTH - 0.01 && p.x < PALM_LENGTH + 0.01 {
                let expected = if p.z < -1.35 {
                    1
                } else if p.z > 1.35 {
                    5
                } else {
                    3
                };
                assert_eq!(bindings.bones_blending[v].joint, expected, "vertex {v} at {p}");
            }
        }
        assert!(scene_skeleton_for(ProceduralMesh::Cube).is_none());
        assert_eq!(scene_skeleton_for(ProceduralMesh::Hand).unwrap().joints.len(), 7);
    }
}
