//! The four skin deformers as jobs (ozz-animation's `SkinningJob` style): a struct of borrowed
//! inputs and `&mut` output slices, `validate()` that returns a typed error, and `run()` that
//! validates and then deforms. Each job has a plain reference implementation written formula
//! by formula ([`Execution::Reference`]) and a fast one (tightly packed data, no allocation,
//! rayon across chunks of [`chunk_len`] vertices); the tests keep them equal.
//!
//! All jobs deform positions and normals from bind model space to posed model space.
//! Output normals are unit length (zero stays zero).

use crate::error::{check_len, SkinError};

mod bones_blending;
mod dual_quaternion;
mod linear;
pub(crate) mod parallel;
mod rigid;
#[cfg(target_arch = "x86_64")]
mod simd;
mod trig;

pub use bones_blending::BonesBlendJob;
pub use dual_quaternion::DualQuatJob;
pub use linear::LinearBlendJob;
pub(crate) use parallel::{all_chunks, for_each_chunk};
pub use parallel::{chunk_len, CHUNK, MAX_CHUNK};
pub use rigid::RigidJob;

/// How a job runs.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum Execution {
    /// The formula as written, one vertex at a time with 4×4 matrices; for tests.
    Reference,
    /// The fast path on the calling thread.
    SingleThreaded,
    /// The fast path on the calling thread and rayon's thread pool together, in chunks of
    /// [`chunk_len`] vertices; afterwards the pool threads linger awake for 1 ms in case the
    /// next job follows (see `run_chunks`).
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

    /// The build of the fast kernels this execution runs on this CPU.
    pub(crate) fn build(self) -> Build {
        if self == Execution::Portable {
            Build::Portable
        } else {
            Build::best()
        }
    }
}

/// The builds of the fast kernels. Which one runs is decided by the CPU alone (the best one
/// it supports) or by [`Execution::Portable`]; there is no switch to force another.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum Build {
    /// glam's SSE2 code (every x86-64 CPU) or scalar code elsewhere.
    Portable,
    /// 256-bit kernels with fused multiply-adds (`deform/simd.rs`).
    Avx2Fma,
    /// CPUs with AVX-512F and AVX-512VL as well: 512-bit kernels for linear blend and dual
    /// quaternion (whose 8-lane kernel, for the last vertices, is compiled once more to use 32
    /// vector registers instead of 16 and spills none); rigid and bones blending run their AVX2
    /// build.
    Avx512Vl,
}

impl Build {
    /// Every build, portable first.
    #[cfg(test)]
    pub(crate) const ALL: [Build; 3] = [Build::Portable, Build::Avx2Fma, Build::Avx512Vl];

    /// The name tests print and assert.
    #[cfg(test)]
    pub(crate) fn name(self) -> &'static str {
        match self {
            Build::Portable => "portable",
            Build::Avx2Fma => "avx2+fma",
            Build::Avx512Vl => "avx512vl",
        }
    }

    /// Whether this CPU can run the build.
    pub(crate) fn runs_here(self) -> bool {
        match self {
            Build::Portable => true,
            #[cfg(target_arch = "x86_64")]
            Build::Avx2Fma => simd::Features::detect().run_avx2_fma(),
            #[cfg(target_arch = "x86_64")]
            Build::Avx512Vl => simd::Features::detect().run_avx512vl(),
            #[cfg(not(target_arch = "x86_64"))]
            Build::Avx2Fma | Build::Avx512Vl => false,
        }
    }

    /// The best build this CPU runs (detected once, then cached by std).
    pub(crate) fn best() -> Build {
        if Build::Avx512Vl.runs_here() {
            Build::Avx512Vl
        } else if Build::Avx2Fma.runs_here() {
            Build::Avx2Fma
        } else {
            Build::Portable
        }
    }
}

/// What the four jobs have in common, so that one function ([`run`]) runs them all.
pub(crate) trait Job {
    /// The job's `validate()`: buffer sizes and the palette, and for inputs that are not
    /// validated by their type (rigid's joint indices), those, in parallel chunks when
    /// `parallel`.
    fn check(&self, parallel: bool) -> Result<(), SkinError>;
    /// The formula as written, one vertex at a time.
    fn reference(&mut self);
    /// The fast path with the given build of its kernels, on the calling thread or in parallel
    /// chunks. Only after [`Job::check`] passed, and only with a build that
    /// [`Build::runs_here`]. Returns the build whose kernels ran: `build`, or the best one below
    /// it that the job has (rigid and bones blending have no AVX-512VL build; a palette with
    /// separate normal matrices runs linear blend's portable path).
    fn fast(&mut self, parallel: bool, build: Build) -> Build;
}

