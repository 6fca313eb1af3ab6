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

use keyrig_core::{Camera, Scene};
use keyrig_render::{HeadlessRenderer, SceneRig, ViewOptions};

use crate::playblast::{FrameError, Playblast, PlayblastError, Progress, Summary};

/// A playblast rendering on its own thread.
pub struct RenderJob {
    /// What is being rendered.
    pub blast: Playblast,
    progress: Arc<Mutex<Option<Progress>>>,
    cancel: Arc<AtomicBool>,
    handle: Option<JoinHandle<Result<Summary, String>>>,
}

impl RenderJob {
    /// Starts rendering `scene` (whose model files resolve against `base_dir`) as `blast`
    /// says, seen by `camera`; refuses before starting an output that is one of the scene's
    /// inputs (its file, the model and sound files it uses).
    ///
    /// # Errors
    /// Bad settings or an output that would replace an input.
    pub fn start(
        scene: Scene,
        scene_file: Option<PathBuf>,
        blast: Playblast,
        camera: Camera,
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
                .spawn(move || render(&scene, base_dir, &blast, camera, &progress, &cancel))
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
    pub fn finish(mut self) -> Result<Summary, String> {
        match self.handle.take().map(JoinHandle::join) {
            Some(Ok(result)) => result,
            Some(Err(_)) => Err("the render thread stopped unexpectedly".into()),
            None => Err("the render was already collected".into()),
        }
    }
}

fn render(
    scene: &Scene,
    base_dir: Option<PathBuf>,
    blast: &Playblast,
    camera: Camera,
    progress: &Mutex<Option<Progress>>,
    cancel: &AtomicBool,
) -> Result<Summary, String> {
    let mut headless =
        HeadlessRenderer::new().map_err(|e| format!("opening a GPU device for rendering: {e}"))?;
    let meshes = crate::files::render_meshes(scene, base_dir.as_deref()).map_err(|e| e.to_string())?;
    let rig = SceneRig::with_loaded(scene, &meshes.skinned, &meshes.morphs)
        .map_err(|e| format!("preparing the scene: {e}"))?
        .with_materials(&meshes.materials);
    rig.upload(headless.renderer_mut()).map_err(|e| format!("uploading meshes: {e}"))?;
    let view = ViewOptions { camera: Some(camera), skeletons: false, ..ViewOptions::default() };
    let mut frame_input =
        |frame: f64| -> Result<_, FrameError> { Ok(rig.frame(rig.time_of_frame(frame), &view)?) };
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
        .map_err(|e| e.to_string())
}
