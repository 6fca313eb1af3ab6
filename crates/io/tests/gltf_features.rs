//! glTF features that no file of the corpus uses, read from small generated files: texture
//! coordinates stored as normalized 16-bit integers, samplers other than the default, an image
//! embedded as a `data:` URI in a .glb, a sparse accessor that replaces every element, and a
//! skin with more inverse bind matrices than joints (glTF requires at least as many).

#[path = "support/big_gltf.rs"]
mod big_gltf;

use big_gltf::{f32_bytes, glb, triangle, Bin};
use glam::{Vec2, Vec3};
use keyrig_core::{FilterMode, Sampler, WrapMode};
use keyrig_io::gltf_import::import_gltf_slice;
use serde_json::json;

/// A 1×1 PNG (one opaque pixel), base64.
const PIXEL_PNG: &str =
    "iVBORw0KGgoAAAANSUhEUgAAAAEAAAABCAYAAAAfFcSJAAAADUlEQVR42mNk+M9QDwADhgGAWjR9awAAAABJRU5ErkJggg==";

/// A .glb of one node, `triangle`, whose mesh's one primitive has the positions of accessor
/// `positions` (of `bin`).
fn triangle_glb(bin: Bin, positions: usize) -> Vec<u8> {
    let root = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "triangle", "mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": positions}}]}],
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    glb(root, bin.bytes)
}

/// A buffer view of `data` (4-byte aligned) without an accessor.
fn view(bin: &mut Bin, data: &[u8]) -> usize {
    while !bin.bytes.len().is_multiple_of(4) {
        bin.bytes.push(0);
    }
    bin.views.push(json!({"buffer": 0, "byteOffset": bin.bytes.len(), "byteLength": data.len()}));
    bin.bytes.extend_from_slice(data);
    bin.views.len() - 1
}

fn u16_bytes(values: &[u16]) -> Vec<u8> {
    values.iter().flat_map(|v| v.to_le_bytes()).collect()
}

/// Texture coordinates as normalized unsigned shorts (0 → 0, 65535 → 1), each primitive's
/// texture with its own sampler, the image a `data:` URI.
#[test]
fn normalized_texture_coordinates_samplers_and_embedded_images() {
    let mut bin = Bin::default();
    let positions = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 0.0, 1.0, 0.0];
    let pos = bin.add(
        &f32_bytes(positions),
        5126,
        4,
        "VEC3",
        Some((json!([0.0, 0.0, 0.0]), json!([1.0, 1.0, 0.0]))),
    );
    let indices = bin.add(&u16_bytes(&[0, 1, 2, 0, 2, 3]), 5123, 6, "SCALAR", None);
    let shorts: [u16; 8] = [0, 0, 65535, 0, 65535, 32768, 16384, 65535];
    let uv16 = bin.add(&u16_bytes(&shorts), 5123, 4, "VEC2", None);
    bin.accessors[uv16]["normalized"] = json!(true);
    let uv32 = bin.add(&f32_bytes([0.0, 0.0, 1.0, 0.0, 1.0, 1.0, 0.0, 1.0]), 5126, 4, "VEC2", None);
    let primitive = |uv: usize, material: usize| json!({"attributes": {"POSITION": pos, "TEXCOORD_0": uv}, "indices": indices, "material": material});
    let material = |texture: usize| json!({"pbrMetallicRoughness": {"baseColorTexture": {"index": texture}}});
    let root = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "quad", "mesh": 0}],
        "meshes": [{"primitives": [primitive(uv16, 0), primitive(uv32, 1)]}],
        "materials": [material(0), material(1)],
        "textures": [{"source": 0, "sampler": 0}, {"source": 0, "sampler": 1}],
        "samplers": [
            {"magFilter": 9728, "minFilter": 9986, "wrapS": 33071, "wrapT": 33648},
            {"magFilter": 9729, "minFilter": 9985, "wrapS": 33648, "wrapT": 10497},
        ],
        "images": [{"uri": format!("data:image/png;base64,{PIXEL_PNG}")}],
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    let model = import_gltf_slice(&glb(root, bin.bytes)).expect("import");
    let prims = &model.meshes[0].primitives;

    let uv = prims[0].texcoords.as_deref().expect("16-bit texture coordinates");
    let want: Vec<Vec2> = shorts.chunks(2).map(|c| Vec2::new(c[0] as f32, c[1] as f32) / 65535.0).collect();
    assert_eq!(uv, &want[..]);
    assert_eq!(uv[2].y, 32768.0 / 65535.0);

    let samplers: Vec<Sampler> =
        prims.iter().map(|p| p.base_colour_texture.as_ref().expect("texture").sampler).collect();
    assert_eq!(
        samplers[0],
        Sampler {
            wrap_u: WrapMode::ClampToEdge,
            wrap_v: WrapMode::MirroredRepeat,
            mag_filter: FilterMode::Nearest,
            min_filter: FilterMode::Nearest,
            mipmap_filter: Some(FilterMode::Linear),
        }
    );
    assert_eq!(
        samplers[1],
        Sampler {
            wrap_u: WrapMode::MirroredRepeat,
            wrap_v: WrapMode::Repeat,
            mag_filter: FilterMode::Linear,
            min_filter: FilterMode::Linear,
            mipmap_filter: Some(FilterMode::Nearest),
        }
    );

    let image = model.image_data[0].as_ref().expect("the embedded PNG is read");
    assert_eq!(image.mime_type, "image/png");
    assert_eq!(&image.bytes[..8], b"\x89PNG\r\n\x1a\n");
    // The whole PNG, up to its IEND chunk (the decoded URI is padded to 4 bytes).
    assert_eq!(&image.bytes[62..70], b"IEND\xaeB`\x82");
}

