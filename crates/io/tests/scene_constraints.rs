//! glTF export bakes object constraints (docs/constraints.md, "Baking and export"): a prop
//! passed from one hand to the other (child of, switched without a pop) and an object aiming
//! at it re-import at every frame where the scene evaluator puts them, in the keyed and the
//! Blender (`--bake`) modes.

use std::collections::HashMap;

use glam::{Quat, Vec3};
use keyrig_core::{
    AimAxis, AimTarget, Animated, ChildOfParent, ConstraintKind, Interpolation, Key, Object,
    ObjectConstraint, RawTrack, Scene,
};
use keyrig_eval::{switch_parent, Overrides, SceneEvaluator};
use keyrig_io::gltf_export::{export_scene, BakeOptions, ExportOptions};
use keyrig_io::gltf_import::import_gltf_slice;

fn linear<T>(keys: Vec<(f64, T)>) -> RawTrack<T> {
    RawTrack::new(
        keys.into_iter().map(|(t, v)| Key::new(t, v).with_interpolation(Interpolation::Linear)).collect(),
    )
}

fn scene() -> Scene {
    let mut l = Object::new("HandL");
    l.translation.track = linear(vec![(0.0, Vec3::new(0.0, 1.0, 0.0)), (2.0, Vec3::new(2.0, 1.0, 2.0))]);
    l.rotation.track = linear(vec![(0.0, Quat::IDENTITY), (2.0, Quat::from_rotation_y(1.2))]);
    let mut r = Object::new("HandR");
    r.translation.track = linear(vec![(0.0, Vec3::new(4.0, 1.0, 0.0)), (2.0, Vec3::new(4.0, 3.0, 0.0))]);
    let mut prop = Object::new("Prop");
    prop.translation = Animated::constant(Vec3::new(0.0, -0.2, 0.1));
    prop.constraints.push(ObjectConstraint::new(
        "Held",
        ConstraintKind::ChildOf {
            parents: vec![ChildOfParent::new(AimTarget::Object("HandL".into()))],
            parent: Animated::constant(0.0),
        },
    ));
    let mut looker = Object::new("Looker");
    looker.translation = Animated::constant(Vec3::new(1.0, 0.0, 3.0));
    looker.constraints.push(ObjectConstraint::new(
        "Watch",
        ConstraintKind::AimAt { target: AimTarget::Object("Prop".into()), axis: AimAxis::NegZ, up: Vec3::Y },
    ));
    let mut scene = Scene { objects: vec![looker, prop, l, r], ..Scene::default() };
    switch_parent(&mut scene, 1, 0, 1.0, AimTarget::Object("HandR".into())).expect("switches");
    scene
}

#[test]
fn constrained_objects_export_where_the_evaluator_puts_them() {
    let scene = scene();
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    let eval = SceneEvaluator::new(&scene, &HashMap::new());
    for options in [
        ExportOptions::default(),
        ExportOptions { bake: Some(BakeOptions::default()), ..ExportOptions::default() },
    ] {
        let exported = export_scene(&scene, &options).expect("export");
        let model = import_gltf_slice(&exported.to_glb()).expect("re-import");
        for (o, name) in [(0, "Looker"), (1, "Prop")] {
            let node = model.nodes.iter().position(|n| n.name == name).expect("node");
            for frame in scene.frame_range.start..=scene.frame_range.end {
                let t = f64::from(frame) / scene.fps;
                let want = eval.object_at(o, t, &Overrides::new()).expect("object").world_from_object;
                let (_, want_r, want_t) = want.to_scale_rotation_translation();
                let pose = model.pose_at(Some(0), t);
                let bake = options.bake.is_some();
                assert!(
                    pose.translation[node].abs_diff_eq(want_t, 1e-3),
                    "{name} at frame {frame} (bake {bake}): {} vs {want_t}",
                    pose.translation[node]
                );
                let angle = pose.rotation[node].angle_between(want_r);
                assert!(angle < 2e-3, "{name} at frame {frame} (bake {bake}): {angle} rad off");
            }
        }
    }
}

/// The `constraints` example of docs/scene-format.md ("ObjectConstraint").
fn documented_constraints() -> String {
    let doc = std::fs::read_to_string(
        std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scene-format.md"),
    )
    .expect("read docs/scene-format.md");
    let section = doc.find("#### ObjectConstraint").expect("the section");
    let start = section + doc[section..].find("```ron\n").expect("a ```ron block") + "```ron\n".len();
    let len = doc[start..].find("```").expect("closing fence");
    doc[start..start + len].to_string()
}

