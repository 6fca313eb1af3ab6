//! The editor's panels, one file each. Every panel is a `ui(ui, app)` function that draws
//! itself into the window and changes the document only through [`crate::document::Document`].

pub mod curves;
pub mod dialogs;
pub mod dope_sheet;
pub mod ik_handle;
pub mod inspector;
pub mod menu;
pub mod outliner;
pub mod status;
pub mod timeline;
pub mod viewport;
