//! The curve editor: the selected channels over time, sampled through the same code as the
//! viewport, so it updates live while a key or a T/C/B slider changes. Positions are drawn per
//! component; rotations as XYZ Euler angles in degrees, unwrapped along the curve; each curve
//! has its own colour, named in the legend. Keys are clicked, box-selected and dragged in time
//! (whole frames) and value, one undo step per drag; Delete, Ctrl+C and Ctrl+V work on them as
//! in the dope sheet. The view zooms (wheel; Ctrl+wheel: time only) and pans (Shift+wheel,
//! middle-drag) with rulers of frames and values; the frame ruler scrubs; *Fit* shows
//! everything, F over the curves frames the selected keys (Home stays the first frame).
//! A rotation channel with spin keys also gets its unwrapped turn (white): the twist about the
//! first spin's axis through spin segments ([`keyrig_edit::spin::unwrapped_twist`], which counts
//! their turns with `Track::spin_degrees`), so a 720° segment climbs to 720 instead of
//! wrapping at ±180°. A channel with cycles (`before`/`after` other than Hold) is drawn over the
//! whole range, its repeats included; the stretches beyond its keys are shaded and named.
//! *Normalize* scales each curve to −1 … 1; *Stacked* gives each kind of curve (translation,
//! rotation, scale, other) a lane of its own framed to its values, with its own ruler, all
//! sharing the time axis ([`Lane`]: every curve's [`ValueMap`] then puts it in its lane, so
//! picking and dragging read the lane's scale).

use std::collections::{BTreeSet, HashMap};
use std::rc::Rc;

use egui::{Align2, Color32, FontId, Pos2, Sense, Shape, Stroke, Ui, Vec2};
use keyrig_core::Scene;
use keyrig_eval::SceneEvaluator;

use crate::actions::{Action, Actions, Edit, SessionChange, Ticket};
use crate::commands::Command;
use crate::context::FrameCtx;
use crate::eval::{continuous_euler, PoseOverrides};
use crate::scene_frame::EvalKey;
use crate::session::{KeyRef, Selection};
use crate::widgets::publish_painted;
use crate::widgets::range_watch::RangeWatch;
use crate::widgets::time_axis::TimeAxis;
use egui::accesskit::Role;
use keyrig_core::channel_id::rotation_mode;
use keyrig_edit::channels::{self, ChannelId, ChannelValue};
use keyrig_edit::{KeyParamChange, SceneEdit};

/// The unwrapped turn of a rotation channel with spin keys (the fourth curve).
const TURN_COLOUR: Color32 = Color32::from_rgb(240, 240, 240);

/// The frames and values the curve view shows.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CurveView {
    pub start: f64,
    pub end: f64,
    pub low: f32,
    pub high: f32,
}

/// What the current pointer gesture in the curve view is doing.
#[derive(Clone, Copy, Debug, PartialEq)]
enum CurveGesture {
    /// Moving the selected keys: whole frames and value (of `component`, in curve units)
    /// already applied; `scale` is how the grabbed curve is drawn (normalised view).
    MoveKeys { frames: i32, value: f32, component: usize, scale: f32 },
    /// A box selection from this point.
    Box { start: Pos2 },
    /// Panning with the middle button from this view.
    Pan { from: CurveView },
    /// Scrubbing the current frame on the frame ruler.
    Scrub,
    /// Dragging a Hermite handle: the key, the component and which tangent; `convert`: the
    /// previous key is not Hermite yet (its segment takes the handle once it is dragged).
    Handle { key: KeyRef, component: usize, outgoing: bool, convert: bool },
}

/// One component over time: (frame, value) samples.
pub type Curve = Vec<(f64, f32)>;

/// What one channel's samples were taken for: the channel, the frames and count, and whether
/// rotations were read as twists.
type SampleKey = (ChannelId, u64, u64, usize, bool);

/// What the key points were placed for: the evaluator, the plot (rect and view, as bits), the
/// channels, and whether rotations were read as twists.
type PointsKey = (EvalKey, [u32; 4], [u64; 4], Vec<ChannelId>, bool, Maps);

/// The curve editor and its own state: the view, the gesture under way, how rotations read,
/// where it was laid out, and its samples (kept while the document, the view and the channel
/// stay the same).
#[derive(Debug, Default)]
pub struct CurveEditor {
    /// `None`: the frame range and every shown value (*Fit*).
    pub view: Option<CurveView>,
    gesture: Option<CurveGesture>,
    /// F was pressed over the curves: frame the selected keys when next laid out.
    frame_keys: bool,
    /// Rotations drawn as their unwrapped twist about the bone axis instead of Euler angles.
    pub rotation_as_twist: bool,
    /// Curves hidden from view (a click on their legend entry), by channel and curve.
    pub hidden: BTreeSet<(ChannelId, usize)>,
    /// Each shown curve scaled to −1 … 1 over the frame range (Blender's Normalize).
    pub normalized: bool,
    /// One lane per kind of curve (translation, rotation, scale, other), stacked and sharing
    /// the time axis, each framed to its own values with its own ruler (Maya's stacked view).
    pub stacked: bool,
    /// Where the curve view was laid out in the last frame (F over it frames its keys).
    rect: Option<egui::Rect>,
    /// The key move pushed in the last frame and the whole frames the gesture has applied once
    /// it is taken.
    pending_move: Option<(Ticket, i32)>,
    /// Samples by channel, frames and count, for the evaluator they were taken from; each
    /// frame keeps only those it used.
    samples: HashMap<SampleKey, (EvalKey, Rc<Vec<Curve>>, bool)>,
    /// The key points of the last plot, kept while it and the document stay the same.
    points: Option<(PointsKey, Rc<Vec<KeyPoint>>)>,
    /// The frame range last laid out: a range that grew refits the view ([`RangeWatch`]).
    range_watch: RangeWatch,
    /// The document and the selected items last laid out: other items are shown fitted, and
    /// another document also starts without Normalize and hidden curves.
    shown: Option<(u64, Vec<crate::session::Selected>)>,
}

/// The axis whose unwrapped turn the curve view draws for a rotation channel: the first spin
/// segment's (in its first key's frame); `None` without spin keys.
#[must_use]
pub fn turn_axis(scene: &Scene, id: ChannelId) -> Option<(keyrig_core::Track<glam::Quat>, glam::DVec3)> {
    let Some(channels::ChannelRef::Rotation(a)) = channels::channel(scene, id) else { return None };
    if a.track.keys.iter().all(|k| k.spin.is_none()) {
        return None;
    }
    let track = keyrig_core::Track::new(&a.track).ok()?;
    let axis = (0..track.key_count()).find_map(|i| track.segment_spin(i))?.0;
    Some((track, axis))
}

/// The channels the curve view shows: those of the selected item and of the selected keys.
#[must_use]
pub fn shown_channels(scene: &Scene, selection: &Selection) -> Vec<ChannelId> {
    let mut ids: Vec<ChannelId> = selection.channels(scene);
    // The item's attributes (visibility, opacity, cone, …) where keyed, after its transform.
    match selection.item {
        Some(crate::session::Selected::Object(o)) => {
            ids.extend(keyrig_core::AttributeId::of_object(scene, o))
        }
        Some(crate::session::Selected::Light(l)) => ids.extend(keyrig_core::AttributeId::of_light(scene, l)),
        _ => {}
    }
    for k in &selection.keys {
        if !ids.contains(&k.channel) {
            ids.push(k.channel);
        }
    }
    ids.retain(|&id| channels::key_count(scene, id) > 0);
    ids
}

/// Samples `id` over frames `[start, end]` at `samples` points as one or three curves of
/// numbers (components, or Euler degrees for rotations; with `twist`, a rotation's twist about
/// the bone axis), and for a rotation with spin keys a fourth: its unwrapped turn in degrees
/// about the first spin's axis ([`turn_axis`]). Overrides are not shown: the curves are the
/// keys'.
#[must_use]
pub fn sample_curves(
    eval: &SceneEvaluator,
    scene: &Scene,
    id: ChannelId,
    (start, end): (f64, f64),
    samples: usize,
    twist: bool,
) -> Vec<Curve> {
    let fps = scene.fps.max(1e-9);
    let none = PoseOverrides::new();
    let n = samples.max(2);
    let mode = rotation_mode(scene, id);
    let mut curves: Vec<Curve> = Vec::new();
    // Rotations read continuously: Euler angles from the channel's first key on
    // ([`continuous_euler`]), each sample the triple nearest the last; quaternions on the
    // hemisphere of the last sample.
    let mut near: Option<Vec<f32>> = match (id.kind(), mode.euler()) {
        (channels::ChannelKind::Rotation, Some(order)) if !twist => {
            continuous_euler(eval, scene, id, order, start / fps, &none).map(|e| e.to_array().to_vec())
        }
        _ => None,
    };
    for i in 0..n {
        let frame = start + (end - start) * i as f64 / (n - 1) as f64;
        let values = shown_components(mode, twist, eval.value(id, frame / fps, &none), near.as_deref());
        if curves.is_empty() {
            curves = vec![Vec::with_capacity(n); values.len()];
        }
        for (c, v) in values.iter().enumerate() {
            let v = if twist && id.kind() == channels::ChannelKind::Rotation {
                // Unwrap the twist so a turn past ±180° stays continuous.
                match curves[c].last() {
                    Some(&(_, prev)) => prev + (v - prev + 180.0).rem_euclid(360.0) - 180.0,
                    None => *v,
                }
            } else {
                *v
            };
            curves[c].push((frame, v));
        }
        if id.kind() == channels::ChannelKind::Rotation && !twist {
            near = Some(values);
        }
    }
    if let Some((track, axis)) = turn_axis(scene, id).filter(|_| !twist) {
        curves.push(
            (0..n)
                .map(|i| {
                    let frame = start + (end - start) * i as f64 / (n - 1) as f64;
                    (frame, keyrig_edit::spin::unwrapped_twist(&track, axis, frame / fps) as f32)
                })
                .collect(),
        );
    }
    curves
}

