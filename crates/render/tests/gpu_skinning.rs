//! GPU skinning agrees with keyrig-skin's CPU reference: all four deformers, both test arms,
//! the paper's poses plus a pose that moves every joint. Buffers are read back from the GPU.
//!
//! Uses whatever adapter wgpu finds (lavapipe without a GPU); no adapter is a failure.

use glam::{Quat, Vec3};
use keyrig_core::{DeformerKind, ProceduralMesh};
use keyrig_render::skinning::read_skinned;
use keyrig_render::{joint_poses, GpuContext, GpuSkinner, OwnedSkinInput, SkinnedVertex};
use keyrig_skin::{
    deform_mesh_into, mesh_for, BlendZone, Deformed, Execution, JointPalette, Pose, SkinnedMesh,
};

fn gpu() -> GpuContext {
    match GpuContext::headless() {
        Ok(gpu) => gpu,
        Err(err) => panic!("GPU tests need a wgpu adapter: {err}"),
    }
}

fn model_size(mesh: &SkinnedMesh) -> f32 {
    let min = mesh.positions.iter().fold(Vec3::MAX, |a, &b| a.min(b));
    let max = mesh.positions.iter().fold(Vec3::MIN, |a, &b| a.max(b));
    (max - min).length()
}

fn poses(joint_count: usize) -> Vec<(&'static str, Pose)> {
    let rest = Pose::rest(joint_count);
    let mut everything = Pose::rest(joint_count);
    for (j, q) in everything.local_rotations.iter_mut().enumerate() {
        let axis = Vec3::new(1.0, 0.3 * j as f32, -0.5).normalize();
        *q = Quat::from_axis_angle(axis, 0.4 + 0.35 * j as f32);
    }
    everything.root_translation = Vec3::new(3.0, -2.0, 5.0);
    vec![
        ("rest", rest.clone()),
        (
            "bend 90° about -Z",
            rest.clone().with_rotation(2, Quat::from_axis_angle(-Vec3::Z, 90f32.to_radians())),
        ),
        ("twist 90° about X", rest.clone().with_rotation(2, Quat::from_rotation_x(90f32.to_radians()))),
        ("twist 170° about X", rest.clone().with_rotation(2, Quat::from_rotation_x(170f32.to_radians()))),
        ("twist 180° about X", rest.clone().with_rotation(2, Quat::from_rotation_x(180f32.to_radians()))),
        ("every joint", everything),
    ]
}

fn check_mesh(gpu: &GpuContext, skinner: &GpuSkinner, kind: ProceduralMesh) {
    let mesh = mesh_for(kind);
    let bindings = mesh.bindings(BlendZone::default()).expect("bindings of a procedural mesh");
    let input = OwnedSkinInput::from_skinned_mesh(&mesh, &bindings);
    let skin = skinner.create_skin(&gpu.device, &input.as_input()).expect("upload");
    let tolerance = 1e-4 * model_size(&mesh);
    for (pose_name, pose) in poses(mesh.skeleton.len()) {
        let palette = JointPalette::new(&mesh.skeleton, &pose).expect("palette");
        let uploaded = skinner.write_joints(&gpu.queue, &skin, 0, &joint_poses(&palette)).expect("joints");
        assert_eq!(uploaded, mesh.skeleton.len() as u64 * 240);
        for deformer in DeformerKind::ALL {
            let mut cpu = Deformed::default();
            deform_mesh_into(&mesh, &bindings, &palette, deformer, Execution::Reference, &mut cpu)
                .expect("CPU");
            let mut encoder = gpu.device.create_command_encoder(&Default::default());
            // Poison: the previous deformer's output is still there, so a pass that writes
            // nothing fails the comparison.
            skinner.encode(&mut encoder, &skin, deformer);
            gpu.queue.submit([encoder.finish()]);
            let out: Vec<SkinnedVertex> =
                read_skinned(&gpu.device, &gpu.queue, &skin.output, skin.vertex_count).expect("readback");
            assert_eq!(out.len(), mesh.vertex_count());
            let mut worst = (0.0f32, 0usize);
            let mut worst_normal = (0.0f32, 0usize);
            for (i, v) in out.iter().enumerate() {
                let d = (v.position() - cpu.positions[i]).length();
                if d > worst.0 || d.is_nan() {
                    worst = (d, i);
                }
                let dn = (v.normal() - cpu.normals[i].normalize_or_zero()).length();
                if dn > worst_normal.0 || dn.is_nan() {
                    worst_normal = (dn, i);
                }
            }
            assert!(
                worst.0 <= tolerance,
                "{kind:?} / {pose_name} / {deformer:?}: vertex {} differs by {} (tolerance {tolerance}): GPU {} CPU {}",
                worst.1,
                worst.0,
                out[worst.1].position(),
                cpu.positions[worst.1]
            );
            assert!(
                worst_normal.0 <= 1e-3,
                "{kind:?} / {pose_name} / {deformer:?}: normal {} differs by {}",
                worst_normal.1,
                worst_normal.0
            );
        }
    }
}

#[test]
fn gpu_matches_cpu_on_the_low_poly_arm() {
    let gpu = gpu();
    let skinner = GpuSkinner::new(&gpu.device);
    check_mesh(&gpu, &skinner, ProceduralMesh::ArmLowPoly);
}

