//! IK constraints in the scene evaluator (issue 19): reachable targets are reached at blend 1,
//! blend 0 is forward kinematics exactly, blend 0.5 lies between, pose overrides apply to FK
//! before IK, and baking reproduces the constrained animation at every baked frame.

use std::collections::HashMap;

use glam::{Quat, Vec3};
use keyrig_core::channel_id::{ChannelId, ChannelValue};
use keyrig_core::{Animated, IkConstraint, Joint, Key, Object, RawTrack, Scene, Skeleton};
use keyrig_eval::{bake_ik_constraint, Overrides, SceneEvaluator};
use proptest::prelude::*;

const BONE: f32 = 0.4;

/// A five-joint arm along +X (0.4 apart) under a moved, turned and scaled object, with keyed
/// FK rotations, and one constraint on `end` with `bones` bones.
fn scene(end: usize, bones: usize, target: Vec3, pole: Option<Vec3>, blend: f32) -> Scene {
    let bone = Vec3::new(BONE, 0.0, 0.0);
    let mut joints = vec![Joint::new("root", None, Vec3::new(0.0, 0.1, 0.0), Quat::IDENTITY)];
    for (i, name) in ["shoulder", "elbow", "forearm", "wrist"].into_iter().enumerate() {
        joints.push(Joint::new(name, Some(i), bone, Quat::from_rotation_y(0.05 * i as f32)));
    }
    joints[0].rotation.track =
        RawTrack::new(vec![Key::new(0.0, Quat::IDENTITY), Key::new(1.0, Quat::from_rotation_z(0.4))]);
    joints[2].rotation = Animated::constant(Quat::from_rotation_z(-0.6));
    joints[3].rotation = Animated::constant(Quat::from_rotation_x(0.3) * Quat::from_rotation_z(-0.4));
    let mut skeleton = Skeleton::new(joints);
    skeleton.root_translation = Animated::constant(Vec3::new(0.0, 0.0, 0.2));
    let mut constraint = IkConstraint::new("Reach", end, bones, target);
    constraint.pole = pole;
    constraint.blend = Animated::constant(blend);
    skeleton.ik_constraints.push(constraint);
    let mut arm = Object::new("Arm");
    arm.translation = Animated::constant(Vec3::new(-1.0, 0.5, 0.3));
    arm.rotation = Animated::constant(Quat::from_rotation_y(0.7));
    arm.scale = Animated::constant(Vec3::splat(1.5));
    arm.skeleton = Some(skeleton);
    Scene { objects: vec![arm], ..Scene::default() }
}

fn evaluate(scene: &Scene, time: f64, overrides: &Overrides) -> keyrig_eval::ObjectState {
    let eval = SceneEvaluator::new(scene, &HashMap::new());
    assert!(eval.problems().is_empty(), "{:?}", eval.problems());
    eval.object_at(0, time, overrides).expect("the arm")
}

/// Object-space position of joint `j`.
fn joint_at(state: &keyrig_eval::ObjectState, j: usize) -> Vec3 {
    state.palette.as_ref().expect("a palette").model_from_joint[j].translation.into()
}

/// The chain's root joint and its FK position (object space), for targets around it.
fn chain_root(end: usize, bones: usize, time: f64) -> Vec3 {
    let fk = scene(end, bones, Vec3::ZERO, None, 0.0);
    joint_at(&evaluate(&fk, time, &Overrides::new()), end - bones)
}

fn chain() -> impl Strategy<Value = (usize, usize)> {
    prop_oneof![Just((4, 2)), Just((4, 3)), Just((4, 4)), Just((3, 2)), Just((3, 3))]
}

/// A target at a fraction of the chain's reach from its root, in any direction.
fn reachable(bones: usize, direction: Vec3, fraction: f32, root: Vec3) -> Vec3 {
    root + direction.normalize() * fraction * BONE * bones as f32
}

