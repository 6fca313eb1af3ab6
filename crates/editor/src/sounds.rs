//! The decoded sound files of the scene's clips, for the waveforms under the dope sheet's ruler.
//!
//! Each file is decoded once, on a thread of its own
//! ([`keyrig_io::sound::decode_sound_file_for_playback`] into a min/max summary and the samples
//! [`crate::audio`] plays), so opening a scene with a long track never holds up a frame; the
//! waveform appears when its thread is done. Files are keyed by their full path (resolved
//! against the scene's folder like model files), so two clips of one file share a summary.

use std::collections::HashMap;
use std::path::{Path, PathBuf};
use std::sync::mpsc::{self, Receiver, TryRecvError};
use std::sync::Arc;

use keyrig_core::{Scene, WaveformSummary};
use keyrig_io::sound::{SoundPcm, MAX_PLAYBACK_FRAMES};

/// Where one sound file's decoding stands.
#[derive(Clone, Debug)]
pub enum SoundLoad {
    /// Its thread is decoding it.
    Loading,
    /// Decoded.
    Ready(Arc<WaveformSummary>),
    /// Why it could not be decoded (the status bar and the row's tooltip say it).
    Failed(String),
}

/// The sound files the scene's clips name, decoded on background threads.
#[derive(Default)]
pub struct SoundStore {
    files: HashMap<PathBuf, SoundLoad>,
    /// The samples of decoded files, for playing them ([`crate::audio`]); a file longer than
    /// [`keyrig_io::sound::MAX_PLAYBACK_FRAMES`] has none and plays silently.
    pcm: HashMap<PathBuf, Arc<SoundPcm>>,
    running: Vec<(PathBuf, Receiver<Decoded>)>,
}

/// What a decoding thread answers.
type Decoded = Result<(WaveformSummary, Option<SoundPcm>), String>;

impl std::fmt::Debug for SoundStore {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.debug_struct("SoundStore")
            .field("files", &self.files.len())
            .field("pcm", &self.pcm.len())
            .field("running", &self.running.len())
            .finish()
    }
}

/// A clip's file resolved against the scene's folder (`base_dir`) when relative.
#[must_use]
pub fn full_path(base_dir: Option<&Path>, path: &str) -> PathBuf {
    match base_dir {
        Some(dir) => dir.join(path),
        None => PathBuf::from(path),
    }
}

impl SoundStore {
    /// Starts decoding every file of `scene`'s clips that is neither decoded nor being decoded,
    /// and lets go of the files no clip names any more (a clip removed, a path changed, another
    /// document): their samples are about 115 MB per ten minutes.
    pub fn request(&mut self, scene: &Scene, base_dir: Option<&Path>) {
        let wanted: Vec<PathBuf> = scene.sounds.iter().map(|clip| full_path(base_dir, &clip.path)).collect();
        if self.files.keys().any(|path| !wanted.contains(path)) {
            self.files.retain(|path, _| wanted.contains(path));
            self.pcm.retain(|path, _| wanted.contains(path));
            // A decoding under way for a file let go answers nobody.
            self.running.retain(|(path, _)| wanted.contains(path));
        }
        for path in wanted {
            if self.files.contains_key(&path) {
                continue;
            }
            let (send, receive) = mpsc::channel();
            let file = path.clone();
            let spawned = std::thread::Builder::new().name("keyrig-sound".into()).spawn(move || {
                let decoded = keyrig_io::sound::decode_sound_file_for_playback(&file, MAX_PLAYBACK_FRAMES)
                    .map(|d| (d.summary, d.pcm))
                    .map_err(|e| e.to_string());
                // The store may be gone (the editor closed): nobody waits for the answer then.
                let _ = send.send(decoded);
            });
            match spawned {
                Ok(_) => {
                    self.files.insert(path.clone(), SoundLoad::Loading);
                    self.running.push((path, receive));
                }
                Err(e) => {
                    self.files.insert(path, SoundLoad::Failed(format!("cannot start a thread: {e}")));
                }
            }
        }
    }

    /// Collects the decodings that finished; returns the failures' messages (for the status
    /// bar), each once.
    pub fn poll(&mut self) -> Vec<String> {
        let mut failures = Vec::new();
        let (files, pcms) = (&mut self.files, &mut self.pcm);
        self.running.retain(|(path, receive)| {
            let outcome = match receive.try_recv() {
                Ok(Ok((summary, pcm))) => {
                    if let Some(pcm) = pcm {
                        pcms.insert(path.clone(), Arc::new(pcm));
                    }
                    SoundLoad::Ready(Arc::new(summary))
                }
                Ok(Err(message)) => SoundLoad::Failed(message),
                Err(TryRecvError::Empty) => return true,
                Err(TryRecvError::Disconnected) => SoundLoad::Failed(format!(
                    "{}: the decoding thread stopped without an answer",
                    path.display()
                )),
            };
            if let SoundLoad::Failed(message) = &outcome {
                failures.push(message.clone());
            }
            files.insert(path.clone(), outcome);
            false
        });
        failures
    }

