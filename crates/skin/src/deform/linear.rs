//! Linear blend skinning ("vertex blending", Magnenat-Thalmann et al. 1988; seed text 000):
//! v' = Σᵢ wᵢ·M(jᵢ)·v with Σ wᵢ = 1, normals by the blended inverse-transpose, renormalized.
//! Collapses under twist (the "candy wrapper"): a 180° twist averages v with its mirror image.

use glam::{Mat3, Mat3A, Mat4, Vec3, Vec3A};

use super::{check_buffers, check_len, for_each_chunk, Build, Execution, Job};
use crate::error::SkinError;
use crate::influences::Influences;
use crate::pose::JointPalette;

/// Linear blend skinning with `N` influences per vertex (4 for most meshes, 8 for glTF meshes
/// with `JOINTS_1`). Zero-weight influences still need an in-range joint index.
///
/// The influences were checked vertex by vertex when they were built ([`Influences::new`]);
/// a run checks only the buffer lengths and that the palette holds their largest joint index.
#[derive(Debug)]
pub struct LinearBlendJob<'a, const N: usize = 4> {
    pub palette: &'a JointPalette,
    pub influences: &'a Influences<N>,
    pub positions: &'a [Vec3],
    pub normals: &'a [Vec3],
    pub out_positions: &'a mut [Vec3],
    pub out_normals: &'a mut [Vec3],
}

impl<const N: usize> LinearBlendJob<'_, N> {
    /// Checks buffer lengths and that the palette holds every joint index: O(joints), not
    /// O(vertices) (the influences are valid by construction).
    pub fn validate(&self) -> Result<(), SkinError> {
        let n = self.positions.len();
        check_len("influences", n, self.influences.len())?;
        check_buffers(n, self.normals.len(), self.out_positions.len(), self.out_normals.len())?;
        self.influences.check_joint_count(self.palette.len())
    }

    /// Validates, then deforms on all cores.
    pub fn run(&mut self) -> Result<(), SkinError> {
        self.run_with(Execution::Parallel)
    }

    /// Validates, then deforms the chosen way.
    pub fn run_with(&mut self, execution: Execution) -> Result<(), SkinError> {
        super::run(self, execution)
    }
}

impl<const N: usize> Job for LinearBlendJob<'_, N> {
    fn check(&self, _parallel: bool) -> Result<(), SkinError> {
        self.validate()
    }

    fn reference(&mut self) {
        for v in 0..self.positions.len() {
            let mut m = Mat4::ZERO;
            let mut nm = Mat3::ZERO;
            for i in 0..N {
                let j = self.influences.joints()[v][i] as usize;
                let w = self.influences.weights()[v][i];
                let mj = Mat4::from(self.palette.skinning[j]);
                m += mj * w;
                nm += match &self.palette.normal_skinning {
                    Some(normals) => Mat3::from(normals[j]),
                    // Rotation times uniform scale: the linear part maps normals (up to length).
                    None => Mat3::from_mat4(mj),
                } * w;
            }
            self.out_positions[v] = m.transform_point3(self.positions[v]);
            self.out_normals[v] = nm * self.normals[v];
        }
    }

    fn fast(&mut self, parallel: bool, build: Build) -> Build {
        let palette = &self.palette.skinning;
        let normal_palette = self.palette.normal_skinning.as_deref();
        let (joints, weights) = (self.influences.joints(), self.influences.weights());
        let (positions, normals) = (self.positions, self.normals);
        #[cfg(target_arch = "x86_64")]
        if normal_palette.is_none() && build == Build::Avx512Vl {
            let stream = super::simd::streams_outputs(positions.len(), N);
            // SAFETY: the CPU has AVX2, FMA, AVX-512F and AVX-512VL (the caller runs only builds
            // that run here); validate() checked that the palette holds every joint index.
            let packed = unsafe { super::simd::pack_palette_avx512(palette) };
            for_each_chunk(parallel, self.out_positions, self.out_normals, |start, out_p, out_n| {
                let end = start + out_p.len();
                // SAFETY: as above.
                unsafe {
                    super::simd::linear_blend_chunk_avx512(
                        &packed,
                        &joints[start..end],
                        &weights[start..end],
                        &positions[start..end],
                        &normals[start..end],
                        out_p,
                        out_n,
                        stream,
                    )
                }
            });
            return Build::Avx512Vl;
        }
        #[cfg(target_arch = "x86_64")]
        if normal_palette.is_none() && build != Build::Portable {
            // SAFETY: the CPU has AVX2 and FMA (the caller runs only builds that run here);
            // validate() checked that the palette holds every joint index of the influences.
            let packed = unsafe { super::simd::pack_palette(palette) };
            for_each_chunk(parallel, self.out_positions, self.out_normals, |start, out_p, out_n| {
                let end = start + out_p.len();
                // SAFETY: as above.
                unsafe {
                    super::simd::linear_blend_chunk(
                        &packed,
                        &joints[start..end],
                        &weights[start..end],
                        &positions[start..end],
                        &normals[start..end],
                        out_p,
                        out_n,
                    )
                }
            });
            return Build::Avx2Fma;
        }
        #[cfg(not(target_arch = "x86_64"))]
        let _ = build;
        for_each_chunk(parallel, self.out_positions, self.out_normals, |start, out_p, out_n| {
            let end = start + out_p.len();
            let inputs = joints[start..end]
                .iter()
                .zip(&weights[start..end])
                .zip(positions[start..end].iter().zip(&normals[start..end]));
            for (((js, ws), (&p, &n)), (op, on)) in inputs.zip(out_p.iter_mut().zip(out_n.iter_mut())) {
                let m0 = &palette[js[0] as usize];
                let w0 = ws[0];
                let mut x = m0.matrix3.x_axis * w0;
                let mut y = m0.matrix3.y_axis * w0;
                let mut z = m0.matrix3.z_axis * w0;
                let mut t = m0.translation * w0;
                for i in 1..N {
                    let m = &palette[js[i] as usize];
                    let w = ws[i];
                    x += m.matrix3.x_axis * w;
                    y += m.matrix3.y_axis * w;
                    z += m.matrix3.z_axis * w;
                    t += m.translation * w;
                }
                *op = (x * p.x + y * p.y + z * p.z + t).into();
                let nm = match normal_palette {
                    Some(normal_palette) => {
                        let mut nm = Mat3A::ZERO;
                        for i in 0..N {
                            nm += normal_palette[js[i] as usize] * ws[i];
                        }
                        nm * Vec3A::from(n)
                    }
                    None => x * n.x + y * n.y + z * n.z,
                };
                *on = nm.into();
            }
        });
        Build::Portable
    }
}
