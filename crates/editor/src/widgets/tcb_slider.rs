//! A tension / continuity / bias slider: a labelled slider over [-1, 1] that snaps to 0
//! when double-clicked. Its number box applies a typed value when editing ends (Enter or
//! focus lost), not on every keystroke, like every number field.

use egui::{PointerButton, Rect, Response, Slider, Ui, Vec2};

/// A slider for one TCB parameter. Double-click on the rail resets it to 0 (the Catmull–Rom
/// default). egui's slider senses drags only, so the double click is read from the pointer.
pub fn tcb_slider_ui(ui: &mut Ui, value: &mut f32, label: &str, tooltip: &str) -> Response {
    let slider = Slider::new(value, -1.0..=1.0).text(label).step_by(0.01).update_while_editing(false);
    let mut response = ui.add(slider).on_hover_text(tooltip);
    // The rail is the slider's first `slider_width` points; the number box and label follow.
    let rail =
        Rect::from_min_size(response.rect.min, Vec2::new(ui.spacing().slider_width, response.rect.height()));
    let double_clicked = ui.input(|i| {
        i.pointer.button_double_clicked(PointerButton::Primary)
            && i.pointer.interact_pos().is_some_and(|p| rail.contains(p))
    });
    if double_clicked && ui.is_enabled() {
        *value = 0.0;
        response.mark_changed();
    }
    response
}
