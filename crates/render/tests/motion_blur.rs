//! Motion blur (keyrig_render::accumulate): a cube crossing the view fast, rendered as the
//! average of sub-frames across the shutter, smears over exactly the distance it travels while
//! the shutter is open — measured against sharp renders at the shutter's opening and closing
//! times — and its edges ramp through the partial coverages in between.
//!
//! Renders on the adapter wgpu finds (lavapipe without a GPU); no adapter fails these tests.

use glam::Vec3;
use keyrig_core::{Animated, Camera, Key, MeshSource, Object, ProceduralMesh, RawTrack, Scene};
use keyrig_render::accumulate::subframe_offsets;
use keyrig_render::image::RgbaImage;
use keyrig_render::{HeadlessRenderer, SceneRig, ViewOptions};

const WIDTH: u32 = 320;
const HEIGHT: u32 = 160;
/// Frame 15 of a 30 fps scene: t = 0.5 s, the middle of the cube's run.
const FRAME: f64 = 15.0;

/// A unit cube running along X from −30 to +30 in one second (2 units a frame at 30 fps), lit
/// by ambient light only (one flat colour), seen straight on from +Z.
fn fast_cube_scene() -> Scene {
    let mut cube = Object::new("Cube");
    cube.mesh = Some(MeshSource::Procedural(ProceduralMesh::Cube));
    cube.translation = Animated::new(
        Vec3::ZERO,
        RawTrack::new(vec![
            Key::new(0.0, Vec3::new(-30.0, 0.0, 0.0)),
            Key::new(1.0, Vec3::new(30.0, 0.0, 0.0)),
        ]),
    );
    Scene {
        objects: vec![cube],
        ambient: Vec3::ONE,
        camera: Camera { target: Vec3::ZERO, yaw_deg: 0.0, pitch_deg: 0.0, distance: 10.0, fov_y_deg: 45.0 },
        ..Scene::default()
    }
}

fn view() -> ViewOptions {
    ViewOptions { grid: false, skeletons: false, ..ViewOptions::default() }
}

/// The first and last column of the middle row that differ from the background (top-left
/// pixel) by more than `threshold` in any channel.
fn extent(image: &RgbaImage, threshold: u8) -> Option<(u32, u32)> {
    let background = image.get_pixel(0, 0).0;
    let y = HEIGHT / 2;
    let differs = |x: u32| {
        let p = image.get_pixel(x, y).0;
        (0..3).any(|c| p[c].abs_diff(background[c]) > threshold)
    };
    let first = (0..WIDTH).find(|&x| differs(x))?;
    let last = (0..WIDTH).rev().find(|&x| differs(x))?;
    Some((first, last))
}

