//! Edit ▸ Retarget… (docs/retargeting.md): a window that reads a source file (a BVH take, a
//! glTF or FBX character, a scene), shows the bone map made from the joints' names as one row
//! per joint of the selected character (a joint selects its skeleton's object; else the first
//! object with a skeleton) with the source joint that drives it, editable, and Apply puts the
//! source's action onto the character as a new action, one undo step
//! ([`SceneEdit::Retarget`]).

use std::path::Path;

use egui::Context;
use keyrig_core::Scene;
use keyrig_edit::retarget::{BoneMap, RetargetOptions};
use keyrig_edit::SceneEdit;

use crate::actions::{Actions, Edit};
use crate::context::FrameCtx;
use crate::session::Selected;

/// The window's fields, kept while the editor runs.
#[derive(Default)]
pub struct RetargetDialog {
    pub open: bool,
    /// The source file's path, as typed.
    pub path: String,
    /// The source read from `path`, and its object with a skeleton.
    pub source: Option<(Box<Scene>, usize)>,
    /// Why the source could not be read.
    pub error: Option<String>,
    /// The map being edited, and the target object it was made for.
    pub map: Option<(usize, BoneMap)>,
    /// The new action's name.
    pub action: String,
    /// Copy the legs only (do not hold planted feet).
    pub no_contacts: bool,
}

/// Reads a source: a scene file, or a model or take as the editor imports it.
fn read_source(path: &Path) -> Result<(Box<Scene>, usize), String> {
    let scene = if crate::files::is_scene_file(path) {
        keyrig_io::project::load_scene(path).map_err(|e| format!("{}: {e}", path.display()))?
    } else {
        crate::files::import_model(path).map_err(|e| e.to_string())?
    };
    let object = scene
        .objects
        .iter()
        .position(|o| o.skeleton.is_some())
        .ok_or_else(|| format!("{}: no object has a skeleton", path.display()))?;
    Ok((Box::new(scene), object))
}

impl RetargetDialog {
    /// The window, while the command opened it.
    pub fn ui(&mut self, ctx: &Context, frame: &FrameCtx<'_>, actions: &mut Actions) {
        if !self.open {
            return;
        }
        let scene = frame.doc.scene();
        let selected = match frame.session.selection.item {
            Some(Selected::Object(o) | Selected::Joint { object: o, .. }) => Some(o),
            _ => None,
        };
        let target = selected
            .filter(|&o| scene.objects.get(o).is_some_and(|x| x.skeleton.is_some()))
            .or_else(|| scene.objects.iter().position(|o| o.skeleton.is_some()));
        let mut open = true;
        let mut apply = false;
        egui::Window::new("Retarget").open(&mut open).collapsible(false).default_width(420.0).show(
            ctx,
            |ui| {
                ui.horizontal(|ui| {
                    let label = ui.label("Source file");
                    ui.add(
                        egui::TextEdit::singleline(&mut self.path)
                            .hint_text("take.bvh, character.glb, scene.ron"),
                    )
                    .labelled_by(label.id);
                    if ui.button("Read").clicked() {
                        match read_source(Path::new(self.path.trim())) {
                            Ok(source) => {
                                self.source = Some(source);
                                self.error = None;
                                self.map = None;
                                if self.action.is_empty() {
                                    self.action = Path::new(self.path.trim()).file_stem().map_or_else(
                                        || "Retargeted".to_owned(),
                                        |s| s.to_string_lossy().replace('/', "_"),
                                    );
                                }
                            }
                            Err(e) => self.error = Some(e),
                        }
                    }
                });
                if let Some(error) = &self.error {
                    ui.colored_label(ui.visuals().error_fg_color, error);
                }
                let (Some((source, source_object)), Some(target)) = (&self.source, target) else {
                    ui.label(if target.is_none() {
                        "The scene has no object with a skeleton."
                    } else {
                        "Read a source file with a skeleton."
                    });
                    return;
                };
                let (Some(source_skeleton), Some(target_skeleton)) = (
                    source.objects[*source_object].skeleton.as_ref(),
                    scene.objects[target].skeleton.as_ref(),
                ) else {
                    return;
                };
                if self.map.as_ref().is_none_or(|(o, _)| *o != target) {
                    self.map = Some((target, BoneMap::automatic(source_skeleton, target_skeleton)));
                }
                let Some((_, map)) = self.map.as_mut() else { return };
                ui.label(format!(
                    "{} ({} joints) drives {} ({} joints): {} pairs",
                    source.objects[*source_object].name,
                    source_skeleton.joints.len(),
                    scene.objects[target].name,
                    target_skeleton.joints.len(),
                    map.pairs.len()
                ));
                egui::ScrollArea::vertical().max_height(320.0).show(ui, |ui| {
                    egui::Grid::new("retarget_map").num_columns(2).striped(true).show(ui, |ui| {
                        for joint in &target_skeleton.joints {
                            ui.label(&joint.name);
                            let current = map.source_of(&joint.name).map(str::to_owned);
                            let mut chosen = current.clone();
                            egui::ComboBox::from_id_salt(("retarget_source", &joint.name))
                                .selected_text(current.as_deref().unwrap_or("—"))
                                .show_ui(ui, |ui| {
                                    ui.selectable_value(&mut chosen, None, "—");
                                    for s in &source_skeleton.joints {
                                        ui.selectable_value(&mut chosen, Some(s.name.clone()), &s.name);
                                    }
                                });
                            if chosen != current {
                                map.set(&joint.name, chosen.as_deref());
                            }
                            ui.end_row();
                        }
                    });
                });
                ui.horizontal(|ui| {
                    ui.label("Action");
                    ui.text_edit_singleline(&mut self.action);
                });
                ui.checkbox(&mut self.no_contacts, "Copy the legs only (do not hold planted feet)");
                let valid = !map.pairs.is_empty()
                    && map.resolve(source_skeleton, target_skeleton).is_ok()
                    && !self.action.is_empty()
                    && !self.action.contains('/');
                ui.horizontal(|ui| {
                    if ui.add_enabled(valid, egui::Button::new("Apply")).clicked() {
                        apply = true;
                    }
                    if ui.button("Cancel").clicked() {
                        self.open = false;
                    }
                });
            },
        );
        if apply {
            if let (Some((source, source_object)), Some((object, map))) = (&self.source, &self.map) {
                let mut options = RetargetOptions::new(scene.unused_action_name(&self.action));
                if self.no_contacts {
                    options.contacts = None;
                }
                let edit = SceneEdit::Retarget {
                    source: source.clone(),
                    source_object: *source_object,
                    object: *object,
                    map: map.clone(),
                    options,
                };
                actions.edit(Edit::scene(edit));
                self.open = false;
            }
        }
        if !open {
            self.open = false;
        }
    }
}
