//! Data shared by `benches/deformers.rs` (criterion) and
//! `examples/deformer_timing.rs` (interleaved minimum times), so both measure the same thing:
//! a random branching skeleton of [`JOINTS`] joints, a random pose, and vertices with 4
//! influences on neighbouring joints.

use glam::{Mat4, Quat, Vec3};
use keyrig_skin::{
    BonesBlendBindings, BonesBlendVertex, DualQuat, Influences, JointPalette, Pose, RestJoint, RestSkeleton,
};

pub const JOINTS: usize = 64;

pub struct Lcg(pub u64);

impl Lcg {
    pub fn next_f32(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 40) as f32) / ((1u64 << 24) as f32)
    }
    pub fn vec3(&mut self, r: f32) -> Vec3 {
        Vec3::new(self.next_f32() - 0.5, self.next_f32() - 0.5, self.next_f32() - 0.5) * 2.0 * r
    }
    pub fn quat(&mut self) -> Quat {
        Quat::from_axis_angle(
            self.vec3(1.0).try_normalize().unwrap_or(Vec3::X),
            (self.next_f32() - 0.5) * 6.0,
        )
    }
    pub fn index(&mut self, n: usize) -> usize {
        ((self.next_f32() * n as f32) as usize).min(n - 1)
    }
}

pub struct Data {
    pub skeleton: RestSkeleton,
    pub palette: JointPalette,
    pub dual_quaternions: Vec<DualQuat>,
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
    pub joints: Vec<[u16; 4]>,
    pub weights: Vec<[f32; 4]>,
    /// `joints` and `weights`, validated once (what the jobs take).
    pub influences: Influences,
    pub bones: Vec<u16>,
    /// Bones-blending bindings, validated once (what the job takes).
    pub bindings: BonesBlendBindings,
    // The same data in ozz's layout (for the C++ driver, tools/ozz-driver).
    pub ozz_palette: Vec<Mat4>,
    pub ozz_joints: Vec<u16>,
    pub ozz_weights: Vec<f32>,
}

pub fn data(n: usize) -> Data {
    data_with_joints(n, JOINTS)
}

/// [`data`] with a skeleton of `joint_count` joints (at least 4).
pub fn data_with_joints(n: usize, joint_count: usize) -> Data {
    let mut rng = Lcg(42);
    let joints: Vec<RestJoint> = (0..joint_count)
        .map(|j| {
            RestJoint::new(
                format!("j{j}"),
                if j == 0 { None } else { Some(rng.index(j)) },
                rng.vec3(1.0),
                rng.quat(),
            )
        })
        .collect();
    let skeleton = RestSkeleton::new(&joints).unwrap();
    let rotations = (0..joint_count).map(|_| rng.quat()).collect();
    let pose = Pose::from_rotations(rotations, rng.vec3(1.0));
    let palette = JointPalette::new(&skeleton, &pose).unwrap();
    let dual_quaternions = palette.dual_quaternions().unwrap();
    let mut d = Data {
        ozz_palette: palette.skinning.iter().map(|m| Mat4::from(*m)).collect(),
        skeleton,
        palette,
        dual_quaternions,
        positions: Vec::with_capacity(n),
        normals: Vec::with_capacity(n),
        joints: Vec::with_capacity(n),
        weights: Vec::with_capacity(n),
        influences: Influences::default(),
        bones: Vec::with_capacity(n),
        bindings: BonesBlendBindings::default(),
        ozz_joints: Vec::with_capacity(4 * n),
        ozz_weights: Vec::with_capacity(3 * n),
    };
    let mut bindings = Vec::with_capacity(n);
    for _ in 0..n {
        d.positions.push(rng.vec3(10.0));
        d.normals.push(rng.vec3(1.0).try_normalize().unwrap_or(Vec3::Y));
        // Neighbouring joints, as in real meshes (a vertex near one place in the skeleton).
        let base = rng.index(joint_count - 3);
        let js = [base as u16, base as u16 + 1, base as u16 + 2, base as u16 + 3];
        let ws = [0.0f32; 4].map(|_| rng.next_f32() + 0.01);
        let sum: f32 = ws.iter().sum();
        let ws = ws.map(|w| w / sum);
        d.joints.push(js);
        d.weights.push(ws);
        d.bones.push(js[0]);
        let k = base + 1;
        bindings.push(BonesBlendVertex { joint: k as u32, t: rng.next_f32() });
        d.ozz_joints.extend_from_slice(&js);
        d.ozz_weights.extend_from_slice(&ws[..3]);
    }
    d.influences = Influences::new(d.joints.clone(), d.weights.clone(), joint_count).unwrap();
    d.bindings = BonesBlendBindings::new(bindings, d.skeleton.parents()).unwrap();
    d
}
