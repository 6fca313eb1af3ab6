//! `keyrig render --frames` of `assets/showcase.ron` through its cameras (issue 31 item 4).
//! At the marker of frame 45 the picture cuts from the dolly camera, aimed at the elbow, to the
//! close-up camera tracking the wrist: the arm's thickness in the image's middle column is
//! checked on both sides of the cut against a pinhole projection of the arm's cross-section
//! worked out here (the paper's 25-sided 43.744 × 40.12 cm ellipse, from each camera's keyed
//! eye and lens, looking at its aim target). At 2.5 s, half-way through the forearm's turn, the
//! deformer switches from linear blend to bones blending: the candy wrapper of frame 74 is
//! gone in frame 75.
//!
//! Renders on the adapter wgpu finds (lavapipe without a GPU).

use std::path::Path;
use std::process::Command;

use glam::{DVec3, Vec3};
use keyrig_core::channel::ChannelPath;
use keyrig_render::image::RgbaImage;

const WIDTH: u32 = 960;
const HEIGHT: u32 = 540;

fn showcase() -> String {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/showcase.ron");
    path.to_str().expect("utf-8 path").to_owned()
}

/// Renders `frames` (`A..B`) of the showcase without grid and skeleton; the images by frame.
fn render(dir: &Path, frames: &str) -> impl Fn(u32) -> RgbaImage {
    let pattern = dir.join("show_###.png");
    let out = Command::new(env!("CARGO_BIN_EXE_keyrig"))
        .args(["render", &showcase(), "--no-grid", "--no-skeleton", "--frames", frames, "-o"])
        .arg(&pattern)
        .output()
        .expect("run keyrig");
    assert!(out.status.success(), "keyrig render failed: {}", String::from_utf8_lossy(&out.stderr));
    let dir = dir.to_path_buf();
    move |n| {
        let image =
            keyrig_render::image::open(dir.join(format!("show_{n:03}.png"))).expect("a PNG").to_rgba8();
        assert_eq!(image.dimensions(), (WIDTH, HEIGHT), "the scene's render size");
        image
    }
}

fn differs(a: [u8; 4], b: [u8; 4]) -> bool {
    a.iter().zip(&b).any(|(x, y)| x.abs_diff(*y) > 12)
}

/// Pixels of column `x` that are not the background (the top-left corner's colour).
fn column_coverage(image: &RgbaImage, x: u32) -> u32 {
    let background = image.get_pixel(0, 0).0;
    (0..image.height()).filter(|&y| differs(image.get_pixel(x, y).0, background)).count() as u32
}

/// The arm's cross-section as the paper gives it: 25 points at angles 2πk/25 on an ellipse
/// scaled so that their bounding box is 43.744 cm (Y) × 40.12 cm (Z), in metres.
fn cross_section() -> Vec<(f64, f64)> {
    let angles: Vec<(f64, f64)> =
        (0..25).map(|k| (std::f64::consts::TAU * f64::from(k) / 25.0).sin_cos()).collect();
    let span = |f: fn(&(f64, f64)) -> f64| {
        let values = angles.iter().map(f);
        values.clone().fold(f64::MIN, f64::max) - values.fold(f64::MAX, f64::min)
    };
    let (a, b) = (0.43744 / span(|p| p.1), 0.4012 / span(|p| p.0));
    angles.iter().map(|&(s, c)| (a * c, b * s)).collect()
}

/// How many pixels of the middle column a straight run of the arm covers, seen through a
/// pinhole camera at `eye` looking at `target` (+Y up, no roll) with a vertical field of view
/// `fov_y` (radians): the run is the arm's axis from `x0` to `x1` at height 1 (the arm's
/// object lies at y = 1, z = 0), its cross-section turned `twist_deg` about the axis.
fn expected_coverage(eye: Vec3, target: Vec3, fov_y: f64, (x0, x1): (f64, f64), twist_deg: f64) -> f64 {
    let (eye, target) = (eye.as_dvec3(), target.as_dvec3());
    let forward = (target - eye).normalize();
    let right = forward.cross(DVec3::Y).normalize();
    let up = right.cross(forward);
    let scale = f64::from(HEIGHT) / 2.0 / (fov_y / 2.0).tan();
    let (sin, cos) = twist_deg.to_radians().sin_cos();
    let section = cross_section();
    let column = f64::from(WIDTH / 2) + 0.5;
    let (mut top, mut bottom) = (f64::MAX, f64::MIN);
    for i in 0..=600 {
        let x = x0 + (x1 - x0) * f64::from(i) / 600.0;
        for k in 0..section.len() {
            let (p, q) = (section[k], section[(k + 1) % section.len()]);
            for step in 0..=20 {
                let f = f64::from(step) / 20.0;
                let (y, z) = (p.0 + (q.0 - p.0) * f, p.1 + (q.1 - p.1) * f);
                let point = DVec3::new(x, 1.0 + cos * y - sin * z, sin * y + cos * z);
                let d = point - eye;
                let depth = d.dot(forward);
                let px = f64::from(WIDTH) / 2.0 + d.dot(right) / depth * scale;
                if (px - column).abs() <= 0.5 {
                    let py = f64::from(HEIGHT) / 2.0 - d.dot(up) / depth * scale;
                    top = top.min(py);
                    bottom = bottom.max(py);
                }
            }
        }
    }
    assert!(top < bottom, "the run crosses the middle column");
    bottom - top
}

