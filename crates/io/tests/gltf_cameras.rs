//! glTF cameras in and out (issue 31):
//!
//! - the corpus sample `Cameras.gltf` (a perspective and an orthographic camera) imports as
//!   two scene cameras whose projection equals the glTF 2.0 specification's matrices (§3.10.3,
//!   written out here from the file's numbers, read with `serde_json`);
//! - a scene with keyed cameras (TCB translation, a rotation with a spin, a keyed focal
//!   length, an orthographic zoom, an aimed camera) exports with every animated camera
//!   property equal at every key time and every frame, read back by an independent reader of
//!   the GLB written here (chunks, accessors and the specification's samplers, not keyrig-io's
//!   importer), lens animation as `KHR_animation_pointer` channels;
//! - a camera's keyed visibility exports as `KHR_node_visibility` with a STEP pointer channel
//!   and a hidden camera as `visible: false`; keyrig's importer reads the lens and visibility
//!   channels back and names the pointer it skips (`xmag`);
//! - the Khronos glTF-Validator reports 0 errors and 0 warnings on both exports.

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::{DQuat, Mat4, Quat, Vec3, Vec4};
use keyrig_core::{
    Aim, AimTarget, Animated, AnimatedTrack, Interpolation, Key, MeshSource, Object, ProceduralMesh,
    Projection, RawTrack, RenderSize, Scene, SceneCamera, Spin, Tcb,
};
use keyrig_io::gltf_export::{export_scene, ExportOptions};
use serde_json::Value;

fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus").join(rel)
}

/// Runs the Khronos glTF-Validator on `file`: (errors, warnings, report).
fn validate(file: &Path) -> (u64, u64, String) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/validate-gltf");
    assert!(
        dir.join("node_modules/gltf-validator").is_dir(),
        "the Khronos glTF-Validator is not installed: run `npm ci --prefix tools/validate-gltf`"
    );
    let output = Command::new("node").arg(dir.join("validate.mjs")).arg(file).output().expect("run node");
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let report: Value = serde_json::from_str(stdout.trim()).unwrap_or_else(|e| panic!("{e}: {stdout}"));
    (report["errors"].as_u64().unwrap(), report["warnings"].as_u64().unwrap(), stdout)
}

/// A GLB file read from its bytes: the JSON chunk and the BIN chunk (glTF 2.0 §4.4).
struct Glb {
    json: Value,
    bin: Vec<u8>,
}

impl Glb {
    fn read(bytes: &[u8]) -> Glb {
        let u32_at = |at: usize| u32::from_le_bytes(bytes[at..at + 4].try_into().unwrap()) as usize;
        assert_eq!(&bytes[0..4], b"glTF");
        assert_eq!(u32_at(4), 2);
        assert_eq!(u32_at(8), bytes.len());
        let json_len = u32_at(12);
        assert_eq!(&bytes[16..20], b"JSON");
        let json = serde_json::from_slice(&bytes[20..20 + json_len]).expect("JSON chunk");
        let at = 20 + json_len;
        let bin = if at < bytes.len() {
            assert_eq!(&bytes[at + 4..at + 8], b"BIN\0");
            bytes[at + 8..at + 8 + u32_at(at)].to_vec()
        } else {
            Vec::new()
        };
        Glb { json, bin }
    }

    /// A float accessor's elements.
    fn floats(&self, accessor: u64) -> Vec<Vec<f64>> {
        let a = &self.json["accessors"][accessor as usize];
        assert_eq!(a["componentType"], 5126, "float accessor");
        let width = match a["type"].as_str().unwrap() {
            "SCALAR" => 1,
            "VEC3" => 3,
            "VEC4" => 4,
            other => panic!("type {other}"),
        };
        let view = &self.json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        let start = view["byteOffset"].as_u64().unwrap_or(0) + a["byteOffset"].as_u64().unwrap_or(0);
        let stride = view["byteStride"].as_u64().unwrap_or(4 * width as u64);
        (0..a["count"].as_u64().unwrap())
            .map(|i| {
                (0..width)
                    .map(|c| {
                        let at = (start + i * stride + 4 * c as u64) as usize;
                        f64::from(f32::from_le_bytes(self.bin[at..at + 4].try_into().unwrap()))
                    })
                    .collect()
            })
            .collect()
    }

