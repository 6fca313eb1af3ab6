//! The deformer jobs: reference and fast paths agree, known poses give known results, and bad
//! inputs are typed errors that leave the (poisoned) outputs alone.

use glam::{Quat, Vec3};
use keyrig_core::{DeformerKind, ProceduralMesh};
use keyrig_skin::{
    deform_mesh_into, mesh_for, BlendZone, BonesBlendBindings, BonesBlendJob, BonesBlendVertex, Deformed,
    DualQuatJob, Execution, Influences, JointPalette, LinearBlendJob, Pose, RestJoint, RestSkeleton,
    RigidJob, SkinError,
};
use proptest::prelude::*;

/// A small deterministic generator (64-bit LCG), so failures reproduce.
struct Lcg(u64);

impl Lcg {
    fn next_f32(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 40) as f32) / ((1u64 << 24) as f32)
    }
    fn range(&mut self, lo: f32, hi: f32) -> f32 {
        lo + (hi - lo) * self.next_f32()
    }
    fn vec3(&mut self, r: f32) -> Vec3 {
        Vec3::new(self.range(-r, r), self.range(-r, r), self.range(-r, r))
    }
    fn quat(&mut self) -> Quat {
        let axis = self.vec3(1.0).try_normalize().unwrap_or(Vec3::X);
        Quat::from_axis_angle(axis, self.range(-3.1, 3.1))
    }
    fn index(&mut self, n: usize) -> usize {
        ((self.next_f32() * n as f32) as usize).min(n - 1)
    }
}

/// A branching skeleton of `n` joints with random rest rotations.
fn random_skeleton(rng: &mut Lcg, n: usize) -> RestSkeleton {
    let joints: Vec<RestJoint> = (0..n)
        .map(|j| {
            let parent = if j == 0 { None } else { Some(rng.index(j)) };
            RestJoint::new(format!("j{j}"), parent, rng.vec3(2.0), rng.quat())
        })
        .collect();
    RestSkeleton::new(&joints).unwrap()
}

fn random_pose(rng: &mut Lcg, n: usize) -> Pose {
    let rotations = (0..n).map(|_| rng.quat()).collect();
    Pose::from_rotations(rotations, rng.vec3(1.0))
}

struct Data {
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    joints: Vec<[u16; 4]>,
    weights: Vec<[f32; 4]>,
    bones: Vec<u16>,
    bindings: Vec<BonesBlendVertex>,
}

fn random_data(rng: &mut Lcg, skeleton: &RestSkeleton, n: usize) -> Data {
    let joint_count = skeleton.len();
    let mut d = Data {
        positions: Vec::new(),
        normals: Vec::new(),
        joints: Vec::new(),
        weights: Vec::new(),
        bones: Vec::new(),
        bindings: Vec::new(),
    };
    for v in 0..n {
        d.positions.push(rng.vec3(5.0));
        d.normals.push(rng.vec3(1.0).try_normalize().unwrap_or(Vec3::Y));
        let js = [0; 4].map(|_| rng.index(joint_count) as u16);
        let mut ws = [0.0f32; 4].map(|_| rng.next_f32() + 0.01);
        if v % 7 == 0 {
            ws[3] = 0.0; // zero-weight influences occur in real data
        }
        let sum: f32 = ws.iter().sum();
        d.joints.push(js);
        d.weights.push(ws.map(|w| w / sum));
        d.bones.push(js[0]);
        let k = rng.index(joint_count);
        let t = if skeleton.parents()[k].is_some() { rng.next_f32() } else { 1.0 };
        d.bindings
            .push(BonesBlendVertex { joint: k as u32, t: if v % 11 == 0 && t < 1.0 { 0.0 } else { t } });
    }
    d
}

fn max_difference(a: &[Vec3], b: &[Vec3]) -> f32 {
    a.iter().zip(b).map(|(x, y)| (*x - *y).abs().max_element()).fold(0.0, f32::max)
}

/// Runs a job-building closure for each execution and returns positions and normals.
fn run_all(
    n: usize,
    mut job: impl FnMut(Execution, &mut [Vec3], &mut [Vec3]) -> Result<(), SkinError>,
) -> Vec<Deformed> {
    [Execution::Reference, Execution::SingleThreaded, Execution::Parallel, Execution::Portable]
        .into_iter()
        .map(|e| {
            let mut out = Deformed { positions: vec![Vec3::NAN; n], normals: vec![Vec3::NAN; n] };
            job(e, &mut out.positions, &mut out.normals).unwrap();
            out
        })
        .collect()
}

