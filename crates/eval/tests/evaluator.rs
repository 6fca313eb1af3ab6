//! The scene evaluator against the pieces it is made of: keyrig-core's tracks for every
//! channel, keyrig-skin's pose sampler and joint palette for skeletons, the morph clips for
//! vertex animation; overrides win; invalid data is listed with its path and still evaluates.

use std::collections::HashMap;
use std::f32::consts::FRAC_PI_2;
use std::sync::Arc;

use glam::{Affine3A, Quat, Vec3};
use keyrig_core::channel_id::{ChannelId, ChannelValue};
use keyrig_core::{
    Animated, AnimatedTrack, Interpolation, Key, Light, LightKind, MeshSource, Object, ProceduralMesh,
    RawTrack, Scene,
};
use keyrig_eval::morph::{MorphClip, MorphClips};
use keyrig_eval::{LoadedMesh, Overrides, SceneEvaluator};
use keyrig_skin::{JointPalette, Pose, RestSkeleton};

/// An arm with keyed elbow rotation, forearm translation and wrist scale; a moving cube
/// without a skeleton; a light whose intensity is keyed.
fn scene() -> Scene {
    let mut scene = Scene::default();
    let mut arm = Object::new("Arm");
    arm.mesh = Some(MeshSource::Procedural(ProceduralMesh::ArmLowPoly));
    let mut skeleton = keyrig_skin::scene_skeleton_for(ProceduralMesh::ArmLowPoly).expect("arm");
    skeleton.joints[1].rotation.track = RawTrack::new(vec![
        Key::new(0.0, Quat::IDENTITY),
        Key::new(1.0, Quat::from_rotation_z(FRAC_PI_2)),
        Key::new(2.0, Quat::from_rotation_x(1.0)),
    ]);
    skeleton.joints[2].translation.track =
        RawTrack::new(vec![Key::new(0.0, Vec3::ZERO), Key::new(2.0, Vec3::new(0.0, 5.0, 0.0))]);
    skeleton.joints[3].scale.track = RawTrack::new(vec![
        Key::new(0.0, Vec3::ONE).with_interpolation(Interpolation::Linear),
        Key::new(2.0, Vec3::splat(2.0)),
    ]);
    arm.skeleton = Some(skeleton);
    arm.translation.track = RawTrack::new(vec![Key::new(0.0, Vec3::ZERO), Key::new(2.0, Vec3::X)]);
    scene.objects.push(arm);
    let mut cube = Object::new("Cube");
    cube.mesh = Some(MeshSource::Procedural(ProceduralMesh::Cube));
    cube.rotation.track =
        RawTrack::new(vec![Key::new(0.0, Quat::IDENTITY), Key::new(1.0, Quat::from_rotation_y(1.0))]);
    scene.objects.push(cube);
    scene.lights.push(Light {
        name: "Key".into(),
        kind: LightKind::Point,
        enabled: true,
        position: Animated::constant(Vec3::Y),
        direction: Animated::constant(Vec3::NEG_Y),
        colour: Animated::constant(Vec3::ONE),
        intensity: Animated::new(1.0, RawTrack::new(vec![Key::new(0.0, 1.0), Key::new(1.0, 3.0)])),
        attributes: Default::default(),
    });
    scene
}

