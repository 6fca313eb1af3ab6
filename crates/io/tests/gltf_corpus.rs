//! Every glTF model of the external corpus imports; animations keep their curves; linear
//! blend skinning matches an independent computation written straight from the glTF
//! specification with the gltf crate's own readers.

use std::path::{Path, PathBuf};

use glam::{Mat4, Quat, Vec3};
use keyrig_core::Interpolation;
use keyrig_io::gltf_import::{import_gltf_file, import_gltf_slice};
use keyrig_io::model::{sample_vec3, ChannelTarget, ImportedModel};

fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf").join(rel)
}

/// (file, nodes, meshes, skins, joints of skin 0, animations)
const MODELS: [(&str, usize, usize, usize, usize, usize); 9] = [
    ("RiggedSimple/RiggedSimple.glb", 5, 1, 1, 2, 1),
    ("RiggedSimple/glTF/RiggedSimple.gltf", 5, 1, 1, 2, 1),
    ("RiggedFigure/RiggedFigure.glb", 22, 1, 1, 19, 1),
    ("CesiumMan/CesiumMan.glb", 22, 1, 1, 19, 1),
    ("SimpleSkin/glTF/SimpleSkin.gltf", 3, 1, 1, 2, 1),
    ("SimpleSkin/glTF-Embedded/SimpleSkin.gltf", 3, 1, 1, 2, 1),
    ("Fox/Fox.glb", 26, 1, 1, 24, 3),
    ("InterpolationTest/InterpolationTest.glb", 12, 10, 0, 0, 9),
    ("AnimatedMorphCube/AnimatedMorphCube.glb", 1, 1, 0, 0, 1),
];

fn load(rel: &str) -> ImportedModel {
    import_gltf_file(&corpus(rel)).unwrap_or_else(|e| panic!("{rel}: {e}"))
}

#[test]
fn every_corpus_model_imports_with_expected_structure() {
    for (file, nodes, meshes, skins, joints, animations) in MODELS {
        let m = load(file);
        assert_eq!(m.nodes.len(), nodes, "{file}: nodes");
        assert_eq!(m.meshes.len(), meshes, "{file}: meshes");
        assert_eq!(m.skins.len(), skins, "{file}: skins");
        if skins > 0 {
            assert_eq!(m.skins[0].joints.len(), joints, "{file}: joints");
            assert_eq!(m.skins[0].inverse_bind_matrices.len(), joints, "{file}: inverse bind matrices");
        }
        assert_eq!(m.animations.len(), animations, "{file}: animations");
        for mesh in &m.meshes {
            for p in mesh.primitives.iter() {
                assert!(!p.positions.is_empty());
                assert!(p.indices.iter().all(|&i| (i as usize) < p.positions.len()), "{file}");
                assert_eq!(p.joint_sets.len(), p.weight_sets.len());
            }
        }
    }
}

#[test]
fn external_and_embedded_buffers_give_the_same_model_as_binary() {
    assert_eq!(
        load("RiggedSimple/RiggedSimple.glb").skins,
        load("RiggedSimple/glTF/RiggedSimple.gltf").skins
    );
    assert_eq!(
        load("RiggedSimple/RiggedSimple.glb").meshes[0].primitives[0].positions,
        load("RiggedSimple/glTF/RiggedSimple.gltf").meshes[0].primitives[0].positions
    );
    assert_eq!(load("SimpleSkin/glTF/SimpleSkin.gltf"), load("SimpleSkin/glTF-Embedded/SimpleSkin.gltf"));
}

#[test]
fn external_buffers_need_a_folder() {
    let data = std::fs::read(corpus("SimpleSkin/glTF/SimpleSkin.gltf")).expect("read");
    let err = import_gltf_slice(&data).expect_err("external buffers from memory");
    assert!(err.to_string().starts_with("/buffers/0/uri: "), "{err}");
}

