//! Imported characters move exactly as their glTF file says.
//!
//! For every skinned model of the external corpus (`../shared/corpus/gltf/`) and every
//! animation in it, the vertices keyrig shows (glTF import → keyrig scene → keyrig-core's
//! tracks → keyrig-skin's joint palette → linear blend skinning → the object's transform) are
//! compared at every frame (30 fps, the scene's rate) with an independent evaluation of the same
//! file, written here from the glTF 2.0 specification alone:
//!
//! - the file is read with the `gltf` crate's own importer and accessor readers (not keyrig-io's
//!   importer);
//! - samplers follow the specification's Appendix C in f64: STEP holds, LINEAR lerps
//!   translations and scales and slerps rotations the short way, CUBICSPLINE is the Hermite
//!   `h00·v_k + h10·t_d·b_k + h01·v_{k+1} + h11·t_d·a_{k+1}` (rotations normalized after it);
//!   times outside the keys clamp;
//! - node matrices `T·R·S` are composed from the scene root down in f64, joint matrices are
//!   `globalTransform(joint) · inverseBindMatrix`, and a vertex is `Σ wᵢ · jointMatrix(jᵢ) · v`
//!   with the weights of every JOINTS_n/WEIGHTS_n set, normalized to sum 1 (the specification
//!   asks files to store them so).
//!
//! Every vertex must agree within 1e-4 of the model's size (the diagonal of its rest-frame
//! bounding box). docs/interchange.md describes this check.

use std::path::{Path, PathBuf};

use glam::{DMat4, DQuat, DVec3, Vec3};
use gltf::animation::util::ReadOutputs;
use gltf::animation::{Interpolation, Property};

const TOLERANCE: f64 = 1e-4;
const FPS: f64 = 30.0;

fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../shared/corpus/gltf").join(rel)
}

/// The skinned models of the corpus.
const SKINNED: [&str; 6] = [
    "RiggedSimple/RiggedSimple.glb",
    "RiggedSimple/glTF/RiggedSimple.gltf",
    "RiggedFigure/RiggedFigure.glb",
    "CesiumMan/CesiumMan.glb",
    "SimpleSkin/glTF/SimpleSkin.gltf",
    "Fox/Fox.glb",
];

/// One animation channel as the specification reads it.
struct Channel {
    node: usize,
    property: Property,
    interpolation: Interpolation,
    times: Vec<f64>,
    /// Values per key: 3 or 4 components; CUBICSPLINE stores (in-tangent, value, out-tangent).
    values: Vec<Vec<f64>>,
}

struct Reference {
    parents: Vec<Option<usize>>,
    rest: Vec<(DVec3, DQuat, DVec3)>,
    animations: Vec<Vec<Channel>>,
}

fn read_reference(doc: &gltf::Document, buffers: &[gltf::buffer::Data]) -> Reference {
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
                        // them (SimpleSkin's keys are 2e-4 off unit length), so they are
                        // normalized before interpolating, as a rotation must be.
                        ReadOutputs::Rotations(it) => it
                            .into_f32()
                            .map(|v| {
                                let q: Vec<f64> = v.iter().map(|&x| f64::from(x)).collect();
                                let len = q.iter().map(|x| x * x).sum::<f64>().sqrt();
                                q.iter().map(|x| x / len).collect()
                            })
                            .collect(),
                        ReadOutputs::MorphTargetWeights(_) => return None,
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
    Reference { parents, rest, animations }
}

fn hermite(u: f64) -> [f64; 4] {
    let (u2, u3) = (u * u, u * u * u);
    [2.0 * u3 - 3.0 * u2 + 1.0, u3 - 2.0 * u2 + u, -2.0 * u3 + 3.0 * u2, u3 - u2]
}

