//! An independent glTF 2.0 evaluator, written from the specification alone, shared by the
//! tests that compare keyrig with glTF files (`gltf_reference`, `export_roundtrip`,
//! `export_bake`). It does not use keyrig-io's importer:
//!
//! - files are read with the `gltf` crate's own importer and accessor readers;
//! - samplers follow the specification's Appendix C in f64: STEP holds, LINEAR lerps
//!   translations, scales and weights and slerps rotations the short way, CUBICSPLINE is the
//!   Hermite `h00·v_k + h10·t_d·b_k + h01·v_{k+1} + h11·t_d·a_{k+1}` (rotations normalized after
//!   it); times outside the keys clamp. [`Interpolator::Blender`] evaluates instead the way
//!   Blender 3.4 imports a file: tangents ignored (CUBICSPLINE as linear between the values),
//!   rotations blended component-wise and normalized, no sign alignment;
//! - node matrices `T·R·S` are composed from the scene root down in f64; a mesh is morphed
//!   (`base + Σ wᵢ·Δᵢ`, weights from the node's channel, else the node's or the mesh's
//!   defaults), then skinned (`Σ wᵢ·jointMatrix(jᵢ)·v`, `jointMatrix = globalTransform(joint) ·
//!   inverseBindMatrix`, weights of every JOINTS_n/WEIGHTS_n set normalized to sum 1) or placed
//!   by the node's global transform.
#![allow(dead_code)]

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::{DMat4, DQuat, DVec3, Vec3};
use gltf::animation::util::ReadOutputs;
use gltf::animation::{Interpolation, Property};

/// A file of the external corpus (`tests/corpus/`).
#[must_use]
pub fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("corpus").join(rel)
}

/// How LINEAR and CUBICSPLINE samplers are read.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Interpolator {
    /// The glTF 2.0 specification (Appendix C).
    Spec,
    /// Blender 3.4's importer: tangents ignored, quaternions lerped component-wise.
    Blender,
}

/// One animation channel as the specification reads it.
pub struct Channel {
    pub node: usize,
    pub property: Property,
    pub interpolation: Interpolation,
    pub times: Vec<f64>,
    /// Values per key: 3 or 4 components, or one per morph target; CUBICSPLINE stores
    /// (in-tangent, value, out-tangent).
    pub values: Vec<Vec<f64>>,
}

pub struct Reference {
    pub parents: Vec<Option<usize>>,
    pub rest: Vec<(DVec3, DQuat, DVec3)>,
    /// Default morph weights per node (the node's, else its mesh's; empty without a mesh).
    pub default_weights: Vec<Vec<f64>>,
    pub animations: Vec<Vec<Channel>>,
}

