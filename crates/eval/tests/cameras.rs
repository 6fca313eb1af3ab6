//! Scene cameras in the evaluator: keyed translation, rotation (with every key option a
//! transform has) and lens through keyrig-core's tracks; an aim at an object, a joint or a
//! point checked against the look-at basis computed here; overrides win; missing targets are
//! listed and keep the keyed rotation.

use std::collections::HashMap;

use glam::{Quat, Vec3};
use keyrig_core::channel_id::{ChannelId, ChannelValue};
use keyrig_core::{
    Aim, AimTarget, AnimatedTrack, Interpolation, Key, Lens, MeshSource, Object, ProceduralMesh, Projection,
    RawTrack, Scene, SceneCamera, Spin, Tcb,
};
use keyrig_eval::{Overrides, SceneEvaluator};

fn scene() -> Scene {
    let mut scene = Scene::default();
    let mut arm = Object::new("Arm");
    arm.mesh = Some(MeshSource::Procedural(ProceduralMesh::ArmLowPoly));
    arm.skeleton = Some(keyrig_skin::scene_skeleton_for(ProceduralMesh::ArmLowPoly).expect("arm"));
    arm.translation.track =
        RawTrack::new(vec![Key::new(0.0, Vec3::ZERO), Key::new(2.0, Vec3::new(0.0, 0.0, -3.0))]);
    scene.objects.push(arm);
    let mut dolly = SceneCamera::new("Dolly", Vec3::new(0.0, 1.0, 8.0));
    dolly.translation.track = RawTrack::new(vec![
        Key::new(0.0, Vec3::new(0.0, 1.0, 8.0)).with_tcb(Tcb::new(0.5, 0.0, 0.0)),
        Key::new(1.0, Vec3::new(2.0, 1.0, 6.0)),
        Key::new(2.0, Vec3::new(4.0, 1.5, 5.0)),
    ]);
    dolly.rotation.track = RawTrack::new(vec![
        Key::new(0.0, Quat::IDENTITY).with_interpolation(Interpolation::Linear),
        Key::new(2.0, Quat::IDENTITY).with_spin(Spin::Angle { axis: Vec3::Y, degrees: 360.0 }),
    ]);
    dolly.projection = Projection::FocalLength { sensor_height_mm: 24.0 };
    dolly.lens.value = 35.0;
    dolly.lens.track = RawTrack::new(vec![
        Key::new(0.0, 35.0).with_interpolation(Interpolation::Linear),
        Key::new(2.0, 85.0),
    ]);
    scene.cameras.push(dolly);
    let mut track = SceneCamera::new("Track", Vec3::new(3.0, 2.0, 4.0));
    track.aim = Some(Aim::at(AimTarget::Joint { object: "Arm".into(), joint: "hand".into() }));
    scene.cameras.push(track);
    scene
}

fn joint_names(scene: &Scene) -> Vec<String> {
    scene.objects[0].skeleton.as_ref().unwrap().joints.iter().map(|j| j.name.clone()).collect()
}

#[test]
fn keyed_cameras_follow_their_tracks() {
    let mut scene = scene();
    let last = joint_names(&scene).pop().unwrap();
    if let Some(aim) = &mut scene.cameras[1].aim {
        aim.target = AimTarget::Joint { object: "Arm".into(), joint: last };
    }
    let eval = SceneEvaluator::new(&scene, &HashMap::new());
    assert_eq!(eval.problems(), []);
    let translation = AnimatedTrack::new(&scene.cameras[0].translation).unwrap();
    let rotation = AnimatedTrack::new(&scene.cameras[0].rotation).unwrap();
    for t in [0.0, 0.3, 1.0, 1.7, 2.0] {
        let state = eval.evaluate(t, &Overrides::new());
        let dolly = state.cameras[0];
        assert!(dolly.eye().abs_diff_eq(translation.sample(t), 1e-6), "{t}");
        let q = Quat::from_mat3a(&dolly.world_from_camera.matrix3);
        assert!(q.dot(rotation.sample(t).normalize()).abs() > 1.0 - 1e-6, "{t}");
        // Focal length keyed from 35 to 85 mm on a 24 mm sensor: fov = 2·atan(12 / f).
        let f = 35.0 + 50.0 * (t as f32 / 2.0);
        let Lens::Perspective { fov_y } = dolly.lens else { panic!("perspective") };
        assert!((fov_y - 2.0 * (12.0 / f).atan()).abs() < 1e-5, "{t}: {fov_y}");
        // The standalone query agrees with the whole-scene evaluation.
        assert_eq!(eval.camera_at(0, t, &Overrides::new()), Some(dolly));
        assert_eq!(eval.camera_at(1, t, &Overrides::new()), Some(state.cameras[1]));
    }
    // The spin key turns the camera a whole turn: halfway it faces the other way.
    let half = eval.camera_at(0, 1.0, &Overrides::new()).unwrap();
    assert!(half.forward().abs_diff_eq(Vec3::Z, 1e-5), "{}", half.forward());
}