/// The numbers the curve view draws for a value: a vector's components, a scalar, and a
/// rotation as its channel's mode reads it — Euler angles in degrees in its order (the triple
/// nearest `near` when given), or the quaternion's w, x, y, z (on `near`'s hemisphere) — or,
/// with `twist`, its twist about the bone axis (X) in degrees (wrapped here; the curves unwrap
/// it along time).
fn shown_components(
    mode: keyrig_core::RotationMode,
    twist: bool,
    value: Option<ChannelValue>,
    near: Option<&[f32]>,
) -> Vec<f32> {
    match value {
        Some(ChannelValue::Vec3(v)) => v.to_array().to_vec(),
        Some(ChannelValue::Rotation(q)) if twist => {
            vec![keyrig_edit::spin::twist_degrees(q.as_dquat(), keyrig_edit::spin::BONE_AXIS.as_dvec3())
                as f32]
        }
        Some(ChannelValue::Rotation(q)) => match mode.euler() {
            Some(order) => match near {
                Some(&[x, y, z, ..]) => order.angles_near(q, glam::Vec3::new(x, y, z)),
                _ => order.angles(q),
            }
            .to_array()
            .to_vec(),
            None => {
                let flip = match near {
                    Some(&[w, x, y, z, ..]) => q.dot(glam::Quat::from_xyzw(x, y, z, w)) < 0.0,
                    _ => q.w < 0.0,
                };
                let q = if flip { -q } else { q };
                vec![q.w, q.x, q.y, q.z]
            }
        },
        Some(ChannelValue::Scalar(s)) => vec![s],
        None => Vec::new(),
    }
}

/// How many value curves a channel has (1 for scalars and twists, 4 for quaternions, else 3);
/// a rotation with spin keys has its unwrapped turn after them.
fn value_count(scene: &Scene, id: ChannelId, twist: bool) -> usize {
    match id.kind() {
        channels::ChannelKind::Scalar => 1,
        channels::ChannelKind::Rotation if twist => 1,
        channels::ChannelKind::Rotation if rotation_mode(scene, id).euler().is_none() => 4,
        _ => 3,
    }
}

/// The fewest frames F over the curves shows around the selected keys (one key is not zoomed
/// to a frame's width).
const MIN_FRAMED_FRAMES: f64 = 20.0;

/// Width of the value ruler and height of the frame ruler, points.
const VALUE_RULER: f32 = 44.0;
const FRAME_RULER: f32 = 16.0;
/// How close (points) the pointer must be to a key to take it.
const PICK_RADIUS: f32 = 6.0;

/// One colour per shown curve (channel and component), distinct for up to twelve curves.
const PALETTE: [Color32; 12] = [
    Color32::from_rgb(235, 85, 85),
    Color32::from_rgb(95, 205, 95),
    Color32::from_rgb(95, 145, 245),
    Color32::from_rgb(240, 200, 80),
    Color32::from_rgb(215, 110, 230),
    Color32::from_rgb(80, 210, 215),
    Color32::from_rgb(245, 150, 70),
    Color32::from_rgb(160, 230, 120),
    Color32::from_rgb(150, 150, 255),
    Color32::from_rgb(255, 140, 180),
    Color32::from_rgb(190, 170, 120),
    Color32::from_rgb(130, 200, 170),
];

/// The colour of curve `c` of the `n`-th shown channel: a channel's components take
/// neighbouring colours, so two channels never share one (up to four channels); the unwrapped
/// turn is white.
fn curve_colour(n: usize, c: usize, is_turn: bool) -> Color32 {
    if is_turn {
        return TURN_COLOUR;
    }
    PALETTE[(n * 3 + c) % PALETTE.len()]
}

/// "X", "Y", "Z" for a vector or Euler angle component, "W" … "Z" for a quaternion's, "turn"
/// for the unwrapped turn.
fn component_name(scene: &Scene, id: ChannelId, c: usize) -> &'static str {
    let quaternion =
        id.kind() == channels::ChannelKind::Rotation && rotation_mode(scene, id).euler().is_none();
    match (id.kind(), c) {
        (channels::ChannelKind::Scalar, _) => "",
        _ if quaternion => ["W", "X", "Y", "Z", "turn"].get(c).copied().unwrap_or("turn"),
        (_, 0) => "X",
        (_, 1) => "Y",
        (_, 2) => "Z",
        _ => "turn",
    }
}

/// How many curves a channel draws: its values and, for a rotation with spin keys, its turn.
fn curve_count(scene: &Scene, id: ChannelId, twist: bool) -> usize {
    value_count(scene, id, twist) + usize::from(!twist && turn_axis(scene, id).is_some())
}

/// Screen mapping of the plot: frames across (the time axis the dope sheet shares), values up.
#[derive(Clone, Copy, Debug)]
struct Plot {
    rect: egui::Rect,
    view: CurveView,
}

impl Plot {
    fn axis(&self) -> TimeAxis {
        TimeAxis {
            left: self.rect.left(),
            right: self.rect.right(),
            start: self.view.start,
            end: self.view.end,
        }
    }

    fn pos(&self, frame: f64, value: f32) -> Pos2 {
        let v = self.view;
        Pos2::new(
            self.axis().x(frame),
            self.rect.bottom() - (value - v.low) / (v.high - v.low).max(1e-9) * self.rect.height(),
        )
    }

    fn frame(&self, x: f32) -> f64 {
        self.axis().frame(x)
    }

    fn frames_per_point(&self) -> f64 {
        self.axis().frames_per_point()
    }

    fn values_per_point(&self) -> f32 {
        (self.view.high - self.view.low) / self.rect.height().max(1.0)
    }
}

/// A key on one component's curve.
#[derive(Clone, Copy, Debug, PartialEq)]
struct KeyPoint {
    key: KeyRef,
    component: usize,
    pos: Pos2,
}

/// A Bézier-style handle of a selected Hermite key: a third of the way to the neighbouring key
/// in time, along the key's tangent (value per second) of `component`.
#[derive(Clone, Copy, Debug, PartialEq)]
struct Handle {
    key: KeyRef,
    component: usize,
    /// The out-tangent (towards the next key), or the in-tangent (towards the previous one).
    outgoing: bool,
    pos: Pos2,
    /// The key's own point, and the seconds the handle spans (a third of the segment).
    key_pos: Pos2,
    seconds: f64,
    /// An in-handle of a Hermite key after a key that is not Hermite: dragging it makes the
    /// previous key Hermite too (keeping its shape), so that the segment takes the tangent.
    convert: bool,
    /// How the curve is drawn.
    map: ValueMap,
}

/// The handles of the selected Hermite keys of position and scalar channels among `ids`: the
/// out-handle and the in-handle of each (both tangents are stored), on the curves as drawn.
fn handles(scene: &Scene, selection: &Selection, plot: &Plot, ids: &[ChannelId], maps: &Maps) -> Vec<Handle> {
    let fps = scene.fps.max(1e-9);
    let mut out = Vec::new();
    for &key in &selection.keys {
        if key.channel.kind() == channels::ChannelKind::Rotation {
            continue;
        }
        let Some(n) = ids.iter().position(|&id| id == key.channel) else { continue };
        // Per key, not the whole track's times: A can select every key of a long track.
        let time_of = |i: usize| channels::key_params(scene, key.channel, i).map(|p| p.0);
        let (Some(t), Some(value)) = (time_of(key.index), channels::key_value(scene, key.channel, key.index))
        else {
            continue;
        };
        let values: Vec<f32> = match value {
            ChannelValue::Vec3(v) => v.to_array().to_vec(),
            ChannelValue::Scalar(s) => vec![s],
            ChannelValue::Rotation(_) => continue,
        };
        let (inn, outt) = channels::key_tangents(scene, key.channel, key.index);
        let hermite = |i: usize| {
            channels::key_params(scene, key.channel, i)
                .is_some_and(|p| p.1 == keyrig_core::Interpolation::Hermite)
        };
        let mut add = |tangent: Option<Vec<f32>>, neighbour: Option<f64>, outgoing: bool, convert: bool| {
            let (Some(tangent), Some(other)) = (tangent, neighbour) else { return };
            let seconds = (other - t).abs() / 3.0;
            let sign = if outgoing { 1.0 } else { -1.0 };
            for (c, (&v, &m)) in values.iter().zip(&tangent).enumerate() {
                let Some(map) = maps.get(n).and_then(|m| m.get(c)).copied().flatten() else { continue };
                out.push(Handle {
                    key,
                    component: c,
                    outgoing,
                    pos: plot
                        .pos((t + sign * seconds) * fps, map.apply(v + sign as f32 * m * seconds as f32)),
                    key_pos: plot.pos(t * fps, map.apply(v)),
                    seconds,
                    convert,
                    map,
                });
            }
        };
        if hermite(key.index) {
            add(outt, time_of(key.index + 1), true, false);
        }
        if key.index > 0 && (hermite(key.index - 1) || hermite(key.index)) {
            add(inn, time_of(key.index - 1), false, !hermite(key.index - 1));
        }
    }
    out
}

