//! The dope sheet: a fixed frame ruler over rows in the outliner's order — each object, its
//! transform channels and its joints in hierarchy order (indented by depth), then the lights.
//! Objects, lights and joints with several animated channels are groups: a summary row of every
//! key beneath it, collapsible with its triangle. Keys are diamonds to click, box-select and
//! drag in time (whole frames, one undo step per drag); a summary diamond stands for every key
//! beneath it at that frame.
//!
//! Cost follows what is visible: only rows in view are laid out and painted, only keys in the
//! visible frames are read (binary search on the sorted tracks), keys that fall on the same
//! pixel are drawn and hit-tested as one, and the whole sheet is one interactive area whose
//! pointer position is mapped to a row and a pixel rather than a widget per key. Keys closer
//! than a diamond's width are drawn as ticks of a band (motion-capture density).
//!
//! The time axis zooms with Ctrl+wheel (about the pointer) and pans with Shift+wheel, a
//! horizontal wheel or a middle-button drag; *View all* fits the frame range, every key and every
//! sound clip.
//! Keys out of view are marked at the row's ends (◀ 12, 3 ▶); a click on a marker brings them
//! into view. Frames outside the scene's range are shaded.

use std::collections::BTreeSet;

use egui::{Align2, Color32, CursorIcon, FontId, PointerButton, Pos2, Rect, Sense, Stroke, Ui, Vec2};
use keyrig_core::{KeyType, Scene};

use crate::actions::{Action, Actions, Edit, SessionChange, Ticket};
use crate::context::FrameCtx;
use crate::session::{KeyRef, Selected, Selection};
use crate::widgets::flat_fill;
use crate::widgets::key_diamond::{paint_diamond, type_fill, type_scale, DIAMOND_RADIUS};
use crate::widgets::key_type_menu::key_type_menu_ui;
use crate::widgets::publish_painted;
use crate::widgets::range_watch::RangeWatch;
use crate::widgets::time_axis::TimeAxis;
use egui::accesskit::Role;
use keyrig_edit::channels::{self, ChannelId};

mod sound_rows;

const ROW_HEIGHT: f32 = 17.0;
const RULER_HEIGHT: f32 = 20.0;
/// Space between the name column and the keys, and at the keys' right end, points: room for
/// a diamond at either end of the view and, beyond it, the count of keys out of view.
const PAD: f32 = 24.0;
/// Room kept for the scroll bar at the right.
const SCROLL_BAR: f32 = 8.0;
const INDENT: f32 = 12.0;
/// The name column's width limits, points.
const MIN_NAME_WIDTH: f32 = 60.0;
const DEFAULT_NAME_WIDTH: f32 = 170.0;
/// Keys closer than this (points) are drawn as ticks of a dense band instead of diamonds.
const DENSE_SPACING: f32 = 3.0;
/// The fewest frames the zoomed time axis shows.
const MIN_SPAN: f64 = 4.0;

/// The frames shown at the left and right end of the dope sheet's keys.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeView {
    pub start: f64,
    pub end: f64,
}

/// What the current pointer gesture in the dope sheet is doing.
#[derive(Clone, Copy, Debug, PartialEq)]
enum Gesture {
    /// Moving the selected keys: whole frames already applied.
    MoveKeys { applied: i32 },
    /// A box selection from this point.
    Box { start: Pos2 },
    /// Panning the time axis with the middle button from this view.
    Pan { from: TimeView },
}

/// The dope sheet and its own state: the view of the time axis, the gesture under way, the
/// collapsed groups and the name column's width.
#[derive(Debug, Default)]
pub struct DopeSheet {
    /// The pointer gesture in progress (moving keys, box selection, panning).
    gesture: Option<Gesture>,
    /// The frames the dope sheet shows; `None` follows the scene's frame range.
    view: Option<TimeView>,
    /// Collapsed groups (objects, lights, joints with several channels).
    collapsed: BTreeSet<Selected>,
    /// The name column's width, points, once resized.
    name_width: Option<f32>,
    /// The key move pushed in the last frame and the whole frames the gesture has applied once
    /// it is taken (a move onto another key is refused).
    pending_move: Option<(Ticket, i32)>,
    /// A sound clip being dragged in time.
    sound_drag: Option<sound_rows::SoundDrag>,
    /// The frame range last laid out: a range that grew refits the view ([`RangeWatch`]).
    range_watch: RangeWatch,
}

/// What a row stands for.
#[derive(Clone, Debug, PartialEq)]
enum RowKind {
    /// A collapsible group (object, light, joint with several channels): shows every key beneath.
    Group { collapsed: bool },
    /// One channel.
    Channel(ChannelId),
}

/// One row of the dope sheet.
#[derive(Clone, Debug)]
struct Row {
    label: String,
    depth: usize,
    kind: RowKind,
    /// Channels whose keys the row shows (a group: every channel beneath it).
    shows: Vec<ChannelId>,
    /// The scene item the row belongs to.
    item: Selected,
}

impl Row {
    fn group(&self) -> bool {
        matches!(self.kind, RowKind::Group { .. })
    }
}

