//! Channels through their public paths: spin angles, domains and names as `keyrig sample` and
//! the editor read them.

use glam::{Quat, Vec3};
use keyrig_core::channel::ChannelPath;
use keyrig_core::{Animated, Joint, Key, Object, RawTrack, Scene, Skeleton, Spin};

/// An arm whose forearm turns 360° about X between 0 s and 2 s (one spin key), and whose
/// object translation is keyed from 1 s to 3 s.
fn twist() -> Scene {
    let mut forearm = Joint::new("forearm", None, Vec3::ZERO, Quat::IDENTITY);
    forearm.rotation = Animated::new(
        Quat::IDENTITY,
        RawTrack::new(vec![
            Key::new(0.0, Quat::IDENTITY),
            Key::new(2.0, Quat::IDENTITY).with_spin(Spin::Angle { axis: Vec3::X, degrees: 360.0 }),
        ]),
    );
    let mut arm = Object::new("Arm");
    arm.skeleton = Some(Skeleton::new(vec![forearm]));
    arm.translation.track = RawTrack::new(vec![Key::new(1.0, Vec3::ZERO), Key::new(3.0, Vec3::X)]);
    let mut scene = Scene::default();
    scene.objects.push(arm);
    scene
}

#[test]
fn a_spin_channel_reports_the_angle_turned() {
    let scene = twist();
    let channel = ChannelPath::parse("object/Arm/joint/forearm/rotation").unwrap().resolve(&scene).unwrap();
    assert!(channel.has_spin());
    assert_eq!(channel.spin_degrees(0.0), Some(0.0));
    let middle = channel.spin_degrees(1.0).expect("inside the spin segment");
    assert!((middle - 180.0).abs() < 1e-9, "{middle}");
    assert_eq!(channel.spin_degrees(2.0), Some(360.0));

    // Channels without spin keys, and channels that are not rotations, have none.
    let translation = ChannelPath::parse("object/Arm/translation").unwrap().resolve(&scene).unwrap();
    assert!(!translation.has_spin());
    assert_eq!(translation.spin_degrees(2.0), None);
    let still = ChannelPath::parse("object/Arm/rotation").unwrap().resolve(&scene).unwrap();
    assert_eq!(still.spin_degrees(1.0), None);
}

#[test]
fn domains_are_the_keyed_range() {
    let scene = twist();
    let resolve = |path: &str| ChannelPath::parse(path).unwrap().resolve(&scene).unwrap();
    assert_eq!(resolve("object/Arm/translation").domain(), Some((1.0, 3.0)));
    assert_eq!(resolve("object/Arm/joint/forearm/rotation").domain(), Some((0.0, 2.0)));
    assert_eq!(resolve("object/Arm/scale").domain(), None);
}

#[test]
fn joint_translation_and_scale_are_listed_when_keyed_or_not_at_rest() {
    let joint = |name: &str| Joint::new(name, Some(0), Vec3::X, Quat::IDENTITY);
    let mut keyed = joint("keyed");
    keyed.translation.track = RawTrack::new(vec![Key::new(0.0, Vec3::ZERO)]);
    keyed.scale.track = RawTrack::new(vec![Key::new(0.0, Vec3::ONE)]);
    let mut moved = joint("moved");
    moved.translation.value = Vec3::Y;
    moved.scale.value = Vec3::splat(2.0);
    let mut arm = Object::new("Arm");
    arm.skeleton = Some(Skeleton {
        joints: vec![Joint::new("root", None, Vec3::ZERO, Quat::IDENTITY), keyed, moved],
        root_translation: Animated::constant(Vec3::ZERO),
        ik_constraints: Vec::new(),
    });
    let mut scene = Scene::default();
    scene.objects.push(arm);
    let joints: Vec<String> = keyrig_core::channel::list_channels(&scene)
        .iter()
        .map(ToString::to_string)
        .filter(|path| path.contains("/joint/"))
        .collect();
    assert_eq!(
        joints,
        [
            "object/Arm/joint/root/rotation",
            "object/Arm/joint/keyed/translation",
            "object/Arm/joint/keyed/rotation",
            "object/Arm/joint/keyed/scale",
            "object/Arm/joint/moved/translation",
            "object/Arm/joint/moved/rotation",
            "object/Arm/joint/moved/scale",
        ]
    );
}

#[test]
fn channel_ids_know_their_kind_of_value() {
    use keyrig_core::channel_id::{ChannelId, ChannelKind};
    for (id, kind) in [
        (ChannelId::ObjectTranslation(0), ChannelKind::Vec3),
        (ChannelId::ObjectRotation(0), ChannelKind::Rotation),
        (ChannelId::ObjectScale(0), ChannelKind::Vec3),
        (ChannelId::RootTranslation(0), ChannelKind::Vec3),
        (ChannelId::JointTranslation { object: 0, joint: 1 }, ChannelKind::Vec3),
        (ChannelId::JointRotation { object: 0, joint: 1 }, ChannelKind::Rotation),
        (ChannelId::JointScale { object: 0, joint: 1 }, ChannelKind::Vec3),
        (ChannelId::LightPosition(0), ChannelKind::Vec3),
        (ChannelId::LightDirection(0), ChannelKind::Vec3),
        (ChannelId::LightColour(0), ChannelKind::Vec3),
        (ChannelId::LightIntensity(0), ChannelKind::Scalar),
    ] {
        assert_eq!(id.kind(), kind, "{id:?}");
    }
}

