//! `keyrig render` end to end: the demo scene to PNG (one frame and a range), an MD2 model from
//! the shared corpus through GPU morphing, and clear errors for bad arguments and files.
//!
//! Renders on the adapter wgpu finds (lavapipe without a GPU); no adapter fails these tests.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

fn keyrig(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_keyrig")).args(args).output().expect("run keyrig")
}

fn demo_scene() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo.ron")
}

fn stderr(out: &Output) -> String {
    String::from_utf8_lossy(&out.stderr).into_owned()
}

fn distinct_colours(image: &keyrig_render::image::RgbaImage) -> usize {
    let mut colours: Vec<[u8; 4]> = image.pixels().map(|p| p.0).collect();
    colours.sort_unstable();
    colours.dedup();
    colours.len()
}

#[test]
fn renders_one_frame_of_the_demo_scene() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("frame.png");
    let demo = demo_scene();
    let result = keyrig(&[
        "render",
        demo.to_str().expect("utf-8 path"),
        "--frame",
        "45",
        "--size",
        "320x180",
        "--deformer",
        "dual-quaternion",
        "--select",
        "joint:Arm/wrist",
        "-o",
        out.to_str().expect("utf-8 path"),
    ]);
    assert!(result.status.success(), "keyrig render failed: {}", stderr(&result));
    let image = keyrig_render::image::open(&out).expect("a PNG").to_rgba8();
    assert_eq!(image.dimensions(), (320, 180));
    // A lit mesh, a grid and a background: far more than a handful of colours.
    assert!(distinct_colours(&image) > 50, "the image looks empty");
}

#[test]
fn renders_a_numbered_range_with_a_pattern() {
    let dir = tempfile::tempdir().expect("tempdir");
    let pattern = dir.path().join("seq").join("arm_###.png");
    let demo = demo_scene();
    let result = keyrig(&[
        "render",
        demo.to_str().expect("utf-8 path"),
        "--frames",
        "10..12",
        "--size",
        "96x64",
        "--style",
        "wireframe",
        "-o",
        pattern.to_str().expect("utf-8 path"),
    ]);
    assert!(result.status.success(), "keyrig render failed: {}", stderr(&result));
    let mut images = Vec::new();
    for frame in 10..=12 {
        let path = dir.path().join("seq").join(format!("arm_{frame:03}.png"));
        images.push(
            keyrig_render::image::open(&path)
                .unwrap_or_else(|e| panic!("{}: {e}", path.display()))
                .to_rgba8(),
        );
    }
    // The arm moves between frames.
    assert_ne!(images[0], images[2]);
}

#[test]
fn renders_an_md2_model_through_gpu_morphing() {
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/md2");
    let model = std::fs::read_dir(&corpus)
        .unwrap_or_else(|e| {
            panic!("{}: {e} (the shared corpus must be beside the checkout)", corpus.display())
        })
        .filter_map(|entry| entry.ok().map(|e| e.path()))
        .flat_map(|p| {
            if p.is_dir() {
                std::fs::read_dir(&p)
                    .map(|d| d.filter_map(|e| e.ok().map(|e| e.path())).collect())
                    .unwrap_or_default()
            } else {
                vec![p]
            }
        })
        .find(|p| p.extension().is_some_and(|e| e.eq_ignore_ascii_case("md2")))
        .expect("an .md2 file in the corpus");
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("md2.png");
    let result = keyrig(&[
        "render",
        model.to_str().expect("utf-8 path"),
        "--frame",
        "4",
        "--size",
        "128x128",
        "-o",
        out.to_str().expect("utf-8 path"),
    ]);
    assert!(result.status.success(), "keyrig render {} failed: {}", model.display(), stderr(&result));
    let image = keyrig_render::image::open(&out).expect("a PNG").to_rgba8();
    assert!(distinct_colours(&image) > 20, "the image looks empty");
}

#[test]
fn renders_an_animated_gltf_model_with_its_skin() {
    let model = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf/CesiumMan/CesiumMan.glb");
    assert!(model.exists(), "{} is missing (the shared corpus must be beside the checkout)", model.display());
    let dir = tempfile::tempdir().expect("tempdir");
    let mut images = Vec::new();
    for frame in ["0", "12"] {
        let out = dir.path().join(format!("cesium_{frame}.png"));
        let result = keyrig(&[
            "render",
            model.to_str().expect("utf-8 path"),
            "--frame",
            frame,
            "--size",
            "128x128",
            "--deformer",
            "linear",
            "-o",
            out.to_str().expect("utf-8 path"),
        ]);
        assert!(result.status.success(), "keyrig render {} failed: {}", model.display(), stderr(&result));
        images.push(keyrig_render::image::open(&out).expect("a PNG").to_rgba8());
    }
    assert!(distinct_colours(&images[0]) > 20, "the image looks empty");
    // The walk cycle moves the figure between frames 0 and 12.
    assert_ne!(images[0], images[1]);
}

/// Distinct colours with each channel quantized to 16 levels: shading of one flat colour gives
/// a few dozen, a texture many more.
fn quantized_colours(image: &keyrig_render::image::RgbaImage) -> usize {
    let mut colours: Vec<[u8; 3]> = image.pixels().map(|p| [p.0[0] / 16, p.0[1] / 16, p.0[2] / 16]).collect();
    colours.sort_unstable();
    colours.dedup();
    colours.len()
}

