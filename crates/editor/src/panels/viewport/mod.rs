//! The 3D viewport: orbit (left drag on empty space), pan (right or middle drag, or
//! Shift+left drag), zoom (scroll); the ground grid, the skeleton's bones, objects, lights, the
//! transform gizmo of the selection (or, in IK posing, the IK handle of a selected joint:
//! [`crate::panels::ik_handle`]), and click-to-select on joints, objects and lights.

use egui::{Align2, Color32, FontId, Pos2, Rect, Sense, Stroke, Ui};
use glam::{Affine3A, DQuat, DVec3, Quat, Vec3};
use keyrig_core::LightKind;
use transform_gizmo_egui::math::Transform;
use transform_gizmo_egui::{GizmoConfig, GizmoInteraction, GizmoMode, GizmoOrientation, GizmoResult};

use crate::app::EditorApp;
use crate::camera::{OrbitCamera, Projection};
use crate::channels::{ChannelId, ChannelValue, Turn};
use crate::eval::ObjectPose;
use crate::session::Selected;
use crate::twist::{RingDrag, RingDragState};
use crate::view::RenderStyle;

/// Pick radius around joints and lights, points.
const PICK_RADIUS: f32 = 9.0;

/// What the viewport shows this frame, evaluated once and shared by its parts.
struct ViewportFrame {
    eval: std::sync::Arc<keyrig_eval::SceneEvaluator>,
    state: keyrig_eval::SceneState,
    poses: Vec<Option<ObjectPose>>,
    /// Deformed (or static) meshes in world space by object, skinned on the CPU: they feed
    /// the cross-section measure and, without a GPU viewport, the painter.
    cpu_meshes: Vec<(usize, Vec<Vec3>, Vec<u32>)>,
    /// What could not be drawn (shown in red over the viewport).
    errors: Vec<String>,
}

/// The viewport: evaluates the frame, draws it (GPU, else the painter), the skeleton and
/// light overlays, the gizmo; then camera navigation and click-to-select.
pub fn ui(ui: &mut Ui, app: &mut EditorApp) {
    egui::CentralPanel::default().frame(egui::Frame::NONE).show_inside(ui, |ui| {
        let rect = ui.available_rect_before_wrap();
        let response = ui.allocate_rect(rect, Sense::click_and_drag());
        let painter = ui.painter_at(rect);
        // Filled below only when the painter draws: under the GPU image it would double the
        // pixels a CPU rasterizer shades (docs/benchmarks.md, "Editor").
        let background = painter.add(egui::Shape::Noop);
        app.view.viewport_rect = Some(rect);

        let mut frame = evaluate_frame(app);
        record_bounds(app, &frame.poses, &frame.cpu_meshes);
        // Framing after an import moves the camera before anything is drawn this frame.
        if let Some(objects) = app.view.frame_request.take() {
            app.frame_objects(&objects);
        }
        let projection = Projection::new(&app.view.camera, rect);

        let gpu_drawn = gpu_ui(ui, app, rect, &frame.eval, &frame.state, &mut frame.errors);
        if !gpu_drawn {
            painter.set(background, egui::Shape::rect_filled(rect, 0.0, Color32::from_rgb(38, 40, 46)));
            paint_scene(&painter, &projection, app, &frame.cpu_meshes);
        }
        paint_axes(&painter, &projection, app, &frame.poses);
        if !gpu_drawn && app.view.bones {
            paint_bones(&painter, &projection, app, &frame.poses);
        }
        paint_lights(&painter, &projection, app, &frame.state);
        let pick_targets = pick_targets(&projection, app, &frame);

        // Gizmo for the selection (drawn last, on top); in IK posing a selected joint shows its
        // IK handle instead. Either owns the primary button only on one of its handles; scroll,
        // right/middle drags and drags that start elsewhere stay with the camera, as in
        // Blender's viewport.
        let gizmo_owns_primary =
            match crate::panels::ik_handle::handle_ui(ui, app, &projection, rect, &response, &frame.poses) {
                Some(owns) => owns,
                None => gizmo_ui(ui, app, &projection, rect, &response, &frame.poses),
            };
        let boxing = box_select(ui, app, &response, &painter, &pick_targets, gizmo_owns_primary);
        navigate(ui, app, &response, rect, gizmo_owns_primary || boxing);
        if response.clicked() && !gizmo_owns_primary {
            if let Some(pos) = response.interact_pointer_pos() {
                let adding = ui.input(|i| i.modifiers.shift || i.modifiers.command);
                match (pick(&pick_targets, pos), adding) {
                    (Some(item), true) => app.session.selection.toggle(item),
                    (hit, false) => app.session.selection.select_only(hit),
                    (None, true) => {}
                }
            }
        }
        overlay_ui(&painter, rect, app, &frame.errors);
        app.viewport_errors = frame.errors;
    });
}

