//! Scene files: every error class (with file, line and column), atomic save with backup,
//! refusal to touch newer files, and byte-identical round trips.

use std::fs;
use std::path::{Path, PathBuf};

use glam::{Quat, Vec3};
use keyrig_core::{
    Animated, Cycle, Cycles, Interpolation, Joint, Key, Light, LightKind, Object, RawTrack, Scene, Skeleton,
    Tcb,
};
use keyrig_io::demo::{demo_scene, DEMO_RON};
use keyrig_io::scene_file::{self, SceneFileError, CURRENT_VERSION};
use proptest::prelude::*;
use proptest::strategy::ValueTree;

fn origin() -> &'static Path {
    Path::new("test.ron")
}

/// Parses `text`, expecting an error; returns it with its Display text.
fn parse_err(text: &str) -> (SceneFileError, String) {
    match scene_file::from_str(text, origin()) {
        Ok(_) => panic!("expected an error for:\n{text}"),
        Err(e) => {
            let shown = e.to_string();
            (e, shown)
        }
    }
}

/// A minimal valid document around `scene_fields`.
fn doc(scene_fields: &str) -> String {
    format!("(\n    version: 4,\n    scene: (\n{scene_fields}\n    ),\n)\n")
}

const TIMING: &str = "        fps: 30.0,\n        frame_range: (start: 0, end: 10),";

#[test]
fn minimal_document_loads_with_defaults() {
    let scene = scene_file::from_str(&doc(TIMING), origin()).expect("valid");
    assert_eq!(
        scene,
        Scene { frame_range: keyrig_core::FrameRange { start: 0, end: 10 }, ..Scene::default() }
    );
}

#[test]
fn newer_version_is_refused_with_its_place() {
    // Fields this keyrig does not know: "too new" must win over "unknown field".
    let (err, shown) = parse_err("(\n  version: 5,\n  scene: (fps: 30.0, hologram: true),\n)");
    assert!(matches!(
        err,
        SceneFileError::TooNew { found: 5, supported: CURRENT_VERSION, line: 2, column: 12, .. }
    ));
    assert!(shown.starts_with("test.ron:2:12: scene format version 5 is newer"), "{shown}");
}

#[test]
fn version_after_the_scene_is_read_too() {
    // Hand-edited files may put `version` last: the slower two-pass path reads them.
    let text = format!("(\n    scene: (\n{TIMING}\n    ),\n    version: 4,\n)\n");
    assert_eq!(scene_file::from_str(&text, origin()).unwrap().frame_range.end, 10);
    // A version-1 file with its version last is migrated the same way.
    assert_eq!(
        scene_file::from_str(&text.replace("version: 4", "version: 1"), origin()).unwrap().frame_range.end,
        10
    );
    let (err, _) = parse_err(&text.replace("version: 4", "version: 5"));
    assert!(matches!(err, SceneFileError::TooNew { found: 5, line: 6, column: 14, .. }), "{err:?}");
    let (err, shown) = parse_err(&text.replace("version: 4,", "version: 4,\n    version: 4,"));
    assert!(matches!(err, SceneFileError::Syntax { .. }), "{err:?}");
    assert!(shown.contains("version"), "{shown}");
}

#[test]
fn older_versions_without_migration_are_refused() {
    let (err, shown) = parse_err(&doc(TIMING).replace("version: 4", "version: 0"));
    assert!(matches!(err, SceneFileError::TooOld { found: 0, line: 2, column: 14, .. }), "{err:?}");
    assert!(shown.contains("version 0 is not supported"), "{shown}");
}

#[test]
fn missing_version_is_a_syntax_error() {
    let (err, shown) = parse_err(&format!("(\n    scene: (\n{TIMING}\n    ),\n)\n"));
    assert!(matches!(err, SceneFileError::Syntax { .. }));
    assert!(shown.contains("version"), "{shown}");
    assert!(shown.starts_with("test.ron:"), "{shown}");
}

#[test]
fn unknown_fields_are_rejected_at_their_place() {
    let text =
        doc(&format!("{TIMING}\n        objects: [\n            (name: \"A\", colour: 1),\n        ],"));
    let (err, shown) = parse_err(&text);
    let SceneFileError::Syntax { line, column, message, .. } = &err else { panic!("{err:?}") };
    assert_eq!(*line, 7);
    assert!(*column >= 23, "column {column}");
    assert!(message.contains("colour"), "{message}");
    assert!(shown.starts_with("test.ron:7:"), "{shown}");
    // At the top level and inside the envelope too.
    let (_, shown) = parse_err("(version: 1, comment: \"x\", scene: ())");
    assert!(shown.contains("comment"), "{shown}");
}

#[test]
fn wrong_types_are_syntax_errors_with_place() {
    let (err, shown) = parse_err(&doc("        fps: \"fast\",\n        frame_range: (start: 0, end: 10),"));
    assert!(matches!(err, SceneFileError::Syntax { line: 4, .. }), "{err:?}");
    assert!(shown.starts_with("test.ron:4:"), "{shown}");
    let (err, _) = parse_err(&doc("        fps: 30.0,\n        frame_range: (start: 0.5, end: 10),"));
    assert!(matches!(err, SceneFileError::Syntax { line: 5, .. }), "{err:?}");
    let (err, _) = parse_err(&doc(
        "        fps: 30.0,\n        frame_range: (start: 0, end: 10),\n        ambient: (1.0, 2.0),",
    ));
    assert!(matches!(err, SceneFileError::Syntax { line: 6, .. }), "{err:?}");
}

