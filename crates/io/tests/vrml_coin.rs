//! Imported VRML97 / X3D animation against Coin3D, the toolkit the IAnimEd thesis was built
//! on: for every interpolator file of `tests/corpus/vrml` and `tests/corpus/x3d`, each
//! channel keyrig imports, sampled through the scene evaluator (what `keyrig sample` prints),
//! equals Coin's own evaluation of the interpolator (`coin_reference.py`, through Debian's
//! `python3-pivy`) at every frame of the scene's range; a `CoordinateInterpolator`'s morph
//! frames equal Coin's points.
//!
//! Where Coin is not the specification: Coin's `SoVRMLColorInterpolator` blends in RGB, while
//! VRML97 (ISO/IEC 14772-1 §6.10) and X3D interpolate colours in HSV. keyrig follows the
//! specification, so colour channels are checked against the specification's HSV formula
//! written here, independently of keyrig-io's (`hsv_spec`), and the test also shows that
//! Coin's RGB differs.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use glam::Vec3;
use keyrig_core::channel_id::{ChannelId, ChannelValue};
use keyrig_eval::{Overrides, SceneEvaluator};

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus")
}

/// A Python with pivy: `python3` when it has it, else Debian's `/usr/bin/python3`.
fn python() -> String {
    for candidate in ["python3", "/usr/bin/python3"] {
        let ok = Command::new(candidate)
            .args(["-c", "from pivy import coin"])
            .output()
            .is_ok_and(|o| o.status.success());
        if ok {
            return candidate.to_owned();
        }
    }
    panic!(
        "no python3 with pivy (Coin3D) found: the VRML reference tests need Debian's python3-pivy \
         (apt-get install python3-pivy libcoin-dev)"
    );
}

#[derive(Debug, serde::Deserialize)]
struct Record {
    interpolator: String,
    #[serde(rename = "type")]
    kind: String,
    target: String,
    target_type: String,
    field: String,
    cycle: f64,
    #[serde(rename = "loop")]
    looping: bool,
    values: Vec<Vec<f64>>,
}

fn coin(python: &str, file: &Path, fps: f64, last: i32) -> Vec<Record> {
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/coin_reference.py");
    let out = Command::new(python)
        .arg(&script)
        .arg(file)
        .arg(fps.to_string())
        .arg(last.to_string())
        .output()
        .expect("run coin_reference.py");
    assert!(
        out.status.success(),
        "{}: coin_reference.py failed: {}",
        file.display(),
        String::from_utf8_lossy(&out.stderr)
    );
    serde_json::from_slice(&out.stdout).expect("coin_reference.py prints JSON")
}

/// The name a DEF becomes in keyrig (`X`, or `X 2`, `X 3`… for later instances).
fn is_instance_of(name: &str, def: &str) -> bool {
    name == def
        || name.strip_prefix(def).and_then(|r| r.strip_prefix(' ')).is_some_and(|n| n.parse::<u32>().is_ok())
}

fn numbers(v: ChannelValue) -> Vec<f64> {
    match v {
        ChannelValue::Vec3(v) => v.to_array().map(f64::from).to_vec(),
        ChannelValue::Rotation(q) => q.to_array().map(f64::from).to_vec(),
        ChannelValue::Scalar(s) => vec![f64::from(s)],
    }
}

