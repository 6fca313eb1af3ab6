//! Shared pieces of the malformed-file suites: a counting allocator that records the peak
//! bytes allocated by the current thread, deterministic mutations of a file, and a
//! panic-catching runner.

#![allow(dead_code)]

use std::alloc::{GlobalAlloc, Layout, System};
use std::cell::Cell;
use std::panic::{catch_unwind, AssertUnwindSafe};

/// Counts the bytes allocated by each thread and the peak since [`reset_peak`].
pub struct CountingAlloc;

thread_local! {
    static CURRENT: Cell<isize> = const { Cell::new(0) };
    static PEAK: Cell<isize> = const { Cell::new(0) };
}

fn add(delta: isize) {
    // `try_with` because the allocator can run while thread-locals are being torn down.
    let _ = CURRENT.try_with(|c| {
        let now = c.get() + delta;
        c.set(now);
        let _ = PEAK.try_with(|p| {
            if now > p.get() {
                p.set(now);
            }
        });
    });
}

unsafe impl GlobalAlloc for CountingAlloc {
    unsafe fn alloc(&self, layout: Layout) -> *mut u8 {
        add(layout.size() as isize);
        unsafe { System.alloc(layout) }
    }
    unsafe fn dealloc(&self, ptr: *mut u8, layout: Layout) {
        add(-(layout.size() as isize));
        unsafe { System.dealloc(ptr, layout) }
    }
    unsafe fn realloc(&self, ptr: *mut u8, layout: Layout, new_size: usize) -> *mut u8 {
        add(new_size as isize - layout.size() as isize);
        unsafe { System.realloc(ptr, layout, new_size) }
    }
}

/// Runs `f` and returns its result and the peak bytes it had allocated at once (on this
/// thread, above what was allocated when it started).
pub fn measure_peak<R>(f: impl FnOnce() -> R) -> (R, usize) {
    let start = CURRENT.with(Cell::get);
    PEAK.with(|p| p.set(start));
    let result = f();
    let peak = PEAK.with(Cell::get) - start;
    (result, peak.max(0) as usize)
}

/// A small deterministic pseudo-random generator (xorshift64*), so every run mutates the
/// same bytes.
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.max(1))
    }
    pub fn next_u64(&mut self) -> u64 {
        let mut x = self.0;
        x ^= x >> 12;
        x ^= x << 25;
        x ^= x >> 27;
        self.0 = x;
        x.wrapping_mul(0x2545_f491_4f6c_dd1d)
    }
    pub fn below(&mut self, n: usize) -> usize {
        (self.next_u64() % n.max(1) as u64) as usize
    }
}

/// One malformed variant of a file and how it was made.
pub struct Mutant {
    pub label: String,
    pub bytes: Vec<u8>,
}

/// Truncations at `count` evenly spread lengths (always including 0 and len − 1).
pub fn truncations(data: &[u8], count: usize) -> Vec<Mutant> {
    let mut cuts: Vec<usize> = (0..count).map(|i| i * data.len() / count.max(1)).collect();
    cuts.push(data.len().saturating_sub(1));
    cuts.dedup();
    cuts.into_iter()
        .map(|n| Mutant { label: format!("truncated to {n} bytes"), bytes: data[..n].to_vec() })
        .collect()
}

/// `count` variants with `flips` random bytes each replaced by random values.
pub fn byte_flips(data: &[u8], count: usize, flips: usize, seed: u64) -> Vec<Mutant> {
    let mut rng = Rng::new(seed);
    (0..count)
        .map(|i| {
            let mut bytes = data.to_vec();
            let mut where_ = Vec::new();
            for _ in 0..flips {
                let at = rng.below(bytes.len());
                bytes[at] ^= (rng.below(255) + 1) as u8;
                where_.push(at);
            }
            Mutant { label: format!("flip #{i} at bytes {where_:?}"), bytes }
        })
        .collect()
}

/// Overwrites the 4 bytes at `offset` with `value` (little-endian).
pub fn overwrite_u32(data: &[u8], offset: usize, value: u32, label: &str) -> Mutant {
    let mut bytes = data.to_vec();
    if offset + 4 <= bytes.len() {
        bytes[offset..offset + 4].copy_from_slice(&value.to_le_bytes());
    }
    Mutant { label: format!("{label}: bytes {offset}..{} := {value:#x}", offset + 4), bytes }
}

/// Runs `parse` on every mutant. Fails (with every offending mutant listed) if any panics,
/// if any allocates more than `max_alloc(len)` bytes at once, or if an error message lacks
/// a location according to `has_location`. Returns (accepted, rejected) counts.
pub fn run_suite<E: std::fmt::Display, T>(
    name: &str,
    mutants: &[Mutant],
    parse: impl Fn(&[u8]) -> Result<T, E>,
    max_alloc: impl Fn(usize) -> usize,
    has_location: impl Fn(&E) -> bool,
) -> (usize, usize) {
    let mut failures = Vec::new();
    let (mut ok, mut rejected) = (0, 0);
    let previous_hook = std::panic::take_hook();
    // MALFORMED_SHOW_PANICS=1 keeps the default hook, to see where a panic comes from.
    if std::env::var_os("MALFORMED_SHOW_PANICS").is_none() {
        std::panic::set_hook(Box::new(|_| {}));
    }
    for m in mutants {
        let outcome = measure_peak(|| catch_unwind(AssertUnwindSafe(|| parse(&m.bytes).map(|_| ()))));
        match outcome {
            (Err(panic), _) => {
                let msg = panic
                    .downcast_ref::<String>()
                    .cloned()
                    .or_else(|| panic.downcast_ref::<&str>().map(|s| (*s).to_owned()))
                    .unwrap_or_default();
                failures.push(format!("{}: PANIC {msg}", m.label));
            }
            (Ok(result), peak) => {
                let limit = max_alloc(m.bytes.len());
                if peak > limit {
                    failures.push(format!("{}: allocated {peak} bytes at once, limit {limit}", m.label));
                }
                match result {
                    Ok(()) => ok += 1,
                    Err(e) => {
                        rejected += 1;
                        if !has_location(&e) {
                            failures.push(format!("{}: error without a location: {e}", m.label));
                        }
                    }
                }
            }
        }
    }
    std::panic::set_hook(previous_hook);
    assert!(
        failures.is_empty(),
        "{name}: {} of {} mutants failed:\n{}",
        failures.len(),
        mutants.len(),
        failures.join("\n")
    );
    eprintln!(
        "{name}: {} malformed files, {ok} imported, {rejected} rejected with a location, 0 panics",
        mutants.len()
    );
    (ok, rejected)
}
