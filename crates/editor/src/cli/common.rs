//! What several subcommands share: loading a scene leniently, checking frames against its
//! range, writing to standard output.

use std::io::Write;
use std::path::Path;

use anyhow::{bail, Context};
use keyrig_core::Scene;
use keyrig_io::scene_file::{self, LocatedProblem};

/// Frames and times a headless command is asked for must lie in the scene's frame range
/// (`start..=end` frames, at the scene's rate); outside it is an error that states the range,
/// never a silent clamp. A model opened on its own gets the range of its mapping (its first
/// animation, or one loop of an MD2 model).
///
/// # Errors
/// `frame` is not finite or outside the range.
pub fn check_frame(scene: &Scene, frame: f64, what: &str) -> anyhow::Result<()> {
    if !frame.is_finite() {
        bail!("{what}: not a finite number");
    }
    let (start, end) = (f64::from(scene.frame_range.start), f64::from(scene.frame_range.end));
    // Times convert to frames with a rounding error; do not refuse the range's own ends.
    let slack = 1e-9 * (1.0 + start.abs().max(end.abs()));
    if frame < start - slack || frame > end + slack {
        bail!(
            "{what} is outside the scene's frame range {}..={} (at {} fps: {:.4}..={:.4} s)",
            scene.frame_range.start,
            scene.frame_range.end,
            scene.fps,
            start / scene.fps,
            end / scene.fps
        );
    }
    Ok(())
}

/// The time in seconds of `--frame` or `--time` (exactly one given), checked against the
/// scene's frame range ([`check_frame`]).
///
/// # Errors
/// Neither or both given, not finite, or outside the range.
pub fn time_in_range(scene: &Scene, frame: Option<f64>, time: Option<f64>) -> anyhow::Result<f64> {
    match (frame, time) {
        (Some(frame), None) => {
            check_frame(scene, frame, &format!("--frame {frame}"))?;
            Ok(frame / scene.fps)
        }
        (None, Some(time)) => {
            if !time.is_finite() {
                bail!("--time {time}: not a finite number");
            }
            check_frame(scene, time * scene.fps, &format!("--time {time}"))?;
            Ok(time)
        }
        _ => bail!("give exactly one of --frame and --time"),
    }
}

/// Loads the scene at `path` for a headless command. `.ron` scenes are read leniently (problems
/// are returned beside the scene, located in the file); `.glb`/`.gltf` models are imported and
/// mapped to a scene with keyrig-io's mapping (every animation an action), whose problems have no file
/// position; VRML97, X3D and Open Inventor files likewise through `keyrig_io::vrml`. MD2 models
/// hold vertex animation, not channels, and are refused.
pub fn load_scene_lenient(path: &Path, command: &str) -> anyhow::Result<(Scene, Vec<LocatedProblem>)> {
    let ext = path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase);
    if keyrig_io::vrml::is_vrml_path(path) {
        let model = keyrig_io::vrml::import_vrml_file(path)?;
        let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
        let scene = model.to_scene(&name);
        let problems =
            scene.problems().into_iter().map(|problem| LocatedProblem { problem, position: None }).collect();
        return Ok((scene, problems));
    }
    if keyrig_io::bvh::is_bvh_path(path) {
        let scene = keyrig_io::bvh::import_scene(path)?;
        let problems =
            scene.problems().into_iter().map(|problem| LocatedProblem { problem, position: None }).collect();
        return Ok((scene, problems));
    }
    match ext.as_deref() {
        Some("ron") => Ok(scene_file::load_lenient(path)?),
        Some("glb" | "gltf" | "fbx") => load_gltf(path).map(|(_, scene, problems)| (scene, problems)),
        Some("md2") => bail!(
            "{}: MD2 models hold vertex animation (frames and clips), not channels; \
             `keyrig {command}` reads .ron scenes, .glb/.gltf/.fbx models and .bvh takes",
            path.display()
        ),
        _ => bail!(
            "{}: unknown file type; `keyrig {command}` reads .ron scenes, .glb/.gltf/.fbx models, .bvh takes and .wrl/.wrz/.x3d/.x3dv/.iv files",
            path.display()
        ),
    }
}

/// Imports the glTF model at `path` and maps it to a scene (every animation an action), as
/// [`load_scene_lenient`] does; the model comes back too (`keyrig info` lists what it skipped).
pub fn load_gltf(
    path: &Path,
) -> anyhow::Result<(keyrig_io::model::ImportedModel, Scene, Vec<LocatedProblem>)> {
    let model = keyrig_io::fbx::import_model_file(path)?;
    let name = path.file_name().map(|n| n.to_string_lossy().into_owned()).unwrap_or_default();
    let scene = model
        .to_scene_all(&name)
        .with_context(|| format!("{}: mapping the model to a scene", path.display()))?;
    let problems =
        scene.problems().into_iter().map(|problem| LocatedProblem { problem, position: None }).collect();
    Ok((model, scene, problems))
}

/// Writes to stdout; a closed pipe (`keyrig sample … | head`) is not an error.
pub fn write_stdout(bytes: &[u8]) -> anyhow::Result<()> {
    let mut out = std::io::stdout().lock();
    match out.write_all(bytes).and_then(|()| out.flush()) {
        Ok(()) => Ok(()),
        Err(e) if e.kind() == std::io::ErrorKind::BrokenPipe => Ok(()),
        Err(e) => Err(e).context("writing to standard output"),
    }
}

/// `scene` playing `action` (`--action NAME` of `sample` and `deform`): the action is made
/// active on every object it has keys for (docs/actions.md), and the frame range widened to
/// its keys; `None` leaves the scene as it is.
///
/// # Errors
/// An action the scene does not have, naming those it has.
pub fn with_action(scene: Scene, action: Option<&str>, file: &Path) -> anyhow::Result<Scene> {
    let Some(name) = action else { return Ok(scene) };
    let mut out = scene.playing_action(name, false).map_err(|_| {
        let names: Vec<String> = scene.actions.iter().map(|a| format!("{:?}", a.name)).collect();
        anyhow::anyhow!(
            "{}: --action {name:?}: the scene has no such action; its actions: {}",
            file.display(),
            if names.is_empty() { "none".to_owned() } else { names.join(", ") }
        )
    })?;
    let summary = out.action_summaries().into_iter().find(|a| a.name == name);
    if let Some((t0, t1)) = summary.and_then(|a| a.time_range) {
        let (a, b) = ((t0 * out.fps).floor(), (t1 * out.fps).ceil());
        if a.is_finite() && b.is_finite() {
            out.frame_range.start = out.frame_range.start.min(a.clamp(-1e6, 1e6) as i32);
            out.frame_range.end = out.frame_range.end.max(b.clamp(-1e6, 1e6) as i32);
        }
    }
    Ok(out)
}
