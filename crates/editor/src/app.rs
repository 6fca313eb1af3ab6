//! The editor application: the [`Document`], the [`Session`] and the [`ViewState`] together
//! with the editor's caches (the prepared frame [`SceneFrame`], the mesh store), the panels
//! ([`Panels`], each with its own state), the frame's queue of [`Action`]s, and the operations
//! that span them (commands, keying, files). Every change the panels, menus and shortcuts ask
//! for is applied here, in [`EditorApp::apply_actions`]. The frame's layout is in
//! [`crate::window`].

use std::path::PathBuf;
use std::sync::Arc;

use std::time::Duration;

use egui::Context;
use glam::Quat;
use keyrig_core::{DeformerKind, Scene};
use keyrig_eval::SceneEvaluator;

pub use crate::actions::PendingAction;
use crate::actions::{Action, Actions, EditResults, SessionChange, Unsaved, ViewChange};
use crate::camera::{Bounds, OrbitCamera};
use crate::commands::Command;
pub use crate::context::Status;
use crate::document::Document;
use crate::eval::ObjectPose;
pub use crate::files::DialogPurpose;
use crate::files::{self, BackgroundImport, ImportPurpose, Recent, Recovery};
use crate::panels::Panels;
use crate::scene_frame::SceneFrame;
use crate::session::{KeyRef, Selected, Session};
use crate::view::ViewState;
use keyrig_edit::channels::{self, ChannelId, ChannelValue};

/// Start-up options (tests use a temporary folder for recovery and recent files).
#[derive(Clone, Debug, Default)]
pub struct EditorOptions {
    /// Folder for the recovery file and the recent-files list; the platform's data folder
    /// when `None`.
    pub data_dir: Option<PathBuf>,
    /// Seconds between autosaves of a dirty document (default 30).
    pub autosave_seconds: Option<f64>,
}

/// The whole editor.
pub struct EditorApp {
    /// Whether [`crate::fonts::install`] ran on the context (at start-up, else on the first
    /// frame).
    pub(crate) fonts_installed: bool,
    /// Whether the window is cleared with the panels' background colour (eframe, through
    /// [`eframe::App::clear_color`]); otherwise each frame paints it ([`crate::theme`]).
    pub(crate) window_clears_background: bool,
    /// The depth format of egui's render pass in the window (set before [`EditorApp::attach_gpu`]
    /// when eframe was asked for a depth buffer): the viewport is then drawn straight into it.
    pub(crate) window_depth: Option<egui_wgpu::wgpu::TextureFormat>,
    /// The scene and its undo history.
    pub doc: Document,
    /// Selection, clock, record mode, overrides, clipboard.
    pub session: Session,
    /// Camera and viewport options.
    pub view: ViewState,
    pub(crate) status: Option<Status>,
    pub(crate) pending: Option<PendingAction>,
    pub(crate) recent: Recent,
    /// The sessions remembered per scene file ([`crate::reopen`]).
    pub(crate) sessions: files::Sessions,
    /// The panel sizes of the last frame, remembered with the session.
    pub(crate) panel_sizes: Option<files::sessions::PanelSizes>,
    /// Panel sizes a restored session gives the next frame.
    pub(crate) restore_panels: Option<files::sessions::PanelSizes>,
    pub(crate) recovery: Recovery,
    /// The autosave timer (a thread of its own: it writes while the window is idle).
    pub(crate) autosave: crate::autosave::Autosave,
    /// A recovered scene the user has been offered, not yet accepted or declined.
    pub(crate) recovery_offer: Option<Scene>,
    pub(crate) file_dialog: egui_file_dialog::FileDialog,
    pub(crate) dialog_purpose: Option<DialogPurpose>,
    /// Meshes of model files the scene refers to.
    pub(crate) meshes: files::MeshStore,
    /// Sound files of the scene's clips, decoded on their threads (the dope sheet's waveforms).
    pub(crate) sounds: crate::sounds::SoundStore,
    /// The sound device and how playback follows it.
    pub(crate) audio: crate::audio::Audio,
    /// The frame's preparation: the evaluator, the evaluated scene, CPU skinning, bounds.
    pub(crate) scene: SceneFrame,
    /// The panels, each with its own gesture and view state.
    pub(crate) panels: Panels,
    /// What the panels, menus and shortcuts asked for this frame, applied at its end.
    pub(crate) actions: Actions,
    /// What the last applied edits reported back to the panels that pushed them.
    pub(crate) results: EditResults,
    /// The document (id, revision) the selection was last checked against.
    pub(crate) selection_checked: (u64, u64),
    /// Model imports running on background threads (the status bar shows them).
    pub(crate) imports: Vec<files::BackgroundImport>,
    /// File ▸ Import scale: the factor models imported into the scene are scaled by (1 keeps
    /// the file's own unit), kept while the editor runs.
    pub(crate) import_scale: f32,
    /// Smoothed time between frames while playing, seconds (shown in the status bar).
    pub(crate) frame_time: Option<f32>,
    /// File ▸ Render animation running on its thread.
    pub(crate) render: Option<crate::render_job::RenderJob>,
    /// `keyrig edit --benchmark-frames N`: plays, measures N frames, prints and quits.
    pub(crate) frame_benchmark: Option<crate::frame_bench::FrameBenchmark>,
    pub(crate) window_title: String,
    pub(crate) close_sent: bool,
    pub(crate) quit_confirmed: bool,
}

impl EditorApp {
    /// An editor on `scene` (from `path` when it came from a file).
    #[must_use]
    pub fn new(scene: Scene, path: Option<PathBuf>, options: EditorOptions) -> Self {
        let data_dir = options.data_dir.clone().or_else(files::default_data_dir);
        let recovery = Recovery::new(data_dir.as_deref());
        let recovery_offer = recovery.load_pending();
        let view = ViewState::new(scene.camera.sanitized());
        let session = Session::at_start(scene.frame_range);
        EditorApp {
            fonts_installed: false,
            window_clears_background: false,
            window_depth: None,
            doc: Document::new(scene, path),
            session,
            view,
            status: None,
            pending: None,
            recent: Recent::load(data_dir.as_deref()),
            sessions: files::Sessions::new(data_dir.as_deref()),
            panel_sizes: None,
            restore_panels: None,
            autosave: crate::autosave::Autosave::new(
                recovery.clone(),
                std::time::Duration::from_secs_f64(
                    options.autosave_seconds.unwrap_or(30.0).clamp(0.001, 1e9),
                ),
            ),
            recovery,
            recovery_offer,
            file_dialog: egui_file_dialog::FileDialog::new(),
            dialog_purpose: None,
            meshes: files::MeshStore::default(),
            sounds: crate::sounds::SoundStore::default(),
            audio: crate::audio::Audio::default(),
            scene: SceneFrame::default(),
            panels: Panels::default(),
            actions: Actions::default(),
            results: EditResults::default(),
            selection_checked: (0, 0),
            imports: Vec::new(),
            import_scale: 1.0,
            frame_time: None,
            render: None,
            frame_benchmark: None,
            window_title: String::new(),
            close_sent: false,
            quit_confirmed: false,
        }
    }

    /// The status-bar message, if any.
    #[must_use]
    pub fn status(&self) -> Option<&Status> {
        self.status.as_ref()
    }

    /// The action waiting for the unsaved-changes dialog, if any.
    #[must_use]
    pub fn pending(&self) -> Option<&PendingAction> {
        self.pending.as_ref()
    }

    /// A recovered scene offered and not yet accepted or declined.
    #[must_use]
    pub fn recovery_offer(&self) -> Option<&Scene> {
        self.recovery_offer.as_ref()
    }

    /// The CPU-skinned frames of the objects (the cross-section readout and the painter
    /// read them).
    #[must_use]
    pub fn skin_cache(&self) -> &crate::skinning::SkinCache {
        self.scene.skin_cache()
    }

    /// The panels and their state.
    #[must_use]
    pub fn panels(&self) -> &Panels {
        &self.panels
    }

    /// Where the viewport was laid out in the last frame (screen points).
    #[must_use]
    pub fn viewport_rect(&self) -> Option<egui::Rect> {
        self.panels.viewport.rect()
    }

    /// Where the curve editor was laid out in the last frame (screen points).
    #[must_use]
    pub fn curves_rect(&self) -> Option<egui::Rect> {
        self.panels.curves.rect()
    }

    /// Each object's deformed bounds (world space) as last computed: every frame the painter
    /// draws, and whenever framing asked for them.
    #[must_use]
    pub fn object_bounds(&self) -> &[Option<Bounds>] {
        self.scene.object_bounds()
    }

    /// The union of the last computed bounds of `objects` (all when `None`).
    #[must_use]
    pub fn bounds_of(&self, objects: Option<&[usize]>) -> Option<Bounds> {
        self.scene.bounds_of(objects)
    }

    /// The frames the dope sheet shows now.
    #[must_use]
    pub fn dope_sheet_view(&self) -> crate::panels::dope_sheet::TimeView {
        self.panels.dope_sheet.time_view(self.doc.scene())
    }

