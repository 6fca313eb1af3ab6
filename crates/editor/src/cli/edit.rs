//! `keyrig edit [FILE]` (and `keyrig` with no arguments): open the editor.

use std::path::PathBuf;

#[derive(clap::Args, Debug, Default)]
pub struct EditArgs {
    /// Scene (.ron) or model (.glb, .gltf, .md2) to open; the demo scene when omitted.
    pub file: Option<PathBuf>,
}

pub fn run(args: EditArgs) -> anyhow::Result<()> {
    keyrig_editor::run_editor(args.file)
}
