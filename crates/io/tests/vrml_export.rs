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

use glam::{Quat, Vec3};
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

/// `assets/cameras.ron` with keyed attributes: the arm changes colour (through a breakdown key)
/// and fades, a spot light opens its cone.
fn attributes_scene() -> keyrig_core::Scene {
    use keyrig_core::{Animated, Key, RawTrack};
    let mut scene = keyrig_io::project::load_scene(&assets().join("cameras.ron")).unwrap();
    let arm = &mut scene.objects[0];
    arm.attributes.colour = Some(Animated::new(
        Vec3::new(0.8, 0.2, 0.1),
        RawTrack::new(vec![
            Key::new(0.0, Vec3::new(0.8, 0.2, 0.1)),
            // Key types travel in the metadata scene (a breakdown between two keyframes).
            Key::new(1.0, Vec3::new(0.1, 0.3, 0.9)).with_key_type(keyrig_core::KeyType::Breakdown),
            Key::new(2.0, Vec3::new(0.2, 0.9, 0.2)),
        ]),
    ));
    arm.attributes.opacity = Animated::new(1.0, RawTrack::new(vec![Key::new(0.5, 1.0), Key::new(1.5, 0.3)]));
    let mut spot = scene.lights[0].clone();
    spot.name = "Spot".into();
    spot.kind = keyrig_core::LightKind::Spot { cutoff_deg: 30.0, inner_angle_deg: 20.0, dropoff: 1.0 };
    spot.attributes.cutoff_deg =
        Some(Animated::new(30.0, RawTrack::new(vec![Key::new(0.0, 20.0), Key::new(2.0, 45.0)])));
    scene.lights.push(spot);
    scene
}

/// The assets and `attributes_scene`, by name.
fn scenes() -> Vec<(String, keyrig_core::Scene)> {
    let mut out: Vec<(String, keyrig_core::Scene)> =
        ["demo.ron", "twist.ron", "cycle.ron", "ik.ron", "characters.ron", "cameras.ron"]
            .iter()
            .map(|a| ((*a).to_owned(), keyrig_io::project::load_scene(&assets().join(a)).unwrap()))
            .collect();
    out.push(("attributes.ron".to_owned(), attributes_scene()));
    out.push(("euler.ron".to_owned(), euler_scene()));
    out
}

/// The demo with Euler keys (issue 30): the Cube keyed on all three angles, Y past a turn, and
/// the elbow's keys in ZXY order. VRML has only axis–angle rotations: the export writes
/// quaternion keys that follow the angles, and its metadata keeps the Euler keys.
fn euler_scene() -> keyrig_core::Scene {
    use keyrig_core::channel_id::{set_rotation_keys, ChannelId};
    let mut scene = keyrig_io::project::load_scene(&assets().join("demo.ron")).unwrap();
    let cube = scene.objects.iter().position(|o| o.name == "Cube").expect("the demo's cube");
    let xyz = keyrig_core::RotationMode::Euler(keyrig_core::EulerOrder::XYZ);
    assert!(set_rotation_keys(&mut scene, ChannelId::ObjectRotation(cube), xyz, true).unwrap());
    let euler = scene.objects[cube].rotation_euler.as_mut().expect("Euler keys");
    euler.track.keys[1].value.x = 60.0;
    euler.track.keys[2].value.z = -45.0;
    euler.track.keys[3].value.y = 500.0;
    let zxy = keyrig_core::RotationMode::Euler(keyrig_core::EulerOrder::ZXY);
    assert!(
        set_rotation_keys(&mut scene, ChannelId::JointRotation { object: 0, joint: 1 }, zxy, true).unwrap()
    );
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    scene
}

#[test]
fn keyrig_reads_its_own_export_back_to_the_same_keys() {
    let dir = tempfile::tempdir().unwrap();
    for (asset, scene) in scenes() {
        let asset = asset.as_str();
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
                    assert_eq!(a.attributes, b.attributes, "{here}: {}", a.name);
                } else {
                    // Its mesh is procedural or its model file is there: skeleton, deformer
                    // and keys come back whole, not as the vertex animation.
                    assert_eq!(*a, b, "{here}: {} comes back whole", a.name);
                }
            }
            assert_eq!(back.lights, scene.lights, "{here}: lights");
            assert_eq!(back.cameras, scene.cameras, "{here}: cameras");
            assert_eq!(back.active_camera, scene.active_camera, "{here}: active camera");
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

