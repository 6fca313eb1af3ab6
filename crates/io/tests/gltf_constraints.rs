//! glTF export bakes object constraints (docs/constraints.md, "Baking and export"): a prop
//! passed from one hand to the other (child of, switched without a pop) and an object aiming
//! at it re-import at every frame where the scene evaluator puts them, in the keyed and the
//! Blender (`--bake`) modes.

use std::collections::HashMap;

use glam::{Quat, Vec3};
use keyrig_core::{
    AimAxis, AimTarget, Animated, ChildOfParent, ConstraintKind, Interpolation, Key, Object, ObjectConstraint,
    RawTrack, Scene,
};
use keyrig_eval::{switch_parent, Overrides, SceneEvaluator};
use keyrig_io::gltf_export::{export_scene, BakeOptions, ExportOptions};
use keyrig_io::gltf_import::import_gltf_slice;

fn linear<T>(keys: Vec<(f64, T)>) -> RawTrack<T> {
    RawTrack::new(keys.into_iter().map(|(t, v)| Key::new(t, v).with_interpolation(Interpolation::Linear)).collect())
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
    for options in [ExportOptions::default(), ExportOptions { bake: Some(BakeOptions::default()), ..ExportOptions::default() }]
    {
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
