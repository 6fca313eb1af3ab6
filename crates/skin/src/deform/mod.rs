//! The four skin deformers as jobs (ozz-animation's `SkinningJob` style): a struct of borrowed
//! inputs and `&mut` output slices, `validate()` that returns a typed error, and `run()` that
//! validates and then deforms. Each job has a plain reference implementation written formula
//! by formula ([`Execution::Reference`]) and a fast one (tightly packed data, no allocation,
//! rayon across chunks of [`chunk_len`] vertices); the tests keep them equal.
//!
//! All jobs deform positions and normals from bind model space to posed model space.
//! Output normals are unit length (zero stays zero).

use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use glam::Vec3;

use crate::error::SkinError;

mod bones_blending;
mod dual_quaternion;
mod linear;
mod rigid;
#[cfg(target_arch = "x86_64")]
mod simd;
mod trig;

pub use bones_blending::BonesBlendJob;
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
    /// The same with AVX-512VL enabled: the dual quaternion kernel is compiled once more, to
    /// use 32 vector registers instead of 16 (it spills none); the other kernels run their AVX2
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
            Build::Avx2Fma => simd::available(),
            #[cfg(target_arch = "x86_64")]
            Build::Avx512Vl => simd::avx512_available(),
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
    /// [`Build::runs_here`].
    fn fast(&mut self, parallel: bool, build: Build);
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
pub(crate) fn run_build<J: Job>(job: &mut J, build: Build) -> Option<Result<(), SkinError>> {
    if !build.runs_here() {
        return None;
    }
    Some(job.check(false).map(|()| job.fast(false, build)))
}

/// Fewest vertices per parallel task: enough to amortize claiming a chunk. Jobs of up to
/// 16 · `CHUNK` vertices are cut into chunks of exactly this size.
pub const CHUNK: usize = 4096;

/// Most vertices per parallel task.
pub const MAX_CHUNK: usize = 32768;

/// Vertices per parallel task for a job of `n` vertices: about a sixteenth of the job, within
/// [`CHUNK`]..=[`MAX_CHUNK`]. Sixteen chunks keep two to eight threads balanced; longer chunks
/// than `CHUNK` pay at a million vertices, where every chunk a thread claims starts its input
/// and output streams afresh in DRAM (rigid on 2 cores: 1.46 ms with chunks of 4096 vertices,
/// 1.31–1.35 ms with 32768; docs/benchmarks.md).
pub fn chunk_len(n: usize) -> usize {
    (n / 16).clamp(CHUNK, MAX_CHUNK)
}

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
    let all_good =
        all_chunks(parallel, joints.len(), |r| influences_pass(&joints[r.clone()], &weights[r], joint_count));
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
pub(crate) fn influences_pass<const N: usize>(
    joints: &[[u16; N]],
    weights: &[[f32; N]],
    joint_count: usize,
) -> bool {
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
/// the calling thread or in chunks of [`chunk_len`] vertices shared out by [`run_chunks`]:
/// the one parallel helper of the four jobs.
pub(crate) fn for_each_chunk<F>(
    parallel: bool,
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
    kernel: F,
) where
    F: Fn(usize, &mut [Vec3], &mut [Vec3]) + Sync + Send,
{
    let n = out_positions.len();
    let chunk_len = chunk_len(n);
    if !(parallel && n > chunk_len) {
        kernel(0, out_positions, out_normals);
        return;
    }
    // Each chunk's output slices, taken by whichever thread claims the chunk.
    type Slot<'a> = Mutex<Option<(&'a mut [Vec3], &'a mut [Vec3])>>;
    let slots: Vec<Slot> = out_positions
        .chunks_mut(chunk_len)
        .zip(out_normals.chunks_mut(chunk_len))
        .map(|c| Mutex::new(Some(c)))
        .collect();
    run_chunks(slots.len(), |c| {
        let taken = slots[c].lock().map(|mut slot| slot.take());
        if let Ok(Some((p, q))) = taken {
            kernel(c * chunk_len, p, q);
        }
    });
}

/// Adds one to a counter when dropped, also when the work it guards panics: the threads that
/// wait for the count then finish, and rayon's scope passes the panic on instead of the wait
/// spinning for ever.
struct CountOnDrop<'a>(&'a AtomicUsize);