/// The rows in display order; collapsed groups hide what is beneath them. Only keyed channels
/// have rows, whatever is selected: selecting an item never inserts rows that would shift the
/// ones under the pointer (as Blender's dope sheet lists only animated channels).
fn rows(scene: &Scene, collapsed: &BTreeSet<Selected>) -> Vec<Row> {
    let keyed = |id: ChannelId| channels::key_count(scene, id) > 0;
    let mut out = Vec::new();
    let channel_row = |id: ChannelId, label: String, depth: usize, item: Selected| Row {
        label,
        depth,
        kind: RowKind::Channel(id),
        shows: vec![id],
        item,
    };
    for (o, object) in scene.objects.iter().enumerate() {
        let item = Selected::Object(o);
        let folded = collapsed.contains(&item);
        out.push(Row {
            label: object.name.clone(),
            depth: 0,
            kind: RowKind::Group { collapsed: folded },
            shows: ChannelId::of_object(scene, o),
            item,
        });
        if folded {
            continue;
        }
        let rotation = keyrig_core::channel_id::rotation_or_euler(scene, ChannelId::ObjectRotation(o));
        for id in [ChannelId::ObjectTranslation(o), rotation, ChannelId::ObjectScale(o)] {
            if keyed(id) {
                out.push(channel_row(id, id.channel_name().to_owned(), 1, item));
            }
        }
        // Visibility, colour, opacity, morph weights, deformer: where in use.
        for id in keyrig_core::AttributeId::of_object(scene, o) {
            if keyed(id) {
                out.push(channel_row(id, attribute_label(id), 1, item));
            }
        }
        // Object constraints: influence, a child-of parent, a path offset, where keyed.
        for (c, constraint) in object.constraints.iter().enumerate() {
            for property in keyrig_core::channel_id::ConstraintProperty::of_constraint(constraint) {
                let id = ChannelId::Constraint { object: o, constraint: c, property };
                if keyed(id) {
                    out.push(channel_row(id, format!("{} {}", constraint.name, id.channel_name()), 1, item));
                }
            }
        }
        let Some(skeleton) = &object.skeleton else { continue };
        let root = ChannelId::RootTranslation(o);
        if keyed(root) {
            out.push(channel_row(root, root.channel_name().to_owned(), 1, item));
        }
        // IK constraints: their target and IK/FK blend, where keyed.
        for (c, constraint) in skeleton.ik_constraints.iter().enumerate() {
            for id in [
                ChannelId::IkTarget { object: o, constraint: c },
                ChannelId::IkBlend { object: o, constraint: c },
            ] {
                if keyed(id) {
                    out.push(channel_row(id, format!("{} {}", constraint.name, id.channel_name()), 1, item));
                }
            }
        }
        for (j, depth) in skeleton.depth_first() {
            let joint = &skeleton.joints[j];
            let item = Selected::Joint { object: o, joint: j };
            let mut ids = Vec::with_capacity(3);
            if joint.translation.is_animated() {
                ids.push(ChannelId::JointTranslation { object: o, joint: j });
            }
            ids.push(if joint.rotation_euler.is_some() {
                ChannelId::JointEuler { object: o, joint: j }
            } else {
                ChannelId::JointRotation { object: o, joint: j }
            });
            if joint.scale.is_animated() {
                ids.push(ChannelId::JointScale { object: o, joint: j });
            }
            if let [id] = ids[..] {
                out.push(channel_row(id, format!("{} {}", joint.name, id.channel_name()), 1 + depth, item));
                continue;
            }
            let folded = collapsed.contains(&item);
            out.push(Row {
                label: joint.name.clone(),
                depth: 1 + depth,
                kind: RowKind::Group { collapsed: folded },
                shows: ids.clone(),
                item,
            });
            if !folded {
                for id in ids {
                    out.push(channel_row(id, id.channel_name().to_owned(), 2 + depth, item));
                }
            }
        }
    }
    for (l, light) in scene.lights.iter().enumerate() {
        let item = Selected::Light(l);
        let folded = collapsed.contains(&item);
        let mut all = ChannelId::of_light(l).to_vec();
        all.extend(keyrig_core::AttributeId::of_light(scene, l));
        out.push(Row {
            label: light.name.clone(),
            depth: 0,
            kind: RowKind::Group { collapsed: folded },
            shows: all.clone(),
            item,
        });
        if folded {
            continue;
        }
        for id in all {
            if keyed(id) {
                out.push(channel_row(id, attribute_label(id), 1, item));
            }
        }
    }
    for (c, camera) in scene.cameras.iter().enumerate() {
        let item = Selected::Camera(c);
        let folded = collapsed.contains(&item);
        let all = ChannelId::of_camera(scene, c);
        out.push(Row {
            label: camera.name.clone(),
            depth: 0,
            kind: RowKind::Group { collapsed: folded },
            shows: all.clone(),
            item,
        });
        if folded {
            continue;
        }
        for id in all {
            if keyed(id) {
                out.push(channel_row(id, id.channel_name().to_owned(), 1, item));
            }
        }
    }
    out
}

/// A row's label: the channel's name, with the target of a morph weight.
fn attribute_label(id: ChannelId) -> String {
    match id {
        ChannelId::Attribute(keyrig_core::AttributeId::MorphWeight { target, .. }) => {
            format!("morph {target}")
        }
        _ => id.channel_name().to_owned(),
    }
}

/// Where things are: the name column, the keys and the frames they show.
#[derive(Clone, Copy, Debug)]
struct Geometry {
    /// Left and right of the name column.
    names: (f32, f32),
    /// Left and right of the keys.
    keys: (f32, f32),
    view: TimeView,
    fps: f64,
}

impl Geometry {
    /// The keys' time axis (shared with the curve view).
    fn axis(&self) -> TimeAxis {
        TimeAxis { left: self.keys.0, right: self.keys.1, start: self.view.start, end: self.view.end }
    }

    fn x(&self, frame: f64) -> f32 {
        self.axis().x(frame)
    }

    fn frame(&self, x: f32) -> f64 {
        self.axis().frame(x)
    }

    fn frames_per_point(&self) -> f64 {
        self.axis().frames_per_point()
    }

    /// The frames with room for half a diamond at either end (keys there are still drawn).
    fn visible_seconds(&self) -> (f64, f64) {
        let margin = f64::from(DIAMOND_RADIUS) * self.frames_per_point();
        ((self.view.start - margin) / self.fps, (self.view.end + margin) / self.fps)
    }
}

/// The default view: the scene's frame range.
fn range_view(scene: &Scene) -> TimeView {
    let range = scene.frame_range;
    TimeView { start: f64::from(range.start), end: f64::from(range.end.max(range.start + 1)) }
}

/// The view that shows the frame range, every key of the scene and every sound clip (`clips`:
/// their first and last frames).
fn view_all(scene: &Scene, clips: &[(f64, f64)]) -> TimeView {
    let fps = scene.fps.max(1e-9);
    let mut view = range_view(scene);
    for &(first, last) in clips.iter().filter(|(a, b)| a.is_finite() && b.is_finite()) {
        view.start = view.start.min(first.floor());
        view.end = view.end.max(last.ceil());
    }
    for id in ChannelId::all(scene) {
        let window = channels::keys_between(scene, id, f64::NEG_INFINITY, f64::INFINITY);
        if let (Some(first), Some(last)) = (window.times.first(), window.times.last()) {
            view.start = view.start.min((first * fps).floor());
            view.end = view.end.max((last * fps).ceil());
        }
    }
    if view == range_view(scene) {
        return view;
    }
    let margin = (view.end - view.start) * 0.02;
    TimeView { start: view.start - margin, end: view.end + margin }
}

