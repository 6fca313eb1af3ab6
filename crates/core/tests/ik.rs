//! Inverse kinematics (issue 19, `keyrig_core::ik`; docs/ik.md).
//!
//! Every check measures the solved chain by its own forward kinematics, written here with
//! affine matrices (the solver uses quaternions and vectors), from the rotations the solver
//! returns:
//!
//! ```text
//!   world_from_parent · T(o_0)·R(r_0)·R(q_0) · T(o_1)·R(r_1)·R(q_1) · T(o_2) …
//!   root ●────── bone 0 ──────● middle ────── bone 1 ──────● end (hand)
//! ```

use std::f64::consts::PI;

use glam::{Affine3A, DAffine3, DQuat, DVec3, Quat, Vec3};
use keyrig_core::ik::{
    chain_joints, solve_fabrik, solve_two_bone, FabrikSettings, IkChain, IkError, IkReport, Pole, REACH_SLACK,
};
use keyrig_core::{Joint, Skeleton};
use proptest::collection::vec;
use proptest::prelude::*;

/// A chain's inputs, owned.
#[derive(Clone, Debug)]
struct Rig {
    world_from_parent: Affine3A,
    translations: Vec<Vec3>,
    rest: Vec<Quat>,
    rotations: Vec<Quat>,
}

impl Rig {
    fn chain(&self) -> IkChain<'_> {
        IkChain {
            world_from_parent: self.world_from_parent,
            translations: &self.translations,
            rest_rotations: &self.rest,
            rotations: &self.rotations,
        }
    }

    fn bone_lengths(&self) -> Vec<f64> {
        self.translations[1..].iter().map(|t| t.as_dvec3().length()).collect()
    }

    /// The chain's length in the parent's frame.
    fn reach(&self) -> f64 {
        self.bone_lengths().iter().sum()
    }

    /// Shortest reach: a bone longer than all the others together cannot fold back to the root.
    fn shortest(&self) -> f64 {
        let lengths = self.bone_lengths();
        let longest = lengths.iter().copied().fold(0.0, f64::max);
        (2.0 * longest - self.reach()).max(0.0)
    }

    fn world(&self) -> DAffine3 {
        self.world_from_parent.as_daffine3()
    }

    /// Uniform scale of the parent transform (the tests that use it build uniform ones).
    fn scale(&self) -> f64 {
        self.world().matrix3.determinant().cbrt()
    }

    /// A point `distance` (parent-frame units) from the root along `direction` (parent frame),
    /// in world space.
    fn world_target(&self, direction: DVec3, distance: f64) -> Vec3 {
        let local = self.translations[0].as_dvec3() + direction.normalize() * distance;
        self.world().transform_point3(local).as_vec3()
    }

    /// World positions of the joints posed by `rotations`.
    fn positions(&self, rotations: &[Quat]) -> Vec<DVec3> {
        let mut m = self.world();
        let mut out = Vec::new();
        for (i, t) in self.translations.iter().enumerate() {
            m *= DAffine3::from_translation(t.as_dvec3());
            out.push(m.translation);
            m *= DAffine3::from_quat(self.rest[i].as_dquat().normalize())
                * DAffine3::from_quat(rotations[i].as_dquat().normalize());
        }
        out
    }
}

fn unit_dir() -> impl Strategy<Value = DVec3> {
    (-1.0..1.0f64, -1.0..1.0f64, -1.0..1.0f64)
        .prop_filter("direction", |(x, y, z)| DVec3::new(*x, *y, *z).length() > 0.1)
        .prop_map(|(x, y, z)| DVec3::new(x, y, z).normalize())
}

fn unit_quat() -> impl Strategy<Value = Quat> {
    (unit_dir(), -PI..PI).prop_map(|(axis, angle)| DQuat::from_axis_angle(axis, angle).as_quat())
}

/// A chain of `bones` bones, 0.2–2 long, in any pose, under a rotated, moved and uniformly
/// scaled parent.
fn rig(bones: std::ops::RangeInclusive<usize>) -> impl Strategy<Value = Rig> {
    bones.prop_flat_map(|n| {
        (
            (unit_quat(), vec(-5.0..5.0f32, 3), 0.5..2.0f32),
            vec(-1.0..1.0f32, 3),
            vec((unit_dir(), 0.2..2.0f64), n),
            vec(unit_quat(), n + 1),
            vec(unit_quat(), n + 1),
        )
            .prop_map(|((pr, pt, ps), root, bones, rest, rotations)| {
                let mut translations = vec![Vec3::from_slice(&root)];
                translations.extend(bones.iter().map(|(dir, len)| (*dir * *len).as_vec3()));
                Rig {
                    world_from_parent: Affine3A::from_scale_rotation_translation(
                        Vec3::splat(ps),
                        pr,
                        Vec3::from_slice(&pt),
                    ),
                    translations,
                    rest,
                    rotations,
                }
            })
    })
}

/// The demo-like arm: upper arm 1.0 and forearm 0.8 along +X, bent up (+Y) at the elbow, at the
/// origin of an identity parent; its plane is z = 0.
fn arm() -> Rig {
    Rig {
        world_from_parent: Affine3A::IDENTITY,
        translations: vec![Vec3::ZERO, Vec3::new(1.0, 0.0, 0.0), Vec3::new(0.8, 0.0, 0.0)],
        rest: vec![Quat::IDENTITY; 3],
        rotations: vec![Quat::from_rotation_z(0.3), Quat::from_rotation_z(-0.9), Quat::IDENTITY],
    }
}