impl Drop for CountOnDrop<'_> {
    fn drop(&mut self) {
        self.0.fetch_add(1, Ordering::Release);
    }
}

/// Spins until `done()` (another thread's short piece of work), yielding now and then in case
/// that thread lost its core to another process.
fn wait_until(done: impl Fn() -> bool) {
    let mut spins = 0u32;
    while !done() {
        spins += 1;
        if spins.is_multiple_of(1024) {
            std::thread::yield_now();
        } else {
            std::hint::spin_loop();
        }
    }
}

/// Whether `pass(range)` holds for every chunk of `0..len` ([`chunk_len`] vertices each), on the
/// calling thread or shared out by [`run_chunks`]. Every chunk is checked (no early exit).
pub(crate) fn all_chunks<P>(parallel: bool, len: usize, pass: P) -> bool
where
    P: Fn(Range<usize>) -> bool + Sync,
{
    let chunk = chunk_len(len);
    if parallel && len > chunk {
        let ok = AtomicBool::new(true);
        run_chunks(len.div_ceil(chunk), |c| {
            if !pass(c * chunk..((c + 1) * chunk).min(len)) {
                ok.store(false, Ordering::Relaxed);
            }
        });
        ok.into_inner()
    } else {
        pass(0..len)
    }
}

/// Runs `work(c)` for every chunk `c` in `0..count` on the calling thread *and* rayon's
/// other threads, each claiming the next chunk from a shared counter.
///
/// Why not `par_chunks`: rayon's pool threads sleep between frames, and waking one costs
/// 25–50 µs on the 2-core VM the benchmarks ran on, while the calling thread — which
/// `par_chunks` puts to sleep until the pool is done — would have to be woken again at the end.
/// Against a job of 0.1–0.5 ms (100 000 vertices) those two wake-ups ate most of the second
/// core. Here the calling thread starts on the first chunk at once, the helpers join in when they
/// wake — at once when they are still lingering after the previous job ([`POOL_LINGER`]) —
/// and at the end the calling thread spins for the helpers' last chunks (one chunk's time at
/// most) instead of sleeping. See docs/benchmarks.md, skinning section.
pub(crate) fn run_chunks<W>(count: usize, work: W)
where
    W: Fn(usize) + Sync,
{
    let next = AtomicUsize::new(0);
    let done = AtomicUsize::new(0);
    let claim_and_work = || loop {
        let c = next.fetch_add(1, Ordering::Relaxed);
        if c >= count {
            break;
        }
        let _count = CountOnDrop(&done);
        work(c);
    };
    rayon::in_place_scope(|scope| {
        for _ in 1..rayon::current_num_threads().min(count) {
            scope.spawn(|_| claim_and_work());
        }
        claim_and_work();
        // Every chunk is claimed; wait for the helpers' last ones without sleeping.
        wait_until(|| done.load(Ordering::Acquire) == count);
    });
    keep_pool_awake();
}

/// How long rayon's pool threads stay awake, spinning, after a parallel skinning job
/// (`Execution::Parallel`) in case the next one follows: 1 ms. A job that finds them awake gets
/// its other cores at once instead of after the 20–50 µs a sleeping thread takes to wake. The
/// order of GNU OpenMP's default spin before a worker sleeps (`GOMP_SPINCOUNT`, 300 000 spins);
/// long enough to cover a short stretch of single-threaded work between two jobs (a
/// 100 000-vertex job is 0.1–0.7 ms), short enough that an idle program keeps no core busy.
/// All pool threads but one linger (the calling thread keeps a core for itself); the clock
/// restarts with every parallel job. Fixed: timing experiments with other values belong in a
/// branch of `examples/deformer_timing.rs`, not in the library's API.
const POOL_LINGER: Duration = Duration::from_millis(1);

/// Parallel jobs finished so far: a lingering thread restarts its clock when this moves.
static JOBS_DONE: AtomicU64 = AtomicU64::new(0);
/// Lingering tasks not yet finished (queued or running). A new round of them is spawned only
/// when this is 0, so no thread ever runs two.
static LINGERING: AtomicUsize = AtomicUsize::new(0);

