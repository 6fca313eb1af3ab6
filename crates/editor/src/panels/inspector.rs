//! The inspector: the selection's transform (changes go through record mode or the pose), the
//! key inspector (interpolation mode and T/C/B of the selected keys, and the cycles of their
//! channel before and after its keys), and the deformer with its
//! parameters, plus the cross-section measure of the selected joint, and an object's
//! constraints (`constraints`: add, retarget, remove, key their influence).

pub mod action;
mod camera;
mod constraints;
pub mod pose_library;

use egui::Ui;
use glam::Vec3;
use keyrig_core::{AttributeId, Cycle, DeformerKind, Interpolation, KeyType, Tcb};

use crate::actions::{Action, Actions, Edit, SessionChange};
use crate::context::FrameCtx;
use crate::eval::continuous_euler;
use crate::session::Selected;
use crate::widgets::field::{number_field, FieldChange};
use crate::widgets::measure::measure_ui;
use crate::widgets::tcb_slider::tcb_slider_ui;
use keyrig_core::channel_id::rotation_mode;
use keyrig_core::RotationMode;
use keyrig_edit::channels::{self, ChannelId, ChannelValue};
use keyrig_edit::edit::Animate;
use keyrig_edit::{KeyParamChange, SceneEdit};

/// Starts applying a field's change: a committed (typed) value is its own undo step, so any
/// open continuous group is closed first; a drag continues its group until release.
fn begin(actions: &mut Actions, change: FieldChange) {
    if change == FieldChange::Committed {
        actions.push(Action::CloseGroup);
    }
}

/// The inspector. Its fields show the frame's values and push their changes; its own state is
/// the pose library's name field.
#[derive(Debug, Default)]
pub struct Inspector {
    pose_library: pose_library::PoseLibraryUi,
    action: action::ActionUi,
}

impl Inspector {
    pub fn ui(&mut self, ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
        egui::Panel::right("inspector").resizable(true).default_size(270.0).show_inside(ui, |ui| {
            egui::ScrollArea::vertical().show(ui, |ui| {
                ui.heading("Inspector");
                selection_ui(ui, ctx, actions);
                ui.separator();
                key_inspector_ui(ui, ctx, actions);
                ui.separator();
                self.pose_library.ui(ui, ctx, actions);
                ui.separator();
                reference_image_ui(ui, ctx, actions);
                // The selected object's or light's attributes, after the key inspector so that
                // opening them moves nothing above.
                match ctx.session.selection.item {
                    Some(Selected::Object(o)) => object_attributes_ui(ui, ctx, actions, o),
                    Some(Selected::Light(l)) => light_attributes_ui(ui, ctx, actions, l),
                    _ => {}
                }
                deformer_ui(ui, ctx, actions);
                // The active action of the selected object (or of the joint's object), last so
                // that opening it moves nothing above.
                if let Some(Selected::Object(o) | Selected::Joint { object: o, .. }) =
                    ctx.session.selection.item
                {
                    ui.separator();
                    self.action.ui(ui, ctx, actions, o);
                }
            });
        });
    }
}

/// A row of three drag values. Each carries the accessible label "<label> X" (Y, Z), which is
/// what screen readers and the UI tests find.
fn vec3_editor(ui: &mut Ui, label: &str, marker: &str, v: &mut Vec3, speed: f64) -> FieldChange {
    ui.horizontal(|ui| {
        ui.label(label);
        if !marker.is_empty() {
            ui.weak(marker);
        }
    });
    ui.horizontal(|ui| {
        let mut changed = FieldChange::None;
        for (axis, c) in ["X", "Y", "Z"].iter().zip([&mut v.x, &mut v.y, &mut v.z]) {
            ui.label(*axis);
            let name = format!("{label} {axis}");
            let (_, change) = number_field(ui, c, &name, |d| d.speed(speed).max_decimals(3));
            if change.any() {
                changed = change;
            }
        }
        changed
    })
    .inner
}

/// A row of four drag values for a quaternion, labelled "<label> W" (X, Y, Z).
fn quat_editor(ui: &mut Ui, label: &str, marker: &str, v: &mut glam::Vec4) -> FieldChange {
    ui.horizontal(|ui| {
        ui.label(label);
        if !marker.is_empty() {
            ui.weak(marker);
        }
    });
    ui.horizontal(|ui| {
        let mut changed = FieldChange::None;
        let mut components = v.to_array();
        for (axis, c) in ["W", "X", "Y", "Z"].iter().zip(components.iter_mut()) {
            let name = format!("{label} {axis}");
            let (_, change) = number_field(ui, c, &name, |d| d.speed(0.005).max_decimals(4));
            if change.any() {
                changed = change;
            }
        }
        *v = glam::Vec4::from_array(components);
        changed
    })
    .inner
}

