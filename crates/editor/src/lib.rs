//! keyrig-editor: the eframe/egui application.
//!
//! - [`state`]: the document (scene, file, dirty flag, undo/redo), selection and playback.
//! - [`commands`]: every user action with label, tooltip and shortcuts (menus, shortcut
//!   handler and help window all read it).
//! - [`channels`]: addressing animated values and the key operations on them.
//! - [`panels`]: outliner, inspector, timeline (dope sheet), curves, viewport, dialogs.
//! - [`widgets`]: key diamond, TCB slider.
//! - [`twist`]: ring drags, the spins of turned keys, the unwrapped twist about a bone.
//! - [`ik_posing`]: IK posing — the chain of a dragged end joint, its pole, one drag's solves.
//! - [`playblast`]: frame ranges rendered offscreen into GIF, APNG, MP4 or numbered PNGs,
//!   with motion blur (`keyrig render --frames`, File ▸ Render animation).
//! - [`app`]: [`EditorApp`], which ties them together; [`run_editor`] opens the window.

use std::path::PathBuf;

pub mod actions;
pub mod app;
pub mod audio;
pub mod autosave;
pub mod camera;
pub mod cameras;
pub mod commands;
pub mod context;
pub mod document;
pub mod edits;
pub mod eval;
pub mod files;
pub mod fonts;
pub mod frame_bench;
pub mod gpu_view;
pub mod hidden;
pub mod ik_constraints;
pub mod ik_posing;
pub mod keying_sets;
pub mod onion;
pub mod panels;
pub mod playblast;
pub mod pose_library;
pub mod reference_image;
pub mod render_job;
pub mod reopen;
pub mod scene_frame;
pub mod session;
pub mod skinning;
pub mod sounds;
pub mod staples;
pub mod theme;
pub mod twist;
pub mod view;
pub mod widgets;
pub mod window;

pub use app::{EditorApp, EditorOptions};
pub use commands::Command;

/// Initial window size, points.
pub const WINDOW_SIZE: [f32; 2] = [1280.0, 800.0];

/// Builds the editor for `file` (a scene or a model), or for the demo scene when `None`. An
/// unreadable file opens the demo scene with the error in the status bar, so the editor
/// always starts. A model is read in the background while the editor shows an empty scene
/// ([`EditorApp::wait_for_background_work`]).
#[must_use]
pub fn editor_for(file: Option<PathBuf>, options: EditorOptions) -> EditorApp {
    match file {
        None => EditorApp::new(keyrig_io::demo::demo_scene(), None, options),
        Some(path) if !files::is_scene_file(&path) => {
            let mut app = EditorApp::new(keyrig_core::Scene::default(), None, options);
            app.open_path(path);
            app
        }
        Some(path) => match files::open_any(&path) {
            Ok(scene) => {
                let scene_path = files::is_scene_file(&path).then(|| path.clone());
                let mut app = EditorApp::new(scene, scene_path, options);
                app.recent.add(&path);
                app.restore_session();
                app
            }
            Err(e) => {
                let mut app = EditorApp::new(keyrig_io::demo::demo_scene(), None, options);
                app.error(e.to_string());
                app
            }
        },
    }
}

/// Opens the editor window on `file`, or on the demo scene when `None`.
pub fn run_editor(
    file: Option<PathBuf>,
    benchmark_frames: Option<u32>,
    window_size: Option<[f32; 2]>,
) -> anyhow::Result<()> {
    let mut app = editor_for(file, EditorOptions::default());
    if let Some(frames) = benchmark_frames {
        app.benchmark_frames(frames);
    }
    let title = app.doc.title();
    let mut options = eframe::NativeOptions {
        viewport: egui::ViewportBuilder::default()
            .with_title(title)
            .with_inner_size(window_size.unwrap_or(WINDOW_SIZE))
            .with_min_inner_size([800.0, 500.0])
            .with_drag_and_drop(true),
        renderer: eframe::Renderer::Wgpu,
        ..Default::default()
    };
    // On a CPU rasterizer, waiting for vsync costs a quarter of the frames (docs/benchmarks.md,
    // "Editor"), and the viewport is drawn straight into egui's pass, which then needs a depth
    // buffer (docs/rendering.md, "Embedding in the editor"); a GPU keeps vsync and draws the
    // viewport with MSAA into its own image.
    let cpu = gpu_view::default_adapter_is_cpu();
    if cpu {
        options.wgpu_options.present_mode = egui_wgpu::wgpu::PresentMode::AutoNoVsync;
        options.depth_buffer = gpu_view::WINDOW_DEPTH_BITS;
    }
    let window_depth = egui_wgpu::depth_format_from_bits(options.depth_buffer, options.stencil_buffer);
    eframe::run_native(
        "keyrig",
        options,
        Box::new(|cc| {
            fonts::install(&cc.egui_ctx);
            theme::install(&cc.egui_ctx);
            app.fonts_installed = true;
            app.window_clears_background = true;
            app.window_depth = window_depth;
            // The GPU viewport needs eframe's wgpu device; without it the painter draws.
            if let Some(render_state) = &cc.wgpu_render_state {
                app.attach_gpu(render_state);
            }
            Ok(Box::new(app))
        }),
    )
    .map_err(|e| anyhow::anyhow!("cannot open the editor window: {e}"))
}
