//! Every check of `Scene::problems` and of channel paths, reached by one broken scene or path
//! each: the problem's field path and message, exactly.

use glam::{Quat, Vec3};
use keyrig_core::channel::ChannelPath;
use keyrig_core::track::SpinProblem;
use keyrig_core::{
    Animated, Cycle, Interpolation, Joint, Key, Light, LightKind, MeshSource, Object, RawTrack, Scene,
    Skeleton, Spin,
};

/// A valid scene: an object with a two-joint skeleton and a spot light.
fn base() -> Scene {
    let mut scene = Scene::default();
    let mut arm = Object::new("Arm");
    arm.skeleton = Some(Skeleton {
        joints: vec![
            Joint::new("upper", None, Vec3::ZERO, Quat::IDENTITY),
            Joint::new("lower", Some(0), Vec3::X, Quat::IDENTITY),
        ],
        root_translation: Animated::constant(Vec3::ZERO),
        ik_constraints: Vec::new(),
    });
    scene.objects.push(arm);
    scene.lights.push(Light {
        name: "Spot".into(),
        kind: LightKind::Spot { cutoff_deg: 30.0, inner_angle_deg: 20.0, dropoff: 1.0 },
        enabled: true,
        position: Animated::constant(Vec3::Y),
        direction: Animated::constant(Vec3::NEG_Y),
        colour: Animated::constant(Vec3::ONE),
        intensity: Animated::constant(1.0),
        attributes: Default::default(),
    });
    scene
}

fn arm(scene: &mut Scene) -> &mut Object {
    &mut scene.objects[0]
}

fn joints(scene: &mut Scene) -> &mut Vec<Joint> {
    &mut scene.objects[0].skeleton.as_mut().expect("skeleton").joints
}

fn light(scene: &mut Scene) -> &mut Light {
    &mut scene.lights[0]
}

fn spot(scene: &mut Scene) -> (&mut f32, &mut f32, &mut f32) {
    match &mut scene.lights[0].kind {
        LightKind::Spot { cutoff_deg, inner_angle_deg, dropoff } => (cutoff_deg, inner_angle_deg, dropoff),
        other => panic!("a spot light, not {other:?}"),
    }
}

fn rotation_keys(keys: Vec<Key<Quat>>) -> RawTrack<Quat> {
    RawTrack::new(keys)
}

fn quarter_x() -> Quat {
    Quat::from_rotation_x(std::f32::consts::FRAC_PI_2)
}

type Break = fn(&mut Scene);

