//! Actions (docs/actions.md): every key lives in one place, switching actions loses nothing,
//! and the problems of a scene's actions are found.

use glam::{Quat, Vec3};
use keyrig_core::{
    Action, ActionChannel, ActionKeys, Animated, Joint, Key, Object, RawTrack, Scene, Skeleton,
};

fn moving(keys: &[(f64, f32)]) -> Animated<Vec3> {
    let keys = keys.iter().map(|&(t, x)| Key::new(t, Vec3::new(x, 0.0, 0.0))).collect();
    Animated::new(Vec3::ZERO, RawTrack::new(keys))
}

fn turning(degrees: f32) -> Animated<Quat> {
    Animated::new(
        Quat::IDENTITY,
        RawTrack::new(vec![
            Key::new(0.0, Quat::IDENTITY),
            Key::new(1.0, Quat::from_rotation_z(degrees.to_radians())),
        ]),
    )
}

/// A cube keyed in "Walk" and an arm with a joint, with no action named yet.
fn scene() -> Scene {
    let mut scene = Scene::default();
    let mut cube = Object::new("Cube");
    cube.translation = moving(&[(0.0, 0.0), (1.0, 2.0)]);
    let mut arm = Object::new("Arm");
    let mut elbow = Joint::new("elbow", None, Vec3::ZERO, Quat::IDENTITY);
    elbow.rotation = turning(90.0);
    arm.skeleton = Some(Skeleton::new(vec![elbow]));
    scene.objects = vec![cube, arm];
    scene
}

#[test]
fn assigning_actions_swaps_keys_and_loses_nothing() {
    let mut scene = scene();
    scene.name_unnamed_keys("Walk");
    assert_eq!(scene.objects[0].action.as_deref(), Some("Walk"));
    assert_eq!(scene.objects[1].action.as_deref(), Some("Walk"));
    let walking = scene.clone();

    // A new action on the cube: its keys go into Walk, it plays nothing.
    scene.new_action(0, "Run").expect("new");
    assert_eq!(scene.objects[0].action.as_deref(), Some("Run"));
    assert!(!scene.objects[0].translation.is_animated());
    let walk = &scene.actions[scene.action_index("Walk").expect("Walk")];
    assert_eq!(walk.channels.len(), 1);
    assert_eq!(walk.channels[0].path, "object/Cube/translation");
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());

    // Key the cube in Run, switch back: Walk's keys return, Run keeps its own.
    scene.objects[0].translation = moving(&[(0.0, 5.0), (0.5, 6.0)]);
    scene.assign_action(0, Some("Walk")).expect("assign");
    assert_eq!(scene.objects[0].translation, walking.objects[0].translation);
    let run = &scene.actions[scene.action_index("Run").expect("Run")];
    assert_eq!(run.channels.len(), 1);
    assert!(
        matches!(&run.channels[0].keys, ActionKeys::Vec3(a) if a.track.len() == 2 && a.track.keys[0].value.x == 5.0)
    );
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());

    // Back and forth again: identical scenes.
    let before = scene.clone();
    scene.assign_action(0, Some("Run")).expect("assign");
    scene.assign_action(0, Some("Walk")).expect("assign");
    assert_eq!(scene, before);
    // The arm was never touched.
    assert_eq!(scene.objects[1], walking.objects[1]);
}

#[test]
fn keys_without_an_action_are_kept_in_one_named_after_the_object() {
    let mut scene = scene();
    scene.objects[0].action = None;
    scene.assign_action(0, None).expect("no change");
    scene.actions.push(Action { name: "Idle".into(), channels: Vec::new() });
    scene.assign_action(0, Some("Idle")).expect("assign");
    let kept = scene.action_index("CubeAction").expect("the cube's keys are kept in CubeAction");
    assert_eq!(scene.actions[kept].channels[0].path, "object/Cube/translation");
    scene.assign_action(0, Some("CubeAction")).expect("assign");
    assert!(scene.objects[0].translation.is_animated());
}

#[test]
fn duplicate_rename_and_delete() {
    let mut scene = scene();
    scene.name_unnamed_keys("Walk");
    scene.duplicate_action(1, "Walk.copy").expect("duplicate");
    assert_eq!(scene.objects[1].action.as_deref(), Some("Walk.copy"));
    // The copy plays the same keys; the original keeps them stored.
    assert!(scene.objects[1].skeleton.as_ref().expect("skeleton").joints[0].rotation.is_animated());
    let walk = &scene.actions[scene.action_index("Walk").expect("Walk")];
    assert_eq!(walk.channels.len(), 1);
    assert_eq!(walk.channels[0].path, "object/Arm/joint/elbow/rotation");
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());

    scene.rename_action("Walk", "Stroll").expect("rename");
    assert_eq!(scene.objects[0].action.as_deref(), Some("Stroll"));
    assert!(scene.rename_action("Stroll", "Walk.copy").is_err(), "a taken name is refused");
    assert!(scene.rename_action("Stroll", "a/b").is_err(), "'/' is refused");

    scene.delete_action("Walk.copy").expect("delete");
    assert_eq!(scene.objects[1].action, None);
    assert!(!scene.objects[1].skeleton.as_ref().expect("skeleton").joints[0].rotation.is_animated());
    scene.assign_action(1, Some("Stroll")).expect("assign");
    assert!(scene.objects[1].skeleton.as_ref().expect("skeleton").joints[0].rotation.is_animated());
    assert!(scene.assign_action(1, Some("Nope")).is_err());
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
}

