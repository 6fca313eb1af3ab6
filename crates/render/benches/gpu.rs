//! GPU benchmarks on the adapter wgpu finds (lavapipe without a GPU):
//! - `skinning/<deformer>/<n>`: one compute pass over n vertices (4 influences), submitted and
//!   waited for; joint data re-uploaded each iteration as in a real frame;
//! - `demo_frame/1280x720`: one whole frame of assets/demo.ron (sampling, palettes, upload,
//!   skinning, drawing, MSAA resolve), waited for but not read back; also with 1 sample per
//!   pixel (`1280x720_1x`) and with parts of the frame removed (`clear_only`, `meshes_only`,
//!   `grid_only`, `no_grid`) to show where the time goes.
//!
//! Bytes uploaded per frame are printed (they are exact counts, not timings).
//! Run: `cargo bench -p keyrig-render --bench gpu -- --warm-up-time 1 --measurement-time 3`

use criterion::{criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::{Quat, Vec3};
use keyrig_core::{DeformerKind, ProceduralMesh};
use keyrig_render::{
    joint_poses, GpuContext, GpuSkinner, HeadlessRenderer, OwnedSkinInput, SceneRig, ViewOptions, Viewport,
    HEADLESS_FORMAT,
};
use keyrig_skin::{mesh_for, BlendZone, JointPalette, Pose};

/// The high-poly arm tiled `copies` times side by side (same skeleton and weights).
fn tiled_arm(vertex_count: usize) -> (OwnedSkinInput, Vec<keyrig_render::JointPose>) {
    let mesh = mesh_for(ProceduralMesh::ArmHighPoly);
    let bindings = mesh.bindings(BlendZone::default()).expect("bindings");
    let one = OwnedSkinInput::from_skinned_mesh(&mesh, &bindings);
    let n = one.positions.len();
    let mut input = OwnedSkinInput {
        positions: Vec::with_capacity(vertex_count),
        normals: Vec::with_capacity(vertex_count),
        joints: Vec::with_capacity(vertex_count),
        weights: Vec::with_capacity(vertex_count),
        rigid_joints: Vec::with_capacity(vertex_count),
        blend: Vec::with_capacity(vertex_count),
        bind_from_model: one.bind_from_model.clone(),
    };
    for i in 0..vertex_count {
        let k = i % n;
        let copy = (i / n) as f32;
        input.positions.push(one.positions[k] + Vec3::new(0.0, 0.0, copy * 50.0));
        input.normals.push(one.normals[k]);
        input.joints.push(one.joints[k]);
        input.weights.push(one.weights[k]);
        input.rigid_joints.push(one.rigid_joints[k]);
        input.blend.push(one.blend[k]);
    }
    let pose = Pose::rest(mesh.skeleton.len())
        .with_rotation(1, Quat::from_rotation_z(-0.8))
        .with_rotation(2, Quat::from_rotation_x(2.5));
    let palette = JointPalette::new(&mesh.skeleton, &pose).expect("palette");
    (input, joint_poses(&palette))
}

fn skinning(c: &mut Criterion) {
    let gpu = GpuContext::headless().unwrap_or_else(|e| panic!("{e}"));
    eprintln!("adapter: {}", gpu.adapter_summary());
    let skinner = GpuSkinner::new(&gpu.device);
    let mut group = c.benchmark_group("skinning");
    group.sample_size(10);
    for n in [100_000usize, 1_000_000] {
        let (input, poses) = tiled_arm(n);
        let skin = skinner.create_skin(&gpu.device, &input.as_input()).expect("upload");
        group.throughput(Throughput::Elements(n as u64));
        for deformer in DeformerKind::ALL {
            group.bench_with_input(BenchmarkId::new(deformer.cli_name(), n), &n, |b, _| {
                b.iter(|| {
                    let bytes = skinner.write_joints(&gpu.queue, &skin, 0, &poses).expect("joints");
                    let mut encoder = gpu.device.create_command_encoder(&Default::default());
                    skinner.encode(&mut encoder, &skin, deformer);
                    gpu.queue.submit([encoder.finish()]);
                    gpu.device.poll(wgpu::PollType::wait_indefinitely()).expect("poll");
                    bytes
                });
            });
        }
        eprintln!(
            "skinning {n} vertices: {} bytes of joint data uploaded per frame ({} joints × {} bytes); \
             vertex data ({} bytes) uploaded once",
            poses.len() as u64 * keyrig_render::skinning::JOINT_FRAME_BYTES,
            poses.len(),
            keyrig_render::skinning::JOINT_FRAME_BYTES,
            n as u64 * keyrig_render::skinning::SKIN_VERTEX_BYTES,
        );
    }
    group.finish();
}

fn demo_frame(c: &mut Criterion) {
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo.ron");
    let scene = keyrig_io::scene_file::load(&path).unwrap_or_else(|e| panic!("{e}"));
    let mut headless = HeadlessRenderer::new().unwrap_or_else(|e| panic!("{e}"));
    let rig = SceneRig::new(&scene).expect("rig");
    rig.upload(headless.renderer_mut()).expect("upload");
    let view = ViewOptions::default();
    let mut group = c.benchmark_group("demo_frame");
    group.sample_size(20);
    let mut frame_number = 0u32;
    let mut last_stats = None;
    // Where the time goes: the same frame with parts of it removed.
    type Strip = fn(&mut keyrig_render::FrameInput);
    let parts: [(&str, Strip); 5] = [
        ("", |_| {}),
        ("/clear_only", |f| {
            f.items.clear();
            f.grid_spacing = None;
            f.skeletons.clear();
            f.motion_paths.clear();
            f.light_gizmos.clear();
        }),
        ("/meshes_only", |f| {
            f.grid_spacing = None;
            f.skeletons.clear();
            f.motion_paths.clear();
            f.light_gizmos.clear();
        }),
        ("/grid_only", |f| {
            f.items.clear();
            f.skeletons.clear();
            f.motion_paths.clear();
            f.light_gizmos.clear();
        }),
        ("/no_grid", |f| f.grid_spacing = None),
    ];
    // 4× MSAA (headless images, `keyrig render`) and 1 sample (the editor on a CPU adapter).
    for (samples, size_name) in [(4, "1280x720"), (1, "1280x720_1x")] {
        headless.renderer_mut().set_sample_count(samples).expect("sample count");
        let viewport =
            Viewport::with_sample_count(&headless.gpu().device, 1280, 720, HEADLESS_FORMAT, samples)
                .expect("viewport");
        for (part, strip) in parts {
            group.bench_function(format!("{size_name}{part}"), |b| {
                b.iter(|| {
                    frame_number = (frame_number + 1) % 90;
                    let mut frame =
                        rig.frame(rig.time_of_frame(f64::from(frame_number)), &view).expect("frame");
                    strip(&mut frame);
                    let stats = headless.renderer_mut().render(&frame, &viewport).expect("render");
                    headless.gpu().device.poll(wgpu::PollType::wait_indefinitely()).expect("poll");
                    if part.is_empty() {
                        last_stats = Some(stats);
                    }
                });
            });
        }
    }
    group.finish();
    if let Some(stats) = last_stats {
        eprintln!(
            "demo frame uploads: {} bytes total = joints {} + uniforms {} + overlay lines {} + morph {}; \
             {} vertices deformed, {} draw calls",
            stats.bytes_uploaded(),
            stats.joint_bytes,
            stats.uniform_bytes,
            stats.overlay_bytes,
            stats.morph_bytes,
            stats.deformed_vertices,
            stats.draw_calls
        );
    }
}

criterion_group!(benches, skinning, demo_frame);
criterion_main!(benches);