/// Loads the model files the scene shows (the evaluator reads no files), evaluates the
/// scene now and skins or morphs every mesh on the CPU.
fn evaluate_frame(app: &mut EditorApp) -> ViewportFrame {
    let time = app.time();
    let base_dir = app.doc.path().and_then(std::path::Path::parent).map(std::path::Path::to_path_buf);
    let mut errors: Vec<String> = Vec::new();
    for object in &app.doc.scene().objects {
        if let Some(keyrig_core::MeshSource::File { path, mesh, .. }) = &object.mesh {
            if let Err(e) = app.meshes.get(base_dir.as_deref(), path, *mesh) {
                errors.push(format!("{}: {e}", object.name));
            }
        }
    }
    let eval = app.evaluator();
    let state = eval.evaluate(time, &app.session.overrides);
    let poses: Vec<Option<ObjectPose>> =
        state.objects.iter().map(|s| Some(ObjectPose::from_state(s))).collect();

    let mut cpu_meshes: Vec<(usize, Vec<Vec3>, Vec<u32>)> = Vec::new();
    for (o, object_state) in state.objects.iter().enumerate() {
        let object = &app.doc.scene().objects[o];
        let world_from_object = object_state.world_from_object;
        if let (Some(skin), Some(palette)) = (eval.skin(o), &object_state.palette) {
            match app.skin.skin(o, skin, palette, object.deformer.kind) {
                Ok(view) => cpu_meshes.push((
                    o,
                    crate::skinning::to_world(world_from_object, view.positions),
                    view.indices.to_vec(),
                )),
                Err(e) => errors.push(format!("{}: {e}", object.name)),
            }
            continue;
        }
        app.skin.forget(o);
        if let Some(e) = &object_state.palette_error {
            errors.push(format!("{}: pose: {e}", object.name));
        }
        let Some(keyrig_core::MeshSource::File { path, mesh, .. }) = &object.mesh else { continue };
        match (app.meshes.peek(base_dir.as_deref(), path, *mesh), &object_state.morph) {
            (Some(crate::files::FileMesh::Morph(morph)), Some(Ok(blend))) => {
                let positions = app.skin.morph(o, morph, *blend);
                cpu_meshes.push((
                    o,
                    crate::skinning::to_world(world_from_object, positions),
                    morph.indices().to_vec(),
                ));
            }
            (Some(crate::files::FileMesh::Morph(_)), Some(Err(e))) => {
                errors.push(format!("{}: {e}", object.name))
            }
            (Some(crate::files::FileMesh::Static { positions, indices }), _) => {
                cpu_meshes.push((
                    o,
                    crate::skinning::to_world(world_from_object, positions),
                    indices.clone(),
                ));
            }
            _ => {}
        }
    }
    for problem in eval.problems().iter().take(3) {
        errors.push(problem.to_string());
    }
    ViewportFrame { eval, state, poses, cpu_meshes, errors }
}

/// The painter's scene without a GPU viewport: grid and meshes.
fn paint_scene(
    painter: &egui::Painter,
    projection: &Projection,
    app: &EditorApp,
    cpu_meshes: &[(usize, Vec<Vec3>, Vec<u32>)],
) {
    if app.view.grid {
        draw_grid(painter, projection);
    }
    for (o, world, indices) in cpu_meshes {
        let selected = app.session.selection.item == Some(Selected::Object(*o));
        draw_mesh(painter, projection, &app.view.camera, world, indices, app.view.style, selected);
    }
}

/// Bones and joints of every skeleton (the painter's skeleton overlay; the GPU viewport draws
/// its own).
fn paint_bones(
    painter: &egui::Painter,
    projection: &Projection,
    app: &EditorApp,
    poses: &[Option<ObjectPose>],
) {
    let scene = app.doc.scene();
    for (o, pose) in poses.iter().enumerate() {
        let Some(pose) = pose else { continue };
        let Some(skeleton) = &scene.objects[o].skeleton else { continue };
        for (j, joint) in skeleton.joints.iter().enumerate() {
            let world = pose.world_from_object * pose.object_from_joint[j];
            let at: Vec3 = world.translation.into();
            let selected = app.session.selection.item == Some(Selected::Joint { object: o, joint: j });
            let bone_colour =
                if selected { Color32::from_rgb(255, 200, 60) } else { Color32::from_rgb(120, 200, 255) };
            if let Some(p) = joint.parent.filter(|&p| p < j) {
                let from: Vec3 = (pose.world_from_object * pose.object_from_joint[p]).translation.into();
                if let Some(seg) = projection.project_segment(from, at) {
                    painter.line_segment(seg, Stroke::new(3.0, bone_colour));
                }
            }
            // The last joint of a chain draws a stub along its local X.
            if !skeleton.joints.iter().any(|c| c.parent == Some(j)) {
                let tip = world.transform_point3(Vec3::X * 0.15);
                if let Some(seg) = projection.project_segment(at, tip) {
                    painter.line_segment(seg, Stroke::new(2.0, bone_colour));
                }
            }
            if let Some(p) = projection.project(at) {
                painter.circle(p, 5.0, Color32::from_rgb(30, 30, 30), Stroke::new(2.0, bone_colour));
            }
        }
    }
}

/// The axes of objects without a mesh (empties, skeletons alone).
fn paint_axes(
    painter: &egui::Painter,
    projection: &Projection,
    app: &EditorApp,
    poses: &[Option<ObjectPose>],
) {
    for (object, pose) in app.doc.scene().objects.iter().zip(poses) {
        if let (None, Some(pose)) = (&object.mesh, pose) {
            draw_axes(painter, projection, pose.world_from_object);
        }
    }
}

/// Light icons with their direction.
fn paint_lights(
    painter: &egui::Painter,
    projection: &Projection,
    app: &EditorApp,
    state: &keyrig_eval::SceneState,
) {
    for ((l, light), light_state) in app.doc.scene().lights.iter().enumerate().zip(&state.lights) {
        let pos = light_state.position;
        let Some(p) = projection.project(pos) else { continue };
        let selected = app.session.selection.item == Some(Selected::Light(l));
        let colour = if selected {
            Color32::from_rgb(255, 200, 60)
        } else if light.enabled {
            Color32::from_rgb(255, 240, 150)
        } else {
            Color32::GRAY
        };
        painter.circle_stroke(p, 7.0, Stroke::new(2.0, colour));
        for k in 0..8 {
            let a = k as f32 * std::f32::consts::TAU / 8.0;
            let d = egui::vec2(a.cos(), a.sin());
            painter.line_segment([p + d * 9.0, p + d * 13.0], Stroke::new(1.5, colour));
        }
        let dir = light_state.direction;
        if let Some(seg) = projection.project_segment(pos, pos + dir.normalize_or_zero() * 0.5) {
            painter.arrow(seg[0], seg[1] - seg[0], Stroke::new(1.0, colour));
        }
    }
}