#[test]
fn gpu_matches_cpu_on_the_high_poly_arm() {
    let gpu = gpu();
    let skinner = GpuSkinner::new(&gpu.device);
    check_mesh(&gpu, &skinner, ProceduralMesh::ArmHighPoly);
}

#[test]
fn gpu_matches_cpu_on_the_branching_hand() {
    let gpu = gpu();
    let skinner = GpuSkinner::new(&gpu.device);
    check_mesh(&gpu, &skinner, ProceduralMesh::Hand);
}

#[test]
fn morphing_interpolates_two_frames() {
    let gpu = gpu();
    let skinner = GpuSkinner::new(&gpu.device);
    let frame_a: Vec<SkinnedVertex> =
        (0..100).map(|i| SkinnedVertex::new(Vec3::new(i as f32, 0.0, 1.0), Vec3::X)).collect();
    let frame_b: Vec<SkinnedVertex> =
        (0..100).map(|i| SkinnedVertex::new(Vec3::new(i as f32, 10.0, -1.0), Vec3::Y)).collect();
    let morph = skinner.create_morph(&gpu.device, &[frame_a.clone(), frame_b.clone()]).expect("upload");
    for t in [0.0f32, 0.25, 1.0] {
        skinner.write_morph(&gpu.queue, &morph, 0, 0, 1, t).expect("params");
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        skinner.encode_morph(&mut encoder, &morph);
        gpu.queue.submit([encoder.finish()]);
        let out = read_skinned(&gpu.device, &gpu.queue, &morph.output, morph.vertex_count).expect("readback");
        for (i, v) in out.iter().enumerate() {
            let expected = frame_a[i].position().lerp(frame_b[i].position(), t);
            assert!(
                (v.position() - expected).length() < 1e-5,
                "t {t} vertex {i}: {} vs {expected}",
                v.position()
            );
            let n = Vec3::X.lerp(Vec3::Y, t).normalize();
            assert!((v.normal() - n).length() < 1e-5, "t {t} vertex {i} normal {}", v.normal());
        }
    }
    let err = skinner.write_morph(&gpu.queue, &morph, 7, 0, 2, 0.5).unwrap_err();
    assert!(err.to_string().contains("morph frame 2 out of range"), "{err}");
}

/// glTF-style inverse bind matrices with non-uniform scale: the palette is not rigid, normals
/// need the inverse-transpose (keyrig-skin's `normal_skinning`), and GPU rigid / linear blend
/// must still agree with the CPU.
#[test]
fn gpu_matches_cpu_with_non_uniform_inverse_bind_matrices() {
    let gpu = gpu();
    let skinner = GpuSkinner::new(&gpu.device);
    let arm = mesh_for(ProceduralMesh::ArmLowPoly);
    let joints: Vec<keyrig_skin::RestJoint> = (0..arm.skeleton.len())
        .map(|j| {
            let rest = arm.skeleton.parent_from_joint()[j];
            keyrig_skin::RestJoint::new(
                arm.skeleton.names()[j].clone(),
                arm.skeleton.parents()[j],
                rest.translation.into(),
                Quat::IDENTITY,
            )
        })
        .collect();
    let ibms: Vec<glam::Mat4> = arm
        .skeleton
        .joint_from_bind_model()
        .iter()
        .map(|a| glam::Mat4::from_scale(Vec3::new(1.0, 1.6, 0.7)) * glam::Mat4::from(*a))
        .collect();
    let skeleton = keyrig_skin::RestSkeleton::with_inverse_bind_matrices(&joints, &ibms).expect("skeleton");
    let mesh = arm.with_skeleton(skeleton).expect("rebind");
    let bindings = mesh.bindings(BlendZone::default()).expect("bindings");
    let input = OwnedSkinInput::from_skinned_mesh(&mesh, &bindings);
    let skin = skinner.create_skin(&gpu.device, &input.as_input()).expect("upload");
    let pose = Pose::rest(mesh.skeleton.len()).with_rotation(2, Quat::from_rotation_x(1.0));
    let palette = JointPalette::new(&mesh.skeleton, &pose).expect("palette");
    assert!(palette.normal_skinning.is_some(), "the test needs a non-uniform palette");
    skinner.write_joints(&gpu.queue, &skin, 0, &joint_poses(&palette)).expect("joints");
    let tolerance = 1e-4 * model_size(&mesh) * 1.6;
    for deformer in [DeformerKind::Rigid, DeformerKind::LinearBlend] {
        let mut cpu = Deformed::default();
        deform_mesh_into(&mesh, &bindings, &palette, deformer, Execution::Reference, &mut cpu).expect("CPU");
        let mut encoder = gpu.device.create_command_encoder(&Default::default());
        skinner.encode(&mut encoder, &skin, deformer);
        gpu.queue.submit([encoder.finish()]);
        let out = read_skinned(&gpu.device, &gpu.queue, &skin.output, skin.vertex_count).expect("readback");
        for (i, v) in out.iter().enumerate() {
            let d = (v.position() - cpu.positions[i]).length();
            assert!(d <= tolerance, "{deformer:?} vertex {i}: position off by {d}");
            let dn = (v.normal() - cpu.normals[i].normalize_or_zero()).length();
            assert!(dn <= 1e-3, "{deformer:?} vertex {i}: normal {} vs {}", v.normal(), cpu.normals[i]);
        }
    }
}