/// The rotation mode of a rotation channel (its object's or joint's): quaternion, or Euler
/// angles in one of the six orders, and whether its keys are Euler keys (docs/channels.md,
/// "Euler keys"). With quaternion keys the mode changes what is shown and typed, not the keys;
/// the *Euler keys* box converts the keys to three angle curves and back, and with Euler keys a
/// new order converts them to it. Each change is one undo step.
fn rotation_mode_ui(
    ui: &mut Ui,
    ctx: &FrameCtx<'_>,
    actions: &mut Actions,
    id: ChannelId,
    mode: RotationMode,
) {
    let euler_keys = keyrig_core::channel_id::has_euler_keys(ctx.scene(), id);
    let help = match mode.euler() {
        Some(order) => order.formula(),
        None => "The unit quaternion w, x, y, z; typed values are normalised".to_owned(),
    };
    let mut chosen = mode;
    let mut wants_euler = euler_keys;
    // One row (the inspector keeps its height): the mode, and the Euler keys box beside it.
    let row = ui.horizontal(|ui| {
        let response = egui::ComboBox::from_id_salt(("rotation mode", id))
            .selected_text(mode.label())
            .show_ui(ui, |ui| {
                for choice in RotationMode::ALL {
                    let tip = match choice.euler() {
                        Some(order) => order.formula(),
                        None => "Quaternion components w, x, y, z".to_owned(),
                    };
                    ui.selectable_value(&mut chosen, choice, choice.label()).on_hover_text(tip);
                }
            })
            .response;
        ui.ctx().accesskit_node_builder(response.id, |node| node.set_label("Rotation mode"));
        if mode.euler().is_some() {
            // A locked rotation keeps its keys: the box shows their form and cannot switch it.
            let (_, locked) = keyrig_edit::channels::mute_and_lock(
                ctx.scene(),
                keyrig_core::channel_id::rotation_or_euler(ctx.scene(), id),
            );
            ui.add_enabled(!locked, egui::Checkbox::new(&mut wants_euler, "Euler keys")).on_hover_text(
                "Key the rotation as three angle curves in this order, each interpolated on its own \
                 (as Blender's and Maya's Euler rotations), instead of quaternion keys with Squad. \
                 Switching converts the keys; the rotation at each key stays.",
            );
        }
        response
    });
    row.inner.on_hover_text(if euler_keys {
        format!(
            "{help}. The keys are Euler keys: another order converts them (the rotation at each \
             key is kept); Quaternion converts them back to quaternion keys."
        )
    } else {
        format!(
            "{help}. The keys stay quaternions, interpolated as before; the mode changes what the \
             inspector and the curves show and type."
        )
    });
    if chosen != mode || wants_euler != euler_keys {
        actions.push(Action::CloseGroup);
        actions.edit(Edit::scene(SceneEdit::RotationMode {
            channel: id,
            mode: chosen,
            euler_keys: wants_euler,
        }));
    }
}

/// A colour button that opens egui's colour picker, for a linear-RGB colour as the scene stores
/// it (components above 1 are clamped by the picker only when it is used). The button carries
/// the accessible label `label`; its tooltip shows the stored numbers.
fn colour_editor(ui: &mut Ui, label: &str, marker: &str, v: &mut Vec3) -> bool {
    ui.horizontal(|ui| {
        ui.label(label);
        let mut rgb = v.to_array();
        let response = egui::color_picker::color_edit_button_rgb(ui, &mut rgb)
            .on_hover_text(format!("Linear RGB {:.3}, {:.3}, {:.3}; click to pick a colour", v.x, v.y, v.z));
        let name = label.to_owned();
        ui.ctx().accesskit_node_builder(response.id, |node| node.set_label(name));
        if !marker.is_empty() {
            ui.weak(marker);
        }
        let changed = response.changed() && Vec3::from_array(rgb) != *v;
        if changed {
            *v = Vec3::from_array(rgb);
        }
        changed
    })
    .inner
}

