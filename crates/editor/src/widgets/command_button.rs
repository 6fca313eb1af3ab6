//! A toolbar button for a [`Command`]: its text, its tooltip with the shortcut, and the command
//! queued when clicked (the menu bar and the timeline's playback controls use it).

use egui::Ui;

use crate::actions::Actions;
use crate::commands::Command;

/// A toolbar button for `command` showing `text` (selected when `on`); queues the command when
/// clicked.
pub fn tool_button(ui: &mut Ui, actions: &mut Actions, command: Command, text: &str, on: bool) {
    let tip = format!("{} ({})", command.tooltip(), command.shortcut_text(ui.ctx()));
    if ui.selectable_label(on, text).on_hover_text(tip).clicked() {
        actions.command(command);
    }
}
