//! What key edits cost in a motion-capture-sized scene: 10 cubes whose translation and
//! rotation tracks hold 5,000 keys each (100,000 keys). It runs 1,000 single-key edits the way
//! the editor does them — `Document::edit` (undo snapshot, change check) and
//! `SceneEvaluator::update` — and prints the process's resident memory before and after and
//! the time per edit (median and worst). docs/benchmarks.md records the figures.
//!
//! Run: `cargo run --release -p keyrig-editor --example edit_memory`

use std::collections::HashMap;
use std::time::Instant;

use glam::{Quat, Vec3};
use keyrig_core::channel_id::{ChannelId, ChannelValue};
use keyrig_core::{Key, MeshSource, Object, ProceduralMesh, RawTrack, Scene};
use keyrig_editor::document::Document;
use keyrig_eval::SceneEvaluator;

const CUBES: usize = 10;
const KEYS_PER_TRACK: usize = 5_000;
const EDITS: usize = 1_000;

/// Resident set size of this process in bytes (Linux `/proc/self/statm`).
fn resident_bytes() -> Option<u64> {
    let statm = std::fs::read_to_string("/proc/self/statm").ok()?;
    let pages: u64 = statm.split_whitespace().nth(1)?.parse().ok()?;
    Some(pages * 4096)
}

fn scene() -> Scene {
    let mut scene = Scene {
        frame_range: keyrig_core::FrameRange { start: 0, end: KEYS_PER_TRACK as i32 },
        ..Scene::default()
    };
    for c in 0..CUBES {
        let mut cube = Object::new(format!("Cube{c}"));
        cube.mesh = Some(MeshSource::Procedural(ProceduralMesh::Cube));
        let t = |k: usize| k as f64 / scene.fps;
        cube.translation.track = RawTrack::new(
            (0..KEYS_PER_TRACK)
                .map(|k| Key::new(t(k), Vec3::new(c as f32, (k as f32 * 0.1).sin(), 0.0)))
                .collect(),
        );
        cube.rotation.track = RawTrack::new(
            (0..KEYS_PER_TRACK).map(|k| Key::new(t(k), Quat::from_rotation_y(k as f32 * 0.01))).collect(),
        );
        scene.objects.push(cube);
    }
    scene
}

fn main() {
    let before_scene = resident_bytes();
    let mut doc = Document::new(scene(), None);
    let mut eval = SceneEvaluator::new(doc.scene(), &HashMap::new());
    let start = resident_bytes();
    let mut times = Vec::with_capacity(EDITS);
    for e in 0..EDITS {
        let cube = e % CUBES;
        let time = (e * 7 % KEYS_PER_TRACK) as f64 / doc.scene().fps;
        let t0 = Instant::now();
        doc.edit("move key", |s| {
            keyrig_edit::channels::set_key(
                s,
                ChannelId::ObjectTranslation(cube),
                time,
                ChannelValue::Vec3(Vec3::new(cube as f32, e as f32 * 1e-3, 1.0)),
            );
        });
        let rebuilt = eval.update(doc.scene(), &HashMap::new());
        times.push(t0.elapsed().as_secs_f64() * 1e3);
        assert_eq!(rebuilt.channels, 1, "one channel changed");
    }
    let end = resident_bytes();
    times.sort_by(f64::total_cmp);
    let mb = |b: Option<u64>| b.map_or("?".to_owned(), |b| format!("{:.1} MB", b as f64 / 1e6));
    println!(
        "{} keys in {CUBES} cubes; resident: {} before the scene, {} with the scene and its evaluator, {} after {EDITS} edits (growth {})",
        2 * CUBES * KEYS_PER_TRACK,
        mb(before_scene),
        mb(start),
        mb(end),
        match (start, end) {
            (Some(a), Some(b)) => format!("{:.1} MB", (b as f64 - a as f64) / 1e6),
            _ => "?".to_owned(),
        }
    );
    println!(
        "per edit (Document::edit + SceneEvaluator::update): median {:.3} ms, 90th percentile {:.3} ms, worst {:.3} ms",
        times[EDITS / 2],
        times[EDITS * 9 / 10],
        times[EDITS - 1]
    );
    println!("undo steps kept: {}", doc.undo_len());
}