/// Where each object origin, joint and light is on screen, for click-to-select (objects
/// first, then their joints, then lights, as they were drawn).
fn pick_targets(projection: &Projection, app: &EditorApp, frame: &ViewportFrame) -> Vec<(Pos2, Selected)> {
    let scene = app.doc.scene();
    let mut targets = Vec::new();
    for (o, pose) in frame.poses.iter().enumerate() {
        let Some(pose) = pose else { continue };
        if let Some(p) = projection.project(pose.world_from_object.translation.into()) {
            targets.push((p, Selected::Object(o)));
        }
        let Some(skeleton) = &scene.objects[o].skeleton else { continue };
        for j in 0..skeleton.joints.len() {
            let at: Vec3 = (pose.world_from_object * pose.object_from_joint[j]).translation.into();
            if let Some(p) = projection.project(at) {
                targets.push((p, Selected::Joint { object: o, joint: j }));
            }
        }
    }
    for (l, light_state) in frame.state.lights.iter().enumerate().take(scene.lights.len()) {
        if let Some(p) = projection.project(light_state.position) {
            targets.push((p, Selected::Light(l)));
        }
    }
    targets
}

/// The nearest pick target within [`PICK_RADIUS`] of `pos` (nothing when none is).
fn pick(targets: &[(Pos2, Selected)], pos: Pos2) -> Option<Selected> {
    targets
        .iter()
        .filter(|(p, _)| p.distance(pos) <= PICK_RADIUS)
        .min_by(|a, b| a.0.distance(pos).total_cmp(&b.0.distance(pos)))
        .map(|(_, s)| *s)
}

/// Ctrl+drag on empty space draws a box and selects the joints inside it when released
/// (Ctrl+Shift+drag adds them to the selection). Returns whether a box drag is under way.
fn box_select(
    ui: &Ui,
    app: &mut EditorApp,
    response: &egui::Response,
    painter: &egui::Painter,
    targets: &[(Pos2, Selected)],
    gizmo_owns_primary: bool,
) -> bool {
    let (ctrl, shift) = ui.input(|i| (i.modifiers.command, i.modifiers.shift));
    if response.drag_started_by(egui::PointerButton::Primary) && ctrl && !gizmo_owns_primary {
        app.view.box_select = ui.input(|i| i.pointer.press_origin());
    }
    let Some(start) = app.view.box_select else { return false };
    let Some(now) = ui.input(|i| i.pointer.latest_pos()) else { return true };
    let area = Rect::from_two_pos(start, now);
    painter.rect(
        area,
        0.0,
        Color32::from_rgba_unmultiplied(90, 170, 255, 30),
        Stroke::new(1.0, Color32::from_rgb(90, 170, 255)),
        egui::StrokeKind::Inside,
    );
    if response.drag_stopped() || !ui.input(|i| i.pointer.primary_down()) {
        app.view.box_select = None;
        let joints: Vec<Selected> = targets
            .iter()
            .filter(|(p, item)| area.contains(*p) && matches!(item, Selected::Joint { .. }))
            .map(|(_, item)| *item)
            .collect();
        let selection = &mut app.session.selection;
        if !shift {
            selection.select_only(None);
        }
        for joint in joints {
            if !selection.contains(joint) {
                selection.toggle(joint);
            }
        }
    }
    true
}

/// Orbit (left drag), pan (right or middle drag, Shift+left drag) and zoom (scroll); a
/// primary drag the gizmo owns is left to it.
fn navigate(ui: &Ui, app: &mut EditorApp, response: &egui::Response, rect: Rect, gizmo_owns_primary: bool) {
    let shift = ui.input(|i| i.modifiers.shift);
    let primary = response.dragged_by(egui::PointerButton::Primary) && !gizmo_owns_primary;
    if primary && !shift {
        let d = response.drag_delta();
        app.view.camera.orbit(d.x, d.y);
    } else if response.dragged_by(egui::PointerButton::Secondary)
        || response.dragged_by(egui::PointerButton::Middle)
        || (primary && shift)
    {
        let d = response.drag_delta();
        app.view.camera.pan(d.x, d.y, rect.height());
    }
    if response.contains_pointer() {
        let scroll = ui.input(|i| i.smooth_scroll_delta.y);
        if scroll != 0.0 {
            app.view.camera.zoom(scroll);
        }
    }
}

