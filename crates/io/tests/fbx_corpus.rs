//! FBX import checked against the authoring tools themselves: each corpus FBX file with OBJ
//! frames (`NAME_FRAME.obj`, exported by 3ds Max, Maya or Blender from the same scene at that
//! frame: tests/corpus/SOURCES.md, "fbx/ufbx") is imported, mapped onto a keyrig scene
//! (`ImportedModel::to_scene`), evaluated at the frame's time by keyrig-eval and deformed by
//! keyrig-skin with the file's skinning method; the positions must lie within 1e-3 of the
//! model's size (its bounding-box diagonal) of the OBJ's.
//!
//! The OBJ is in the FBX file's own units and axes; the import is in keyrig's (metres, +Y up).
//! The OBJ's positions are mapped by the import's `keyrig_from_file` (the conversion ufbx
//! applied), so the comparison is in keyrig's space and checks that conversion too.
//!
//! Matching: the OBJ writers reorder and split vertices (3ds Max's Max2Obj writes faces in
//! another order), so each OBJ position is matched to the nearest deformed keyrig vertex and
//! each keyrig vertex to the nearest OBJ position; the figure is the larger of the two largest
//! distances (a symmetric Hausdorff distance between the two vertex sets).

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use glam::{Mat4, Vec3};
use keyrig_io::fbx::{import_fbx, import_fbx_file, import_fbx_slice, is_fbx_path, FbxErrorKind, FbxImport};
use keyrig_skin::{deform_mesh, BlendZone, JointPalette};

fn corpus(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/fbx/ufbx").join(name)
}

/// (FBX file, OBJ file, frame).
const FRAMES: [(&str, &str, f64); 12] = [
    ("max7_skin_5000_binary.fbx", "max7_skin_5.obj", 5.0),
    ("max7_skin_5000_binary.fbx", "max7_skin_15.obj", 15.0),
    ("maya_transformed_skin_7700_binary.fbx", "maya_transformed_skin_0.obj", 0.0),
    ("maya_transformed_skin_7700_binary.fbx", "maya_transformed_skin_4.obj", 4.0),
    ("maya_transformed_skin_7700_binary.fbx", "maya_transformed_skin_8.obj", 8.0),
    ("maya_instanced_skin_7700_ascii.fbx", "maya_instanced_skin_0.obj", 0.0),
    ("maya_instanced_skin_7700_ascii.fbx", "maya_instanced_skin_4.obj", 4.0),
    ("maya_instanced_skin_7700_ascii.fbx", "maya_instanced_skin_8.obj", 8.0),
    ("blender_293_half_skinned_7400_binary.fbx", "blender_293_half_skinned.obj", 0.0),
    ("max2009_cube_anim_6100_binary.fbx", "max2009_cube_anim_15.obj", 15.0),
    ("max2009_cube_anim_6100_binary.fbx", "max2009_cube_anim_45.obj", 45.0),
    ("maya_anim_layers_over_acc_orders_7500_binary.fbx", "maya_anim_layers_over_acc_orders_18.obj", 18.0),
];

/// An OBJ's vertex positions (`v` lines) and its `# ufbx:` flags (ufbx's notes on how the tool
/// wrote the file).
struct Obj {
    positions: Vec<Vec3>,
    flags: Vec<String>,
}

fn read_obj(path: &Path) -> Obj {
    let text = std::fs::read_to_string(path).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
    let mut positions = Vec::new();
    let mut flags = Vec::new();
    for line in text.lines() {
        let line = line.trim();
        if let Some(flag) = line.strip_prefix("# ufbx:") {
            flags.push(flag.trim().to_owned());
        } else if let Some(rest) = line.strip_prefix("v ") {
            let xyz: Vec<f32> =
                rest.split_whitespace().take(3).map(|x| x.parse().expect("OBJ coordinate")).collect();
            assert_eq!(xyz.len(), 3, "{}: {line}", path.display());
            positions.push(Vec3::new(xyz[0], xyz[1], xyz[2]));
        }
    }
    Obj { positions, flags }
}

