//! Views that follow and a tidy outliner (issue 30, item 4), with real pointer and wheel
//! events: a zoomed dope sheet and curve editor refit when an import grows the frame range and
//! keep the animator's zoom otherwise (undo, a frame change); imported models stand beside
//! what the scene holds instead of on top of it, each in one undo step; an object's skeleton
//! folds away in the outliner and stays folded for the session.

mod common;

use common::{corpus, harness, press};

use egui::{Event, Key, Modifiers, MouseWheelUnit, Pos2};
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use keyrig_editor::EditorApp;

fn wheel(h: &mut Harness<'_, EditorApp>, at: Pos2, modifiers: Modifiers) {
    h.event(Event::PointerMoved(at));
    h.event(Event::MouseWheel {
        unit: MouseWheelUnit::Line,
        delta: egui::vec2(0.0, 3.0),
        modifiers,
        phase: egui::TouchPhase::Move,
    });
    h.run();
}

fn import(h: &mut Harness<'_, EditorApp>, relative: &str) {
    h.input_mut()
        .dropped_files
        .push(egui::DroppedFile { path: Some(corpus(relative)), ..Default::default() });
    h.step();
    h.state_mut().wait_for_background_work();
    h.run();
}

/// Object `o`'s box as the viewport drew it last.
fn drawn_bounds(h: &Harness<'_, EditorApp>, o: usize) -> keyrig_editor::camera::Bounds {
    h.state().object_bounds().get(o).copied().flatten().unwrap_or_else(|| panic!("object {o} has bounds"))
}

#[test]
fn an_import_that_grows_the_range_refits_zoomed_views_and_stands_beside_the_scene() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    // The arm's elbow: its curves are shown.
    h.get_by_label("elbow").click();
    h.run();

    // Zoom the dope sheet (Ctrl+wheel over its keys) and the curves (wheel over the plot).
    let ctrl = Modifiers { ctrl: true, command: true, ..Modifiers::NONE };
    let sheet = h.get_by_label("↔ View all").rect().center() + egui::vec2(400.0, 40.0);
    wheel(&mut h, sheet, ctrl);
    let zoomed = h.state().dope_sheet_view();
    assert!(zoomed.end - zoomed.start < 80.0, "the dope sheet zoomed: {zoomed:?}");
    let plot = h.state().curves_rect().expect("laid out").center();
    wheel(&mut h, plot, Modifiers::NONE);
    let curves = h.state().panels().curves.view.expect("the curves zoomed");
    assert!(curves.end - curves.start < 80.0, "{curves:?}");

    // A frame change keeps both zooms.
    press(&mut h, Modifiers::NONE, Key::ArrowRight);
    assert_eq!(h.state().dope_sheet_view(), zoomed);
    assert_eq!(h.state().panels().curves.view, Some(curves));

    // Sydney's loop is longer than the demo's 90 frames: the range grows and both views show it.
    let demo = h.state().doc.scene().objects.len();
    let demo_box = (0..demo)
        .filter_map(|o| h.state().object_bounds().get(o).copied().flatten())
        .reduce(keyrig_editor::camera::Bounds::union);
    let demo_box = demo_box.expect("the demo has bounds");
    import(&mut h, "md2/sydney/sydney.md2");
    let end = h.state().doc.scene().frame_range.end;
    assert!(end > 90, "range end {end}");
    let view = h.state().dope_sheet_view();
    assert!(view.start <= 0.0 && view.end >= f64::from(end), "the dope sheet shows 0–{end}: {view:?}");
    assert_eq!(h.state().panels().curves.view, None, "the curves fit the grown range");
    let status = h.state().status().cloned().expect("a message");
    assert!(status.text.contains("placed beside the scene"), "{status:?}");

    // Sydney stands beside the demo, on the ground as her file puts her, not on top of it.
    let sydney = drawn_bounds(&h, demo);
    assert!(sydney.min.x > demo_box.max.x, "Sydney {sydney:?} is right of the demo {demo_box:?}");
    let gap = sydney.min.x - demo_box.max.x;
    assert!(
        gap < sydney.max.x - sydney.min.x + demo_box.max.x - demo_box.min.x,
        "beside, not far off: {gap}"
    );
    // A second model stands beside both.
    import(&mut h, "md2/faerie/faerie.md2");
    let faerie = drawn_bounds(&h, demo + 1);
    assert!(faerie.min.x > sydney.max.x, "the faerie {faerie:?} is right of Sydney {sydney:?}");

    // Zoomed again, an undo that shrinks the range leaves the zoom alone.
    wheel(&mut h, sheet, ctrl);
    let zoomed = h.state().dope_sheet_view();
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(h.state().doc.scene().objects.len(), demo + 1, "the faerie's import is one undo step");
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(h.state().doc.scene().objects.len(), demo, "and Sydney's, her move with it");
    assert_eq!(h.state().doc.scene().frame_range.end, 90);
    assert_eq!(h.state().dope_sheet_view(), zoomed, "a range that shrank keeps the zoom");
}

