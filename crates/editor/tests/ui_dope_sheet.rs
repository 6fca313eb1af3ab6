//! The dope sheet on a character, used as an animator does with real pointer and wheel events:
//! rows in hierarchy order, collapsing groups, summary keys that select and move every key
//! beneath them, keys out of view, zooming and panning the time axis, and a motion-capture
//! track drawn one mark per pixel.

mod common;

use common::{drag, harness, press};

use egui::{Event, Key, Modifiers, MouseWheelUnit, Pos2};
use egui_kittest::kittest::{NodeT, Queryable};
use egui_kittest::Harness;
use glam::{Quat, Vec3};
use keyrig_core::{FrameRange, Joint, Key as SceneKey, Object, RawTrack, Scene, Skeleton};
use keyrig_edit::channels::{self, ChannelId};
use keyrig_editor::session::KeyRef;
use keyrig_editor::EditorApp;

/// Two legs whose joints are stored in an order that is not the hierarchy's (hip, both knees,
/// then both feet): rotation keys at frames 0, 30 and 60 on every joint, the left knee's
/// translation keyed too (a group of two channels), and a right-foot key at frame 120, after
/// the 0–60 range.
fn legs_scene() -> Scene {
    let mut scene = Scene { fps: 30.0, frame_range: FrameRange { start: 0, end: 60 }, ..Scene::default() };
    let names =
        [("hip", None), ("l_knee", Some(0)), ("r_knee", Some(0)), ("l_foot", Some(1)), ("r_foot", Some(2))];
    let mut joints: Vec<Joint> = names
        .iter()
        .map(|&(name, parent)| Joint::new(name, parent, Vec3::new(0.0, -1.0, 0.0), Quat::IDENTITY))
        .collect();
    for (j, joint) in joints.iter_mut().enumerate() {
        let mut keys: Vec<SceneKey<Quat>> = [0.0, 1.0, 2.0]
            .iter()
            .map(|&t| SceneKey::new(t, Quat::from_rotation_x(0.2 * t as f32 + j as f32 * 0.1)))
            .collect();
        if joint.name == "r_foot" {
            keys.push(SceneKey::new(4.0, Quat::from_rotation_x(0.9)));
        }
        joint.rotation.track = RawTrack::new(keys);
    }
    joints[1].translation.track = RawTrack::new(vec![
        SceneKey::new(0.0, Vec3::ZERO),
        SceneKey::new(1.0, Vec3::new(0.0, 0.1, 0.0)),
        SceneKey::new(2.0, Vec3::ZERO),
    ]);
    let mut legs = Object::new("legs");
    legs.skeleton = Some(Skeleton::new(joints));
    scene.objects.push(legs);
    scene
}

fn open(dir: &std::path::Path, scene: &Scene) -> Harness<'static, EditorApp> {
    let path = dir.join("scene.ron");
    keyrig_io::scene_file::save(&path, scene).expect("write the scene");
    harness(dir, Some(path))
}

/// The dope sheet's row names, top to bottom.
fn row_labels(h: &Harness<'_, EditorApp>) -> Vec<String> {
    let mut rows: Vec<(f32, String)> = h
        .get_all_by_role(egui::accesskit::Role::Row)
        .filter_map(|n| {
            let label = n.accesskit_node().label()?;
            Some((n.rect().top(), label.strip_prefix("dope sheet row ")?.to_owned()))
        })
        .collect();
    rows.sort_by(|a, b| a.0.total_cmp(&b.0));
    rows.into_iter().map(|(_, l)| l).collect()
}

fn rotation(joint: usize) -> ChannelId {
    ChannelId::JointRotation { object: 0, joint }
}

fn frames(h: &Harness<'_, EditorApp>, id: ChannelId) -> Vec<i64> {
    let scene = h.state().doc.scene();
    channels::key_times(scene, id).iter().map(|t| (t * scene.fps).round() as i64).collect()
}

#[test]
fn rows_follow_the_hierarchy_and_groups_collapse() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = open(dir.path(), &legs_scene());
    assert_eq!(
        row_labels(&h),
        [
            "legs",
            "hip rotation",
            "l_knee",
            "translation",
            "rotation",
            "l_foot rotation",
            "r_knee rotation",
            "r_foot rotation"
        ],
        "children follow their parent, whatever the file's order"
    );
    h.get_by_label("collapse l_knee").click();
    h.run();
    assert_eq!(
        row_labels(&h),
        ["legs", "hip rotation", "l_knee", "l_foot rotation", "r_knee rotation", "r_foot rotation"]
    );
    // The collapsed group still shows its keys: two channels at frame 30.
    assert!(h.query_by_label("keys l_knee frame 30 (2)").is_some());
    h.get_by_label("collapse legs").click();
    h.run();
    assert_eq!(row_labels(&h), ["legs"]);
    h.get_by_label("expand legs").click();
    h.run();
    h.get_by_label("expand l_knee").click();
    h.run();
    assert_eq!(row_labels(&h).len(), 8);
}