    /// Channel `id` sampled as the curve editor draws it (its rotation reading included) over
    /// frames `start..=end` at `samples` points.
    #[must_use]
    pub fn sample_curves(&self, id: ChannelId, start: f64, end: f64, samples: usize) -> Vec<Vec<(f64, f32)>> {
        let twist = self.panels.curves.rotation_as_twist;
        crate::panels::curves::sample_curves(
            &self.evaluator(),
            self.doc.scene(),
            id,
            (start, end),
            samples,
            twist,
        )
    }

    /// Model imports still running.
    #[must_use]
    pub fn imports(&self) -> &[files::BackgroundImport] {
        &self.imports
    }

    /// What the viewport could not draw in the last frame.
    #[must_use]
    pub fn viewport_errors(&self) -> &[String] {
        self.panels.viewport.errors()
    }

    /// The GPU viewport, when the editor runs on eframe's wgpu backend.
    #[must_use]
    pub fn gpu(&self) -> Option<&crate::gpu_view::GpuView> {
        self.panels.viewport.gpu()
    }

    /// Plays, measures `frames` frames, prints the figures and closes the window
    /// (`keyrig edit --benchmark-frames N`).
    pub fn benchmark_frames(&mut self, frames: u32) {
        self.frame_benchmark = Some(crate::frame_bench::FrameBenchmark::new(frames));
    }

    /// The document's scene evaluator, in step with the document and its loaded meshes.
    #[must_use]
    pub fn evaluator(&self) -> Arc<SceneEvaluator> {
        self.scene.evaluator(&self.doc, &self.meshes)
    }

    /// The key the evaluator was built for: the GPU view rebuilds its rig when it changes.
    #[must_use]
    pub fn evaluator_key(&self) -> (u64, u64, u64) {
        crate::scene_frame::evaluator_key(&self.doc, &self.meshes)
    }

    /// The value of a channel now (sampled, or its pose override).
    #[must_use]
    pub fn value_now(&self, id: ChannelId) -> Option<ChannelValue> {
        self.evaluator().value(id, self.time(), &self.session.overrides)
    }

    /// Object `o` evaluated now.
    #[must_use]
    pub fn object_pose_now(&self, o: usize) -> Option<ObjectPose> {
        self.evaluator()
            .object_at(o, self.time(), &self.session.overrides)
            .map(|s| ObjectPose::from_state(&s))
    }

    /// Gives the editor keyrig-render on eframe's wgpu device; on a CPU rasterizer the viewport
    /// renders without anti-aliasing (see [`crate::gpu_view::GpuView::new`]).
    pub fn attach_gpu(&mut self, render_state: &egui_wgpu::RenderState) {
        let gpu = crate::gpu_view::GpuView::new(render_state, self.window_depth);
        self.view.antialiasing = gpu.antialiasing();
        self.panels.viewport.attach_gpu(gpu);
    }

    /// Current time in seconds.
    #[must_use]
    pub fn time(&self) -> f64 {
        self.session.time(self.doc.scene().fps)
    }

    /// Shows a message in the status bar.
    pub fn info(&mut self, text: impl Into<String>) {
        self.status = Some(Status { text: text.into(), is_error: false, at: std::time::Instant::now() });
    }

    /// Shows an error in the status bar.
    pub fn error(&mut self, text: impl Into<String>) {
        self.status = Some(Status { text: text.into(), is_error: true, at: std::time::Instant::now() });
    }

    /// Moves the clock to a whole frame; pose overrides are dropped.
    pub fn set_frame(&mut self, frame: i32) {
        self.session.set_frame(frame, self.doc.scene().frame_range);
    }

    /// Replaces the document (new, open, recover).
    pub fn replace_document(&mut self, scene: Scene, path: Option<PathBuf>) {
        // The session of the file being left is remembered for its next opening.
        self.remember_session();
        self.view.camera = scene.camera.sanitized();
        // Record mode and the key clipboard carry over to the new document.
        let session = Session {
            record: self.session.record,
            clipboard: std::mem::take(&mut self.session.clipboard),
            pose_clipboard: std::mem::take(&mut self.session.pose_clipboard),
            ik: self.session.ik.for_new_document(),
            ..Session::at_start(scene.frame_range)
        };
        self.panels.viewport.release_ik_handle();
        self.doc = Document::new(scene, path);
        self.session = session;
    }

    /// The object index the selection belongs to (the joint's object for joints).
    #[must_use]
    pub fn selected_object(&self) -> Option<usize> {
        self.session.selected_object()
    }

    /// The IK chain that ends at `joint` of `object` now (its length as chosen in the inspector),
    /// or why that joint cannot be posed with IK.
    pub fn ik_chain(
        &self,
        object: usize,
        joint: usize,
    ) -> Result<crate::ik_posing::PosedChain, crate::ik_posing::IkPoseError> {
        let scene = self.doc.scene();
        let name = scene.objects.get(object).map(|o| o.name.clone()).unwrap_or_default();
        let pose =
            self.object_pose_now(object).ok_or(crate::ik_posing::IkPoseError::NoPose { object: name })?;
        let bones = self.session.ik.chain_bones(object, joint);
        crate::ik_posing::PosedChain::new(scene, &pose, object, joint, bones)
    }

    /// Turns IK posing on or off and says what to do next (or why the selected joint cannot be
    /// posed with IK).
    pub fn toggle_ik_posing(&mut self) {
        self.session.ik.enabled = !self.session.ik.enabled;
        self.panels.viewport.release_ik_handle();
        if !self.session.ik.enabled {
            self.info("IK posing off");
            return;
        }
        match self.session.selection.item {
            Some(Selected::Joint { object, joint }) => match self.ik_chain(object, joint) {
                Ok(chain) => {
                    let end = chain.names.last().cloned().unwrap_or_default();
                    self.info(format!(
                        "IK posing: drag the handle at {end}; chain {} ({})",
                        chain.describe(),
                        chain.solver_label()
                    ));
                }
                Err(e) => self.error(e.to_string()),
            },
            _ => self.info(
                "IK posing on: select the end joint of a chain (a hand) and drag the handle drawn at it",
            ),
        }
    }

    /// The rotation ring being dragged, if any (tests read which ring and mapping).
    #[must_use]
    pub fn ring_drag(&self) -> Option<&crate::twist::RingDrag> {
        self.panels.viewport.ring_drag()
    }

    /// Keys the current values of the active keying set's channels of the selection at the
    /// current frame ([`crate::keying_sets`]); in IK posing, with a joint selected, also the
    /// joints of its chain (what an IK drag poses).
    pub fn insert_key(&mut self) {
        let set = self.session.keying_set;
        let mut ids = set.channels(self.doc.scene(), self.session.selection.items());
        if let (true, Some(Selected::Joint { object, joint })) =
            (self.session.ik.enabled, self.session.selection.item)
        {
            for id in self.ik_chain(object, joint).map(|c| c.turned_channels()).unwrap_or_default() {
                if !ids.contains(&id) {
                    ids.push(id);
                }
            }
        }
        if ids.is_empty() {
            self.error("Insert key: select an object, joint or light first");
            return;
        }
        let time = self.session.key_time(self.doc.scene().fps);
        let values: Vec<(ChannelId, ChannelValue)> =
            ids.iter().filter_map(|&id| self.value_now(id).map(|v| (id, v))).collect();
        let frame = self.session.playback.whole_frame();
        self.doc.edit(&format!("insert key at frame {frame}"), |scene| {
            for (id, v) in &values {
                channels::set_key(scene, *id, time, *v);
            }
        });
        for id in ids {
            self.session.overrides.remove(&id);
        }
        self.session.selection.retain_valid(self.doc.scene());
        match set {
            crate::keying_sets::KeyingSet::Selected => {
                self.info(format!("Keyed {} channel(s) at frame {frame}", values.len()));
            }
            set => self.info(format!("Keyed {} channel(s) at frame {frame} ({})", values.len(), set.label())),
        }
    }

    /// Deletes the selected object or light (undoable); a joint is not deleted on its own.
    pub fn delete_selected_item(&mut self) {
        let Some(item) = self.session.selection.item else {
            self.info("Delete: nothing selected");
            return;
        };
        let name = item_name(self.doc.scene(), item).unwrap_or_default();
        match item {
            Selected::Object(o) => {
                self.doc.edit(&format!("delete object {name}"), |scene| {
                    let gone = scene.objects.remove(o);
                    keyrig_edit::camera_edits::forget_aim_targets(scene, &gone.name);
                    scene.forget_in_actions(&gone.name);
                });
            }
            Selected::Light(l) => {
                self.doc.edit(&format!("delete light {name}"), |scene| {
                    scene.lights.remove(l);
                });
            }
            Selected::Camera(c) => {
                self.doc.edit(&format!("delete camera {name}"), |scene| {
                    keyrig_edit::camera_edits::remove_camera(scene, c);
                });
            }
            Selected::Joint { .. } => {
                self.error(format!(
                    "Delete: {name} is a joint of a skeleton; select its object to delete the whole model"
                ));
                return;
            }
        }
        self.session.forget_removed(item);
        self.scene.forget_bounds();
        self.info(format!("Deleted {name}"));
    }