fn assert_all_equal(runs: &[Deformed], what: &str) {
    for run in &runs[1..] {
        let dp = max_difference(&runs[0].positions, &run.positions);
        let dn = max_difference(&runs[0].normals, &run.normals);
        // Positions reach ~20 units: 2e-4 is ~1e-5 of the model size.
        assert!(dp < 2e-4, "{what}: positions differ by {dp}");
        assert!(dn < 1e-4, "{what}: normals differ by {dn}");
    }
    for p in &runs[0].positions {
        assert!(p.is_finite(), "{what}: non-finite output");
    }
}

#[test]
fn reference_and_fast_paths_agree() {
    // (joints, vertices): more than two chunks, so the parallel path really splits; and a
    // large skeleton with few vertices, where dual quaternions skip the per-frame sign table.
    for (joint_count, n) in [(12, 10_000), (70, 1_003)] {
        agreement(joint_count, n);
    }
}

fn agreement(joint_count: usize, n: usize) {
    let mut rng = Lcg(7 + joint_count as u64);
    let skeleton = random_skeleton(&mut rng, joint_count);
    let d = random_data(&mut rng, &skeleton, n);
    let influences = Influences::new(d.joints.clone(), d.weights.clone(), skeleton.len()).unwrap();
    for round in 0..3 {
        let pose = random_pose(&mut rng, skeleton.len());
        let palette = JointPalette::new(&skeleton, &pose).unwrap();
        let dqs = palette.dual_quaternions().unwrap();
        let rigid = run_all(n, |e, op, on| {
            RigidJob {
                palette: &palette,
                joints: &d.bones,
                positions: &d.positions,
                normals: &d.normals,
                out_positions: op,
                out_normals: on,
            }
            .run_with(e)
        });
        assert_all_equal(&rigid, &format!("rigid, round {round}"));
        let linear = run_all(n, |e, op, on| {
            LinearBlendJob {
                palette: &palette,
                influences: &influences,
                positions: &d.positions,
                normals: &d.normals,
                out_positions: op,
                out_normals: on,
            }
            .run_with(e)
        });
        assert_all_equal(&linear, &format!("linear, round {round}"));
        let bindings = BonesBlendBindings::new(d.bindings.clone(), skeleton.parents()).unwrap();
        let bones = run_all(n, |e, op, on| {
            BonesBlendJob {
                palette: &palette,
                parents: skeleton.parents(),
                bindings: &bindings,
                positions: &d.positions,
                normals: &d.normals,
                out_positions: op,
                out_normals: on,
            }
            .run_with(e)
        });
        assert_all_equal(&bones, &format!("bones blending, round {round}"));
        let dq = run_all(n, |e, op, on| {
            DualQuatJob {
                dual_quaternions: &dqs,
                influences: &influences,
                positions: &d.positions,
                normals: &d.normals,
                out_positions: op,
                out_normals: on,
            }
            .run_with(e)
        });
        assert_all_equal(&dq, &format!("dual quaternion, round {round}"));
    }
}

#[test]
fn more_than_four_influences_work() {
    let mut rng = Lcg(3);
    let skeleton = random_skeleton(&mut rng, 9);
    let pose = random_pose(&mut rng, 9);
    let palette = JointPalette::new(&skeleton, &pose).unwrap();
    let n = 5000;
    let positions: Vec<Vec3> = (0..n).map(|_| rng.vec3(3.0)).collect();
    let normals: Vec<Vec3> = (0..n).map(|_| rng.vec3(1.0).normalize()).collect();
    let joints: Vec<[u16; 8]> = (0..n).map(|_| [0; 8].map(|_| rng.index(9) as u16)).collect();
    let weights: Vec<[f32; 8]> = (0..n)
        .map(|_| {
            let ws = [0.0f32; 8].map(|_| rng.next_f32() + 0.01);
            let s: f32 = ws.iter().sum();
            ws.map(|w| w / s)
        })
        .collect();
    let influences = Influences::new(joints, weights, skeleton.len()).unwrap();
    let runs = run_all(n, |e, op, on| {
        LinearBlendJob {
            palette: &palette,
            influences: &influences,
            positions: &positions,
            normals: &normals,
            out_positions: op,
            out_normals: on,
        }
        .run_with(e)
    });
    assert_all_equal(&runs, "linear, 8 influences");
    let dqs = palette.dual_quaternions().unwrap();
    let runs = run_all(n, |e, op, on| {
        DualQuatJob {
            dual_quaternions: &dqs,
            influences: &influences,
            positions: &positions,
            normals: &normals,
            out_positions: op,
            out_normals: on,
        }
        .run_with(e)
    });
    assert_all_equal(&runs, "dual quaternion, 8 influences");
}