/// The skinned glTF meshes of a scene's model-file objects, loaded as keyrig loads them for
/// `keyrig deform` (the mesh node's skin, bound to the object's skeleton).
fn loaded_meshes(scene: &keyrig_core::Scene) -> HashMap<usize, keyrig_eval::LoadedMesh> {
    let mut out = HashMap::new();
    for (o, object) in scene.objects.iter().enumerate() {
        let Some(keyrig_core::MeshSource::File { path, mesh, .. }) = &object.mesh else { continue };
        if !(path.ends_with(".glb") || path.ends_with(".gltf")) {
            continue;
        }
        let model = keyrig_io::gltf_import::import_gltf_file(&assets().join(path)).unwrap();
        let index = mesh.unwrap_or(0);
        let node = model.nodes.iter().position(|n| n.mesh == Some(index)).unwrap();
        if model.nodes[node].skin.is_some() {
            let skinned = model.skinned_mesh(node).unwrap();
            out.insert(o, keyrig_eval::LoadedMesh::Skinned(std::sync::Arc::new(skinned)));
        }
    }
    out
}

/// The vertices of an MD2 object's mesh at `t` as the editor plays it.
fn md2_blend(object: &keyrig_core::Object, t: f64) -> Vec<Vec3> {
    let Some(keyrig_core::MeshSource::File { path, clip, fps, .. }) = &object.mesh else {
        panic!("an MD2 object")
    };
    let model = keyrig_io::md2::load_md2_file(&assets().join(path)).unwrap();
    let clips = model
        .clips
        .iter()
        .map(|c| keyrig_eval::morph::MorphClip { name: c.name.clone(), frames: c.frames.clone() })
        .collect();
    let morph = keyrig_eval::morph::MorphClips::new(model.frames.len(), clips).unwrap();
    let b = morph.blend_at(clip.as_deref(), fps.unwrap_or(keyrig_core::MD2_DEFAULT_FPS), t).unwrap();
    let (a, c) =
        (model.frame_pose(b.frame_a as usize).unwrap(), model.frame_pose(b.frame_b as usize).unwrap());
    a.positions.iter().zip(&c.positions).map(|(p, q)| p.lerp(*q, b.t)).collect()
}

