//! Light colours are edited with a colour picker (not X/Y/Z fields), with the same pose /
//! record / undo behaviour as every other inspector field.

mod common;

use common::{harness, press};

use egui::accesskit::{Action, ActionData, ActionRequest, Role};
use egui::{Event, Key, Modifiers};
use egui_kittest::kittest::{NodeT, Queryable};
use egui_kittest::Harness;
use glam::Vec3;
use keyrig_edit::channels::{self, ChannelId, ChannelValue};
use keyrig_editor::EditorApp;

/// The demo's first light, `Key`.
const KEY_COLOUR: ChannelId = ChannelId::LightColour(0);

fn colour_now(h: &Harness<'_, EditorApp>) -> Vec3 {
    match h.state().value_now(KEY_COLOUR) {
        Some(ChannelValue::Vec3(v)) => v,
        other => panic!("light colour: {other:?}"),
    }
}

/// Opens the picker of the light's colour and sets its red component (0–255, sRGB-encoded as
/// egui's picker shows it) through the picker's own drag value, as a screen reader would.
fn pick_red(h: &mut Harness<'_, EditorApp>, red: f64) {
    h.get_by_role_and_label(Role::ColorWell, "Colour").click();
    h.run();
    let (target_node, target_tree) = {
        let red_field = h
            .get_all_by_role(Role::SpinButton)
            .find(|n| n.value().is_some_and(|v| v.starts_with("R ")))
            .expect("the picker's R field");
        red_field.accesskit_node().locate()
    };
    h.event(Event::AccessKitActionRequest(ActionRequest {
        action: Action::SetValue,
        target_node,
        target_tree,
        data: Some(ActionData::NumericValue(red)),
    }));
    h.run();
    press(h, Modifiers::NONE, Key::Escape);
}

#[test]
fn a_light_colour_is_a_colour_picker_with_pose_record_and_undo() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    // The outliner's row (the dope sheet has a `Key` row too).
    h.get_all_by_label("Key").next().expect("the Key light in the outliner").click();
    h.run();
    assert_eq!(h.state().session.selection.item, Some(keyrig_editor::session::Selected::Light(0)));
    assert!(h.query_by_label("Colour X").is_none(), "no X/Y/Z fields for a colour");
    assert!(h.query_by_role_and_label(Role::ColorWell, "Colour").is_some(), "a colour button");
    let before = colour_now(&h);
    assert!(before.x > 0.5, "the demo's key light is not dark red already: {before}");

    // Without record mode the unkeyed colour is set in the document (as any unkeyed field),
    // as one undo step.
    assert_eq!(channels::key_count(h.state().doc.scene(), KEY_COLOUR), 0);
    pick_red(&mut h, 0.0);
    let picked = colour_now(&h);
    assert!(picked.x < 1e-3, "red picked to 0: {picked}");
    assert!((picked.y - before.y).abs() < 0.01 && (picked.z - before.z).abs() < 0.01, "{before} → {picked}");
    assert!(h.state().doc.scene().lights[0].colour.value.x < 1e-3, "the document holds it");
    assert_eq!(channels::key_count(h.state().doc.scene(), KEY_COLOUR), 0, "no key without record");
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert!((colour_now(&h) - before).length() < 1e-4, "undo restores the colour");

    // With record mode: a key at the current frame, undone by Ctrl+Z.
    h.get_by_label("⏺ Record").click();
    h.run();
    assert!(h.state().session.record);
    pick_red(&mut h, 0.0);
    assert_eq!(channels::key_count(h.state().doc.scene(), KEY_COLOUR), 1, "record keys the colour");
    assert!(colour_now(&h).x < 1e-3);
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(channels::key_count(h.state().doc.scene(), KEY_COLOUR), 0, "undo removes the key");
    assert!((colour_now(&h) - before).length() < 1e-4, "undo restores the colour");
}

/// Issue 42, 4: *Animate colour* starts the channel at the colour the object shows — the
/// demo's Cube stays the renderer's blue, not a white-grey — one undo step.
#[test]
fn animate_colour_keeps_the_colour_the_object_shows() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("Cube").click();
    h.run();
    let shown = keyrig_render::scene_frame::object_palette_colour(&h.state().evaluator(), 1);
    assert_eq!(shown, Vec3::new(0.35, 0.55, 0.8), "the Cube is drawn the palette's blue");
    let steps = h.state().doc.undo_len();
    if h.query_by_label("Visibility and look").is_some() && h.query_by_label("Animate colour").is_none() {
        h.get_by_label("Visibility and look").click();
        h.run();
    }
    // The inspector's sections above (constraints, key) may put it below the fold.
    h.get_by_label("Animate colour").scroll_to_me();
    h.run();
    h.get_by_label("Animate colour").click();
    h.run();
    let colour = h.state().doc.scene().objects[1].attributes.colour.as_ref().map(|c| c.value);
    assert_eq!(colour, Some(shown), "the channel starts at the colour shown");
    assert_eq!(h.state().doc.undo_len(), steps + 1);
    assert_eq!(h.state().doc.undo_label(), Some("animate colour"));
}

/// Issue 42, 12: a spot cone whose cutoff goes below its inner angle was accepted silently.
/// The values stay as typed (the other angle may be about to follow), and the inspector says
/// under the cone's fields what the light does then: lit fully out to the cutoff, a hard edge.
#[test]
fn a_spot_cutoff_below_its_inner_angle_is_warned_in_the_inspector() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    // The outliner's row (the dope sheet has a `Key` row too).
    h.get_all_by_label("Key").next().expect("the Key light in the outliner").click();
    h.run();
    if h.query_by_label("Animate cone").is_none() {
        h.get_by_label("Visibility, range and cone").click();
        h.run();
    }
    h.get_by_label("Animate cone").click();
    h.run();
    let warning = "is below the inner angle";
    assert!(h.query_by_label_contains(warning).is_none(), "the demo's cone is sound");
    let inner = match h.state().value_now(ChannelId::Attribute(keyrig_core::AttributeId::LightInnerAngle(0)))
    {
        Some(ChannelValue::Scalar(s)) => s,
        other => panic!("an inner angle: {other:?}"),
    };
    common::set_value(&mut h, Role::SpinButton, "Cutoff (°)", f64::from(inner) - 5.0);
    let cutoff = h.state().value_now(ChannelId::Attribute(keyrig_core::AttributeId::LightCutoff(0)));
    assert_eq!(cutoff, Some(ChannelValue::Scalar(inner - 5.0)), "the typed cutoff is kept");
    assert!(h.query_by_label_contains(warning).is_some(), "the inspector warns");
    assert!(h.query_by_label_contains("with a hard edge").is_some(), "and says what the light does");
    common::set_value(&mut h, Role::SpinButton, "Cutoff (°)", f64::from(inner) + 5.0);
    assert!(h.query_by_label_contains(warning).is_none(), "gone once the cone is sound again");
}
