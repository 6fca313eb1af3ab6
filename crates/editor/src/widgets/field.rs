//! Number fields that commit once: a [`DragValue`] whose typed text applies when editing ends
//! (Enter or focus lost; Escape cancels) rather than on every keystroke, and which tells a drag
//! (one undo step per drag, closed on release) from a committed value (one undo step).

use egui::{DragValue, Response, Ui};

/// How a number field changed this frame.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FieldChange {
    /// Nothing to apply.
    None,
    /// The value moves under a drag: apply it with [`crate::document::Document::edit_continuous`];
    /// the group closes when the drag is released.
    Dragged,
    /// A typed value was committed (Enter or focus lost), or set by an arrow key or a screen
    /// reader: validate it and apply it as one undo step.
    Committed,
}

impl FieldChange {
    #[must_use]
    pub fn any(self) -> bool {
        self != FieldChange::None
    }
}

/// Adds a number field for `value` with the accessible label `label`; `configure` sets its
/// speed, range and decimals. Typed text applies only when editing ends; −0 shows as 0.
pub fn number_field<'a, N: egui::emath::Numeric>(
    ui: &mut Ui,
    value: &'a mut N,
    label: &str,
    configure: impl FnOnce(DragValue<'a>) -> DragValue<'a>,
) -> (Response, FieldChange) {
    // A negative zero (a rotation's component that rounded to 0) shows as 0, not "-0.0".
    let field = DragValue::new(value).custom_formatter(|n, decimals| {
        egui::emath::format_with_decimals_in_range(if n == 0.0 { 0.0 } else { n }, decimals)
    });
    let response = ui.add(configure(field).update_while_editing(false));
    let name = label.to_owned();
    ui.ctx().accesskit_node_builder(response.id, |node| node.set_label(name));
    let change = if !response.changed() {
        FieldChange::None
    } else if response.dragged() {
        FieldChange::Dragged
    } else {
        FieldChange::Committed
    };
    (response, change)
}