/// Renders the viewport with keyrig-render when the editor runs on eframe's wgpu backend.
/// Returns false (and adds the reason to `errors` when there is one) to let the painter draw.
fn gpu_ui(
    ui: &Ui,
    app: &mut EditorApp,
    rect: Rect,
    eval: &std::sync::Arc<keyrig_eval::SceneEvaluator>,
    state: &keyrig_eval::SceneState,
    errors: &mut Vec<String>,
) -> bool {
    let Some(mut gpu) = app.gpu.take() else { return false };
    let scene = app.doc.scene();
    let c = app.view.camera;
    let view = keyrig_render::ViewOptions {
        style: app.view.style,
        textures: app.view.textures,
        deformer: None,
        grid: app.view.grid,
        skeletons: app.view.bones,
        motion_path: app.view.motion_path,
        selection: app.session.selection.item,
        camera: Some(c),
        depth_range: Some(c.depth_range(app.view.bounds_of(None))),
        ..keyrig_render::ViewOptions::default()
    };
    let ppp = ui.ctx().pixels_per_point() * app.view.resolution_scale.clamp(0.25, 1.0);
    let size = [(rect.width() * ppp).round().max(1.0) as u32, (rect.height() * ppp).round().max(1.0) as u32];
    let rig_key = app.evaluator_key();
    let mut morph_meshes = std::collections::HashMap::new();
    let mut materials = std::collections::HashMap::new();
    if gpu.needs_rig(rig_key) {
        let base_dir = app.doc.path().and_then(std::path::Path::parent).map(std::path::Path::to_path_buf);
        materials = app.meshes.materials_for(base_dir.as_deref(), scene);
        for (o, object) in scene.objects.iter().enumerate() {
            if let Some(keyrig_core::MeshSource::File { path, mesh, .. }) = &object.mesh {
                if let Some(crate::files::FileMesh::Morph(m)) =
                    app.meshes.peek(base_dir.as_deref(), path, *mesh)
                {
                    morph_meshes.insert(o, std::sync::Arc::clone(m));
                }
            }
        }
    }
    let ghosts = match app.session.selected_object() {
        Some(o) if app.view.onion.enabled => {
            crate::onion::ghost_frames(&app.view.onion, scene, o, app.session.playback.frame)
                .into_iter()
                .filter_map(|g| {
                    let state =
                        eval.object_at(o, g.frame / scene.fps.max(1e-9), &keyrig_eval::Overrides::new())?;
                    Some((o, state, g.ghost))
                })
                .collect()
        }
        _ => Vec::new(),
    };
    let frame = crate::gpu_view::GpuFrame {
        scene,
        rig_key,
        evaluator: std::sync::Arc::clone(eval),
        state,
        overrides: &app.session.overrides,
        view,
        morph_meshes,
        materials,
        ghosts,
    };
    if let Err(e) = gpu.set_antialiasing(app.view.antialiasing) {
        errors.push(format!("GPU viewport: {e}"));
    }
    let drawn = match gpu.render(frame, size) {
        Ok(texture) => {
            let uv = Rect::from_min_max(Pos2::ZERO, Pos2::new(1.0, 1.0));
            ui.painter().with_clip_rect(rect).image(texture, rect, uv, Color32::WHITE);
            true
        }
        Err(e) => {
            errors.push(format!("GPU viewport: {e}"));
            false
        }
    };
    app.gpu = Some(gpu);
    drawn
}

/// Keeps each object's world bounds as drawn this frame (the deformed mesh; joints and origin
/// for an object without one) for framing and the clip planes.
fn record_bounds(app: &mut EditorApp, poses: &[Option<ObjectPose>], meshes: &[(usize, Vec<Vec3>, Vec<u32>)]) {
    use crate::camera::Bounds;
    let mut bounds: Vec<Option<Bounds>> = poses
        .iter()
        .map(|pose| {
            let pose = pose.as_ref()?;
            let origin: Vec3 = pose.world_from_object.translation.into();
            Bounds::of(std::iter::once(origin).chain(
                pose.object_from_joint.iter().map(|f| (pose.world_from_object * *f).translation.into()),
            ))
        })
        .collect();
    for (o, world, _) in meshes {
        if let (Some(slot), Some(mesh)) = (bounds.get_mut(*o), Bounds::of(world.iter().copied())) {
            // A mesh's own box: its joints may sit outside it (a root far below the feet).
            *slot = Some(mesh);
        }
    }
    app.view.object_bounds = bounds;
}

fn draw_grid(painter: &egui::Painter, projection: &Projection) {
    let n = 10;
    for i in -n..=n {
        let f = i as f32 * 0.5;
        let e = n as f32 * 0.5;
        let colour = if i == 0 { Color32::from_gray(110) } else { Color32::from_gray(62) };
        for (a, b) in
            [(Vec3::new(f, 0.0, -e), Vec3::new(f, 0.0, e)), (Vec3::new(-e, 0.0, f), Vec3::new(e, 0.0, f))]
        {
            if let Some(seg) = projection.project_segment(a, b) {
                painter.line_segment(seg, Stroke::new(1.0, colour));
            }
        }
    }
    // World axes.
    for (axis, colour) in
        [(Vec3::X, Color32::from_rgb(200, 70, 70)), (Vec3::Z, Color32::from_rgb(70, 110, 220))]
    {
        if let Some(seg) = projection.project_segment(Vec3::ZERO, axis * 0.5) {
            painter.line_segment(seg, Stroke::new(2.0, colour));
        }
    }
}

/// Axes of an object without a mesh (X red, Y green, Z blue), 0.2 units long.
fn draw_axes(painter: &egui::Painter, projection: &Projection, world_from_object: Affine3A) {
    let origin: Vec3 = world_from_object.translation.into();
    for (axis, colour) in [
        (Vec3::X, Color32::from_rgb(220, 80, 80)),
        (Vec3::Y, Color32::from_rgb(80, 200, 80)),
        (Vec3::Z, Color32::from_rgb(80, 130, 240)),
    ] {
        let tip = world_from_object.transform_point3(axis * 0.2);
        if let Some(seg) = projection.project_segment(origin, tip) {
            painter.line_segment(seg, Stroke::new(2.0, colour));
        }
    }
}