#[test]
fn non_finite_numbers_are_reported_at_the_token() {
    // `NaN`, `inf`, and a literal too large for f32 (it becomes inf).
    let text = doc(&format!(
        "{TIMING}\n        ambient: (0.1, NaN, 0.1),\n        camera: (target: (0.0, 0.0, -inf), yaw_deg: 0.0, pitch_deg: 1e39, distance: 1.0, fov_y_deg: 45.0),"
    ));
    let (err, shown) = parse_err(&text);
    let SceneFileError::Invalid { problems, .. } = &err else { panic!("{err:?}") };
    let got: Vec<(String, Option<(usize, usize)>)> =
        problems.iter().map(|p| (p.problem.path.clone(), p.position)).collect();
    assert_eq!(
        got,
        [
            ("ambient.y".to_string(), Some((6, 24))),
            ("camera.target.z".to_string(), Some((7, 37))),
            ("camera.pitch_deg".to_string(), Some((7, 69))),
        ]
    );
    assert!(
        shown.starts_with("test.ron: invalid scene, 3 problems: 6:24: ambient.y: not a finite number"),
        "{shown}"
    );
    assert_eq!(err.position(), Some((6, 24)));
    // f64 fields: key times.
    let text = doc(&format!(
        "{TIMING}\n        objects: [(name: \"A\", translation: (value: (0.0, 0.0, 0.0), track: [(time: inf, value: (0.0, 0.0, 0.0))]), rotation: (value: (0.0, 0.0, 0.0, 1.0)), scale: (value: (1.0, 1.0, 1.0)))],"
    ));
    let (err, _) = parse_err(&text);
    let SceneFileError::Invalid { problems, .. } = &err else { panic!("{err:?}") };
    assert_eq!(problems[0].problem.path, "objects[0].translation.track[0].time");
    assert_eq!(problems[0].position, Some((6, 84)));
}

#[test]
fn unsorted_keys_and_bad_parents_report_paths_and_places() {
    let mut scene = demo_scene();
    {
        let skeleton = scene.objects[0].skeleton.as_mut().expect("arm skeleton");
        skeleton.joints[2].rotation.track.keys.swap(3, 4);
        skeleton.joints[3].parent = Some(3);
        skeleton.joints[1].parent = Some(9);
    }
    let text = scene_file::to_string(&scene).expect("serialize");
    let (err, _) = parse_err(&text);
    let SceneFileError::Invalid { problems, .. } = &err else { panic!("{err:?}") };
    let line_of = |needle: &str, nth: usize| -> usize {
        text.lines()
            .enumerate()
            .filter(|(_, l)| l.contains(needle))
            .nth(nth)
            .map(|(i, _)| i + 1)
            .expect(needle)
    };
    let got: Vec<(&str, usize)> =
        problems.iter().map(|p| (p.problem.path.as_str(), p.position.expect("located").0)).collect();
    assert_eq!(
        got,
        [
            ("objects[0].skeleton.joints[1].parent", line_of("parent: Some(9)", 0)),
            ("objects[0].skeleton.joints[2].rotation.track[4].time", line_of("(time: 1.6666666666666667", 0)),
            ("objects[0].skeleton.joints[3].parent", line_of("parent: Some(3)", 0)),
        ]
    );
    assert!(problems[0].problem.message.contains("out of range"));
    assert!(problems[1].problem.message.contains("out of order"));
    assert!(problems[2].problem.message.contains("must come before joint 3"));
    // The lenient loader returns the scene with the same problems.
    let (loaded, lenient) = scene_file::from_str_lenient(&text, origin()).expect("parses");
    assert_eq!(loaded, scene);
    assert_eq!(&lenient, problems);
}

#[test]
fn truncated_files_fail_cleanly_at_every_length() {
    // Every prefix of the demo (stepping over multi-byte characters) is an error, never a panic.
    let mut cut = 0;
    while cut < DEMO_RON.len() - 2 {
        if DEMO_RON.is_char_boundary(cut) {
            let result = scene_file::from_str(&DEMO_RON[..cut], origin());
            let err = result.expect_err("a truncated demo must not load");
            assert!(err.position().is_some(), "cut {cut}: {err}");
        }
        cut += 7;
    }
    let (_, shown) = parse_err(&DEMO_RON[..DEMO_RON.len() / 2]);
    assert!(shown.contains("unexpected end of file (is the file truncated?)"), "{shown}");
}

#[test]
fn not_utf8_is_reported_with_place() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bin.ron");
    fs::write(&path, b"(\n  version: 1,\n  scene: (fps: \xff30.0),\n)").unwrap();
    let err = scene_file::load(&path).expect_err("not UTF-8");
    assert!(matches!(err, SceneFileError::Syntax { line: 3, column: 16, .. }), "{err:?}");
    assert!(err.to_string().contains("not UTF-8 text (invalid byte at offset 31)"), "{err}");
}

