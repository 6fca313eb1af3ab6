//! Editor state kept apart from the UI: the [`Document`] (scene, file, dirty flag, undo
//! history), the [`Selection`] and the [`Playback`] clock.
//!
//! Every change to the scene goes through [`Document::edit`] (or [`Document::edit_continuous`]
//! for drags), which records a whole-scene snapshot for undo. Widgets never keep their own
//! undo state.

use std::collections::BTreeSet;
use std::path::{Path, PathBuf};

use keyrig_core::Scene;

use crate::channels::ChannelId;

/// How many undo steps are kept.
pub const UNDO_LIMIT: usize = 200;

/// Most bytes of key data the undo steps may hold of their own (a step shares every track
/// its edit did not change with the scene after it, so most steps hold little). Past this the
/// oldest steps are dropped, at least one step is always kept.
pub const UNDO_MEMORY_LIMIT: usize = 64 << 20;

#[derive(Clone, Debug)]
struct Snapshot {
    label: String,
    scene: Scene,
    /// Key data this snapshot holds that the scene after it does not share (copy-on-write
    /// keys): what keeping the step costs.
    bytes: usize,
}

/// The scene being edited, where it lives on disk, and its history.
#[derive(Clone, Debug)]
pub struct Document {
    scene: Scene,
    path: Option<PathBuf>,
    dirty: bool,
    undo: Vec<Snapshot>,
    redo: Vec<Snapshot>,
    /// Id of the continuous edit (a drag) whose snapshot is already on the undo stack.
    open_group: Option<String>,
    /// Increases on every change of `scene` (edits, undo, redo); caches compare it.
    revision: u64,
    /// Distinguishes documents (new, open), so caches keyed by revision do not mix them up.
    id: u64,
}

static NEXT_DOCUMENT_ID: std::sync::atomic::AtomicU64 = std::sync::atomic::AtomicU64::new(1);

impl Document {
    /// A document for `scene`, clean, with no history.
    #[must_use]
    pub fn new(scene: Scene, path: Option<PathBuf>) -> Self {
        let id = NEXT_DOCUMENT_ID.fetch_add(1, std::sync::atomic::Ordering::Relaxed);
        Document {
            scene,
            path,
            dirty: false,
            undo: Vec::new(),
            redo: Vec::new(),
            open_group: None,
            revision: 0,
            id,
        }
    }

    #[must_use]
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    #[must_use]
    pub fn path(&self) -> Option<&Path> {
        self.path.as_deref()
    }

    /// True when the scene differs from what was last saved or opened.
    #[must_use]
    pub fn is_dirty(&self) -> bool {
        self.dirty
    }

    /// Increases on every change of the scene.
    #[must_use]
    pub fn revision(&self) -> u64 {
        self.revision
    }

    /// Identifies this document's current content for caches: (document, revision).
    #[must_use]
    pub fn cache_key(&self) -> (u64, u64) {
        (self.id, self.revision)
    }

    /// The file name, or "untitled".
    #[must_use]
    pub fn display_name(&self) -> String {
        self.path
            .as_deref()
            .and_then(Path::file_name)
            .map_or_else(|| "untitled".to_owned(), |n| n.to_string_lossy().into_owned())
    }

    /// The window title: `keyrig — name` with a `*` when dirty.
    #[must_use]
    pub fn title(&self) -> String {
        format!("keyrig — {}{}", self.display_name(), if self.dirty { "*" } else { "" })
    }

    /// Applies `change` to the scene as one undoable step labelled `label`. If the change
    /// leaves the scene equal to what it was, nothing is recorded. Returns whether it changed.
    pub fn edit(&mut self, label: &str, change: impl FnOnce(&mut Scene)) -> bool {
        self.open_group = None;
        let before = self.scene.clone();
        change(&mut self.scene);
        if self.scene == before {
            return false;
        }
        self.push_undo(label, before);
        true
    }

    /// Like [`Document::edit`], but consecutive calls with the same `group` (one slider drag,
    /// one gizmo drag) form a single undo step until [`Document::close_group`] is called.
    pub fn edit_continuous(&mut self, group: &str, label: &str, change: impl FnOnce(&mut Scene)) -> bool {
        let before = self.scene.clone();
        change(&mut self.scene);
        if self.scene == before {
            return false;
        }
        if self.open_group.as_deref() == Some(group) {
            self.redo.clear();
            self.dirty = true;
            self.revision += 1;
        } else {
            self.push_undo(label, before);
            self.open_group = Some(group.to_owned());
        }
        true
    }

    /// Ends the current continuous edit; the next one starts a new undo step.
    pub fn close_group(&mut self) {
        self.open_group = None;
    }