/// Largest difference between two series: for rotations the angle in degrees (q and −q are
/// one rotation), else the largest component difference.
fn difference(rotation: bool, a: &[f64], b: &[f64]) -> f64 {
    if rotation {
        // In f64, as 2·atan2(|a − b|, |a + b|) with b's sign aligned to a: exact near 0°,
        // where acos of a dot product loses its digits.
        let norm = |v: &[f64]| {
            let n = v.iter().map(|x| x * x).sum::<f64>().sqrt();
            v.iter().map(|x| x / n).collect::<Vec<f64>>()
        };
        let (a, mut b) = (norm(a), norm(b));
        if a.iter().zip(&b).map(|(x, y)| x * y).sum::<f64>() < 0.0 {
            b.iter_mut().for_each(|x| *x = -*x);
        }
        let minus = a.iter().zip(&b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt();
        let plus = a.iter().zip(&b).map(|(x, y)| (x + y) * (x + y)).sum::<f64>().sqrt();
        (2.0 * minus.atan2(plus)).to_degrees() * 2.0
    } else {
        a.iter().zip(b).map(|(x, y)| (x - y).abs()).fold(0.0, f64::max)
    }
}

/// VRML97 §6.10's colour interpolation, written from the specification: convert both keys to
/// HSV (hue in degrees), interpolate hue along the shorter arc and saturation and value
/// linearly, convert back.
fn hsv_spec(a: [f64; 3], b: [f64; 3], u: f64) -> [f64; 3] {
    fn to_hsv([r, g, b]: [f64; 3]) -> [f64; 3] {
        let max = r.max(g).max(b);
        let min = r.min(g).min(b);
        let c = max - min;
        let h = if c == 0.0 {
            f64::NAN
        } else if max == r {
            60.0 * ((g - b) / c).rem_euclid(6.0)
        } else if max == g {
            60.0 * ((b - r) / c + 2.0)
        } else {
            60.0 * ((r - g) / c + 4.0)
        };
        [h, if max == 0.0 { 0.0 } else { c / max }, max]
    }
    fn to_rgb([h, s, v]: [f64; 3]) -> [f64; 3] {
        let c = v * s;
        let hp = h.rem_euclid(360.0) / 60.0;
        let x = c * (1.0 - (hp % 2.0 - 1.0).abs());
        let (r, g, b) = match hp as u32 {
            0 => (c, x, 0.0),
            1 => (x, c, 0.0),
            2 => (0.0, c, x),
            3 => (0.0, x, c),
            4 => (x, 0.0, c),
            _ => (c, 0.0, x),
        };
        let m = v - c;
        [r + m, g + m, b + m]
    }
    let (mut p, mut q) = (to_hsv(a), to_hsv(b));
    if p[0].is_nan() {
        p[0] = if q[0].is_nan() { 0.0 } else { q[0] };
    }
    if q[0].is_nan() {
        q[0] = p[0];
    }
    let mut dh = q[0] - p[0];
    if dh > 180.0 {
        dh -= 360.0;
    }
    if dh < -180.0 {
        dh += 360.0;
    }
    to_rgb([p[0] + u * dh, p[1] + u * (q[1] - p[1]), p[2] + u * (q[2] - p[2])])
}

/// The specification's colour at each frame: the interpolator's keys from the file (read here
/// with a regular expression, not keyrig's parser) evaluated with [`hsv_spec`].
fn spec_colours(
    file: &Path,
    interpolator: &str,
    cycle: f64,
    looping: bool,
    fps: f64,
    last: i32,
) -> Vec<Vec<f64>> {
    let text = std::fs::read_to_string(file).unwrap();
    let numbers = |s: &str| -> Vec<f64> {
        s.split(|c: char| c.is_whitespace() || c == ',' || c == '[' || c == ']' || c == '"' || c == '\'')
            .filter_map(|t| t.parse().ok())
            .collect()
    };
    let (key, value) = if file.extension().is_some_and(|e| e == "x3d") {
        let start = text
            .find(&format!("DEF='{interpolator}'"))
            .or_else(|| text.find(&format!("DEF=\"{interpolator}\"")))
            .unwrap();
        let element = &text[text[..start].rfind('<').unwrap()..];
        let element = &element[..element.find('>').unwrap()];
        let attr = |name: &str| {
            let i = element.find(&format!(" {name}=")).unwrap() + name.len() + 2;
            let quote = element.as_bytes()[i] as char;
            let rest = &element[i + 1..];
            rest[..rest.find(quote).unwrap()].to_owned()
        };
        (numbers(&attr("key")), numbers(&attr("keyValue")))
    } else {
        let start = text.find(&format!("DEF {interpolator} ")).unwrap();
        let body = &text[start..];
        let body = &body[..body.find('}').unwrap()];
        let list = |name: &str| {
            let i = body.find(&format!("{name} ")).unwrap() + name.len();
            let rest = &body[i..];
            let open = rest.find('[').unwrap();
            numbers(&rest[open..open + rest[open..].find(']').unwrap()])
        };
        (list("key"), list("keyValue"))
    };
    let colours: Vec<[f64; 3]> = value.chunks_exact(3).map(|c| [c[0], c[1], c[2]]).collect();
    (0..=last)
        .map(|frame| {
            let t = f64::from(frame) / fps;
            let q = t / cycle;
            let f = if !looping {
                q.clamp(0.0, 1.0)
            } else if q <= 1.0 {
                q
            } else {
                q - q.floor()
            };
            let n = key.len();
            if f <= key[0] {
                return colours[0].to_vec();
            }
            if f >= key[n - 1] {
                return colours[n - 1].to_vec();
            }
            let i = key.iter().rposition(|&k| k <= f).unwrap();
            let u = (f - key[i]) / (key[i + 1] - key[i]);
            hsv_spec(colours[i], colours[i + 1], u).to_vec()
        })
        .collect()
}

/// Checks one file; returns how many channels and frames were compared.
fn check(python: &str, file: &Path) -> (usize, usize) {
    let model = keyrig_io::vrml::import_vrml_file(file).unwrap_or_else(|e| panic!("{e}"));
    let scene = model.to_scene("model");
    let evaluator = SceneEvaluator::new(&scene, &HashMap::new());
    let (fps, last) = (scene.fps, scene.frame_range.end);
    let records = coin(python, file, fps, last);
    assert!(!records.is_empty(), "{}: Coin found no animation", file.display());
    let sample = |id: ChannelId| -> Vec<Vec<f64>> {
        (0..=last)
            .map(|f| {
                numbers(evaluator.value(id, f64::from(f) / fps, &Overrides::default()).expect("channel"))
            })
            .collect()
    };
    let worst = |rotation: bool, a: &[Vec<f64>], b: &[Vec<f64>]| -> (f64, usize) {
        a.iter()
            .zip(b)
            .enumerate()
            .map(|(f, (x, y))| (difference(rotation, x, y), f))
            .fold((0.0, 0), |m, d| if d.0 > m.0 { d } else { m })
    };
    let skipped = model.skipped_lines().join("\n");
    let mut compared = 0;
    for r in &records {
        let here = format!("{}: {} {} → {}.{}", file.display(), r.kind, r.interpolator, r.target, r.field);
        match (r.target_type.as_str(), r.field.as_str()) {
            ("Transform", "translation" | "rotation" | "scale") => {
                // Every object or joint that is an instance of this DEF and animates the
                // property; at least one must be driven by this interpolator. (An object takes
                // the name of the nearest DEF above its shape, which may be below the animated
                // Transform: then every animated channel of the property is a candidate.)
                let named = scene.objects.iter().any(|o| {
                    is_instance_of(&o.name, &r.target)
                        || o.skeleton
                            .iter()
                            .flat_map(|s| s.joints.iter())
                            .any(|j| is_instance_of(&j.name, &r.target))
                });
                let mut candidates = Vec::new();
                for (o, object) in scene.objects.iter().enumerate() {
                    if !named || is_instance_of(&object.name, &r.target) {
                        let (id, animated) = match r.field.as_str() {
                            "translation" => {
                                (ChannelId::ObjectTranslation(o), object.translation.is_animated())
                            }
                            "rotation" => (ChannelId::ObjectRotation(o), object.rotation.is_animated()),
                            _ => (ChannelId::ObjectScale(o), object.scale.is_animated()),
                        };
                        if animated {
                            candidates.push((format!("object/{}", object.name), id));
                        }
                    }
                    for (j, joint) in object.skeleton.iter().flat_map(|s| s.joints.iter()).enumerate() {
                        if !named || is_instance_of(&joint.name, &r.target) {
                            let (id, animated) = match r.field.as_str() {
                                "translation" => (
                                    ChannelId::JointTranslation { object: o, joint: j },
                                    joint.translation.is_animated(),
                                ),
                                "rotation" => (
                                    ChannelId::JointRotation { object: o, joint: j },
                                    joint.rotation.is_animated(),
                                ),
                                _ => {
                                    (ChannelId::JointScale { object: o, joint: j }, joint.scale.is_animated())
                                }
                            };
                            if animated {
                                candidates.push((format!("object/{}/joint/{}", object.name, joint.name), id));
                            }
                        }
                    }
                }
                assert!(!candidates.is_empty(), "{here}: keyrig has no animated channel for it");
                let rotation = r.field == "rotation";
                let results: Vec<(String, f64, usize)> = candidates
                    .iter()
                    .map(|(name, id)| {
                        let (d, f) = worst(rotation, &sample(*id), &r.values);
                        (name.clone(), d, f)
                    })
                    .collect();
                let tolerance = if rotation { 1e-3 } else { 1e-5 };
                assert!(
                    results.iter().any(|(_, d, _)| *d <= tolerance),
                    "{here}: no keyrig channel equals Coin's values: {results:?}"
                );
                compared += 1;
            }
            ("DirectionalLight" | "PointLight" | "SpotLight", field) => {
                let l = scene
                    .lights
                    .iter()
                    .position(|l| is_instance_of(&l.name, &r.target))
                    .unwrap_or_else(|| panic!("{here}: no light"));
                let (id, expected) = match field {
                    "direction" => (ChannelId::LightDirection(l), r.values.clone()),
                    "location" => (ChannelId::LightPosition(l), r.values.clone()),
                    "intensity" => (ChannelId::LightIntensity(l), r.values.clone()),
                    "cutOffAngle" | "beamWidth" => {
                        let id = if field == "cutOffAngle" {
                            keyrig_core::AttributeId::LightCutoff(l)
                        } else {
                            keyrig_core::AttributeId::LightInnerAngle(l)
                        };
                        let degrees = r.values.iter().map(|v| vec![v[0].to_degrees()]).collect();
                        (ChannelId::Attribute(id), degrees)
                    }
                    "color" => {
                        let spec = spec_colours(file, &r.interpolator, r.cycle, r.looping, fps, last);
                        let (coin_vs_spec, _) = worst(false, &spec, &r.values);
                        // Coin blends in RGB; the specification in HSV.
                        assert!(coin_vs_spec > 1e-3, "{here}: Coin agrees with HSV ({coin_vs_spec})");
                        (ChannelId::LightColour(l), spec)
                    }
                    other => {
                        assert!(
                            skipped.contains(&format!(".{other} animation")),
                            "{here}: not listed as skipped:\n{skipped}"
                        );
                        continue;
                    }
                };
                let tolerance = if field == "color" { 1.5e-3 } else { 1e-5 };
                let (d, f) = worst(false, &sample(id), &expected);
                assert!(d <= tolerance, "{here}: differs by {d} at frame {f}");
                compared += 1;
            }
            ("Viewpoint", field @ ("position" | "orientation" | "fieldOfView")) => {
                let c = scene
                    .cameras
                    .iter()
                    .position(|c| is_instance_of(&c.name, &r.target))
                    .unwrap_or_else(|| panic!("{here}: no camera"));
                let (id, expected) = match field {
                    "position" => (ChannelId::CameraTranslation(c), r.values.clone()),
                    "orientation" => (ChannelId::CameraRotation(c), r.values.clone()),
                    // VRML's field of view in radians; keyrig's lens in degrees.
                    _ => (
                        ChannelId::CameraLens(c),
                        r.values.iter().map(|v| v.iter().map(|x| x.to_degrees()).collect()).collect(),
                    ),
                };
                let rotation = field == "orientation";
                // f32 precision of the values (the castle's camera flies 300 units out).
                let size = expected.iter().flatten().fold(1.0f64, |m, x| m.max(x.abs()));
                let tolerance = if rotation { 1e-3 } else { 1e-5 * size };
                let (d, f) = worst(rotation, &sample(id), &expected);
                assert!(
                    d <= tolerance,
                    "{here}: camera {} differs by {d} at frame {f}",
                    scene.cameras[c].name
                );
                compared += 1;
            }
            ("Material", field @ ("diffuseColor" | "transparency")) => {
                // Every object whose material this is has the attribute; at least one is
                // driven by this interpolator.
                let expected = if field == "diffuseColor" {
                    // The specification's HSV (Coin's RGB agrees only where the blend keeps
                    // its hue and saturation).
                    spec_colours(file, &r.interpolator, r.cycle, r.looping, fps, last)
                } else {
                    r.values.iter().map(|v| vec![1.0 - v[0]]).collect()
                };
                let results: Vec<(String, f64)> = scene
                    .objects
                    .iter()
                    .enumerate()
                    .filter_map(|(o, object)| {
                        let id = if field == "diffuseColor" {
                            object.attributes.colour.as_ref()?;
                            keyrig_core::AttributeId::ObjectColour(o)
                        } else {
                            object.attributes.opacity.is_animated().then_some(())?;
                            keyrig_core::AttributeId::ObjectOpacity(o)
                        };
                        Some((
                            object.name.clone(),
                            worst(false, &sample(ChannelId::Attribute(id)), &expected).0,
                        ))
                    })
                    .collect();
                let tolerance = if field == "diffuseColor" { 1.5e-3 } else { 1e-5 };
                assert!(
                    results.iter().any(|(_, d)| *d <= tolerance),
                    "{here}: no object's {field} equals: {results:?}"
                );
                compared += 1;
            }
            ("Coordinate", "point") => {
                let (o, mesh) = scene
                    .objects
                    .iter()
                    .zip(&model.meshes)
                    .find(|(_, m)| m.morph.is_some())
                    .unwrap_or_else(|| panic!("{here}: no morphing mesh"));
                let morph = mesh.morph.as_ref().unwrap();
                let clips = keyrig_eval::morph::MorphClips::new(morph.frames.len(), Vec::new())
                    .unwrap()
                    .with_key_times(morph.times.clone(), morph.period)
                    .unwrap();
                let points = mesh.vertex_points.as_ref().expect("a polygon mesh");
                let mut worst_d: f64 = 0.0;
                for (frame, coin_points) in r.values.iter().enumerate() {
                    let b = clips.blend_at(None, 10.0, frame as f64 / fps).unwrap();
                    let (fa, fb) = (&morph.frames[b.frame_a as usize], &morph.frames[b.frame_b as usize]);
                    for (v, &p) in points.iter().enumerate() {
                        let keyrig = fa.positions[v].lerp(fb.positions[v], b.t);
                        let c = &coin_points[3 * p as usize..3 * p as usize + 3];
                        let coin =
                            mesh.baked.transform_point3(Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32));
                        worst_d = worst_d.max(f64::from((keyrig - coin).abs().max_element()));
                    }
                }
                assert!(worst_d <= 1e-5, "{here} ({}): morph differs by {worst_d}", o.name);
                compared += 1;
            }
            (kind, field) => {
                assert!(
                    skipped.contains(&format!("{kind}.{field} animation")),
                    "{here}: neither imported nor listed as not imported:\n{skipped}"
                );
            }
        }
    }
    (compared, last as usize + 1)
}

