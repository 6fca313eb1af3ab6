//! The session remembered per scene file: the current frame, the viewport's camera, the
//! selection and the panel sizes an animator left a scene with, restored when it is opened
//! again.
//!
//! They live in the editor's data folder (`sessions.json`, beside `recent.txt`), keyed by the
//! scene file's full path, not in the scene file: the scene is what the animator edits, shares
//! and puts under version control, and where one person left the playhead or the camera is
//! neither an edit of it (it would make every reopened file dirty, and every commit carry a
//! frame number) nor the same for two people sharing the file. The file keeps the
//! [`SESSION_LIMIT`] scenes used last; one that cannot be read is treated as empty (a
//! convenience, as the recent-files list is) and rewritten by the next save.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use keyrig_core::{Camera, Scene};
use serde::{Deserialize, Serialize};

use super::FileError;
use crate::session::{Selected, Selection};

/// How many scene files' sessions are kept.
pub const SESSION_LIMIT: usize = 50;

/// The file in the data folder.
const FILE_NAME: &str = "sessions.json";

/// A selected item by name, so that it finds its item again when objects were added or
/// reordered by another program.
#[derive(Clone, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ItemName {
    Object(String),
    Joint { object: String, joint: String },
    Light(String),
    Camera(String),
}

impl ItemName {
    /// The name of `item` in `scene` (none when it does not exist).
    #[must_use]
    pub fn of(scene: &Scene, item: Selected) -> Option<Self> {
        Some(match item {
            Selected::Object(o) => ItemName::Object(scene.objects.get(o)?.name.clone()),
            Selected::Joint { object, joint } => {
                let o = scene.objects.get(object)?;
                let j = o.skeleton.as_ref()?.joints.get(joint)?;
                ItemName::Joint { object: o.name.clone(), joint: j.name.clone() }
            }
            Selected::Light(l) => ItemName::Light(scene.lights.get(l)?.name.clone()),
            Selected::Camera(c) => ItemName::Camera(scene.cameras.get(c)?.name.clone()),
        })
    }

    /// The item of `scene` this name finds (none when it has gone).
    #[must_use]
    pub fn find(&self, scene: &Scene) -> Option<Selected> {
        let object = |name: &str| scene.objects.iter().position(|o| o.name == name);
        match self {
            ItemName::Object(name) => object(name).map(Selected::Object),
            ItemName::Joint { object: o, joint } => {
                let o = object(o)?;
                let skeleton = scene.objects[o].skeleton.as_ref()?;
                let j = skeleton.joints.iter().position(|x| &x.name == joint)?;
                Some(Selected::Joint { object: o, joint: j })
            }
            ItemName::Light(name) => scene.lights.iter().position(|l| &l.name == name).map(Selected::Light),
            ItemName::Camera(name) => {
                scene.cameras.iter().position(|c| &c.name == name).map(Selected::Camera)
            }
        }
    }
}

/// The sizes of the resizable panels, points.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub struct PanelSizes {
    /// The outliner's width.
    pub outliner: f32,
    /// The inspector's width.
    pub inspector: f32,
    /// The height of the timeline (transport, dope sheet and curves).
    pub timeline: f32,
}

impl PanelSizes {
    /// egui's ids of the outliner, the inspector and the timeline panel.
    pub const IDS: [&'static str; 3] = ["outliner", "inspector", "timeline"];

    /// The sizes egui kept for the panels in the last frame (none before the first frame).
    #[must_use]
    pub fn read(ctx: &egui::Context) -> Option<Self> {
        let size =
            |id: &str| egui::containers::panel::PanelState::load(ctx, egui::Id::new(id)).map(|s| s.size());
        let [outliner, inspector, timeline] = Self::IDS.map(size);
        Some(PanelSizes { outliner: outliner?.x, inspector: inspector?.x, timeline: timeline?.y })
    }

    /// Gives the panels these sizes from the next frame on (egui reads a panel's size from its
    /// state; the window keeps each within what fits).
    pub fn apply(self, ctx: &egui::Context) {
        let sizes =
            [egui::vec2(self.outliner, 1.0), egui::vec2(self.inspector, 1.0), egui::vec2(1.0, self.timeline)];
        for (id, size) in Self::IDS.into_iter().zip(sizes) {
            let size = egui::vec2(size.x.clamp(1.0, 4000.0), size.y.clamp(1.0, 4000.0));
            let state = egui::containers::panel::PanelState {
                rect: egui::Rect::from_min_size(egui::Pos2::ZERO, size),
            };
            ctx.data_mut(|d| d.insert_persisted(egui::Id::new(id), state));
        }
    }
}

/// What is remembered of one scene file's session.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub struct SavedSession {
    /// The scene file (its full path).
    pub scene: PathBuf,
    /// The current frame.
    pub frame: i32,
    /// The viewport's orbit camera.
    pub camera: Camera,
    /// The selected items, the active one first.
    pub selection: Vec<ItemName>,
    /// The panel sizes, when the window had been laid out.
    #[serde(default)]
    pub panels: Option<PanelSizes>,
}

