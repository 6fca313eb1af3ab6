//! `KHR_animation_pointer` and `KHR_node_visibility` import: the Khronos samples open, their
//! pointer channels hold the file's keys (checked against the accessors read here straight from
//! the GLB with serde_json, not through keyrig's importer), and unknown pointers are skipped and
//! named.

use std::path::{Path, PathBuf};

use keyrig_core::Interpolation;
use keyrig_io::gltf_import::{import_gltf_file, import_gltf_slice};
use keyrig_io::gltf_pointer::{PointerKeys, PointerTarget};
use serde_json::Value;

fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf").join(rel)
}

/// The JSON and BIN chunks of a GLB.
fn glb(path: &Path) -> (Value, Vec<u8>) {
    let data = std::fs::read(path).unwrap();
    let u32_at = |o: usize| u32::from_le_bytes(data[o..o + 4].try_into().unwrap()) as usize;
    let json_len = u32_at(12);
    let json: Value = serde_json::from_slice(&data[20..20 + json_len]).unwrap();
    let bin_at = 20 + json_len;
    let bin_len = u32_at(bin_at);
    (json, data[bin_at + 8..bin_at + 8 + bin_len].to_vec())
}

/// The float components of accessor `a` (tightly packed FLOAT accessors only).
fn floats(json: &Value, bin: &[u8], a: usize) -> Vec<f32> {
    let acc = &json["accessors"][a];
    assert_eq!(acc["componentType"], 5126);
    let n = acc["count"].as_u64().unwrap() as usize
        * match acc["type"].as_str().unwrap() {
            "SCALAR" => 1,
            "VEC3" => 3,
            "VEC4" => 4,
            t => panic!("{t}"),
        };
    let view = &json["bufferViews"][acc["bufferView"].as_u64().unwrap() as usize];
    let start =
        view["byteOffset"].as_u64().unwrap_or(0) as usize + acc["byteOffset"].as_u64().unwrap_or(0) as usize;
    (0..n).map(|i| f32::from_le_bytes(bin[start + 4 * i..start + 4 * i + 4].try_into().unwrap())).collect()
}

#[test]
fn animated_colors_cube_opens_with_its_base_colour_channel() {
    let path = corpus("AnimatedColorsCube/AnimatedColorsCube.glb");
    let model = import_gltf_file(&path).unwrap_or_else(|e| panic!("{e}"));
    assert!(model.skipped_channels.is_empty(), "{:?}", model.skipped_channels);
    let anim = &model.animations[0];
    assert_eq!(anim.channels.len(), 2, "translation and rotation of node 0");
    assert_eq!(anim.pointers.len(), 1);
    let p = &anim.pointers[0];
    assert_eq!(p.pointer, "/materials/0/pbrMetallicRoughness/baseColorFactor");
    assert_eq!(p.target, PointerTarget::MaterialBaseColour(0));
    let PointerKeys::Vec4(track) = &p.keys else { panic!("{:?}", p.keys) };
    let (json, bin) = glb(&path);
    let sampler = &json["animations"][0]["samplers"][2];
    let times = floats(&json, &bin, sampler["input"].as_u64().unwrap() as usize);
    let values = floats(&json, &bin, sampler["output"].as_u64().unwrap() as usize);
    assert_eq!(track.keys.len(), 151);
    assert_eq!(times.len(), 151);
    for (k, key) in track.keys.iter().enumerate() {
        assert_eq!(key.time, f64::from(times[k]));
        assert_eq!(key.value.to_array(), values[4 * k..4 * k + 4]);
        assert_eq!(key.interpolation, Interpolation::Linear);
    }
    assert_eq!(anim.duration(), 3.0, "the node channels run to 3 s, the colour to 2.5 s");
    // The primitive knows its material, so the scene mapping can find what the pointer colours.
    assert_eq!(model.meshes[0].primitives[0].material, Some(0));
}