/// Keys of one row that fall on one pixel column.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Bucket {
    /// The pixel column (rounded x, points).
    px: i32,
    /// The frame of the first key in it.
    frame: f64,
    count: usize,
    selected: usize,
    /// Set for a bucket of exactly one key: that key.
    single: Option<KeyRef>,
    /// The type of its keys when they share one (a mix is drawn as keyframes).
    key_type: Option<KeyType>,
}

/// The row's keys in view, one bucket per pixel column, sorted by column; and the number of
/// keys before and after the view with the nearest frame on each side.
fn buckets(ctx: &FrameCtx<'_>, row: &Row, geo: &Geometry) -> (Vec<Bucket>, Marker, Marker) {
    let scene = ctx.scene();
    let (from, to) = geo.visible_seconds();
    let mut columns: Vec<Bucket> = Vec::new();
    let (mut before, mut after) = (Marker::default(), Marker::default());
    for &id in &row.shows {
        let window = channels::keys_between(scene, id, from, to);
        before.add(window.before, window.nearest_before.map(|t| t * geo.fps), f64::max);
        after.add(window.after, window.nearest_after.map(|t| t * geo.fps), f64::min);
        let types = channels::key_types(scene, id, window.first, window.times.len());
        for (i, time) in window.times.iter().enumerate() {
            let frame = time * geo.fps;
            let px = geo.x(frame).round() as i32;
            let key = KeyRef { channel: id, index: window.first + i };
            let selected = usize::from(ctx.session.selection.keys.contains(&key));
            let key_type = types.get(i).copied();
            columns.push(Bucket { px, frame, count: 1, selected, single: Some(key), key_type });
        }
    }
    if row.shows.len() > 1 {
        columns.sort_by_key(|b| b.px);
    }
    let mut merged: Vec<Bucket> = Vec::with_capacity(columns.len());
    for b in columns {
        match merged.last_mut() {
            Some(last) if last.px == b.px => {
                last.count += b.count;
                last.selected += b.selected;
                last.single = None;
                last.frame = last.frame.min(b.frame);
                last.key_type = last.key_type.filter(|&t| Some(t) == b.key_type);
            }
            _ => merged.push(b),
        }
    }
    (merged, before, after)
}

/// Keys of a row beyond one end of the view.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
struct Marker {
    count: usize,
    /// The frame of the nearest such key.
    nearest: Option<f64>,
}

impl Marker {
    fn add(&mut self, count: usize, nearest: Option<f64>, pick: fn(f64, f64) -> f64) {
        self.count += count;
        self.nearest = match (self.nearest, nearest) {
            (Some(a), Some(b)) => Some(pick(a, b)),
            (a, b) => a.or(b),
        };
    }
}

/// Every key of `row` whose pixel column is `px`.
fn keys_at(scene: &Scene, row: &Row, geo: &Geometry, px: i32) -> Vec<KeyRef> {
    keys_in(scene, row, geo, px as f32 - 0.5, px as f32 + 0.5)
}

/// Every key of `row` drawn between `left` and `right` (points).
fn keys_in(scene: &Scene, row: &Row, geo: &Geometry, left: f32, right: f32) -> Vec<KeyRef> {
    let (from, to) = (geo.frame(left) / geo.fps, geo.frame(right) / geo.fps);
    let mut out = Vec::new();
    for &id in &row.shows {
        let window = channels::keys_between(scene, id, from - 1e-9, to + 1e-9);
        for (i, time) in window.times.iter().enumerate() {
            let x = geo.x(time * geo.fps).round();
            if x >= left.round() && x <= right.round() {
                out.push(KeyRef { channel: id, index: window.first + i });
            }
        }
    }
    out
}

/// What is under the pointer in the rows.
#[derive(Clone, Debug, PartialEq)]
enum Hit {
    Expander(usize),
    Name(usize),
    /// The keys of a row drawn at the pixel column nearest the pointer.
    Keys(usize, Vec<KeyRef>),
    /// An out-of-view marker: the frame of the nearest key beyond the view.
    Marker(f64),
    Empty,
}

/// Draws the dope sheet into the space `ui` has left.
impl DopeSheet {
    /// The view of the time axis now (the frame range until the user zooms or pans).
    #[must_use]
    pub fn time_view(&self, scene: &Scene) -> TimeView {
        self.view.unwrap_or_else(|| range_view(scene))
    }

    /// Draws the dope sheet into the space `ui` has left.
    pub fn ui(&mut self, ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
        // The key move of the last frame: the gesture counts its frames once it was taken.
        if let Some((ticket, wanted)) = self.pending_move.take() {
            if let (true, Some(Gesture::MoveKeys { applied })) =
                (ctx.results.moved(ticket), &mut self.gesture)
            {
                *applied = wanted;
            }
        }
        let scene = ctx.scene();
        // A range that grew (an import that extended it) shows all of it, as *View all*.
        if self.range_watch.grew(ctx.doc.cache_key().0, scene.frame_range) {
            let all = view_all(scene, &sound_rows::clip_spans(ctx));
            self.view = (all != range_view(scene)).then_some(all);
        }
        let rows = rows(scene, &self.collapsed);
        let full = ui.available_rect_before_wrap();
        let max_name = (full.width() - 120.0).max(MIN_NAME_WIDTH);
        let name_width = self.name_width.unwrap_or(DEFAULT_NAME_WIDTH).clamp(MIN_NAME_WIDTH, max_name);
        let geo = Geometry {
            names: (full.left(), full.left() + name_width),
            keys: (
                full.left() + name_width + PAD,
                (full.right() - PAD - SCROLL_BAR).max(full.left() + name_width + PAD + 20.0),
            ),
            view: self.time_view(scene),
            fps: scene.fps.max(1e-9),
        };

        let (header, _) = ui.allocate_exact_size(Vec2::new(full.width(), RULER_HEIGHT), Sense::hover());
        self.header_ui(ui, ctx, actions, header, &geo);
        // The sound clips' rows head the rows and scroll with them.
        let strip_height = sound_rows::SOUND_ROW_HEIGHT * scene.sounds.len() as f32;

        let body_top = ui.cursor().top();
        egui::ScrollArea::vertical()
            .id_salt("dope_sheet_scroll")
            .auto_shrink([false, false])
            .scroll_source(egui::scroll_area::ScrollSource {
                drag: false,
                ..egui::scroll_area::ScrollSource::ALL
            })
            .show_viewport(ui, |ui, viewport| {
                let top_left = ui.max_rect().min;
                self.body_ui(ui, ctx, actions, &rows, &geo, viewport, strip_height);
                if strip_height > 0.0 {
                    let strip = Rect::from_min_size(top_left, Vec2::new(ui.max_rect().width(), strip_height));
                    self.sound_rows_ui(ui, ctx, actions, strip, &geo);
                }
            });
        let sheet =
            Rect::from_min_max(full.min, Pos2::new(full.right(), ui.min_rect().bottom().max(body_top)));

        self.resize_names_ui(ui, sheet, &geo);
        self.navigate(ui, sheet, &geo);
    }

