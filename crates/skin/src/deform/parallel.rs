//! The one parallel helper of the four jobs (and of influence validation): chunks of a job
//! shared out between the calling thread and rayon's pool, whose threads linger awake for a
//! moment after each job.

use std::ops::Range;
use std::sync::atomic::{AtomicBool, AtomicU64, AtomicUsize, Ordering};
use std::sync::Mutex;
use std::time::{Duration, Instant};

use glam::Vec3;

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
        // all_chunks checks consecutive chunks of chunk_len vertices that cover the job once.
        for (n, parallel) in [(100_000, true), (100_000, false), (3 * CHUNK, true)] {
            let seen = Mutex::new(Vec::new());
            assert!(all_chunks(parallel, n, |r| {
                seen.lock().unwrap().push(r);
                true
            }));
            let mut seen = seen.into_inner().unwrap();
            seen.sort_unstable_by_key(|r| r.start);
            let len = if parallel && n > chunk_len(n) { chunk_len(n) } else { n };
            let expected: Vec<Range<usize>> = (0..n).step_by(len).map(|s| s..(s + len).min(n)).collect();
            assert_eq!(seen, expected, "{n} vertices, parallel {parallel}");
        }
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

    /// A job that arrives while a pool thread lingers is shared with it and gives the same
    /// output; a panicking one still reaches the caller; and the lingering ends on its own.
    #[test]
    fn a_lingering_pool_thread_takes_the_next_job_then_sleeps() {
        let n = 7 * CHUNK + 3;
        let (mut p, mut q) = (vec![Vec3::NAN; n], vec![Vec3::NAN; n]);
        // Every parallel job is counted (the lingering threads restart their clock on it).
        let before = JOBS_DONE.load(Ordering::SeqCst);
        for_each_chunk(true, &mut p, &mut q, |_, _, _| {});
        assert!(JOBS_DONE.load(Ordering::SeqCst) > before);
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
}