    /// The sampler of the channel of node `node` and `path` (or of the pointer `pointer`).
    fn channel(&self, node: Option<usize>, path: &str, pointer: Option<&str>) -> Option<Sampler> {
        let animation = &self.json["animations"][0];
        let channel = animation["channels"].as_array()?.iter().find(|c| {
            let target = &c["target"];
            target["path"] == path
                && node.is_none_or(|n| target["node"] == n)
                && pointer.is_none_or(|p| target["extensions"]["KHR_animation_pointer"]["pointer"] == p)
        })?;
        let sampler = &animation["samplers"][channel["sampler"].as_u64().unwrap() as usize];
        Some(Sampler {
            times: self.floats(sampler["input"].as_u64().unwrap()).into_iter().map(|v| v[0]).collect(),
            values: self.floats(sampler["output"].as_u64().unwrap()),
            interpolation: sampler["interpolation"].as_str().unwrap_or("LINEAR").to_owned(),
        })
    }

    /// The STEP boolean channel on `pointer` (KHR_node_visibility): key times and 0/1 bytes.
    fn visibility(&self, pointer: &str) -> (Vec<f64>, Vec<u8>) {
        let animation = &self.json["animations"][0];
        let channel = animation["channels"]
            .as_array()
            .unwrap()
            .iter()
            .find(|c| c["target"]["extensions"]["KHR_animation_pointer"]["pointer"] == pointer)
            .expect("visibility channel");
        let sampler = &animation["samplers"][channel["sampler"].as_u64().unwrap() as usize];
        assert_eq!(sampler["interpolation"], "STEP");
        let times = self.floats(sampler["input"].as_u64().unwrap()).into_iter().map(|v| v[0]).collect();
        let a = &self.json["accessors"][sampler["output"].as_u64().unwrap() as usize];
        assert_eq!(a["componentType"], 5121, "unsigned bytes");
        let view = &self.json["bufferViews"][a["bufferView"].as_u64().unwrap() as usize];
        let start =
            (view["byteOffset"].as_u64().unwrap_or(0) + a["byteOffset"].as_u64().unwrap_or(0)) as usize;
        (times, self.bin[start..start + a["count"].as_u64().unwrap() as usize].to_vec())
    }

    fn node_named(&self, name: &str) -> usize {
        self.json["nodes"].as_array().unwrap().iter().position(|n| n["name"] == name).expect("node")
    }
}

/// An animation sampler, evaluated as glTF 2.0 Appendix C says: STEP holds, LINEAR lerps
/// (slerps rotations the short way), CUBICSPLINE is the Hermite of (in-tangent, value,
/// out-tangent) triples; times outside the keys clamp.
struct Sampler {
    times: Vec<f64>,
    values: Vec<Vec<f64>>,
    interpolation: String,
}

impl Sampler {
    fn at(&self, t: f64, rotation: bool) -> Vec<f64> {
        let cubic = self.interpolation == "CUBICSPLINE";
        let value = |k: usize| if cubic { self.values[3 * k + 1].clone() } else { self.values[k].clone() };
        let n = self.times.len();
        if t <= self.times[0] {
            return value(0);
        }
        if t >= self.times[n - 1] {
            return value(n - 1);
        }
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let (td, u) = (t1 - t0, (t - t0) / (t1 - t0));
        let (a, b) = (value(k), value(k + 1));
        match self.interpolation.as_str() {
            "STEP" => a,
            "CUBICSPLINE" => {
                let (u2, u3) = (u * u, u * u * u);
                let h = [2.0 * u3 - 3.0 * u2 + 1.0, u3 - 2.0 * u2 + u, -2.0 * u3 + 3.0 * u2, u3 - u2];
                let (out_k, in_k1) = (&self.values[3 * k + 2], &self.values[3 * (k + 1)]);
                (0..a.len())
                    .map(|i| h[0] * a[i] + h[1] * td * out_k[i] + h[2] * b[i] + h[3] * td * in_k1[i])
                    .collect()
            }
            _ if rotation => {
                let q = |v: &[f64]| DQuat::from_xyzw(v[0], v[1], v[2], v[3]).normalize();
                let (qa, mut qb) = (q(&a), q(&b));
                if qa.dot(qb) < 0.0 {
                    qb = -qb;
                }
                qa.slerp(qb, u).to_array().to_vec()
            }
            _ => (0..a.len()).map(|i| a[i] + u * (b[i] - a[i])).collect(),
        }
    }
}

fn angle_deg(a: &[f64], b: Quat) -> f64 {
    let a = DQuat::from_xyzw(a[0], a[1], a[2], a[3]).normalize();
    let d = a.dot(b.as_dquat().normalize()).abs().min(1.0);
    2.0 * d.acos().to_degrees()
}