    /// Copies the selected object, light or camera (keys, mesh and skeleton included) under a
    /// new unique name (`Arm` → `Arm.001`), adds it to the end of the scene, selects it and
    /// starts moving it with the pointer, as Blender's Shift+D: a click or Enter places it,
    /// Escape or a right-click leaves it on the original. The copy and its move are one undo
    /// step.
    pub fn duplicate_selected_item(&mut self) {
        let group = crate::panels::viewport::GRAB_GROUP;
        // A grab under way (Shift+D pressed again) ends where it is: the new copy is a step of
        // its own.
        self.doc.close_group();
        let scene = self.doc.scene();
        let copy = match self.session.selection.item {
            Some(Selected::Object(o)) => {
                let mut object = scene.objects[o].clone();
                object.name = unique_name(&object.name, scene.objects.iter().map(|x| x.name.as_str()));
                // The copy keeps the original's look: drawn with the renderer's palette (no
                // material, no colour channel), its colour would follow its new place among the
                // objects, so it gets the original's as its colour attribute.
                if let Some(colour) = self.palette_colour_shown(o) {
                    object.attributes.colour = Some(keyrig_core::Animated::constant(colour));
                }
                let name = object.name.clone();
                let index = scene.objects.len();
                self.doc.edit_continuous(group, &format!("duplicate as {name}"), |scene| {
                    scene.objects.push(object)
                });
                Some((Selected::Object(index), name))
            }
            Some(Selected::Light(l)) => {
                let mut light = scene.lights[l].clone();
                light.name = unique_name(&light.name, scene.lights.iter().map(|x| x.name.as_str()));
                let name = light.name.clone();
                let index = scene.lights.len();
                self.doc.edit_continuous(group, &format!("duplicate as {name}"), |scene| {
                    scene.lights.push(light)
                });
                Some((Selected::Light(index), name))
            }
            Some(Selected::Camera(c)) => {
                let mut camera = scene.cameras[c].clone();
                camera.name = unique_name(&camera.name, scene.cameras.iter().map(|x| x.name.as_str()));
                let name = camera.name.clone();
                let index = scene.cameras.len();
                self.doc.edit_continuous(group, &format!("duplicate as {name}"), |scene| {
                    scene.cameras.push(camera)
                });
                Some((Selected::Camera(index), name))
            }
            Some(Selected::Joint { .. }) => {
                self.error("Duplicate: joints are duplicated with their model; select the object");
                None
            }
            None => {
                self.info("Duplicate: select an object or light first");
                None
            }
        };
        if let Some((item, name)) = copy {
            self.session.selection.select_only(Some(item));
            self.session.selection.keys.clear();
            self.panels.viewport.start_grab();
            self.info(format!(
                "Duplicated as {name}: it follows the pointer; click or Enter places it, Escape or right-click leaves it on the original"
            ));
        }
    }

    /// The palette colour object `o` is drawn with
    /// ([`keyrig_render::scene_frame::object_palette_colour`]), when that is the colour it
    /// shows: it has a drawn mesh, no colour channel and no material of its own. `None`
    /// otherwise (its colour goes with it when it is copied).
    fn palette_colour_shown(&self, o: usize) -> Option<glam::Vec3> {
        let object = self.doc.scene().objects.get(o)?;
        if object.attributes.colour.is_some() {
            return None;
        }
        if let Some(keyrig_core::MeshSource::File { path, mesh, .. }) = &object.mesh {
            let base_dir = self.doc.path().and_then(std::path::Path::parent);
            if self.meshes.material(base_dir, path, *mesh).is_some() {
                return None;
            }
        }
        let eval = self.evaluator();
        (eval.skin(o).is_some() || eval.morph(o).is_some())
            .then(|| keyrig_render::scene_frame::object_palette_colour(&eval, o))
    }

    /// Opens the outliner's name field on the selected item.
    pub fn start_rename(&mut self) {
        match self.session.selection.item {
            Some(item) => {
                let name = item_name(self.doc.scene(), item).unwrap_or_default();
                self.panels.outliner.start_rename(item, name);
            }
            None => self.info("Rename: select an object, joint or light first"),
        }
    }

    /// Renames an object, joint or light (one undo step). Names are not empty and unique
    /// among objects, among lights, and among the joints of one skeleton (channel paths
    /// address them by name); a refused name leaves the item as it was and says why.
    pub fn rename_item(&mut self, item: Selected, name: &str) -> bool {
        let name = name.trim();
        let scene = self.doc.scene();
        let Some(old) = item_name(scene, item) else { return false };
        if name == old {
            return false;
        }
        let taken = match item {
            Selected::Object(o) => scene.objects.iter().enumerate().any(|(i, x)| i != o && x.name == name),
            Selected::Light(l) => scene.lights.iter().enumerate().any(|(i, x)| i != l && x.name == name),
            Selected::Camera(c) => scene.cameras.iter().enumerate().any(|(i, x)| i != c && x.name == name),
            Selected::Joint { object, joint } => scene.objects[object]
                .skeleton
                .as_ref()
                .is_some_and(|s| s.joints.iter().enumerate().any(|(i, j)| i != joint && j.name == name)),
        };
        if name.is_empty() {
            self.error(format!("Rename {old}: a name cannot be empty"));
            return false;
        }
        if name.chars().count() > MAX_NAME_CHARS {
            self.error(format!("Rename {old}: a name has at most {MAX_NAME_CHARS} characters"));
            return false;
        }
        if taken {
            self.error(format!("Rename {old}: the name {name} is taken"));
            return false;
        }
        let new = name.to_owned();
        self.doc.edit(&format!("rename {old} to {name}"), |scene| match item {
            Selected::Object(o) => {
                let old = std::mem::replace(&mut scene.objects[o].name, new.clone());
                keyrig_edit::camera_edits::rename_aim_targets(scene, &old, None, &new);
                scene.rename_in_actions(&old, None, &new);
            }
            Selected::Light(l) => scene.lights[l].name = new,
            Selected::Camera(c) => keyrig_edit::camera_edits::rename_camera(scene, c, new),
            Selected::Joint { object, joint } => {
                let old = scene.objects[object]
                    .skeleton
                    .as_mut()
                    .map(|s| std::mem::replace(&mut s.joints[joint].name, new.clone()));
                if let Some(old) = old {
                    let owner = scene.objects[object].name.clone();
                    keyrig_edit::camera_edits::rename_aim_targets(scene, &owner, Some(&old), &new);
                    scene.rename_in_actions(&owner, Some(&old), &new);
                }
            }
        });
        if let Selected::Object(_) = item {
            self.session.hidden.rename(&old, name);
        }
        self.info(format!("Renamed {old} to {name}"));
        true
    }

    /// Goes to the nearest key after (or before) the current frame among the channels of the
    /// selection (every channel when nothing is selected), as Blender's Up and Down arrows do.
    pub fn jump_to_key(&mut self, forward: bool) {
        let scene = self.doc.scene();
        let selected = self.session.selection.key_channels(scene);
        let ids = if selected.is_empty() { ChannelId::all(scene) } else { selected };
        let fps = scene.fps.max(1e-9);
        let now = self.session.playback.whole_frame();
        let frames =
            ids.iter().flat_map(|&id| channels::key_times(scene, id)).map(|t| (t * fps).round() as i32);
        let target =
            if forward { frames.filter(|&f| f > now).min() } else { frames.filter(|&f| f < now).max() };
        match target {
            Some(frame) => {
                self.set_frame(frame);
                let range = self.doc.scene().frame_range;
                if !(range.start..=range.end).contains(&frame) {
                    self.info(format!("The key at frame {frame} is outside the frame range"));
                }
            }
            None => self.info(format!("No key {} frame {now}", if forward { "after" } else { "before" })),
        }
    }

    /// Copies the values of the selected joints and objects (a character: every joint) at the
    /// current frame.
    pub fn copy_pose(&mut self) {
        let pose = self.pose_channels();
        if pose.is_empty() {
            self.info("Copy pose: select joints or a character first");
            return;
        }
        self.info(format!("Copied the pose of {} channel(s)", pose.len()));
        self.session.pose_clipboard = pose;
    }

    /// The values now of the channels a pose holds: those of the selection (a character's whole
    /// skeleton when its object is selected), lights left out.
    #[must_use]
    pub fn pose_channels(&self) -> Vec<(ChannelId, ChannelValue)> {
        let ids = self.session.selection.key_channels(self.doc.scene());
        ids.into_iter()
            .filter(|id| {
                !matches!(
                    id,
                    ChannelId::LightPosition(_)
                        | ChannelId::LightDirection(_)
                        | ChannelId::LightColour(_)
                        | ChannelId::LightIntensity(_)
                )
            })
            // Euler keys are copied as the rotation they give, so a pose pastes (and mirrors)
            // onto quaternion and Euler keys alike.
            .map(|id| match id {
                ChannelId::ObjectEuler(_) | ChannelId::JointEuler { .. } => {
                    keyrig_core::channel_id::euler_partner(id).unwrap_or(id)
                }
                _ => id,
            })
            .filter_map(|id| self.value_now(id).map(|v| (id, v)))
            .collect()
    }