#[test]
fn renaming_an_object_or_a_joint_renames_the_stored_paths() {
    let mut scene = scene();
    scene.name_unnamed_keys("Walk");
    scene.new_action(1, "Idle").expect("new");
    scene.objects[1].name = "Limb".into();
    scene.rename_in_actions("Arm", None, "Limb");
    scene.objects[1].skeleton.as_mut().expect("skeleton").joints[0].name = "knee".into();
    scene.rename_in_actions("Limb", Some("elbow"), "knee");
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    scene.assign_action(1, Some("Walk")).expect("assign");
    assert!(scene.objects[1].skeleton.as_ref().expect("skeleton").joints[0].rotation.is_animated());
}

#[test]
fn euler_keys_travel_with_their_action() {
    let mut scene = scene();
    scene.objects[0].rotation_euler = Some(moving(&[(0.0, 0.0), (1.0, 720.0)]));
    scene.name_unnamed_keys("Spin");
    scene.new_action(0, "Still").expect("new");
    assert!(scene.objects[0].rotation_euler.as_ref().is_none_or(|e| !e.is_animated()));
    scene.objects[0].rotation = turning(45.0);
    scene.assign_action(0, Some("Spin")).expect("assign");
    assert_eq!(scene.objects[0].rotation_euler.as_ref().map(|e| e.track.len()), Some(2));
    assert!(!scene.objects[0].rotation.is_animated());
    scene.assign_action(0, Some("Still")).expect("assign");
    assert!(scene.objects[0].rotation_euler.is_none(), "quaternion keys play without Euler keys");
    assert!(scene.objects[0].rotation.is_animated());
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
}

#[test]
fn playing_one_action_and_summaries() {
    let mut scene = scene();
    scene.name_unnamed_keys("Walk");
    scene.new_action(0, "Run").expect("new");
    scene.objects[0].translation = moving(&[(0.0, 5.0), (2.0, 6.0)]);
    let run = scene.playing_action("Run", true).expect("Run");
    assert!(run.objects[0].translation.is_animated());
    assert!(run.keyed_channels_of(1).is_empty(), "the arm plays no keys of Run");
    let walk = scene.playing_action("Walk", false).expect("Walk");
    assert_eq!(walk.objects[0].action.as_deref(), Some("Walk"));
    assert_eq!(walk.objects[0].translation.track.keys[1].value.x, 2.0);
    let summaries = scene.action_summaries();
    assert_eq!(summaries[0].name, "Walk");
    assert_eq!(summaries[0].active_on, ["Arm"]);
    assert_eq!((summaries[0].channels, summaries[0].keys), (2, 4));
    assert_eq!(summaries[1].time_range, Some((0.0, 2.0)));
}

#[test]
fn problems_of_actions_name_the_place() {
    let mut scene = scene();
    scene.objects[0].action = Some("Missing".into());
    scene.actions = vec![
        Action { name: "A".into(), channels: Vec::new() },
        Action { name: "A".into(), channels: Vec::new() },
        Action {
            name: "B".into(),
            channels: vec![
                ActionChannel {
                    path: "object/Nobody/translation".into(),
                    keys: ActionKeys::Vec3(moving(&[(0.0, 1.0)])),
                },
                ActionChannel {
                    path: "object/Cube/rotation".into(),
                    keys: ActionKeys::Vec3(moving(&[(0.0, 1.0)])),
                },
                ActionChannel {
                    path: "light/Sun/intensity".into(),
                    keys: ActionKeys::Scalar(Animated::constant(1.0)),
                },
                ActionChannel {
                    path: "object/Cube/scale".into(),
                    keys: ActionKeys::Vec3(moving(&[(1.0, 1.0), (0.0, 2.0)])),
                },
            ],
        },
    ];
    let problems: Vec<String> = scene.problems().iter().map(ToString::to_string).collect();
    let has = |path: &str, text: &str| problems.iter().any(|p| p.starts_with(path) && p.contains(text));
    assert!(has("objects[0].action", "no action \"Missing\""), "{problems:#?}");
    assert!(has("actions[1].name", "duplicate action name"), "{problems:#?}");
    assert!(has("actions[2].channels[0].path", "Nobody"), "{problems:#?}");
    assert!(has("actions[2].channels[1].keys", "Rotation"), "{problems:#?}");
    assert!(has("actions[2].channels[2].path", "light"), "{problems:#?}");
    assert!(has("actions[2].channels[3].keys", "out of order"), "{problems:#?}");
}

#[test]
fn keys_in_no_action_duplicated_under_the_objects_default_name_are_one_action() {
    let mut scene = scene();
    scene.duplicate_action(0, "CubeAction").expect("duplicate");
    assert_eq!(scene.objects[0].action.as_deref(), Some("CubeAction"));
    assert!(scene.objects[0].translation.is_animated(), "the keys play on");
    assert_eq!(scene.actions.iter().filter(|a| a.name == "CubeAction").count(), 1);
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    // Pushed down: one strip of it, nothing lost.
    let track = scene.push_down(1).expect("the arm's keys");
    assert_eq!(scene.objects[1].clip_tracks[track].strips[0].action, "ArmAction");
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
}
