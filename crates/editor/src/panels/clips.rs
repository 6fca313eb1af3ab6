//! The clip editor (docs/clips.md, docs/guide.md "Clips"): the selected object's clip tracks
//! with their strips on a time axis, an action selector that adds a strip, *Push down* and
//! *Merge down*, and the scene's layers with their weights. It shares the dope sheet's place in
//! the bottom panel (the *Clips* tab).
//!
//! Dragging a strip moves it; dragging its left or right edge trims it; dragging the small
//! handles at its top corners sets its blend in and out; a right click opens its menu (speed,
//! repeat, influence, reverse, blend mode, extrapolation, root motion, delete). A drag shows the
//! strip where it would go and becomes one undo step when released
//! ([`keyrig_edit::ClipEdit`]); a move stops at the neighbouring strips.

use egui::{Color32, Pos2, Rect, Sense, Stroke, Ui, Vec2};
use keyrig_core::{ClipTrack, Extrapolation, LayerMode, Scene, Strip, StripBlend};
use keyrig_edit::{ClipEdit, SceneEdit};

use crate::actions::{Action, Actions, Edit, SessionChange};
use crate::context::FrameCtx;
use crate::widgets::time_axis::TimeAxis;

const ROW: f32 = 24.0;
const NAMES: f32 = 150.0;
const EDGE: f32 = 6.0;
const HANDLE: f32 = 10.0;

/// What part of a strip a drag holds.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Grip {
    Body,
    TrimIn,
    TrimOut,
    BlendIn,
    BlendOut,
}

#[derive(Clone, Debug)]
struct StripDrag {
    object: usize,
    track: usize,
    strip: usize,
    grip: Grip,
    /// The strip when the drag began, and the pointer's frame then.
    origin: Strip,
    from_frame: f64,
    /// The pointer's frame in the last frame the button was down: the drag ends there (a
    /// release can come with a move away in the same frame).
    last_frame: f64,
}

/// The clip editor's state: whether its tab is shown, the drag in progress, the action the
/// selector adds and the new layer's name.
#[derive(Debug, Default)]
pub struct ClipEditor {
    /// The Clips tab is shown in place of the dope sheet.
    pub shown: bool,
    drag: Option<StripDrag>,
    add_action: Option<String>,
    layer_name: String,
}

fn blend_colour(blend: StripBlend) -> Color32 {
    match blend {
        StripBlend::Replace => Color32::from_rgb(70, 110, 160),
        StripBlend::Combine => Color32::from_rgb(90, 140, 90),
        StripBlend::Add => Color32::from_rgb(150, 110, 60),
    }
}

impl StripDrag {
    /// The strip as the drag has it with the pointer at `frame` (whole frames), kept clear of
    /// the neighbouring strips of `track`.
    fn dragged(&self, track: &ClipTrack, frame: f64) -> Strip {
        let mut s = self.origin.clone();
        let delta = (frame - self.from_frame).round();
        let before =
            self.strip.checked_sub(1).and_then(|i| track.strips.get(i)).map_or(f64::NEG_INFINITY, Strip::end);
        let after = track.strips.get(self.strip + 1).map_or(f64::INFINITY, |n| n.start);
        match self.grip {
            Grip::Body => {
                let length = s.length();
                s.start = (s.start + delta).max(before).min(after - length);
            }
            Grip::TrimIn => {
                // The start and the first action frame move together: the rest stays put.
                let room = (s.action_length() - 1.0) / s.speed;
                let d = delta.max(before - s.start).min(room);
                s.start += d;
                s.action_in += d * s.speed;
            }
            Grip::TrimOut => {
                let d = (delta * s.speed / s.repeat).max(1.0 - s.action_length());
                let d = d.min((after - s.end()) * s.speed / s.repeat);
                s.action_out += d;
            }
            Grip::BlendIn => s.blend_in = (self.origin.blend_in + delta).clamp(0.0, s.length() - s.blend_out),
            Grip::BlendOut => {
                s.blend_out = (self.origin.blend_out - delta).clamp(0.0, s.length() - s.blend_in)
            }
        }
        s.blend_in = s.blend_in.min(s.length());
        s.blend_out = s.blend_out.min(s.length() - s.blend_in);
        s
    }
}

