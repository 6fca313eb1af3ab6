//! Generators of large, valid glTF files (as .glb bytes) for the scale tests and the import
//! benchmark: wide and deep skeletons with an animation channel on every joint, many skinned
//! mesh nodes, and primitives that share their accessors.

#![allow(dead_code)]

use serde_json::{json, Value};

/// The shape of a generated node hierarchy.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Shape {
    /// Every joint a child of the first (one level).
    Wide,
    /// Each joint the child of the one before (a chain `n` deep).
    Deep,
}

pub fn f32_bytes(values: impl IntoIterator<Item = f32>) -> Vec<u8> {
    values.into_iter().flat_map(f32::to_le_bytes).collect()
}

/// Builds the binary buffer, buffer views and accessors.
#[derive(Default)]
pub struct Bin {
    pub bytes: Vec<u8>,
    pub views: Vec<Value>,
    pub accessors: Vec<Value>,
}

impl Bin {
    pub fn add(
        &mut self,
        data: &[u8],
        component: u32,
        count: usize,
        type_: &str,
        minmax: Option<(Value, Value)>,
    ) -> usize {
        while !self.bytes.len().is_multiple_of(4) {
            self.bytes.push(0);
        }
        self.views.push(json!({"buffer": 0, "byteOffset": self.bytes.len(), "byteLength": data.len()}));
        self.bytes.extend_from_slice(data);
        let mut a = json!({"bufferView": self.views.len() - 1, "componentType": component, "count": count, "type": type_});
        if let Some((min, max)) = minmax {
            a["min"] = min;
            a["max"] = max;
        }
        self.accessors.push(a);
        self.accessors.len() - 1
    }
}

/// Packs a glTF JSON document and its buffer into a .glb.
pub fn glb(mut root: Value, bin: Vec<u8>) -> Vec<u8> {
    root["buffers"] = json!([{"byteLength": bin.len()}]);
    let mut j = serde_json::to_vec(&root).expect("json");
    while !j.len().is_multiple_of(4) {
        j.push(b' ');
    }
    let mut b = bin;
    while !b.len().is_multiple_of(4) {
        b.push(0);
    }
    let total = 12 + 8 + j.len() + 8 + b.len();
    let mut out = Vec::with_capacity(total);
    out.extend_from_slice(b"glTF");
    out.extend_from_slice(&2u32.to_le_bytes());
    out.extend_from_slice(&(total as u32).to_le_bytes());
    out.extend_from_slice(&(j.len() as u32).to_le_bytes());
    out.extend_from_slice(b"JSON");
    out.extend_from_slice(&j);
    out.extend_from_slice(&(b.len() as u32).to_le_bytes());
    out.extend_from_slice(b"BIN\0");
    out.extend_from_slice(&b);
    out
}

/// One triangle whose three vertices are bound to joints 0, 1 and 2 (of a skin with at least
/// three joints), with the accessors (position, joints, weights, indices) it needs.
pub fn triangle(bin: &mut Bin) -> Value {
    triangle_at(bin, 0.0)
}

/// [`triangle`] moved `x` along the x axis.
pub fn triangle_at(bin: &mut Bin, x: f32) -> Value {
    let pos = bin.add(
        &f32_bytes([x, 0.0, 0.0, x + 1.0, 0.0, 0.0, x, 1.0, 0.0]),
        5126,
        3,
        "VEC3",
        Some((json!([x, 0.0, 0.0]), json!([x + 1.0, 1.0, 0.0]))),
    );
    let joints: Vec<u8> =
        [0u16, 0, 0, 0, 1, 0, 0, 0, 2, 0, 0, 0].iter().flat_map(|j| j.to_le_bytes()).collect();
    let joints = bin.add(&joints, 5123, 3, "VEC4", None);
    let weights = bin.add(
        &f32_bytes([1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0]),
        5126,
        3,
        "VEC4",
        None,
    );
    let indices: Vec<u8> = [0u16, 1, 2, 0].iter().flat_map(|i| i.to_le_bytes()).collect();
    let indices = bin.add(&indices[..6], 5123, 3, "SCALAR", None);
    json!({"attributes": {"POSITION": pos, "JOINTS_0": joints, "WEIGHTS_0": weights}, "indices": indices})
}