/// After a parallel job: counts it, and unless pool threads are lingering already, sends
/// every pool thread but the last a lingering task (see [`POOL_LINGER`]). Nothing on a
/// single-threaded pool, where a lingering thread would take the caller's only core.
fn keep_pool_awake() {
    // SeqCst here and in `linger`: either this job's count is seen by the last lingering task
    // before it leaves (it then starts a new round), or its leaving is seen here.
    JOBS_DONE.fetch_add(1, Ordering::SeqCst);
    let lingerers = rayon::current_num_threads() - 1;
    if lingerers > 0 {
        start_lingering(lingerers);
    }
}

/// Spawns a round of `lingerers` lingering tasks, one per pool thread, if none is running.
fn start_lingering(lingerers: usize) {
    if LINGERING.compare_exchange(0, lingerers, Ordering::SeqCst, Ordering::SeqCst).is_ok() {
        rayon::spawn_broadcast(move |ctx| {
            if ctx.index() < lingerers {
                linger(lingerers);
            }
        });
    }
}

/// A lingering task: runs whatever rayon work turns up (a new job's helper task among it,
/// taken at once instead of through a wake-up) and spins in between, until the linger has
/// passed since the last parallel job finished.
fn linger(lingerers: usize) {
    let mut seen = JOBS_DONE.load(Ordering::SeqCst);
    let mut since = Instant::now();
    loop {
        if rayon::yield_now() == Some(rayon::Yield::Executed) {
            continue;
        }
        let jobs = JOBS_DONE.load(Ordering::SeqCst);
        let now = Instant::now();
        if jobs != seen {
            (seen, since) = (jobs, now);
        } else if now.duration_since(since) >= POOL_LINGER {
            // The last one out starts a new round if a job finished meanwhile: that job may
            // have found this round still running and started none.
            if LINGERING.fetch_sub(1, Ordering::SeqCst) == 1 && JOBS_DONE.load(Ordering::SeqCst) != seen {
                start_lingering(lingerers);
            }
            return;
        }
        for _ in 0..32 {
            std::hint::spin_loop();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::influences::Influences;

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
    fn a_panicking_chunk_panics_the_caller_instead_of_hanging_it() {
        let outcome = std::panic::catch_unwind(|| {
            run_chunks(40, |c| {
                if c == 39 {
                    panic!("chunk {c}");
                }
            })
        });
        assert!(outcome.is_err());
    }

    #[test]
    fn chunks_are_each_run_once_and_cover_the_outputs() {
        for n in [0, 1, CHUNK, CHUNK + 1, 5 * CHUNK + 17, 40 * CHUNK + 3] {
            let runs: Vec<AtomicUsize> = (0..n.div_ceil(CHUNK) + 1).map(|_| AtomicUsize::new(0)).collect();
            run_chunks(n.div_ceil(CHUNK), |c| {
                runs[c].fetch_add(1, Ordering::Relaxed);
            });
            let counts: Vec<usize> = runs.iter().map(|r| r.load(Ordering::Relaxed)).collect();
            let mut expected = vec![1; n.div_ceil(CHUNK)];
            expected.push(0);
            assert_eq!(counts, expected, "{n} vertices");

            for parallel in [false, true] {
                let mut p = vec![Vec3::NAN; n];
                let mut q = vec![Vec3::NAN; n];
                for_each_chunk(parallel, &mut p, &mut q, |start, p, q| {
                    for (i, (p, q)) in p.iter_mut().zip(q).enumerate() {
                        *p = Vec3::splat((start + i) as f32);
                        *q = -*p;
                    }
                });
                assert!(p.iter().enumerate().all(|(i, p)| *p == Vec3::splat(i as f32)), "{n} {parallel}");
                assert!(q.iter().enumerate().all(|(i, q)| *q == Vec3::splat(-(i as f32))), "{n} {parallel}");
                let bad = n / 2;
                assert_eq!(all_chunks(parallel, n, |r| !r.contains(&bad)), n == 0, "{n} {parallel}");
                assert!(
                    all_chunks(parallel, n, |r| r.end <= n && (r.start < r.end || n == 0)),
                    "{n} {parallel}"
                );
            }
        }
    }

    /// Chunks are a sixteenth of the job within CHUNK..=MAX_CHUNK, and the parallel kernel
    /// sees exactly those: consecutive, each `chunk_len` long but the last.
    #[test]
    fn chunk_length_grows_with_the_job() {
        assert_eq!(chunk_len(0), CHUNK);
        assert_eq!(chunk_len(16 * CHUNK), CHUNK);
        assert_eq!(chunk_len(16 * CHUNK + 16), CHUNK + 1);
        assert_eq!(chunk_len(100_000), 6_250);
        assert_eq!(chunk_len(16 * MAX_CHUNK), MAX_CHUNK);
        assert_eq!(chunk_len(1_000_000), MAX_CHUNK);
        for n in [100_000, 16 * MAX_CHUNK + 7] {
            let seen = Mutex::new(Vec::new());
            let (mut p, mut q) = (vec![Vec3::ZERO; n], vec![Vec3::ZERO; n]);
            for_each_chunk(true, &mut p, &mut q, |start, p, _| {
                seen.lock().unwrap().push((start, p.len()));
            });
            let mut seen = seen.into_inner().unwrap();
            seen.sort_unstable();
            let len = chunk_len(n);
            let expected: Vec<(usize, usize)> = (0..n).step_by(len).map(|s| (s, len.min(n - s))).collect();
            assert_eq!(seen, expected, "{n} vertices");
        }
    }

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

    /// A job that arrives while a pool thread lingers is shared with it and gives the same
    /// output; a panicking one still reaches the caller; and the lingering ends on its own.
    #[test]
    fn a_lingering_pool_thread_takes_the_next_job_then_sleeps() {
        let n = 7 * CHUNK + 3;
        let (mut p, mut q) = (vec![Vec3::NAN; n], vec![Vec3::NAN; n]);
        for round in 0..20 {
            for_each_chunk(true, &mut p, &mut q, |start, p, q| {
                for (i, (p, q)) in p.iter_mut().zip(q).enumerate() {
                    *p = Vec3::new((start + i) as f32, round as f32, 0.0);
                    *q = -*p;
                }
            });
            assert!(
                p.iter()
                    .zip(&q)
                    .enumerate()
                    .all(|(i, (p, q))| *p == Vec3::new(i as f32, round as f32, 0.0) && *q == -*p),
                "round {round}"
            );
            if round == 10 {
                let outcome = std::panic::catch_unwind(|| run_chunks(8, |c| assert_ne!(c, 5, "chunk {c}")));
                assert!(outcome.is_err());
            }
        }

        // Once no job has finished for the linger, the lingering task leaves the pool (other
        // tests' parallel jobs may restart its clock meanwhile, hence the generous bound, which
        // only keeps a broken build from hanging).
        let start = Instant::now();
        while LINGERING.load(Ordering::SeqCst) > 0 {
            assert!(start.elapsed() < Duration::from_secs(60), "a pool thread kept lingering");
            std::thread::sleep(Duration::from_millis(1));
        }
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

    /// Runs `job(build)` for every build of the fast kernels, compares each output with the
    /// reference, and returns the names of the builds it ran (those this CPU runs).
    fn builds_match<F>(
        what: &str,
        n: usize,
        reference: &(Vec<Vec3>, Vec<Vec3>),
        mut job: F,
    ) -> Vec<&'static str>
    where
        F: FnMut(Build, &mut [Vec3], &mut [Vec3]) -> Option<Result<(), SkinError>>,
    {
        let mut ran = Vec::new();
        for build in Build::ALL {
            let (mut p, mut q) = (vec![Vec3::NAN; n], vec![Vec3::NAN; n]);
            match job(build, &mut p, &mut q) {
                None => assert!(!build.runs_here(), "{what}: {} runs here but was not run", build.name()),
                Some(result) => {
                    assert_eq!(result, Ok(()), "{what} {}", build.name());
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
        use glam::Quat;

        use crate::influences::{BonesBlendBindings, BonesBlendVertex};
        use crate::pose::{JointPalette, Pose};
        use crate::skeleton::{RestJoint, RestSkeleton};

        let mut rng = Lcg(0x5EED + N as u64);
        let joint_count = 37;
        let random_rotation = |rng: &mut Lcg| {
            let axis = rng.vec3(1.0).try_normalize().unwrap_or(Vec3::X);
            Quat::from_axis_angle(axis, (rng.next_f32() - 0.5) * 6.0)
        };
        let rest: Vec<RestJoint> = (0..joint_count)
            .map(|j| {
                let parent = (j > 0).then(|| rng.index(j));
                RestJoint::new(format!("j{j}"), parent, rng.vec3(2.0), random_rotation(&mut rng))
            })
            .collect();
        let skeleton = RestSkeleton::new(&rest).unwrap();
        let pose = Pose::from_rotations(
            (0..joint_count).map(|_| random_rotation(&mut rng)).collect(),
            rng.vec3(1.0),
        );
        let palette = JointPalette::new(&skeleton, &pose).unwrap();
        assert!(palette.normal_skinning.is_none(), "a rigid palette, so the SIMD linear kernel runs");
        let dqs = palette.dual_quaternions().unwrap();
        let mut checked = Vec::new();
        for n in [8 * 125 + 3, 8 + 4 + 1, 7, 2, 0] {
            let positions: Vec<Vec3> = (0..n).map(|_| rng.vec3(10.0)).collect();
            let normals: Vec<Vec3> = (0..n).map(|_| rng.vec3(1.0).normalize_or(Vec3::Y)).collect();
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
            checked.extend(builds_match("rigid", n, &want, job).into_iter().map(|b| ("rigid", b)));
            let (want, job) = job!(|out_positions, out_normals| LinearBlendJob {
                palette,
                influences,
                positions: ps,
                normals: ns,
                out_positions,
                out_normals,
            });
            checked.extend(builds_match("linear", n, &want, job).into_iter().map(|b| ("linear", b)));
            let (want, job) = job!(|out_positions, out_normals| DualQuatJob {
                dual_quaternions: dqs,
                influences,
                positions: ps,
                normals: ns,
                out_positions,
                out_normals,
            });
            checked.extend(builds_match("dual quaternion", n, &want, job).into_iter().map(|b| ("dual", b)));
            let (want, job) = job!(|out_positions, out_normals| BonesBlendJob {
                palette,
                parents: skeleton.parents(),
                bindings,
                positions: ps,
                normals: ns,
                out_positions,
                out_normals,
            });
            checked.extend(builds_match("bones blending", n, &want, job).into_iter().map(|b| ("bones", b)));
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

    /// Rigid skinning in every build this CPU runs against the formula, on sub-slices that
    /// start at every offset modulo 4 and have every remainder after the SIMD kernel's groups of
    /// 4, with the palette's own linear part and with a separate normal palette; nothing outside
    /// the slice is written.
    #[test]
    fn rigid_builds_match_the_formula_on_every_slice() {
        use glam::{Affine3A, Quat};

        use crate::pose::JointPalette;

        let mut rng = Lcg(0x816D);
        let skinning: Vec<Affine3A> = (0..9)
            .map(|_| {
                let axis = rng.vec3(1.0).try_normalize().unwrap_or(Vec3::X);
                let rotation = Quat::from_axis_angle(axis, (rng.next_f32() - 0.5) * 6.0);
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
        let positions: Vec<Vec3> = (0..n).map(|_| rng.vec3(10.0)).collect();
        let normals: Vec<Vec3> = (0..n).map(|_| rng.vec3(1.0).normalize_or(Vec3::Y)).collect();
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
                            Some(result) => assert_eq!(result, Ok(())),
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

    #[test]
    fn normalize_scales_to_one() {
        let mut ws = [[2.0f32, 2.0], [0.0, 3.0]];
        normalize_weights(&mut ws).unwrap();
        assert_eq!(ws, [[0.5, 0.5], [0.0, 1.0]]);
        assert_eq!(normalize_weights(&mut [[0.0f32, 0.0]]), Err(SkinError::ZeroWeights { vertex: 0 }));
    }
}
