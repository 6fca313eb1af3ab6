//! The `keyrig` binary: with no arguments it opens the editor on the demo scene; subcommands
//! serve scripts and batch work (docs/design.md §7).

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
    /// Export a scene (.ron) or a model (.glb, .gltf, .md2) as glTF 2.0 (.glb or .gltf): meshes, skins, morph targets, materials, animation and lights; --bake for Blender.
    Export(cli::export::ExportArgs),
    /// Convert a model to glTF 2.0: MD2 clips as morph-target animation, glTF through keyrig's mapping.
    Convert(cli::convert::ConvertArgs),
    /// Make a scene file (.ron) from a model (.glb, .gltf, .md2), as the editor opens it.
    Import(cli::import::ImportArgs),
    /// Render a frame of a scene or model to PNG, or a frame range as a playblast (MP4, GIF,
    /// animated PNG or numbered PNGs), offscreen, optionally motion-blurred.
    Render(cli::render::RenderArgs),
    /// Summarize a scene: timing, objects, joints, lights, tracks, keys and validation problems.
    Info(cli::info::InfoArgs),
    /// Print one channel's values over a frame or time range as CSV or JSON.
    Sample(cli::sample::SampleArgs),
    /// Deformed vertex positions and normals of an object at a frame or time (OBJ or JSON).
    Deform(cli::deform::DeformArgs),
    /// Clean up dense keys: Butterworth smoothing (--smooth-hz) and key reduction within an
    /// angle and a distance (--reduce, --reduce-angle, --reduce-distance), to a scene file.
    Clean(cli::clean::CleanArgs),
    /// Put the action one skeleton plays onto another (bone map from joint names or a file,
    /// rest poses aligned, root motion scaled by leg length, planted feet held), to a scene file.
    Retarget(cli::retarget::RetargetArgs),
}

fn main() -> ExitCode {
    let cli = Cli::parse();
    let result = match cli.command {
        None => cli::edit::run(cli::edit::EditArgs::default()),
        Some(Command::Edit(args)) => cli::edit::run(args),
        Some(Command::Export(args)) => cli::export::run(args),
        Some(Command::Convert(args)) => cli::convert::run(args),
        Some(Command::Import(args)) => cli::import::run(args),
        Some(Command::Render(args)) => cli::render::run(args),
        Some(Command::Info(args)) => cli::info::run(args),
        Some(Command::Sample(args)) => cli::sample::run(args),
        Some(Command::Deform(args)) => cli::deform::run(args),
        Some(Command::Clean(args)) => cli::clean::run(args),
        Some(Command::Retarget(args)) => cli::retarget::run(args),
    };
    match result {
        Ok(()) => ExitCode::SUCCESS,
        Err(err) => {
            // A hostile file's token can be megabytes long: never echo it whole.
            eprintln!("keyrig: error: {}", keyrig_io::message::clip_long_tokens(&error_text(&err)));
            ExitCode::FAILURE
        }
    }
}

/// The error and its causes joined by ": ", as anyhow's `{:#}` does, but without a cause whose
/// text the message before it already contains: keyrig's library errors put their source in
/// their own message (`path: cannot read: …`), so `{:#}` would print it twice.
fn error_text(err: &anyhow::Error) -> String {
    let mut text = err.to_string();
    for cause in err.chain().skip(1) {
        let cause = cause.to_string();
        if !text.contains(&cause) {
            text.push_str(": ");
            text.push_str(&cause);
        }
    }
    text
}

#[cfg(test)]
mod tests {
    use super::error_text;

    #[derive(Debug, thiserror::Error)]
    #[error("scene.ron: cannot read: {source}")]
    struct ReadError {
        source: std::io::Error,
    }

    #[test]
    fn causes_already_in_the_message_are_not_repeated() {
        let io = std::io::Error::new(std::io::ErrorKind::NotFound, "no such file");
        let err = anyhow::Error::new(ReadError { source: io });
        assert_eq!(error_text(&err), "scene.ron: cannot read: no such file");
    }

    #[test]
    fn context_keeps_the_cause_it_does_not_mention() {
        let err = anyhow::anyhow!("weights are NaN").context("arm.ron: object `Arm`");
        assert_eq!(error_text(&err), "arm.ron: object `Arm`: weights are NaN");
    }
}
