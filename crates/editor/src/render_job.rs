//! File ▸ Render animation: a playblast ([`crate::playblast`]) of the open scene on a thread of
//! its own, so the editor stays usable while it renders.
//!
//! The thread gets a copy of the scene (edits made meanwhile do not change the render), opens
//! its own headless GPU device, loads the scene's model files as `keyrig render` does, and
//! renders through [`Playblast::run`]. The UI thread reads the [`Progress`] it publishes after
//! each frame (for the dialog's bar and time left), can ask it to stop (the movie is then not
//! written), and collects its outcome once it has finished ([`RenderJob::is_finished`]).

use std::ops::ControlFlow;
use std::path::PathBuf;
use std::sync::atomic::{AtomicBool, Ordering};
use std::sync::{Arc, Mutex};
use std::thread::JoinHandle;

use keyrig_core::Scene;
use keyrig_render::{HeadlessRenderer, SceneRig, ViewOptions};

use crate::playblast::{FrameError, Playblast, PlayblastError, Progress, Summary};
use crate::view::LookThrough;

/// A playblast rendering on its own thread.
pub struct RenderJob {
    /// What is being rendered.
    pub blast: Playblast,
    progress: Arc<Mutex<Option<Progress>>>,
    cancel: Arc<AtomicBool>,
    handle: Option<JoinHandle<Result<Summary, RenderJobError>>>,
}

/// Why a render on its thread did not finish.
#[derive(Debug, thiserror::Error)]
pub enum RenderJobError {
    #[error("opening a GPU device for rendering: {0}")]
    Device(keyrig_render::RenderError),
    #[error(transparent)]
    Meshes(#[from] crate::files::FileError),
    #[error("preparing the scene: {0}")]
    Prepare(keyrig_render::SceneFrameError),
    #[error("uploading meshes: {0}")]
    Upload(keyrig_render::SceneFrameError),
    #[error(transparent)]
    Playblast(#[from] PlayblastError),
    #[error("the render thread stopped unexpectedly")]
    ThreadStopped,
    #[error("the render was already collected")]
    Collected,
}

impl RenderJob {
    /// Starts rendering `scene` (whose model files resolve against `base_dir`) as `blast`
    /// says, drawn with `view` and seen through `through` (by `view.camera` when `None`), frame by frame as
    /// `keyrig render` does ([`crate::playblast::scene_frame`]); refuses before starting an output that is one of the scene's
    /// inputs (its file, the model and sound files it uses).
    ///
    /// # Errors
    /// Bad settings or an output that would replace an input.
    pub fn start(
        scene: Scene,
        scene_file: Option<PathBuf>,
        blast: Playblast,
        view: ViewOptions,
        through: Option<LookThrough>,
    ) -> Result<RenderJob, PlayblastError> {
        blast.validate()?;
        let base_dir = scene_file.as_deref().and_then(|p| p.parent()).map(std::path::Path::to_path_buf);
        let mut inputs = keyrig_io::project::scene_inputs(&scene, base_dir.as_deref());
        if let Some(file) = &scene_file {
            inputs.push((file.clone(), "the scene file".to_owned()));
        }
        blast.check_outputs(&inputs)?;
        let progress = Arc::new(Mutex::new(None));
        let cancel = Arc::new(AtomicBool::new(false));
        let handle = {
            let (blast, progress, cancel) = (blast.clone(), Arc::clone(&progress), Arc::clone(&cancel));
            std::thread::Builder::new()
                .name("keyrig render".into())
                .spawn(move || render(&scene, base_dir, &blast, (view, through), &progress, &cancel))
                .map_err(|e| PlayblastError::Settings(format!("cannot start the render thread: {e}")))?
        };
        Ok(RenderJob { blast, progress, cancel, handle: Some(handle) })
    }

    /// The progress after the last frame rendered (`None` before the first).
    #[must_use]
    pub fn progress(&self) -> Option<Progress> {
        self.progress.lock().ok().and_then(|p| *p)
    }

    /// Asks the thread to stop after the frame it is rendering; the movie is not written.
    pub fn cancel(&self) {
        self.cancel.store(true, Ordering::Relaxed);
    }

    /// Whether cancelling was asked for.
    #[must_use]
    pub fn is_cancelling(&self) -> bool {
        self.cancel.load(Ordering::Relaxed)
    }

    #[must_use]
    pub fn is_finished(&self) -> bool {
        self.handle.as_ref().is_none_or(JoinHandle::is_finished)
    }

    /// Waits for the thread and returns what it did, or why it stopped.
    ///
    /// # Errors
    /// The render failed or was cancelled (the message says which).
    pub fn finish(mut self) -> Result<Summary, RenderJobError> {
        match self.handle.take().map(JoinHandle::join) {
            Some(Ok(result)) => result,
            Some(Err(_)) => Err(RenderJobError::ThreadStopped),
            None => Err(RenderJobError::Collected),
        }
    }
}

fn render(
    scene: &Scene,
    base_dir: Option<PathBuf>,
    blast: &Playblast,
    (view, through): (ViewOptions, Option<LookThrough>),
    progress: &Mutex<Option<Progress>>,
    cancel: &AtomicBool,
) -> Result<Summary, RenderJobError> {
    let mut headless = HeadlessRenderer::new().map_err(RenderJobError::Device)?;
    let meshes = crate::files::render_meshes(scene, base_dir.as_deref())?;
    let rig = SceneRig::with_loaded(scene, &meshes.skinned, &meshes.morphs)
        .map_err(RenderJobError::Prepare)?
        .with_materials(&meshes.materials);
    rig.upload(headless.renderer_mut()).map_err(RenderJobError::Upload)?;
    let mut frame_input = |frame: f64| -> Result<_, FrameError> {
        Ok(crate::playblast::scene_frame(&rig, &view, through, frame)?)
    };
    blast
        .run(&mut headless, &mut frame_input, &mut |p| {
            if let Ok(mut slot) = progress.lock() {
                *slot = Some(*p);
            }
            if cancel.load(Ordering::Relaxed) {
                ControlFlow::Break(())
            } else {
                ControlFlow::Continue(())
            }
        })
        .map_err(RenderJobError::from)
}