#[test]
fn the_scene_at_a_time_is_what_its_tracks_and_skeletons_say() {
    let scene = scene();
    let eval = SceneEvaluator::new(&scene, &HashMap::new());
    assert!(eval.problems().is_empty(), "{:?}", eval.problems());
    let skeleton = scene.objects[0].skeleton.as_ref().unwrap();
    // The pose straight from keyrig-core's tracks, joint by joint.
    let sample = |t: f64| {
        let track3 = |a: &keyrig_core::Animated<Vec3>| AnimatedTrack::new(a).unwrap().sample(t);
        Pose {
            local_translations: skeleton.joints.iter().map(|j| track3(&j.translation)).collect(),
            local_rotations: skeleton
                .joints
                .iter()
                .map(|j| AnimatedTrack::new(&j.rotation).unwrap().sample(t))
                .collect(),
            local_scales: skeleton.joints.iter().map(|j| track3(&j.scale)).collect(),
            root_translation: track3(&skeleton.root_translation),
        }
    };
    let skin = eval.skin(0).expect("the arm is skinned");
    for t in [-1.0, 0.0, 0.3, 1.0, 1.7, 2.0, 5.0] {
        let state = eval.evaluate(t, &Overrides::new());
        assert_eq!(state.objects.len(), 2);
        let arm = &state.objects[0];
        let expected_pose = sample(t);
        let pose = arm.pose.as_ref().expect("pose");
        assert_eq!(pose.local_translations, expected_pose.local_translations, "t = {t}");
        assert_eq!(pose.local_scales, expected_pose.local_scales, "t = {t}");
        // The evaluator hands out unit quaternions (the tracks round to f32 first).
        for (q, e) in pose.local_rotations.iter().zip(&expected_pose.local_rotations) {
            assert!(q.abs_diff_eq(*e, 1e-6) && (q.length() - 1.0).abs() < 1e-6, "t = {t}: {q} vs {e}");
        }
        let expected = JointPalette::new(&skin.mesh.skeleton, &expected_pose).unwrap();
        let palette = arm.palette.as_ref().expect("palette");
        for (m, e) in palette.skinning.iter().zip(&expected.skinning) {
            assert!(m.abs_diff_eq(*e, 1e-5), "t = {t}");
        }
        let translation = AnimatedTrack::new(&scene.objects[0].translation).unwrap().sample(t);
        assert!(arm.world_from_object.abs_diff_eq(Affine3A::from_translation(translation), 1e-6));
        // The cube: no skeleton, its rest palette, its rotation track.
        let cube = &state.objects[1];
        assert!(cube.pose.is_none());
        assert!(cube.palette.is_some(), "a skinned mesh without a skeleton gets its rest palette");
        let q = AnimatedTrack::new(&scene.objects[1].rotation).unwrap().sample(t).normalize();
        assert!(cube.world_from_object.abs_diff_eq(Affine3A::from_quat(q), 1e-6));
        let light = state.lights[0];
        let intensity = AnimatedTrack::new(&scene.lights[0].intensity).unwrap().sample(t);
        assert_eq!(light.intensity, intensity);
        assert_eq!(light.position, Vec3::Y);
        // Single channels agree with the whole evaluation.
        let id = ChannelId::JointRotation { object: 0, joint: 1 };
        assert_eq!(
            eval.value(id, t, &Overrides::new()),
            Some(ChannelValue::Rotation(expected_pose.local_rotations[1]))
        );
    }
    // Full joint poses: the forearm moves up, the wrist scales.
    let end = eval.evaluate(2.0, &Overrides::new());
    let pose = end.objects[0].pose.as_ref().unwrap();
    assert_eq!(pose.local_translations[2], Vec3::new(0.0, 5.0, 0.0));
    assert_eq!(pose.local_scales[3], Vec3::splat(2.0));
    assert_eq!(eval.value(ChannelId::JointScale { object: 9, joint: 0 }, 0.0, &Overrides::new()), None);
}