#[test]
fn fox_has_named_clips_textures_and_normals() {
    let m = load("Fox/Fox.glb");
    let names: Vec<&str> = m.animations.iter().map(|a| a.name.as_str()).collect();
    assert_eq!(names, ["Survey", "Walk", "Run"]);
    let prim = &m.meshes[0].primitives[0];
    assert!(prim.texcoords.is_some() && prim.base_colour_texture.is_some());
    assert!(!m.images.is_empty());
}

#[test]
fn cubic_spline_keeps_its_tangents_and_curve() {
    let m = load("InterpolationTest/InterpolationTest.glb");
    let doc =
        gltf::Gltf::open(corpus("InterpolationTest/InterpolationTest.glb")).expect("gltf crate opens it");
    let blob = doc.blob.clone().expect("blob");
    let mut checked = 0;
    for (a, anim) in doc.animations().enumerate() {
        for (c, channel) in anim.channels().enumerate() {
            let sampler = channel.sampler();
            let reader = channel.reader(|_| Some(&blob[..]));
            let times: Vec<f32> = reader.read_inputs().expect("inputs").collect();
            let gltf::animation::util::ReadOutputs::Translations(out) =
                reader.read_outputs().expect("outputs")
            else {
                continue;
            };
            let out: Vec<Vec3> = out.map(Vec3::from_array).collect();
            let ChannelTarget::Translation(track) = &m.animations[a].channels[c].target else {
                panic!("channel kind differs")
            };
            if sampler.interpolation() == gltf::animation::Interpolation::CubicSpline {
                assert!(track.keys.iter().all(|k| k.interpolation == Interpolation::Hermite));
                for k in 0..times.len() - 1 {
                    let td = times[k + 1] - times[k];
                    let (vk, bk) = (out[3 * k + 1], out[3 * k + 2]);
                    let (ak1, vk1) = (out[3 * (k + 1)], out[3 * (k + 1) + 1]);
                    for u in [0.0f32, 0.25, 0.5, 0.9] {
                        let (u2, u3) = (u * u, u * u * u);
                        let expected = (2.0 * u3 - 3.0 * u2 + 1.0) * vk
                            + td * (u3 - 2.0 * u2 + u) * bk
                            + (-2.0 * u3 + 3.0 * u2) * vk1
                            + td * (u3 - u2) * ak1;
                        let got = sample_vec3(track, f64::from(times[k] + u * td)).expect("sample");
                        assert!(
                            (got - expected).length() < 1e-4,
                            "anim {a} key {k} u {u}: {got} vs {expected}"
                        );
                        checked += 1;
                    }
                }
            } else {
                for (k, &t) in times.iter().enumerate() {
                    assert_eq!(sample_vec3(track, f64::from(t)), Some(out[k]));
                    checked += 1;
                }
            }
        }
    }
    assert!(checked > 20, "only {checked} samples checked");
}

#[test]
fn morph_weights_animate() {
    let m = load("AnimatedMorphCube/AnimatedMorphCube.glb");
    let prim = &m.meshes[0].primitives[0];
    assert_eq!(prim.morph_targets.len(), 2);
    let ChannelTarget::Weights(w) = &m.animations[0].channels[0].target else {
        panic!("not a weights channel")
    };
    assert_eq!(w.targets, 2);
    let duration = m.animations[0].duration();
    let mut moved = false;
    for step in 0..=20 {
        let t = duration * f64::from(step) / 20.0;
        let pose = m.pose_at(Some(0), t);
        let weights = &pose.weights[0];
        assert_eq!(weights.len(), 2);
        assert!(weights.iter().all(|w| (-1e-4..=1.0001).contains(w)), "t {t}: {weights:?}");
        let positions = m.deformed_positions(0, Some(0), t).expect("mesh")[0].clone();
        moved |= positions[..] != prim.positions[..];
    }
    assert!(moved, "the morph animation never moves a vertex");
}