fn direction() -> impl Strategy<Value = Vec3> {
    (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0)
        .prop_filter("not zero", |(x, y, z)| Vec3::new(*x, *y, *z).length() > 0.2)
        .prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(200))]

    /// Blend 1: the evaluated end joint reaches a reachable target within 1e-5 of the chain's
    /// length, with or without a pole, at any time (the FK pose under the chain moves).
    #[test]
    fn blend_1_reaches_reachable_targets(
        (end, bones) in chain(),
        direction in direction(),
        fraction in 0.3f32..0.95,
        pole in proptest::option::of(direction()),
        time in 0.0f64..1.0,
    ) {
        let root = chain_root(end, bones, time);
        let target = reachable(bones, direction, fraction, root);
        let pole = pole.map(|p| root + p);
        let state = evaluate(&scene(end, bones, target, pole, 1.0), time, &Overrides::new());
        let length = BONE * bones as f32;
        let miss = joint_at(&state, end).distance(target);
        prop_assert!(miss <= 1e-5 * length, "missed by {miss} (chain {length})");
    }

    /// Blend 0 is forward kinematics exactly (the same bits as without the constraint); blend
    /// 0.5 turns each chain joint halfway (by angle) from its FK rotation to its IK rotation.
    #[test]
    fn blend_0_is_fk_and_blend_half_is_between(
        (end, bones) in chain(),
        direction in direction(),
        fraction in 0.3f32..0.95,
        time in 0.0f64..1.0,
    ) {
        let none = Overrides::new();
        let target = reachable(bones, direction, fraction, chain_root(end, bones, time));
        let mut fk_scene = scene(end, bones, target, None, 0.0);
        let fk = evaluate(&fk_scene, time, &none);
        fk_scene.objects[0].skeleton.as_mut().expect("a skeleton").ik_constraints.clear();
        let without = evaluate(&fk_scene, time, &none);
        let (a, b) = (fk.pose.as_ref().expect("a pose"), without.pose.as_ref().expect("a pose"));
        prop_assert_eq!(&a.local_rotations, &b.local_rotations);
        prop_assert_eq!(&fk.palette.as_ref().expect("a palette").model_from_joint,
            &without.palette.as_ref().expect("a palette").model_from_joint);

        let ik = evaluate(&scene(end, bones, target, None, 1.0), time, &none);
        let half = evaluate(&scene(end, bones, target, None, 0.5), time, &none);
        for j in end - bones..end {
            let q_fk = a.local_rotations[j];
            let q_ik = ik.pose.as_ref().expect("a pose").local_rotations[j];
            let q_half = half.pose.as_ref().expect("a pose").local_rotations[j];
            // Angles in f64 from atan2: glam's `angle_between` takes an approximate acos of the
            // dot product, which cannot tell angles below ~1e-3 apart.
            let angle = |a: Quat, b: Quat| {
                let d = a.as_dquat().conjugate() * b.as_dquat();
                2.0 * glam::DVec3::new(d.x, d.y, d.z).length().atan2(d.w.abs())
            };
            let whole = angle(q_fk, q_ik);
            let (first, second) = (angle(q_fk, q_half), angle(q_half, q_ik));
            prop_assert!((first - whole / 2.0).abs() < 1e-4 && (second - whole / 2.0).abs() < 1e-4,
                "joint {j}: {first} + {second} vs {whole}");
        }
    }
}

/// Pose overrides (a gizmo drag) change the FK pose the chain is solved from: an override of a
/// joint above the chain moves the chain's root, and the end still reaches the target.
#[test]
fn overrides_apply_to_fk_before_ik() {
    let target = reachable(2, Vec3::new(1.0, 0.5, 0.2), 0.8, chain_root(4, 2, 0.0));
    let s = scene(4, 2, target, None, 1.0);
    let mut overrides = Overrides::new();
    let turn = Quat::from_rotation_z(0.2);
    overrides.insert(ChannelId::JointRotation { object: 0, joint: 1 }, ChannelValue::Rotation(turn));
    let plain = evaluate(&s, 0.0, &Overrides::new());
    let state = evaluate(&s, 0.0, &overrides);
    assert_eq!(state.pose.as_ref().expect("a pose").local_rotations[1], turn);
    assert!(joint_at(&state, 2).distance(joint_at(&plain, 2)) > 1e-3, "the chain's root moved");
    assert!(joint_at(&state, 4).distance(target) < 1e-5 * 0.8);
    // An override of the blend wins over its channel.
    overrides.insert(ChannelId::IkBlend { object: 0, constraint: 0 }, ChannelValue::Scalar(0.0));
    let fk = evaluate(&s, 0.0, &overrides);
    assert_eq!(fk.pose.as_ref().expect("a pose").local_rotations[2], Quat::from_rotation_z(-0.6).normalize());
}