#[test]
fn missing_file_names_the_path() {
    let err = scene_file::load(Path::new("/nonexistent/keyrig/scene.ron")).expect_err("missing");
    assert!(matches!(err, SceneFileError::Read { .. }));
    assert!(err.to_string().starts_with("/nonexistent/keyrig/scene.ron: cannot read:"), "{err}");
}

fn entries(dir: &Path) -> Vec<String> {
    let mut names: Vec<String> =
        fs::read_dir(dir).unwrap().map(|e| e.unwrap().file_name().to_string_lossy().into_owned()).collect();
    names.sort();
    names
}

#[test]
fn save_is_atomic_and_keeps_a_backup() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("scene.ron");
    let first = demo_scene();
    scene_file::save(&path, &first).expect("first save");
    assert_eq!(entries(dir.path()), ["scene.ron"]);
    assert_eq!(fs::read_to_string(&path).unwrap(), DEMO_RON);

    let mut second = first.clone();
    second.fps = 24.0;
    scene_file::save(&path, &second).expect("second save");
    assert_eq!(entries(dir.path()), ["scene.ron", "scene.ron.bak"]);
    assert_eq!(fs::read_to_string(scene_file::backup_path(&path)).unwrap(), DEMO_RON);
    assert_eq!(scene_file::load(&path).unwrap(), second);

    // A third save replaces the backup with the second version.
    scene_file::save(&path, &first).expect("third save");
    assert_eq!(scene_file::load(&scene_file::backup_path(&path)).unwrap(), second);
    assert_eq!(entries(dir.path()), ["scene.ron", "scene.ron.bak"]);
}

#[test]
fn failed_saves_leave_no_partial_file() {
    let dir = tempfile::tempdir().unwrap();
    // The target is a directory: the save is refused before a temporary file is made.
    let target = dir.path().join("taken.ron");
    fs::create_dir(&target).unwrap();
    let err = scene_file::save(&target, &demo_scene()).expect_err("cannot replace a directory");
    assert!(matches!(err, SceneFileError::Write { .. }), "{err:?}");
    assert!(err.to_string().contains("taken.ron: cannot write: the path is a folder"), "{err}");
    assert_eq!(entries(dir.path()), ["taken.ron"]);

    // A folder that does not exist.
    let err = scene_file::save(&dir.path().join("no/such/dir.ron"), &demo_scene()).expect_err("no folder");
    assert!(matches!(err, SceneFileError::Write { .. }), "{err:?}");

    // An invalid scene is refused before anything is written: the old file stays as it was.
    let path = dir.path().join("scene.ron");
    scene_file::save(&path, &demo_scene()).unwrap();
    let mut bad = demo_scene();
    bad.fps = f64::NAN;
    let err = scene_file::save(&path, &bad).expect_err("NaN fps");
    assert!(err.to_string().contains("fps: not a finite number"), "{err}");
    assert_eq!(fs::read_to_string(&path).unwrap(), DEMO_RON);
    assert_eq!(entries(dir.path()), ["scene.ron", "taken.ron"]);
}

#[test]
fn save_refuses_to_overwrite_newer_files() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("future.ron");
    for text in [
        "(version: 5, scene: (fps: 30.0))\n",
        // A newer file in syntax this keyrig cannot parse at all is still recognized.
        "(version: 6, scene: <<binary-ish future syntax>>)\n",
        // Even when the syntax it cannot parse comes before the version.
        "#![enable(teleportation)]\n(version: 7, scene: ())\n",
    ] {
        fs::write(&path, text).unwrap();
        let err = scene_file::save(&path, &demo_scene()).expect_err("newer file");
        assert!(matches!(err, SceneFileError::RefuseOverwriteNewer { .. }), "{err:?}");
        assert!(err.to_string().contains("will not overwrite"), "{err}");
        assert_eq!(fs::read_to_string(&path).unwrap(), text);
        assert_eq!(entries(dir.path()), ["future.ron"]);
    }
    // A file of the current version, or garbage, is overwritten (and kept as the backup).
    fs::write(&path, "not a scene").unwrap();
    scene_file::save(&path, &demo_scene()).expect("overwrite garbage");
    assert_eq!(fs::read_to_string(scene_file::backup_path(&path)).unwrap(), "not a scene");
}

#[test]
fn demo_round_trip_is_byte_identical() {
    let dir = tempfile::tempdir().unwrap();
    let a = dir.path().join("a.ron");
    let b = dir.path().join("b.ron");
    let scene = scene_file::from_str(DEMO_RON, origin()).expect("demo loads");
    scene_file::save(&a, &scene).unwrap();
    let again = scene_file::load(&a).unwrap();
    scene_file::save(&b, &again).unwrap();
    assert_eq!(fs::read(&a).unwrap(), DEMO_RON.as_bytes());
    assert_eq!(fs::read(&a).unwrap(), fs::read(&b).unwrap());
}

