//! IK constraints in the scene model: every validation problem with its path and message,
//! their channels (ids, labels, paths), and the solve on a local pose.

use glam::{Quat, Vec3};
use keyrig_core::channel::{list_channels, ChannelPath};
use keyrig_core::channel_id::{channel, ChannelId, ChannelKind, ChannelRef};
use keyrig_core::ik_constraint::{ConstraintChain, ConstraintError, LocalPose};
use keyrig_core::{Animated, IkConstraint, Joint, Key, Object, RawTrack, Scene, Skeleton};

/// An arm of four joints along +X (0.4 apart) with one constraint "Reach" on the wrist, 2 bones.
fn scene() -> Scene {
    let bone = Vec3::new(0.4, 0.0, 0.0);
    let mut skeleton = Skeleton::new(vec![
        Joint::new("shoulder", None, Vec3::ZERO, Quat::IDENTITY),
        Joint::new("elbow", Some(0), bone, Quat::IDENTITY),
        Joint::new("forearm", Some(1), bone, Quat::IDENTITY),
        Joint::new("wrist", Some(2), bone, Quat::IDENTITY),
    ]);
    skeleton.ik_constraints.push(IkConstraint::new("Reach", 3, 2, Vec3::new(0.9, 0.3, 0.0)));
    let mut arm = Object::new("Arm");
    arm.skeleton = Some(skeleton);
    Scene { objects: vec![arm], ..Scene::default() }
}

fn reach(scene: &mut Scene) -> &mut IkConstraint {
    &mut scene.objects[0].skeleton.as_mut().expect("a skeleton").ik_constraints[0]
}

fn problems(scene: &Scene) -> Vec<String> {
    scene.problems().iter().map(ToString::to_string).collect()
}

#[test]
fn a_valid_constraint_has_no_problems() {
    assert_eq!(problems(&scene()), Vec::<String>::new());
}

/// A change that breaks one thing of the scene.
type Breaker = Box<dyn Fn(&mut Scene)>;

#[test]
fn every_problem_names_its_field() {
    let at = "objects[0].skeleton.ik_constraints[0]";
    let cases: Vec<(Breaker, String)> = vec![
        (Box::new(|s| reach(s).end = 9), format!("{at}.end: end joint 9 is outside the skeleton (4 joints)")),
        (
            Box::new(|s| reach(s).bones = 1),
            format!("{at}.bones: an IK constraint needs a chain of at least 2 bones; this one has 1"),
        ),
        (
            Box::new(|s| reach(s).bones = 4),
            format!(
                "{at}.bones: a chain of 4 bones is too long: joint 3 (\"wrist\") has 3 joint(s) above it"
            ),
        ),
        (
            Box::new(|s| {
                s.objects[0].skeleton.as_mut().expect("a skeleton").joints[2].rest_translation = Vec3::ZERO
            }),
            format!(
                "{at}: joint 2 (\"forearm\") sits on its parent: a zero-length bone has no direction to aim"
            ),
        ),
        (
            Box::new(|s| reach(s).blend = Animated::constant(1.5)),
            format!("{at}.blend.value: IK/FK blend 1.5 is outside [0, 1] (0 = keyed FK, 1 = IK)"),
        ),
        (
            Box::new(|s| {
                reach(s).blend.track = RawTrack::new(vec![Key::new(0.0, 0.0), Key::new(1.0, -0.25)]);
            }),
            format!("{at}.blend.track[1].value: IK/FK blend -0.25 is outside [0, 1] (0 = keyed FK, 1 = IK)"),
        ),
        (
            Box::new(|s| reach(s).target = Animated::constant(Vec3::new(f32::NAN, 0.0, 0.0))),
            format!("{at}.target.value.x: not a finite number"),
        ),
        (
            Box::new(|s| reach(s).pole = Some(Vec3::new(0.0, f32::INFINITY, 0.0))),
            format!("{at}.pole.y: not a finite number"),
        ),
        (
            Box::new(|s| reach(s).name = "a/b".into()),
            format!("{at}.name: IK constraint name \"a/b\" contains '/', which separates channel path parts"),
        ),
        (Box::new(|s| reach(s).name = String::new()), format!("{at}.name: IK constraint name is empty")),
    ];
    for (break_it, expected) in cases {
        let mut s = scene();
        break_it(&mut s);
        assert_eq!(problems(&s), vec![expected]);
    }
    let mut s = scene();
    let again = reach(&mut s).clone();
    s.objects[0].skeleton.as_mut().expect("a skeleton").ik_constraints.push(again);
    assert_eq!(
        problems(&s),
        vec!["objects[0].skeleton.ik_constraints[1].name: duplicate IK constraint name \"Reach\" (also IK constraint 0)"]
    );
}