#[test]
fn light_visibility_reads_static_and_animated_visibility() {
    let path = corpus("LightVisibility/LightVisibility.glb");
    let model = import_gltf_file(&path).unwrap_or_else(|e| panic!("{e}"));
    let visible: Vec<bool> = model.nodes.iter().map(|n| n.visible).collect();
    assert_eq!(visible, [true, false, true, true, true, true, true]);
    let anim = &model.animations[0];
    assert_eq!(anim.name, "BlinkingBlueLight");
    assert_eq!(anim.pointers.len(), 1);
    assert_eq!(anim.pointers[0].target, PointerTarget::NodeVisible(5));
    let PointerKeys::Scalar(track) = &anim.pointers[0].keys else { panic!() };
    let (json, bin) = glb(&path);
    let sampler = &json["animations"][0]["samplers"][0];
    let times = floats(&json, &bin, sampler["input"].as_u64().unwrap() as usize);
    let out = &json["accessors"][sampler["output"].as_u64().unwrap() as usize];
    assert_eq!(out["componentType"], 5121, "booleans as unsigned bytes");
    let view = &json["bufferViews"][out["bufferView"].as_u64().unwrap() as usize];
    let start = view["byteOffset"].as_u64().unwrap_or(0) as usize;
    assert_eq!(track.keys.len(), 11);
    for (k, key) in track.keys.iter().enumerate() {
        assert_eq!(key.time, f64::from(times[k]));
        assert_eq!(key.value, f32::from(bin[start + k].min(1)));
        assert_eq!(key.interpolation, Interpolation::Step);
    }
    assert!(track.keys.iter().any(|k| k.value == 0.0) && track.keys.iter().any(|k| k.value == 1.0));
}

/// A minimal .gltf with one node and the given animation channels (all on sampler 0, one key).
fn with_channels(channels: &str, extra: &str) -> Vec<u8> {
    // One float key time (0.0) and one VEC4 value (1, 0.5, 0.25, 1) in a base64 buffer.
    let mut bytes = Vec::new();
    for f in [0.0f32, 1.0, 0.5, 0.25, 1.0] {
        bytes.extend_from_slice(&f.to_le_bytes());
    }
    let b64 = base64(&bytes);
    format!(
        r#"{{"asset":{{"version":"2.0"}},"nodes":[{{"name":"n"}}],{extra}
        "buffers":[{{"byteLength":20,"uri":"data:application/octet-stream;base64,{b64}"}}],
        "bufferViews":[{{"buffer":0,"byteLength":4}},{{"buffer":0,"byteOffset":4,"byteLength":16}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":1,"type":"SCALAR","min":[0],"max":[0]}},
                     {{"bufferView":1,"componentType":5126,"count":1,"type":"VEC4"}}],
        "animations":[{{"channels":[{channels}],"samplers":[{{"input":0,"output":1}}]}}]}}"#
    )
    .into_bytes()
}

fn base64(bytes: &[u8]) -> String {
    const A: &[u8; 64] = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/";
    let mut out = String::new();
    for chunk in bytes.chunks(3) {
        let b = [chunk[0], *chunk.get(1).unwrap_or(&0), *chunk.get(2).unwrap_or(&0)];
        let n = (u32::from(b[0]) << 16) | (u32::from(b[1]) << 8) | u32::from(b[2]);
        for i in 0..4 {
            if i <= chunk.len() {
                out.push(A[(n >> (18 - 6 * i)) as usize & 63] as char);
            } else {
                out.push('=');
            }
        }
    }
    out
}

