//! Export of the keyed attributes: visibility (`KHR_node_visibility`), material colour and
//! opacity, light range / cone (`KHR_animation_pointer`) and morph weights; a scene without
//! attributes exports exactly as before. The Khronos validator reports no errors, both extensions are used but not
//! required, and an independent reader of the exported JSON (serde_json and a glTF sampler
//! written here from the specification, not keyrig's importer) finds every animated property
//! equal to the scene's channel at every key time of either.

use std::path::{Path, PathBuf};
use std::process::Command;

use keyrig_core::channel::ChannelPath;
use keyrig_core::channel_id::ChannelValue;
use keyrig_core::{Animated, Interpolation, Key, LightKind, RawTrack, Scene};
use keyrig_io::gltf_export::{export_scene, ExportOptions, ExportedGltf};
use serde_json::Value;

fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf").join(rel)
}

/// Errors and the report of the Khronos glTF-Validator on `file`.
fn validate(file: &Path) -> (u64, String) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/validate-gltf");
    assert!(
        dir.join("node_modules/gltf-validator").is_dir(),
        "the Khronos glTF-Validator is not installed: run `npm ci --prefix tools/validate-gltf`"
    );
    let output = Command::new("node").arg(dir.join("validate.mjs")).arg(file).output().expect("node");
    let stdout = String::from_utf8_lossy(&output.stdout).into_owned();
    let report: Value = serde_json::from_str(stdout.trim()).unwrap_or_else(|e| panic!("{e}: {stdout}"));
    (report["errors"].as_u64().expect("errors"), stdout)
}

fn export_and_validate(scene: &Scene, options: &ExportOptions) -> ExportedGltf {
    let exported = export_scene(scene, options).unwrap_or_else(|e| panic!("{e}"));
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("attributes.glb");
    exported.write(&path).unwrap();
    let (errors, report) = validate(&path);
    assert_eq!(errors, 0, "{report}");
    assert!(exported.json.get("extensionsRequired").is_none(), "used, never required");
    exported
}

/// The components of accessor `a`: floats, or unsigned bytes as 0/1.
fn accessor(json: &Value, bin: &[u8], a: usize) -> (Vec<f64>, usize) {
    let acc = &json["accessors"][a];
    let width = match acc["type"].as_str().unwrap() {
        "SCALAR" => 1,
        "VEC3" => 3,
        "VEC4" => 4,
        t => panic!("{t}"),
    };
    let n = acc["count"].as_u64().unwrap() as usize * width;
    let view = &json["bufferViews"][acc["bufferView"].as_u64().unwrap() as usize];
    let start =
        view["byteOffset"].as_u64().unwrap_or(0) as usize + acc["byteOffset"].as_u64().unwrap_or(0) as usize;
    let values = match acc["componentType"].as_u64().unwrap() {
        5126 => (0..n)
            .map(|i| f64::from(f32::from_le_bytes(bin[start + 4 * i..start + 4 * i + 4].try_into().unwrap())))
            .collect(),
        5121 => (0..n).map(|i| f64::from(bin[start + i])).collect(),
        c => panic!("component type {c}"),
    };
    (values, width)
}

/// A glTF sampler: key times, interpolation and outputs (per element `width` components).
struct Curve {
    times: Vec<f64>,
    interpolation: String,
    values: Vec<f64>,
    width: usize,
}

impl Curve {
    /// The value at `t` as glTF 2.0 defines it (Appendix C): held outside the keys, STEP holds,
    /// LINEAR lerps, CUBICSPLINE is the Hermite of (v_k, b_k, v_{k+1}, a_{k+1}) scaled by t_d.
    fn at(&self, t: f64) -> Vec<f64> {
        let w = self.width;
        let cubic = self.interpolation == "CUBICSPLINE";
        let value = |k: usize| -> &[f64] {
            let e = if cubic { 3 * k + 1 } else { k };
            &self.values[e * w..e * w + w]
        };
        let n = self.times.len();
        if t <= self.times[0] {
            return value(0).to_vec();
        }
        if t >= self.times[n - 1] {
            return value(n - 1).to_vec();
        }
        let k = self.times.partition_point(|&x| x <= t) - 1;
        let (t0, t1) = (self.times[k], self.times[k + 1]);
        let u = (t - t0) / (t1 - t0);
        match self.interpolation.as_str() {
            "STEP" => value(k).to_vec(),
            "LINEAR" => value(k).iter().zip(value(k + 1)).map(|(a, b)| a + u * (b - a)).collect(),
            _ => {
                let td = t1 - t0;
                let out_k = &self.values[(3 * k + 2) * w..(3 * k + 2) * w + w];
                let in_k1 = &self.values[(3 * (k + 1)) * w..(3 * (k + 1)) * w + w];
                let (u2, u3) = (u * u, u * u * u);
                (0..w)
                    .map(|i| {
                        (2.0 * u3 - 3.0 * u2 + 1.0) * value(k)[i]
                            + (u3 - 2.0 * u2 + u) * td * out_k[i]
                            + (-2.0 * u3 + 3.0 * u2) * value(k + 1)[i]
                            + (u3 - u2) * td * in_k1[i]
                    })
                    .collect()
            }
        }
    }
}