#[test]
fn rest_pose_leaves_every_mesh_unchanged() {
    for kind in
        [ProceduralMesh::ArmLowPoly, ProceduralMesh::ArmHighPoly, ProceduralMesh::Hand, ProceduralMesh::Cube]
    {
        let mesh = mesh_for(kind);
        let bindings = mesh.bindings(BlendZone::default()).unwrap();
        let palette = JointPalette::new(&mesh.skeleton, &Pose::rest(mesh.skeleton.len())).unwrap();
        for deformer in DeformerKind::ALL {
            for execution in [Execution::Reference, Execution::Parallel] {
                let mut out = Deformed::default();
                deform_mesh_into(&mesh, &bindings, &palette, deformer, execution, &mut out).unwrap();
                assert!(max_difference(&out.positions, &mesh.positions) < 1e-4, "{kind:?} {deformer:?}");
                assert!(max_difference(&out.normals, &mesh.normals) < 1e-5, "{kind:?} {deformer:?}");
            }
        }
    }
}

/// A three-joint chain along X: a (0) → b (x = 4) → c (x = 8).
fn chain() -> RestSkeleton {
    RestSkeleton::new(&[
        RestJoint::new("a", None, Vec3::ZERO, Quat::IDENTITY),
        RestJoint::new("b", Some(0), Vec3::new(4.0, 0.0, 0.0), Quat::IDENTITY),
        RestJoint::new("c", Some(1), Vec3::new(4.0, 0.0, 0.0), Quat::IDENTITY),
    ])
    .unwrap()
}

fn bones_blend(
    palette: &JointPalette,
    skeleton: &RestSkeleton,
    bindings: &[BonesBlendVertex],
    p: &[Vec3],
) -> Vec<Vec3> {
    let bindings = &BonesBlendBindings::new(bindings.to_vec(), skeleton.parents()).unwrap();
    let normals = vec![Vec3::Y; p.len()];
    let mut out = vec![Vec3::NAN; p.len()];
    let mut out_n = vec![Vec3::NAN; p.len()];
    BonesBlendJob {
        palette,
        parents: skeleton.parents(),
        bindings,
        positions: p,
        normals: &normals,
        out_positions: &mut out,
        out_normals: &mut out_n,
    }
    .run()
    .unwrap();
    out
}

#[test]
fn bones_blending_ends_are_the_rigid_transforms() {
    let skeleton = chain();
    let mut rng = Lcg(11);
    let pose = random_pose(&mut rng, 3);
    let palette = JointPalette::new(&skeleton, &pose).unwrap();
    let p: Vec<Vec3> = (0..50).map(|_| rng.vec3(6.0)).collect();
    for k in 1..3usize {
        let zero = bones_blend(
            &palette,
            &skeleton,
            &vec![BonesBlendVertex { joint: k as u32, t: 0.0 }; p.len()],
            &p,
        );
        let one = bones_blend(
            &palette,
            &skeleton,
            &vec![BonesBlendVertex { joint: k as u32, t: 1.0 }; p.len()],
            &p,
        );
        for (i, v) in p.iter().enumerate() {
            let parent = palette.skinning[k - 1].transform_point3(*v);
            let own = palette.skinning[k].transform_point3(*v);
            assert!(zero[i].abs_diff_eq(parent, 1e-4), "t = 0 at joint {k}: {} vs {parent}", zero[i]);
            assert!(one[i].abs_diff_eq(own, 1e-4), "t = 1 at joint {k}: {} vs {own}", one[i]);
        }
    }
}