#[test]
fn unknown_pointers_and_nodeless_channels_are_skipped_and_named() {
    let json = with_channels(
        r#"{"sampler":0,"target":{"path":"pointer","extensions":{"KHR_animation_pointer":{"pointer":"/materials/0/emissiveFactor"}}}},
           {"sampler":0,"target":{"path":"pointer","extensions":{"KHR_animation_pointer":{"pointer":"/cameras/0/perspective/yfov"}}}},
           {"sampler":0,"target":{"path":"rotation"}},
           {"sampler":0,"target":{"node":0,"path":"rotation"}},
           {"sampler":0,"target":{"path":"pointer","extensions":{"KHR_animation_pointer":{"pointer":"/nodes/7/rotation"}}}}"#,
        r#""materials":[{}],"#,
    );
    let model = import_gltf_slice(&json).unwrap_or_else(|e| panic!("{e}"));
    assert_eq!(model.animations[0].channels.len(), 1, "the node channel stays");
    let skipped: Vec<String> = model.skipped_channels.iter().map(ToString::to_string).collect();
    assert_eq!(skipped.len(), 4, "{skipped:#?}");
    assert!(
        skipped[0].starts_with("/animations/0/channels/0 (/materials/0/emissiveFactor): "),
        "{}",
        skipped[0]
    );
    assert!(skipped[1].contains("camera 0 does not exist (the file has 0)"), "{}", skipped[1]);
    assert!(skipped[2].starts_with("/animations/0/channels/2: no node"), "{}", skipped[2]);
    assert!(skipped[3].contains("node 7 does not exist (the file has 1)"), "{}", skipped[3]);
}

#[test]
fn a_node_rotation_pointer_is_a_node_channel() {
    let json = with_channels(
        r#"{"sampler":0,"target":{"path":"pointer","extensions":{"KHR_animation_pointer":{"pointer":"/nodes/0/rotation"}}}}"#,
        "",
    );
    let model = import_gltf_slice(&json).unwrap_or_else(|e| panic!("{e}"));
    let channels = &model.animations[0].channels;
    assert_eq!(channels.len(), 1);
    let keyrig_io::model::ChannelTarget::Rotation(track) = &channels[0].target else { panic!() };
    let q = glam::Vec4::new(1.0, 0.5, 0.25, 1.0).normalize();
    assert!((glam::Vec4::from(track.keys[0].value) - q).length() < 1e-6);
}

#[test]
fn a_bad_pointer_output_is_an_error_with_its_place() {
    // baseColorFactor is VEC4; a light intensity pointer on the same VEC4 output is refused.
    let json = with_channels(
        r#"{"sampler":0,"target":{"path":"pointer","extensions":{"KHR_animation_pointer":{"pointer":"/extensions/KHR_lights_punctual/lights/0/intensity"}}}}"#,
        r#""extensions":{"KHR_lights_punctual":{"lights":[{"type":"point"}]}},"extensionsUsed":["KHR_lights_punctual"],"#,
    );
    let err = import_gltf_slice(&json).unwrap_err().to_string();
    assert!(err.starts_with("/accessors/1: accessor: type Vec4"), "{err}");
}

#[test]
fn the_scene_holds_colour_opacity_and_visibility_as_channels() {
    use keyrig_core::channel::ChannelPath;
    let path = corpus("AnimatedColorsCube/AnimatedColorsCube.glb");
    let model = import_gltf_file(&path).unwrap();
    let scene = model.to_scene("AnimatedColorsCube.glb", Some(0)).unwrap();
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    let (json, bin) = glb(&path);
    let sampler = &json["animations"][0]["samplers"][2];
    let times = floats(&json, &bin, sampler["input"].as_u64().unwrap() as usize);
    let values = floats(&json, &bin, sampler["output"].as_u64().unwrap() as usize);
    let colour = ChannelPath::parse("object/TestCube/colour").unwrap().resolve(&scene).unwrap();
    let opacity = ChannelPath::parse("object/TestCube/opacity").unwrap().resolve(&scene).unwrap();
    for (k, &t) in times.iter().enumerate() {
        let rgba = &values[4 * k..4 * k + 4];
        assert_eq!(
            colour.sample(f64::from(t)),
            keyrig_core::channel_id::ChannelValue::Vec3(glam::Vec3::new(rgba[0], rgba[1], rgba[2]))
        );
        assert_eq!(opacity.sample(f64::from(t)), keyrig_core::channel_id::ChannelValue::Scalar(rgba[3]));
    }
    // The other cubes use other materials: no colour channel, always opaque.
    assert!(scene.objects[1].attributes.colour.is_none());

    let model = import_gltf_file(&corpus("LightVisibility/LightVisibility.glb")).unwrap();
    let scene = model.to_scene("LightVisibility.glb", Some(0)).unwrap();
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    let names: Vec<&str> = scene.lights.iter().map(|l| l.name.as_str()).collect();
    assert_eq!(
        names,
        [
            "InvisibleLight",
            "ChildOfInvisibleShouldBeInvisible",
            "DescendantOfInvisibleShouldBeInvisible",
            "light1",
            "light2"
        ]
    );
    // The invisible node hides its light and every light below it.
    for (light, name) in scene.lights.iter().zip(&names).take(3) {
        assert_eq!(light.attributes.visible, keyrig_core::Animated::constant(0.0), "{name}");
    }
    assert_eq!(scene.lights[3].attributes.visible, keyrig_core::Animated::constant(1.0));
    assert_eq!(scene.lights[4].attributes.visible.track.len(), 11);
    // KHR_lights_punctual range 5 is kept; the cone stays the kind's (not animated).
    assert_eq!(scene.lights[3].attributes.range, Some(keyrig_core::Animated::constant(5.0)));
}