#[test]
fn a_summary_key_selects_and_moves_every_key_beneath_it_in_one_undo_step() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = open(dir.path(), &legs_scene());
    let original = h.state().doc.scene().clone();
    // Frame 30 holds six keys beneath the object: five rotations and the knee's translation.
    h.get_by_label("keys legs frame 30 (6)").click();
    h.run();
    assert_eq!(h.state().session.selection.keys.len(), 6);
    assert!(h.state().session.selection.keys.iter().all(|k| k.index == 1));

    let at_30 = h.get_by_label("keys legs frame 30 (6)").rect().center();
    let at_60 = h.get_by_label("keys legs frame 60 (6)").rect().center();
    let per_frame = (at_60.x - at_30.x) / 30.0;
    drag(&mut h, at_30, at_30 + egui::vec2(per_frame * 5.0, 0.0));
    for joint in 0..5 {
        assert_eq!(frames(&h, rotation(joint))[..3], [0, 35, 60], "joint {joint}");
    }
    assert_eq!(frames(&h, ChannelId::JointTranslation { object: 0, joint: 1 }), [0, 35, 60]);
    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(h.state().doc.scene(), &original, "the whole drag is one undo step");
}

#[test]
fn keys_out_of_view_are_counted_and_a_click_brings_them_into_view() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = open(dir.path(), &legs_scene());
    // Frame 120 lies after the 0–60 range the sheet shows: counted, not drawn.
    assert!(h.query_by_label("key r_foot rotation frame 120").is_none());
    h.get_by_label("r_foot rotation: 1 key after the view").click();
    h.run();
    let view = h.state().dope_sheet_view();
    assert!(view.start < 120.0 && view.end > 120.0, "the key comes into view: {view:?}");
    assert!(h.query_by_label("key r_foot rotation frame 120").is_some());

    // View all shows the range and every key.
    h.get_by_label("↔ View all").click();
    h.run();
    let view = h.state().dope_sheet_view();
    assert!(view.start <= 0.0 && view.end >= 120.0, "{view:?}");
    assert!(h.query_by_label("key hip rotation frame 0").is_some());
    assert!(h.query_by_label("key r_foot rotation frame 120").is_some());
}

fn wheel(h: &mut Harness<'_, EditorApp>, at: Pos2, delta: egui::Vec2, modifiers: Modifiers) {
    h.event(Event::PointerMoved(at));
    h.event(Event::MouseWheel {
        unit: MouseWheelUnit::Line,
        delta,
        modifiers,
        phase: egui::TouchPhase::Move,
    });
    h.run();
}

#[test]
fn ctrl_wheel_zooms_about_the_pointer_and_shift_wheel_pans() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = open(dir.path(), &legs_scene());
    let before = h.state().dope_sheet_view();
    let at_30 = h.get_by_label("key hip rotation frame 30").rect().center();
    let ctrl = Modifiers { ctrl: true, command: true, ..Modifiers::NONE };
    wheel(&mut h, at_30, egui::vec2(0.0, 3.0), ctrl);
    let zoomed = h.state().dope_sheet_view();
    assert!(zoomed.end - zoomed.start < 0.8 * (before.end - before.start), "{before:?} → {zoomed:?}");
    // Frame 30 stays under the pointer.
    let moved = h.get_by_label("key hip rotation frame 30").rect().center();
    assert!((moved.x - at_30.x).abs() < 1.0, "frame 30 at {} then {}", at_30.x, moved.x);
    // Zoomed in, frame 0 is out of view and counted instead.
    assert!(h.query_by_label("key hip rotation frame 0").is_none());
    assert!(h.query_by_label("hip rotation: 1 key before the view").is_some());

    let shift = Modifiers { shift: true, ..Modifiers::NONE };
    wheel(&mut h, at_30, egui::vec2(0.0, 2.0), shift);
    let panned = h.state().dope_sheet_view();
    assert!((panned.end - panned.start - (zoomed.end - zoomed.start)).abs() < 1e-6, "panning keeps the zoom");
    assert!(panned.start != zoomed.start, "Shift+wheel pans: {zoomed:?} → {panned:?}");
}