impl ClipEditor {
    pub fn ui(&mut self, ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
        let scene = ctx.scene();
        let Some(o) = ctx.selected_object() else {
            ui.label("Select an object to see its clip tracks.");
            self.layers_ui(ui, scene, actions);
            return;
        };
        let object = &scene.objects[o];
        let frame_now = ctx.time() * scene.fps;
        self.header_ui(ui, scene, o, frame_now, actions);
        // The time axis: the frame range, or what the strips span when they reach beyond it.
        let (mut start, mut end) = (f64::from(scene.frame_range.start), f64::from(scene.frame_range.end));
        for s in object.clip_tracks.iter().flat_map(|t| &t.strips) {
            if s.is_playable() {
                start = start.min(s.start);
                end = end.max(s.end());
            }
        }
        let rows = object.clip_tracks.len().max(1);
        let height = ROW * (rows as f32 + 1.0) + 4.0;
        let (area, _) = ui.allocate_exact_size(Vec2::new(ui.available_width(), height), Sense::hover());
        let axis = TimeAxis {
            left: area.left() + NAMES,
            right: area.right() - 8.0,
            start,
            end: end.max(start + 1.0),
        };
        let painter = ui.painter_at(area);
        painter.rect_filled(area, 0.0, ui.visuals().extreme_bg_color);
        // The ruler: a click or drag there sets the frame.
        let ruler =
            Rect::from_min_max(Pos2::new(axis.left, area.top()), Pos2::new(axis.right, area.top() + ROW));
        let ruler_response = ui.interact(ruler, ui.id().with("clip ruler"), Sense::click_and_drag());
        if let Some(p) = ruler_response.interact_pointer_pos() {
            actions.session(SessionChange::SetFrame(axis.frame(p.x).round() as i32));
        }
        let step = ((end - start) / 10.0).max(1.0).round();
        let mut f = (start / step).ceil() * step;
        while f <= end {
            let x = axis.x(f);
            painter.line_segment(
                [Pos2::new(x, ruler.bottom() - 5.0), Pos2::new(x, area.bottom())],
                Stroke::new(1.0, ui.visuals().faint_bg_color),
            );
            painter.text(
                Pos2::new(x + 2.0, ruler.top() + 2.0),
                egui::Align2::LEFT_TOP,
                format!("{f}"),
                egui::FontId::proportional(11.0),
                ui.visuals().weak_text_color(),
            );
            f += step;
        }
        if object.clip_tracks.is_empty() {
            painter.text(
                Pos2::new(area.left() + 8.0, area.top() + ROW * 1.5),
                egui::Align2::LEFT_CENTER,
                "No clip tracks: push the active action down, or add a strip of an action.",
                egui::FontId::proportional(12.0),
                ui.visuals().weak_text_color(),
            );
        }
        let pointer = ui.input(|i| i.pointer.interact_pos());
        if let (Some(d), Some(p)) = (&mut self.drag, pointer) {
            if ui.input(|i| i.pointer.any_down()) {
                d.last_frame = axis.frame(p.x);
            }
        }
        let any_solo = object.clip_tracks.iter().any(|t| t.solo);
        // Tracks bottom-up: the first track is drawn lowest.
        for (k, track) in object.clip_tracks.iter().enumerate() {
            let row_top = area.top() + ROW * (1.0 + (object.clip_tracks.len() - 1 - k) as f32);
            let row = Rect::from_min_size(Pos2::new(area.left(), row_top), Vec2::new(area.width(), ROW));
            self.track_header_ui(ui, row, o, k, track, actions);
            let faded = !track.plays(any_solo);
            for (i, strip) in track.strips.iter().enumerate() {
                let dragging = self.drag.as_ref().filter(|d| (d.object, d.track, d.strip) == (o, k, i));
                let shown = match dragging {
                    Some(d) => d.dragged(track, d.last_frame),
                    None => strip.clone(),
                };
                self.strip_ui(ui, &painter, &axis, row, (o, k, i), track, &shown, faded, actions);
            }
        }
        // The current frame.
        let x = axis.x(frame_now);
        painter.line_segment(
            [Pos2::new(x, area.top()), Pos2::new(x, area.bottom())],
            Stroke::new(1.5, Color32::from_rgb(230, 90, 60)),
        );
        // A drag ends: one undo step.
        if let Some(d) = &self.drag {
            if !ui.input(|i| i.pointer.any_down()) {
                if let Some(track) = object.clip_tracks.get(d.track) {
                    let value = d.dragged(track, d.last_frame);
                    if value != d.origin {
                        let edit =
                            ClipEdit::Strip { object: d.object, track: d.track, strip: d.strip, value };
                        actions.edit(Edit::scene(SceneEdit::Clip(edit)));
                    }
                }
                self.drag = None;
            }
        }
        ui.add_space(ROW * 0.5);
        ui.separator();
        self.layers_ui(ui, scene, actions);
    }

