//! Interleaved minimum-time measurement of the four deformers on the same data as
//! `benches/deformers.rs`. The peer, ozz-animation's C++ `SkinningJob`, is timed by
//! `tools/ozz-driver/driver.cc` on data this example writes (`KEYRIG_SKIN_DUMP=DIR`, below);
//! run the two alternately, as docs/skinning-vs-ozz.md shows. On a shared machine the minimum
//! over many interleaved rounds is far less sensitive to other processes than criterion's
//! mean; use it for the ratios, and criterion for the full statistics.
//!
//! Two plain copies are the memory-bandwidth reference: `copy_50` moves as many bytes as rigid
//! (50 per vertex, read + written), `copy_72` as many as linear blend and dual quaternion (72);
//! in the all-cores pass they copy in parallel chunks on rayon's pool. They run in rounds of
//! their own after the deformers' rounds, so that they do not evict the deformers' data between
//! one deformer and the next.
//!
//! A last pass runs each deformer after sleeping 16.7 ms (one job per frame at 60 fps), on one
//! thread and then on all cores: jobs that start cold, with the pool asleep.
//!
//! cargo run --release -p keyrig-skin --example deformer_timing -- [VERTICES] [ROUNDS]
//!
//! `KEYRIG_SKIN_DUMP=DIR` also writes the data in ozz-animation's layout for the C++ driver:
//! `palette.f32` (16 floats per joint, column-major), `joints.u16` (4 per vertex),
//! `weights3.f32` (3 per vertex; ozz restores the fourth as 1 − Σ), `positions.f32`,
//! `normals.f32` (3 per vertex) and `keyrig_positions.f32` (linear blend's output, to check).
//!
//! `KEYRIG_SKIN_WEIGHT_PRECISION=1` runs only an accuracy check instead: the weights stored
//! as normalized 16-bit integers (as glTF allows; three rounded, the fourth 65535 − their sum)
//! against the f32 weights, linear blend's largest position error relative to the posed
//! model's size (bounding-box diagonal). No kernel reads such weights; this measures whether
//! one could.
//!
//! `KEYRIG_SKIN_JOINTS=COUNT` gives the skeleton COUNT joints instead of 64.

use std::time::{Duration, Instant};

use glam::Vec3;
use keyrig_skin::{BonesBlendJob, DualQuatJob, Execution, LinearBlendJob, RigidJob};
use rayon::prelude::*;

