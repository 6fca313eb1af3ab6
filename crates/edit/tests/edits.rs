//! Every [`SceneEdit`] applied to the demo scene without a window: what it changes, what it
//! leaves alone, and the undo step's name it gives.

use glam::Vec3;
use keyrig_core::{
    AimTarget, Cycle, Cycles, DeformerKind, FrameRange, Interpolation, KeyType, Projection, RotationMode,
    Scene, SceneCamera, SoundClip, Tcb,
};
use keyrig_edit::channels::{self, ChannelId, ChannelValue};
use keyrig_edit::edit::Animate;
use keyrig_edit::{KeyParamChange, KeyRef, SceneEdit};

const ELBOW: ChannelId = ChannelId::JointRotation { object: 0, joint: 1 };

fn demo() -> Scene {
    keyrig_io::demo::demo_scene()
}

/// Applies `edit` to a copy of `scene`, returning the copy and the label read before it.
fn applied(scene: &Scene, edit: &SceneEdit) -> (Scene, String) {
    let label = edit.label(scene);
    let mut out = scene.clone();
    edit.apply(&mut out);
    (out, label)
}

fn key(index: usize) -> KeyRef {
    KeyRef { channel: ELBOW, index }
}

#[test]
fn key_params_write_only_the_fields_that_changed() {
    let scene = demo();
    let keys = vec![key(1), key(2)];
    // The two keys differ in tension and continuity: a bias change keeps both of theirs.
    let change = KeyParamChange { bias: Some(-0.9), ..Default::default() };
    let (after, label) = applied(&scene, &SceneEdit::KeyParams { keys, change });
    assert_eq!(label, "bias -0.90 on 2 keys");
    let (_, _, one) = channels::key_params(&after, ELBOW, 1).unwrap();
    let (_, _, two) = channels::key_params(&after, ELBOW, 2).unwrap();
    assert_eq!((one.tension, one.continuity, one.bias), (0.5, 0.0, -0.9));
    assert_eq!((two.tension, two.continuity, two.bias), (0.0, -0.5, -0.9));
    // Other keys are untouched.
    assert_eq!(channels::key_params(&after, ELBOW, 3), channels::key_params(&scene, ELBOW, 3));
}

#[test]
fn key_params_from_a_row_and_from_the_interpolation_menu_are_one_edit() {
    let scene = demo();
    let before = (Interpolation::Tcb, Tcb::new(0.5, 0.0, 0.3));
    let change = KeyParamChange::between(before, (Interpolation::Linear, Tcb::new(0.5, 0.0, 0.3)));
    assert_eq!(change, KeyParamChange { interpolation: Some(Interpolation::Linear), ..Default::default() });
    let (after, label) = applied(&scene, &SceneEdit::KeyParams { keys: vec![key(1)], change });
    assert_eq!(label, "interpolation Linear on elbow rotation key at frame 15");
    let (_, mode, tcb) = channels::key_params(&after, ELBOW, 1).unwrap();
    assert_eq!((mode, tcb.tension, tcb.bias), (Interpolation::Linear, 0.5, 0.3));

    // The menu's "TCB spline, clamped": the mode and the clamp, each key keeping its T/C/B.
    let change =
        KeyParamChange { interpolation: Some(Interpolation::Tcb), clamped: Some(true), ..Default::default() };
    let (after, label) = applied(&after, &SceneEdit::KeyParams { keys: vec![key(1), key(2)], change });
    assert_eq!(label, "interpolation Tcb, clamped on 2 keys");
    for (i, tension) in [(1, 0.5), (2, 0.0)] {
        let (_, mode, tcb) = channels::key_params(&after, ELBOW, i).unwrap();
        assert_eq!((mode, tcb.clamped, tcb.tension), (Interpolation::Tcb, true, tension));
    }
}

