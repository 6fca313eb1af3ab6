//! Modal dialogs: keyboard-shortcut help (built from the command list), the confirmation
//! before losing changes, and the offer to recover an autosaved scene.

use egui::{Context, Id, Modal};

use crate::app::{EditorApp, PendingAction};
use crate::commands::Command;

/// The help window: every command with its shortcuts and tooltip.
pub fn help_ui(ctx: &Context, app: &mut EditorApp) {
    let mut open = app.view.show_help;
    // Sized to the window (every row of the list fits on a 1280×800 window; a smaller one
    // scrolls), with the explanations wrapping rather than running off the edge.
    let screen = ctx.content_rect().size();
    egui::Window::new("Keyboard shortcuts")
        .open(&mut open)
        .resizable(true)
        .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
        .default_size(egui::vec2((screen.x * 0.8).min(900.0), screen.y * 0.97))
        .show(ctx, |ui| {
            egui::ScrollArea::vertical().auto_shrink([false, false]).show(ui, |ui| {
                egui::Grid::new("help_grid").striped(true).num_columns(3).spacing([12.0, 0.0]).show(
                    ui,
                    |ui| {
                        for command in Command::ALL {
                            ui.label(command.label());
                            ui.monospace(command.shortcut_text(ctx));
                            ui.add(
                                egui::Label::new(egui::RichText::new(command.tooltip()).weak().small())
                                    .wrap(),
                            );
                            ui.end_row();
                        }
                    },
                );
            });
        });
    app.view.show_help = open && app.view.show_help;
}

/// Asks what to do with unsaved changes before a pending New, Open or Quit.
pub fn confirm_ui(ctx: &Context, app: &mut EditorApp) {
    let Some(action) = app.pending.clone() else { return };
    let what = match action {
        PendingAction::New => "starting a new scene",
        PendingAction::Open(_) => "opening another file",
        PendingAction::Quit => "quitting",
    };
    let mut choice = None;
    Modal::new(Id::new("confirm_unsaved")).show(ctx, |ui| {
        ui.heading("Unsaved changes");
        ui.label(format!("{} has unsaved changes. Save them before {what}?", app.doc.display_name()));
        ui.horizontal(|ui| {
            if ui.button("Save").clicked() {
                choice = Some(0);
            }
            if ui.button("Discard changes").clicked() {
                choice = Some(1);
            }
            if ui.button("Cancel").clicked() {
                choice = Some(2);
            }
        });
    });
    match choice {
        Some(0) => {
            app.pending = None;
            app.save();
            if !app.doc.is_dirty() {
                app.perform(action);
            }
        }
        Some(1) => {
            app.pending = None;
            app.perform(action);
        }
        Some(2) => app.pending = None,
        _ => {}
    }
}

/// Offers the scene autosaved by a session that did not exit cleanly.
pub fn recovery_ui(ctx: &Context, app: &mut EditorApp) {
    if app.recovery_offer.is_none() {
        return;
    }
    let origin = app.recovery.origin();
    let mut choice = None;
    Modal::new(Id::new("offer_recovery")).show(ctx, |ui| {
        ui.heading("Recover unsaved work?");
        let from =
            origin.as_ref().map_or_else(|| "an untitled scene".to_owned(), |p| p.display().to_string());
        ui.label(format!("keyrig did not exit cleanly. An autosave of {from} was found."));
        ui.horizontal(|ui| {
            if ui.button("Recover").clicked() {
                choice = Some(true);
            }
            if ui.button("Discard autosave").clicked() {
                choice = Some(false);
            }
        });
    });
    match choice {
        Some(true) => {
            if let Some(scene) = app.recovery_offer.take() {
                app.replace_document(scene, origin);
                app.doc.mark_dirty();
                app.info("Recovered the autosaved scene; save it to keep it");
            }
        }
        Some(false) => {
            app.recovery_offer = None;
            app.autosave.clear();
        }
        None => {}
    }
}
