//! Times `BindJob` on the benchmark's 50 000-vertex tube once per method (a quick look; the
//! figures in docs/benchmarks.md come from `cargo bench -p keyrig-skin --bench bind`).
//!
//! cargo run --release -p keyrig-skin --example bind_timing [bones]

use glam::{Quat, Vec3};
use keyrig_skin::{tube_mesh, BindJob, BindMethod, RestJoint, RestSkeleton};

fn main() {
    let bones: usize = std::env::args().nth(1).and_then(|a| a.parse().ok()).unwrap_or(4);
    let (positions, indices) = tube_mesh(250, 200, 16.0, 1.0);
    let step = 16.0 / bones as f32;
    let joints: Vec<RestJoint> = (0..bones)
        .map(|j| {
            let t = if j == 0 { Vec3::ZERO } else { Vec3::X * step };
            RestJoint::new(format!("j{j}"), j.checked_sub(1), t, Quat::IDENTITY)
        })
        .collect();
    let skeleton = RestSkeleton::new(&joints).expect("chain");
    for method in BindMethod::ALL {
        let started = std::time::Instant::now();
        let influences = BindJob::new(&positions, &indices, &skeleton, method).run().expect("bind");
        println!(
            "{}: {} vertices, {bones} bones, {:.3} s",
            method.name(),
            influences.len(),
            started.elapsed().as_secs_f64()
        );
    }
}
