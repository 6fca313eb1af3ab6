//! `keyrig render` through scene cameras (issue 31): the active camera at each frame by default
//! (switched by a marker), `--camera NAME`, `--view`, and the scene's render size; the size
//! of a unit cube in the image checked against the pinhole and orthographic projections
//! worked out here; `keyrig sample` of camera channels; clear errors.
//!
//! Renders on the adapter wgpu finds (lavapipe without a GPU).

use std::path::Path;
use std::process::{Command, Output};

use glam::{Quat, Vec3};
use keyrig_core::{
    Aim, AimTarget, Animated, Key, Light, LightKind, Marker, MeshSource, Object, ProceduralMesh, Projection,
    RawTrack, RenderSize, Scene, SceneCamera,
};
use keyrig_render::image::RgbaImage;

fn keyrig(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_keyrig")).args(args).output().expect("run keyrig")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

/// A unit cube at the origin; "On" looks at it from 5 units down +Z (40° field of view), "Off"
/// stands there looking away; "Ortho" looks at it orthographically with a view 4 units tall.
/// A marker at frame 10 switches to "Off".
fn scene() -> Scene {
    let mut cube = Object::new("Cube");
    cube.mesh = Some(MeshSource::Procedural(ProceduralMesh::Cube));
    let mut on = SceneCamera::new("On", Vec3::new(0.0, 0.0, 5.0));
    on.aim = Some(Aim::at(AimTarget::Object("Cube".into())));
    let mut off = SceneCamera::new("Off", Vec3::new(0.0, 0.0, 5.0));
    off.rotation = Animated::constant(Quat::from_rotation_y(std::f32::consts::PI));
    let mut ortho = SceneCamera::new("Ortho", Vec3::new(0.0, 0.0, 30.0));
    ortho.projection = Projection::Orthographic;
    ortho.lens = Animated::constant(4.0);
    Scene {
        objects: vec![cube],
        lights: vec![Light {
            name: "Front".into(),
            kind: LightKind::Directional,
            enabled: true,
            position: Animated::constant(Vec3::new(0.0, 0.0, 60.0)),
            direction: Animated::constant(Vec3::new(0.0, 0.0, -1.0)),
            colour: Animated::constant(Vec3::ONE),
            intensity: Animated::constant(1.0),
            attributes: Default::default(),
        }],
        cameras: vec![on, off, ortho],
        markers: vec![Marker { name: "away".into(), frame: 10, camera: Some("Off".into()) }],
        render_size: Some(RenderSize { width: 200, height: 100 }),
        ..Scene::default()
    }
}

fn write_scene(dir: &Path, scene: &Scene) -> String {
    let path = dir.join("cameras.ron");
    keyrig_io::scene_file::save(&path, scene).expect("save");
    path.to_str().expect("utf-8 path").to_owned()
}

fn render(scene: &str, dir: &Path, extra: &[&str]) -> RgbaImage {
    let out = dir.join("out.png");
    let mut args = vec!["render", scene, "--no-grid", "-o", out.to_str().expect("utf-8 path")];
    args.extend_from_slice(extra);
    let result = keyrig(&args);
    assert!(result.status.success(), "keyrig render {extra:?} failed: {}", stderr(&result));
    keyrig_render::image::open(&out).expect("a PNG").to_rgba8()
}

fn differs(a: [u8; 4], b: [u8; 4]) -> bool {
    a.iter().zip(&b).any(|(x, y)| x.abs_diff(*y) > 12)
}

/// Pixels of the middle row and column that are not the background (the corner's colour).
fn extent(image: &RgbaImage) -> (u32, u32) {
    let background = image.get_pixel(0, 0).0;
    let (w, h) = image.dimensions();
    let row = (0..w).filter(|&x| differs(image.get_pixel(x, h / 2).0, background)).count();
    let column = (0..h).filter(|&y| differs(image.get_pixel(w / 2, y).0, background)).count();
    (row as u32, column as u32)
}

#[test]
fn renders_through_the_active_camera_at_each_frame() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = write_scene(dir.path(), &scene());
    // Frame 0: "On" (the first camera), at the scene's render size.
    let image = render(&scene, dir.path(), &["--frame", "0"]);
    assert_eq!(image.dimensions(), (200, 100));
    // The cube's front face is 4.5 units away, seen with a 40° vertical field of view: the
    // view is 2·4.5·tan 20° = 3.2757 units tall, so the unit face covers 100/3.2757 = 30.5
    // pixels each way (square pixels: the horizontal field follows the aspect).
    let (wide, tall) = extent(&image);
    let expected = 100.0 / (2.0 * 4.5 * 20f64.to_radians().tan());
    for got in [wide, tall] {
        assert!((f64::from(got) - expected).abs() <= 2.0, "{wide}×{tall} pixels, expected {expected:.1}");
    }
    // Frame 10: the marker switched to "Off", which looks away: nothing but background.
    assert_eq!(extent(&render(&scene, dir.path(), &["--frame", "10"])), (0, 0));
    // --camera chooses, at any frame; --size overrides the render size.
    assert_eq!(extent(&render(&scene, dir.path(), &["--frame", "0", "--camera", "Off"])), (0, 0));
    let image = render(&scene, dir.path(), &["--frame", "10", "--camera", "Ortho", "--size", "300x100"]);
    assert_eq!(image.dimensions(), (300, 100));
    // Orthographic, 4 units tall: the unit cube is a quarter of the height, 25 pixels, and as
    // wide, whatever its distance.
    let (wide, tall) = extent(&image);
    assert!(wide.abs_diff(25) <= 2 && tall.abs_diff(25) <= 2, "{wide}×{tall}");
    // --view: the saved viewport view (orbiting the origin) sees the cube at frame 10 too.
    let (wide, _) = extent(&render(&scene, dir.path(), &["--frame", "10", "--view"]));
    assert!(wide > 10, "the view sees the cube");
}