/// Key types are saved only where a key is not a plain keyframe (`key_type: Breakdown`), read
/// back to the same scene and written again to the same bytes; keyframes add nothing to the
/// file (the demo's bytes stay those of `demo_round_trip_is_byte_identical`).
#[test]
fn key_types_are_saved_only_where_not_keyframes() {
    use keyrig_core::KeyType;
    let mut scene = Scene::default();
    let mut o = Object::new("Ball");
    o.translation.track = RawTrack::new(vec![
        Key::new(0.0, Vec3::ZERO),
        Key::new(0.5, Vec3::Y).with_key_type(KeyType::Breakdown),
        Key::new(1.0, Vec3::X).with_key_type(KeyType::Extreme),
        Key::new(1.5, Vec3::X).with_key_type(KeyType::MovingHold),
    ]);
    scene.objects.push(o);
    let text = scene_file::to_string(&scene).unwrap();
    assert_eq!(text.matches("key_type").count(), 3, "{text}");
    for line in ["key_type: Breakdown", "key_type: Extreme", "key_type: MovingHold"] {
        assert!(text.contains(line), "{line} in {text}");
    }
    let back = scene_file::from_str(&text, origin()).expect("loads");
    assert_eq!(back, scene);
    assert_eq!(scene_file::to_string(&back).unwrap(), text);
    assert!(!DEMO_RON.contains("key_type"), "the demo's keys are keyframes and say nothing of it");
}

#[test]
fn hermite_keys_and_comments_round_trip() {
    let mut scene = Scene::default();
    let mut o = Object::new("Imported \"glTF\" node \\ ünïcode");
    o.translation.track = RawTrack::new(vec![
        Key {
            time: 0.0,
            value: Vec3::ZERO,
            interpolation: Interpolation::Hermite,
            tcb: Tcb::ZERO,
            in_tangent: Some(Vec3::X),
            out_tangent: Some(Vec3::new(1e-30, -0.0, 3.4e38)),
            spin: None,
            key_type: keyrig_core::KeyType::Keyframe,
        },
        Key { in_tangent: Some(Vec3::Y), ..Key::new(1.0 / 3.0, Vec3::ONE) },
    ]);
    scene.objects.push(o);
    let text = scene_file::to_string(&scene).unwrap();
    let back = scene_file::from_str(&text, origin()).expect("loads");
    assert_eq!(back, scene);
    assert_eq!(scene_file::to_string(&back).unwrap(), text);
    // Comments a user added by hand are allowed (and dropped by the next save).
    let commented = text.replacen("(\n", "// my scene\n(\n    /* format */\n", 1);
    assert_eq!(scene_file::from_str(&commented, origin()).unwrap(), scene);
}

// ---------------------------------------------------------------------------------------------
// Generated scenes: save → load → save is byte-identical and floats come back bit for bit.

fn finite_f32() -> impl Strategy<Value = f32> + Clone {
    prop_oneof![
        -1e6f32..1e6,
        any::<f32>().prop_filter("finite", |v| v.is_finite()),
        Just(-0.0f32),
        Just(f32::MIN_POSITIVE),
        Just(f32::MAX),
        Just(1e-45f32),
    ]
}

fn vec3() -> impl Strategy<Value = Vec3> + Clone {
    (finite_f32(), finite_f32(), finite_f32()).prop_map(|(x, y, z)| Vec3::new(x, y, z))
}

fn quat() -> impl Strategy<Value = Quat> + Clone {
    (-1.0f32..1.0, -1.0f32..1.0, -1.0f32..1.0, 0.1f32..1.0)
        .prop_map(|(x, y, z, w)| Quat::from_xyzw(x, y, z, w))
}

fn tcb() -> impl Strategy<Value = Tcb> + Clone {
    (-1.0f32..=1.0, -1.0f32..=1.0, -1.0f32..=1.0).prop_map(|(t, c, b)| Tcb::new(t, c, b))
}

fn keys<T: std::fmt::Debug + Clone + 'static>(
    value: impl Strategy<Value = T>,
) -> impl Strategy<Value = Vec<Key<T>>> {
    prop::collection::vec((1e-6f64..10.0, value, tcb(), 0..3u8), 0..6).prop_map(|raw| {
        let mut time = 0.0;
        raw.into_iter()
            .map(|(dt, value, tcb, mode)| {
                time += dt;
                let interpolation =
                    [Interpolation::Step, Interpolation::Linear, Interpolation::Tcb][mode as usize];
                Key::new(time, value).with_tcb(tcb).with_interpolation(interpolation)
            })
            .collect()
    })
}

fn animated<T: std::fmt::Debug + Clone + 'static>(
    value: impl Strategy<Value = T> + Clone,
) -> impl Strategy<Value = Animated<T>> {
    (value.clone(), keys(value), cycle(), cycle()).prop_map(|(value, keys, before, after)| {
        // Cycles need two keys (else the scene has a problem); Hold is the default.
        let cycles = if keys.len() >= 2 { Cycles::new(before, after) } else { Cycles::HOLD };
        Animated::new(value, RawTrack::new(keys)).with_cycles(cycles)
    })
}

fn cycle() -> impl Strategy<Value = Cycle> + Clone {
    prop::sample::select(Cycle::ALL.to_vec())
}