/// A skeleton of `joints` joint nodes (≥ 3) in `shape`, one skinned triangle mesh on its own
/// root node, and one animation with a LINEAR rotation channel on every joint (all channels
/// share one input and one output accessor).
pub fn skeleton(joints: usize, shape: Shape) -> Vec<u8> {
    assert!(joints >= 3);
    let mut bin = Bin::default();
    let primitive = triangle(&mut bin);
    let ibm = bin.add(
        &f32_bytes((0..joints).flat_map(|j| {
            let y = match shape {
                Shape::Wide => 0.0,
                Shape::Deep => -(j as f32) * 0.01,
            };
            [1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 0.0, y, 0.0, 1.0]
        })),
        5126,
        joints,
        "MAT4",
        None,
    );
    let times = bin.add(&f32_bytes([0.0, 1.0]), 5126, 2, "SCALAR", Some((json!([0.0]), json!([1.0]))));
    let half = std::f32::consts::FRAC_1_SQRT_2 * 0.1;
    let rotations = bin.add(
        &f32_bytes([0.0, 0.0, 0.0, 1.0, half, 0.0, 0.0, (1.0 - half * half).sqrt()]),
        5126,
        2,
        "VEC4",
        None,
    );
    let mut nodes: Vec<Value> = (0..joints)
        .map(|j| json!({"name": format!("joint{j}"), "translation": [0.0, if j == 0 { 0.0 } else { 0.01 }, 0.0]}))
        .collect();
    match shape {
        Shape::Wide => nodes[0]["children"] = json!((1..joints).collect::<Vec<_>>()),
        Shape::Deep => {
            for (j, node) in nodes.iter_mut().enumerate().take(joints - 1) {
                node["children"] = json!([j + 1]);
            }
        }
    }
    nodes.push(json!({"name": "mesh", "mesh": 0, "skin": 0}));
    let channels: Vec<Value> =
        (0..joints).map(|j| json!({"sampler": 0, "target": {"node": j, "path": "rotation"}})).collect();
    let root = json!({
        "asset": {"version": "2.0", "generator": "keyrig big_gltf"},
        "scene": 0,
        "scenes": [{"nodes": [0, joints]}],
        "nodes": nodes,
        "meshes": [{"primitives": [primitive]}],
        "skins": [{"joints": (0..joints).collect::<Vec<_>>(), "inverseBindMatrices": ibm, "skeleton": 0}],
        "animations": [{"channels": channels, "samplers": [{"input": times, "output": rotations, "interpolation": "LINEAR"}]}],
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    glb(root, bin.bytes)
}

/// `count` root nodes that each show the same skinned mesh with the same three-joint skin.
pub fn many_skinned_nodes(count: usize) -> Vec<u8> {
    let mut bin = Bin::default();
    let primitive = triangle(&mut bin);
    let mut nodes: Vec<Value> =
        vec![json!({"name": "j0", "children": [1, 2]}), json!({"name": "j1"}), json!({"name": "j2"})];
    nodes.extend((0..count).map(|i| json!({"name": format!("instance{i}"), "mesh": 0, "skin": 0})));
    let roots: Vec<usize> = std::iter::once(0).chain(3..3 + count).collect();
    let root = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": roots}],
        "nodes": nodes,
        "meshes": [{"primitives": [primitive]}],
        "skins": [{"joints": [0, 1, 2]}],
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    glb(root, bin.bytes)
}

/// One mesh of `primitives` primitives that all use the same POSITION, NORMAL and index
/// accessors of `vertices` vertices (a valid file: glTF allows any sharing).
pub fn shared_accessors(vertices: usize, primitives: usize) -> Vec<u8> {
    let mut bin = Bin::default();
    let positions: Vec<f32> = (0..vertices).flat_map(|i| [i as f32 * 0.001, (i % 7) as f32, 0.0]).collect();
    let max = (vertices.max(1) - 1) as f32 * 0.001;
    let pos = bin.add(
        &f32_bytes(positions),
        5126,
        vertices,
        "VEC3",
        Some((json!([0.0, 0.0, 0.0]), json!([max, 6.0, 0.0]))),
    );
    let normal =
        bin.add(&f32_bytes((0..vertices).flat_map(|_| [0.0, 0.0, 1.0])), 5126, vertices, "VEC3", None);
    let tris = vertices / 3 * 3;
    let indices: Vec<u8> = (0..tris as u32).flat_map(u32::to_le_bytes).collect();
    let idx = bin.add(&indices, 5125, tris, "SCALAR", None);
    let prims: Vec<Value> = (0..primitives)
        .map(|_| json!({"attributes": {"POSITION": pos, "NORMAL": normal}, "indices": idx}))
        .collect();
    let root = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": [{"name": "shared", "mesh": 0}],
        "meshes": [{"primitives": prims}],
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    glb(root, bin.bytes)
}

/// Six vertices on a zig-zag, indexed 0..6 once as a triangle strip (mesh 0, on node 0) and
/// once as a triangle fan (mesh 1, on node 1).
pub fn strip_and_fan() -> Vec<u8> {
    let mut bin = Bin::default();
    let positions =
        [0.0, 0.0, 0.0, 0.0, 1.0, 0.0, 1.0, 0.0, 0.0, 1.0, 1.0, 0.0, 2.0, 0.0, 0.0, 2.0, 1.0, 0.0];
    let pos = bin.add(
        &f32_bytes(positions),
        5126,
        6,
        "VEC3",
        Some((json!([0.0, 0.0, 0.0]), json!([2.0, 1.0, 0.0]))),
    );
    let indices: Vec<u8> = (0u16..6).flat_map(u16::to_le_bytes).collect();
    let indices = bin.add(&indices, 5123, 6, "SCALAR", None);
    let mesh = |mode: u32| json!({"primitives": [{"attributes": {"POSITION": pos}, "indices": indices, "mode": mode}]});
    let root = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 1]}],
        "nodes": [{"name": "strip", "mesh": 0}, {"name": "fan", "mesh": 1}],
        "meshes": [mesh(5), mesh(6)],
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    glb(root, bin.bytes)
}

