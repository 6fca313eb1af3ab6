//! `keyrig edit FILE --benchmark-frames N`: play N frames in the real window, print frame-time
//! statistics split into preparation and drawing, and exit — so scripts can measure the
//! editor (docs/benchmarks.md).
//!
//! Per frame: the *frame* time is the wall-clock interval from the start of one editor frame to
//! the start of the next; *preparation* is the time the editor spends in its own frame code
//! (scene evaluation, CPU skinning, the panels' layout) minus the viewport's GPU render call;
//! *drawing* is the rest: keyrig-render's viewport, egui's tessellation and rendering, and
//! presenting the window. The first frames (warm-up: building the evaluator and uploading
//! meshes) are not counted. *CPU per frame* is the process's CPU time (every thread: the
//! editor's and the CPU rasterizer's) over the measured frames divided by their number: unlike
//! the frame rate it hardly depends on what else the machine runs, so it compares changes made
//! on a loaded machine.

use std::time::{Duration, Instant};

/// Frames played before measuring.
const WARM_UP: u32 = 10;

/// A running benchmark.
#[derive(Debug)]
pub struct FrameBenchmark {
    frames: u32,
    warm_up: u32,
    last_start: Option<Instant>,
    /// The previous frame's preparation time, paired with its interval when the next starts.
    pending_prepare: Option<Duration>,
    samples: Vec<(Duration, Duration)>,
    /// The process's CPU time when the first measured frame started and when the last ended.
    cpu: (Option<Duration>, Option<Duration>),
}

/// The CPU time of this process so far, all threads together (Linux: `/proc/self/stat`'s
/// `utime` + `stime`, in the kernel's fixed 100 Hz user ticks); `None` elsewhere.
fn process_cpu_time() -> Option<Duration> {
    let stat = std::fs::read_to_string("/proc/self/stat").ok()?;
    // Fields after the command name (which may hold spaces) start at field 3 (`state`).
    let rest = &stat[stat.rfind(')')? + 2..];
    let mut fields = rest.split(' ');
    let utime: u64 = fields.nth(11)?.parse().ok()?;
    let stime: u64 = fields.next()?.parse().ok()?;
    Some(Duration::from_millis((utime + stime) * 10))
}

/// Median, 90th percentile and worst of some durations, in milliseconds.
fn stats(mut ms: Vec<f64>) -> (f64, f64, f64) {
    ms.sort_by(f64::total_cmp);
    let n = ms.len();
    if n == 0 {
        return (0.0, 0.0, 0.0);
    }
    (ms[n / 2], ms[(n * 9 / 10).min(n - 1)], ms[n - 1])
}

impl FrameBenchmark {
    /// Measures `frames` frames after a short warm-up.
    #[must_use]
    pub fn new(frames: u32) -> Self {
        FrameBenchmark {
            frames: frames.max(1),
            warm_up: WARM_UP,
            last_start: None,
            pending_prepare: None,
            samples: Vec::new(),
            cpu: (None, None),
        }
    }

    /// Marks the start of an editor frame; returns its start instant.
    pub fn frame_started(&mut self) -> Instant {
        let now = Instant::now();
        if let (Some(last), Some(prepare)) = (self.last_start, self.pending_prepare.take()) {
            if self.warm_up > 0 {
                self.warm_up -= 1;
            } else {
                self.samples.push((prepare, now - last));
                if self.is_done() {
                    self.cpu.1 = process_cpu_time();
                }
            }
        }
        if self.warm_up == 0 && self.cpu.0.is_none() {
            self.cpu.0 = process_cpu_time();
        }
        self.last_start = Some(now);
        now
    }

    /// Records the preparation time of the frame that started at `start`, given the time its
    /// viewport's GPU render call took.
    pub fn frame_prepared(&mut self, start: Instant, gpu_render: Duration) {
        self.pending_prepare = Some(start.elapsed().saturating_sub(gpu_render));
    }

    /// True once every frame was measured.
    #[must_use]
    pub fn is_done(&self) -> bool {
        self.samples.len() >= self.frames as usize
    }

    /// The report: frame, preparation and drawing times (median, 90th percentile, worst) and
    /// the frame rate.
    #[must_use]
    pub fn report(&self, viewport: &str) -> String {
        let ms = |d: Duration| d.as_secs_f64() * 1e3;
        let frame = stats(self.samples.iter().map(|s| ms(s.1)).collect());
        let prepare = stats(self.samples.iter().map(|s| ms(s.0)).collect());
        let draw = stats(self.samples.iter().map(|s| ms(s.1.saturating_sub(s.0))).collect());
        let total: f64 = self.samples.iter().map(|s| s.1.as_secs_f64()).sum();
        let cpu = match self.cpu {
            (Some(start), Some(end)) if !self.samples.is_empty() => format!(
                "\ncpu      {:.1} ms per frame (the process's CPU time, every thread)",
                ms(end.saturating_sub(start)) / self.samples.len() as f64
            ),
            _ => String::new(),
        };
        format!(
            "keyrig frame benchmark: {} frames, {viewport}\n\
             frame    median {:.2} ms, 90% {:.2} ms, worst {:.2} ms ({:.1} frames per second)\n\
             prepare  median {:.2} ms, 90% {:.2} ms, worst {:.2} ms (evaluation, CPU skinning, UI)\n\
             draw     median {:.2} ms, 90% {:.2} ms, worst {:.2} ms (viewport, egui, present){cpu}",
            self.samples.len(),
            frame.0,
            frame.1,
            frame.2,
            self.samples.len() as f64 / total.max(1e-9),
            prepare.0,
            prepare.1,
            prepare.2,
            draw.0,
            draw.1,
            draw.2,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn frames_after_the_warm_up_are_measured_and_reported() {
        let mut bench = FrameBenchmark::new(3);
        let mut starts = 0;
        while !bench.is_done() {
            let start = bench.frame_started();
            starts += 1;
            bench.frame_prepared(start, Duration::ZERO);
        }
        // Warm-up frames, then one frame's interval is known only when the next starts.
        assert_eq!(starts, WARM_UP + 4);
        let report = bench.report("test");
        assert!(report.starts_with("keyrig frame benchmark: 3 frames, test"), "{report}");
        assert!(report.contains("prepare  median") && report.contains("frames per second"), "{report}");
        if cfg!(target_os = "linux") {
            assert!(report.contains("ms per frame (the process's CPU time"), "{report}");
        }
    }

    #[test]
    fn the_process_cpu_time_grows_with_work() {
        if !cfg!(target_os = "linux") {
            assert_eq!(process_cpu_time(), None);
            return;
        }
        let before = process_cpu_time().expect("/proc/self/stat");
        // Busy work until the kernel's tick counter moves (bounded, so a broken reader fails
        // instead of hanging).
        let started = Instant::now();
        let mut x = 0u64;
        let mut after = before;
        while after == before && started.elapsed() < Duration::from_secs(20) {
            for _ in 0..1_000_000 {
                x = std::hint::black_box(x.wrapping_mul(6364136223846793005).wrapping_add(1));
            }
            after = process_cpu_time().expect("/proc/self/stat");
        }
        assert!(after > before, "{before:?} → {after:?}");
    }
}