    /// Whether any file is still being decoded.
    #[must_use]
    pub fn is_loading(&self) -> bool {
        !self.running.is_empty()
    }

    /// The state of the clip file `path` (relative to `base_dir`), if it was requested.
    #[must_use]
    pub fn get(&self, base_dir: Option<&Path>, path: &str) -> Option<&SoundLoad> {
        self.files.get(&full_path(base_dir, path))
    }

    /// The summary of the clip file `path`, once decoded.
    #[must_use]
    pub fn summary(&self, base_dir: Option<&Path>, path: &str) -> Option<&Arc<WaveformSummary>> {
        match self.get(base_dir, path) {
            Some(SoundLoad::Ready(summary)) => Some(summary),
            _ => None,
        }
    }

    /// The samples of the clip file `path`, once decoded (for playing it).
    #[must_use]
    pub fn pcm(&self, base_dir: Option<&Path>, path: &str) -> Option<&Arc<SoundPcm>> {
        self.pcm.get(&full_path(base_dir, path))
    }

    /// Waits (at most `limit`) for every decoding under way; for tests and the command line.
    pub fn wait(&mut self, limit: std::time::Duration) -> Vec<String> {
        let deadline = std::time::Instant::now() + limit;
        let mut failures = Vec::new();
        while self.is_loading() && std::time::Instant::now() < deadline {
            failures.extend(self.poll());
            if self.is_loading() {
                std::thread::sleep(std::time::Duration::from_millis(5));
            }
        }
        failures
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use keyrig_core::SoundClip;

    fn fixtures() -> PathBuf {
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../io/tests/fixtures/sound")
    }

    #[test]
    fn clips_decode_once_per_file_on_threads() {
        let mut scene = Scene::default();
        scene.sounds.push(SoundClip::new("tone.flac", 0.0));
        scene.sounds.push(SoundClip::new("tone.flac", 30.0));
        scene.sounds.push(SoundClip::new("missing.wav", 0.0));
        let mut store = SoundStore::default();
        store.request(&scene, Some(&fixtures()));
        assert_eq!(store.running.len(), 2, "one thread per file");
        assert!(matches!(store.get(Some(&fixtures()), "tone.flac"), Some(SoundLoad::Loading)));
        let failures = store.wait(std::time::Duration::from_secs(20));
        assert!(!store.is_loading());
        assert_eq!(failures.len(), 1, "{failures:?}");
        assert!(failures[0].contains("missing.wav"), "{failures:?}");
        let summary = store.summary(Some(&fixtures()), "tone.flac").expect("decoded");
        assert_eq!((summary.sample_rate, summary.channels, summary.frames), (22_050, 2, 11_025));
        let pcm = store.pcm(Some(&fixtures()), "tone.flac").expect("samples to play");
        assert_eq!(pcm.frames(), 11_025);
        assert!(store.pcm(Some(&fixtures()), "missing.wav").is_none());
        // Requested again (every frame does): nothing restarts, the failure is not repeated.
        store.request(&scene, Some(&fixtures()));
        assert!(!store.is_loading());
        assert!(store.poll().is_empty());
        assert!(matches!(store.get(Some(&fixtures()), "missing.wav"), Some(SoundLoad::Failed(_))));
        assert!(store.get(None, "tone.flac").is_none(), "another folder, another file");
        // The missing file's clip removed: its entry goes, the decoded file stays.
        scene.sounds.pop();
        store.request(&scene, Some(&fixtures()));
        assert!(store.get(Some(&fixtures()), "missing.wav").is_none());
        assert!(store.pcm(Some(&fixtures()), "tone.flac").is_some());
        // No clip left: the samples are let go.
        scene.sounds.clear();
        store.request(&scene, Some(&fixtures()));
        assert!(store.get(Some(&fixtures()), "tone.flac").is_none());
        assert!(store.pcm(Some(&fixtures()), "tone.flac").is_none());
        assert_eq!(format!("{store:?}"), "SoundStore { files: 0, pcm: 0, running: 0 }");
    }
}
