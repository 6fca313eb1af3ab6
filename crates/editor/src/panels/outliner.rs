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
        // Only the rows in view are laid out (a scene of thousands of items costs what shows).
        let scene = app.doc.scene();
        let mut entries: Vec<Option<(Selected, usize)>> = Vec::new();
        for (o, object) in scene.objects.iter().enumerate() {
            entries.push(Some((Selected::Object(o), 0)));
            if let Some(skeleton) = &object.skeleton {
                entries.extend(
                    hierarchy(skeleton)
                        .into_iter()
                        .map(|(j, depth)| Some((Selected::Joint { object: o, joint: j }, 1 + depth))),
                );
            }
        }
        entries.push(None);
        entries.extend((0..scene.lights.len()).map(|l| Some((Selected::Light(l), 0))));
        let row_height = ui.spacing().interact_size.y;
        egui::ScrollArea::vertical().auto_shrink([false, false]).show_rows(
            ui,
            row_height,
            entries.len(),
            |ui, visible| {
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
                for entry in &entries[visible] {
                    let Some((item, depth)) = *entry else {
                        ui.add_sized([ui.available_width(), row_height], egui::Separator::default());
                        continue;
                    };
                    let name = match item {
                        Selected::Object(o) => scene.objects[o].name.as_str(),
                        Selected::Joint { object, joint } => scene.objects[object]
                            .skeleton
                            .as_ref()
                            .map_or("", |s| s.joints[joint].name.as_str()),
                        Selected::Light(l) => scene.lights[l].name.as_str(),
                    };
                    if depth == 0 {
                        row(ui, item, name);
                    } else {
                        ui.horizontal(|ui| {
                            ui.add_space(INDENT * depth as f32);
                            row(ui, item, name);
                        });
                    }
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
            },
        );
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

/// The joints of `skeleton` in depth-first order (children follow their parent, in index
/// order) with their depth (0 for a root), in time linear in the joint count. A parent whose
/// index is not below the child's makes the child a root, so a broken file cannot loop.
#[must_use]
pub fn hierarchy(skeleton: &Skeleton) -> Vec<(usize, usize)> {
    let n = skeleton.joints.len();
    let parent = |j: usize| skeleton.joints[j].parent.filter(|&p| p < j);
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
    for j in 0..n {
        if let Some(p) = parent(j) {
            children[p].push(j);
        }
    }
    let mut out = Vec::with_capacity(n);
    let mut stack: Vec<(usize, usize)> =
        (0..n).rev().filter(|&j| parent(j).is_none()).map(|j| (j, 0)).collect();
    while let Some((j, depth)) = stack.pop() {
        out.push((j, depth));
        stack.extend(children[j].iter().rev().map(|&c| (c, depth + 1)));
    }
    out
}