fn overlay_ui(painter: &egui::Painter, rect: Rect, app: &EditorApp, errors: &[String]) {
    let mut lines = vec![format!("Frame {}  ·  {:.2} s", app.session.playback.whole_frame(), app.time())];
    if let Some(o) =
        app.selected_object().or_else(|| app.doc.scene().objects.iter().position(|x| x.skeleton.is_some()))
    {
        if let Some(object) = app.doc.scene().objects.get(o) {
            if object.skeleton.is_some() {
                lines.push(format!("{}: {}", object.name, object.deformer.kind.label()));
            }
        }
    }
    if let Some(text) = measure_text(app) {
        lines.push(text);
    }
    let onion = &app.view.onion;
    if onion.enabled {
        lines.push(match app.selected_object() {
            Some(_) if app.gpu.is_none() => "Onion skin: shown in the GPU viewport only".to_owned(),
            Some(_) => format!("Onion skin: {} before, {} after", onion.before, onion.after),
            None => "Onion skin: select an object or joint".to_owned(),
        });
    }
    let text = lines.join("\n");
    painter.text(
        rect.left_top() + egui::vec2(10.0, 8.0),
        Align2::LEFT_TOP,
        text,
        FontId::proportional(13.0),
        Color32::from_gray(220),
    );
    for (i, e) in errors.iter().enumerate() {
        painter.text(
            rect.left_bottom() + egui::vec2(10.0, -10.0 - 16.0 * i as f32),
            Align2::LEFT_BOTTOM,
            e,
            FontId::proportional(13.0),
            Color32::from_rgb(255, 110, 110),
        );
    }
    if app.session.record {
        painter.rect_stroke(
            rect.shrink(1.0),
            0.0,
            Stroke::new(2.0, Color32::from_rgb(220, 50, 50)),
            egui::StrokeKind::Inside,
        );
        painter.text(
            rect.right_top() + egui::vec2(-10.0, 8.0),
            Align2::RIGHT_TOP,
            "● REC",
            FontId::proportional(14.0),
            Color32::from_rgb(255, 80, 80),
        );
    }
}

/// The world transform the gizmo edits for the selection, and which channels it drives.
fn gizmo_target(app: &EditorApp, poses: &[Option<ObjectPose>]) -> Option<(Affine3A, GizmoKind)> {
    match app.session.selection.item? {
        Selected::Joint { object, joint } => {
            let pose = poses.get(object)?.as_ref()?;
            Some((
                pose.world_from_object * *pose.object_from_joint.get(joint)?,
                GizmoKind::Joint { object, joint },
            ))
        }
        Selected::Object(o) => Some((poses.get(o)?.as_ref()?.world_from_object, GizmoKind::Object(o))),
        Selected::Light(l) => {
            let kind = app.doc.scene().lights.get(l)?.kind;
            let Some(ChannelValue::Vec3(p)) = app.value_now(ChannelId::LightPosition(l)) else { return None };
            let aim = match kind {
                LightKind::Point => Quat::IDENTITY,
                LightKind::Directional | LightKind::Spot { .. } => {
                    let Some(ChannelValue::Vec3(d)) = app.value_now(ChannelId::LightDirection(l)) else {
                        return None;
                    };
                    light_aim(d)
                }
            };
            Some((Affine3A::from_rotation_translation(aim, p), GizmoKind::Light(l, kind)))
        }
    }
}

/// The light's local axis that points along its direction (as glTF's lights shine along −Z).
const LIGHT_AXIS: Vec3 = Vec3::NEG_Z;

/// A rotation that takes [`LIGHT_AXIS`] onto the direction `d` (any twist about `d`; only the
/// direction is a channel).
fn light_aim(d: Vec3) -> Quat {
    match d.try_normalize() {
        Some(d) => Quat::from_rotation_arc(LIGHT_AXIS, d),
        None => Quat::IDENTITY,
    }
}

#[derive(Clone, Copy)]
enum GizmoKind {
    Joint { object: usize, joint: usize },
    Object(usize),
    Light(usize, LightKind),
}

fn to_transform(a: Affine3A) -> Transform {
    let (s, r, t) = a.to_scale_rotation_translation();
    Transform::from_scale_rotation_translation(s.as_dvec3(), r.as_dquat(), t.as_dvec3())
}