/// The deformed positions of every mesh object of the model's scene at `time` of its first
/// animation, in model (world) space, as keyrig shows them: the scene evaluator's pose and
/// object transform, keyrig-skin's deformer of the object's kind (the file's skinning method);
/// by object name.
///
/// `transform_skin`: Maya shows (and exports) a skinned mesh moved by its node's current world
/// transform relative to the node's bind pose (the bind pose of another instance of the mesh
/// where the node has none); the FBX SDK, ufbx and keyrig, like glTF, skin in world space and
/// leave the skinned mesh node's transform out. ufbx's test runner applies that move to its own
/// result before comparing with such OBJ files (`# ufbx:transform_skin`); so does this test.
fn keyrig_positions(import: &FbxImport, time: f64, transform_skin: bool) -> Vec<(String, Vec<Vec3>)> {
    let model = &import.model;
    let animation = (!model.animations.is_empty()).then_some(0);
    let scene = model.to_scene("model.fbx", animation).expect("scene");
    let eval = keyrig_eval::SceneEvaluator::new(&scene, &HashMap::new());
    let world = model.world_matrices(&model.pose_at(animation, time));
    let mut out = Vec::new();
    for (o, object) in scene.objects.iter().enumerate() {
        let node = model.nodes.iter().position(|n| n.name == object.name).expect("node of object");
        let mesh_index = model.nodes[node].mesh.expect("mesh");
        let state = eval.object_at(o, time, &keyrig_eval::Overrides::new()).expect("state");
        let world_from_object = Mat4::from(state.world_from_object);
        let positions: Vec<Vec3> = if model.nodes[node].skin.is_some() {
            let mesh = model.skinned_mesh(node).expect("skinned mesh");
            let pose = state.pose.expect("pose");
            let palette = JointPalette::new(&mesh.skeleton, &pose).expect("palette");
            let bindings = mesh.bindings(BlendZone::new(0.25, 0.25).expect("zone")).expect("bindings");
            let deformed = deform_mesh(&mesh, &bindings, &palette, object.deformer.kind).expect("deform");
            let bind = import.bind_world[node].or_else(|| {
                (0..model.nodes.len())
                    .filter(|&n| model.nodes[n].mesh == Some(mesh_index))
                    .find_map(|n| import.bind_world[n])
            });
            let fix = match (transform_skin, bind) {
                (true, Some(bind)) => world[node] * bind.inverse(),
                _ => Mat4::IDENTITY,
            };
            deformed.positions.iter().map(|p| (fix * world_from_object).transform_point3(*p)).collect()
        } else {
            let mesh = model.rigid_mesh(mesh_index).expect("rigid mesh");
            mesh.positions.iter().map(|p| world_from_object.transform_point3(*p)).collect()
        };
        out.push((object.name.clone(), positions));
    }
    out
}

fn nearest(p: Vec3, set: &[Vec3]) -> f32 {
    set.iter().map(|q| p.distance(*q)).fold(f32::INFINITY, f32::min)
}

/// Symmetric Hausdorff distance between two point sets.
fn distance(a: &[Vec3], b: &[Vec3]) -> f32 {
    let ab = a.iter().map(|p| nearest(*p, b)).fold(0.0, f32::max);
    let ba = b.iter().map(|p| nearest(*p, a)).fold(0.0, f32::max);
    ab.max(ba)
}

/// Maya's layered file: ufbx blends an additive and an override layer over Euler rotations of
/// six rotation orders; for the orders below its result differs from Maya's by more than the
/// bar (keyrig's import equals ufbx's own evaluation: `layered_file_follows_ufbx_evaluation`).
/// Measured at frame 18: ZXY 2.0e-3, YXZ, YZX and ZYX 9.0e-2 of the size; XYZ and XZY 2.4e-6.
const UFBX_LAYER_DIFFERENCES: [&str; 4] = ["ZXY", "YXZ", "YZX", "ZYX"];