/// Baking writes a key per frame on the chain's joints (not its end) and sets the blend to 0;
/// the baked scene shows, at every baked frame, the pose the constraint showed.
///
/// Tolerance: a baked key is the evaluated f32 rotation itself and a track passes through its
/// keys (keyrig-core's track property), so the only difference is the rounding of normalizing
/// the sampled quaternion (a few 1e-8 per component); 1e-6 of the chain's length and 1e-6 in
/// quaternion components (about 2e-6 rad) allow for that
/// with margin, and would catch a key at the wrong frame (the target moves ~1e-2 per frame).
#[test]
fn bake_reproduces_the_constraint_at_every_baked_frame() {
    let root = chain_root(4, 3, 0.0);
    let mut s = scene(4, 3, root, Some(root + Vec3::Y), 1.0);
    let start = root + Vec3::new(0.7, 0.3, 0.1);
    let c = &mut s.objects[0].skeleton.as_mut().expect("a skeleton").ik_constraints[0];
    c.target = Animated::new(
        start,
        RawTrack::new(vec![
            Key::new(0.0, start),
            Key::new(0.5, root + Vec3::new(0.3, 0.8, -0.2)),
            Key::new(1.0, root + Vec3::new(0.9, -0.2, 0.3)),
        ]),
    );
    c.blend = Animated::new(1.0, RawTrack::new(vec![Key::new(0.0, 0.2), Key::new(0.8, 1.0)]));
    // Keys of the chain's joints outside the range stay; those inside are replaced.
    s.objects[0].skeleton.as_mut().expect("a skeleton").joints[2].rotation.track = RawTrack::new(vec![
        Key::new(0.1, Quat::from_rotation_z(-0.6)),
        Key::new(2.0, Quat::from_rotation_z(-0.1)),
    ]);
    let (first, last) = (0, 30);
    let eval = SceneEvaluator::new(&s, &HashMap::new());
    let none = Overrides::new();
    let before: Vec<_> =
        (first..=last).map(|f| eval.object_at(0, f64::from(f) / s.fps, &none).expect("the arm")).collect();
    let mut baked = s.clone();
    let report = bake_ik_constraint(&mut baked, 0, 0, first, last).expect("bakes");
    assert_eq!(report.joints, vec![1, 2, 3]);
    assert_eq!(report.frames, 31);
    let skeleton = baked.objects[0].skeleton.as_ref().expect("a skeleton");
    assert_eq!(skeleton.ik_constraints[0].blend, Animated::constant(0.0));
    assert_eq!(skeleton.joints[1].rotation.track.len(), 31);
    assert_eq!(skeleton.joints[2].rotation.track.len(), 32, "the key at 2 s is kept");
    assert_eq!(
        skeleton.joints[4].rotation,
        s.objects[0].skeleton.as_ref().expect("a skeleton").joints[4].rotation
    );
    let eval = SceneEvaluator::new(&baked, &HashMap::new());
    assert!(eval.problems().is_empty(), "{:?}", eval.problems());
    let length = 3.0 * BONE;
    for (i, frame) in (first..=last).enumerate() {
        let after = eval.object_at(0, f64::from(frame) / baked.fps, &none).expect("the arm");
        for j in 0..5 {
            let (a, b) = (joint_at(&before[i], j), joint_at(&after, j));
            assert!(a.distance(b) <= 1e-6 * length, "frame {frame}, joint {j}: {a:?} vs {b:?}");
            let (qa, qb) = (
                before[i].pose.as_ref().expect("a pose").local_rotations[j],
                after.pose.as_ref().expect("a pose").local_rotations[j],
            );
            let apart = (qa - qb).length().min((qa + qb).length());
            assert!(apart <= 1e-6, "frame {frame}, joint {j}: {qa:?} vs {qb:?}");
        }
    }
}

#[test]
fn bake_refuses_what_it_cannot_bake() {
    let mut s = scene(4, 2, Vec3::X, None, 1.0);
    assert_eq!(
        bake_ik_constraint(&mut s, 0, 3, 0, 10).map_err(|e| e.to_string()),
        Err("object 0 has no IK constraint 3".to_string())
    );
    assert_eq!(
        bake_ik_constraint(&mut s, 0, 0, 10, 0).map_err(|e| e.to_string()),
        Err("cannot bake frames 10..=0: the range is empty".to_string())
    );
    s.objects[0].skeleton.as_mut().expect("a skeleton").ik_constraints[0].bones = 9;
    assert_eq!(
        bake_ik_constraint(&mut s, 0, 0, 0, 10).map_err(|e| e.to_string()),
        Err("objects[0].skeleton.ik_constraints[0]: a chain of 9 bones is too long: joint 4 (\"wrist\") has 4 joint(s) above it".to_string())
    );
}