    /// The fixed header: *View all* over the names, the frame ruler (click or drag to scrub)
    /// over the keys, with the frames outside the scene's range shaded.
    fn header_ui(
        &mut self,
        ui: &mut Ui,
        ctx: &FrameCtx<'_>,
        actions: &mut Actions,
        header: Rect,
        geo: &Geometry,
    ) {
        let visuals = ui.visuals().clone();
        let painter = ui.painter_at(header);
        painter.rect_filled(header, 0.0, visuals.faint_bg_color);
        let button =
            Rect::from_min_size(header.min + Vec2::new(2.0, 1.0), Vec2::new(70.0, RULER_HEIGHT - 2.0));
        if ui
            .put(button, egui::Button::new("↔ View all").small())
            .on_hover_text("Show the whole frame range and every key (Ctrl+wheel zooms, Shift+wheel pans)")
            .clicked()
        {
            self.view = Some(view_all(ctx.scene(), &sound_rows::clip_spans(ctx)));
        }
        let ruler = Rect::from_min_max(
            Pos2::new(geo.keys.0 - PAD, header.top()),
            Pos2::new(geo.keys.1 + PAD, header.bottom()),
        );
        let response = ui.interact(ruler, ui.id().with("ruler"), Sense::click_and_drag());
        let response = response.on_hover_text("Click or drag to scrub");
        if response.clicked() || response.dragged_by(PointerButton::Primary) {
            if let Some(p) = response.interact_pointer_pos() {
                ctx.set_frame(actions, geo.frame(p.x).round() as i32);
            }
        }
        let painter = painter.with_clip_rect(ruler);
        shade_outside_range(&painter, ctx.scene(), geo, ruler, visuals.extreme_bg_color.gamma_multiply(0.8));
        sound_rows::ruler_waveforms(&painter, ctx, geo, ruler);
        let step = tick_step(geo.view.end - geo.view.start, geo.keys.1 - geo.keys.0);
        let mut f = (geo.view.start / step as f64).floor() as i64 * step;
        while (f as f64) <= geo.view.end {
            let x = geo.x(f as f64);
            if x >= geo.keys.0 - 1.0 {
                painter.line_segment(
                    [Pos2::new(x, ruler.bottom() - 5.0), Pos2::new(x, ruler.bottom())],
                    Stroke::new(1.0, visuals.weak_text_color()),
                );
                painter.text(
                    Pos2::new(x, ruler.top() + 2.0),
                    Align2::CENTER_TOP,
                    f.to_string(),
                    FontId::proportional(10.0),
                    visuals.weak_text_color(),
                );
            }
            f += step;
        }
        preview_band(&painter, ctx.scene(), geo, ruler);
        marker_flags(&painter, ctx.scene(), geo, ruler);
        current_frame_line(&painter, ctx, geo, ruler);
    }
}

/// The preview range, while one is set: an orange band along the ruler's bottom over its
/// frames ([`crate::widgets::preview_range`]).
fn preview_band(painter: &egui::Painter, scene: &Scene, geo: &Geometry, ruler: Rect) {
    if scene.preview_range.is_none() {
        return;
    }
    let range = scene.playback_range();
    let (x0, x1) = (geo.x(f64::from(range.start)), geo.x(f64::from(range.end)));
    let band =
        Rect::from_min_max(Pos2::new(x0, ruler.bottom() - 3.0), Pos2::new(x1.max(x0 + 1.0), ruler.bottom()));
    painter.rect_filled(band, 0.0, crate::widgets::preview_range::PREVIEW_COLOUR);
}

/// The scene's timeline markers on the ruler: a flag at each marker's frame with its name (and
/// the camera it switches to).
fn marker_flags(painter: &egui::Painter, scene: &Scene, geo: &Geometry, ruler: Rect) {
    let colour = Color32::from_rgb(230, 200, 90);
    for marker in &scene.markers {
        let x = geo.x(f64::from(marker.frame));
        if x < geo.keys.0 - PAD || x > geo.keys.1 + PAD {
            continue;
        }
        let bottom = ruler.bottom();
        painter.add(egui::Shape::convex_polygon(
            vec![Pos2::new(x - 4.0, bottom - 7.0), Pos2::new(x + 4.0, bottom - 7.0), Pos2::new(x, bottom)],
            colour,
            Stroke::NONE,
        ));
        let text = match &marker.camera {
            Some(camera) => format!("{} ▸ {camera}", marker.name),
            None => marker.name.clone(),
        };
        painter.text(
            Pos2::new(x + 5.0, bottom - 8.0),
            Align2::LEFT_BOTTOM,
            text,
            FontId::proportional(10.0),
            colour,
        );
    }
}