#[test]
fn coin3d_plays_the_export_as_keyrig_samples_the_scene() {
    let python = python();
    let script = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/coin_reference.py");
    let dir = tempfile::tempdir().unwrap();
    for (asset, scene) in scenes() {
        let asset = asset.as_str();
        let eval = SceneEvaluator::new(&scene, &loaded_meshes(&scene));
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
                let target = r
                    .target
                    .trim_end_matches("_xf")
                    .trim_end_matches("_points")
                    .trim_end_matches("_material");
                let object = scene.objects.iter().position(|o| o.name.replace(' ', "_") == target);
                let light = scene.lights.iter().position(|l| l.name.replace(' ', "_") == target);
                let camera = scene.cameras.iter().position(|c| c.name.replace(' ', "_") == r.target);
                for (frame, coin) in r.values.iter().enumerate() {
                    let t = time(frame);
                    let sample = |id| eval.value(id, t, &none).unwrap();
                    let camera_state = || eval.camera_at(camera.unwrap(), t, &none).unwrap();
                    let (difference, tolerance) = match (object, light, r.field.as_str()) {
                        _ if camera.is_some() => match r.field.as_str() {
                            "position" => {
                                let eye = camera_state().eye();
                                let d = eye
                                    .to_array()
                                    .iter()
                                    .zip(coin)
                                    .map(|(a, b)| (f64::from(*a) - b).abs())
                                    .fold(0.0, f64::max);
                                (d, 1e-4 * size)
                            }
                            "orientation" => {
                                let q = Quat::from_mat3a(&camera_state().world_from_camera.matrix3);
                                (angle_deg(&q.to_array().map(f64::from), coin), 0.05)
                            }
                            "fieldOfView" | "heightAngle" => {
                                let keyrig_core::Lens::Perspective { fov_y } = camera_state().lens else {
                                    panic!("{here}")
                                };
                                ((f64::from(fov_y) - coin[0]).abs(), 1e-4)
                            }
                            other => panic!("{here}: a camera has no {other}"),
                        },
                        (Some(o), _, "diffuseColor") => {
                            let id = ChannelId::Attribute(keyrig_core::AttributeId::ObjectColour(o));
                            let ChannelValue::Vec3(v) = sample(id) else { panic!() };
                            let d = v
                                .clamp(Vec3::ZERO, Vec3::ONE)
                                .to_array()
                                .iter()
                                .zip(coin)
                                .map(|(a, b)| (f64::from(*a) - b).abs())
                                .fold(0.0, f64::max);
                            // Coin blends RGB between samples that follow keyrig's HSV keys
                            // within 10⁻³: both differences together.
                            (d, 2e-3)
                        }
                        (Some(o), _, "transparency") => {
                            let id = ChannelId::Attribute(keyrig_core::AttributeId::ObjectOpacity(o));
                            let ChannelValue::Scalar(opacity) = sample(id) else { panic!() };
                            ((1.0 - f64::from(opacity.clamp(0.0, 1.0)) - coin[0]).abs(), 1e-4)
                        }
                        (_, Some(l), field @ ("cutOffAngle" | "beamWidth")) => {
                            let id = if field == "cutOffAngle" {
                                keyrig_core::AttributeId::LightCutoff(l)
                            } else {
                                keyrig_core::AttributeId::LightInnerAngle(l)
                            };
                            let ChannelValue::Scalar(degrees) = sample(ChannelId::Attribute(id)) else {
                                panic!()
                            };
                            ((f64::from(degrees.to_radians()) - coin[0]).abs(), 1e-4)
                        }
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
                        (Some(o), _, "point") if eval.skin(o).is_none() => {
                            // An MD2 model: the editor's playing rule (keyrig-eval's
                            // MorphClips::blend_at: frame (t·fps) mod n, blended with the next,
                            // the last with the first), on the file's frames.
                            let frames = md2_blend(&scene.objects[o], t);
                            let d = frames
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
            let least = match asset {
                "demo.ron" => 6,
                // Two cameras' positions, orientations and lenses (the Track's lens is still).
                "cameras.ron" => 5,
                // And the arm's colour and transparency, the spot's cone.
                "attributes.ron" => 8,
                // The arm, the cube, Cesium Man, the fox and Sydney.
                "characters.ron" => 5,
                _ => 1,
            };
            assert!(checked >= least, "{asset} → .{ext}: {checked}");
        }
    }
}

#[test]
fn a_skinned_object_whose_model_file_is_gone_comes_back_as_its_vertex_animation() {
    let dir = tempfile::tempdir().unwrap();
    let mut scene = keyrig_io::project::load_scene(&assets().join("characters.ron")).unwrap();
    let o = scene
        .objects
        .iter()
        .position(|o| o.skeleton.is_some() && matches!(o.mesh, Some(keyrig_core::MeshSource::File { .. })))
        .expect("a skinned model-file character");
    let copy = dir.path().join("character.glb");
    if let Some(keyrig_core::MeshSource::File { path, .. }) = &mut scene.objects[o].mesh {
        std::fs::copy(&*path, &copy).unwrap();
        *path = copy.to_string_lossy().into_owned();
    }
    let file = write(dir.path(), &scene, "characters.wrl");
    let name = scene.objects[o].name.clone();
    let whole = keyrig_io::vrml::import_vrml_file(&file).unwrap().to_scene(&file.to_string_lossy());
    assert_eq!(whole.objects.iter().find(|x| x.name == name), Some(&scene.objects[o]), "with its model file");
    std::fs::remove_file(&copy).unwrap();
    let back = keyrig_io::vrml::import_vrml_file(&file).unwrap().to_scene(&file.to_string_lossy());
    let morph = back.objects.iter().find(|x| x.name == name).expect("the character");
    assert!(morph.skeleton.is_none(), "without its model file it is the export's vertex animation");
    assert!(
        matches!(&morph.mesh, Some(keyrig_core::MeshSource::File { path, .. }) if *path == file.to_string_lossy()),
        "{:?}",
        morph.mesh
    );
}
