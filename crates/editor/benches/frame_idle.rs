//! What a frame of the editor costs when nothing changed against when the animation plays, on
//! `assets/demo.ron` and `assets/characters.ron` (the demo with CesiumMan, the Fox and an MD2
//! model), with every panel laid out in a 1280×800 egui_kittest harness.
//!
//! - `prepare/{scene}/{viewport}/{idle,playing}`: the frame's preparation alone
//!   (`EditorApp::prepare_frame`: mesh files checked, the evaluator in step with the document,
//!   the scene evaluated at the clock's time, the CPU skinning the panels ask for), after the
//!   harness laid the panels out. *Idle* prepares the same frame again (nothing playing,
//!   nothing edited); *playing* first moves the clock 1/60 s on, as playback does. With the
//!   painter viewport every mesh is skinned on the CPU; with the GPU viewport (keyrig-render on
//!   kittest's wgpu adapter, lavapipe here) nothing is, and the clip planes' box comes from the
//!   joints.
//! - `frame/{scene}/{idle,playing}`: one whole frame of the painter harness (preparation, every
//!   panel's layout and the painter's viewport; egui's output is not rasterized).
//!
//! Run: `cargo bench -p keyrig-editor --bench frame_idle -- --warm-up-time 1 --measurement-time 3`

use std::hint::black_box;
use std::path::{Path, PathBuf};

use criterion::{criterion_group, criterion_main, Criterion};
use egui_kittest::Harness;
use keyrig_editor::{editor_for, EditorApp, EditorOptions};

const SIZE: egui::Vec2 = egui::Vec2::new(1280.0, 800.0);
/// One frame of playback at 60 frames per second.
const DT: f64 = 1.0 / 60.0;

fn options(dir: &Path) -> EditorOptions {
    EditorOptions { data_dir: Some(dir.to_path_buf()), autosave_seconds: Some(1e9) }
}

/// The editor on `scene` in a painter harness, settled (every panel laid out once).
fn painter_harness(scene: &Path, dir: &Path) -> Harness<'static, EditorApp> {
    let app = editor_for(Some(scene.to_path_buf()), options(dir));
    let mut h = Harness::builder()
        .with_size(SIZE)
        .with_step_dt(DT as f32)
        .build_ui_state(|ui, app: &mut EditorApp| app.ui(ui), app);
    h.run_steps(3);
    h
}

/// The editor on `scene` with the GPU viewport on kittest's wgpu adapter, settled.
fn gpu_harness(scene: &Path, dir: &Path) -> Harness<'static, EditorApp> {
    let (scene, dir) = (scene.to_path_buf(), dir.to_path_buf());
    let mut h = Harness::builder().wgpu().with_size(SIZE).with_step_dt(DT as f32).build_eframe(move |cc| {
        let mut app = editor_for(Some(scene), options(&dir));
        if let Some(rs) = &cc.wgpu_render_state {
            app.attach_gpu(rs);
        }
        app
    });
    h.run_steps(3);
    assert!(h.state().gpu().is_some(), "kittest's wgpu renderer gives the editor a device");
    h
}

/// Moves the clock one frame of playback on (looping over the range).
fn play_one_frame(app: &mut EditorApp) {
    let scene = app.doc.scene();
    let (fps, range) = (scene.fps, scene.frame_range);
    app.session.playback.playing = true;
    app.session.playback.advance(DT, fps, range.start, range.end);
}

fn frame_idle(c: &mut Criterion) {
    let dir = tempfile::tempdir().expect("temp dir");
    let assets = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets");
    let mut group = c.benchmark_group("frame_idle");
    for name in ["demo", "characters"] {
        let scene: PathBuf = assets.join(format!("{name}.ron"));
        for (viewport, mut h) in
            [("painter", painter_harness(&scene, dir.path())), ("gpu", gpu_harness(&scene, dir.path()))]
        {
            assert!(h.state().viewport_errors().is_empty(), "{name}: {:?}", h.state().viewport_errors());
            group.bench_function(format!("prepare/{name}/{viewport}/idle"), |b| {
                b.iter(|| black_box(h.state_mut()).prepare_frame());
            });
            group.bench_function(format!("prepare/{name}/{viewport}/playing"), |b| {
                b.iter(|| {
                    let app = black_box(h.state_mut());
                    play_one_frame(app);
                    app.prepare_frame();
                });
            });
        }
        let mut h = painter_harness(&scene, dir.path());
        group.bench_function(format!("frame/{name}/idle"), |b| b.iter(|| h.step()));
        h.state_mut().session.playback.playing = true;
        group.bench_function(format!("frame/{name}/playing"), |b| b.iter(|| h.step()));
    }
    group.finish();
}

criterion_group!(benches, frame_idle);
criterion_main!(benches);
