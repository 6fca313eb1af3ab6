//! Writes the scenes the editor's scale is measured on (docs/benchmarks.md, "Editor at scale"):
//!
//! - `cubes-200x3.ron`: 200 animated cubes, translation and rotation tracks of 3 keys each;
//! - `cubes-200x250.ron`: 200 cubes with 250 keys per track (100,000 keys);
//! - `cubes-10x5000.ron`: 10 cubes with 5,000 keys per track (100,000 keys, the density of
//!   motion capture: a key on every frame at 30 fps for almost three minutes).
//!
//! Every key lies on a whole frame inside the scene's frame range, as keys recorded in the
//! editor do. The files are generated, not shipped.
//!
//! Run: `cargo run --release -p keyrig-editor --example stress_scenes -- OUT_DIR`, then e.g.
//! `keyrig edit OUT_DIR/cubes-10x5000.ron --benchmark-frames 300 --window-size 1280x800`.

use std::path::PathBuf;

use glam::{Quat, Vec3};
use keyrig_core::{FrameRange, Key, MeshSource, Object, ProceduralMesh, RawTrack, Scene};

/// (file name, cubes, keys per track).
const SCENES: [(&str, usize, usize); 3] =
    [("cubes-200x3.ron", 200, 3), ("cubes-200x250.ron", 200, 250), ("cubes-10x5000.ron", 10, 5_000)];

/// A grid of `cubes` cubes whose translation and rotation have `keys` keys each, one frame
/// apart for dense tracks and spread over 90 frames for sparse ones.
fn scene(cubes: usize, keys: usize) -> Scene {
    let fps = 30.0;
    let frames_between = (90 / keys.max(1)).max(1);
    let last_frame = ((keys - 1) * frames_between).max(1);
    let mut scene = Scene {
        fps,
        frame_range: FrameRange { start: 0, end: i32::try_from(last_frame).expect("frame range fits i32") },
        ..Scene::default()
    };
    let side = (cubes as f64).sqrt().ceil() as usize;
    for c in 0..cubes {
        let mut cube = Object::new(format!("Cube{c:03}"));
        cube.mesh = Some(MeshSource::Procedural(ProceduralMesh::Cube));
        let home = Vec3::new((c % side) as f32 * 2.5, 0.0, (c / side) as f32 * 2.5);
        let phase = c as f32 * 0.37;
        let time = |k: usize| (k * frames_between) as f64 / fps;
        cube.translation.track = RawTrack::new(
            (0..keys).map(|k| Key::new(time(k), home + Vec3::Y * (k as f32 * 0.13 + phase).sin())).collect(),
        );
        cube.rotation.track = RawTrack::new(
            (0..keys).map(|k| Key::new(time(k), Quat::from_rotation_y(k as f32 * 0.05 + phase))).collect(),
        );
        scene.objects.push(cube);
    }
    scene
}

fn main() -> anyhow::Result<()> {
    let out = PathBuf::from(std::env::args().nth(1).unwrap_or_else(|| ".".to_owned()));
    std::fs::create_dir_all(&out)?;
    for (name, cubes, keys) in SCENES {
        let path = out.join(name);
        let scene = scene(cubes, keys);
        keyrig_io::scene_file::save(&path, &scene)?;
        println!("{}: {cubes} cubes, {keys} keys per track, {} keys", path.display(), cubes * keys * 2);
    }
    Ok(())
}