    /// The action selector, Add strip, Push down and Merge down.
    fn header_ui(&mut self, ui: &mut Ui, scene: &Scene, o: usize, frame: f64, actions: &mut Actions) {
        let object = &scene.objects[o];
        ui.horizontal_wrapped(|ui| {
            ui.strong(&object.name);
            let chosen = self.add_action.clone().filter(|a| scene.action_index(a).is_some());
            let label = ui.label("Action");
            egui::ComboBox::from_id_salt("clip action")
                .selected_text(chosen.clone().unwrap_or_else(|| "(choose)".to_owned()))
                .show_ui(ui, |ui| {
                    for a in &scene.actions {
                        ui.selectable_value(&mut self.add_action, Some(a.name.clone()), &a.name);
                    }
                })
                .response
                .labelled_by(label.id)
                .on_hover_text("The action Add strip places");
            let add = ui.add_enabled(chosen.is_some(), egui::Button::new("Add strip"));
            if add
                .on_hover_text("A new track on top with a strip of the action, starting at the current frame")
                .clicked()
            {
                if let Some(action) = chosen {
                    let edit = ClipEdit::AddStrip { object: o, action, start: frame.round() };
                    actions.edit(Edit::scene(SceneEdit::Clip(edit)));
                }
            }
            let can_push = !scene.keyed_channels_of(o).is_empty();
            if ui
                .add_enabled(can_push, egui::Button::new("Push down"))
                .on_hover_text(
                    "The active action becomes a strip on a new top track; the object then plays no action",
                )
                .clicked()
            {
                actions.edit(Edit::scene(SceneEdit::Clip(ClipEdit::PushDown { object: o })));
            }
            let mixing = scene.objects.iter().any(|x| !x.clip_tracks.is_empty()) || !scene.layers.is_empty();
            if ui
                .add_enabled(mixing, egui::Button::new("Merge down"))
                .on_hover_text(
                    "Bake the clip tracks and layers into each object's active action, a key per frame",
                )
                .clicked()
            {
                actions.edit(Edit::scene(SceneEdit::Clip(ClipEdit::MergeDown)));
            }
        });
    }

    /// A track's name and its mute and solo toggles.
    fn track_header_ui(
        &self,
        ui: &mut Ui,
        row: Rect,
        o: usize,
        k: usize,
        track: &ClipTrack,
        actions: &mut Actions,
    ) {
        let names = Rect::from_min_size(row.min, Vec2::new(NAMES - 4.0, ROW));
        ui.put(names, |ui: &mut Ui| {
            ui.horizontal(|ui| {
                let mut mute = track.mute;
                let mut solo = track.solo;
                let m = ui.toggle_value(&mut mute, "M").on_hover_text(format!("Mute track {}", track.name));
                let s = ui.toggle_value(&mut solo, "S").on_hover_text(format!("Solo track {}", track.name));
                ui.label(&track.name);
                if m.changed() || s.changed() {
                    let edit = ClipEdit::Track { object: o, track: k, mute, solo };
                    actions.edit(Edit::scene(SceneEdit::Clip(edit)));
                }
            })
            .response
        });
    }