/// Shows the gizmo and lets it take the primary button when the pointer is on one of its
/// handles (transform-gizmo's pick test); returns true while it owns the primary button (a
/// press on a handle, until release), so the camera neither orbits nor picks then.
///
/// transform-gizmo-egui's `interact` puts a click-and-drag widget under the pointer wherever
/// it is, which takes hover, scroll and every drag from the viewport while anything is
/// selected; this drives the gizmo with [`Gizmo::update`] instead, from the viewport's own
/// response.
///
/// The rotation rings of joints and objects are turned by the editor itself: transform-gizmo
/// maps the pointer to the angle around the ring's centre on screen with no way to change it,
/// which turns a ring seen edge-on by 0° and a thin ring by large jumps. A press on a ring
/// asks transform-gizmo which ring it picked; from then on [`RingDrag`] follows the pointer
/// (around the centre, accumulated over several turns, or 1° per point along an edge-on
/// ring; 15° steps with Ctrl) and [`EditorApp::apply_turn`] keys the turn, spin included.
fn gizmo_ui(
    ui: &mut Ui,
    app: &mut EditorApp,
    projection: &Projection,
    rect: Rect,
    response: &egui::Response,
    poses: &[Option<ObjectPose>],
) -> bool {
    let Some((world, kind)) = gizmo_target(app, poses) else {
        app.gizmo_drag = false;
        app.ring_drag = None;
        return false;
    };
    let modes = match kind {
        GizmoKind::Joint { .. } => GizmoMode::all_rotate(),
        GizmoKind::Object(_) => GizmoMode::all_rotate() | GizmoMode::all_translate(),
        // Point lights have only a place, directional lights only a direction (their icon's
        // place is not used for lighting), spot lights both.
        GizmoKind::Light(_, LightKind::Point) => GizmoMode::all_translate(),
        GizmoKind::Light(_, LightKind::Directional) => GizmoMode::all_rotate(),
        GizmoKind::Light(_, LightKind::Spot { .. }) => GizmoMode::all_rotate() | GizmoMode::all_translate(),
    };
    let to_rows = |m: glam::Mat4| m.as_dmat4().into();
    app.gizmo.update_config(GizmoConfig {
        view_matrix: to_rows(projection.camera_from_world),
        projection_matrix: to_rows(projection.clip_from_camera),
        viewport: transform_gizmo_egui::Rect::from_min_max(
            transform_gizmo_egui::math::Pos2::new(rect.min.x, rect.min.y),
            transform_gizmo_egui::math::Pos2::new(rect.max.x, rect.max.y),
        ),
        modes,
        orientation: GizmoOrientation::Local,
        pixels_per_point: ui.ctx().pixels_per_point(),
        ..Default::default()
    });
    let targets = [to_transform(world)];
    let (hover, pressed, down, any_down, snap) = ui.input(|i| {
        (
            i.pointer.hover_pos(),
            i.pointer.primary_pressed(),
            i.pointer.primary_down(),
            i.pointer.any_down(),
            i.modifiers.ctrl || i.modifiers.command,
        )
    });
    let cursor = hover.unwrap_or_default();
    let interaction = |hovered: bool, drag_started: bool, dragging: bool| GizmoInteraction {
        cursor_pos: (cursor.x, cursor.y),
        hovered,
        drag_started,
        dragging,
    };
    if let Some(mut ring) = app.ring_drag.take() {
        // A rotation ring drag of our own: the angle follows the pointer (RingDrag), the
        // gizmo only draws its handles where the target now is.
        if let Some(p) = hover {
            ring.drag.drag_to(p);
        }
        let degrees = ring.drag.degrees(snap);
        let delta = degrees - ring.applied;
        if delta != 0.0 {
            if let Some(ChannelValue::Rotation(from)) = app.value_now(ring.channel) {
                let axis = ring.frame.inverse() * ring.drag.axis;
                app.apply_turn(ring.channel, Turn { from, axis, degrees: delta }, "gizmo");
                ring.applied = degrees;
            }
        }
        let _ = app.gizmo.update(interaction(false, false, false), &targets);
        paint_gizmo(ui, &app.gizmo, rect);
        paint_ring_drag(ui, rect, &ring, degrees, hover, snap);
        if down {
            app.ring_drag = Some(ring);
        } else {
            app.gizmo_drag = false;
        }
        return true;
    }
    if !app.gizmo_drag {
        // Place the handles for this frame's target and camera (no input) so that the pick
        // test below sees what is drawn.
        let _ = app.gizmo.update(interaction(false, false, false), &targets);
    }
    // No other drag (orbit, pan) under way, or one starting now.
    let free = !any_down || pressed;
    let on_handle = free
        && response.contains_pointer()
        && hover.is_some_and(|p| rect.contains(p) && app.gizmo.pick_preview((p.x, p.y)));
    if pressed && on_handle {
        app.gizmo_drag = true;
    }
    let owns = app.gizmo_drag || on_handle;
    let result =
        app.gizmo.update(interaction(owns, pressed && app.gizmo_drag, down && app.gizmo_drag), &targets);
    if !down {
        app.gizmo_drag = false;
    }
    // A press on a rotation ring of a joint or object starts a drag of our own (RingDrag):
    // transform-gizmo only tells which ring was picked.
    if let (true, Some((GizmoResult::Rotation { axis, is_view_axis, .. }, _))) = (pressed, &result) {
        if let Some((channel, frame)) = rotation_channel(app, kind, poses) {
            let (_, world_rotation, centre_world) = world.to_scale_rotation_translation();
            let axis = DVec3::from(*axis).as_vec3();
            let axis = if *is_view_axis { axis } else { world_rotation * axis };
            let eye = app.view.camera.eye();
            let centre_world: Vec3 = centre_world;
            let step = 0.01 * (centre_world - eye).length().max(1e-3);
            let screen_dir = |v: Vec3| match (
                projection.project(centre_world),
                projection.project(centre_world + v.normalize_or_zero() * step),
            ) {
                (Some(a), Some(b)) => b - a,
                _ => egui::Vec2::ZERO,
            };
            if let (Some(centre), Some(press)) = (projection.project(centre_world), hover) {
                let radius = if *is_view_axis { VIEW_RING_RADIUS } else { AXIS_RING_RADIUS };
                let drag = RingDrag::new(axis, centre_world - eye, centre, press, radius, screen_dir);
                app.ring_drag = Some(RingDragState { drag, channel, frame, applied: 0.0 });
                // End transform-gizmo's own drag; it draws idle handles from now on.
                let _ = app.gizmo.update(interaction(false, false, false), &targets);
                paint_gizmo(ui, &app.gizmo, rect);
                return true;
            }
        }
    }
    paint_gizmo(ui, &app.gizmo, rect);
    let Some((result, transforms)) = result else { return owns };
    let Some(new) = transforms.first() else { return owns };
    let new_rotation: Quat = DQuat::from(new.rotation).as_quat().normalize();
    let new_translation: Vec3 = DVec3::from(new.translation).as_vec3();
    let group = "gizmo";
    match kind {
        GizmoKind::Joint { object, joint } => {
            // F(j) = F(p)·R(j)·T(j): T = (world_from_parent·R(j))⁻¹ · new world rotation.
            let scene = app.doc.scene();
            let Some(skeleton) = scene.objects.get(object).and_then(|o| o.skeleton.as_ref()) else {
                return owns;
            };
            let Some(pose) = poses.get(object).and_then(|p| p.as_ref()) else { return owns };
            let j = &skeleton.joints[joint];
            let parent_world = match j.parent.filter(|&p| p < joint) {
                Some(p) => pose.world_from_object * pose.object_from_joint[p],
                None => pose.world_from_object,
            };
            let (_, parent_rotation, _) = parent_world.to_scale_rotation_translation();
            let local = joint_rotation_from_world(parent_rotation, j.rest_rotation, new_rotation);
            app.apply_pose(
                ChannelId::JointRotation { object, joint },
                ChannelValue::Rotation(local.normalize()),
                group,
            );
        }
        GizmoKind::Object(o) => {
            if matches!(result, GizmoResult::Translation { .. }) {
                app.apply_pose(ChannelId::ObjectTranslation(o), ChannelValue::Vec3(new_translation), group);
            } else {
                app.apply_pose(ChannelId::ObjectRotation(o), ChannelValue::Rotation(new_rotation), group);
            }
        }
        GizmoKind::Light(l, _) => {
            if matches!(result, GizmoResult::Translation { .. }) {
                app.apply_pose(ChannelId::LightPosition(l), ChannelValue::Vec3(new_translation), group);
            } else if let Some(ChannelValue::Vec3(old)) = app.value_now(ChannelId::LightDirection(l)) {
                // Keep the direction's length (it need not be unit), turn it with the gizmo.
                let length = old.length();
                let length = if length > 0.0 { length } else { 1.0 };
                let direction = (new_rotation * LIGHT_AXIS) * length;
                app.apply_pose(ChannelId::LightDirection(l), ChannelValue::Vec3(direction), group);
            }
        }
    }
    owns
}

