//! The outliner: objects (with their skeleton as an indented tree, [`keyrig_core::Skeleton::depth_first`])
//! lights and scene cameras. A click selects one item, Shift- or Ctrl-click adds or removes one; double-click
//! renames; the context menu renames, duplicates and deletes. An object's skeleton folds away
//! with the triangle before its name (Shift+click: every skeleton), so two characters do not
//! make a long scroll; what is folded is remembered for the session (by object name, for the
//! open document), never saved.

use std::collections::BTreeSet;

use egui::Ui;

use crate::actions::{Action, Actions, SessionChange};
use crate::commands::Command;
use crate::context::FrameCtx;
use crate::session::Selected;

/// Indentation per tree level, points.
const INDENT: f32 = 14.0;

/// An item being renamed in the outliner: Enter or leaving the field applies the name (one
/// undo step), Escape cancels.
#[derive(Clone, Debug, PartialEq)]
pub struct Renaming {
    pub item: Selected,
    pub text: String,
    /// The field has been given the keyboard once.
    pub focused: bool,
}

/// What the user did to an item this frame.
enum Choice {
    Click { adding: bool },
    Rename,
    CancelRename,
    Command(Command),
}

/// The outliner and its own state: the name field of an item being renamed, and the objects
/// whose skeletons are folded away.
#[derive(Debug, Default)]
pub struct Outliner {
    renaming: Option<Renaming>,
    /// Objects (by name) whose skeleton is folded away, for the document of that id.
    collapsed: (u64, BTreeSet<String>),
}

/// A click on a skeleton's triangle: fold or unfold `object`, or with Shift every skeleton.
struct Fold {
    object: usize,
    every: bool,
}

impl Outliner {
    /// The item being renamed and the text typed so far, if any.
    #[must_use]
    pub fn renaming(&self) -> Option<&Renaming> {
        self.renaming.as_ref()
    }

    /// Opens the name field on `item`, showing its name `name` (Rename, Ctrl+R).
    pub fn start_rename(&mut self, item: Selected, name: String) {
        self.renaming = Some(Renaming { item, text: name, focused: false });
    }

    /// Whether object `name`'s skeleton is folded away in the outliner.
    #[must_use]
    pub fn is_collapsed(&self, name: &str) -> bool {
        self.collapsed.1.contains(name)
    }

    /// Forgets a rename in progress (the document was replaced).
    pub fn cancel_rename(&mut self) {
        self.renaming = None;
    }