#[test]
fn blur_spans_the_distance_travelled_while_the_shutter_is_open() {
    let scene = fast_cube_scene();
    let rig = SceneRig::new(&scene).expect("rig");
    let mut headless = HeadlessRenderer::new().expect("a wgpu adapter (lavapipe without a GPU)");
    rig.upload(headless.renderer_mut()).expect("upload");
    let frame_at = |frame: f64| rig.frame(rig.time_of_frame(frame), &view()).expect("frame");

    let shutter = 0.5;
    let samples = 16;
    let mut sharp = |frame: f64| headless_image(&mut headless, &[frame_at(frame)]);
    let open = sharp(FRAME - shutter / 2.0);
    let close = sharp(FRAME + shutter / 2.0);
    let still = sharp(FRAME);
    let subframes: Vec<_> = subframe_offsets(samples, shutter).iter().map(|o| frame_at(FRAME + o)).collect();
    let blurred = headless_image(&mut headless, &subframes);

    let (open_first, _) = extent(&open, 8).expect("the cube at the shutter's opening");
    let (close_first, close_last) = extent(&close, 8).expect("the cube at its closing");
    let (still_first, still_last) = extent(&still, 8).expect("the cube at the frame");
    let cube_width = still_last - still_first;
    let travelled = close_first - open_first;
    assert!(cube_width > 10, "the cube is {cube_width} px wide");
    // Fast: in half a frame it moves more than its own width (2 units a frame on average,
    // faster in the middle of the two-key curve).
    assert!(travelled > cube_width, "{travelled} px travelled, the cube is {cube_width} px wide");
    // Off the axis the cube shows a sliver of a side face: a pixel or two wider.
    let close_width = close_last - close_first;
    assert!(close_width.abs_diff(cube_width) <= 2, "{close_width} px at closing, {cube_width} at the frame");

    // The blur covers from where the cube was when the shutter opened to where it was when it
    // closed. A pixel the cube covers in one sub-frame of 16 differs from the background by
    // 1/16 of the contrast (≈ 15 levels here), so a threshold of 4 sees it.
    let (blur_first, blur_last) = extent(&blurred, 4).expect("the blurred cube");
    assert!(
        blur_first.abs_diff(open_first) <= 2,
        "blur starts at {blur_first}, the cube at opening at {open_first}"
    );
    assert!(
        blur_last.abs_diff(close_last) <= 2,
        "blur ends at {blur_last}, the cube at closing at {close_last}"
    );
    let blur_width = blur_last - blur_first;
    assert!(
        blur_width.abs_diff(cube_width + travelled) <= 3,
        "blur {blur_width} px; cube {cube_width} px + travel {travelled} px"
    );

    // Partial coverage: along the leading and trailing edges the blur ramps through values
    // between the background and the cube's colour; the sharp frame has almost none.
    let y = HEIGHT / 2;
    let background = f32::from(blurred.get_pixel(0, 0).0[0]);
    let cube = f32::from(still.get_pixel((still_first + still_last) / 2, y).0[0]);
    let between = |image: &RgbaImage| {
        (0..WIDTH)
            .filter(|&x| {
                let v = f32::from(image.get_pixel(x, y).0[0]);
                let (lo, hi) = (background.min(cube), background.max(cube));
                v > lo + 0.1 * (hi - lo) && v < hi - 0.1 * (hi - lo)
            })
            .count()
    };
    assert!(between(&blurred) as u32 >= travelled, "{} partly covered pixels", between(&blurred));
    assert!(between(&still) <= 4, "the sharp frame has {} partly covered pixels", between(&still));
    // At the middle of the blur the cube is there for cube_width / travelled of the shutter
    // (it moves nearly uniformly within it): the pixel is that mix of cube and background in
    // linear light (sRGB decoded).
    let linear = |v: f32| srgb_to_linear(v / 255.0);
    let centre = linear(f32::from(blurred.get_pixel((blur_first + blur_last) / 2, y).0[0]));
    let coverage = (centre - linear(background)) / (linear(cube) - linear(background));
    let expected = cube_width as f32 / travelled as f32;
    assert!((coverage - expected).abs() < 0.1, "centre covered {coverage}, expected {expected}");
}

#[test]
fn one_subframe_is_the_plain_render_and_equal_subframes_average_to_it() {
    let scene = fast_cube_scene();
    let rig = SceneRig::new(&scene).expect("rig");
    let mut headless = HeadlessRenderer::new().expect("a wgpu adapter (lavapipe without a GPU)");
    rig.upload(headless.renderer_mut()).expect("upload");
    let frame = rig.frame(rig.time_of_frame(FRAME), &view()).expect("frame");
    let plain = headless_image(&mut headless, std::slice::from_ref(&frame));
    // Four copies of one frame: the average is the frame (16-bit float sums, within one level).
    let averaged = headless_image(&mut headless, &[frame.clone(), frame.clone(), frame.clone(), frame]);
    let worst = plain
        .pixels()
        .zip(averaged.pixels())
        .flat_map(|(a, b)| (0..4).map(move |c| a.0[c].abs_diff(b.0[c])))
        .max();
    assert!(worst.is_some_and(|w| w <= 1), "largest difference {worst:?}");
    assert!(headless.render_image_blurred(&[], WIDTH, HEIGHT).is_err(), "no sub-frames is an error");
}

fn headless_image(headless: &mut HeadlessRenderer, frames: &[keyrig_render::FrameInput]) -> RgbaImage {
    headless.render_image_blurred(frames, WIDTH, HEIGHT).expect("render").0
}

/// The sRGB decoding curve (IEC 61966-2-1).
fn srgb_to_linear(v: f32) -> f32 {
    if v <= 0.04045 {
        v / 12.92
    } else {
        ((v + 0.055) / 1.055).powf(2.4)
    }
}
