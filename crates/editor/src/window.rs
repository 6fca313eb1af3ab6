//! One frame of the editor window, in order: the playback clock; shortcuts, finished imports
//! and dropped files queued as actions; the frame's preparation ([`crate::scene_frame`]: the
//! evaluator in step with the document, the scene evaluated at the clock's time, what the
//! panels need skinned on the CPU); the panels laid out from the read-only
//! [`FrameCtx`], each pushing what it wants changed; then every queued action applied in order
//! ([`EditorApp::apply_actions`]), so the next frame draws from the state after them; the
//! autosave, the window's title and close handling. Also [`eframe::App`] for [`EditorApp`].

use egui::{Key, Modifiers, Vec2};

use crate::actions::{Action, ViewChange};
use crate::app::{EditorApp, PendingAction};
use crate::commands::{pressed, Pressed};
use crate::context::FrameCtx;
use crate::panels;

impl EditorApp {
    /// One frame of the editor, drawn into `ui` (the whole window).
    pub fn ui(&mut self, ui: &mut egui::Ui) {
        let ctx = ui.ctx().clone();
        let benchmark_start = self.frame_benchmark.as_mut().map(|b| {
            self.session.playback.playing = true;
            b.frame_started()
        });
        self.frame(ui, &ctx);
        if let (Some(bench), Some(start)) = (&mut self.frame_benchmark, benchmark_start) {
            let gpu = self.panels.viewport.gpu().map_or(std::time::Duration::ZERO, |g| g.last_render_time);
            bench.frame_prepared(start, gpu);
            if bench.is_done() {
                let viewport = match self.panels.viewport.gpu() {
                    Some(gpu) => format!("GPU viewport on {}", gpu.adapter_name()),
                    None => "painter viewport".to_owned(),
                };
                let size = ctx.content_rect().size();
                println!("{} at {}x{} points", bench.report(&viewport), size.x, size.y);
                self.frame_benchmark = None;
                ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            }
            ctx.request_repaint();
        }
    }

    fn frame(&mut self, ui: &mut egui::Ui, ctx: &egui::Context) {
        let ctx = ctx.clone();
        if !self.fonts_installed {
            crate::fonts::install(&ctx);
            crate::theme::install(&ctx);
            self.fonts_installed = true;
        }
        if !self.window_clears_background {
            let background = crate::theme::panel_background(&ctx.global_style().visuals);
            ui.painter().rect_filled(ctx.content_rect(), 0.0, background);
        }
        self.panel_sizes_ui(&ctx, true);
        // Playback clock.
        let dt = ctx.input(|i| f64::from(i.stable_dt));
        let scene = self.doc.scene();
        let (fps, range) = (scene.fps, scene.playback_range());
        if self.session.playback.playing {
            // While the sound plays, the clock follows the sound's (crate::audio::clock).
            let dt = self.audio.played_seconds().unwrap_or(dt);
            self.session.playback.advance(dt, fps, range.start, range.end);
            ctx.request_repaint();
            let raw = ctx.input(|i| i.unstable_dt);
            if raw.is_finite() && raw > 0.0 {
                self.frame_time = Some(self.frame_time.map_or(raw, |t| t * 0.9 + raw * 0.1));
            }
        } else {
            self.frame_time = None;
        }

        // A file dialog owns the keyboard while it is open: what is typed into it (or pressed
        // while its list has the focus) never reaches the editor's shortcuts.
        let shortcuts = if self.dialog_purpose.is_some() { Vec::new() } else { pressed(&ctx) };
        for input in shortcuts {
            self.actions.push(match input {
                Pressed::Command(command) => Action::Command(command),
                Pressed::Copy => Action::Copy,
                Pressed::Cut => Action::Cut,
                Pressed::Paste(text) => Action::Paste(text),
            });
        }
        // Escape closes the help window.
        if self.view.show_help && ctx.input_mut(|i| i.consume_key(Modifiers::NONE, Key::Escape)) {
            self.actions.view(ViewChange::ShowHelp(false));
        }
        self.poll_background_work(&ctx);
        self.handle_dropped_files(&ctx);
        // What came with the frame's input is applied before anything is drawn, so this frame
        // shows it (a shortcut's effect, a started import in the status bar).
        self.apply_actions(&ctx);

        self.prepare_frame();
        self.layout(ui, &ctx);
        self.dialog_ui(&ctx);

        // What the panels asked for: the next frame draws it, and is asked for now. The outcomes
        // the panels read this frame are replaced by those of these edits.
        self.results.clear();
        if self.apply_actions(&ctx) {
            ctx.request_repaint();
        }
        self.follow_audio(&ctx);
        // A drag (slider, gizmo, key drag) ends when the pointer is released, after its edits.
        // A grab (Shift+D's move) follows the pointer with no button held: its step stays open.
        if !ctx.input(|i| i.pointer.any_down()) && !self.panels.viewport.holds_undo_group() {
            self.doc.close_group();
        }
        self.note_autosave();
        self.panel_sizes_ui(&ctx, false);

        // Viewport commands request a repaint: send the title only when it changes.
        let title = self.doc.title();
        if title != self.window_title {
            ctx.send_viewport_cmd(egui::ViewportCommand::Title(title.clone()));
            self.window_title = title;
        }
        if self.quit_confirmed && !self.close_sent {
            ctx.send_viewport_cmd(egui::ViewportCommand::Close);
            self.close_sent = true;
        }
        if ctx.input(|i| i.viewport().close_requested()) && !self.quit_confirmed && self.doc.is_dirty() {
            ctx.send_viewport_cmd(egui::ViewportCommand::CancelClose);
            self.pending = Some(PendingAction::Quit);
        }
    }
}