/// Reads a file's node hierarchy and animations.
#[must_use]
pub fn read_reference(doc: &gltf::Document, buffers: &[gltf::buffer::Data]) -> Reference {
    let mut parents = vec![None; doc.nodes().len()];
    for node in doc.nodes() {
        for child in node.children() {
            parents[child.index()] = Some(node.index());
        }
    }
    let rest = doc
        .nodes()
        .map(|n| {
            let (t, r, s) = n.transform().decomposed();
            (
                DVec3::from(Vec3::from(t)),
                DQuat::from_xyzw(r[0].into(), r[1].into(), r[2].into(), r[3].into()),
                DVec3::from(Vec3::from(s)),
            )
        })
        .collect();
    let default_weights = doc
        .nodes()
        .map(|n| {
            let w = n.weights().or_else(|| n.mesh().and_then(|m| m.weights())).unwrap_or(&[]);
            let targets =
                n.mesh().map_or(0, |m| m.primitives().map(|p| p.morph_targets().count()).max().unwrap_or(0));
            (0..targets).map(|i| w.get(i).map_or(0.0, |&x| f64::from(x))).collect()
        })
        .collect();
    let animations = doc
        .animations()
        .map(|anim| {
            anim.channels()
                .filter_map(|channel| {
                    let reader = channel.reader(|b| Some(&buffers[b.index()]));
                    let times: Vec<f64> = reader.read_inputs()?.map(f64::from).collect();
                    let values: Vec<Vec<f64>> = match reader.read_outputs()? {
                        ReadOutputs::Translations(it) | ReadOutputs::Scales(it) => {
                            it.map(|v| v.iter().map(|&x| f64::from(x)).collect()).collect()
                        }
                        // The specification stores rotations as unit quaternions; files round
                        // them (SimpleSkin's keys are 2e-4 off unit length), so value keys are
                        // normalized before interpolating, as a rotation must be (tangents are
                        // not rotations and stay as stored).
                        ReadOutputs::Rotations(it) => {
                            let cubic = channel.sampler().interpolation() == Interpolation::CubicSpline;
                            it.into_f32()
                                .enumerate()
                                .map(|(i, v)| {
                                    let q: Vec<f64> = v.iter().map(|&x| f64::from(x)).collect();
                                    if cubic && i % 3 != 1 {
                                        return q;
                                    }
                                    let len = q.iter().map(|x| x * x).sum::<f64>().sqrt();
                                    q.iter().map(|x| x / len).collect()
                                })
                                .collect()
                        }
                        ReadOutputs::MorphTargetWeights(w) => {
                            let flat: Vec<f64> = w.into_f32().map(f64::from).collect();
                            let per_key = if channel.sampler().interpolation() == Interpolation::CubicSpline {
                                3 * times.len()
                            } else {
                                times.len()
                            };
                            let n = flat.len() / per_key.max(1);
                            flat.chunks(n.max(1)).map(<[f64]>::to_vec).collect()
                        }
                    };
                    Some(Channel {
                        node: channel.target().node().index(),
                        property: channel.target().property(),
                        interpolation: channel.sampler().interpolation(),
                        times,
                        values,
                    })
                })
                .collect()
        })
        .collect();
    Reference { parents, rest, default_weights, animations }
}

fn hermite(u: f64) -> [f64; 4] {
    let (u2, u3) = (u * u, u * u * u);
    [2.0 * u3 - 3.0 * u2 + 1.0, u3 - 2.0 * u2 + u, -2.0 * u3 + 3.0 * u2, u3 - u2]
}

fn normalized(mut p: Vec<f64>) -> Vec<f64> {
    let len = p.iter().map(|x| x * x).sum::<f64>().sqrt();
    p.iter_mut().for_each(|x| *x /= len);
    p
}

/// The sampler of `c` at time `t`.
#[must_use]
pub fn sample(c: &Channel, t: f64, how: Interpolator) -> Vec<f64> {
    let cubic = c.interpolation == Interpolation::CubicSpline;
    let value = |k: usize| if cubic { c.values[3 * k + 1].clone() } else { c.values[k].clone() };
    let n = c.times.len();
    if t <= c.times[0] {
        return value(0);
    }
    if t >= c.times[n - 1] {
        return value(n - 1);
    }
    let k = c.times.partition_point(|&x| x <= t) - 1;
    let td = c.times[k + 1] - c.times[k];
    let u = (t - c.times[k]) / td;
    let (a, b) = (value(k), value(k + 1));
    let rotation = c.property == Property::Rotation;
    let lerp = |a: &[f64], b: &[f64]| -> Vec<f64> { a.iter().zip(b).map(|(x, y)| x + u * (y - x)).collect() };
    match (c.interpolation, how) {
        (Interpolation::Step, _) => a,
        (_, Interpolator::Blender) if rotation => normalized(lerp(&a, &b)),
        (_, Interpolator::Blender) => lerp(&a, &b),
        (Interpolation::Linear, Interpolator::Spec) if rotation => {
            let dot: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            let sign = if dot < 0.0 { -1.0 } else { 1.0 };
            let angle = dot.abs().min(1.0).acos();
            if angle < 1e-12 {
                return a;
            }
            let (wa, wb) = (((1.0 - u) * angle).sin() / angle.sin(), sign * (u * angle).sin() / angle.sin());
            a.iter().zip(&b).map(|(x, y)| wa * x + wb * y).collect()
        }
        (Interpolation::Linear, Interpolator::Spec) => lerp(&a, &b),
        (Interpolation::CubicSpline, Interpolator::Spec) => {
            let out_tangent = &c.values[3 * k + 2];
            let in_tangent = &c.values[3 * (k + 1)];
            let h = hermite(u);
            let p: Vec<f64> = (0..a.len())
                .map(|i| h[0] * a[i] + h[1] * td * out_tangent[i] + h[2] * b[i] + h[3] * td * in_tangent[i])
                .collect();
            if rotation {
                normalized(p)
            } else {
                p
            }
        }
    }
}