/// (what is broken, how, the problems as `path: message`)
fn table() -> Vec<(&'static str, Break, Vec<String>)> {
    let s = |v: &[&str]| v.iter().map(|p| (*p).to_string()).collect::<Vec<_>>();
    let spin = |path: &str, problem: SpinProblem| vec![format!("{path}: {problem}")];
    vec![
        // The scene's own fields.
        ("fps zero", |sc| sc.fps = 0.0, s(&["fps: 0 must be > 0"])),
        ("fps negative", |sc| sc.fps = -1.0, s(&["fps: -1 must be > 0"])),
        ("fps +inf", |sc| sc.fps = f64::INFINITY, s(&["fps: not a finite number (+inf)"])),
        ("fps -inf", |sc| sc.fps = f64::NEG_INFINITY, s(&["fps: not a finite number (-inf)"])),
        (
            "empty frame range",
            |sc| sc.frame_range.start = 61,
            s(&["frame_range: empty range: start 61 is after end 60"]),
        ),
        ("one-frame range", |sc| sc.frame_range.start = 60, vec![]),
        ("ambient", |sc| sc.ambient.x = f32::NAN, s(&["ambient.x: not a finite number"])),
        // Names.
        ("empty object name", |sc| arm(sc).name.clear(), s(&["objects[0].name: object name is empty"])),
        (
            "object name with /",
            |sc| arm(sc).name = "a/b".into(),
            s(&["objects[0].name: object name \"a/b\" contains '/', which separates channel path parts"]),
        ),
        (
            "duplicate light name",
            |sc| {
                let copy = sc.lights[0].clone();
                sc.lights.push(copy);
            },
            s(&["lights[1].name: duplicate light name \"Spot\" (also light 0)"]),
        ),
        ("empty joint name", |sc| joints(sc)[1].name.clear(), s(&["objects[0].skeleton.joints[1].name: joint name is empty"])),
        // Object transform.
        (
            "zero static rotation",
            |sc| arm(sc).rotation.value = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0),
            s(&["objects[0].rotation.value: zero quaternion: not a rotation"]),
        ),
        (
            "non-finite scale",
            |sc| arm(sc).scale.value.z = f32::INFINITY,
            s(&["objects[0].scale.value.z: not a finite number"]),
        ),
        // Skeleton.
        (
            "no joints",
            |sc| joints(sc).clear(),
            s(&["objects[0].skeleton.joints: a skeleton needs at least one joint"]),
        ),
        (
            "first joint with a parent",
            |sc| joints(sc)[0].parent = Some(0),
            s(&["objects[0].skeleton.joints[0].parent: the first joint must be the root (parent None)"]),
        ),
        (
            "joint its own parent",
            |sc| joints(sc)[1].parent = Some(1),
            s(&["objects[0].skeleton.joints[1].parent: parent 1 must come before joint 1 (joints are stored parents first)"]),
        ),
        (
            "parent out of range",
            |sc| joints(sc)[1].parent = Some(2),
            s(&["objects[0].skeleton.joints[1].parent: parent 2 is out of range (the skeleton has 2 joints)"]),
        ),
        (
            "second root",
            |sc| joints(sc)[1].parent = None,
            s(&["objects[0].skeleton.joints[1].parent: only the first joint may be a root (parent None); give this joint a parent"]),
        ),
        (
            "rest translation",
            |sc| joints(sc)[1].rest_translation.y = f32::NAN,
            s(&["objects[0].skeleton.joints[1].rest_translation.y: not a finite number"]),
        ),
        (
            "zero rest rotation",
            |sc| joints(sc)[1].rest_rotation = Quat::from_xyzw(0.0, 0.0, 0.0, 0.0),
            s(&["objects[0].skeleton.joints[1].rest_rotation: zero quaternion: not a rotation"]),
        ),
        (
            "non-finite rest rotation",
            |sc| joints(sc)[1].rest_rotation = Quat::from_xyzw(0.0, 0.0, 0.0, f32::NAN),
            s(&["objects[0].skeleton.joints[1].rest_rotation.w: not a finite number"]),
        ),
        (
            "joint translation and scale",
            |sc| {
                joints(sc)[1].translation.value.x = f32::NAN;
                joints(sc)[1].scale.value.y = f32::NAN;
            },
            s(&[
                "objects[0].skeleton.joints[1].translation.value.x: not a finite number",
                "objects[0].skeleton.joints[1].scale.value.y: not a finite number",
            ]),
        ),
        (
            "root translation",
            |sc| sc.objects[0].skeleton.as_mut().unwrap().root_translation.value.x = f32::NEG_INFINITY,
            s(&["objects[0].skeleton.root_translation.value.x: not a finite number"]),
        ),
        // Deformer.
        (
            "blend fractions",
            |sc| {
                arm(sc).deformer.blend_parent_fraction = 1.5;
                arm(sc).deformer.blend_child_fraction = -0.25;
            },
            s(&[
                "objects[0].deformer.blend_parent_fraction: 1.5 is outside [0, 1]",
                "objects[0].deformer.blend_child_fraction: -0.25 is outside [0, 1]",
            ]),
        ),
        (
            "blend fraction limits",
            |sc| {
                arm(sc).deformer.blend_parent_fraction = 0.0;
                arm(sc).deformer.blend_child_fraction = 1.0;
            },
            vec![],
        ),
        (
            "non-finite blend fraction",
            |sc| arm(sc).deformer.blend_child_fraction = f32::NAN,
            s(&["objects[0].deformer.blend_child_fraction: not a finite number (NaN)"]),
        ),
        // Model files.
        (
            "empty model path and clip",
            |sc| arm(sc).mesh = Some(MeshSource::File { path: String::new(), mesh: None, clip: Some(String::new()), fps: None }),
            s(&[
                "objects[0].mesh.path: empty model file path",
                "objects[0].mesh.clip: empty clip name (leave the field out to play every frame)",
            ]),
        ),
        // Keys.
        (
            "key time",
            |sc| arm(sc).translation.track = RawTrack::new(vec![Key::new(f64::NAN, Vec3::ZERO)]),
            s(&["objects[0].translation.track[0].time: not a finite number (NaN)"]),
        ),
        (
            "duplicate key time",
            |sc| arm(sc).translation.track = RawTrack::new(vec![Key::new(1.0, Vec3::ZERO), Key::new(1.0, Vec3::X)]),
            s(&["objects[0].translation.track[1].time: duplicate key time 1 s (same as key 0)"]),
        ),
        (
            "key T/C/B not finite",
            |sc| {
                let mut key = Key::new(0.0, Vec3::ZERO);
                key.tcb.bias = f32::NAN;
                arm(sc).translation.track = RawTrack::new(vec![key]);
            },
            s(&["objects[0].translation.track[0].tcb.bias: not a finite number (NaN)"]),
        ),
        (
            "key T/C/B limits",
            |sc| {
                let mut key = Key::new(0.0, Vec3::ZERO);
                key.tcb.tension = -1.0;
                key.tcb.continuity = 1.0;
                arm(sc).translation.track = RawTrack::new(vec![key]);
            },
            vec![],
        ),
        (
            "continuity out of range",
            |sc| {
                let mut key = Key::new(0.0, Vec3::ZERO);
                key.tcb.continuity = -1.5;
                arm(sc).translation.track = RawTrack::new(vec![key]);
            },
            s(&["objects[0].translation.track[0].tcb.continuity: -1.5 is outside [-1, 1]"]),
        ),
        (
            "tangents not finite",
            |sc| {
                let mut key = Key::new(0.0, Vec3::ZERO);
                key.in_tangent = Some(Vec3::new(f32::NAN, 0.0, 0.0));
                key.out_tangent = Some(Vec3::new(0.0, 0.0, f32::INFINITY));
                arm(sc).translation.track = RawTrack::new(vec![key]);
            },
            s(&[
                "objects[0].translation.track[0].in_tangent.x: not a finite number",
                "objects[0].translation.track[0].out_tangent.z: not a finite number",
            ]),
        ),
        (
            "scalar key value",
            |sc| light(sc).intensity.track = RawTrack::new(vec![Key::new(0.0, f32::NAN)]),
            s(&["lights[0].intensity.track[0].value: not a finite number"]),
        ),
        // Cycles.
        (
            "cycle on one key",
            |sc| {
                let translation = &mut arm(sc).translation;
                translation.track = RawTrack::new(vec![Key::new(0.0, Vec3::ZERO)]);
                translation.after = Cycle::Repeat;
            },
            s(&["objects[0].translation.after: Repeat after the keys needs at least two keys (a cycle repeats the time from the first key to the last)"]),
        ),
        (
            "cycle over unsorted keys",
            |sc| {
                let translation = &mut arm(sc).translation;
                translation.track = RawTrack::new(vec![Key::new(1.0, Vec3::ZERO), Key::new(0.5, Vec3::X)]);
                translation.before = Cycle::PingPong;
            },
            s(&[
                "objects[0].translation.track[1].time: keys out of order: 0.5 s comes after key 0 at 1 s",
                "objects[0].translation.before: Ping-pong before the keys needs a positive, finite period (last key time − first key time)",
            ]),
        ),
        (
            "cycle on a value without keys",
            |sc| arm(sc).translation.after = Cycle::Repeat,
            vec![],
        ),
        // Spins.
        (
            "spin on a vector key",
            |sc| {
                arm(sc).translation.track = RawTrack::new(vec![
                    Key::new(0.0, Vec3::ZERO),
                    Key::new(1.0, Vec3::X).with_spin(Spin::Turns(1)),
                ]);
            },
            spin("objects[0].translation.track[1].spin", SpinProblem::NotARotation),
        ),
        (
            "spin on the first key",
            |sc| arm(sc).rotation.track = rotation_keys(vec![Key::new(0.0, Quat::IDENTITY).with_spin(Spin::Turns(1))]),
            spin("objects[0].rotation.track[0].spin", SpinProblem::FirstKey),
        ),
        (
            "spin out of range",
            |sc| {
                arm(sc).rotation.track = rotation_keys(vec![
                    Key::new(0.0, Quat::IDENTITY),
                    Key::new(1.0, quarter_x()).with_spin(Spin::Turns(1001)),
                ]);
            },
            spin("objects[0].rotation.track[1].spin", SpinProblem::OutOfRange),
        ),
        (
            "spin ending a Hermite segment",
            |sc| {
                let mut start = Key::new(0.0, Quat::IDENTITY).with_interpolation(Interpolation::Hermite);
                start.out_tangent = Some(Quat::from_xyzw(0.0, 0.0, 0.0, 0.0));
                let mut end = Key::new(1.0, quarter_x()).with_spin(Spin::Turns(1));
                end.in_tangent = Some(Quat::from_xyzw(0.0, 0.0, 0.0, 0.0));
                arm(sc).rotation.track = rotation_keys(vec![start, end]);
            },
            spin("objects[0].rotation.track[1].spin", SpinProblem::AfterHermite),
        ),
        (
            "Turns between equal keys",
            |sc| {
                arm(sc).rotation.track = rotation_keys(vec![
                    Key::new(0.0, Quat::IDENTITY),
                    Key::new(1.0, Quat::IDENTITY).with_spin(Spin::Turns(1)),
                ]);
            },
            spin("objects[0].rotation.track[1].spin", SpinProblem::AmbiguousAxis),
        ),
        (
            "Angle that does not arrive at the value",
            |sc| {
                arm(sc).rotation.track = rotation_keys(vec![
                    Key::new(0.0, Quat::IDENTITY),
                    Key::new(1.0, Quat::IDENTITY).with_spin(Spin::Angle { axis: Vec3::X, degrees: 90.0 }),
                ]);
            },
            spin("objects[0].rotation.track[1].spin", SpinProblem::Disagrees),
        ),
        (
            "Angle that arrives at the value",
            |sc| {
                arm(sc).rotation.track = rotation_keys(vec![
                    Key::new(0.0, Quat::IDENTITY),
                    Key::new(1.0, quarter_x()).with_spin(Spin::Angle { axis: Vec3::X, degrees: 450.0 }),
                ]);
            },
            vec![],
        ),
        // Lights.
        (
            "zero spot direction key",
            |sc| light(sc).direction.track = RawTrack::new(vec![Key::new(0.0, Vec3::NEG_Y), Key::new(1.0, Vec3::ZERO)]),
            s(&["lights[0].direction.track[1].value: zero direction"]),
        ),
        (
            "a point light needs no direction",
            |sc| {
                light(sc).kind = LightKind::Point;
                light(sc).direction.value = Vec3::ZERO;
            },
            vec![],
        ),
        (
            "negative colour key",
            |sc| light(sc).colour.track = RawTrack::new(vec![Key::new(0.0, Vec3::new(1.0, -1.0, 1.0))]),
            vec![format!("lights[0].colour.track[0].value: negative colour component in {}", Vec3::new(1.0, -1.0, 1.0))],
        ),
        (
            "negative intensity key",
            |sc| light(sc).intensity.track = RawTrack::new(vec![Key::new(0.0, 1.0), Key::new(1.0, -0.5)]),
            s(&["lights[0].intensity.track[1].value: negative intensity -0.5"]),
        ),
        (
            "cutoff zero",
            |sc| *spot(sc).0 = 0.0,
            s(&[
                "lights[0].kind.cutoff_deg: 0° is outside (0°, 90°]",
                "lights[0].kind.inner_angle_deg: 20° must be in (0°, cutoff_deg = 0°]",
            ]),
        ),
        ("cutoff 90°", |sc| *spot(sc).0 = 90.0, vec![]),
        ("cutoff over 90°", |sc| *spot(sc).0 = 90.5, s(&["lights[0].kind.cutoff_deg: 90.5° is outside (0°, 90°]"])),
        (
            "inner angle zero",
            |sc| *spot(sc).1 = 0.0,
            s(&["lights[0].kind.inner_angle_deg: 0° must be in (0°, cutoff_deg = 30°]"]),
        ),
        ("inner angle at the cutoff", |sc| *spot(sc).1 = 30.0, vec![]),
        (
            "cutoff not finite",
            |sc| *spot(sc).0 = f32::NAN,
            s(&["lights[0].kind.cutoff_deg: not a finite number (NaN)"]),
        ),
        (
            "inner angle not finite",
            |sc| *spot(sc).1 = f32::INFINITY,
            s(&["lights[0].kind.inner_angle_deg: not a finite number (+inf)"]),
        ),
        ("dropoff negative", |sc| *spot(sc).2 = -0.5, s(&["lights[0].kind.dropoff: negative dropoff -0.5"])),
        ("dropoff zero", |sc| *spot(sc).2 = 0.0, vec![]),
        ("dropoff not finite", |sc| *spot(sc).2 = f32::NAN, s(&["lights[0].kind.dropoff: not a finite number (NaN)"])),
        // Camera.
        (
            "camera numbers not finite",
            |sc| {
                sc.camera.target.z = f32::NAN;
                sc.camera.yaw_deg = f32::INFINITY;
                sc.camera.pitch_deg = f32::NAN;
            },
            s(&[
                "camera.target.z: not a finite number",
                "camera.yaw_deg: not a finite number (+inf)",
                "camera.pitch_deg: not a finite number (NaN)",
            ]),
        ),
        ("camera distance zero", |sc| sc.camera.distance = 0.0, s(&["camera.distance: 0 must be > 0"])),
        ("field of view 180°", |sc| sc.camera.fov_y_deg = 180.0, s(&["camera.fov_y_deg: 180° is outside (0°, 180°)"])),
        ("field of view 0°", |sc| sc.camera.fov_y_deg = 0.0, s(&["camera.fov_y_deg: 0° is outside (0°, 180°)"])),
        ("field of view NaN", |sc| sc.camera.fov_y_deg = f32::NAN, s(&["camera.fov_y_deg: not a finite number (NaN)"])),
    ]
}

