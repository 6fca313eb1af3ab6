//! `keyrig export` and `keyrig convert` end to end: the real binary on the demo scene and the
//! MD2 corpus, the Khronos glTF-Validator on what they write, and clear errors on bad input.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const KEYRIG: &str = env!("CARGO_BIN_EXE_keyrig");

fn demo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo.ron")
}

fn md2(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/md2").join(rel)
}

fn keyrig(args: &[&std::ffi::OsStr]) -> Output {
    Command::new(KEYRIG).args(args).output().expect("run keyrig")
}

fn os<S: AsRef<std::ffi::OsStr> + ?Sized>(s: &S) -> &std::ffi::OsStr {
    s.as_ref()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn assert_fails_with(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert!(!o.status.success(), "expected failure; stderr:\n{err}");
    assert!(!err.contains("panicked"), "panic:\n{err}");
    for n in needles {
        assert!(err.contains(n), "stderr lacks {n:?}:\n{err}");
    }
}

/// Zero errors from the Khronos glTF-Validator (tools/validate-gltf).
fn assert_valid(file: &Path) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/validate-gltf");
    assert!(
        dir.join("node_modules/gltf-validator").is_dir(),
        "the Khronos glTF-Validator is not installed: install Node.js (18 or newer) and run \
         `npm ci --prefix tools/validate-gltf` in the repository root"
    );
    let out = Command::new("node").arg(dir.join("validate.mjs")).arg(file).output().unwrap_or_else(|e| {
        panic!("cannot run `node` ({e}): install Node.js (18 or newer) and run `npm ci --prefix tools/validate-gltf`")
    });
    let report = String::from_utf8_lossy(&out.stdout);
    assert!(out.status.success() && report.contains("\"errors\":0"), "{}: {report}", file.display());
}

