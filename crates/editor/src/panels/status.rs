//! The status bar: the last message or error, the undo step, record mode and the frame.

use egui::{Color32, RichText, Ui};

use crate::app::EditorApp;

pub fn ui(ui: &mut Ui, app: &mut EditorApp) {
    egui::Panel::bottom("status_bar").show_inside(ui, |ui| {
        ui.horizontal(|ui| {
            if app.record {
                ui.label(RichText::new("● REC").color(Color32::from_rgb(255, 80, 80)).strong());
            }
            ui.label(format!("Frame {}", app.playback.whole_frame()));
            if let Some(t) = app.frame_time {
                ui.weak(format!("{:.1} ms/frame ({:.0} fps)", t * 1000.0, 1.0 / t.max(1e-6)));
            }
            if let Some(gpu) = &app.gpu {
                ui.weak("GPU viewport").on_hover_text(gpu.adapter_name());
            }
            if let Some(label) = app.doc.undo_label() {
                ui.weak(format!("Last edit: {label}"));
            }
            if let Some(status) = &app.status {
                ui.separator();
                let text = RichText::new(&status.text);
                if status.is_error {
                    ui.label(text.color(ui.visuals().error_fg_color));
                } else {
                    ui.label(text);
                }
            }
        });
    });
}