#[test]
fn the_name_column_is_resized_by_dragging_its_border() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = open(dir.path(), &legs_scene());
    let row = h.get_by_label("dope sheet row hip rotation").rect();
    let key_before = h.get_by_label("key hip rotation frame 0").rect().center();
    let border = Pos2::new(row.right(), row.center().y);
    drag(&mut h, border, border + egui::vec2(60.0, 0.0));
    let wider = h.get_by_label("dope sheet row hip rotation").rect();
    assert!((wider.width() - row.width() - 60.0).abs() < 2.0, "{} → {}", row.width(), wider.width());
    let key_after = h.get_by_label("key hip rotation frame 0").rect().center();
    assert!((key_after.x - key_before.x - 60.0).abs() < 2.0, "the keys move right with the border");
}

/// A 5,000-key track: more keys than pixels. Keys on one pixel are one mark (and one
/// accessible node), and a click selects every key on that pixel.
#[test]
fn a_motion_capture_track_is_drawn_one_mark_per_pixel() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut scene = Scene { fps: 30.0, frame_range: FrameRange { start: 0, end: 4999 }, ..Scene::default() };
    let mut cube = Object::new("mocap");
    cube.translation.track = RawTrack::new(
        (0..5000).map(|k| SceneKey::new(f64::from(k) / 30.0, Vec3::new(0.0, k as f32, 0.0))).collect(),
    );
    scene.objects.push(cube);
    let mut h = open(dir.path(), &scene);
    let marks: Vec<(String, egui::Rect)> = h
        .get_all_by_role(egui::accesskit::Role::Button)
        .filter_map(|n| {
            let label = n.accesskit_node().label()?;
            label.starts_with("keys mocap translation").then(|| (label, n.rect()))
        })
        .collect();
    let ruler = h.get_by_label("dope sheet row translation").rect();
    assert!(!marks.is_empty(), "the track's keys are drawn");
    assert!(
        marks.len() as f32 <= 1280.0 - ruler.right(),
        "{} marks for 5,000 keys: at most one per pixel column",
        marks.len()
    );
    // Every mark stands for the keys of its pixel; together they are every key in view.
    let total: usize = marks
        .iter()
        .map(|(label, _)| {
            label.rsplit('(').next().and_then(|n| n.trim_end_matches(')').parse::<usize>().ok()).unwrap_or(0)
        })
        .sum();
    assert_eq!(total, 5000);
    let (label, rect) = &marks[marks.len() / 2];
    let count: usize = label.rsplit('(').next().unwrap().trim_end_matches(')').parse().unwrap();
    h.get_by_label(label).click();
    h.run();
    let selected: Vec<KeyRef> = h.state().session.selection.keys.iter().copied().collect();
    assert_eq!(selected.len(), count, "a click on {label} at {rect:?} selects its keys");
    let indices: Vec<usize> = selected.iter().map(|k| k.index).collect();
    assert!(indices.windows(2).all(|w| w[1] == w[0] + 1), "neighbouring keys: {indices:?}");
}

/// assets/ik.ron: the IK constraint's keyed target and IK/FK blend have dope-sheet rows under
/// the arm, and a click on a blend key shows the blend's curve.
#[test]
fn ik_constraint_channels_have_rows_and_curves() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = open(dir.path(), &keyrig_io::demo::ik_scene());
    let labels = row_labels(&h);
    assert!(labels.iter().any(|l| l == "Reach IK target"), "{labels:?}");
    assert!(labels.iter().any(|l| l == "Reach IK blend"), "{labels:?}");
    let blend = ChannelId::IkBlend { object: 0, constraint: 0 };
    let frame = {
        let scene = h.state().doc.scene();
        (channels::key_times(scene, blend)[0] * scene.fps).round() as i64
    };
    h.get_by_label(&format!("key Reach IK blend frame {frame}")).click();
    h.run();
    assert_eq!(h.state().session.selection.keys.iter().next().map(|k| k.channel), Some(blend));
    assert!(h.query_by_label("Curves: Reach IK blend").is_some(), "the curve view shows the blend");
}

/// A right click, as the mouse gives it, at `at`.
fn right_click(h: &mut Harness<'_, EditorApp>, at: Pos2) {
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
}

