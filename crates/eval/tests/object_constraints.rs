//! Object constraints in the scene evaluator (issue 42, item 16), checked against the
//! definitions of docs/constraints.md written out here in f64 — not by calling keyrig's
//! constraint code: the expected world transforms are composed in this file from the keys,
//! the targets and the formulas.
//!
//! ```text
//! time (s)   0          1          2
//! Hand L     ●──────────●──────────●    translation (0,1,0) → (2,1,0) → (2,1,2), turning about Y
//! Hand R     ●─────────────────────●    translation (4,1,0) → (4,3,0)
//! Prop       child of Hand L ──────┤ switched at 1.0 ├── child of Hand R
//! ```

use std::collections::HashMap;

use glam::{Affine3A, DAffine3, DMat3, DQuat, DVec3, Quat, Vec3};
use keyrig_core::channel_id::{ChannelId, ConstraintProperty};
use keyrig_core::{
    AimAxis, AimTarget, Animated, ChildOfParent, ConstraintKind, Interpolation, Joint, Key, Object,
    ObjectConstraint, RawTrack, Scene, Skeleton,
};
use keyrig_eval::{bake_object_constraints, switch_parent, Overrides, SceneEvaluator};

fn linear<T>(keys: Vec<(f64, T)>) -> RawTrack<T> {
    RawTrack::new(
        keys.into_iter().map(|(t, v)| Key::new(t, v).with_interpolation(Interpolation::Linear)).collect(),
    )
}

// ---- the definitions, in f64 ----------------------------------------------------------------

fn d3(v: Vec3) -> DVec3 {
    v.as_dvec3()
}

fn dq(q: Quat) -> DQuat {
    q.as_dquat().normalize()
}

/// Slerp the short way: a · exp(w · log(a⁻¹ · b)).
fn slerp(a: DQuat, b: DQuat, w: f64) -> DQuat {
    let b = if a.dot(b) < 0.0 { -b } else { b };
    let rel = (a.conjugate() * b).normalize();
    let angle = 2.0 * rel.xyz().length().atan2(rel.w);
    if angle.abs() < 1e-15 {
        return a;
    }
    let axis = rel.xyz().normalize();
    (a * DQuat::from_axis_angle(axis, angle * w)).normalize()
}

/// Linear keys between two times: lerp of values.
fn lerp_keys(keys: &[(f64, DVec3)], t: f64) -> DVec3 {
    if t <= keys[0].0 {
        return keys[0].1;
    }
    for w in keys.windows(2) {
        if t <= w[1].0 {
            let s = (t - w[0].0) / (w[1].0 - w[0].0);
            return w[0].1.lerp(w[1].1, s);
        }
    }
    keys.last().unwrap().1
}

fn slerp_keys(keys: &[(f64, DQuat)], t: f64) -> DQuat {
    if t <= keys[0].0 {
        return keys[0].1;
    }
    for w in keys.windows(2) {
        if t <= w[1].0 {
            let s = (t - w[0].0) / (w[1].0 - w[0].0);
            return slerp(w[0].1, w[1].1, s);
        }
    }
    keys.last().unwrap().1
}

/// R = [f, u, f × u] · [a, a_up, a × a_up]ᵀ with r = f × up / |f × up|, u = r × f.
fn aim(forward: DVec3, up: DVec3, a: DVec3, a_up: DVec3) -> DQuat {
    let f = forward.normalize();
    let r = f.cross(up).normalize();
    let u = r.cross(f);
    let world = DMat3::from_cols(f, u, f.cross(u));
    let local = DMat3::from_cols(a, a_up, a.cross(a_up));
    DQuat::from_mat3(&(world * local.transpose())).normalize()
}

fn trs(t: DVec3, r: DQuat, s: DVec3) -> DAffine3 {
    DAffine3::from_scale_rotation_translation(s, r, t)
}

// ---- comparing ------------------------------------------------------------------------------

fn assert_affine(got: &Affine3A, want: &DAffine3, eps: f64, what: &str) {
    let got = got.as_daffine3();
    let cols = |m: &DAffine3| [m.matrix3.x_axis, m.matrix3.y_axis, m.matrix3.z_axis, m.translation];
    for (i, (g, w)) in cols(&got).into_iter().zip(cols(want)).enumerate() {
        assert!(
            g.abs_diff_eq(w, eps),
            "{what}: column {i} is {g}, expected {w} (off by {})",
            (g - w).length()
        );
    }
}