impl Reference {
    /// The last key time of `animation`.
    #[must_use]
    pub fn duration(&self, animation: usize) -> f64 {
        self.animations[animation].iter().filter_map(|c| c.times.last()).fold(0.0, |a, &b| a.max(b))
    }

    /// Local TRS of every node at time `t` of `animation` (the rest pose for `None`).
    #[must_use]
    pub fn local(&self, animation: Option<usize>, t: f64, how: Interpolator) -> Vec<(DVec3, DQuat, DVec3)> {
        let mut local = self.rest.clone();
        for c in animation.map_or(&[][..], |a| &self.animations[a][..]) {
            let v = sample(c, t, how);
            match c.property {
                Property::Translation => local[c.node].0 = DVec3::new(v[0], v[1], v[2]),
                Property::Rotation => local[c.node].1 = DQuat::from_xyzw(v[0], v[1], v[2], v[3]),
                Property::Scale => local[c.node].2 = DVec3::new(v[0], v[1], v[2]),
                Property::MorphTargetWeights => {}
            }
        }
        local
    }

    /// `globalTransform` of every node at time `t` of `animation`.
    #[must_use]
    pub fn world(&self, animation: Option<usize>, t: f64, how: Interpolator) -> Vec<DMat4> {
        let local = self.local(animation, t, how);
        let mut world: Vec<Option<DMat4>> = vec![None; local.len()];
        fn resolve(
            n: usize,
            parents: &[Option<usize>],
            local: &[(DVec3, DQuat, DVec3)],
            world: &mut [Option<DMat4>],
        ) -> DMat4 {
            if let Some(m) = world[n] {
                return m;
            }
            let (t, r, s) = local[n];
            let m = DMat4::from_scale_rotation_translation(s, r, t);
            let m = match parents[n] {
                Some(p) => resolve(p, parents, local, world) * m,
                None => m,
            };
            world[n] = Some(m);
            m
        }
        (0..local.len()).map(|n| resolve(n, &self.parents, &local, &mut world)).collect()
    }

    /// Morph weights of `node` at time `t` of `animation`.
    #[must_use]
    pub fn weights(&self, node: usize, animation: Option<usize>, t: f64, how: Interpolator) -> Vec<f64> {
        animation
            .and_then(|a| {
                self.animations[a]
                    .iter()
                    .find(|c| c.node == node && c.property == Property::MorphTargetWeights)
            })
            .map_or_else(|| self.default_weights[node].clone(), |c| sample(c, t, how))
    }
}

/// A mesh node's vertices as the reference deforms them: the triangle primitives' vertices one
/// after the other, their morph targets, and the skin when the node has one.
pub struct MeshNode {
    pub node: usize,
    pub positions: Vec<DVec3>,
    /// Per morph target, the position displacement of every vertex.
    pub targets: Vec<Vec<DVec3>>,
    pub skin: Option<SkinData>,
}

pub struct SkinData {
    pub influences: Vec<Vec<(usize, f64)>>,
    pub joints: Vec<usize>,
    pub inverse_bind: Vec<DMat4>,
}

