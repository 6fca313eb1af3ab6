//! The outliner: objects (with their skeleton as an indented tree) and lights. A click selects
//! one item, Shift- or Ctrl-click adds or removes one; double-click renames; the context menu
//! renames, duplicates and deletes.

use egui::Ui;
use keyrig_core::Skeleton;

use crate::app::EditorApp;
use crate::commands::Command;
use crate::session::Selected;
use crate::view::Renaming;

/// Indentation per tree level, points.
const INDENT: f32 = 14.0;

/// What the user did to an item this frame.
enum Action {
    Click { adding: bool },
    Rename,
    CancelRename,
    Command(Command),
}

pub fn ui(ui: &mut Ui, app: &mut EditorApp) {
    egui::Panel::left("outliner").resizable(true).default_size(190.0).show_inside(ui, |ui| {
        ui.heading("Outliner");
        egui::ScrollArea::vertical().show(ui, |ui| {
            let mut action = None;
            let scene = app.doc.scene();
            let selection = &app.session.selection;
            let renaming = &mut app.view.renaming;
            let mut row = |ui: &mut Ui, item: Selected, name: &str| {
                if let Some(r) = renaming.as_mut().filter(|r| r.item == item) {
                    if let Some(done) = rename_field(ui, r) {
                        action = Some((item, if done { Action::Rename } else { Action::CancelRename }));
                    }
                    return;
                }
                let response = ui.selectable_label(selection.contains(item), name).on_hover_text(name);
                // A quick click before a double click makes egui count three: rename on either.
                if response.double_clicked() || response.triple_clicked() {
                    *renaming = Some(Renaming { item, text: name.to_owned(), focused: false });
                } else if response.clicked() {
                    let adding = ui.input(|i| i.modifiers.shift || i.modifiers.command);
                    action = Some((item, Action::Click { adding }));
                }
                response.context_menu(|ui| {
                    let joint = matches!(item, Selected::Joint { .. });
                    for command in [Command::RenameItem, Command::DuplicateItem, Command::Delete] {
                        let enabled = !(joint && command != Command::RenameItem);
                        if ui.add_enabled(enabled, egui::Button::new(command.label())).clicked() {
                            action = Some((item, Action::Command(command)));
                            ui.close();
                        }
                    }
                });
            };
            for (o, object) in scene.objects.iter().enumerate() {
                row(ui, Selected::Object(o), object.name.as_str());
                if let Some(skeleton) = &object.skeleton {
                    for j in depth_first(skeleton) {
                        ui.horizontal(|ui| {
                            ui.add_space(INDENT * (1 + depth(skeleton, j)) as f32);
                            row(
                                ui,
                                Selected::Joint { object: o, joint: j },
                                skeleton.joints[j].name.as_str(),
                            );
                        });
                    }
                }
            }
            ui.separator();
            for (l, light) in scene.lights.iter().enumerate() {
                row(ui, Selected::Light(l), light.name.as_str());
            }
            match action {
                Some((item, Action::Click { adding: true })) => app.session.selection.toggle(item),
                Some((item, Action::Click { adding: false })) => {
                    app.session.selection.select_only(Some(item))
                }
                Some((item, Action::Rename)) => {
                    if let Some(r) = app.view.renaming.take() {
                        app.rename_item(item, &r.text);
                    }
                }
                Some((_, Action::CancelRename)) => app.view.renaming = None,
                Some((item, Action::Command(command))) => {
                    app.session.selection.select_only(Some(item));
                    app.session.selection.keys.clear();
                    app.run_command(ui.ctx(), command);
                }
                None => {}
            }
        });
    });
}

/// The name field of an item being renamed: `Some(true)` when Enter or a click elsewhere
/// ends the edit (apply), `Some(false)` on Escape (cancel).
fn rename_field(ui: &mut Ui, renaming: &mut Renaming) -> Option<bool> {
    let response = ui.add(egui::TextEdit::singleline(&mut renaming.text).desired_width(f32::INFINITY));
    if !renaming.focused {
        response.request_focus();
        renaming.focused = true;
        return None;
    }
    if response.lost_focus() {
        let cancelled = ui.input(|i| i.key_pressed(egui::Key::Escape));
        return Some(!cancelled);
    }
    None
}

/// Depth of joint `j` (0 for a root). Parents with an index not below the child's are treated
/// as roots, so a broken file cannot loop.
fn depth(skeleton: &Skeleton, j: usize) -> usize {
    let mut d = 0;
    let mut current = j;
    while let Some(p) = skeleton.joints[current].parent.filter(|&p| p < current) {
        d += 1;
        current = p;
    }
    d
}

/// Joint indices in depth-first order (children follow their parent).
fn depth_first(skeleton: &Skeleton) -> Vec<usize> {
    let n = skeleton.joints.len();
    let mut out = Vec::with_capacity(n);
    let mut stack: Vec<usize> =
        (0..n).rev().filter(|&j| skeleton.joints[j].parent.is_none_or(|p| p >= j)).collect();
    while let Some(j) = stack.pop() {
        out.push(j);
        stack.extend((j + 1..n).rev().filter(|&c| skeleton.joints[c].parent == Some(j)));
    }
    out
}
