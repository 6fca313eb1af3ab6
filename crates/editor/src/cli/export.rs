//! `keyrig export FILE -o OUT.glb|OUT.gltf [--bake]`: a scene (.ron) — or a model (.glb,
//! .gltf, .md2) mapped onto a scene as the editor opens it — as glTF 2.0: every object's mesh,
//! skin, morph targets, material, animation and the lights (see docs/interchange.md).
//!
//! Position tracks are written exactly (CUBICSPLINE); rotation tracks key for key where glTF
//! can express them (LINEAR slerp, CUBICSPLINE Hermite), else resampled as LINEAR within
//! `--rotation-tolerance` degrees. `--bake` (Blender mode) writes LINEAR keys only, dense
//! enough for importers that ignore tangents and blend quaternions component-wise. The file is
//! written atomically (temporary file, sync, rename), never over the input or a model file the
//! scene uses, and imported again as a check before the command reports success.

use std::path::{Path, PathBuf};

use anyhow::{bail, Context};
use keyrig_io::gltf_export::{export_scene, BakeOptions, ExportOptions};

#[derive(clap::Args, Debug)]
pub struct ExportArgs {
    /// Scene file (.ron) or model (.glb, .gltf, .md2, .wrl, .wrz, .x3d, .x3dv, .iv).
    pub scene: PathBuf,
    /// Output file: .glb (binary) or .gltf (JSON with the buffer embedded); or .wrl (VRML97),
    /// .x3dv / .x3d (X3D classic / XML), .iv (Open Inventor) with the animation as
    /// interpolators and keyrig's own keys as metadata.
    #[arg(short, long)]
    pub output: PathBuf,
    /// Largest angle in degrees between an exported rotation and the scene's curve.
    #[arg(long, default_value_t = 0.05, allow_negative_numbers = true)]
    pub rotation_tolerance: f64,
    /// Blender mode: LINEAR keys only, placed so that importers which ignore CUBICSPLINE
    /// tangents and blend quaternions component-wise (Blender 3.4) show the same motion
    /// within the tolerances.
    #[arg(long)]
    pub bake: bool,
    /// With --bake: largest translation or scale difference, in scene units.
    #[arg(long, default_value_t = 1e-4, allow_negative_numbers = true, requires = "bake")]
    pub position_tolerance: f64,
}

pub fn run(args: ExportArgs) -> anyhow::Result<()> {
    if !(args.rotation_tolerance.is_finite() && args.rotation_tolerance > 0.0) {
        bail!("--rotation-tolerance must be a positive number of degrees, got {}", args.rotation_tolerance);
    }
    if !(args.position_tolerance.is_finite() && args.position_tolerance > 0.0) {
        bail!(
            "--position-tolerance must be a positive number of scene units, got {}",
            args.position_tolerance
        );
    }
    check_output_extension(&args.output)?;
    let (scene, base_dir) = load_scene_or_model(&args.scene)?;
    let mut inputs = vec![(args.scene.clone(), "the input file".to_owned())];
    inputs.extend(keyrig_io::project::scene_inputs(&scene, base_dir.as_deref()));
    keyrig_io::file_io::refuse_overwriting(&args.output, &inputs)?;
    if let Some(format) = keyrig_io::vrml::export::ExportFormat::of_path(&args.output) {
        return export_vrml(&args, &scene, base_dir, format);
    }
    if keyrig_io::bvh::is_bvh_path(&args.output) {
        return export_bvh(&args, &scene);
    }
    let options = ExportOptions {
        rotation_tolerance_deg: args.rotation_tolerance,
        base_dir,
        bake: args
            .bake
            .then(|| BakeOptions { position_tolerance: args.position_tolerance, ..BakeOptions::default() }),
    };
    let exported =
        export_scene(&scene, &options).with_context(|| format!("{}: cannot export", args.scene.display()))?;
    exported.write(&args.output)?;
    keyrig_io::gltf_import::import_gltf_file(&args.output)
        .with_context(|| format!("{}: the written file does not import again", args.output.display()))?;
    eprintln!(
        "keyrig: wrote {} ({} objects, {} lights{})",
        args.output.display(),
        scene.objects.len(),
        scene.lights.len(),
        if args.bake { ", baked" } else { "" }
    );
    Ok(())
}