#[test]
fn key_type_hermite_handles_and_a_tangent() {
    let scene = demo();
    let edit = SceneEdit::KeyType { keys: vec![key(2)], key_type: KeyType::Extreme };
    let (after, label) = applied(&scene, &edit);
    assert_eq!(label, "key type Extreme on elbow rotation key at frame 30");
    assert_eq!(channels::key_type(&after, ELBOW, 2), Some(KeyType::Extreme));
    assert_eq!(channels::key_type(&after, ELBOW, 1), Some(KeyType::Keyframe));

    // Hermite handles on the Cube's translation keep the curve's shape.
    let cube = ChannelId::ObjectTranslation(1);
    assert!(channels::key_count(&scene, cube) >= 3);
    let keys = vec![KeyRef { channel: cube, index: 1 }];
    let (after, label) = applied(&scene, &SceneEdit::HermiteHandles { keys });
    assert_eq!(label, "Hermite handles on Cube translation key at frame 30");
    let (_, mode, _) = channels::key_params(&after, cube, 1).unwrap();
    assert_eq!(mode, Interpolation::Hermite);
    let (inn, out) = channels::key_tangents(&after, cube, 1);
    assert!(inn.is_some() && out.is_some());

    let edit = SceneEdit::Tangent {
        key: KeyRef { channel: cube, index: 1 },
        outgoing: true,
        component: 1,
        value: 2.5,
        convert: false,
        drag: channels::HandleDrag::Aligned,
    };
    let (after, label) = applied(&after, &edit);
    assert_eq!(label, "drag out handle of Cube translation key 1");
    assert_eq!(channels::key_tangents(&after, cube, 1).1.unwrap()[1], 2.5);
}

/// Issue 42, 9: a Hermite key's handles are aligned: dragging one turns the other with it, so
/// the curve keeps no kink; an Alt drag (Free) moves one alone and breaks the pair, whose
/// handles then move alone until they are equal again; each component is its own pair.
#[test]
fn hermite_handles_stay_aligned_unless_broken() {
    let scene = demo();
    let cube = ChannelId::ObjectTranslation(1);
    let key = KeyRef { channel: cube, index: 1 };
    let (after, _) = applied(&scene, &SceneEdit::HermiteHandles { keys: vec![key] });
    let tangents = |scene: &keyrig_core::Scene| {
        let (inn, out) = channels::key_tangents(scene, cube, 1);
        (inn.expect("in-tangent"), out.expect("out-tangent"))
    };
    let (inn, out) = tangents(&after);
    for c in 0..3 {
        assert!(channels::tangents_aligned(inn[c], out[c]), "converted without a kink: {inn:?} {out:?}");
    }
    let drag = |outgoing: bool, value: f32, drag: channels::HandleDrag| SceneEdit::Tangent {
        key,
        outgoing,
        component: 1,
        value,
        convert: false,
        drag,
    };
    // An aligned drag of the out-handle turns the in-handle with it; X and Z stay.
    let (after, _) = applied(&after, &drag(true, 2.5, channels::HandleDrag::Aligned));
    let (i1, o1) = tangents(&after);
    assert_eq!((i1[1], o1[1]), (2.5, 2.5));
    assert_eq!((i1[0], i1[2]), (inn[0], inn[2]));
    // Alt: the out-handle alone; the pair is broken.
    let (after, _) = applied(&after, &drag(true, -1.0, channels::HandleDrag::Free));
    let (i2, o2) = tangents(&after);
    assert_eq!((i2[1], o2[1]), (2.5, -1.0));
    // A broken pair's handles move alone, even without Alt.
    let (after, _) = applied(&after, &drag(false, 4.0, channels::HandleDrag::Aligned));
    let (i3, o3) = tangents(&after);
    assert_eq!((i3[1], o3[1]), (4.0, -1.0));
    // Align handles makes the pair one tangent again (their mean); drags turn both again.
    let (after, label) = applied(&after, &SceneEdit::AlignHandles { keys: vec![key] });
    assert_eq!(label, "align handles on Cube translation key at frame 30");
    let (i4, o4) = tangents(&after);
    assert_eq!((i4[1], o4[1]), (1.5, 1.5));
    let (after, _) = applied(&after, &drag(true, 3.0, channels::HandleDrag::Aligned));
    let (i5, o5) = tangents(&after);
    assert_eq!((i5[1], o5[1]), (3.0, 3.0));
}

