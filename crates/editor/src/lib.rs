//! keyrig-editor: the eframe/egui application.

use std::path::PathBuf;

/// Opens the editor window on `file`, or on the demo scene when `None`.
pub fn run_editor(file: Option<PathBuf>) -> anyhow::Result<()> {
    let _ = file;
    anyhow::bail!("the editor window is not built yet")
}