/// A faint line down the rows at each marker's frame.
fn marker_lines(painter: &egui::Painter, scene: &Scene, geo: &Geometry, rect: Rect) {
    for marker in &scene.markers {
        let x = geo.x(f64::from(marker.frame));
        if x >= geo.keys.0 - PAD && x <= geo.keys.1 + PAD {
            painter.line_segment(
                [Pos2::new(x, rect.top()), Pos2::new(x, rect.bottom())],
                Stroke::new(1.0, Color32::from_rgba_unmultiplied(230, 200, 90, 90)),
            );
        }
    }
}

/// Shades the frames of `rect` outside the scene's frame range.
fn shade_outside_range(painter: &egui::Painter, scene: &Scene, geo: &Geometry, rect: Rect, colour: Color32) {
    let range = scene.frame_range;
    let (a, b) = (geo.x(f64::from(range.start)), geo.x(f64::from(range.end)));
    if a > rect.left() {
        painter.rect_filled(Rect::from_min_max(rect.min, Pos2::new(a, rect.bottom())), 0.0, colour);
    }
    if b < rect.right() {
        painter.rect_filled(Rect::from_min_max(Pos2::new(b, rect.top()), rect.max), 0.0, colour);
    }
}

fn current_frame_line(painter: &egui::Painter, ctx: &FrameCtx<'_>, geo: &Geometry, rect: Rect) {
    let x = geo.x(ctx.session.playback.frame);
    if x >= geo.keys.0 - PAD && x <= geo.keys.1 + PAD {
        painter.line_segment(
            [Pos2::new(x, rect.top()), Pos2::new(x, rect.bottom())],
            Stroke::new(2.0, Color32::from_rgb(90, 170, 255)),
        );
    }
}

