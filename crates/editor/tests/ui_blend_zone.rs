//! The bones-blending zone keyed from the inspector (issue 31): *Animate blend zone* makes the
//! zone's two fractions channels, a field keys its channel in record mode at the current frame,
//! the dope sheet lists the row, the arm in the viewport deforms with the keyed zone, and undo
//! takes the key back.

mod common;

use common::{go_to_frame, harness, press, set_value};

use egui::accesskit::Role;
use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;
use keyrig_core::channel_id::ChannelId;
use keyrig_core::AttributeId;
use keyrig_editor::session::Selected;
use keyrig_skin::{deform_mesh_into, BlendZone, Deformed, Execution};

#[test]
fn the_blend_zone_keys_in_record_mode_and_reshapes_the_arm() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("forearm").click();
    h.run();
    assert_eq!(h.state().session.selection.item, Some(Selected::Joint { object: 0, joint: 2 }));
    h.get_by_label("Animate blend zone").click();
    h.run();
    let zone = |h: &egui_kittest::Harness<'_, keyrig_editor::EditorApp>| {
        let a = &h.state().doc.scene().objects[0].attributes;
        (a.blend_parent_fraction.clone(), a.blend_child_fraction.clone())
    };
    let (parent, child) = zone(&h);
    assert_eq!(parent.map(|p| p.value), Some(0.25), "from the arm's setting");
    assert_eq!(child.as_ref().map(|c| c.value), Some(0.25));

    h.get_by_label("⏺ Record").click();
    h.run();
    // Frame 60: the demo's forearm is turned 180°.
    go_to_frame(&mut h, 60);
    set_value(&mut h, Role::Slider, "Keyed zone into child", 0.6);
    let child = zone(&h).1.expect("the child fraction is a channel");
    let keys = &child.track.keys;
    assert_eq!(keys.len(), 1, "one key written");
    assert_eq!((keys[0].time, keys[0].value), (2.0, 0.6));
    // The dope sheet lists an object's attribute rows from `AttributeId::of_object`.
    assert!(
        AttributeId::of_object(h.state().doc.scene(), 0)
            .contains(&ChannelId::Attribute(AttributeId::BlendChild(0))),
        "a dope-sheet row"
    );

    // The viewport's skinned arm is the arm bound for the keyed zone.
    let app = h.state();
    let eval = app.evaluator();
    let skin = eval.skin(0).expect("skinned");
    let state = eval.object_at(0, 2.0, &Default::default()).expect("state");
    let bindings =
        skin.mesh.bindings(BlendZone { parent_fraction: 0.25, child_fraction: 0.6 }).expect("bindings");
    let mut expected = Deformed::default();
    deform_mesh_into(
        &skin.mesh,
        &bindings,
        state.palette.as_ref().expect("palette"),
        keyrig_core::DeformerKind::BonesBlending,
        Execution::Reference,
        &mut expected,
    )
    .expect("deform");
    let shown = app.skin_cache().deformed_positions(0).expect("the arm is skinned");
    let off = shown.iter().zip(&expected.positions).map(|(a, b)| a.distance(*b)).fold(0.0, f32::max);
    assert!(off < 1e-3, "the viewport's arm is {off} cm off the keyed zone's");

    press(&mut h, Modifiers::COMMAND, Key::Z);
    let child = zone(&h).1.expect("still a channel");
    assert!(child.track.keys.is_empty(), "undo takes the key back");
}