    fn push_undo(&mut self, label: &str, before: Scene) {
        let bytes = before.key_bytes_not_shared_with(&self.scene);
        self.undo.push(Snapshot { label: label.to_owned(), scene: before, bytes });
        // At most UNDO_LIMIT steps, and the oldest go first once the steps together hold more
        // than UNDO_MEMORY_LIMIT bytes of keys of their own (as Blender's undo memory limit).
        let mut held: usize = self.undo.iter().map(|s| s.bytes).sum();
        let mut drop = 0;
        while self.undo.len() - drop > 1 && (self.undo.len() - drop > UNDO_LIMIT || held > UNDO_MEMORY_LIMIT)
        {
            held -= self.undo[drop].bytes;
            drop += 1;
        }
        self.undo.drain(..drop);
        self.redo.clear();
        self.dirty = true;
        self.revision += 1;
    }

    /// Number of undo steps kept (at most [`UNDO_LIMIT`]).
    #[must_use]
    pub fn undo_len(&self) -> usize {
        self.undo.len()
    }

    /// Label of the step [`Document::undo`] would revert.
    #[must_use]
    pub fn undo_label(&self) -> Option<&str> {
        self.undo.last().map(|s| s.label.as_str())
    }

    /// Label of the step [`Document::redo`] would repeat.
    #[must_use]
    pub fn redo_label(&self) -> Option<&str> {
        self.redo.last().map(|s| s.label.as_str())
    }

    /// Reverts the last step. Returns false when there is nothing to undo.
    pub fn undo(&mut self) -> bool {
        self.open_group = None;
        let Some(snapshot) = self.undo.pop() else { return false };
        let current = std::mem::replace(&mut self.scene, snapshot.scene);
        let bytes = current.key_bytes_not_shared_with(&self.scene);
        self.redo.push(Snapshot { label: snapshot.label, scene: current, bytes });
        self.dirty = true;
        self.revision += 1;
        true
    }

    /// Repeats the last undone step. Returns false when there is nothing to redo.
    pub fn redo(&mut self) -> bool {
        self.open_group = None;
        let Some(snapshot) = self.redo.pop() else { return false };
        let current = std::mem::replace(&mut self.scene, snapshot.scene);
        let bytes = current.key_bytes_not_shared_with(&self.scene);
        self.undo.push(Snapshot { label: snapshot.label, scene: current, bytes });
        self.dirty = true;
        self.revision += 1;
        true
    }

    /// Records that the scene was saved to `path`.
    pub fn mark_saved(&mut self, path: PathBuf) {
        self.path = Some(path);
        self.dirty = false;
    }

    /// Marks the document as changed without an undo step (e.g. a recovered scene).
    pub fn mark_dirty(&mut self) {
        self.dirty = true;
    }
}

/// What is selected in the scene.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Selected {
    Object(usize),
    Joint { object: usize, joint: usize },
    Light(usize),
}

/// One key of one channel (index into the channel's track).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub struct KeyRef {
    pub channel: ChannelId,
    pub index: usize,
}

/// The selected scene item and the selected keys.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Selection {
    pub item: Option<Selected>,
    pub keys: BTreeSet<KeyRef>,
}

impl Selection {
    /// The channels the selected item owns (a joint's rotation, an object's transform, a light's
    /// channels).
    #[must_use]
    pub fn channels(&self, scene: &Scene) -> Vec<ChannelId> {
        match self.item {
            Some(Selected::Object(o)) => {
                vec![ChannelId::ObjectTranslation(o), ChannelId::ObjectRotation(o), ChannelId::ObjectScale(o)]
                    .into_iter()
                    .filter(|_| o < scene.objects.len())
                    .collect()
            }
            Some(Selected::Joint { object, joint }) => {
                let exists = scene
                    .objects
                    .get(object)
                    .and_then(|o| o.skeleton.as_ref())
                    .is_some_and(|s| joint < s.joints.len());
                if exists {
                    ChannelId::of_object(scene, object)
                        .into_iter()
                        .filter(|id| {
                            matches!(id, ChannelId::JointTranslation { joint: j, .. }
                                | ChannelId::JointRotation { joint: j, .. }
                                | ChannelId::JointScale { joint: j, .. } if *j == joint)
                        })
                        .collect()
                } else {
                    Vec::new()
                }
            }
            Some(Selected::Light(l)) if l < scene.lights.len() => ChannelId::of_light(l).to_vec(),
            _ => Vec::new(),
        }
    }

    /// Drops selections that no longer exist in `scene` (after undo, open, delete).
    pub fn retain_valid(&mut self, scene: &Scene) {
        let item_ok = match self.item {
            None => true,
            Some(Selected::Object(o)) => o < scene.objects.len(),
            Some(Selected::Joint { object, joint }) => scene
                .objects
                .get(object)
                .and_then(|o| o.skeleton.as_ref())
                .is_some_and(|s| joint < s.joints.len()),
            Some(Selected::Light(l)) => l < scene.lights.len(),
        };
        if !item_ok {
            self.item = None;
        }
        self.keys.retain(|k| k.index < crate::channels::key_count(scene, k.channel));
    }
}