fn two_bone(rig: &Rig, target: Vec3, pole: Pole) -> (Vec<Quat>, IkReport) {
    let mut out = vec![Quat::NAN; rig.translations.len()];
    let report = solve_two_bone(&rig.chain(), target, pole, &mut out).expect("valid chain");
    (out, report)
}

fn fabrik(rig: &Rig, target: Vec3, pole: Option<Pole>) -> (Vec<Quat>, IkReport) {
    let mut out = vec![Quat::NAN; rig.translations.len()];
    let report =
        solve_fabrik(&rig.chain(), target, pole, &FabrikSettings::default(), &mut out).expect("valid chain");
    (out, report)
}

/// The angle of the rotation between two unit quaternions (radians, in [0, π]).
fn rotation_angle(a: Quat, b: Quat) -> f64 {
    let dot = a.as_dquat().normalize().dot(b.as_dquat().normalize()).abs().min(1.0);
    2.0 * dot.acos()
}

/// The component of `v` perpendicular to the unit vector `axis`.
fn reject(v: DVec3, axis: DVec3) -> DVec3 {
    v - axis * v.dot(axis)
}

/// A point of the chain parent's frame in world space, as the pole of `rig`.
fn world_pole(rig: &Rig, local: DVec3) -> Vec3 {
    rig.world().transform_point3(local).as_vec3()
}

// ---------------------------------------------------------------------------------------------
// Two-bone solver
// ---------------------------------------------------------------------------------------------

proptest! {
    #![proptest_config(ProptestConfig::with_cases(512))]

    /// Targets within the reach are reached within 1e-5 of the chain's length, the middle joint
    /// is where the law of cosines (computed here in f64) puts it, on the pole's side.
    #[test]
    fn two_bone_reaches_and_agrees_with_the_law_of_cosines(
        rig in rig(2..=2),
        direction in unit_dir(),
        fraction in 0.0..1.0f64,
        pole_local in vec(-3.0..3.0f64, 3),
    ) {
        let [l1, l2] = rig.bone_lengths()[..] else { unreachable!() };
        let (lo, hi) = ((l1 - l2).abs(), l1 + l2);
        let d = lo + (hi - lo) * fraction;
        let target = rig.world_target(direction, d);
        let root = rig.translations[0].as_dvec3();
        let pole_local = DVec3::from_slice(&pole_local);
        let pole_perp = reject(pole_local - root, direction);
        prop_assume!(pole_perp.length() > 0.05 && d > 1e-3);
        let (out, report) = two_bone(&rig, target, Pole::Point(world_pole(&rig, pole_local)));
        let s = rig.scale();
        let length = s * hi;
        let p = rig.positions(&out);
        prop_assert!(report.reachable);
        prop_assert!(p[2].distance(target.as_dvec3()) <= 1e-5 * length, "end {} target {target} ({report:?})", p[2]);
        prop_assert!(report.distance <= 1e-5 * length);
        // Law of cosines, in the parent's frame, for the target and pole as given (rounded to
        // f32, which matters where the elbow is ill-conditioned, near full extension): x along
        // the root→target axis, h towards the pole.
        let local = rig.world().inverse();
        let to_target = local.transform_point3(target.as_dvec3()) - root;
        let (d, direction) = (to_target.length().clamp(lo, hi), to_target.normalize());
        let v = reject(local.transform_point3(world_pole(&rig, pole_local).as_dvec3()) - root, direction).normalize();
        let x = (l1 * l1 - l2 * l2 + d * d) / (2.0 * d);
        let h = (l1 * l1 - x * x).max(0.0).sqrt();
        let elbow = rig.world().transform_point3(root + direction * x + v * h);
        prop_assert!(p[1].distance(elbow) <= 1e-5 * length, "elbow {} expected {elbow}", p[1]);
        // The elbow's inner angle: cos C = (l1² + l2² − d²)/(2·l1·l2).
        let inner = (p[0] - p[1]).angle_between(p[2] - p[1]);
        let expected = ((l1 * l1 + l2 * l2 - d * d) / (2.0 * l1 * l2)).clamp(-1.0, 1.0).acos();
        prop_assert!((inner - expected).abs() <= 1e-3, "inner angle {inner} expected {expected}");
        // The pole's side of the root→target line.
        let u = (target.as_dvec3() - p[0]).normalize();
        let side = reject(p[1] - p[0], u).dot(reject(world_pole(&rig, pole_local).as_dvec3() - p[0], u));
        prop_assert!(side >= -1e-6 * length * length, "elbow on the far side: {side}");
    }

    /// Beyond the reach the chain is straight and points at the target.
    #[test]
    fn two_bone_unreachable_is_straight_at_the_target(
        rig in rig(2..=2),
        direction in unit_dir(),
        beyond in 1.0001..5.0f64,
        pole in vec(-3.0..3.0f32, 3),
    ) {
        let target = rig.world_target(direction, rig.reach() * beyond);
        let (out, report) = two_bone(&rig, target, Pole::Point(Vec3::from_slice(&pole)));
        prop_assert!(!report.reachable);
        assert_straight_at(&rig, &out, target)?;
        prop_assert!((report.distance - rig.scale() * rig.reach() * (beyond - 1.0)).abs() <= 1e-5 * rig.scale() * rig.reach());
    }

    /// Each joint's new rotation is its old one turned by the smallest rotation that moves its
    /// bone (q' = swing·q with the swing about an axis perpendicular to the bone): the twist
    /// about the bone's axis is kept.
    #[test]
    fn two_bone_keeps_each_joints_twist(
        rig in rig(2..=2),
        direction in unit_dir(),
        fraction in 0.05..0.95f64,
        pole in vec(-3.0..3.0f32, 3),
    ) {
        let target = rig.world_target(direction, rig.reach() * fraction);
        let (out, _) = two_bone(&rig, target, Pole::Point(Vec3::from_slice(&pole)));
        assert_swings(&rig, &out)?;
    }

    /// Twisting the root joint about its bone in the input twists the result the same way.
    #[test]
    fn two_bone_carries_an_input_twist_through(
        rig in rig(2..=2),
        direction in unit_dir(),
        fraction in 0.05..0.95f64,
        pole in vec(-3.0..3.0f64, 3),
        twist in -3.0..3.0f64,
    ) {
        let pole = DVec3::from_slice(&pole);
        let root = rig.translations[0].as_dvec3();
        prop_assume!(reject(pole - root, direction).length() > 0.05);
        let target = rig.world_target(direction, rig.reach() * fraction);
        let pole = Pole::Point(world_pole(&rig, pole));
        let (plain, _) = two_bone(&rig, target, pole);
        let axis = rig.translations[1].as_dvec3().normalize();
        // Near a half turn the smallest rotation's axis swings with the input's rounding.
        let (before, after) = (rig.rotations[0].as_dquat() * axis, plain[0].as_dquat() * axis);
        prop_assume!(before.normalize().dot(after.normalize()) > -0.9);
        let mut twisted = rig.clone();
        twisted.rotations[0] = (rig.rotations[0].as_dquat() * DQuat::from_axis_angle(axis, twist)).as_quat();
        let (out, _) = two_bone(&twisted, target, pole);
        let expected = plain[0].as_dquat() * DQuat::from_axis_angle(axis, twist);
        prop_assert!(rotation_angle(out[0], expected.as_quat()) <= 1e-5, "{:?} vs {:?}", out[0], expected);
    }

    /// Solving again from the solved pose changes nothing.
    #[test]
    fn two_bone_is_idempotent(rig in rig(2..=2), direction in unit_dir(), fraction in 0.05..0.95f64) {
        let target = rig.world_target(direction, rig.reach() * fraction);
        let pole = Pole::Swivel { angle: 0.4, reference: Vec3::Y };
        let (first, _) = two_bone(&rig, target, pole);
        let mut again = rig.clone();
        again.rotations = first.clone();
        let (second, _) = two_bone(&again, target, pole);
        for (a, b) in first.iter().zip(&second) {
            prop_assert!(rotation_angle(*a, *b) <= 1e-5);
        }
    }

    /// A swivel angle turns the bend plane about the root→target axis from the reference.
    #[test]
    fn swivel_turns_the_bend_plane(
        direction in unit_dir(),
        reference in unit_dir(),
        angle in -3.1..3.1f32,
        fraction in 0.1..0.9f64,
    ) {
        let rig = arm();
        prop_assume!(reject(reference, direction).length() > 0.05);
        let (lo, hi) = (rig.shortest(), rig.reach());
        let target = rig.world_target(direction, lo + (hi - lo) * fraction);
        let (out, _) = two_bone(&rig, target, Pole::Swivel { angle, reference: reference.as_vec3() });
        let p = rig.positions(&out);
        let v0 = reject(reference, direction).normalize();
        let a = f64::from(angle);
        let expected = v0 * a.cos() + direction.cross(v0) * a.sin();
        let bend = reject(p[1] - p[0], direction).normalize();
        prop_assert!(bend.distance(expected) <= 1e-5, "bend {bend} expected {expected}");
    }
}