#[test]
fn a_range_switches_cameras_at_the_marker() {
    let dir = tempfile::tempdir().expect("tempdir");
    let scene = write_scene(dir.path(), &scene());
    let pattern = dir.path().join("seq_##.png");
    let result = keyrig(&[
        "render",
        &scene,
        "--no-grid",
        "--frames",
        "9..10",
        "-o",
        pattern.to_str().expect("utf-8 path"),
    ]);
    assert!(result.status.success(), "{}", stderr(&result));
    let frame =
        |n: u32| keyrig_render::image::open(dir.path().join(format!("seq_{n:02}.png"))).unwrap().to_rgba8();
    assert!(extent(&frame(9)).0 > 20, "frame 9 through On");
    assert_eq!(extent(&frame(10)), (0, 0), "frame 10 through Off");
}

#[test]
fn camera_channels_sample_and_bad_cameras_are_explained() {
    let dir = tempfile::tempdir().expect("tempdir");
    let mut s = scene();
    s.cameras[0].lens.track = RawTrack::new(vec![Key::new(0.0, 40.0), Key::new(1.0, 20.0)]);
    let scene = write_scene(dir.path(), &s);
    let result = keyrig(&["sample", &scene, "--channel", "camera/On/lens", "--frame", "30"]);
    assert!(result.status.success(), "{}", stderr(&result));
    let text = String::from_utf8_lossy(&result.stdout);
    assert_eq!(text.trim(), "frame,time,value\n30,1,20");

    let out = dir.path().join("x.png");
    let out = out.to_str().expect("utf-8 path");
    let cases: [(&[&str], &str); 4] = [
        (
            &["render", &scene, "--camera", "Wide", "-o", out],
            "no camera named `Wide` (cameras: On, Off, Ortho)",
        ),
        (&["render", &scene, "--camera", "On", "--view", "-o", out], "cannot be used with"),
        (&["sample", &scene, "--channel", "camera/Off/roll", "--frame", "0"], "has no aim constraint"),
        (&["sample", &scene, "--channel", "camera/Wide/lens", "--frame", "0"], "no camera named \"Wide\""),
    ];
    for (args, expected) in cases {
        let result = keyrig(args);
        assert!(!result.status.success(), "{args:?} should fail");
        let message = stderr(&result);
        assert!(message.contains(expected), "{args:?}: expected `{expected}` in: {message}");
    }
    let demo = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo.ron");
    let result = keyrig(&["render", demo.to_str().unwrap(), "--camera", "On", "-o", out]);
    assert!(stderr(&result).contains("the scene has no cameras"), "{}", stderr(&result));
}