/// glTF reference, written independently of keyrig-io: sample every LINEAR/STEP channel with
/// glam's own lerp/slerp, compose node matrices down the scene tree, and skin with
/// Σ w · (global(joint) · IBM) · v using the gltf crate's readers.
fn reference_skinning(path: &Path, anim_index: usize, time: f32) -> Vec<(usize, Vec<Vec3>)> {
    let (doc, buffers, _) = gltf::import(path).expect("gltf crate imports corpus file");
    let get = |b: gltf::Buffer| Some(&buffers[b.index()].0[..]);
    let mut trs: Vec<(Vec3, Quat, Vec3)> = doc
        .nodes()
        .map(|n| {
            let (t, r, s) = n.transform().decomposed();
            (Vec3::from(t), Quat::from_array(r), Vec3::from(s))
        })
        .collect();
    let anim = doc.animations().nth(anim_index).expect("animation");
    for ch in anim.channels() {
        let r = ch.reader(get);
        let times: Vec<f32> = r.read_inputs().expect("in").collect();
        let k = times.iter().rposition(|&t| t <= time).unwrap_or(0);
        let k1 = (k + 1).min(times.len() - 1);
        let u = if k1 == k || time <= times[0] {
            0.0
        } else {
            ((time - times[k]) / (times[k1] - times[k])).min(1.0)
        };
        let step = ch.sampler().interpolation() == gltf::animation::Interpolation::Step;
        let u = if step { 0.0 } else { u };
        let node = ch.target().node().index();
        match r.read_outputs().expect("out") {
            gltf::animation::util::ReadOutputs::Translations(o) => {
                let v: Vec<Vec3> = o.map(Vec3::from).collect();
                trs[node].0 = v[k].lerp(v[k1], u);
            }
            gltf::animation::util::ReadOutputs::Scales(o) => {
                let v: Vec<Vec3> = o.map(Vec3::from).collect();
                trs[node].2 = v[k].lerp(v[k1], u);
            }
            gltf::animation::util::ReadOutputs::Rotations(o) => {
                let v: Vec<Quat> = o.into_f32().map(Quat::from_array).collect();
                trs[node].1 = v[k].normalize().slerp(v[k1].normalize(), u);
            }
            gltf::animation::util::ReadOutputs::MorphTargetWeights(_) => {}
        }
    }
    let mut global = vec![Mat4::IDENTITY; trs.len()];
    fn walk(n: gltf::Node, parent: Mat4, trs: &[(Vec3, Quat, Vec3)], global: &mut [Mat4]) {
        let (t, r, s) = trs[n.index()];
        let m = parent * Mat4::from_scale_rotation_translation(s, r, t);
        global[n.index()] = m;
        for c in n.children() {
            walk(c, m, trs, global);
        }
    }
    for scene in doc.scenes() {
        for n in scene.nodes() {
            walk(n, Mat4::IDENTITY, &trs, &mut global);
        }
    }
    let mut out = Vec::new();
    for node in doc.nodes() {
        let (Some(mesh), Some(skin)) = (node.mesh(), node.skin()) else { continue };
        let ibms: Vec<Mat4> = skin
            .reader(get)
            .read_inverse_bind_matrices()
            .map(|it| it.map(|m| Mat4::from_cols_array_2d(&m)).collect())
            .unwrap_or_else(|| vec![Mat4::IDENTITY; skin.joints().count()]);
        let joint_mats: Vec<Mat4> =
            skin.joints().zip(&ibms).map(|(j, ibm)| global[j.index()] * *ibm).collect();
        for prim in mesh.primitives() {
            let r = prim.reader(get);
            let pos: Vec<Vec3> = r.read_positions().expect("pos").map(Vec3::from).collect();
            let joints: Vec<[u16; 4]> = r.read_joints(0).expect("joints").into_u16().collect();
            let weights: Vec<[f32; 4]> = r.read_weights(0).expect("weights").into_f32().collect();
            let skinned = pos
                .iter()
                .enumerate()
                .map(|(v, p)| {
                    let mut m = Mat4::ZERO;
                    for i in 0..4 {
                        m += joint_mats[joints[v][i] as usize] * weights[v][i];
                    }
                    m.transform_point3(*p)
                })
                .collect();
            out.push((node.index(), skinned));
        }
    }
    out
}

