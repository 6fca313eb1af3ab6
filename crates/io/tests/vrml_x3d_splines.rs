//! X3D's `SquadOrientationInterpolator` and `SplineScalarInterpolator` are not in Coin (a
//! VRML97 toolkit): what keyrig imports from them, sampled through the scene evaluator (what
//! `keyrig sample` prints), is checked at every frame against the specification's formulas
//! written here, independently of keyrig's quaternion and spline code (own quaternion
//! arithmetic on `[w, x, y, z]` arrays):
//!
//! * Squad (ISO/IEC 19775-1 §19.4.13, Shoemake 1987): `squad(qᵢ, qᵢ₊₁, sᵢ, sᵢ₊₁, u) =
//!   slerp(slerp(qᵢ, qᵢ₊₁, u), slerp(sᵢ, sᵢ₊₁, u), 2u(1−u))`, `sᵢ = qᵢ·exp(−(log(qᵢ⁻¹qᵢ₊₁) +
//!   log(qᵢ⁻¹qᵢ₋₁))/4)`; the ends, which the specification leaves open, as X_ITE plays them:
//!   `s₀ = q₀`, `sₙ₋₁ = qₙ₋₁` (with `closed`, `qₙ₋₂` and `q₁` are the wrapped neighbours).
//! * Hermite splines (§19.2.4): `[s³ s² s 1]·C·[vᵢ, vᵢ₊₁, F⁺ᵢTᵢ, F⁻ᵢ₊₁Tᵢ₊₁]`,
//!   `F⁺ᵢ = 2Δᵢ₋₁/(Δᵢ₋₁+Δᵢ)`, `F⁻ᵢ = 2Δᵢ/(Δᵢ₋₁+Δᵢ)` (1 at an open spline's ends), `Tᵢ` the
//!   key's velocity or `(vᵢ₊₁ − vᵢ₋₁)/2` (zero at the open ends).
//!
//! Evenly spaced squad keys must come in exactly (the TCB keys keyrig keeps, within float
//! rounding); unevenly spaced ones resampled within `SQUAD_TOLERANCE_DEG`.

use std::collections::HashMap;

use keyrig_core::channel_id::{ChannelId, ChannelValue};
use keyrig_core::Interpolation;
use keyrig_eval::{Overrides, SceneEvaluator};
use keyrig_io::vrml::splines::SQUAD_TOLERANCE_DEG;

type Q = [f64; 4];

fn mul(a: Q, b: Q) -> Q {
    [
        a[0] * b[0] - a[1] * b[1] - a[2] * b[2] - a[3] * b[3],
        a[0] * b[1] + a[1] * b[0] + a[2] * b[3] - a[3] * b[2],
        a[0] * b[2] - a[1] * b[3] + a[2] * b[0] + a[3] * b[1],
        a[0] * b[3] + a[1] * b[2] - a[2] * b[1] + a[3] * b[0],
    ]
}

fn conj(a: Q) -> Q {
    [a[0], -a[1], -a[2], -a[3]]
}

fn dot(a: Q, b: Q) -> f64 {
    a.iter().zip(b).map(|(x, y)| x * y).sum()
}

fn neg(a: Q) -> Q {
    a.map(|x| -x)
}

/// Unit quaternion → pure quaternion `(0, θ/2·n)`.
fn qlog(a: Q) -> [f64; 3] {
    let s = (a[1] * a[1] + a[2] * a[2] + a[3] * a[3]).sqrt();
    if s < 1e-300 {
        return [0.0; 3];
    }
    let half = s.atan2(a[0]);
    [a[1] / s * half, a[2] / s * half, a[3] / s * half]
}

