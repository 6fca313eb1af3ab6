//! The four skin deformers as jobs (ozz-animation's `SkinningJob` style): a struct of borrowed
//! inputs and `&mut` output slices, `validate()` that returns a typed error, and `run()` that
//! validates and then deforms. Each job has a plain reference implementation written formula
//! by formula ([`Execution::Reference`]) and a fast one (tightly packed data, no allocation,
//! rayon across chunks of [`CHUNK`] vertices); the tests keep them equal.
//!
//! All jobs deform positions and normals from bind model space to posed model space.
//! Output normals are unit length (zero stays zero).

use glam::Vec3;
use rayon::prelude::*;

use crate::error::SkinError;

mod bones_blending;
mod dual_quaternion;
mod linear;
mod rigid;
#[cfg(target_arch = "x86_64")]
mod simd;

pub use bones_blending::{BonesBlendJob, BonesBlendVertex};
pub use dual_quaternion::DualQuatJob;
pub use linear::LinearBlendJob;
pub use rigid::RigidJob;

/// How a job runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Execution {
    /// The formula as written, one vertex at a time with 4×4 matrices; for tests.
    Reference,
    /// The fast path on the calling thread.
    SingleThreaded,
    /// The fast path on rayon's thread pool, in chunks of [`CHUNK`] vertices.
    #[default]
    Parallel,
    /// The fast path on the calling thread without the CPU-specific (AVX2 + FMA) kernels: what
    /// runs on CPUs without them; for tests.
    Portable,
}

impl Execution {
    pub(crate) fn parallel(self) -> bool {
        self == Execution::Parallel
    }

    /// Whether CPU-specific kernels may be used.
    #[cfg(target_arch = "x86_64")]
    pub(crate) fn simd(self) -> bool {
        self != Execution::Portable && simd::available()
    }
}

/// Vertices per rayon task: large enough to amortize scheduling, small enough to balance.
pub const CHUNK: usize = 4096;

/// Largest allowed |Σw − 1| for a vertex's weights.
pub const WEIGHT_SUM_TOLERANCE: f32 = 1e-3;

pub(crate) fn check_len(what: &'static str, expected: usize, found: usize) -> Result<(), SkinError> {
    if expected == found {
        Ok(())
    } else {
        Err(SkinError::LengthMismatch { what, expected, found })
    }
}

/// Checks positions/normals/outputs have `n` entries.
pub(crate) fn check_buffers(
    n: usize,
    normals: usize,
    out_positions: usize,
    out_normals: usize,
) -> Result<(), SkinError> {
    check_len("normals", n, normals)?;
    check_len("output positions", n, out_positions)?;
    check_len("output normals", n, out_normals)
}

/// Checks N-influence joint indices and weights: indices in range, weights finite,
/// non-negative, not all zero and summing to 1 within [`WEIGHT_SUM_TOLERANCE`].
pub fn validate_influences<const N: usize>(
    joints: &[[u16; N]],
    weights: &[[f32; N]],
    joint_count: usize,
) -> Result<(), SkinError> {
    validate_influences_with(joints, weights, joint_count, true)
}

/// [`validate_influences`], on the calling thread or in parallel chunks. A branch-free pass
/// over all vertices answers "all good?" cheaply (it runs every frame); only when it fails does
/// a second pass look for the first bad vertex to report.
pub(crate) fn validate_influences_with<const N: usize>(
    joints: &[[u16; N]],
    weights: &[[f32; N]],
    joint_count: usize,
    parallel: bool,
) -> Result<(), SkinError> {
    check_len("weights", joints.len(), weights.len())?;
    let all_good = if parallel && joints.len() > CHUNK {
        joints
            .par_chunks(CHUNK)
            .zip(weights.par_chunks(CHUNK))
            .all(|(j, w)| influences_pass(j, w, joint_count))
    } else {
        influences_pass(joints, weights, joint_count)
    };
    if all_good {
        Ok(())
    } else {
        first_bad_influence(joints, weights, joint_count)
    }
}

/// True when every vertex passes; written without early exits so that it vectorizes: the
/// largest joint index must be in range, the largest weight bit pattern must be that of a
/// finite non-negative float (≤ 0x7F7F_FFFF: negative numbers have the sign bit set, NaN and
/// infinity an all-ones exponent), and every vertex's sum must be 1 within the tolerance.
fn influences_pass<const N: usize>(joints: &[[u16; N]], weights: &[[f32; N]], joint_count: usize) -> bool {
    let mut max_joint = 0u16;
    let mut max_bits = 0u32;
    let mut sums_ok = true;
    for (js, ws) in joints.iter().zip(weights) {
        let mut sum = 0.0f32;
        for i in 0..N {
            max_joint = max_joint.max(js[i]);
            max_bits = max_bits.max(ws[i].to_bits());
            sum += ws[i];
        }
        sums_ok &= (sum - 1.0).abs() <= WEIGHT_SUM_TOLERANCE;
    }
    (max_joint as usize) < joint_count && max_bits <= 0x7F7F_FFFF && sums_ok
}