fn channel_editor(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions, id: ChannelId, label: &str) {
    let Some(value) = ctx.value_now(id) else { return };
    let keyed_here = ctx.keyed_here(id);
    let marker = if ctx.session.overrides.contains_key(&id) {
        "posed, press I to key"
    } else if keyed_here {
        "(keyed)"
    } else {
        ""
    };
    let group = format!("inspector {id:?}");
    match value {
        ChannelValue::Vec3(mut v)
            if matches!(
                id,
                ChannelId::LightColour(_) | ChannelId::Attribute(AttributeId::ObjectColour(_))
            ) =>
        {
            if colour_editor(ui, label, marker, &mut v) && v.is_finite() {
                actions.edit(Edit::Pose { id, value: ChannelValue::Vec3(v), group });
            }
        }
        ChannelValue::Vec3(mut e)
            if matches!(id, ChannelId::ObjectEuler(_) | ChannelId::JointEuler { .. }) =>
        {
            // Euler keys: the angles themselves, typed as they are keyed (720 stays two turns).
            let change = vec3_editor(ui, label, marker, &mut e, 0.5);
            if change.any() && e.is_finite() {
                begin(actions, change);
                actions.edit(Edit::Pose { id, value: ChannelValue::Vec3(e), group });
            }
            rotation_mode_ui(ui, ctx, actions, id, rotation_mode(ctx.scene(), id));
        }
        ChannelValue::Vec3(mut v) => {
            let change = vec3_editor(ui, label, marker, &mut v, 0.01);
            if change.any() && v.is_finite() {
                begin(actions, change);
                actions.edit(Edit::Pose { id, value: ChannelValue::Vec3(v), group });
            }
        }
        ChannelValue::Rotation(q) => {
            let mode = rotation_mode(ctx.scene(), id);
            match mode.euler() {
                Some(order) => {
                    // Continuous from the channel's first key: a spin reads 0 → 360, not a flip.
                    let mut e = continuous_euler(
                        &ctx.evaluator(),
                        ctx.scene(),
                        id,
                        order,
                        ctx.time(),
                        &ctx.session.overrides,
                    )
                    .unwrap_or_else(|| order.angles(q));
                    let before = e;
                    let change = vec3_editor(ui, label, marker, &mut e, 0.5);
                    if change.any() && e.is_finite() {
                        begin(actions, change);
                        match euler_turn(order, before, e) {
                            // One angle changed: a turn about that angle's axis, so an angle
                            // typed a turn or more away (X 0 → 360) keys the spin that makes
                            // the curve read it, as the twist field does.
                            Some((axis, degrees)) => {
                                let turn = keyrig_edit::channels::Turn { from: q, axis, degrees };
                                actions.edit(Edit::Turn { id, turn, group: group.clone() });
                            }
                            None => {
                                let value = ChannelValue::Rotation(order.to_quat(e));
                                actions.edit(Edit::Pose { id, value, group: group.clone() });
                            }
                        }
                    }
                }
                None => {
                    let mut v = glam::Vec4::new(q.w, q.x, q.y, q.z);
                    let change = quat_editor(ui, label, marker, &mut v);
                    let q = glam::Quat::from_xyzw(v.y, v.z, v.w, v.x);
                    if change.any() && q.is_finite() && q.length() > 1e-6 {
                        begin(actions, change);
                        let value = ChannelValue::Rotation(q.normalize());
                        actions.edit(Edit::Pose { id, value, group: group.clone() });
                    }
                }
            }
            rotation_mode_ui(ui, ctx, actions, id, mode);
            if matches!(id, ChannelId::JointRotation { .. }) {
                twist_ui(ui, ctx, actions, id, q, &group);
            }
        }
        ChannelValue::Scalar(s) if id.is_visibility() => {
            // Visibility: a check box, keyed (Step) in record mode like any channel.
            let mut shown = s >= 0.5;
            let changed = ui
                .horizontal(|ui| {
                    let r = ui.checkbox(&mut shown, label);
                    ui.weak(marker);
                    r.changed()
                })
                .inner;
            if changed {
                actions.push(Action::CloseGroup);
                let value = ChannelValue::Scalar(if shown { 1.0 } else { 0.0 });
                actions.edit(Edit::Pose { id, value, group });
            }
        }
        ChannelValue::Scalar(s) if matches!(id, ChannelId::Attribute(AttributeId::Deformer(_))) => {
            let current = keyrig_core::attribute_id::deformer_from_value(s).unwrap_or_default();
            let mut chosen = current;
            ui.horizontal(|ui| {
                egui::ComboBox::from_label(label).selected_text(current.label()).show_ui(ui, |ui| {
                    for k in DeformerKind::ALL {
                        ui.selectable_value(&mut chosen, k, k.label());
                    }
                });
                ui.weak(marker);
            });
            if chosen != current {
                actions.push(Action::CloseGroup);
                let value = ChannelValue::Scalar(keyrig_core::attribute_id::deformer_value(chosen));
                actions.edit(Edit::Pose { id, value, group });
            }
        }
        ChannelValue::Scalar(mut s)
            if matches!(
                id,
                ChannelId::Attribute(
                    AttributeId::ObjectOpacity(_) | AttributeId::BlendParent(_) | AttributeId::BlendChild(_)
                ) | ChannelId::CameraAimInfluence(_)
                    | ChannelId::Constraint {
                        property: keyrig_core::channel_id::ConstraintProperty::Influence
                            | keyrig_core::channel_id::ConstraintProperty::Offset,
                        ..
                    }
            ) =>
        {
            let changed = ui
                .horizontal(|ui| {
                    let r = ui.add(egui::Slider::new(&mut s, 0.0..=1.0).text(label));
                    ui.weak(marker);
                    r
                })
                .inner;
            if changed.changed() && s.is_finite() {
                if changed.drag_stopped() || !changed.dragged() {
                    actions.push(Action::CloseGroup);
                }
                actions.edit(Edit::Pose { id, value: ChannelValue::Scalar(s), group });
            }
        }
        ChannelValue::Scalar(mut s) => {
            let changed = ui
                .horizontal(|ui| {
                    ui.label(label);
                    let (_, change) = number_field(ui, &mut s, label, |d| d.speed(0.05));
                    ui.weak(marker);
                    change
                })
                .inner;
            if changed.any() && s.is_finite() {
                begin(actions, changed);
                actions.edit(Edit::Pose { id, value: ChannelValue::Scalar(s), group });
            }
        }
    }
}

/// When the Euler angles `before` → `after` (degrees, `order`) differ in one angle only: the
/// axis (in the channel's parent frame) about which that change turns the rotation, and by how
/// many degrees. Changing one Euler angle by Δ turns the rotation by Δ about one fixed axis
/// (the angle's own axis carried by the rotations applied after it), so the change is a
/// [`keyrig_edit::channels::Turn`] from the rotation before.
fn euler_turn(
    order: keyrig_core::EulerOrder,
    before: glam::Vec3,
    after: glam::Vec3,
) -> Option<(glam::Vec3, f64)> {
    let changed: Vec<usize> = (0..3).filter(|&c| before[c] != after[c]).collect();
    let &[c] = changed.as_slice() else { return None };
    let degrees = f64::from(after[c]) - f64::from(before[c]);
    let mut step = before;
    step[c] += 10.0;
    let (axis, angle) = (order.to_quat(step) * order.to_quat(before).inverse()).normalize().to_axis_angle();
    // A 10° step: the angle is 10° about `axis` (or 350° about it, the other way round).
    let axis = if angle > std::f32::consts::PI { -axis } else { axis };
    (degrees.is_finite() && axis.is_finite() && axis.length() > 0.5).then_some((axis.normalize(), degrees))
}

/// The joint's twist about its bone axis (local +X) in degrees, unwrapped through spin keys
/// (it reads 720 after two turns). Typing a value turns the joint about the bone by the
/// difference; in record mode the key gets the spin that makes its segment turn that far.
fn twist_ui(
    ui: &mut Ui,
    ctx: &FrameCtx<'_>,
    actions: &mut Actions,
    id: ChannelId,
    q: glam::Quat,
    group: &str,
) {
    let Some(twist) = ctx.twist_now(id) else { return };
    let mut value = twist;
    let (response, change) = ui
        .horizontal(|ui| {
            ui.label("Twist (°)");
            let (response, change) =
                number_field(ui, &mut value, "Twist (°)", |d| d.speed(1.0).max_decimals(2));
            if let Some(turns) = crate::twist::turns_readout(twist) {
                ui.weak(turns);
            }
            (response, change)
        })
        .inner;
    response.on_hover_text(
        "Turn about the bone axis (the joint's X), in degrees, counting whole turns: \
         720 is two turns. In record mode the key turns that far from the previous key.",
    );
    let delta = value - twist;
    if change.any() && delta.is_finite() && delta != 0.0 {
        begin(actions, change);
        let axis = q * keyrig_edit::spin::BONE_AXIS;
        let turn = keyrig_edit::channels::Turn { from: q, axis, degrees: delta };
        actions.edit(Edit::Turn { id, turn, group: group.to_owned() });
    }
}

