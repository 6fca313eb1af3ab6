//! The menu bar and the toolbar under it. Menu items come from [`Command`]: label, tooltip and
//! shortcut text; choosing one queues it.

use egui::{Button, Ui};
use keyrig_core::DeformerKind;

use crate::actions::{Action, Actions, PendingAction, SessionChange, ViewChange};
use crate::commands::Command;
use crate::context::FrameCtx;
use crate::view::RenderStyle;
use crate::widgets::command_button::tool_button;

/// A menu entry for `command`; queues it when clicked.
fn command_button(
    ui: &mut Ui,
    ctx: &FrameCtx<'_>,
    actions: &mut Actions,
    command: Command,
    checked: Option<bool>,
) {
    let egui_ctx = ui.ctx().clone();
    let shortcut = command.shortcuts().first().map(|s| egui_ctx.format_shortcut(s)).unwrap_or_default();
    let enabled = match command {
        Command::Undo => ctx.doc.undo_label().is_some(),
        Command::Redo => ctx.doc.redo_label().is_some(),
        _ => true,
    };
    // Undo and Redo say which step they revert or repeat ("Undo move key").
    let label = match command {
        Command::Undo => ctx.doc.undo_label().map(|step| format!("{} {step}", command.label())),
        Command::Redo => ctx.doc.redo_label().map(|step| format!("{} {step}", command.label())),
        _ => None,
    }
    .unwrap_or_else(|| command.label().to_owned());
    let button = match checked {
        Some(on) => Button::selectable(on, label),
        None => Button::new(label),
    };
    let response = ui.add_enabled(enabled, button.shortcut_text(shortcut)).on_hover_text(command.tooltip());
    if response.clicked() {
        actions.command(command);
        ui.close();
    }
}

/// The import scales offered by name: the unit a model was made in, and the factor that
/// turns it into metres.
pub const IMPORT_SCALES: [(&str, f32); 6] = [
    ("×1: the file's own unit (glTF, VRML metres; FBX converted)", 1.0),
    ("×0.01: made in centimetres", 0.01),
    ("×0.001: made in millimetres", 0.001),
    ("×0.0254: made in inches", 0.0254),
    ("×0.3048: made in feet", 0.3048),
    ("×100: made in metres, for a scene in centimetres", 100.0),
];

/// File ▸ Import scale: the scale now, a field to type another (taken with Enter, refused with a
/// message when it is not a number above 0) and the usual ones by unit.
fn import_scale_ui(ui: &mut Ui, scale: f32, actions: &mut Actions) {
    ui.label(format!(
        "Models are imported in their file's unit (glTF, VRML, X3D, Inventor: metres; FBX: its own unit, converted to metres), times {}",
        crate::files::placement::format_scale(scale)
    ));
    let id = ui.make_persistent_id("import_scale_text");
    let mut text: String = ui.data_mut(|d| d.get_temp(id)).unwrap_or_default();
    ui.horizontal(|ui| {
        let label = ui.label("Scale ×");
        let hint = crate::files::placement::format_scale(scale);
        let response = ui
            .add(egui::TextEdit::singleline(&mut text).hint_text(hint).desired_width(80.0))
            .labelled_by(label.id);
        let entered = response.lost_focus() && ui.input(|i| i.key_pressed(egui::Key::Enter));
        if ui.button("Set").clicked() || entered {
            actions.push(Action::ImportScale(text.clone()));
            ui.data_mut(|d| d.remove::<String>(id));
        } else if response.changed() {
            ui.data_mut(|d| d.insert_temp(id, text.clone()));
        }
    });
    ui.separator();
    for (label, value) in IMPORT_SCALES {
        if ui.add(Button::selectable(scale == value, label)).clicked() {
            actions.push(Action::ImportScale(crate::files::placement::format_scale(value)));
            ui.data_mut(|d| d.remove::<String>(id));
            ui.close();
        }
    }
}