/// The playback clock. The current time is kept in frames (fractional while playing).
#[derive(Clone, Debug, PartialEq)]
pub struct Playback {
    pub frame: f64,
    pub playing: bool,
    pub looping: bool,
    /// Every-frame playback: each drawn frame advances one scene frame, however long it
    /// took (slow motion when drawing is slower than the scene's fps). Off (the default) is
    /// real-time playback: the clock follows the wall clock and drops frames to keep time.
    pub every_frame: bool,
}

impl Default for Playback {
    fn default() -> Self {
        Playback { frame: 0.0, playing: false, looping: true, every_frame: false }
    }
}

impl Playback {
    /// Current time in seconds for a scene running at `fps`.
    #[must_use]
    pub fn time(&self, fps: f64) -> f64 {
        if fps > 0.0 {
            self.frame / fps
        } else {
            0.0
        }
    }

    /// The whole frame the clock is on (what keys are written at).
    #[must_use]
    pub fn whole_frame(&self) -> i32 {
        self.frame.round() as i32
    }

    /// Advances by `dt` seconds at `fps`, looping or stopping at the end of `[start, end]`.
    pub fn advance(&mut self, dt: f64, fps: f64, start: i32, end: i32) {
        if !(self.playing && dt.is_finite() && fps.is_finite() && fps > 0.0) {
            return;
        }
        let (start, end) = (f64::from(start), f64::from(end.max(start)));
        self.frame += if self.every_frame { 1.0 } else { dt * fps };
        if self.frame > end {
            if self.looping && end > start {
                self.frame = start + (self.frame - start) % (end - start);
            } else {
                self.frame = end;
                self.playing = false;
            }
        }
        if self.frame < start {
            self.frame = start;
        }
    }

    /// Starts or stops playback; starting at (or past) the end with looping off starts from
    /// `start`, as a player's Play at the end of a clip does.
    pub fn toggle_play(&mut self, start: i32, end: i32) {
        if !self.playing && !self.looping && self.frame >= f64::from(end) {
            self.frame = f64::from(start);
        }
        self.playing = !self.playing;
    }

    /// Scene frames shown per second while playing, given the smoothed seconds between drawn
    /// frames: every drawn frame in every-frame mode, at most the scene's fps in real time.
    #[must_use]
    pub fn achieved_fps(&self, frame_time: f64, fps: f64) -> f64 {
        let drawn = 1.0 / frame_time.max(1e-6);
        if self.every_frame {
            drawn
        } else {
            drawn.min(fps)
        }
    }

    /// Jumps to a whole frame, clamped to `[start, end]`.
    pub fn go_to(&mut self, frame: i32, start: i32, end: i32) {
        self.frame = f64::from(frame.clamp(start, end.max(start)));
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use keyrig_core::Object;

    #[test]
    fn edit_undo_redo_restore_exact_scenes() {
        let mut doc = Document::new(Scene::default(), None);
        let original = doc.scene().clone();
        assert!(doc.edit("add box", |s| s.objects.push(Object::new("Box"))));
        let edited = doc.scene().clone();
        assert!(doc.is_dirty());
        assert!(doc.undo());
        assert_eq!(doc.scene(), &original);
        assert!(doc.redo());
        assert_eq!(doc.scene(), &edited);
        assert!(!doc.redo());
    }

    #[test]
    fn edit_without_change_records_nothing() {
        let mut doc = Document::new(Scene::default(), None);
        assert!(!doc.edit("nothing", |_| {}));
        assert!(!doc.is_dirty());
        assert_eq!(doc.undo_label(), None);
    }

    #[test]
    fn continuous_edits_form_one_step() {
        let mut doc = Document::new(Scene::default(), None);
        for fps in [24.0, 25.0, 26.0] {
            doc.edit_continuous("fps", "change fps", |s| s.fps = fps);
        }
        doc.close_group();
        doc.edit_continuous("fps", "change fps", |s| s.fps = 60.0);
        assert!(doc.undo());
        assert_eq!(doc.scene().fps, 26.0);
        assert!(doc.undo());
        assert_eq!(doc.scene().fps, 30.0);
        assert!(!doc.undo());
    }

    #[test]
    fn playback_loops_and_stops() {
        let mut p = Playback { frame: 9.0, playing: true, looping: true, every_frame: false };
        p.advance(0.1, 30.0, 0, 10);
        assert!((p.frame - 2.0).abs() < 1e-9, "{}", p.frame);
        let mut p = Playback { frame: 9.0, playing: true, looping: false, every_frame: false };
        p.advance(0.1, 30.0, 0, 10);
        assert_eq!(p.frame, 10.0);
        assert!(!p.playing);
        // Play at the end with looping off starts from the first frame.
        p.toggle_play(0, 10);
        assert!(p.playing);
        assert_eq!(p.frame, 0.0);
        // With looping on, Play at the end stays (the next step wraps).
        let mut p = Playback { frame: 10.0, playing: false, looping: true, every_frame: false };
        p.toggle_play(0, 10);
        assert_eq!(p.frame, 10.0);
    }

    #[test]
    fn real_time_drops_frames_and_every_frame_does_not() {
        // A slow draw (0.1 s) at 30 fps: real time jumps 3 frames, every-frame mode 1.
        let mut p = Playback { frame: 0.0, playing: true, looping: true, every_frame: false };
        p.advance(0.1, 30.0, 0, 100);
        assert!((p.frame - 3.0).abs() < 1e-9);
        assert!((p.achieved_fps(0.1, 30.0) - 10.0).abs() < 1e-9);
        assert!((p.achieved_fps(0.01, 30.0) - 30.0).abs() < 1e-9, "never above the scene's fps");
        p.every_frame = true;
        p.advance(0.1, 30.0, 0, 100);
        assert!((p.frame - 4.0).abs() < 1e-9);
        assert!((p.achieved_fps(0.01, 30.0) - 100.0).abs() < 1e-6);
    }

    #[test]
    fn title_shows_name_and_dirty_marker() {
        let mut doc = Document::new(Scene::default(), Some(PathBuf::from("/tmp/arm.ron")));
        assert_eq!(doc.title(), "keyrig — arm.ron");
        doc.edit("fps", |s| s.fps = 24.0);
        assert_eq!(doc.title(), "keyrig — arm.ron*");
    }
}

#[cfg(test)]
mod undo_memory_tests {
    use super::*;
    use glam::Vec3;
    use keyrig_core::{Key, Object, RawTrack};

