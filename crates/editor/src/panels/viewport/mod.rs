//! The 3D viewport: orbit (left drag on empty space), pan (right or middle drag, or
//! Shift+left drag), zoom (scroll); the ground grid, the skeleton's bones, objects, lights, the
//! transform gizmo of the selection (`gizmo.rs`; or, in IK posing, the IK handle of a selected
//! joint: [`ik_handle`]), and click-to-select on joints, objects and lights. The scene is drawn by
//! keyrig-render on the GPU ([`crate::gpu_view`]) or, without one, by egui's painter
//! (`painter.rs`) from the meshes the frame skinned on the CPU.

mod constraint_lines;
mod gizmo;
mod grab;
pub mod ik_handle;
pub mod ik_targets;
pub mod motion_path;
mod painter;
mod reference;
mod targets;

use egui::{Align2, Color32, FontId, Pos2, Rect, Sense, Stroke, Ui};
use glam::Vec3;

use crate::actions::{Actions, SessionChange, ViewChange};
use crate::camera::{OrbitCamera, Projection};
use crate::context::FrameCtx;
use crate::gpu_view::GpuView;
use crate::ik_posing::IkGrab;
use crate::scene_frame::Wanted;
use crate::session::Selected;
use crate::widgets::measure::measure_text;

pub use gizmo::{joint_rotation_from_world, GizmoTool};
pub use grab::GRAB_GROUP;
pub use targets::Pivot;

/// Pick radius around joints and lights, points.
const PICK_RADIUS: f32 = 9.0;

/// The viewport and its own state: the gizmo and its drags, the IK handle's grab, a box
/// selection, the GPU view, where it was laid out and what it could not draw.
#[derive(Default)]
pub struct Viewport {
    gizmo: gizmo::GizmoState,
    /// A grab (Shift+D's move) under way.
    grab: grab::Grab,
    /// The reference image behind the scene, loaded.
    reference: reference::ReferenceView,
    /// A drag of a key on the motion path, until release.
    path_key: Option<motion_path::KeyDrag>,
    /// A drag of an IK constraint's target, until release.
    ik_target: Option<ik_targets::TargetDrag>,
    /// A press on the IK handle (IK posing), until release.
    ik_grab: Option<IkGrab>,
    /// Where a Ctrl+drag box selection started (screen points).
    box_select: Option<Pos2>,
    /// keyrig-render on eframe's device; `None` without the wgpu backend (the painter draws).
    gpu: Option<GpuView>,
    /// The GPU view could not draw the last frame: the painter draws, from CPU-skinned meshes.
    gpu_failed: bool,
    /// Where the viewport was laid out in the last frame (screen points).
    rect: Option<Rect>,
    /// What the viewport could not draw in the last frame (shown in red over it).
    errors: Vec<String>,
}

impl Viewport {
    /// Gives the viewport keyrig-render on eframe's wgpu device.
    pub fn attach_gpu(&mut self, gpu: GpuView) {
        self.gpu = Some(gpu);
        self.gpu_failed = false;
    }

    /// The GPU view, when the editor runs on eframe's wgpu backend.
    #[must_use]
    pub fn gpu(&self) -> Option<&GpuView> {
        self.gpu.as_ref()
    }

    /// Where the viewport was laid out in the last frame (screen points), for picking tools and
    /// tests that aim at what it shows.
    #[must_use]
    pub fn rect(&self) -> Option<Rect> {
        self.rect
    }

    /// Width / height of the viewport (16:10 before the first frame).
    #[must_use]
    pub fn aspect(&self) -> f32 {
        self.rect.map_or(1.6, |r| r.width() / r.height().max(1.0))
    }

    /// What the viewport could not draw in the last frame.
    #[must_use]
    pub fn errors(&self) -> &[String] {
        &self.errors
    }

    /// The gizmo's tool: which handles it shows.
    #[must_use]
    pub fn gizmo_tool(&self) -> GizmoTool {
        self.gizmo.tool
    }

    /// Chooses the gizmo's tool (W, E, S); choosing the one in use goes back to move and turn.
    /// Returns the tool now in use.
    pub fn toggle_gizmo_tool(&mut self, tool: GizmoTool) -> GizmoTool {
        self.gizmo.tool = if self.gizmo.tool == tool { GizmoTool::MoveAndTurn } else { tool };
        self.gizmo.tool
    }

