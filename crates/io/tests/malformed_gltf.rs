//! Malformed glTF files made from the corpus — truncated, bytes flipped, counts of 2^31,
//! offsets past the end, NaN, indices out of range, node cycles — each is rejected with a
//! location (byte offset, line:column or JSON pointer) or imported, never a panic, and never
//! with more memory than the file can justify.

#[path = "support/big_gltf.rs"]
mod big_gltf;
mod malformed_support;

use std::path::{Path, PathBuf};

use keyrig_io::gltf_import::{import_gltf_file, import_gltf_slice, GltfError, Location};
use malformed_support::{byte_flips, run_suite, truncations, CountingAlloc, Mutant, Rng};
use serde_json::{json, Value};

#[global_allocator]
static ALLOC: CountingAlloc = CountingAlloc;

fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf").join(rel)
}

const GLBS: [&str; 6] = [
    "RiggedSimple/RiggedSimple.glb",
    "RiggedFigure/RiggedFigure.glb",
    "CesiumMan/CesiumMan.glb",
    "Fox/Fox.glb",
    "InterpolationTest/InterpolationTest.glb",
    "AnimatedMorphCube/AnimatedMorphCube.glb",
];

/// Splits a valid .glb into its JSON value and BIN chunk.
fn split_glb(data: &[u8]) -> (Value, Vec<u8>) {
    let json_len = u32::from_le_bytes(data[12..16].try_into().expect("4 bytes")) as usize;
    let json: Value = serde_json::from_slice(&data[20..20 + json_len]).expect("corpus JSON");
    let bin_start = 20 + json_len;
    let bin = if bin_start + 8 <= data.len() { data[bin_start + 8..].to_vec() } else { Vec::new() };
    (json, bin)
}

/// Packs JSON and BIN into a .glb (chunks padded to 4 bytes).
fn pack_glb(json: &Value, bin: &[u8]) -> Vec<u8> {
    let mut j = serde_json::to_vec(json).expect("serialize");
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin.to_vec();
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + if b.is_empty() { 0 } else { 8 + b.len() };
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(&0x4E4F_534Au32.to_le_bytes());
    out.extend_from_slice(&j);
    if !b.is_empty() {
        out.extend_from_slice(&(b.len() as u32).to_le_bytes());
        out.extend_from_slice(&0x004E_4942u32.to_le_bytes());
        out.extend_from_slice(&b);
    }
    out
}

/// Sets `pointer` in `json` to `value` if the pointer exists.
fn set(json: &Value, pointer: &str, value: Value) -> Option<Value> {
    let mut j = json.clone();
    *j.pointer_mut(pointer)? = value;
    Some(j)
}

