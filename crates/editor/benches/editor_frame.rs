//! Frame time of the editor on the demo scene at 1280×720 while the animation plays.
//!
//! - `painter`: one UI frame without a GPU (CPU skinning, egui painter viewport, dope sheet,
//!   curves), as in the UI tests; egui output is not rasterized.
//! - `gpu_viewport_{full,half}_resolution`: one whole frame through eframe's wgpu path: the UI, keyrig-render's
//!   GPU skinning and viewport, and egui's own rendering, waited for by reading the window
//!   image back (the read-back, 1280×720×4 bytes, is part of the figure); the viewport
//!   texture at full or half resolution.
//!
//! Run: `cargo bench -p keyrig-editor --bench editor_frame -- --warm-up-time 1 --measurement-time 5`

use criterion::{criterion_group, criterion_main, Criterion};
use egui_kittest::Harness;
use keyrig_editor::gpu_view::GpuView;
use keyrig_editor::{editor_for, EditorApp, EditorOptions};

const SIZE: egui::Vec2 = egui::Vec2::new(1280.0, 720.0);

fn options(dir: &std::path::Path) -> EditorOptions {
    EditorOptions { data_dir: Some(dir.to_path_buf()), autosave_seconds: Some(1e9) }
}

fn frame_time(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut group = c.benchmark_group("editor_frame_1280x720");

    let app = editor_for(None, options(dir.path()));
    let mut painter = Harness::builder()
        .with_size(SIZE)
        .with_step_dt(1.0 / 60.0)
        .build_ui_state(|ui, app: &mut EditorApp| app.ui(ui), app);
    painter.state_mut().playback.playing = true;
    group.bench_function("painter", |b| b.iter(|| painter.step()));

    for (name, scale) in [("gpu_viewport_full_resolution", 1.0), ("gpu_viewport_half_resolution", 0.5)] {
        let data_dir = dir.path().to_path_buf();
        let mut gpu =
            Harness::builder().wgpu().with_size(SIZE).with_step_dt(1.0 / 60.0).build_eframe(move |cc| {
                let mut app = editor_for(None, options(&data_dir));
                if let Some(rs) = &cc.wgpu_render_state {
                    app.attach_gpu(rs);
                }
                app.view.resolution_scale = scale;
                app
            });
        let adapter =
            gpu.state().gpu.as_ref().map(GpuView::adapter_name).expect("the wgpu harness gives a device");
        eprintln!("adapter: {adapter}");
        gpu.state_mut().playback.playing = true;
        group.bench_function(name, |b| {
            b.iter(|| {
                gpu.step();
                gpu.render().expect("render the frame")
            });
        });
    }
    group.finish();
}

criterion_group!(benches, frame_time);
criterion_main!(benches);
