//! The inspector's section for a scene camera: its keyed channels (translation, rotation,
//! lens, an aimed camera's roll, visibility: keyed in record mode like every channel), its projection,
//! clip planes and aim target, and the buttons that look through it and set it to the view.

use egui::Ui;
use keyrig_core::{AimTarget, Projection};

use crate::actions::{Actions, Edit};
use crate::commands::Command;
use crate::context::FrameCtx;
use crate::widgets::field::number_field;
use keyrig_edit::channels::ChannelId;
use keyrig_edit::SceneEdit;

pub(super) fn camera_ui(
    ui: &mut Ui,
    ctx: &FrameCtx<'_>,
    actions: &mut Actions,
    c: usize,
    channel_editor: fn(&mut Ui, &FrameCtx<'_>, &mut Actions, ChannelId, &str),
) {
    let Some(camera) = ctx.scene().cameras.get(c).cloned() else { return };
    ui.strong(format!("Camera: {}", camera.name));
    let active = ctx.scene().active_camera_at(ctx.session.playback.frame) == Some(c);
    if active {
        ui.weak("the active camera at this frame");
    }
    channel_editor(ui, ctx, actions, ChannelId::CameraTranslation(c), "Translation");
    match &camera.aim {
        None => channel_editor(ui, ctx, actions, ChannelId::CameraRotation(c), "Rotation (°)"),
        Some(_) => {
            channel_editor(ui, ctx, actions, ChannelId::CameraRoll(c), "Roll (°)");
            // Keyed like any channel: 0 the keyed rotation, 1 the aim (docs/constraints.md).
            channel_editor(ui, ctx, actions, ChannelId::CameraAimInfluence(c), "Aim influence");
        }
    }
    let projection = camera.projection;
    let lens_label = match projection {
        Projection::Perspective => "Field of view (°)",
        Projection::FocalLength { .. } => "Focal length (mm)",
        Projection::Orthographic => "View height",
    };
    channel_editor(ui, ctx, actions, ChannelId::CameraLens(c), lens_label);
    channel_editor(ui, ctx, actions, ChannelId::CameraVisible(c), "Visible");

    let mut chosen = projection;
    egui::ComboBox::from_label("Projection").selected_text(projection.label()).show_ui(ui, |ui| {
        for p in [
            Projection::Perspective,
            Projection::FocalLength { sensor_height_mm: 24.0 },
            Projection::Orthographic,
        ] {
            let same = std::mem::discriminant(&p) == std::mem::discriminant(&projection);
            if ui.selectable_label(same, p.label()).clicked() && !same {
                chosen = p;
            }
        }
    });
    if chosen != projection {
        actions.edit(Edit::scene(SceneEdit::CameraProjection { camera: c, projection: chosen }));
    }
    let mut near = camera.near;
    let mut far = camera.far.unwrap_or(0.0);
    ui.horizontal(|ui| {
        ui.label("Clip");
        let (_, near_change) = number_field(ui, &mut near, "Near clip", |d| d.speed(0.01).max_decimals(3));
        let (_, far_change) = number_field(ui, &mut far, "Far clip", |d| d.speed(1.0).max_decimals(2));
        if (near_change.any() || far_change.any()) && near.is_finite() && far.is_finite() {
            let far = (far > 0.0 || projection == Projection::Orthographic).then_some(far);
            actions.edit(Edit::continuous("camera clip", SceneEdit::CameraClip { camera: c, near, far }));
        }
    });
    if camera.far.is_none() {
        ui.weak("far plane at infinity (0)");
    }
    aim_ui(ui, ctx, actions, c, &camera.aim);
    ui.horizontal(|ui| {
        for command in [Command::LookThroughCamera, Command::CameraToView] {
            if ui.button(command.label()).on_hover_text(command.tooltip()).clicked() {
                actions.command(command);
            }
        }
    });
}

/// What the camera aims at: nothing (its keyed rotation), or an object of the scene.
fn aim_ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions, c: usize, aim: &Option<keyrig_core::Aim>) {
    let current = match aim.as_ref().map(|a| &a.target) {
        None => "Nothing (keyed rotation)".to_owned(),
        Some(AimTarget::Object(o)) => o.clone(),
        Some(AimTarget::Joint { object, joint }) => format!("{object} / {joint}"),
        Some(AimTarget::Point(p)) => format!("point ({:.2}, {:.2}, {:.2})", p.x, p.y, p.z),
    };
    let mut chosen: Option<Option<AimTarget>> = None;
    egui::ComboBox::from_label("Aim at").selected_text(current).show_ui(ui, |ui| {
        if ui.selectable_label(aim.is_none(), "Nothing (keyed rotation)").clicked() {
            chosen = Some(None);
        }
        for object in &ctx.scene().objects {
            if ui.selectable_label(false, &object.name).clicked() {
                chosen = Some(Some(AimTarget::Object(object.name.clone())));
            }
            if let Some(skeleton) = &object.skeleton {
                for joint in &skeleton.joints {
                    if ui.selectable_label(false, format!("{} / {}", object.name, joint.name)).clicked() {
                        chosen = Some(Some(AimTarget::Joint {
                            object: object.name.clone(),
                            joint: joint.name.clone(),
                        }));
                    }
                }
            }
        }
    });
    if let Some(target) = chosen {
        actions.edit(Edit::scene(SceneEdit::CameraAim { camera: c, target }));
    }
}
