//! The inspector's Pose library section: a name field, *Add pose* (the selection's pose at the
//! current frame under that name), and a row per saved pose with *Apply*, *Apply mirrored*,
//! *Rename* (to the name in the field) and *Delete pose* ([`crate::pose_library`]).

use egui::Ui;

use crate::actions::{Action, Actions, PoseLibraryAction};
use crate::context::FrameCtx;

/// The section's own state: the name field.
#[derive(Debug, Default)]
pub struct PoseLibraryUi {
    name: String,
}

impl PoseLibraryUi {
    pub fn ui(&mut self, ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
        let poses = &ctx.scene().poses;
        egui::CollapsingHeader::new(format!("Pose library ({})", poses.len()))
            .id_salt("pose library")
            .default_open(true)
            .show(ui, |ui| {
                let selected = ctx.session.selection.item.is_some();
                ui.horizontal(|ui| {
                    let label = ui.label("Pose name");
                    ui.add(egui::TextEdit::singleline(&mut self.name).desired_width(120.0).hint_text("Pose"))
                        .labelled_by(label.id)
                        .on_hover_text("The name Add pose saves under, or Rename gives");
                });
                let add = ui
                    .add_enabled(selected, egui::Button::new("Add pose"))
                    .on_hover_text("Save the selection's pose at this frame (a character's whole skeleton when its object is selected)")
                    .on_disabled_hover_text("Select joints or a character first");
                if add.clicked() {
                    actions.push(Action::PoseLibrary(PoseLibraryAction::Add(self.name.trim().to_owned())));
                    self.name.clear();
                }
                for (index, pose) in poses.iter().enumerate() {
                    ui.push_id(("pose", index), |ui| {
                        ui.horizontal_wrapped(|ui| {
                            ui.strong(&pose.name).on_hover_text(format!("{} channel(s)", pose.values.len()));
                            let apply = |mirrored| Action::PoseLibrary(PoseLibraryAction::Apply { index, mirrored });
                            if ui
                                .add_enabled(selected, egui::Button::new("Apply"))
                                .on_hover_text("Set the selection to this pose (keys in record mode)")
                                .clicked()
                            {
                                actions.push(apply(false));
                            }
                            if ui
                                .add_enabled(selected, egui::Button::new("Apply mirrored"))
                                .on_hover_text("The pose mirrored across the character's symmetry plane, left and right swapped")
                                .clicked()
                            {
                                actions.push(apply(true));
                            }
                            if ui.button("Rename").on_hover_text("Rename to the name in the field").clicked() {
                                let name = self.name.trim().to_owned();
                                actions.push(Action::PoseLibrary(PoseLibraryAction::Rename { index, name }));
                                self.name.clear();
                            }
                            if ui.button("Delete pose").clicked() {
                                actions.push(Action::PoseLibrary(PoseLibraryAction::Delete(index)));
                            }
                        });
                    });
                }
            });
    }
}