/// A cube, a dolly camera (TCB translation, a rotation turning 360° about Y with a spin, a
/// focal length keyed 28 → 50 mm), an orthographic camera zooming, and a camera aimed at the
/// cube as it moves.
fn scene() -> Scene {
    let mut cube = Object::new("Cube");
    cube.mesh = Some(MeshSource::Procedural(ProceduralMesh::Cube));
    cube.translation.track = RawTrack::new(vec![
        Key::new(0.0, Vec3::ZERO).with_interpolation(Interpolation::Linear),
        Key::new(2.0, Vec3::new(2.0, 0.5, -1.0)),
    ]);
    let mut dolly = SceneCamera::new("Dolly", Vec3::new(0.0, 1.0, 6.0));
    dolly.projection = Projection::FocalLength { sensor_height_mm: 24.0 };
    dolly.translation.track = RawTrack::new(vec![
        Key::new(0.0, Vec3::new(0.0, 1.0, 6.0)).with_tcb(Tcb::new(0.3, -0.2, 0.1)),
        Key::new(1.0, Vec3::new(1.0, 1.2, 4.0)),
        Key::new(2.0, Vec3::new(2.0, 1.0, 3.0)),
    ]);
    dolly.rotation.track = RawTrack::new(vec![
        Key::new(0.0, Quat::IDENTITY),
        Key::new(2.0, Quat::IDENTITY).with_spin(Spin::Angle { axis: Vec3::Y, degrees: 360.0 }),
    ]);
    dolly.lens = Animated::new(28.0, RawTrack::new(vec![Key::new(0.0, 28.0), Key::new(2.0, 50.0)]));
    let mut top = SceneCamera::new("Top", Vec3::new(0.0, 10.0, 0.0));
    top.projection = Projection::Orthographic;
    top.rotation = Animated::constant(Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2));
    top.lens = Animated::new(6.0, RawTrack::new(vec![Key::new(0.0, 6.0), Key::new(1.5, 3.0)]));
    top.far = Some(50.0);
    top.visible = Animated::new(
        1.0,
        RawTrack::new(vec![
            Key::new(0.0, 1.0).with_interpolation(Interpolation::Step),
            Key::new(1.0, 0.0).with_interpolation(Interpolation::Step),
            Key::new(1.5, 1.0).with_interpolation(Interpolation::Step),
        ]),
    );
    let mut follow = SceneCamera::new("Follow", Vec3::new(4.0, 2.0, 4.0));
    follow.aim = Some(Aim {
        up: Vec3::Y,
        roll: Animated::new(0.0, RawTrack::new(vec![Key::new(0.0, 0.0), Key::new(2.0, 20.0)])),
        target: AimTarget::Object("Cube".into()),
        influence: Animated::constant(1.0),
    });
    follow.far = None;
    follow.visible = Animated::constant(0.0);
    Scene {
        objects: vec![cube],
        cameras: vec![dolly, top, follow],
        render_size: Some(RenderSize { width: 960, height: 540 }),
        ..Scene::default()
    }
}