#[test]
fn constraint_channels_have_ids_paths_and_labels() {
    let s = scene();
    let target = ChannelId::IkTarget { object: 0, constraint: 0 };
    let blend = ChannelId::IkBlend { object: 0, constraint: 0 };
    assert_eq!(target.kind(), ChannelKind::Vec3);
    assert_eq!(blend.kind(), ChannelKind::Scalar);
    assert_eq!(target.field_path(), "objects[0].skeleton.ik_constraints[0].target");
    assert_eq!(blend.label(&s), "Reach IK blend");
    assert!(matches!(channel(&s, blend), Some(ChannelRef::Scalar(a)) if a.value == 1.0));
    let ids = ChannelId::of_object(&s, 0);
    assert_eq!(&ids[ids.len() - 2..], &[target, blend]);
    for (text, id) in [("object/Arm/ik/Reach/target", target), ("object/Arm/ik/Reach/blend", blend)] {
        let path = ChannelPath::parse(text).expect("parses");
        assert_eq!(path.to_string(), text);
        assert_eq!(path.id(&s), Ok(id));
        assert!(list_channels(&s).contains(&path));
    }
    let err = |p: &str| ChannelPath::parse(p).and_then(|c| c.id(&s)).expect_err(p).to_string();
    assert_eq!(
        err("object/Arm/ik/Grab/target"),
        "channel path \"object/Arm/ik/Grab/target\": object \"Arm\" has no IK constraint named \"Grab\"; IK constraints: \"Reach\""
    );
    assert_eq!(
        err("object/Arm/ik/Reach/pole"),
        "channel path \"object/Arm/ik/Reach/pole\": unknown IK constraint property \"pole\"; IK constraint properties are: target, blend"
    );
    assert!(err("object/Arm/ik/Reach").contains("object/<name>/ik/<constraint>/<property>"));
}

/// The chain a constraint names, and the solve: on the target at blend 1, untouched at 0.
#[test]
fn the_chain_is_solved_on_a_local_pose() {
    let s = scene();
    let skeleton = s.objects[0].skeleton.as_ref().expect("a skeleton");
    let chain = ConstraintChain::new(skeleton, &skeleton.ik_constraints[0]).expect("a chain");
    assert_eq!(chain.joints, vec![1, 2, 3]);
    assert_eq!(chain.turned_joints(), &[1, 2]);
    let translations = vec![Vec3::ZERO; 4];
    let scales = vec![Vec3::ONE; 4];
    let fk = vec![Quat::from_rotation_z(0.3), Quat::IDENTITY, Quat::IDENTITY, Quat::from_rotation_x(0.2)];
    let mut rotations = fk.clone();
    let mut pose = LocalPose {
        translations: &translations,
        rotations: &mut rotations,
        scales: &scales,
        root_translation: Vec3::ZERO,
    };
    assert_eq!(chain.solve(&mut pose, Vec3::new(0.9, 0.3, 0.0), None, 0.0), Ok(None));
    assert_eq!(rotations, fk, "blend 0 leaves the pose as it is");
    let mut pose = LocalPose {
        translations: &translations,
        rotations: &mut rotations,
        scales: &scales,
        root_translation: Vec3::ZERO,
    };
    let report =
        chain.solve(&mut pose, Vec3::new(0.9, 0.3, 0.0), None, 1.0).expect("solves").expect("a report");
    assert!(report.reachable && report.distance < 1e-6, "{report:?}");
    assert_eq!(
        (rotations[0], rotations[3]),
        (fk[0], fk[3]),
        "joints outside the chain and its end keep theirs"
    );
    let mut pose = LocalPose {
        translations: &translations,
        rotations: &mut rotations,
        scales: &scales,
        root_translation: Vec3::ZERO,
    };
    assert_eq!(
        chain.solve(&mut pose, Vec3::new(f32::NAN, 0.0, 0.0), None, 1.0).map_err(|e| e.to_string()),
        Err("IK target is not finite: [NaN, 0, 0]".to_string())
    );
    let mut short = vec![Quat::IDENTITY; 2];
    let mut pose = LocalPose {
        translations: &translations,
        rotations: &mut short,
        scales: &scales,
        root_translation: Vec3::ZERO,
    };
    assert_eq!(
        chain.solve(&mut pose, Vec3::X, None, 1.0),
        Err(ConstraintError::PoseMismatch { expected: 4, found: 2 })
    );
}
