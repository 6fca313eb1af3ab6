//! glTF export of spin keys (issue 14): rotation segments beyond half a turn are resampled so
//! that every exported step turns at most 90° and the glTF LINEAR sampler — slerp between
//! consecutive keys the short way, as the glTF 2.0 specification's Appendix C writes it —
//! reproduces the turns. The exported keys are read straight from the JSON and the binary
//! buffer and interpolated here, independently of keyrig's importer.

use glam::{DQuat, DVec3, Quat, Vec3};
use keyrig_core::{AnimatedTrack, Interpolation, Key, Object, RawTrack, Scene, Spin, Tcb};
use keyrig_io::gltf_export::{export_scene, ExportOptions, ExportedGltf, MAX_ROTATION_STEP_DEG};
use serde_json::Value;

/// The floats of accessor `index` (FLOAT components, tightly packed).
fn floats(gltf: &ExportedGltf, index: usize) -> Vec<f32> {
    let accessor = &gltf.json["accessors"][index];
    assert_eq!(accessor["componentType"], 5126, "FLOAT");
    let width = match accessor["type"].as_str().unwrap() {
        "SCALAR" => 1,
        "VEC3" => 3,
        "VEC4" => 4,
        other => panic!("type {other}"),
    };
    let count = accessor["count"].as_u64().unwrap() as usize;
    let view = &gltf.json["bufferViews"][accessor["bufferView"].as_u64().unwrap() as usize];
    let start = view["byteOffset"].as_u64().unwrap_or(0) as usize
        + accessor["byteOffset"].as_u64().unwrap_or(0) as usize;
    (0..count * width)
        .map(|i| f32::from_le_bytes(gltf.bin[start + 4 * i..start + 4 * i + 4].try_into().unwrap()))
        .collect()
}

/// `(times, quaternions)` of the rotation channel targeting the node named `name`.
fn rotation_keys(gltf: &ExportedGltf, name: &str) -> (Vec<f64>, Vec<DQuat>) {
    let nodes = gltf.json["nodes"].as_array().unwrap();
    let node = nodes.iter().position(|n| n["name"] == name).unwrap_or_else(|| panic!("no node {name}"));
    let animation = &gltf.json["animations"][0];
    let channel = animation["channels"]
        .as_array()
        .unwrap()
        .iter()
        .find(|c| c["target"]["node"] == node && c["target"]["path"] == "rotation")
        .unwrap_or_else(|| panic!("no rotation channel for {name}"));
    let sampler: &Value = &animation["samplers"][channel["sampler"].as_u64().unwrap() as usize];
    assert_eq!(sampler["interpolation"], "LINEAR");
    let times =
        floats(gltf, sampler["input"].as_u64().unwrap() as usize).into_iter().map(f64::from).collect();
    let values = floats(gltf, sampler["output"].as_u64().unwrap() as usize)
        .chunks(4)
        .map(|q| DQuat::from_xyzw(q[0].into(), q[1].into(), q[2].into(), q[3].into()))
        .collect();
    (times, values)
}

/// glTF 2.0 Appendix C slerp: `a = acos(|d|)`, `s = sign(d)`, `(sin(a(1−t))/sin a)·q_k +
/// s·(sin(a·t)/sin a)·q_{k+1}` (normalized lerp where `a` is tiny).
fn gltf_slerp(q0: DQuat, q1: DQuat, t: f64) -> DQuat {
    let d = q0.dot(q1);
    let (a, s) = (d.abs().min(1.0).acos(), if d < 0.0 { -1.0 } else { 1.0 });
    if a < 1e-6 {
        return (q0 * (1.0 - t) + q1 * (s * t)).normalize();
    }
    (q0 * ((a * (1.0 - t)).sin() / a.sin()) + q1 * (s * (a * t).sin() / a.sin())).normalize()
}

/// The glTF LINEAR sampler at `t` (clamped).
fn gltf_sample(times: &[f64], values: &[DQuat], t: f64) -> DQuat {
    if t <= times[0] {
        return values[0];
    }
    let k = times.partition_point(|&x| x <= t);
    if k >= times.len() {
        return values[values.len() - 1];
    }
    gltf_slerp(values[k - 1], values[k], (t - times[k - 1]) / (times[k] - times[k - 1]))
}

fn angle_deg(a: DQuat, b: DQuat) -> f64 {
    let d = a.conjugate() * b;
    2.0 * DVec3::new(d.x, d.y, d.z).length().atan2(d.w.abs()).to_degrees()
}

/// Exports `scene` and checks the rotation channel of `node` (animating `rest · track`)
/// against keyrig's track at 4000 times: within `ExportOptions::rotation_tolerance_deg` plus
/// f32 rounding, every step at most 90°; returns the number of exported keys.
fn check_export(scene: &Scene, node: &str, rest: Quat, track: &AnimatedTrack<Quat>) -> usize {
    let options = ExportOptions::default();
    let gltf = export_scene(scene, &options).expect("export");
    let (times, values) = rotation_keys(&gltf, node);
    for (k, w) in values.windows(2).enumerate() {
        let step = angle_deg(w[0], w[1]);
        assert!(step <= MAX_ROTATION_STEP_DEG + 1e-4, "{node}: step {k} turns {step}°");
        // Signs kept consistent, so that component-wise blending (Blender's) takes the short way
        // and never passes through zero.
        assert!(w[0].dot(w[1]) >= 0.0, "{node}: keys {k} and {} have opposite signs", k + 1);
    }
    let track = track.track().expect("keyed");
    let (start, end) = track.domain();
    let tolerance = options.rotation_tolerance_deg + 2e-3; // + f32 key times and values
    let mut worst = 0.0f64;
    for i in 0..=4000 {
        let t = start + (end - start) * f64::from(i) / 4000.0;
        let expected = rest.as_dquat() * track.sample_wide(t);
        let got = gltf_sample(&times, &values, t);
        let error = angle_deg(expected, got);
        worst = worst.max(error);
        assert!(error <= tolerance, "{node} t = {t}: glTF {got:?} vs keyrig {expected:?}: {error}°");
    }
    eprintln!("{node}: {} keys, worst {worst:.4}°", values.len());
    values.len()
}