fn selection_ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
    let scene = ctx.scene();
    match ctx.session.selection.item {
        None => {
            ui.label("Nothing selected. Click an object, joint or light in the outliner or the viewport.");
        }
        Some(Selected::Camera(c)) => camera::camera_ui(ui, ctx, actions, c, channel_editor),
        Some(Selected::Object(o)) => {
            let name = scene.objects.get(o).map(|x| x.name.clone()).unwrap_or_default();
            ui.strong(format!("Object: {name}"));
            channel_editor(ui, ctx, actions, ChannelId::ObjectTranslation(o), "Translation");
            let rotation = keyrig_core::channel_id::rotation_or_euler(scene, ChannelId::ObjectRotation(o));
            channel_editor(ui, ctx, actions, rotation, "Rotation (°)");
            channel_editor(ui, ctx, actions, ChannelId::ObjectScale(o), "Scale");
            md2_ui(ui, ctx, actions, o);
            constraints::constraints_ui(ui, ctx, actions, o, channel_editor);
        }
        Some(Selected::Joint { object, joint }) => {
            let name = scene
                .objects
                .get(object)
                .and_then(|x| x.skeleton.as_ref())
                .and_then(|s| s.joints.get(joint))
                .map(|j| j.name.clone())
                .unwrap_or_default();
            ui.strong(format!("Joint: {name}"));
            let (moves, scales) = scene
                .objects
                .get(object)
                .and_then(|x| x.skeleton.as_ref())
                .and_then(|s| s.joints.get(joint))
                .map_or((false, false), |j| {
                    (
                        j.translation.is_animated() || j.translation.value != glam::Vec3::ZERO,
                        j.scale.is_animated() || j.scale.value != glam::Vec3::ONE,
                    )
                });
            if moves {
                channel_editor(
                    ui,
                    ctx,
                    actions,
                    ChannelId::JointTranslation { object, joint },
                    "Translation",
                );
            }
            let rotation =
                keyrig_core::channel_id::rotation_or_euler(scene, ChannelId::JointRotation { object, joint });
            channel_editor(ui, ctx, actions, rotation, "Rotation (°)");
            if scales {
                channel_editor(ui, ctx, actions, ChannelId::JointScale { object, joint }, "Scale");
            }
            ik_constraints_ui(ui, ctx, actions, object, joint);
            if ctx.session.ik.enabled {
                ik_chain_ui(ui, ctx, actions, object, joint);
            }
        }
        Some(Selected::Light(l)) => {
            let name = scene.lights.get(l).map(|x| x.name.clone()).unwrap_or_default();
            ui.strong(format!("Light: {name}"));
            for (id, label) in
                ChannelId::of_light(l).into_iter().zip(["Position", "Direction", "Colour", "Intensity"])
            {
                channel_editor(ui, ctx, actions, id, label);
            }
        }
    }
}

/// Starts animating an attribute (a constant channel at its current setting), one undo step.
fn set_attribute(actions: &mut Actions, what: Animate) {
    actions.push(Action::CloseGroup);
    actions.edit(Edit::continuous("attribute", SceneEdit::Animate(what)));
    actions.push(Action::CloseGroup);
}

/// The colour object `o` shows now without a colour channel: its material's base colour (a
/// model file's, with textures shown), else the renderer's palette colour for it.
fn shown_colour(ctx: &FrameCtx<'_>, o: usize) -> Vec3 {
    let material = match ctx.scene().objects.get(o).and_then(|x| x.mesh.as_ref()) {
        Some(keyrig_core::MeshSource::File { path, mesh, .. }) if ctx.view.textures => {
            ctx.meshes.material(ctx.base_dir(), path, *mesh)
        }
        _ => None,
    };
    match material {
        Some(m) => Vec3::new(m.base_colour[0], m.base_colour[1], m.base_colour[2]),
        None => keyrig_render::scene_frame::object_palette_colour(&ctx.evaluator(), o),
    }
}

/// An object's keyable attributes — visible, opacity, colour (once set), morph weights — under
/// a header that is open while any is set.
fn object_attributes_ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions, o: usize) {
    let Some(object) = ctx.scene().objects.get(o) else { return };
    egui::CollapsingHeader::new("Visibility and look")
        .id_salt(("object attributes", o))
        .default_open(!object.attributes.is_default())
        .show(ui, |ui| object_attributes_fields(ui, ctx, actions, o));
}

fn object_attributes_fields(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions, o: usize) {
    let Some(object) = ctx.scene().objects.get(o) else { return };
    let a = &object.attributes;
    let id = |a: AttributeId| ChannelId::Attribute(a);
    channel_editor(ui, ctx, actions, id(AttributeId::ObjectVisible(o)), "Visible");
    channel_editor(ui, ctx, actions, id(AttributeId::ObjectOpacity(o)), "Opacity");
    if a.colour.is_some() {
        channel_editor(ui, ctx, actions, id(AttributeId::ObjectColour(o)), "Colour");
    } else if object.mesh.is_some()
        && ui
            .button("Animate colour")
            .on_hover_text("Give the object a colour channel that replaces its material's base colour")
            .clicked()
    {
        set_attribute(actions, Animate::Colour { object: o, from: shown_colour(ctx, o) });
    }
    for target in 0..a.morph_weights.len() {
        let label = format!("Morph {target}");
        channel_editor(ui, ctx, actions, id(AttributeId::MorphWeight { object: o, target }), &label);
    }
}