proptest! {
    /// Bones blending keeps every vertex's distance to its joint, for any rotation and t.
    #[test]
    fn bones_blending_keeps_distance_to_the_joint(
        ax in -1.0f32..1.0, ay in -1.0f32..1.0, az in -1.0f32..1.0, angle in -3.1f32..3.1,
        t in 0.0f32..=1.0, x in -3.0f32..3.0, y in -2.0f32..2.0, z in -2.0f32..2.0,
    ) {
        let axis = Vec3::new(ax, ay, az).try_normalize().unwrap_or(Vec3::X);
        let skeleton = chain();
        let pose = Pose::rest(3).with_rotation(1, Quat::from_axis_angle(axis, angle)).with_rotation(0, Quat::from_rotation_z(0.4));
        let palette = JointPalette::new(&skeleton, &pose).unwrap();
        let v = Vec3::new(4.0 + x, y, z);
        let out = bones_blend(&palette, &skeleton, &[BonesBlendVertex { joint: 1, t }], &[v]);
        let rest = v.distance(skeleton.rest_position(1));
        let posed = out[0].distance(palette.joint_position(1));
        prop_assert!((rest - posed).abs() < 1e-4 * rest.max(1.0), "rest {} posed {}", rest, posed);
    }
}

#[test]
fn dual_quaternion_with_one_influence_is_rigid() {
    let mut rng = Lcg(5);
    let skeleton = random_skeleton(&mut rng, 6);
    let palette = JointPalette::new(&skeleton, &random_pose(&mut rng, 6)).unwrap();
    let dqs = palette.dual_quaternions().unwrap();
    let n = 200;
    let d = random_data(&mut rng, &skeleton, n);
    let joints: Vec<[u16; 4]> = d.bones.iter().map(|&b| [b, 0, 0, 0]).collect();
    let weights = vec![[1.0f32, 0.0, 0.0, 0.0]; n];
    let influences = Influences::new(joints, weights, skeleton.len()).unwrap();
    let (mut a, mut an, mut b, mut bn) =
        (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n], vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
    DualQuatJob {
        dual_quaternions: &dqs,
        influences: &influences,
        positions: &d.positions,
        normals: &d.normals,
        out_positions: &mut a,
        out_normals: &mut an,
    }
    .run()
    .unwrap();
    RigidJob {
        palette: &palette,
        joints: &d.bones,
        positions: &d.positions,
        normals: &d.normals,
        out_positions: &mut b,
        out_normals: &mut bn,
    }
    .run()
    .unwrap();
    assert!(max_difference(&a, &b) < 1e-4);
    assert!(max_difference(&an, &bn) < 1e-5);
}