/// Checks the job, then deforms the chosen way: every job's `run_with`.
pub(crate) fn run<J: Job>(job: &mut J, execution: Execution) -> Result<(), SkinError> {
    job.check(execution.parallel())?;
    match execution {
        Execution::Reference => job.reference(),
        Execution::SingleThreaded | Execution::Parallel | Execution::Portable => {
            job.fast(execution.parallel(), execution.build());
        }
    }
    Ok(())
}

/// [`run`] with a chosen build of the fast kernels on the calling thread, for the tests that
/// check every build this CPU runs. `None` when the CPU cannot run it.
#[cfg(test)]
pub(crate) fn run_build<J: Job>(job: &mut J, build: Build) -> Option<Result<Build, SkinError>> {
    if !build.runs_here() {
        return None;
    }
    Some(job.check(false).map(|()| job.fast(false, build)))
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

#[cfg(test)]
mod tests {
    use glam::Vec3;

    use super::*;
    use crate::influences::Influences;

    /// A bad vertex in the last of several parallel chunks gives the typed error naming it and
    /// leaves every output untouched: when the input is built (influences, bones-blending
    /// bindings) or when the job checks it against its palette (all four jobs).
    #[test]
    fn parallel_jobs_refuse_bad_input_in_any_chunk_before_writing() {
        use glam::Quat;

        use crate::influences::{BonesBlendBindings, BonesBlendVertex};
        use crate::pose::{JointPalette, Pose};
        use crate::skeleton::{RestJoint, RestSkeleton};

        let skeleton = RestSkeleton::new(&[
            RestJoint::new("root", None, Vec3::ZERO, Quat::IDENTITY),
            RestJoint::new("child", Some(0), Vec3::X, Quat::IDENTITY),
        ])
        .unwrap();
        let palette = JointPalette::new(&skeleton, &Pose::rest(2)).unwrap();
        let dqs = palette.dual_quaternions().unwrap();
        let n = 3 * CHUNK + 5;
        let bad = n - 2;
        let (positions, normals) = (vec![Vec3::ONE; n], vec![Vec3::Y; n]);
        let mut bones = vec![1u16; n];
        let mut joints = vec![[0u16, 1, 0, 0]; n];
        let mut weights = vec![[0.5f32, 0.5, 0.0, 0.0]; n];
        let mut bindings = vec![BonesBlendVertex { joint: 1, t: 0.5 }; n];
        let mut bad_t = bindings.clone();
        bad_t[bad].t = f32::NAN;
        assert!(matches!(
            BonesBlendBindings::new(bad_t, skeleton.parents()),
            Err(SkinError::BadBlendParameter { vertex, .. }) if vertex == bad
        ));
        bones[bad] = 2;
        joints[bad][1] = 2;
        bindings[bad].joint = 2;
        let (mut op, mut on) = (vec![Vec3::NAN; n], vec![Vec3::NAN; n]);
        let out_of_range = SkinError::JointOutOfRange { vertex: bad, influence: 0, joint: 2, joint_count: 2 };
        let rigid = RigidJob {
            palette: &palette,
            joints: &bones,
            positions: &positions,
            normals: &normals,
            out_positions: &mut op,
            out_normals: &mut on,
        }
        .run();
        assert_eq!(rigid, Err(out_of_range.clone()));
        // Influences checked against a skeleton of 3 joints do not fit a palette of 2: the job
        // refuses them, naming the first vertex that reaches past the palette.
        assert_eq!(
            Influences::new(joints.clone(), weights.clone(), 2),
            Err(SkinError::JointOutOfRange { vertex: bad, influence: 1, joint: 2, joint_count: 2 })
        );
        let influences = Influences::new(joints.clone(), weights.clone(), 3).unwrap();
        let linear = LinearBlendJob {
            palette: &palette,
            influences: &influences,
            positions: &positions,
            normals: &normals,
            out_positions: &mut op,
            out_normals: &mut on,
        }
        .run();
        assert_eq!(
            linear,
            Err(SkinError::JointOutOfRange { vertex: bad, influence: 1, joint: 2, joint_count: 2 })
        );
        let dual = DualQuatJob {
            dual_quaternions: &dqs,
            influences: &influences,
            positions: &positions,
            normals: &normals,
            out_positions: &mut op,
            out_normals: &mut on,
        }
        .run();
        assert_eq!(
            dual,
            Err(SkinError::JointOutOfRange { vertex: bad, influence: 1, joint: 2, joint_count: 2 })
        );
        // Bindings checked against a skeleton of 3 joints do not fit a palette of 2.
        let bindings = BonesBlendBindings::new(bindings, &[None, Some(0), Some(1)]).unwrap();
        let blend = BonesBlendJob {
            palette: &palette,
            parents: skeleton.parents(),
            bindings: &bindings,
            positions: &positions,
            normals: &normals,
            out_positions: &mut op,
            out_normals: &mut on,
        }
        .run();
        assert_eq!(blend, Err(out_of_range.clone()));
        assert!(op.iter().chain(&on).all(|v| v.is_nan()));

        // A weight of −0.0 is not negative: the influences are built and the job runs.
        joints[bad][1] = 1;
        weights[bad] = [1.0, -0.0, 0.0, 0.0];
        let influences = Influences::new(joints, weights, 2).unwrap();
        let linear = LinearBlendJob {
            palette: &palette,
            influences: &influences,
            positions: &positions,
            normals: &normals,
            out_positions: &mut op,
            out_normals: &mut on,
        }
        .run();
        assert_eq!(linear, Ok(()));
        assert!(op.iter().all(|p| (*p - Vec3::ONE).length() < 1e-5));
    }

    /// A small deterministic generator (the tests need no statistics, only varied data).
    struct Lcg(u64);

    impl Lcg {
        fn next_f32(&mut self) -> f32 {
            self.0 = self.0.wrapping_mul(6_364_136_223_846_793_005).wrapping_add(1_442_695_040_888_963_407);
            ((self.0 >> 40) as f32) / ((1u64 << 24) as f32)
        }
        fn vec3(&mut self, r: f32) -> Vec3 {
            Vec3::new(self.next_f32() - 0.5, self.next_f32() - 0.5, self.next_f32() - 0.5) * 2.0 * r
        }
        fn index(&mut self, n: usize) -> usize {
            ((self.next_f32() * n as f32) as usize).min(n - 1)
        }
        /// A rotation by up to ±3 radians about a random axis.
        fn rotation(&mut self) -> glam::Quat {
            let axis = self.vec3(1.0).try_normalize().unwrap_or(Vec3::X);
            glam::Quat::from_axis_angle(axis, (self.next_f32() - 0.5) * 6.0)
        }
        /// `n` positions within 10 of the origin and `n` unit normals (positions first).
        fn points(&mut self, n: usize) -> (Vec<Vec3>, Vec<Vec3>) {
            let positions = (0..n).map(|_| self.vec3(10.0)).collect();
            let normals = (0..n).map(|_| self.vec3(1.0).normalize_or(Vec3::Y)).collect();
            (positions, normals)
        }
    }

    fn assert_close(build: &str, what: &str, got: &[Vec3], want: &[Vec3]) {
        for (v, (g, w)) in got.iter().zip(want).enumerate() {
            let diff = (*g - *w).abs().max_element();
            assert!(diff <= 1e-4 * (1.0 + w.abs().max_element()), "{build} {what} {v}: {g} vs {w}");
        }
    }

    /// Influences with ties for the largest weight (the dual quaternion pivot), zero weights
    /// and all-equal weights.
    fn random_influences<const N: usize>(rng: &mut Lcg, n: usize, joint_count: usize) -> Influences<N> {
        let joints = (0..n).map(|_| [0; N].map(|_| rng.index(joint_count) as u16)).collect();
        let weights = (0..n)
            .map(|v| {
                let mut ws = [0.0f32; N].map(|_| rng.next_f32() + 0.01);
                match v % 5 {
                    0 => ws = [1.0; N],
                    1 => ws[N - 1] = 0.0,
                    2 => ws[1] = ws[0],
                    _ => {}
                }
                let sum: f32 = ws.iter().sum();
                ws.map(|w| w / sum)
            })
            .collect();
        Influences::normalized(joints, weights, joint_count).unwrap()
    }

    /// The kernels a job with an AVX-512VL build of its own runs for each build asked for.
    fn own_kernels(build: Build) -> Build {
        build
    }

    /// The kernels rigid and bones blending (no AVX-512VL build) run for each build asked for.
    fn no_avx512_kernels(build: Build) -> Build {
        if build == Build::Avx512Vl {
            Build::Avx2Fma
        } else {
            build
        }
    }

    /// Linear blend with a separate normal palette runs its portable path whatever is asked for.
    fn portable_kernels(_: Build) -> Build {
        Build::Portable
    }

    /// Runs `job(build)` for every build of the fast kernels, compares each output with the
    /// reference, and returns the names of the builds it ran (those this CPU runs).
    fn builds_match<F>(
        what: &str,
        n: usize,
        reference: &(Vec<Vec3>, Vec<Vec3>),
        kernels: fn(Build) -> Build,
        mut job: F,
    ) -> Vec<&'static str>
    where
        F: FnMut(Build, &mut [Vec3], &mut [Vec3]) -> Option<Result<Build, SkinError>>,
    {
        let mut ran = Vec::new();
        for build in Build::ALL {
            let (mut p, mut q) = (vec![Vec3::NAN; n], vec![Vec3::NAN; n]);
            match job(build, &mut p, &mut q) {
                None => assert!(!build.runs_here(), "{what}: {} runs here but was not run", build.name()),
                Some(result) => {
                    // The job ran the kernels asked for (else the others are never tested here).
                    assert_eq!(result, Ok(kernels(build)), "{what} {}: which kernels ran", build.name());
                    let name = format!("{what} {}", build.name());
                    assert_close(&name, "position", &p, &reference.0);
                    assert_close(&name, "normal", &q, &reference.1);
                    ran.push(build.name());
                }
            }
        }
        ran
    }

    /// Every job's fast kernels in every build this CPU runs (portable everywhere; AVX2+FMA and
    /// AVX-512VL where the CPU has them) against the job's reference path, with 4 and 8
    /// influences, on lengths with every remainder after the SIMD kernels' groups of 4 and 8.
    /// The test prints the builds it checked and fails if it checked none, or missed one the
    /// CPU runs.
    fn every_build_matches_the_reference<const N: usize>() -> Vec<&'static str> {
        use crate::influences::{BonesBlendBindings, BonesBlendVertex};
        use crate::pose::{JointPalette, Pose};
        use crate::skeleton::{RestJoint, RestSkeleton};

        let mut rng = Lcg(0x5EED + N as u64);
        let joint_count = 37;
        let rest: Vec<RestJoint> = (0..joint_count)
            .map(|j| {
                let parent = (j > 0).then(|| rng.index(j));
                RestJoint::new(format!("j{j}"), parent, rng.vec3(2.0), rng.rotation())
            })
            .collect();
        let skeleton = RestSkeleton::new(&rest).unwrap();
        let pose = Pose::from_rotations((0..joint_count).map(|_| rng.rotation()).collect(), rng.vec3(1.0));
        let palette = JointPalette::new(&skeleton, &pose).unwrap();
        assert!(palette.normal_skinning.is_none(), "a rigid palette, so the SIMD linear kernel runs");
        let dqs = palette.dual_quaternions().unwrap();
        let mut checked = Vec::new();
        for n in [8 * 125 + 3, 8 + 4 + 1, 7, 2, 0] {
            let (positions, normals) = rng.points(n);
            let influences = random_influences::<N>(&mut rng, n, joint_count);
            let bones: Vec<u16> = (0..n).map(|_| rng.index(joint_count) as u16).collect();
            let bindings = (0..n)
                .map(|v| {
                    let joint = rng.index(joint_count);
                    let t =
                        if v % 3 == 0 || skeleton.parents()[joint].is_none() { 1.0 } else { rng.next_f32() };
                    BonesBlendVertex { joint: joint as u32, t }
                })
                .collect();
            let bindings = BonesBlendBindings::new(bindings, skeleton.parents()).unwrap();
            let (ps, ns) = (&positions[..], &normals[..]);
            let (palette, skeleton, dqs) = (&palette, &skeleton, &dqs[..]);
            let (influences, bindings, bones) = (&influences, &bindings, &bones[..]);
            let reference = |job: &mut dyn FnMut(&mut [Vec3], &mut [Vec3])| {
                let mut out = (vec![Vec3::NAN; n], vec![Vec3::NAN; n]);
                job(&mut out.0, &mut out.1);
                out
            };
            macro_rules! job {
                ($make:expr) => {{
                    let want =
                        reference(&mut |op, on| run(&mut $make(op, on), Execution::Reference).unwrap());
                    (want, move |build, op: &mut [Vec3], on: &mut [Vec3]| {
                        run_build(&mut $make(op, on), build)
                    })
                }};
            }
            let (want, job) = job!(|out_positions, out_normals| RigidJob {
                palette,
                joints: bones,
                positions: ps,
                normals: ns,
                out_positions,
                out_normals,
            });
            checked.extend(
                builds_match("rigid", n, &want, no_avx512_kernels, job).into_iter().map(|b| ("rigid", b)),
            );
            let (want, job) = job!(|out_positions, out_normals| LinearBlendJob {
                palette,
                influences,
                positions: ps,
                normals: ns,
                out_positions,
                out_normals,
            });
            checked.extend(
                builds_match("linear", n, &want, own_kernels, job).into_iter().map(|b| ("linear", b)),
            );
            let (want, job) = job!(|out_positions, out_normals| DualQuatJob {
                dual_quaternions: dqs,
                influences,
                positions: ps,
                normals: ns,
                out_positions,
                out_normals,
            });
            checked.extend(
                builds_match("dual quaternion", n, &want, own_kernels, job).into_iter().map(|b| ("dual", b)),
            );
            let (want, job) = job!(|out_positions, out_normals| BonesBlendJob {
                palette,
                parents: skeleton.parents(),
                bindings,
                positions: ps,
                normals: ns,
                out_positions,
                out_normals,
            });
            checked.extend(
                builds_match("bones blending", n, &want, no_avx512_kernels, job)
                    .into_iter()
                    .map(|b| ("bones", b)),
            );
        }
        let mut builds: Vec<&'static str> = checked.iter().map(|&(_, b)| b).collect();
        builds.dedup();
        builds.sort_unstable();
        builds.dedup();
        // Every job ran in every build, on every length.
        assert_eq!(checked.len(), 4 * 5 * builds.len(), "{checked:?}");
        eprintln!("N = {N}: checked the builds {builds:?} of the rigid, linear, dual quaternion and bones-blending kernels");
        builds
    }

    /// The builds the tests must have checked on this CPU, found independently of
    /// [`Build::runs_here`].
    fn builds_this_cpu_runs() -> Vec<&'static str> {
        #[allow(unused_mut)]
        let mut builds = vec!["portable"];
        #[cfg(target_arch = "x86_64")]
        {
            if std::arch::is_x86_feature_detected!("avx2") && std::arch::is_x86_feature_detected!("fma") {
                builds.push("avx2+fma");
                if std::arch::is_x86_feature_detected!("avx512f")
                    && std::arch::is_x86_feature_detected!("avx512vl")
                {
                    builds.push("avx512vl");
                }
            }
        }
        builds.sort_unstable();
        builds
    }

    #[test]
    fn every_build_this_cpu_runs_matches_the_reference_4() {
        let checked = every_build_matches_the_reference::<4>();
        assert!(checked.contains(&"portable"), "{checked:?}");
        assert_eq!(checked, builds_this_cpu_runs());
    }

    #[test]
    fn every_build_this_cpu_runs_matches_the_reference_8() {
        let checked = every_build_matches_the_reference::<8>();
        assert!(checked.contains(&"portable"), "{checked:?}");
        assert_eq!(checked, builds_this_cpu_runs());
    }

    /// The AVX-512 linear blend kernel with ordinary and with streaming stores against the
    /// formula, on sub-slices that start at every offset modulo 4 vertices (so every 16-byte
    /// alignment of the outputs, which decides the streaming stores' single-vertex head) and
    /// have every remainder after its groups of 4, with outputs at equal and at different
    /// offsets modulo 16 bytes (which falls back to ordinary stores), 4 and 8 influences;
    /// nothing outside the slice is written. Runs where the CPU has AVX-512F and AVX-512VL and
    /// says so; fails if it did not run on such a CPU.
    #[test]
    fn linear_blend_avx512_kernel_matches_the_formula_with_either_store() {
        #[cfg(target_arch = "x86_64")]
        fn check<const N: usize>(rng: &mut Lcg) -> usize {
            use glam::Affine3A;

            let joint_count = 11;
            let palette: Vec<Affine3A> = (0..joint_count)
                .map(|_| {
                    let rotation = rng.rotation();
                    Affine3A::from_rotation_translation(rotation, rng.vec3(3.0))
                })
                .collect();
            let n = 41;
            let (positions, normals) = rng.points(n);
            let influences = random_influences::<N>(rng, n, joint_count);
            let (joints, weights) = (influences.joints(), influences.weights());
            // SAFETY (both): only on CPUs with AVX-512F and AVX-512VL.
            let packed = unsafe { simd::pack_palette_avx512(&palette) };
            let mut runs = 0;
            for stream in [false, true] {
                // Normals one vertex further into their buffer: a different offset modulo 16.
                for shift in [0, 1] {
                    for start in 0..4 {
                        for len in 0..=n - start - 5 {
                            let r = start..start + len;
                            let rn = start + shift..start + shift + len;
                            let mut out = (vec![Vec3::NAN; n], vec![Vec3::NAN; n]);
                            unsafe {
                                simd::linear_blend_chunk_avx512(
                                    &packed,
                                    &joints[r.clone()],
                                    &weights[r.clone()],
                                    &positions[r.clone()],
                                    &normals[r.clone()],
                                    &mut out.0[r.clone()],
                                    &mut out.1[rn.clone()],
                                    stream,
                                );
                            }
                            for v in 0..n {
                                assert_eq!(!r.contains(&v), out.0[v].is_nan(), "position {v} of {r:?}");
                                assert_eq!(!rn.contains(&v), out.1[v].is_nan(), "normal {v} of {rn:?}");
                            }
                            for (k, v) in r.clone().enumerate() {
                                let (mut m, mut t) = (glam::Mat3A::ZERO, glam::Vec3A::ZERO);
                                for i in 0..N {
                                    let (a, w) = (palette[joints[v][i] as usize], weights[v][i]);
                                    m += a.matrix3 * w;
                                    t += a.translation * w;
                                }
                                let p = Vec3::from(m * glam::Vec3A::from(positions[v]) + t);
                                let q = Vec3::from(m * glam::Vec3A::from(normals[v]));
                                let (dp, dn) = (
                                    (out.0[v] - p).abs().max_element(),
                                    (out.1[start + shift + k] - q).abs().max_element(),
                                );
                                assert!(
                                    dp < 1e-4 && dn < 1e-5,
                                    "N = {N}, stream {stream}, shift {shift}, {r:?}, vertex {v}: {dp} {dn}"
                                );
                            }
                            runs += 1;
                        }
                    }
                }
            }
            runs
        }

        #[cfg(target_arch = "x86_64")]
        {
            let has_avx512 = std::arch::is_x86_feature_detected!("avx2")
                && std::arch::is_x86_feature_detected!("fma")
                && std::arch::is_x86_feature_detected!("avx512f")
                && std::arch::is_x86_feature_detected!("avx512vl");
            assert_eq!(has_avx512, Build::Avx512Vl.runs_here());
            if has_avx512 {
                let mut rng = Lcg(0x512);
                let runs = check::<4>(&mut rng) + check::<8>(&mut rng);
                eprintln!(
                    "avx512vl linear blend kernel: checked {runs} slices with ordinary and streaming stores"
                );
                // Per N, store and shift: lengths 0..=36 from start 0, 0..=35 from 1, and so on.
                assert_eq!(runs, 2 * 2 * 2 * (37 + 36 + 35 + 34));
            } else {
                eprintln!("no AVX-512F/VL on this CPU: the AVX-512 linear blend kernel was not checked");
            }
        }
    }

    /// The 16-lane AVX-512 dual quaternion kernel with ordinary and with streaming stores
    /// against the reference, on sub-slices that start at every offset modulo 16 vertices (so
    /// every 64-byte alignment of the outputs, which decides the streaming stores' head) and
    /// have every remainder after their groups of 16, with outputs at equal and at different
    /// offsets modulo 64 bytes (which falls back to ordinary stores), 4 and 8 influences;
    /// nothing outside the slice is written. Runs where the CPU has AVX-512F and AVX-512VL and
    /// says so; fails if it did not run on such a CPU.
    #[test]
    fn dual_quaternion_avx512_kernel_matches_the_reference_with_either_store() {
        #[cfg(target_arch = "x86_64")]
        fn check<const N: usize>(rng: &mut Lcg) -> usize {
            use crate::dual_quat::DualQuat;
            use crate::DualQuatJob;

            let joint_count = 11;
            let dqs: Vec<DualQuat> = (0..joint_count)
                .map(|_| {
                    let rotation = rng.rotation();
                    DualQuat::from_rotation_translation(rotation, rng.vec3(3.0))
                })
                .collect();
            let n = 70;
            let (positions, normals) = rng.points(n);
            let influences = random_influences::<N>(rng, n, joint_count);
            let mut expected = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
            DualQuatJob {
                dual_quaternions: &dqs,
                influences: &influences,
                positions: &positions,
                normals: &normals,
                out_positions: &mut expected.0,
                out_normals: &mut expected.1,
            }
            .run_with(Execution::Reference)
            .unwrap();
            let (joints, weights) = (influences.joints(), influences.weights());
            // SAFETY (both): only on CPUs with AVX-512F and AVX-512VL.
            let packed = unsafe { simd::pack_dual_quaternions(&dqs) };
            let mut runs = 0;
            for stream in [false, true] {
                // Normals one vertex further into their buffer: a different offset modulo 64.
                for shift in [0, 1] {
                    for start in 0..16 {
                        for len in (0..=n - start - 17).step_by(3) {
                            let r = start..start + len;
                            let rn = start + shift..start + shift + len;
                            // One buffer, the normals 80 vertices (15 cache lines) after the
                            // positions: both outputs at the same offset modulo 64 bytes.
                            let mut buffer = vec![Vec3::NAN; 80 + n];
                            let (positions_out, normals_out) = buffer.split_at_mut(80);
                            let out = (&mut positions_out[..n], normals_out);
                            unsafe {
                                simd::dual_quaternion_chunk_avx512_x16(
                                    &packed,
                                    &joints[r.clone()],
                                    &weights[r.clone()],
                                    &positions[r.clone()],
                                    &normals[r.clone()],
                                    &mut out.0[r.clone()],
                                    &mut out.1[rn.clone()],
                                    stream,
                                );
                            }
                            for v in 0..n {
                                assert_eq!(!r.contains(&v), out.0[v].is_nan(), "position {v} of {r:?}");
                                assert_eq!(!rn.contains(&v), out.1[v].is_nan(), "normal {v} of {rn:?}");
                            }
                            assert!(buffer[n..80].iter().all(|p| p.is_nan()), "positions past {r:?}");
                            let (positions_out, normals_out) = buffer.split_at(80);
                            for (k, v) in r.clone().enumerate() {
                                let (dp, dn) = (
                                    (positions_out[v] - expected.0[v]).abs().max_element(),
                                    (normals_out[start + shift + k] - expected.1[v]).abs().max_element(),
                                );
                                assert!(
                                    dp < 1e-4 && dn < 1e-5,
                                    "N = {N}, stream {stream}, shift {shift}, {r:?}, vertex {v}: {dp} {dn}"
                                );
                            }
                            runs += 1;
                        }
                    }
                }
            }
            runs
        }

        #[cfg(target_arch = "x86_64")]
        {
            if Build::Avx512Vl.runs_here() {
                let mut rng = Lcg(0xD0A);
                let runs = check::<4>(&mut rng) + check::<8>(&mut rng);
                eprintln!(
                    "avx512vl dual quaternion kernel: checked {runs} slices with ordinary and streaming stores"
                );
                // Per N, store and shift: lengths 0, 3, … up to 53 − start for each start 0..16.
                let per: usize = (0..16).map(|start: usize| (53 - start) / 3 + 1).sum();
                assert_eq!(runs, 2 * 2 * 2 * per);
            } else {
                eprintln!("no AVX-512F/VL on this CPU: the AVX-512 dual quaternion kernel was not checked");
            }
        }
    }

    /// Streaming stores only for jobs larger than a last-level cache this CPU reports.
    #[test]
    fn outputs_stream_only_past_the_last_level_cache() {
        #[cfg(target_arch = "x86_64")]
        {
            assert!(!simd::streams_outputs(0, 4));
            let streams = |vertices: usize| simd::streams_outputs(vertices, 4);
            match (0..usize::BITS).map(|b| 1usize << b).find(|&vertices| streams(vertices)) {
                // The first power of two past the cache (72 bytes a vertex): at least 256 KiB
                // (no x86-64 CPU has a smaller last level) and no more than 4 GiB.
                Some(vertices) => {
                    let bytes = vertices * simd::bytes_per_vertex(4);
                    eprintln!("outputs stream from {vertices} vertices ({} KiB)", bytes >> 10);
                    assert!((256 << 10..=8 << 30).contains(&bytes), "{bytes}");
                    // Eight influences move more bytes a vertex.
                    assert!(simd::streams_outputs(vertices, 8));
                    assert!(streams(usize::MAX));
                }
                // CPUID gives the size on every x86-64 CPU this runs on (the sysfs test checks
                // it); without it the test would check nothing.
                None => panic!("the last-level cache size is unknown: outputs never stream, nothing checked"),
            }
        }
    }

    /// Rigid skinning in every build this CPU runs against the formula, on sub-slices that
    /// start at every offset modulo 4 and have every remainder after the SIMD kernel's groups of
    /// 4, with the palette's own linear part and with a separate normal palette; nothing outside
    /// the slice is written.
    #[test]
    fn rigid_builds_match_the_formula_on_every_slice() {
        use glam::Affine3A;

        use crate::pose::JointPalette;

        let mut rng = Lcg(0x816D);
        let skinning: Vec<Affine3A> = (0..9)
            .map(|_| {
                let rotation = rng.rotation();
                Affine3A::from_scale_rotation_translation(
                    Vec3::splat(0.5) + rng.vec3(0.3).abs(),
                    rotation,
                    rng.vec3(3.0),
                )
            })
            .collect();
        let normal_palette: Vec<glam::Mat3A> =
            skinning.iter().map(|m| m.matrix3.inverse().transpose()).collect();
        let n = 23;
        let (positions, normals) = rng.points(n);
        let joints: Vec<u16> = (0..n).map(|_| rng.index(9) as u16).collect();
        let mut checked = Vec::new();
        for separate in [false, true] {
            let palette = JointPalette {
                skinning: skinning.clone(),
                normal_skinning: separate.then(|| normal_palette.clone()),
                ..JointPalette::default()
            };
            for build in Build::ALL {
                for start in 0..4 {
                    for len in 0..=n - start - 4 {
                        let r = start..start + len;
                        let mut out = (vec![Vec3::NAN; n], vec![Vec3::NAN; n]);
                        let mut job = RigidJob {
                            palette: &palette,
                            joints: &joints[r.clone()],
                            positions: &positions[r.clone()],
                            normals: &normals[r.clone()],
                            out_positions: &mut out.0[r.clone()],
                            out_normals: &mut out.1[r.clone()],
                        };
                        match run_build(&mut job, build) {
                            None => {
                                assert!(!build.runs_here());
                                continue;
                            }
                            Some(result) => assert_eq!(result, Ok(no_avx512_kernels(build))),
                        }
                        for v in 0..n {
                            if !r.contains(&v) {
                                assert!(
                                    out.0[v].is_nan() && out.1[v].is_nan(),
                                    "vertex {v} of {r:?} written"
                                );
                                continue;
                            }
                            let j = joints[v] as usize;
                            let p = skinning[j].transform_point3(positions[v]);
                            let nm = palette.normal_skinning.as_ref().map_or(skinning[j].matrix3, |np| np[j])
                                * normals[v];
                            let (dp, dn) =
                                ((out.0[v] - p).abs().max_element(), (out.1[v] - nm).abs().max_element());
                            assert!(
                                dp < 1e-4 && dn < 1e-5,
                                "{}: {r:?}, vertex {v}, separate normals {separate}: {dp} {dn}",
                                build.name()
                            );
                        }
                    }
                }
                if build.runs_here() {
                    checked.push(build.name());
                }
            }
        }
        checked.sort_unstable();
        checked.dedup();
        eprintln!("rigid: checked the builds {checked:?}");
        assert_eq!(checked, builds_this_cpu_runs());
    }

    /// With non-uniform scale the palette carries separate normal matrices: rigid and linear
    /// blend read them (the SIMD builds hand such palettes to the portable kernels) and match
    /// the reference in every build.
    #[test]
    fn scaled_palettes_use_their_normal_matrices_in_every_build() {
        use glam::Quat;

        use crate::pose::{JointPalette, Pose};
        use crate::skeleton::{RestJoint, RestSkeleton};

        let mut rng = Lcg(0x5CA1E);
        let joint_count = 9;
        let rest: Vec<RestJoint> = (0..joint_count)
            .map(|j| RestJoint::new(format!("j{j}"), (j > 0).then(|| j - 1), rng.vec3(2.0), Quat::IDENTITY))
            .collect();
        let skeleton = RestSkeleton::new(&rest).unwrap();
        let mut pose = Pose::from_rotations(
            (0..joint_count).map(|_| Quat::from_axis_angle(Vec3::Z, rng.next_f32() * 3.0)).collect(),
            Vec3::ZERO,
        );
        pose.local_scales = (0..joint_count).map(|_| Vec3::splat(0.5) + rng.vec3(0.4).abs()).collect();
        let palette = JointPalette::new(&skeleton, &pose).unwrap();
        assert!(palette.normal_skinning.is_some(), "non-uniform scale needs normal matrices");
        let n = 37;
        let (positions, normals) = rng.points(n);
        let influences = random_influences::<4>(&mut rng, n, joint_count);
        let bones: Vec<u16> = (0..n).map(|_| rng.index(joint_count) as u16).collect();
        let (ps, ns, palette, influences, bones) =
            (&positions[..], &normals[..], &palette, &influences, &bones[..]);
        let reference = |job: &mut dyn FnMut(&mut [Vec3], &mut [Vec3])| {
            let mut out = (vec![Vec3::NAN; n], vec![Vec3::NAN; n]);
            job(&mut out.0, &mut out.1);
            out
        };
        macro_rules! check {
            ($what:expr, $kernels:expr, $make:expr) => {{
                let want = reference(&mut |op, on| run(&mut $make(op, on), Execution::Reference).unwrap());
                let mut ran = builds_match($what, n, &want, $kernels, |build, op, on| {
                    run_build(&mut $make(op, on), build)
                });
                ran.sort_unstable();
                assert_eq!(ran, builds_this_cpu_runs());
            }};
        }
        check!("scaled linear", portable_kernels, |out_positions, out_normals| LinearBlendJob {
            palette,
            influences,
            positions: ps,
            normals: ns,
            out_positions,
            out_normals,
        });
        check!("scaled rigid", no_avx512_kernels, |out_positions, out_normals| RigidJob {
            palette,
            joints: bones,
            positions: ps,
            normals: ns,
            out_positions,
            out_normals,
        });
    }

    /// Only `Parallel` shares the work out (the results are the same either way, so this is
    /// checked on its own).
    #[test]
    fn only_parallel_execution_runs_in_parallel() {
        assert!(Execution::Parallel.parallel());
        for execution in [Execution::Reference, Execution::SingleThreaded, Execution::Portable] {
            assert!(!execution.parallel(), "{execution:?}");
        }
    }

    /// `Execution` picks the best build the CPU runs, or the portable one when asked.
    #[test]
    fn executions_pick_the_best_build_or_the_portable_one() {
        let best = *builds_this_cpu_runs()
            .iter()
            .max_by_key(|b| ["portable", "avx2+fma", "avx512vl"].iter().position(|n| n == *b))
            .unwrap();
        eprintln!("this CPU runs the {best} build");
        for execution in [Execution::SingleThreaded, Execution::Parallel] {
            assert_eq!(execution.build().name(), best);
        }
        assert_eq!(Execution::Portable.build(), Build::Portable);
        assert!(Build::Portable.runs_here());
    }
}