#[test]
fn the_base_scene_is_valid() {
    assert_eq!(base().problems(), Vec::new());
}

#[test]
fn every_check_reports_its_field_and_problem() {
    for (what, break_it, expected) in table() {
        let mut scene = base();
        break_it(&mut scene);
        let got: Vec<String> = scene.problems().iter().map(ToString::to_string).collect();
        assert_eq!(got, expected, "{what}");
    }
}

#[test]
fn channel_path_syntax_errors_name_the_problem() {
    for (path, problem) in [
        ("object", "missing property"),
        ("light/Key", "missing property"),
        ("object/Arm/rotation/x", "too many parts"),
        ("light/Key/intensity/x", "too many parts"),
        ("object/Arm/joint", "a joint channel is object/<name>/joint/<joint>/<property>"),
        ("object/Arm/joint/elbow/rotation/x", "a joint channel is object/<name>/joint/<joint>/<property>"),
        ("/object/Arm/rotation", "empty part"),
        ("object/Arm/rotation/", "empty part"),
        ("camera", "missing property"),
        ("camera/Shot/lens/x", "too many parts"),
        ("lamp", "unknown kind \"lamp\""),
    ] {
        let err = ChannelPath::parse(path).expect_err(path).to_string();
        assert!(err.contains(problem), "{path}: {err}");
        assert!(err.contains(path), "{path}: the error names the path: {err}");
    }
    for path in
        ["light/Key/position", "light/Key/direction", "light/Key/color", "object/Arm/joint/elbow/translation"]
    {
        assert!(ChannelPath::parse(path).is_ok(), "{path}");
    }
}
