//! keyrig scenes written as VRML97, X3D and Open Inventor:
//!
//! - read back by keyrig, every key of every object and light is the same (T/C/B, cycles and
//!   spins included: keyrig's scene rides along as metadata), in all four encodings;
//! - read by Coin3D (`coin_reference.py`, Debian's `python3-pivy`), the exported `.wrl` and
//!   `.iv` play what keyrig plays: at every frame of the range, each interpolator Coin evaluates
//!   equals `keyrig sample` of the original scene (the scene evaluator) within 10⁻⁴ of the
//!   scene's size for positions and 0.05° for rotations, and a skinned arm's
//!   CoordinateInterpolator equals the mesh keyrig deforms with the object's own deformer.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::process::Command;

use glam::Vec3;
use keyrig_core::channel_id::{ChannelId, ChannelValue};
use keyrig_eval::{Overrides, SceneEvaluator};
use keyrig_io::vrml::export::{export_scene, ExportFormat, VrmlExportOptions};

fn assets() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets")
}

fn python() -> String {
    for candidate in ["python3", "/usr/bin/python3"] {
        if Command::new(candidate)
            .args(["-c", "from pivy import coin"])
            .output()
            .is_ok_and(|o| o.status.success())
        {
            return candidate.to_owned();
        }
    }
    panic!("no python3 with pivy (Coin3D): apt-get install python3-pivy libcoin-dev");
}

fn write(dir: &Path, scene: &keyrig_core::Scene, name: &str) -> PathBuf {
    let path = dir.join(name);
    let format = ExportFormat::of_path(&path).unwrap();
    let text = export_scene(scene, format, &VrmlExportOptions::default()).unwrap();
    keyrig_io::file_io::write_atomic(&path, text.as_bytes()).unwrap();
    path
}

#[test]
fn keyrig_reads_its_own_export_back_to_the_same_keys() {
    let dir = tempfile::tempdir().unwrap();
    for asset in ["demo.ron", "twist.ron", "cycle.ron", "ik.ron", "characters.ron"] {
        let scene = keyrig_io::project::load_scene(&assets().join(asset)).unwrap();
        for ext in ["x3d", "iv", "wrl", "x3dv"] {
            let path = write(dir.path(), &scene, &format!("{}.{ext}", asset.trim_end_matches(".ron")));
            let model = keyrig_io::vrml::import_vrml_file(&path).unwrap_or_else(|e| panic!("{e}"));
            let here = format!("{asset} → .{ext}");
            assert_eq!(model.metadata_scene.as_ref(), Some(&scene), "{here}: the metadata scene");
            let back = model.to_scene("x");
            assert_eq!((back.fps, back.frame_range), (scene.fps, scene.frame_range), "{here}");
            let with_mesh: Vec<&keyrig_core::Object> =
                scene.objects.iter().filter(|o| o.mesh.is_some()).collect();
            assert_eq!(back.objects.len(), with_mesh.len(), "{here}");
            for (a, b) in with_mesh.iter().zip(&back.objects) {
                assert_eq!(a.name, b.name, "{here}");
                if a.skeleton.is_none() {
                    assert_eq!(a.translation, b.translation, "{here}: {}", a.name);
                    assert_eq!(a.rotation, b.rotation, "{here}: {}", a.name);
                    assert_eq!(a.scale, b.scale, "{here}: {}", a.name);
                }
            }
            assert_eq!(back.lights, scene.lights, "{here}: lights");
            assert!(model.skipped.is_empty(), "{here}: {:?}", model.skipped_lines());
        }
    }
}

#[derive(Debug, serde::Deserialize)]
struct Record {
    #[serde(rename = "type")]
    kind: String,
    target: String,
    field: String,
    values: Vec<Vec<f64>>,
}

fn angle_deg(a: &[f64], b: &[f64]) -> f64 {
    let n = |v: &[f64]| {
        let l = v.iter().map(|x| x * x).sum::<f64>().sqrt();
        v.iter().map(|x| x / l).collect::<Vec<_>>()
    };
    let (a, mut b) = (n(a), n(b));
    if a.iter().zip(&b).map(|(x, y)| x * y).sum::<f64>() < 0.0 {
        b.iter_mut().for_each(|x| *x = -*x);
    }
    let minus = a.iter().zip(&b).map(|(x, y)| (x - y) * (x - y)).sum::<f64>().sqrt();
    let plus = a.iter().zip(&b).map(|(x, y)| (x + y) * (x + y)).sum::<f64>().sqrt();
    4.0 * minus.atan2(plus).to_degrees()
}

