//! `keyrig sample FILE --channel PATH (--frames A..B | --times A..B | --frame F | --time T)
//! [--step S] [--format csv|json] [--rotation-format quat|euler]`: the values of one channel
//! over time, one row per sample (channel paths: docs/channels.md). A rotation channel with
//! spin keys gets one more column, `spin_deg`: the unwrapped angle turned since the start of
//! the spin segment (empty outside spin segments); channels without spins print as before.

use std::path::PathBuf;

use anyhow::{bail, Context};
use keyrig_core::channel::{list_channels, Channel, ChannelPath, RotationFormat};
use keyrig_core::Scene;

/// Most rows one call may print; larger requests are refused rather than filling a disk.
pub const MAX_SAMPLES: usize = 10_000_000;

#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum SampleFormat {
    /// Comma-separated values with a header line.
    #[default]
    Csv,
    /// One JSON object with a `samples` array.
    Json,
}

#[derive(clap::ValueEnum, Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum RotationFormatArg {
    /// Unit quaternion x, y, z, w.
    #[default]
    Quat,
    /// Euler angles in degrees, extrinsic X, Y, Z (q = Rz·Ry·Rx, Blender's "XYZ Euler").
    Euler,
}

#[derive(clap::Args, Debug)]
#[command(group(clap::ArgGroup::new("when").required(true).args(["frames", "times", "frame", "time"])))]
pub struct SampleArgs {
    /// Scene file (.ron) or glTF model (.glb, .gltf; every animation an action).
    pub file: PathBuf,
    /// The value to sample, e.g. object/Arm/joint/elbow/rotation (see docs/channels.md).
    #[arg(long)]
    pub channel: Option<String>,
    /// Inclusive frame range A..B, stepped by --step frames (default 1).
    #[arg(long, value_name = "A..B", allow_hyphen_values = true)]
    pub frames: Option<String>,
    /// Inclusive time range A..B in seconds, stepped by --step seconds (default one frame).
    #[arg(long, value_name = "A..B", allow_hyphen_values = true)]
    pub times: Option<String>,
    /// A single frame (may be fractional).
    #[arg(long, allow_hyphen_values = true)]
    pub frame: Option<f64>,
    /// A single time in seconds.
    #[arg(long, allow_hyphen_values = true)]
    pub time: Option<f64>,
    /// Step between samples: frames for --frames, seconds for --times.
    #[arg(long, allow_negative_numbers = true)]
    pub step: Option<f64>,
    /// Output format.
    #[arg(long, value_enum, default_value_t = SampleFormat::Csv)]
    pub format: SampleFormat,
    /// How rotations are printed.
    #[arg(long, value_enum, default_value_t = RotationFormatArg::Quat)]
    pub rotation_format: RotationFormatArg,
    /// Write to this file (atomically) instead of standard output.
    #[arg(short, long, value_name = "OUT")]
    pub output: Option<PathBuf>,
    /// Play this action (docs/actions.md) instead of the ones active in the file.
    #[arg(long, value_name = "NAME")]
    pub action: Option<String>,
}

/// Parses `A..B` (also `A..=B`; both inclusive) into two finite numbers with A ≤ B.
fn parse_range(flag: &str, text: &str) -> anyhow::Result<(f64, f64)> {
    let Some((a, b)) = text.split_once("..") else {
        bail!("--{flag} {text:?}: expected a range A..B, e.g. 0..90");
    };
    let b = b.strip_prefix('=').unwrap_or(b);
    let number = |s: &str, which: &str| -> anyhow::Result<f64> {
        let v: f64 = s
            .trim()
            .parse()
            .map_err(|_| anyhow::anyhow!("--{flag} {text:?}: {which} {s:?} is not a number"))?;
        if !v.is_finite() {
            bail!("--{flag} {text:?}: {which} {s:?} is not a finite number");
        }
        Ok(v)
    };
    let (a, b) = (number(a, "start")?, number(b, "end")?);
    if a > b {
        bail!("--{flag} {text:?}: the start {a} is after the end {b}");
    }
    Ok((a, b))
}