#[test]
fn keyed_cameras_export_equal_at_every_key_and_frame() {
    let scene = scene();
    let exported = export_scene(&scene, &ExportOptions::default()).expect("export");
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("cameras.glb");
    exported.write(&path).expect("write");
    let (errors, warnings, report) = validate(&path);
    assert_eq!((errors, warnings), (0, 0), "{report}");
    let glb = Glb::read(&std::fs::read(&path).unwrap());
    assert_eq!(
        glb.json["extensionsUsed"],
        serde_json::json!(["KHR_animation_pointer", "KHR_node_visibility"]),
        "used, never required"
    );
    assert!(glb.json.get("extensionsRequired").is_none());
    let eval = keyrig_eval::SceneEvaluator::new(&scene, &std::collections::HashMap::new());
    let none = keyrig_eval::Overrides::new();
    let frames: Vec<f64> = (0..=60).map(|f| f64::from(f) / 30.0).collect();
    let aspect = 960.0 / 540.0;

    // Dolly: a perspective camera; yfov is 2·atan(12 mm / focal length) at the first frame.
    let node = glb.node_named("Dolly");
    let camera = &glb.json["cameras"][glb.json["nodes"][node]["camera"].as_u64().unwrap() as usize];
    assert_eq!(camera["type"], "perspective");
    let p = &camera["perspective"];
    assert!((p["yfov"].as_f64().unwrap() - 2.0 * (12.0f64 / 28.0).atan()).abs() < 1e-6, "{p}");
    assert!((p["aspectRatio"].as_f64().unwrap() - aspect).abs() < 1e-6);
    assert!(
        (p["znear"].as_f64().unwrap() - 0.1).abs() < 1e-7
            && (p["zfar"].as_f64().unwrap() - 1000.0).abs() < 1e-3
    );
    let translation = glb.channel(Some(node), "translation", None).expect("translation channel");
    let rotation = glb.channel(Some(node), "rotation", None).expect("rotation channel");
    let camera_index = glb.json["nodes"][node]["camera"].as_u64().unwrap();
    let yfov = glb
        .channel(None, "pointer", Some(&format!("/cameras/{camera_index}/perspective/yfov")))
        .expect("yfov pointer channel");
    let dolly = &scene.cameras[0];
    for key in dolly.translation.track.keys.iter() {
        let got = translation.at(key.time, false);
        assert!(
            Vec3::new(got[0] as f32, got[1] as f32, got[2] as f32).abs_diff_eq(key.value, 1e-5),
            "{got:?}"
        );
    }
    let keyrig_rotation = AnimatedTrack::new(&dolly.rotation).unwrap();
    let keyrig_translation = AnimatedTrack::new(&dolly.translation).unwrap();
    for &t in &frames {
        // Rotations are resampled within the export tolerance (0.05°), the spin's whole turn
        // included; positions exactly (CUBICSPLINE with keyrig's tangents).
        let angle = angle_deg(&rotation.at(t, true), keyrig_rotation.sample(t));
        assert!(angle < 0.05 + 1e-3, "rotation at {t}: {angle}°");
        let got = translation.at(t, false);
        let want = keyrig_translation.sample(t);
        assert!(Vec3::new(got[0] as f32, got[1] as f32, got[2] as f32).abs_diff_eq(want, 1e-4), "{t}");
        let keyrig_lens = eval.camera_at(0, t, &none).unwrap().lens;
        let keyrig_core::Lens::Perspective { fov_y } = keyrig_lens else { panic!("perspective") };
        assert!((yfov.at(t, false)[0] - f64::from(fov_y)).abs() < 1e-6, "yfov at {t}");
    }
    // Halfway through the spin the camera faces +Z: the export turned the whole way round.
    let half = rotation.at(1.0, true);
    let half = Quat::from_xyzw(half[0] as f32, half[1] as f32, half[2] as f32, half[3] as f32);
    assert!((half * Vec3::NEG_Z).abs_diff_eq(Vec3::Z, 1e-3), "{}", half * Vec3::NEG_Z);

    // Top: orthographic, ymag = height / 2 and xmag = ymag · aspect at every frame.
    let node = glb.node_named("Top");
    let camera_index = glb.json["nodes"][node]["camera"].as_u64().unwrap();
    let o = &glb.json["cameras"][camera_index as usize]["orthographic"];
    assert!(
        (o["ymag"].as_f64().unwrap() - 3.0).abs() < 1e-6 && (o["zfar"].as_f64().unwrap() - 50.0).abs() < 1e-6
    );
    let ymag =
        glb.channel(None, "pointer", Some(&format!("/cameras/{camera_index}/orthographic/ymag"))).unwrap();
    let xmag =
        glb.channel(None, "pointer", Some(&format!("/cameras/{camera_index}/orthographic/xmag"))).unwrap();
    let height = AnimatedTrack::new(&scene.cameras[1].lens).unwrap();
    let key_times = scene.cameras[1].lens.track.keys.iter().map(|k| k.time);
    for t in frames.iter().copied().chain(key_times) {
        let want = f64::from(height.sample(t)) / 2.0;
        assert!((ymag.at(t, false)[0] - want).abs() < 1e-5, "ymag at {t}");
        assert!((xmag.at(t, false)[0] - want * aspect).abs() < 1e-4, "xmag at {t}");
    }
    assert!(glb.channel(Some(node), "rotation", None).is_none(), "an unkeyed rotation has no channel");
    // Its keyed visibility: KHR_node_visibility on its node, a STEP boolean pointer channel equal
    // to the scene's at every key time and frame.
    assert_eq!(glb.json["nodes"][node]["extensions"]["KHR_node_visibility"]["visible"], true);
    let visible = glb.visibility(&format!("/nodes/{node}/extensions/KHR_node_visibility/visible"));
    assert_eq!(visible.0.len(), 3);
    let keyrig_visible = AnimatedTrack::new(&scene.cameras[1].visible).unwrap();
    for t in frames.iter().copied().chain(visible.0.iter().copied()) {
        let k = visible.0.partition_point(|&x| x <= t).max(1) - 1;
        assert_eq!(f32::from(visible.1[k]), keyrig_visible.sample(t), "visible at {t}");
    }

    // Follow: aimed at the moving cube; glTF has no constraints, so its rotation is baked and
    // must look at the cube, rolled, at every frame. Infinite far plane: no zfar.
    let node = glb.node_named("Follow");
    let camera_index = glb.json["nodes"][node]["camera"].as_u64().unwrap() as usize;
    assert!(glb.json["cameras"][camera_index]["perspective"].get("zfar").is_none());
    assert_eq!(glb.json["nodes"][node]["extensions"]["KHR_node_visibility"]["visible"], false, "hidden");
    let rotation = glb.channel(Some(node), "rotation", None).expect("baked rotation");
    let cube = AnimatedTrack::new(&scene.objects[0].translation).unwrap();
    for &t in &frames {
        let got = rotation.at(t, true);
        let q = Quat::from_xyzw(got[0] as f32, got[1] as f32, got[2] as f32, got[3] as f32);
        let want = eval.camera_at(2, t, &none).unwrap();
        assert!(angle_deg(&got, Quat::from_mat3a(&want.world_from_camera.matrix3)) < 0.05 + 1e-3, "{t}");
        let to_cube = (cube.sample(t) - Vec3::new(4.0, 2.0, 4.0)).normalize();
        assert!((q * Vec3::NEG_Z).abs_diff_eq(to_cube, 2e-3), "looks at the cube at {t}");
    }

    // keyrig's importer reads the pointer channels back: the orthographic lens key for key
    // (ymag → 2·ymag), the visibility keys, the hidden camera; xmag is skipped and named.
    let back = keyrig_io::gltf_import::import_gltf_file(&path).expect("re-import");
    let skipped: Vec<String> = back.skipped_channels.iter().map(ToString::to_string).collect();
    assert_eq!(skipped.len(), 1, "{skipped:?}");
    assert!(skipped[0].contains("orthographic/xmag"), "{skipped:?}");
    let again = back.to_scene("cameras.glb", Some(0)).expect("scene");
    let top = again.cameras.iter().find(|c| c.name == "Top").unwrap();
    let original = &scene.cameras[1];
    let read = AnimatedTrack::new(&top.lens).unwrap();
    for k in original.lens.track.keys.iter() {
        assert!((read.sample(k.time) - k.value).abs() < 1e-5, "lens at {}", k.time);
    }
    assert_eq!(top.visible.track.keys.len(), 3);
    for (a, b) in top.visible.track.keys.iter().zip(original.visible.track.keys.iter()) {
        assert_eq!((a.time as f32, a.value, a.interpolation), (b.time as f32, b.value, b.interpolation));
    }
    let follow = again.cameras.iter().find(|c| c.name == "Follow").unwrap();
    assert_eq!(follow.visible.value, 0.0);
    assert_eq!(again.problems(), Vec::new());
}