#[test]
fn morph_weights_become_one_channel_per_target() {
    let model = import_gltf_file(&corpus("AnimatedMorphCube/AnimatedMorphCube.glb")).unwrap();
    let scene = model.to_scene("AnimatedMorphCube.glb", Some(0)).unwrap();
    let weights = &scene.objects[0].attributes.morph_weights;
    assert_eq!(weights.len(), 2);
    let keyrig_io::model::ChannelTarget::Weights(w) = &model.animations[0].channels[0].target else {
        panic!()
    };
    for (k, key) in w.keys.iter().enumerate() {
        for (t, channel) in weights.iter().enumerate() {
            assert_eq!(channel.track.keys[k].time, key.time);
            assert_eq!(channel.track.keys[k].value, key.value[t]);
        }
    }
}

/// A .gltf with a perspective camera (node 0, keyed visibility), an orthographic one (node 1,
/// hidden) and pointer channels on both: yfov and ymag (kept), znear and xmag (skipped).
fn camera_file() -> Vec<u8> {
    let mut bytes = Vec::new();
    // 0: times (0, 1); 8: yfov (0.5, 1.0); 16: ymag (1.5, 3.0); 24: znear (0.1, 0.2);
    // 32: visibility (1, 0) as unsigned bytes.
    for f in [0.0f32, 1.0, 0.5, 1.0, 1.5, 3.0, 0.1, 0.2] {
        bytes.extend_from_slice(&f.to_le_bytes());
    }
    bytes.extend_from_slice(&[1, 0, 0, 0]);
    let b64 = base64(&bytes);
    let pointer = |sampler: usize, p: &str| {
        format!(
            r#"{{"sampler":{sampler},"target":{{"path":"pointer","extensions":{{"KHR_animation_pointer":{{"pointer":"{p}"}}}}}}}}"#
        )
    };
    let channels = [
        pointer(0, "/cameras/0/perspective/yfov"),
        pointer(1, "/cameras/1/orthographic/ymag"),
        pointer(2, "/cameras/0/perspective/znear"),
        pointer(1, "/cameras/1/orthographic/xmag"),
        pointer(3, "/nodes/0/extensions/KHR_node_visibility/visible"),
    ]
    .join(",");
    format!(
        r#"{{"asset":{{"version":"2.0"}},
        "extensionsUsed":["KHR_animation_pointer","KHR_node_visibility"],
        "cameras":[{{"type":"perspective","perspective":{{"yfov":0.5,"znear":0.1,"zfar":100}}}},
                   {{"type":"orthographic","orthographic":{{"xmag":1.5,"ymag":1.5,"znear":0.1,"zfar":50}}}}],
        "nodes":[{{"name":"Persp","camera":0,"translation":[0,1,5]}},
                 {{"name":"Ortho","camera":1,"extensions":{{"KHR_node_visibility":{{"visible":false}}}}}}],
        "buffers":[{{"byteLength":36,"uri":"data:application/octet-stream;base64,{b64}"}}],
        "bufferViews":[{{"buffer":0,"byteLength":8}},{{"buffer":0,"byteOffset":8,"byteLength":8}},
                       {{"buffer":0,"byteOffset":16,"byteLength":8}},{{"buffer":0,"byteOffset":24,"byteLength":8}},
                       {{"buffer":0,"byteOffset":32,"byteLength":2}}],
        "accessors":[{{"bufferView":0,"componentType":5126,"count":2,"type":"SCALAR","min":[0],"max":[1]}},
                     {{"bufferView":1,"componentType":5126,"count":2,"type":"SCALAR"}},
                     {{"bufferView":2,"componentType":5126,"count":2,"type":"SCALAR"}},
                     {{"bufferView":3,"componentType":5126,"count":2,"type":"SCALAR"}},
                     {{"bufferView":4,"componentType":5121,"count":2,"type":"SCALAR"}}],
        "animations":[{{"channels":[{channels}],
            "samplers":[{{"input":0,"output":1}},{{"input":0,"output":2}},{{"input":0,"output":3}},
                        {{"input":0,"output":4,"interpolation":"STEP"}}]}}]}}"#
    )
    .into_bytes()
}