/// Structured edits of the document: hostile counts, offsets, indices and cycles.
fn json_edits(json: &Value) -> Vec<(String, Value)> {
    let mut edits = Vec::new();
    let n = |key: &str| json.get(key).and_then(Value::as_array).map_or(0, Vec::len);
    let mut push = |label: String, v: Option<Value>| {
        if let Some(v) = v {
            edits.push((label, v));
        }
    };
    for a in 0..n("accessors").min(12) {
        for (field, value) in [
            ("count", json!(2_147_483_648u64)),
            ("count", json!(0)),
            ("count", json!(-1)),
            ("byteOffset", json!(1u64 << 31)),
            ("bufferView", json!(9999)),
            ("componentType", json!(5121)),
            ("type", json!("MAT4")),
        ] {
            push(
                format!("/accessors/{a}/{field} := {value}"),
                set(json, &format!("/accessors/{a}/{field}"), value),
            );
        }
    }
    for v in 0..n("bufferViews").min(8) {
        for (field, value) in [
            ("byteLength", json!(2_147_483_648u64)),
            ("byteOffset", json!(1u64 << 30)),
            ("byteStride", json!(4)),
        ] {
            push(
                format!("/bufferViews/{v}/{field} := {value}"),
                set(json, &format!("/bufferViews/{v}/{field}"), value),
            );
        }
    }
    push("/buffers/0/byteLength := 2^31".into(), set(json, "/buffers/0/byteLength", json!(2_147_483_648u64)));
    push("/buffers/0/uri := /dev/zero".into(), set(json, "/buffers/0/uri", json!("/dev/zero")));
    push("/buffers/0/uri := ../x.bin".into(), set(json, "/buffers/0/uri", json!("../x.bin")));
    push(
        "/buffers/0/uri := data:bad".into(),
        set(json, "/buffers/0/uri", json!("data:application/octet-stream;base64,@@@")),
    );
    // Node cycles: the last node becomes a child of itself; node 0 a child of its child.
    let nodes = n("nodes");
    if nodes > 0 {
        let last = nodes - 1;
        push(
            format!("node {last} child of itself"),
            set(json, &format!("/nodes/{last}/children"), json!([last])),
        );
        if let Some(child) = json.pointer("/nodes/0/children/0").and_then(Value::as_u64) {
            push(
                format!("cycle 0 -> {child} -> 0"),
                set(json, &format!("/nodes/{child}/children"), json!([0])),
            );
        }
        push("/nodes/0/mesh := 9999".into(), set(json, "/nodes/0/mesh", json!(9999)));
        push("/nodes/0/children := [9999]".into(), set(json, "/nodes/0/children", json!([9999])));
        push("/nodes/0/rotation := zero".into(), set(json, "/nodes/0/rotation", json!([0.0, 0.0, 0.0, 0.0])));
        push("/nodes/0/scale := 1e39".into(), set(json, "/nodes/0/scale", json!([1e39, 1.0, 1.0])));
    }
    for s in 0..n("skins") {
        push(format!("/skins/{s}/joints := [9999]"), set(json, &format!("/skins/{s}/joints"), json!([9999])));
        push(format!("/skins/{s}/joints := []"), set(json, &format!("/skins/{s}/joints"), json!([])));
    }
    for a in 0..n("animations").min(3) {
        push(
            format!("/animations/{a}/samplers/0/interpolation := CUBICSPLINE"),
            set(json, &format!("/animations/{a}/samplers/0/interpolation"), json!("CUBICSPLINE")),
        );
        push(
            format!("/animations/{a}/channels/0/target/node := 9999"),
            set(json, &format!("/animations/{a}/channels/0/target/node"), json!(9999)),
        );
        push(
            format!("/animations/{a}/channels/0/target/path := weights"),
            set(json, &format!("/animations/{a}/channels/0/target/path"), json!("weights")),
        );
        if let Some(output) = json.pointer(&format!("/animations/{a}/samplers/0/output")).cloned() {
            push(
                format!("/animations/{a}/samplers/0/input := output"),
                set(json, &format!("/animations/{a}/samplers/0/input"), output),
            );
        }
    }
    push(
        "extensionsRequired := [KHR_draco_mesh_compression]".into(),
        set(json, "/asset", json!({"version": "2.0"})).and_then(|j| {
            let mut j = j;
            j.as_object_mut()?.insert("extensionsRequired".into(), json!(["KHR_draco_mesh_compression"]));
            Some(j)
        }),
    );
    for pointer in [
        "/textures/0/source",
        "/textures/0/sampler",
        "/materials/0/pbrMetallicRoughness/baseColorTexture/index",
        "/meshes/0/primitives/0/material",
        "/meshes/0/primitives/0/indices",
        "/meshes/0/primitives/0/attributes/POSITION",
        "/meshes/0/primitives/0/attributes/JOINTS_0",
        "/skins/0/inverseBindMatrices",
        "/skins/0/skeleton",
        "/scenes/0/nodes/0",
        "/scene",
        "/images/0/bufferView",
        "/nodes/0/skin",
        "/animations/0/channels/0/sampler",
        "/animations/0/samplers/0/output",
    ] {
        push(format!("{pointer} := 9999"), set(json, pointer, json!(9999)));
        push(format!("{pointer} := -1"), set(json, pointer, json!(-1)));
    }
    push("/meshes/0/primitives/0/mode := 1".into(), set(json, "/meshes/0/primitives/0/mode", json!(1)));
    push("/meshes/0/primitives/0/mode := 5".into(), set(json, "/meshes/0/primitives/0/mode", json!(5)));
    push("/meshes/0/primitives/0/mode := 6".into(), set(json, "/meshes/0/primitives/0/mode", json!(6)));
    push("/meshes/0/primitives/0/mode := 99".into(), set(json, "/meshes/0/primitives/0/mode", json!(99)));
    push("/asset/version := 3.0".into(), set(json, "/asset/version", json!("3.0")));
    edits
}