/// `keyrig export … -o OUT.bvh`: the first object with a skeleton as a BVH take
/// (`keyrig_io::bvh::export_scene`), sampled at every frame of the range; read back as a check.
fn export_bvh(args: &ExportArgs, scene: &keyrig_core::Scene) -> anyhow::Result<()> {
    if args.bake {
        bail!("--bake is for glTF; a BVH take is written as one key per frame");
    }
    let object = scene
        .objects
        .iter()
        .position(|o| o.skeleton.is_some())
        .with_context(|| format!("{}: no object has a skeleton to write as BVH", args.scene.display()))?;
    keyrig_io::bvh::export_scene(scene, object, &args.output)?;
    keyrig_io::bvh::import_scene(&args.output)
        .with_context(|| format!("{}: the written file does not import again", args.output.display()))?;
    eprintln!("keyrig: wrote {} ({})", args.output.display(), scene.objects[object].name);
    Ok(())
}

/// `keyrig export … -o OUT.wrl|.x3dv|.x3d|.iv`: keyrig-io's VRML/X3D/Inventor writer, with
/// the rotation tolerance of the command line and a position tolerance of 10⁻⁴ of the scene's
/// size; written atomically and read back as a check.
fn export_vrml(
    args: &ExportArgs,
    scene: &keyrig_core::Scene,
    base_dir: Option<PathBuf>,
    format: keyrig_io::vrml::export::ExportFormat,
) -> anyhow::Result<()> {
    if args.bake {
        bail!("--bake is for glTF; VRML, X3D and Inventor files are always written as linear keys");
    }
    let options = keyrig_io::vrml::export::VrmlExportOptions {
        base_dir,
        rotation_tolerance_deg: args.rotation_tolerance,
        ..keyrig_io::vrml::export::VrmlExportOptions::default()
    };
    let text = keyrig_io::vrml::export::export_scene(scene, format, &options)
        .with_context(|| format!("{}: cannot export", args.scene.display()))?;
    keyrig_io::file_io::write_atomic(&args.output, text.as_bytes())
        .with_context(|| format!("writing {}", args.output.display()))?;
    keyrig_io::vrml::import_vrml_file(&args.output)
        .with_context(|| format!("{}: the written file does not import again", args.output.display()))?;
    eprintln!(
        "keyrig: wrote {} ({} objects, {} lights)",
        args.output.display(),
        scene.objects.len(),
        scene.lights.len()
    );
    Ok(())
}

/// A scene file with the folder its model paths resolve against, or a model (.glb, .gltf,
/// .md2, .wrl, .wrz, .x3d, .x3dv, .iv) mapped onto a scene as the editor opens it (every animation an action; an MD2 plays every
/// frame), with absolute model paths.
pub fn load_scene_or_model(path: &Path) -> anyhow::Result<(keyrig_core::Scene, Option<PathBuf>)> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    match ext.as_deref() {
        Some(
            "glb" | "gltf" | "fbx" | "bvh" | "md2" | "wrl" | "wrz" | "x3d" | "x3dv" | "x3dz" | "x3dvz" | "iv",
        ) => {
            let scene = keyrig_editor::files::import_model(path).map_err(anyhow::Error::msg)?;
            Ok((scene, None))
        }
        _ => {
            let scene = keyrig_io::scene_file::load(path).with_context(|| format!("{}", path.display()))?;
            Ok((scene, Some(keyrig_io::file_io::parent_or_dot(path))))
        }
    }
}

/// `.glb`, `.gltf`, `.wrl`, `.x3dv`, `.x3d`, `.iv` or `.bvh`, case-insensitive.
pub fn check_output_extension(path: &std::path::Path) -> anyhow::Result<()> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if !matches!(ext.as_deref(), Some("glb" | "gltf" | "bvh"))
        && keyrig_io::vrml::export::ExportFormat::of_path(path).is_none()
    {
        bail!("{}: the output must end in .glb, .gltf, .wrl, .x3dv, .x3d, .iv or .bvh", path.display());
    }
    Ok(())
}
