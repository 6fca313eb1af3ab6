//! Small custom widgets: each is `thing_ui(ui, ...) -> Response` plus, where it fits, an
//! `impl Widget` wrapper (the egui demo's recipe: allocate, handle input, paint, report
//! accessibility info).

pub mod command_button;
pub mod field;
pub mod flat_fill;
pub mod key_diamond;
pub mod key_type_menu;
pub mod measure;
pub mod preview_range;
pub mod range_watch;
pub mod tcb_slider;
pub mod time_axis;
pub mod waveform;

/// Tells accessibility tools (and UI tests) about something painted rather than laid out as a
/// widget — a key diamond, a curve point, a dope-sheet row — at `rect` (screen points), with the
/// role, the label `label()` gives and, where given, whether it is selected. Nothing is built,
/// not even the label, while no accessibility client listens (the window's usual case), so a
/// panel can publish every mark it draws.
pub fn publish_painted(
    ctx: &egui::Context,
    id: egui::Id,
    role: egui::accesskit::Role,
    rect: egui::Rect,
    label: impl FnOnce() -> String,
    selected: Option<bool>,
) {
    ctx.accesskit_node_builder(id, |node| {
        node.set_role(role);
        node.set_label(label());
        if let Some(selected) = selected {
            node.set_selected(selected);
        }
        node.set_bounds(egui::accesskit::Rect {
            x0: rect.min.x.into(),
            y0: rect.min.y.into(),
            x1: rect.max.x.into(),
            y1: rect.max.y.into(),
        });
    });
}
