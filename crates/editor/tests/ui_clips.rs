//! The clip editor (docs/clips.md): push the active action down as a strip, drag it, set its
//! blend in with its handle, reverse it from its menu, add a layer, save and read back — each
//! one undo step.

mod common;

use common::{drag, harness};

use egui::{Event, Modifiers, Pos2};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use keyrig_editor::EditorApp;

fn cube<'a>(h: &'a Harness<'_, EditorApp>) -> &'a keyrig_core::Object {
    h.state().doc.scene().objects.iter().find(|o| o.name == "Cube").expect("Cube")
}

fn click(h: &mut Harness<'_, EditorApp>, label: &str) {
    h.get_by_label(label).scroll_to_me();
    h.run();
    h.get_by_label(label).click();
    h.run();
}

const STRIP: &str = "strip Wave on track Track 1";

#[test]
fn the_clip_editor_pushes_down_drags_blends_and_saves_strips() {
    let dir = tempfile::tempdir().expect("temp dir");
    let file = dir.path().join("clips.ron");
    let mut scene = keyrig_io::demo::demo_scene();
    scene.name_unnamed_keys("Wave");
    keyrig_io::scene_file::save(&file, &scene).expect("save");
    let mut h = harness(dir.path(), Some(file.clone()));
    h.get_all_by_label("Cube").next().expect("the Cube in the outliner").click();
    h.run();
    click(&mut h, "Clips");

    // Push down: the Cube's keys become a strip of Wave over the frames they span.
    let steps = h.state().doc.undo_len();
    click(&mut h, "Push down");
    assert_eq!(h.state().doc.undo_len(), steps + 1);
    assert_eq!(h.state().doc.undo_label(), Some("push down the action of Cube"));
    assert_eq!(cube(&h).action, None);
    assert!(!cube(&h).translation.is_animated(), "the keys are stored in Wave");
    let strip = cube(&h).clip_tracks[0].strips[0].clone();
    assert_eq!((strip.action.as_str(), strip.start, strip.action_in), ("Wave", 0.0, 0.0));
    assert!(h.state().doc.scene().problems().is_empty());

    // Drag the strip's body to the right: it moves by whole frames, one undo step.
    let rect = h.get_by_label(STRIP).rect();
    let steps = h.state().doc.undo_len();
    drag(&mut h, rect.center(), rect.center() + egui::vec2(60.0, 0.0));
    let moved = cube(&h).clip_tracks[0].strips[0].clone();
    assert!(moved.start >= 1.0 && moved.start.fract() == 0.0, "moved to frame {}", moved.start);
    assert_eq!(
        (moved.action_in, moved.action_out),
        (strip.action_in, strip.action_out),
        "a move keeps the trim"
    );
    assert_eq!(h.state().doc.undo_len(), steps + 1);
    assert!(h.state().doc.undo_label().is_some_and(|l| l.starts_with("strip Wave at frames")));

    // The blend-in handle at the strip's top left: dragged right, the strip ramps in.
    let rect = h.get_by_label(STRIP).rect();
    let handle = Pos2::new(rect.left() + 2.0, rect.top() + 6.0);
    drag(&mut h, handle, handle + egui::vec2(40.0, 0.0));
    let blended = cube(&h).clip_tracks[0].strips[0].clone();
    assert!(blended.blend_in >= 1.0, "blend in {}", blended.blend_in);
    assert_eq!(blended.start, moved.start, "a blend drag does not move the strip");

    // Its menu reverses it.
    let at = h.get_by_label(STRIP).rect().center();
    h.event(Event::PointerMoved(at));
    for pressed in [true, false] {
        h.event(Event::PointerButton {
            pos: at,
            button: egui::PointerButton::Secondary,
            pressed,
            modifiers: Modifiers::NONE,
        });
    }
    h.run();
    click(&mut h, "Reverse");
    assert!(cube(&h).clip_tracks[0].strips[0].reverse);

    // A layer with its own action.
    click(&mut h, "New layer");
    h.event(Event::Text("Fix".to_owned()));
    h.run();
    click(&mut h, "Add layer");
    let scene = h.state().doc.scene();
    assert_eq!(scene.layers.len(), 1);
    assert!(scene.action_index(&scene.layers[0].action).is_some());
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());

    // Saved and read back as it is.
    h.state_mut().save_to(file.clone());
    let back = keyrig_io::scene_file::load(&file).expect("reads back");
    assert_eq!(&back, h.state().doc.scene());
}
