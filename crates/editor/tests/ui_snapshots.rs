//! A few image snapshots of the whole editor, rendered through eframe's wgpu path on whatever
//! adapter wgpu finds (lavapipe without a GPU), so the GPU viewport (keyrig-render) is in the
//! picture. Compared with `tests/snapshots/*.png` with tolerances: rasterizers differ in
//! anti-aliasing and MSAA patterns, so a per-pixel threshold plus a small budget of differing
//! pixels (0.5 % of the image). Update with `UPDATE_SNAPSHOTS=1 cargo test -p keyrig-editor
//! --test ui_snapshots`.

mod common;

use common::{go_to_frame, gpu_harness};

use egui::{Key, Modifiers};
use egui_kittest::kittest::Queryable;
use egui_kittest::SnapshotOptions;

const SIZE: [f32; 2] = [960.0, 600.0];

fn options() -> SnapshotOptions {
    let pixels = (SIZE[0] * SIZE[1]) as usize;
    SnapshotOptions::new().threshold(1.5).failed_pixel_count_threshold(pixels / 200)
}

#[test]
fn twist_at_frame_60_linear_blend_and_bones_blending() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = gpu_harness(dir.path(), SIZE);
    h.get_by_label("forearm").click();
    h.run();
    go_to_frame(&mut h, 60);
    h.key_press_modifiers(Modifiers::NONE, Key::Num2);
    h.run();
    let gpu_error = h.state().status().cloned().filter(|s| s.is_error);
    assert_eq!(gpu_error, None);
    h.snapshot_options("editor_linear_blend_twist", &options());
    h.key_press_modifiers(Modifiers::NONE, Key::Num3);
    h.run();
    h.snapshot_options("editor_bones_blending_twist", &options());
}

#[test]
fn an_imported_skinned_gltf_renders_on_the_gpu() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = gpu_harness(dir.path(), SIZE);
    let model = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../tests/corpus/gltf/RiggedSimple/RiggedSimple.glb");
    h.state_mut().import_path(model);
    h.state_mut().wait_for_background_work();
    h.run();
    assert!(!h.state().status().is_some_and(|s| s.is_error), "{:?}", h.state().status().cloned());
    assert_eq!(h.state().viewport_errors(), Vec::<String>::new());
    let stats = h.state().gpu().and_then(|g| g.last_stats).expect("a GPU frame");
    // The demo arm has 1250 vertices; the imported cylinder is skinned on the GPU as well.
    assert!(stats.deformed_vertices > 1250, "{stats:?}");
}
