//! Each deformer on 1 000, 100 000 and 1 000 000 vertices with 4 influences (positions and
//! normals), single-threaded and on all cores, beside two peers measured in the same run:
//!
//! - `ozz_port`: ozz-animation-rs 0.11's `SkinningJob` loop for 4 influences with normals
//!   (`skinning_impl!` in its src/skinning_job.rs), re-implemented here on identical data: a
//!   Mat4 palette blended column by column with the last weight rebuilt as 1 − Σw, palette
//!   lookups through bounds-checked `get`, `transform_point3` / `transform_vector3`, normals not
//!   renormalized. The crate itself cannot be a dependency: it enables glam's `core-simd`
//!   (nightly `portable_simd`), which rustc 1.95 refuses, and its SIMD code no longer compiles
//!   against today's `std::simd` even with RUSTC_BOOTSTRAP.
//! - `memcpy`: a plain copy moving as many bytes (read + write) as linear blend does — the
//!   memory-bandwidth bound.
//!
//! Throughput is reported as bytes moved per second: read (positions 12 B, normals 12 B,
//! joints 8 B, weights 16 B; rigid: 2 B joint; bones blending: 8 B binding) plus written
//! (positions and normals, 24 B) per vertex.
//!
//! cargo bench -p keyrig-skin --bench deformers -- --warm-up-time 1 --measurement-time 2

use criterion::{black_box, criterion_group, criterion_main, BenchmarkId, Criterion, Throughput};
use glam::{Mat4, Quat, Vec3, Vec4};
use keyrig_skin::{
    BonesBlendJob, BonesBlendVertex, DualQuat, DualQuatJob, Execution, JointPalette, LinearBlendJob, Pose,
    RestJoint, RestSkeleton, RigidJob,
};

const JOINTS: usize = 64;

struct Lcg(u64);

impl Lcg {
    fn next_f32(&mut self) -> f32 {
        self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
        ((self.0 >> 40) as f32) / ((1u64 << 24) as f32)
    }
    fn vec3(&mut self, r: f32) -> Vec3 {
        Vec3::new(self.next_f32() - 0.5, self.next_f32() - 0.5, self.next_f32() - 0.5) * 2.0 * r
    }
    fn quat(&mut self) -> Quat {
        Quat::from_axis_angle(
            self.vec3(1.0).try_normalize().unwrap_or(Vec3::X),
            (self.next_f32() - 0.5) * 6.0,
        )
    }
    fn index(&mut self, n: usize) -> usize {
        ((self.next_f32() * n as f32) as usize).min(n - 1)
    }
}

struct Data {
    skeleton: RestSkeleton,
    palette: JointPalette,
    dual_quaternions: Vec<DualQuat>,
    positions: Vec<Vec3>,
    normals: Vec<Vec3>,
    joints: Vec<[u16; 4]>,
    weights: Vec<[f32; 4]>,
    bones: Vec<u16>,
    bindings: Vec<BonesBlendVertex>,
    // The same data in ozz's layout.
    ozz_palette: Vec<Mat4>,
    ozz_joints: Vec<u16>,
    ozz_weights: Vec<f32>,
}

fn data(n: usize) -> Data {
    let mut rng = Lcg(42);
    let joints: Vec<RestJoint> = (0..JOINTS)
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
    let pose =
        Pose { local_rotations: (0..JOINTS).map(|_| rng.quat()).collect(), root_translation: rng.vec3(1.0) };
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
        bones: Vec::with_capacity(n),
        bindings: Vec::with_capacity(n),
        ozz_joints: Vec::with_capacity(4 * n),
        ozz_weights: Vec::with_capacity(3 * n),
    };
    for _ in 0..n {
        d.positions.push(rng.vec3(10.0));
        d.normals.push(rng.vec3(1.0).try_normalize().unwrap_or(Vec3::Y));
        // Neighbouring joints, as in real meshes (a vertex near one place in the skeleton).
        let base = rng.index(JOINTS - 3);
        let js = [base as u16, base as u16 + 1, base as u16 + 2, base as u16 + 3];
        let ws = [0.0f32; 4].map(|_| rng.next_f32() + 0.01);
        let sum: f32 = ws.iter().sum();
        let ws = ws.map(|w| w / sum);
        d.joints.push(js);
        d.weights.push(ws);
        d.bones.push(js[0]);
        let k = base + 1;
        d.bindings.push(BonesBlendVertex { joint: k as u32, t: rng.next_f32() });
        d.ozz_joints.extend_from_slice(&js);
        d.ozz_weights.extend_from_slice(&ws[..3]);
    }
    d
}