#[test]
fn bad_inputs_are_typed_errors_and_leave_outputs_alone() {
    let skeleton = chain();
    let palette = JointPalette::new(&skeleton, &Pose::rest(3)).unwrap();
    let dqs = palette.dual_quaternions().unwrap();
    let positions = [Vec3::ONE; 2];
    let normals = [Vec3::Y; 2];
    let poison = Vec3::splat(-7.0);
    let (mut op, mut on) = ([poison; 2], [poison; 2]);

    let mut rigid = |joints: &[u16]| {
        RigidJob {
            palette: &palette,
            joints,
            positions: &positions,
            normals: &normals,
            out_positions: &mut op,
            out_normals: &mut on,
        }
        .run()
    };
    assert_eq!(
        rigid(&[0, 3]),
        Err(SkinError::JointOutOfRange { vertex: 1, influence: 0, joint: 3, joint_count: 3 })
    );
    let (mut vp, mut vn) = ([poison; 2], [poison; 2]);
    let job = RigidJob {
        palette: &palette,
        joints: &[0, 3],
        positions: &positions,
        normals: &normals,
        out_positions: &mut vp,
        out_normals: &mut vn,
    };
    assert_eq!(
        job.validate(),
        Err(SkinError::JointOutOfRange { vertex: 1, influence: 0, joint: 3, joint_count: 3 })
    );
    assert!(matches!(rigid(&[0]), Err(SkinError::LengthMismatch { what: "joints", expected: 2, found: 1 })));
    assert_eq!(op, [poison; 2]);

    type Case = ([[u16; 4]; 2], [[f32; 4]; 2], SkinError);
    let cases: [Case; 5] = [
        (
            [[0, 1, 0, 0], [0, 9, 0, 0]],
            [[0.5, 0.5, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]],
            SkinError::JointOutOfRange { vertex: 1, influence: 1, joint: 9, joint_count: 3 },
        ),
        (
            [[0, 1, 0, 0]; 2],
            [[0.5, 0.5, 0.0, 0.0], [f32::NAN, 1.0, 0.0, 0.0]],
            SkinError::NonFiniteWeight { vertex: 1, influence: 0, weight: f32::NAN },
        ),
        (
            [[0, 1, 0, 0]; 2],
            [[1.5, -0.5, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]],
            SkinError::NegativeWeight { vertex: 0, influence: 1, weight: -0.5 },
        ),
        ([[0, 1, 0, 0]; 2], [[0.5, 0.5, 0.0, 0.0], [0.0; 4]], SkinError::ZeroWeights { vertex: 1 }),
        (
            [[0, 1, 0, 0]; 2],
            [[0.2, 0.2, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]],
            SkinError::WeightSum { vertex: 0, sum: 0.4 },
        ),
    ];
    for (joints, weights, expected) in cases {
        // Bad influences never become `Influences`: the error names the vertex (NaN != NaN:
        // compare the rendered message).
        let built = Influences::new(joints.to_vec(), weights.to_vec(), 3);
        assert_eq!(built.unwrap_err().to_string(), expected.to_string());
    }
    // Influences checked against a larger skeleton than the palette: the job refuses them in
    // its O(1) check and names the vertex, before writing anything.
    let wide = Influences::new(vec![[0, 1, 0, 0], [0, 9, 0, 0]], vec![[0.5, 0.5, 0.0, 0.0]; 2], 10).unwrap();
    let expected = SkinError::JointOutOfRange { vertex: 1, influence: 1, joint: 9, joint_count: 3 };
    let r = LinearBlendJob {
        palette: &palette,
        influences: &wide,
        positions: &positions,
        normals: &normals,
        out_positions: &mut op,
        out_normals: &mut on,
    }
    .run();
    assert_eq!(r, Err(expected.clone()));
    let r = DualQuatJob {
        dual_quaternions: &dqs,
        influences: &wide,
        positions: &positions,
        normals: &normals,
        out_positions: &mut op,
        out_normals: &mut on,
    }
    .run();
    assert_eq!(r, Err(expected));
    assert_eq!(op, [poison; 2]);
    let good = Influences::new(vec![[0u16, 1, 0, 0]; 2], vec![[0.5f32, 0.5, 0.0, 0.0]; 2], 3).unwrap();
    let r = LinearBlendJob {
        palette: &palette,
        influences: &good,
        positions: &positions,
        normals: &normals[..1],
        out_positions: &mut op,
        out_normals: &mut on,
    }
    .run();
    assert!(matches!(r, Err(SkinError::LengthMismatch { what: "normals", expected: 2, found: 1 })));
    let (mut short, mut short_n) = ([poison; 1], [poison; 1]);
    let r = LinearBlendJob {
        palette: &palette,
        influences: &good,
        positions: &positions,
        normals: &normals,
        out_positions: &mut short,
        out_normals: &mut short_n,
    }
    .run();
    assert!(matches!(r, Err(SkinError::LengthMismatch { what: "output positions", expected: 2, found: 1 })));

    let bb_cases = [
        (
            [BonesBlendVertex { joint: 1, t: 0.5 }, BonesBlendVertex { joint: 4, t: 0.5 }],
            SkinError::JointOutOfRange { vertex: 1, influence: 0, joint: 4, joint_count: 3 },
        ),
        (
            [BonesBlendVertex { joint: 1, t: 1.5 }, BonesBlendVertex { joint: 1, t: 0.5 }],
            SkinError::BadBlendParameter { vertex: 0, t: 1.5 },
        ),
        (
            [BonesBlendVertex { joint: 1, t: f32::NAN }, BonesBlendVertex { joint: 1, t: 0.5 }],
            SkinError::BadBlendParameter { vertex: 0, t: f32::NAN },
        ),
        (
            [BonesBlendVertex { joint: 1, t: 0.5 }, BonesBlendVertex { joint: 0, t: 0.5 }],
            SkinError::RootBlend { vertex: 1, joint: 0, t: 0.5 },
        ),
    ];
    for (bindings, expected) in &bb_cases {
        // Bad bindings are refused when they are built, naming the vertex.
        let built = BonesBlendBindings::new(bindings.to_vec(), skeleton.parents());
        assert_eq!(built.unwrap_err().to_string(), expected.to_string());
    }
    // Bindings built for another skeleton (5 joints, joint 0 with a parent) reach the job, which
    // refuses them against its own before writing anything.
    let other_parents = [Some(1), Some(0), Some(1), Some(2), Some(3)];
    for (bindings, expected) in [&bb_cases[0], &bb_cases[3]] {
        let bindings = BonesBlendBindings::new(bindings.to_vec(), &other_parents).unwrap();
        let r = BonesBlendJob {
            palette: &palette,
            parents: skeleton.parents(),
            bindings: &bindings,
            positions: &positions,
            normals: &normals,
            out_positions: &mut op,
            out_normals: &mut on,
        }
        .run();
        assert_eq!(r.unwrap_err().to_string(), expected.to_string());
        assert_eq!(op, [poison; 2]);
    }
}