    /// Applies the copied pose at the current frame: in record mode as keys, otherwise as
    /// the pose shown (overrides on animated channels, values of static ones); one undo step.
    /// Mirrored, the pose is reflected across each character's symmetry plane onto the joints
    /// of the other side, whatever their local axes ([`keyrig_edit::mirror::mirror_clipboard`]), as
    /// Blender's Paste Flipped; the status bar says which joints paired.
    pub fn paste_pose(&mut self, mirrored: bool) {
        if self.session.pose_clipboard.is_empty() {
            self.info("Paste pose: copy a pose first (Alt+C)");
            return;
        }
        let pose = self.session.pose_clipboard.clone();
        let what = if mirrored { "paste pose mirrored" } else { "paste pose" };
        match self.apply_pose_values(&pose, mirrored, what, None) {
            (count, Some(report)) => {
                self.info(format!("Pasted the pose on {count} channel(s), mirrored. {report}"));
            }
            (count, None) => self.info(format!("Pasted the pose on {count} channel(s)")),
        }
    }

    /// Applies `pose` (channel values) at the current frame, as Paste pose does: in record mode
    /// as keys, otherwise as the pose shown (overrides on animated channels, values of static
    /// ones); one undo step labelled `what`. Mirrored, the pose is reflected across each
    /// character's symmetry plane first ([`keyrig_edit::mirror::mirror_clipboard`]). With `only`, the
    /// channels outside it are left alone (a pose applied to a selection). Returns how many
    /// channels it set and, mirrored, the report of which joints paired.
    pub fn apply_pose_values(
        &mut self,
        pose: &[(ChannelId, ChannelValue)],
        mirrored: bool,
        what: &str,
        only: Option<&[ChannelId]>,
    ) -> (usize, Option<String>) {
        let scene = self.doc.scene();
        let (pose, report) = if mirrored {
            let paste = keyrig_edit::mirror::mirror_clipboard(scene, pose, |o| {
                self.object_pose_now(o).map(|p| p.pose)
            });
            (paste.values, Some(paste.report))
        } else {
            (pose.to_vec(), None)
        };
        let pose: Vec<(ChannelId, ChannelValue)> = pose
            .into_iter()
            .filter(|(id, _)| {
                only.is_none_or(|only| {
                    only.contains(id)
                        || keyrig_core::channel_id::euler_partner(*id).is_some_and(|e| only.contains(&e))
                })
            })
            // A rotation of an object or joint with Euler keys goes to those keys.
            .map(|(id, value)| self.keys_channel(id, value, None))
            .filter(|&(id, _)| channels::channel(scene, id).is_some())
            .collect();
        let time = self.session.key_time(scene.fps);
        let frame = self.session.playback.whole_frame();
        let count = pose.len();
        if self.session.record {
            self.doc.edit(&format!("{what} at frame {frame}"), |scene| {
                for &(id, value) in &pose {
                    channels::set_key(scene, id, time, value);
                }
            });
            for (id, _) in &pose {
                self.session.overrides.remove(id);
            }
        } else {
            let (animated, fixed): (Vec<_>, Vec<_>) =
                pose.into_iter().partition(|(id, _)| channels::key_count(self.doc.scene(), *id) > 0);
            self.doc.edit(what, |scene| {
                for &(id, value) in &fixed {
                    channels::set_static_value(scene, id, value);
                }
            });
            for (id, value) in animated {
                self.session.overrides.insert(id, value);
            }
        }
        (count, report)
    }

    /// Deletes the selected keys.
    pub fn delete_selected_keys(&mut self) {
        if self.session.selection.keys.is_empty() {
            self.info("Delete: no keys selected");
            return;
        }
        let keys: Vec<KeyRef> = self.session.selection.keys.iter().copied().collect();
        let n = keys.len();
        self.doc.edit(&format!("delete {n} key(s)"), |scene| {
            let mut by_channel: std::collections::BTreeMap<ChannelId, Vec<usize>> = Default::default();
            for k in &keys {
                by_channel.entry(k.channel).or_default().push(k.index);
            }
            for (id, indices) in by_channel {
                channels::delete_keys(scene, id, &indices);
            }
        });
        self.session.selection.keys.clear();
        self.info(format!("Deleted {n} key(s)"));
    }

    /// Copies the selected keys to the editor's clipboard.
    pub fn copy_selected_keys(&mut self) {
        self.session.clipboard = self
            .session
            .selection
            .keys
            .iter()
            .filter_map(|k| channels::copy_key(self.doc.scene(), k.channel, k.index))
            .collect();
        self.info(format!("Copied {} key(s)", self.session.clipboard.len()));
    }

    /// Pastes the clipboard at the current frame, keeping the keys' relative timing.
    pub fn paste_keys(&mut self) {
        if self.session.clipboard.is_empty() {
            self.info("Paste: the clipboard is empty");
            return;
        }
        let fps = self.doc.scene().fps.max(1e-9);
        let now = f64::from(self.session.playback.whole_frame()) / fps;
        let earliest = self.session.clipboard.iter().map(|k| k.time).fold(f64::INFINITY, f64::min);
        let copies = self.session.clipboard.clone();
        let mut pasted = Vec::new();
        self.doc.edit(&format!("paste {} key(s)", copies.len()), |scene| {
            for c in &copies {
                if let Some(index) = channels::paste_key(scene, c, now + (c.time - earliest)) {
                    pasted.push(KeyRef { channel: c.channel, index });
                }
            }
        });
        self.session.selection.keys = pasted.into_iter().collect();
        self.session.selection.retain_valid(self.doc.scene());
    }

    /// Sets the deformer of the selected object (or of every skinned object when none is
    /// selected).
    pub fn set_deformer(&mut self, kind: DeformerKind) {
        let targets = self.deformer_targets();
        if targets.is_empty() {
            self.info("No skinned object to deform: deformers apply to objects with a skeleton");
            return;
        }
        self.doc.edit(&format!("deformer {}", kind.label()), |scene| {
            for o in targets {
                if let Some(object) = scene.objects.get_mut(o) {
                    object.deformer.kind = kind;
                }
            }
        });
        self.info(format!("Deformer: {}", kind.label()));
    }

    /// The objects the deformer commands act on: the selected object when it is skinned (has a
    /// skeleton), otherwise every skinned object; empty when the scene has none (an MD2 or a
    /// static model on its own).
    #[must_use]
    pub fn deformer_targets(&self) -> Vec<usize> {
        crate::commands::deformer_targets(self.doc.scene(), self.selected_object())
    }

    /// The deformer the menu and toolbar show as chosen ([`crate::commands::current_deformer`]:
    /// the one in effect at this frame); `None` without a skinned object.
    #[must_use]
    pub fn current_deformer(&self) -> Option<DeformerKind> {
        crate::commands::current_deformer(self.doc.scene(), self.scene.state(), self.selected_object())
    }

    /// Brings the deformed bounds of every object in step with the document and the clock,
    /// skinning on the CPU what the frame did not (framing asks for them).
    fn bounds_now(&mut self) {
        let time = self.time();
        self.scene.ensure_bounds(&self.doc, &mut self.meshes, time, &self.session.overrides);
    }

    /// Frames the selection as Blender's View Selected does (keeping the view's angles): an
    /// object's deformed bounds fill the view; a joint is centred with its bone (the segment
    /// to its parent and children) in view; a light is centred at the current distance;
    /// with nothing selected the whole scene is framed.
    pub fn frame_selection(&mut self) {
        self.bounds_now();
        let aspect = self.panels.viewport.aspect();
        match self.session.selection.item {
            Some(Selected::Joint { object, joint }) => {
                let Some(pose) = self.object_pose_now(object) else { return };
                let Some(skeleton) = self.doc.scene().objects.get(object).and_then(|o| o.skeleton.as_ref())
                else {
                    return;
                };
                let world = |j: usize| -> glam::Vec3 {
                    (pose.world_from_object * pose.object_from_joint[j]).translation.into()
                };
                if joint >= pose.object_from_joint.len() {
                    return;
                }
                let at = world(joint);
                let neighbours = skeleton
                    .joints
                    .iter()
                    .enumerate()
                    .filter(|(c, j)| j.parent == Some(joint) && *c < pose.object_from_joint.len())
                    .map(|(c, _)| world(c))
                    .chain(skeleton.joints[joint].parent.filter(|&p| p < joint).map(world));
                let reach = neighbours.map(|p| p.distance(at)).fold(0.0f32, f32::max);
                let object_radius = self.scene.bounds_of(Some(&[object])).map_or(0.5, |b| b.radius());
                let radius = if reach > 0.0 { reach } else { object_radius * 0.2 };
                self.view.camera.target = at;
                self.view.camera.distance = self.view.camera.distance_to_fit(radius, aspect);
            }
            Some(Selected::Object(o)) => match self.scene.bounds_of(Some(&[o])) {
                Some(bounds) => self.view.camera.frame(bounds, aspect),
                None => {
                    if let Some(pose) = self.object_pose_now(o) {
                        self.view.camera.target = pose.world_from_object.translation.into();
                    }
                }
            },
            Some(Selected::Light(l)) => {
                if let Some(ChannelValue::Vec3(p)) = self.value_now(ChannelId::LightPosition(l)) {
                    self.view.camera.target = p;
                }
            }
            Some(Selected::Camera(c)) => {
                if let Some(ChannelValue::Vec3(p)) = self.value_now(ChannelId::CameraTranslation(c)) {
                    self.view.camera.target = p;
                }
            }
            None => match self.scene.bounds_of(None) {
                Some(bounds) => self.view.camera.frame(bounds, aspect),
                None => self.info("Nothing to frame: the scene is empty"),
            },
        }
    }