/// The value range of the curves.
fn value_extent(all: &[(ChannelId, Rc<Vec<Curve>>)]) -> Option<(f32, f32)> {
    let (mut lo, mut hi) = (f32::INFINITY, f32::NEG_INFINITY);
    for (_, curves) in all {
        for &(_, v) in curves.iter().flatten() {
            if v.is_finite() {
                lo = lo.min(v);
                hi = hi.max(v);
            }
        }
    }
    (lo.is_finite() && hi.is_finite()).then_some((lo, hi))
}

/// How one curve is drawn: its values scaled about `mid` and moved by `offset` (normalised
/// view, stacked lanes): plotted = (value − mid) × scale + offset.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ValueMap {
    pub mid: f32,
    pub scale: f32,
    pub offset: f32,
}

impl ValueMap {
    pub const IDENTITY: ValueMap = ValueMap { mid: 0.0, scale: 1.0, offset: 0.0 };

    /// The plotted value of a curve value.
    #[must_use]
    pub fn apply(self, v: f32) -> f32 {
        (v - self.mid) * self.scale + self.offset
    }

    /// The curve value of a plotted value.
    #[must_use]
    pub fn invert(self, y: f32) -> f32 {
        (y - self.offset) / self.scale + self.mid
    }

    /// The map that puts `lo … hi` on −1 … 1 (a flat curve is centred, not stretched).
    #[must_use]
    pub fn normalizing(lo: f32, hi: f32) -> Self {
        let mid = 0.5 * (lo + hi);
        let half = 0.5 * (hi - lo);
        ValueMap { mid, scale: if half > 1e-6 { 1.0 / half } else { 1.0 }, offset: 0.0 }
    }

    /// This map followed by `then`: `then.apply(self.apply(v))`.
    #[must_use]
    pub fn then(self, then: ValueMap) -> Self {
        ValueMap {
            mid: self.mid,
            scale: self.scale * then.scale,
            offset: (self.offset - then.mid) * then.scale + then.offset,
        }
    }
}

/// What a lane of the stacked view holds: curves that share a unit.
#[derive(Clone, Copy, Debug, PartialEq, Eq, PartialOrd, Ord)]
pub enum LaneKind {
    /// Positions: object, joint, root and camera translation, light positions, IK targets.
    Translation,
    /// Rotations read as angles (Euler degrees, twists, unwrapped turns).
    Rotation,
    /// Rotations read as quaternion components (−1 … 1).
    Quaternion,
    /// Object and joint scale.
    Scale,
    /// Everything else: attributes, light colour and intensity, IK blend, camera lens …
    Other,
}

impl LaneKind {
    /// The lane that `id`'s curves go to (rotations by how their channel's mode reads them).
    #[must_use]
    pub fn of(scene: &Scene, id: ChannelId, twist: bool) -> Self {
        match id {
            ChannelId::ObjectTranslation(_)
            | ChannelId::RootTranslation(_)
            | ChannelId::JointTranslation { .. }
            | ChannelId::LightPosition(_)
            | ChannelId::CameraTranslation(_)
            | ChannelId::IkTarget { .. } => LaneKind::Translation,
            ChannelId::ObjectScale(_) | ChannelId::JointScale { .. } => LaneKind::Scale,
            // Euler keys are angles in degrees.
            ChannelId::ObjectEuler(_) | ChannelId::JointEuler { .. } => LaneKind::Rotation,
            _ if id.kind() == channels::ChannelKind::Rotation => {
                if !twist && rotation_mode(scene, id).euler().is_none() {
                    LaneKind::Quaternion
                } else {
                    LaneKind::Rotation
                }
            }
            _ => LaneKind::Other,
        }
    }

    /// The lane's name, drawn in its top-left corner.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            LaneKind::Translation => "Translation",
            LaneKind::Rotation => "Rotation (°)",
            LaneKind::Quaternion => "Rotation (quaternion)",
            LaneKind::Scale => "Scale",
            LaneKind::Other => "Other",
        }
    }
}

/// The part of each lane's height its curves use (the rest is a margin above and below).
const LANE_FILL: f32 = 0.84;

/// One lane of the stacked view: a band of the plotted values (`index` counted from the top;
/// lane `i` of `n` spans plotted `n − 1 − i … n − i`) where the values `lo … hi` of its curves
/// (as the normalised view reads them, when on) are framed on their own scale.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Lane {
    pub kind: LaneKind,
    pub index: usize,
    pub lo: f32,
    pub hi: f32,
    /// How many lanes are stacked.
    pub count: usize,
}

impl Lane {
    /// The map from the lane's values to the plotted values.
    #[must_use]
    pub fn map(&self) -> ValueMap {
        let bottom = (self.count - 1 - self.index) as f32;
        let k = LANE_FILL / (self.hi - self.lo).max(1e-9);
        ValueMap { mid: self.lo, scale: k, offset: bottom + 0.5 * (1.0 - LANE_FILL) }
    }

    /// The plotted values the lane spans (bottom, top).
    #[must_use]
    pub fn band(&self) -> (f32, f32) {
        let bottom = (self.count - 1 - self.index) as f32;
        (bottom, bottom + 1.0)
    }
}

/// Per channel, per curve: how it is drawn (`None`: hidden).
type Maps = Vec<Vec<Option<ValueMap>>>;

/// The curves as drawn: mapped by `maps`, hidden ones empty (their index kept).
fn displayed(all: &[(ChannelId, Rc<Vec<Curve>>)], maps: &Maps) -> Vec<(ChannelId, Rc<Vec<Curve>>)> {
    all.iter()
        .enumerate()
        .map(|(n, (id, curves))| {
            let shown = curves
                .iter()
                .enumerate()
                .map(|(c, curve)| match maps.get(n).and_then(|m| m.get(c)).copied().flatten() {
                    Some(map) if map == ValueMap::IDENTITY => curve.clone(),
                    Some(map) => curve.iter().map(|&(f, v)| (f, map.apply(v))).collect(),
                    None => Vec::new(),
                })
                .collect();
            (*id, Rc::new(shown))
        })
        .collect()
}

/// The key points of the shown curves in view: each key of each channel on each of its shown
/// components, at the value its curve reads there (Euler angles continuous with the curve,
/// twists unwrapped onto it), mapped as the curve is drawn.
fn key_points(
    eval: &SceneEvaluator,
    scene: &Scene,
    twist: bool,
    plot: &Plot,
    all: &[(ChannelId, Rc<Vec<Curve>>)],
    maps: &Maps,
) -> Vec<KeyPoint> {
    let fps = scene.fps.max(1e-9);
    let none = PoseOverrides::new();
    let mut out = Vec::new();
    let mut last_column = std::collections::HashMap::new();
    for (n, (id, curves)) in all.iter().enumerate() {
        let mode = rotation_mode(scene, *id);
        let window =
            channels::keys_between(scene, *id, plot.view.start / fps - 1e-9, plot.view.end / fps + 1e-9);
        for (i, time) in window.times.iter().enumerate() {
            let frame = time * fps;
            // Each curve's sample nearest the key: the reading the key continues.
            let near: Vec<f32> = curves
                .iter()
                .filter_map(|curve| {
                    curve
                        .iter()
                        .min_by(|a, b| (a.0 - frame).abs().total_cmp(&(b.0 - frame).abs()))
                        .map(|&(_, v)| v)
                })
                .collect();
            let raw = shown_components(mode, twist, eval.value(*id, *time, &none), Some(&near));
            for (c, raw) in raw.into_iter().enumerate() {
                let Some(map) = maps.get(n).and_then(|m| m.get(c)).copied().flatten() else { continue };
                let value = match near.get(c) {
                    Some(&near) if twist && id.kind() == channels::ChannelKind::Rotation => {
                        raw + 360.0 * ((near - raw) / 360.0).round()
                    }
                    _ => raw,
                };
                let pos = plot.pos(frame, map.apply(value));
                // One point per pixel column and component (motion-capture density).
                let column = (pos.x.round() as i32, *id, c);
                if last_column.insert(column, ()).is_some() {
                    continue;
                }
                out.push(KeyPoint {
                    key: KeyRef { channel: *id, index: window.first + i },
                    component: c,
                    pos,
                });
            }
        }
    }
    out
}