#[test]
fn camera_pointers_become_lens_keys_and_the_rest_are_skipped_and_named() {
    let model = import_gltf_slice(&camera_file()).unwrap_or_else(|e| panic!("{e}"));
    let targets: Vec<PointerTarget> = model.animations[0].pointers.iter().map(|p| p.target).collect();
    assert_eq!(
        targets,
        vec![PointerTarget::CameraYfov(0), PointerTarget::CameraYmag(1), PointerTarget::NodeVisible(0)]
    );
    let skipped: Vec<String> = model.skipped_channels.iter().map(ToString::to_string).collect();
    assert_eq!(skipped.len(), 2, "{skipped:#?}");
    assert_eq!(
        skipped[0],
        "/animations/0/channels/2 (/cameras/0/perspective/znear): keyrig's clip planes are not keyed: the camera keeps the file's"
    );
    assert!(skipped[1].starts_with("/animations/0/channels/3 (/cameras/1/orthographic/xmag): keyrig's orthographic view width follows"), "{}", skipped[1]);

    let scene = model.to_scene("cameras.gltf", Some(0)).unwrap();
    assert_eq!(scene.problems(), Vec::new());
    let (persp, ortho) = (&scene.cameras[0], &scene.cameras[1]);
    // yfov radians → field of view in degrees, key for key; ymag → view height 2·ymag.
    let lens: Vec<(f64, f32)> = persp.lens.track.keys.iter().map(|k| (k.time, k.value)).collect();
    assert_eq!(lens, vec![(0.0, 0.5f32.to_degrees()), (1.0, 1.0f32.to_degrees())]);
    assert!(persp.lens.track.keys.iter().all(|k| k.interpolation == Interpolation::Linear));
    let height: Vec<(f64, f32)> = ortho.lens.track.keys.iter().map(|k| (k.time, k.value)).collect();
    assert_eq!(height, vec![(0.0, 3.0), (1.0, 6.0)]);
    assert_eq!((persp.near, persp.far), (0.1, Some(100.0)), "the file's clip planes");
    // Visibility: the perspective camera's keyed (Step), the orthographic camera's hidden.
    let shown: Vec<(f64, f32, Interpolation)> =
        persp.visible.track.keys.iter().map(|k| (k.time, k.value, k.interpolation)).collect();
    assert_eq!(shown, vec![(0.0, 1.0, Interpolation::Step), (1.0, 0.0, Interpolation::Step)]);
    assert!(!ortho.visible.is_animated() && ortho.visible.value == 0.0);
    let listed: Vec<String> =
        keyrig_core::channel::list_channels(&scene).iter().map(ToString::to_string).collect();
    assert!(
        listed.contains(&"camera/Persp/visible".to_owned())
            && listed.contains(&"camera/Ortho/visible".to_owned()),
        "{listed:?}"
    );
}
