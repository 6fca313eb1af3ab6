//! Headless subcommands of the `keyrig` binary. Each module has an `…Args` (clap) and a
//! `run(args) -> anyhow::Result<()>`; what several share is in [`common`].

pub mod clean;
pub mod common;
pub mod convert;
pub mod deform;
pub mod edit;
pub mod export;
pub mod import;
pub mod info;
pub mod render;
pub mod retarget;
pub mod sample;