    /// One strip: its box, ramps and handles, its drags and its menu.
    #[allow(clippy::too_many_arguments)]
    fn strip_ui(
        &mut self,
        ui: &mut Ui,
        painter: &egui::Painter,
        axis: &TimeAxis,
        row: Rect,
        (o, k, i): (usize, usize, usize),
        track: &ClipTrack,
        strip: &Strip,
        faded: bool,
        actions: &mut Actions,
    ) {
        if !strip.is_playable() {
            return;
        }
        let (x0, x1) = (axis.x(strip.start), axis.x(strip.end()).max(axis.x(strip.start) + 4.0));
        let rect = Rect::from_min_max(Pos2::new(x0, row.top() + 2.0), Pos2::new(x1, row.bottom() - 2.0));
        let mut fill = blend_colour(strip.blend);
        if faded {
            fill = fill.gamma_multiply(0.4);
        }
        painter.rect_filled(rect, 3.0, fill);
        // The ramps: a line from the bottom at the strip's ends to the top where the blend ends.
        let ramp = Stroke::new(1.5, Color32::WHITE);
        if strip.blend_in > 0.0 {
            let xb = axis.x(strip.start + strip.blend_in);
            painter.line_segment([Pos2::new(x0, rect.bottom()), Pos2::new(xb, rect.top())], ramp);
        }
        if strip.blend_out > 0.0 {
            let xb = axis.x(strip.end() - strip.blend_out);
            painter.line_segment([Pos2::new(xb, rect.top()), Pos2::new(x1, rect.bottom())], ramp);
        }
        let mut text = strip.action.clone();
        if strip.repeat != 1.0 {
            text += &format!(" ×{}", strip.repeat);
        }
        if strip.reverse {
            text += " ⟲";
        }
        painter.with_clip_rect(rect).text(
            rect.left_center() + Vec2::new(6.0, 0.0),
            egui::Align2::LEFT_CENTER,
            text,
            egui::FontId::proportional(12.0),
            Color32::WHITE,
        );
        // Hit areas: the blend handles at the top corners, the edges, then the body.
        let id = ui.id().with(("clip strip", o, k, i));
        // A handle takes the upper part of the strip's height around its blend's end (drawn
        // as a small square at the top), so a press a little below the corner still finds it.
        let handle = |x: f32| {
            Rect::from_min_max(
                Pos2::new(x - HANDLE / 2.0, rect.top()),
                Pos2::new(x + HANDLE / 2.0, rect.top() + rect.height() * 0.7),
            )
        };
        let handle_in = handle(axis.x(strip.start + strip.blend_in));
        let handle_out = handle(axis.x(strip.end() - strip.blend_out));
        for h in [handle_in, handle_out] {
            let square = Rect::from_min_size(Pos2::new(h.left() + 1.5, h.top()), Vec2::splat(HANDLE - 3.0));
            painter.rect_filled(square, 1.0, Color32::from_gray(230));
        }
        let label = format!("strip {} on track {}", strip.action, track.name);
        let body = ui.interact(rect, id, Sense::click_and_drag()).on_hover_text(format!(
            "{label}: frames {:.1}–{:.1}; drag to move, drag an edge to trim, right click for more",
            strip.start,
            strip.end()
        ));
        body.widget_info(|| egui::WidgetInfo::labeled(egui::WidgetType::Button, true, &label));
        let parts = [
            (handle_in, Grip::BlendIn, "blend in"),
            (handle_out, Grip::BlendOut, "blend out"),
            (
                Rect::from_min_max(rect.min, Pos2::new(rect.left() + EDGE, rect.bottom())),
                Grip::TrimIn,
                "trim in",
            ),
            (
                Rect::from_min_max(Pos2::new(rect.right() - EDGE, rect.top()), rect.max),
                Grip::TrimOut,
                "trim out",
            ),
        ];
        if body.drag_started() {
            // Where the button went down, not where the drag was recognised a few points on.
            let p = ui
                .input(|i| i.pointer.press_origin())
                .or(body.interact_pointer_pos())
                .unwrap_or(rect.center());
            let grip = parts.iter().find(|(r, _, _)| r.contains(p)).map_or(Grip::Body, |(_, g, _)| *g);
            let origin = track.strips.get(i).cloned().unwrap_or_else(|| strip.clone());
            let from_frame = axis.frame(p.x);
            // The pointer has moved on since the press: the drag is where it is now.
            let last_frame = body.interact_pointer_pos().map_or(from_frame, |q| axis.frame(q.x));
            self.drag =
                Some(StripDrag { object: o, track: k, strip: i, grip, origin, from_frame, last_frame });
        }
        if let Some(p) = body.hover_pos() {
            let icon = match parts.iter().find(|(r, _, _)| r.contains(p)).map(|(_, g, _)| *g) {
                Some(Grip::TrimIn | Grip::TrimOut | Grip::BlendIn | Grip::BlendOut) => {
                    egui::CursorIcon::ResizeHorizontal
                }
                _ => egui::CursorIcon::Grab,
            };
            ui.ctx().set_cursor_icon(icon);
        }
        body.context_menu(|ui| strip_menu(ui, (o, k, i), strip, actions));
    }