fn object() -> impl Strategy<Value = Object> {
    ("[a-zA-Z0-9 _\"\\\\é-]{1,12}", animated(vec3()), animated(quat()), animated(vec3()), 0..4usize).prop_map(
        |(name, translation, rotation, scale, joints)| {
            let mut o = Object::new(name);
            o.translation = translation;
            o.rotation = rotation;
            o.scale = scale;
            if joints > 0 {
                o.skeleton = Some(Skeleton {
                    joints: (0..joints)
                        .map(|i| Joint {
                            // Zero translation and unit scale (left out of the file) on some
                            // joints, other values on the rest.
                            translation: Animated::constant(Vec3::new(0.0, 0.01 * i as f32, 0.0)),
                            rotation: Animated::constant(Quat::from_rotation_x(i as f32)),
                            scale: Animated::constant(Vec3::splat(1.0 + 0.5 * (i % 2) as f32)),
                            ..Joint::new(
                                format!("j{i}"),
                                i.checked_sub(1),
                                Vec3::new(0.1 * i as f32, 0.0, 0.0),
                                Quat::IDENTITY,
                            )
                        })
                        .collect(),
                    root_translation: Animated::constant(Vec3::ZERO),
                    ik_constraints: Vec::new(),
                });
            }
            o
        },
    )
}

fn light() -> impl Strategy<Value = Light> {
    (animated(vec3()), animated(0.0f32..1e4), any::<bool>()).prop_map(|(position, intensity, enabled)| {
        Light {
            name: "L".into(),
            kind: LightKind::Spot { cutoff_deg: 40.0, inner_angle_deg: 20.0, dropoff: 1.5 },
            enabled,
            position,
            direction: Animated::constant(Vec3::NEG_Y),
            colour: Animated::constant(Vec3::ONE),
            intensity,
            attributes: Default::default(),
        }
    })
}

fn scene() -> impl Strategy<Value = Scene> {
    (
        0.001f64..1000.0,
        -100i32..100,
        0i32..1000,
        vec3(),
        prop::collection::vec(object(), 0..3),
        prop::option::of(light()),
    )
        .prop_map(|(fps, start, len, ambient, objects, light)| Scene {
            fps,
            frame_range: keyrig_core::FrameRange { start, end: start + len },
            ambient,
            objects,
            lights: light.into_iter().collect(),
            camera: keyrig_core::Camera::default(),
            ..Scene::default()
        })
}

proptest! {
    #![proptest_config(ProptestConfig::with_cases(64))]

    #[test]
    fn generated_scenes_round_trip_exactly(scene in scene()) {
        let text = scene_file::to_string(&scene).unwrap();
        let (back, _problems) = scene_file::from_str_lenient(&text, origin()).unwrap();
        // Bit-exact floats (PartialEq would accept 0.0 == -0.0).
        prop_assert_eq!(format!("{back:?}"), format!("{scene:?}"));
        prop_assert_eq!(&back, &scene);
        prop_assert_eq!(scene_file::to_string(&back).unwrap(), text);
    }
}

#[test]
fn generated_files_round_trip_through_disk() {
    let dir = tempfile::tempdir().unwrap();
    let mut runner = proptest::test_runner::TestRunner::deterministic();
    let mut saved = 0;
    for i in 0..16 {
        let scene = scene().new_tree(&mut runner).unwrap().current();
        if !scene.problems().is_empty() {
            continue;
        }
        saved += 1;
        let a: PathBuf = dir.path().join(format!("{i}a.ron"));
        let b: PathBuf = dir.path().join(format!("{i}b.ron"));
        scene_file::save(&a, &scene).unwrap();
        scene_file::save(&b, &scene_file::load(&a).unwrap()).unwrap();
        assert_eq!(fs::read(&a).unwrap(), fs::read(&b).unwrap());
    }
    assert!(saved >= 8, "only {saved} of 16 generated scenes were valid");
}

/// Version 1 (joints with rotations only) is migrated: the demo as version 1 wrote it opens as
/// today's demo with its keys as the action "Action", and saving it writes the current version.
#[test]
fn version_1_files_are_migrated() {
    let v1 = include_str!("fixtures/demo-v1.ron");
    assert!(v1.contains("version: 1,"));
    let scene = scene_file::from_str(v1, Path::new("demo-v1.ron")).expect("a version-1 file opens");
    assert_eq!(scene, demo_as_one_action());
    let joint = &scene.objects[0].skeleton.as_ref().expect("arm").joints[1];
    assert_eq!((joint.translation.value, joint.scale.value), (glam::Vec3::ZERO, glam::Vec3::ONE));
    assert!(!joint.translation.is_animated() && !joint.scale.is_animated());
    assert_eq!(scene_file::to_string(&scene).unwrap(), scene_file::to_string(&demo_as_one_action()).unwrap());
    assert!(DEMO_RON.contains("version: 4,"));
    // A version-1 file may not use the version-2 joint fields.
    let bad = v1.replacen("rest_rotation:", "translation: (value: (1.0, 0.0, 0.0)),\n rest_rotation:", 1);
    let (err, shown) = parse_err(&bad);
    assert!(matches!(err, SceneFileError::Syntax { .. }), "{err:?}");
    assert!(shown.contains("translation"), "{shown}");
}