    /// Frames `objects` (their deformed bounds from the last frame), as after an import.
    pub fn frame_objects(&mut self, objects: &[usize]) {
        self.bounds_now();
        if let Some(bounds) = self.scene.bounds_of(Some(objects)) {
            let aspect = self.panels.viewport.aspect();
            self.view.camera.frame(bounds, aspect);
        }
    }

    /// Points the camera at a preset.
    pub fn camera_preset(&mut self, command: Command) {
        let c = &mut self.view.camera;
        match command {
            Command::CameraFront => (c.yaw_deg, c.pitch_deg) = (0.0, 0.0),
            Command::CameraSide => (c.yaw_deg, c.pitch_deg) = (90.0, 0.0),
            Command::CameraTop => (c.yaw_deg, c.pitch_deg) = (0.0, 89.9),
            Command::CameraShoulder | Command::CameraElbow => {
                let joint = if command == Command::CameraShoulder { 0 } else { 1 };
                let object = self
                    .selected_object()
                    .or_else(|| self.doc.scene().objects.iter().position(|o| o.skeleton.is_some()));
                let Some(o) = object else {
                    self.error("No skeleton in the scene to look at");
                    return;
                };
                let Some(pose) = self.object_pose_now(o) else { return };
                let Some(f) = pose.object_from_joint.get(joint) else {
                    self.error("The skeleton has too few joints for this view");
                    return;
                };
                let world = pose.world_from_object * *f;
                let target: glam::Vec3 = world.translation.into();
                self.bounds_now();
                let aspect = self.panels.viewport.aspect();
                let bounds = self.scene.bounds_of(Some(&[o]));
                let c = &mut self.view.camera;
                c.target = target;
                // Look along the bone (+X of the joint frame) from the child side, slightly above.
                c.yaw_deg = 90.0;
                c.pitch_deg = 10.0;
                // From outside the mesh: past where the view ray leaves the object's bounds,
                // and far enough to see a fifth of the object around the joint.
                let radius = bounds.map_or(0.2, |b| b.radius() * 0.2);
                let outside = bounds.map_or(0.0, |b| b.exit_distance(target, (c.eye() - target).normalize()));
                c.distance = (outside * 1.15 + radius * 0.5).max(c.distance_to_fit(radius, aspect));
            }
            _ => {}
        }
    }

    /// Runs a command.
    pub fn run_command(&mut self, ctx: &Context, command: Command) {
        // Playback, Home and End keep to the preview range while one is set.
        let range = self.doc.scene().playback_range();
        match command {
            Command::New => self.request(PendingAction::New),
            Command::Open => self.request(PendingAction::Open(None)),
            Command::Save => self.save(),
            Command::SaveAs => self.open_dialog(DialogPurpose::SaveAs),
            Command::Import => self.open_dialog(DialogPurpose::Import),
            Command::ImportSound => self.open_dialog(DialogPurpose::ImportSound),
            Command::ExportGltf => self.open_dialog(DialogPurpose::Export),
            Command::RenderAnimation => self.view.show_render = true,
            Command::Quit => self.request(PendingAction::Quit),
            Command::Undo => {
                if let Some(label) = self.doc.undo_label().map(str::to_owned) {
                    self.doc.undo();
                    self.info(format!("Undo {label}"));
                }
                self.session.selection.retain_valid(self.doc.scene());
            }
            Command::Redo => {
                if let Some(label) = self.doc.redo_label().map(str::to_owned) {
                    self.doc.redo();
                    self.info(format!("Redo {label}"));
                }
                self.session.selection.retain_valid(self.doc.scene());
            }
            Command::ToggleRecord => self.session.record = !self.session.record,
            Command::InsertKey => self.insert_key(),
            Command::ToggleIk => self.toggle_ik_posing(),
            Command::Delete => {
                if self.session.selection.keys.is_empty() && self.session.selection.item.is_some() {
                    self.delete_selected_item();
                } else {
                    self.delete_selected_keys();
                }
            }
            Command::DuplicateItem => self.duplicate_selected_item(),
            Command::RenameItem => self.start_rename(),
            Command::CopyKeys => {
                self.copy_selected_keys();
                if !self.session.clipboard.is_empty() {
                    ctx.copy_text(self.clipboard_text());
                }
            }
            Command::PasteKeys => self.paste_keys(),
            Command::PlayPause => {
                self.session.playback.toggle_play(range.start, range.end);
                self.session.overrides.clear();
            }
            Command::ToggleLoop => self.session.playback.looping = !self.session.playback.looping,
            Command::NextFrame => self.set_frame(self.session.playback.whole_frame() + 1),
            Command::PrevFrame => self.set_frame(self.session.playback.whole_frame() - 1),
            Command::FirstFrame => self.set_frame(range.start),
            Command::LastFrame => self.set_frame(range.end),
            Command::PrevKey => self.jump_to_key(false),
            Command::NextKey => self.jump_to_key(true),
            Command::CopyPose => self.copy_pose(),
            Command::PastePose => self.paste_pose(false),
            Command::PastePoseMirrored => self.paste_pose(true),
            Command::ToggleGrid => self.view.grid = !self.view.grid,
            Command::ToggleBones => self.view.bones = !self.view.bones,
            Command::ToggleOnionSkin => self.view.onion.enabled = !self.view.onion.enabled,
            Command::SetDeformer(kind) => self.set_deformer(kind),
            Command::CameraFront
            | Command::CameraSide
            | Command::CameraTop
            | Command::CameraShoulder
            | Command::CameraElbow => self.camera_preset(command),
            Command::FrameSelection => {
                // Over the curve editor F frames its selected keys, as in Blender's graph editor
                // (the curve view does it when it is next laid out).
                let over_curves =
                    ctx.input(|i| i.pointer.hover_pos()).is_some_and(|p| self.panels.curves.contains(p));
                if over_curves {
                    self.panels.curves.request_frame_keys();
                } else {
                    self.frame_selection();
                }
            }
            Command::ShowHelp => self.view.show_help = !self.view.show_help,
            Command::UndoHistory => self.view.show_undo_history = !self.view.show_undo_history,
            Command::GizmoMove | Command::GizmoTurn | Command::GizmoScale => {
                use crate::panels::viewport::GizmoTool;
                let tool = match command {
                    Command::GizmoMove => GizmoTool::Move,
                    Command::GizmoTurn => GizmoTool::Turn,
                    _ => GizmoTool::Scale,
                };
                let now = self.panels.viewport.toggle_gizmo_tool(tool);
                self.info(format!("Gizmo: {}", now.label().to_lowercase()));
            }
            Command::LookThroughCamera => self.toggle_look_through(),
            Command::CameraToView => self.camera_to_view(),
            Command::AddCamera => self.add_camera(),
            Command::HideSelected => self.hide_selected(),
            Command::ShowHidden => self.show_hidden(),
            Command::TogglePreviewRange => self.toggle_preview_range(),
            Command::ToggleMarker => self.toggle_marker(),
            Command::BindCameraToMarker => self.bind_camera_to_marker(),
            Command::ReduceKeys => {
                self.panels.cleanup.open = Some(crate::panels::cleanup_dialog::CleanupMode::Reduce);
            }
            Command::SmoothKeys => {
                self.panels.cleanup.open = Some(crate::panels::cleanup_dialog::CleanupMode::Smooth);
            }
            Command::Retarget => self.panels.retarget.open = true,
        }
        ctx.request_repaint();
    }

    /// Goes back or forward to the state after `steps` undo steps (the undo history's rows):
    /// undoes or redoes one step at a time, as Ctrl+Z and Ctrl+Shift+Z would, and says where it
    /// got to.
    pub fn undo_to(&mut self, steps: usize) {
        let mut moved = false;
        while self.doc.undo_len() > steps && self.doc.undo() {
            moved = true;
        }
        while self.doc.undo_len() < steps && self.doc.redo() {
            moved = true;
        }
        self.session.selection.retain_valid(self.doc.scene());
        if moved {
            match self.doc.undo_label().map(str::to_owned) {
                Some(label) => self.info(format!("Back to {label}")),
                None => self.info("Back to the start of the history"),
            }
        }
    }