#[test]
fn scaled_palettes_are_refused_by_dual_quaternions_only() {
    let skeleton = RestSkeleton::new(&[RestJoint {
        name: "s".into(),
        parent: None,
        parent_from_joint: glam::Affine3A::from_scale(Vec3::new(1.0, 1.0, 1.0)),
    }])
    .unwrap();
    let ibm = [glam::Mat4::from_scale(Vec3::new(2.0, 1.0, 1.0))];
    let scaled = RestSkeleton::with_inverse_bind_matrices(
        &[RestJoint { name: "s".into(), parent: None, parent_from_joint: glam::Affine3A::IDENTITY }],
        &ibm,
    )
    .unwrap();
    assert!(JointPalette::new(&skeleton, &Pose::rest(1)).unwrap().dual_quaternions().is_ok());
    let palette = JointPalette::new(&scaled, &Pose::rest(1)).unwrap();
    assert!(matches!(palette.dual_quaternions(), Err(SkinError::NonRigidTransform { joint: 0, .. })));
    // Non-uniform scale: normals use the inverse-transpose.
    let normals = palette.normal_skinning.as_ref().expect("non-uniform scale needs normal matrices");
    let n = (normals[0] * glam::Vec3A::new(1.0, 1.0, 0.0)).normalize();
    assert!(n.abs_diff_eq(glam::Vec3A::new(0.5, 1.0, 0.0).normalize(), 1e-6));
}

#[test]
fn bending_one_finger_leaves_the_others() {
    let hand = mesh_for(ProceduralMesh::Hand);
    let bindings = hand.bindings(BlendZone::default()).unwrap();
    let finger0 = hand.skeleton.find("finger0.0").unwrap();
    let pose = Pose::rest(hand.skeleton.len()).with_rotation(finger0, Quat::from_rotation_z(-1.2));
    let palette = JointPalette::new(&hand.skeleton, &pose).unwrap();
    for deformer in DeformerKind::ALL {
        let mut out = Deformed::default();
        deform_mesh_into(&hand, &bindings, &palette, deformer, Execution::Parallel, &mut out).unwrap();
        let mut moved = 0;
        for (v, (p, q)) in hand.positions.iter().zip(&out.positions).enumerate() {
            if p.z > 1.0 {
                assert!(p.abs_diff_eq(*q, 1e-4), "{deformer:?}: vertex {v} of another finger moved");
            }
            if p.z < -1.9 && p.x > 10.0 && p.distance(*q) > 1.0 {
                moved += 1;
            }
        }
        assert!(moved > 30, "{deformer:?}: only {moved} vertices of finger 0 moved");
    }
}

#[test]
fn multi_weight_meshes_get_bones_blending_bindings() {
    // The high-poly arm without its single weights: bindings come from the derived weights.
    let mut arm = mesh_for(ProceduralMesh::ArmHighPoly);
    let from_single = arm.bindings(BlendZone::default()).unwrap();
    arm.bones = None;
    let from_weights = arm.bindings(BlendZone::default()).unwrap();
    let pose = Pose::rest(4).with_rotation(2, Quat::from_rotation_x(std::f32::consts::PI * 0.9));
    let palette = JointPalette::new(&arm.skeleton, &pose).unwrap();
    let mut a = Deformed::default();
    let mut b = Deformed::default();
    let single = keyrig_skin::MeshBindings {
        rigid: from_weights.rigid.clone(),
        bones_blending: from_single.bones_blending,
    };
    deform_mesh_into(&arm, &single, &palette, DeformerKind::BonesBlending, Execution::Parallel, &mut a)
        .unwrap();
    deform_mesh_into(&arm, &from_weights, &palette, DeformerKind::BonesBlending, Execution::Parallel, &mut b)
        .unwrap();
    assert!(
        max_difference(&a.positions, &b.positions) < 1e-3,
        "{}",
        max_difference(&a.positions, &b.positions)
    );
}