#[path = "../benches/support/mod.rs"]
mod support;

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().map(|a| a.parse()).transpose()?.unwrap_or(100_000);
    let rounds: usize = args.next().map(|a| a.parse()).transpose()?.unwrap_or(40);
    let data = match std::env::var("KEYRIG_SKIN_JOINTS") {
        Ok(joints) => match joints.parse::<usize>() {
            Ok(count) if (4..=u16::MAX as usize).contains(&count) => support::data_with_joints(n, count),
            _ => {
                return Err(
                    format!("KEYRIG_SKIN_JOINTS={joints:?}: expected a joint count from 4 to 65535").into()
                )
            }
        },
        Err(_) => support::data(n),
    };
    if let Some(dir) = std::env::var_os("KEYRIG_SKIN_DUMP") {
        dump(&data, std::path::Path::new(&dir))?;
    }
    if std::env::var_os("KEYRIG_SKIN_WEIGHT_PRECISION").is_some() {
        return weight_precision(&data);
    }
    let mut op = vec![Vec3::ZERO; n];
    let mut on = vec![Vec3::ZERO; n];
    let names = ["rigid", "linear", "bones_blending", "dual_quaternion", "copy_50", "copy_72"];
    // Bytes read + written per vertex (positions, normals, influences in; positions, normals out).
    let bytes_per_vertex = [50, 72, 56, 72, 50, 72];
    let copy_source = vec![1.0f32; n * 72 / 8];
    let mut copy_target = vec![0.0f32; n * 72 / 8];
    for execution in [Execution::SingleThreaded, Execution::Parallel] {
        let mut best = [Duration::MAX; 6];
        for _ in 0..rounds {
            for (d, slot) in best.iter_mut().enumerate().take(4) {
                let start = Instant::now();
                deform(d, &data, execution, &mut op, &mut on)?;
                std::hint::black_box(&op);
                *slot = (*slot).min(start.elapsed());
            }
        }
        for _ in 0..rounds {
            for (d, slot) in best.iter_mut().enumerate().skip(4) {
                // Half the bytes read, half written.
                let floats = n * bytes_per_vertex[d] / 8;
                let (from, to) = (&copy_source[..floats], &mut copy_target[..floats]);
                let start = Instant::now();
                if execution == Execution::Parallel {
                    to.par_chunks_mut(16 * 1024)
                        .zip(from.par_chunks(16 * 1024))
                        .for_each(|(t, f)| t.copy_from_slice(f));
                } else {
                    to.copy_from_slice(from);
                }
                std::hint::black_box(&copy_target);
                *slot = (*slot).min(start.elapsed());
            }
        }
        println!("{n} vertices, {execution:?}, minimum of {rounds} interleaved rounds:");
        let lbs = best[1].as_secs_f64();
        for ((name, t), bytes) in names.iter().zip(best).zip(bytes_per_vertex) {
            let t = t.as_secs_f64();
            println!(
                "  {name:16} {:9.3} ms  {:6.1} Mvertices/s  {:5.2}x linear  {:5.1} GB/s",
                t * 1e3,
                n as f64 / t / 1e6,
                t / lbs,
                (n * bytes) as f64 / t / 1e9
            );
        }
    }
    // One job per frame at 60 frames per second: each deformer after an idle gap of 16.7 ms, on
    // one thread and on all cores. The pool threads are asleep when the job starts (the gap is
    // longer than their linger), as for an editor skinning one mesh per frame.
    let gap = Duration::from_micros(16_667);
    let gap_rounds = rounds.min(20);
    let mut best = [[Duration::MAX; 2]; 4];
    for (e, execution) in [Execution::SingleThreaded, Execution::Parallel].into_iter().enumerate() {
        for _ in 0..gap_rounds {
            for (d, slots) in best.iter_mut().enumerate() {
                std::thread::sleep(gap);
                let start = Instant::now();
                deform(d, &data, execution, &mut op, &mut on)?;
                std::hint::black_box(&op);
                slots[e] = slots[e].min(start.elapsed());
            }
        }
    }
    println!(
        "{n} vertices, each job after an idle gap of {:.1} ms (one job per frame at 60 fps), minimum of \
         {gap_rounds} rounds:",
        gap.as_secs_f64() * 1e3
    );
    for (name, [one, all]) in names.iter().zip(best) {
        let (one, all) = (one.as_secs_f64(), all.as_secs_f64());
        println!(
            "  {name:16} {:9.3} ms 1 thread  {:9.3} ms all cores  {:5.2}x",
            one * 1e3,
            all * 1e3,
            one / all
        );
    }
    Ok(())
}

/// Runs deformer `d` (0 rigid, 1 linear blend, 2 bones blending, 3 dual quaternion).
fn deform(
    d: usize,
    data: &support::Data,
    execution: Execution,
    op: &mut [Vec3],
    on: &mut [Vec3],
) -> Result<(), Box<dyn std::error::Error>> {
    match d {
        0 => RigidJob {
            palette: &data.palette,
            joints: &data.bones,
            positions: &data.positions,
            normals: &data.normals,
            out_positions: op,
            out_normals: on,
        }
        .run_with(execution)?,
        1 => LinearBlendJob {
            palette: &data.palette,
            influences: &data.influences,
            positions: &data.positions,
            normals: &data.normals,
            out_positions: op,
            out_normals: on,
        }
        .run_with(execution)?,
        2 => BonesBlendJob {
            palette: &data.palette,
            parents: data.skeleton.parents(),
            bindings: &data.bindings,
            positions: &data.positions,
            normals: &data.normals,
            out_positions: op,
            out_normals: on,
        }
        .run_with(execution)?,
        _ => DualQuatJob {
            dual_quaternions: &data.dual_quaternions,
            influences: &data.influences,
            positions: &data.positions,
            normals: &data.normals,
            out_positions: op,
            out_normals: on,
        }
        .run_with(execution)?,
    }
    Ok(())
}