#[test]
fn overrides_take_part_in_the_same_evaluation() {
    let scene = scene();
    let eval = SceneEvaluator::new(&scene, &HashMap::new());
    let id = ChannelId::JointRotation { object: 0, joint: 0 };
    let turn = Quat::from_rotation_y(0.7);
    let overrides: Overrides =
        [(id, ChannelValue::Rotation(turn)), (ChannelId::LightIntensity(0), ChannelValue::Scalar(9.0))]
            .into();
    let state = eval.evaluate(0.5, &overrides);
    let arm = &state.objects[0];
    assert_eq!(arm.pose.as_ref().unwrap().local_rotations[0], turn);
    // F(0) carries the override, and so does every joint below it.
    let (_, rotation, _) = arm.palette.as_ref().unwrap().model_from_joint[0].to_scale_rotation_translation();
    assert!(rotation.abs_diff_eq(turn, 1e-6));
    assert_eq!(state.lights[0].intensity, 9.0);
    assert_eq!(eval.value(id, 0.5, &overrides), Some(ChannelValue::Rotation(turn)));
    // A zero quaternion as an override is not a rotation: the identity is shown instead.
    let zero: Overrides = [(id, ChannelValue::Rotation(Quat::from_xyzw(0.0, 0.0, 0.0, 0.0)))].into();
    let state = eval.evaluate(0.5, &zero);
    assert_eq!(state.objects[0].pose.as_ref().unwrap().local_rotations[0], Quat::IDENTITY);
}

#[test]
fn invalid_data_is_listed_with_its_path_and_still_evaluates() {
    let mut scene = scene();
    let elbow = &mut scene.objects[0].skeleton.as_mut().unwrap().joints[1].rotation;
    elbow.value = Quat::from_rotation_z(0.25);
    elbow.track.keys[2].time = 0.5; // out of order
    scene.lights[0].intensity.track.keys[1].value = f32::NAN;
    let eval = SceneEvaluator::new(&scene, &HashMap::new());
    let paths: Vec<&str> = eval.problems().iter().map(|p| p.path.as_str()).collect();
    assert!(paths.contains(&"objects[0].skeleton.joints[1].rotation.track[2].time"), "{paths:?}");
    assert!(paths.contains(&"lights[0].intensity.track[1].value"), "{paths:?}");
    // The invalid channels hold their static values; the rest still animates.
    let state = eval.evaluate(1.0, &Overrides::new());
    let pose = state.objects[0].pose.as_ref().unwrap();
    assert_eq!(pose.local_rotations[1], Quat::from_rotation_z(0.25));
    assert_eq!(state.lights[0].intensity, 1.0);
    assert!(state.objects[0].palette.is_some());
    assert_eq!(
        eval.problems()[0].to_string(),
        format!("{}: {}", eval.problems()[0].path, eval.problems()[0].message)
    );
}

#[test]
fn loaded_meshes_skin_and_morph() {
    let mut scene = Scene::default();
    let mut model = Object::new("Model");
    model.mesh = Some(MeshSource::File {
        path: "m.md2".into(),
        mesh: None,
        clip: Some("run".into()),
        fps: Some(10.0),
    });
    scene.objects.push(model);
    let mut character = Object::new("Character");
    character.mesh = Some(MeshSource::file("c.glb", Some(0)));
    character.skeleton = keyrig_skin::scene_skeleton_for(ProceduralMesh::ArmLowPoly);
    scene.objects.push(character);
    let clips = MorphClips::new(12, vec![MorphClip { name: "run".into(), frames: 4..8 }]).unwrap();
    let arm_rest = RestSkeleton::from_scene(scene.objects[1].skeleton.as_ref().unwrap()).unwrap();
    let arm_mesh = keyrig_skin::mesh_for(ProceduralMesh::ArmLowPoly).fit_to_skeleton(arm_rest).unwrap();
    let meshes: HashMap<usize, LoadedMesh> =
        [(0, LoadedMesh::Morph(Arc::new(clips))), (1, LoadedMesh::Skinned(Arc::new(arm_mesh)))].into();
    let eval = SceneEvaluator::new(&scene, &meshes);
    assert!(eval.problems().is_empty(), "{:?}", eval.problems());
    let state = eval.evaluate(0.25, &Overrides::new());
    let blend = state.objects[0].morph.clone().expect("morph").expect("blend");
    assert_eq!((blend.frame_a, blend.frame_b), (6, 7));
    assert!(eval.skin(1).is_some() && state.objects[1].palette.is_some());

    // A clip the model does not have, and a skinned mesh bound to another skeleton.
    scene.objects[0].mesh =
        Some(MeshSource::File { path: "m.md2".into(), mesh: None, clip: Some("fly".into()), fps: None });
    scene.objects[1].skeleton.as_mut().unwrap().joints.pop();
    let eval = SceneEvaluator::new(&scene, &meshes);
    let problems: Vec<String> = eval.problems().iter().map(ToString::to_string).collect();
    assert!(
        problems.iter().any(|p| p.starts_with("objects[0].mesh.clip: no clip named `fly`")),
        "{problems:?}"
    );
    assert!(
        problems.iter().any(|p| p.starts_with("objects[1].skeleton: 3 joints, but the mesh")),
        "{problems:?}"
    );
    assert!(eval.skin(1).is_none() && eval.morph(0).is_none());
}

