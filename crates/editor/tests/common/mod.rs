//! What the editor's UI tests share: an editor in an egui_kittest harness (with or without the
//! GPU viewport), key presses, frame steps, AccessKit value changes and corpus paths.

// Each test binary uses its own subset of these helpers.
#![allow(dead_code)]

use egui::accesskit::{Action, ActionData, ActionRequest, Role};
use egui::{Event, Key, Modifiers};
use egui_kittest::kittest::{NodeT, Queryable};
use egui_kittest::Harness;
use keyrig_editor::{editor_for, EditorApp, EditorOptions};

/// The window size of the painter-viewport tests.
pub const WINDOW: [f32; 2] = [1280.0, 800.0];

/// `tests/corpus` in the repository (see its SOURCES.md).
pub fn corpus(relative: &str) -> std::path::PathBuf {
    std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus").join(relative)
}

/// An editor on `file` (the demo scene when `None`) whose recovery and recent files live in
/// `dir`, autosaving after `autosave_seconds`; the viewport is egui's painter (no GPU).
pub fn harness_autosaving(
    dir: &std::path::Path,
    file: Option<std::path::PathBuf>,
    autosave_seconds: f64,
) -> Harness<'static, EditorApp> {
    let options =
        EditorOptions { data_dir: Some(dir.to_path_buf()), autosave_seconds: Some(autosave_seconds) };
    let app = editor_for(file, options);
    let mut harness = Harness::builder()
        .with_size(egui::Vec2::from(WINDOW))
        .build_ui_state(|ui, app: &mut EditorApp| app.ui(ui), app);
    settle(&mut harness);
    harness
}

/// Runs frames until the editor stops asking for them. A model opened on start is read in
/// the background and the editor repaints every 50 ms until it is done, and a status-bar
/// message asks for a repaint when it is due to go away; either can take more frames than the
/// harness allows on a loaded machine: that alone is not a failure (tests wait with
/// `wait_for_background_work`). Repainting for any other reason is.
pub fn settle(harness: &mut Harness<'_, EditorApp>) {
    if let Err(e) = harness.try_run() {
        let status_showing = harness.state().status().is_some_and(|s| s.seconds_left() > 0.0);
        assert!(
            !harness.state().imports().is_empty() || status_showing,
            "the editor keeps repainting with no import running and no status message showing: {e}"
        );
    }
}

/// [`harness_autosaving`] that never autosaves during a test.
pub fn harness(dir: &std::path::Path, file: Option<std::path::PathBuf>) -> Harness<'static, EditorApp> {
    harness_autosaving(dir, file, 1e9)
}

/// The editor on the demo scene with the GPU viewport, as `keyrig` opens it, in a window of
/// `size` points; the viewport renders at full resolution whatever the adapter.
pub fn gpu_harness(dir: &std::path::Path, size: [f32; 2]) -> Harness<'static, EditorApp> {
    gpu_harness_for(dir, size, None)
}

/// [`gpu_harness`] on `file` (the demo scene when `None`).
pub fn gpu_harness_for(
    dir: &std::path::Path,
    size: [f32; 2],
    file: Option<std::path::PathBuf>,
) -> Harness<'static, EditorApp> {
    let dir = dir.to_path_buf();
    let mut harness = Harness::builder().wgpu().with_size(egui::Vec2::from(size)).build_eframe(move |cc| {
        let mut app = editor_for(file, EditorOptions { data_dir: Some(dir), autosave_seconds: Some(1e9) });
        if let Some(rs) = &cc.wgpu_render_state {
            app.attach_gpu(rs);
        }
        app.view.resolution_scale = 1.0;
        app
    });
    harness.run();
    assert!(harness.state().gpu().is_some(), "kittest's wgpu renderer gives the editor a device");
    harness
}

/// Presses `key` with `modifiers` and runs the frame.
pub fn press(h: &mut Harness<'_, EditorApp>, modifiers: Modifiers, key: Key) {
    h.key_press_modifiers(modifiers, key);
    h.run();
}

