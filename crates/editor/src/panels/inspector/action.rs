//! The inspector's Action section (docs/actions.md): the selected object's active action in a
//! combo box that assigns another, a name field, and *New action*, *Duplicate action*, *Rename
//! action* (to the name in the field) and *Delete action*. Each change is one undo step
//! ([`keyrig_edit::edit::ActionEdit`]); a name that is empty, holds `/` or is taken is refused
//! with a message.

use egui::Ui;
use keyrig_core::Scene;
use keyrig_edit::edit::ActionEdit;
use keyrig_edit::SceneEdit;

use crate::actions::{Action, Actions, Edit};
use crate::context::FrameCtx;

/// The section's own state: the name field.
#[derive(Debug, Default)]
pub struct ActionUi {
    name: String,
}

/// Why `name` cannot name a new action in `scene`; `None` when it can.
fn refusal(scene: &Scene, name: &str) -> Option<String> {
    if name.is_empty() {
        Some("type a name in the Action name field first".to_owned())
    } else if name.contains('/') {
        Some(format!("{name:?}: an action name cannot contain '/'"))
    } else if scene.action_index(name).is_some() {
        Some(format!("there is already an action {name:?}"))
    } else {
        None
    }
}

impl ActionUi {
    /// The section for object `o`.
    pub fn ui(&mut self, ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions, o: usize) {
        let scene = ctx.scene();
        let Some(object) = scene.objects.get(o) else { return };
        let current = object.action.clone();
        egui::CollapsingHeader::new(format!("Action ({})", scene.actions.len()))
            .id_salt("action")
            .default_open(true)
            .show(ui, |ui| {
                ui.horizontal(|ui| {
                    let label = ui.label("Action");
                    let shown = current.clone().unwrap_or_else(|| "(none)".to_owned());
                    let mut chosen = current.clone();
                    egui::ComboBox::from_id_salt("active action")
                        .selected_text(shown)
                        .show_ui(ui, |ui| {
                            ui.selectable_value(&mut chosen, None, "(none)");
                            for a in &scene.actions {
                                ui.selectable_value(&mut chosen, Some(a.name.clone()), &a.name);
                            }
                        })
                        .response
                        .labelled_by(label.id)
                        .on_hover_text("The action this object plays: its keys are what the dope sheet and the curve editor show");
                    if chosen != current {
                        let edit = ActionEdit::Assign { object: o, name: chosen };
                        actions.edit(Edit::scene(SceneEdit::Action(edit)));
                    }
                });
                ui.horizontal(|ui| {
                    let label = ui.label("Action name");
                    ui.add(egui::TextEdit::singleline(&mut self.name).desired_width(120.0).hint_text("Walk"))
                        .labelled_by(label.id)
                        .on_hover_text("The name New, Duplicate and Rename use");
                });
                let name = self.name.trim().to_owned();
                let mut named = |make: &dyn Fn(String) -> ActionEdit, actions: &mut Actions| {
                    match refusal(scene, &name) {
                        Some(why) => actions.push(Action::Error(format!("Action: {why}"))),
                        None => {
                            actions.edit(Edit::scene(SceneEdit::Action(make(name.clone()))));
                            self.name.clear();
                        }
                    }
                };
                ui.horizontal_wrapped(|ui| {
                    if ui.button("New action").on_hover_text("An empty action under the name, made active (the keys go to the old action)").clicked() {
                        named(&|name| ActionEdit::New { object: o, name }, actions);
                    }
                    if ui.button("Duplicate action").on_hover_text("A copy of the keys this object plays under the name, made active").clicked() {
                        named(&|name| ActionEdit::Duplicate { object: o, name }, actions);
                    }
                    if let Some(old) = current.clone() {
                        if ui.button("Rename action").on_hover_text("Rename the active action to the name in the field").clicked() {
                            named(&|new| ActionEdit::Rename { old: old.clone(), new }, actions);
                        }
                        if ui.button("Delete action").on_hover_text("Delete the active action and its keys").clicked() {
                            actions.edit(Edit::scene(SceneEdit::Action(ActionEdit::Delete { name: old })));
                        }
                    }
                });
            });
    }
}