    /// Asks to run an action that would lose unsaved changes; it runs at once when the
    /// document is clean, otherwise a confirmation dialog appears.
    pub fn request(&mut self, action: PendingAction) {
        if self.doc.is_dirty() {
            self.pending = Some(action);
        } else {
            self.perform(action);
        }
    }

    /// Runs an action without asking.
    pub fn perform(&mut self, action: PendingAction) {
        match action {
            PendingAction::New => {
                self.replace_document(Scene::default(), None);
                self.info("New scene");
            }
            PendingAction::Open(Some(path)) => self.open_path(path),
            PendingAction::Open(None) => self.open_dialog(DialogPurpose::Open),
            PendingAction::Quit => {
                self.autosave.clear();
                self.quit_confirmed = true;
            }
        }
    }

    /// Opens a scene or model file (decided by its extension); models are read in the
    /// background ([`EditorApp::wait_for_background_work`]).
    pub fn open_path(&mut self, path: PathBuf) {
        if !files::is_scene_file(&path) {
            self.start_import(path, files::ImportPurpose::Open);
            return;
        }
        match files::open_any(&path) {
            Ok(scene) => {
                self.replace_document(scene, files::is_scene_file(&path).then(|| path.clone()));
                self.recent.add(&path);
                self.restore_session();
                self.info(format!("Opened {}", path.display()));
            }
            Err(e) => self.error(e.to_string()),
        }
    }

    /// Saves to the document's file, or asks for one.
    pub fn save(&mut self) {
        match self.doc.path().map(PathBuf::from) {
            Some(path) => self.save_to(path),
            None => self.open_dialog(DialogPurpose::SaveAs),
        }
    }

    /// Saves to `path`.
    pub fn save_to(&mut self, path: PathBuf) {
        let scene = self.doc.scene();
        match keyrig_io::project::save_scene(&path, scene) {
            Ok(()) => {
                self.doc.mark_saved(path.clone());
                self.autosave.clear();
                self.recent.add(&path);
                self.remember_session();
                self.info(format!("Saved {}", path.display()));
            }
            Err(e) => self.error(e.to_string()),
        }
    }

    fn open_dialog(&mut self, purpose: DialogPurpose) {
        self.dialog_purpose = Some(purpose);
        let folder = self.doc.path().and_then(std::path::Path::parent).map(std::path::Path::to_path_buf);
        let stem = self
            .doc
            .path()
            .and_then(std::path::Path::file_stem)
            .map_or_else(|| "Untitled".to_owned(), |s| s.to_string_lossy().into_owned());
        let storage = std::mem::take(self.file_dialog.storage_mut());
        self.file_dialog = files::file_dialog(purpose, &stem, folder, storage);
        match purpose {
            DialogPurpose::Open
            | DialogPurpose::Import
            | DialogPurpose::ImportSound
            | DialogPurpose::ReferenceImage => {
                self.file_dialog.pick_file();
            }
            DialogPurpose::SaveAs | DialogPurpose::Export => self.file_dialog.save_file(),
        }
    }

    /// Which file dialog is open, if any (tests).
    #[must_use]
    pub fn dialog_purpose(&self) -> Option<DialogPurpose> {
        self.dialog_purpose
    }

    pub(crate) fn dialog_ui(&mut self, ctx: &Context) {
        let Some(purpose) = self.dialog_purpose else { return };
        self.file_dialog.update(ctx);
        if let Some(path) = self.file_dialog.take_picked() {
            self.dialog_purpose = None;
            self.actions.push(Action::FilePicked(purpose, path));
        } else if matches!(
            self.file_dialog.state(),
            egui_file_dialog::DialogState::Cancelled | egui_file_dialog::DialogState::Closed
        ) {
            self.dialog_purpose = None;
        }
    }

    /// Imports a model into the current scene as new objects, read in the background and
    /// applied as one undoable edit ([`EditorApp::wait_for_background_work`]).
    pub fn import_path(&mut self, path: PathBuf) {
        if files::is_sound_file(&path) {
            self.add_sound(&path);
            return;
        }
        self.start_import(path, files::ImportPurpose::Import);
    }

    /// Adds the sound file at `path` as a clip starting at the current frame, one undo step
    /// (File ▸ Import sound, Ctrl+I, or a sound file dropped on the window); the dope sheet's
    /// sound rows show it as soon as it is decoded.
    pub fn add_sound(&mut self, path: &std::path::Path) {
        let path = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
        let start = f64::from(self.session.playback.whole_frame());
        let clip = keyrig_core::SoundClip::new(path.to_string_lossy(), start);
        let edit = keyrig_edit::SceneEdit::AddSound(clip);
        let label = edit.label(self.doc.scene());
        self.doc.edit(&label, |scene| edit.apply(scene));
        self.info(label);
    }

    /// Exports the scene as glTF.
    pub fn export_to(&mut self, path: PathBuf) {
        let base_dir = self.doc.path().and_then(std::path::Path::parent).map(std::path::Path::to_path_buf);
        match files::export_gltf(&path, self.doc.scene(), base_dir.as_deref()) {
            Ok(()) => self.info(format!("Exported {}", path.display())),
            Err(e) => self.error(e.to_string()),
        }
    }

    pub(crate) fn handle_dropped_files(&mut self, ctx: &Context) {
        let dropped: Vec<PathBuf> =
            ctx.input(|i| i.raw.dropped_files.iter().filter_map(|f| f.path.clone()).collect());
        for path in dropped {
            self.actions.push(Action::Dropped(path));
        }
    }

    /// Hands the document to the autosave timer (a copy only when it changed); the timer's
    /// thread writes it when due, drawing or not.
    pub(crate) fn note_autosave(&mut self) {
        let doc = &self.doc;
        self.autosave.note(doc.cache_key(), doc.is_dirty(), || {
            (doc.scene().clone(), doc.path().map(std::path::Path::to_path_buf))
        });
        if let Some(e) = self.autosave.take_error() {
            self.error(format!("Autosave failed: {e}"));
        }
    }

    /// Copies the selected keys and deletes them (Ctrl+X).
    pub(crate) fn cut_keys(&mut self, ctx: &Context) {
        self.run_command(ctx, Command::CopyKeys);
        if !self.session.clipboard.is_empty() {
            self.delete_selected_keys();
        }
    }

    /// Pastes keys from system clipboard text (written by this or another keyrig window);
    /// other text pastes the editor's own clipboard.
    pub fn paste_text(&mut self, text: &str) {
        if let Some(keys) = channels::keys_from_clipboard_text(text) {
            self.session.clipboard = keys;
        }
        self.paste_keys();
    }

    /// The copied keys as system clipboard text.
    #[must_use]
    pub fn clipboard_text(&self) -> String {
        channels::keys_to_clipboard_text(&self.session.clipboard)
    }

    /// Whether the user confirmed quitting (tests check it instead of a closed window).
    #[must_use]
    pub fn quit_confirmed(&self) -> bool {
        self.quit_confirmed
    }

    /// The rotation of a joint shown now (sampled, or its override).
    #[must_use]
    pub fn joint_rotation(&self, object: usize, joint: usize) -> Option<Quat> {
        match self.value_now(ChannelId::JointRotation { object, joint })? {
            ChannelValue::Rotation(q) => Some(q),
            _ => None,
        }
    }
}

impl EditorApp {
    /// Starts reading a model in the background for `purpose`: an import into the scene is
    /// scaled by the import scale ([`EditorApp::set_import_scale`]), a model opened on its
    /// own keeps the file's unit.
    pub fn start_import(&mut self, path: PathBuf, purpose: ImportPurpose) {
        let scale = match purpose {
            ImportPurpose::Import => self.import_scale,
            ImportPurpose::Open => 1.0,
        };
        self.imports.push(BackgroundImport::start(path, purpose, scale));
    }

    /// The factor models imported into the scene are scaled by (File ▸ Import scale).
    #[must_use]
    pub fn import_scale(&self) -> f32 {
        self.import_scale
    }

    /// Sets the import scale from what the user typed or chose (File ▸ Import scale): a
    /// number from 1e-6 to 1e6; anything else (0, negative, NaN, text) is refused with a
    /// message in the status bar and the scale stays as it was. Returns whether it was taken.
    pub fn set_import_scale(&mut self, text: &str) -> bool {
        match files::placement::parse_import_scale(text) {
            Ok(scale) => {
                self.import_scale = scale;
                self.info(format!(
                    "Import scale {}: models imported from now on (Ctrl+I) are scaled by it",
                    files::placement::format_scale(scale)
                ));
                true
            }
            Err(message) => {
                self.error(message);
                false
            }
        }
    }