    /// The ring drag under way, if any.
    #[must_use]
    pub fn ring_drag(&self) -> Option<&crate::twist::RingDrag> {
        self.gizmo.ring.as_ref().map(|r| &r.drag)
    }

    /// Starts a grab of the selection in the next frame (Shift+D: the duplicate follows the
    /// pointer until a click or Enter places it).
    pub fn start_grab(&mut self) {
        self.grab = grab::Grab::Requested;
    }

    /// Whether a grab is under way: the window keeps its undo group open while no button is
    /// held.
    #[must_use]
    pub fn holds_undo_group(&self) -> bool {
        self.grab.active()
    }

    /// Lets go of the IK handle (IK posing turned off, another document).
    pub fn release_ik_handle(&mut self) {
        self.ik_grab = None;
    }

    /// What the viewport needs prepared on the CPU this frame: every mesh for the painter, the
    /// selected joint's object for the cross-section readout, the clip planes' box for the GPU.
    #[must_use]
    pub fn wanted(&self, selection: Option<Selected>) -> Wanted {
        let painter = self.gpu.is_none() || self.gpu_failed;
        Wanted {
            cpu_meshes: painter,
            cpu_object: match selection {
                Some(Selected::Joint { object, .. }) => Some(object),
                _ => None,
            },
            depth_bounds: !painter,
        }
    }

    /// The viewport: draws the frame (GPU, else the painter), the skeleton and light overlays,
    /// the gizmo; then camera navigation and click-to-select.
    pub fn ui(&mut self, ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
        egui::CentralPanel::default().frame(egui::Frame::NONE).show_inside(ui, |ui| {
            let rect = ui.available_rect_before_wrap();
            let response = ui.allocate_rect(rect, Sense::click_and_drag());
            let painter = ui.painter_at(rect);
            // Filled below only when the painter draws: under the GPU image it would double the
            // pixels a CPU rasterizer shades (docs/benchmarks.md, "Editor").
            let background = painter.add(egui::Shape::Noop);
            self.rect = Some(rect);
            let through = look_through_state(ctx);
            let projection = match &through {
                Some(camera) => Projection::through(camera, rect),
                None => Projection::new(&ctx.view.camera, rect),
            };
            let mut errors = ctx.scene.errors().to_vec();

            // The reference image goes under the scene: on the background the painter fills, or
            // under a GPU image rendered see-through.
            let behind = painter.add(egui::Shape::Noop);
            let reference = self.reference.shape(ui, ctx, rect, &mut errors);
            let see_through = reference.is_some();
            let gpu_drawn = self.gpu_ui(ui, ctx, rect, &mut errors, see_through);
            if !gpu_drawn || see_through {
                painter.set(background, egui::Shape::rect_filled(rect, 0.0, Color32::from_rgb(38, 40, 46)));
            }
            if let Some(shape) = reference {
                painter.set(behind, shape);
            }
            if !gpu_drawn {
                painter::paint_scene(&painter, &projection, ctx);
            }
            painter::paint_axes(&painter, &projection, ctx);
            if !gpu_drawn && ctx.view.bones {
                painter::paint_bones(&painter, &projection, ctx);
            }
            painter::paint_lights(&painter, &projection, ctx);
            constraint_lines::paint(&painter, &projection, ctx);
            if !gpu_drawn {
                painter::paint_cameras(&painter, &projection, ctx);
            }
            if through.is_some() {
                painter::paint_render_frame(&painter, rect, ctx);
            }
            let pick_targets = pick_targets(&projection, ctx);

            // Gizmo for the selection (drawn last, on top); in IK posing a selected joint shows
            // its IK handle instead. Either owns the primary button only on one of its handles;
            // scroll, right/middle drags and drags that start elsewhere stay with the camera, as
            // in Blender's viewport.
            // A grab (Shift+D) owns the pointer and the gizmo waits until it ends.
            let grabbing = self.grab.active();
            let grab_owns = self.grab.ui(ui, ctx, actions, &projection, rect);
            // An IK constraint's target under the pointer, or being dragged, comes before the
            // gizmo.
            let target_owns = !grabbing
                && ik_targets::ui(ui, ctx, actions, &mut self.ik_target, &projection, rect, &response);
            // So does a key handle of the motion path.
            let target_owns = target_owns
                || (!grabbing
                    && motion_path::ui(ui, ctx, actions, &mut self.path_key, &projection, rect, &response));
            let handle = if grabbing {
                Some(grab_owns)
            } else if target_owns {
                Some(true)
            } else if ik_handle::handle_joint(ctx).is_some() {
                self.gizmo.drag = false;
                self.gizmo.ring = None;
                ik_handle::handle_ui(ui, ctx, actions, &mut self.ik_grab, &projection, rect, &response)
            } else {
                self.ik_grab = None;
                None
            };
            // The gizmo's tools (W, E, S are commands), as buttons while something is selected.
            if ctx.session.selection.item.is_some() {
                let object = matches!(ctx.session.selection.item, Some(crate::session::Selected::Object(_)));
                let tools = [
                    (GizmoTool::Move, crate::commands::Command::GizmoMove),
                    (GizmoTool::Turn, crate::commands::Command::GizmoTurn),
                    (GizmoTool::Scale, crate::commands::Command::GizmoScale),
                ];
                let mut x = 8.0;
                for (tool, command) in tools {
                    if tool == GizmoTool::Scale && !object {
                        continue;
                    }
                    let at = egui::Rect::from_min_size(
                        rect.left_bottom() + egui::vec2(x, -30.0),
                        egui::vec2(52.0, 22.0),
                    );
                    x += 56.0;
                    let button = ui
                        .put(at, egui::Button::selectable(self.gizmo.tool == tool, tool.label()))
                        .on_hover_text(format!(
                            "{} ({}; again: move and turn)",
                            command.tooltip(),
                            command.shortcut_text(ui.ctx())
                        ));
                    if button.clicked() {
                        actions.command(command);
                    }
                }
            }
            let gizmo_owns_primary = match handle {
                Some(owns) => owns,
                None => self.gizmo.ui(ui, ctx, actions, &projection, rect, &response),
            };
            let boxing = self.box_select(ui, actions, &response, &painter, &pick_targets, gizmo_owns_primary);
            navigate(ui, ctx, actions, &response, rect, gizmo_owns_primary || boxing);
            if response.clicked() && !gizmo_owns_primary {
                if let Some(pos) = response.interact_pointer_pos() {
                    let adding = ui.input(|i| i.modifiers.shift || i.modifiers.command);
                    match (pick(&pick_targets, pos), adding) {
                        (Some(item), true) => actions.session(SessionChange::Toggle(item)),
                        (hit, false) => actions.session(SessionChange::SelectOnly(hit)),
                        (None, true) => {}
                    }
                }
            }
            self.pivot_ui(ui, rect);
            overlay_ui(&painter, rect, ctx, &errors, self.gpu.is_some());
            self.errors = errors;
        });
    }
}