/// The sample instants: `(frame, time)` pairs.
fn instants(args: &SampleArgs, fps: f64) -> anyhow::Result<Vec<(f64, f64)>> {
    let single = |v: f64, flag: &str| -> anyhow::Result<f64> {
        if v.is_finite() {
            Ok(v)
        } else {
            bail!("--{flag} {v}: not a finite number")
        }
    };
    if args.step.is_some() && (args.frame.is_some() || args.time.is_some()) {
        bail!("--step applies to --frames and --times ranges, not to a single --frame or --time");
    }
    if let Some(f) = args.frame {
        let f = single(f, "frame")?;
        return Ok(vec![(f, f / fps)]);
    }
    if let Some(t) = args.time {
        let t = single(t, "time")?;
        return Ok(vec![(t * fps, t)]);
    }
    let (flag, text, in_frames) = match (&args.frames, &args.times) {
        (Some(r), _) => ("frames", r.as_str(), true),
        (None, Some(r)) => ("times", r.as_str(), false),
        (None, None) => bail!("give one of --frames A..B, --times A..B, --frame F or --time T"),
    };
    let (a, b) = parse_range(flag, text)?;
    let step = args.step.unwrap_or(if in_frames { 1.0 } else { 1.0 / fps });
    if !(step.is_finite() && step > 0.0) {
        bail!("--step {step}: must be a positive number");
    }
    // Count with a little slack so that 0..1 by 0.1 includes 1 despite rounding.
    let count = ((b - a) / step * (1.0 + 1e-12) + 1e-9).floor() + 1.0;
    if count > MAX_SAMPLES as f64 {
        bail!("--{flag} {text} with step {step} gives {count} samples; at most {MAX_SAMPLES} are allowed");
    }
    Ok((0..count as usize)
        .map(|i| {
            let v = a + i as f64 * step;
            if in_frames {
                (v, v / fps)
            } else {
                (v * fps, v)
            }
        })
        .collect())
}

/// Resolves `--channel`, listing the scene's channels when it is missing.
fn resolve_channel(args: &SampleArgs, scene: &Scene) -> anyhow::Result<Channel> {
    let Some(text) = &args.channel else {
        let names: Vec<String> = list_channels(scene).iter().map(ToString::to_string).collect();
        bail!("missing --channel PATH; this scene's channels are:\n  {}", names.join("\n  "));
    };
    let path = ChannelPath::parse(text)?;
    path.resolve(scene).with_context(|| format!("{}", args.file.display()))
}

/// The index-based id of `--channel` (already resolved by [`resolve_channel`]).
fn channel_id(args: &SampleArgs, scene: &Scene) -> anyhow::Result<keyrig_core::channel_id::ChannelId> {
    let text = args.channel.as_deref().unwrap_or_default();
    Ok(ChannelPath::parse(text)?.id(scene)?)
}

/// A component as printed: f32 (the precision of the scene's values), with −0 shown as 0.
fn tidy(v: f64) -> f32 {
    v as f32 + 0.0
}

/// An unwrapped angle as printed: rounded to 1e-9° (hiding the f64 noise of `u·θ`, far
/// below the f32 precision of the keys), with −0 shown as 0.
fn tidy_degrees(degrees: f64) -> f64 {
    (degrees * 1e9).round() / 1e9 + 0.0
}