fn world(eval: &SceneEvaluator, o: usize, t: f64) -> Affine3A {
    eval.object_at(o, t, &Overrides::new()).expect("the object").world_from_object
}

// ---- the scene ------------------------------------------------------------------------------

const HAND_L_T: [(f64, [f64; 3]); 3] =
    [(0.0, [0.0, 1.0, 0.0]), (1.0, [2.0, 1.0, 0.0]), (2.0, [2.0, 1.0, 2.0])];
const HAND_L_ANGLE: [(f64, f64); 2] = [(0.0, 0.0), (2.0, 1.2)];
const HAND_R_T: [(f64, [f64; 3]); 2] = [(0.0, [4.0, 1.0, 0.0]), (2.0, [4.0, 3.0, 0.0])];

type VecKeys = Vec<(f64, DVec3)>;
type QuatKeys = Vec<(f64, DQuat)>;

fn hand_l_keys() -> (VecKeys, QuatKeys) {
    (
        HAND_L_T.iter().map(|(t, v)| (*t, DVec3::from_array(*v))).collect(),
        HAND_L_ANGLE.iter().map(|(t, a)| (*t, dq(Quat::from_rotation_y(*a as f32)))).collect(),
    )
}

/// Hand L's world transform by the definition of Linear keys.
fn hand_l(t: f64) -> DAffine3 {
    let (tk, rk) = hand_l_keys();
    trs(lerp_keys(&tk, t), slerp_keys(&rk, t), DVec3::ONE)
}

fn hand_r(t: f64) -> DAffine3 {
    let tk: Vec<(f64, DVec3)> = HAND_R_T.iter().map(|(t, v)| (*t, DVec3::from_array(*v))).collect();
    trs(lerp_keys(&tk, t), DQuat::IDENTITY, DVec3::splat(2.0))
}

const PROP_T: Vec3 = Vec3::new(0.0, -0.2, 0.1);
const PROP_R: f32 = 0.3;

fn prop_own() -> DAffine3 {
    trs(d3(PROP_T), dq(Quat::from_rotation_x(PROP_R)), DVec3::ONE)
}

/// Hand L, Hand R, and a prop held by Hand L (a child-of constraint, no offset).
fn hands() -> Scene {
    let mut l = Object::new("Hand L");
    let (tk, rk) = hand_l_keys();
    l.translation.track = linear(tk.iter().map(|(t, v)| (*t, v.as_vec3())).collect());
    l.rotation.track = linear(rk.iter().map(|(t, q)| (*t, q.as_quat())).collect());
    let mut r = Object::new("Hand R");
    r.translation.track =
        linear(HAND_R_T.iter().map(|(t, v)| (*t, DVec3::from_array(*v).as_vec3())).collect());
    r.scale = Animated::constant(Vec3::splat(2.0));
    let mut prop = Object::new("Prop");
    prop.translation = Animated::constant(PROP_T);
    prop.rotation = Animated::constant(Quat::from_rotation_x(PROP_R));
    prop.constraints.push(ObjectConstraint::new(
        "Held",
        ConstraintKind::ChildOf {
            parents: vec![ChildOfParent::new(AimTarget::Object("Hand L".into()))],
            parent: Animated::constant(0.0),
        },
    ));
    Scene { objects: vec![prop, l, r], ..Scene::default() }
}

fn evaluator(scene: &Scene) -> SceneEvaluator {
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    let eval = SceneEvaluator::new(scene, &HashMap::new());
    assert!(eval.problems().is_empty(), "{:?}", eval.problems());
    eval
}

// ---- child of ------------------------------------------------------------------------------