impl DopeSheet {
    /// The rows: laid out as one area the height of every row, `top` points down the scrolled
    /// content (under the sound clips' rows), painted and hit-tested only where `viewport` (the
    /// visible part, in content coordinates) shows them.
    #[allow(clippy::too_many_arguments)]
    fn body_ui(
        &mut self,
        ui: &mut Ui,
        ctx: &FrameCtx<'_>,
        actions: &mut Actions,
        rows: &[Row],
        geo: &Geometry,
        viewport: Rect,
        top: f32,
    ) {
        let scene = ctx.scene();
        // The rows start `top` points into the scrolled content, under the sound clips' rows.
        let origin = ui.max_rect().min + Vec2::new(0.0, top);
        let viewport = viewport.translate(Vec2::new(0.0, -top));
        let height = ROW_HEIGHT * rows.len() as f32 + 4.0;
        let content = Rect::from_min_size(
            origin,
            Vec2::new(ui.max_rect().width(), height.max(viewport.height() - top)),
        );
        let body = ui.allocate_rect(content, Sense::click_and_drag());
        let visible = Rect::from_min_max(origin + viewport.min.to_vec2(), origin + viewport.max.to_vec2());
        let first = ((viewport.min.y / ROW_HEIGHT).floor().max(0.0) as usize).min(rows.len());
        let last = ((viewport.max.y / ROW_HEIGHT).ceil().max(0.0) as usize).min(rows.len());
        let row_rect = |r: usize| {
            let top = origin.y + r as f32 * ROW_HEIGHT;
            Rect::from_min_max(Pos2::new(content.left(), top), Pos2::new(content.right(), top + ROW_HEIGHT))
        };

        let painter = ui.painter_at(visible);
        let visuals = ui.visuals().clone();
        crate::widgets::flat_fill::fill(&painter, visible, visuals.extreme_bg_color, ctx.gpu_fills);
        let keys_rect = Rect::from_min_max(
            Pos2::new(geo.keys.0 - PAD, visible.top()),
            Pos2::new(geo.keys.1 + PAD, visible.bottom()),
        );
        shade_outside_range(&painter, scene, geo, keys_rect, visuals.faint_bg_color.gamma_multiply(0.5));
        let keys_painter = painter.with_clip_rect(keys_rect.intersect(visible));
        let names_painter = painter.with_clip_rect(Rect::from_min_max(
            Pos2::new(geo.names.0, visible.top()),
            Pos2::new(geo.names.1, visible.bottom()),
        ));
        let mut truncated: Option<usize> = None;
        let hover = body.hover_pos();
        // Row shades, composited over the background here so they are opaque fills (cheap on a
        // CPU rasterizer, widgets::flat_fill); the out-of-range shade goes back over them.
        let selected_row =
            flat_fill::over(visuals.extreme_bg_color, visuals.selection.bg_fill.gamma_multiply(0.35));
        let odd_row = flat_fill::over(visuals.extreme_bg_color, visuals.faint_bg_color.gamma_multiply(0.5));
        let outside = visuals.faint_bg_color.gamma_multiply(0.5);
        for (r, row) in rows.iter().enumerate().take(last).skip(first) {
            let rect = row_rect(r);
            let shade = if ctx.session.selection.contains(row.item) {
                Some(selected_row)
            } else {
                (r % 2 == 1).then_some(odd_row)
            };
            if let Some(colour) = shade {
                flat_fill::fill(&painter, rect, colour, ctx.gpu_fills);
                shade_outside_range(&painter, scene, geo, rect.intersect(keys_rect), outside);
            }
            // Name, with the expander of a group.
            let indent = geo.names.0 + 4.0 + INDENT * row.depth as f32;
            if let RowKind::Group { collapsed } = row.kind {
                let text = if collapsed { "▶" } else { "▼" };
                names_painter.text(
                    Pos2::new(indent, rect.center().y),
                    Align2::LEFT_CENTER,
                    text,
                    FontId::proportional(9.0),
                    visuals.weak_text_color(),
                );
            }
            let colour = if row.group() { visuals.strong_text_color() } else { visuals.text_color() };
            let galley = names_painter.layout_no_wrap(row.label.clone(), FontId::proportional(12.0), colour);
            let text_left = indent + 12.0;
            if text_left + galley.size().x > geo.names.1
                && hover.is_some_and(|p| rect.contains(p) && p.x < geo.names.1)
            {
                truncated = Some(r);
            }
            names_painter.galley(
                Pos2::new(text_left, rect.center().y - galley.size().y / 2.0),
                galley,
                colour,
            );
            publish_row(ui, row, Rect::from_min_max(rect.min, Pos2::new(geo.names.1, rect.bottom())), indent);

            // Keys.
            let y = rect.center().y;
            let (buckets, before, after) = buckets(ctx, row, geo);
            let summary = row.group();
            let mut band: Option<(f32, f32)> = None;
            for (i, b) in buckets.iter().enumerate() {
                let x = b.px as f32;
                let dense = [i.checked_sub(1), Some(i + 1)]
                    .into_iter()
                    .flatten()
                    .filter_map(|j| buckets.get(j))
                    .any(|n| (n.px - b.px).abs() as f32 <= DENSE_SPACING);
                let selected = b.selected > 0;
                let frame = b.frame;
                let outside = frame < f64::from(scene.frame_range.start) - 1e-6
                    || frame > f64::from(scene.frame_range.end) + 1e-6;
                if dense {
                    // A band: one rectangle per run of neighbouring unselected marks (a run of a
                    // motion-capture track is one shape), selected marks as their own ticks.
                    if selected || outside {
                        let colour = key_colour(selected, summary, outside);
                        keys_painter.rect_filled(
                            Rect::from_min_max(Pos2::new(x - 0.5, y - 4.5), Pos2::new(x + 0.5, y + 4.5)),
                            0.0,
                            colour,
                        );
                    } else {
                        match &mut band {
                            Some((_, end)) if (x - *end) <= DENSE_SPACING => *end = x,
                            _ => {
                                paint_band(&keys_painter, band.take(), y, key_colour(false, summary, false));
                                band = Some((x, x));
                            }
                        }
                    }
                } else {
                    // Each key type its own size and colour (breakdowns small and blue, …).
                    let key_type = b.key_type.unwrap_or_default();
                    let radius =
                        (if summary { DIAMOND_RADIUS - 1.5 } else { DIAMOND_RADIUS }) * type_scale(key_type);
                    let hovered =
                        hover.is_some_and(|p| (p.x - x).abs() <= DIAMOND_RADIUS && rect.contains(p));
                    let fill = match type_fill(key_type, selected) {
                        Some(fill) if outside => fill.gamma_multiply(0.55),
                        Some(fill) => fill,
                        None => key_colour(selected, summary, outside),
                    };
                    paint_diamond(
                        &keys_painter,
                        Pos2::new(x, y),
                        radius + if hovered { 1.0 } else { 0.0 },
                        fill,
                        selected,
                    );
                }
                publish_key(ui, scene, row, b, Pos2::new(x, y));
            }
            paint_band(&keys_painter, band, y, key_colour(false, summary, false));
            for (marker, left) in [(before, true), (after, false)] {
                if marker.count > 0 {
                    let text =
                        if left { format!("◀{}", marker.count) } else { format!("{}▶", marker.count) };
                    let (pos, align) = if left {
                        (Pos2::new(geo.keys.0 - PAD + 1.0, y), Align2::LEFT_CENTER)
                    } else {
                        (Pos2::new(geo.keys.1 + PAD - 1.0, y), Align2::RIGHT_CENTER)
                    };
                    let drawn = painter.text(
                        pos,
                        align,
                        &text,
                        FontId::proportional(10.0),
                        Color32::from_rgb(255, 170, 60),
                    );
                    publish_marker(ui, row, marker, left, drawn);
                }
            }
        }
        marker_lines(&painter, scene, geo, visible);
        current_frame_line(&painter, ctx, geo, visible);

        // Pointer.
        let additive = ui.input(|i| i.modifiers.shift || i.modifiers.command);
        let hit_at = |pos: Pos2| -> Hit { hit(ctx, rows, geo, origin, pos) };
        let selection = &ctx.session.selection;
        if let Some(r) = truncated {
            body.clone().on_hover_text_at_pointer(row_path(scene, &rows[r]));
        } else if let Some(p) = hover {
            if let Hit::Marker(frame) = hit_at(p) {
                body.clone().on_hover_text_at_pointer(format!(
                    "Keys out of view, the nearest at frame {frame:.0}: click to show them"
                ));
            }
        }
        if let Some(pos) = body.interact_pointer_pos().filter(|_| body.clicked()) {
            match hit_at(pos) {
                Hit::Expander(r) => {
                    let item = rows[r].item;
                    if !self.collapsed.remove(&item) {
                        self.collapsed.insert(item);
                    }
                }
                Hit::Name(r) => {
                    if additive {
                        actions.session(SessionChange::Toggle(rows[r].item));
                    } else {
                        actions.session(SessionChange::SelectOnly(Some(rows[r].item)));
                    }
                }
                Hit::Keys(r, keys) => select_keys(selection, actions, &rows[r], keys, additive),
                Hit::Marker(frame) => self.view = Some(show_frame(geo, frame)),
                Hit::Empty => actions.session(SessionChange::SetKeys(BTreeSet::new())),
            }
        }
        // A right click on keys that are not selected selects them; the menu sets the type of
        // the selected keys (Blender's R in the dope sheet; R here is record).
        if let Some(pos) = body.interact_pointer_pos().filter(|_| body.secondary_clicked()) {
            if let Hit::Keys(r, keys) = hit_at(pos) {
                if !keys.iter().all(|k| selection.keys.contains(k)) {
                    select_keys(selection, actions, &rows[r], keys, false);
                }
            }
        }
        body.context_menu(|ui| key_type_menu_ui(ui, selection, actions));
        let press = ui.input(|i| i.pointer.press_origin());
        if let Some(origin_pos) = press.filter(|_| body.drag_started_by(PointerButton::Primary)) {
            self.gesture = match hit_at(origin_pos) {
                Hit::Keys(r, keys) => {
                    if !keys.iter().all(|k| selection.keys.contains(k)) {
                        select_keys(selection, actions, &rows[r], keys, additive);
                    }
                    Some(Gesture::MoveKeys { applied: 0 })
                }
                Hit::Empty | Hit::Name(_) | Hit::Expander(_) => Some(Gesture::Box { start: origin_pos }),
                Hit::Marker(_) => None,
            };
        }
        if body.drag_started_by(PointerButton::Middle) {
            self.gesture = Some(Gesture::Pan { from: geo.view });
        }
        match self.gesture {
            Some(Gesture::MoveKeys { applied }) => {
                if let Some(delta) = body.total_drag_delta() {
                    let wanted = (f64::from(delta.x) * geo.frames_per_point()).round() as i32;
                    let step = wanted - applied;
                    if step != 0 && self.pending_move.is_none() {
                        let ticket = actions.ticket();
                        actions.edit(Edit::MoveSelectedKeys { seconds: f64::from(step) / geo.fps, ticket });
                        self.pending_move = Some((ticket, wanted));
                    }
                }
                if body.drag_stopped() {
                    actions.push(Action::CloseGroup);
                    self.gesture = None;
                }
            }
            Some(Gesture::Box { start }) => {
                if let Some(now) = ui.input(|i| i.pointer.interact_pos()) {
                    let rect = Rect::from_two_pos(start, now);
                    painter.rect_stroke(
                        rect,
                        0.0,
                        Stroke::new(1.0, visuals.selection.stroke.color),
                        egui::StrokeKind::Inside,
                    );
                    if body.drag_stopped() {
                        if !additive {
                            actions.session(SessionChange::SetKeys(BTreeSet::new()));
                        }
                        let top = (((rect.top() - origin.y) / ROW_HEIGHT).floor().max(0.0) as usize)
                            .min(rows.len());
                        let bottom = (((rect.bottom() - origin.y) / ROW_HEIGHT).floor().max(0.0) as usize
                            + 1)
                        .min(rows.len());
                        for (r, row) in rows.iter().enumerate().take(bottom).skip(top) {
                            let y = row_rect(r).center().y;
                            if y < rect.top() || y > rect.bottom() {
                                continue;
                            }
                            let keys = keys_in(scene, row, geo, rect.left(), rect.right());
                            if !keys.is_empty() {
                                actions.session(SessionChange::AddKeys(keys));
                            }
                        }
                        self.gesture = None;
                    }
                }
            }
            Some(Gesture::Pan { from }) => {
                if let Some(delta) = body.total_drag_delta() {
                    let axis = TimeAxis { start: from.start, end: from.end, ..geo.axis() };
                    let (start, end) = axis.panned(delta.x);
                    self.view = Some(TimeView { start, end });
                }
                if body.drag_stopped() {
                    self.gesture = None;
                }
            }
            None => {}
        }
        if !ui.input(|i| i.pointer.any_down()) && !body.drag_stopped() {
            self.gesture = None;
        }
    }
}