/// Every channel of the exported animation by its target: the pointer, or `/nodes/N/<path>`.
fn uses(exported: &ExportedGltf, extension: &str) -> bool {
    exported.json["extensionsUsed"].as_array().is_some_and(|u| u.iter().any(|e| e == extension))
}

fn read_curves(exported: &ExportedGltf) -> Vec<(String, Curve)> {
    let (json, bin) = (&exported.json, &exported.bin[..]);
    let anim = &json["animations"][0];
    anim["channels"]
        .as_array()
        .unwrap()
        .iter()
        .map(|c| {
            let target = &c["target"];
            let name = match target["path"].as_str().unwrap() {
                "pointer" => {
                    target["extensions"]["KHR_animation_pointer"]["pointer"].as_str().unwrap().to_owned()
                }
                path => format!("/nodes/{}/{path}", target["node"]),
            };
            let s = &anim["samplers"][c["sampler"].as_u64().unwrap() as usize];
            let (times, _) = accessor(json, bin, s["input"].as_u64().unwrap() as usize);
            let (values, width) = accessor(json, bin, s["output"].as_u64().unwrap() as usize);
            let interpolation = s["interpolation"].as_str().unwrap_or("LINEAR").to_owned();
            (name, Curve { times, interpolation, values, width })
        })
        .collect()
}

fn curve<'a>(curves: &'a [(String, Curve)], name: &str) -> &'a Curve {
    &curves.iter().find(|(n, _)| n == name).unwrap_or_else(|| panic!("no channel {name}")).1
}

fn node_index(exported: &ExportedGltf, name: &str) -> usize {
    exported.json["nodes"].as_array().unwrap().iter().position(|n| n["name"] == name).unwrap()
}

/// The scene channel's value at `t` as numbers.
fn scene_value(scene: &Scene, path: &str, t: f64) -> Vec<f64> {
    let channel = ChannelPath::parse(path).unwrap().resolve(scene).unwrap_or_else(|e| panic!("{e}"));
    match channel.sample(t) {
        ChannelValue::Scalar(v) => vec![f64::from(v)],
        ChannelValue::Vec3(v) => v.to_array().map(f64::from).to_vec(),
        ChannelValue::Rotation(q) => q.to_array().map(f64::from).to_vec(),
    }
}

/// Compares `curve` (its components `components`, through `map`) with scene channel `path` at
/// every key time of both.
fn same_at_every_key(
    scene: &Scene,
    path: &str,
    curve: &Curve,
    components: std::ops::Range<usize>,
    map: impl Fn(f64) -> f64,
    tol: f64,
) {
    let channel = ChannelPath::parse(path).unwrap().resolve(scene).unwrap();
    let mut times = curve.times.clone();
    if let Some((a, b)) = channel.domain() {
        times.extend([a, b]);
    }
    let keys = keyrig_core::channel::list_channels(scene);
    assert!(keys.iter().any(|k| k.to_string() == path), "{path} is listed");
    for t in times {
        let ours = scene_value(scene, path, t);
        let theirs: Vec<f64> = curve.at(t)[components.clone()].iter().map(|&v| map(v)).collect();
        for (a, b) in ours.iter().zip(&theirs) {
            assert!((a - b).abs() <= tol, "{path} at {t}: scene {ours:?}, glTF {theirs:?}");
        }
    }
}

fn step_keys(values: &[(f64, f32)]) -> RawTrack<f32> {
    RawTrack::new(
        values.iter().map(|&(t, v)| Key::new(t, v).with_interpolation(Interpolation::Step)).collect(),
    )
}