    /// Queues the imports that have finished (applied with the frame's other actions); while
    /// some still run, asks for a repaint soon (the status bar shows them).
    pub fn poll_background_work(&mut self, ctx: &egui::Context) {
        let (done, running): (Vec<_>, Vec<_>) =
            std::mem::take(&mut self.imports).into_iter().partition(BackgroundImport::is_finished);
        self.imports = running;
        for import in done {
            self.actions.push(Action::ImportFinished(import));
        }
        if !self.imports.is_empty() {
            ctx.request_repaint_after(Duration::from_millis(50));
        }
        if self.render.as_ref().is_some_and(crate::render_job::RenderJob::is_finished) {
            if let Some(job) = self.render.take() {
                let output = job.blast.output.display().to_string();
                match job.finish() {
                    Ok(summary) => self.info(format!(
                        "Rendered {} frames to {output} in {:.1} s",
                        summary.frames,
                        summary.wall_time.as_secs_f64()
                    )),
                    Err(e) => self.error(format!("Render animation: {e}")),
                }
            }
        }
        if self.render.is_some() {
            ctx.request_repaint_after(Duration::from_millis(100));
        }
        self.poll_sounds();
        if self.sounds.is_loading() {
            ctx.request_repaint_after(Duration::from_millis(50));
        }
    }

    /// Starts decoding the sound files of clips that are new, and reports those that failed.
    fn poll_sounds(&mut self) {
        let base_dir = self.doc.path().and_then(std::path::Path::parent).map(std::path::Path::to_path_buf);
        self.sounds.request(self.doc.scene(), base_dir.as_deref());
        for failure in self.sounds.poll() {
            self.error(format!("Sound clip: {failure}"));
        }
    }

    /// Starts File ▸ Render animation on its own thread, from a copy of the scene seen by the
    /// viewport's camera.
    fn start_render(
        &mut self,
        blast: crate::playblast::Playblast,
        through: Option<crate::view::LookThrough>,
    ) {
        if self.render.is_some() {
            self.error("A render is already running".to_owned());
            return;
        }
        let scene = self.doc.scene().clone();
        let file = self.doc.path().map(std::path::Path::to_path_buf);
        // Drawn as keyrig render draws it, with the viewport's grid and bones toggles.
        let view = keyrig_render::ViewOptions {
            grid: self.view.grid,
            skeletons: self.view.bones,
            ..crate::playblast::playblast_view(Some(self.view.camera))
        };
        match crate::render_job::RenderJob::start(scene, file, blast, view, through) {
            Ok(job) => self.render = Some(job),
            Err(e) => self.error(format!("Render animation: {e}")),
        }
    }

    /// Whether File ▸ Render animation is running.
    #[must_use]
    pub fn rendering(&self) -> bool {
        self.render.is_some()
    }

    /// Waits for a running render to finish (tests).
    pub fn wait_for_render(&mut self) {
        while self.render.as_ref().is_some_and(|job| !job.is_finished()) {
            std::thread::sleep(Duration::from_millis(20));
        }
    }

    /// Waits for every running import and applies it (tests, and before quitting).
    pub fn wait_for_background_work(&mut self) {
        for import in std::mem::take(&mut self.imports) {
            self.apply_import(import);
        }
        self.poll_sounds();
        for failure in self.sounds.wait(Duration::from_secs(60)) {
            self.error(format!("Sound clip: {failure}"));
        }
    }

    fn apply_import(&mut self, import: BackgroundImport) {
        let (path, purpose, elapsed, scale) =
            (import.path.clone(), import.purpose, import.elapsed(), import.scale);
        let imported = match import.finish() {
            Ok(imported) => imported,
            Err(e) => {
                self.error(e.to_string());
                return;
            }
        };
        // An added model stands beside what the scene holds (its box at rest against the
        // scene's as drawn now), moved in the import's own undo step.
        let offset = match purpose {
            ImportPurpose::Import => files::placement::model_bounds(&imported.scene, &imported.meshes)
                .map_or(glam::Vec3::ZERO, |model| {
                    self.bounds_now();
                    files::placement::offset_beside(self.scene.bounds_of(None), model)
                }),
            ImportPurpose::Open => glam::Vec3::ZERO,
        };
        // A mesh that failed to load is stored with its error: the viewport reports it over
        // the object, as for a scene file that names a broken model.
        for ((file, mesh), loaded) in imported.meshes {
            self.meshes.insert(file, mesh, loaded);
        }
        let seconds = elapsed.as_secs_f64();
        // What the file holds that keyrig did not take is said, never dropped silently.
        let skipped = match imported.not_imported.as_slice() {
            [] => String::new(),
            lines => format!(
                "; not imported ({} kind{}, `keyrig info` lists them): {}",
                lines.len(),
                if lines.len() == 1 { "" } else { "s" },
                lines.iter().take(3).cloned().collect::<Vec<_>>().join("; ")
            ),
        };
        match purpose {
            ImportPurpose::Open => {
                let n = imported.scene.objects.len();
                self.replace_document(imported.scene, None);
                // Frame what the viewport draws (deformed, in its own units) once it has.
                self.actions.push(Action::FrameObjects((0..n).collect()));
                self.recent.add(&path);
                self.info(format!("Opened {} ({seconds:.2} s){skipped}", path.display()));
            }
            ImportPurpose::Import => {
                let mut scene = imported.scene;
                files::placement::move_by(&mut scene, offset);
                let n = scene.objects.len();
                let first = self.doc.scene().objects.len();
                self.actions.push(Action::FrameObjects((first..first + n).collect()));
                // The model's animation (its keys, or the range its own scene gives it, as an
                // MD2 loop) in seconds; the scene's range grows to cover it, in the same step.
                let model_seconds = keyrig_edit::channels::last_key_time(&scene)
                    .unwrap_or(0.0)
                    .max(f64::from(scene.frame_range.end) / scene.fps.max(1e-9));
                let range = self.doc.scene().frame_range;
                let needed = (model_seconds * self.doc.scene().fps - 1e-6).ceil() as i32;
                let extend = needed > range.end && needed <= 100_000;
                self.doc.edit(&format!("import {}", path.display()), |doc| {
                    // Object names stay unique (channel paths and stored actions name them):
                    // an imported object whose name is taken becomes `name.001`, ….
                    for i in 0..scene.objects.len() {
                        let old = scene.objects[i].name.clone();
                        let taken = |n: &str| {
                            doc.objects.iter().any(|o| o.name == n)
                                || scene.objects.iter().enumerate().any(|(j, o)| j != i && o.name == n)
                        };
                        if taken(&old) {
                            let new = (1..)
                                .map(|k| format!("{old}.{k:03}"))
                                .find(|n| !taken(n))
                                .unwrap_or_else(|| old.clone());
                            scene.rename_in_actions(&old, None, &new);
                            scene.objects[i].name = new;
                        }
                    }
                    // The model's actions come too (docs/actions.md), renamed where the scene
                    // already has one of that name.
                    for mut action in std::mem::take(&mut scene.actions) {
                        let name = doc.unused_action_name(&action.name);
                        if name != action.name {
                            for o in &mut scene.objects {
                                if o.action.as_deref() == Some(action.name.as_str()) {
                                    o.action = Some(name.clone());
                                }
                            }
                            action.name = name;
                        }
                        doc.actions.push(action);
                    }
                    doc.objects.extend(scene.objects);
                    doc.lights.extend(scene.lights);
                    if extend {
                        doc.frame_range.end = needed;
                    }
                });
                self.recent.add(&path);
                let extended = if extend {
                    format!(
                        "; frame range extended from {}–{} to {}–{needed} to cover its animation",
                        range.start, range.end, range.start
                    )
                } else {
                    String::new()
                };
                let placed = if offset == glam::Vec3::ZERO {
                    String::new()
                } else {
                    format!("; placed beside the scene ({:+.2} along X)", offset.x)
                };
                let scaled = if scale == 1.0 {
                    String::new()
                } else {
                    format!(", scaled ×{}", files::placement::format_scale(scale))
                };
                let unit = format!(" ({}{scaled})", imported.unit);
                let message = format!(
                    "Imported {n} object(s) from {}{unit} ({seconds:.2} s){placed}{extended}{skipped}",
                    path.display()
                );
                // A model far larger or smaller than what the scene holds (one modelled in
                // centimetres) is said, with the scale that fits, for as long as an error.
                self.bounds_now();
                let boxes = self.scene.object_bounds();
                let (before, added) = boxes.split_at(first.min(boxes.len()));
                let name = path
                    .file_stem()
                    .map_or_else(|| "The model".to_owned(), |s| s.to_string_lossy().into_owned());
                let warning = files::placement::size_ratio(before, &added[..n.min(added.len())])
                    .and_then(|ratio| files::placement::size_warning(&name, ratio, scale));
                match warning {
                    Some(warning) => self.error(format!("{warning}. {message}")),
                    None => self.info(message),
                }
            }
        }
    }
}