#[test]
fn mute_lock_and_cycles_of_a_channel() {
    let scene = demo();
    let (after, label) = applied(&scene, &SceneEdit::Mute { channel: ELBOW, muted: true });
    assert_eq!(label, "mute elbow rotation");
    assert_eq!(channels::mute_and_lock(&after, ELBOW), (true, false));
    let (after, label) = applied(&after, &SceneEdit::Lock { channel: ELBOW, locked: true });
    assert_eq!(label, "lock elbow rotation");
    assert_eq!(channels::mute_and_lock(&after, ELBOW), (true, true));
    let (after, label) = applied(&after, &SceneEdit::Mute { channel: ELBOW, muted: false });
    assert_eq!(label, "unmute elbow rotation");
    assert_eq!(channels::mute_and_lock(&after, ELBOW), (false, true));

    let cycles = Cycles { before: Cycle::Hold, after: Cycle::Repeat };
    let (after, label) = applied(&scene, &SceneEdit::Cycles { channel: ELBOW, cycles });
    assert_eq!(label, "elbow rotation: Repeat after keys");
    assert_eq!(channels::cycles(&after, ELBOW), Some(cycles));
}

#[test]
fn rotation_mode_and_euler_keys() {
    let scene = demo();
    let edit = SceneEdit::RotationMode {
        channel: ELBOW,
        mode: RotationMode::Euler(keyrig_core::EulerOrder::ZYX),
        euler_keys: false,
    };
    let (after, label) = applied(&scene, &edit);
    assert_eq!(label, "rotation mode ZYX Euler of elbow rotation");
    assert_eq!(
        keyrig_core::channel_id::rotation_mode(&after, ELBOW),
        RotationMode::Euler(keyrig_core::EulerOrder::ZYX)
    );
    // Only the mode: the keys are the same quaternions.
    assert_eq!(channels::key_value(&after, ELBOW, 2), channels::key_value(&scene, ELBOW, 2));

    let edit = SceneEdit::RotationMode {
        channel: ELBOW,
        mode: RotationMode::Euler(keyrig_core::EulerOrder::XYZ),
        euler_keys: true,
    };
    let (after, label) = applied(&scene, &edit);
    assert_eq!(label, "Euler keys (XYZ Euler) for elbow rotation");
    let euler = keyrig_core::channel_id::euler_partner(ELBOW).unwrap();
    assert_eq!(channels::key_count(&after, euler), channels::key_count(&scene, ELBOW));
    // The elbow bends 90° about −Z at frame 30.
    let Some(ChannelValue::Vec3(angles)) = channels::key_value(&after, euler, 2) else { panic!("Euler key") };
    assert!((angles - Vec3::new(0.0, 0.0, -90.0)).length() < 1e-3, "{angles}");

    let back = SceneEdit::RotationMode {
        channel: ELBOW,
        mode: RotationMode::Euler(keyrig_core::EulerOrder::XYZ),
        euler_keys: false,
    };
    assert_eq!(back.label(&after), "quaternion keys for elbow rotation");
    let mut again = after.clone();
    back.apply(&mut again);
    assert_eq!(channels::key_count(&again, euler), 0);
    assert_eq!(channels::key_count(&again, ELBOW), channels::key_count(&scene, ELBOW));
}

