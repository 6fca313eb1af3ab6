//! `keyrig convert IN.md2|IN.glb|IN.gltf -o OUT.glb|OUT.gltf`: an MD2 model's frames as glTF
//! morph targets, one animation per clip (stand, run, …) at `--fps` frames per second, the
//! skin image found next to the model as the base-colour texture; a glTF model through
//! keyrig's scene mapping and export (every animation an action, as `keyrig export MODEL` does; with
//! `--bake`, Blender mode). See docs/interchange.md. The file is written atomically, never
//! over the model or its skin, and imported again as a check.

use std::path::PathBuf;

use anyhow::{bail, Context};
use keyrig_io::gltf_export::{export_md2, Md2ExportOptions};

#[derive(clap::Args, Debug)]
pub struct ConvertArgs {
    /// Input model (.md2, .glb, .gltf).
    pub input: PathBuf,
    /// Output file: .glb (binary) or .gltf (JSON with the buffer embedded).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Playback rate of the clips, frames per second (Quake 2 used 10).
    #[arg(long, default_value_t = 10.0, allow_negative_numbers = true)]
    pub fps: f64,
    /// glTF input: Blender mode (LINEAR keys only; see `keyrig export --bake`).
    #[arg(long)]
    pub bake: bool,
}

pub fn run(args: ConvertArgs) -> anyhow::Result<()> {
    crate::cli::export::check_output_extension(&args.output)?;
    if keyrig_io::vrml::export::ExportFormat::of_path(&args.output).is_some() {
        bail!(
            "{}: `keyrig convert` writes glTF; write VRML, X3D or Inventor with `keyrig export`",
            args.output.display()
        );
    }
    let ext = args.input.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some("md2") => {}
        Some("glb" | "gltf" | "wrl" | "wrz" | "x3d" | "x3dv" | "x3dz" | "x3dvz" | "iv") => {
            return crate::cli::export::run(crate::cli::export::ExportArgs {
                scene: args.input,
                output: args.output,
                rotation_tolerance: 0.05,
                bake: args.bake,
                position_tolerance: 1e-4,
            });
        }
        _ => bail!(
            "{}: only .md2, .glb, .gltf, .wrl, .wrz, .x3d, .x3dv and .iv models can be converted (export a scene with `keyrig export`)",
            args.input.display()
        ),
    }
    let range = keyrig_io::gltf_export::MD2_FPS_RANGE;
    if !(args.fps.is_finite() && range.contains(&args.fps)) {
        bail!("--fps {}: must be between {} and {} frames per second", args.fps, range.start(), range.end());
    }
    let model = keyrig_io::md2::load_md2_file(&args.input)?;
    let mut inputs = vec![(args.input.clone(), "the input model".to_owned())];
    if let Some(skin) = &model.skin {
        inputs.push((skin.path.clone(), "the model's skin image".to_owned()));
    }
    keyrig_io::file_io::refuse_overwriting(&args.output, &inputs)?;
    let exported = export_md2(&model, Md2ExportOptions { fps: args.fps })
        .with_context(|| format!("{}: cannot convert", args.input.display()))?;
    exported.write(&args.output)?;
    keyrig_io::gltf_import::import_gltf_file(&args.output)
        .with_context(|| format!("{}: the written file does not import again", args.output.display()))?;
    let skin = model
        .skin
        .as_ref()
        .map_or_else(|| "no skin image".to_owned(), |s| format!("skin {}", s.path.display()));
    eprintln!(
        "keyrig: wrote {} ({} frames, {} clips, {skin})",
        args.output.display(),
        model.frames.len(),
        model.clips.len()
    );
    Ok(())
}