#[test]
fn attributes_of_a_hand_made_scene_export_and_read_back() {
    let mut scene = keyrig_io::demo::demo_scene();
    let cube = scene.objects.iter().position(|o| o.name == "Cube").unwrap();
    let a = &mut scene.objects[cube].attributes;
    a.visible = Animated::new(1.0, step_keys(&[(0.0, 1.0), (1.0, 0.0), (1.5, 1.0)]));
    a.opacity =
        Animated::new(1.0, RawTrack::new(vec![Key::new(0.0, 1.0), Key::new(0.5, 0.8), Key::new(2.0, 0.0)]));
    let key_light = scene.lights.iter().position(|l| l.name == "Key").unwrap();
    scene.lights[key_light].kind = LightKind::Spot { cutoff_deg: 40.0, inner_angle_deg: 20.0, dropoff: 1.0 };
    let la = &mut scene.lights[key_light].attributes;
    la.cutoff_deg = Some(Animated::new(40.0, RawTrack::new(vec![Key::new(0.0, 40.0), Key::new(2.0, 25.0)])));
    la.range = Some(Animated::constant(12.0));
    la.visible = Animated::new(1.0, step_keys(&[(0.0, 1.0), (1.0, 0.0)]));
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());

    let exported = export_and_validate(&scene, &ExportOptions::default());
    assert!(uses(&exported, "KHR_animation_pointer") && uses(&exported, "KHR_node_visibility"));
    let curves = read_curves(&exported);
    let node = node_index(&exported, "Cube");
    assert_eq!(exported.json["nodes"][node]["extensions"]["KHR_node_visibility"]["visible"], true);
    let vis = curve(&curves, &format!("/nodes/{node}/extensions/KHR_node_visibility/visible"));
    assert_eq!(vis.interpolation, "STEP");
    same_at_every_key(&scene, "object/Cube/visible", vis, 0..1, |v| v, 0.0);
    // The cube's own material carries the opacity (alpha), blended.
    let mesh = exported.json["nodes"][node]["mesh"].as_u64().unwrap() as usize;
    let material = exported.json["meshes"][mesh]["primitives"][0]["material"].as_u64().unwrap() as usize;
    assert_eq!(exported.json["materials"][material]["alphaMode"], "BLEND");
    let colour = curve(&curves, &format!("/materials/{material}/pbrMetallicRoughness/baseColorFactor"));
    same_at_every_key(&scene, "object/Cube/opacity", colour, 3..4, |v| v, 1e-6);

    let light_node = node_index(&exported, "Key");
    let light =
        exported.json["nodes"][light_node]["extensions"]["KHR_lights_punctual"]["light"].as_u64().unwrap();
    let entry = &exported.json["extensions"]["KHR_lights_punctual"]["lights"][light as usize];
    assert_eq!(entry["range"], 12.0);
    let base = format!("/extensions/KHR_lights_punctual/lights/{light}");
    same_at_every_key(
        &scene,
        "light/Key/cutoff_deg",
        curve(&curves, &format!("{base}/spot/outerConeAngle")),
        0..1,
        f64::to_degrees,
        1e-4,
    );
    // Intensity keeps its export from before attributes: no pointer channel.
    assert!(curves.iter().all(|(n, _)| n != &format!("{base}/intensity")));
    same_at_every_key(
        &scene,
        "light/Key/visible",
        curve(&curves, &format!("/nodes/{light_node}/extensions/KHR_node_visibility/visible")),
        0..1,
        |v| v,
        0.0,
    );
}

#[test]
fn a_scene_without_attributes_exports_no_extension_channels() {
    let scene = keyrig_io::demo::demo_scene();
    let exported = export_scene(&scene, &ExportOptions::default()).unwrap();
    assert_eq!(exported.json["extensionsUsed"], serde_json::json!(["KHR_lights_punctual"]));
    let channels = exported.json["animations"][0]["channels"].as_array().unwrap();
    assert!(channels.iter().all(|c| c["target"].get("node").is_some()), "every channel targets a node");
}