#[test]
fn linear_blend_skinning_matches_the_gltf_definition() {
    let skinned = [
        "RiggedSimple/RiggedSimple.glb",
        "RiggedSimple/glTF/RiggedSimple.gltf",
        "RiggedFigure/RiggedFigure.glb",
        "CesiumMan/CesiumMan.glb",
        "SimpleSkin/glTF/SimpleSkin.gltf",
        "Fox/Fox.glb",
    ];
    for file in skinned {
        let m = load(file);
        for anim in 0..m.animations.len() {
            let duration = m.animations[anim].duration();
            for step in 0..7 {
                let t = duration * f64::from(step) / 6.0;
                let reference = reference_skinning(&corpus(file), anim, t as f32);
                assert!(!reference.is_empty(), "{file}: no skinned mesh");
                for (node, expected) in reference {
                    let got = m.deformed_positions(node, Some(anim), t).expect("mesh");
                    let got = &got[0];
                    let (lo, hi) =
                        expected.iter().fold((Vec3::MAX, Vec3::MIN), |(l, h), p| (l.min(*p), h.max(*p)));
                    let size = (hi - lo).length().max(1e-3);
                    let max_err =
                        got.iter().zip(&expected).map(|(a, b)| (*a - *b).length()).fold(0.0, f32::max);
                    assert!(
                        max_err <= 1e-4 * size,
                        "{file} anim {anim} t {t}: max error {max_err} (size {size})"
                    );
                    // Finite and bounded: nothing flies off beyond the rest size.
                    let rest = &m.meshes[m.nodes[node].mesh.expect("mesh")].primitives[0].positions;
                    let (rl, rh) =
                        rest.iter().fold((Vec3::MAX, Vec3::MIN), |(l, h), p| (l.min(*p), h.max(*p)));
                    let rest_size = (rh - rl).length();
                    assert!(got.iter().all(|p| p.is_finite()), "{file}");
                    let centre = (rl + rh) * 0.5;
                    assert!(
                        got.iter().all(|p| (*p - centre).length() < 20.0 * rest_size + 10.0),
                        "{file}: vertex flew off"
                    );
                }
            }
        }
    }
}

#[test]
fn every_corpus_model_maps_onto_a_scene_that_saves_and_loads() {
    for (file, ..) in MODELS {
        let m = load(file);
        let animation = if m.animations.is_empty() { None } else { Some(0) };
        let scene = m.to_scene("model.glb", animation).unwrap_or_else(|e| panic!("{file}: {e}"));
        let mesh_nodes = m.nodes.iter().filter(|n| n.mesh.is_some()).count();
        assert_eq!(scene.objects.len(), mesh_nodes, "{file}: one object per mesh node");
        let text = keyrig_io::scene_file::to_string(&scene).unwrap_or_else(|e| panic!("{file}: {e}"));
        let back = keyrig_io::scene_file::from_str(&text, Path::new("model.ron"))
            .unwrap_or_else(|e| panic!("{file}: the mapped scene does not load again: {e}"));
        assert_eq!(back.objects.len(), scene.objects.len(), "{file}");
        // Every rotation track of every joint validates in keyrig-core.
        for object in &scene.objects {
            for joint in object.skeleton.iter().flat_map(|s| &s.joints) {
                keyrig_core::AnimatedTrack::new(&joint.rotation)
                    .unwrap_or_else(|e| panic!("{file} {}: {e}", joint.name));
            }
        }
    }
}