/// The demo as a file of version 1–3 opens: its keys become the action "Action", active on
/// the objects with keys (docs/scene-format.md, "Versions and migration").
fn demo_as_one_action() -> keyrig_core::Scene {
    let mut scene = demo_scene();
    scene.name_unnamed_keys(keyrig_core::DEFAULT_ACTION);
    scene
}

/// Version 2 files (everything keyrig wrote before cameras, markers and the new channels) open
/// unchanged but for the action: versions 3 and 4 only added fields whose absence means "none",
/// so the demo as version 2 wrote it is today's demo with its keys as one action.
#[test]
fn version_2_files_open_unchanged() {
    let v2 = include_str!("fixtures/demo-v2.ron");
    assert!(v2.contains("version: 2,"));
    let scene = scene_file::from_str(v2, Path::new("demo-v2.ron")).expect("a version-2 file opens");
    assert_eq!(scene, demo_as_one_action());
}

/// A version-3 file holds one animation: it opens with its keys as the action "Action" on every
/// object with keys, nothing moved or lost, and saves as version 4 with that action, which
/// opens again to the same scene (docs/actions.md).
#[test]
fn version_3_files_become_one_action() {
    let v3 = include_str!("fixtures/demo-v3.ron");
    assert!(v3.contains("version: 3,"));
    let scene = scene_file::from_str(v3, Path::new("demo-v3.ron")).expect("a version-3 file opens");
    assert_eq!(scene, demo_as_one_action());
    assert_eq!(scene.objects.iter().filter(|o| o.action.as_deref() == Some("Action")).count(), 2);
    assert_eq!(scene.actions.len(), 1);
    // Every key is where it was: the same channels as the demo's, playing.
    let demo = demo_scene();
    for (a, b) in scene.objects.iter().zip(&demo.objects) {
        assert_eq!(a.translation, b.translation);
        assert_eq!(a.skeleton, b.skeleton);
    }
    let saved = scene_file::to_string(&scene).unwrap();
    assert!(saved.contains("version: 4,") && saved.contains("\"Action\""), "{saved}");
    let again = scene_file::from_str(&saved, Path::new("demo-v4.ron")).expect("the saved file opens");
    assert_eq!(again, scene);
    assert_eq!(scene_file::to_string(&again).unwrap(), saved);
}

/// Every scene file that ships (assets/) and every complete scene document in the docs
/// (```ron blocks that start with `(` and hold a `version`, outlines with `…` aside) opens,
/// whatever its version.
#[test]
fn every_shipped_and_documented_scene_opens() {
    let root = Path::new(env!("CARGO_MANIFEST_DIR")).join("../..");
    let mut opened = 0;
    for dir in ["assets", "crates/io/tests/fixtures"] {
        for entry in fs::read_dir(root.join(dir)).unwrap() {
            let path = entry.unwrap().path();
            if path.extension().is_some_and(|e| e == "ron") {
                scene_file::load(&path).unwrap_or_else(|e| panic!("{e}"));
                opened += 1;
            }
        }
    }
    for entry in fs::read_dir(root.join("docs")).unwrap() {
        let path = entry.unwrap().path();
        if path.extension().is_none_or(|e| e != "md") {
            continue;
        }
        let text = fs::read_to_string(&path).unwrap();
        for block in text.split("```ron\n").skip(1) {
            let block = &block[..block.find("```").expect("closed block")];
            // Outlines with `…` in place of fields are not documents.
            if block.starts_with('(') && block.contains("version:") && !block.contains('…') {
                scene_file::from_str(block, &path).unwrap_or_else(|e| panic!("{e}"));
                opened += 1;
            }
        }
    }
    assert!(opened >= 3, "found only {opened} scene documents");
}

/// Cycles are written after the keys, by name, and only when not Hold; a cycle on a track with
/// one key is a problem at the `after` line.
#[test]
fn cycles_are_written_readably_and_checked() {
    let mut scene = demo_scene();
    let cube = &mut scene.objects[1];
    cube.translation.after = Cycle::RepeatOffset;
    cube.rotation.before = Cycle::PingPong;
    let text = scene_file::to_string(&scene).expect("serialize");
    assert_eq!(text.matches("after: RepeatOffset,\n").count(), 1, "{text}");
    assert_eq!(text.matches("before: PingPong,\n").count(), 1, "{text}");
    assert_eq!(scene_file::from_str(&text, origin()).expect("valid"), scene);
    // Without cycles nothing is written: the demo saves as before.
    assert!(!DEMO_RON.contains("before:") && !DEMO_RON.contains("after:"));

    let one_key = doc(&format!(
        "{TIMING}\n        objects: [(name: \"Box\", translation: (value: (0.0, 0.0, 0.0), track: [(time: 0.0, value: (0.0, 0.0, 0.0))],\n            after: Repeat), rotation: (value: (0.0, 0.0, 0.0, 1.0)), scale: (value: (1.0, 1.0, 1.0)))],"
    ));
    let (err, shown) = parse_err(&one_key);
    let SceneFileError::Invalid { problems, .. } = &err else { panic!("{err:?}") };
    assert_eq!(problems.len(), 1, "{shown}");
    assert_eq!(problems[0].problem.path, "objects[0].translation.after");
    assert_eq!(
        problems[0].position.map(|p| p.0),
        Some(one_key.lines().position(|l| l.contains("after: Repeat")).unwrap() + 1)
    );
    assert!(shown.contains("Repeat after the keys needs at least two keys"), "{shown}");
}