#[test]
fn khronos_samples_round_trip_with_every_animated_property_equal() {
    // AnimatedColorsCube: the base colour pointer, read back from the export against the
    // original file's keys (both read here).
    let file = corpus("AnimatedColorsCube/AnimatedColorsCube.glb");
    let model = keyrig_io::gltf_import::import_gltf_file(&file).unwrap();
    let scene = model.to_scene("AnimatedColorsCube.glb", Some(0)).unwrap();
    let options =
        ExportOptions { base_dir: Some(file.parent().unwrap().to_path_buf()), ..ExportOptions::default() };
    let exported = export_and_validate(&scene, &options);
    assert!(uses(&exported, "KHR_animation_pointer"));
    let curves = read_curves(&exported);
    let node = node_index(&exported, "TestCube");
    let mesh = exported.json["nodes"][node]["mesh"].as_u64().unwrap() as usize;
    let material = exported.json["meshes"][mesh]["primitives"][0]["material"].as_u64().unwrap() as usize;
    let exported_colour =
        curve(&curves, &format!("/materials/{material}/pbrMetallicRoughness/baseColorFactor"));
    let original = {
        let data = std::fs::read(&file).unwrap();
        let len = u32::from_le_bytes(data[12..16].try_into().unwrap()) as usize;
        let json: Value = serde_json::from_slice(&data[20..20 + len]).unwrap();
        let bin_len = u32::from_le_bytes(data[20 + len..24 + len].try_into().unwrap()) as usize;
        let bin = data[28 + len..28 + len + bin_len].to_vec();
        let s = &json["animations"][0]["samplers"][2];
        let (times, _) = accessor(&json, &bin, s["input"].as_u64().unwrap() as usize);
        let (values, width) = accessor(&json, &bin, s["output"].as_u64().unwrap() as usize);
        Curve { times, interpolation: s["interpolation"].as_str().unwrap().to_owned(), values, width }
    };
    assert_eq!(exported_colour.times.len(), original.times.len());
    for &t in original.times.iter().chain(&exported_colour.times) {
        let (a, b) = (original.at(t), exported_colour.at(t));
        for (x, y) in a.iter().zip(&b) {
            assert!((x - y).abs() < 1e-6, "at {t}: file {a:?}, export {b:?}");
        }
    }
    same_at_every_key(&scene, "object/TestCube/colour", exported_colour, 0..3, |v| v, 1e-6);

    // LightVisibility: static visibility on every light node (hidden below the invisible
    // node), the blinking light keyed.
    let file = corpus("LightVisibility/LightVisibility.glb");
    let model = keyrig_io::gltf_import::import_gltf_file(&file).unwrap();
    let scene = model.to_scene("LightVisibility.glb", Some(0)).unwrap();
    let options =
        ExportOptions { base_dir: Some(file.parent().unwrap().to_path_buf()), ..ExportOptions::default() };
    let exported = export_and_validate(&scene, &options);
    let curves = read_curves(&exported);
    for (name, shown) in [("InvisibleLight", false), ("DescendantOfInvisibleShouldBeInvisible", false)] {
        let n = node_index(&exported, name);
        assert_eq!(
            exported.json["nodes"][n]["extensions"]["KHR_node_visibility"]["visible"], shown,
            "{name}"
        );
    }
    let blinking = node_index(&exported, "light2");
    same_at_every_key(
        &scene,
        "light/light2/visible",
        curve(&curves, &format!("/nodes/{blinking}/extensions/KHR_node_visibility/visible")),
        0..1,
        |v| v,
        0.0,
    );

    // AnimatedMorphCube: the scene's morph-weight channels as the node's weights channel.
    let file = corpus("AnimatedMorphCube/AnimatedMorphCube.glb");
    let model = keyrig_io::gltf_import::import_gltf_file(&file).unwrap();
    let scene = model.to_scene("AnimatedMorphCube.glb", Some(0)).unwrap();
    let options =
        ExportOptions { base_dir: Some(file.parent().unwrap().to_path_buf()), ..ExportOptions::default() };
    let exported = export_and_validate(&scene, &options);
    let curves = read_curves(&exported);
    let node = node_index(&exported, &scene.objects[0].name);
    let weights = curve(&curves, &format!("/nodes/{node}/weights"));
    // Weights are one element per target: regroup as width 2.
    let grouped = Curve {
        width: 2,
        times: weights.times.clone(),
        interpolation: weights.interpolation.clone(),
        values: weights.values.clone(),
    };
    for target in 0..2 {
        same_at_every_key(
            &scene,
            &format!("object/{}/morph/{target}", scene.objects[0].name),
            &grouped,
            target..target + 1,
            |v| v,
            1e-6,
        );
    }
}