fn first_bad_influence<const N: usize>(
    joints: &[[u16; N]],
    weights: &[[f32; N]],
    joint_count: usize,
) -> Result<(), SkinError> {
    for (vertex, (js, ws)) in joints.iter().zip(weights).enumerate() {
        let mut sum = 0.0f32;
        for influence in 0..N {
            let joint = js[influence] as usize;
            if joint >= joint_count {
                return Err(SkinError::JointOutOfRange { vertex, influence, joint, joint_count });
            }
            let weight = ws[influence];
            if !weight.is_finite() {
                return Err(SkinError::NonFiniteWeight { vertex, influence, weight });
            }
            if weight < 0.0 {
                return Err(SkinError::NegativeWeight { vertex, influence, weight });
            }
            sum += weight;
        }
        if sum == 0.0 {
            return Err(SkinError::ZeroWeights { vertex });
        }
        if (sum - 1.0).abs() > WEIGHT_SUM_TOLERANCE {
            return Err(SkinError::WeightSum { vertex, sum });
        }
    }
    Ok(())
}

/// Scales each vertex's weights to sum to 1. Fails on the same bad weights as
/// [`validate_influences`] (non-finite, negative, all zero); use it in importers.
pub fn normalize_weights<const N: usize>(weights: &mut [[f32; N]]) -> Result<(), SkinError> {
    for (vertex, ws) in weights.iter_mut().enumerate() {
        let mut sum = 0.0f32;
        for (influence, &weight) in ws.iter().enumerate() {
            if !weight.is_finite() {
                return Err(SkinError::NonFiniteWeight { vertex, influence, weight });
            }
            if weight < 0.0 {
                return Err(SkinError::NegativeWeight { vertex, influence, weight });
            }
            sum += weight;
        }
        if sum == 0.0 {
            return Err(SkinError::ZeroWeights { vertex });
        }
        for w in ws.iter_mut() {
            *w /= sum;
        }
    }
    Ok(())
}

/// Runs `kernel(first_vertex, out_positions_chunk, out_normals_chunk)` over the outputs, on
/// the calling thread or in parallel chunks.
pub(crate) fn for_each_chunk<F>(
    parallel: bool,
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
    kernel: F,
) where
    F: Fn(usize, &mut [Vec3], &mut [Vec3]) + Sync + Send,
{
    if parallel && out_positions.len() > CHUNK {
        out_positions
            .par_chunks_mut(CHUNK)
            .zip(out_normals.par_chunks_mut(CHUNK))
            .enumerate()
            .for_each(|(c, (p, n))| kernel(c * CHUNK, p, n));
    } else {
        kernel(0, out_positions, out_normals);
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn influence_errors_name_vertex_and_influence() {
        let joints = [[0u16, 1], [0, 5]];
        let good = [[0.5f32, 0.5], [1.0, 0.0]];
        assert_eq!(
            validate_influences(&joints, &good, 2),
            Err(SkinError::JointOutOfRange { vertex: 1, influence: 1, joint: 5, joint_count: 2 })
        );
        let joints = [[0u16, 1], [0, 1]];
        assert_eq!(validate_influences(&joints, &good, 2), Ok(()));
        assert!(matches!(
            validate_influences(&joints, &[[0.5, 0.5], [f32::NAN, 1.0]], 2),
            Err(SkinError::NonFiniteWeight { vertex: 1, influence: 0, .. })
        ));
        assert!(matches!(
            validate_influences(&joints, &[[1.5, -0.5], [1.0, 0.0]], 2),
            Err(SkinError::NegativeWeight { vertex: 0, influence: 1, .. })
        ));
        assert_eq!(
            validate_influences(&joints, &[[0.5, 0.5], [0.0, 0.0]], 2),
            Err(SkinError::ZeroWeights { vertex: 1 })
        );
        assert!(matches!(
            validate_influences(&joints, &[[0.5, 0.4], [1.0, 0.0]], 2),
            Err(SkinError::WeightSum { vertex: 0, .. })
        ));
        assert!(matches!(
            validate_influences(&joints, &good[..1], 2),
            Err(SkinError::LengthMismatch { expected: 2, found: 1, .. })
        ));
    }

    #[test]
    fn normalize_scales_to_one() {
        let mut ws = [[2.0f32, 2.0], [0.0, 3.0]];
        normalize_weights(&mut ws).unwrap();
        assert_eq!(ws, [[0.5, 0.5], [0.0, 1.0]]);
        assert_eq!(normalize_weights(&mut [[0.0f32, 0.0]]), Err(SkinError::ZeroWeights { vertex: 0 }));
    }
}