impl CurveEditor {
    /// Where the curve view was laid out in the last frame.
    #[must_use]
    pub fn rect(&self) -> Option<egui::Rect> {
        self.rect
    }

    /// Whether `pos` (screen points) is over the curve view as last laid out.
    #[must_use]
    pub fn contains(&self, pos: Pos2) -> bool {
        self.rect.is_some_and(|r| r.contains(pos))
    }

    /// F over the curves: frames the selected keys when next laid out.
    pub fn request_frame_keys(&mut self) {
        self.frame_keys = true;
    }

    /// The curves of `ids` over `[start, end]` at `samples` points, sampled once per document
    /// revision, view and channel (a frame that changed none of them samples nothing).
    fn curves_over(
        &mut self,
        ctx: &FrameCtx<'_>,
        ids: &[ChannelId],
        (start, end): (f64, f64),
        samples: usize,
    ) -> Vec<(ChannelId, Rc<Vec<Curve>>)> {
        let eval_key = crate::scene_frame::evaluator_key(ctx.doc, ctx.meshes);
        let twist = self.rotation_as_twist;
        let mut eval = None;
        ids.iter()
            .map(|&id| {
                let key = (id, start.to_bits(), end.to_bits(), samples, twist);
                match self.samples.get_mut(&key) {
                    Some((k, curves, used)) if *k == eval_key => {
                        *used = true;
                        (id, Rc::clone(curves))
                    }
                    _ => {
                        let eval = eval.get_or_insert_with(|| ctx.evaluator());
                        let curves =
                            Rc::new(sample_curves(eval, ctx.scene(), id, (start, end), samples, twist));
                        self.samples.insert(key, (eval_key, Rc::clone(&curves), true));
                        (id, curves)
                    }
                }
            })
            .collect()
    }

    /// The key points of `all` on `plot`, placed once per document revision, plot and channels.
    fn key_points(
        &mut self,
        ctx: &FrameCtx<'_>,
        ids: &[ChannelId],
        plot: &Plot,
        all: &[(ChannelId, Rc<Vec<Curve>>)],
        maps: &Maps,
    ) -> Rc<Vec<KeyPoint>> {
        let (r, v) = (plot.rect, plot.view);
        let key: PointsKey = (
            crate::scene_frame::evaluator_key(ctx.doc, ctx.meshes),
            [r.min.x.to_bits(), r.min.y.to_bits(), r.max.x.to_bits(), r.max.y.to_bits()],
            [v.start.to_bits(), v.end.to_bits(), u64::from(v.low.to_bits()), u64::from(v.high.to_bits())],
            ids.to_vec(),
            self.rotation_as_twist,
            maps.clone(),
        );
        if let Some((k, points)) = &self.points {
            if *k == key {
                return Rc::clone(points);
            }
        }
        let points =
            Rc::new(key_points(&ctx.evaluator(), ctx.scene(), self.rotation_as_twist, plot, all, maps));
        self.points = Some((key, Rc::clone(&points)));
        points
    }

    /// How each curve of `ids` is drawn: hidden, scaled to −1 … 1 over the frame range
    /// (normalised view), into its lane (stacked view), or as it is.
    fn maps(&mut self, ctx: &FrameCtx<'_>, ids: &[ChannelId]) -> Maps {
        self.layout(ctx, ids).0
    }

    /// How each curve of `ids` is drawn ([`CurveEditor::maps`]) and, in the stacked view, the
    /// lanes: one per kind of the shown curves, top to bottom in [`LaneKind`]'s order, each
    /// framed to what its curves take over the frame range (as the normalised view reads them
    /// when it is on).
    fn layout(&mut self, ctx: &FrameCtx<'_>, ids: &[ChannelId]) -> (Maps, Vec<Lane>) {
        let base = self.curve_maps(ctx, ids);
        if !self.stacked {
            return (base, Vec::new());
        }
        let scene = ctx.scene();
        let range = scene.frame_range;
        let (start, end) = (f64::from(range.start), f64::from(range.end.max(range.start + 1)));
        let whole = self.curves_over(ctx, ids, (start, end), 200);
        let twist = self.rotation_as_twist;
        let mut extents: std::collections::BTreeMap<LaneKind, (f32, f32)> = Default::default();
        for (n, &id) in ids.iter().enumerate() {
            let kind = LaneKind::of(scene, id, twist);
            let Some((_, curves)) = whole.get(n) else { continue };
            for (c, curve) in curves.iter().enumerate() {
                let Some(map) = base.get(n).and_then(|m| m.get(c)).copied().flatten() else { continue };
                let extent = extents.entry(kind).or_insert((f32::INFINITY, f32::NEG_INFINITY));
                for &(_, v) in curve {
                    let v = map.apply(v);
                    if v.is_finite() {
                        *extent = (extent.0.min(v), extent.1.max(v));
                    }
                }
            }
        }
        let count = extents.len();
        let lanes: Vec<Lane> = extents
            .into_iter()
            .enumerate()
            .map(|(index, (kind, (lo, hi)))| {
                let (lo, hi) = if !(lo.is_finite() && hi.is_finite()) {
                    (-1.0, 1.0)
                } else if hi - lo < 1e-4 * lo.abs().max(hi.abs()).max(1.0) {
                    // A flat lane: its value in the middle, half a unit each way.
                    (lo - 0.5, hi + 0.5)
                } else {
                    (lo, hi)
                };
                Lane { kind, index, lo, hi, count }
            })
            .collect();
        let maps = ids
            .iter()
            .enumerate()
            .map(|(n, &id)| {
                let kind = LaneKind::of(scene, id, twist);
                let lane = lanes.iter().find(|l| l.kind == kind).map(Lane::map);
                base.get(n)
                    .map(|curves| {
                        curves.iter().map(|m| m.and_then(|m| lane.map(|lane| m.then(lane)))).collect()
                    })
                    .unwrap_or_default()
            })
            .collect();
        (maps, lanes)
    }

    /// The view the curves are drawn in: the one zoomed or framed to, else *Fit*'s; in the
    /// stacked view, every lane's values whatever the zoom (the lanes frame their own).
    fn current_view(&mut self, ctx: &FrameCtx<'_>, ids: &[ChannelId]) -> CurveView {
        let view = match self.view {
            Some(view) => view,
            None => self.fit_view(ctx, ids),
        };
        self.with_lanes(ctx, ids, view)
    }

    /// `view` with, in the stacked view, the plotted values of every lane.
    fn with_lanes(&mut self, ctx: &FrameCtx<'_>, ids: &[ChannelId], view: CurveView) -> CurveView {
        if !self.stacked {
            return view;
        }
        let lanes = self.layout(ctx, ids).1.len().max(1);
        CurveView { low: 0.0, high: lanes as f32, ..view }
    }

    /// How each curve of `ids` is drawn before lanes: hidden, scaled to −1 … 1 over the frame
    /// range (normalised view), or as it is.
    fn curve_maps(&mut self, ctx: &FrameCtx<'_>, ids: &[ChannelId]) -> Maps {
        let scene = ctx.scene();
        let range = scene.frame_range;
        let (start, end) = (f64::from(range.start), f64::from(range.end.max(range.start + 1)));
        let whole = if self.normalized { Some(self.curves_over(ctx, ids, (start, end), 200)) } else { None };
        ids.iter()
            .enumerate()
            .map(|(n, &id)| {
                let count = curve_count(scene, id, self.rotation_as_twist);
                (0..count)
                    .map(|c| {
                        if self.hidden.contains(&(id, c)) {
                            return None;
                        }
                        let curve =
                            whole.as_ref().and_then(|w| w.get(n)).and_then(|(_, curves)| curves.get(c));
                        Some(match curve {
                            Some(curve) => {
                                let (lo, hi) =
                                    curve.iter().fold((f32::INFINITY, f32::NEG_INFINITY), |(lo, hi), p| {
                                        (lo.min(p.1), hi.max(p.1))
                                    });
                                if lo.is_finite() && hi.is_finite() {
                                    ValueMap::normalizing(lo, hi)
                                } else {
                                    ValueMap::IDENTITY
                                }
                            }
                            None => ValueMap::IDENTITY,
                        })
                    })
                    .collect()
            })
            .collect()
    }

    /// The view that shows the frame range and every shown value of `ids` (with a margin).
    fn fit_view(&mut self, ctx: &FrameCtx<'_>, ids: &[ChannelId]) -> CurveView {
        let range = ctx.scene().frame_range;
        let (start, end) = (f64::from(range.start), f64::from(range.end.max(range.start + 1)));
        let all = self.curves_over(ctx, ids, (start, end), 200);
        let maps = self.maps(ctx, ids);
        let (mut lo, mut hi) = value_extent(&displayed(&all, &maps)).unwrap_or((-1.0, 1.0));
        if hi - lo < 1e-3 {
            lo -= 0.5;
            hi += 0.5;
        }
        let pad = (hi - lo) * 0.08;
        self.with_lanes(ctx, ids, CurveView { start, end, low: lo - pad, high: hi + pad })
    }

