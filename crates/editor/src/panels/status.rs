//! The status bar: the last message (for a few seconds) or error (half a minute), the undo step, record mode and the frame, and
//! the model imports running in the background (file, stage, a progress bar where the
//! fraction is known or a spinner where it is not, elapsed time).

use egui::{Color32, RichText, Ui};

use crate::context::{FrameCtx, Status};
use crate::gpu_view::GpuView;

/// The status bar; `gpu` is the viewport's GPU view, when there is one.
pub fn ui(ui: &mut Ui, ctx: &FrameCtx<'_>, gpu: Option<&GpuView>) {
    egui::Panel::bottom("status_bar").show_inside(ui, |ui| {
        ui.horizontal(|ui| {
            if ctx.session.record {
                ui.label(RichText::new("● REC").color(Color32::from_rgb(255, 80, 80)).strong());
            }
            ui.label(format!("Frame {}", ctx.session.playback.whole_frame()));
            if let Some(t) = ctx.frame_time {
                ui.weak(format!("{:.1} ms/frame ({:.0} fps)", t * 1000.0, 1.0 / t.max(1e-6)));
            }
            if let Some(gpu) = gpu {
                ui.weak("GPU viewport").on_hover_ui(|ui| {
                    ui.label(gpu.adapter_name());
                });
            }
            if let Some(label) = ctx.doc.undo_label() {
                ui.weak(format!("Last edit: {label}"));
            }
            for import in ctx.imports {
                ui.separator();
                import_ui(ui, import);
            }
            let left = ctx.status.map_or(0.0, Status::seconds_left);
            if left > 0.0 {
                // Wake up to take the message away when it is due, drawing or not. At least half
                // a second ahead: egui repaints at once for a delay shorter than a frame, and a
                // message in its last moments must not keep the editor repainting (the message
                // goes at most half a second late).
                ui.ctx().request_repaint_after(std::time::Duration::from_secs_f32(left.max(0.5)));
            }
            if let Some(status) = ctx.status.filter(|_| left > 0.0) {
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

/// One running import: a spinner, "Importing sydney.md2: reading", a progress bar where the
/// fraction is known, and the elapsed time. The editor repaints every 50 ms while an import
/// runs; the spinner turns with the elapsed time (egui's own spinner would ask for a repaint
/// every frame).
fn import_ui(ui: &mut Ui, import: &crate::files::BackgroundImport) {
    let progress = import.progress();
    let elapsed = import.elapsed().as_secs_f64();
    let name = import
        .path
        .file_name()
        .map_or_else(|| import.path.display().to_string(), |n| n.to_string_lossy().into_owned());
    let verb = match import.purpose {
        crate::files::ImportPurpose::Open => "Opening",
        crate::files::ImportPurpose::Import => "Importing",
    };
    spinner_ui(ui, elapsed);
    ui.label(format!("{verb} {name}: {}", progress.stage)).on_hover_text(import.path.display().to_string());
    if let Some(fraction) = progress.fraction {
        ui.add(egui::ProgressBar::new(fraction).desired_width(80.0).show_percentage());
    }
    ui.weak(format!("{elapsed:.1} s"));
}

/// A three-quarter circle turning once a second, drawn for `elapsed` seconds.
fn spinner_ui(ui: &mut Ui, elapsed: f64) {
    let size = ui.text_style_height(&egui::TextStyle::Body);
    let (rect, _) = ui.allocate_exact_size(egui::vec2(size, size), egui::Sense::hover());
    let radius = rect.height() * 0.4;
    let start = (elapsed * std::f64::consts::TAU) as f32;
    let points: Vec<egui::Pos2> = (0..=24)
        .map(|i| {
            let a = start + i as f32 / 24.0 * 1.5 * std::f32::consts::PI;
            rect.center() + radius * egui::vec2(a.cos(), a.sin())
        })
        .collect();
    ui.painter().add(egui::Shape::line(points, egui::Stroke::new(2.0, ui.visuals().strong_text_color())));
}