impl EditorApp {
    /// Applies every queued action in the order it was pushed, each once; an action may queue
    /// more (an import frames its objects), which are applied after it. Returns whether any
    /// changed something (the frame then asks for another, which draws the result): an edit
    /// that left the document and the pose overrides as they were (a gizmo held still) did
    /// not. The selection is checked against the document when the document changed.
    pub fn apply_actions(&mut self, ctx: &Context) -> bool {
        let mut changed = false;
        while let Some(action) = self.actions.pop() {
            if let Action::Edit(_) = action {
                let key = self.doc.cache_key();
                let overrides = self.session.overrides.clone();
                self.apply(ctx, action);
                changed |= key != self.doc.cache_key() || overrides != self.session.overrides;
            } else {
                self.apply(ctx, action);
                changed = true;
            }
        }
        let key = self.doc.cache_key();
        if key != self.selection_checked {
            self.session.selection.retain_valid(self.doc.scene());
            self.selection_checked = key;
        }
        changed
    }

    /// Applies one action: the one place where the document, the session and the view change
    /// at the panels' request.
    fn apply(&mut self, ctx: &Context, action: Action) {
        match action {
            Action::Command(command) => self.run_command(ctx, command),
            Action::Copy => self.run_command(ctx, Command::CopyKeys),
            Action::Cut => self.cut_keys(ctx),
            Action::Paste(text) => self.paste_text(&text),
            Action::Edit(edit) => self.apply_edit(edit),
            Action::CloseGroup => self.doc.close_group(),
            Action::UndoTo(steps) => self.undo_to(steps),
            Action::Session(change) => self.apply_session(change),
            Action::View(change) => self.apply_view(change),
            Action::Info(text) => self.info(text),
            Action::Error(text) => self.error(text),
            Action::Rename { item, name } => {
                self.rename_item(item, &name);
            }
            Action::BakeIk { object, constraint } => self.bake_ik_constraint(object, constraint),
            Action::SwitchParent { object, constraint, target } => {
                self.switch_parent(object, constraint, target);
            }
            Action::PoseLibrary(action) => self.pose_library(action),
            Action::KeepIk { object, joint } => self.keep_ik_constraint(object, joint),
            Action::FrameObjects(objects) => self.frame_objects(&objects),
            Action::Request(pending) => self.request(pending),
            Action::ResolveUnsaved(choice) => {
                let Some(action) = self.pending.take() else { return };
                match choice {
                    Unsaved::Save => {
                        self.save();
                        if !self.doc.is_dirty() {
                            self.perform(action);
                        }
                    }
                    Unsaved::Discard => self.perform(action),
                    Unsaved::Cancel => {}
                }
            }
            Action::Recover(true) => {
                if let Some(scene) = self.recovery_offer.take() {
                    let origin = self.recovery.origin();
                    self.replace_document(scene, origin);
                    self.doc.mark_dirty();
                    self.info("Recovered the autosaved scene; save it to keep it");
                }
            }
            Action::Recover(false) => {
                self.recovery_offer = None;
                self.autosave.clear();
            }
            Action::FilePicked(purpose, path) => match purpose {
                DialogPurpose::Open => self.open_path(path),
                DialogPurpose::SaveAs => self.save_to(files::with_extension_if_missing(path, "ron")),
                DialogPurpose::Import => self.import_path(path),
                DialogPurpose::ImportSound => self.add_sound(&path),
                DialogPurpose::Export => self.export_to(files::with_extension_if_missing(path, "glb")),
                DialogPurpose::ReferenceImage => self.set_reference_image(&path),
            },
            Action::ChooseReferenceImage => self.open_dialog(DialogPurpose::ReferenceImage),
            Action::ImportScale(text) => {
                self.set_import_scale(&text);
            }
            Action::Dropped(path) => {
                if files::is_image_file(&path) {
                    self.set_reference_image(&path);
                } else if files::is_scene_file(&path) {
                    self.request(PendingAction::Open(Some(path)));
                } else {
                    self.import_path(path);
                }
            }
            Action::ImportFinished(import) => self.apply_import(import),
            Action::Add(kind) => self.add_item(kind),
            Action::StartRender { blast, through } => self.start_render(blast, through),
            Action::CancelRender => {
                if let Some(job) = &self.render {
                    job.cancel();
                }
            }
        }
    }

    fn apply_session(&mut self, change: SessionChange) {
        let selection = &mut self.session.selection;
        match change {
            SessionChange::SelectOnly(item) => selection.select_only(item),
            SessionChange::Toggle(item) => selection.toggle(item),
            SessionChange::Add(item) => {
                if !selection.contains(item) {
                    selection.toggle(item);
                }
            }
            SessionChange::SetKeys(keys) => selection.keys = keys,
            SessionChange::AddKeys(keys) => selection.keys.extend(keys),
            SessionChange::RemoveKeys(keys) => {
                for k in &keys {
                    selection.keys.remove(k);
                }
            }
            SessionChange::SetFrame(frame) => self.set_frame(frame),
            SessionChange::EveryFrame(on) => self.session.playback.every_frame = on,
            SessionChange::KeyingSet(set) => self.session.keying_set = set,
            SessionChange::ChainBones { object, joint, bones } => {
                self.session.ik.set_chain_bones(object, joint, bones);
            }
            SessionChange::RememberPole { chain, pole } => self.session.ik.remember_pole(&chain, pole),
        }
    }

    fn apply_view(&mut self, change: ViewChange) {
        let view = &mut self.view;
        match change {
            ViewChange::Camera(camera) => view.camera = camera,
            ViewChange::Style(style) => view.style = style,
            ViewChange::Textures(on) => view.textures = on,
            ViewChange::ResolutionScale(scale) => view.resolution_scale = scale,
            ViewChange::Antialiasing(on) => view.antialiasing = on,
            ViewChange::Onion(onion) => view.onion = onion,
            ViewChange::ShowHelp(on) => view.show_help = on,
            ViewChange::ShowUndoHistory(on) => view.show_undo_history = on,
            ViewChange::LookThrough(camera) => view.look_through = camera,
            ViewChange::ShowRender(on) => view.show_render = on,
        }
    }
}

/// The undo group of an IK handle drag: its edits are one undo step.
pub const IK_DRAG_GROUP: &str = "ik drag";

/// Longest name the editor's rename accepts, characters.
pub const MAX_NAME_CHARS: usize = 256;

/// The name of an object, joint or light, if it exists.
#[must_use]
pub fn item_name(scene: &Scene, item: Selected) -> Option<String> {
    Some(match item {
        Selected::Object(o) => scene.objects.get(o)?.name.clone(),
        Selected::Light(l) => scene.lights.get(l)?.name.clone(),
        Selected::Camera(c) => scene.cameras.get(c)?.name.clone(),
        Selected::Joint { object, joint } => {
            scene.objects.get(object)?.skeleton.as_ref()?.joints.get(joint)?.name.clone()
        }
    })
}

/// `name` with the first free numbered suffix among `taken` (`Arm` → `Arm.001`, `Arm.001` →
/// `Arm.002`), as Blender names copies.
#[must_use]
pub fn unique_name<'a>(name: &str, taken: impl Iterator<Item = &'a str>) -> String {
    let taken: std::collections::HashSet<&str> = taken.collect();
    let base = match name.rsplit_once('.') {
        Some((base, n)) if n.len() == 3 && n.bytes().all(|b| b.is_ascii_digit()) => base,
        _ => name,
    };
    (1..)
        .map(|n| format!("{base}.{n:03}"))
        .find(|candidate| !taken.contains(candidate.as_str()))
        .expect("a free name")
}

/// The sound output ([`crate::audio`]), followed once a frame.
impl EditorApp {
    /// The sound after the frame's actions: see [`crate::audio::Audio::follow`].
    pub(crate) fn follow_audio(&mut self, ctx: &egui::Context) {
        let base_dir = self.doc.path().and_then(std::path::Path::parent).map(std::path::Path::to_path_buf);
        let notice = self.audio.follow(
            self.doc.scene(),
            self.doc.cache_key(),
            base_dir.as_deref(),
            &self.sounds,
            &self.session.playback,
        );
        if let Some(notice) = notice {
            self.info(notice);
        }
        if self.audio.is_opening() {
            ctx.request_repaint_after(std::time::Duration::from_millis(50));
        }
    }

    /// Where the sound device stands.
    #[must_use]
    pub fn audio_availability(&self) -> crate::audio::Availability {
        self.audio.availability()
    }
}

#[cfg(test)]
mod status_tests {
    use super::Status;

    #[test]
    fn messages_leave_the_status_bar_after_their_time() {
        let now = std::time::Instant::now();
        let info = Status { text: "Saved".into(), is_error: false, at: now };
        assert!(info.seconds_left() > Status::INFO_SECONDS - 1.0);
        let old = std::time::Duration::from_secs_f32(Status::INFO_SECONDS + 1.0);
        let then = now.checked_sub(old).expect("the monotonic clock started more than nine seconds ago");
        assert_eq!(Status { at: then, ..info.clone() }.seconds_left(), 0.0, "an old message is gone");
        let error = Status { text: "Cannot save".into(), is_error: true, at: then };
        assert!(error.seconds_left() > 0.0, "an error stays longer");
    }
}
