//! What a panel draws from: the frame's read-only context. Panels read the document, the
//! session, the view and the evaluated scene here and change nothing outside their own state;
//! what they want changed they push as [`crate::actions::Action`]s.

use std::path::{Path, PathBuf};
use std::sync::Arc;

use keyrig_core::Scene;
use keyrig_eval::SceneEvaluator;

use crate::actions::{EditResults, PendingAction};
use crate::document::Document;
use crate::eval::ObjectPose;
use crate::files::{BackgroundImport, MeshStore, Recovery};
use crate::ik_posing::{IkPoseError, PosedChain};
use crate::scene_frame::SceneFrame;
use crate::session::{Selected, Session};
use crate::view::ViewState;
use keyrig_edit::channels::{self, ChannelId, ChannelValue};

/// A status-bar message.
#[derive(Clone, Debug, PartialEq)]
pub struct Status {
    pub text: String,
    pub is_error: bool,
    /// When it was shown: the status bar lets a message go after [`Status::INFO_SECONDS`]
    /// (an error after [`Status::ERROR_SECONDS`]), so it never describes an older state.
    pub at: std::time::Instant,
}

impl Status {
    /// How long a message stays in the status bar.
    pub const INFO_SECONDS: f32 = 8.0;
    /// How long an error stays.
    pub const ERROR_SECONDS: f32 = 30.0;

    /// Seconds it has left in the status bar (0 when it is gone).
    #[must_use]
    pub fn seconds_left(&self) -> f32 {
        let lasts = if self.is_error { Self::ERROR_SECONDS } else { Self::INFO_SECONDS };
        (lasts - self.at.elapsed().as_secs_f32()).max(0.0)
    }
}

/// The frame as the panels see it: everything read-only.
pub struct FrameCtx<'a> {
    /// The scene and its undo history.
    pub doc: &'a Document,
    /// Selection, clock, record mode, overrides, clipboard.
    pub session: &'a Session,
    /// Camera and viewport options.
    pub view: &'a ViewState,
    /// The evaluated scene of this frame and what was skinned on the CPU for it.
    pub scene: &'a SceneFrame,
    /// Meshes of model files the scene refers to.
    pub meshes: &'a MeshStore,
    /// Sound files of the scene's clips, decoded or being decoded.
    pub sounds: &'a crate::sounds::SoundStore,
    /// What the last frame's edits reported (whether a key move was taken).
    pub results: &'a EditResults,
    /// The status-bar message, if any.
    pub status: Option<&'a Status>,
    /// Model imports running on background threads.
    pub imports: &'a [BackgroundImport],
    /// Smoothed time between frames while playing, seconds.
    pub frame_time: Option<f32>,
    /// The recent-files list, newest first.
    pub recent: &'a [PathBuf],
    /// The action waiting for the unsaved-changes dialog.
    pub pending: Option<&'a PendingAction>,
    /// The recovery file, while its autosaved scene is offered.
    pub recovery: Option<&'a Recovery>,
    /// Whether opaque backgrounds can be filled by the GPU viewport's paint callback
    /// ([`crate::widgets::flat_fill`]): the window is drawn with wgpu.
    pub gpu_fills: bool,
    /// File ▸ Render animation, while it runs.
    pub render: Option<&'a crate::render_job::RenderJob>,
    /// File ▸ Import scale: the factor imported models are scaled by.
    pub import_scale: f32,
}

impl FrameCtx<'_> {
    /// The deformer the toolbar and the Deformer menu show as chosen: the one in effect at this
    /// frame (a keyed deformer's value, else the object's setting; as the viewport's overlay
    /// names it) of the first object the deformer commands act on; `None` without a skinned
    /// object.
    #[must_use]
    pub fn deformer_in_effect(&self) -> Option<keyrig_core::DeformerKind> {
        crate::commands::current_deformer(self.scene(), self.scene.state(), self.selected_object())
    }

    /// The scene camera the viewport looks through at the current frame, if any (markers cut
    /// between cameras while looking through the active one).
    #[must_use]
    pub fn looking_through(&self) -> Option<usize> {
        self.view.look_through?.camera_at(self.scene(), self.session.playback.frame)
    }

    /// The document's scene.
    #[must_use]
    pub fn scene(&self) -> &Scene {
        self.doc.scene()
    }

    /// The folder relative mesh paths resolve against (the document's).
    #[must_use]
    pub fn base_dir(&self) -> Option<&Path> {
        self.doc.path().and_then(Path::parent)
    }

    /// The current time in seconds.
    #[must_use]
    pub fn time(&self) -> f64 {
        self.session.time(self.doc.scene().fps)
    }

    /// The document's scene evaluator (in step with the document).
    #[must_use]
    pub fn evaluator(&self) -> Arc<SceneEvaluator> {
        self.scene.evaluator(self.doc, self.meshes)
    }

    /// The value of a channel now (sampled, or its pose override).
    #[must_use]
    pub fn value_now(&self, id: ChannelId) -> Option<ChannelValue> {
        self.evaluator().value(id, self.time(), &self.session.overrides)
    }

    /// Object `o`'s pose this frame.
    #[must_use]
    pub fn pose(&self, o: usize) -> Option<&ObjectPose> {
        self.scene.pose(o)
    }

    /// The object the selection belongs to (the joint's object for joints).
    #[must_use]
    pub fn selected_object(&self) -> Option<usize> {
        self.session.selected_object()
    }

    /// Whether `item` is the active selection.
    #[must_use]
    pub fn is_active(&self, item: Selected) -> bool {
        self.session.selection.item == Some(item)
    }

    /// The IK chain that ends at `joint` of `object` this frame (its length as chosen in the
    /// inspector), or why that joint cannot be posed with IK.
    pub fn ik_chain(&self, object: usize, joint: usize) -> Result<PosedChain, IkPoseError> {
        let scene = self.doc.scene();
        let name = scene.objects.get(object).map(|o| o.name.clone()).unwrap_or_default();
        let pose = self.pose(object).ok_or(IkPoseError::NoPose { object: name })?;
        PosedChain::new(scene, pose, object, joint, self.session.ik.chain_bones(object, joint))
    }

    /// The twist of a rotation channel about its bone axis now, degrees, unwrapped through
    /// spin keys ([`crate::eval::twist_now`]).
    #[must_use]
    pub fn twist_now(&self, id: ChannelId) -> Option<f64> {
        let Some(ChannelValue::Rotation(q)) = self.value_now(id) else { return None };
        Some(crate::eval::twist_now(self.doc.scene(), id, q, self.time()))
    }

    /// Queues moving the clock to `frame` (a scrub, the Frame field), unless it is there already
    /// with no pose override to drop.
    pub fn set_frame(&self, actions: &mut crate::actions::Actions, frame: i32) {
        if self.session.set_frame_changes(frame, self.scene().frame_range) {
            actions.session(crate::actions::SessionChange::SetFrame(frame));
        }
    }

    /// Whether channel `id` has a key at the current whole frame.
    #[must_use]
    pub fn keyed_here(&self, id: ChannelId) -> bool {
        let scene = self.doc.scene();
        channels::key_at(scene, id, f64::from(self.session.playback.whole_frame()) / scene.fps.max(1e-9))
            .is_some()
    }
}