/// An edit rebuilds only what it changed: the channel whose keys it touched (the others still
/// share their keys with the evaluator's copies), the mesh and bindings only when the mesh,
/// the skeleton's rest pose or the deformer settings change; the result equals an evaluator
/// built from scratch.
#[test]
fn updates_rebuild_only_what_an_edit_changed() {
    let mut scene = scene();
    let mut eval = SceneEvaluator::new(&scene, &HashMap::new());
    let same = |eval: &SceneEvaluator, scene: &Scene| {
        let fresh = SceneEvaluator::new(scene, &HashMap::new());
        for t in [0.0, 0.4, 1.3, 2.0] {
            let (a, b) = (eval.evaluate(t, &Overrides::new()), fresh.evaluate(t, &Overrides::new()));
            for (x, y) in a.objects.iter().zip(&b.objects) {
                assert_eq!(x.world_from_object, y.world_from_object);
                assert_eq!(x.pose, y.pose);
                assert_eq!(x.palette, y.palette);
            }
            assert_eq!(a.lights, b.lights);
        }
        assert_eq!(eval.problems(), fresh.problems());
    };
    // Nothing changed: nothing rebuilt.
    assert_eq!(eval.update(&scene, &HashMap::new()), keyrig_eval::Rebuilt::default());
    // One key of one joint: one channel.
    let before = scene.clone();
    scene.objects[0].skeleton.as_mut().unwrap().joints[1].rotation.track.keys[1].value =
        Quat::from_rotation_y(1.0);
    assert!(before.objects[0].skeleton.as_ref().unwrap().joints[2]
        .translation
        .track
        .keys
        .shares_with(&scene.objects[0].skeleton.as_ref().unwrap().joints[2].translation.track.keys));
    let skin_before = std::sync::Arc::clone(&eval.skin(0).unwrap().mesh);
    assert_eq!(eval.update(&scene, &HashMap::new()), keyrig_eval::Rebuilt { channels: 1, meshes: 0 });
    assert!(std::sync::Arc::ptr_eq(&skin_before, &eval.skin(0).unwrap().mesh), "the mesh is kept");
    same(&eval, &scene);
    // A static value and a light's keys.
    scene.objects[1].translation.value = Vec3::Z;
    scene.lights[0].intensity.track.keys.push(Key::new(2.0, 0.5));
    assert_eq!(eval.update(&scene, &HashMap::new()), keyrig_eval::Rebuilt { channels: 2, meshes: 0 });
    same(&eval, &scene);
    // A channel's cycle alone (its keys untouched) is a change too.
    scene.objects[1].rotation.after = keyrig_core::Cycle::Repeat;
    assert_eq!(eval.update(&scene, &HashMap::new()), keyrig_eval::Rebuilt { channels: 1, meshes: 0 });
    same(&eval, &scene);
    // Deformer settings rebuild the object's bindings (and its channels).
    scene.objects[0].deformer.blend_child_fraction = 0.5;
    let rebuilt = eval.update(&scene, &HashMap::new());
    assert_eq!(rebuilt.meshes, 1);
    assert!(!std::sync::Arc::ptr_eq(&skin_before, &eval.skin(0).unwrap().mesh));
    same(&eval, &scene);
    // An invalid edit becomes a problem, and its undo removes it.
    let valid = scene.clone();
    scene.objects[1].rotation.track.keys[1].time = f64::NAN;
    assert_eq!(eval.update(&scene, &HashMap::new()).channels, 1);
    assert_eq!(eval.problems().len(), 1);
    same(&eval, &scene);
    assert_eq!(eval.update(&valid, &HashMap::new()).channels, 1);
    assert!(eval.problems().is_empty());
    // Objects and lights removed and added.
    scene = valid.clone();
    scene.objects.pop();
    scene.lights.clear();
    eval.update(&scene, &HashMap::new());
    same(&eval, &scene);
    let rebuilt = eval.update(&valid, &HashMap::new());
    assert_eq!(rebuilt.meshes, 1);
    same(&eval, &valid);
}

