//! `keyrig edit [FILE]` (and `keyrig` with no arguments): open the editor.

use std::path::PathBuf;

#[derive(clap::Args, Debug, Default)]
pub struct EditArgs {
    /// Scene (.ron) or model (.glb, .gltf, .md2) to open; the demo scene when omitted.
    pub file: Option<PathBuf>,
    /// Play this many frames, print frame-time statistics (preparation and drawing) and exit
    /// (docs/benchmarks.md).
    #[arg(long, value_name = "N", value_parser = clap::value_parser!(u32).range(1..=1_000_000))]
    pub benchmark_frames: Option<u32>,
    /// Inner size of the window in points, `WIDTHxHEIGHT` (default 1280x800).
    #[arg(long, value_name = "WxH", value_parser = parse_size)]
    pub window_size: Option<[f32; 2]>,
}

fn parse_size(text: &str) -> Result<[f32; 2], String> {
    let (w, h) = text
        .split_once(['x', 'X'])
        .ok_or_else(|| format!("{text:?}: expected WIDTHxHEIGHT, e.g. 1600x1000"))?;
    let parse = |v: &str| -> Result<f32, String> {
        v.trim()
            .parse::<u32>()
            .ok()
            .filter(|v| (200..=16_384).contains(v))
            .map(|v| v as f32)
            .ok_or_else(|| format!("{text:?}: sizes are whole numbers of points from 200 to 16384"))
    };
    Ok([parse(w)?, parse(h)?])
}

pub fn run(args: EditArgs) -> anyhow::Result<()> {
    keyrig_editor::run_editor(args.file, args.benchmark_frames, args.window_size)
}