/// Overwrites floats and indices in the BIN chunk through the accessors that point at them:
/// NaN positions and key times, joint indices of 255, decreasing times.
fn bin_edits(json: &Value, bin: &[u8]) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let Some(accessors) = json.get("accessors").and_then(Value::as_array) else { return out };
    let views = json.get("bufferViews").and_then(Value::as_array).cloned().unwrap_or_default();
    for (i, acc) in accessors.iter().enumerate().take(24) {
        let Some(view) = acc.get("bufferView").and_then(Value::as_u64).and_then(|v| views.get(v as usize))
        else {
            continue;
        };
        let start = view.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize
            + acc.get("byteOffset").and_then(Value::as_u64).unwrap_or(0) as usize;
        if start + 4 > bin.len() {
            continue;
        }
        let component = acc.get("componentType").and_then(Value::as_u64).unwrap_or(0);
        let mut b = bin.to_vec();
        if component == 5126 {
            b[start..start + 4].copy_from_slice(&f32::NAN.to_bits().to_le_bytes());
            out.push((format!("accessor {i} first float := NaN"), b.clone()));
            b[start..start + 4].copy_from_slice(&1e30f32.to_bits().to_le_bytes());
            out.push((format!("accessor {i} first float := 1e30"), b));
        } else {
            for byte in &mut b[start..start + 4] {
                *byte = 0xff;
            }
            out.push((format!("accessor {i} first integers := 0xff.."), b));
        }
    }
    out
}

fn has_location(e: &GltfError) -> bool {
    !matches!(e.location, Location::File) && !e.to_string().is_empty()
}

/// Peak memory allowed for an input of `len` bytes: the file itself is borrowed; the model
/// holds decoded floats (up to a few times the bytes they came from) and the parsed JSON.
fn max_alloc(len: usize) -> usize {
    8 * len + (512 << 10)
}

#[test]
fn malformed_glb_files_are_rejected_with_a_location_never_a_panic() {
    let mut mutants = Vec::new();
    for (i, file) in GLBS.iter().enumerate() {
        let data = std::fs::read(corpus(file)).expect("read corpus");
        let (json, bin) = split_glb(&data);
        let mut local = truncations(&data, 25);
        local.extend(byte_flips(&data, 25, 3, 0xabc + i as u64));
        // Flips inside the JSON chunk (the structure) rather than anywhere.
        let json_len = u32::from_le_bytes(data[12..16].try_into().expect("4")) as usize;
        let mut rng = Rng::new(0x77 + i as u64);
        for k in 0..25 {
            let mut b = data.clone();
            let at = 20 + rng.below(json_len);
            b[at] = b"{}[]\",:0-e9 x"[rng.below(13)];
            local.push(Mutant { label: format!("JSON byte {at} replaced #{k}"), bytes: b });
        }
        for (offset, value) in
            [(8usize, u32::MAX), (8, 0x8000_0000), (12, 0x8000_0000), (12, 0), (4, 1), (16, 0)]
        {
            local.push(malformed_support::overwrite_u32(&data, offset, value, "GLB header"));
        }
        for (label, j) in json_edits(&json) {
            local.push(Mutant { label, bytes: pack_glb(&j, &bin) });
        }
        for (label, b) in bin_edits(&json, &bin) {
            local.push(Mutant { label, bytes: pack_glb(&json, &b) });
        }
        for m in &mut local {
            m.label = format!("{file}: {}", m.label);
        }
        mutants.extend(local);
    }
    let total = mutants.len();
    assert!(total >= 600, "only {total} mutants");
    let (accepted, rejected) = run_suite("glb", &mutants, import_gltf_slice, max_alloc, has_location);
    assert!(rejected > total / 2, "only {rejected} of {total} rejected ({accepted} accepted)");
}