/// An arm in centimetres (upper arm 60, forearm 40, bent at the elbow): a chain whose length is
/// far from 1, so that tolerances relative to it differ from absolute ones.
fn long_arm() -> Rig {
    Rig { translations: vec![Vec3::ZERO, Vec3::new(60.0, 0.0, 0.0), Vec3::new(40.0, 0.0, 0.0)], ..arm() }
}

/// The inner edge of the reach (a forearm shorter than the upper arm cannot bring the hand
/// nearer the shoulder than their difference) has the same slack as the outer one: 1e-6 of the
/// chain's length.
#[test]
fn two_bone_reach_slack_is_relative_to_the_chain_length() {
    let rig = long_arm();
    let (reach, shortest) = (rig.reach(), rig.shortest());
    assert_eq!((reach, shortest), (100.0, 20.0));
    let pole = Pole::Point(Vec3::new(0.0, 50.0, 0.0));
    for (distance, reachable) in [
        (shortest - 0.5 * REACH_SLACK * reach, true),
        (shortest - 20.0 * REACH_SLACK * reach, false),
        (reach + 0.5 * REACH_SLACK * reach, true),
        (reach + 20.0 * REACH_SLACK * reach, false),
    ] {
        let (_, report) = two_bone(&rig, Vec3::new(distance as f32, 0.0, 0.0), pole);
        assert_eq!(report.reachable, reachable, "target {distance} from the root");
    }
}

/// A target on the root (within 1e-9 of the chain's length: no direction the solver can trust)
/// folds the chain along its current root→end axis, wherever rounding put the target.
#[test]
fn two_bone_target_on_the_root_keeps_the_chains_direction() {
    let rig = long_arm();
    let before = rig.positions(&rig.rotations);
    let axis = (before[2] - before[0]).normalize();
    let upper = (before[1] - before[0]).normalize();
    assert!(axis.angle_between(upper) > 0.1, "the arm is bent");
    let across = axis.any_orthonormal_vector();
    for offset in [DVec3::ZERO, across * 1e-8, -axis * 1e-8] {
        let target = (before[0] + offset).as_vec3();
        let (rotations, _) = two_bone(&rig, target, Pole::Point(Vec3::new(0.0, 0.0, 50.0)));
        let after = rig.positions(&rotations);
        let end = after[2] - after[0];
        assert!((end.length() - rig.shortest()).abs() < 1e-4, "offset {offset}: end at {}", end.length());
        assert!(end.normalize().angle_between(axis) < 1e-5, "offset {offset}: end {end}, axis {axis}");
    }
}