/// `evaluate_into` over a state that held other times, a failed pose and a larger scene gives
/// exactly what a fresh `evaluate` gives (compared through `Debug`, which prints every float so
/// that it reads back to the same bits).
#[test]
fn evaluating_into_a_reused_state_equals_a_fresh_evaluation() {
    let scene = scene();
    let eval = SceneEvaluator::new(&scene, &HashMap::new());
    let none = Overrides::new();
    let elbow = ChannelId::JointRotation { object: 0, joint: 1 };
    // A zero quaternion cannot be normalized: the evaluator turns it into the identity, so the
    // pose stays valid; a non-finite translation makes the palette fail.
    let broken: Overrides =
        [(ChannelId::JointTranslation { object: 0, joint: 2 }, ChannelValue::Vec3(Vec3::NAN))].into();
    let turned: Overrides = [(elbow, ChannelValue::Rotation(Quat::from_rotation_y(0.5)))].into();
    // Poison: a state of a larger scene (three objects, two lights) at another time.
    let mut bigger = scene.clone();
    bigger.objects.push(scene.objects[1].clone());
    bigger.lights.push(scene.lights[0].clone());
    let mut state = SceneEvaluator::new(&bigger, &HashMap::new()).evaluate(7.5, &none);
    assert_eq!(state.objects.len(), 3);
    for (time, overrides) in
        [(0.25, &none), (1.5, &broken), (1.5, &none), (0.75, &turned), (2.0, &none), (0.0, &broken)]
    {
        eval.evaluate_into(time, overrides, &mut state);
        let fresh = eval.evaluate(time, overrides);
        assert_eq!(format!("{state:?}"), format!("{fresh:?}"), "t = {time}, overrides {overrides:?}");
        assert_eq!((state.objects.len(), state.lights.len()), (2, 1));
    }
    eval.evaluate_into(1.5, &broken, &mut state);
    assert!(state.objects[0].palette.is_none() && state.objects[0].palette_error.is_some());
}