#[test]
fn malformed_gltf_text_files_are_rejected_with_a_location_never_a_panic() {
    // Embedded buffers: the whole file is one JSON text.
    let data = std::fs::read(corpus("SimpleSkin/glTF-Embedded/SimpleSkin.gltf")).expect("read");
    let json: Value = serde_json::from_slice(&data).expect("json");
    let mut mutants = truncations(&data, 60);
    mutants.extend(byte_flips(&data, 80, 2, 0x1234));
    for (label, j) in json_edits(&json) {
        mutants.push(Mutant { label, bytes: serde_json::to_vec_pretty(&j).expect("json") });
    }
    let (_, rejected) = run_suite("gltf text", &mutants, import_gltf_slice, max_alloc, has_location);
    assert!(rejected > mutants.len() / 2);
    // A syntax error is reported by line and column.
    let e = import_gltf_slice(b"{\n  \"asset\": {\"version\": \"2.0\"},\n  \"nodes\": [ { ] \n}")
        .expect_err("bad JSON");
    assert!(matches!(e.location, Location::LineColumn { line: 3, .. }), "{e}");
}

#[test]
fn malformed_external_buffer_gltf_files_are_rejected_never_a_panic() {
    // Mutations of a .gltf with an external .bin, imported from a folder that holds the bin.
    let dir = tempfile::tempdir().expect("tempdir");
    let src = corpus("RiggedSimple/glTF");
    std::fs::copy(src.join("RiggedSimple0.bin"), dir.path().join("RiggedSimple0.bin")).expect("copy bin");
    let data = std::fs::read(src.join("RiggedSimple.gltf")).expect("read");
    let json: Value = serde_json::from_slice(&data).expect("json");
    let mut mutants = truncations(&data, 20);
    mutants.extend(byte_flips(&data, 20, 2, 0x4321));
    for (label, j) in json_edits(&json) {
        mutants.push(Mutant { label, bytes: serde_json::to_vec(&j).expect("json") });
    }
    let path = dir.path().join("model.gltf");
    let parse = |bytes: &[u8]| {
        std::fs::write(&path, bytes).map_err(|e| e.to_string())?;
        import_gltf_file(&path).map_err(|e| e.to_string())
    };
    let (_, rejected) = run_suite(
        "gltf external",
        &mutants,
        parse,
        |len| 8 * len + (1 << 20),
        |e: &String| e.contains(": ") && !e.ends_with(": "),
    );
    assert!(rejected > mutants.len() / 2);
}

#[test]
fn hostile_fields_get_specific_errors() {
    let data = std::fs::read(corpus("RiggedSimple/RiggedSimple.glb")).expect("read");
    let (json, bin) = split_glb(&data);
    let count = import_gltf_slice(&pack_glb(
        &set(&json, "/accessors/0/count", json!(2_147_483_648u64)).expect("p"),
        &bin,
    ))
    .expect_err("huge count");
    assert_eq!(count.location, Location::Pointer("/accessors/0".into()), "{count}");
    let child = json.pointer("/nodes/0/children/0").and_then(Value::as_u64).expect("child");
    let cyc = import_gltf_slice(&pack_glb(
        &set(&json, &format!("/nodes/{child}/children"), json!([0])).expect("p"),
        &bin,
    ))
    .expect_err("cycle");
    assert!(cyc.to_string().contains("cycle") || cyc.to_string().contains("parent"), "{cyc}");
    let short = import_gltf_slice(&data[..data.len() - 4]).expect_err("truncated");
    assert_eq!(short.location, Location::Byte(8), "{short}");
}