#[test]
fn corpus_frames_match_the_authoring_tools_obj() {
    let mut report = Vec::new();
    let mut failures = Vec::new();
    for (fbx, obj, frame) in FRAMES {
        let import = import_fbx(&corpus(fbx)).unwrap_or_else(|e| panic!("{e}"));
        let obj_file = read_obj(&corpus(obj));
        let expected: Vec<Vec3> =
            obj_file.positions.iter().map(|p| import.keyrig_from_file.transform_point3(*p)).collect();
        let time = frame / import.frames_per_second;
        let transform_skin = obj_file.flags.iter().any(|f| f == "transform_skin");
        let objects = keyrig_positions(&import, time, transform_skin);
        let (lo, hi) = expected.iter().fold((Vec3::MAX, Vec3::MIN), |(l, h), p| (l.min(*p), h.max(*p)));
        let size = (hi - lo).length();
        assert!(size > 0.0 && !objects.is_empty(), "{fbx}");
        let layered = fbx.starts_with("maya_anim_layers");
        // Every object's vertices lie on the OBJ's; with the OBJ's vertices all matched by the
        // objects together.
        let mut all = Vec::new();
        let mut worst = 0.0f32;
        for (name, positions) in &objects {
            let error = positions.iter().map(|p| nearest(*p, &expected)).fold(0.0, f32::max) / size;
            let known = layered && UFBX_LAYER_DIFFERENCES.contains(&name.as_str());
            report.push(format!(
                "  {name}: {error:.2e}{}",
                if known { " (ufbx's layer blending)" } else { "" }
            ));
            if known {
                assert!(error < 0.1, "{fbx} {name}: {error}");
            } else {
                worst = worst.max(error);
                all.extend_from_slice(positions);
                if error.is_nan() || error > 1e-3 {
                    failures.push(format!("{fbx} frame {frame} object {name}: {error:.2e} of the size"));
                }
            }
        }
        let covered = expected.iter().map(|p| nearest(*p, &all)).fold(0.0, f32::max) / size;
        // The layered file's OBJ also holds the objects left out above: there, the objects'
        // own figures.
        let pooled = if layered { worst } else { distance(&all, &expected) / size };
        let plain = if transform_skin {
            let plain: Vec<Vec3> =
                keyrig_positions(&import, time, false).into_iter().flat_map(|x| x.1).collect();
            format!(", without Maya's bind-relative move {:.2e}", distance(&plain, &expected) / size)
        } else {
            String::new()
        };
        report.insert(
            report.len() - objects.len(),
            format!(
                "{fbx} frame {frame} ({obj}): {} OBJ / {} keyrig vertices, size {size:.4} m, max error {pooled:.2e} of the size{plain}",
                expected.len(),
                all.len()
            ),
        );
        if !layered && (covered.is_nan() || covered > 1e-3) {
            failures.push(format!(
                "{fbx} frame {frame}: an OBJ vertex is {covered:.2e} of the size from keyrig's"
            ));
        }
    }
    for line in &report {
        eprintln!("{line}");
    }
    assert!(failures.is_empty(), "over 1e-3 of the size:\n{}", failures.join("\n"));
}

/// keyrig's import of the layered file equals ufbx's own evaluation of it (every node's local
/// rotation and translation at the OBJ's frame and between frames): the differences from Maya
/// above are ufbx's, not the mapping's.
#[test]
fn layered_file_follows_ufbx_evaluation() {
    let path = corpus("maya_anim_layers_over_acc_orders_7500_binary.fbx");
    let import = import_fbx(&path).expect("import");
    let model = &import.model;
    let opts = ufbx::LoadOpts {
        target_axes: ufbx::CoordinateAxes {
            right: ufbx::CoordinateAxis::PositiveX,
            up: ufbx::CoordinateAxis::PositiveY,
            front: ufbx::CoordinateAxis::PositiveZ,
        },
        target_unit_meters: 1.0,
        space_conversion: ufbx::SpaceConversion::ModifyGeometry,
        ..Default::default()
    };
    let scene = ufbx::load_file(path.to_str().expect("path"), opts).expect("ufbx");
    assert_eq!(scene.anim_layers.len(), 3, "base, additive and override layers");
    for frame in [18.0, 6.0] {
        let time = frame / import.frames_per_second;
        let pose = model.pose_at(Some(0), time);
        for node in scene.nodes.iter().filter(|n| !n.is_root) {
            let t = ufbx::evaluate_transform(&scene.anim, node, time);
            let name: &str = &node.element.name;
            let i = model.nodes.iter().position(|n| n.name == name).expect("node");
            let q = glam::Quat::from_xyzw(
                t.rotation.x as f32,
                t.rotation.y as f32,
                t.rotation.z as f32,
                t.rotation.w as f32,
            );
            assert!(q.dot(pose.rotation[i]).abs() > 1.0 - 1e-6, "{name} frame {frame}");
            let v = Vec3::new(t.translation.x as f32, t.translation.y as f32, t.translation.z as f32);
            assert!(v.distance(pose.translation[i]) < 1e-6, "{name} frame {frame}");
        }
    }
}