/// A light's keyable attributes — visible, range and (spot lights) the cone — under a header
/// that is open while any is set.
fn light_attributes_ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions, l: usize) {
    let Some(light) = ctx.scene().lights.get(l) else { return };
    egui::CollapsingHeader::new("Visibility, range and cone")
        .id_salt(("light attributes", l))
        .default_open(!light.attributes.is_default())
        .show(ui, |ui| light_attributes_fields(ui, ctx, actions, l));
}

fn light_attributes_fields(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions, l: usize) {
    let Some(light) = ctx.scene().lights.get(l) else { return };
    let a = &light.attributes;
    let id = |a: AttributeId| ChannelId::Attribute(a);
    channel_editor(ui, ctx, actions, id(AttributeId::LightVisible(l)), "Visible");
    if a.range.is_some() {
        channel_editor(ui, ctx, actions, id(AttributeId::LightRange(l)), "Range");
    } else if !matches!(light.kind, keyrig_core::LightKind::Directional)
        && ui
            .button("Limit range")
            .on_hover_text("Give the light a range beyond which it has no effect")
            .clicked()
    {
        set_attribute(actions, Animate::LightRange { light: l, from: 10.0 });
    }
    if let keyrig_core::LightKind::Spot { cutoff_deg, inner_angle_deg, .. } = light.kind {
        if a.cutoff_deg.is_some() || a.inner_angle_deg.is_some() {
            channel_editor(ui, ctx, actions, id(AttributeId::LightCutoff(l)), "Cutoff (°)");
            channel_editor(ui, ctx, actions, id(AttributeId::LightInnerAngle(l)), "Inner angle (°)");
            if let Some(warning) = cone_warning(ctx, l) {
                ui.colored_label(ui.visuals().warn_fg_color, warning);
            }
        } else if ui.button("Animate cone").on_hover_text("Key the spot's cutoff and inner angles").clicked()
        {
            set_attribute(actions, Animate::Cone { light: l, cutoff_deg, inner_angle_deg });
        }
    }
}

/// The warning under a spot's cone fields when its cutoff is below its inner angle at this
/// frame (a key or a typed value can put it there): the light is then lit fully out to the
/// cutoff with a hard edge, the inner angle held to the cutoff (as the evaluator and the
/// renderer do), which is seldom what was meant. The values are kept as typed: the other
/// angle may be about to change.
fn cone_warning(ctx: &FrameCtx<'_>, l: usize) -> Option<String> {
    let scalar = |a| match ctx.value_now(ChannelId::Attribute(a)) {
        Some(ChannelValue::Scalar(s)) => Some(s),
        _ => None,
    };
    let cutoff = scalar(AttributeId::LightCutoff(l))?;
    let inner = scalar(AttributeId::LightInnerAngle(l))?;
    (cutoff < inner).then(|| {
        format!(
            "Warning: the cutoff ({cutoff:.1}°) is below the inner angle ({inner:.1}°): the cone is lit \
             fully out to the cutoff, with a hard edge (the inner angle is held to the cutoff)"
        )
    })
}

/// The IK constraints that end at the selected joint: name and chain, their target and blend
/// (keyable like any channel) and "Bake IK to keys".
fn ik_constraints_ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions, object: usize, joint: usize) {
    for c in keyrig_edit::ik::ending_at(ctx.scene(), object, joint) {
        let Some(constraint) = ctx
            .scene()
            .objects
            .get(object)
            .and_then(|o| o.skeleton.as_ref())
            .and_then(|s| s.ik_constraints.get(c))
            .cloned()
        else {
            continue;
        };
        ui.separator();
        ui.strong(format!("IK constraint: {}", constraint.name));
        ui.label(format!(
            "{} bones, {}",
            constraint.bones,
            if constraint.bones == 2 { "two-bone solver" } else { "FABRIK" }
        ));
        channel_editor(ui, ctx, actions, ChannelId::IkTarget { object, constraint: c }, "Target");
        channel_editor(ui, ctx, actions, ChannelId::IkBlend { object, constraint: c }, "IK/FK blend");
        if ui
            .button("Bake IK to keys")
            .on_hover_text(
                "Key the solved rotations of the chain's joints at every frame of the range and set \
                 the blend to 0 (one undo step)",
            )
            .clicked()
        {
            actions.push(Action::BakeIk { object, constraint: c });
        }
    }
}

/// IK posing's chain for the selected joint: its length in bones ("IK chain (bones)", from two
/// up to the skeleton's root), the joints it runs through and its solver, or why the joint
/// cannot be posed with IK.
fn ik_chain_ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions, object: usize, joint: usize) {
    ui.separator();
    ui.strong("IK posing");
    let scene = ctx.scene();
    let Some(skeleton) = scene.objects.get(object).and_then(|o| o.skeleton.as_ref()) else { return };
    // Joints above this one (parents come before their children in a valid skeleton).
    let mut above = 0;
    let mut j = joint;
    while let Some(p) = skeleton.joints.get(j).and_then(|x| x.parent).filter(|&p| p < j) {
        above += 1;
        j = p;
    }
    let asked = ctx.session.ik.chain_bones(object, joint);
    if above >= 2 {
        let mut bones = asked.clamp(2, above);
        let change = ui
            .horizontal(|ui| {
                ui.label("Chain (bones)");
                let (response, change) =
                    number_field(ui, &mut bones, "IK chain (bones)", |d| d.range(2..=above).speed(0.05));
                response.on_hover_text(
                    "How many bones above the selected joint the IK handle moves: 2 uses the \
                     two-bone solver (shoulder–elbow–wrist), more use FABRIK",
                );
                change
            })
            .inner;
        if change.any() && bones != asked {
            actions.session(SessionChange::ChainBones { object, joint, bones });
            let chain = ctx
                .pose(object)
                .map(|pose| crate::ik_posing::PosedChain::new(scene, pose, object, joint, bones));
            if let Some(Ok(chain)) = chain {
                actions.push(Action::Info(format!(
                    "IK chain: {} ({})",
                    chain.describe(),
                    chain.solver_label()
                )));
            }
        }
    }
    match ctx.ik_chain(object, joint) {
        Ok(chain) => {
            ui.label(format!("{} · {}", chain.describe(), chain.solver_label()));
            ui.weak(
                "Drag the orange handle at the joint in the viewport. The chain keeps the side it \
                 bends to when the drag starts; in record mode each of its joints is keyed.",
            );
            if ui
                .button("Keep as IK constraint")
                .on_hover_text(
                    "Add an IK constraint on this chain, its target keyed here at the current frame: \
                     the evaluator then solves the chain every frame",
                )
                .clicked()
            {
                actions.push(Action::KeepIk { object, joint });
            }
        }
        Err(e) => {
            ui.colored_label(ui.visuals().error_fg_color, e.to_string());
        }
    }
}