#[test]
fn two_bone_bends_towards_the_pole_on_either_side() {
    let rig = arm();
    let target = Vec3::new(1.2, 0.2, 0.0);
    for (pole, side) in [(Vec3::new(0.5, 0.0, 2.0), DVec3::Z), (Vec3::new(0.5, 0.0, -2.0), -DVec3::Z)] {
        let (out, _) = two_bone(&rig, target, Pole::Point(pole));
        let p = rig.positions(&out);
        let u = (target.as_dvec3() - p[0]).normalize();
        let bend = reject(p[1] - p[0], u).normalize();
        assert!(bend.dot(side) > 0.99, "pole {pole}: bend {bend}");
    }
}

/// The target passes through the chain's plane (z = 0) on a straight line while the pole
/// stays put: the joint rotations change by a small angle per step (no flip), whether each step
/// starts from the previous solution (a drag) or from the same pose.
#[test]
fn two_bone_sweep_through_the_chain_plane_is_continuous() {
    let base = arm();
    let pole = Pole::Point(Vec3::new(0.6, 1.5, 0.0));
    let steps = 2000;
    for feed_back in [true, false] {
        for (from, to) in [
            (Vec3::new(1.2, 0.3, -1.0), Vec3::new(1.2, 0.3, 1.0)),
            (Vec3::new(0.4, -0.5, -1.2), Vec3::new(1.0, 0.8, 1.1)),
            (Vec3::new(-0.5, 0.2, -1.0), Vec3::new(-0.4, -0.3, 1.0)),
        ] {
            let mut rig = base.clone();
            let mut previous: Option<Vec<Quat>> = None;
            let mut worst = 0.0f64;
            for k in 0..=steps {
                let target = from.lerp(to, k as f32 / steps as f32);
                let (out, report) = two_bone(&rig, target, pole);
                assert!(report.distance < 1e-5, "step {k}: {report:?}");
                if let Some(prev) = &previous {
                    for (j, (a, b)) in prev.iter().zip(&out).enumerate() {
                        let change = rotation_angle(*a, *b);
                        worst = worst.max(change);
                        assert!(
                            change < 0.02,
                            "feed back {feed_back}, {from}→{to}, step {k}, joint {j}: {change} rad"
                        );
                        if feed_back {
                            assert!(a.dot(*b) > 0.0, "quaternion sign flipped at step {k}, joint {j}");
                        }
                    }
                }
                if feed_back {
                    rig.rotations = out.clone();
                }
                previous = Some(out);
            }
            assert!(worst > 0.0);
        }
    }
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    /// Random paths of the target inside the reach (an arc about the root, the distance changing
    /// linearly), with a pole kept away from every root→target line of the path: a drag gives
    /// continuous rotations.
    #[test]
    fn two_bone_random_sweeps_are_continuous(
        rig in rig(2..=2),
        a in (unit_dir(), 0.15..0.85f64),
        b in (unit_dir(), 0.15..0.85f64),
        tilt in (unit_dir(), 0.0..0.8f64),
    ) {
        let [l1, l2] = rig.bone_lengths()[..] else { unreachable!() };
        let (lo, hi) = ((l1 - l2).abs(), l1 + l2);
        let root = rig.translations[0].as_dvec3();
        let normal = a.0.cross(b.0);
        prop_assume!(normal.length() > 0.05);
        let pole = (normal.normalize() + tilt.0 * tilt.1).normalize();
        let pole_local = root + pole * 2.0 * hi;
        let steps = 400;
        let arc = DQuat::from_rotation_arc(a.0, b.0);
        let path: Vec<DVec3> = (0..=steps)
            .map(|k| {
                let s = k as f64 / steps as f64;
                let direction = DQuat::IDENTITY.slerp(arc, s) * a.0;
                root + direction * (lo + (hi - lo) * (a.1 + (b.1 - a.1) * s))
            })
            .collect();
        for t in &path {
            prop_assume!(reject(pole, (*t - root).normalize()).length() > 0.3);
        }
        let mut drag = rig.clone();
        let mut previous: Option<Vec<Quat>> = None;
        for (k, t) in path.iter().enumerate() {
            let target = rig.world().transform_point3(*t).as_vec3();
            let (out, report) = two_bone(&drag, target, Pole::Point(world_pole(&rig, pole_local)));
            prop_assert!(report.distance <= 1e-5 * rig.scale() * hi);
            if let Some(prev) = &previous {
                for (j, (p, q)) in prev.iter().zip(&out).enumerate() {
                    let change = rotation_angle(*p, *q);
                    prop_assert!(change < 0.1, "step {k}, joint {j}: {change} rad");
                }
            }
            drag.rotations = out.clone();
            previous = Some(out);
        }
    }
}

// ---------------------------------------------------------------------------------------------
// FABRIK
// ---------------------------------------------------------------------------------------------

