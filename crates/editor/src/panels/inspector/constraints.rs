//! The inspector's "Constraints" section of an object (docs/constraints.md): each constraint
//! with its kind, its target (a combo of the scene's objects and joints), its keyed influence
//! (and a child-of constraint's parent or a follow path's offset) and a Remove button; below,
//! "Add constraint" with the kinds. Every change is one `SceneEdit`, one undo step.

use egui::Ui;
use keyrig_core::channel_id::ConstraintProperty;
use keyrig_core::{AimTarget, ConstraintKind, Scene};

use crate::actions::{Action, Actions, Edit};
use crate::context::FrameCtx;
use keyrig_edit::channels::ChannelId;
use keyrig_edit::edit::{new_constraint, target_label, CONSTRAINT_KINDS};
use keyrig_edit::SceneEdit;

pub(super) fn constraints_ui(
    ui: &mut Ui,
    ctx: &FrameCtx<'_>,
    actions: &mut Actions,
    o: usize,
    channel_editor: fn(&mut Ui, &FrameCtx<'_>, &mut Actions, ChannelId, &str),
) {
    let scene = ctx.scene();
    let Some(object) = scene.objects.get(o) else { return };
    ui.separator();
    ui.strong("Constraints");
    for (c, constraint) in object.constraints.iter().enumerate() {
        ui.horizontal(|ui| {
            ui.label(format!("{}: {}", constraint.name, constraint.kind.label()));
            if ui.button("Remove").on_hover_text("Remove this constraint (one undo step)").clicked() {
                actions.edit(Edit::scene(SceneEdit::RemoveConstraint { object: o, constraint: c }));
            }
        });
        match &constraint.kind {
            ConstraintKind::AimAt { target, .. }
            | ConstraintKind::CopyLocation { target }
            | ConstraintKind::CopyRotation { target } => {
                let label = format!("Target of {}", constraint.name);
                if let Some(target) = target_combo(ui, scene, &object.name, Some(target), &label) {
                    actions.edit(Edit::scene(SceneEdit::ConstraintTarget {
                        object: o,
                        constraint: c,
                        target,
                    }));
                }
            }
            ConstraintKind::ChildOf { parents, .. } => {
                let names: Vec<String> = parents.iter().map(|p| target_label(&p.target)).collect();
                ui.weak(format!("parents: {}", names.join(", ")));
                // A switch at the current frame, keeping the object where it is; the world is
                // the point target at the origin (docs/constraints.md, "Child of").
                let label = format!("Switch {} here to", constraint.name);
                if let Some(target) = target_combo(ui, scene, &object.name, None, &label) {
                    actions.push(Action::SwitchParent { object: o, constraint: c, target });
                }
            }
            ConstraintKind::FollowPath { points, space, .. } => {
                ui.weak(format!(
                    "a path of {} points in {}",
                    points.len(),
                    space.as_deref().unwrap_or("world space")
                ));
            }
        }
        for property in ConstraintProperty::of_constraint(constraint) {
            let label = match property {
                ConstraintProperty::Influence => "Influence",
                ConstraintProperty::Parent => "Parent (index)",
                ConstraintProperty::Offset => "Path offset",
            };
            channel_editor(
                ui,
                ctx,
                actions,
                ChannelId::Constraint { object: o, constraint: c, property },
                label,
            );
        }
    }
    // New constraints aim at the first other object; its target combo changes that.
    let first_other =
        scene.objects.iter().find(|x| x.name != object.name).map(|x| AimTarget::Object(x.name.clone()));
    ui.add_enabled_ui(first_other.is_some(), |ui| {
        egui::ComboBox::from_label("Add constraint").selected_text("…").show_ui(ui, |ui| {
            for kind in CONSTRAINT_KINDS {
                let clicked = ui.selectable_label(false, kind).clicked();
                if let (true, Some(target)) = (clicked, first_other.clone()) {
                    if let Some(constraint) = new_constraint(scene, o, kind, target) {
                        actions.edit(Edit::scene(SceneEdit::AddConstraint { object: o, constraint }));
                    }
                }
            }
        });
    });
}

/// A combo of the scene's objects and joints other than `own` (an object cannot be its own
/// target), showing `current`; without one (a parent switch) it also offers the world, the
/// point target at the origin. The one chosen, if any.
fn target_combo(
    ui: &mut Ui,
    scene: &Scene,
    own: &str,
    current: Option<&AimTarget>,
    label: &str,
) -> Option<AimTarget> {
    let mut chosen = None;
    let shown = current.map_or_else(|| "…".to_owned(), target_label);
    egui::ComboBox::from_label(label).selected_text(shown).show_ui(ui, |ui| {
        if current.is_none() && ui.selectable_label(false, "World (release)").clicked() {
            chosen = Some(AimTarget::Point(glam::Vec3::ZERO));
        }
        for object in scene.objects.iter().filter(|x| x.name != own) {
            let target = AimTarget::Object(object.name.clone());
            if ui.selectable_label(current == Some(&target), &object.name).clicked() {
                chosen = Some(target);
            }
            for joint in object.skeleton.iter().flat_map(|s| &s.joints) {
                let target = AimTarget::Joint { object: object.name.clone(), joint: joint.name.clone() };
                if ui.selectable_label(current == Some(&target), target_label(&target)).clicked() {
                    chosen = Some(target);
                }
            }
        }
    });
    chosen
}
