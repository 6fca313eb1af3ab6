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
    /// Export a scene (.ron) as glTF 2.0 (.glb or .gltf) with skins, animation and lights.
    Export(cli::export::ExportArgs),
    /// Convert an MD2 model to glTF 2.0 morph-target animation (.glb or .gltf).
    Convert(cli::convert::ConvertArgs),
    /// Render a frame or a frame range of a scene (.ron) or MD2 model to PNG, offscreen.
    Render(cli::render::RenderArgs),
    /// Summarize a scene: timing, objects, joints, lights, tracks, keys and validation problems.
    Info(cli::info::InfoArgs),
    /// Print one channel's values over a frame or time range as CSV or JSON.
    Sample(cli::sample::SampleArgs),
    /// Deformed vertex positions and normals of an object at a frame or time (OBJ or JSON).
    Deform(cli::deform::DeformArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        None => cli::edit::run(cli::edit::EditArgs::default()),
        Some(Command::Edit(args)) => cli::edit::run(args),
        Some(Command::Export(args)) => cli::export::run(args),
        Some(Command::Convert(args)) => cli::convert::run(args),
        Some(Command::Render(args)) => cli::render::run(args),
        Some(Command::Info(args)) => cli::info::run(args),
        Some(Command::Sample(args)) => cli::sample::run(args),
        Some(Command::Deform(args)) => cli::deform::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            eprintln!("keyrig: error: {err:#}");
            ExitCode::FAILURE
        }
    }
}