#[test]
fn every_animation_stack_is_an_animation_with_its_name() {
    let import = import_fbx(&corpus("maya_anim_layers_over_acc_orders_7500_binary.fbx")).expect("import");
    let names: Vec<&str> = import.model.animations.iter().map(|a| a.name.as_str()).collect();
    assert!(!names.is_empty());
    assert!(names.iter().all(|n| !n.is_empty()), "{names:?}");
    assert!(import.model.animations.iter().all(|a| !a.channels.is_empty()), "{names:?}");
    for file in ["max2009_cube_anim_6100_binary.fbx", "max7_skin_5000_binary.fbx"] {
        let model = import_fbx_file(&corpus(file)).expect("import");
        assert!(!model.animations.is_empty(), "{file}");
        assert!(model.animations[0].duration() > 0.0, "{file}");
    }
}

#[test]
fn textured_skinned_character_reads_skin_uvs_and_texture() {
    let model = import_fbx_file(&corpus("blender_293_barbarian_7400_binary.fbx")).expect("import");
    assert!(!model.skins.is_empty());
    let node = model.nodes.iter().position(|n| n.skin.is_some() && n.mesh.is_some()).expect("skinned node");
    let mesh = model.skinned_mesh(node).expect("skinned mesh");
    assert!(mesh.positions.iter().all(|p| p.is_finite()));
    let m = model.nodes[node].mesh.expect("mesh");
    let prim = &model.meshes[m].primitives[0];
    assert!(prim.texcoords.is_some());
    let texture = prim.base_colour_texture.as_ref().expect("base colour texture");
    let data = model.image_data[texture.image].as_ref().expect("texture bytes read next to the file");
    assert_eq!(data.mime_type, "image/png");
    let material = model.material(m).expect("material").expect("triangles");
    assert!(material.base_colour_texture.is_some());
    // Units: Blender writes centimetres-scaled metres; the character is human-sized.
    let (lo, hi) = prim.positions.iter().fold((Vec3::MAX, Vec3::MIN), |(l, h), p| (l.min(*p), h.max(*p)));
    assert!(hi.is_finite() && lo.is_finite());
}

#[test]
fn skins_map_onto_keyrig_with_the_files_method() {
    for file in ["max7_skin_5000_binary.fbx", "maya_transformed_skin_7700_binary.fbx"] {
        let model = import_fbx_file(&corpus(file)).expect("import");
        let skin = &model.skins[0];
        assert_eq!(skin.joints.len(), skin.inverse_bind_matrices.len(), "{file}");
        assert_eq!(skin.deformer, Some(keyrig_core::DeformerKind::LinearBlend), "{file}");
        let scene = model.to_scene("model.fbx", Some(0)).expect("scene");
        assert!(scene.objects.iter().any(|o| o.skeleton.is_some()), "{file}");
        // The scene saves and loads again (the loader checks every track).
        let text = keyrig_io::scene_file::to_string(&scene).unwrap_or_else(|e| panic!("{file}: {e}"));
        keyrig_io::scene_file::from_str(&text, Path::new("model.ron"))
            .unwrap_or_else(|e| panic!("{file}: the mapped scene does not load again: {e}"));
    }
}

#[test]
fn fbx_paths_are_recognised_by_extension() {
    assert!(is_fbx_path(Path::new("a/b.fbx")));
    assert!(is_fbx_path(Path::new("B.FBX")));
    assert!(!is_fbx_path(Path::new("b.glb")));
    assert!(!is_fbx_path(Path::new("fbx")));
}