/// Paints a band of dense keys from `x0` to `x1` (one mark per pixel column between them).
fn paint_band(painter: &egui::Painter, band: Option<(f32, f32)>, y: f32, colour: Color32) {
    if let Some((x0, x1)) = band {
        painter.rect_filled(
            Rect::from_min_max(Pos2::new(x0 - 0.5, y - 4.5), Pos2::new(x1 + 0.5, y + 4.5)),
            0.0,
            colour,
        );
    }
}

/// The colour of a key: selected keys yellow, summaries darker, keys outside the frame range
/// dimmed.
fn key_colour(selected: bool, summary: bool, outside: bool) -> Color32 {
    let colour = match (selected, summary) {
        (true, _) => Color32::from_rgb(255, 200, 60),
        (false, false) => Color32::from_gray(200),
        (false, true) => Color32::from_gray(150),
    };
    if outside {
        colour.gamma_multiply(0.55)
    } else {
        colour
    }
}

/// "CesiumMan ▸ Skeleton_arm_joint_L ▸ rotation": where a row sits, for its tooltip.
fn row_path(scene: &Scene, row: &Row) -> String {
    match row.kind {
        RowKind::Channel(id) => id.label(scene),
        RowKind::Group { .. } => row.label.clone(),
    }
}

/// Tells accessibility tools (and UI tests) about a drawn key: "key elbow rotation frame 15",
/// or for several keys on one pixel or a summary "keys Arm frame 15 (4)".
fn publish_key(ui: &Ui, scene: &Scene, row: &Row, bucket: &Bucket, centre: Pos2) {
    let id = match (bucket.single, &row.kind) {
        (Some(key), RowKind::Channel(_)) => ui.id().with(("key", key.channel, key.index)),
        _ => ui.id().with(("keys", row.item, row.shows.first().copied(), bucket.px)),
    };
    // The size the key is drawn at (a breakdown smaller, an extreme larger).
    let scale = type_scale(bucket.key_type.unwrap_or_default());
    let rect = Rect::from_center_size(centre, Vec2::splat(DIAMOND_RADIUS * 2.0 * scale + 2.0));
    let label = || {
        let frame = bucket.frame.round() as i64;
        match (bucket.single, &row.kind) {
            (Some(key), RowKind::Channel(_)) => {
                format!("key {} frame {frame}", key.channel.label(scene))
            }
            _ => format!("keys {} frame {frame} ({})", row_path(scene, row), bucket.count),
        }
    };
    publish_painted(ui.ctx(), id, Role::Button, rect, label, Some(bucket.selected > 0));
    // A key that is not a plain keyframe says its type ("Breakdown").
    if let Some(key_type) = bucket.key_type.filter(|t| !t.is_keyframe()) {
        ui.ctx().accesskit_node_builder(id, |node| node.set_description(key_type.label()));
    }
}

/// Tells accessibility tools (and UI tests) about the count of a row's keys out of view:
/// "r_foot rotation: 1 key after the view".
fn publish_marker(ui: &Ui, row: &Row, marker: Marker, before: bool, rect: Rect) {
    let key = (row.item, row.depth, row.shows.first().copied(), before);
    let label = || {
        let keys = if marker.count == 1 { "key" } else { "keys" };
        let side = if before { "before" } else { "after" };
        format!("{}: {} {keys} {side} the view", row.label, marker.count)
    };
    publish_painted(ui.ctx(), ui.id().with(("marker", key)), Role::Button, rect, label, None);
}