/// The clip and playback rate of a vertex-animated (MD2) object, edited through the document
/// (one undo step per clip choice, one per fps drag).
fn md2_ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions, o: usize) {
    let Some(keyrig_core::MeshSource::File { path, mesh, clip, fps }) =
        ctx.scene().objects.get(o).and_then(|x| x.mesh.clone())
    else {
        return;
    };
    // The frame's preparation loaded every model file the scene names.
    let clips: Vec<(String, usize)> = match ctx.meshes.peek(ctx.base_dir(), &path, mesh) {
        Some(crate::files::FileMesh::Morph(m)) => {
            m.clips().iter().map(|c| (c.name.clone(), c.frames.len())).collect()
        }
        _ => return,
    };
    ui.separator();
    ui.strong("Vertex animation (MD2)");
    let all_frames = "All frames";
    let mut chosen = clip.clone();
    let response = egui::ComboBox::from_label("Clip")
        .selected_text(chosen.as_deref().unwrap_or(all_frames))
        .show_ui(ui, |ui| {
            ui.selectable_value(&mut chosen, None, all_frames);
            for (name, frames) in &clips {
                ui.selectable_value(&mut chosen, Some(name.clone()), format!("{name} ({frames} frames)"));
            }
        })
        .response;
    response.on_hover_text("Which frame group of the model plays, looping over scene time");
    let mut rate = fps.unwrap_or(keyrig_core::MD2_DEFAULT_FPS);
    let rate_change = ui
        .horizontal(|ui| {
            ui.label("Rate (fps)");
            let (response, change) =
                number_field(ui, &mut rate, "Model fps", |d| d.speed(0.1).max_decimals(2));
            response.on_hover_text("Model frames per second (Quake 2 played its models at 10)");
            change
        })
        .inner;
    let frames = match clip.as_deref() {
        None => clips.iter().map(|(_, n)| n).sum::<usize>(),
        Some(name) => clips.iter().find(|(c, _)| c == name).map_or(0, |(_, n)| *n),
    };
    let seconds = frames as f64 / fps.unwrap_or(keyrig_core::MD2_DEFAULT_FPS);
    let timeline_frames = seconds * ctx.scene().fps;
    ui.weak(format!("One loop: {frames} model frames, {seconds:.2} s, {timeline_frames:.0} timeline frames"));
    if chosen != clip {
        actions.edit(Edit::scene(SceneEdit::ModelClip { object: o, clip: chosen }));
    }
    if rate_change == FieldChange::Dragged {
        rate = rate.clamp(0.1, 1000.0);
    }
    if rate_change.any() && !(rate.is_finite() && (0.1..=1000.0).contains(&rate)) {
        actions.push(Action::Error(format!("Model fps must be between 0.1 and 1000 (typed {rate})")));
    } else if rate_change.any() && Some(rate) != fps {
        begin(actions, rate_change);
        actions.edit(Edit::continuous("md2 fps", SceneEdit::ModelFps { object: o, fps: rate }));
    }
}

/// Interpolation mode names shown in the key inspector.
fn mode_label(mode: Interpolation) -> &'static str {
    match mode {
        Interpolation::Step => "Step",
        Interpolation::Linear => "Linear",
        Interpolation::Tcb => "TCB spline",
        Interpolation::Hermite => "Hermite (tangents)",
    }
}

