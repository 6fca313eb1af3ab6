//! Small custom widgets: each is `thing_ui(ui, ...) -> Response` plus, where it fits, an
//! `impl Widget` wrapper (the egui demo's recipe: allocate, handle input, paint, report
//! accessibility info).

pub mod field;
pub mod key_diamond;
pub mod tcb_slider;
