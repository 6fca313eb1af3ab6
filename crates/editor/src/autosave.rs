//! Autosave on a timer of its own: a background thread writes the recovery file
//! ([`crate::files::Recovery`]) a fixed time after the first unsaved change, whether or not
//! the window draws. An idle editor (no input, no redraw) with unsaved changes still writes
//! its recovery file, so a crash after a pause loses nothing.
//!
//! The UI thread hands the thread a copy of the scene when the document changes
//! ([`Autosave::note`]); the thread sleeps on a condition variable until the write is due.
//! Saving, a clean quit or a declined recovery clear the file through [`Autosave::clear`],
//! which also drops a write that is pending, so a stale autosave never outlives a save.

use std::path::PathBuf;
use std::sync::{Arc, Condvar, Mutex, MutexGuard};
use std::thread::JoinHandle;
use std::time::{Duration, Instant};

use keyrig_core::Scene;

use crate::files::Recovery;

/// What the UI thread and the autosave thread share.
#[derive(Default)]
struct State {
    /// The scene to write (and the document it came from) when the write is due.
    pending: Option<(Scene, Option<PathBuf>)>,
    /// When the pending scene is to be written.
    due: Option<Instant>,
    /// The last write's error, for the status bar.
    error: Option<crate::files::FileError>,
    /// Recovery files written so far.
    writes: u64,
    stop: bool,
}

type Shared = Arc<(Mutex<State>, Condvar)>;

/// The autosave timer and its thread.
pub struct Autosave {
    shared: Shared,
    interval: Duration,
    recovery: Recovery,
    /// The document (cache key) last handed to the thread.
    noted: Option<(u64, u64)>,
    thread: Option<JoinHandle<()>>,
}

fn lock(shared: &Shared) -> MutexGuard<'_, State> {
    // A panic on the autosave thread must not take the editor with it: keep using the state.
    shared.0.lock().unwrap_or_else(std::sync::PoisonError::into_inner)
}

impl Autosave {
    /// Starts the timer thread writing to `recovery` `interval` after the first unsaved change
    /// (and again `interval` after each later one while changes keep coming).
    #[must_use]
    pub fn new(recovery: Recovery, interval: Duration) -> Self {
        let shared: Shared = Arc::new((Mutex::new(State::default()), Condvar::new()));
        let thread_shared = Arc::clone(&shared);
        let thread_recovery = recovery.clone();
        let thread = std::thread::Builder::new()
            .name("keyrig-autosave".to_owned())
            .spawn(move || run(&thread_shared, &thread_recovery))
            .ok();
        Autosave { shared, interval, recovery, noted: None, thread }
    }

    /// Tells the timer about the document once per frame: `key` changes with every edit,
    /// `scene` is called (and cloned) only when it did and the document is dirty. A clean
    /// document cancels a pending write.
    pub fn note(&mut self, key: (u64, u64), dirty: bool, scene: impl FnOnce() -> (Scene, Option<PathBuf>)) {
        if !dirty {
            if self.noted.is_some() {
                let mut state = lock(&self.shared);
                state.pending = None;
                state.due = None;
                self.noted = None;
            }
            return;
        }
        if self.noted == Some(key) {
            return;
        }
        self.noted = Some(key);
        let snapshot = scene();
        let mut state = lock(&self.shared);
        state.pending = Some(snapshot);
        if state.due.is_none() {
            state.due = Some(Instant::now() + self.interval);
        }
        self.shared.1.notify_all();
    }

    /// Drops a pending write and removes the recovery files (after a save, a clean quit, a
    /// declined recovery). Holds the lock the thread writes under, so no write lands after.
    pub fn clear(&mut self) {
        let mut state = lock(&self.shared);
        state.pending = None;
        state.due = None;
        self.noted = None;
        self.recovery.clear();
    }

    /// The error of the last write, once (the status bar shows it).
    #[must_use]
    pub fn take_error(&self) -> Option<crate::files::FileError> {
        lock(&self.shared).error.take()
    }

    /// How many recovery files this timer has written.
    #[must_use]
    pub fn writes(&self) -> u64 {
        lock(&self.shared).writes
    }
}

/// The thread: sleeps until a write is due, then writes the latest scene.
fn run(shared: &Shared, recovery: &Recovery) {
    let (mutex, wake) = (&shared.0, &shared.1);
    let mut state = mutex.lock().unwrap_or_else(std::sync::PoisonError::into_inner);
    loop {
        if state.stop {
            return;
        }
        let now = Instant::now();
        state = match state.due {
            None => wake.wait(state).unwrap_or_else(std::sync::PoisonError::into_inner),
            Some(due) if due > now => {
                wake.wait_timeout(state, due - now).unwrap_or_else(std::sync::PoisonError::into_inner).0
            }
            Some(_) => {
                state.due = None;
                if let Some((scene, origin)) = state.pending.take() {
                    // Written under the lock: `Autosave::clear` waits for it.
                    match recovery.write(&scene, origin.as_deref()) {
                        Ok(()) => state.writes += 1,
                        Err(e) => state.error = Some(e),
                    }
                }
                state
            }
        };
    }
}

impl Drop for Autosave {
    fn drop(&mut self) {
        lock(&self.shared).stop = true;
        self.shared.1.notify_all();
        if let Some(thread) = self.thread.take() {
            let _ = thread.join();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    /// The write happens on the timer thread with nobody calling in after the edit.
    #[test]
    fn a_dirty_document_is_written_after_the_interval_without_further_calls() {
        let dir = tempfile::tempdir().expect("temp dir");
        let recovery = Recovery::new(Some(dir.path()));
        let mut autosave = Autosave::new(recovery.clone(), Duration::from_millis(100));
        let scene = keyrig_io::demo::demo_scene();
        autosave.note((1, 1), true, || (scene.clone(), None));
        assert!(recovery.load_pending().is_none(), "not before the interval");
        let deadline = Instant::now() + Duration::from_secs(10);
        while recovery.load_pending().is_none() && Instant::now() < deadline {
            std::thread::sleep(Duration::from_millis(20));
        }
        assert_eq!(recovery.load_pending().as_ref(), Some(&scene), "the recovery file holds the scene");
        assert_eq!(autosave.writes(), 1);
        // The same document is not written again; a clean document cancels a pending write.
        autosave.note((1, 1), true, || unreachable!("unchanged documents are not copied"));
        autosave.note((1, 2), true, || (scene.clone(), None));
        autosave.note((1, 2), false, || unreachable!());
        autosave.clear();
        std::thread::sleep(Duration::from_millis(300));
        assert!(recovery.load_pending().is_none(), "cleared, and no write came after");
        assert_eq!(autosave.writes(), 1);
    }
}