#[test]
fn export_writes_a_valid_glb_and_gltf_of_the_demo_scene() {
    let dir = tempfile::tempdir().expect("tempdir");
    for name in ["demo.glb", "demo.gltf"] {
        let out = dir.path().join(name);
        let o = keyrig(&[os("export"), demo().as_os_str(), os("-o"), out.as_os_str()]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert_valid(&out);
        let model = keyrig_io::gltf_import::import_gltf_file(&out).expect("imports");
        assert_eq!(model.skins.len(), 1, "the arm's skin");
        assert_eq!(model.lights.len(), 2);
        assert_eq!(model.animations.len(), 1);
    }
}

fn gltf(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf").join(rel)
}

#[test]
fn models_export_and_import_directly() {
    let dir = tempfile::tempdir().expect("tempdir");
    // export and convert take a model file directly (export used to fail with "not UTF-8 text").
    let fox = gltf("Fox/Fox.glb");
    for (command, name, extra) in [
        ("export", "fox.glb", None),
        ("export", "fox-baked.gltf", Some("--bake")),
        ("convert", "fox-converted.glb", None),
    ] {
        let out = dir.path().join(name);
        let mut args = vec![os(command), fox.as_os_str(), os("-o"), out.as_os_str()];
        args.extend(extra.map(os));
        let o = keyrig(&args);
        assert!(o.status.success(), "{command} {name}: {}", stderr(&o));
        assert_valid(&out);
        let model = keyrig_io::gltf_import::import_gltf_file(&out).expect("imports");
        assert_eq!(model.skins.len(), 1, "{name}: the fox's skin");
        assert_eq!(model.skins[0].joints.len(), 24 + 1, "{name}: its 24 joints and the root node above them");
        assert_eq!(model.images.len(), 1, "{name}: its texture");
    }
    let o = keyrig(&[
        os("export"),
        md2("dolphin/dolphin.md2").as_os_str(),
        os("-o"),
        dir.path().join("d.glb").as_os_str(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_valid(&dir.path().join("d.glb"));

    // import makes a scene file that refers to the model relative to the scene's folder.
    let model = dir.path().join("Fox.glb");
    std::fs::copy(&fox, &model).expect("copy");
    let scene = dir.path().join("fox.ron");
    let o =
        keyrig(&[os("import"), model.as_os_str(), os("-o"), scene.as_os_str(), os("--animation"), os("1")]);
    assert!(o.status.success(), "{}", stderr(&o));
    let loaded = keyrig_io::scene_file::load(&scene).expect("scene loads");
    assert!(
        matches!(&loaded.objects[0].mesh, Some(keyrig_core::MeshSource::File { path, .. }) if path == "Fox.glb"),
        "{:?}",
        loaded.objects[0].mesh
    );
    assert_eq!(loaded.frame_range.end, 22, "the Walk animation (23 frames at 30 fps)");
    let out = dir.path().join("fox-from-scene.glb");
    let o = keyrig(&[os("export"), scene.as_os_str(), os("-o"), out.as_os_str()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_valid(&out);
    // import never writes over its model, and wants a .ron output.
    assert_fails_with(
        &keyrig(&[os("import"), model.as_os_str(), os("-o"), model.as_os_str()]),
        &["Fox.glb", ".ron"],
    );
    assert_fails_with(
        &keyrig(&[os("import"), model.as_os_str(), os("-o"), scene.as_os_str(), os("--animation"), os("9")]),
        &["--animation 9", "3 animation"],
    );
}

#[test]
fn convert_writes_valid_morph_animation_of_an_md2() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("rat.glb");
    let o =
        keyrig(&[os("convert"), md2("ratamahatta/ratamahatta.md2").as_os_str(), os("-o"), out.as_os_str()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("16 clips"), "{}", stderr(&o));
    assert_valid(&out);
    let model = keyrig_io::gltf_import::import_gltf_file(&out).expect("imports");
    assert_eq!(model.animations.len(), 16);
    assert_eq!(model.animations[1].name, "run");
}

#[test]
fn bad_inputs_fail_with_the_file_and_the_place() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("x.glb");
    // Missing scene.
    let missing = dir.path().join("missing.ron");
    assert_fails_with(
        &keyrig(&[os("export"), missing.as_os_str(), os("-o"), out.as_os_str()]),
        &["missing.ron"],
    );
    // Wrong output extension.
    assert_fails_with(
        &keyrig(&[os("export"), demo().as_os_str(), os("-o"), os("out.obj")]),
        &["out.obj", ".glb"],
    );
    // A truncated MD2: the byte offset of the problem.
    let bytes = std::fs::read(md2("dolphin/dolphin.md2")).expect("read");
    let bad = dir.path().join("bad.md2");
    std::fs::write(&bad, &bytes[..1000]).expect("write");
    assert_fails_with(
        &keyrig(&[os("convert"), bad.as_os_str(), os("-o"), out.as_os_str()]),
        &["bad.md2", "byte 64"],
    );
    // Not an MD2.
    assert_fails_with(
        &keyrig(&[os("convert"), demo().as_os_str(), os("-o"), out.as_os_str()]),
        &["only .md2"],
    );
    // A bad frame rate.
    let o = keyrig(&[
        os("convert"),
        md2("dolphin/dolphin.md2").as_os_str(),
        os("-o"),
        out.as_os_str(),
        os("--fps"),
        os("0"),
    ]);
    assert_fails_with(&o, &["fps"]);
    // A scene with a syntax error: line and column.
    let broken = dir.path().join("broken.ron");
    std::fs::write(&broken, "(version: 1, fps: 30.0,, )").expect("write");
    assert_fails_with(
        &keyrig(&[os("export"), broken.as_os_str(), os("-o"), out.as_os_str()]),
        &["broken.ron"],
    );
}

#[test]
fn outputs_never_replace_an_input_or_a_model_the_scene_uses() {
    let dir = tempfile::tempdir().expect("tempdir");
    // A scene whose cube is a glTF model beside it.
    let model = dir.path().join("rigged.glb");
    std::fs::copy(
        Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf/RiggedSimple/RiggedSimple.glb"),
        &model,
    )
    .expect("copy model");
    let before = std::fs::read(&model).expect("read model");
    let text = std::fs::read_to_string(demo())
        .expect("demo")
        .replace("mesh: Some(Procedural(Cube)),", "mesh: Some(File(path: \"rigged.glb\")),");
    let scene = dir.path().join("scene.ron");
    std::fs::write(&scene, text).expect("scene");
    assert_fails_with(
        &keyrig(&[os("export"), scene.as_os_str(), os("-o"), model.as_os_str()]),
        &["rigged.glb", "refusing to overwrite the model file that objects[1] (`Cube`) uses"],
    );
    // The same file through another path.
    let dotted = dir.path().join(".").join("rigged.glb");
    assert_fails_with(
        &keyrig(&[os("export"), scene.as_os_str(), os("-o"), dotted.as_os_str()]),
        &["refusing to overwrite the model file"],
    );
    assert_eq!(std::fs::read(&model).expect("read model"), before, "the model is untouched");
    // convert never replaces its model or the model's skin.
    let folder = dir.path().join("sydney");
    std::fs::create_dir(&folder).expect("mkdir");
    for name in ["sydney.md2", "sydney.bmp"] {
        std::fs::copy(md2("sydney").join(name), folder.join(name)).expect("copy");
    }
    let skin = folder.join("sydney.bmp");
    let o = keyrig(&[
        os("convert"),
        folder.join("sydney.md2").as_os_str(),
        os("-o"),
        folder.join("sydney.gltf").as_os_str(),
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    // deform refuses its own input.
    let o = keyrig(&[
        os("deform"),
        scene.as_os_str(),
        os("--frame"),
        os("1"),
        os("--deformer"),
        os("linear"),
        os("-o"),
        scene.as_os_str(),
    ]);
    assert!(!o.status.success());
    assert!(skin.exists());
}

#[test]
fn frame_rates_far_out_of_range_are_refused_with_a_short_message() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("x.glb");
    for fps in ["1e300", "-10", "1e-300"] {
        let o = keyrig(&[
            os("convert"),
            md2("dolphin/dolphin.md2").as_os_str(),
            os("-o"),
            out.as_os_str(),
            os("--fps"),
            os(fps),
        ]);
        assert_fails_with(&o, &["--fps", "must be between 0.01 and 1000 frames per second"]);
        assert!(stderr(&o).len() < 300, "{}", stderr(&o));
    }
    assert!(!out.exists());
}

/// Kills `keyrig export` at times spread over its run while it replaces an existing file:
/// the file must always be the old one or the complete new one, never a truncated mix.
#[test]
fn an_export_killed_during_the_write_leaves_the_old_or_the_new_file() {
    let dir = tempfile::tempdir().expect("tempdir");
    let out = dir.path().join("demo.gltf");
    let run = |tolerance: &str| {
        let mut command = Command::new(KEYRIG);
        command.args([
            os("export"),
            demo().as_os_str(),
            os("-o"),
            out.as_os_str(),
            os("--rotation-tolerance"),
            os(tolerance),
        ]);
        command
    };
    // The old file (coarse rotation tolerance) and the new one (fine): different bytes.
    assert!(run("1").status().expect("run").success());
    let old = std::fs::read(&out).expect("old");
    let start = std::time::Instant::now();
    assert!(run("0.001").status().expect("run").success());
    let whole = start.elapsed();
    let new = std::fs::read(&out).expect("new");
    assert_ne!(old, new);
    let mut outcomes = [0usize; 2];
    for trial in 0..20u32 {
        std::fs::write(&out, &old).expect("reset");
        let mut child = run("0.001").spawn().expect("spawn");
        std::thread::sleep(whole * trial / 20);
        let _ = child.kill();
        let _ = child.wait();
        let now = std::fs::read(&out).expect("the target is never removed");
        assert!(
            now == old || now == new,
            "trial {trial}: {} bytes, neither the old nor the new file",
            now.len()
        );
        outcomes[usize::from(now == new)] += 1;
    }
    eprintln!("killed exports: {} left the old file, {} the new one", outcomes[0], outcomes[1]);
}

fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus").join(rel)
}

/// Issue 40: the commands read BVH takes and FBX models. `info` describes them, `import` writes
/// a scene that loads with the same joints, `export -o take.bvh` writes a take that reads back
/// to the same poses (sampled with `keyrig sample` at three frames), and `deform` of an FBX
/// skin at a frame writes its mesh. A file that is neither is refused with its name.
#[test]
fn bvh_takes_and_fbx_models_through_the_commands() {
    let dir = tempfile::tempdir().expect("temp dir");
    let take = corpus("bvh/cmu-bvh11/131_01.bvh");
    let info = keyrig(&[os("info"), take.as_os_str()]);
    assert!(info.status.success(), "{}", stderr(&info));
    let text = String::from_utf8_lossy(&info.stdout);
    assert!(text.contains("BVH motion capture take") && text.contains("120 fps"), "{text}");
    assert!(text.contains("38 joints"), "31 joints and 7 End Sites: {text}");

    let scene = dir.path().join("take.ron");
    let out = keyrig(&[os("import"), take.as_os_str(), os("-o"), scene.as_os_str()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let imported = keyrig_io::scene_file::load(&scene).expect("the imported scene loads");
    let skeleton = imported.objects[0].skeleton.as_ref().expect("a skeleton");
    assert_eq!(skeleton.joints.len(), 38);
    assert!(skeleton.joints.iter().any(|j| j.rotation_euler.is_some()), "Euler keys as in the file");

    // Named as the take: a take's object is named after its file.
    std::fs::create_dir(dir.path().join("out")).expect("a folder");
    let again = dir.path().join("out/131_01.bvh");
    let out = keyrig(&[os("export"), scene.as_os_str(), os("-o"), again.as_os_str()]);
    assert!(out.status.success(), "{}", stderr(&out));
    let sample = |file: &Path| {
        let out = keyrig(&[
            os("sample"),
            file.as_os_str(),
            os("--channel"),
            os("object/131_01/joint/LeftKnee/rotation"),
            os("--frames"),
            os("0..600"),
            os("--step"),
            os("300"),
        ]);
        assert!(out.status.success(), "{}", stderr(&out));
        String::from_utf8_lossy(&out.stdout).lines().skip(1).map(str::to_owned).collect::<Vec<_>>()
    };
    let (a, b) = (sample(&take), sample(&again));
    assert_eq!(a.len(), 3, "{a:?}");
    for (x, y) in a.iter().zip(&b) {
        let nums =
            |l: &str| l.split(',').skip(2).map(|v| v.parse::<f64>().expect("a number")).collect::<Vec<_>>();
        for (p, q) in nums(x).iter().zip(nums(y)) {
            assert!((p - q).abs() < 1e-4 || (p + q).abs() < 1e-4, "{x} vs {y}");
        }
    }

    let fbx = corpus("fbx/ufbx/max7_skin_5000_binary.fbx");
    let info = keyrig(&[os("info"), fbx.as_os_str()]);
    assert!(info.status.success(), "{}", stderr(&info));
    assert!(String::from_utf8_lossy(&info.stdout).contains("FBX model"));
    let obj = dir.path().join("max7.obj");
    let out = keyrig(&[
        os("deform"),
        fbx.as_os_str(),
        os("--frame"),
        os("5"),
        os("--deformer"),
        os("linear"),
        os("-o"),
        obj.as_os_str(),
    ]);
    assert!(out.status.success(), "{}", stderr(&out));
    let vertices =
        std::fs::read_to_string(&obj).expect("the OBJ").lines().filter(|l| l.starts_with("v ")).count();
    assert!(vertices > 100, "{vertices} vertices");

    let junk = dir.path().join("junk.fbx");
    std::fs::write(&junk, b"not an fbx file at all").expect("write");
    assert_fails_with(&keyrig(&[os("info"), junk.as_os_str()]), &["junk.fbx"]);
    let junk = dir.path().join("junk.bvh");
    std::fs::write(&junk, b"HIERARCHY\nROOT Hips\n{\n").expect("write");
    assert_fails_with(&keyrig(&[os("info"), junk.as_os_str()]), &["junk.bvh"]);
}

/// Issue 42, 14: `keyrig import --scale` scales the model about the origin on top of its file's
/// unit: the Fox, modelled in centimetres, at 0.01 is the same scene a hundredth the size (its
/// object's scale and place, its framed view), which renders the same picture; 0, a negative
/// scale, NaN and text are refused with the option's name.
#[test]
fn import_scale_scales_the_model_and_refuses_bad_factors() {
    let dir = tempfile::tempdir().expect("tempdir");
    let fox = gltf("Fox/Fox.glb");
    let import = |name: &str, scale: Option<&str>| {
        let scene = dir.path().join(name);
        let mut args = vec![os("import"), fox.as_os_str(), os("-o"), scene.as_os_str()];
        if let Some(scale) = scale {
            args.extend([os("--scale"), os(scale)]);
        }
        let o = keyrig(&args);
        assert!(o.status.success(), "{name}: {}", stderr(&o));
        (scene.clone(), keyrig_io::scene_file::load(&scene).expect("scene loads"))
    };
    let (large_file, large) = import("large.ron", None);
    let (small_file, small) = import("small.ron", Some("0.01"));
    assert_eq!(large.objects.len(), small.objects.len());
    for (l, s) in large.objects.iter().zip(&small.objects) {
        assert!((s.scale.value - l.scale.value * 0.01).length() < 1e-6, "{}", s.name);
        assert!((s.translation.value - l.translation.value * 0.01).length() < 1e-4, "{}", s.name);
        // Inside the object nothing changes: its scale carries the skeleton and its keys.
        assert_eq!(s.skeleton, l.skeleton, "{}", s.name);
    }
    assert!((small.camera.distance - large.camera.distance * 0.01).abs() < 1e-3 * large.camera.distance);
    assert!((small.camera.target - large.camera.target * 0.01).length() < 1e-3 * large.camera.distance);

    // The same picture, a hundredth the size: the skinned mesh is scaled with its object.
    let render = |scene: &Path, name: &str| {
        let out = dir.path().join(name);
        let o = keyrig(&[
            os("render"),
            scene.as_os_str(),
            os("--frame"),
            os("10"),
            os("--size"),
            os("160x120"),
            os("-o"),
            out.as_os_str(),
        ]);
        assert!(o.status.success(), "render {name}: {}", stderr(&o));
        keyrig_render::image::open(&out).expect("a PNG").to_rgba8()
    };
    let (a, b) = (render(&large_file, "large.png"), render(&small_file, "small.png"));
    let differing = a
        .pixels()
        .zip(b.pixels())
        .filter(|(p, q)| p.0.iter().zip(q.0).any(|(x, y)| x.abs_diff(y) > 24))
        .count();
    let fox_pixels = a.pixels().zip(a.pixels().skip(1)).filter(|(p, q)| p != q).count();
    assert!(fox_pixels > 100, "the Fox is drawn");
    assert!(differing * 50 < a.pixels().len(), "{differing} of {} pixels differ", a.pixels().len());

    for bad in ["0", "-1", "NaN", "inf", "cm"] {
        let out = dir.path().join("bad.ron");
        assert_fails_with(
            &keyrig(&[os("import"), fox.as_os_str(), os("-o"), out.as_os_str(), os("--scale"), os(bad)]),
            &["--scale", "import scale"],
        );
        assert!(!out.exists(), "{bad}: nothing written");
    }
}
