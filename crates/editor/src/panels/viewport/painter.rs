//! The viewport drawn with egui's painter, when there is no GPU viewport (the UI tests, or a
//! GPU failure): the grid, the meshes as the frame skinned them on the CPU (flat-shaded, back
//! faces culled, sorted far to near), and the overlays both viewports share (object axes,
//! lights; bones where the GPU does not draw them).

use egui::{Color32, Pos2, Stroke};
use glam::{Affine3A, Vec3};

use crate::camera::{OrbitCamera, Projection};
use crate::context::FrameCtx;
use crate::session::Selected;
use crate::view::RenderStyle;

/// The painter's scene without a GPU viewport: grid and the meshes as this frame deformed
/// them on the CPU.
pub(super) fn paint_scene(painter: &egui::Painter, projection: &Projection, ctx: &FrameCtx<'_>) {
    if ctx.view.grid {
        draw_grid(painter, projection);
    }
    let scene = ctx.scene();
    for o in 0..scene.objects.len() {
        // Hidden objects (their visibility attribute) are not drawn, as on the GPU.
        if ctx.scene.state().and_then(|s| s.objects.get(o)).is_some_and(|s| !s.look.visible)
            || ctx.session.hidden.object(scene, o)
        {
            continue;
        }
        let (Some(pose), Some((positions, indices))) =
            (ctx.pose(o), ctx.scene.cpu_mesh(o, scene, ctx.meshes, ctx.base_dir()))
        else {
            continue;
        };
        let world: Vec<Vec3> =
            positions.iter().map(|&p| pose.world_from_object.transform_point3(p)).collect();
        let selected = ctx.is_active(Selected::Object(o));
        draw_mesh(painter, projection, &ctx.view.camera, &world, indices, ctx.view.style, selected);
    }
}

/// Bones and joints of every skeleton (the painter's skeleton overlay; the GPU viewport draws
/// its own).
pub(super) fn paint_bones(painter: &egui::Painter, projection: &Projection, ctx: &FrameCtx<'_>) {
    let scene = ctx.scene();
    for (o, pose) in ctx.scene.poses().iter().enumerate() {
        let Some(pose) = pose else { continue };
        let Some(skeleton) = &scene.objects[o].skeleton else { continue };
        if ctx.session.hidden.object(scene, o) {
            continue;
        }
        for (j, joint) in skeleton.joints.iter().enumerate() {
            let world = pose.world_from_object * pose.object_from_joint[j];
            let at: Vec3 = world.translation.into();
            let selected = ctx.is_active(Selected::Joint { object: o, joint: j });
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
pub(super) fn paint_axes(painter: &egui::Painter, projection: &Projection, ctx: &FrameCtx<'_>) {
    let scene = ctx.scene();
    for (o, (object, pose)) in scene.objects.iter().zip(ctx.scene.poses()).enumerate() {
        if ctx.session.hidden.object(scene, o) {
            continue;
        }
        if let (None, Some(pose)) = (&object.mesh, pose) {
            draw_axes(painter, projection, pose.world_from_object);
        }
    }
}

/// Light icons with their direction.
pub(super) fn paint_lights(painter: &egui::Painter, projection: &Projection, ctx: &FrameCtx<'_>) {
    let Some(state) = ctx.scene.state() else { return };
    for ((l, light), light_state) in ctx.scene().lights.iter().enumerate().zip(&state.lights) {
        let pos = light_state.position;
        let Some(p) = projection.project(pos) else { continue };
        let selected = ctx.is_active(Selected::Light(l));
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

/// Each shown scene camera but the one looked through as its frustum (keyrig-render's lines, drawn
/// by the painter when the GPU does not draw).
pub(super) fn paint_cameras(painter: &egui::Painter, projection: &Projection, ctx: &FrameCtx<'_>) {
    let Some(state) = ctx.scene.state() else { return };
    let scene = ctx.scene();
    let aspect = scene.render_size.map_or(16.0 / 9.0, keyrig_core::RenderSize::aspect);
    let active = scene.active_camera_at(ctx.session.playback.frame);
    let mut lines = keyrig_render::overlay::Lines::default();
    // The renderer's overlay size: in proportion to the distance looked from.
    let marker = match super::look_through_state(ctx) {
        Some(through) => through.eye().distance(ctx.view.camera.target).max(1e-3) * 0.008,
        None => ctx.view.camera.distance * 0.008,
    };
    for (c, camera) in state.cameras.iter().enumerate() {
        if ctx.looking_through() == Some(c) || !camera.is_usable() || !camera.visible {
            continue;
        }
        let gizmo = keyrig_render::CameraGizmo {
            camera: *camera,
            aspect,
            selected: ctx.is_active(Selected::Camera(c)),
            active: active == Some(c),
        };
        keyrig_render::overlay::camera_gizmo(&mut lines, &gizmo, marker);
    }
    for pair in lines.vertices.chunks_exact(2) {
        let at =
            |v: &keyrig_render::overlay::LineVertex| Vec3::new(v.position[0], v.position[1], v.position[2]);
        let [r, g, b, _] = pair[0].colour.map(|x| (x.clamp(0.0, 1.0) * 255.0) as u8);
        if let Some(seg) = projection.project_segment(at(&pair[0]), at(&pair[1])) {
            painter.line_segment(seg, Stroke::new(1.5, Color32::from_rgb(r, g, b)));
        }
    }
}

/// Looking through a scene camera: the part of the viewport its rendered image covers (the
/// scene's render aspect about the vertical field of view), outlined, with the camera's name.
pub(super) fn paint_render_frame(painter: &egui::Painter, rect: egui::Rect, ctx: &FrameCtx<'_>) {
    let scene = ctx.scene();
    let Some(camera) = ctx.looking_through().and_then(|c| scene.cameras.get(c)) else { return };
    let aspect = scene.render_size.map_or(16.0 / 9.0, keyrig_core::RenderSize::aspect);
    let width = (rect.height() * aspect).min(rect.width());
    let frame = egui::Rect::from_center_size(rect.center(), egui::vec2(width, rect.height()));
    let shade = Color32::from_black_alpha(110);
    for side in [
        egui::Rect::from_min_max(rect.min, egui::pos2(frame.left(), rect.bottom())),
        egui::Rect::from_min_max(egui::pos2(frame.right(), rect.top()), rect.max),
    ] {
        if side.width() > 0.5 {
            painter.rect_filled(side, 0.0, shade);
        }
    }
    painter.rect_stroke(frame, 0.0, Stroke::new(1.0, Color32::from_gray(200)), egui::StrokeKind::Inside);
    painter.text(
        frame.left_bottom() + egui::vec2(8.0, -6.0),
        egui::Align2::LEFT_BOTTOM,
        format!("Camera: {}", camera.name),
        egui::FontId::proportional(14.0),
        Color32::from_gray(230),
    );
}

pub(super) fn draw_grid(painter: &egui::Painter, projection: &Projection) {
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