#[test]
fn child_of_carries_the_prop_and_switches_hands_without_a_pop() {
    let mut scene = hands();
    let switch = 1.0;
    let index =
        switch_parent(&mut scene, 0, 0, switch, AimTarget::Object("Hand R".into())).expect("switches");
    assert_eq!(index, 1);
    let eval = evaluator(&scene);
    // offset_R = F_R(s)⁻¹ · F_L(s) · W  · W⁻¹ (the result under Hand L at the switch, over the
    // prop's own transform): the prop does not move at the switch.
    let offset_r = hand_r(switch).inverse() * hand_l(switch) * prop_own() * prop_own().inverse();
    for frame in 0..=60 {
        let t = f64::from(frame) / 30.0;
        let want = if t < switch { hand_l(t) * prop_own() } else { hand_r(t) * offset_r * prop_own() };
        assert_affine(&world(&eval, 0, t), &want, 2e-5, &format!("prop at {t:.3} s"));
    }
    // No pop: just before and at the switch the prop is in the same place.
    let before = world(&eval, 0, switch - 1e-6);
    let at = world(&eval, 0, switch);
    assert!(before.abs_diff_eq(at, 1e-4), "{before:?} → {at:?}");
    // The parent channel is a keyed STEP channel: 0 before, 1 from the switch on.
    let parent = ChannelId::Constraint { object: 0, constraint: 0, property: ConstraintProperty::Parent };
    let at_time = |t| match eval.value(parent, t, &Overrides::new()) {
        Some(keyrig_core::channel_id::ChannelValue::Scalar(v)) => v,
        other => panic!("{other:?}"),
    };
    assert_eq!((at_time(0.5), at_time(0.99), at_time(1.0), at_time(1.7)), (0.0, 0.0, 1.0, 1.0));
    // And back to Hand L at 1.5 s: a third parent entry, again without a pop.
    let back =
        switch_parent(&mut scene, 0, 0, 1.5, AimTarget::Object("Hand L".into())).expect("switches back");
    assert_eq!(back, 2);
    let eval = evaluator(&scene);
    let offset_l2 = hand_l(1.5).inverse() * hand_r(1.5) * offset_r * prop_own() * prop_own().inverse();
    assert_affine(&world(&eval, 0, 1.8), &(hand_l(1.8) * offset_l2 * prop_own()), 2e-5, "back in Hand L");
    assert!(world(&eval, 0, 1.5 - 1e-6).abs_diff_eq(world(&eval, 0, 1.5), 1e-4));
}

#[test]
fn child_of_influence_blends_decomposed_transforms() {
    let mut scene = hands();
    scene.objects[0].constraints[0].influence = Animated::constant(0.25);
    let eval = evaluator(&scene);
    for t in [0.0, 0.7, 1.3, 2.0] {
        let own = prop_own();
        let full = hand_l(t) * own;
        let (s0, r0, t0) = own.to_scale_rotation_translation();
        let (s1, r1, t1) = full.to_scale_rotation_translation();
        let want = trs(t0.lerp(t1, 0.25), slerp(r0, r1, 0.25), s0.lerp(s1, 0.25));
        assert_affine(&world(&eval, 0, t), &want, 2e-5, &format!("quarter influence at {t}"));
    }
}

#[test]
fn no_parent_and_a_missing_parent_leave_the_own_transform() {
    let mut scene = hands();
    if let ConstraintKind::ChildOf { parent, .. } = &mut scene.objects[0].constraints[0].kind {
        *parent = Animated::constant(-1.0);
    }
    let eval = evaluator(&scene);
    assert_affine(&world(&eval, 0, 0.5), &prop_own(), 1e-6, "no parent");
}

// ---- aim, copy, follow path ---------------------------------------------------------------

#[test]
fn aim_at_points_the_axis_at_the_target_with_keyed_influence() {
    let mut scene = hands();
    scene.objects[0].constraints.clear();
    let mut looker = Object::new("Looker");
    looker.translation = Animated::constant(Vec3::new(1.0, 0.0, 3.0));
    looker.rotation = Animated::constant(Quat::from_rotation_z(0.4));
    let mut c = ObjectConstraint::new(
        "Watch",
        ConstraintKind::AimAt {
            target: AimTarget::Object("Hand L".into()),
            axis: AimAxis::PosX,
            up: Vec3::Y,
        },
    );
    c.influence.track = linear(vec![(0.0, 0.0), (2.0, 1.0)]);
    looker.constraints.push(c);
    scene.objects.insert(0, looker);
    let eval = evaluator(&scene);
    let own_r = dq(Quat::from_rotation_z(0.4));
    let eye = DVec3::new(1.0, 0.0, 3.0);
    for frame in 0..=60 {
        let t = f64::from(frame) / 30.0;
        let target = hand_l(t).translation;
        let full = aim(target - eye, DVec3::Y, DVec3::X, DVec3::Y);
        let want = trs(eye, slerp(own_r, full, t / 2.0), DVec3::ONE);
        assert_affine(&world(&eval, 0, t), &want, 2e-5, &format!("looker at {t:.3} s"));
    }
    // At full influence its +X points at the target.
    let w = world(&eval, 0, 2.0);
    let x = w.transform_vector3(Vec3::X).as_dvec3();
    assert!(x.abs_diff_eq((hand_l(2.0).translation - eye).normalize(), 1e-5), "{x}");
}