#[test]
fn a_skeleton_folds_away_in_the_outliner_for_the_session() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let name = h.state().doc.scene().objects[0].name.clone();
    assert!(h.query_by_label("wrist").is_some(), "the arm's joints are listed");
    h.get_by_label(&format!("fold the skeleton of {name}")).click();
    h.run();
    assert!(h.query_by_label("wrist").is_none(), "the skeleton folded away");
    assert!(h.state().panels().outliner.is_collapsed(&name));
    // The object stays listed (the outliner's entry is the leftmost of those named so) and
    // selects; a frame change and a selection leave the skeleton folded.
    let entry = h.query_all_by_label(&name).map(|n| n.rect().center()).min_by(|a, b| a.x.total_cmp(&b.x));
    let entry = entry.expect("the object stays listed");
    press(&mut h, Modifiers::NONE, Key::ArrowRight);
    h.event(Event::PointerMoved(entry));
    for pressed in [true, false] {
        h.event(Event::PointerButton {
            pos: entry,
            button: egui::PointerButton::Primary,
            pressed,
            modifiers: Modifiers::NONE,
        });
    }
    h.run();
    assert_eq!(h.state().session.selection.item, Some(keyrig_editor::session::Selected::Object(0)));
    assert!(h.query_by_label("wrist").is_none());
    h.get_by_label(&format!("unfold the skeleton of {name}")).click();
    h.run();
    assert!(h.query_by_label("wrist").is_some(), "the skeleton shows again");
}

#[test]
fn h_hides_the_selection_in_the_viewport_and_alt_h_shows_it() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let wrist = common::on_screen(h.state(), common::joint_world(h.state(), 0, 3));
    // A joint selected: H hides its object and deselects it.
    h.get_by_label("wrist").click();
    h.run();
    press(&mut h, Modifiers::NONE, Key::H);
    let scene = h.state().doc.scene().clone();
    assert!(h.state().session.hidden.object(&scene, 0), "the arm is hidden");
    assert_eq!(h.state().session.selection.item, None);
    assert!(!h.state().doc.is_dirty(), "hiding is not an edit of the scene");
    // A click on the hidden wrist selects nothing.
    let click = |h: &mut Harness<'_, EditorApp>, at: Pos2| {
        h.event(Event::PointerMoved(at));
        for pressed in [true, false] {
            h.event(Event::PointerButton {
                pos: at,
                button: egui::PointerButton::Primary,
                pressed,
                modifiers: Modifiers::NONE,
            });
        }
        h.run();
    };
    click(&mut h, wrist);
    assert_eq!(h.state().session.selection.item, None, "a hidden joint is not picked");
    // The outliner still selects it; Alt+H shows it, and the click picks the wrist again.
    assert!(h.query_by_label("wrist").is_some());
    press(&mut h, Modifiers::ALT, Key::H);
    assert!(h.state().session.hidden.is_empty());
    let status = h.state().status().cloned().expect("a message");
    assert!(status.text.contains("Showed 1 hidden object"), "{status:?}");
    click(&mut h, wrist);
    assert_eq!(
        h.state().session.selection.item,
        Some(keyrig_editor::session::Selected::Joint { object: 0, joint: 3 }),
        "shown again, the wrist is picked"
    );
}

