//! The document: the scene being edited, its file, dirty flag and undo history.
//!
//! Every change to the scene goes through [`Document::edit`] (or [`Document::edit_continuous`]
//! for drags), which records a whole-scene snapshot for undo. Widgets never keep their own
//! undo state.

use std::path::{Path, PathBuf};

use keyrig_core::Scene;

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

    /// [`Document::edit_continuous`] whose undo step is named for where the gesture has got to:
    /// each call of the group renames it (a slider dragged to −0.90 is "bias -0.90", not the
    /// first frame's "bias -0.10"). For the edits of one kind a drag repeats (`SceneEdit`s).
    pub fn edit_continuous_renamed(
        &mut self,
        group: &str,
        label: &str,
        change: impl FnOnce(&mut Scene),
    ) -> bool {
        let continuing = self.open_group.as_deref() == Some(group);
        let changed = self.edit_continuous(group, label, change);
        if changed && continuing {
            if let Some(step) = self.undo.last_mut() {
                label.clone_into(&mut step.label);
            }
        }
        changed
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

    /// Labels of the undo steps kept, oldest first (the last is [`Document::undo_label`]).
    pub fn undo_labels(&self) -> impl Iterator<Item = &str> {
        self.undo.iter().map(|s| s.label.as_str())
    }

    /// Labels of the steps that can be redone, in the order [`Document::redo`] repeats them.
    pub fn redo_labels(&self) -> impl Iterator<Item = &str> {
        self.redo.iter().rev().map(|s| s.label.as_str())
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

    /// Issue 42, 6: a drag of a slider is one undo step named for where it ended.
    #[test]
    fn a_renamed_continuous_edit_is_named_for_its_last_step() {
        let mut doc = Document::new(scene(3), None);
        for (i, bias) in [-0.1_f32, -0.5, -0.9].into_iter().enumerate() {
            let label = format!("bias {bias:.2} on A translation key at frame 1");
            doc.edit_continuous_renamed("key inspector", &label, |s| {
                s.objects[0].translation.track.keys[1].tcb.bias = bias
            });
            assert_eq!(doc.undo_len(), 1, "step {i}: one undo step");
        }
        assert_eq!(doc.undo_label(), Some("bias -0.90 on A translation key at frame 1"));
        doc.close_group();
        // A plain continuous edit keeps the name its gesture started with.
        doc.edit_continuous("grab", "duplicate as A.001", |s| s.objects[0].name = "A.001".into());
        doc.edit_continuous("grab", "pose A.001 translation", |s| s.objects[0].translation.value = Vec3::Y);
        assert_eq!(doc.undo_label(), Some("duplicate as A.001"));
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