/// The glTF 2.0 projection matrices (§3.10.3), from the specification, row by row, in
/// OpenGL's clip space (depth −1..1).
fn gltf_projection(camera: &Value, aspect: f64) -> Mat4 {
    let f = |v: &Value| v.as_f64().unwrap() as f32;
    let rows = if camera["type"] == "perspective" {
        let p = &camera["perspective"];
        let (y, n) = (f(&p["yfov"]), f(&p["znear"]));
        let a = p.get("aspectRatio").map_or(aspect as f32, f);
        let t = (0.5 * y).tan();
        let (r2, r3) = match p.get("zfar").map(f) {
            Some(z) => ([0.0, 0.0, (z + n) / (n - z), 2.0 * z * n / (n - z)], [0.0, 0.0, -1.0, 0.0]),
            None => ([0.0, 0.0, -1.0, -2.0 * n], [0.0, 0.0, -1.0, 0.0]),
        };
        [[1.0 / (a * t), 0.0, 0.0, 0.0], [0.0, 1.0 / t, 0.0, 0.0], r2, r3]
    } else {
        let o = &camera["orthographic"];
        let (r, t, n, z) = (f(&o["xmag"]), f(&o["ymag"]), f(&o["znear"]), f(&o["zfar"]));
        [
            [1.0 / r, 0.0, 0.0, 0.0],
            [0.0, 1.0 / t, 0.0, 0.0],
            [0.0, 0.0, 2.0 / (n - z), (z + n) / (n - z)],
            [0.0, 0.0, 0.0, 1.0],
        ]
    };
    Mat4::from_cols_array_2d(&rows).transpose()
}