/// Every interpolator file of the corpus, in each encoding it comes in.
#[test]
fn imported_animation_equals_coin3d_at_every_frame() {
    let python = python();
    let files = [
        "vrml/castle-demo-models/vrml_engine_doc_simple_examples/moving.wrl",
        "vrml/vrml2sourcebook/Chapter08AnimatingPositionOrientationScale/Figure08_3PositionInterpolator.wrl",
        "vrml/vrml2sourcebook/Chapter08AnimatingPositionOrientationScale/Figure08_4OrientationInterpolator.wrl",
        "vrml/vrml2sourcebook/Chapter08AnimatingPositionOrientationScale/Figure08_5AnimatingScale.wrl",
        "vrml/vrml2sourcebook/Chapter13PointsLinesFaces/Figure13_17aMorphingCube.wrl",
        "vrml/vrml2sourcebook/Chapter20Lighting/Figure20_14DirectionalLightSunAnimated.wrl",
        "vrml/vrml2sourcebook/Chapter31Prototypes/Figure31_9SpinGroupPrototype.wrl",
        "x3d/vrml2sourcebook/Chapter08AnimatingPositionOrientationScale/Figure08_3PositionInterpolator.x3d",
        "x3d/vrml2sourcebook/Chapter08AnimatingPositionOrientationScale/Figure08_3PositionInterpolator.x3dv",
        "x3d/vrml2sourcebook/Chapter08AnimatingPositionOrientationScale/Figure08_4OrientationInterpolator.x3d",
        "x3d/vrml2sourcebook/Chapter08AnimatingPositionOrientationScale/Figure08_5AnimatingScale.x3d",
        "x3d/vrml2sourcebook/Chapter13PointsLinesFaces/Figure13_17aMorphingCube.x3d",
        "x3d/vrml2sourcebook/Chapter13PointsLinesFaces/Figure13_17aMorphingCube.x3dv",
        "x3d/vrml2sourcebook/Chapter20Lighting/Figure20_14DirectionalLightSunAnimated.x3d",
        "x3d/nist-conformance/Interpolators/PositionInterpolator/simple.x3d",
        "x3d/nist-conformance/Interpolators/PositionInterpolator/hierarchy.x3d",
        "x3d/nist-conformance/Interpolators/OrientationInterpolator/simple.x3d",
        "x3d/nist-conformance/Interpolators/OrientationInterpolator/hierarchy.x3d",
        "x3d/nist-conformance/Interpolators/ScalarInterpolator/simple.x3d",
        "x3d/nist-conformance/Interpolators/ColorInterpolator/simple.x3d",
        "x3d/nist-conformance/Interpolators/ColorInterpolator/samekeys.x3d",
        "x3d/nist-conformance/Interpolators/CoordinateInterpolator/simple.x3d",
        "x3d/nist-conformance/Sensors/TimeSensor/loop.x3d",
        "x3d/castle-demo-models/animation/simple_tests_interpolation_and_time/orientation_cos_1.x3d",
        "x3d/castle-demo-models/animation/simple_tests_interpolation_and_time/orientation_interpolation.x3dv",
        "x3d/castle-demo-models/animation/simple_tests_interpolation_and_time/worm_crawl.x3dv",
        "x3d/castle-demo-models/lights_materials/light_color_animated.x3dv",
        "x3d/castle-demo-models/x3d/animate_camera.x3dv",
    ];
    let mut total = 0;
    for f in files {
        let (channels, frames) = check(&python, &corpus().join(f));
        eprintln!("{f}: {channels} channels × {frames} frames equal Coin's");
        total += channels;
    }
    assert!(total >= 25, "{total} channels compared");
}