/// ozz-animation-rs's 4-influence, positions-and-normals skinning loop, on glam Mat4.
fn ozz_port(d: &Data, out_positions: &mut [Vec3], out_normals: &mut [Vec3]) -> Result<(), &'static str> {
    #[inline(always)]
    fn col_mul(m: &Mat4, w: Vec4) -> Mat4 {
        Mat4::from_cols(m.x_axis * w, m.y_axis * w, m.z_axis * w, m.w_axis * w)
    }
    let (matrices, indices, weights) = (&d.ozz_palette, &d.ozz_joints, &d.ozz_weights);
    for i in 0..d.positions.len() {
        let wo = i * 3;
        let io = i * 4;
        let w = Vec4::splat(weights[wo]);
        let mut sum = w;
        let mut transform = col_mul(matrices.get(indices[io] as usize).ok_or("index")?, w);
        for j in 1..3 {
            let w = Vec4::splat(weights[wo + j]);
            sum += w;
            transform += col_mul(matrices.get(indices[io + j] as usize).ok_or("index")?, w);
        }
        let w = Vec4::ONE - sum;
        transform += col_mul(matrices.get(indices[io + 3] as usize).ok_or("index")?, w);
        out_positions[i] = transform.transform_point3(d.positions[i]);
        out_normals[i] = transform.transform_vector3(d.normals[i]);
    }
    Ok(())
}

fn bench_deformers(c: &mut Criterion) {
    for n in [1_000usize, 100_000, 1_000_000] {
        let d = data(n);
        let mut out_p = vec![Vec3::ZERO; n];
        let mut out_n = vec![Vec3::ZERO; n];
        let mut group = c.benchmark_group(format!("skin/{n}"));
        if n >= 1_000_000 {
            group.sample_size(10);
        }
        let written = 24 * n as u64;
        let lbs_bytes = 48 * n as u64 + written;

        // The bandwidth bound: copy half of LBS's traffic (read it, write it).
        let src = vec![0u8; lbs_bytes as usize / 2];
        let mut dst = vec![0u8; lbs_bytes as usize / 2];
        group.throughput(Throughput::Bytes(lbs_bytes));
        group.bench_function("memcpy", |b| {
            b.iter(|| {
                dst.copy_from_slice(black_box(&src));
                black_box(&mut dst);
            })
        });
        group.bench_function("ozz_port/1-thread", |b| {
            b.iter(|| ozz_port(black_box(&d), &mut out_p, &mut out_n).unwrap())
        });

        // What run() adds every frame: checking the 4 joints and weights of every vertex.
        group.throughput(Throughput::Bytes(24 * n as u64));
        group.bench_function("validate_weights/1-thread", |b| {
            b.iter(|| {
                LinearBlendJob {
                    palette: &d.palette,
                    joints: &d.joints,
                    weights: &d.weights,
                    positions: &d.positions,
                    normals: &d.normals,
                    out_positions: &mut out_p,
                    out_normals: &mut out_n,
                }
                .validate_single_threaded()
                .unwrap()
            })
        });
        for (label, execution) in
            [("1-thread", Execution::SingleThreaded), ("all-cores", Execution::Parallel)]
        {
            group.throughput(Throughput::Bytes(26 * n as u64 + written));
            group.bench_function(BenchmarkId::new("rigid", label), |b| {
                b.iter(|| {
                    RigidJob {
                        palette: &d.palette,
                        joints: &d.bones,
                        positions: &d.positions,
                        normals: &d.normals,
                        out_positions: &mut out_p,
                        out_normals: &mut out_n,
                    }
                    .run_with(execution)
                    .unwrap()
                })
            });
            group.throughput(Throughput::Bytes(lbs_bytes));
            group.bench_function(BenchmarkId::new("linear", label), |b| {
                b.iter(|| {
                    LinearBlendJob {
                        palette: &d.palette,
                        joints: &d.joints,
                        weights: &d.weights,
                        positions: &d.positions,
                        normals: &d.normals,
                        out_positions: &mut out_p,
                        out_normals: &mut out_n,
                    }
                    .run_with(execution)
                    .unwrap()
                })
            });
            group.throughput(Throughput::Bytes(32 * n as u64 + written));
            group.bench_function(BenchmarkId::new("bones_blending", label), |b| {
                b.iter(|| {
                    BonesBlendJob {
                        palette: &d.palette,
                        parents: d.skeleton.parents(),
                        bindings: &d.bindings,
                        positions: &d.positions,
                        normals: &d.normals,
                        out_positions: &mut out_p,
                        out_normals: &mut out_n,
                    }
                    .run_with(execution)
                    .unwrap()
                })
            });
            group.throughput(Throughput::Bytes(lbs_bytes));
            group.bench_function(BenchmarkId::new("dual_quaternion", label), |b| {
                b.iter(|| {
                    DualQuatJob {
                        dual_quaternions: &d.dual_quaternions,
                        joints: &d.joints,
                        weights: &d.weights,
                        positions: &d.positions,
                        normals: &d.normals,
                        out_positions: &mut out_p,
                        out_normals: &mut out_n,
                    }
                    .run_with(execution)
                    .unwrap()
                })
            });
        }
        group.finish();
    }
}

criterion_group!(benches, bench_deformers);
criterion_main!(benches);
