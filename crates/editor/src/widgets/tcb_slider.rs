//! A tension / continuity / bias slider: a labelled slider over [-1, 1] that snaps to 0
//! when double-clicked.

use egui::{Response, Slider, Ui};

/// A slider for one TCB parameter. Double-click resets it to 0 (the Catmull–Rom default).
pub fn tcb_slider_ui(ui: &mut Ui, value: &mut f32, label: &str, tooltip: &str) -> Response {
    let response = ui.add(Slider::new(value, -1.0..=1.0).text(label).step_by(0.01)).on_hover_text(tooltip);
    if response.double_clicked() {
        *value = 0.0;
    }
    response
}