/// The specification's sampler at time `t`.
fn sample(c: &Channel, t: f64) -> Vec<f64> {
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
    match c.interpolation {
        Interpolation::Step => a,
        Interpolation::Linear if rotation => {
            let dot: f64 = a.iter().zip(&b).map(|(x, y)| x * y).sum();
            let sign = if dot < 0.0 { -1.0 } else { 1.0 };
            let angle = dot.abs().min(1.0).acos();
            if angle < 1e-12 {
                return a;
            }
            let (wa, wb) = (((1.0 - u) * angle).sin() / angle.sin(), sign * (u * angle).sin() / angle.sin());
            a.iter().zip(&b).map(|(x, y)| wa * x + wb * y).collect()
        }
        Interpolation::Linear => a.iter().zip(&b).map(|(x, y)| x + u * (y - x)).collect(),
        Interpolation::CubicSpline => {
            let out_tangent = &c.values[3 * k + 2];
            let in_tangent = &c.values[3 * (k + 1)];
            let h = hermite(u);
            let mut p: Vec<f64> = (0..a.len())
                .map(|i| h[0] * a[i] + h[1] * td * out_tangent[i] + h[2] * b[i] + h[3] * td * in_tangent[i])
                .collect();
            if rotation {
                let len = p.iter().map(|x| x * x).sum::<f64>().sqrt();
                p.iter_mut().for_each(|x| *x /= len);
            }
            p
        }
    }
}

impl Reference {
    fn duration(&self, animation: usize) -> f64 {
        self.animations[animation].iter().filter_map(|c| c.times.last()).fold(0.0, |a, &b| a.max(b))
    }