#[test]
fn animating_attributes_starts_constant_channels() {
    let scene = demo();
    let cube = 1;
    let (after, label) = applied(
        &scene,
        &SceneEdit::Animate(Animate::Colour { object: cube, from: Vec3::new(0.1, 0.2, 0.9) }),
    );
    assert_eq!(label, "animate colour");
    assert_eq!(
        after.objects[cube].attributes.colour.as_ref().map(|c| c.value),
        Some(Vec3::new(0.1, 0.2, 0.9))
    );

    let (after, _) = applied(&scene, &SceneEdit::Animate(Animate::Deformer { object: 0, value: 2.0 }));
    assert_eq!(after.objects[0].attributes.deformer.as_ref().map(|c| c.value), Some(2.0));
    let (after, _) =
        applied(&scene, &SceneEdit::Animate(Animate::BlendZone { object: 0, parent: 0.3, child: 0.2 }));
    assert_eq!(after.objects[0].attributes.blend_parent_fraction.as_ref().map(|c| c.value), Some(0.3));
    assert_eq!(after.objects[0].attributes.blend_child_fraction.as_ref().map(|c| c.value), Some(0.2));
    let (after, label) = applied(&scene, &SceneEdit::Animate(Animate::LightRange { light: 0, from: 10.0 }));
    assert_eq!(label, "light range");
    assert_eq!(after.lights[0].attributes.range.as_ref().map(|c| c.value), Some(10.0));
    let edit = SceneEdit::Animate(Animate::Cone { light: 0, cutoff_deg: 30.0, inner_angle_deg: 20.0 });
    let (after, _) = applied(&scene, &edit);
    assert_eq!(after.lights[0].attributes.cutoff_deg.as_ref().map(|c| c.value), Some(30.0));
    assert_eq!(after.lights[0].attributes.inner_angle_deg.as_ref().map(|c| c.value), Some(20.0));
    assert_eq!(after.problems(), Vec::new());
}

#[test]
fn deformer_camera_sound_and_reference_edits() {
    let mut scene = demo();
    scene.cameras.push(SceneCamera::new("Dolly", Vec3::new(0.0, 1.0, 5.0)));
    scene.sounds.push(SoundClip::new("/tmp/line.wav", 0.0));

    let mut settings = scene.objects[0].deformer;
    settings.kind = DeformerKind::DualQuaternion;
    let (after, label) = applied(&scene, &SceneEdit::Deformer { object: 0, settings });
    assert_eq!(label, "deformer Dual quaternion");
    assert_eq!(after.objects[0].deformer.kind, DeformerKind::DualQuaternion);

    let edit = SceneEdit::CameraProjection {
        camera: 0,
        projection: Projection::FocalLength { sensor_height_mm: 24.0 },
    };
    let (after, label) = applied(&scene, &edit);
    assert_eq!(label, "Dolly projection");
    assert!(matches!(after.cameras[0].projection, Projection::FocalLength { .. }));
    let (after, label) = applied(&scene, &SceneEdit::CameraClip { camera: 0, near: 0.5, far: Some(80.0) });
    assert_eq!(label, "Dolly clip planes");
    assert_eq!((after.cameras[0].near, after.cameras[0].far), (0.5, Some(80.0)));
    let target = AimTarget::Object("Cube".into());
    let (after, label) = applied(&scene, &SceneEdit::CameraAim { camera: 0, target: Some(target.clone()) });
    assert_eq!(label, "camera aim");
    assert_eq!(after.cameras[0].aim.as_ref().map(|a| a.target.clone()), Some(target));
    let (after, _) = applied(&after, &SceneEdit::CameraAim { camera: 0, target: None });
    assert!(after.cameras[0].aim.is_none());

    let (after, label) = applied(&scene, &SceneEdit::SoundMute { clip: 0, muted: true });
    assert_eq!(label, "mute sound clip line.wav");
    assert!(after.sounds[0].mute);
    let (after, label) = applied(&scene, &SceneEdit::SoundStart { clip: 0, start_frame: 14.0 });
    assert_eq!(label, "move sound clip line.wav to frame 14");
    assert_eq!(after.sounds[0].start_frame, 14.0);

    // Indices that do not exist leave the scene as it is.
    for edit in [
        SceneEdit::SoundMute { clip: 5, muted: true },
        SceneEdit::CameraClip { camera: 9, near: 1.0, far: None },
        SceneEdit::Deformer { object: 9, settings },
        SceneEdit::ModelFps { object: 0, fps: 12.0 },
        SceneEdit::ReferenceOpacity(0.5),
    ] {
        let (after, _) = applied(&scene, &edit);
        assert_eq!(after, scene, "{edit:?}");
    }
}

