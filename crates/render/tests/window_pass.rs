//! A frame drawn straight into a render pass the caller owns ([`Renderer::prepare`] and
//! [`FrameDraws::record`]), as the editor draws its viewport into egui's pass on a CPU
//! rasterizer: into a window-like target that is not sRGB (the shaders encode), inside a
//! viewport rect of a larger target. It must show the same image as the offscreen render.

use keyrig_render::{HeadlessRenderer, Renderer, SceneRig, Selected, ViewOptions, DEPTH_FORMAT};

const WIDTH: u32 = 160;
const HEIGHT: u32 = 112;
/// Where the viewport sits in the larger window-like target.
const LEFT: u32 = 12;
const TOP: u32 = 7;
const WINDOW: (u32, u32) = (WIDTH + 30, HEIGHT + 20);
/// The window's colour outside the viewport (a colour the scene does not have).
const OUTSIDE: [u8; 4] = [255, 0, 255, 255];
/// Shader encoding against the hardware's sRGB encoding: at most this apart per channel.
const CHANNEL_TOLERANCE: u8 = 2;

fn window_texture(r: &HeadlessRenderer, format: wgpu::TextureFormat) -> (wgpu::Texture, wgpu::Texture) {
    let device = &r.gpu().device;
    let texture = |label, format, usage| {
        device.create_texture(&wgpu::TextureDescriptor {
            label: Some(label),
            size: wgpu::Extent3d { width: WINDOW.0, height: WINDOW.1, depth_or_array_layers: 1 },
            mip_level_count: 1,
            sample_count: 1,
            dimension: wgpu::TextureDimension::D2,
            format,
            usage,
            view_formats: &[],
        })
    };
    (
        texture("window", format, wgpu::TextureUsages::RENDER_ATTACHMENT | wgpu::TextureUsages::COPY_SRC),
        texture("window depth", DEPTH_FORMAT, wgpu::TextureUsages::RENDER_ATTACHMENT),
    )
}

#[test]
fn a_frame_drawn_into_a_window_pass_matches_the_offscreen_render() {
    let mut r = HeadlessRenderer::new().unwrap_or_else(|e| panic!("GPU tests need a wgpu adapter: {e}"));
    let scene = keyrig_io::demo::demo_scene();
    let rig = SceneRig::new(&scene).expect("scene rig");
    rig.upload(r.renderer_mut()).expect("upload");
    // Lit meshes, the depth-tested grid, skeletons and a motion path on top, a spot light.
    let view = ViewOptions {
        grid: true,
        skeletons: true,
        motion_path: true,
        selection: Some(Selected::Joint { object: 0, joint: 2 }),
        ..ViewOptions::default()
    };
    let frame = rig.frame(1.1, &view).expect("frame");
    // One sample per pixel, as in the window's pass.
    r.renderer_mut().set_sample_count(1).expect("one sample");
    let (expected, _) = r.render_image(&frame, WIDTH, HEIGHT).expect("offscreen render");

    // The editor's window: Bgra8Unorm (egui-wgpu's preferred format), one sample.
    let format = wgpu::TextureFormat::Bgra8Unorm;
    assert!(!format.is_srgb());
    r.renderer_mut().set_target(format, 1).expect("window pipelines");
    let (window, depth) = window_texture(&r, format);
    let renderer: &mut Renderer = r.renderer_mut();
    let (draws, stats) = renderer.prepare(&frame, (WIDTH, HEIGHT)).expect("prepare");
    assert!(stats.draw_calls >= 5, "background, meshes, grid and overlays: {} draws", stats.draw_calls);
    assert_eq!(draws.len(), stats.draw_calls as usize);

    let (device, queue) = (&r.gpu().device, &r.gpu().queue);
    let colour_view = window.create_view(&wgpu::TextureViewDescriptor::default());
    let depth_view = depth.create_view(&wgpu::TextureViewDescriptor::default());
    let mut encoder =
        device.create_command_encoder(&wgpu::CommandEncoderDescriptor { label: Some("window") });
    {
        let mut pass = encoder.begin_render_pass(&wgpu::RenderPassDescriptor {
            label: Some("window pass"),
            color_attachments: &[Some(wgpu::RenderPassColorAttachment {
                view: &colour_view,
                depth_slice: None,
                resolve_target: None,
                ops: wgpu::Operations {
                    load: wgpu::LoadOp::Clear(wgpu::Color {
                        r: f64::from(OUTSIDE[0]) / 255.0,
                        g: f64::from(OUTSIDE[1]) / 255.0,
                        b: f64::from(OUTSIDE[2]) / 255.0,
                        a: 1.0,
                    }),
                    store: wgpu::StoreOp::Store,
                },
            })],
            // Depth cleared to 1, as egui-wgpu clears the window's; the colour is not cleared
            // for the frame (the frame's own fill paints its rect).
            depth_stencil_attachment: Some(wgpu::RenderPassDepthStencilAttachment {
                view: &depth_view,
                depth_ops: Some(wgpu::Operations {
                    load: wgpu::LoadOp::Clear(1.0),
                    store: wgpu::StoreOp::Discard,
                }),
                stencil_ops: None,
            }),
            timestamp_writes: None,
            occlusion_query_set: None,
            multiview_mask: None,
        });
        // As egui-wgpu sets up a paint callback: the viewport and the scissor on its rect.
        pass.set_viewport(LEFT as f32, TOP as f32, WIDTH as f32, HEIGHT as f32, 0.0, 1.0);
        pass.set_scissor_rect(LEFT, TOP, WIDTH, HEIGHT);
        draws.record(&mut pass);
    }
    queue.submit([encoder.finish()]);
    let window = keyrig_render::headless::read_texture(device, queue, &window, format).expect("read back");

    let mut worst = 0u8;
    let mut differing = 0usize;
    for (x, y, pixel) in window.enumerate_pixels() {
        let inside = (LEFT..LEFT + WIDTH).contains(&x) && (TOP..TOP + HEIGHT).contains(&y);
        if !inside {
            assert_eq!(pixel.0, OUTSIDE, "({x}, {y}) lies outside the viewport and must stay untouched");
            continue;
        }
        let want = expected.get_pixel(x - LEFT, y - TOP);
        let d = pixel.0.iter().zip(want.0.iter()).map(|(a, b)| a.abs_diff(*b)).max().unwrap_or(0);
        worst = worst.max(d);
        differing += usize::from(d > CHANNEL_TOLERANCE);
    }
    assert_eq!(
        differing, 0,
        "{differing} pixels differ from the offscreen render by more than {CHANNEL_TOLERANCE} (worst {worst})"
    );
    // The frame is not empty: the arm, the cube and the grid are in it.
    let distinct: std::collections::HashSet<[u8; 4]> = expected.pixels().map(|p| p.0).collect();
    assert!(distinct.len() > 100, "{} colours", distinct.len());
}
