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

/// The reference image lies behind the scene in the GPU viewport: the scene is rendered
/// see-through (cleared to transparent) and blended over the image egui draws beneath, so the
/// background shows the image and the arm's surface shows the arm as it does without one.
#[test]
fn the_reference_image_is_behind_the_gpu_scene() {
    let dir = tempfile::tempdir().expect("temp dir");
    let png = dir.path().join("red.png");
    image::RgbaImage::from_pixel(16, 9, image::Rgba([255, 0, 0, 255])).save(&png).expect("png");
    let render = |with_image: bool| {
        let mut scene = keyrig_io::demo::demo_scene();
        if with_image {
            scene.reference_image =
                Some(keyrig_core::ReferenceImage { path: "red.png".into(), opacity: 1.0 });
        }
        let file = dir.path().join(format!("shot-{with_image}.ron"));
        keyrig_io::project::save_scene(&file, &scene).expect("save");
        let data = dir.path().to_path_buf();
        let mut h = Harness::builder().wgpu().with_size(egui::Vec2::from(SIZE)).build_eframe(move |cc| {
            let options = EditorOptions { data_dir: Some(data), autosave_seconds: Some(1e9) };
            let mut app = editor_for(Some(file), options);
            if let Some(rs) = &cc.wgpu_render_state {
                app.attach_gpu(rs);
            }
            app
        });
        h.run();
        assert!(h.state().viewport_errors().is_empty(), "{:?}", h.state().viewport_errors());
        let rect = h.state().viewport_rect().expect("laid out");
        let pose = h.state().object_pose_now(0).expect("the arm");
        let elbow: glam::Vec3 = (pose.world_from_object * pose.object_from_joint[1]).translation.into();
        let on_arm = keyrig_editor::camera::Projection::new(&h.state().view.camera, rect)
            .project(elbow)
            .expect("in view");
        let image = h.render().expect("render the window");
        let ppp = h.ctx.pixels_per_point();
        let pixel = |p: egui::Pos2| image.get_pixel((p.x * ppp) as u32, (p.y * ppp) as u32).0;
        // Above the horizon at the top middle, inside the image fitted to the viewport's height.
        (pixel(egui::pos2(rect.center().x, rect.min.y + 4.0)), pixel(on_arm))
    };
    let (background, arm) = render(false);
    let (background_behind, arm_behind) = render(true);
    assert!(background[0] < 80, "no image: the dark background {background:?}");
    assert!(
        background_behind[0] > 200 && background_behind[1] < 60 && background_behind[2] < 60,
        "the red image shows behind the scene: {background_behind:?}"
    );
    for (a, b) in arm.iter().zip(arm_behind) {
        assert!(
            a.abs_diff(b) <= 6,
            "the arm is drawn over the image as without it: {arm:?} vs {arm_behind:?}"
        );
    }
}