#[test]
fn the_twist_example_exports_a_full_turn() {
    let scene = keyrig_io::demo::twist_scene();
    let joint = &scene.objects[0].skeleton.as_ref().unwrap().joints[2];
    let track = AnimatedTrack::new(&joint.rotation).unwrap();
    let keys = check_export(&scene, "forearm", joint.rest_rotation, &track);
    assert!(keys >= 9, "a 360° turn needs at least 9 keys of ≤ 45°, got {keys}");
}

#[test]
fn mixed_spin_keys_export_within_tolerance() {
    // 0 ── TCB, Turns(2) ──▶ 1 ── Linear, Angle(−720° about a tilted axis) ──▶ 2 ── short ──▶ 3
    //   ── TCB (T/C/B ≠ 0), Turns(−1): the long way ──▶ 4
    let tilted = Vec3::new(0.2, 1.0, -0.4).normalize();
    let q1 = Quat::from_rotation_z(100f32.to_radians());
    let q2 = q1 * Quat::from_axis_angle(tilted, (-720f32).to_radians());
    let q3 = q2 * Quat::from_rotation_x(0.6);
    let q4 = q3 * Quat::from_rotation_y(2.0);
    let mut o = Object::new("Spinner");
    o.rotation.track = RawTrack::new(vec![
        Key::new(0.0, Quat::IDENTITY),
        Key::new(1.0, q1).with_spin(Spin::Turns(2)).with_interpolation(Interpolation::Linear),
        Key::new(1.5, q2)
            .with_spin(Spin::Angle { axis: tilted, degrees: -720.0 })
            .with_tcb(Tcb::new(0.2, -0.3, 0.4)),
        Key::new(2.7, q3).with_tcb(Tcb::new(-0.5, 0.0, 0.5)),
        Key::new(3.0, q4).with_spin(Spin::Turns(-1)),
    ]);
    let mut scene = Scene::default();
    scene.frame_range.end = 90;
    scene.objects.push(o);
    assert_eq!(scene.problems(), Vec::new());
    let track = AnimatedTrack::new(&scene.objects[0].rotation).unwrap();
    check_export(&scene, "Spinner", Quat::IDENTITY, &track);
    // An all-Linear track with a spin is resampled too (key for key would lose the turns).
    let linear: Vec<Key<Quat>> = scene.objects[0]
        .rotation
        .track
        .keys
        .iter()
        .map(|k| k.clone().with_interpolation(Interpolation::Linear))
        .collect();
    scene.objects[0].rotation.track = RawTrack::new(linear);
    let track = AnimatedTrack::new(&scene.objects[0].rotation).unwrap();
    let keys = check_export(&scene, "Spinner", Quat::IDENTITY, &track);
    assert!(keys > 5, "{keys}");
}

/// A spin segment is cut into pieces of at most `SPIN_PIECE_DEG` of its unwrapped angle before
/// the keys are placed, so that every piece's ends are keys (here 25 pieces of a 1108.6° turn,
/// ends no halving of the segment lands on), and no more keys than the tolerance needs.
#[test]
fn spin_segments_have_a_key_at_every_piece_boundary() {
    use keyrig_io::gltf_export::SPIN_PIECE_DEG;
    let mut o = Object::new("Spinner");
    o.rotation.track = RawTrack::new(vec![
        Key::new(0.0, Quat::IDENTITY).with_interpolation(Interpolation::Linear),
        Key::new(2.0, Quat::from_rotation_y(0.5)).with_spin(Spin::Turns(3)),
    ]);
    let mut scene = Scene::default();
    scene.frame_range.end = 60;
    scene.objects.push(o);
    let animated = AnimatedTrack::new(&scene.objects[0].rotation).unwrap();
    let track = animated.track().expect("keyed");
    let (_, degrees) = track.segment_spin(0).expect("a spin segment");
    let pieces = (degrees.abs() / SPIN_PIECE_DEG).ceil() as usize;
    assert_eq!(pieces, 25, "{degrees}°");
    let keys = check_export(&scene, "Spinner", Quat::IDENTITY, &animated);
    let gltf = export_scene(&scene, &ExportOptions::default()).expect("export");
    let (times, _) = rotation_keys(&gltf, "Spinner");
    for k in 1..pieces {
        let t = 2.0 * k as f64 / pieces as f64;
        assert!(times.iter().any(|&x| (x - t).abs() < 1e-6), "no key at {t}: {times:?}");
    }
    // A linear spin at a constant rate is exact between the pieces' ends: they are all its keys.
    assert_eq!(keys, pieces + 1, "{times:?}");
}