    /// A scene of two objects whose translation tracks hold `keys` keys each.
    fn scene(keys: usize) -> Scene {
        let mut scene = Scene::default();
        for name in ["A", "B"] {
            let mut o = Object::new(name);
            o.translation.track =
                RawTrack::new((0..keys).map(|k| Key::new(k as f64, Vec3::X * k as f32)).collect());
            scene.objects.push(o);
        }
        scene
    }

    #[test]
    fn an_undo_step_holds_only_the_tracks_its_edit_changed() {
        let mut doc = Document::new(scene(1000), None);
        assert!(doc.edit("move", |s| s.objects[0].translation.track.keys[3].value = Vec3::Y));
        let before = &doc.undo.last().expect("a step").scene;
        // B's keys are the same list in the step and in the scene; A's were copied by the edit.
        assert!(before.objects[1]
            .translation
            .track
            .keys
            .shares_with(&doc.scene().objects[1].translation.track.keys));
        assert!(!before.objects[0]
            .translation
            .track
            .keys
            .shares_with(&doc.scene().objects[0].translation.track.keys));
        let key = std::mem::size_of::<Key<Vec3>>();
        assert_eq!(doc.undo.last().unwrap().bytes, 1000 * key);
        // An edit that changes nothing leaves no step and copies nothing.
        assert!(!doc.edit("nothing", |s| s.objects[1].translation.value = Vec3::ZERO));
        assert_eq!(doc.undo_len(), 1);
        assert!(doc.undo());
        assert_eq!(doc.scene().objects[0].translation.track.keys[3].value, Vec3::X * 3.0);
        assert!(doc.redo());
        assert_eq!(doc.scene().objects[0].translation.track.keys[3].value, Vec3::Y);
    }

    #[test]
    fn undo_history_stays_within_its_memory_limit() {
        // Each edit copies a track of 200,000 keys (about 20 MB): only a few steps fit in the
        // limit, the newest are kept, and undoing them still works.
        let keys = 200_000;
        let mut doc = Document::new(scene(keys), None);
        for e in 0..12 {
            assert!(doc.edit("move", |s| s.objects[0].translation.track.keys[5].value =
                Vec3::Z * e as f32 + Vec3::ONE));
        }
        let held: usize = doc.undo.iter().map(|s| s.bytes).sum();
        assert!(held <= UNDO_MEMORY_LIMIT, "{held} bytes held");
        assert!(doc.undo_len() >= 2 && doc.undo_len() < 12, "{} steps", doc.undo_len());
        let kept = doc.undo_len();
        for _ in 0..kept {
            assert!(doc.undo());
        }
        assert!(!doc.undo());
        let oldest_kept = 12 - kept;
        assert_eq!(
            doc.scene().objects[0].translation.track.keys[5].value,
            Vec3::Z * (oldest_kept as f32 - 1.0) + Vec3::ONE
        );
    }
}