#[test]
fn the_cut_at_the_marker_changes_the_camera_and_the_switch_repairs_the_twist() {
    let scene = keyrig_io::scene_file::load(Path::new(&showcase())).expect("opens");
    let sample_vec3 = |path: &str, time: f64| {
        let value = ChannelPath::parse(path).unwrap().resolve(&scene).unwrap().sample(time);
        let c = value.components(keyrig_core::channel::RotationFormat::Quat);
        Vec3::new(c[0] as f32, c[1] as f32, c[2] as f32)
    };
    let dir = tempfile::tempdir().expect("tempdir");
    let frame = render(dir.path(), "44..45");

    // Frame 44, through Dolly: at its last key (1.4 s), a 35 mm lens on a 24 mm sensor,
    // looking at the elbow at (−0.400395, 1, 0); the elbow does not move.
    let elbow = Vec3::new(-0.400395, 1.0, 0.0);
    let eye = sample_vec3("camera/Dolly/translation", 44.0 / 30.0);
    assert_eq!(eye, Vec3::new(-0.3, 1.15, 2.4));
    let fov = 2.0 * (12.0f64 / 35.0).atan();
    let wide = expected_coverage(eye, elbow, fov, (-0.55, -0.25), 0.0);
    let got = column_coverage(&frame(44), WIDTH / 2);
    assert!((f64::from(got) - wide).abs() <= 3.0, "frame 44 (Dolly): {got} pixels, expected {wide:.1}");

    // Frame 45, through Track: at its first key, 40° field of view, looking at the wrist at
    // (0.400395, 1, 0), which turns with the forearm about the arm's axis.
    let wrist = Vec3::new(0.400395, 1.0, 0.0);
    let eye = sample_vec3("camera/Track/translation", 1.5);
    assert_eq!(eye, Vec3::new(0.9, 1.1, 1.0));
    let twist = ChannelPath::parse("object/Arm/joint/forearm/rotation").unwrap().resolve(&scene).unwrap();
    let turned = twist.spin_degrees(1.5).expect("in the turn");
    let close = expected_coverage(eye, wrist, 40f64.to_radians(), (0.25, 0.55), turned);
    let got = column_coverage(&frame(45), WIDTH / 2);
    assert!((f64::from(got) - close).abs() <= 3.0, "frame 45 (Track): {got} pixels, expected {close:.1}");
    assert!(close > 1.5 * wide, "the cut is a close-up: {close:.1} against {wide:.1} pixels");

    // Frames 74 and 75 through Track: the forearm is at 180° ± 1.2°. Linear blend collapses
    // the arm at the forearm joint (the candy wrapper; seen from the side and at an angle, its
    // neck measures about 0.6 of the arm's widest column in the image); with bones blending
    // the narrowest column measures about 0.8 of it, 40 pixels or more above the wrapper.
    let frame = render(dir.path(), "74..75");
    let narrowest = |image: &RgbaImage| {
        let columns: Vec<u32> = (0..WIDTH / 2).map(|x| column_coverage(image, x)).collect();
        (*columns.iter().min().unwrap(), *columns.iter().max().unwrap())
    };
    let (pinched, full) = narrowest(&frame(74));
    assert!(
        f64::from(pinched) < 0.65 * f64::from(full),
        "linear blend at 178.8°: {pinched} of {full} pixels"
    );
    let (round, full) = narrowest(&frame(75));
    assert!(
        f64::from(round) > 0.75 * f64::from(full) && round > pinched + 40,
        "bones blending at 180°: {round} of {full} pixels"
    );
}