/// The X3D XML and X3D classic twins of the Sourcebook's SpinGroup PROTO (which the reference
/// script does not translate for Coin) import to the same channels as the VRML97 file Coin
/// checks above.
#[test]
fn proto_files_in_every_encoding_import_the_same_animation() {
    let load = |f: &str| {
        let model = keyrig_io::vrml::import_vrml_file(&corpus().join(f)).unwrap();
        model.to_scene("model")
    };
    let wrl = load("vrml/vrml2sourcebook/Chapter31Prototypes/Figure31_9SpinGroupPrototype.wrl");
    for other in [
        "x3d/vrml2sourcebook/Chapter31Prototypes/Figure31_9SpinGroupPrototype.x3d",
        "x3d/vrml2sourcebook/Chapter31Prototypes/Figure31_9SpinGroupPrototype.x3dv",
    ] {
        let scene = load(other);
        assert_eq!(scene.objects.len(), wrl.objects.len(), "{other}");
        for (a, b) in scene.objects.iter().zip(&wrl.objects) {
            assert_eq!(a.name, b.name, "{other}");
            assert_eq!(a.rotation, b.rotation, "{other}: {}", a.name);
            assert_eq!(a.skeleton, b.skeleton, "{other}: {}", a.name);
        }
    }
}

/// X3D's `SplinePositionInterpolator` is not in Coin (a VRML97 toolkit): keyrig's Hermite keys
/// are checked against the specification's formula written here (ISO/IEC 19775-1, 19.2.4
/// "Hermite spline interpolation"): `S(s) = [s³ s² s 1] · C · [vᵢ, vᵢ₊₁, T⁰ᵢ, T¹ᵢ₊₁]` with
/// `C = [[2, −2, 1, 1], [−3, 3, −2, −1], [0, 0, 1, 0], [1, 0, 0, 0]]`, `Tᵢ = (vᵢ₊₁ − vᵢ₋₁)/2`
/// (zero at the ends of an open spline), `T⁰ᵢ = F⁺ᵢ·Tᵢ`, `T¹ᵢ = F⁻ᵢ·Tᵢ`,
/// `F⁻ᵢ = 2(tᵢ₊₁ − tᵢ)/(tᵢ₊₁ − tᵢ₋₁)`, `F⁺ᵢ = 2(tᵢ − tᵢ₋₁)/(tᵢ₊₁ − tᵢ₋₁)` — on unevenly spaced
/// keys, where the scaling matters, at every frame.
#[test]
fn x3d_spline_position_interpolator_follows_the_specification() {
    let keys = [0.0, 0.2, 0.3, 0.7, 1.0];
    let values = [[0.0, 0.0, 0.0], [1.0, 2.0, 0.0], [2.0, 0.5, 1.0], [3.0, 3.0, -1.0], [5.0, 0.0, 0.0]];
    let text = format!(
        r#"<X3D><Scene>
  <TimeSensor DEF="T" cycleInterval="3" loop="true"/>
  <SplinePositionInterpolator DEF="S" key="{}" keyValue="{}"/>
  <Transform DEF="X"><Shape><Box/></Shape></Transform>
  <ROUTE fromNode="T" fromField="fraction_changed" toNode="S" toField="set_fraction"/>
  <ROUTE fromNode="S" fromField="value_changed" toNode="X" toField="set_translation"/>
</Scene></X3D>"#,
        keys.map(|k| k.to_string()).join(" "),
        values.iter().map(|v| format!("{} {} {}", v[0], v[1], v[2])).collect::<Vec<_>>().join(", ")
    );
    let model = keyrig_io::vrml::import_vrml_slice(text.as_bytes(), "spline.x3d").unwrap();
    let scene = model.to_scene("spline.x3d");
    let evaluator = SceneEvaluator::new(&scene, &HashMap::new());
    let n = keys.len();
    let tangent = |i: usize| -> [f64; 3] {
        if i == 0 || i == n - 1 {
            [0.0; 3]
        } else {
            std::array::from_fn(|c| (values[i + 1][c] - values[i - 1][c]) / 2.0)
        }
    };
    let (mut compared, mut worst) = (0, 0.0f64);
    for frame in 0..=scene.frame_range.end {
        let t = f64::from(frame) / scene.fps;
        let f = (t / 3.0).min(1.0);
        let i = (0..n - 1).rfind(|&i| keys[i] <= f).unwrap();
        let s = (f - keys[i]) / (keys[i + 1] - keys[i]);
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
        let (t0, t1) = (tangent(i).map(|x| x * f_plus(i)), tangent(i + 1).map(|x| x * f_minus(i + 1)));
        let h = [
            2.0 * s * s * s - 3.0 * s * s + 1.0,
            -2.0 * s * s * s + 3.0 * s * s,
            s * s * s - 2.0 * s * s + s,
            s * s * s - s * s,
        ];
        let expected: [f64; 3] = std::array::from_fn(|c| {
            h[0] * values[i][c] + h[1] * values[i + 1][c] + h[2] * t0[c] + h[3] * t1[c]
        });
        let got =
            numbers(evaluator.value(ChannelId::ObjectTranslation(0), t, &Overrides::default()).unwrap());
        let d = got.iter().zip(expected).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
        worst = worst.max(d);
        compared += 1;
    }
    assert!(compared == 91 && worst < 1e-5, "{compared} frames, worst {worst}");
}

