//! The `keyrig` binary: with no arguments it opens the editor on the demo scene; subcommands
//! serve scripts and batch work (DESIGN.md §7).

use std::process::ExitCode;

use clap::{Parser, Subcommand};

mod cli;

/// keyrig: a keyframe animation editor with TCB splines and four skin deformers.
#[derive(Parser, Debug)]
#[command(name = "keyrig", version, about, long_about = None)]
struct Cli {
    #[command(subcommand)]
    command: Option<Command>,
}

#[derive(Subcommand, Debug)]
enum Command {
    /// Open the editor on a scene (.ron) or a model (.glb, .gltf, .md2).
    Edit(cli::edit::EditArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        None => cli::edit::run(cli::edit::EditArgs::default()),
        Some(Command::Edit(args)) => cli::edit::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("keyrig: error: {err:#}");
            ExitCode::FAILURE
        }
    }
}