fn qexp(v: [f64; 3]) -> Q {
    let h = (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
    if h < 1e-300 {
        return [1.0, 0.0, 0.0, 0.0];
    }
    let k = h.sin() / h;
    [h.cos(), v[0] * k, v[1] * k, v[2] * k]
}

/// Great-arc interpolation without choosing the short way (Shoemake's slerp).
fn slerp(a: Q, b: Q, u: f64) -> Q {
    let c = dot(a, b).clamp(-1.0, 1.0);
    let theta = c.acos();
    if theta.abs() < 1e-12 {
        return a;
    }
    let (wa, wb) = (((1.0 - u) * theta).sin() / theta.sin(), (u * theta).sin() / theta.sin());
    std::array::from_fn(|i| wa * a[i] + wb * b[i])
}

/// VRML's axis-angle rotation as a unit quaternion.
fn axis_angle(r: [f64; 4]) -> Q {
    let n = (r[0] * r[0] + r[1] * r[1] + r[2] * r[2]).sqrt();
    let (s, c) = (r[3] / 2.0).sin_cos();
    [c, r[0] / n * s, r[1] / n * s, r[2] / n * s]
}

/// The rotation angle between two unit quaternions, degrees (q and −q are one rotation).
fn degrees_between(a: Q, b: Q) -> f64 {
    let b = if dot(a, b) < 0.0 { neg(b) } else { b };
    let d: f64 = a.iter().zip(b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt();
    let s: f64 = a.iter().zip(b).map(|(x, y)| (x + y) * (x + y)).sum::<f64>().sqrt();
    (4.0 * d.atan2(s)).to_degrees()
}

/// `sᵢ = qᵢ·exp(−(log(qᵢ⁻¹qᵢ₊₁) + log(qᵢ⁻¹qᵢ₋₁))/4)`, neighbours turned to the key's sign.
fn shoemake(prev: Q, q: Q, next: Q) -> Q {
    let prev = if dot(prev, q) < 0.0 { neg(prev) } else { prev };
    let next = if dot(next, q) < 0.0 { neg(next) } else { next };
    let a = qlog(mul(conj(q), next));
    let b = qlog(mul(conj(q), prev));
    mul(q, qexp(std::array::from_fn(|i| -(a[i] + b[i]) / 4.0)))
}

/// The squad interpolator at fraction `f`.
fn squad_spec(keys: &[f64], rotations: &[[f64; 4]], closed: bool, f: f64) -> Q {
    let n = keys.len();
    let mut q: Vec<Q> = Vec::new();
    for r in rotations {
        let x = axis_angle(*r);
        let x = match q.last() {
            Some(&p) if dot(p, x) < 0.0 => neg(x),
            _ => x,
        };
        q.push(x);
    }
    let s = |i: usize| {
        if i > 0 && i + 1 < n {
            shoemake(q[i - 1], q[i], q[i + 1])
        } else if closed {
            shoemake(q[n - 2], q[i], q[1])
        } else {
            q[i]
        }
    };
    if f <= keys[0] {
        return q[0];
    }
    if f >= keys[n - 1] {
        return q[n - 1];
    }
    let i = (0..n - 1).rfind(|&i| keys[i] <= f).unwrap();
    let u = (f - keys[i]) / (keys[i + 1] - keys[i]);
    slerp(slerp(q[i], q[i + 1], u), slerp(s(i), s(i + 1), u), 2.0 * u * (1.0 - u))
}

fn rotation_file(keys: &[f64], rotations: &[[f64; 4]], cycle: f64, looping: bool, closed: bool) -> String {
    format!(
        r#"<X3D><Scene>
  <TimeSensor DEF="T" cycleInterval="{cycle}" loop="{looping}"/>
  <SquadOrientationInterpolator DEF="S" closed="{closed}" key="{}" keyValue="{}"/>
  <Transform DEF="X"><Shape><Box/></Shape></Transform>
  <ROUTE fromNode="T" fromField="fraction_changed" toNode="S" toField="set_fraction"/>
  <ROUTE fromNode="S" fromField="value_changed" toNode="X" toField="set_rotation"/>
</Scene></X3D>"#,
        keys.iter().map(f64::to_string).collect::<Vec<_>>().join(" "),
        rotations.iter().map(|r| r.map(|x| x.to_string()).join(" ")).collect::<Vec<_>>().join(", ")
    )
}

/// Imports a squad file and compares keyrig's rotation with the specification's at every
/// frame: (frames compared, worst angle in degrees, keys keyrig holds, any TCB key).
fn squad_case(
    keys: &[f64],
    rotations: &[[f64; 4]],
    cycle: f64,
    looping: bool,
    closed: bool,
) -> (usize, f64, usize, bool) {
    let text = rotation_file(keys, rotations, cycle, looping, closed);
    let model = keyrig_io::vrml::import_vrml_slice(text.as_bytes(), "squad.x3d").unwrap();
    let scene = model.to_scene("squad.x3d");
    let track = &scene.objects[0].rotation.track.keys;
    let tcb = track.iter().any(|k| k.interpolation == Interpolation::Tcb);
    let evaluator = SceneEvaluator::new(&scene, &HashMap::new());
    let (mut frames, mut worst) = (0, 0.0f64);
    // The scene's range (what `keyrig sample` takes) is one cycle.
    for frame in 0..=scene.frame_range.end {
        let t = f64::from(frame) / scene.fps;
        let f = (t / cycle).min(1.0);
        let expected = squad_spec(keys, rotations, closed, f);
        let ChannelValue::Rotation(got) =
            evaluator.value(ChannelId::ObjectRotation(0), t, &Overrides::default()).unwrap()
        else {
            panic!("not a rotation")
        };
        let got = [got.w, got.x, got.y, got.z].map(f64::from);
        worst = worst.max(degrees_between(got, expected));
        frames += 1;
    }
    (frames, worst, track.len(), tcb)
}

const ROTATIONS: [[f64; 4]; 5] = [
    [0.0, 0.0, 1.0, 0.0],
    [1.0, 0.0, 0.0, 1.2],
    [0.0, 1.0, 0.0, 2.0],
    [1.0, 1.0, 0.0, -1.0],
    [0.0, 0.0, 1.0, 0.7],
];

#[test]
fn evenly_spaced_squad_is_imported_exactly() {
    let keys = [0.0, 0.25, 0.5, 0.75, 1.0];
    for looping in [true, false] {
        let (frames, worst, held, tcb) = squad_case(&keys, &ROTATIONS, 4.0, looping, false);
        // Exact: keyrig holds the file's five keys as TCB keys and plays the same curve.
        assert!(tcb && held == 5, "looping {looping}: {held} keys, TCB {tcb}");
        assert!(worst < 1e-4, "looping {looping}: worst {worst}° over {frames} frames");
        assert_eq!(frames, 121);
    }
    // Keys that do not start at 0 or end at 1 (hold keys around them), still evenly spaced.
    let keys = [0.1, 0.3, 0.5, 0.7, 0.9];
    let (frames, worst, held, tcb) = squad_case(&keys, &ROTATIONS, 3.0, true, false);
    assert!(tcb && held == 7, "{held} keys, TCB {tcb}");
    assert!(worst < 1e-4, "worst {worst}° over {frames} frames");
}

#[test]
fn unevenly_spaced_squad_is_resampled_within_the_tolerance() {
    let keys = [0.0, 0.1, 0.45, 0.6, 1.0];
    for looping in [true, false] {
        let (frames, worst, held, tcb) = squad_case(&keys, &ROTATIONS, 4.0, looping, false);
        assert!(!tcb && held > keys.len(), "looping {looping}: {held} keys");
        // The tolerance, plus f32 rounding of the keys.
        assert!(
            worst <= SQUAD_TOLERANCE_DEG + 1e-4,
            "looping {looping}: worst {worst}° over {frames} frames"
        );
        assert!(frames >= 121);
    }
}

#[test]
fn closed_and_two_key_squads_follow_the_specification() {
    // Closed: the first and last keys are one rotation, the neighbours wrap.
    let keys = [0.0, 0.25, 0.5, 0.75, 1.0];
    let mut closed = ROTATIONS;
    closed[4] = closed[0];
    let (frames, worst, _, tcb) = squad_case(&keys, &closed, 2.0, true, true);
    assert!(tcb, "a looping closed squad with even keys is keyrig's repeating TCB track");
    assert!(worst < 1e-4, "closed: worst {worst}° over {frames} frames");
    // Two keys: squad is the slerp.
    let (frames, worst, held, _) = squad_case(&[0.2, 0.6], &ROTATIONS[1..3], 1.0, false, false);
    assert!(worst < 1e-4 && held == 4, "two keys: worst {worst}° over {frames} frames, {held} keys");
}

/// The Hermite spline of §19.2.4 at fraction `f` (open spline).
fn hermite_spec(keys: &[f64], values: &[f64], velocity: Option<&[f64]>, f: f64) -> f64 {
    let n = keys.len();
    if f <= keys[0] {
        return values[0];
    }
    if f >= keys[n - 1] {
        return values[n - 1];
    }
    let tangent = |i: usize| match velocity {
        Some(v) => v[i],
        None if i == 0 || i == n - 1 => 0.0,
        None => (values[i + 1] - values[i - 1]) / 2.0,
    };
    let f_plus = |i: usize| {
        if i == 0 || i == n - 1 {
            1.0
        } else {
            2.0 * (keys[i] - keys[i - 1]) / (keys[i + 1] - keys[i - 1])
        }
    };
    let f_minus = |i: usize| {
        if i == 0 || i == n - 1 {
            1.0
        } else {
            2.0 * (keys[i + 1] - keys[i]) / (keys[i + 1] - keys[i - 1])
        }
    };
    let i = (0..n - 1).rfind(|&i| keys[i] <= f).unwrap();
    let s = (f - keys[i]) / (keys[i + 1] - keys[i]);
    let (s2, s3) = (s * s, s * s * s);
    // [s³ s² s 1] · C · [v_i, v_i+1, T0_i, T1_i+1]ᵀ with C = [[2,−2,1,1],[−3,3,−2,−1],[0,0,1,0],[1,0,0,0]].
    let g = [values[i], values[i + 1], f_plus(i) * tangent(i), f_minus(i + 1) * tangent(i + 1)];
    let c = [[2.0, -2.0, 1.0, 1.0], [-3.0, 3.0, -2.0, -1.0], [0.0, 0.0, 1.0, 0.0], [1.0, 0.0, 0.0, 0.0]];
    let row = [s3, s2, s, 1.0];
    (0..4).map(|r| row[r] * (0..4).map(|k| c[r][k] * g[k]).sum::<f64>()).sum()
}

#[test]
fn x3d_spline_scalar_interpolator_follows_the_specification() {
    let keys = [0.0, 0.15, 0.3, 0.8, 1.0];
    let values = [0.2, 0.9, 0.4, 0.6, 0.1];
    let velocity = [0.5, -1.0, 0.3, 0.0, -0.4];
    let list = |v: &[f64]| v.iter().map(f64::to_string).collect::<Vec<_>>().join(" ");
    let text = format!(
        r#"<X3D><Scene>
  <TimeSensor DEF="T" cycleInterval="3" loop="true"/>
  <SplineScalarInterpolator DEF="A" key="{k}" keyValue="{v}"/>
  <SplineScalarInterpolator DEF="B" key="{k}" keyValue="{v}" keyVelocity="{w}"/>
  <PointLight DEF="L1"/>
  <PointLight DEF="L2"/>
  <ROUTE fromNode="T" fromField="fraction_changed" toNode="A" toField="set_fraction"/>
  <ROUTE fromNode="T" fromField="fraction_changed" toNode="B" toField="set_fraction"/>
  <ROUTE fromNode="A" fromField="value_changed" toNode="L1" toField="set_intensity"/>
  <ROUTE fromNode="B" fromField="value_changed" toNode="L2" toField="set_intensity"/>
</Scene></X3D>"#,
        k = list(&keys),
        v = list(&values),
        w = list(&velocity)
    );
    let model = keyrig_io::vrml::import_vrml_slice(text.as_bytes(), "scalar.x3d").unwrap();
    assert!(model.skipped.iter().all(|s| !s.what.contains("Spline")), "{:?}", model.skipped);
    let scene = model.to_scene("scalar.x3d");
    let evaluator = SceneEvaluator::new(&scene, &HashMap::new());
    for (light, velocity) in [(0, None), (1, Some(&velocity[..]))] {
        let (mut frames, mut worst) = (0, 0.0f64);
        for frame in 0..=scene.frame_range.end {
            let t = f64::from(frame) / scene.fps;
            let expected = hermite_spec(&keys, &values, velocity, (t / 3.0).min(1.0));
            let ChannelValue::Scalar(got) =
                evaluator.value(ChannelId::LightIntensity(light), t, &Overrides::default()).unwrap()
            else {
                panic!("not a scalar")
            };
            worst = worst.max((f64::from(got) - expected).abs());
            frames += 1;
        }
        assert!(frames == 91 && worst < 1e-5, "light {light}: {frames} frames, worst {worst}");
    }
}

#[test]
fn spline_interpolators_with_equal_keys_are_listed_not_imported() {
    let text = r#"<X3D><Scene>
  <TimeSensor DEF="T" cycleInterval="1" loop="true"/>
  <SquadOrientationInterpolator DEF="S" key="0 0.5 0.5 1" keyValue="0 0 1 0, 0 0 1 1, 0 0 1 2, 0 0 1 3"/>
  <Transform DEF="X"><Shape><Box/></Shape></Transform>
  <ROUTE fromNode="T" fromField="fraction_changed" toNode="S" toField="set_fraction"/>
  <ROUTE fromNode="S" fromField="value_changed" toNode="X" toField="set_rotation"/>
</Scene></X3D>"#;
    let model = keyrig_io::vrml::import_vrml_slice(text.as_bytes(), "jump.x3d").unwrap();
    assert!(
        model
            .skipped
            .iter()
            .any(|s| s.what == "SquadOrientationInterpolator" && s.why.contains("equal keys")),
        "{:?}",
        model.skipped
    );
    assert!(model.objects[0].rotation.track.keys.is_empty());
}

// ---------------------------------------------------------------------------------------
// Export: keyrig keys → X3D spline and squad interpolators

fn tcb(tension: f32, bias: f32) -> keyrig_core::Tcb {
    keyrig_core::Tcb { tension, continuity: 0.0, bias, clamped: false }
}

/// A scene whose channels are X3D splines exactly (evenly spaced TCB keys with C = 0; for the
/// rotation T = C = B = 0 inside and X_ITE's open ends, bias −1 first and +1 last) beside
/// channels that are not (uneven keys; T = C = B = 0 rotation ends).
fn spline_scene() -> keyrig_core::Scene {
    use glam::{Quat, Vec3};
    use keyrig_core::{Animated, Key, RawTrack};
    let even = [0.0, 0.5, 1.0, 1.5, 2.0];
    let points = [
        Vec3::ZERO,
        Vec3::new(1.0, 2.0, 0.5),
        Vec3::new(2.5, 0.0, 1.0),
        Vec3::new(3.0, 3.0, -1.0),
        Vec3::new(5.0, 1.0, 0.0),
    ];
    let turns = [
        Quat::IDENTITY,
        Quat::from_axis_angle(Vec3::X, 1.2),
        Quat::from_axis_angle(Vec3::Y, 2.0),
        Quat::from_axis_angle(Vec3::new(1.0, 1.0, 0.0).normalize(), -1.0),
        Quat::from_axis_angle(Vec3::Z, 0.7),
    ];
    let mut a = keyrig_core::Object::new("Even");
    a.translation = Animated::new(
        Vec3::ZERO,
        RawTrack::new(
            even.iter()
                .zip(points)
                .enumerate()
                .map(|(i, (&t, p))| Key::new(t, p).with_tcb(tcb(0.1 * i as f32, 0.3 - 0.2 * i as f32)))
                .collect(),
        ),
    );
    a.rotation = Animated::new(
        Quat::IDENTITY,
        RawTrack::new(
            even.iter()
                .zip(turns)
                .enumerate()
                .map(|(i, (&t, q))| {
                    Key::new(t, q).with_tcb(tcb(
                        0.0,
                        if i == 0 {
                            -1.0
                        } else if i == 4 {
                            1.0
                        } else {
                            0.0
                        },
                    ))
                })
                .collect(),
        ),
    );
    let uneven = [0.0, 0.3, 1.2, 1.4, 2.0];
    let mut b = keyrig_core::Object::new("Uneven");
    b.translation = Animated::new(
        Vec3::ZERO,
        RawTrack::new(uneven.iter().zip(points).map(|(&t, p)| Key::new(t, p)).collect()),
    );
    b.rotation = Animated::new(
        Quat::IDENTITY,
        RawTrack::new(even.iter().zip(turns).map(|(&t, q)| Key::new(t, q)).collect()),
    );
    let levels = [0.3, 0.6, 0.4, 0.7, 0.5];
    let light = keyrig_core::Light {
        name: "Lamp".into(),
        kind: keyrig_core::LightKind::Point,
        enabled: true,
        position: Animated::constant(Vec3::new(0.0, 4.0, 0.0)),
        direction: Animated::constant(-Vec3::Y),
        colour: Animated::constant(Vec3::ONE),
        intensity: Animated::new(
            0.3,
            RawTrack::new(even.iter().zip(levels).map(|(&t, v)| Key::new(t, v)).collect()),
        ),
        attributes: Default::default(),
    };
    keyrig_core::Scene { objects: vec![a, b], lights: vec![light], ..keyrig_core::Scene::default() }
}

/// One interpolator of an exported `.x3d`: its type, fields and where it is routed.
struct Written {
    kind: String,
    key: Vec<f64>,
    value: Vec<f64>,
    velocity: Vec<f64>,
}

fn floats(text: Option<&str>) -> Vec<f64> {
    text.unwrap_or("")
        .split(|c: char| c.is_whitespace() || c == ',')
        .filter(|s| !s.is_empty())
        .map(|s| s.parse().unwrap())
        .collect()
}

/// The interpolators of an exported X3D XML document by `target.field`.
fn interpolators(text: &str) -> HashMap<String, Written> {
    let doc = roxmltree::Document::parse(text).unwrap();
    let mut by_def = HashMap::new();
    for n in doc.descendants().filter(|n| n.tag_name().name().ends_with("Interpolator")) {
        by_def.insert(
            n.attribute("DEF").unwrap().to_owned(),
            Written {
                kind: n.tag_name().name().to_owned(),
                key: floats(n.attribute("key")),
                value: floats(n.attribute("keyValue")),
                velocity: floats(n.attribute("keyVelocity")),
            },
        );
    }
    let mut out = HashMap::new();
    for r in doc.descendants().filter(|n| n.tag_name().name() == "ROUTE") {
        if let Some(w) = by_def.remove(r.attribute("fromNode").unwrap()) {
            out.insert(format!("{}.{}", r.attribute("toNode").unwrap(), r.attribute("toField").unwrap()), w);
        }
    }
    out
}

/// keyrig's keys that X3D's spline and squad interpolators hold exactly are written as those
/// (and the others resampled as before); the exported keys, evaluated by the specification's
/// formulas written in this test, equal `keyrig sample` of the scene at every frame.
#[test]
fn exported_spline_and_squad_interpolators_play_what_keyrig_plays() {
    let scene = spline_scene();
    let text = keyrig_io::vrml::export::export_scene(
        &scene,
        keyrig_io::vrml::export::ExportFormat::X3dXml,
        &keyrig_io::vrml::export::VrmlExportOptions::default(),
    )
    .unwrap();
    let written = interpolators(&text);
    let kind = |k: &str| written[k].kind.as_str();
    assert_eq!(kind("Even.translation"), "SplinePositionInterpolator");
    assert_eq!(kind("Even.rotation"), "SquadOrientationInterpolator");
    assert_eq!(kind("Lamp.intensity"), "SplineScalarInterpolator");
    assert_eq!(kind("Uneven.translation"), "PositionInterpolator");
    assert_eq!(
        kind("Uneven.rotation"),
        "OrientationInterpolator",
        "T = C = B = 0 ends are not X_ITE's squad ends"
    );
    for k in ["Even.translation", "Even.rotation", "Lamp.intensity"] {
        assert_eq!(written[k].key.len(), 5, "{k}: key for key");
    }
    let evaluator = SceneEvaluator::new(&scene, &HashMap::new());
    let at = |id, t| evaluator.value(id, t, &Overrides::default()).unwrap();
    let (mut worst_position, mut worst_angle, mut worst_scalar) = (0.0f64, 0.0f64, 0.0f64);
    for frame in 0..=scene.frame_range.end {
        let t = f64::from(frame) / scene.fps;
        let f = t / 2.0;
        let w = &written["Even.translation"];
        let ChannelValue::Vec3(p) = at(ChannelId::ObjectTranslation(0), t) else { panic!() };
        for c in 0..3 {
            let values: Vec<f64> = w.value.iter().skip(c).step_by(3).copied().collect();
            let velocity: Vec<f64> = w.velocity.iter().skip(c).step_by(3).copied().collect();
            let spec = hermite_spec(&w.key, &values, Some(&velocity), f);
            worst_position = worst_position.max((spec - f64::from(p[c])).abs());
        }
        let w = &written["Even.rotation"];
        let rotations: Vec<[f64; 4]> = w.value.chunks_exact(4).map(|c| [c[0], c[1], c[2], c[3]]).collect();
        let ChannelValue::Rotation(q) = at(ChannelId::ObjectRotation(0), t) else { panic!() };
        let spec = squad_spec(&w.key, &rotations, false, f);
        worst_angle = worst_angle.max(degrees_between(spec, [q.w, q.x, q.y, q.z].map(f64::from)));
        let w = &written["Lamp.intensity"];
        let ChannelValue::Scalar(i) = at(ChannelId::LightIntensity(0), t) else { panic!() };
        let spec = hermite_spec(&w.key, &w.value, Some(&w.velocity), f);
        worst_scalar = worst_scalar.max((spec - f64::from(i)).abs());
    }
    assert!(worst_position < 1e-5, "positions: worst {worst_position}");
    assert!(worst_angle < 1e-3, "rotations: worst {worst_angle}°");
    assert!(worst_scalar < 1e-5, "intensity: worst {worst_scalar}");
    // The classic encoding writes the same nodes; VRML97 and Inventor have none of them.
    let classic = keyrig_io::vrml::export::export_scene(
        &scene,
        keyrig_io::vrml::export::ExportFormat::X3dClassic,
        &keyrig_io::vrml::export::VrmlExportOptions::default(),
    )
    .unwrap();
    assert!(
        classic.contains("SplinePositionInterpolator") && classic.contains("SquadOrientationInterpolator")
    );
    let wrl = keyrig_io::vrml::export::export_scene(
        &scene,
        keyrig_io::vrml::export::ExportFormat::Vrml97,
        &keyrig_io::vrml::export::VrmlExportOptions::default(),
    )
    .unwrap();
    assert!(!wrl.contains("Spline") && !wrl.contains("Squad"));
}