/// Equal keys make a jump (VRML97 §4.6.8): the segment before ends on the first of their
/// values and the last shows from the key on; Coin agrees at every frame, including the frame
/// on the key (the samekeys case of the NIST suite, on a Transform keyrig imports, and on an
/// orientation), for a looping and a one-shot sensor.
#[test]
fn equal_keys_jump_as_coin_does() {
    let python = python();
    let dir = tempfile::tempdir().unwrap();
    for looping in ["TRUE", "FALSE"] {
        let path = dir.path().join(format!("jump_{looping}.wrl"));
        std::fs::write(
            &path,
            format!(
                "#VRML V2.0 utf8\nDEF T TimeSensor {{ cycleInterval 2 loop {looping} }}\n\
                 DEF P PositionInterpolator {{ key [ 0.1 0.5 0.5 0.5 0.9 ] keyValue [ 0 0 0, 1 0 0, 5 5 5, 0 2 0, 0 0 3 ] }}\n\
                 DEF O OrientationInterpolator {{ key [ 0 0.5 0.5 1 ] keyValue [ 0 0 1 0, 0 0 1 1, 1 0 0 2, 1 0 0 0.5 ] }}\n\
                 DEF X Transform {{ children Shape {{ geometry Box {{ }} }} }}\n\
                 ROUTE T.fraction_changed TO P.set_fraction\nROUTE T.fraction_changed TO O.set_fraction\n\
                 ROUTE P.value_changed TO X.set_translation\nROUTE O.value_changed TO X.set_rotation\n"
            ),
        )
        .unwrap();
        let (channels, frames) = check(&python, &path);
        assert_eq!((channels, frames), (2, 61), "{looping}");
    }
}