#[test]
fn the_corpus_cameras_import_with_the_specifications_projection_and_export_again() {
    let file = corpus("gltf/Cameras/glTF-Embedded/Cameras.gltf");
    let json: Value = serde_json::from_slice(&std::fs::read(&file).unwrap()).unwrap();
    let model = keyrig_io::gltf_import::import_gltf_file(&file).expect("import");
    assert_eq!(model.cameras.len(), 2);
    let scene = model.to_scene("Cameras.gltf", None).expect("scene");
    assert_eq!(scene.problems(), Vec::new());
    assert_eq!(scene.cameras.len(), 2);
    assert_eq!(scene.render_size, Some(RenderSize { width: 720, height: 720 }), "aspectRatio 1");
    let eval = keyrig_eval::SceneEvaluator::new(&scene, &std::collections::HashMap::new());
    let none = keyrig_eval::Overrides::new();
    for (c, node) in [(0usize, 1usize), (1, 2)] {
        let camera = &scene.cameras[c];
        let file_camera = &json["cameras"][json["nodes"][node]["camera"].as_u64().unwrap() as usize];
        let t = &json["nodes"][node]["translation"];
        let at = Vec3::new(
            t[0].as_f64().unwrap() as f32,
            t[1].as_f64().unwrap() as f32,
            t[2].as_f64().unwrap() as f32,
        );
        assert_eq!(camera.translation.value, at);
        let state = eval.camera_at(c, 0.0, &none).unwrap();
        // Points in view space, projected by keyrig (wgpu depth 0..1) and by the
        // specification's matrix, whose depth maps to 0..1 as z' = (z + w) / 2.
        let ours = state.clip_from_view(1.0);
        let theirs = gltf_projection(file_camera, 1.0);
        for p in [
            Vec4::new(0.2, -0.3, -1.0, 1.0),
            Vec4::new(-1.0, 0.5, -20.0, 1.0),
            Vec4::new(0.0, 0.0, -99.0, 1.0),
        ] {
            let (a, b) = (ours * p, theirs * p);
            let b = Vec4::new(b.x, b.y, 0.5 * (b.z + b.w), b.w);
            assert!(a.abs_diff_eq(b, 1e-3 * b.abs().max_element().max(1.0)), "camera {c}, {p}: {a} vs {b}");
        }
    }

    // Exported again, the cameras are the file's, and the Validator finds nothing wrong.
    let options =
        ExportOptions { base_dir: file.parent().map(Path::to_path_buf), ..ExportOptions::default() };
    let exported = export_scene(&scene, &options).expect("export");
    let dir = tempfile::tempdir().expect("tempdir");
    let path = dir.path().join("cameras.glb");
    exported.write(&path).expect("write");
    let (errors, warnings, report) = validate(&path);
    assert_eq!((errors, warnings), (0, 0), "{report}");
    let glb = Glb::read(&std::fs::read(&path).unwrap());
    let close = |a: &Value, b: &Value| (a.as_f64().unwrap() - b.as_f64().unwrap()).abs() < 1e-6;
    for (c, source) in [(0usize, 0usize), (1, 1)] {
        let node = glb.node_named(&scene.cameras[c].name);
        let out = &glb.json["cameras"][glb.json["nodes"][node]["camera"].as_u64().unwrap() as usize];
        let src = &json["cameras"][source];
        assert_eq!(out["type"], src["type"]);
        let kind = src["type"].as_str().unwrap();
        for (field, value) in src[kind].as_object().unwrap() {
            assert!(close(&out[kind][field], value), "{kind}.{field}: {} vs {value}", out[kind][field]);
        }
    }
    // keyrig's importer reads its own export back to the same cameras.
    let back = keyrig_io::gltf_import::import_gltf_slice(&std::fs::read(&path).unwrap()).expect("re-import");
    let again = back.to_scene("cameras.glb", None).expect("scene");
    for (a, b) in again.cameras.iter().zip(&scene.cameras) {
        assert_eq!((a.projection, a.near, a.far), (b.projection, b.near, b.far));
        assert!((a.lens.value - b.lens.value).abs() < 1e-4);
        assert!(a.translation.value.abs_diff_eq(b.translation.value, 1e-6));
    }
}
