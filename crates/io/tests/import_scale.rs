//! Import scales linearly and memory stays bounded: generated files with 100,000 nodes (a
//! wide and a deep skeleton with a channel on every joint, and 100,000 skinned mesh nodes)
//! import in seconds, and primitives that share an accessor share its decoded values.

#[path = "support/big_gltf.rs"]
mod big_gltf;
#[path = "malformed_support/mod.rs"]
mod malformed_support;

use std::time::Instant;

use big_gltf::Shape;
use keyrig_io::gltf_import::import_gltf_slice;
use malformed_support::{measure_peak, CountingAlloc};

#[global_allocator]
static ALLOC: CountingAlloc = CountingAlloc;

/// Runs `f`, printing how long it took (shown with `--nocapture`). Nothing is asserted about
/// the time: these tests check that files this large import correctly (a quadratic step would
/// make them run for minutes); `cargo bench -p keyrig-io --bench import_scale` measures the speed.
fn timed<R>(what: &str, f: impl FnOnce() -> R) -> R {
    let start = Instant::now();
    let r = f();
    eprintln!("{what}: {:.2?}", start.elapsed());
    r
}

#[test]
fn a_hundred_thousand_node_skeletons_import_in_seconds() {
    for shape in [Shape::Wide, Shape::Deep] {
        let bytes = big_gltf::skeleton(100_000, shape);
        let model = timed(&format!("{shape:?} 100k import"), || import_gltf_slice(&bytes).expect("import"));
        assert_eq!(model.nodes.len(), 100_001);
        assert_eq!(model.animations[0].channels.len(), 100_000);
        // The reference pose and world matrices (used by deform, render, export) are linear too.
        let world = timed(&format!("{shape:?} 100k world matrices"), || {
            model.world_matrices(&model.pose_at(Some(0), 0.5))
        });
        assert_eq!(world.len(), 100_001);
        // Mapping the skin onto a keyrig skeleton walks each joint up to the first node already
        // taken: linear for a chain 100,000 deep too.
        let mapped = timed(&format!("{shape:?} 100k to_scene"), || model.to_scene("big.glb", Some(0)));
        let Ok(scene) = mapped else { panic!("{shape:?}: the skeleton does not map onto a scene") };
        let joints = scene.objects.iter().find_map(|o| o.skeleton.as_ref()).map(|s| s.joints.len());
        assert_eq!(joints, Some(100_000), "{shape:?}");
    }
}

#[test]
fn a_hundred_thousand_skinned_mesh_nodes_import_in_seconds() {
    let bytes = big_gltf::many_skinned_nodes(100_000);
    let model = timed("100k skinned nodes import", || import_gltf_slice(&bytes).expect("import"));
    assert_eq!(model.nodes.len(), 100_003);
}

#[test]
fn import_time_grows_linearly() {
    // Doubling the node count must not come near quadrupling the time (quadratic growth).
    let time = |n: usize| {
        let bytes = big_gltf::skeleton(n, Shape::Wide);
        let start = Instant::now();
        import_gltf_slice(&bytes).expect("import");
        start.elapsed().as_secs_f64()
    };
    let _warm = time(5_000);
    let (small, large) = (time(20_000), time(80_000));
    eprintln!("20k: {small:.3} s, 80k: {large:.3} s, ratio {:.1} (linear: 4, quadratic: 16)", large / small);
    assert!(large / small < 9.0, "20k nodes {small:.3} s, 80k {large:.3} s");
}

#[test]
fn shared_accessors_are_decoded_once() {
    let (vertices, primitives) = (30_000, 100);
    let bytes = big_gltf::shared_accessors(vertices, primitives);
    let (model, peak) = measure_peak(|| import_gltf_slice(&bytes).expect("import"));
    let prims = &model.meshes[0].primitives;
    assert_eq!(prims.len(), primitives);
    assert!(prims.iter().all(|p| std::sync::Arc::ptr_eq(&p.positions, &prims[0].positions)));
    assert!(prims.iter().all(|p| std::sync::Arc::ptr_eq(&p.indices, &prims[0].indices)));
    // Decoded once: positions, normals (12 bytes a vertex each) and indices (4 a vertex).
    let decoded = vertices * (12 + 12 + 4);
    eprintln!("file {} bytes, decoded {decoded} bytes, peak {peak} bytes", bytes.len());
    assert!(peak < 4 * decoded + (1 << 20), "peak {peak} bytes for {decoded} bytes of decoded data");
}

/// The mapping onto a scene of 100,000 skinned mesh nodes sharing one skin: one skeleton is
/// built per skin and the animation's channels are indexed by node once, so this is linear.
#[test]
fn a_hundred_thousand_skinned_mesh_nodes_map_onto_a_scene_in_seconds() {
    let bytes = big_gltf::many_skinned_nodes(100_000);
    let model = import_gltf_slice(&bytes).expect("import");
    let scene = timed("100k skinned nodes to_scene", || model.to_scene("many.glb", None).expect("scene"));
    assert_eq!(scene.objects.len(), 100_000);
}