fn key_inspector_ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
    ui.strong("Key");
    let keys: Vec<_> = ctx.session.selection.keys.iter().copied().collect();
    let Some(first) = keys.first().copied() else {
        ui.weak("No key selected. Click a diamond in the dope sheet.");
        return;
    };
    let scene = ctx.scene();
    let Some((time, mut mode, mut tcb)) = channels::key_params(scene, first.channel, first.index) else {
        return;
    };
    let fps = scene.fps.max(1e-9);
    let params: Vec<(f64, Interpolation, Tcb)> =
        keys.iter().filter_map(|k| channels::key_params(scene, k.channel, k.index)).collect();
    let describe = |k: &crate::session::KeyRef, time: f64| {
        format!("{} at frame {}", k.channel.label(scene), (time * fps).round() as i64)
    };
    if keys.len() == 1 {
        ui.label(describe(&first, time));
    } else {
        // Every selected key, and which values differ between them (shown as mixed; a change
        // applies the one value that moved to all of them).
        egui::CollapsingHeader::new(format!("{} keys selected (editing all)", keys.len()))
            .id_salt("selected keys")
            .show(ui, |ui| {
                egui::ScrollArea::vertical().max_height(120.0).show_rows(ui, 16.0, keys.len(), |ui, rows| {
                    for r in rows {
                        if let Some((t, _, _)) = params.get(r) {
                            ui.label(describe(&keys[r], *t));
                        }
                    }
                });
            });
    }
    let mixed = |f: &dyn Fn(&(f64, Interpolation, Tcb)) -> f32| params.iter().any(|p| f(p) != f(&params[0]));
    let mixed_mode = params.iter().any(|p| p.1 != params[0].1);
    let mixed_tension = mixed(&|p| p.2.tension);
    let mixed_continuity = mixed(&|p| p.2.continuity);
    let mixed_bias = mixed(&|p| p.2.bias);
    let mixed_clamped = params.iter().any(|p| p.2.clamped != params[0].2.clamped);
    let before = (mode, tcb);
    let shown_mode = if mixed_mode { "— mixed —" } else { mode_label(mode) };
    // One row: the interpolation and the key type (the section keeps its height).
    ui.horizontal(|ui| {
        let response = egui::ComboBox::from_id_salt("key interpolation")
            .selected_text(shown_mode)
            .show_ui(ui, |ui| {
                for m in [Interpolation::Step, Interpolation::Linear, Interpolation::Tcb] {
                    ui.selectable_value(&mut mode, m, mode_label(m));
                }
                // Hermite needs stored tangents (imported glTF CUBICSPLINE keys); it is only
                // offered for keys that already have it.
                if before.0 == Interpolation::Hermite {
                    ui.selectable_value(
                        &mut mode,
                        Interpolation::Hermite,
                        mode_label(Interpolation::Hermite),
                    );
                }
            })
            .response
            .on_hover_text("Interpolation: how the curve leaves this key");
        ui.ctx().accesskit_node_builder(response.id, |node| node.set_label("Interpolation"));
        key_type_ui(ui, ctx, actions, &keys);
    });
    let tcb_enabled = mode == Interpolation::Tcb;
    ui.add_enabled_ui(tcb_enabled, |ui| {
        tcb_slider_ui(
            ui,
            &mut tcb.tension,
            if mixed_tension { "Tension (mixed)" } else { "Tension" },
            "Tension: +1 tightens the curve at the key, −1 loosens it",
        );
        tcb_slider_ui(
            ui,
            &mut tcb.continuity,
            if mixed_continuity { "Continuity (mixed)" } else { "Continuity" },
            "Continuity: 0 is smooth; ±1 makes a corner at the key",
        );
        tcb_slider_ui(
            ui,
            &mut tcb.bias,
            if mixed_bias { "Bias (mixed)" } else { "Bias" },
            "Bias: −1 anticipates (overshoots before), +1 overshoots after the key",
        );
        // On one line with the reset, so the key section keeps its height.
        ui.horizontal(|ui| {
            ui.checkbox(&mut tcb.clamped, if mixed_clamped { "Clamped (mixed)" } else { "Clamped" })
                .on_hover_text(
                    "Keep the curve from overshooting this key: flat at a peak, a dip or a neighbour \
                     of the same value (two equal keys hold their value between them), limited \
                     elsewhere (Blender's auto-clamped handles)",
                );
            if ui.button("Reset T/C/B").on_hover_text("Catmull–Rom / Shoemake squad").clicked() {
                tcb = Tcb::ZERO;
            }
        });
    });
    if (mode, tcb) != before {
        let change = KeyParamChange::between(before, (mode, tcb));
        actions.edit(Edit::continuous("key inspector", SceneEdit::KeyParams { keys: keys.clone(), change }));
    }
    cycles_ui(ui, ctx, actions, first.channel);
}

/// The selected keys' type (keyframe, breakdown, moving hold, extreme: what they mean to the
/// animator, drawn in the dope sheet in their own shape; playback ignores it), shown as mixed
/// when they differ; choosing one sets it on every selected key, one undo step.
fn key_type_ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions, keys: &[crate::session::KeyRef]) {
    let scene = ctx.scene();
    let types: Vec<KeyType> =
        keys.iter().filter_map(|k| channels::key_type(scene, k.channel, k.index)).collect();
    let Some(&first) = types.first() else { return };
    let mixed = types.iter().any(|&t| t != first);
    let mut chosen = None;
    let response = egui::ComboBox::from_id_salt("key type")
        .selected_text(if mixed { "— mixed —" } else { first.label() })
        .show_ui(ui, |ui| {
            for t in KeyType::ALL {
                if ui.selectable_label(!mixed && t == first, t.label()).clicked() {
                    chosen = Some(t);
                }
            }
        })
        .response
        .on_hover_text(
            "Key type: what the key means to you (Blender's keyframe types); drawn in the dope \
             sheet, ignored by playback",
        );
    ui.ctx().accesskit_node_builder(response.id, |node| node.set_label("Key type"));
    if let Some(chosen) = chosen.filter(|&t| mixed || t != first) {
        actions.push(Action::CloseGroup);
        actions.edit(Edit::scene(SceneEdit::KeyType { keys: keys.to_vec(), key_type: chosen }));
    }
}

/// The channel's behaviour before its first key and after its last (cycles, docs/design.md §9): two
/// combo boxes, "Before keys" and "After keys", each an undoable edit of the channel of the
/// first selected key.
fn cycles_ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions, id: ChannelId) {
    let scene = ctx.scene();
    let Some(old) = channels::cycles(scene, id) else { return };
    let keyed = channels::key_count(scene, id) >= 2;
    ui.add_space(4.0);
    ui.strong("Channel cycles");
    let mut cycles = old;
    ui.add_enabled_ui(keyed, |ui| {
        for (label, cycle, hover) in [
            ("Before keys", &mut cycles.before, "What the channel does before its first key"),
            ("After keys", &mut cycles.after, "What the channel does after its last key"),
        ] {
            egui::ComboBox::from_label(label)
                .selected_text(cycle.label())
                .show_ui(ui, |ui| {
                    for c in Cycle::ALL {
                        ui.selectable_value(cycle, c, c.label()).on_hover_text(cycle_hover(c));
                    }
                })
                .response
                .on_hover_text(hover)
                .on_disabled_hover_text("A cycle needs at least two keys");
        }
    });
    if cycles != old {
        actions.edit(Edit::scene(SceneEdit::Cycles { channel: id, cycles }));
    }
}