/// Every job checks every buffer's length against the positions' and names the one that is
/// off (one vertex short), before writing anything.
#[test]
fn every_job_names_the_buffer_of_the_wrong_length() {
    let skeleton = chain();
    let palette = JointPalette::new(&skeleton, &Pose::rest(3)).unwrap();
    let dqs = palette.dual_quaternions().unwrap();
    let n = 3;
    let positions = vec![Vec3::ONE; n];
    let normals = vec![Vec3::Y; n];
    let joints = vec![1u16; n];
    let influences = Influences::new(vec![[0u16, 1, 0, 0]; n], vec![[0.5f32, 0.5, 0.0, 0.0]; n], 3).unwrap();
    let bindings =
        BonesBlendBindings::new(vec![BonesBlendVertex { joint: 1, t: 0.5 }; n], skeleton.parents()).unwrap();
    let short_influences =
        Influences::new(influences.joints()[1..].to_vec(), influences.weights()[1..].to_vec(), 3).unwrap();
    let short_bindings = BonesBlendBindings::new(bindings[1..].to_vec(), skeleton.parents()).unwrap();
    let poison = Vec3::splat(-7.0);
    // Which buffer is one short: 0 positions (so every other buffer is one too long), 1 normals,
    // 2 output positions, 3 output normals, 4 the per-vertex joints, influences or bindings.
    let expected = |short: usize, per_vertex: &'static str| {
        let (what, expected, found) = match short {
            0 => (per_vertex, n - 1, n),
            1 => ("normals", n, n - 1),
            2 => ("output positions", n, n - 1),
            3 => ("output normals", n, n - 1),
            _ => (per_vertex, n, n - 1),
        };
        Err(SkinError::LengthMismatch { what, expected, found })
    };
    let cut = |short: usize, which: usize, len: usize| if short == which { len - 1 } else { len };
    for short in 0..5 {
        let (mut op, mut on) = (vec![poison; n], vec![poison; n]);
        let (p, nr) = (&positions[..cut(short, 0, n)], &normals[..cut(short, 1, n)]);
        let (op, on) = (&mut op[..cut(short, 2, n)], &mut on[..cut(short, 3, n)]);
        let rigid = RigidJob {
            palette: &palette,
            joints: &joints[..cut(short, 4, n)],
            positions: p,
            normals: nr,
            out_positions: op,
            out_normals: on,
        }
        .run();
        assert_eq!(rigid, expected(short, "joints"), "rigid, buffer {short} short");
        let influences = if short == 4 { &short_influences } else { &influences };
        let linear = LinearBlendJob {
            palette: &palette,
            influences,
            positions: p,
            normals: nr,
            out_positions: op,
            out_normals: on,
        }
        .run();
        assert_eq!(linear, expected(short, "influences"), "linear, buffer {short} short");
        let dual = DualQuatJob {
            dual_quaternions: &dqs,
            influences,
            positions: p,
            normals: nr,
            out_positions: op,
            out_normals: on,
        }
        .run();
        assert_eq!(dual, expected(short, "influences"), "dual quaternion, buffer {short} short");
        let bindings = if short == 4 { &short_bindings } else { &bindings };
        let blend = BonesBlendJob {
            palette: &palette,
            parents: skeleton.parents(),
            bindings,
            positions: p,
            normals: nr,
            out_positions: op,
            out_normals: on,
        }
        .run();
        assert_eq!(blend, expected(short, "bones-blending bindings"), "bones blending, buffer {short} short");
        assert!(op.iter().chain(on.iter()).all(|v| *v == poison));
    }
    // Bones blending also needs one parent entry per palette joint.
    let (mut op, mut on) = (vec![poison; n], vec![poison; n]);
    let blend = BonesBlendJob {
        palette: &palette,
        parents: &skeleton.parents()[..2],
        bindings: &bindings,
        positions: &positions,
        normals: &normals,
        out_positions: &mut op,
        out_normals: &mut on,
    }
    .run();
    assert_eq!(blend, Err(SkinError::LengthMismatch { what: "joint parents", expected: 3, found: 2 }));
}