/// Draws the menu bar and toolbar as a top panel.
pub fn ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
    egui::Panel::top("menu_bar").show_inside(ui, |ui| {
        egui::MenuBar::new().ui(ui, |ui| {
            ui.menu_button("File", |ui| {
                for c in [Command::New, Command::Open] {
                    command_button(ui, ctx, actions, c, None);
                }
                ui.menu_button("Open recent", |ui| {
                    if ctx.recent.is_empty() {
                        ui.label("No recent files");
                    }
                    for path in ctx.recent {
                        if ui.button(path.display().to_string()).clicked() {
                            actions.push(Action::Request(PendingAction::Open(Some(path.clone()))));
                            ui.close();
                        }
                    }
                });
                ui.separator();
                for c in [Command::Save, Command::SaveAs] {
                    command_button(ui, ctx, actions, c, None);
                }
                ui.separator();
                for c in [Command::Import, Command::ImportSound] {
                    command_button(ui, ctx, actions, c, None);
                }
                // Typing into its field must not close it: only a click outside does.
                let stay_open = egui::containers::menu::MenuConfig::new()
                    .close_behavior(egui::PopupCloseBehavior::CloseOnClickOutside);
                egui::containers::menu::SubMenuButton::new("Import scale")
                    .config(stay_open)
                    .ui(ui, |ui| import_scale_ui(ui, ctx.import_scale, actions))
                    .0
                    .on_hover_text("The factor models imported into the scene are scaled by (1 keeps the file's unit)");
                for c in [Command::ExportGltf, Command::RenderAnimation] {
                    command_button(ui, ctx, actions, c, None);
                }
                ui.separator();
                command_button(ui, ctx, actions, Command::Quit, None);
            });
            ui.menu_button("Edit", |ui| {
                command_button(ui, ctx, actions, Command::Undo, None);
                command_button(ui, ctx, actions, Command::Redo, None);
                command_button(ui, ctx, actions, Command::UndoHistory, Some(ctx.view.show_undo_history));
                ui.separator();
                for c in [
                    Command::InsertKey,
                    Command::Delete,
                    Command::CopyKeys,
                    Command::PasteKeys,
                    Command::DuplicateItem,
                    Command::RenameItem,
                ] {
                    command_button(ui, ctx, actions, c, None);
                }
                ui.separator();
                for c in [Command::ReduceKeys, Command::SmoothKeys, Command::Retarget] {
                    command_button(ui, ctx, actions, c, None);
                }
                ui.separator();
                let (record, ik) = (ctx.session.record, ctx.session.ik.enabled);
                command_button(ui, ctx, actions, Command::ToggleRecord, Some(record));
                command_button(ui, ctx, actions, Command::ToggleIk, Some(ik));
            });
            ui.menu_button("Add", |ui| {
                for kind in keyrig_edit::scene_add::AddKind::ALL {
                    if matches!(
                        kind,
                        keyrig_edit::scene_add::AddKind::PointLight | keyrig_edit::scene_add::AddKind::Camera
                    ) {
                        ui.separator();
                    }
                    if ui.button(kind.label()).on_hover_text(kind.tooltip()).clicked() {
                        actions.push(Action::Add(kind));
                        ui.close();
                    }
                }
            });
            ui.menu_button("View", |ui| {
                let view = ctx.view;
                command_button(ui, ctx, actions, Command::ToggleGrid, Some(view.grid));
                command_button(ui, ctx, actions, Command::ToggleBones, Some(view.bones));
                command_button(ui, ctx, actions, Command::ToggleOnionSkin, Some(view.onion.enabled));
                for c in [Command::GizmoMove, Command::GizmoTurn, Command::GizmoScale] {
                    command_button(ui, ctx, actions, c, None);
                }
                for c in [Command::HideSelected, Command::ShowHidden] {
                    command_button(ui, ctx, actions, c, None);
                }
                if ui
                    .button("Reference image…")
                    .on_hover_text("An image (PNG, JPEG, BMP) shown behind the scene, saved with it; its opacity is in the inspector")
                    .clicked()
                {
                    actions.push(Action::ChooseReferenceImage);
                    ui.close();
                }
                ui.menu_button("Onion skin settings", |ui| {
                    let mut onion = view.onion;
                    onion_settings_ui(ui, &mut onion);
                    if onion != view.onion {
                        actions.view(ViewChange::Onion(onion));
                    }
                });
                ui.separator();
                for c in [
                    Command::CameraFront,
                    Command::CameraSide,
                    Command::CameraTop,
                    Command::CameraShoulder,
                    Command::CameraElbow,
                    Command::FrameSelection,
                ] {
                    command_button(ui, ctx, actions, c, None);
                }
                ui.separator();
                let looking = ctx.view.look_through.is_some();
                command_button(ui, ctx, actions, Command::LookThroughCamera, Some(looking));
                for c in [Command::CameraToView, Command::AddCamera] {
                    command_button(ui, ctx, actions, c, None);
                }
                ui.separator();
                for style in RenderStyle::ALL {
                    if ui.radio(view.style == style, style.label()).clicked() {
                        actions.view(ViewChange::Style(style));
                        ui.close();
                    }
                }
                let mut textures = view.textures;
                let response = ui.checkbox(&mut textures, "Textures").on_hover_text(
                    "Draw imported models with their materials (glTF base colour and texture, MD2 \
                     skins) in the solid style; off shows plain per-object colours",
                );
                if response.changed() {
                    actions.view(ViewChange::Textures(textures));
                }
                ui.separator();
                for (scale, label) in [(1.0, "Full resolution"), (0.5, "Half resolution")] {
                    let tip = "Pixels the GPU viewport renders per screen pixel; half is four times cheaper \
                               on a CPU rasterizer";
                    if ui.radio(view.resolution_scale == scale, label).on_hover_text(tip).clicked() {
                        actions.view(ViewChange::ResolutionScale(scale));
                        ui.close();
                    }
                }
                let mut antialiasing = view.antialiasing;
                let response = ui.checkbox(&mut antialiasing, "Anti-aliasing (4× MSAA)").on_hover_text(
                    "Smooth edges in the GPU viewport; off by default on a CPU rasterizer such as \
                     lavapipe, where it costs more than drawing the scene",
                );
                if response.changed() {
                    actions.view(ViewChange::Antialiasing(antialiasing));
                }
            });
            ui.menu_button("Deformer", |ui| {
                let current = ctx.deformer_in_effect();
                for kind in DeformerKind::ALL {
                    command_button(ui, ctx, actions, Command::SetDeformer(kind), Some(current == Some(kind)));
                }
            });
            ui.menu_button("Playback", |ui| {
                let (playing, looping) = (ctx.session.playback.playing, ctx.session.playback.looping);
                command_button(ui, ctx, actions, Command::PlayPause, Some(playing));
                command_button(ui, ctx, actions, Command::ToggleLoop, Some(looping));
                for c in [Command::FirstFrame, Command::PrevFrame, Command::NextFrame, Command::LastFrame] {
                    command_button(ui, ctx, actions, c, None);
                }
                ui.separator();
                for c in [Command::ToggleMarker, Command::BindCameraToMarker] {
                    command_button(ui, ctx, actions, c, None);
                }
            });
            ui.menu_button("Help", |ui| {
                command_button(ui, ctx, actions, Command::ShowHelp, None);
            });
        });
        toolbar_ui(ui, ctx, actions);
    });
}

