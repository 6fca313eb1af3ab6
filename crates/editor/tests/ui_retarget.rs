//! Edit ▸ Retarget… (docs/retargeting.md) on CesiumMan: the shortcut opens the window, the CMU
//! 131 take is read and mapped from the joints' names, Apply makes the new action in one undo
//! step, and undo gives the scene back exactly.

mod common;

use common::{corpus, harness, press};

use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;

#[test]
fn retarget_the_cmu_walk_onto_cesium_man_in_one_undo_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), Some(corpus("gltf/CesiumMan/CesiumMan.glb")));
    h.state_mut().wait_for_background_work();
    h.run();
    let original = h.state().doc.scene().clone();

    press(&mut h, Modifiers::COMMAND.plus(Modifiers::ALT), Key::R);
    let take = corpus("bvh/cmu-bvh11/131_01.bvh");
    h.get_by_label("Source file").click();
    h.run();
    h.get_by_label("Source file").type_text(take.to_str().unwrap());
    h.run();
    h.get_by_label("Read").click();
    h.run();
    h.get_by_label_contains("19 pairs");
    h.get_by_label("Apply").click();
    h.run();
    let scene = h.state().doc.scene();
    assert_eq!(scene.objects[0].action.as_deref(), Some("131_01"));
    assert!(scene.action_index("animation0").is_some());
    let head = &scene.objects[0].skeleton.as_ref().unwrap().joints[14];
    assert_eq!(head.rotation.track.len(), 994);
    assert_eq!(h.state().doc.undo_label(), Some("retarget 131_01 onto Cesium_Man"));

    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert!(*h.state().doc.scene() == original, "undo gives the scene back exactly");
}