/// A joint lists its translation (scale) channel when that is keyed or not the identity, so an
/// imported character's bone offsets show, and keyrig's own rigs keep one row per joint.
#[test]
fn joint_translations_and_scales_are_listed_where_keyed_or_not_identity() {
    use keyrig_core::channel_id::ChannelId;
    let joint = |name: &str| Joint::new(name, None, Vec3::ZERO, Quat::IDENTITY);
    let keys = |v: Vec3| Animated::new(v, RawTrack::new(vec![Key::new(0.0, v), Key::new(1.0, v)]));
    let mut offset = joint("offset");
    offset.translation.value = Vec3::new(0.0, 0.3, 0.0);
    offset.scale.value = Vec3::splat(2.0);
    let mut keyed = joint("keyed");
    keyed.translation = keys(Vec3::ZERO);
    keyed.scale = keys(Vec3::ONE);
    let mut arm = Object::new("Arm");
    arm.skeleton = Some(Skeleton::new(vec![offset, keyed, joint("plain")]));
    let mut scene = Scene::default();
    scene.objects.push(arm);
    let ids = ChannelId::of_object(&scene, 0);
    let object = 0;
    for joint in [0, 1] {
        assert!(ids.contains(&ChannelId::JointTranslation { object, joint }), "joint {joint}: {ids:?}");
        assert!(ids.contains(&ChannelId::JointScale { object, joint }), "joint {joint}: {ids:?}");
    }
    assert!(!ids.contains(&ChannelId::JointTranslation { object, joint: 2 }), "{ids:?}");
    assert!(!ids.contains(&ChannelId::JointScale { object, joint: 2 }), "{ids:?}");
    assert!(ids.contains(&ChannelId::JointRotation { object, joint: 2 }), "{ids:?}");
}

/// Euler keys (issue 30) through their paths: `rotation_euler` samples the angles in degrees,
/// `rotation` the rotation they make in the channel's order; a joint without Euler keys says
/// so; the scene's checks name a quaternion-mode channel with Euler keys and quaternion keys
/// left beside them.
#[test]
fn euler_keys_sample_as_angles_and_as_the_rotation_they_make() {
    let mut scene = twist();
    {
        let joint = &mut scene.objects[0].skeleton.as_mut().unwrap().joints[0];
        joint.rotation = Animated::constant(Quat::IDENTITY);
        joint.rotation_mode = keyrig_core::RotationMode::Euler(keyrig_core::EulerOrder::ZYX);
        joint.rotation_euler = Some(Animated::new(
            Vec3::ZERO,
            RawTrack::new(vec![
                Key::new(0.0, Vec3::ZERO).with_interpolation(keyrig_core::Interpolation::Linear),
                Key::new(2.0, Vec3::new(60.0, 0.0, 720.0)),
            ]),
        ));
    }
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    let angles =
        ChannelPath::parse("object/Arm/joint/forearm/rotation_euler").unwrap().resolve(&scene).unwrap();
    assert_eq!(angles.column_names(keyrig_core::channel::RotationFormat::Quat), ["x_deg", "y_deg", "z_deg"]);
    assert_eq!(angles.sample(1.0), keyrig_core::channel::ChannelValue::Vec3(Vec3::new(30.0, 0.0, 360.0)));
    let rotation = ChannelPath::parse("object/Arm/joint/forearm/rotation").unwrap().resolve(&scene).unwrap();
    assert_eq!(rotation.domain(), Some((0.0, 2.0)));
    // ZYX: Z turns first, X last: R = Rx(15)·Rz(180) at 0.5 s.
    let keyrig_core::channel::ChannelValue::Rotation(q) = rotation.sample(0.5) else { panic!("a rotation") };
    let want = Quat::from_rotation_x(15f32.to_radians()) * Quat::from_rotation_z(180f32.to_radians());
    assert!(q.dot(want).abs() > 1.0 - 1e-6, "{q} vs {want}");
    assert!(keyrig_core::channel::list_channels(&scene)
        .iter()
        .any(|p| p.to_string() == "object/Arm/joint/forearm/rotation_euler"));
    // An object without Euler keys.
    let err = ChannelPath::parse("object/Arm/rotation_euler").unwrap().resolve(&scene).unwrap_err();
    assert!(err.to_string().contains("quaternion keys"), "{err}");
    // Checks: Euler keys need an Euler order, and leave no quaternion keys beside them.
    let joint = &mut scene.objects[0].skeleton.as_mut().unwrap().joints[0];
    joint.rotation_mode = keyrig_core::RotationMode::Quaternion;
    joint.rotation.track = RawTrack::new(vec![Key::new(0.0, Quat::IDENTITY)]);
    let problems: Vec<String> = scene.problems().iter().map(ToString::to_string).collect();
    assert!(problems.iter().all(|p| !p.contains("  ")), "one space between words: {problems:?}");
    assert!(
        problems.iter().any(|p| p.starts_with("objects[0].skeleton.joints[0].rotation_mode") && p.contains("Quaternion")),
        "{problems:?}"
    );
    assert!(
        problems.iter().any(|p| p.starts_with("objects[0].skeleton.joints[0].rotation.track")
            && p.contains("beside Euler keys")),
        "{problems:?}"
    );
}