/// Writes the data in ozz-animation's layout (see the module docs) for the C++ driver.
fn dump(data: &support::Data, dir: &std::path::Path) -> Result<(), Box<dyn std::error::Error>> {
    fn floats(values: impl IntoIterator<Item = f32>) -> Vec<u8> {
        values.into_iter().flat_map(f32::to_le_bytes).collect()
    }
    std::fs::create_dir_all(dir)?;
    let n = data.positions.len();
    let (mut op, mut on) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
    deform(1, data, Execution::SingleThreaded, &mut op, &mut on)?;
    let files: [(&str, Vec<u8>); 6] = [
        ("palette.f32", floats(data.ozz_palette.iter().flat_map(|m| m.to_cols_array()))),
        ("joints.u16", data.ozz_joints.iter().flat_map(|j| j.to_le_bytes()).collect()),
        ("weights3.f32", floats(data.ozz_weights.iter().copied())),
        ("positions.f32", floats(data.positions.iter().flat_map(|p| p.to_array()))),
        ("normals.f32", floats(data.normals.iter().flat_map(|p| p.to_array()))),
        ("keyrig_positions.f32", floats(op.iter().flat_map(|p| p.to_array()))),
    ];
    for (name, bytes) in files {
        std::fs::write(dir.join(name), bytes)?;
    }
    Ok(())
}

/// Linear blend with unorm16 weights against f32 weights (see the module docs), with two ways
/// of making the four 16-bit weights sum to exactly 65535: the fourth gets the remainder (as
/// ozz-animation restores its last weight), or the largest does (the smallest relative error).
fn weight_precision(data: &support::Data) -> Result<(), Box<dyn std::error::Error>> {
    let n = data.positions.len();
    let (mut exact, mut exact_n) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
    deform(1, data, Execution::Reference, &mut exact, &mut exact_n)?;
    let min = exact.iter().fold(Vec3::MAX, |a, &b| a.min(b));
    let max = exact.iter().fold(Vec3::MIN, |a, &b| a.max(b));
    let size = (max - min).length();
    for remainder_on_largest in [false, true] {
        let quantized: Vec<[f32; 4]> = data
            .weights
            .iter()
            .map(|ws| {
                let last = if remainder_on_largest {
                    (0..4).max_by(|&a, &b| ws[a].total_cmp(&ws[b])).unwrap_or(3)
                } else {
                    3
                };
                let mut q = ws.map(|w| (w * 65535.0).round() as u32);
                let others: u32 = (0..4).filter(|&i| i != last).map(|i| q[i]).sum();
                q[last] = 65535u32.saturating_sub(others);
                q.map(|q| q as f32 / 65535.0)
            })
            .collect();
        let influences = keyrig_skin::Influences::new(data.joints.clone(), quantized, data.palette.len())?;
        let (mut q, mut q_n) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
        LinearBlendJob {
            palette: &data.palette,
            influences: &influences,
            positions: &data.positions,
            normals: &data.normals,
            out_positions: &mut q,
            out_normals: &mut q_n,
        }
        .run_with(Execution::Reference)?;
        let worst = exact.iter().zip(&q).map(|(a, b)| a.distance(*b)).fold(0.0f32, f32::max);
        let mean = exact.iter().zip(&q).map(|(a, b)| a.distance(*b) as f64).sum::<f64>() / n as f64;
        let scheme = if remainder_on_largest { "largest weight" } else { "fourth weight" };
        println!(
            "{n} vertices, unorm16 weights, remainder on the {scheme}: model size {size:.3}, largest position \
             error {worst:.3e} ({:.2e} of the size), mean {mean:.3e} ({:.2e} of the size)",
            worst / size,
            mean / size as f64
        );
    }
    Ok(())
}