/// A three-joint skeleton along +Y (rest translations only): joint j's model position is the
/// sum of the rest translations up to it.
fn arm_with_skeleton() -> Object {
    let joints = vec![
        Joint::new("root", None, Vec3::new(0.0, 0.5, 0.0), Quat::IDENTITY),
        Joint::new("elbow", Some(0), Vec3::new(0.0, 1.0, 0.0), Quat::IDENTITY),
        Joint::new("hand", Some(1), Vec3::new(0.0, 1.0, 0.5), Quat::IDENTITY),
    ];
    let mut arm = Object::new("Arm");
    arm.translation.track = linear(vec![(0.0, Vec3::new(-2.0, 0.0, 0.0)), (2.0, Vec3::new(-2.0, 0.0, 4.0))]);
    arm.rotation = Animated::constant(Quat::from_rotation_z(0.5));
    arm.scale = Animated::constant(Vec3::splat(1.5));
    arm.skeleton = Some(Skeleton::new(joints));
    arm
}

fn arm_world(t: f64) -> DAffine3 {
    trs(
        lerp_keys(&[(0.0, DVec3::new(-2.0, 0.0, 0.0)), (2.0, DVec3::new(-2.0, 0.0, 4.0))], t),
        dq(Quat::from_rotation_z(0.5)),
        DVec3::splat(1.5),
    )
}

#[test]
fn copy_location_from_a_joint_and_copy_rotation_from_an_object() {
    let mut scene = hands();
    scene.objects[0].constraints.clear();
    scene.objects.push(arm_with_skeleton());
    let mut follower = Object::new("Follower");
    follower.rotation = Animated::constant(Quat::from_rotation_x(-0.3));
    follower.scale = Animated::constant(Vec3::new(1.0, 2.0, 1.0));
    follower.constraints.push(ObjectConstraint::new(
        "On hand",
        ConstraintKind::CopyLocation {
            target: AimTarget::Joint { object: "Arm".into(), joint: "hand".into() },
        },
    ));
    let mut turn = ObjectConstraint::new(
        "Turn like L",
        ConstraintKind::CopyRotation { target: AimTarget::Object("Hand L".into()) },
    );
    turn.influence = Animated::constant(0.5);
    follower.constraints.push(turn);
    scene.objects.insert(0, follower);
    let eval = evaluator(&scene);
    let hand_in_model = DVec3::new(0.0, 0.5, 0.0) + DVec3::new(0.0, 1.0, 0.0) + DVec3::new(0.0, 1.0, 0.5);
    for t in [0.0, 0.4, 1.0, 1.6, 2.0] {
        let at = arm_world(t).transform_point3(hand_in_model);
        let (_, hand_r, _) = hand_l(t).to_scale_rotation_translation();
        let r = slerp(dq(Quat::from_rotation_x(-0.3)), hand_r, 0.5);
        let want = trs(at, r, DVec3::new(1.0, 2.0, 1.0));
        assert_affine(&world(&eval, 0, t), &want, 2e-5, &format!("follower at {t}"));
    }
}