/// Where each object origin, joint and light is on screen, for click-to-select (objects
/// first, then their joints, then lights, as they were drawn).
fn pick_targets(projection: &Projection, ctx: &FrameCtx<'_>) -> Vec<(Pos2, Selected)> {
    let scene = ctx.scene();
    let mut targets = Vec::new();
    for (o, pose) in ctx.scene.poses().iter().enumerate() {
        let Some(pose) = pose else { continue };
        if ctx.session.hidden.object(scene, o) {
            continue;
        }
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
    let lights = ctx.scene.state().map_or(&[][..], |s| s.lights.as_slice());
    for (l, light_state) in lights.iter().enumerate().take(scene.lights.len()) {
        if let Some(p) = projection.project(light_state.position) {
            targets.push((p, Selected::Light(l)));
        }
    }
    let cameras = ctx.scene.state().map_or(&[][..], |s| s.cameras.as_slice());
    for (c, camera) in cameras.iter().enumerate().take(scene.cameras.len()) {
        if ctx.looking_through() == Some(c) {
            continue;
        }
        if let Some(p) = projection.project(camera.eye()) {
            targets.push((p, Selected::Camera(c)));
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

impl Viewport {
    /// The size in pixels of the reference image shown behind the scene, when one is.
    #[must_use]
    pub fn reference_image_size(&self) -> Option<[usize; 2]> {
        self.reference.size()
    }

    /// The pivot setting in the viewport's top-right corner, as Blender's header: where the
    /// gizmo turns several selected items about ([`Pivot`]).
    fn pivot_ui(&mut self, ui: &mut Ui, rect: Rect) {
        // Below the record marker, which takes the corner itself.
        let area =
            Rect::from_min_size(egui::pos2(rect.right() - 186.0, rect.top() + 30.0), egui::vec2(180.0, 22.0));
        let pivot = &mut self.gizmo.pivot;
        ui.put(area, |ui: &mut Ui| {
            egui::ComboBox::from_label("Pivot")
                .selected_text(pivot.label())
                .width(132.0)
                .show_ui(ui, |ui| {
                    for choice in Pivot::ALL {
                        ui.selectable_value(pivot, choice, choice.label()).on_hover_text(choice.help());
                    }
                })
                .response
                .on_hover_text("Pivot point: where several selected items turn about")
        });
    }

    /// The gizmo's pivot setting.
    #[must_use]
    pub fn pivot(&self) -> Pivot {
        self.gizmo.pivot
    }

    /// Ctrl+drag on empty space draws a box and selects the joints inside it when released
    /// (Ctrl+Shift+drag adds them to the selection). Returns whether a box drag is under way.
    fn box_select(
        &mut self,
        ui: &Ui,
        actions: &mut Actions,
        response: &egui::Response,
        painter: &egui::Painter,
        targets: &[(Pos2, Selected)],
        gizmo_owns_primary: bool,
    ) -> bool {
        let (ctrl, shift) = ui.input(|i| (i.modifiers.command, i.modifiers.shift));
        if response.drag_started_by(egui::PointerButton::Primary) && ctrl && !gizmo_owns_primary {
            self.box_select = ui.input(|i| i.pointer.press_origin());
        }
        let Some(start) = self.box_select else { return false };
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
            self.box_select = None;
            let joints = targets
                .iter()
                .filter(|(p, item)| area.contains(*p) && matches!(item, Selected::Joint { .. }))
                .map(|(_, item)| *item);
            if !shift {
                actions.session(SessionChange::SelectOnly(None));
            }
            for joint in joints {
                actions.session(SessionChange::Add(joint));
            }
        }
        true
    }
}

/// Orbit (left drag), pan (right or middle drag, Shift+left drag) and zoom (scroll); a
/// primary drag the gizmo owns is left to it.
fn navigate(
    ui: &Ui,
    ctx: &FrameCtx<'_>,
    actions: &mut Actions,
    response: &egui::Response,
    rect: Rect,
    gizmo_owns_primary: bool,
) {
    let mut camera = ctx.view.camera;
    let shift = ui.input(|i| i.modifiers.shift);
    let primary = response.dragged_by(egui::PointerButton::Primary) && !gizmo_owns_primary;
    if primary && !shift {
        let d = response.drag_delta();
        camera.orbit(d.x, d.y);
    } else if response.dragged_by(egui::PointerButton::Secondary)
        || response.dragged_by(egui::PointerButton::Middle)
        || (primary && shift)
    {
        let d = response.drag_delta();
        camera.pan(d.x, d.y, rect.height());
    }
    if response.contains_pointer() {
        let scroll = ui.input(|i| i.smooth_scroll_delta.y);
        if scroll != 0.0 {
            camera.zoom(scroll);
        }
    }
    if camera != ctx.view.camera {
        // Orbiting, panning or zooming leaves a scene camera's view for the orbit camera.
        if ctx.view.look_through.is_some() {
            actions.view(ViewChange::LookThrough(None));
        }
        actions.view(ViewChange::Camera(camera));
    }
}

/// The scene camera the viewport looks through this frame, when it does and it can be
/// projected.
fn look_through_state(ctx: &FrameCtx<'_>) -> Option<keyrig_eval::CameraState> {
    let c = ctx.looking_through()?;
    ctx.scene.state()?.cameras.get(c).copied().filter(keyrig_eval::CameraState::is_usable)
}

impl Viewport {
    /// Renders the viewport with keyrig-render when the editor runs on eframe's wgpu backend.
    /// Returns false (and adds the reason to `errors` when there is one) to let the painter draw.
    fn gpu_ui(
        &mut self,
        ui: &Ui,
        ctx: &FrameCtx<'_>,
        rect: Rect,
        errors: &mut Vec<String>,
        see_through: bool,
    ) -> bool {
        let Some(gpu) = self.gpu.as_mut() else { return false };
        let Some(state) = ctx.scene.state() else { return false };
        let scene = ctx.scene();
        // Objects hidden with H are left out of what is drawn.
        let state = ctx.session.hidden.drawn(scene, state);
        let state = state.as_ref();
        let eval = ctx.evaluator();
        let c = ctx.view.camera;
        let view = keyrig_render::ViewOptions {
            style: ctx.view.style,
            textures: ctx.view.textures,
            deformer: None,
            grid: ctx.view.grid,
            skeletons: ctx.view.bones,
            motion_path: ctx.view.motion_path,
            selection: ctx.session.selection.item,
            camera: Some(c),
            depth_range: Some(c.depth_range(ctx.scene.depth_bounds())),
            look_through: look_through_state(ctx).and(ctx.looking_through()),
            ..keyrig_render::ViewOptions::default()
        };
        let ppp = ui.ctx().pixels_per_point() * ctx.view.resolution_scale.clamp(0.25, 1.0);
        let size =
            [(rect.width() * ppp).round().max(1.0) as u32, (rect.height() * ppp).round().max(1.0) as u32];
        let rig_key = crate::scene_frame::evaluator_key(ctx.doc, ctx.meshes);
        let mut morph_meshes = std::collections::HashMap::new();
        let mut materials = std::collections::HashMap::new();
        if gpu.needs_rig(rig_key) {
            let base_dir = ctx.base_dir();
            materials = ctx.meshes.materials_for(base_dir, scene);
            for (o, object) in scene.objects.iter().enumerate() {
                if let Some(keyrig_core::MeshSource::File { path, mesh, .. }) = &object.mesh {
                    if let Some(crate::files::FileMesh::Morph(m)) = ctx.meshes.peek(base_dir, path, *mesh) {
                        morph_meshes.insert(o, std::sync::Arc::clone(m));
                    }
                }
            }
        }
        let ghosts = match ctx.selected_object() {
            Some(o) if ctx.view.onion.enabled => {
                crate::onion::ghost_frames(&ctx.view.onion, scene, o, ctx.session.playback.frame)
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
            evaluator: std::sync::Arc::clone(&eval),
            state,
            overrides: &ctx.session.overrides,
            view,
            morph_meshes,
            materials,
            ghosts,
            see_through,
        };
        if let Err(e) = gpu.set_antialiasing(ctx.view.antialiasing) {
            errors.push(format!("GPU viewport: {e}"));
        }
        let one_to_one = ctx.view.resolution_scale >= 1.0;
        let drawn = match gpu.render(frame, size, one_to_one) {
            Ok(image) => {
                ui.painter().with_clip_rect(rect).add(image.paint_callback(rect));
                true
            }
            Err(e) => {
                errors.push(format!("GPU viewport: {e}"));
                false
            }
        };
        // A failed frame is drawn by the painter from the next frame on, whose preparation skins
        // the meshes on the CPU: ask for that frame now.
        if !drawn && !self.gpu_failed {
            ui.ctx().request_repaint();
        }
        self.gpu_failed = !drawn;
        drawn
    }
}

/// The frame, the deformer, the cross-section measure and the onion skin in the corner; what
/// could not be drawn in red; the record frame.
fn overlay_ui(painter: &egui::Painter, rect: Rect, ctx: &FrameCtx<'_>, errors: &[String], gpu: bool) {
    let mut lines = vec![format!("Frame {}  ·  {:.2} s", ctx.session.playback.whole_frame(), ctx.time())];
    if let Some(o) =
        ctx.selected_object().or_else(|| ctx.scene().objects.iter().position(|x| x.skeleton.is_some()))
    {
        if let Some(object) = ctx.scene().objects.get(o) {
            if object.skeleton.is_some() {
                // The deformer the frame uses: a keyed deformer's value at this time, else the
                // object's setting.
                let evaluated = ctx.scene.state().and_then(|s| s.objects.get(o)).map(|s| s.look.deformer);
                let kind = evaluated.unwrap_or(object.deformer.kind);
                let keyed = if kind == object.deformer.kind { "" } else { " (keyed)" };
                lines.push(format!("{}: {}{keyed}", object.name, kind.label()));
            }
        }
    }
    if let Some(text) = measure_text(ctx) {
        lines.push(text);
    }
    let onion = &ctx.view.onion;
    if onion.enabled {
        lines.push(match ctx.selected_object() {
            Some(_) if !gpu => "Onion skin: shown in the GPU viewport only".to_owned(),
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
    if ctx.session.record {
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