    /// Frames the selected keys (all shown keys when none is selected): F over the curve view.
    /// The frames from the first selected key to the last (at least [`MIN_FRAMED_FRAMES`]), and
    /// every value the shown curves of their channels take there as drawn — spins and
    /// unwrapped angles included, so a 0° → 360° turn frames 0 … 360 — at least a tenth of the
    /// whole view's value span.
    fn frame_selected_keys(&mut self, ctx: &FrameCtx<'_>, ids: &[ChannelId]) {
        if ids.is_empty() {
            return;
        }
        let fit = self.fit_view(ctx, ids);
        let scene = ctx.scene();
        let fps = scene.fps.max(1e-9);
        let (mut f0, mut f1) = (f64::INFINITY, f64::NEG_INFINITY);
        let mut channels_of_keys: Vec<ChannelId> = Vec::new();
        for k in ctx.session.selection.keys.iter().filter(|k| ids.contains(&k.channel)) {
            let Some((time, _, _)) = channels::key_params(scene, k.channel, k.index) else { continue };
            f0 = f0.min(time * fps);
            f1 = f1.max(time * fps);
            if !channels_of_keys.contains(&k.channel) {
                channels_of_keys.push(k.channel);
            }
        }
        if !f0.is_finite() {
            self.view = Some(fit);
            return;
        }
        let grow = (MIN_FRAMED_FRAMES - (f1 - f0)).max(0.0) * 0.5;
        let (f0, f1) = (f0 - grow, f1 + grow);
        let all = self.curves_over(ctx, ids, (f0, f1), 400);
        let maps = self.maps(ctx, ids);
        let shown = displayed(&all, &maps);
        let (mut v0, mut v1) = (f32::INFINITY, f32::NEG_INFINITY);
        for (id, curves) in &shown {
            if !channels_of_keys.contains(id) {
                continue;
            }
            for &(_, v) in curves.iter().flatten() {
                if v.is_finite() {
                    v0 = v0.min(v);
                    v1 = v1.max(v);
                }
            }
        }
        if !v0.is_finite() {
            (v0, v1) = (fit.low, fit.high);
        }
        let min_span = (fit.high - fit.low) * 0.1;
        let grow_v = (min_span - (v1 - v0)).max(0.0) * 0.5;
        let (v0, v1) = (v0 - grow_v, v1 + grow_v);
        let (df, dv) = ((f1 - f0) * 0.08, (v1 - v0).max(1e-3) * 0.08);
        let framed = CurveView { start: f0 - df, end: f1 + df, low: v0 - dv, high: v1 + dv };
        self.view = Some(self.with_lanes(ctx, ids, framed));
    }

    /// Notes the document `doc` (its id) and the `items` selected now. Other items than last
    /// time (another object, joint or light selected, or none) are shown fitted (*Fit*: the
    /// frame range and every value), so a zoom or value framing made for one item never leaves
    /// the next one's curves off the plot; another document (opened, new, recovered) also
    /// starts with every curve shown and not normalised. The first look changes nothing.
    fn follow_shown(&mut self, doc: u64, items: Vec<crate::session::Selected>) {
        match &self.shown {
            Some((seen_doc, _)) if *seen_doc != doc => {
                self.view = None;
                self.normalized = false;
                self.hidden.clear();
                self.gesture = None;
            }
            Some((_, seen)) if *seen != items => self.view = None,
            _ => {}
        }
        if self.shown.as_ref().is_none_or(|(d, seen)| *d != doc || *seen != items) {
            self.shown = Some((doc, items));
        }
    }

    /// The curve view: its header (title, legend, Fit), the plot and its rulers. The pointer
    /// clicks or box-selects keys, drags them in time (whole frames) and value, drags Hermite
    /// handles, scrubs on the frame ruler; the wheel zooms (Ctrl: time only; Shift: pan), a
    /// middle-drag pans. Painted from this frame's state, after the view's own changes.
    pub fn ui(&mut self, ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions) {
        for (_, _, used) in self.samples.values_mut() {
            *used = false;
        }
        // The key move of the last frame: the gesture counts its frames once it was taken.
        if let Some((ticket, wanted)) = self.pending_move.take() {
            if let (true, Some(CurveGesture::MoveKeys { frames, .. })) =
                (ctx.results.moved(ticket), &mut self.gesture)
            {
                *frames = wanted;
            }
        }
        let scene = ctx.scene();
        // A range that grew (an import that extended it) is shown whole, as *Fit* shows it.
        if self.range_watch.grew(ctx.doc.cache_key().0, scene.frame_range) {
            self.view = None;
        }
        let ids = shown_channels(scene, &ctx.session.selection);
        let selection = &ctx.session.selection;
        let items: Vec<_> = selection.item.into_iter().chain(selection.others.iter().copied()).collect();
        self.follow_shown(ctx.doc.cache_key().0, items);
        ui.horizontal(|ui| {
            let title = match ids.as_slice() {
                [] => "Curves: select an animated object, joint or light".to_owned(),
                [one] => format!("Curves: {}", one.label(scene)),
                many => format!("Curves: {} channels", many.len()),
            };
            ui.label(title);
            let fit = "Show the frame range and every value (F over the curves frames the selected keys)";
            if !ids.is_empty() && ui.small_button("Fit").on_hover_text(fit).clicked() {
                self.view = None;
            }
            if !ids.is_empty() {
                let normalize = ui
                    .selectable_label(self.normalized, "Normalize")
                    .on_hover_text("Each curve scaled to −1 … 1 over the frame range, so small and large curves read together");
                if normalize.clicked() {
                    self.normalized = !self.normalized;
                    self.view = None;
                }
                let stacked = ui.selectable_label(self.stacked, "Stacked").on_hover_text(
                    "One lane per kind (translation, rotation, scale, other), each on its own value \
                     scale, sharing the time axis",
                );
                if stacked.clicked() {
                    self.stacked = !self.stacked;
                    self.view = None;
                }
                if !self.hidden.is_empty() && ui.small_button("Show all").clicked() {
                    self.hidden.clear();
                }
            }
        });
        if !ids.is_empty() {
            self.legend_ui(ui, ctx, actions, &ids);
        }
        let size = ui.available_size().max(Vec2::new(100.0, 60.0));
        let (rect, response) = ui.allocate_exact_size(size, Sense::click_and_drag());
        let clip = rect.intersect(ui.clip_rect());
        self.rect = Some(rect);
        if !ids.is_empty() {
            self.interact(ui, ctx, actions, &ids, rect, &response);
        }
        self.paint(ui, ctx, &ids, rect, clip);
        self.samples.retain(|_, (_, _, used)| *used);
    }

    /// What the pointer and the keyboard do over the curves (see [`CurveEditor::ui`]).
    fn interact(
        &mut self,
        ui: &mut Ui,
        ctx: &FrameCtx<'_>,
        actions: &mut Actions,
        ids: &[ChannelId],
        rect: egui::Rect,
        response: &egui::Response,
    ) {
        let scene = ctx.scene();
        let selection = &ctx.session.selection;
        if std::mem::take(&mut self.frame_keys) {
            self.frame_selected_keys(ctx, ids);
        }
        let view = self.current_view(ctx, ids);
        let plot = Plot { rect: plot_rect(rect), view };
        let samples = (plot.rect.width() / 2.0).clamp(16.0, 800.0) as usize;
        let all = self.curves_over(ctx, ids, (view.start, view.end), samples);
        let maps = self.maps(ctx, ids);
        let points = self.key_points(ctx, ids, &plot, &all, &maps);
        let scale_of = |key: KeyRef, component: usize| {
            ids.iter()
                .position(|&id| id == key.channel)
                .and_then(|n| maps.get(n).and_then(|m| m.get(component)).copied().flatten())
                .map_or(1.0, |m| m.scale)
        };
        let pick = |pos: Pos2| {
            points
                .iter()
                .map(|p| (p, p.pos.distance(pos)))
                .filter(|(_, d)| *d <= PICK_RADIUS)
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(p, _)| *p)
        };
        let additive = ui.input(|i| i.modifiers.shift || i.modifiers.command);
        let on_ruler = |pos: Pos2| pos.y > plot.rect.bottom();
        // Blender's graph editor: A selects every key shown, Alt+A none (over the curves, and not
        // while a text field has the keyboard).
        if response.hovered() && !ui.ctx().text_edit_focused() {
            let (all_keys, none) = ui.input(|i| {
                (
                    i.key_pressed(egui::Key::A) && i.modifiers.is_none(),
                    i.key_pressed(egui::Key::A) && i.modifiers.alt,
                )
            });
            if all_keys {
                for &id in ids {
                    let count = channels::key_count(scene, id);
                    actions.session(SessionChange::AddKeys(
                        (0..count).map(|index| KeyRef { channel: id, index }).collect(),
                    ));
                }
            } else if none {
                actions.session(SessionChange::SetKeys(BTreeSet::new()));
            }
        }