#[test]
fn an_aimed_camera_looks_at_its_joint() {
    let mut scene = scene();
    let names = joint_names(&scene);
    let last = names.last().unwrap().clone();
    let j = names.len() - 1;
    scene.cameras[1].aim = Some(Aim {
        up: Vec3::Y,
        roll: keyrig_core::Animated::new(0.0, RawTrack::new(vec![Key::new(0.0, 0.0), Key::new(2.0, 90.0)])),
        target: AimTarget::Joint { object: "Arm".into(), joint: last },
        influence: keyrig_core::Animated::constant(1.0),
    });
    let eval = SceneEvaluator::new(&scene, &HashMap::new());
    for t in [0.0, 1.0, 2.0] {
        let state = eval.evaluate(t, &Overrides::new());
        let arm = &state.objects[0];
        let joint = arm
            .world_from_object
            .transform_point3a(arm.palette.as_ref().unwrap().model_from_joint[j].translation);
        let camera = state.cameras[1];
        let eye = Vec3::new(3.0, 2.0, 4.0);
        // Look-at by hand: forward to the joint, right = forward × up, up' = right × forward.
        let forward = (Vec3::from(joint) - eye).normalize();
        let right = forward.cross(Vec3::Y).normalize();
        let up = right.cross(forward);
        let roll = (45.0 * t as f32).to_radians();
        let rolled_up = up * roll.cos() - right * roll.sin();
        assert!(camera.forward().abs_diff_eq(forward, 1e-5), "{t}");
        assert!(camera.world_from_camera.transform_vector3(Vec3::Y).abs_diff_eq(rolled_up, 1e-5), "{t}");
    }
    // The roll channel and an override of it.
    assert_eq!(
        eval.value(ChannelId::CameraRoll(1), 2.0, &Overrides::new()),
        Some(ChannelValue::Scalar(90.0))
    );
    let overrides = Overrides::from([(ChannelId::CameraRoll(1), ChannelValue::Scalar(0.0))]);
    let still = eval.camera_at(1, 2.0, &overrides).unwrap();
    let unrolled = eval.camera_at(1, 0.0, &Overrides::new()).unwrap();
    let up = |c: keyrig_eval::CameraState| c.world_from_camera.transform_vector3(Vec3::Y);
    assert!(up(still).y > 0.9 * up(unrolled).y);
}

#[test]
fn overrides_edits_and_missing_targets() {
    let mut scene = scene();
    scene.cameras[1].aim = Some(Aim::at(AimTarget::Object("Ghost".into())));
    let mut eval = SceneEvaluator::new(&scene, &HashMap::new());
    assert_eq!(eval.problems().len(), 1);
    assert_eq!(eval.problems()[0].path, "cameras[1].aim.target");
    // Without its target, the camera keeps its keyed rotation (the identity).
    let c = eval.camera_at(1, 0.0, &Overrides::new()).unwrap();
    assert!(c.forward().abs_diff_eq(Vec3::NEG_Z, 1e-6));

    let overrides = Overrides::from([
        (ChannelId::CameraTranslation(0), ChannelValue::Vec3(Vec3::splat(9.0))),
        (ChannelId::CameraLens(0), ChannelValue::Scalar(24.0)),
    ]);
    let c = eval.camera_at(0, 0.5, &overrides).unwrap();
    assert_eq!(c.eye(), Vec3::splat(9.0));
    assert_eq!(c.lens, Lens::Perspective { fov_y: 2.0 * 0.5f32.atan() });

    // Aiming at an object that exists: an edit reaches the evaluator through update, which
    // rebuilds no channel of an unchanged camera.
    scene.cameras[1].aim.as_mut().unwrap().target = AimTarget::Object("Arm".into());
    let rebuilt = eval.update(&scene, &HashMap::new());
    assert_eq!(rebuilt.channels, 0);
    assert_eq!(eval.problems(), []);
    let c = eval.camera_at(1, 2.0, &Overrides::new()).unwrap();
    let to_arm = (Vec3::new(0.0, 0.0, -3.0) - Vec3::new(3.0, 2.0, 4.0)).normalize();
    assert!(c.forward().abs_diff_eq(to_arm, 1e-5));
    scene.cameras[0].lens.track.keys[1].value = 50.0;
    assert_eq!(eval.update(&scene, &HashMap::new()).channels, 1);
    scene.cameras.pop();
    eval.update(&scene, &HashMap::new());
    assert_eq!(eval.evaluate(0.0, &Overrides::new()).cameras.len(), 1);
    assert_eq!(eval.camera_at(1, 0.0, &Overrides::new()), None);
}
