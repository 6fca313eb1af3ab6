//! `keyrig clean FILE -o OUT.ron [--smooth-hz HZ] [--reduce] [--reduce-angle DEG]
//! [--reduce-distance U] [--reduce-value V] [--object NAME]`: curve clean-up of dense keys
//! (docs/cleanup.md) — a Butterworth low-pass smoothing and/or key reduction to an error
//! bound — of every keyed channel of the scene (or of one object), written as a scene file.
//! FILE is a scene or anything the other commands read as one (a glTF, FBX or BVH model, a
//! VRML/X3D/Inventor file). Smoothing runs first, then reduction. The scene is written
//! atomically and never over the input or a model the scene uses.

use std::path::PathBuf;

use anyhow::{bail, Context};
use keyrig_edit::cleanup::{keyed_channels, reduce_keys, smooth_keys, CleanupReport, ReduceTolerance};

#[derive(clap::Args, Debug)]
pub struct CleanArgs {
    /// Scene file (.ron) or model (.glb, .gltf, .fbx, .bvh, .wrl, .wrz, .x3d, .x3dv, .iv).
    pub scene: PathBuf,
    /// Output scene file (.ron).
    #[arg(short, long)]
    pub output: PathBuf,
    /// Smooth with a 2nd-order Butterworth low-pass of this cutoff (Hz), forwards and
    /// backwards (no lag); below half the frame rate.
    #[arg(long, allow_negative_numbers = true)]
    pub smooth_hz: Option<f64>,
    /// Reduce keys within the tolerances below (their defaults unless given); implied by any
    /// --reduce-* flag.
    #[arg(long)]
    pub reduce: bool,
    /// Largest angle (degrees) a reduced rotation may differ from the original at any key or
    /// frame.
    #[arg(long, allow_negative_numbers = true)]
    pub reduce_angle: Option<f64>,
    /// Largest distance a reduced position may differ, in scene units (0.001 = 1 mm in a
    /// scene in metres).
    #[arg(long, allow_negative_numbers = true)]
    pub reduce_distance: Option<f64>,
    /// Largest difference of any other value (scale, colour, scalars).
    #[arg(long, allow_negative_numbers = true)]
    pub reduce_value: Option<f64>,
    /// Only this object's channels (default: every keyed channel of the scene).
    #[arg(long)]
    pub object: Option<String>,
}

pub fn run(args: CleanArgs) -> anyhow::Result<()> {
    let reduce = args.reduce
        || args.reduce_angle.is_some()
        || args.reduce_distance.is_some()
        || args.reduce_value.is_some();
    if !reduce && args.smooth_hz.is_none() {
        bail!("nothing to do: give --smooth-hz HZ, --reduce or a --reduce-* tolerance");
    }
    let tolerance = ReduceTolerance {
        angle_deg: args.reduce_angle.unwrap_or(ReduceTolerance::DEFAULT.angle_deg),
        distance: args.reduce_distance.unwrap_or(ReduceTolerance::DEFAULT.distance),
        value: args.reduce_value.unwrap_or(ReduceTolerance::DEFAULT.value),
    };
    tolerance.check().map_err(|e| anyhow::anyhow!("--reduce-*: {e}"))?;
    if !keyrig_editor::files::is_scene_file(&args.output) {
        bail!(
            "{}: the output must end in .ron (`keyrig export` writes other formats)",
            args.output.display()
        );
    }
    let mut scene = if keyrig_editor::files::is_scene_file(&args.scene) {
        keyrig_io::project::load_scene(&args.scene).with_context(|| format!("{}", args.scene.display()))?
    } else {
        keyrig_editor::files::import_model(&args.scene).map_err(anyhow::Error::msg)?
    };
    let mut inputs = vec![(args.scene.clone(), "the input file".to_owned())];
    inputs.extend(keyrig_io::project::scene_inputs(&scene, None));
    keyrig_io::file_io::refuse_overwriting(&args.output, &inputs)?;
    let objects = match &args.object {
        Some(name) => {
            let Some(o) = scene.objects.iter().position(|o| &o.name == name) else {
                bail!("{}: no object is named {name:?}", args.scene.display());
            };
            Some(vec![o])
        }
        None => None,
    };
    let channels = keyed_channels(&scene, objects.as_deref());
    let mut said = Vec::new();
    if let Some(hz) = args.smooth_hz {
        let report =
            smooth_keys(&mut scene, &channels, hz).map_err(|e| anyhow::anyhow!("--smooth-hz: {e}"))?;
        said.push(format!("smoothed {} channels below {hz} Hz", report.channels));
        warn_skipped(&scene, &report);
    }
    if reduce {
        let report =
            reduce_keys(&mut scene, &channels, tolerance).map_err(|e| anyhow::anyhow!("--reduce-*: {e}"))?;
        said.push(format!(
            "reduced {} channels from {} to {} keys, at most {:.3}°, {:.3e} (distance), {:.3e} (value) from the original",
            report.channels,
            report.keys_before,
            report.keys_after,
            report.max_angle_deg,
            report.max_distance,
            report.max_value
        ));
        warn_skipped(&scene, &report);
    }
    keyrig_io::project::save_scene(&args.output, &scene)?;
    eprintln!("keyrig: wrote {} ({})", args.output.display(), said.join("; "));
    Ok(())
}

fn warn_skipped(scene: &keyrig_core::Scene, report: &CleanupReport) {
    for (id, why) in &report.skipped {
        eprintln!("keyrig: {} left as it was: {}", id.label(scene), why.reason());
    }
}