        if let Some(pos) = response.interact_pointer_pos().filter(|_| response.clicked()) {
            if on_ruler(pos) {
                ctx.set_frame(actions, plot.frame(pos.x).round() as i32);
            } else if let Some(point) = pick(pos) {
                select_key(selection, actions, point.key, additive);
            } else if !additive {
                actions.session(SessionChange::SetKeys(BTreeSet::new()));
            }
        }
        let press = ui.input(|i| i.pointer.press_origin());
        let grips = handles(scene, selection, &plot, ids, &maps);
        let grip_at = |pos: Pos2| {
            grips
                .iter()
                .map(|h| (h, h.pos.distance(pos)))
                .filter(|(_, d)| *d <= PICK_RADIUS)
                .min_by(|a, b| a.1.total_cmp(&b.1))
                .map(|(h, _)| *h)
        };
        if let Some(origin) = press.filter(|_| response.drag_started_by(egui::PointerButton::Primary)) {
            self.gesture = if on_ruler(origin) {
                Some(CurveGesture::Scrub)
            } else if let Some(grip) = grip_at(origin) {
                Some(CurveGesture::Handle {
                    key: grip.key,
                    component: grip.component,
                    outgoing: grip.outgoing,
                    convert: grip.convert,
                })
            } else if let Some(point) = pick(origin) {
                if !selection.keys.contains(&point.key) {
                    select_key(selection, actions, point.key, additive);
                }
                Some(CurveGesture::MoveKeys {
                    frames: 0,
                    value: 0.0,
                    component: point.component,
                    scale: scale_of(point.key, point.component),
                })
            } else {
                Some(CurveGesture::Box { start: origin })
            };
        }
        if response.drag_started_by(egui::PointerButton::Middle) {
            self.gesture = Some(CurveGesture::Pan { from: view });
        }
        // Only while the pointer drags: the frame of the release reports no movement.
        let delta = response.total_drag_delta().filter(|_| response.dragged());
        match self.gesture {
            Some(CurveGesture::Scrub) => {
                if let Some(pos) = response.interact_pointer_pos() {
                    ctx.set_frame(actions, plot.frame(pos.x).round() as i32);
                }
            }
            Some(CurveGesture::MoveKeys { frames, value, component, scale }) if delta.is_some() => {
                let delta = delta.unwrap_or_default();
                // The keys keep the view they were grabbed in, so a drag moves them by what the
                // pointer moved.
                self.view.get_or_insert(view);
                let wanted_frames = (f64::from(delta.x) * plot.frames_per_point()).round() as i32;
                // In curve units: the pointer moves the drawn curve (scaled when normalised).
                let wanted_value = -delta.y * plot.values_per_point() / scale;
                let mut applied = (frames, value);
                if wanted_frames != frames && self.pending_move.is_none() {
                    let ticket = actions.ticket();
                    let seconds = f64::from(wanted_frames - frames) / scene.fps.max(1e-9);
                    actions.edit(Edit::MoveSelectedKeys { seconds, ticket });
                    self.pending_move = Some((ticket, wanted_frames));
                }
                if (wanted_value - value).abs() > f32::EPSILON {
                    let twist = self.rotation_as_twist;
                    actions.edit(Edit::ShiftSelectedValues { component, delta: wanted_value - value, twist });
                    applied.1 = wanted_value;
                }
                self.gesture =
                    Some(CurveGesture::MoveKeys { frames: applied.0, value: applied.1, component, scale });
            }
            Some(CurveGesture::Box { start }) => {
                if response.drag_stopped() {
                    if let Some(end) =
                        response.interact_pointer_pos().or(ui.input(|i| i.pointer.latest_pos()))
                    {
                        let area = egui::Rect::from_two_pos(start, end);
                        if !additive {
                            actions.session(SessionChange::SetKeys(BTreeSet::new()));
                        }
                        let inside: Vec<KeyRef> =
                            points.iter().filter(|p| area.contains(p.pos)).map(|p| p.key).collect();
                        if !inside.is_empty() {
                            actions.session(SessionChange::AddKeys(inside));
                        }
                    }
                }
            }
            Some(CurveGesture::Pan { from }) if delta.is_some() => {
                let delta = delta.unwrap_or_default();
                let frames = -f64::from(delta.x) * plot.frames_per_point();
                let values = if self.stacked { 0.0 } else { delta.y * plot.values_per_point() };
                self.view = Some(CurveView {
                    start: from.start + frames,
                    end: from.end + frames,
                    low: from.low + values,
                    high: from.high + values,
                });
            }
            Some(CurveGesture::Handle { key, component, outgoing, convert }) if delta.is_some() => {
                // The handle follows the pointer's value; its time stays a third of the segment.
                let grip =
                    grips.iter().find(|h| h.key == key && h.component == component && h.outgoing == outgoing);
                if let (Some(grip), Some(pointer)) = (grip, response.interact_pointer_pos()) {
                    let value_at = |y: f32| {
                        view.low
                            + (plot.rect.bottom() - y) / plot.rect.height().max(1.0) * (view.high - view.low)
                    };
                    let rise =
                        grip.map.invert(value_at(pointer.y)) - grip.map.invert(value_at(grip.key_pos.y));
                    let tangent = rise / grip.seconds.max(1e-9) as f32 * if outgoing { 1.0 } else { -1.0 };
                    // Alt moves the handle alone (breaks the pair); else an aligned pair turns
                    // together.
                    let drag = if ui.input(|i| i.modifiers.alt) {
                        keyrig_edit::channels::HandleDrag::Free
                    } else {
                        keyrig_edit::channels::HandleDrag::Aligned
                    };
                    actions.edit(Edit::continuous(
                        "curve handle",
                        SceneEdit::Tangent { key, outgoing, component, value: tangent, convert, drag },
                    ));
                }
            }
            Some(CurveGesture::MoveKeys { .. } | CurveGesture::Pan { .. } | CurveGesture::Handle { .. })
            | None => {}
        }
        if response.drag_stopped() {
            if matches!(self.gesture, Some(CurveGesture::MoveKeys { .. } | CurveGesture::Handle { .. })) {
                actions.push(Action::CloseGroup);
            }
            self.gesture = None;
        }
        if !ui.input(|i| i.pointer.any_down()) && !response.drag_stopped() {
            self.gesture = None;
        }
        if let Some(pointer) = response.hover_pos() {
            self.zoom_and_pan(ui, &plot, pointer);
        }
        response.context_menu(|ui| key_menu_ui(ui, selection, actions));
    }

    /// Wheel over the curves zooms both axes about the pointer, Ctrl+wheel the time axis only,
    /// Shift+wheel (or a horizontal wheel) pans in time.
    fn zoom_and_pan(&mut self, ui: &Ui, plot: &Plot, pointer: Pos2) {
        let (zoom, scroll) = ui.input(|i| (i.zoom_delta(), i.smooth_scroll_delta));
        let mut view = plot.view;
        let anchor_frame = plot.frame(pointer.x);
        let anchor_value = view.low
            + (plot.rect.bottom() - pointer.y) / plot.rect.height().max(1.0) * (view.high - view.low);
        // The shortest span in frames a zoom keeps.
        const MIN_SPAN: f64 = 2.0;
        let zoom_time = |view: &mut CurveView, factor: f64| {
            let axis = TimeAxis { start: view.start, end: view.end, ..plot.axis() };
            (view.start, view.end) = axis.zoomed(anchor_frame, factor, MIN_SPAN);
        };
        if (zoom - 1.0).abs() > 1e-4 {
            zoom_time(&mut view, f64::from(zoom));
        }
        if scroll.y.abs() > 0.0 {
            let factor = (scroll.y * 0.004).exp();
            zoom_time(&mut view, f64::from(factor));
            // The stacked view's lanes frame their own values: the wheel zooms time only.
            if !self.stacked {
                let span = ((view.high - view.low) / factor).max(1e-3);
                let t = (anchor_value - view.low) / (view.high - view.low).max(1e-9);
                view.low = anchor_value - t * span;
                view.high = view.low + span;
            }
        }
        if scroll.x.abs() > 0.0 {
            let shift = -f64::from(scroll.x) * plot.frames_per_point();
            view.start += shift;
            view.end += shift;
        }
        if view != plot.view {
            self.view = Some(view);
        }
    }

    /// The legend: per channel its mute and lock toggles, then a swatch and name per curve —
    /// a click hides or shows the curve, Ctrl+click shows it alone (again: every curve) — and
    /// how rotations read.
    fn legend_ui(&mut self, ui: &mut Ui, ctx: &FrameCtx<'_>, actions: &mut Actions, ids: &[ChannelId]) {
        let scene = ctx.scene();
        let twist = self.rotation_as_twist;
        let every: Vec<(ChannelId, usize)> =
            ids.iter().flat_map(|&id| (0..curve_count(scene, id, twist)).map(move |c| (id, c))).collect();
        ui.horizontal_wrapped(|ui| {
            for (n, &id) in ids.iter().enumerate() {
                let label = id.label(scene);
                let values = value_count(scene, id, twist);
                let (muted, locked) = channels::mute_and_lock(scene, id);
                let mute = ui
                    .selectable_label(muted, egui::RichText::new("M").small())
                    .on_hover_text(format!("Mute {label}: it plays its static value, its keys are kept"));
                let name = format!("mute {label}");
                ui.ctx().accesskit_node_builder(mute.id, |node| node.set_label(name));
                if mute.clicked() {
                    actions.push(Action::CloseGroup);
                    actions.edit(Edit::scene(SceneEdit::Mute { channel: id, muted: !muted }));
                }
                let lock = ui
                    .selectable_label(locked, egui::RichText::new("🔒").small())
                    .on_hover_text(format!("Lock {label}: its keys and value cannot be changed"));
                let name = format!("lock {label}");
                ui.ctx().accesskit_node_builder(lock.id, |node| node.set_label(name));
                if lock.clicked() {
                    actions.push(Action::CloseGroup);
                    actions.edit(Edit::scene(SceneEdit::Lock { channel: id, locked: !locked }));
                }
                for c in 0..curve_count(scene, id, twist) {
                    let colour = curve_colour(n, c, c >= values);
                    let visible = !self.hidden.contains(&(id, c));
                    let (swatch, _) = ui.allocate_exact_size(Vec2::new(10.0, 10.0), Sense::hover());
                    if visible {
                        ui.painter().rect_filled(swatch, 2.0, colour);
                    } else {
                        ui.painter().rect_stroke(swatch, 2.0, Stroke::new(1.0, colour), egui::StrokeKind::Inside);
                    }
                    let name = if values == 1 && c == 0 && id.kind() == channels::ChannelKind::Rotation {
                        format!("{label} twist")
                    } else {
                        format!("{label} {}", component_name(scene, id, c)).trim_end().to_owned()
                    };
                    let mut text = egui::RichText::new(name).small();
                    if !visible {
                        text = text.weak().strikethrough();
                    }
                    let entry = ui
                        .selectable_label(visible, text)
                        .on_hover_text("Click: hide or show this curve. Ctrl+click: show it alone (again: all)");
                    if entry.clicked() {
                        if ui.input(|i| i.modifiers.command) {
                            let alone = every.iter().all(|&k| (k == (id, c)) != self.hidden.contains(&k));
                            self.hidden = if alone {
                                BTreeSet::new()
                            } else {
                                every.iter().copied().filter(|&k| k != (id, c)).collect()
                            };
                        } else if !self.hidden.remove(&(id, c)) {
                            self.hidden.insert((id, c));
                        }
                    }
                }
            }
            if ids.iter().any(|id| id.kind() == channels::ChannelKind::Rotation) {
                let twist = &mut self.rotation_as_twist;
                ui.label(egui::RichText::new("rotations:").small().weak());
                ui.selectable_value(twist, false, egui::RichText::new("As each channel's mode").small())
                    .on_hover_text(
                        "Rotations as their channel's rotation mode reads them (inspector): Euler angles \
                         in its order, continuous from key to key, or the quaternion's w, x, y, z",
                    );
                ui.selectable_value(twist, true, egui::RichText::new("Twist about X").small()).on_hover_text(
                    "Rotations as their twist about the bone axis (X), degrees, unwrapped: a 720° twist climbs to 720",
                );
            }
        });
    }
}