#[test]
fn coin3d_plays_the_export_as_keyrig_samples_the_scene() {
    let python = python();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/coin_reference.py");
    let dir = tempfile::tempdir().unwrap();
    for asset in ["demo.ron", "twist.ron", "cycle.ron", "ik.ron"] {
        let scene = keyrig_io::project::load_scene(&assets().join(asset)).unwrap();
        let eval = SceneEvaluator::new(&scene, &HashMap::new());
        let none = Overrides::default();
        let (fps, start, end) = (scene.fps, scene.frame_range.start, scene.frame_range.end);
        let time = |frame: usize| f64::from(start) / fps + frame as f64 / fps;
        // The scene's size: its meshes at rest.
        let mut bounds = (Vec3::MAX, Vec3::MIN);
        for o in 0..scene.objects.len() {
            if let Some(skin) = eval.skin(o) {
                for p in &skin.mesh.positions {
                    bounds = (bounds.0.min(*p), bounds.1.max(*p));
                }
            }
        }
        let size = f64::from((bounds.1 - bounds.0).length()).max(1.0);
        for ext in ["wrl", "iv"] {
            let path = write(dir.path(), &scene, &format!("{}.{ext}", asset.trim_end_matches(".ron")));
            let out = Command::new(&python)
                .arg(&script)
                .arg(&path)
                .arg(fps.to_string())
                .arg((end - start).to_string())
                .output()
                .unwrap();
            assert!(out.status.success(), "{}: {}", path.display(), String::from_utf8_lossy(&out.stderr));
            let records: Vec<Record> = serde_json::from_slice(&out.stdout).unwrap();
            let mut checked = 0;
            for r in &records {
                let here = format!("{asset} → .{ext}: {} → {}.{}", r.kind, r.target, r.field);
                let target = r.target.trim_end_matches("_xf").trim_end_matches("_points");
                let object = scene.objects.iter().position(|o| o.name.replace(' ', "_") == target);
                let light = scene.lights.iter().position(|l| l.name.replace(' ', "_") == target);
                for (frame, coin) in r.values.iter().enumerate() {
                    let t = time(frame);
                    let sample = |id| eval.value(id, t, &none).unwrap();
                    let (difference, tolerance) = match (object, light, r.field.as_str()) {
                        (Some(o), _, "translation" | "scale" | "scaleFactor") => {
                            let id = if r.field == "translation" {
                                ChannelId::ObjectTranslation(o)
                            } else {
                                ChannelId::ObjectScale(o)
                            };
                            let ChannelValue::Vec3(v) = sample(id) else { panic!() };
                            let d = v
                                .to_array()
                                .iter()
                                .zip(coin)
                                .map(|(a, b)| (f64::from(*a) - b).abs())
                                .fold(0.0, f64::max);
                            (d, 1e-4 * size)
                        }
                        (Some(o), _, "rotation") => {
                            let ChannelValue::Rotation(q) = sample(ChannelId::ObjectRotation(o)) else {
                                panic!()
                            };
                            (angle_deg(&q.to_array().map(f64::from), coin), 0.05)
                        }
                        (Some(o), _, "point") => {
                            let skin = eval.skin(o).expect("a skinned object");
                            let state = eval.object_at(o, t, &none).unwrap();
                            let mut deformed = keyrig_skin::Deformed::default();
                            keyrig_skin::deform_mesh_into(
                                &skin.mesh,
                                &skin.bindings,
                                state.palette.as_ref().unwrap(),
                                scene.objects[o].deformer.kind,
                                keyrig_skin::Execution::Reference,
                                &mut deformed,
                            )
                            .unwrap();
                            let d = deformed
                                .positions
                                .iter()
                                .enumerate()
                                .map(|(v, p)| {
                                    let c = Vec3::new(
                                        coin[3 * v] as f32,
                                        coin[3 * v + 1] as f32,
                                        coin[3 * v + 2] as f32,
                                    );
                                    f64::from((*p - c).abs().max_element())
                                })
                                .fold(0.0, f64::max);
                            (d, 1e-4 * size)
                        }
                        (_, Some(l), field) => {
                            let id = match field {
                                "location" => ChannelId::LightPosition(l),
                                "direction" => ChannelId::LightDirection(l),
                                "intensity" => ChannelId::LightIntensity(l),
                                _ => ChannelId::LightColour(l),
                            };
                            // VRML's intensities and colours lie in [0, 1].
                            let values: Vec<f64> = match sample(id) {
                                ChannelValue::Vec3(v) if field == "color" => {
                                    v.clamp(Vec3::ZERO, Vec3::ONE).to_array().map(f64::from).to_vec()
                                }
                                ChannelValue::Vec3(v) => v.to_array().map(f64::from).to_vec(),
                                ChannelValue::Scalar(s) => vec![f64::from(s.clamp(0.0, 1.0))],
                                ChannelValue::Rotation(_) => panic!(),
                            };
                            let d = values.iter().zip(coin).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
                            (d, if field == "intensity" { 1e-4 } else { 1e-4 * size })
                        }
                        _ => panic!("{here}: an interpolator for nothing keyrig has"),
                    };
                    assert!(difference <= tolerance, "{here}: frame {frame}: {difference} > {tolerance}");
                }
                checked += 1;
            }
            eprintln!("{asset} → .{ext}: {checked} interpolators equal keyrig at every frame");
            assert!(checked >= if asset == "demo.ron" { 6 } else { 1 }, "{asset} → .{ext}: {checked}");
        }
    }
}