proptest! {
    #![proptest_config(ProptestConfig::with_cases(256))]

    /// Chains of 2 to 10 bones reach targets anywhere inside their reach (up to its edges, where
    /// FABRIK alone converges slowly) within 1e-5 of their length, with and without a pole, and
    /// whether the passes converge or stop early and the finish closes the gap; every joint
    /// keeps its twist.
    #[test]
    fn fabrik_reaches_reachable_targets(
        rig in rig(2..=10),
        direction in unit_dir(),
        fraction in prop_oneof![0.0..=1.0f64, Just(0.0), Just(1e-4), Just(0.9999), Just(1.0)],
        pole in prop::option::of(vec(-3.0..3.0f32, 3)),
        max_iterations in prop_oneof![Just(1u32), Just(4), Just(64)],
    ) {
        let (lo, hi) = (rig.shortest(), rig.reach());
        let d = lo + (hi - lo) * fraction;
        let target = rig.world_target(direction, d);
        let settings = FabrikSettings { max_iterations, ..FabrikSettings::default() };
        let mut out = vec![Quat::NAN; rig.translations.len()];
        let pole = pole.map(|p| Pole::Point(Vec3::from_slice(&p)));
        let report = solve_fabrik(&rig.chain(), target, pole, &settings, &mut out).expect("valid chain");
        let length = rig.scale() * hi;
        let end = *rig.positions(&out).last().unwrap();
        prop_assert!(report.reachable);
        prop_assert!(end.distance(target.as_dvec3()) <= 1e-5 * length, "end {end} target {target} {report:?}");
        prop_assert!((report.distance - end.distance(target.as_dvec3())).abs() <= 1e-6 * length);
        assert_swings(&rig, &out)?;
    }

    /// Beyond the reach the chain is straight and points at the target.
    #[test]
    fn fabrik_unreachable_is_straight_at_the_target(
        rig in rig(2..=10),
        direction in unit_dir(),
        beyond in 1.0001..5.0f64,
        swivel in prop::option::of(-3.0..3.0f32),
    ) {
        let target = rig.world_target(direction, rig.reach() * beyond);
        let pole = swivel.map(|angle| Pole::Swivel { angle, reference: Vec3::Y });
        let (out, report) = fabrik(&rig, target, pole);
        prop_assert!(!report.reachable);
        prop_assert_eq!(report.iterations, 0);
        assert_straight_at(&rig, &out, target)?;
    }

    /// With a pole, the chain's bend (the sum of the inner joints' offsets from the root→end
    /// axis) points at the pole's side of that axis.
    #[test]
    fn fabrik_bends_the_chain_towards_the_pole(
        rig in rig(2..=8),
        direction in unit_dir(),
        fraction in 0.1..0.9f64,
        pole in vec(-4.0..4.0f32, 3),
    ) {
        let (lo, hi) = (rig.shortest(), rig.reach());
        let target = rig.world_target(direction, lo + (hi - lo) * fraction);
        let pole = Vec3::from_slice(&pole);
        let (out, _) = fabrik(&rig, target, Some(Pole::Point(pole)));
        let p = rig.positions(&out);
        let length = rig.scale() * hi;
        let axis = (p[p.len() - 1] - p[0]).normalize();
        let bend: DVec3 = p[1..p.len() - 1].iter().map(|q| reject(*q - p[0], axis)).sum();
        let to_pole = reject(pole.as_dvec3() - p[0], axis);
        prop_assume!(to_pole.length() > 1e-3 * length && bend.length() > 1e-3 * length);
        let cos = bend.normalize().dot(to_pole.normalize());
        prop_assert!(cos >= 1.0 - 1e-6, "bend {bend}, pole side {to_pole}: cos {cos}");
    }

    /// Solving again from the solved pose changes nothing.
    #[test]
    fn fabrik_is_idempotent(
        rig in rig(2..=10),
        direction in unit_dir(),
        fraction in 0.0..=1.0f64,
        pole in prop::option::of(vec(-3.0..3.0f32, 3)),
    ) {
        let (lo, hi) = (rig.shortest(), rig.reach());
        let target = rig.world_target(direction, lo + (hi - lo) * fraction);
        let pole = pole.map(|p| Pole::Point(Vec3::from_slice(&p)));
        let (first, _) = fabrik(&rig, target, pole);
        let mut again = rig.clone();
        again.rotations = first.clone();
        let (second, report) = fabrik(&again, target, pole);
        for (j, (a, b)) in first.iter().zip(&second).enumerate() {
            prop_assert!(rotation_angle(*a, *b) <= 1e-4, "joint {j}: {} rad ({report:?})", rotation_angle(*a, *b));
        }
    }

    /// For two bones with a pole point, FABRIK converges to the analytic solution.
    #[test]
    fn fabrik_agrees_with_the_two_bone_solver(
        rig in rig(2..=2),
        direction in unit_dir(),
        fraction in 0.05..0.95f64,
        pole in vec(-3.0..3.0f64, 3),
    ) {
        let pole = DVec3::from_slice(&pole);
        let root = rig.translations[0].as_dvec3();
        prop_assume!(reject(pole - root, direction).length() > 0.1);
        let (lo, hi) = (rig.shortest(), rig.reach());
        let target = rig.world_target(direction, lo + (hi - lo) * fraction);
        let pole = Pole::Point(world_pole(&rig, pole));
        let (analytic, _) = two_bone(&rig, target, pole);
        let (iterative, _) = fabrik(&rig, target, Some(pole));
        let (a, b) = (rig.positions(&analytic), rig.positions(&iterative));
        prop_assert!(a[1].distance(b[1]) <= 1e-4 * rig.scale() * hi, "{} vs {}", a[1], b[1]);
    }
}

