//! The view: how the editor looks at the document — the orbit camera and the viewport's
//! options. Changing it never touches the document or its undo history.

use keyrig_core::Camera;

/// How the viewport draws meshes: keyrig-render's one type (solid, wireframe, points).
pub use keyrig_render::RenderStyle;

/// How the editor looks at the document: the camera and the viewport's options. Not saved
/// with the scene and not undone: the camera starts from the scene's `camera` and is
/// remembered per scene file with the session ([`crate::reopen`]). The panels' own state
/// (views, gestures, rects) lives in the panels ([`crate::panels`]).
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
    /// Draw materials (glTF base colour and texture, MD2 skins); off shows the plain
    /// per-object colours.
    pub textures: bool,
    /// The shortcut list (F12) is open.
    pub show_help: bool,
    /// The undo history window (Ctrl+Alt+Z) is open.
    pub show_undo_history: bool,
    /// The Render animation dialog is open.
    pub show_render: bool,
    /// Ghosts of the selected object at other frames (View ▸ Onion skin).
    pub onion: crate::onion::OnionSkin,
    /// The viewport looks through a scene camera instead of the orbit camera (View ▸ Look
    /// through camera, 0): the active one, which markers switch, or one chosen camera.
    pub look_through: Option<LookThrough>,
}

/// Which scene camera the viewport looks through.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum LookThrough {
    /// The scene's active camera at each frame: a marker bound to a camera cuts to it, as the
    /// render does ([`keyrig_core::Scene::active_camera_at`]).
    Active,
    /// This camera (an index of `Scene::cameras`) whatever the markers say.
    Camera(usize),
}

impl LookThrough {
    /// The camera looked through at `frame`.
    #[must_use]
    pub fn camera_at(self, scene: &keyrig_core::Scene, frame: f64) -> Option<usize> {
        match self {
            LookThrough::Active => scene.active_camera_at(frame),
            LookThrough::Camera(c) => (c < scene.cameras.len()).then_some(c),
        }
    }
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
            textures: true,
            show_help: false,
            show_undo_history: false,
            show_render: false,
            onion: crate::onion::OnionSkin::default(),
            look_through: None,
        }
    }
}