/// A sparse accessor may replace every element of its base (`sparse.count` equal to `count`).
#[test]
fn a_sparse_accessor_may_replace_every_element() {
    let mut bin = Bin::default();
    let base = [0.0; 9];
    let pos =
        bin.add(&f32_bytes(base), 5126, 3, "VEC3", Some((json!([0.0, 0.0, 0.0]), json!([2.0, 2.0, 0.0]))));
    let replaced = [2.0, 0.0, 0.0, 0.0, 2.0, 0.0, 2.0, 2.0, 0.0];
    let sparse_indices = view(&mut bin, &u16_bytes(&[0, 1, 2]));
    let sparse_values = view(&mut bin, &f32_bytes(replaced));
    bin.accessors[pos]["sparse"] = json!({
        "count": 3,
        "indices": {"bufferView": sparse_indices, "componentType": 5123},
        "values": {"bufferView": sparse_values},
    });
    let model = import_gltf_slice(&triangle_glb(bin, pos)).expect("import");
    let want: Vec<Vec3> = replaced.chunks(3).map(Vec3::from_slice).collect();
    assert_eq!(&model.meshes[0].primitives[0].positions[..], &want[..]);
}

/// A skin may have more inverse bind matrices than joints: the first ones are the joints'.
#[test]
fn a_skin_may_have_more_inverse_bind_matrices_than_joints() {
    let mut bin = Bin::default();
    let primitive = triangle(&mut bin);
    let translated = |y: f32| [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, y, 0.0, 1.0];
    let ibm = bin.add(&f32_bytes((0..4).flat_map(|j| translated(-(j as f32)))), 5126, 4, "MAT4", None);
    let root = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 3]}],
        "nodes": [
            {"name": "j0", "children": [1]},
            {"name": "j1", "translation": [0.0, 1.0, 0.0], "children": [2]},
            {"name": "j2", "translation": [0.0, 1.0, 0.0]},
            {"name": "mesh", "mesh": 0, "skin": 0},
        ],
        "meshes": [{"primitives": [primitive]}],
        "skins": [{"joints": [0, 1, 2], "inverseBindMatrices": ibm}],
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    let model = import_gltf_slice(&glb(root, bin.bytes)).expect("import");
    let matrices = &model.skins[0].inverse_bind_matrices;
    assert_eq!(matrices.len(), 4);
    for (j, m) in matrices.iter().enumerate() {
        assert_eq!(m.w_axis.y, -(j as f32), "matrix {j}");
    }
}

/// Accessors without a buffer view (zeros, then their sparse values) are read; together they
/// may not decode to more bytes than the file holds.
#[test]
fn accessors_without_a_view_decode_within_the_files_size() {
    let document = |count: usize| {
        let mut bin = Bin::default();
        let sparse_indices = view(&mut bin, &u16_bytes(&[1]));
        let sparse_values = view(&mut bin, &f32_bytes([2.0, 3.0, 4.0]));
        bin.accessors.push(json!({
            "componentType": 5126,
            "count": count,
            "type": "VEC3",
            "min": [0.0, 0.0, 0.0],
            "max": [2.0, 3.0, 4.0],
            "sparse": {
                "count": 1,
                "indices": {"bufferView": sparse_indices, "componentType": 5123},
                "values": {"bufferView": sparse_values},
            },
        }));
        triangle_glb(bin, 0)
    };
    let model = import_gltf_slice(&document(3)).expect("import");
    assert_eq!(
        &model.meshes[0].primitives[0].positions[..],
        [Vec3::ZERO, Vec3::new(2.0, 3.0, 4.0), Vec3::ZERO]
    );
    // Twelve times as many bytes as the file holds.
    let size = document(3).len();
    let err = import_gltf_slice(&document(size)).expect_err("more than the file holds");
    assert!(
        err.to_string().contains("accessors without a bufferView would decode to more than the file's"),
        "{err}"
    );
}

fn corpus(rel: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf").join(rel)
}