/// An animation lasts until the last key of any of its channels, as the gltf crate reads the
/// samplers' inputs.
#[test]
fn animation_durations_are_the_last_key_times() {
    let mut checked = 0;
    for (file, ..) in MODELS {
        let (doc, buffers, _) = gltf::import(corpus(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        let m = load(file);
        for (a, anim) in doc.animations().enumerate() {
            let last = anim
                .channels()
                .filter_map(|c| c.reader(|b| Some(&buffers[b.index()])).read_inputs())
                .flat_map(|times| times.map(f64::from))
                .fold(0.0, f64::max);
            let duration = m.animations[a].duration();
            assert!((duration - last).abs() < 1e-6, "{file} animation {a}: {duration} vs {last}");
            checked += 1;
        }
    }
    assert!(checked > 10, "only {checked} animations checked");
}

/// CUBICSPLINE rotations and morph weights sample as glTF 2.0 Appendix C writes the Hermite
/// curve (rotations normalized after it); slerp takes the short way for either sign of a key.
#[test]
fn cubic_spline_rotations_and_weights_follow_the_specification() {
    use keyrig_core::{Interpolation, Key, RawTrack};
    use keyrig_io::model::{sample_quat, sample_weights, slerp_short, WeightsTrack};
    // Two keys two seconds apart; at u = 1/2 the basis is (1/2, 1/8, 1/2, −1/8).
    let weights = WeightsTrack {
        targets: 2,
        keys: vec![
            Key {
                in_tangent: Some(vec![0.0, 0.0]),
                out_tangent: Some(vec![1.0, -1.0]),
                ..Key::new(0.0, vec![0.0, 1.0])
            }
            .with_interpolation(Interpolation::Hermite),
            Key {
                in_tangent: Some(vec![0.5, 0.0]),
                out_tangent: Some(vec![0.0, 0.0]),
                ..Key::new(2.0, vec![1.0, 0.0])
            }
            .with_interpolation(Interpolation::Hermite),
        ],
    };
    // 0.5·0 + (1/8)·2·1 + 0.5·1 − (1/8)·2·0.5 = 0.625; 0.5·1 − (1/8)·2·1 + 0 − 0 = 0.25.
    let got = sample_weights(&weights, 1.0).expect("weights");
    assert!((got[0] - 0.625).abs() < 1e-6 && (got[1] - 0.25).abs() < 1e-6, "{got:?}");

    let (a, b) = (Quat::from_rotation_z(0.2), Quat::from_rotation_z(1.0));
    let tangent = Quat::from_xyzw(0.0, 0.0, 0.4, 0.0);
    let rotations = RawTrack::new(vec![
        Key { out_tangent: Some(tangent), ..Key::new(0.0, a) }.with_interpolation(Interpolation::Hermite),
        Key { in_tangent: Some(tangent), ..Key::new(2.0, b) }.with_interpolation(Interpolation::Hermite),
    ]);
    let v = 0.5 * glam::Vec4::from(a) + 0.25 * glam::Vec4::from(tangent) + 0.5 * glam::Vec4::from(b)
        - 0.25 * glam::Vec4::from(tangent);
    let expected = Quat::from_vec4(v.normalize());
    let got = sample_quat(&rotations, 1.0).expect("rotation");
    let close = |p: Quat, q: Quat| (glam::Vec4::from(p) - glam::Vec4::from(q)).length() < 1e-5;
    assert!(close(got, expected), "{got} vs {expected}");
    let off_middle = sample_quat(&rotations, 0.5).expect("rotation");
    let (u, td) = (0.25f32, 2.0f32);
    let (u2, u3) = (u * u, u * u * u);
    let v = (2.0 * u3 - 3.0 * u2 + 1.0) * glam::Vec4::from(a)
        + td * (u3 - 2.0 * u2 + u) * glam::Vec4::from(tangent)
        + (-2.0 * u3 + 3.0 * u2) * glam::Vec4::from(b)
        + td * (u3 - u2) * glam::Vec4::from(tangent);
    assert!(close(off_middle, Quat::from_vec4(v.normalize())), "{off_middle}");

    let (c, d) = (Quat::from_rotation_y(0.3), Quat::from_rotation_y(1.3));
    let half = slerp_short(c, -d, 0.5);
    assert!(close(half, Quat::from_rotation_y(0.8)), "{half}");
}

/// CesiumMan's material is its base colour texture, decoded.
#[test]
fn materials_carry_their_base_colour_texture() {
    let m = load("CesiumMan/CesiumMan.glb");
    let mesh = m.nodes.iter().find_map(|n| n.mesh).expect("a mesh node");
    let material = m.material(mesh).expect("decodes").expect("a material");
    let texture = material.base_colour_texture.expect("a texture");
    assert!(texture.width() > 0 && texture.height() > 0);
}