pub fn run(args: SampleArgs) -> anyhow::Result<()> {
    let (scene, problems) = super::common::load_scene_lenient(&args.file, "sample")?;
    let scene = super::common::with_action(scene, args.action.as_deref(), &args.file)?;
    if !(scene.fps.is_finite() && scene.fps > 0.0) {
        bail!(
            "{}: fps {} is not a positive number; cannot convert frames to time",
            args.file.display(),
            scene.fps
        );
    }
    let channel = resolve_channel(&args, &scene)?;
    // Problems elsewhere in the scene do not stop sampling a valid channel, but are mentioned.
    if !problems.is_empty() {
        eprintln!(
            "keyrig: warning: {}: the scene has {} validation problem{} (see `keyrig info`)",
            args.file.display(),
            problems.len(),
            if problems.len() == 1 { "" } else { "s" }
        );
    }
    let instants = instants(&args, scene.fps)?;
    // Every instant lies in the scene's frame range (the range ends suffice: they are sorted).
    let flag = |v: f64| match (&args.frames, &args.times, args.frame) {
        (Some(r), _, _) => format!("--frames {r}: frame {v}"),
        (None, Some(r), _) => format!("--times {r}: time {}", v / scene.fps),
        (None, None, Some(f)) => format!("--frame {f}"),
        _ => format!("--time {}", v / scene.fps),
    };
    for &(frame, _) in instants.first().into_iter().chain(instants.last()) {
        super::common::check_frame(&scene, frame, &flag(frame))?;
    }
    let rotation = match args.rotation_format {
        RotationFormatArg::Quat => RotationFormat::Quat,
        RotationFormatArg::Euler => RotationFormat::EulerDegrees,
    };
    let columns = channel.column_names(rotation);
    // Values come from the one scene evaluator (the editor's, `render`'s); `channel` names
    // and checks what is sampled.
    let eval = keyrig_eval::SceneEvaluator::new(&scene, &std::collections::HashMap::new());
    let id = channel_id(&args, &scene)?;
    let none = keyrig_eval::Overrides::new();
    let value = |time: f64| eval.value(id, time, &none).expect("the channel was resolved in this scene");
    // Spin segments turn beyond what a quaternion (or Euler angles) can show: print the
    // unwrapped angle beside it, in f64 degrees to keep many turns exact.
    let spin = channel.has_spin();
    let text = match args.format {
        SampleFormat::Csv => {
            let mut out = String::with_capacity(instants.len() * 48);
            out.push_str("frame,time");
            for c in columns {
                out.push(',');
                out.push_str(c);
            }
            if spin {
                out.push_str(",spin_deg");
            }
            out.push('\n');
            for &(frame, time) in &instants {
                use std::fmt::Write as _;
                let _ = write!(out, "{frame},{time}");
                for v in value(time).components(rotation) {
                    let _ = write!(out, ",{}", tidy(v));
                }
                if spin {
                    out.push(',');
                    if let Some(degrees) = eval.spin_degrees(id, time) {
                        let _ = write!(out, "{}", tidy_degrees(degrees));
                    }
                }
                out.push('\n');
            }
            out
        }
        SampleFormat::Json => {
            let samples: Vec<serde_json::Value> = instants
                .iter()
                .map(|&(frame, time)| {
                    let values: Vec<f32> = value(time).components(rotation).into_iter().map(tidy).collect();
                    let value = if values.len() == 1 {
                        serde_json::json!(values[0])
                    } else {
                        serde_json::json!(values)
                    };
                    let mut sample = serde_json::json!({ "frame": frame, "time": time, "value": value });
                    if spin {
                        sample["spin_deg"] = serde_json::json!(eval.spin_degrees(id, time).map(tidy_degrees));
                    }
                    sample
                })
                .collect();
            let doc = serde_json::json!({
                "file": args.file.display().to_string(),
                "channel": channel.path,
                "field": channel.field,
                "columns": columns,
                "keys": channel.key_count,
                "samples": samples,
            });
            serde_json::to_string_pretty(&doc).context("writing JSON")? + "\n"
        }
    };
    match &args.output {
        None => super::common::write_stdout(text.as_bytes()),
        Some(out) => {
            let mut inputs = vec![(args.file.clone(), "the input file".to_owned())];
            inputs.extend(keyrig_io::project::scene_inputs(&scene, args.file.parent()));
            keyrig_io::file_io::refuse_overwriting(out, &inputs)?;
            keyrig_io::file_io::write_atomic(out, text.as_bytes())
                .with_context(|| format!("{}: cannot write", out.display()))
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ranges() {
        assert_eq!(parse_range("frames", "0..90").unwrap(), (0.0, 90.0));
        assert_eq!(parse_range("frames", "-5..=5").unwrap(), (-5.0, 5.0));
        assert_eq!(parse_range("times", "0.5..1.25").unwrap(), (0.5, 1.25));
        for bad in ["10", "a..b", "5..1", "0..inf", "NaN..1", ".."] {
            assert!(parse_range("frames", bad).is_err(), "{bad}");
        }
    }
}