/// Screen radius of transform-gizmo's axis rings with its default visuals (gizmo_size).
const AXIS_RING_RADIUS: f32 = 75.0;
/// Screen radius of its view-axis ring (gizmo_size + stroke width + 5).
const VIEW_RING_RADIUS: f32 = 84.0;

/// The rotation channel the gizmo's rings turn for a joint or object, and the world rotation
/// of the frame its value is expressed in.
fn rotation_channel(
    app: &EditorApp,
    kind: GizmoKind,
    poses: &[Option<ObjectPose>],
) -> Option<(ChannelId, Quat)> {
    match kind {
        GizmoKind::Joint { object, joint } => {
            let skeleton = app.doc.scene().objects.get(object)?.skeleton.as_ref()?;
            let pose = poses.get(object)?.as_ref()?;
            let j = skeleton.joints.get(joint)?;
            let parent_world = match j.parent.filter(|&p| p < joint) {
                Some(p) => pose.world_from_object * *pose.object_from_joint.get(p)?,
                None => pose.world_from_object,
            };
            let (_, parent_rotation, _) = parent_world.to_scale_rotation_translation();
            Some((ChannelId::JointRotation { object, joint }, parent_rotation * j.rest_rotation))
        }
        GizmoKind::Object(o) => Some((ChannelId::ObjectRotation(o), Quat::IDENTITY)),
        GizmoKind::Light(..) => None,
    }
}

/// Shows a ring drag: the start and current directions (around the centre) or the line the
/// drag follows (edge-on), and the angle turned, with "snap 15°" while Ctrl is held.
fn paint_ring_drag(
    ui: &Ui,
    rect: Rect,
    ring: &RingDragState,
    degrees: f64,
    pointer: Option<Pos2>,
    snap: bool,
) {
    let painter = ui.painter().with_clip_rect(rect);
    let colour = Color32::from_rgb(255, 215, 90);
    let stroke = Stroke::new(1.5, colour);
    let centre = ring.drag.centre;
    match ring.drag.mapping {
        crate::twist::RingMapping::Around { .. } => {
            if let Some(p) = pointer {
                painter.line_segment([centre, p], stroke);
            }
            painter.circle_filled(centre, 3.0, colour);
        }
        crate::twist::RingMapping::Along { tangent } => {
            let t = egui::vec2(tangent.x, tangent.y) * VIEW_RING_RADIUS;
            let at = pointer.unwrap_or(centre);
            painter.arrow(at - t * 0.5, t, stroke);
        }
    }
    let turns = (degrees.abs() / 360.0).floor();
    let mut text = format!("{degrees:+.1}°");
    if turns >= 1.0 {
        text.push_str(&format!("  ({turns:.0} turn{})", if turns >= 2.0 { "s" } else { "" }));
    }
    if snap {
        text.push_str("  snap 15°");
    }
    let at = pointer.unwrap_or(centre) + egui::vec2(16.0, -18.0);
    painter.text(
        at + egui::vec2(1.0, 1.0),
        Align2::LEFT_BOTTOM,
        &text,
        FontId::proportional(14.0),
        Color32::BLACK,
    );
    painter.text(at, Align2::LEFT_BOTTOM, text, FontId::proportional(14.0), colour);
}

/// Draws the gizmo's triangles (transform-gizmo's draw data, in screen points).
fn paint_gizmo(ui: &Ui, gizmo: &transform_gizmo_egui::Gizmo, rect: Rect) {
    let draw = gizmo.draw();
    let vertices = draw
        .vertices
        .into_iter()
        .zip(draw.colors)
        .map(|(pos, [r, g, b, a])| egui::epaint::Vertex {
            pos: pos.into(),
            uv: Pos2::default(),
            color: egui::Rgba::from_rgba_premultiplied(r, g, b, a).into(),
        })
        .collect();
    ui.painter().with_clip_rect(rect).add(egui::Mesh {
        indices: draw.indices,
        vertices,
        ..Default::default()
    });
}

