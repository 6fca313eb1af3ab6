//! `keyrig export SCENE.ron -o OUT.glb|OUT.gltf`: the scene's meshes, skeletons, skins,
//! object/joint/light animation and lights as glTF 2.0 (see docs/interchange.md).
//!
//! Position tracks are written exactly (CUBICSPLINE); rotation tracks are resampled as
//! LINEAR within `--rotation-tolerance` degrees. The file is written atomically (temporary
//! file, sync, rename), never over the scene or a model file the scene uses, and imported
//! again as a check before the command reports success.

use std::path::PathBuf;

use anyhow::{bail, Context};
use keyrig_io::gltf_export::{export_scene, ExportOptions};

#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    /// Scene file (.ron).
    pub scene: PathBuf,
    /// Output file: .glb (binary) or .gltf (JSON with the buffer embedded).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Largest angle in degrees between an exported rotation and the scene's curve.
    #[arg(long, default_value_t = 0.05, allow_negative_numbers = true)]
    pub rotation_tolerance: f64,
}

pub fn run(args: ExportArgs) -> anyhow::Result<()> {
    if !(args.rotation_tolerance.is_finite() && args.rotation_tolerance > 0.0) {
        bail!("--rotation-tolerance must be a positive number of degrees, got {}", args.rotation_tolerance);
    }
    check_output_extension(&args.output)?;
    let scene =
        keyrig_io::scene_file::load(&args.scene).with_context(|| format!("{}", args.scene.display()))?;
    let base_dir = keyrig_io::file_io::parent_or_dot(&args.scene);
    let mut inputs = vec![(args.scene.clone(), "the input scene".to_owned())];
    inputs.extend(keyrig_io::file_io::scene_inputs(&scene, Some(&base_dir)));
    keyrig_io::file_io::refuse_overwriting(&args.output, &inputs)?;
    let options = ExportOptions { rotation_tolerance_deg: args.rotation_tolerance, base_dir: Some(base_dir) };
    let exported =
        export_scene(&scene, &options).with_context(|| format!("{}: cannot export", args.scene.display()))?;
    exported.write(&args.output)?;
    keyrig_io::gltf_import::import_gltf_file(&args.output)
        .with_context(|| format!("{}: the written file does not import again", args.output.display()))?;
    eprintln!(
        "keyrig: wrote {} ({} objects, {} lights)",
        args.output.display(),
        scene.objects.len(),
        scene.lights.len()
    );
    Ok(())
}

/// `.glb` or `.gltf`, case-insensitive.
pub fn check_output_extension(path: &std::path::Path) -> anyhow::Result<()> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("glb" | "gltf")) {
        bail!("{}: the output must end in .glb or .gltf", path.display());
    }
    Ok(())
}
