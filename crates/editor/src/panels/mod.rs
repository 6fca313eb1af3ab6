//! The editor's panels, one module each. A panel is a type that holds its own gesture and view
//! state (the viewport its gizmo, drags, IK grab and GPU view; the dope sheet and the curve
//! editor their views and gestures; the outliner its name field; the timeline its FPS drag) and
//! draws with `ui(&mut self, ui, &FrameCtx, &mut Actions)`: it reads the document, the session
//! and the evaluated scene from the frame's read-only [`crate::context::FrameCtx`] and pushes
//! what it wants changed into [`crate::actions::Actions`]. Panels never call each other (a test,
//! `tests/tests/module_graph.rs`, fails if one names another); what two of them share lives
//! outside them (the time axis and the cross-section readout in [`crate::widgets`], the key
//! edits in [`crate::edits`], a skeleton's walk on [`keyrig_core::Skeleton`]). The menu bar,
//! the status bar and the dialogs keep no state and are functions of the same shape.

pub mod cleanup_dialog;
pub mod clips;
pub mod curves;
pub mod dialogs;
pub mod dope_sheet;
pub mod inspector;
pub mod menu;
pub mod outliner;
pub mod render_dialog;
pub mod retarget_dialog;
pub mod status;
pub mod timeline;
pub mod viewport;

/// The panels with state, as the window lays them out.
#[derive(Default)]
pub struct Panels {
    pub timeline: timeline::Timeline,
    pub dope_sheet: dope_sheet::DopeSheet,
    pub clips: clips::ClipEditor,
    pub curves: curves::CurveEditor,
    pub outliner: outliner::Outliner,
    pub inspector: inspector::Inspector,
    pub viewport: viewport::Viewport,
    pub render: render_dialog::RenderDialog,
    pub cleanup: cleanup_dialog::CleanupDialog,
    pub retarget: retarget_dialog::RetargetDialog,
}