/// Valid but hostile files (issue 16): huge names, shared accessors, deep and wide node
/// trees and many skinned nodes import within the same memory bound as the malformed ones,
/// never a panic, and map onto a scene.
#[test]
fn hostile_valid_files_import_within_the_memory_bound() {
    let (json, bin) = split_glb(&std::fs::read(corpus("RiggedSimple/RiggedSimple.glb")).expect("read"));
    let mut cases: Vec<(String, Vec<u8>)> = Vec::new();
    for len in [65_505usize, 1 << 20] {
        let mut j = json.clone();
        let huge = "n".repeat(len);
        for pointer in ["/nodes/0/name", "/nodes/2/name", "/meshes/0/name", "/animations/0/name"] {
            if let Some(v) = set(&j, pointer, json!(huge)) {
                j = v;
            }
        }
        cases.push((format!("names of {len} characters"), pack_glb(&j, &bin)));
    }
    cases.push(("100 primitives sharing accessors".into(), big_gltf::shared_accessors(3_000, 100)));
    cases.push(("10,000 primitives sharing accessors".into(), big_gltf::shared_accessors(30, 10_000)));
    cases.push(("deep tree of 20,000 joints".into(), big_gltf::skeleton(20_000, big_gltf::Shape::Deep)));
    cases.push(("wide tree of 20,000 joints".into(), big_gltf::skeleton(20_000, big_gltf::Shape::Wide)));
    cases.push(("2,000 skinned mesh nodes".into(), big_gltf::many_skinned_nodes(2_000)));
    for (label, bytes) in cases {
        // The import is measured; the mapping onto a scene (one object per skinned node, each
        // with its own skeleton: output, not input) only has to work.
        let (result, peak) =
            malformed_support::measure_peak(|| std::panic::catch_unwind(|| import_gltf_slice(&bytes)));
        let model =
            result.unwrap_or_else(|_| panic!("{label}: panic")).unwrap_or_else(|e| panic!("{label}: {e}"));
        assert!(model.to_scene("x.glb", None).is_ok(), "{label}: mapping");
        eprintln!(
            "{label}: {} bytes, peak {peak} bytes ({:.1}×)",
            bytes.len(),
            peak as f64 / bytes.len() as f64
        );
        // A file that is almost all JSON (10,000 primitives of ~53 bytes of JSON each) costs
        // what gltf-json's parsed structures take, about 700 bytes a primitive (a BTreeMap of
        // attributes each): allowed twice the bound. Decoded data is shared either way.
        let bound =
            if label.starts_with("10,000") { 2 * max_alloc(bytes.len()) } else { max_alloc(bytes.len()) };
        assert!(peak <= bound, "{label}: peak {peak} bytes for a {}-byte file", bytes.len());
    }
}

/// Files that are not regular files are refused before a byte is read, with the file named.
#[test]
fn non_regular_files_are_refused_before_reading() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut paths = vec![(dir.path().to_path_buf(), "a folder")];
    #[cfg(unix)]
    {
        paths.push((PathBuf::from("/dev/zero"), "a character device"));
        let fifo = dir.path().join("pipe.glb");
        if std::process::Command::new("mkfifo").arg(&fifo).status().is_ok_and(|s| s.success()) {
            paths.push((fifo, "a FIFO"));
        }
    }
    for (path, what) in paths {
        let err = import_gltf_file(&path).expect_err("refused");
        assert!(err.to_string().contains(what), "{}: {err}", path.display());
        let err = keyrig_io::md2::load_md2_file(&path).expect_err("refused");
        assert!(err.to_string().contains(what), "{}: {err}", path.display());
        let err = keyrig_io::scene_file::load(&path).expect_err("refused");
        assert!(err.to_string().contains(what), "{}: {err}", path.display());
    }
}

