//! `keyrig info` and `keyrig sample` end to end: the real binary on the demo scene and on bad
//! files and arguments.

use std::path::{Path, PathBuf};
use std::process::{Command, Output};

const KEYRIG: &str = env!("CARGO_BIN_EXE_keyrig");

fn demo() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo.ron")
}

fn keyrig(args: &[&str]) -> Output {
    Command::new(KEYRIG).args(args).output().expect("run keyrig")
}

fn stdout(o: &Output) -> String {
    String::from_utf8_lossy(&o.stdout).into_owned()
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// A failed run: non-zero exit, no panic, and stderr containing every `needle`.
fn assert_fails_with(o: &Output, needles: &[&str]) {
    let err = stderr(o);
    assert!(!o.status.success(), "expected failure, got success; stdout:\n{}", stdout(o));
    assert!(!err.contains("panicked"), "panic:\n{err}");
    for n in needles {
        assert!(err.contains(n), "stderr lacks {n:?}:\n{err}");
    }
}

fn write_temp(dir: &tempfile::TempDir, name: &str, text: &str) -> PathBuf {
    let path = dir.path().join(name);
    std::fs::write(&path, text).expect("write temp file");
    path
}

#[test]
fn info_summarizes_the_demo() {
    let demo = demo();
    let o = keyrig(&["info", demo.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    for needle in [
        "timing:   30 fps, frames 0..=90 (91 frames, 3.000 s)",
        "\"Arm\": mesh procedural ArmHighPoly, deformer bones-blending",
        "skeleton: 4 joints",
        "[2] \"forearm\": parent \"elbow\"",
        "\"Key\": spot (cutoff 35°",
        "\"Sun\": directional",
        "tracks:   8 animated of 19 channels, 37 keys",
        "object/Arm/joint/forearm/rotation   8 keys, 0.000..3.000 s",
        "problems: none",
    ] {
        assert!(out.contains(needle), "info lacks {needle:?}:\n{out}");
    }
}

#[test]
fn info_json() {
    let demo = demo();
    let o = keyrig(&["info", demo.to_str().unwrap(), "--format", "json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("info --format json is JSON");
    assert_eq!(v["fps"], 30.0);
    assert_eq!(v["frame_range"], serde_json::json!([0, 90]));
    assert_eq!(v["duration_s"], 3.0);
    assert_eq!(v["keys"], 37);
    assert_eq!(v["objects"][0]["joints"].as_array().map(Vec::len), Some(4));
    assert_eq!(v["lights"].as_array().map(Vec::len), Some(2));
    assert_eq!(v["problems"], serde_json::json!([]));
}

#[test]
fn info_lists_problems_with_place_and_fails() {
    let dir = tempfile::tempdir().unwrap();
    // Key 1 comes before key 0; the light's intensity is negative.
    let text = r#"(
    version: 1,
    scene: (
        fps: 24.0,
        frame_range: (start: 0, end: 48),
        objects: [
            (
                name: "Box",
                translation: (
                    value: (0.0, 0.0, 0.0),
                    track: [
                        (time: 1.0, value: (0.0, 0.0, 0.0)),
                        (time: 0.5, value: (1.0, 0.0, 0.0)),
                    ],
                ),
                rotation: (value: (0.0, 0.0, 0.0, 1.0)),
                scale: (value: (1.0, 1.0, 1.0)),
            ),
        ],
        lights: [
            (
                name: "Lamp",
                kind: Point,
                position: (value: (0.0, 2.0, 0.0)),
                direction: (value: (0.0, -1.0, 0.0)),
                colour: (value: (1.0, 1.0, 1.0)),
                intensity: (value: -3.0),
            ),
        ],
    ),
)
"#;
    let path = write_temp(&dir, "bad.ron", text);
    let o = keyrig(&["info", path.to_str().unwrap()]);
    assert_fails_with(&o, &["bad.ron: 2 validation problems"]);
    let out = stdout(&o);
    assert!(out.contains("problems: 2"), "{out}");
    assert!(out.contains("bad.ron:13:32: objects[0].translation.track[1].time: keys out of order"), "{out}");
    assert!(out.contains("bad.ron:27:36: lights[0].intensity.value: negative intensity -3"), "{out}");
    // `sample` still samples a valid channel of that scene, with a warning.
    let o = keyrig(&["sample", path.to_str().unwrap(), "--channel", "light/Lamp/position", "--frame", "0"]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stderr(&o).contains("2 validation problems"), "{}", stderr(&o));
    assert_eq!(stdout(&o), "frame,time,x,y,z\n0,0,0,2,0\n");
    // … but not the invalid one, and says which key is wrong.
    let o =
        keyrig(&["sample", path.to_str().unwrap(), "--channel", "object/Box/translation", "--frame", "0"]);
    assert_fails_with(&o, &["objects[0].translation.track[1].time", "earlier than the previous key"]);
}

#[test]
fn bad_files_name_file_place_and_problem() {
    let dir = tempfile::tempdir().unwrap();
    let cases: [(&str, &str, &[&str]); 5] = [
        ("syntax.ron", "(\n    version: 1,\n    scene: (fps: 30.0,, )\n)\n", &["syntax.ron:3:"]),
        (
            "truncated.ron",
            "(\n    version: 1,\n    scene: (\n        fps: 30.0,\n",
            &["truncated.ron:", "truncated"],
        ),
        ("newer.ron", "(version: 7, scene: (future: true))\n", &["newer.ron:1:11:", "version 7 is newer"]),
        (
            "unknown.ron",
            "(version: 1, scene: (fps: 30.0, frame_range: (start: 0, end: 1), colour_grading: 2))\n",
            &["unknown.ron:1:", "colour_grading"],
        ),
        (
            "nan.ron",
            "(version: 1, scene: (fps: NaN, frame_range: (start: 0, end: 1)))\n",
            &["nan.ron", "1:27:", "fps: not a finite number"],
        ),
    ];
    for (name, text, needles) in cases {
        let path = write_temp(&dir, name, text);
        let o = keyrig(&["info", path.to_str().unwrap()]);
        let err = stderr(&o) + &stdout(&o);
        assert!(!o.status.success(), "{name}: expected failure");
        assert!(!err.contains("panicked"), "{name}: panic:\n{err}");
        for n in needles {
            assert!(err.contains(n), "{name}: output lacks {n:?}:\n{err}");
        }
    }
    let missing = dir.path().join("missing.ron");
    assert_fails_with(&keyrig(&["info", missing.to_str().unwrap()]), &["missing.ron: cannot read"]);
    let glb = write_temp(&dir, "model.glb", "glTF");
    assert_fails_with(
        &keyrig(&["info", glb.to_str().unwrap()]),
        &["model.glb: byte 0: GLB container: file is 4 bytes, shorter than the 12-byte header"],
    );
    let md2 = write_temp(&dir, "model.md2", "IDP2");
    assert_fails_with(&keyrig(&["info", md2.to_str().unwrap()]), &["model.md2: byte 0: file is 4 bytes"]);
    assert_fails_with(
        &keyrig(&["sample", md2.to_str().unwrap(), "--channel", "object/A/rotation", "--frame", "1"]),
        &["model.md2: MD2 models hold vertex animation"],
    );
    let txt = write_temp(&dir, "notes.txt", "hello");
    assert_fails_with(
        &keyrig(&["sample", txt.to_str().unwrap(), "--frame", "1"]),
        &["notes.txt: unknown file type"],
    );
}

#[test]
fn sample_csv_over_frames_passes_through_keys() {
    let demo = demo();
    let o = keyrig(&[
        "sample",
        demo.to_str().unwrap(),
        "--channel",
        "object/Arm/joint/forearm/rotation",
        "--frames",
        "0..90",
        "--step",
        "10",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines[0], "frame,time,x,y,z,w");
    assert_eq!(lines.len(), 1 + 10, "{out}");
    assert_eq!(lines[1], "0,0,0,0,0,1");
    // Frame 60 is the 180° twist key: q = (1, 0, 0, 0) up to f32 rounding of the key.
    let row: Vec<f64> = lines[7].split(',').map(|c| c.parse().unwrap()).collect();
    assert_eq!(row[0], 60.0);
    assert!((row[1] - 2.0).abs() < 1e-12);
    assert!((row[2].abs() - 1.0).abs() < 1e-6 && row[5].abs() < 1e-6, "{}", lines[7]);
}

#[test]
fn sample_euler_degrees_and_times() {
    let demo = demo();
    let o = keyrig(&[
        "sample",
        demo.to_str().unwrap(),
        "--channel",
        "object/Arm/joint/elbow/rotation",
        "--times",
        "0.5..1.5",
        "--step",
        "0.5",
        "--rotation-format",
        "euler",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines[0], "frame,time,x_deg,y_deg,z_deg");
    // Keys: 45° at 0.5 s, 90° at 1.0 s and 1.5 s, about −Z.
    let z: Vec<f64> = lines[1..].iter().map(|l| l.split(',').nth(4).unwrap().parse().unwrap()).collect();
    assert_eq!(z.len(), 3);
    for (got, want) in z.iter().zip([-45.0, -90.0, -90.0]) {
        assert!((got - want).abs() < 1e-3, "{out}");
    }
    assert!(lines[1].starts_with("15,0.5,"), "{out}");
}

#[test]
fn sample_json() {
    let demo = demo();
    let o = keyrig(&[
        "sample",
        demo.to_str().unwrap(),
        "--channel",
        "object/Cube/translation",
        "--frames",
        "0..2",
        "--format",
        "json",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(v["channel"], "object/Cube/translation");
    assert_eq!(v["field"], "objects[1].translation");
    assert_eq!(v["columns"], serde_json::json!(["x", "y", "z"]));
    assert_eq!(v["keys"], 5);
    let samples = v["samples"].as_array().expect("samples");
    assert_eq!(samples.len(), 3);
    assert_eq!(samples[0]["value"], serde_json::json!([-0.8f32, 0.3f32, 0.8f32]));
    assert_eq!(samples[2]["frame"], 2.0);

    let o = keyrig(&[
        "sample",
        demo.to_str().unwrap(),
        "--channel",
        "light/Key/intensity",
        "--time",
        "1",
        "--format",
        "json",
    ]);
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(v["samples"][0]["value"], 2.5);
}

#[test]
fn sample_bad_arguments() {
    let demo = demo();
    let d = demo.to_str().unwrap();
    let cases: [(&[&str], &[&str]); 9] = [
        (
            &["--channel", "object/Leg/rotation", "--frame", "1"],
            &["no object named \"Leg\"", "\"Arm\", \"Cube\""],
        ),
        (&["--channel", "object/Arm/size", "--frame", "1"], &["unknown object property \"size\""]),
        (
            &["--channel", "object/Arm/joint/knee/rotation", "--frame", "1"],
            &["joints: \"shoulder\", \"elbow\""],
        ),
        (
            &["--channel", "light/Fill/colour", "--frame", "1"],
            &["no light named \"Fill\"", "\"Key\", \"Sun\""],
        ),
        (&["--frame", "1"], &["missing --channel", "object/Arm/joint/elbow/rotation"]),
        (&["--channel", "object/Arm/rotation", "--frames", "9..1"], &["start 9 is after the end 1"]),
        (&["--channel", "object/Arm/rotation", "--frames", "0..x"], &["end \"x\" is not a number"]),
        (
            &["--channel", "object/Arm/rotation", "--frames", "0..9", "--step", "0"],
            &["--step 0: must be a positive"],
        ),
        (
            &["--channel", "object/Arm/rotation", "--frames", "0..1e12", "--step", "1e-3"],
            &["at most 10000000"],
        ),
    ];
    for (args, needles) in cases {
        let mut all = vec!["sample", d];
        all.extend_from_slice(args);
        assert_fails_with(&keyrig(&all), needles);
    }
    // Clap-level errors: no time given, two given, unknown format.
    assert_fails_with(&keyrig(&["sample", d, "--channel", "object/Arm/rotation"]), &["--frames"]);
    assert_fails_with(
        &keyrig(&["sample", d, "--channel", "object/Arm/rotation", "--frame", "1", "--time", "1"]),
        &["cannot be used with"],
    );
    assert_fails_with(
        &keyrig(&["sample", d, "--channel", "object/Arm/rotation", "--frame", "1", "--format", "xml"]),
        &["invalid value 'xml'"],
    );
    assert_fails_with(
        &keyrig(&["sample", d, "--channel", "object/Arm/rotation", "--time", "NaN"]),
        &["--time NaN"],
    );
}

/// A skinned, animated glTF model of the shared corpus (see tests/corpus/SOURCES.md).
fn rigged_simple() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf/RiggedSimple/RiggedSimple.glb")
}

#[test]
fn info_and_sample_read_gltf_models() {
    let model = rigged_simple();
    let model = model.to_str().unwrap();
    let o = keyrig(&["info", model, "--format", "json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let joints = v["objects"][0]["joints"].as_array().expect("a skinned object with joints");
    assert!(!joints.is_empty());
    let tracks = v["tracks"].as_array().expect("tracks");
    let channel = tracks
        .iter()
        .filter_map(|t| t["channel"].as_str())
        .find(|c| c.contains("/joint/") && c.ends_with("/rotation"))
        .expect("an animated joint rotation")
        .to_string();
    let o = keyrig(&["sample", model, "--channel", &channel, "--frames", "0..10", "--format", "json"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    let samples = v["samples"].as_array().expect("samples");
    assert_eq!(samples.len(), 11);
    for s in samples {
        let q: Vec<f64> = s["value"].as_array().unwrap().iter().map(|c| c.as_f64().unwrap()).collect();
        let norm = q.iter().map(|c| c * c).sum::<f64>().sqrt();
        assert!((norm - 1.0).abs() < 1e-5, "{q:?}");
    }
}

#[test]
fn info_summarizes_md2_models() {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/md2");
    let mut seen = 0;
    for entry in std::fs::read_dir(&dir).expect("corpus md2 folder") {
        let folder = entry.unwrap().path();
        if !folder.is_dir() {
            continue;
        }
        for file in std::fs::read_dir(&folder).unwrap() {
            let path = file.unwrap().path();
            if path.extension().and_then(|e| e.to_str()) != Some("md2") {
                continue;
            }
            let o = keyrig(&["info", path.to_str().unwrap(), "--format", "json"]);
            assert!(o.status.success(), "{}: {}", path.display(), stderr(&o));
            let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
            assert!(v["frames"].as_u64().unwrap() > 0 && v["triangles"].as_u64().unwrap() > 0, "{v}");
            let clip_frames: u64 =
                v["clips"].as_array().unwrap().iter().map(|c| c["frames"].as_u64().unwrap()).sum();
            assert_eq!(clip_frames, v["frames"].as_u64().unwrap(), "clips cover every frame");
            seen += 1;
        }
    }
    assert!(seen > 0, "no .md2 in {}", dir.display());
}

fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus").join(rel)
}

#[test]
fn info_does_not_panic_on_a_node_name_of_65505_characters() {
    let dir = tempfile::tempdir().unwrap();
    let mut doc: serde_json::Value = serde_json::from_str(
        &std::fs::read_to_string(corpus("gltf/SimpleSkin/glTF-Embedded/SimpleSkin.gltf")).unwrap(),
    )
    .unwrap();
    // Node 2 is the animated joint: its name ends up in a channel path of the track table.
    for len in [65_505usize, 70_000] {
        doc["nodes"][2]["name"] = serde_json::json!("x".repeat(len));
        let path = dir.path().join("huge.gltf");
        std::fs::write(&path, serde_json::to_string(&doc).unwrap()).unwrap();
        let o = keyrig(&["info", path.to_str().unwrap()]);
        assert!(o.status.success(), "{}", stderr(&o));
        assert!(stdout(&o).contains("problems: none"));
    }
}

#[test]
fn frames_outside_the_range_and_bad_numbers_are_clear_errors() {
    let demo = demo();
    let d = demo.to_str().unwrap();
    let channel = ["--channel", "object/Arm/rotation"];
    let run = |extra: &[&str]| {
        let mut args = vec!["sample", d];
        args.extend_from_slice(&channel);
        args.extend_from_slice(extra);
        keyrig(&args)
    };
    assert_fails_with(&run(&["--frame", "91"]), &["--frame 91 is outside the scene's frame range 0..=90"]);
    // `-10` is a negative number, not a flag.
    assert_fails_with(&run(&["--frame", "-10"]), &["--frame -10 is outside the scene's frame range 0..=90"]);
    assert_fails_with(&run(&["--frames", "-10..5"]), &["frame -10 is outside the scene's frame range"]);
    assert_fails_with(&run(&["--time", "3.5"]), &["--time 3.5 is outside the scene's frame range 0..=90"]);
    assert_fails_with(
        &run(&["--frames", "0..10", "--step", "-1"]),
        &["--step -1: must be a positive number"],
    );
    assert!(run(&["--frame", "90"]).status.success());
}

#[test]
fn a_scene_file_with_a_byte_order_mark_is_read() {
    let dir = tempfile::tempdir().unwrap();
    let mut bytes = b"\xEF\xBB\xBF".to_vec();
    bytes.extend(std::fs::read(demo()).unwrap());
    let path = dir.path().join("bom.ron");
    std::fs::write(&path, bytes).unwrap();
    let o = keyrig(&["info", path.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("problems: none"));
}

#[test]
fn error_messages_do_not_echo_huge_tokens() {
    let dir = tempfile::tempdir().unwrap();
    let token = "y".repeat(5_000_000);
    let path = write_temp(&dir, "huge.ron", &format!("(version: 1, scene: ({token}: 1))"));
    let o = keyrig(&["info", path.to_str().unwrap()]);
    let err = stderr(&o);
    assert!(!o.status.success());
    assert!(err.len() < 2_000, "{} bytes of error", err.len());
    assert!(err.contains("yyyy… (5000002 bytes)"), "{err}");
    // serde_json quotes the string it did not expect.
    let text = format!("{{\"asset\": {{\"version\": \"2.0\"}}, \"nodes\": [{{\"mesh\": \"{token}\"}}]}}");
    let gltf = write_temp(&dir, "huge.gltf", &text);
    let o = keyrig(&["info", gltf.to_str().unwrap()]);
    let err = stderr(&o);
    assert!(!o.status.success() && err.len() < 2_000, "{} bytes of error", err.len());
    assert!(err.contains("yyyy… (500000"), "{err}");
}

#[test]
fn an_md2_model_opened_by_a_bare_file_name_keeps_its_skin() {
    let folder = corpus("md2/faerie");
    let o = Command::new(KEYRIG).args(["info", "faerie.md2"]).current_dir(&folder).output().unwrap();
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(stdout(&o).contains("image ./faerie2.bmp"), "{}", stdout(&o));
}

#[test]
fn info_reports_a_skinned_mesh_needing_more_joints_than_its_skeleton_has() {
    let dir = tempfile::tempdir().unwrap();
    let mut scene = keyrig_io::scene_file::load(&demo()).unwrap();
    let skeleton = scene.objects[0].skeleton.as_mut().unwrap();
    skeleton.joints.pop();
    let path = dir.path().join("fewer.ron");
    keyrig_io::scene_file::save(&path, &scene).unwrap();
    let o = keyrig(&["info", path.to_str().unwrap()]);
    assert!(stdout(&o).contains("problems: 1"), "{}", stdout(&o));
    assert!(
        stdout(&o).contains("objects[0].skeleton: the procedural ArmHighPoly mesh does not fit"),
        "{}",
        stdout(&o)
    );
    assert_fails_with(&o, &["1 validation problem"]);
}

#[test]
fn non_regular_files_are_refused_before_reading() {
    let dir = tempfile::tempdir().unwrap();
    let zero = dir.path().join("zero.glb");
    std::os::unix::fs::symlink("/dev/zero", &zero).unwrap();
    assert_fails_with(
        &keyrig(&["info", zero.to_str().unwrap()]),
        &["zero.glb", "a character device is not a regular file"],
    );
    let folder = dir.path().join("folder.ron");
    std::fs::create_dir(&folder).unwrap();
    assert_fails_with(
        &keyrig(&["info", folder.to_str().unwrap()]),
        &["folder.ron", "a folder is not a regular file"],
    );
    let fifo = dir.path().join("pipe.md2");
    let made = Command::new("mkfifo").arg(&fifo).status().map(|s| s.success()).unwrap_or(false);
    if made {
        // Without a writer, a read would wait forever; keyrig refuses before opening it.
        let start = std::time::Instant::now();
        assert_fails_with(
            &keyrig(&["info", fifo.to_str().unwrap()]),
            &["pipe.md2", "a FIFO (named pipe) is not a regular file"],
        );
        assert!(start.elapsed() < std::time::Duration::from_secs(10));
    }
}

/// Spin keys (issue 14): `assets/twist.ron` turns the forearm 360° with two keys; `sample`
/// prints the unwrapped angle beside the quaternion, and channels without spins keep their
/// columns.
#[test]
fn sample_prints_the_unwrapped_angle_of_spin_segments() {
    let twist = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/twist.ron");
    let args = |format: &str| {
        keyrig(&[
            "sample",
            twist.to_str().unwrap(),
            "--channel",
            "object/Arm/joint/forearm/rotation",
            "--frames",
            "0..60",
            "--step",
            "15",
            "--format",
            format,
        ])
    };
    let o = args("csv");
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines[0], "frame,time,x,y,z,w,spin_deg");
    assert_eq!(lines.len(), 1 + 5, "{out}");
    assert_eq!(lines[1], "0,0,0,0,0,1,0");
    // Frame 30 (1 s, mid-time): half a turn about X; frame 60: the whole turn, 360° unwrapped.
    let row = |i: usize| -> Vec<f64> { lines[i].split(',').map(|c| c.parse().unwrap()).collect() };
    let mid = row(3);
    assert_eq!(mid[0], 30.0);
    assert!((mid[2].abs() - 1.0).abs() < 1e-6 && mid[5].abs() < 1e-6, "{}", lines[3]);
    assert_eq!(mid[6], 180.0, "{}", lines[3]);
    let end = row(5);
    assert_eq!(end[6], 360.0, "{}", lines[5]);
    assert!((end[5].abs() - 1.0).abs() < 1e-6, "{}", lines[5]);
    // TCB eases in: a quarter of the time is less than a quarter of the turn.
    assert!(row(2)[6] > 0.0 && row(2)[6] < 90.0, "{}", lines[2]);

    let o = args("json");
    let v: serde_json::Value = serde_json::from_slice(&o.stdout).expect("JSON");
    assert_eq!(v["columns"], serde_json::json!(["x", "y", "z", "w"]));
    assert_eq!(v["samples"][2]["spin_deg"], 180.0);
    assert_eq!(v["samples"][4]["spin_deg"], 360.0);

    // A channel without spins (the shoulder here, or any demo channel) prints as before.
    let o = keyrig(&[
        "sample",
        twist.to_str().unwrap(),
        "--channel",
        "object/Arm/joint/elbow/rotation",
        "--frame",
        "30",
    ]);
    assert_eq!(stdout(&o), "frame,time,x,y,z,w\n30,1,0,0,0,1\n");
}

/// Issue 31: `keyrig info` of a glTF file lists the animation pointers it skipped, with why —
/// here an orthographic camera's `xmag` (its width follows the height and the render aspect),
/// exported by keyrig next to the `ymag` channel it reads — and `keyrig sample` reads the
/// camera's lens and visibility channels from the file.
#[test]
fn info_lists_skipped_camera_pointers_and_sample_reads_camera_channels() {
    use keyrig_core::{Animated, Interpolation, Key, Projection, RawTrack, Scene, SceneCamera};
    let dir = tempfile::tempdir().unwrap();
    let mut top = SceneCamera::new("Top", glam::Vec3::new(0.0, 10.0, 0.0));
    top.projection = Projection::Orthographic;
    top.far = Some(50.0);
    let linear = |t: f64, v: f32| Key::new(t, v).with_interpolation(Interpolation::Linear);
    top.lens = Animated::new(6.0, RawTrack::new(vec![linear(0.0, 6.0), linear(1.0, 3.0)]));
    let step = |t: f64, v: f32| Key::new(t, v).with_interpolation(Interpolation::Step);
    top.visible = Animated::new(1.0, RawTrack::new(vec![step(0.0, 1.0), step(0.5, 0.0)]));
    let scene = Scene { cameras: vec![top], ..Scene::default() };
    let exported =
        keyrig_io::gltf_export::export_scene(&scene, &keyrig_io::gltf_export::ExportOptions::default())
            .unwrap();
    let file = dir.path().join("top.glb");
    exported.write(&file).unwrap();

    let o = keyrig(&["info", file.to_str().unwrap()]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    assert!(out.contains("skipped channels: 1\n"), "{out}");
    assert!(
        out.contains("(/cameras/0/orthographic/xmag): keyrig's orthographic view width follows its height (ymag) and the scene's render aspect"),
        "{out}"
    );
    let o = keyrig(&[
        "sample",
        file.to_str().unwrap(),
        "--channel",
        "camera/Top/lens",
        "--frames",
        "0..30",
        "--step",
        "15",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(stdout(&o), "frame,time,value\n0,0,6\n15,0.5,4.5\n30,1,3\n");
    let o = keyrig(&[
        "sample",
        file.to_str().unwrap(),
        "--channel",
        "camera/Top/visible",
        "--frames",
        "0..30",
        "--step",
        "15",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    assert_eq!(stdout(&o), "frame,time,value\n0,0,1\n15,0.5,0\n30,1,0\n");
}

/// `keyrig sample` of Euler keys (issue 30): `rotation_euler` prints the angles in degrees
/// (Y climbing 0 → 360 on the demo's Cube switched to Euler keys), `rotation` the rotation they
/// make, and a channel without Euler keys says what to sample instead.
#[test]
fn sample_euler_keys_as_angles_and_as_rotations() {
    use keyrig_core::channel_id::{set_rotation_keys, ChannelId};
    let mut scene = keyrig_io::demo::demo_scene();
    let cube = scene.objects.iter().position(|o| o.name == "Cube").expect("the demo's cube");
    let xyz = keyrig_core::RotationMode::Euler(keyrig_core::EulerOrder::XYZ);
    assert!(set_rotation_keys(&mut scene, ChannelId::ObjectRotation(cube), xyz, true).unwrap());
    let dir = tempfile::tempdir().unwrap();
    let file = write_temp(&dir, "euler.ron", &keyrig_io::scene_file::to_string(&scene).unwrap());
    let file = file.to_str().unwrap();
    let o = keyrig(&[
        "sample",
        file,
        "--channel",
        "object/Cube/rotation_euler",
        "--frames",
        "0..90",
        "--step",
        "15",
    ]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let lines: Vec<&str> = out.lines().collect();
    assert_eq!(lines[0], "frame,time,x_deg,y_deg,z_deg");
    let y: Vec<f64> = lines[1..].iter().map(|l| l.split(',').nth(3).unwrap().parse().unwrap()).collect();
    for (got, want) in y.iter().zip([0.0, 60.0, 120.0, 180.0, 240.0, 300.0, 360.0]) {
        assert!((got - want).abs() < 1e-3, "{out}");
    }
    let o = keyrig(&["sample", file, "--channel", "object/Cube/rotation", "--frames", "45..45"]);
    assert!(o.status.success(), "{}", stderr(&o));
    let out = stdout(&o);
    let row: Vec<f64> = out.lines().nth(1).unwrap().split(',').map(|c| c.parse().unwrap()).collect();
    // Y 180°: q = (0, ±1, 0, 0).
    assert!((row[3].abs() - 1.0).abs() < 1e-5 && row[5].abs() < 1e-5, "{out}");
    assert_fails_with(
        &keyrig(&["sample", file, "--channel", "object/Arm/rotation_euler", "--frames", "0..1"]),
        &["rotation_euler", "quaternion keys"],
    );
}