/// The demo's elbow key at frame 15 made a breakdown from the dope sheet's context menu (a
/// right click on the key selects it): drawn smaller than its keyframe neighbours and said to
/// be a breakdown, one undo step; an extreme is drawn larger; the type is saved and read back.
#[test]
fn a_right_click_on_a_key_makes_it_a_breakdown_drawn_smaller_and_saved() {
    use keyrig_core::KeyType;
    const ELBOW: ChannelId = ChannelId::JointRotation { object: 0, joint: 1 };
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    let original = h.state().doc.scene().clone();
    let size = |h: &Harness<'_, EditorApp>, frame: i32| {
        h.get_by_label(&format!("key elbow rotation frame {frame}")).rect().width()
    };
    let description = |h: &Harness<'_, EditorApp>, frame: i32| {
        h.get_by_label(&format!("key elbow rotation frame {frame}")).accesskit_node().description()
    };
    let keyframe = size(&h, 15);
    assert_eq!(description(&h, 15), None, "a keyframe says nothing of its type");

    let at = h.get_by_label("key elbow rotation frame 15").rect().center();
    right_click(&mut h, at);
    let selected: Vec<KeyRef> = h.state().session.selection.keys.iter().copied().collect();
    assert_eq!(selected, [KeyRef { channel: ELBOW, index: 1 }], "the right click selects the key");
    h.get_by_label("Breakdown").click();
    h.run();
    let scene = h.state().doc.scene();
    assert_eq!(channels::key_type(scene, ELBOW, 1), Some(KeyType::Breakdown));
    assert_eq!(channels::key_type(scene, ELBOW, 2), Some(KeyType::Keyframe), "only the selected key");
    assert!(size(&h, 15) < 0.8 * keyframe, "a breakdown is drawn smaller: {} vs {keyframe}", size(&h, 15));
    assert_eq!(description(&h, 15).as_deref(), Some("Breakdown"));
    assert_eq!(size(&h, 30), keyframe, "its neighbour stays a keyframe");

    // Saved and read back with its type; the playback does not change.
    let path = dir.path().join("typed.ron");
    keyrig_io::scene_file::save(&path, h.state().doc.scene()).expect("saves");
    let text = std::fs::read_to_string(&path).expect("reads");
    assert_eq!(text.matches("key_type: Breakdown").count(), 1, "one typed key in the file");
    assert_eq!(&keyrig_io::scene_file::load(&path).expect("loads"), h.state().doc.scene());
    assert_eq!(
        channels::key_value(h.state().doc.scene(), ELBOW, 1),
        channels::key_value(&original, ELBOW, 1),
        "the type changes no value"
    );

    press(&mut h, Modifiers::COMMAND, Key::Z);
    assert_eq!(h.state().doc.scene(), &original, "one undo step");

    // An extreme is drawn larger than a keyframe.
    let at = h.get_by_label("key elbow rotation frame 30").rect().center();
    right_click(&mut h, at);
    h.get_by_label("Extreme").click();
    h.run();
    assert_eq!(channels::key_type(h.state().doc.scene(), ELBOW, 2), Some(KeyType::Extreme));
    assert!(size(&h, 30) > 1.1 * keyframe, "an extreme is drawn larger");
}

/// The key inspector shows the selected key's type and changes it (issue 30): the elbow's key
/// at frame 15 clicked in the dope sheet reads *Keyframe*; *Extreme* from the inspector's *Key
/// type* makes it one, one undo step named by what changed.
#[test]
fn the_key_inspector_shows_and_sets_the_key_type() {
    use keyrig_core::KeyType;
    const ELBOW: ChannelId = ChannelId::JointRotation { object: 0, joint: 1 };
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = harness(dir.path(), None);
    h.get_by_label("key elbow rotation frame 15").click();
    h.run();
    let undo = h.state().doc.undo_len();
    h.get_by_label("Key type").click();
    h.run();
    h.get_by_label("Extreme").click();
    h.run();
    assert_eq!(channels::key_type(h.state().doc.scene(), ELBOW, 1), Some(KeyType::Extreme));
    assert_eq!(channels::key_type(h.state().doc.scene(), ELBOW, 2), Some(KeyType::Keyframe));
    assert_eq!(h.state().doc.undo_len(), undo + 1);
    assert_eq!(h.state().doc.undo_label(), Some("key type Extreme on elbow rotation key at frame 15"));
}

/// Issue 42, 10: selecting an object (a click on its outliner entry) inserts no rows for its
/// unkeyed translation, rotation and scale: the rows under the pointer stay where they were.
#[test]
fn selecting_an_object_does_not_shift_the_rows() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = open(dir.path(), &legs_scene());
    let before = row_labels(&h);
    let hip = h.get_by_label("dope sheet row hip rotation").rect();
    h.state_mut().session.selection = keyrig_editor::session::Selection::default();
    h.get_all_by_label("legs")
        .min_by(|a, b| a.rect().left().total_cmp(&b.rect().left()))
        .expect("the outliner's entry")
        .click();
    h.run();
    assert!(h.state().session.selection.contains(keyrig_editor::session::Selected::Object(0)));
    assert_eq!(row_labels(&h), before, "no rows for the object's unkeyed channels");
    assert_eq!(h.get_by_label("dope sheet row hip rotation").rect(), hip, "the rows stay put");
}
