//! Headless subcommands of the `keyrig` binary. Each module has an `…Args` (clap) and a
//! `run(args) -> anyhow::Result<()>`.

pub mod convert;
pub mod deform;
pub mod edit;
pub mod export;
pub mod import;
pub mod info;
pub mod render;
pub mod sample;

use anyhow::bail;
use keyrig_core::Scene;

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