/// Renders `model` at 256×256 without grid and skeleton, with or without textures.
fn render_model(model: &Path, dir: &Path, textures: bool) -> keyrig_render::image::RgbaImage {
    assert!(model.exists(), "{} is missing (the shared corpus must be beside the checkout)", model.display());
    let out = dir.join(format!("model_{textures}.png"));
    let mut args = vec![
        "render",
        model.to_str().expect("utf-8 path"),
        "--size",
        "256x256",
        "--no-grid",
        "--no-skeleton",
        "-o",
        out.to_str().expect("utf-8 path"),
    ];
    if !textures {
        args.push("--no-textures");
    }
    let result = keyrig(&args);
    assert!(result.status.success(), "keyrig render {} failed: {}", model.display(), stderr(&result));
    keyrig_render::image::open(&out).expect("a PNG").to_rgba8()
}

#[test]
fn models_render_with_their_textures_not_flat_grey() {
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus");
    let dir = tempfile::tempdir().expect("tempdir");
    // CesiumMan: a JPEG base-colour texture (white suit, green and blue panels); Fox: a PNG
    // one; ratamahatta: an MD2 model with its skin in skins/.
    for (model, factor) in
        [("gltf/CesiumMan/CesiumMan.glb", 3), ("gltf/Fox/Fox.glb", 2), ("md2/ratamahatta/ratamahatta.md2", 2)]
    {
        let model = corpus.join(model);
        let textured = quantized_colours(&render_model(&model, dir.path(), true));
        let plain = quantized_colours(&render_model(&model, dir.path(), false));
        assert!(plain < 60, "{}: --no-textures draws one lit colour, {plain} colours", model.display());
        assert!(
            textured > 60 && textured > factor * plain,
            "{}: {textured} colours textured, {plain} without: the texture is not drawn",
            model.display()
        );
    }
}

#[test]
fn bad_arguments_and_files_are_explained() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("x.png");
    let out = out.to_str().expect("utf-8 path");
    let demo = demo_scene();
    let demo = demo.to_str().expect("utf-8 path");

    let cases: [(&[&str], &str); 7] = [
        (&["render", demo, "--select", "joint:Arm/knee", "-o", out], "has no joint `knee`"),
        (&["render", demo, "--select", "camera", "-o", out], "expected object:NAME"),
        (&["render", demo, "--deformer", "wobbly", "-o", out], "--deformer `wobbly`"),
        (&["render", demo, "--size", "0x10", "-o", out], "between 1 and"),
        (&["render", demo, "--frames", "9..3", "-o", out], "after end"),
        (&["render", demo, "--frame", "NaN", "-o", out], "not a finite number"),
        (&["render", "/nonexistent/scene.ron", "-o", out], "/nonexistent/scene.ron"),
    ];
    for (args, expected) in cases {
        let result = keyrig(args);
        assert!(!result.status.success(), "{args:?} should fail");
        let message = stderr(&result);
        assert!(message.contains(expected), "{args:?}: expected `{expected}` in: {message}");
        assert!(!message.contains("panicked"), "{args:?} panicked: {message}");
    }

    // A scene file that is not RON at all.
    let broken = dir.path().join("broken.ron");
    std::fs::write(&broken, "(version: 1, scene: (fps: ").expect("write");
    let result = keyrig(&["render", broken.to_str().expect("utf-8 path"), "-o", out]);
    assert!(!result.status.success());
    assert!(stderr(&result).contains("broken.ron"), "{}", stderr(&result));
}

/// Issue 29: a scene made from a model (`keyrig import`) renders, whatever the model holds —
/// a skinned character, meshes without a skin (bound rigidly to one joint) or an MD2 model —
/// and shows what rendering the model file itself shows (an MD2 model on its own is drawn
/// about its centre, its scene stands it on the ground: only glTF pictures are compared).
#[test]
fn a_scene_made_from_any_model_renders_as_the_model_does() {
    let corpus = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus");
    let dir = tempfile::tempdir().expect("tempdir");
    for (n, model) in [
        "gltf/CesiumMan/CesiumMan.glb",
        "gltf/InterpolationTest/InterpolationTest.glb",
        "gltf/AnimatedMorphCube/AnimatedMorphCube.glb",
        "md2/sydney/sydney.md2",
    ]
    .into_iter()
    .enumerate()
    {
        let model = corpus.join(model);
        let scene = dir.path().join(format!("scene{n}.ron"));
        let imported =
            keyrig(&["import", model.to_str().expect("utf-8"), "-o", scene.to_str().expect("utf-8")]);
        assert!(imported.status.success(), "import {}: {}", model.display(), stderr(&imported));
        let render = |file: &Path, name: &str| {
            let out = dir.path().join(format!("{name}{n}.png"));
            let result = keyrig(&[
                "render",
                file.to_str().expect("utf-8"),
                "--frame",
                "10",
                "--size",
                "160x120",
                "-o",
                out.to_str().expect("utf-8"),
            ]);
            assert!(result.status.success(), "render {}: {}", file.display(), stderr(&result));
            keyrig_render::image::open(&out).expect("a PNG").to_rgba8()
        };
        let (from_model, from_scene) = (render(&model, "model"), render(&scene, "scene"));
        assert!(distinct_colours(&from_scene) > 20, "{}: the scene's image looks empty", model.display());
        if model.extension().is_some_and(|e| e == "md2") {
            continue;
        }
        let differ = from_model
            .pixels()
            .zip(from_scene.pixels())
            .filter(|(a, b)| a.0.iter().zip(b.0).any(|(x, y)| x.abs_diff(y) > 8))
            .count();
        assert!(
            differ * 100 < from_model.len() / 4,
            "{}: {differ} of {} pixels differ between the model and its scene",
            model.display(),
            from_model.len() / 4
        );
    }
}