#[test]
fn follow_path_by_arc_length_turning_along_the_path() {
    let mut scene = Scene::default();
    let mut space = Object::new("Track");
    space.translation = Animated::constant(Vec3::new(0.0, 1.0, 0.0));
    space.rotation = Animated::constant(Quat::from_rotation_y(std::f32::consts::FRAC_PI_2));
    let mut car = Object::new("Car");
    car.translation = Animated::constant(Vec3::new(9.0, 9.0, 9.0));
    let mut offset = Animated::constant(0.0);
    offset.track = linear(vec![(0.0, 0.0), (2.0, 1.0)]);
    car.constraints.push(ObjectConstraint::new(
        "Drive",
        ConstraintKind::FollowPath {
            points: vec![Vec3::ZERO, Vec3::new(3.0, 0.0, 0.0), Vec3::new(3.0, 0.0, 1.0)],
            space: Some("Track".into()),
            offset,
            axis: Some(AimAxis::PosX),
        },
    ));
    scene.objects = vec![car, space];
    let eval = evaluator(&scene);
    let space_w = trs(DVec3::Y, dq(Quat::from_rotation_y(std::f32::consts::FRAC_PI_2)), DVec3::ONE);
    // Length 3 + 1 = 4: the corner is at offset 0.75 (t = 1.5 s).
    for frame in 0..=60 {
        let t = f64::from(frame) / 30.0;
        let s = 4.0 * (t / 2.0);
        let (p, d) = if s <= 3.0 {
            (DVec3::new(s, 0.0, 0.0), DVec3::X)
        } else {
            (DVec3::new(3.0, 0.0, s - 3.0), DVec3::Z)
        };
        let at = space_w.transform_point3(p);
        let r = aim(space_w.transform_vector3(d), DVec3::Y, DVec3::X, DVec3::Y);
        assert_affine(&world(&eval, 0, t), &trs(at, r, DVec3::ONE), 2e-5, &format!("car at {t:.3} s"));
    }
}

// ---- order, cycles, problems -------------------------------------------------------------

#[test]
fn targets_are_evaluated_first_and_evaluate_agrees_with_object_at() {
    // Object 0 copies object 1's location; object 1 is a child of object 2 (Hand L).
    let mut scene = hands();
    let mut first = Object::new("First");
    first.constraints.push(ObjectConstraint::new(
        "Stick",
        ConstraintKind::CopyLocation { target: AimTarget::Object("Prop".into()) },
    ));
    scene.objects.insert(0, first);
    let eval = evaluator(&scene);
    for t in [0.0, 0.5, 1.25, 2.0] {
        let state = eval.evaluate(t, &Overrides::new());
        let want = trs((hand_l(t) * prop_own()).translation, DQuat::IDENTITY, DVec3::ONE);
        assert_affine(&state.objects[0].world_from_object, &want, 2e-5, "evaluate");
        assert_affine(&world(&eval, 0, t), &want, 2e-5, "object_at");
        assert_eq!(state.objects[1].world_from_object, world(&eval, 1, t));
    }
}

#[test]
fn a_cycle_is_a_problem_and_evaluates_without_constraints() {
    let mut scene = Scene::default();
    let mut a = Object::new("A");
    a.translation = Animated::constant(Vec3::X);
    a.constraints.push(ObjectConstraint::new(
        "L",
        ConstraintKind::CopyLocation { target: AimTarget::Object("B".into()) },
    ));
    let mut b = Object::new("B");
    b.translation = Animated::constant(Vec3::Y);
    b.constraints.push(ObjectConstraint::new(
        "L",
        ConstraintKind::CopyLocation { target: AimTarget::Object("A".into()) },
    ));
    scene.objects = vec![a, b];
    let problems = scene.problems();
    assert!(
        problems.iter().any(|p| p.path == "objects[0].constraints" && p.message.contains("cycle")),
        "{problems:?}"
    );
    let eval = SceneEvaluator::new(&scene, &HashMap::new());
    assert!(eval.problems().iter().any(|p| p.message.contains("cycle")), "{:?}", eval.problems());
    let state = eval.evaluate(0.5, &Overrides::new());
    assert_eq!(Vec3::from(state.objects[0].world_from_object.translation), Vec3::X);
    assert_eq!(Vec3::from(world(&eval, 1, 0.5).translation), Vec3::Y);
}