/// Triangle strips and fans are imported as the triangles they stand for, each wound as the
/// strip or fan winds its first one (glTF 2.0 § 3.7.2.1).
#[test]
fn triangle_strips_and_fans_become_triangles_in_order() {
    let model = import_gltf_slice(&big_gltf::strip_and_fan()).expect("strip and fan");
    let indices = |mesh: usize| model.meshes[mesh].primitives[0].indices.to_vec();
    assert_eq!(indices(0), [0, 1, 2, 2, 1, 3, 2, 3, 4, 4, 3, 5], "strip");
    assert_eq!(indices(1), [0, 1, 2, 0, 2, 3, 0, 3, 4, 0, 4, 5], "fan");
}

/// The .glb container's own checks say where and what: a file shorter than its header, a
/// header without chunks, a second BIN chunk; paths with quoted keys become JSON pointers; a node's morph weights are
/// kept.
#[test]
fn glb_structure_and_node_fields_are_read_as_written() {
    let short = import_gltf_slice(b"glTF\x02\0\0\0").expect_err("8 bytes");
    assert_eq!(short.location, Location::Byte(0), "{short}");
    assert!(short.to_string().contains("shorter than the 12-byte header"), "{short}");
    // A header and nothing else is long enough: what it lacks is its JSON chunk.
    let bare = import_gltf_slice(b"glTF\x02\0\0\0\x0c\0\0\0").expect_err("12 bytes");
    assert_eq!(bare.location, Location::Byte(12), "{bare}");
    assert!(bare.to_string().contains("no JSON chunk"), "{bare}");

    let data = std::fs::read(corpus("AnimatedMorphCube/AnimatedMorphCube.glb")).expect("read");
    let (json, bin) = split_glb(&data);
    let mut twice = pack_glb(&json, &bin);
    let second = twice.len();
    twice.extend_from_slice(&4u32.to_le_bytes());
    twice.extend_from_slice(&0x004E_4942u32.to_le_bytes());
    twice.extend_from_slice(&[0; 4]);
    let total = twice.len() as u32;
    twice[8..12].copy_from_slice(&total.to_le_bytes());
    let err = import_gltf_slice(&twice).expect_err("two BIN chunks");
    assert_eq!(err.location, Location::Byte(second + 4), "{err}");
    assert!(err.to_string().contains("BIN chunk must follow the JSON chunk, once"), "{err}");
    // A second JSON chunk, after the BIN chunk.
    let mut two_json = pack_glb(&json, &bin);
    let second = two_json.len();
    two_json.extend_from_slice(&4u32.to_le_bytes());
    two_json.extend_from_slice(b"JSON");
    two_json.extend_from_slice(b"{}  ");
    let total = two_json.len() as u32;
    two_json[8..12].copy_from_slice(&total.to_le_bytes());
    let err = import_gltf_slice(&two_json).expect_err("two JSON chunks");
    assert_eq!(err.location, Location::Byte(second + 4), "{err}");
    assert!(err.to_string().contains("JSON must be the first and only JSON chunk"), "{err}");

    let targets =
        json.pointer("/meshes/0/primitives/0/targets").and_then(Value::as_array).expect("targets").len();
    let weights: Vec<f64> = (0..targets).map(|i| 0.25 * (i + 1) as f64).collect();
    let node = json["nodes"]
        .as_array()
        .expect("nodes")
        .iter()
        .position(|n| n.get("mesh").is_some())
        .expect("mesh node");
    let with_weights = set(&json, &format!("/nodes/{node}"), {
        let mut n = json["nodes"][node].clone();
        n["weights"] = json!(weights);
        n
    })
    .expect("node");
    let model = import_gltf_slice(&pack_glb(&with_weights, &bin)).expect("node weights are fine");
    let expected: Vec<f32> = weights.iter().map(|&w| w as f32).collect();
    assert_eq!(model.nodes[node].weights.as_deref(), Some(&expected[..]));

    assert_eq!(
        keyrig_io::gltf_import::json_pointer_from_path(r#"meshes[0].extras["a.b/c~d"].x"#),
        "/meshes/0/extras/a.b~1c~0d/x"
    );
}