/// Goes to `frame` as a user would: Home, then the right arrow `frame` times.
pub fn go_to_frame(h: &mut Harness<'_, EditorApp>, frame: i32) {
    press(h, Modifiers::NONE, Key::Home);
    for _ in 0..frame {
        press(h, Modifiers::NONE, Key::ArrowRight);
    }
    assert_eq!(h.state().session.playback.whole_frame(), frame);
}

/// Sets a drag value or slider found by its role and accessible label, as a screen reader
/// would.
pub fn set_value(h: &mut Harness<'_, EditorApp>, role: Role, label: &str, value: f64) {
    let (target_node, target_tree) = h.get_by_role_and_label(role, label).accesskit_node().locate();
    h.event(Event::AccessKitActionRequest(ActionRequest {
        action: Action::SetValue,
        target_node,
        target_tree,
        data: Some(ActionData::NumericValue(value)),
    }));
    h.run();
}

/// Drags with the primary button from `from` to `to` in ten moves, one frame each, as a
/// hand would across the dope sheet.
pub fn drag(h: &mut Harness<'_, EditorApp>, from: egui::Pos2, to: egui::Pos2) {
    let button = |pos, pressed| Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers: Modifiers::NONE,
    };
    h.event(Event::PointerMoved(from));
    h.event(button(from, true));
    h.step();
    for i in 1..=10 {
        h.event(Event::PointerMoved(from + (to - from) * (i as f32 / 10.0)));
        h.step();
    }
    h.event(button(to, false));
    h.run();
}

/// Sends one pointer event and runs the frame.
pub fn pointer(h: &mut Harness<'_, EditorApp>, event: Event) {
    h.event(event);
    h.run();
}

/// Hovers `path[0]`, presses the primary button there, moves through the rest of `path` one
/// frame per point, releases at the last point and moves away, so the next frame neither
/// hovers nor drags what was grabbed (a gizmo ring, an IK handle).
pub fn drag_along(h: &mut Harness<'_, EditorApp>, path: &[egui::Pos2]) {
    drag_along_with(h, path, Modifiers::NONE);
}

/// [`drag_along`] with `modifiers` held from the press to the release (as egui-winit reports
/// a held Ctrl: in every frame's input).
pub fn drag_along_with(h: &mut Harness<'_, EditorApp>, path: &[egui::Pos2], modifiers: Modifiers) {
    let (Some(&start), Some(&end)) = (path.first(), path.last()) else { return };
    let button = |pos: egui::Pos2, pressed: bool| Event::PointerButton {
        pos,
        button: egui::PointerButton::Primary,
        pressed,
        modifiers,
    };
    h.input_mut().modifiers = modifiers;
    pointer(h, Event::PointerMoved(start));
    pointer(h, Event::PointerMoved(start));
    pointer(h, button(start, true));
    for &p in &path[1..] {
        pointer(h, Event::PointerMoved(p));
    }
    pointer(h, button(end, false));
    h.input_mut().modifiers = Modifiers::NONE;
    pointer(h, Event::PointerMoved(end + egui::vec2(0.0, -200.0)));
}

/// Where a world point is on screen in the editor's viewport now.
pub fn on_screen(app: &EditorApp, at: glam::Vec3) -> egui::Pos2 {
    let rect = app.viewport_rect().expect("the viewport was laid out");
    keyrig_editor::camera::Projection::new(&app.view.camera, rect)
        .project(at)
        .expect("the point is in front of the camera")
}

/// World position of joint `joint` of object `object` as the editor evaluates it now (keys and
/// pose overrides).
pub fn joint_world(app: &EditorApp, object: usize, joint: usize) -> glam::Vec3 {
    let pose = app.object_pose_now(object).expect("the object has a pose");
    (pose.world_from_object * pose.object_from_joint[joint]).translation.into()
}
