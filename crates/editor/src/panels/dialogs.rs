//! Dialogs: keyboard-shortcut help (built from the command list), the undo history, the
//! confirmation before losing changes, and the offer to recover an autosaved scene.

use egui::{Context, Id, Modal};

use crate::actions::{Action, Actions, PendingAction, Unsaved, ViewChange};
use crate::commands::Command;
use crate::context::FrameCtx;

/// The help window: every command with its shortcuts and tooltip.
pub fn help_ui(ctx: &Context, frame: &FrameCtx<'_>, actions: &mut Actions) {
    let shown = frame.view.show_help;
    let mut open = shown;
    // Sized to the window, the list in two halves side by side (every row fits on a 1280×800
    // window; a smaller one scrolls), with the explanations wrapping rather than running off
    // the edge.
    let screen = ctx.content_rect().size();
    egui::Window::new("Keyboard shortcuts")
        .open(&mut open)
        .resizable(true)
        .anchor(egui::Align2::CENTER_CENTER, egui::Vec2::ZERO)
        .default_size(egui::vec2((screen.x * 0.95).min(1250.0), screen.y * 0.97))
        .show(ctx, |ui| {
            // Rows of 16 points, not egui's 18 (a grid row is at least `interact_size.y`): the
            // list has no buttons to hit, and all of it fits 800 points.
            ui.spacing_mut().interact_size.y = 16.0;
            egui::ScrollArea::vertical().auto_shrink([false, false]).show(ui, |ui| {
                let half = Command::ALL.len().div_ceil(2);
                ui.columns(2, |columns| {
                    for (c, ui) in columns.iter_mut().enumerate() {
                        let commands = &Command::ALL
                            [(c * half).min(Command::ALL.len())..((c + 1) * half).min(Command::ALL.len())];
                        egui::Grid::new(("help_grid", c))
                            .striped(true)
                            .num_columns(3)
                            .spacing([12.0, 0.0])
                            .show(ui, |ui| {
                                for command in commands {
                                    ui.label(command.label());
                                    ui.monospace(command.shortcut_text(ctx));
                                    ui.add(
                                        egui::Label::new(
                                            egui::RichText::new(command.tooltip()).weak().small(),
                                        )
                                        .wrap(),
                                    );
                                    ui.end_row();
                                }
                            });
                    }
                });
            });
        });
    if shown && !open {
        actions.view(ViewChange::ShowHelp(false));
    }
}

/// The undo history (Ctrl+Alt+Z, *Edit ▸ Undo history*): the start of the history, every undo
/// step kept (oldest first) and the steps that can be redone (greyed), the current state
/// highlighted. A click on a row goes back, or forward, to the state after that step.
pub fn undo_history_ui(ctx: &Context, frame: &FrameCtx<'_>, actions: &mut Actions) {
    let shown = frame.view.show_undo_history;
    if !shown {
        return;
    }
    let mut open = shown;
    let doc = frame.doc;
    let current = doc.undo_len();
    egui::Window::new("Undo history")
        .open(&mut open)
        .resizable(true)
        .default_pos(ctx.content_rect().right_top() + egui::vec2(-320.0, 60.0))
        .default_size(egui::vec2(300.0, 360.0))
        .show(ctx, |ui| {
            egui::ScrollArea::vertical().auto_shrink([false, false]).show(ui, |ui| {
                let done = std::iter::once("Start of the history").chain(doc.undo_labels());
                for (steps, label) in done.enumerate() {
                    if ui.selectable_label(steps == current, label).clicked() && steps != current {
                        actions.push(Action::UndoTo(steps));
                    }
                }
                for (n, label) in doc.redo_labels().enumerate() {
                    let text = egui::RichText::new(label).weak();
                    if ui
                        .selectable_label(false, text)
                        .on_hover_text("Undone: a click redoes up to it")
                        .clicked()
                    {
                        actions.push(Action::UndoTo(current + n + 1));
                    }
                }
            });
        });
    if !open {
        actions.view(ViewChange::ShowUndoHistory(false));
    }
}

/// Asks what to do with unsaved changes before a pending New, Open or Quit.
pub fn confirm_ui(ctx: &Context, frame: &FrameCtx<'_>, actions: &mut Actions) {
    let Some(action) = frame.pending else { return };
    let what = match action {
        PendingAction::New => "starting a new scene",
        PendingAction::Open(_) => "opening another file",
        PendingAction::Quit => "quitting",
    };
    let mut choice = None;
    Modal::new(Id::new("confirm_unsaved")).show(ctx, |ui| {
        ui.heading("Unsaved changes");
        ui.label(format!("{} has unsaved changes. Save them before {what}?", frame.doc.display_name()));
        ui.horizontal(|ui| {
            if ui.button("Save").clicked() {
                choice = Some(Unsaved::Save);
            }
            if ui.button("Discard changes").clicked() {
                choice = Some(Unsaved::Discard);
            }
            if ui.button("Cancel").clicked() {
                choice = Some(Unsaved::Cancel);
            }
        });
    });
    if let Some(choice) = choice {
        actions.push(Action::ResolveUnsaved(choice));
    }
}

/// Offers the scene autosaved by a session that did not exit cleanly.
pub fn recovery_ui(ctx: &Context, frame: &FrameCtx<'_>, actions: &mut Actions) {
    let Some(recovery) = frame.recovery else { return };
    let origin = recovery.origin();
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
    if let Some(recover) = choice {
        actions.push(Action::Recover(recover));
    }
}
