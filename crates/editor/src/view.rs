//! The view: how the editor looks at the document — the orbit camera, viewport options and
//! the panels' interaction state. Changing it never touches the document or its undo history.

use egui::Pos2;
use keyrig_core::Camera;

use crate::camera::Bounds;

/// How the viewport draws meshes: keyrig-render's one type (solid, wireframe, points).
pub use keyrig_render::RenderStyle;

/// How the editor looks at the document: the camera, viewport options and the panels' own
/// state. Not saved with the scene (the camera is copied to it on save) and not undone.
#[derive(Clone, Debug)]
pub struct ViewState {
    pub camera: Camera,
    pub grid: bool,
    pub bones: bool,
    /// Draw the selected object's or joint's motion path (GPU viewport).
    pub motion_path: bool,
    /// Pixels of the GPU viewport per screen pixel: 1 (full, the default) or 0.5 (half, four
    /// times fewer pixels to rasterize).
    pub resolution_scale: f32,
    /// 4× MSAA in the GPU viewport (off by default on a CPU rasterizer, where it costs more
    /// than the rest of the viewport).
    pub antialiasing: bool,
    pub style: RenderStyle,
    /// Where the viewport was laid out in the last frame (screen points), for picking tools
    /// and tests that aim at what the viewport shows.
    pub viewport_rect: Option<egui::Rect>,
    /// Where the curve view was laid out this frame; it is painted at the end of the frame
    /// ([`crate::panels::curves::paint_pending`]) so that edits made later in the frame (a
    /// slider in the inspector, a gizmo in the viewport) show in the same frame.
    pub pending_curves: Option<(egui::LayerId, egui::Rect)>,
    /// World bounds of each object as drawn in the last frame (deformed mesh, or joints and
    /// origin), by object index: framing (F, imports) and the clip planes use them.
    pub object_bounds: Vec<Option<Bounds>>,
    /// Objects to frame once their bounds are known (after an import or opening a model).
    pub frame_request: Option<Vec<usize>>,
    /// Draw materials (glTF base colour and texture, MD2 skins); off shows the plain
    /// per-object colours.
    pub textures: bool,
    /// The dope sheet's interaction state.
    pub timeline: TimelineState,
    /// The shortcut list (F12) is open.
    pub show_help: bool,
    /// The outliner's name field, while an item is being renamed.
    pub renaming: Option<Renaming>,
    /// Where a Ctrl+drag box selection in the viewport started (screen points).
    pub box_select: Option<egui::Pos2>,
    /// Ghosts of the selected object at other frames (View ▸ Onion skin).
    pub onion: crate::onion::OnionSkin,
    /// The curve editor's view and gesture.
    pub curves: CurveViewState,
    /// Where the curve editor was laid out in the last frame (F over it frames its keys).
    pub curves_rect: Option<egui::Rect>,
}

/// An item being renamed in the outliner: Enter or leaving the field applies the name (one
/// undo step), Escape cancels.
#[derive(Clone, Debug, PartialEq)]
pub struct Renaming {
    pub item: crate::session::Selected,
    pub text: String,
    /// The field has been given the keyboard once.
    pub focused: bool,
}

impl ViewState {
    /// The default view of a scene: its camera, grid, bones and motion paths on.
    #[must_use]
    pub fn new(camera: Camera) -> Self {
        ViewState {
            camera,
            grid: true,
            bones: true,
            motion_path: true,
            resolution_scale: 1.0,
            antialiasing: true,
            style: RenderStyle::Solid,
            viewport_rect: None,
            pending_curves: None,
            object_bounds: Vec::new(),
            frame_request: None,
            textures: true,
            timeline: TimelineState::default(),
            show_help: false,
            renaming: None,
            box_select: None,
            onion: crate::onion::OnionSkin::default(),
            curves: CurveViewState::default(),
            curves_rect: None,
        }
    }

    /// The union of the bounds of `objects` (all when `None`).
    #[must_use]
    pub fn bounds_of(&self, objects: Option<&[usize]>) -> Option<Bounds> {
        let pick = |o: usize| self.object_bounds.get(o).copied().flatten();
        let all: Vec<usize> = (0..self.object_bounds.len()).collect();
        objects.unwrap_or(&all).iter().filter_map(|&o| pick(o)).reduce(Bounds::union)
    }

    /// Width / height of the viewport (16:10 before the first frame).
    #[must_use]
    pub fn aspect(&self) -> f32 {
        self.viewport_rect.map_or(1.6, |r| r.width() / r.height().max(1.0))
    }
}

/// Interaction state of the dope sheet that lives across frames.
#[derive(Clone, Debug, Default)]
pub struct TimelineState {
    /// The pointer gesture in progress (moving keys, box selection, panning).
    pub(crate) gesture: Option<Gesture>,
    /// The frames the dope sheet shows; `None` follows the scene's frame range.
    pub view: Option<TimeView>,
    /// Collapsed groups (objects, lights, joints with several channels).
    pub collapsed: std::collections::BTreeSet<crate::session::Selected>,
    /// The name column's width, points, once resized.
    pub name_width: Option<f32>,
    /// When the FPS changes, keys keep their frames (true) or their times in seconds (false).
    pub keep_frames: bool,
    /// (fps, start, end) when the current FPS drag started.
    pub(crate) fps_drag_origin: Option<(f64, i32, i32)>,
}

/// The frames shown at the left and right end of the dope sheet's keys
/// ([`crate::panels::dope_sheet`]).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct TimeView {
    pub start: f64,
    pub end: f64,
}

/// What the current pointer gesture in the dope sheet is doing.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Gesture {
    /// Moving the selected keys: whole frames already applied.
    MoveKeys { applied: i32 },
    /// A box selection from this point.
    Box { start: Pos2 },
    /// Panning the time axis with the middle button from this view.
    Pan { from: TimeView },
}

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
pub enum CurveGesture {
    /// Moving the selected keys: whole frames and value (of `component`) already applied.
    MoveKeys { frames: i32, value: f32, component: usize },
    /// A box selection from this point.
    Box { start: Pos2 },
    /// Panning with the middle button from this view.
    Pan { from: CurveView },
    /// Scrubbing the current frame on the frame ruler.
    Scrub,
    /// Dragging a Hermite handle: the key, the component and which tangent.
    Handle { key: crate::session::KeyRef, component: usize, outgoing: bool },
}

/// The curve view's own state (the view, a gesture); not saved, not undone.
#[derive(Clone, Debug, Default)]
pub struct CurveViewState {
    /// `None`: the frame range and every shown value (*Fit*).
    pub view: Option<CurveView>,
    pub(crate) gesture: Option<CurveGesture>,
    /// F was pressed over the curves: frame the selected keys when next laid out.
    pub(crate) frame_keys: bool,
    /// Rotations drawn as their unwrapped twist about the bone axis instead of Euler angles.
    pub rotation_as_twist: bool,
}