/// A 10-joint chain dragged along a circle that crosses its plane, with a pole: continuous.
#[test]
fn fabrik_drag_is_continuous() {
    let n = 9;
    let mut rig = Rig {
        world_from_parent: Affine3A::IDENTITY,
        translations: std::iter::once(Vec3::ZERO)
            .chain(std::iter::repeat_n(Vec3::new(0.2, 0.0, 0.0), n))
            .collect(),
        rest: vec![Quat::IDENTITY; n + 1],
        rotations: std::iter::once(Quat::IDENTITY)
            .chain(std::iter::repeat_n(Quat::from_rotation_z(0.15), n))
            .collect(),
    };
    let pole = Some(Pole::Point(Vec3::new(0.9, 2.0, 0.0)));
    let steps = 1000;
    let mut previous: Option<Vec<Quat>> = None;
    for k in 0..=steps {
        let angle = 2.0 * std::f32::consts::PI * k as f32 / steps as f32;
        let target = Vec3::new(1.2, 0.3 * angle.cos(), 0.8 * angle.sin());
        let (out, report) = fabrik(&rig, target, pole);
        assert!(report.distance < 1e-5 * 1.8, "step {k}: {report:?}");
        if let Some(prev) = &previous {
            for (j, (a, b)) in prev.iter().zip(&out).enumerate() {
                let change = rotation_angle(*a, *b);
                assert!(change < 0.1, "step {k}, joint {j}: {change} rad");
            }
        }
        rig.rotations = out.clone();
        previous = Some(out);
    }
}

/// A parent that scales non-uniformly: the end joint still lands on the world target.
#[test]
fn non_uniform_parent_scale_reaches_the_world_target() {
    let mut rig = arm();
    rig.world_from_parent = Affine3A::from_scale_rotation_translation(
        Vec3::new(2.0, 0.5, 1.0),
        Quat::from_rotation_y(0.7),
        Vec3::ONE,
    );
    let target = rig.world().transform_point3(DVec3::new(0.9, 0.6, 0.4)).as_vec3();
    let (out, report) = two_bone(&rig, target, Pole::Point(Vec3::new(0.0, 5.0, 0.0)));
    assert!(report.reachable);
    assert!(rig.positions(&out)[2].distance(target.as_dvec3()) < 1e-5);
    let (out, _) = fabrik(&rig, target, None);
    assert!(rig.positions(&out)[2].distance(target.as_dvec3()) < 1e-5);
}

/// The end joint's rotation is returned as given.
#[test]
fn end_joint_rotation_is_left_alone() {
    let mut rig = arm();
    rig.rotations[2] = Quat::from_rotation_x(0.5);
    let (out, _) = two_bone(&rig, Vec3::new(1.0, 0.5, 0.2), Pole::Point(Vec3::Y));
    assert_eq!(out[2], rig.rotations[2]);
    let (out, _) = fabrik(&rig, Vec3::new(1.0, 0.5, 0.2), None);
    assert_eq!(out[2], rig.rotations[2]);
}

