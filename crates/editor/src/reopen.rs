//! The session restored on reopen: when a scene file is saved, another document replaces it or
//! the editor quits, its current frame, viewport camera, selection and panel sizes are
//! remembered in the data folder ([`crate::files::sessions`]); opening the file again restores
//! them. Nothing of it goes into the scene file or its undo history.

use crate::app::EditorApp;
use crate::camera::OrbitCamera;
use crate::files::sessions::{ItemName, PanelSizes, SavedSession};

impl EditorApp {
    /// What would be remembered of the document's session now (none for a document without a
    /// file).
    #[must_use]
    pub fn saved_session(&self) -> Option<SavedSession> {
        let scene = self.doc.scene();
        Some(SavedSession {
            scene: self.doc.path()?.to_path_buf(),
            frame: self.session.playback.whole_frame(),
            camera: self.view.camera,
            selection: self.session.selection.items().filter_map(|item| ItemName::of(scene, item)).collect(),
            panels: self.panel_sizes,
        })
    }

    /// Remembers the document's session for its file (nothing for a document without one). A
    /// document with unsaved changes keeps the session remembered when it was last saved: those
    /// changes are being discarded, and a camera framing discarded imports would open the saved
    /// file on an empty view. A data folder that cannot be written loses only the convenience:
    /// the status bar says so.
    pub fn remember_session(&mut self) {
        if self.doc.is_dirty() {
            return;
        }
        let Some(saved) = self.saved_session() else { return };
        if let Err(e) = self.sessions.store(saved) {
            self.error(format!("The session was not remembered: {e}"));
        }
    }

    /// Restores the session remembered for the document's file: the frame, the camera, the
    /// selection (items found by name), and the panel sizes from the next frame on. Returns
    /// whether one was remembered.
    pub fn restore_session(&mut self) -> bool {
        let Some(saved) = self.doc.path().and_then(|path| self.sessions.load(path)) else { return false };
        let scene = self.doc.scene();
        let range = scene.frame_range;
        self.session.selection = saved.selection_in(scene);
        self.session.set_frame(saved.frame, range);
        self.view.camera = saved.camera.sanitized();
        self.restore_panels = saved.panels;
        true
    }

    /// Gives the panels the sizes a restored session asked for (at the start of a frame) and
    /// keeps the sizes egui laid them out with (at its end), for [`EditorApp::saved_session`].
    pub(crate) fn panel_sizes_ui(&mut self, ctx: &egui::Context, start: bool) {
        if start {
            if let Some(sizes) = self.restore_panels.take() {
                sizes.apply(ctx);
            }
        } else if let Some(sizes) = PanelSizes::read(ctx) {
            self.panel_sizes = Some(sizes);
        }
    }
}