/// CUBICSPLINE morph weights between keys two seconds apart: the tangents are per second, so
/// the Hermite terms scale them by the key spacing (glTF 2.0, Appendix C).
#[test]
fn cubic_spline_weights_scale_their_tangents_by_the_key_spacing() {
    let mut bin = Bin::default();
    let positions = [0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0];
    let pos = bin.add(
        &f32_bytes(positions),
        5126,
        3,
        "VEC3",
        Some((json!([0.0, 0.0, 0.0]), json!([1.0, 1.0, 0.0]))),
    );
    let target = bin.add(
        &f32_bytes([0.0, 0.0, 1.0].repeat(3)),
        5126,
        3,
        "VEC3",
        Some((json!([0.0, 0.0, 1.0]), json!([0.0, 0.0, 1.0]))),
    );
    let times = bin.add(&f32_bytes([0.0, 2.0]), 5126, 2, "SCALAR", Some((json!([0.0]), json!([2.0]))));
    // Per key: in-tangent, value, out-tangent (one target).
    let values = bin.add(&f32_bytes([0.0, 0.0, 2.0, -0.5, 1.0, 0.0]), 5126, 6, "SCALAR", None);
    let root = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "morph", "mesh": 0}],
        "meshes": [{"primitives": [{"attributes": {"POSITION": pos}, "targets": [{"POSITION": target}]}], "weights": [0.0]}],
        "animations": [{
            "channels": [{"sampler": 0, "target": {"node": 0, "path": "weights"}}],
            "samplers": [{"input": times, "output": values, "interpolation": "CUBICSPLINE"}],
        }],
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    let model = import_gltf_slice(&glb(root, bin.bytes)).expect("import");
    let keyrig_io::model::ChannelTarget::Weights(track) = &model.animations[0].channels[0].target else {
        panic!("a weights channel")
    };
    // u = 1/2, t_d = 2: h00 p0 + h10 t_d m0 + h01 p1 + h11 t_d m1
    //                 = 0 + (1/8)(2)(2) + (1/2)(1) + (−1/8)(2)(−0.5) = 1.125.
    let w = keyrig_io::model::sample_weights(track, 1.0).expect("weights");
    assert!((w[0] - 1.125).abs() < 1e-6, "{w:?}");
}

/// A skinned mesh keeps the texture coordinates of its file (CesiumMan's, in vertex order).
#[test]
fn a_skinned_mesh_keeps_its_texture_coordinates() {
    let model = keyrig_io::gltf_import::import_gltf_file(&corpus("CesiumMan/CesiumMan.glb")).expect("import");
    let node = model.nodes.iter().position(|n| n.skin.is_some() && n.mesh.is_some()).expect("skinned node");
    let mesh = model.skinned_mesh(node).expect("skinned mesh");
    let want: Vec<Vec2> = model.meshes[model.nodes[node].mesh.expect("mesh")]
        .primitives
        .iter()
        .flat_map(|p| p.texcoords.as_deref().expect("texture coordinates").iter().copied())
        .collect();
    assert!(want.iter().any(|uv| *uv != Vec2::ZERO));
    assert_eq!(mesh.uvs.as_deref(), Some(&want[..]));
}

/// A model changed in memory whose skin names a node that does not exist maps without a
/// panic (the importer never makes one: this guards hand-made models).
#[test]
fn a_skin_joint_past_the_last_node_does_not_panic() {
    let mut model =
        keyrig_io::gltf_import::import_gltf_file(&corpus("RiggedSimple/RiggedSimple.glb")).expect("import");
    let past = model.nodes.len();
    model.skins[0].joints.push(past);
    let mapped = std::panic::catch_unwind(|| model.to_scene("x.glb", None).map(|s| s.objects.len()));
    assert!(mapped.is_ok(), "mapping panicked");
}

/// Found by the `gltf` fuzz target (a mutated InterpolationTest.glb): an image in a buffer
/// view without its `mimeType`, and an image with neither a URI nor a buffer view, made the
/// gltf crate's `Image::source` unwrap and panic. Both import; the image's bytes are read from
/// the view when there is one (its type sniffed from the bytes), and are absent otherwise.
#[test]
fn images_without_a_mime_type_or_a_source_do_not_panic() {
    let data = std::fs::read(corpus("InterpolationTest/InterpolationTest.glb")).expect("corpus file");
    let json_len = u32::from_le_bytes(data[12..16].try_into().expect("4 bytes")) as usize;
    let root: serde_json::Value = serde_json::from_slice(&data[20..20 + json_len]).expect("JSON");
    let bin_len =
        u32::from_le_bytes(data[20 + json_len..24 + json_len].try_into().expect("4 bytes")) as usize;
    let bin = data[28 + json_len..28 + json_len + bin_len].to_vec();
    assert!(root["images"][0]["bufferView"].is_u64(), "the corpus file embeds its image in a view");
    let mut no_mime = root.clone();
    no_mime["images"][0].as_object_mut().expect("an image").remove("mimeType");
    let model = import_gltf_slice(&glb(no_mime, bin.clone())).expect("imports without the MIME type");
    let image = model.image_data[0].as_ref().expect("the view's bytes are read");
    assert_eq!(image.mime_type, "image/jpeg");
    let mut no_source = root;
    let image = no_source["images"][0].as_object_mut().expect("an image");
    image.remove("mimeType");
    image.remove("bufferView");
    let model = import_gltf_slice(&glb(no_source, bin)).expect("imports without an image source");
    assert!(model.image_data[0].is_none());
}