/// A target on the root, or a pole on the root→target line: defined, finite answers.
#[test]
fn degenerate_targets_and_poles_give_finite_rotations() {
    let mut equal = arm();
    equal.translations[2] = Vec3::new(1.0, 0.0, 0.0);
    for rig in [arm(), equal] {
        for (target, pole) in [
            (Vec3::ZERO, Pole::Point(Vec3::Y)),
            (Vec3::new(1.0, 0.0, 0.0), Pole::Point(Vec3::new(3.0, 0.0, 0.0))),
            (Vec3::new(1.0, 0.0, 0.0), Pole::Swivel { angle: 1.0, reference: Vec3::X }),
        ] {
            let (out, _) = two_bone(&rig, target, pole);
            assert!(out.iter().all(|q| q.is_finite()), "{target} {pole:?}: {out:?}");
            let (out, _) = fabrik(&rig, target, Some(pole));
            assert!(out.iter().all(|q| q.is_finite()), "{target} {pole:?}: {out:?}");
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Errors: refused with a clear message, never a panic
// ---------------------------------------------------------------------------------------------

#[test]
fn zero_length_bones_are_refused_naming_the_joint() {
    let mut rig = arm();
    rig.translations[2] = Vec3::ZERO;
    let mut out = [Quat::IDENTITY; 3];
    let error = solve_two_bone(&rig.chain(), Vec3::X, Pole::Point(Vec3::Y), &mut out).unwrap_err();
    assert_eq!(error, IkError::ZeroLengthBone { joint: 2 });
    assert_eq!(
        error.to_string(),
        "IK chain joint 2 sits on its parent joint 1: a zero-length bone has no direction to aim"
    );
    let mut rig = arm();
    rig.translations[1] = Vec3::splat(1e-9);
    let error = solve_fabrik(&rig.chain(), Vec3::X, None, &FabrikSettings::default(), &mut out).unwrap_err();
    assert_eq!(error, IkError::ZeroLengthBone { joint: 1 });
}

#[test]
fn non_finite_targets_and_poles_are_refused() {
    let rig = arm();
    let mut out = [Quat::IDENTITY; 3];
    let chain = rig.chain();
    let nan_target = Vec3::new(f32::NAN, 0.0, 1.0);
    let error = solve_two_bone(&chain, nan_target, Pole::Point(Vec3::Y), &mut out).unwrap_err();
    assert_eq!(error.to_string(), "IK target is not finite: [NaN, 0, 1]");
    let error =
        solve_fabrik(&chain, Vec3::new(0.0, f32::INFINITY, 0.0), None, &FabrikSettings::default(), &mut out)
            .unwrap_err();
    assert_eq!(error.to_string(), "IK target is not finite: [0, inf, 0]");
    let error =
        solve_two_bone(&chain, Vec3::X, Pole::Point(Vec3::new(0.0, 0.0, f32::NAN)), &mut out).unwrap_err();
    assert_eq!(error.to_string(), "IK pole is not finite: [0, 0, NaN]");
    let error =
        solve_two_bone(&chain, Vec3::X, Pole::Swivel { angle: f32::NAN, reference: Vec3::Y }, &mut out)
            .unwrap_err();
    assert_eq!(error.to_string(), "IK pole swivel angle is not finite: NaN");
    let error = solve_two_bone(&chain, Vec3::X, Pole::Swivel { angle: 0.0, reference: Vec3::ZERO }, &mut out)
        .unwrap_err();
    assert_eq!(error.to_string(), "IK pole reference direction is zero: it cannot tell a bend side");
    assert_eq!(out, [Quat::IDENTITY; 3], "a refused solve writes nothing");
}

#[test]
fn short_and_mismatched_chains_are_refused() {
    let rig = arm();
    let settings = FabrikSettings::default();
    let mut out = [Quat::IDENTITY; 3];
    let short = IkChain {
        translations: &rig.translations[..2],
        rest_rotations: &rig.rest[..2],
        rotations: &rig.rotations[..2],
        ..rig.chain()
    };
    let error = solve_fabrik(&short, Vec3::X, None, &settings, &mut out[..2]).unwrap_err();
    assert_eq!(error.to_string(), "an IK chain needs at least 2 bones (3 joints); this one has 2 joint(s)");
    let error = solve_two_bone(&short, Vec3::X, Pole::Point(Vec3::Y), &mut out[..2]).unwrap_err();
    assert_eq!(error, IkError::ChainTooShort { joints: 2 });

    let mismatched = IkChain { rotations: &rig.rotations[..2], ..rig.chain() };
    let error = solve_fabrik(&mismatched, Vec3::X, None, &settings, &mut out).unwrap_err();
    assert_eq!(
        error.to_string(),
        "IK chain inputs differ in length: rotations has 2 entries for a chain of 3 joints"
    );
    let error = solve_fabrik(&rig.chain(), Vec3::X, None, &settings, &mut out[..1]).unwrap_err();
    assert_eq!(error, IkError::LengthMismatch { what: "the output", expected: 3, found: 1 });

    let four = Rig {
        translations: vec![Vec3::ZERO, Vec3::X, Vec3::X, Vec3::X],
        rest: vec![Quat::IDENTITY; 4],
        rotations: vec![Quat::IDENTITY; 4],
        ..arm()
    };
    let mut out4 = [Quat::IDENTITY; 4];
    let error = solve_two_bone(&four.chain(), Vec3::X, Pole::Point(Vec3::Y), &mut out4).unwrap_err();
    assert_eq!(
        error.to_string(),
        "the two-bone IK solver takes exactly 2 bones (3 joints); this chain has 4 joint(s)"
    );
}

#[test]
fn broken_joints_parents_and_settings_are_refused() {
    let settings = FabrikSettings::default();
    let mut out = [Quat::IDENTITY; 3];
    let mut rig = arm();
    rig.translations[0] = Vec3::new(0.0, f32::NAN, 0.0);
    assert_eq!(
        solve_fabrik(&rig.chain(), Vec3::X, None, &settings, &mut out).unwrap_err().to_string(),
        "translation of IK chain joint 0 is not finite"
    );
    let mut rig = arm();
    rig.rotations[1] = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0);
    assert_eq!(
        solve_fabrik(&rig.chain(), Vec3::X, None, &settings, &mut out).unwrap_err().to_string(),
        "rotation of IK chain joint 1 is not a finite, non-zero quaternion"
    );
    let mut rig = arm();
    rig.rest[0] = Quat::from_xyzw(f32::NAN, 0.0, 0.0, 1.0);
    assert_eq!(
        solve_fabrik(&rig.chain(), Vec3::X, None, &settings, &mut out).unwrap_err(),
        IkError::BadRotation { what: "rest rotation", joint: 0 }
    );
    let mut rig = arm();
    rig.world_from_parent = Affine3A::from_scale(Vec3::new(1.0, 0.0, 1.0));
    assert_eq!(
        solve_two_bone(&rig.chain(), Vec3::X, Pole::Point(Vec3::Y), &mut out).unwrap_err().to_string(),
        "the IK chain's parent transform is not finite and invertible"
    );
    let rig = arm();
    let zero = FabrikSettings { max_iterations: 0, ..settings };
    assert_eq!(
        solve_fabrik(&rig.chain(), Vec3::X, None, &zero, &mut out).unwrap_err().to_string(),
        "FABRIK settings: max_iterations must be at least 1"
    );
    let nan = FabrikSettings { tolerance: f64::NAN, ..settings };
    assert!(matches!(
        solve_fabrik(&rig.chain(), Vec3::X, None, &nan, &mut out),
        Err(IkError::BadSettings(_))
    ));
}

fn any_f32() -> impl Strategy<Value = f32> {
    prop_oneof![
        -10.0..10.0f32,
        Just(0.0f32),
        Just(f32::NAN),
        Just(f32::INFINITY),
        Just(-f32::INFINITY),
        Just(f32::MAX),
        Just(1e-30f32),
        any::<f32>(),
    ]
}

fn any_vec3() -> impl Strategy<Value = Vec3> {
    (any_f32(), any_f32(), any_f32()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn any_quat() -> impl Strategy<Value = Quat> {
    (any_f32(), any_f32(), any_f32(), any_f32()).prop_map(|(x, y, z, w)| Quat::from_xyzw(x, y, z, w))
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(1024))]

    /// Whatever the input, the solvers return (finite rotations or an error) and never panic.
    #[test]
    fn no_input_panics(
        joints in 0..6usize,
        translations in vec(any_vec3(), 6),
        rest in vec(any_quat(), 6),
        rotations in vec(any_quat(), 6),
        parent in (any_vec3(), any_quat(), any_vec3()),
        target in any_vec3(),
        pole in any_vec3(),
        angle in any_f32(),
        settings in (0..4u32, any_f32()),
        out_len in 0..7usize,
    ) {
        let chain = IkChain {
            world_from_parent: Affine3A::from_scale_rotation_translation(parent.0, parent.1.normalize(), parent.2),
            translations: &translations[..joints],
            rest_rotations: &rest[..joints],
            rotations: &rotations[..joints],
        };
        let mut out = vec![Quat::IDENTITY; out_len.min(joints + 1)];
        let settings = FabrikSettings { max_iterations: settings.0, tolerance: f64::from(settings.1) };
        for pole in [Pole::Point(pole), Pole::Swivel { angle, reference: pole }] {
            if solve_two_bone(&chain, target, pole, &mut out).is_ok() {
                prop_assert!(out.iter().all(|q| q.is_finite()), "{out:?}");
            }
            if solve_fabrik(&chain, target, Some(pole), &settings, &mut out).is_ok() {
                prop_assert!(out.iter().all(|q| q.is_finite()), "{out:?}");
            }
        }
    }
}

// ---------------------------------------------------------------------------------------------
// Chains in a skeleton
// ---------------------------------------------------------------------------------------------

#[test]
fn chain_joints_walks_from_the_end_up_to_the_root() {
    let mut joints = vec![Joint::new("hips", None, Vec3::ZERO, Quat::IDENTITY)];
    for (name, parent) in [("spine", 0), ("shoulder", 1), ("elbow", 2), ("hand", 3), ("thigh", 0)] {
        joints.push(Joint::new(name, Some(parent), Vec3::X, Quat::IDENTITY));
    }
    let skeleton = Skeleton::new(joints);
    assert_eq!(chain_joints(&skeleton, 2, 4), Ok(vec![2, 3, 4]));
    assert_eq!(chain_joints(&skeleton, 0, 4), Ok(vec![0, 1, 2, 3, 4]));
    assert_eq!(chain_joints(&skeleton, 3, 4), Err(IkError::ChainTooShort { joints: 2 }));
    assert_eq!(
        chain_joints(&skeleton, 5, 4).unwrap_err().to_string(),
        "joint 4 is not below joint 5 in the skeleton: they do not make an IK chain"
    );
    assert_eq!(
        chain_joints(&skeleton, 0, 9).unwrap_err().to_string(),
        "joint 9 is outside the skeleton (6 joints)"
    );
}

// ---------------------------------------------------------------------------------------------
// Shared checks
// ---------------------------------------------------------------------------------------------

/// Every bone points from the root at the target, and the end is one chain length from the root.
fn assert_straight_at(rig: &Rig, out: &[Quat], target: Vec3) -> Result<(), TestCaseError> {
    let p = rig.positions(out);
    let u = (target.as_dvec3() - p[0]).normalize();
    let length = rig.scale() * rig.reach();
    for i in 0..p.len() - 1 {
        let bone = (p[i + 1] - p[i]).normalize();
        prop_assert!(bone.dot(u) >= 1.0 - 1e-9, "bone {i} points {bone}, target direction {u}");
    }
    let end = p[0] + u * length;
    prop_assert!(p.last().unwrap().distance(end) <= 1e-5 * length);
    Ok(())
}

/// Each returned rotation is the input one turned by the minimal rotation between the bone's
/// old and new direction (in the joint's frame before its rotation): `q' = arc(q·ô, q'·ô)·q`.
fn assert_swings(rig: &Rig, out: &[Quat]) -> Result<(), TestCaseError> {
    for (i, solved) in out.iter().enumerate().take(out.len() - 1) {
        let q = rig.rotations[i].as_dquat().normalize();
        let solved = solved.as_dquat().normalize();
        let bone = rig.translations[i + 1].as_dvec3().normalize();
        let (from, to) = (q * bone, solved * bone);
        let cos = from.dot(to);
        if cos < -0.9 {
            continue; // near a half turn the minimal rotation's axis is ill-conditioned
        }
        // The minimal rotation between unit vectors: (1 + from·to, from × to), normalized.
        let c = from.cross(to);
        let arc = DQuat::from_xyzw(c.x, c.y, c.z, 1.0 + cos).normalize();
        let expected = (arc * q).as_quat();
        prop_assert!(
            rotation_angle(out[i], expected) <= 1e-5,
            "joint {i}: {:?} expected {:?}",
            out[i],
            expected
        );
    }
    Ok(())
}

/// A pole on the root→target line cannot tell a side: the chain keeps bending the way it bends
/// now (the demo arm bends in the plane z = 0).
#[test]
fn two_bone_pole_on_the_target_line_keeps_the_current_bend() {
    let rig = arm();
    let before = rig.positions(&rig.rotations);
    for target in [DVec3::new(1.2, 0.0, 0.0), DVec3::new(0.85, 0.85, 0.0), DVec3::new(-0.3, 1.1, 0.0)] {
        let axis = target.normalize();
        let side = reject(before[1], axis);
        for pole in [target * 2.5, target * 0.5] {
            let (rotations, report) = two_bone(&rig, target.as_vec3(), Pole::Point(pole.as_vec3()));
            assert!(report.reachable);
            let p = rig.positions(&rotations);
            assert!((p[2] - target).length() < 1e-5, "target {target}, pole {pole}: end at {}", p[2]);
            assert!(p[1].z.abs() < 1e-6, "target {target}, pole {pole}: elbow at {}", p[1]);
            assert!(reject(p[1], axis).dot(side) > 0.0, "target {target}, pole {pole}: elbow at {}", p[1]);
        }
    }
}