fn cycle_hover(cycle: Cycle) -> &'static str {
    match cycle {
        Cycle::Hold => "Keep the end key's value",
        Cycle::Linear => "Continue at the end key's speed",
        Cycle::Repeat => "Play the keys again and again",
        Cycle::RepeatOffset => "Repeat, each cycle starting where the last ended (walks)",
        Cycle::PingPong => "Play the keys forwards, then backwards",
    }
}

fn deformer_ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
    ui.strong("Deformer");
    let Some(o) =
        ctx.selected_object().or_else(|| ctx.scene().objects.iter().position(|x| x.skeleton.is_some()))
    else {
        ui.weak("No skinned object.");
        return;
    };
    let Some(object) = ctx.scene().objects.get(o) else { return };
    if object.skeleton.is_none() {
        ui.weak(format!("{} has no skeleton.", object.name));
        return;
    }
    let mut settings = object.deformer;
    ui.label(format!("Object: {}", object.name));
    egui::ComboBox::from_label("Method").selected_text(settings.kind.label()).show_ui(ui, |ui| {
        for k in DeformerKind::ALL {
            ui.selectable_value(&mut settings.kind, k, k.label());
        }
    });
    let zone_keyed =
        object.attributes.blend_parent_fraction.is_some() || object.attributes.blend_child_fraction.is_some();
    if settings.kind == DeformerKind::BonesBlending && !zone_keyed {
        ui.add(egui::Slider::new(&mut settings.blend_parent_fraction, 0.0..=1.0).text("Zone into parent"))
            .on_hover_text("How far the blend zone reaches into the parent bone (fraction of its length)");
        ui.add(egui::Slider::new(&mut settings.blend_child_fraction, 0.0..=1.0).text("Zone into child"))
            .on_hover_text("How far the blend zone reaches into the child bone (fraction of its length)");
    }
    if settings.kind == DeformerKind::BonesBlending || object.attributes.deformer.is_some() || zone_keyed {
        blend_zone_channels(ui, ctx, actions, o, &settings);
    }
    // The deformer as a channel: keyed with Step keys, so one take can switch deformers.
    let keyed = ChannelId::Attribute(AttributeId::Deformer(o));
    if object.attributes.deformer.is_some() {
        channel_editor(ui, ctx, actions, keyed, "Keyed deformer");
    } else if ui
        .button("Animate deformer")
        .on_hover_text("Key the deformer (Step keys) to switch deformers during the animation")
        .clicked()
    {
        let value = keyrig_core::attribute_id::deformer_value(settings.kind);
        set_attribute(actions, Animate::Deformer { object: o, value });
    }
    measure_ui(ui, ctx);
    if settings != object.deformer {
        actions.edit(Edit::continuous("deformer settings", SceneEdit::Deformer { object: o, settings }));
    }
}

/// The bones-blending zone as channels: its two fractions keyed like any channel once
/// *Animate blend zone* made them channels (from the object's settings), so one take can
/// widen the zone while the arm twists.
fn blend_zone_channels(
    ui: &mut Ui,
    ctx: &FrameCtx<'_>,
    actions: &mut Actions,
    o: usize,
    settings: &keyrig_core::DeformerSettings,
) {
    let Some(object) = ctx.scene().objects.get(o) else { return };
    let a = &object.attributes;
    if a.blend_parent_fraction.is_some() || a.blend_child_fraction.is_some() {
        for (set, id, label) in [
            (a.blend_parent_fraction.is_some(), AttributeId::BlendParent(o), "Keyed zone into parent"),
            (a.blend_child_fraction.is_some(), AttributeId::BlendChild(o), "Keyed zone into child"),
        ] {
            if set {
                channel_editor(ui, ctx, actions, ChannelId::Attribute(id), label);
            }
        }
    } else if ui
        .button("Animate blend zone")
        .on_hover_text("Key the bones-blending zone's reach into the parent and child bones")
        .clicked()
    {
        let (parent, child) = (settings.blend_parent_fraction, settings.blend_child_fraction);
        set_attribute(actions, Animate::BlendZone { object: o, parent, child });
    }
}

/// The reference image's section, while the scene has one: its file, its opacity (one undo step
/// per drag), another image, or none.
fn reference_image_ui(ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
    let Some(image) = &ctx.scene().reference_image else { return };
    ui.strong("Reference image");
    let name = std::path::Path::new(&image.path)
        .file_name()
        .map_or_else(|| image.path.clone(), |n| n.to_string_lossy().into_owned());
    ui.label(name).on_hover_text(&image.path);
    let mut opacity = image.opacity;
    // The label on its own line: beside the slider it would widen the inspector.
    let label = ui.label("Reference opacity");
    let response = ui.add(egui::Slider::new(&mut opacity, 0.0..=1.0)).labelled_by(label.id);
    if response.changed() && opacity.is_finite() {
        actions.edit(Edit::continuous("reference opacity", SceneEdit::ReferenceOpacity(opacity)));
    }
    ui.horizontal(|ui| {
        if ui.button("Choose image…").clicked() {
            actions.push(Action::ChooseReferenceImage);
        }
        if ui.button("Remove reference image").clicked() {
            actions.edit(Edit::scene(SceneEdit::RemoveReferenceImage));
        }
    });
    ui.separator();
}