#[test]
fn a_byte_order_mark_is_not_part_of_the_document() {
    let text = format!("\u{FEFF}{DEMO_RON}");
    let scene = scene_file::from_str(&text, Path::new("bom.ron")).expect("a BOM is accepted");
    assert_eq!(scene, demo_scene());
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("bom.ron");
    fs::write(&path, text.as_bytes()).unwrap();
    assert_eq!(scene_file::load(&path).expect("from a file"), demo_scene());
}

/// A scene saved with `project::save_scene` names the models below its folder relative to it
/// (`/`-separated) and others by their absolute path; `project::load_scene` makes them absolute
/// again, so the folder can be moved.
#[test]
fn saved_scenes_name_their_models_relative_to_their_folder() {
    use keyrig_core::{MeshSource, Object};
    let dir = tempfile::tempdir().expect("tempdir");
    let models = dir.path().join("models");
    fs::create_dir(&models).expect("models folder");
    let inside = models.join("cube.glb");
    fs::write(&inside, b"not read").expect("model");
    let outside = tempfile::tempdir().expect("another folder");
    let elsewhere = outside.path().join("far.glb");
    let mut scene = Scene::default();
    for (name, path) in [("inside", &inside), ("outside", &elsewhere)] {
        let mut object = Object::new(name);
        object.mesh = Some(MeshSource::file(path.to_str().expect("utf-8"), None));
        scene.objects.push(object);
    }
    let file = dir.path().join("scene.ron");
    keyrig_io::project::save_scene(&file, &scene).expect("save");
    let text = fs::read_to_string(&file).expect("saved");
    assert!(text.contains("\"models/cube.glb\""), "{text}");
    assert!(text.contains(&format!("{:?}", elsewhere.to_str().expect("utf-8"))), "{text}");
    let back = keyrig_io::project::load_scene(&file).expect("load");
    let path = |o: usize| match &back.objects[o].mesh {
        Some(MeshSource::File { path, .. }) => PathBuf::from(path),
        other => panic!("{other:?}"),
    };
    assert_eq!(fs::canonicalize(path(0)).expect("inside"), fs::canonicalize(&inside).expect("inside"));
    assert_eq!(path(1), elsewhere);
}

/// A value with more elements than its type holds (a colour of four numbers where three are
/// expected) is an error, as `ron` reports it, never read as its first three.
#[test]
fn extra_elements_are_an_error_not_dropped() {
    let text = DEMO_RON.replacen("ambient: (0.08, 0.08, 0.08)", "ambient: (0.08, 0.08, 0.08, 0.5)", 1);
    assert_ne!(text, DEMO_RON, "the demo's ambient colour is where the test expects it");
    let line = 1 + text.lines().position(|l| l.contains("ambient:")).expect("ambient line");
    let (_, shown) = parse_err(&text);
    assert!(shown.contains(&format!(":{line}:")), "not placed on line {line}: {shown}");
}

/// Saving over a file of this version is not refused because its text mentions a newer
/// version somewhere (a comment): the version read is its `version` field.
#[test]
fn a_comment_that_mentions_a_version_is_not_the_files_version() {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join("noted.ron");
    let text =
        format!("// merged from a version: 9 draft\n{}", scene_file::to_string(&demo_scene()).unwrap());
    fs::write(&path, &text).unwrap();
    scene_file::save(&path, &demo_scene()).expect("a current file is overwritten");
    assert_eq!(fs::read_to_string(scene_file::backup_path(&path)).unwrap(), text);
}

/// A scene with many problems names the first ten, separated by `; `, and counts the rest;
/// with one problem the word is singular.
#[test]
fn many_problems_show_the_first_ten_and_count_the_rest() {
    let objects: Vec<String> = (0..12)
        .map(|i| {
            format!(
                "(name: \"O{i}\", translation: (value: (NaN, 0.0, 0.0)), rotation: (value: (0.0, 0.0, 0.0, 1.0)), scale: (value: (1.0, 1.0, 1.0)))"
            )
        })
        .collect();
    let (err, shown) = parse_err(&doc(&format!("{TIMING}\n        objects: [{}],", objects.join(", "))));
    let SceneFileError::Invalid { problems, .. } = &err else { panic!("{err:?}") };
    assert_eq!(problems.len(), 12, "{shown}");
    assert!(shown.starts_with("test.ron: invalid scene, 12 problems: "), "{shown}");
    assert!(shown.ends_with("; and 2 more"), "{shown}");
    assert_eq!(shown.matches("; ").count(), 10, "{shown}");
    assert!(
        shown.contains("objects[9].translation") && !shown.contains("objects[10].translation"),
        "{shown}"
    );

    let (_, one) = parse_err(&doc(&format!("{TIMING}\n        objects: [{}],", objects[0])));
    assert!(one.starts_with("test.ron: invalid scene, 1 problem: "), "{one}");
    assert!(!one.contains("; "), "{one}");
}