/// Reads the mesh (and skin) of `node`.
#[must_use]
pub fn mesh_node(node: &gltf::Node<'_>, buffers: &[gltf::buffer::Data]) -> MeshNode {
    let skin = node.skin().map(|skin| {
        let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
        let inverse_bind: Vec<DMat4> =
            match skin.reader(|b| Some(&buffers[b.index()])).read_inverse_bind_matrices() {
                Some(it) => it.map(|m| glam::Mat4::from_cols_array_2d(&m).as_dmat4()).collect(),
                None => vec![DMat4::IDENTITY; joints.len()],
            };
        SkinData { influences: Vec::new(), joints, inverse_bind }
    });
    let mut out = MeshNode { node: node.index(), positions: Vec::new(), targets: Vec::new(), skin };
    let mesh = node.mesh().expect("mesh");
    let target_count = mesh.primitives().map(|p| p.morph_targets().count()).max().unwrap_or(0);
    out.targets = vec![Vec::new(); target_count];
    for prim in mesh.primitives() {
        use gltf::mesh::Mode;
        if !matches!(prim.mode(), Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            continue;
        }
        let reader = prim.reader(|b| Some(&buffers[b.index()]));
        let start = out.positions.len();
        out.positions.extend(reader.read_positions().expect("positions").map(|p| DVec3::from(Vec3::from(p))));
        let n = out.positions.len() - start;
        let mut morphs = reader.read_morph_targets();
        for target in &mut out.targets {
            match morphs.next().and_then(|(p, _, _)| p) {
                Some(p) => target.extend(p.map(|d| DVec3::from(Vec3::from(d)))),
                None => target.extend(std::iter::repeat_n(DVec3::ZERO, n)),
            }
        }
        if let Some(skin) = &mut out.skin {
            skin.influences.resize(out.positions.len(), Vec::new());
            let mut set = 0;
            while let (Some(j), Some(w)) = (reader.read_joints(set), reader.read_weights(set)) {
                for (v, (j, w)) in j.into_u16().zip(w.into_f32()).enumerate() {
                    for i in 0..4 {
                        if w[i] != 0.0 {
                            skin.influences[start + v].push((usize::from(j[i]), f64::from(w[i])));
                        }
                    }
                }
                set += 1;
            }
        }
    }
    out
}

impl MeshNode {
    /// World positions at the pose `world` with morph weights `weights`.
    #[must_use]
    pub fn deform(&self, world: &[DMat4], weights: &[f64]) -> Vec<DVec3> {
        let mut morphed = self.positions.clone();
        for (target, &w) in self.targets.iter().zip(weights) {
            if w != 0.0 {
                for (p, d) in morphed.iter_mut().zip(target) {
                    *p += w * *d;
                }
            }
        }
        match &self.skin {
            None => morphed.iter().map(|p| world[self.node].transform_point3(*p)).collect(),
            Some(skin) => {
                let matrices: Vec<DMat4> =
                    skin.joints.iter().zip(&skin.inverse_bind).map(|(&n, ibm)| world[n] * *ibm).collect();
                morphed
                    .iter()
                    .zip(&skin.influences)
                    .map(|(p, inf)| {
                        let total: f64 = inf.iter().map(|x| x.1).sum();
                        inf.iter().map(|&(j, w)| matrices[j].transform_point3(*p) * (w / total)).sum()
                    })
                    .collect()
            }
        }
    }

    /// The mesh at time `t` of `animation`.
    #[must_use]
    pub fn at(
        &self,
        reference: &Reference,
        animation: Option<usize>,
        t: f64,
        how: Interpolator,
    ) -> Vec<DVec3> {
        self.deform(&reference.world(animation, t, how), &reference.weights(self.node, animation, t, how))
    }
}

/// Diagonal of the bounding box of `points`.
#[must_use]
pub fn size_of(points: &[DVec3]) -> f64 {
    let (lo, hi) = points.iter().fold((DVec3::MAX, DVec3::MIN), |(l, h), p| (l.min(*p), h.max(*p)));
    (hi - lo).length()
}

/// Runs the Khronos glTF-Validator (`tools/validate-gltf`) on `file` and returns (errors,
/// warnings, full report). Fails with instructions when Node.js or the validator is missing.
#[must_use]
pub fn validate(file: &Path) -> (u64, u64, String) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../tools/validate-gltf");
    assert!(
        dir.join("node_modules/gltf-validator").is_dir(),
        "the Khronos glTF-Validator is not installed: install Node.js (18 or newer) and run \
         `npm ci --prefix tools/validate-gltf` in the repository root"
    );
    let output = Command::new("node").arg(dir.join("validate.mjs")).arg(file).output().unwrap_or_else(|e| {
        panic!("cannot run `node` ({e}): install Node.js (18 or newer) and run `npm ci --prefix tools/validate-gltf`")
    });
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let stderr = String::from_utf8_lossy(&output.stderr);
    let report: serde_json::Value = serde_json::from_str(stdout.trim())
        .unwrap_or_else(|e| panic!("validator output ({e}): {stdout} {stderr}"));
    (
        report["errors"].as_u64().expect("errors count"),
        report["warnings"].as_u64().expect("warnings count"),
        stdout,
    )
}