#[test]
fn frame_rate_ranges_and_a_motion_path_key() {
    let scene = demo();
    let (after, label) = applied(&scene, &SceneEdit::FrameRange { start: 5, end: 60 });
    assert_eq!(label, "frame range 5–60");
    assert_eq!((after.frame_range.start, after.frame_range.end), (5, 60));
    let range = FrameRange { start: 30, end: 45 };
    let (after, label) = applied(&scene, &SceneEdit::PreviewRange(range));
    assert_eq!(label, "preview range 30–45");
    assert_eq!(after.preview_range, Some(range));

    // 30 → 60 fps keeping frames: a key at frame 30 (1 s) moves to 0.5 s; the range stays.
    let origin = (scene.fps, scene.frame_range.start, scene.frame_range.end);
    let (after, label) = applied(&scene, &SceneEdit::Retime { origin, fps: 60.0, keep_frames: true });
    assert_eq!(label, "change fps to 60");
    assert_eq!(after.fps, 60.0);
    assert_eq!(after.frame_range, scene.frame_range);
    let t = |s: &Scene| channels::key_params(s, ELBOW, 2).unwrap().0;
    assert!((t(&after) - t(&scene) / 2.0).abs() < 1e-9);
    // Keeping seconds: the keys stay, the range's frames double.
    let (after, _) = applied(&scene, &SceneEdit::Retime { origin, fps: 60.0, keep_frames: false });
    assert_eq!(t(&after), t(&scene));
    assert_eq!(after.frame_range.end, scene.frame_range.end * 2);

    let cube = ChannelId::ObjectTranslation(1);
    let time = channels::key_params(&scene, cube, 1).unwrap().0;
    let edit = SceneEdit::MotionPathKey { channel: cube, time, value: Vec3::new(1.0, 2.0, 3.0) };
    let (after, label) = applied(&scene, &edit);
    assert_eq!(label, "move the key at frame 30 on the motion path");
    assert_eq!(channels::key_value(&after, cube, 1), Some(ChannelValue::Vec3(Vec3::new(1.0, 2.0, 3.0))));
    assert_eq!(channels::key_count(&after, cube), channels::key_count(&scene, cube));
}

#[test]
fn object_constraints_are_added_retargeted_and_removed() {
    use keyrig_core::ConstraintKind;
    use keyrig_edit::edit::{new_constraint, CONSTRAINT_KINDS};
    let scene = demo();
    let cube = scene.objects.iter().position(|o| o.name == "Cube").expect("the demo's cube");
    let arm = AimTarget::Object("Arm".into());
    for kind in CONSTRAINT_KINDS {
        let c = new_constraint(&scene, cube, kind, arm.clone()).expect("a constraint");
        assert_eq!((c.name.as_str(), c.kind.label()), (kind, kind));
    }
    assert!(new_constraint(&scene, cube, "Spin", arm.clone()).is_none());
    let aim = new_constraint(&scene, cube, "Aim at", arm.clone()).unwrap();
    let (after, label) = applied(&scene, &SceneEdit::AddConstraint { object: cube, constraint: aim });
    assert_eq!(label, "add constraint Aim at to Cube");
    assert!(after.problems().is_empty(), "{:?}", after.problems());
    // A second one of the same kind gets a name of its own.
    assert_eq!(new_constraint(&after, cube, "Aim at", arm.clone()).unwrap().name, "Aim at 2");
    let wrist = AimTarget::Joint { object: "Arm".into(), joint: "wrist".into() };
    let edit = SceneEdit::ConstraintTarget { object: cube, constraint: 0, target: wrist.clone() };
    let (retargeted, label) = applied(&after, &edit);
    assert_eq!(label, "Aim at target Arm / wrist");
    assert!(
        matches!(&retargeted.objects[cube].constraints[0].kind, ConstraintKind::AimAt { target, .. } if *target == wrist)
    );
    let (removed, label) = applied(&retargeted, &SceneEdit::RemoveConstraint { object: cube, constraint: 0 });
    assert_eq!(label, "remove constraint Aim at from Cube");
    assert_eq!(removed, scene);
    // Indices that do not exist change nothing.
    assert_eq!(applied(&scene, &SceneEdit::RemoveConstraint { object: cube, constraint: 3 }).0, scene);
    assert_eq!(
        applied(&scene, &SceneEdit::ConstraintTarget { object: 9, constraint: 0, target: wrist }).0,
        scene
    );
}
