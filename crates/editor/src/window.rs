//! One frame of the editor window: the playback clock, shortcuts, the panels in their order,
//! dialogs and the window's title and close handling; and [`eframe::App`] for [`EditorApp`].

use egui::{Key, Modifiers};

use crate::app::{EditorApp, PendingAction};
use crate::commands::{pressed, Command, Pressed};
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
            let gpu = self.gpu.as_ref().map_or(std::time::Duration::ZERO, |g| g.last_render_time);
            bench.frame_prepared(start, gpu);
            if bench.is_done() {
                let viewport = match &self.gpu {
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
            self.fonts_installed = true;
        }
        // Playback clock.
        let dt = ctx.input(|i| f64::from(i.stable_dt));
        let scene = self.doc.scene();
        let (fps, range) = (scene.fps, scene.frame_range);
        if self.session.playback.playing {
            self.session.playback.advance(dt, fps, range.start, range.end);
            ctx.request_repaint();
            let raw = ctx.input(|i| i.unstable_dt);
            if raw.is_finite() && raw > 0.0 {
                self.frame_time = Some(self.frame_time.map_or(raw, |t| t * 0.9 + raw * 0.1));
            }
        } else {
            self.frame_time = None;
        }

        for input in pressed(&ctx) {
            match input {
                Pressed::Command(command) => self.run_command(&ctx, command),
                Pressed::Copy => self.run_command(&ctx, Command::CopyKeys),
                Pressed::Cut => self.cut_keys(&ctx),
                Pressed::Paste(text) => self.paste_text(&text),
            }
        }
        // Escape closes the help window.
        if self.view.show_help && ctx.input_mut(|i| i.consume_key(Modifiers::NONE, Key::Escape)) {
            self.view.show_help = false;
        }
        self.poll_background_work(&ctx);
        self.handle_dropped_files(&ctx);

        panels::menu::ui(ui, self);
        panels::status::ui(ui, self);
        panels::timeline::ui(ui, self);
        panels::outliner::ui(ui, self);
        panels::inspector::ui(ui, self);
        panels::viewport::ui(ui, self);
        panels::curves::paint_pending(&ctx, self);

        panels::dialogs::help_ui(&ctx, self);
        panels::dialogs::confirm_ui(&ctx, self);
        panels::dialogs::recovery_ui(&ctx, self);
        self.dialog_ui(&ctx);

        // A drag (slider, gizmo, key drag) ends when the pointer is released.
        if !ctx.input(|i| i.pointer.any_down()) {
            self.doc.close_group();
        }
        self.session.selection.retain_valid(self.doc.scene());
        self.note_autosave();

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

impl eframe::App for EditorApp {
    fn ui(&mut self, ui: &mut egui::Ui, _frame: &mut eframe::Frame) {
        EditorApp::ui(self, ui);
    }

    fn on_exit(&mut self) {
        // A clean exit leaves no recovery file; a dirty one keeps the last autosave.
        if !self.doc.is_dirty() {
            self.autosave.clear();
        }
    }
}
