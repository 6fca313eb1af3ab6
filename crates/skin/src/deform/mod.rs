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
    /// The fast path on the calling thread and rayon's thread pool together, in chunks of
    /// [`chunk_len`] vertices; afterwards the pool threads linger awake for the next job
    /// ([`set_pool_linger`]).
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

/// Timing and test knob, not part of the supported API: with `force`, dual quaternion jobs
/// run the AVX2 build of their kernel even on CPUs with AVX-512VL (what AVX2-only CPUs run);
/// `place_palette` turns the placed palette copy of that build on (the default) or off (the
/// kernel reads the packed palette where it was allocated). Used by
/// `examples/deformer_timing.rs` through `KEYRIG_SKIN_FORCE_AVX2`; see docs/skinning.md.
#[doc(hidden)]
pub fn force_avx2_dual_quaternion(force: bool, place_palette: bool) {
    #[cfg(target_arch = "x86_64")]
    {
        simd::FORCE_AVX2.store(force, Ordering::Relaxed);
        simd::PLACE_PALETTE.store(place_palette, Ordering::Relaxed);
    }
    #[cfg(not(target_arch = "x86_64"))]
    let _ = (force, place_palette);
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

/// A branch-free "all good?" test of a job's per-vertex inputs over a range of vertices.
pub(crate) type Check<'a> = &'a (dyn Fn(Range<usize>) -> bool + Sync);

/// Runs `kernel(first_vertex, out_positions_chunk, out_normals_chunk)` over the outputs, on
/// the calling thread or in chunks of [`chunk_len`] vertices shared out by [`run_chunks`].
///
/// With a `check`, every chunk's inputs are checked first and the kernel runs only if all pass;
/// the result says whether it ran (on `false` no output was touched). In parallel the checks
/// and the kernel share one dispatch: check tickets come first, and a thread that draws a
/// kernel ticket waits until every check is done, so a job wakes the pool once, not twice.
pub(crate) fn for_each_chunk<F>(
    parallel: bool,
    check: Option<Check>,
    out_positions: &mut [Vec3],
    out_normals: &mut [Vec3],
    kernel: F,
) -> bool
where
    F: Fn(usize, &mut [Vec3], &mut [Vec3]) + Sync + Send,
{
    let n = out_positions.len();
    let chunk_len = chunk_len(n);
    if !(parallel && n > chunk_len) {
        if check.is_some_and(|check| !check(0..n)) {
            return false;
        }
        kernel(0, out_positions, out_normals);
        return true;
    }
    // Each chunk's output slices, taken by whichever thread claims the chunk.
    type Slot<'a> = Mutex<Option<(&'a mut [Vec3], &'a mut [Vec3])>>;
    let slots: Vec<Slot> = out_positions
        .chunks_mut(chunk_len)
        .zip(out_normals.chunks_mut(chunk_len))
        .map(|c| Mutex::new(Some(c)))
        .collect();
    let chunks = slots.len();
    let checks = if check.is_some() { chunks } else { 0 };
    let ok = AtomicBool::new(true);
    let checked = AtomicUsize::new(0);
    run_chunks(checks + chunks, |ticket| {
        if ticket < checks {
            // A check that panics counts as failed, so no kernel runs on unchecked input.
            let mut done = CheckDone { ok: &ok, checked: &checked, passed: false };
            done.passed =
                check.is_none_or(|check| check(ticket * chunk_len..((ticket + 1) * chunk_len).min(n)));
            return;
        }
        // Every check ticket is already claimed and running; wait for the last ones.
        wait_until(|| checked.load(Ordering::Acquire) == checks);
        if ok.load(Ordering::Relaxed) {
            let c = ticket - checks;
            let taken = slots[c].lock().map(|mut slot| slot.take());
            if let Ok(Some((p, q))) = taken {
                kernel(c * chunk_len, p, q);
            }
        }
    });
    ok.into_inner()
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

/// Records one finished check when dropped (also when the check panicked, as a failure).
struct CheckDone<'a> {
    ok: &'a AtomicBool,
    checked: &'a AtomicUsize,
    passed: bool,
}

impl Drop for CheckDone<'_> {
    fn drop(&mut self) {
        if !self.passed {
            self.ok.store(false, Ordering::Relaxed);
        }
        self.checked.fetch_add(1, Ordering::Release);
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
/// wake — at once when they are still lingering after the previous job ([`set_pool_linger`]) —
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

/// How long rayon's pool threads stay awake after a parallel job unless [`set_pool_linger`]
/// says otherwise: 1 ms. The order of GNU OpenMP's default spin before a worker sleeps
/// (`GOMP_SPINCOUNT`, 300 000 spins); Intel's and LLVM's OpenMP runtimes spin far longer
/// (`KMP_BLOCKTIME`, 200 ms). Long enough to cover a short stretch of single-threaded work
/// between two jobs (a 100 000-vertex job is 0.1–0.7 ms), short enough that an idle program
/// keeps no core busy: the threads spin for 1 ms after the last job, then sleep.
pub const DEFAULT_POOL_LINGER: Duration = Duration::from_millis(1);

/// Longest accepted linger (20 ms, a frame at 50–60 frames per second); longer requests are
/// clamped to it, so a program that stops calling jobs has no busy core after at most 20 ms.
pub const MAX_POOL_LINGER: Duration = Duration::from_millis(20);

/// The linger in nanoseconds (0: none).
static LINGER_NS: AtomicU64 = AtomicU64::new(DEFAULT_POOL_LINGER.as_nanos() as u64);
/// Parallel jobs finished so far: a lingering thread restarts its clock when this moves.
static JOBS_DONE: AtomicU64 = AtomicU64::new(0);
/// Lingering tasks not yet finished (queued or running). A new round of them is spawned only
/// when this is 0, so no thread ever runs two.
static LINGERING: AtomicUsize = AtomicUsize::new(0);

/// Sets how long rayon's pool threads stay awake, spinning, after a parallel skinning job
/// (`Execution::Parallel`) in case the next one follows: a job that finds them awake gets its
/// other cores at once instead of after the 20–50 µs a sleeping thread takes to wake. All pool
/// threads but one linger (the calling thread keeps a core for itself); the clock restarts with
/// every parallel job, and once it runs out the threads go back to rayon and sleep.
/// `Duration::ZERO` turns lingering off; values above [`MAX_POOL_LINGER`] are clamped to it.
/// Process-wide; the default is [`DEFAULT_POOL_LINGER`].
pub fn set_pool_linger(linger: Duration) {
    let ns = linger.min(MAX_POOL_LINGER).as_nanos() as u64;
    LINGER_NS.store(ns, Ordering::Relaxed);
}

/// The current linger (see [`set_pool_linger`]).
#[must_use]
pub fn pool_linger() -> Duration {
    Duration::from_nanos(LINGER_NS.load(Ordering::Relaxed))
}

/// After a parallel job: counts it, and unless pool threads are lingering already, sends
/// every pool thread but the last a lingering task (see [`set_pool_linger`]). Nothing on a
/// single-threaded pool, where a lingering thread would take the caller's only core.
fn keep_pool_awake() {
    // SeqCst here and in `linger`: either this job's count is seen by the last lingering task
    // before it leaves (it then starts a new round), or its leaving is seen here.
    JOBS_DONE.fetch_add(1, Ordering::SeqCst);
    let lingerers = rayon::current_num_threads() - 1;
    if LINGER_NS.load(Ordering::Relaxed) > 0 && lingerers > 0 {
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
        } else if now.duration_since(since) >= pool_linger() {
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
                let ran = for_each_chunk(parallel, None, &mut p, &mut q, |start, p, q| {
                    for (i, (p, q)) in p.iter_mut().zip(q).enumerate() {
                        *p = Vec3::splat((start + i) as f32);
                        *q = -*p;
                    }
                });
                assert!(ran);
                assert!(p.iter().enumerate().all(|(i, p)| *p == Vec3::splat(i as f32)), "{n} {parallel}");
                // A failed check anywhere: the kernel runs nowhere.
                let bad = n / 2;
                let refuse = |r: Range<usize>| !r.contains(&bad);
                let mut untouched = vec![Vec3::NAN; n];
                let ran = for_each_chunk(parallel, Some(&refuse), &mut p, &mut untouched, |_, p, q| {
                    p.fill(Vec3::ZERO);
                    q.fill(Vec3::ZERO);
                });
                assert_eq!(ran, n == 0, "{n} {parallel}");
                assert!(n == 0 || untouched.iter().all(|q| q.is_nan()), "{n} {parallel}");
                let accept = |r: Range<usize>| r.end <= n;
                assert!(for_each_chunk(parallel, Some(&accept), &mut p, &mut untouched, |_, p, q| {
                    p.fill(Vec3::ZERO);
                    q.fill(Vec3::ONE);
                }));
                assert!(untouched.iter().all(|q| *q == Vec3::ONE), "{n} {parallel}");
                assert!(q.iter().enumerate().all(|(i, q)| *q == Vec3::splat(-(i as f32))), "{n} {parallel}");
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
            assert!(for_each_chunk(true, None, &mut p, &mut q, |start, p, _| {
                seen.lock().unwrap().push((start, p.len()));
            }));
            let mut seen = seen.into_inner().unwrap();
            seen.sort_unstable();
            let len = chunk_len(n);
            let expected: Vec<(usize, usize)> = (0..n).step_by(len).map(|s| (s, len.min(n - s))).collect();
            assert_eq!(seen, expected, "{n} vertices");
        }
    }

    /// The parallel path checks inputs in the same dispatch as the kernel: a bad vertex in the
    /// last of several chunks still gives the typed error and leaves every output untouched.
    #[test]
    fn parallel_jobs_refuse_bad_input_in_any_chunk_before_writing() {
        use glam::Quat;

        use crate::influences::Influences;
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
        bones[bad] = 2;
        joints[bad][1] = 2;
        bindings[bad].t = f32::NAN;
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
        assert_eq!(rigid, Err(out_of_range));
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
        assert!(matches!(blend, Err(SkinError::BadBlendParameter { vertex, .. }) if vertex == bad));
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
        set_pool_linger(MAX_POOL_LINGER * 3);
        assert_eq!(pool_linger(), MAX_POOL_LINGER);
        set_pool_linger(DEFAULT_POOL_LINGER);
        assert_eq!(pool_linger(), DEFAULT_POOL_LINGER);

        let n = 7 * CHUNK + 3;
        let (mut p, mut q) = (vec![Vec3::NAN; n], vec![Vec3::NAN; n]);
        for round in 0..20 {
            let ran = for_each_chunk(true, None, &mut p, &mut q, |start, p, q| {
                for (i, (p, q)) in p.iter_mut().zip(q).enumerate() {
                    *p = Vec3::new((start + i) as f32, round as f32, 0.0);
                    *q = -*p;
                }
            });
            assert!(ran);
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

    #[test]
    fn normalize_scales_to_one() {
        let mut ws = [[2.0f32, 2.0], [0.0, 3.0]];
        normalize_weights(&mut ws).unwrap();
        assert_eq!(ws, [[0.5, 0.5], [0.0, 1.0]]);
        assert_eq!(normalize_weights(&mut [[0.0f32, 0.0]]), Err(SkinError::ZeroWeights { vertex: 0 }));
    }
}