    /// `globalTransform` of every node at time `t` of `animation`.
    fn world(&self, animation: usize, t: f64) -> Vec<DMat4> {
        let mut local = self.rest.clone();
        for c in &self.animations[animation] {
            let v = sample(c, t);
            match c.property {
                Property::Translation => local[c.node].0 = DVec3::new(v[0], v[1], v[2]),
                Property::Rotation => local[c.node].1 = DQuat::from_xyzw(v[0], v[1], v[2], v[3]),
                Property::Scale => local[c.node].2 = DVec3::new(v[0], v[1], v[2]),
                Property::MorphTargetWeights => {}
            }
        }
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
}

/// A skinned mesh node's vertices as the reference skins them, in keyrig's vertex order (the
/// triangle primitives' vertices one after the other).
struct SkinnedNode {
    positions: Vec<DVec3>,
    influences: Vec<Vec<(usize, f64)>>,
    joints: Vec<usize>,
    inverse_bind: Vec<DMat4>,
}

fn skinned_node(node: &gltf::Node<'_>, buffers: &[gltf::buffer::Data]) -> SkinnedNode {
    let skin = node.skin().expect("skin");
    let joints: Vec<usize> = skin.joints().map(|j| j.index()).collect();
    let inverse_bind: Vec<DMat4> =
        match skin.reader(|b| Some(&buffers[b.index()])).read_inverse_bind_matrices() {
            Some(it) => it.map(|m| glam::Mat4::from_cols_array_2d(&m).as_dmat4()).collect(),
            None => vec![DMat4::IDENTITY; joints.len()],
        };
    let (mut positions, mut influences) = (Vec::new(), Vec::new());
    for prim in node.mesh().expect("mesh").primitives() {
        use gltf::mesh::Mode;
        if !matches!(prim.mode(), Mode::Triangles | Mode::TriangleStrip | Mode::TriangleFan) {
            continue;
        }
        let reader = prim.reader(|b| Some(&buffers[b.index()]));
        let start = positions.len();
        positions.extend(reader.read_positions().expect("positions").map(|p| DVec3::from(Vec3::from(p))));
        influences.resize(positions.len(), Vec::new());
        let mut set = 0;
        while let (Some(j), Some(w)) = (reader.read_joints(set), reader.read_weights(set)) {
            for (v, (j, w)) in j.into_u16().zip(w.into_f32()).enumerate() {
                for i in 0..4 {
                    if w[i] != 0.0 {
                        influences[start + v].push((usize::from(j[i]), f64::from(w[i])));
                    }
                }
            }
            set += 1;
        }
    }
    SkinnedNode { positions, influences, joints, inverse_bind }
}

impl SkinnedNode {
    fn skin(&self, world: &[DMat4]) -> Vec<DVec3> {
        let matrices: Vec<DMat4> =
            self.joints.iter().zip(&self.inverse_bind).map(|(&n, ibm)| world[n] * *ibm).collect();
        self.positions
            .iter()
            .zip(&self.influences)
            .map(|(p, inf)| {
                let total: f64 = inf.iter().map(|x| x.1).sum();
                inf.iter().map(|&(j, w)| matrices[j].transform_point3(*p) * (w / total)).sum()
            })
            .collect()
    }
}

#[test]
fn imported_characters_match_an_independent_gltf_evaluation_at_every_frame() {
    let mut report = Vec::new();
    for file in SKINNED {
        let path = corpus(file);
        let (doc, buffers, _) = gltf::import(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
        let reference = read_reference(&doc, &buffers);
        let model = keyrig_io::gltf_import::import_gltf_file(&path).unwrap_or_else(|e| panic!("{file}: {e}"));
        let skinned: Vec<gltf::Node<'_>> =
            doc.nodes().filter(|n| n.skin().is_some() && n.mesh().is_some()).collect();
        assert!(!skinned.is_empty(), "{file}: no skinned mesh node");
        for animation in 0..reference.animations.len() {
            let scene =
                model.to_scene("model.glb", Some(animation)).unwrap_or_else(|e| panic!("{file}: {e}"));
            for node in &skinned {
                let gltf_node = skinned_node(node, &buffers);
                let object = scene
                    .objects
                    .iter()
                    .find(|o| o.name == model.nodes[node.index()].name)
                    .unwrap_or_else(|| panic!("{file}: no object for node {}", node.index()));
                let skeleton = object.skeleton.as_ref().expect("skeleton");
                let mesh = model.skinned_mesh(node.index()).unwrap_or_else(|e| panic!("{file}: {e}"));
                assert_eq!(mesh.positions.len(), gltf_node.positions.len(), "{file}: vertex count");
                let sampler =
                    keyrig_skin::ScenePoseSampler::new(skeleton).unwrap_or_else(|e| panic!("{file}: {e}"));
                let object_tracks = (
                    keyrig_core::AnimatedTrack::new(&object.translation).expect("translation"),
                    keyrig_core::AnimatedTrack::new(&object.rotation).expect("rotation"),
                    keyrig_core::AnimatedTrack::new(&object.scale).expect("scale"),
                );
                let bindings =
                    mesh.bindings(keyrig_skin::BlendZone::new(0.25, 0.25).expect("zone")).expect("bindings");
                let rest = gltf_node.skin(&reference.world(animation, 0.0));
                let (lo, hi) = rest.iter().fold((DVec3::MAX, DVec3::MIN), |(l, h), p| (l.min(*p), h.max(*p)));
                let size = (hi - lo).length();
                let frames = (reference.duration(animation) * FPS).ceil() as usize;
                let mut worst = 0.0f64;
                for frame in 0..=frames {
                    let t = frame as f64 / FPS;
                    let expected = gltf_node.skin(&reference.world(animation, t));
                    let palette =
                        keyrig_skin::JointPalette::new(&mesh.skeleton, &sampler.sample(t)).expect("palette");
                    let deformed = keyrig_skin::deform_mesh(
                        &mesh,
                        &bindings,
                        &palette,
                        keyrig_core::DeformerKind::LinearBlend,
                    )
                    .expect("linear blend");
                    let world_from_object = glam::Mat4::from_scale_rotation_translation(
                        object_tracks.2.sample(t),
                        object_tracks.1.sample(t),
                        object_tracks.0.sample(t),
                    );
                    for (v, (got, want)) in deformed.positions.iter().zip(&expected).enumerate() {
                        let got = world_from_object.transform_point3(*got).as_dvec3();
                        let error = (got - *want).length() / size;
                        assert!(
                            error <= TOLERANCE,
                            "{file}, animation {animation}, frame {frame} (t = {t}), vertex {v}: keyrig {got:?}, \
                             glTF {want:?}: {error:.2e} of the model's size {size}"
                        );
                        worst = worst.max(error);
                    }
                }
                report
                    .push(format!("{file} animation {animation}: {} frames, worst {worst:.2e}", frames + 1));
            }
        }
    }
    // Shown with --nocapture; docs/interchange.md quotes these figures.
    println!("{}", report.join("\n"));
}