/// A document that is not a scene file at all is refused at its first character; errors
/// outside the text have no position.
#[test]
fn a_document_that_is_not_a_scene_file_is_refused_at_its_start() {
    let (err, shown) = parse_err("[1, 2]");
    assert!(shown.starts_with("test.ron:1:1: "), "{shown}");
    assert_eq!(err.position(), Some((1, 1)), "{shown}");
    let missing = scene_file::load(Path::new("/no/such/folder/scene.ron")).expect_err("no file");
    assert_eq!(missing.position(), None, "{missing}");
}

/// A scene with actions whose channels are stored (the Fox's Walk and Run, docs/actions.md)
/// saves and loads as it is, byte for byte on the second save, and plays each action again.
#[test]
fn scenes_with_stored_actions_save_and_load_as_they_are() {
    let fox = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/gltf/Fox/Fox.glb");
    let model = keyrig_io::gltf_import::import_gltf_file(&fox).expect("Fox");
    let scene = model.to_scene_all(&fox.to_string_lossy()).expect("scene");
    assert!(scene.actions.iter().filter(|a| !a.channels.is_empty()).count() == 2, "Walk and Run stored");
    let dir = tempfile::tempdir().unwrap();
    let (a, b) = (dir.path().join("a.ron"), dir.path().join("b.ron"));
    scene_file::save(&a, &scene).unwrap();
    let text = fs::read_to_string(&a).unwrap();
    assert!(
        text.contains("version: 4,") && text.contains("(name: \"Walk\", channels: [")
            || text.contains("name: \"Walk\"")
    );
    let back = scene_file::load(&a).expect("reads back");
    assert_eq!(back, scene);
    scene_file::save(&b, &back).unwrap();
    assert_eq!(fs::read(&a).unwrap(), fs::read(&b).unwrap());
    let mut walking = back.clone();
    walking.assign_action(0, Some("Walk")).expect("Walk");
    assert_eq!(walking.action_summaries()[1].keys, 378, "{:?}", walking.action_summaries());
}

/// A hand-written version-4 file with actions (also a seed of the `scene_ron` fuzz target):
/// it loads, and the stored action plays its translation and Euler keys when assigned.
#[test]
fn a_hand_written_file_with_actions_loads_and_plays_them() {
    let text = include_str!("fixtures/actions.ron");
    let mut scene = scene_file::from_str(text, Path::new("actions.ron")).expect("loads");
    assert_eq!(scene.actions.len(), 2);
    assert_eq!(scene.objects[0].action.as_deref(), Some("Slide"));
    scene.assign_action(0, Some("Hop")).expect("Hop");
    assert_eq!(scene.objects[0].translation.track.keys[1].value, glam::Vec3::Y);
    assert_eq!(scene.objects[0].rotation_euler.as_ref().map(|e| e.track.len()), Some(2));
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    // A stored path naming nothing is a problem at its place in the file.
    let bad = text.replace("object/Cube/translation", "object/Ghost/translation");
    let (err, shown) = parse_err(&bad);
    assert!(matches!(err, SceneFileError::Invalid { .. }), "{err:?}");
    assert!(shown.contains("actions[1].channels[0].path") && shown.contains("Ghost"), "{shown}");
}

/// A hand-written version-4 file with clip tracks and layers (also a seed of the `scene_ron`
/// fuzz target): it loads, saves and reads back to the same scene, and a strip naming a
/// missing action or a zero speed is refused with its place in the file.
#[test]
fn a_hand_written_file_with_clip_tracks_and_layers_round_trips() {
    let text = include_str!("fixtures/clips.ron");
    let scene = scene_file::from_str(text, Path::new("clips.ron")).expect("loads");
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    assert_eq!(scene.objects[0].clip_tracks.len(), 2);
    assert_eq!(scene.objects[0].clip_tracks[0].strips[1].repeat, 2.5);
    assert_eq!(scene.layers.len(), 2);
    assert_eq!(scene.layers[1].mode, keyrig_core::LayerMode::Override);
    let saved = scene_file::to_string(&scene).expect("saves");
    let back = scene_file::from_str(&saved, Path::new("clips.ron")).expect("reads back");
    assert_eq!(back, scene);
    for (from, to, place) in [
        (
            "action: \"Hop\", start: 30.0",
            "action: \"Skip\", start: 30.0",
            "objects[0].clip_tracks[0].strips[1].action",
        ),
        ("speed: 0.5", "speed: 0.0", "objects[0].clip_tracks[0].strips[1].speed"),
        ("blend_out: 2.0", "blend_out: 20.0", "objects[0].clip_tracks[1].strips[0].blend_out"),
        ("(name: \"Tilt\", action: \"Tilt\"", "(name: \"Tilt\", action: \"Lean\"", "layers[0].action"),
    ] {
        let bad = text.replace(from, to);
        assert_ne!(bad, text, "{from}");
        let (err, shown) = parse_err(&bad);
        assert!(matches!(err, SceneFileError::Invalid { .. }), "{err:?}");
        assert!(shown.contains(place), "{place}: {shown}");
    }
}