/// Euler keys (issue 30): a joint keyed (0, 0, 0) → (40, 270, 0) in XYZ, Linear, evaluates
/// halfway to the hand-written Ry(135°)·Rx(20°) (each angle interpolated on its own; slerp
/// between the keys would turn −45° about Y), its `JointEuler` channel reads the angles, an
/// override of either channel wins, and switching the keys' order (a new rotation mode) or
/// back to quaternion keys is an update that equals a fresh evaluator.
#[test]
fn euler_keys_interpolate_each_angle_and_turn_in_their_order() {
    let mut scene = scene();
    let joint = &mut scene.objects[0].skeleton.as_mut().unwrap().joints[1];
    joint.rotation = Animated::constant(Quat::IDENTITY);
    joint.rotation_euler = Some(Animated::new(
        Vec3::ZERO,
        RawTrack::new(vec![
            Key::new(0.0, Vec3::ZERO).with_interpolation(Interpolation::Linear),
            Key::new(1.0, Vec3::new(40.0, 270.0, 0.0)),
        ]),
    ));
    let (rotation, euler) =
        (ChannelId::JointRotation { object: 0, joint: 1 }, ChannelId::JointEuler { object: 0, joint: 1 });
    let mut eval = SceneEvaluator::new(&scene, &HashMap::new());
    let none = Overrides::new();
    let hand = |axis: usize, degrees: f32| {
        let (s, c) = degrees.to_radians().sin_cos();
        match axis {
            0 => glam::Mat3::from_cols(Vec3::X, Vec3::new(0.0, c, s), Vec3::new(0.0, -s, c)),
            _ => glam::Mat3::from_cols(Vec3::new(c, 0.0, -s), Vec3::Y, Vec3::new(s, 0.0, c)),
        }
    };
    let close = |a: glam::Mat3, b: glam::Mat3| {
        (a - b).to_cols_array().iter().fold(0.0f32, |m, d| m.max(d.abs())) < 1e-5
    };
    let Some(ChannelValue::Rotation(q)) = eval.value(rotation, 0.5, &none) else { panic!("a rotation") };
    assert!(close(glam::Mat3::from_quat(q), hand(1, 135.0) * hand(0, 20.0)), "{q}");
    assert_eq!(eval.value(euler, 0.5, &none), Some(ChannelValue::Vec3(Vec3::new(20.0, 135.0, 0.0))));
    let pose = eval.object_at(0, 0.5, &none).and_then(|s| s.pose).expect("a pose");
    assert!(pose.local_rotations[1].dot(q).abs() > 1.0 - 1e-6, "the skeleton turns the same");
    // Angles typed in the inspector (an override of the Euler channel) turn the joint; a
    // gizmo's rotation override reads back as the angles nearest the keyed ones.
    let mut typed = Overrides::new();
    typed.insert(euler, ChannelValue::Vec3(Vec3::new(0.0, 400.0, 0.0)));
    let Some(ChannelValue::Rotation(t)) = eval.value(rotation, 0.5, &typed) else { panic!() };
    assert!(t.dot(Quat::from_rotation_y(400f32.to_radians())).abs() > 1.0 - 1e-6);
    let mut posed = Overrides::new();
    posed.insert(rotation, ChannelValue::Rotation(Quat::from_rotation_y(140f32.to_radians())));
    let Some(ChannelValue::Vec3(e)) = eval.value(euler, 0.5, &posed) else { panic!() };
    assert!((e - Vec3::new(0.0, 140.0, 0.0)).abs().max_element() < 1e-3, "{e}");
    // A joint with quaternion keys has no Euler channel.
    assert_eq!(eval.value(ChannelId::JointEuler { object: 0, joint: 2 }, 0.5, &none), None);
    // Another order and back to quaternion keys: updates equal fresh evaluators.
    for (mode, euler_keys) in [
        (keyrig_core::RotationMode::Euler(keyrig_core::EulerOrder::ZXY), true),
        (keyrig_core::RotationMode::Quaternion, false),
    ] {
        assert!(keyrig_core::channel_id::set_rotation_keys(&mut scene, rotation, mode, euler_keys).unwrap());
        assert!(eval.update(&scene, &HashMap::new()).channels >= 1);
        let fresh = SceneEvaluator::new(&scene, &HashMap::new());
        for t in [0.0, 1.0] {
            let (Some(ChannelValue::Rotation(a)), Some(ChannelValue::Rotation(b))) =
                (eval.value(rotation, t, &none), fresh.value(rotation, t, &none))
            else {
                panic!()
            };
            assert_eq!(a, b);
            // The keys are the same rotations whatever their form.
            let want = if t == 0.0 {
                Quat::IDENTITY
            } else {
                Quat::from_rotation_y(270f32.to_radians()) * Quat::from_rotation_x(40f32.to_radians())
            };
            assert!(a.dot(want).abs() > 1.0 - 1e-5, "{mode:?} t {t}: {a} vs {want}");
        }
    }
    assert!(scene.objects[0].skeleton.as_ref().unwrap().joints[1].rotation_euler.is_none());
    assert!(eval.problems().is_empty());
}