    /// The layers: add one; each with its mode, weight, mute, solo and delete.
    fn layers_ui(&mut self, ui: &mut Ui, scene: &Scene, actions: &mut Actions) {
        ui.horizontal(|ui| {
            ui.strong(format!("Layers ({})", scene.layers.len()));
            let label = ui.label("New layer");
            ui.add(egui::TextEdit::singleline(&mut self.layer_name).desired_width(100.0).hint_text("Fix"))
                .labelled_by(label.id);
            if ui
                .button("Add layer")
                .on_hover_text("A layer above the clips with a new empty action of its name")
                .clicked()
            {
                let name = self.layer_name.trim().to_owned();
                if name.is_empty() || scene.layers.iter().any(|l| l.name == name) {
                    actions.push(Action::Error(format!("Layers: {name:?} is empty or taken")));
                } else {
                    actions.edit(Edit::scene(SceneEdit::Clip(ClipEdit::AddLayer { name })));
                    self.layer_name.clear();
                }
            }
        });
        for (l, layer) in scene.layers.iter().enumerate() {
            ui.horizontal(|ui| {
                let mut value = layer.clone();
                let mut changed = false;
                changed |= ui
                    .toggle_value(&mut value.mute, "M")
                    .on_hover_text(format!("Mute layer {}", layer.name))
                    .changed();
                changed |= ui
                    .toggle_value(&mut value.solo, "S")
                    .on_hover_text(format!("Solo layer {}", layer.name))
                    .changed();
                ui.label(format!("{} ({})", layer.name, layer.action));
                egui::ComboBox::from_id_salt(("layer mode", l))
                    .selected_text(format!("{:?}", value.mode))
                    .show_ui(ui, |ui| {
                        changed |=
                            ui.selectable_value(&mut value.mode, LayerMode::Additive, "Additive").changed();
                        changed |=
                            ui.selectable_value(&mut value.mode, LayerMode::Override, "Override").changed();
                    });
                if layer.weight.is_animated() {
                    ui.label(format!("weight keyed ({} keys)", layer.weight.track.len()));
                } else {
                    let label = ui.label("Weight");
                    let mut w = value.weight.value;
                    let r = ui.add(egui::Slider::new(&mut w, 0.0..=1.0)).labelled_by(label.id);
                    if r.drag_stopped() || (r.changed() && !r.dragged()) {
                        value.weight = keyrig_core::Animated::constant(w);
                        changed = true;
                    }
                }
                if changed {
                    actions.edit(Edit::scene(SceneEdit::Clip(ClipEdit::Layer { layer: l, value })));
                }
                if ui
                    .small_button("Delete")
                    .on_hover_text(format!("Delete layer {} (its action stays)", layer.name))
                    .clicked()
                {
                    actions.edit(Edit::scene(SceneEdit::Clip(ClipEdit::DeleteLayer { layer: l })));
                }
            });
        }
    }
}

/// A strip's menu: its numbers and choices, and Delete.
fn strip_menu(ui: &mut Ui, (o, k, i): (usize, usize, usize), strip: &Strip, actions: &mut Actions) {
    let mut s = strip.clone();
    let mut changed = false;
    ui.label(format!("{}: frames {:.1}–{:.1}", strip.action, strip.start, strip.end()));
    ui.horizontal(|ui| {
        ui.label("Speed");
        changed |= ui.add(egui::DragValue::new(&mut s.speed).speed(0.01).range(0.01..=100.0)).changed();
        ui.label("Repeat");
        changed |= ui.add(egui::DragValue::new(&mut s.repeat).speed(0.05).range(0.05..=1000.0)).changed();
    });
    ui.horizontal(|ui| {
        ui.label("Influence");
        if strip.influence.is_animated() {
            ui.label(format!("keyed ({} keys)", strip.influence.track.len()));
        } else {
            let mut w = s.influence.value;
            if ui.add(egui::Slider::new(&mut w, 0.0..=1.0)).changed() {
                s.influence = keyrig_core::Animated::constant(w);
                changed = true;
            }
        }
    });
    changed |= ui.checkbox(&mut s.reverse, "Reverse").changed();
    changed |= ui.checkbox(&mut s.continue_root, "Root motion continues").changed();
    ui.horizontal(|ui| {
        ui.label("Blend");
        for (b, name) in
            [(StripBlend::Replace, "Replace"), (StripBlend::Combine, "Combine"), (StripBlend::Add, "Add")]
        {
            changed |= ui.radio_value(&mut s.blend, b, name).changed();
        }
    });
    ui.horizontal(|ui| {
        ui.label("Outside");
        for (e, name) in [
            (Extrapolation::Hold, "Hold"),
            (Extrapolation::HoldForward, "Hold forward"),
            (Extrapolation::Nothing, "Nothing"),
        ] {
            changed |= ui.radio_value(&mut s.extrapolation, e, name).changed();
        }
    });
    // Blends longer than a slower, shorter strip would be refused: keep them inside it.
    s.blend_in = s.blend_in.min(s.length());
    s.blend_out = s.blend_out.min(s.length() - s.blend_in);
    if changed && s != *strip {
        actions.edit(Edit::scene(SceneEdit::Clip(ClipEdit::Strip {
            object: o,
            track: k,
            strip: i,
            value: s,
        })));
    }
    if ui.button("Delete strip").clicked() {
        actions.edit(Edit::scene(SceneEdit::Clip(ClipEdit::DeleteStrip { object: o, track: k, strip: i })));
        ui.close();
    }
}