/// Viewpoints are scene cameras, a Material's diffuse colour and transparency the colour and
/// opacity of its objects, a spot light's cone its cone attributes: keyrig's channels equal
/// Coin's evaluation at every frame (colours against the specification's HSV, as for lights;
/// the field of view and the cone in degrees).
#[test]
fn cameras_materials_and_light_cones_play_as_coin_plays_them() {
    let python = python();
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("cameras.wrl");
    std::fs::write(
        &path,
        "#VRML V2.0 utf8\n\
         DEF T TimeSensor { cycleInterval 3 loop TRUE }\n\
         DEF Cam Viewpoint { position 0 1 8 description \"front\" }\n\
         DEF P PositionInterpolator { key [ 0 0.4 1 ] keyValue [ 0 1 8, 3 2 6, 0 1 4 ] }\n\
         DEF O OrientationInterpolator { key [ 0 0.5 1 ] keyValue [ 0 1 0 0, 0 1 0 0.8, 1 0 0 -0.3 ] }\n\
         DEF F ScalarInterpolator { key [ 0 1 ] keyValue [ 0.785 0.4 ] }\n\
         DEF Box Transform { children Shape { appearance Appearance { material DEF M Material { diffuseColor 1 0 0 } }\n\
           geometry Box { } } }\n\
         DEF C ColorInterpolator { key [ 0 0.5 1 ] keyValue [ 1 0 0, 0 0 1, 0 1 0 ] }\n\
         DEF A ScalarInterpolator { key [ 0 0.7 1 ] keyValue [ 0 0.6 0.2 ] }\n\
         DEF Spot SpotLight { location 0 5 0 direction 0 -1 0 }\n\
         DEF K ScalarInterpolator { key [ 0 1 ] keyValue [ 0.3 1.2 ] }\n\
         DEF W ScalarInterpolator { key [ 0 0.5 1 ] keyValue [ 0.1 0.25 0.2 ] }\n\
         ROUTE T.fraction_changed TO P.set_fraction\nROUTE T.fraction_changed TO O.set_fraction\n\
         ROUTE T.fraction_changed TO F.set_fraction\nROUTE T.fraction_changed TO C.set_fraction\n\
         ROUTE T.fraction_changed TO A.set_fraction\nROUTE T.fraction_changed TO K.set_fraction\n\
         ROUTE T.fraction_changed TO W.set_fraction\n\
         ROUTE P.value_changed TO Cam.set_position\nROUTE O.value_changed TO Cam.set_orientation\n\
         ROUTE F.value_changed TO Cam.set_fieldOfView\nROUTE C.value_changed TO M.set_diffuseColor\n\
         ROUTE A.value_changed TO M.set_transparency\nROUTE K.value_changed TO Spot.set_cutOffAngle\n\
         ROUTE W.value_changed TO Spot.set_beamWidth\n",
    )
    .unwrap();
    let model = keyrig_io::vrml::import_vrml_file(&path).unwrap();
    assert!(model.skipped.is_empty(), "{:?}", model.skipped_lines());
    let scene = model.to_scene("cameras.wrl");
    assert_eq!(scene.cameras.len(), 1);
    assert_eq!(scene.cameras[0].name, "Cam");
    let (channels, frames) = check(&python, &path);
    assert_eq!((channels, frames), (7, 91));
}
