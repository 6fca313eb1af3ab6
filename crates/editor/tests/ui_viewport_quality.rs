//! The GPU viewport's quality settings on the adapter the tests get (lavapipe where there is no
//! GPU): 4× MSAA follows the adapter (off on a CPU rasterizer) and View ▸ Anti-aliasing; the
//! viewport shows the colours `keyrig render` writes (not the linear values, far too dark).

use egui::accesskit::Role;
use egui_kittest::kittest::Queryable;
use egui_kittest::Harness;
use keyrig_editor::{editor_for, EditorApp, EditorOptions};

const SIZE: [f32; 2] = [1280.0, 720.0];

fn gpu_harness(dir: &std::path::Path) -> Harness<'static, EditorApp> {
    let dir = dir.to_path_buf();
    let mut harness = Harness::builder().wgpu().with_size(egui::Vec2::from(SIZE)).build_eframe(move |cc| {
        let mut app = editor_for(None, EditorOptions { data_dir: Some(dir), autosave_seconds: Some(1e9) });
        if let Some(rs) = &cc.wgpu_render_state {
            app.attach_gpu(rs);
        }
        app
    });
    harness.run();
    assert!(harness.state().gpu().is_some(), "kittest's wgpu renderer gives the editor a device");
    harness
}

fn gpu_msaa(h: &Harness<'_, EditorApp>) -> bool {
    h.state().gpu().expect("GPU viewport").antialiasing()
}

#[test]
fn antialiasing_follows_the_adapter_and_the_view_menu() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = gpu_harness(dir.path());
    let cpu = h.state().gpu().expect("GPU viewport").is_cpu_adapter();
    assert_eq!(h.state().view.antialiasing, !cpu, "MSAA on by default only on a GPU");
    assert_eq!(gpu_msaa(&h), !cpu);
    assert_eq!(h.state().view.resolution_scale, 1.0, "full resolution on every adapter");

    for expected in [cpu, !cpu] {
        h.get_by_role_and_label(Role::Button, "View").click();
        h.run();
        h.get_by_label("Anti-aliasing (4× MSAA)").click();
        h.run();
        assert_eq!(h.state().view.antialiasing, expected, "the menu toggles the setting");
        assert_eq!(gpu_msaa(&h), expected, "the renderer follows on the next frame");
        assert!(h.state().viewport_errors().is_empty(), "{:?}", h.state().viewport_errors());
        // Close the menu for the next round.
        h.key_press(egui::Key::Escape);
        h.run();
    }
}

#[test]
fn the_viewport_shows_srgb_encoded_colour() {
    let dir = tempfile::tempdir().expect("temp dir");
    let mut h = gpu_harness(dir.path());
    let rect = h.state().viewport_rect().expect("the viewport was laid out");
    let image = h.render().expect("render the window");
    // Above the horizon, away from the text in the top-left corner: the background, linear
    // (0.018, 0.02, 0.025), which `keyrig render` writes as sRGB (36, 39, 44). Shown linear it
    // would be (5, 5, 6).
    let ppp = h.ctx.pixels_per_point();
    let (x, y) = (((rect.max.x - 6.0) * ppp) as u32, ((rect.min.y + 6.0) * ppp) as u32);
    let pixel = image.get_pixel(x, y).0;
    for (channel, expected) in pixel.iter().zip([36u8, 39, 44]) {
        assert!(channel.abs_diff(expected) <= 3, "viewport background at ({x}, {y}) is {pixel:?}");
    }
}