/// Tells accessibility tools (and UI tests) about a row's name, "dope sheet row elbow rotation",
/// and a group's triangle, "collapse Arm" or "expand Arm".
fn publish_row(ui: &Ui, row: &Row, name: Rect, indent: f32) {
    let key = (row.item, row.depth, matches!(row.kind, RowKind::Group { .. }), row.shows.first().copied());
    let label = || format!("dope sheet row {}", row.label);
    publish_painted(ui.ctx(), ui.id().with(("row", key)), Role::Row, name, label, None);
    if let RowKind::Group { collapsed } = row.kind {
        let expander =
            Rect::from_min_size(Pos2::new(indent - 1.0, name.top()), Vec2::new(11.0, name.height()));
        let label = || format!("{} {}", if collapsed { "expand" } else { "collapse" }, row.label);
        publish_painted(ui.ctx(), ui.id().with(("expander", key)), Role::Button, expander, label, None);
    }
}

/// What is at `pos` (screen points) in the rows laid out from `origin`.
fn hit(ctx: &FrameCtx<'_>, rows: &[Row], geo: &Geometry, origin: Pos2, pos: Pos2) -> Hit {
    let r = ((pos.y - origin.y) / ROW_HEIGHT).floor();
    if r < 0.0 || r as usize >= rows.len() {
        return Hit::Empty;
    }
    let r = r as usize;
    let row = &rows[r];
    if pos.x < geo.names.1 {
        let expander = geo.names.0 + 4.0 + INDENT * row.depth as f32;
        if row.group() && pos.x >= expander - 1.0 && pos.x <= expander + 10.0 {
            return Hit::Expander(r);
        }
        return Hit::Name(r);
    }
    let (buckets, before, after) = buckets(ctx, row, geo);
    let nearest = buckets
        .iter()
        .map(|b| (b, (b.px as f32 - pos.x).abs()))
        .filter(|(_, d)| *d <= DIAMOND_RADIUS + 1.0)
        .min_by(|a, b| a.1.total_cmp(&b.1));
    if let Some((b, _)) = nearest {
        return Hit::Keys(r, keys_at(ctx.scene(), row, geo, b.px));
    }
    let beyond_diamonds = DIAMOND_RADIUS + 1.5;
    if before.count > 0 && pos.x < geo.keys.0 - beyond_diamonds {
        return before.nearest.map_or(Hit::Empty, Hit::Marker);
    }
    if after.count > 0 && pos.x > geo.keys.1 + beyond_diamonds {
        return after.nearest.map_or(Hit::Empty, Hit::Marker);
    }
    Hit::Empty
}

/// A click on keys: selects them (Shift/Ctrl adds them, or removes them when all were
/// selected) and, on a plain click, the item they belong to.
fn select_keys(selection: &Selection, actions: &mut Actions, row: &Row, keys: Vec<KeyRef>, additive: bool) {
    if additive {
        if keys.iter().all(|k| selection.keys.contains(k)) {
            actions.session(SessionChange::RemoveKeys(keys));
        } else {
            actions.session(SessionChange::AddKeys(keys));
        }
        return;
    }
    let owner = match (&row.kind, keys.first()) {
        (RowKind::Channel(_), Some(k)) => crate::session::owner_of(k.channel),
        _ => row.item,
    };
    actions.session(SessionChange::SetKeys(keys.into_iter().collect::<BTreeSet<_>>()));
    actions.session(SessionChange::SelectOnly(Some(owner)));
}

/// The view panned (and if needed widened) so that `frame` shows.
fn show_frame(geo: &Geometry, frame: f64) -> TimeView {
    let view = geo.view;
    let span = view.end - view.start;
    let margin = span * 0.05;
    if frame < view.start {
        TimeView { start: frame - margin, end: frame - margin + span }
    } else {
        TimeView { start: frame + margin - span, end: frame + margin }
    }
}

impl DopeSheet {
    /// Dragging the border between names and keys resizes the name column.
    fn resize_names_ui(&mut self, ui: &mut Ui, sheet: Rect, geo: &Geometry) {
        let handle = Rect::from_min_max(
            Pos2::new(geo.names.1 - 2.0, sheet.top()),
            Pos2::new(geo.names.1 + 4.0, sheet.bottom()),
        );
        let response = ui.interact(handle, ui.id().with("resize_names"), Sense::drag());
        let response = response.on_hover_cursor(CursorIcon::ResizeHorizontal);
        if response.dragged() {
            let width = geo.names.1 - geo.names.0 + response.drag_delta().x;
            self.name_width = Some(width.max(MIN_NAME_WIDTH));
        }
        if response.hovered() || response.dragged() {
            ui.painter().line_segment(
                [Pos2::new(geo.names.1, sheet.top()), Pos2::new(geo.names.1, sheet.bottom())],
                Stroke::new(2.0, ui.visuals().selection.stroke.color),
            );
        }
    }

    /// Ctrl+wheel zooms the time axis about the pointer; Shift+wheel or a horizontal wheel pans.
    fn navigate(&mut self, ui: &mut Ui, sheet: Rect, geo: &Geometry) {
        let Some(pointer) = ui.input(|i| i.pointer.hover_pos()).filter(|p| sheet.contains(*p)) else {
            return;
        };
        if pointer.x < geo.keys.0 - PAD {
            return;
        }
        let (zoom, scroll_x) = ui.input(|i| (i.zoom_delta(), i.smooth_scroll_delta.x));
        let mut axis = geo.axis();
        if (zoom - 1.0).abs() > 1e-4 {
            (axis.start, axis.end) = axis.zoomed(geo.frame(pointer.x), f64::from(zoom), MIN_SPAN);
        }
        if scroll_x.abs() > 0.0 {
            // By the frames per point the sheet was drawn with (before a zoom of this frame).
            let (start, _) = geo.axis().panned(scroll_x);
            let shift = start - geo.view.start;
            (axis.start, axis.end) = (axis.start + shift, axis.end + shift);
        }
        let view = TimeView { start: axis.start, end: axis.end };
        if view != geo.view {
            self.view = Some(view);
        }
    }
}

/// Frames between labelled ticks so that labels are at least ~40 points apart.
fn tick_step(span: f64, width: f32) -> i64 {
    let span = span.max(1.0);
    for step in [1, 2, 5, 10, 20, 50, 100, 200, 500, 1000, 2000, 5000, 10_000, 20_000, 50_000] {
        if f64::from(width) / (span / step as f64) >= 40.0 {
            return step;
        }
    }
    100_000
}
