//! Interleaved minimum-time measurement of the four deformers and the ozz-style loop on the
//! same data as `benches/deformers.rs`. On a shared machine the minimum over many interleaved
//! rounds is far less sensitive to other processes than criterion's mean; use it for the
//! ratios, and criterion for the full statistics.
//!
//! cargo run --release -p keyrig-skin --example deformer_timing -- [VERTICES] [ROUNDS]

use std::time::{Duration, Instant};

use glam::{Mat4, Quat, Vec3, Vec4};
use keyrig_skin::{
    BonesBlendJob, BonesBlendVertex, DualQuatJob, Execution, JointPalette, LinearBlendJob, Pose, RestJoint,
    RestSkeleton, RigidJob,
};

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

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().map(|a| a.parse()).transpose()?.unwrap_or(100_000);
    let rounds: usize = args.next().map(|a| a.parse()).transpose()?.unwrap_or(40);
    const JOINTS: usize = 64;
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
    let skeleton = RestSkeleton::new(&joints)?;
    let pose =
        Pose { local_rotations: (0..JOINTS).map(|_| rng.quat()).collect(), root_translation: rng.vec3(1.0) };
    let palette = JointPalette::new(&skeleton, &pose)?;
    let dqs = palette.dual_quaternions()?;
    let ozz_palette: Vec<Mat4> = palette.skinning.iter().map(|m| Mat4::from(*m)).collect();
    let (mut positions, mut normals, mut js, mut ws, mut bones, mut bindings) =
        (Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new(), Vec::new());
    let (mut ozz_js, mut ozz_ws) = (Vec::new(), Vec::new());
    for _ in 0..n {
        positions.push(rng.vec3(10.0));
        normals.push(rng.vec3(1.0).try_normalize().unwrap_or(Vec3::Y));
        let base = rng.index(JOINTS - 3) as u16;
        let j = [base, base + 1, base + 2, base + 3];
        let w = [0.0f32; 4].map(|_| rng.next_f32() + 0.01);
        let sum: f32 = w.iter().sum();
        let w = w.map(|x| x / sum);
        js.push(j);
        ws.push(w);
        bones.push(base);
        bindings.push(BonesBlendVertex { joint: u32::from(base) + 1, t: rng.next_f32() });
        ozz_js.extend_from_slice(&j);
        ozz_ws.extend_from_slice(&w[..3]);
    }
    let mut op = vec![Vec3::ZERO; n];
    let mut on = vec![Vec3::ZERO; n];
    let names = ["ozz_port", "rigid", "linear", "bones_blending", "dual_quaternion"];
    for execution in [Execution::SingleThreaded, Execution::Parallel] {
        let mut best = [Duration::MAX; 5];
        for _ in 0..rounds {
            for (d, slot) in best.iter_mut().enumerate() {
                let start = Instant::now();
                match d {
                    0 => {
                        for i in 0..n {
                            let (wo, io) = (i * 3, i * 4);
                            let col = |m: &Mat4, w: Vec4| {
                                Mat4::from_cols(m.x_axis * w, m.y_axis * w, m.z_axis * w, m.w_axis * w)
                            };
                            let w = Vec4::splat(ozz_ws[wo]);
                            let mut sum = w;
                            let mut t = col(ozz_palette.get(ozz_js[io] as usize).ok_or("index")?, w);
                            for k in 1..3 {
                                let w = Vec4::splat(ozz_ws[wo + k]);
                                sum += w;
                                t += col(ozz_palette.get(ozz_js[io + k] as usize).ok_or("index")?, w);
                            }
                            t += col(
                                ozz_palette.get(ozz_js[io + 3] as usize).ok_or("index")?,
                                Vec4::ONE - sum,
                            );
                            op[i] = t.transform_point3(positions[i]);
                            on[i] = t.transform_vector3(normals[i]);
                        }
                    }
                    1 => RigidJob {
                        palette: &palette,
                        joints: &bones,
                        positions: &positions,
                        normals: &normals,
                        out_positions: &mut op,
                        out_normals: &mut on,
                    }
                    .run_with(execution)?,
                    2 => LinearBlendJob {
                        palette: &palette,
                        joints: &js,
                        weights: &ws,
                        positions: &positions,
                        normals: &normals,
                        out_positions: &mut op,
                        out_normals: &mut on,
                    }
                    .run_with(execution)?,
                    3 => BonesBlendJob {
                        palette: &palette,
                        parents: skeleton.parents(),
                        bindings: &bindings,
                        positions: &positions,
                        normals: &normals,
                        out_positions: &mut op,
                        out_normals: &mut on,
                    }
                    .run_with(execution)?,
                    _ => DualQuatJob {
                        dual_quaternions: &dqs,
                        joints: &js,
                        weights: &ws,
                        positions: &positions,
                        normals: &normals,
                        out_positions: &mut op,
                        out_normals: &mut on,
                    }
                    .run_with(execution)?,
                }
                std::hint::black_box(&op);
                *slot = (*slot).min(start.elapsed());
            }
        }
        println!("{n} vertices, {execution:?}, minimum of {rounds} interleaved rounds:");
        let lbs = best[2].as_secs_f64();
        for (name, t) in names.iter().zip(best) {
            let t = t.as_secs_f64();
            println!(
                "  {name:16} {:9.3} ms  {:6.1} Mvertices/s  {:5.2}x linear",
                t * 1e3,
                n as f64 / t / 1e6,
                t / lbs
            );
        }
        if execution == Execution::SingleThreaded {
            println!("  linear vs ozz_port throughput: {:.2}x", best[0].as_secs_f64() / lbs);
        }
    }
    Ok(())
}