/// "Cross-section at elbow: 0.98 × rest" for the selected joint, from the last skinned frame.
#[must_use]
pub fn measure_text(app: &EditorApp) -> Option<String> {
    let Some(Selected::Joint { object, joint }) = app.session.selection.item else { return None };
    let name = app.doc.scene().objects.get(object)?.skeleton.as_ref()?.joints.get(joint)?.name.clone();
    Some(match app.skin.cross_section(object, joint)? {
        Ok(section) => format!("Cross-section at {name}: {:.2} × rest", section.ratio()),
        Err(e) => format!("Cross-section at {name}: {e}"),
    })
}

/// The measure beside the deformer settings in the inspector.
pub fn measure_ui(ui: &mut Ui, app: &EditorApp) {
    match measure_text(app) {
        Some(text) => {
            ui.label(text).on_hover_text(
                "Mean distance of the limb's surface from the joint, posed / rest (DESIGN.md §6). \
                 Near 0 is the candy-wrapper collapse of linear blending under twist.",
            );
        }
        None => {
            ui.weak("Select a joint of a skinned mesh to see its cross-section relative to rest.");
        }
    }
}

/// Draws a triangle mesh given in world space: flat-shaded (head light) with back faces culled
/// and triangles sorted far to near, or as a wireframe.
fn draw_mesh(
    painter: &egui::Painter,
    projection: &Projection,
    camera: &keyrig_core::Camera,
    world: &[Vec3],
    indices: &[u32],
    style: RenderStyle,
    selected: bool,
) {
    let eye = camera.eye();
    let screen: Vec<Option<Pos2>> = world.iter().map(|&p| projection.project(p)).collect();
    let base = if selected { [235.0, 200.0, 120.0] } else { [200.0, 180.0, 165.0] };
    let mut tris: Vec<(f32, [usize; 3], f32)> = Vec::with_capacity(indices.len() / 3);
    for t in indices.chunks_exact(3) {
        let [a, b, c] = [t[0] as usize, t[1] as usize, t[2] as usize];
        let (Some(pa), Some(pb), Some(pc)) = (world.get(a), world.get(b), world.get(c)) else { continue };
        let normal = (*pb - *pa).cross(*pc - *pa).normalize_or_zero();
        let centre = (*pa + *pb + *pc) / 3.0;
        let to_eye = (eye - centre).normalize_or_zero();
        let facing = normal.dot(to_eye);
        if style == RenderStyle::Solid && facing <= 0.0 {
            continue;
        }
        tris.push(((eye - centre).length_squared(), [a, b, c], facing.max(0.0)));
    }
    match style {
        RenderStyle::Solid => {
            tris.sort_by(|x, y| y.0.total_cmp(&x.0));
            let mut mesh = egui::Mesh::default();
            for (_, [a, b, c], facing) in &tris {
                let (Some(pa), Some(pb), Some(pc)) = (screen[*a], screen[*b], screen[*c]) else { continue };
                let light = 0.25 + 0.75 * facing;
                let colour = Color32::from_rgb(
                    (base[0] * light) as u8,
                    (base[1] * light) as u8,
                    (base[2] * light) as u8,
                );
                let i = mesh.vertices.len() as u32;
                for p in [pa, pb, pc] {
                    mesh.colored_vertex(p, colour);
                }
                mesh.add_triangle(i, i + 1, i + 2);
            }
            painter.add(egui::Shape::mesh(mesh));
            let edge = Stroke::new(0.5, Color32::from_rgba_unmultiplied(40, 30, 20, 90));
            for (_, [a, b, c], _) in &tris {
                if let (Some(pa), Some(pb), Some(pc)) = (screen[*a], screen[*b], screen[*c]) {
                    painter.add(egui::Shape::closed_line(vec![pa, pb, pc], edge));
                }
            }
        }
        RenderStyle::Wireframe => {
            let edge = Stroke::new(
                1.0,
                if selected { Color32::from_rgb(255, 200, 60) } else { Color32::from_gray(200) },
            );
            for (_, [a, b, c], _) in &tris {
                if let (Some(pa), Some(pb), Some(pc)) = (screen[*a], screen[*b], screen[*c]) {
                    painter.add(egui::Shape::closed_line(vec![pa, pb, pc], edge));
                }
            }
        }
        RenderStyle::Points => {
            let colour = if selected { Color32::from_rgb(255, 200, 60) } else { Color32::from_gray(220) };
            for p in screen.iter().flatten() {
                painter.circle_filled(*p, 1.5, colour);
            }
        }
    }
}

/// The local rotation T(j) that gives joint j the world rotation `world_rotation`, from
/// F(j) = F(p(j))·R(j)·T(j): T(j) = (rot(F(p(j)))·R(j))⁻¹ · world rotation. For a root,
/// `parent_world_rotation` is the object's rotation.
#[must_use]
pub fn joint_rotation_from_world(
    parent_world_rotation: Quat,
    rest_rotation: Quat,
    world_rotation: Quat,
) -> Quat {
    ((parent_world_rotation * rest_rotation).inverse() * world_rotation).normalize()
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn joint_rotation_from_world_inverts_the_chain() {
        let parent = Quat::from_euler(glam::EulerRot::XYZ, 0.3, -0.7, 1.1);
        let rest = Quat::from_rotation_z(0.4);
        let local = Quat::from_euler(glam::EulerRot::XYZ, -0.2, 0.5, 0.9);
        let world = parent * rest * local;
        let back = joint_rotation_from_world(parent, rest, world);
        assert!(back.angle_between(local) < 1e-5, "{back:?} vs {local:?}");
    }
}