/// A bare chain of 500,000 nodes, root first: the importer's cycle check walks each node up
/// to the first node it has already finished, so this is linear too (walking to the root from
/// every node would take 10¹¹ steps).
#[test]
fn a_chain_half_a_million_nodes_deep_imports() {
    let bytes = big_gltf::chain(500_000);
    let model = timed("500k chain import", || import_gltf_slice(&bytes).expect("import"));
    assert_eq!(model.nodes.len(), 500_000);
    assert_eq!(model.nodes[0].parent, None);
    assert!(model.nodes.iter().enumerate().skip(1).all(|(k, n)| n.parent == Some(k - 1)));
    let world = timed("500k chain world matrices", || model.world_matrices(&model.pose_at(None, 0.0)));
    assert_eq!(world.len(), 500_000);
}

/// Issue 29: a file that reuses one accessor in many meshes (100,000 meshes and nodes,
/// 13.2 MB, almost all JSON) imports within 10 times the file's size at the peak (9.05 ×
/// measured): every mesh shares the decoded accessor, meshes written identically share one
/// primitive list, and the meshes' JSON (most of the gltf crate's parsed document, which alone
/// takes 8.4 × this file) is let go before the nodes are read (docs/benchmarks.md, "Import
/// memory").
#[test]
fn one_accessor_reused_by_many_meshes_imports_within_ten_times_the_file() {
    let bytes = big_gltf::reused_accessor_meshes(100_000);
    let (model, peak) = measure_peak(|| import_gltf_slice(&bytes).expect("import"));
    assert_eq!(model.meshes.len(), 100_000);
    assert_eq!(model.nodes.len(), 100_000);
    let first = &model.meshes[0].primitives[0].positions;
    assert!(model.meshes.iter().all(|m| std::sync::Arc::ptr_eq(&m.primitives[0].positions, first)));
    assert!(model.meshes.iter().all(|m| std::sync::Arc::ptr_eq(&m.primitives, &model.meshes[0].primitives)));
    assert!(model.nodes.iter().enumerate().all(|(i, n)| n.mesh == Some(i)), "each node keeps its mesh");
    eprintln!(
        "file {} bytes, import peak {peak} bytes ({:.1} × the file)",
        bytes.len(),
        peak as f64 / bytes.len() as f64
    );
    assert!(peak <= 10 * bytes.len(), "import peak {peak} bytes for a {} byte file", bytes.len());
}

/// Meshes share a primitive list only when the file writes their primitives identically; each
/// keeps its own name and weights, and a different material, accessor or mode is read apart.
#[test]
fn only_identically_written_primitives_are_shared() {
    use serde_json::json;
    let mut bin = big_gltf::Bin::default();
    let pos = bin.add(
        &big_gltf::f32_bytes([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
        5126,
        3,
        "VEC3",
        Some((json!([0.0, 0.0, 0.0]), json!([1.0, 1.0, 0.0]))),
    );
    let other = bin.add(
        &big_gltf::f32_bytes([0.0, 0.0, 0.0, 2.0, 0.0, 0.0, 0.0, 2.0, 0.0]),
        5126,
        3,
        "VEC3",
        Some((json!([0.0, 0.0, 0.0]), json!([2.0, 2.0, 0.0]))),
    );
    let prim = |p: usize| json!({"attributes": {"POSITION": p}});
    let meshes = json!([
        {"name": "a", "primitives": [prim(pos)]},
        {"name": "b", "primitives": [prim(pos)]},
        {"name": "c", "primitives": [{"attributes": {"POSITION": pos}, "material": 0}]},
        {"name": "d", "primitives": [prim(other)]},
        {"name": "e", "primitives": [{"attributes": {"POSITION": pos}, "mode": 0}]},
    ]);
    let root = json!({
        "asset": {"version": "2.0"},
        "nodes": (0..5).map(|i| json!({"mesh": i})).collect::<Vec<_>>(),
        "meshes": meshes,
        "materials": [{"pbrMetallicRoughness": {"baseColorFactor": [1.0, 0.0, 0.0, 1.0]}}],
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    let model = import_gltf_slice(&big_gltf::glb(root, bin.bytes)).expect("import");
    let m = &model.meshes;
    let names: Vec<&str> = m.iter().map(|m| m.name.as_str()).collect();
    assert_eq!(names, ["a", "b", "c", "d", "e"]);
    assert!(std::sync::Arc::ptr_eq(&m[0].primitives, &m[1].primitives));
    for k in 2..5 {
        assert!(!std::sync::Arc::ptr_eq(&m[0].primitives, &m[k].primitives), "mesh {k}");
    }
    assert_eq!(m[2].primitives[0].material, Some(0));
    assert_eq!(m[0].primitives[0].material, None);
    assert_eq!(m[3].primitives[0].positions[1], glam::Vec3::new(2.0, 0.0, 0.0));
    assert_eq!(m[4].primitives[0].mode, keyrig_io::model::PrimitiveMode::Points);
    assert!(model.nodes.iter().enumerate().all(|(i, n)| n.mesh == Some(i)));
}