impl SavedSession {
    /// The selection these names find in `scene` (names that are gone are left out).
    #[must_use]
    pub fn selection_in(&self, scene: &Scene) -> Selection {
        let mut selection = Selection::default();
        for item in self.selection.iter().filter_map(|name| name.find(scene)) {
            if selection.item.is_none() {
                selection.item = Some(item);
            } else {
                selection.others.insert(item);
            }
        }
        selection
    }
}

#[derive(Debug, Default, Serialize, Deserialize)]
struct SessionsFile {
    /// Newest first.
    sessions: Vec<SavedSession>,
}

/// The sessions file in the data folder.
#[derive(Clone, Debug)]
pub struct Sessions {
    dir: Option<PathBuf>,
}

impl Sessions {
    #[must_use]
    pub fn new(dir: Option<&Path>) -> Self {
        Sessions { dir: dir.map(Path::to_path_buf) }
    }

    /// The file's path (none without a data folder).
    #[must_use]
    pub fn file(&self) -> Option<PathBuf> {
        self.dir.as_ref().map(|d| d.join(FILE_NAME))
    }

    fn read(&self) -> SessionsFile {
        self.file()
            .and_then(|f| super::recovery::read_small_text(&f))
            .and_then(|text| serde_json::from_str(&text).ok())
            .unwrap_or_default()
    }

    /// The session remembered for the scene file `scene`, if any.
    #[must_use]
    pub fn load(&self, scene: &Path) -> Option<SavedSession> {
        let key = key(scene);
        self.read().sessions.into_iter().find(|s| s.scene == key)
    }

    /// Remembers `session` for its scene file (first in the list; the oldest beyond
    /// [`SESSION_LIMIT`] go), written atomically.
    pub fn store(&self, mut session: SavedSession) -> Result<(), FileError> {
        let (Some(dir), Some(file)) = (&self.dir, self.file()) else { return Err(FileError::NoDataFolder) };
        session.scene = key(&session.scene);
        let mut all = self.read();
        all.sessions.retain(|s| s.scene != session.scene);
        all.sessions.insert(0, session);
        all.sessions.truncate(SESSION_LIMIT);
        let text = serde_json::to_string_pretty(&all).unwrap_or_default();
        std::fs::create_dir_all(dir)
            .map_err(|e| FileError::Folder { path: dir.clone(), source: Arc::new(e) })?;
        keyrig_io::file_io::write_atomic(&file, text.as_bytes())
            .map_err(|e| FileError::Write { path: file.clone(), source: Arc::new(e) })
    }
}

/// A scene file's key: its canonical path when it exists.
fn key(scene: &Path) -> PathBuf {
    std::fs::canonicalize(scene).unwrap_or_else(|_| scene.to_path_buf())
}

#[cfg(test)]
mod tests {
    use super::*;

    fn session(scene: &Path, frame: i32) -> SavedSession {
        SavedSession {
            scene: scene.to_path_buf(),
            frame,
            camera: Camera::default(),
            selection: vec![ItemName::Joint { object: "Arm".into(), joint: "elbow".into() }],
            panels: Some(PanelSizes { outliner: 200.0, inspector: 300.0, timeline: 250.0 }),
        }
    }

    #[test]
    fn sessions_are_kept_per_scene_newest_first_and_capped() {
        let dir = tempfile::tempdir().expect("temp dir");
        let sessions = Sessions::new(Some(dir.path()));
        let a = dir.path().join("a.ron");
        std::fs::write(&a, "").expect("write");
        assert_eq!(sessions.load(&a), None);
        sessions.store(session(&a, 12)).expect("stored");
        sessions.store(session(&a, 40)).expect("stored");
        let loaded = sessions.load(&a).expect("remembered");
        assert_eq!(loaded.frame, 40, "the newer session replaces the older");
        for i in 0..SESSION_LIMIT {
            sessions.store(session(&dir.path().join(format!("{i}.ron")), 1)).expect("stored");
        }
        assert_eq!(sessions.load(&a), None, "the oldest scene went past the limit");
    }

    #[test]
    fn a_damaged_sessions_file_reads_as_empty_and_is_replaced() {
        let dir = tempfile::tempdir().expect("temp dir");
        std::fs::write(dir.path().join(FILE_NAME), "{ not json").expect("write");
        let sessions = Sessions::new(Some(dir.path()));
        let a = dir.path().join("a.ron");
        assert_eq!(sessions.load(&a), None);
        sessions.store(session(&a, 7)).expect("stored");
        assert_eq!(sessions.load(&a).map(|s| s.frame), Some(7));
    }

    #[test]
    fn names_find_their_items_after_a_reorder() {
        let mut scene = keyrig_io::demo::demo_scene();
        let elbow = ItemName::of(&scene, Selected::Joint { object: 0, joint: 1 }).expect("a joint");
        let mut extra = scene.objects[0].clone();
        extra.name = "Other".into();
        scene.objects.insert(0, extra);
        assert_eq!(elbow.find(&scene), Some(Selected::Joint { object: 1, joint: 1 }));
        scene.objects.remove(1);
        assert_eq!(elbow.find(&scene), None, "a deleted object's joint is not selected");
    }
}