/// The curve view's context menu: the interpolation and the type of the selected keys (one undo
/// step each), and deleting them.
fn key_menu_ui(ui: &mut Ui, selection: &Selection, actions: &mut Actions) {
    use keyrig_core::Interpolation;
    let keys: Vec<KeyRef> = selection.keys.iter().copied().collect();
    if keys.is_empty() {
        ui.label("Select keys first (click, or drag a box)");
        return;
    }
    ui.label(format!("{} selected key(s)", keys.len()));
    let choices = [
        ("Step", Interpolation::Step, false),
        ("Linear", Interpolation::Linear, false),
        ("TCB spline", Interpolation::Tcb, false),
        ("TCB spline, clamped", Interpolation::Tcb, true),
    ];
    for (label, mode, clamped) in choices {
        if ui.button(label).clicked() {
            let change =
                KeyParamChange { interpolation: Some(mode), clamped: Some(clamped), ..Default::default() };
            actions.push(Action::CloseGroup);
            actions.edit(Edit::scene(SceneEdit::KeyParams { keys: keys.clone(), change }));
            ui.close();
        }
    }
    let shapeable = keys.iter().any(|k| k.channel.kind() != channels::ChannelKind::Rotation);
    if ui
        .add_enabled(shapeable, egui::Button::new("Hermite handles (keeps the shape)"))
        .on_hover_text("Explicit tangents to drag, equal to the curve's now (positions and scalars)")
        .clicked()
    {
        actions.push(Action::CloseGroup);
        actions.edit(Edit::scene(SceneEdit::HermiteHandles { keys: keys.clone() }));
        ui.close();
    }
    if ui
        .add_enabled(shapeable, egui::Button::new("Align handles"))
        .on_hover_text(
            "Broken handles (Alt+drag) become one tangent again, their mean: a handle drag then turns both",
        )
        .clicked()
    {
        actions.push(Action::CloseGroup);
        actions.edit(Edit::scene(SceneEdit::AlignHandles { keys: keys.clone() }));
        ui.close();
    }
    ui.separator();
    crate::widgets::key_type_menu::key_type_menu_ui(ui, selection, actions);
    ui.separator();
    if ui.button("Delete keys").clicked() {
        actions.command(Command::Delete);
        ui.close();
    }
}

/// The plot inside the curve view's rect, beside the value ruler and above the frame ruler.
fn plot_rect(rect: egui::Rect) -> egui::Rect {
    egui::Rect::from_min_max(
        Pos2::new(rect.left() + VALUE_RULER, rect.top() + 6.0),
        Pos2::new(rect.right() - 6.0, rect.bottom() - FRAME_RULER),
    )
}

/// A click on a key: selects it alone with its owner, or with Shift/Ctrl adds or removes it.
fn select_key(selection: &Selection, actions: &mut Actions, key: KeyRef, additive: bool) {
    if !additive {
        actions.session(SessionChange::SetKeys(BTreeSet::from([key])));
    } else if selection.keys.contains(&key) {
        actions.session(SessionChange::RemoveKeys(vec![key]));
    } else {
        actions.session(SessionChange::AddKeys(vec![key]));
    }
}