#[test]
fn validation_names_each_field() {
    let mut scene = hands();
    let mut bad = ObjectConstraint::new(
        "Self",
        ConstraintKind::AimAt {
            target: AimTarget::Object("Prop".into()),
            axis: AimAxis::NegZ,
            up: Vec3::ZERO,
        },
    );
    bad.influence = Animated::constant(1.5);
    scene.objects[0].constraints.push(bad);
    scene.objects[0].constraints.push(ObjectConstraint::new(
        "Lost",
        ConstraintKind::CopyRotation {
            target: AimTarget::Joint { object: "Hand L".into(), joint: "thumb".into() },
        },
    ));
    scene.objects[0].constraints.push(ObjectConstraint::new(
        "Path",
        ConstraintKind::FollowPath {
            points: vec![Vec3::ZERO],
            space: None,
            offset: Animated::constant(0.0),
            axis: None,
        },
    ));
    let problems: Vec<String> = scene.problems().iter().map(ToString::to_string).collect();
    let expect = [
        "objects[0].constraints[1].influence.value: influence 1.5 is outside [0, 1]",
        "objects[0].constraints[1].kind.target: \"Prop\" cannot be constrained to itself",
        "objects[0].constraints[1].kind.up: zero up direction",
        "objects[0].constraints[2].kind.target: object \"Hand L\" has no joint named \"thumb\" to constrain to",
        "objects[0].constraints[3].kind.points: a path needs at least 2 points; it has 1",
    ];
    for e in expect {
        assert!(problems.iter().any(|p| p == e), "missing {e:?} in {problems:#?}");
    }
    // Evaluating such a scene neither panics nor loops.
    let eval = SceneEvaluator::new(&scene, &HashMap::new());
    let _ = eval.evaluate(0.5, &Overrides::new());
}

// ---- baking --------------------------------------------------------------------------------

#[test]
fn baking_reproduces_every_frame_and_removes_the_constraints() {
    let mut scene = hands();
    switch_parent(&mut scene, 0, 0, 1.0, AimTarget::Object("Hand R".into())).expect("switches");
    let mut looker = Object::new("Looker");
    looker.translation = Animated::constant(Vec3::new(1.0, 0.0, 3.0));
    looker.constraints.push(ObjectConstraint::new(
        "Watch",
        ConstraintKind::AimAt { target: AimTarget::Object("Prop".into()), axis: AimAxis::NegZ, up: Vec3::Y },
    ));
    scene.objects.push(looker);
    let eval = evaluator(&scene);
    let mut baked = scene.clone();
    assert_eq!(bake_object_constraints(&mut baked, 0, 60), Ok(2));
    assert!(baked.objects.iter().all(|o| o.constraints.is_empty()));
    let baked_eval = evaluator(&baked);
    for frame in 0..=60 {
        let t = f64::from(frame) / 30.0;
        for o in [0, 3] {
            let (want, got) = (world(&eval, o, t), world(&baked_eval, o, t));
            assert!(want.abs_diff_eq(got, 1e-5), "object {o} at frame {frame}: {want:?} vs {got:?}");
        }
    }
}

// ---- a camera's aim, keyable --------------------------------------------------------------

#[test]
fn a_cameras_aim_has_a_keyed_influence() {
    use keyrig_core::{Aim, SceneCamera};
    let mut scene = hands();
    let mut camera = SceneCamera::new("Dolly", Vec3::new(0.0, 2.0, 6.0));
    camera.rotation = Animated::constant(Quat::from_rotation_y(0.3));
    let mut looking = Aim::at(AimTarget::Object("Hand L".into()));
    looking.influence.track = linear(vec![(0.0, 0.0), (2.0, 1.0)]);
    camera.aim = Some(looking);
    scene.cameras.push(camera);
    let eval = evaluator(&scene);
    let eye = DVec3::new(0.0, 2.0, 6.0);
    for frame in [0, 15, 30, 45, 60] {
        let t = f64::from(frame) / 30.0;
        // The aim is an aim at with axis −Z and +Y up, blended from the keyed rotation.
        let aimed = aim(hand_l(t).translation - eye, DVec3::Y, DVec3::NEG_Z, DVec3::Y);
        let want = trs(eye, slerp(dq(Quat::from_rotation_y(0.3)), aimed, t / 2.0), DVec3::ONE);
        let state = eval.evaluate(t, &Overrides::new());
        assert_affine(&state.cameras[0].world_from_camera, &want, 2e-5, &format!("camera at {t}"));
        let alone = eval.camera_at(0, t, &Overrides::new()).expect("the camera");
        assert!(alone.world_from_camera.abs_diff_eq(state.cameras[0].world_from_camera, 1e-6));
    }
}