    pub fn ui(&mut self, ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
        egui::Panel::left("outliner").resizable(true).default_size(190.0).show_inside(ui, |ui| {
            ui.heading("Outliner");
            // Only the rows in view are laid out (a scene of thousands of items costs what shows).
            let scene = ctx.scene();
            let doc = ctx.doc.cache_key().0;
            if self.collapsed.0 != doc {
                self.collapsed = (doc, BTreeSet::new());
            }
            let collapsed = &self.collapsed.1;
            let mut entries: Vec<Option<(Selected, usize)>> = Vec::new();
            for (o, object) in scene.objects.iter().enumerate() {
                entries.push(Some((Selected::Object(o), 0)));
                if let Some(skeleton) = object.skeleton.as_ref().filter(|_| !collapsed.contains(&object.name))
                {
                    entries.extend(
                        skeleton
                            .depth_first()
                            .into_iter()
                            .map(|(j, depth)| Some((Selected::Joint { object: o, joint: j }, 1 + depth))),
                    );
                }
            }
            entries.push(None);
            entries.extend((0..scene.lights.len()).map(|l| Some((Selected::Light(l), 0))));
            if !scene.cameras.is_empty() {
                entries.push(None);
                entries.extend((0..scene.cameras.len()).map(|c| Some((Selected::Camera(c), 0))));
            }
            let row_height = ui.spacing().interact_size.y;
            let mut fold = None;
            egui::ScrollArea::vertical().auto_shrink([false, false]).show_rows(
                ui,
                row_height,
                entries.len(),
                |ui, visible| {
                    let mut choice = None;
                    let selection = &ctx.session.selection;
                    let renaming = &mut self.renaming;
                    let mut row = |ui: &mut Ui, item: Selected, name: &str| {
                        if let Some(r) = renaming.as_mut().filter(|r| r.item == item) {
                            if let Some(done) = rename_field(ui, r) {
                                choice =
                                    Some((item, if done { Choice::Rename } else { Choice::CancelRename }));
                            }
                            return;
                        }
                        // An object hidden in the viewport (H) reads dimmed and slanted.
                        let hidden = match item {
                            Selected::Object(o) => ctx.session.hidden.object(scene, o),
                            _ => false,
                        };
                        let text = egui::RichText::new(name);
                        let text = if hidden { text.weak().italics() } else { text };
                        let response =
                            ui.selectable_label(selection.contains(item), text).on_hover_text(name);
                        // A quick click before a double click makes egui count three: rename on either.
                        if response.double_clicked() || response.triple_clicked() {
                            *renaming = Some(Renaming { item, text: name.to_owned(), focused: false });
                        } else if response.clicked() {
                            let adding = ui.input(|i| i.modifiers.shift || i.modifiers.command);
                            choice = Some((item, Choice::Click { adding }));
                        }
                        response.context_menu(|ui| {
                            let joint = matches!(item, Selected::Joint { .. });
                            for command in [Command::RenameItem, Command::DuplicateItem, Command::Delete] {
                                let enabled = !(joint && command != Command::RenameItem);
                                if ui.add_enabled(enabled, egui::Button::new(command.label())).clicked() {
                                    choice = Some((item, Choice::Command(command)));
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
                            Selected::Camera(c) => scene.cameras[c].name.as_str(),
                        };
                        let skeleton = match item {
                            Selected::Object(o) => scene.objects[o].skeleton.is_some(),
                            _ => false,
                        };
                        if skeleton {
                            ui.horizontal(|ui| {
                                if fold_toggle(ui, name, collapsed.contains(name)) {
                                    let every = ui.input(|i| i.modifiers.shift);
                                    if let Selected::Object(object) = item {
                                        fold = Some(Fold { object, every });
                                    }
                                }
                                row(ui, item, name);
                            });
                        } else if depth == 0 {
                            row(ui, item, name);
                        } else {
                            ui.horizontal(|ui| {
                                ui.add_space(INDENT * depth as f32);
                                row(ui, item, name);
                            });
                        }
                    }
                    match choice {
                        Some((item, Choice::Click { adding: true })) => {
                            actions.session(SessionChange::Toggle(item));
                        }
                        Some((item, Choice::Click { adding: false })) => {
                            actions.session(SessionChange::SelectOnly(Some(item)));
                        }
                        Some((item, Choice::Rename)) => {
                            if let Some(r) = self.renaming.take() {
                                actions.push(Action::Rename { item, name: r.text });
                            }
                        }
                        Some((_, Choice::CancelRename)) => self.renaming = None,
                        Some((item, Choice::Command(command))) => {
                            actions.session(SessionChange::SelectOnly(Some(item)));
                            actions.session(SessionChange::SetKeys(Default::default()));
                            actions.command(command);
                        }
                        None => {}
                    }
                },
            );
            if let Some(Fold { object, every }) = fold {
                self.fold(scene, object, every);
            }
        });
    }
}

impl Outliner {
    /// Folds `object`'s skeleton away, or unfolds it; with `every`, every skeleton takes the
    /// state `object`'s takes.
    fn fold(&mut self, scene: &keyrig_core::Scene, object: usize, every: bool) {
        let Some(name) = scene.objects.get(object).map(|o| o.name.clone()) else { return };
        let collapse = !self.collapsed.1.contains(&name);
        let names: Vec<String> = if every {
            scene.objects.iter().filter(|o| o.skeleton.is_some()).map(|o| o.name.clone()).collect()
        } else {
            vec![name]
        };
        for name in names {
            if collapse {
                self.collapsed.1.insert(name);
            } else {
                self.collapsed.1.remove(&name);
            }
        }
    }
}

/// The triangle that folds an object's skeleton away (▶ folded, ▼ open); true when clicked.
/// Accessibility tools read it as "fold the skeleton of NAME" or "unfold the skeleton of NAME".
fn fold_toggle(ui: &mut Ui, name: &str, collapsed: bool) -> bool {
    let text = if collapsed { "▶" } else { "▼" };
    let response = ui
        .add(egui::Button::new(egui::RichText::new(text).small()).frame(false))
        .on_hover_text("Fold the skeleton away or show it (Shift+click: every skeleton)");
    let label = format!("{} the skeleton of {name}", if collapsed { "unfold" } else { "fold" });
    response.widget_info(|| egui::WidgetInfo::labeled(egui::WidgetType::Button, true, label.clone()));
    response.clicked()
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