/// How many ghosts, and where: every n frames or at the object's keys.
fn onion_settings_ui(ui: &mut Ui, onion: &mut crate::onion::OnionSkin) {
    use crate::onion::{Spacing, MAX_PER_SIDE};
    ui.horizontal(|ui| {
        ui.label("Before");
        ui.add(egui::DragValue::new(&mut onion.before).range(0..=MAX_PER_SIDE));
        ui.label("After");
        ui.add(egui::DragValue::new(&mut onion.after).range(0..=MAX_PER_SIDE));
    });
    let mut step = match onion.spacing {
        Spacing::Frames(n) => n,
        Spacing::Keys => 5,
    };
    ui.horizontal(|ui| {
        if ui.radio(matches!(onion.spacing, Spacing::Frames(_)), "Every").clicked()
            || ui.add(egui::DragValue::new(&mut step).range(1..=1000)).changed()
        {
            onion.spacing = Spacing::Frames(step);
        }
        ui.label("frames");
    });
    if ui
        .radio(onion.spacing == Spacing::Keys, "At keys")
        .on_hover_text("At the selected object's keys")
        .clicked()
    {
        onion.spacing = Spacing::Keys;
    }
}

/// The active keying set, beside *Key* (Blender's Keying menu of the timeline): what `I` keys,
/// and in record mode what is keyed with a changed channel.
fn keying_set_ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
    use crate::keying_sets::KeyingSet;
    let current = ctx.session.keying_set;
    let mut chosen = current;
    egui::ComboBox::from_label("Keying set")
        .selected_text(current.label())
        .show_ui(ui, |ui| {
            for set in KeyingSet::ALL {
                ui.selectable_value(&mut chosen, set, set.label()).on_hover_text(set.description());
            }
        })
        .response
        .on_hover_text(format!(
            "What I keys: {}. In record mode a changed channel is keyed with the set's other \
             channels of its item (Whole character: every joint).",
            current.description()
        ));
    if chosen != current {
        actions.session(SessionChange::KeyingSet(chosen));
    }
}

fn toolbar_ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
    ui.horizontal(|ui| {
        let record = ctx.session.record;
        let rec_text = "⏺ Record";
        let tip = format!(
            "{} ({})",
            Command::ToggleRecord.tooltip(),
            Command::ToggleRecord.shortcut_text(ui.ctx())
        );
        let rec = egui::Button::selectable(
            record,
            egui::RichText::new(rec_text).color(if record {
                egui::Color32::from_rgb(255, 80, 80)
            } else {
                ui.visuals().text_color()
            }),
        );
        if ui.add(rec).on_hover_text(tip).clicked() {
            actions.command(Command::ToggleRecord);
        }
        tool_button(ui, actions, Command::InsertKey, "◆ Key", false);
        keying_set_ui(ui, ctx, actions);
        let ik = ctx.session.ik.enabled;
        tool_button(ui, actions, Command::ToggleIk, "IK", ik);
        ui.separator();
        let (grid, bones) = (ctx.view.grid, ctx.view.bones);
        tool_button(ui, actions, Command::ToggleGrid, "# Grid", grid);
        tool_button(ui, actions, Command::ToggleBones, "Bones", bones);
        ui.separator();
        ui.label("Deformer:");
        let current = ctx.deformer_in_effect();
        for (i, kind) in DeformerKind::ALL.into_iter().enumerate() {
            tool_button(
                ui,
                actions,
                Command::SetDeformer(kind),
                &format!("{} {}", i + 1, kind.label()),
                current == Some(kind),
            );
        }
        ui.separator();
        for (c, t) in [
            (Command::CameraFront, "Front"),
            (Command::CameraSide, "Side"),
            (Command::CameraTop, "Top"),
            (Command::CameraShoulder, "Shoulder"),
            (Command::CameraElbow, "Elbow"),
        ] {
            tool_button(ui, actions, c, t, false);
        }
    });
}