impl EditorApp {
    /// The frame's preparation: what the panels draw from, brought in step with the document,
    /// the clock and the overrides, with what the viewport needs skinned on the CPU. Every
    /// frame runs it before laying out the panels; benchmarks call it alone.
    pub fn prepare_frame(&mut self) {
        let time = self.time();
        let wanted = self.panels.viewport.wanted(self.session.selection.item);
        self.scene.prepare(&self.doc, &mut self.meshes, time, &self.session.overrides, wanted);
    }

    /// The panels in their order, each drawn from the frame's read-only context and pushing its
    /// actions: menu bar, status bar, the timeline's controls over the dope sheet and the curve
    /// view, the outliner, the inspector, the viewport, the dialogs.
    fn layout(&mut self, ui: &mut egui::Ui, egui_ctx: &egui::Context) {
        let ctx = FrameCtx {
            doc: &self.doc,
            session: &self.session,
            view: &self.view,
            scene: &self.scene,
            meshes: &self.meshes,
            sounds: &self.sounds,
            results: &self.results,
            status: self.status.as_ref(),
            imports: &self.imports,
            frame_time: self.frame_time,
            recent: &self.recent.paths,
            pending: self.pending.as_ref(),
            recovery: self.recovery_offer.as_ref().map(|_| &self.recovery),
            gpu_fills: self.panels.viewport.gpu().is_some(),
            render: self.render.as_ref(),
            import_scale: self.import_scale,
        };
        let actions = &mut self.actions;
        let panels = &mut self.panels;
        panels::menu::ui(ui, &ctx, actions);
        panels::status::ui(ui, &ctx, panels.viewport.gpu());
        egui::Panel::bottom("timeline").resizable(true).default_size(310.0).show_inside(ui, |ui| {
            panels.timeline.ui(ui, &ctx, actions);
            ui.separator();
            let available = ui.available_size();
            let curves_width = (available.x * 0.38).max(200.0);
            ui.horizontal_top(|ui| {
                let sheet_size = Vec2::new((available.x - curves_width - 8.0).max(200.0), available.y);
                let layout = egui::Layout::top_down(egui::Align::Min);
                ui.allocate_ui_with_layout(sheet_size, layout, |ui| {
                    // The dope sheet and the clip editor share this place: a tab each.
                    ui.horizontal(|ui| {
                        ui.selectable_value(&mut panels.clips.shown, false, "Dope sheet");
                        ui.selectable_value(&mut panels.clips.shown, true, "Clips")
                            .on_hover_text("Clip tracks, strips and layers (docs/clips.md)");
                    });
                    if panels.clips.shown {
                        egui::ScrollArea::vertical()
                            .id_salt("clips")
                            .show(ui, |ui| panels.clips.ui(ui, &ctx, actions));
                    } else {
                        panels.dope_sheet.ui(ui, &ctx, actions);
                    }
                });
                ui.separator();
                let size = Vec2::new(ui.available_width(), available.y);
                ui.allocate_ui_with_layout(size, layout, |ui| panels.curves.ui(ui, &ctx, actions));
            });
        });
        panels.outliner.ui(ui, &ctx, actions);
        panels.inspector.ui(ui, &ctx, actions);
        panels.viewport.ui(ui, &ctx, actions);

        panels::dialogs::help_ui(egui_ctx, &ctx, actions);
        panels::dialogs::undo_history_ui(egui_ctx, &ctx, actions);
        panels::dialogs::confirm_ui(egui_ctx, &ctx, actions);
        panels::dialogs::recovery_ui(egui_ctx, &ctx, actions);
        panels.render.ui(egui_ctx, &ctx, actions);
        panels.cleanup.ui(egui_ctx, &ctx, actions);
        panels.retarget.ui(egui_ctx, &ctx, actions);
    }
}

impl eframe::App for EditorApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        EditorApp::ui(self, ui);
    }

    /// The panels' background: clearing to it is how the window gets it ([`crate::theme`]).
    fn clear_color(&self, visuals: &egui::Visuals) -> [f32; 4] {
        crate::theme::panel_background(visuals).to_normalized_gamma_f32()
    }

    fn on_exit(&mut self) {
        self.remember_session();
        // A clean exit leaves no recovery file; a dirty one keeps the last autosave.
        if !self.doc.is_dirty() {
            self.autosave.clear();
        }
    }
}
