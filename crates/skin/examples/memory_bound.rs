//! Is rigid skinning of a big mesh on all cores bound by memory bandwidth? Measures, with every
//! cache emptied before each call (96 MiB of other data written first), on one thread and on
//! two:
//!
//! - `read`: summing as many bytes as rigid reads (26 per vertex: positions, normals, joints);
//! - `write`: filling as many bytes as rigid writes (24 per vertex);
//! - `copy`: reading and writing 24 bytes per vertex in one pass (`copy_from_slice`), about
//!   rigid's traffic;
//! - `rigid`: the rigid job itself (`Execution::SingleThreaded` and `Execution::Parallel`).
//!
//! Minimum of the rounds, interleaved; GB/s count the bytes read and written once each. If one
//! thread reading alone already reaches what two threads reach, memory is the limit, and a
//! kernel that moves its bytes at that rate on two threads cannot gain more from the second
//! core than its single-threaded time allows.
//!
//! cargo run --release -p keyrig-skin --example memory_bound -- [VERTICES] [ROUNDS]

use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use glam::Vec3;
use keyrig_skin::{Execution, RigidJob};

#[path = "../benches/support/mod.rs"]
#[allow(dead_code)]
mod support;

/// Runs `work(range)` over `0..n` split into `threads` equal parts, one per thread, and returns
/// the time from the start signal until every part is done. The helper threads are started and
/// spinning before the clock starts, so no thread start-up is timed.
fn split(threads: usize, n: usize, work: &(dyn Fn(std::ops::Range<usize>) + Sync)) -> Duration {
    let go = AtomicBool::new(false);
    std::thread::scope(|s| {
        let helpers: Vec<_> = (1..threads)
            .map(|t| {
                let go = &go;
                s.spawn(move || {
                    while !go.load(Ordering::Acquire) {
                        std::hint::spin_loop();
                    }
                    work(n * t / threads..n * (t + 1) / threads);
                })
            })
            .collect();
        std::thread::sleep(Duration::from_millis(1));
        let start = Instant::now();
        go.store(true, Ordering::Release);
        work(0..n / threads);
        for h in helpers {
            h.join().expect("a helper thread panicked");
        }
        start.elapsed()
    })
}

/// Sixteen independent sums, so the loop is bound by loads, not by one addition chain.
fn sum(xs: &[f32]) -> f32 {
    let mut acc = [0.0f32; 16];
    let chunks = xs.chunks_exact(16);
    let rest: f32 = chunks.remainder().iter().sum();
    for c in chunks {
        for (a, x) in acc.iter_mut().zip(c) {
            *a += x;
        }
    }
    acc.iter().sum::<f32>() + rest
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let mut args = std::env::args().skip(1);
    let n: usize = args.next().map(|a| a.parse()).transpose()?.unwrap_or(1_000_000);
    let rounds: usize = args.next().map(|a| a.parse()).transpose()?.unwrap_or(15);
    // Emptying the caches takes longer than the pool threads linger (1 ms), so the rigid job
    // on 2 threads includes waking its helper (20–50 µs), unlike the spinning helpers of the
    // other measurements.
    let data = support::data(n);
    let (mut op, mut on) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
    let read_floats = n * 26 / 4;
    let write_floats = n * 24 / 4;
    let source = vec![1.0f32; read_floats];
    let mut target = vec![0.0f32; write_floats];
    let mut evict = vec![0u8; 96 << 20];
    let names = ["read", "write", "copy", "rigid"];
    let bytes = [26 * n, 24 * n, 48 * n, 50 * n];
    let mut best = [[Duration::MAX; 2]; 4];
    for _ in 0..rounds {
        for (k, slot) in best.iter_mut().enumerate() {
            for (t, threads) in [1usize, 2].into_iter().enumerate() {
                for line in evict.chunks_mut(64) {
                    line[0] = line[0].wrapping_add(1);
                }
                std::hint::black_box(&evict);
                let target_ptr = target.as_mut_ptr() as usize;
                let elapsed = match k {
                    0 => split(threads, read_floats, &|r| {
                        std::hint::black_box(sum(&source[r]));
                    }),
                    1 => split(threads, write_floats, &|r| {
                        // SAFETY: the threads' ranges are disjoint parts of `target`.
                        let out = unsafe {
                            std::slice::from_raw_parts_mut((target_ptr as *mut f32).add(r.start), r.len())
                        };
                        out.fill(2.0);
                    }),
                    2 => split(threads, write_floats, &|r| {
                        // SAFETY: as above.
                        let out = unsafe {
                            std::slice::from_raw_parts_mut((target_ptr as *mut f32).add(r.start), r.len())
                        };
                        out.copy_from_slice(&source[r]);
                    }),
                    _ => {
                        let start = Instant::now();
                        RigidJob {
                            palette: &data.palette,
                            joints: &data.bones,
                            positions: &data.positions,
                            normals: &data.normals,
                            out_positions: &mut op,
                            out_normals: &mut on,
                        }
                        .run_with(if threads == 1 {
                            Execution::SingleThreaded
                        } else {
                            Execution::Parallel
                        })?;
                        start.elapsed()
                    }
                };
                slot[t] = slot[t].min(elapsed);
                std::hint::black_box((&target, &op));
            }
        }
    }
    println!("{n} vertices, caches emptied before every call, minimum of {rounds} interleaved rounds:");
    for (k, name) in names.iter().enumerate() {
        let [one, two] = best[k].map(|d| d.as_secs_f64());
        println!(
            "  {name:10} {:7.3} ms 1 thread ({:5.1} GB/s)   {:7.3} ms 2 threads ({:5.1} GB/s)   {:.2}x",
            one * 1e3,
            bytes[k] as f64 / one / 1e9,
            two * 1e3,
            bytes[k] as f64 / two / 1e9,
            one / two
        );
    }
    Ok(())
}