#[test]
fn the_preview_range_keeps_playback_home_and_end_to_its_frames_and_is_saved() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    common::go_to_frame(&mut h, 30);
    // Ctrl+Alt+P with no key selected: from the current frame to the range's end.
    press(&mut h, Modifiers::COMMAND.plus(Modifiers::ALT), Key::P);
    let range = |start, end| keyrig_core::FrameRange { start, end };
    assert_eq!(h.state().doc.scene().preview_range, Some(range(30, 90)));
    // The End field of the preview range, typed as a screen reader sets it.
    common::set_value(&mut h, egui::accesskit::Role::SpinButton, "Preview end", 45.0);
    assert_eq!(h.state().doc.scene().preview_range, Some(range(30, 45)));
    assert_eq!(h.state().doc.undo_label(), Some("preview range 30–45"));

    // Playing (every frame: one frame a step) loops over 30–45 only.
    h.get_by_label("Every frame").click();
    h.run();
    h.key_press(Key::Space);
    let mut seen = std::collections::BTreeSet::new();
    for _ in 0..120 {
        h.step();
        seen.insert(h.state().session.playback.whole_frame());
    }
    assert!(h.state().session.playback.playing);
    h.key_press(Key::Space);
    h.run();
    assert!(seen.iter().all(|f| (30..=45).contains(f)), "played frames {seen:?}");
    assert!(seen.contains(&31) && seen.contains(&44), "it went round: {seen:?}");
    // Home and End go to its ends.
    press(&mut h, Modifiers::NONE, Key::End);
    assert_eq!(h.state().session.playback.whole_frame(), 45);
    press(&mut h, Modifiers::NONE, Key::Home);
    assert_eq!(h.state().session.playback.whole_frame(), 30);

    // Saved with the scene; a scene without one writes no field.
    let text = keyrig_io::scene_file::to_string(h.state().doc.scene()).expect("saved");
    let compact: String = text.split_whitespace().collect();
    assert!(compact.contains("preview_range:Some((start:30,end:45,))"), "{text}");
    let reread = keyrig_io::scene_file::from_str(&text, std::path::Path::new("p.ron")).expect("read");
    assert_eq!(reread.preview_range, Some(range(30, 45)));
    // Ctrl+Alt+P again clears it (an undo step), and Home goes to the range's start again.
    press(&mut h, Modifiers::COMMAND.plus(Modifiers::ALT), Key::P);
    assert_eq!(h.state().doc.scene().preview_range, None);
    let text = keyrig_io::scene_file::to_string(h.state().doc.scene()).expect("saved");
    assert!(!text.contains("preview_range"), "{text}");
    press(&mut h, Modifiers::NONE, Key::Home);
    assert_eq!(h.state().session.playback.whole_frame(), 0);
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(h.state().doc.scene().preview_range, Some(range(30, 45)), "undo brings it back");
}

#[test]
fn the_add_menu_adds_primitives_empties_and_lights_where_the_view_looks() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let (objects, lights) = (h.state().doc.scene().objects.len(), h.state().doc.scene().lights.len());
    let target = h.state().view.camera.target;
    let add = |h: &mut Harness<'_, EditorApp>, entry: &str| {
        h.get_by_label("Add").click();
        h.run();
        // The menu's entry: the popup is the last layer (an added "Sphere" is also listed in
        // the outliner and the dope sheet).
        let target = h.query_all_by_label(entry).last().expect("the menu entry").rect().center();
        common::pointer(h, Event::PointerMoved(target));
        for pressed in [true, false] {
            common::pointer(
                h,
                Event::PointerButton {
                    pos: target,
                    button: egui::PointerButton::Primary,
                    pressed,
                    modifiers: Modifiers::NONE,
                },
            );
        }
    };
    add(&mut h, "Sphere");
    let scene = h.state().doc.scene();
    assert_eq!(scene.objects.len(), objects + 1);
    let sphere = &scene.objects[objects];
    assert_eq!(sphere.name, "Sphere");
    assert_eq!(sphere.mesh, Some(keyrig_core::MeshSource::Procedural(keyrig_core::ProceduralMesh::Sphere)));
    assert_eq!(sphere.translation.value, target);
    assert_eq!(h.state().session.selection.item, Some(keyrig_editor::session::Selected::Object(objects)));
    assert_eq!(h.state().doc.undo_label(), Some("add sphere Sphere"));
    // The viewport skinned and drew it: it has bounds about the target, 1 unit from pole to
    // pole (and within 0.5 % of it across: its rings miss the equator).
    let bounds = drawn_bounds(&h, objects);
    assert!((bounds.max.y - bounds.min.y - 1.0).abs() < 1e-3, "{bounds:?}");
    assert!((bounds.max.x - bounds.min.x - 1.0).abs() < 5e-3, "{bounds:?}");
    assert!((((bounds.min + bounds.max) * 0.5) - target).length() < 1e-3, "{bounds:?}");

    // A second sphere gets a free name; an empty and a spot light.
    add(&mut h, "Sphere");
    assert_eq!(h.state().doc.scene().objects[objects + 1].name, "Sphere.001");
    add(&mut h, "Empty");
    assert_eq!(h.state().doc.scene().objects[objects + 2].mesh, None);
    add(&mut h, "Spot light");
    let scene = h.state().doc.scene();
    assert_eq!(scene.lights.len(), lights + 1);
    assert!(matches!(scene.lights[lights].kind, keyrig_core::LightKind::Spot { .. }));
    assert_eq!(h.state().session.selection.item, Some(keyrig_editor::session::Selected::Light(lights)));
    // Each is one undo step.
    for _ in 0..4 {
        press(&mut h, Modifiers::COMMAND, Key::Z);
    }
    assert_eq!(h.state().doc.scene().objects.len(), objects);
    assert_eq!(h.state().doc.scene().lights.len(), lights);
}
