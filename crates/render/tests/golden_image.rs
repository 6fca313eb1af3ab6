//! Golden images: a small scene built in code (the low-poly arm twisted 150° at its second
//! joint, a cube, a spot and a directional light), rendered headless in each style and compared
//! with committed PNGs under tests/golden/ with a tolerance.
//!
//! Regenerate with `KEYRIG_UPDATE_GOLDEN=1 cargo test -p keyrig-render --test golden_image`.
//! On a mismatch the rendered image is written next to the target dir for inspection.

use std::path::{Path, PathBuf};

use glam::{Quat, Vec3};
use keyrig_core::{
    Animated, Camera, DeformerKind, Key, Light, LightKind, MeshSource, Object, ProceduralMesh, RawTrack,
    Scene,
};
use keyrig_render::{HeadlessRenderer, RenderStyle, SceneRig, Selected, ViewOptions};

const WIDTH: u32 = 192;
const HEIGHT: u32 = 128;

/// A channel counts as different above this (8-bit units).
const CHANNEL_TOLERANCE: u8 = 24;
/// At most this fraction of pixels may differ.
const PIXEL_FRACTION: f64 = 0.01;

pub fn test_scene() -> Scene {
    let mut arm = Object::new("Arm");
    arm.mesh = Some(MeshSource::Procedural(ProceduralMesh::ArmLowPoly));
    let mut skeleton = keyrig_skin::scene_skeleton_for(ProceduralMesh::ArmLowPoly).expect("arm skeleton");
    skeleton.joints[2].rotation = Animated::new(
        Quat::IDENTITY,
        RawTrack::new(vec![
            Key::new(0.0, Quat::IDENTITY),
            Key::new(1.0, Quat::from_rotation_x(150f32.to_radians())),
        ]),
    );
    skeleton.joints[1].rotation = Animated::constant(Quat::from_rotation_z(-0.4));
    arm.skeleton = Some(skeleton);
    arm.deformer.kind = DeformerKind::BonesBlending;
    arm.translation = Animated::constant(Vec3::new(-70.0, 40.0, 0.0));

    let mut cube = Object::new("Cube");
    cube.mesh = Some(MeshSource::Procedural(ProceduralMesh::Cube));
    cube.scale = Animated::constant(Vec3::splat(30.0));
    cube.translation = Animated::new(
        Vec3::ZERO,
        RawTrack::new(vec![
            Key::new(0.0, Vec3::new(60.0, 15.0, 60.0)),
            Key::new(0.5, Vec3::new(40.0, 30.0, 70.0)),
            Key::new(1.0, Vec3::new(20.0, 15.0, 60.0)),
        ]),
    );

    let light = |name: &str, kind, position: Vec3, direction: Vec3, intensity: f32| Light {
        name: name.into(),
        kind,
        enabled: true,
        position: Animated::constant(position),
        direction: Animated::constant(direction),
        colour: Animated::constant(Vec3::new(1.0, 0.95, 0.9)),
        intensity: Animated::constant(intensity),
    };
    Scene {
        fps: 30.0,
        frame_range: keyrig_core::FrameRange { start: 0, end: 30 },
        ambient: Vec3::splat(0.08),
        objects: vec![arm, cube],
        lights: vec![
            light(
                "Spot",
                LightKind::Spot { cutoff_deg: 40.0, inner_angle_deg: 25.0, dropoff: 2.0 },
                Vec3::new(0.0, 250.0, 150.0),
                Vec3::new(0.0, -250.0, -150.0),
                80000.0,
            ),
            light("Sun", LightKind::Directional, Vec3::ZERO, Vec3::new(-0.4, -1.0, -0.5), 0.6),
        ],
        camera: Camera {
            target: Vec3::new(0.0, 30.0, 0.0),
            yaw_deg: 25.0,
            pitch_deg: 20.0,
            distance: 320.0,
            fov_y_deg: 45.0,
        },
        sounds: Vec::new(),
    }
}

fn golden_dir() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("tests").join("golden")
}

fn compare(name: &str, actual: &image::RgbaImage) {
    let path = golden_dir().join(format!("{name}.png"));
    if std::env::var_os("KEYRIG_UPDATE_GOLDEN").is_some() {
        actual.save(&path).expect("write golden image");
        return;
    }
    let expected = image::open(&path)
        .unwrap_or_else(|e| panic!("{}: {e} (run with KEYRIG_UPDATE_GOLDEN=1 to create it)", path.display()))
        .to_rgba8();
    assert_eq!(expected.dimensions(), actual.dimensions(), "{name}: size");
    let differing = expected
        .pixels()
        .zip(actual.pixels())
        .filter(|(a, b)| a.0.iter().zip(b.0.iter()).any(|(x, y)| x.abs_diff(*y) > CHANNEL_TOLERANCE))
        .count();
    let fraction = differing as f64 / f64::from(WIDTH * HEIGHT);
    if fraction > PIXEL_FRACTION {
        let out = Path::new(env!("CARGO_TARGET_TMPDIR")).join(format!("{name}.actual.png"));
        actual.save(&out).expect("write actual image");
        panic!(
            "{name}: {differing} pixels ({:.2}%) differ from {} by more than {CHANNEL_TOLERANCE}; actual image: {}",
            fraction * 100.0,
            path.display(),
            out.display()
        );
    }
}

#[test]
fn golden_images_of_each_render_style() {
    let mut headless =
        HeadlessRenderer::new().unwrap_or_else(|e| panic!("GPU tests need a wgpu adapter: {e}"));
    let scene = test_scene();
    let rig = SceneRig::new(&scene).expect("scene rig");
    rig.upload(headless.renderer_mut()).expect("upload");
    for style in RenderStyle::ALL {
        let view = ViewOptions {
            style,
            selection: Some(Selected::Joint { object: 0, joint: 2 }),
            ..ViewOptions::default()
        };
        let frame = rig.frame(1.0, &view).expect("frame");
        let (image, stats) = headless.render_image(&frame, WIDTH, HEIGHT).expect("render");
        // Two skinned meshes: the arm (4 joints) and the cube (1 joint), 240 bytes per joint.
        assert_eq!(stats.joint_bytes, 5 * 240);
        assert_eq!(stats.deformed_vertices, 78 + 24);
        compare(&format!("scene_{}", style.cli_name()), &image);
    }
}

#[test]
fn the_lit_side_is_brighter_than_the_background() {
    let mut headless =
        HeadlessRenderer::new().unwrap_or_else(|e| panic!("GPU tests need a wgpu adapter: {e}"));
    let rig = SceneRig::new(&test_scene()).expect("scene rig");
    rig.upload(headless.renderer_mut()).expect("upload");
    let view = ViewOptions { grid: false, skeletons: false, motion_path: false, ..ViewOptions::default() };
    let frame = rig.frame(0.0, &view).expect("frame");
    let (image, _) = headless.render_image(&frame, WIDTH, HEIGHT).expect("render");
    let background = image.get_pixel(2, 2).0;
    let centre = image.get_pixel(WIDTH / 2, HEIGHT / 2 - 10).0;
    let luma = |p: [u8; 4]| u32::from(p[0]) + u32::from(p[1]) + u32::from(p[2]);
    assert!(luma(centre) > luma(background) + 60, "centre {centre:?} vs background {background:?}");
}