/// `count` nodes and nothing else, each the child of the one before (listed root first, so
/// every node's parent comes before it): a chain `count` deep.
pub fn chain(count: usize) -> Vec<u8> {
    let nodes: Vec<Value> =
        (0..count).map(|k| if k + 1 < count { json!({"children": [k + 1]}) } else { json!({}) }).collect();
    let root = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0]}],
        "nodes": nodes,
    });
    glb(root, Vec::new())
}

/// A three-joint chain and one skinned mesh of two primitives (a triangle at x = 0 and one at
/// x = 2), on the node `two`.
pub fn two_primitive_skin() -> Vec<u8> {
    let mut bin = Bin::default();
    let primitives = [triangle_at(&mut bin, 0.0), triangle_at(&mut bin, 2.0)];
    let root = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": [0, 3]}],
        "nodes": [
            {"name": "j0", "children": [1]},
            {"name": "j1", "children": [2]},
            {"name": "j2"},
            {"name": "two", "mesh": 0, "skin": 0},
        ],
        "meshes": [{"primitives": primitives}],
        "skins": [{"joints": [0, 1, 2]}],
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    glb(root, bin.bytes)
}

/// `meshes` meshes, each of one primitive using the same POSITION, NORMAL and index accessors
/// (one triangle), each shown by a node of its own: a file that reuses one accessor in many
/// meshes, whose size is almost all JSON.
pub fn reused_accessor_meshes(meshes: usize) -> Vec<u8> {
    let mut bin = Bin::default();
    let pos = bin.add(
        &f32_bytes([0.0, 0.0, 0.0, 1.0, 0.0, 0.0, 0.0, 1.0, 0.0]),
        5126,
        3,
        "VEC3",
        Some((json!([0.0, 0.0, 0.0]), json!([1.0, 1.0, 0.0]))),
    );
    let normal = bin.add(&f32_bytes([0.0, 0.0, 1.0, 0.0, 0.0, 1.0, 0.0, 0.0, 1.0]), 5126, 3, "VEC3", None);
    let indices: Vec<u8> = [0u16, 1, 2, 0].iter().flat_map(|i| i.to_le_bytes()).collect();
    let idx = bin.add(&indices[..6], 5123, 3, "SCALAR", None);
    let mesh_list: Vec<Value> = (0..meshes)
        .map(|_| json!({"primitives": [{"attributes": {"POSITION": pos, "NORMAL": normal}, "indices": idx}]}))
        .collect();
    let nodes: Vec<Value> =
        (0..meshes).map(|i| json!({"mesh": i, "translation": [i as f32 * 0.01, 0.0, 0.0]})).collect();
    let root = json!({
        "asset": {"version": "2.0"},
        "scene": 0,
        "scenes": [{"nodes": (0..meshes).collect::<Vec<_>>()}],
        "nodes": nodes,
        "meshes": mesh_list,
        "bufferViews": bin.views,
        "accessors": bin.accessors,
    });
    glb(root, bin.bytes)
}