#[test]
fn the_documented_constraints_load_and_save_in_version_4() {
    let object = |name: &str, extra: &str| {
        format!(
            "(name: {name:?}, translation: (value: (0.0, 0.0, 0.0)), rotation: (value: (0.0, 0.0, 0.0, 1.0)), \
             scale: (value: (1.0, 1.0, 1.0)), {extra})"
        )
    };
    let arm = "skeleton: Some((joints: [(name: \"wrist\", parent: None, rest_translation: (0.0, 1.0, 0.0), \
               rest_rotation: (0.0, 0.0, 0.0, 1.0), rotation: (value: (0.0, 0.0, 0.0, 1.0)))], \
               root_translation: (value: (0.0, 0.0, 0.0))))";
    let text = format!(
        "(version: 4, scene: (fps: 30.0, frame_range: (start: 0, end: 60), objects: [{}, {}, {}, {}]))",
        object("HandL", ""),
        object("HandR", ""),
        object("Arm", arm),
        object("Prop", &documented_constraints()),
    );
    let path = std::path::Path::new("constraints.ron");
    let scene = keyrig_io::scene_file::from_str(&text, path).expect("the documented constraints load");
    let prop = &scene.objects[3];
    assert_eq!(prop.constraints.len(), 2);
    let ConstraintKind::ChildOf { parents, parent } = &prop.constraints[0].kind else { panic!("child of") };
    assert_eq!(parents.len(), 2);
    assert_eq!(parents[0].offset, glam::Mat4::IDENTITY);
    assert_eq!(parents[1].offset.w_axis, glam::Vec4::new(-4.0, 0.0, 0.0, 1.0));
    assert_eq!(parent.track.len(), 2);
    assert_eq!(
        prop.constraints[1].kind,
        ConstraintKind::AimAt {
            target: AimTarget::Joint { object: "Arm".into(), joint: "wrist".into() },
            axis: AimAxis::NegZ,
            up: Vec3::Y,
        }
    );
    let saved = keyrig_io::scene_file::to_string(&scene).expect("saves");
    assert!(saved.contains("version: 4"), "{saved}");
    assert_eq!(keyrig_io::scene_file::from_str(&saved, path).expect("reads back"), scene);
    // A scene without constraints writes no `constraints` field.
    let mut plain = scene.clone();
    plain.objects[3].constraints.clear();
    assert!(!keyrig_io::scene_file::to_string(&plain).expect("saves").contains("constraints"));
}

/// VRML export bakes them too: the interpolators (read without the scene metadata, as another
/// program would) put the prop and the looker where the evaluator does at every frame.
#[test]
fn vrml_export_bakes_constraints_into_its_interpolators() {
    use keyrig_io::vrml::export::{ExportFormat, VrmlExportOptions, METADATA_TAG};
    let mut scene = scene();
    for o in &mut scene.objects {
        o.mesh = Some(keyrig_core::MeshSource::Procedural(keyrig_core::ProceduralMesh::Cube));
    }
    let eval = SceneEvaluator::new(&scene, &HashMap::new());
    let text =
        keyrig_io::vrml::export::export_scene(&scene, ExportFormat::Vrml97, &VrmlExportOptions::default())
            .expect("export");
    // Without the metadata the importer reads the nodes and interpolators alone.
    let text = text.replace(METADATA_TAG, "note");
    let model = keyrig_io::vrml::import_vrml_slice(text.as_bytes(), "constraints.wrl").expect("import");
    let back = model.to_scene("constraints.wrl");
    let back_eval = SceneEvaluator::new(&back, &HashMap::new());
    for (o, name) in [(0, "Looker"), (1, "Prop")] {
        let b = back.objects.iter().position(|x| x.name == name).expect("the object comes back");
        assert!(back.objects[b].constraints.is_empty());
        for frame in scene.frame_range.start..=scene.frame_range.end {
            let t = f64::from(frame) / scene.fps;
            let want = eval.object_at(o, t, &Overrides::new()).expect("object").world_from_object;
            let got = back_eval.object_at(b, t, &Overrides::new()).expect("object").world_from_object;
            let (_, wr, wt) = want.to_scale_rotation_translation();
            let (_, gr, gt) = got.to_scale_rotation_translation();
            assert!(gt.abs_diff_eq(wt, 1e-2), "{name} at frame {frame}: {gt} vs {wt}");
            assert!(gr.angle_between(wr) < 1e-2, "{name} at frame {frame}: {} rad off", gr.angle_between(wr));
        }
    }
}
