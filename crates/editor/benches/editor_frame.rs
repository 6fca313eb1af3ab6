//! Frame time of the editor on the demo scene at 1280×720 while the animation plays.
//!
//! - `painter`: one UI frame without a GPU (CPU skinning, egui painter viewport, dope sheet,
//!   curves), as in the UI tests; egui output is not rasterized.
//! - `wgpu_painter_viewport`: the same UI frame rendered by egui-wgpu and read back (the
//!   viewport drawn by egui's painter, no keyrig-render): the cost of egui's own rendering.
//!
//! The wgpu benches use egui-wgpu with eframe's renderer options (see `eframe_like_renderer`),
//! so egui's fragment shader is the one the running editor uses.
//! - `gpu_viewport_{full,half}_resolution_{msaa4,no_msaa}`: one whole frame through eframe's
//!   wgpu path: the UI, keyrig-render's GPU skinning and viewport, and egui's own rendering,
//!   waited for by reading the window image back (the read-back, 1280×720×4 bytes, is part of
//!   the figure); the viewport texture at full or half resolution, with 4× MSAA or without
//!   (View ▸ Anti-aliasing; the editor's default on a CPU rasterizer is half, no MSAA).
//!
//! - `gpu_viewport_arm_selected` and `…_onion_skin_4_ghosts`: the last at full resolution
//!   without MSAA, with the arm selected, without and with onion skinning (four ghosts).
//!
//! Run: `cargo bench -p keyrig-editor --bench editor_frame -- --warm-up-time 1 --measurement-time 5`

use criterion::{criterion_group, criterion_main, Criterion};
use egui_kittest::wgpu::WgpuTestRenderer;
use egui_kittest::Harness;
use keyrig_editor::gpu_view::GpuView;
use keyrig_editor::{editor_for, EditorApp, EditorOptions};

const SIZE: egui::Vec2 = egui::Vec2::new(1280.0, 720.0);

fn options(dir: &std::path::Path) -> EditorOptions {
    EditorOptions { data_dir: Some(dir.to_path_buf()), autosave_seconds: Some(1e9) }
}

/// egui-wgpu with the options eframe uses (hardware texture filtering, dithering), not
/// kittest's `PREDICTABLE` ones (four `textureLoad`s per fragment), on kittest's adapter (a
/// CPU rasterizer where there is one).
fn eframe_like_renderer() -> WgpuTestRenderer {
    let setup = egui_kittest::wgpu::default_wgpu_setup();
    let instance = pollster::block_on(setup.new_instance());
    let config = egui_wgpu::WgpuConfiguration { wgpu_setup: setup, ..Default::default() };
    let render_state = pollster::block_on(egui_wgpu::RenderState::create(
        &config,
        &instance,
        None,
        egui_wgpu::RendererOptions::default(),
    ))
    .unwrap_or_else(|e| panic!("no wgpu device for the benchmark: {e}"));
    WgpuTestRenderer::from_render_state(render_state)
}

fn frame_time(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut group = c.benchmark_group("editor_frame_1280x720");

    let app = editor_for(None, options(dir.path()));
    let mut painter = Harness::builder()
        .with_size(SIZE)
        .with_step_dt(1.0 / 60.0)
        .build_ui_state(|ui, app: &mut EditorApp| app.ui(ui), app);
    painter.state_mut().session.playback.playing = true;
    group.bench_function("painter", |b| b.iter(|| painter.step()));

    // The window drawn through wgpu with the painter viewport (no keyrig-render): what egui's
    // own rendering and the read-back cost.
    let data_dir = dir.path().to_path_buf();
    let mut egui_only = Harness::builder()
        .renderer(eframe_like_renderer())
        .with_size(SIZE)
        .with_step_dt(1.0 / 60.0)
        .build_eframe(move |_cc| editor_for(None, options(&data_dir)));
    egui_only.state_mut().session.playback.playing = true;
    group.bench_function("wgpu_painter_viewport", |b| {
        b.iter(|| {
            egui_only.step();
            egui_only.render().expect("render the frame")
        });
    });

    // The last two: the arm selected, without and with onion skinning (two ghosts before
    // and two after, every 5 frames): what four ghosts cost.
    for (name, scale, antialiasing, onion) in [
        ("gpu_viewport_half_resolution_msaa4", 0.5, true, None),
        ("gpu_viewport_half_resolution_no_msaa", 0.5, false, None),
        ("gpu_viewport_full_resolution_msaa4", 1.0, true, None),
        ("gpu_viewport_full_resolution_no_msaa", 1.0, false, None),
        ("gpu_viewport_arm_selected", 1.0, false, Some(false)),
        ("gpu_viewport_arm_selected_onion_skin_4_ghosts", 1.0, false, Some(true)),
    ] {
        let data_dir = dir.path().to_path_buf();
        let mut gpu = Harness::builder()
            .renderer(eframe_like_renderer())
            .with_size(SIZE)
            .with_step_dt(1.0 / 60.0)
            .build_eframe(move |cc| {
                let mut app = editor_for(None, options(&data_dir));
                if let Some(rs) = &cc.wgpu_render_state {
                    app.attach_gpu(rs);
                }
                app.view.resolution_scale = scale;
                app.view.antialiasing = antialiasing;
                if let Some(on) = onion {
                    app.session.selection.select_only(Some(keyrig_editor::session::Selected::Object(0)));
                    app.view.onion = keyrig_editor::onion::OnionSkin { enabled: on, ..Default::default() };
                }
                app
            });
        let adapter = gpu.state().gpu().map(GpuView::adapter_name).expect("the wgpu harness gives a device");
        eprintln!("adapter: {adapter}");
        gpu.state_mut().session.playback.playing = true;
        // The first frames build the rig and the viewport texture.
        for _ in 0..3 {
            gpu.step();
        }
        let msaa = gpu.state().gpu().is_some_and(GpuView::antialiasing);
        assert_eq!(msaa, antialiasing, "{name}: the viewport's MSAA setting");
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
