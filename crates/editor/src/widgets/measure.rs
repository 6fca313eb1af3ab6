//! The cross-section readout of the selected joint (docs/skinning.md):
//! "Cross-section at elbow: 0.98 × rest", from the frame's CPU-skinned mesh. The viewport's
//! overlay and the inspector's deformer section show it.

use egui::Ui;

use crate::context::FrameCtx;
use crate::session::Selected;

/// "Cross-section at elbow: 0.98 × rest" for the selected joint, from this frame's skinned mesh
/// of its object; `None` without a selected joint of a skinned mesh.
#[must_use]
pub fn measure_text(ctx: &FrameCtx<'_>) -> Option<String> {
    let Some(Selected::Joint { object, joint }) = ctx.session.selection.item else { return None };
    let name = ctx.scene().objects.get(object)?.skeleton.as_ref()?.joints.get(joint)?.name.clone();
    if !ctx.scene.is_skinned_now(object) {
        return None;
    }
    Some(match ctx.scene.skin_cache().cross_section(object, joint)? {
        Ok(section) => format!("Cross-section at {name}: {:.2} × rest", section.ratio()),
        Err(e) => format!("Cross-section at {name}: {e}"),
    })
}

/// The measure beside the deformer settings in the inspector.
pub fn measure_ui(ui: &mut Ui, ctx: &FrameCtx<'_>) {
    match measure_text(ctx) {
        Some(text) => {
            ui.label(text).on_hover_text(
                "Mean distance of the limb's surface from the joint, posed / rest (docs/design.md §6). \
                 Near 0 is the candy-wrapper collapse of linear blending under twist.",
            );
        }
        None => {
            ui.weak("Select a joint of a skinned mesh to see its cross-section relative to rest.");
        }
    }
}
