//! Onion skinning in the GPU viewport, turned on as a user does (the O key, View ▸ Onion skin
//! settings): ghosts of the selected object are drawn, one draw per ghost, at the frames the
//! settings give; nothing is drawn without a selection or with the option off.

mod common;

use common::{go_to_frame, gpu_harness, press};

use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use keyrig_editor::onion::Spacing;
use keyrig_editor::EditorApp;

fn draw_calls(h: &Harness<'_, EditorApp>) -> u32 {
    h.state().gpu().and_then(|g| g.last_stats).expect("the GPU viewport drew a frame").draw_calls
}

#[test]
fn the_o_key_shows_ghosts_of_the_selected_object() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = gpu_harness(dir.path(), [1280.0, 800.0]);
    go_to_frame(&mut h, 30);
    let alone = draw_calls(&h);

    // On without a selection: nothing to ghost.
    press(&mut h, Modifiers::NONE, Key::O);
    assert!(h.state().view.onion.enabled);
    assert_eq!(draw_calls(&h), alone);

    // The arm selected in the outliner: two ghosts before and two after (every 5 frames).
    h.get_all_by_label("Arm")
        .min_by(|a, b| a.rect().left().total_cmp(&b.rect().left()))
        .expect("row")
        .click();
    h.run();
    let with_ghosts = draw_calls(&h);
    press(&mut h, Modifiers::NONE, Key::O);
    let selected = draw_calls(&h);
    assert_eq!(with_ghosts, selected + 4, "four ghosts, one draw each");
    press(&mut h, Modifiers::NONE, Key::O);
    assert_eq!(draw_calls(&h), selected + 4);

    // At the first frame there is nothing before it.
    go_to_frame(&mut h, 0);
    assert_eq!(draw_calls(&h), selected + 2);

    // Three after, at keys; off again: no ghosts.
    h.state_mut().view.onion.after = 3;
    h.state_mut().view.onion.spacing = Spacing::Keys;
    h.run();
    assert_eq!(draw_calls(&h), selected + 3);
    press(&mut h, Modifiers::NONE, Key::O);
    assert!(!h.state().view.onion.enabled);
    assert_eq!(draw_calls(&h), selected);
}