impl CurveEditor {
    /// Paints the curve view laid out at `rect` (shown within `clip`) from this frame's state,
    /// with the view as this frame's gestures left it.
    fn paint(&mut self, ui: &Ui, ctx: &FrameCtx<'_>, ids: &[ChannelId], rect: egui::Rect, clip: egui::Rect) {
        let painter = ui.painter().with_clip_rect(clip);
        let visuals = ui.visuals().clone();
        crate::widgets::flat_fill::fill(&painter, clip, visuals.extreme_bg_color, ctx.gpu_fills);
        if ids.is_empty() {
            return;
        }
        let view = self.current_view(ctx, ids);
        let plot = Plot { rect: plot_rect(rect), view };
        let scene = ctx.scene();
        let fps = scene.fps.max(1e-9);
        let samples = (plot.rect.width() / 2.0).clamp(16.0, 800.0) as usize;
        let all = self.curves_over(ctx, ids, (view.start, view.end), samples);
        let (maps, lanes) = self.layout(ctx, ids);
        let shown = displayed(&all, &maps);
        let weak = visuals.weak_text_color();
        let grid = Stroke::new(1.0, visuals.faint_bg_color);
        let plot_painter = painter.with_clip_rect(plot.rect.intersect(clip));

        // Frames outside the scene's range, shaded.
        let range = scene.frame_range;
        let (a, b) = (plot.pos(f64::from(range.start), 0.0).x, plot.pos(f64::from(range.end), 0.0).x);
        let shade = visuals.faint_bg_color.gamma_multiply(0.7);
        if a > plot.rect.left() {
            plot_painter.rect_filled(
                egui::Rect::from_min_max(plot.rect.min, Pos2::new(a, plot.rect.bottom())),
                0.0,
                shade,
            );
        }
        if b < plot.rect.right() {
            plot_painter.rect_filled(
                egui::Rect::from_min_max(Pos2::new(b, plot.rect.top()), plot.rect.max),
                0.0,
                shade,
            );
        }

        // Rulers: frames under the plot, values beside it, with grid lines.
        let step = nice_step(view.end - view.start, plot.rect.width(), 45.0).max(1.0);
        let mut f = (view.start / step).ceil() * step;
        while f <= view.end {
            let x = plot.pos(f, 0.0).x;
            plot_painter
                .line_segment([Pos2::new(x, plot.rect.top()), Pos2::new(x, plot.rect.bottom())], grid);
            painter.text(
                Pos2::new(x, plot.rect.bottom() + 2.0),
                Align2::CENTER_TOP,
                format!("{f:.0}"),
                FontId::proportional(9.5),
                weak,
            );
            f += step;
        }
        // One value ruler for the whole plot, or one per lane in its own units.
        let rulers: Vec<(ValueMap, f32, f32)> = if lanes.is_empty() {
            vec![(ValueMap::IDENTITY, view.low, view.high)]
        } else {
            lanes.iter().map(|lane| (lane.map(), lane.lo, lane.hi)).collect()
        };
        for &(map, low, high) in &rulers {
            let height =
                (plot.pos(view.start, map.apply(low)).y - plot.pos(view.start, map.apply(high)).y).abs();
            let vstep = nice_step(f64::from(high - low), height, 28.0);
            let mut v = (f64::from(low) / vstep).ceil() * vstep;
            while v <= f64::from(high) {
                // A tick at zero reads 0, not "-0" (the running sum lands a rounding error below it).
                let tick = if v.abs() < vstep * 1e-6 { 0.0 } else { v };
                let y = plot.pos(view.start, map.apply(tick as f32)).y;
                plot_painter
                    .line_segment([Pos2::new(plot.rect.left(), y), Pos2::new(plot.rect.right(), y)], grid);
                let text = if vstep >= 1.0 {
                    format!("{tick:.0}")
                } else {
                    format!("{tick:.*}", (-vstep.log10()).ceil() as usize)
                };
                painter.text(
                    Pos2::new(plot.rect.left() - 4.0, y),
                    Align2::RIGHT_CENTER,
                    text,
                    FontId::proportional(9.5),
                    weak,
                );
                v += vstep;
            }
        }
        // The stacked view's lanes: a line between two, each named in its top-left corner.
        for lane in &lanes {
            let (bottom, top) = lane.band();
            let y_top = plot.pos(view.start, top).y;
            if lane.index > 0 {
                painter.line_segment(
                    [Pos2::new(rect.left(), y_top), Pos2::new(plot.rect.right(), y_top)],
                    Stroke::new(1.0, visuals.widgets.noninteractive.bg_stroke.color),
                );
            }
            plot_painter.text(
                Pos2::new(plot.rect.left() + 4.0, y_top + 2.0),
                Align2::LEFT_TOP,
                lane.kind.label(),
                FontId::proportional(10.0),
                weak,
            );
            let band = egui::Rect::from_x_y_ranges(
                plot.rect.x_range(),
                plot.pos(view.start, top).y..=plot.pos(view.start, bottom).y,
            );
            let name = format!("curve lane {}", lane.kind.label());
            publish_painted(
                ui.ctx(),
                egui::Id::new(("curve lane", lane.index)),
                Role::Group,
                band,
                move || name,
                None,
            );
        }

        // Cycles: the curves go on beyond the keys (sampled like everything else); the stretches
        // outside the keys are shaded and named ("after: Repeat") so the repeats read as repeats.
        for id in ids {
            let Some(cycles) = channels::cycles(scene, *id).filter(|c| !c.is_hold()) else { continue };
            let window = channels::keys_between(scene, *id, f64::NEG_INFINITY, f64::INFINITY);
            let (Some(&first), Some(&last)) = (window.times.first(), window.times.last()) else { continue };
            let (first, last) =
                ((first * fps).clamp(view.start, view.end), (last * fps).clamp(view.start, view.end));
            for (from, to, cycle, text_at, align) in [
                (view.start, first, cycles.before, first, Align2::RIGHT_TOP),
                (last, view.end, cycles.after, last, Align2::LEFT_TOP),
            ] {
                if cycle.is_hold() || to <= from {
                    continue;
                }
                let (x0, x1) = (plot.pos(from, 0.0).x, plot.pos(to, 0.0).x);
                plot_painter.rect_filled(
                    egui::Rect::from_min_max(
                        Pos2::new(x0, plot.rect.top()),
                        Pos2::new(x1, plot.rect.bottom()),
                    ),
                    0.0,
                    visuals.faint_bg_color.gamma_multiply(0.6),
                );
                let end_name = if align == Align2::LEFT_TOP { "after" } else { "before" };
                plot_painter.text(
                    Pos2::new(plot.pos(text_at, 0.0).x, plot.rect.top()),
                    align,
                    format!("{end_name}: {}", cycle.label()),
                    FontId::proportional(10.0),
                    weak,
                );
            }
        }

        // Curves and their keys (in the stacked view each within its lane).
        for (n, (id, curves)) in shown.iter().enumerate() {
            let values = value_count(scene, *id, self.rotation_as_twist);
            let kind = LaneKind::of(scene, *id, self.rotation_as_twist);
            let curve_painter = match lanes.iter().find(|l| l.kind == kind) {
                Some(lane) => {
                    let (bottom, top) = lane.band();
                    let band = egui::Rect::from_x_y_ranges(
                        plot.rect.x_range(),
                        plot.pos(view.start, top).y..=plot.pos(view.start, bottom).y,
                    );
                    plot_painter.with_clip_rect(band.intersect(plot_painter.clip_rect()))
                }
                None => plot_painter.clone(),
            };
            for (c, curve) in curves.iter().enumerate() {
                let colour = curve_colour(n, c, c >= values);
                let points: Vec<Pos2> = curve.iter().map(|&(f, v)| plot.pos(f, v)).collect();
                curve_painter.add(Shape::line(points, Stroke::new(1.5, colour)));
            }
        }
        let points = self.key_points(ctx, ids, &plot, &all, &maps);
        for p in points.iter() {
            let n = ids.iter().position(|&id| id == p.key.channel).unwrap_or(0);
            let values = value_count(scene, p.key.channel, self.rotation_as_twist);
            let colour = curve_colour(n, p.component, p.component >= values);
            if ctx.session.selection.keys.contains(&p.key) {
                plot_painter.circle(
                    p.pos,
                    4.0,
                    Color32::from_rgb(255, 200, 60),
                    Stroke::new(1.0, Color32::WHITE),
                );
            } else {
                plot_painter.circle_filled(p.pos, 3.0, colour);
            }
        }
        for grip in handles(scene, &ctx.session.selection, &plot, ids, &maps) {
            // An in-handle whose segment is not Hermite yet is drawn dashed-grey until dragged.
            let line = if grip.convert { Color32::from_gray(120) } else { Color32::from_gray(200) };
            plot_painter.line_segment([grip.key_pos, grip.pos], Stroke::new(1.0, line));
            plot_painter.circle(
                grip.pos,
                3.5,
                Color32::from_gray(40),
                Stroke::new(1.5, Color32::from_rgb(255, 200, 60)),
            );
            let side = if grip.outgoing { "out" } else { "in" };
            let r = egui::Rect::from_center_size(grip.pos, Vec2::splat(2.0 * PICK_RADIUS));
            let id = egui::Id::new((
                "curve handle",
                grip.key.channel,
                grip.key.index,
                grip.component,
                grip.outgoing,
            ));
            let label = || {
                let (channel, component) = (grip.key.channel, grip.component);
                format!(
                    "{side} handle {} {} key {}",
                    channel.label(scene),
                    component_name(scene, channel, component),
                    grip.key.index
                )
            };
            publish_painted(ui.ctx(), id, Role::Button, r, label, None);
        }
        if let Some((_, axis)) = ids.iter().find_map(|&id| turn_axis(scene, id)) {
            plot_painter.text(
                Pos2::new(plot.rect.right(), plot.rect.top()),
                Align2::RIGHT_TOP,
                format!(
                    "white: turn about ({:.2}, {:.2}, {:.2}) through spin keys, unwrapped",
                    axis.x, axis.y, axis.z
                ),
                FontId::proportional(10.0),
                weak,
            );
        }
        // The current frame, and a box selection in progress.
        let x = plot.pos(ctx.session.playback.frame, 0.0).x;
        if x >= plot.rect.left() && x <= plot.rect.right() {
            painter.line_segment(
                [Pos2::new(x, plot.rect.top()), Pos2::new(x, rect.bottom())],
                Stroke::new(1.5, Color32::from_rgb(90, 170, 255)),
            );
        }
        if let (Some(CurveGesture::Box { start }), Some(now)) =
            (self.gesture, ui.input(|i| i.pointer.latest_pos()))
        {
            plot_painter.rect_stroke(
                egui::Rect::from_two_pos(start, now),
                0.0,
                Stroke::new(1.0, visuals.selection.stroke.color),
                egui::StrokeKind::Inside,
            );
        }
        // Accessibility tools (and UI tests) see each drawn key: "curve key elbow rotation X frame 30".
        for p in points.iter() {
            let r = egui::Rect::from_center_size(p.pos, Vec2::splat(2.0 * PICK_RADIUS));
            let id = egui::Id::new(("curve key", p.key.channel, p.key.index, p.component));
            let label = || {
                let frame = channels::key_params(scene, p.key.channel, p.key.index)
                    .map_or(0, |k| (k.0 * fps).round() as i64);
                let (channel, component) = (p.key.channel, p.component);
                format!(
                    "curve key {} {} frame {frame}",
                    channel.label(scene),
                    component_name(scene, channel, component)
                )
                .replace("  ", " ")
            };
            publish_painted(ui.ctx(), id, Role::Button, r, label, None);
        }
    }
}

/// Labelled ticks about `min_points` apart along a span: the step (1, 2 or 5 × 10ⁿ).
fn nice_step(span: f64, length: f32, min_points: f32) -> f64 {
    let raw = span.abs().max(1e-9) * f64::from(min_points) / f64::from(length.max(1.0));
    let base = 10f64.powf(raw.log10().floor());
    for m in [1.0, 2.0, 5.0, 10.0] {
        if base * m >= raw {
            return base * m;
        }
    }
    base * 10.0
}