#[test]
fn files_ufbx_refuses_give_typed_errors() {
    // Not FBX at all.
    let e = import_fbx_slice(b"this is not an FBX file").expect_err("garbage");
    assert!(matches!(e.kind, FbxErrorKind::Ufbx { .. }), "{e}");
    // Empty.
    let e = import_fbx_slice(b"").expect_err("empty");
    assert!(matches!(e.kind, FbxErrorKind::Ufbx { .. }), "{e}");
    // Cut off in the middle.
    let bytes = std::fs::read(corpus("max7_skin_5000_binary.fbx")).expect("read");
    let e = import_fbx_slice(&bytes[..bytes.len() / 3]).expect_err("truncated");
    assert!(matches!(e.kind, FbxErrorKind::Ufbx { .. }), "{e}");
    assert!(e.to_string().contains("ufbx"), "{e}");
    // A missing file names itself.
    let missing = corpus("no_such_file.fbx");
    let e = import_fbx_file(&missing).expect_err("missing");
    assert!(matches!(e.kind, FbxErrorKind::Io(_)));
    assert!(e.to_string().contains("no_such_file.fbx"), "{e}");
}

#[test]
fn every_corpus_file_imports_from_memory_as_from_its_file() {
    for entry in std::fs::read_dir(corpus("")).expect("corpus") {
        let path = entry.expect("entry").path();
        if !is_fbx_path(&path) {
            continue;
        }
        let from_file = import_fbx_file(&path).unwrap_or_else(|e| panic!("{e}"));
        let bytes = std::fs::read(&path).expect("read");
        let from_memory = import_fbx_slice(&bytes).unwrap_or_else(|e| panic!("{}: {e}", path.display()));
        assert_eq!(from_file.nodes, from_memory.model.nodes, "{}", path.display());
        assert_eq!(from_file.animations, from_memory.model.animations, "{}", path.display());
        assert!(!from_file.meshes.is_empty(), "{}", path.display());
    }
}

/// glTF export reads an object's `.fbx` model file through the FBX importer (its model loader
/// dispatches on the extension), and the written glTF holds the skin and the animation; the
/// export, imported again, deforms as the FBX does.
#[test]
fn a_scene_of_an_fbx_model_exports_to_gltf() {
    let path = corpus("max7_skin_5000_binary.fbx");
    let import = import_fbx(&path).expect("import");
    let model = &import.model;
    let scene = model.to_scene(path.to_str().expect("path"), Some(0)).expect("scene");
    let options = keyrig_io::gltf_export::ExportOptions::default();
    let exported = keyrig_io::gltf_export::export_scene(&scene, &options).unwrap_or_else(|e| panic!("{e}"));
    let back = keyrig_io::gltf_import::import_gltf_slice(&exported.to_glb()).expect("re-import");
    assert_eq!(back.skins.len(), 1);
    assert!(!back.animations.is_empty());
    let node = back.nodes.iter().position(|n| n.skin.is_some()).expect("skinned node");
    let original = model.nodes.iter().position(|n| n.skin.is_some()).expect("skinned node");
    let (lo, hi) = model.meshes[0].primitives[0]
        .positions
        .iter()
        .fold((Vec3::MAX, Vec3::MIN), |(l, h), p| (l.min(*p), h.max(*p)));
    let size = (hi - lo).length();
    for frame in [0.0, 5.0, 15.0] {
        let t = frame / import.frames_per_second;
        let a: Vec<Vec3> =
            model.deformed_positions(original, Some(0), t).expect("fbx").into_iter().flatten().collect();
        let b: Vec<Vec3> =
            back.deformed_positions(node, Some(0), t).expect("glTF").into_iter().flatten().collect();
        assert!(distance(&a, &b) / size < 1e-3, "t {t}: {}", distance(&a, &b) / size);
    }
}

#[test]
fn model_files_dispatch_on_their_extension() {
    let fbx = keyrig_io::fbx::import_model_file(&corpus("max2009_cube_anim_6100_binary.fbx")).expect("fbx");
    assert_eq!(fbx, import_fbx_file(&corpus("max2009_cube_anim_6100_binary.fbx")).expect("fbx"));
    let gltf =
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf/SimpleSkin/glTF/SimpleSkin.gltf");
    let model = keyrig_io::fbx::import_model_file(&gltf).expect("glTF");
    assert_eq!(model.skins.len(), 1);
    let e = keyrig_io::fbx::import_model_file(&corpus("missing.fbx")).expect_err("missing");
    assert!(matches!(e, keyrig_io::fbx::ModelImportError::Fbx(_)), "{e}");
    let e = keyrig_io::fbx::import_model_file(&corpus("missing.glb")).expect_err("missing");
    assert!(matches!(e, keyrig_io::fbx::ModelImportError::Gltf(_)), "{e}");
}
