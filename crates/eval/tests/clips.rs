//! Clip tracks and layers given bad numbers (docs/clips.md, "Checks"): each problem is found at
//! its field path, and the scene still evaluates without panicking.

use std::collections::HashMap;

use glam::{Quat, Vec3};
use keyrig_core::{Animated, ClipTrack, Joint, Key, Layer, Object, RawTrack, Scene, Skeleton, Strip};
use keyrig_eval::{Overrides, SceneEvaluator};

/// An arm whose elbow turns in action "Bend" (stored) while it plays "Rest".
fn scene() -> Scene {
    let mut scene = Scene::default();
    let mut arm = Object::new("Arm");
    let mut elbow = Joint::new("elbow", None, Vec3::ZERO, Quat::IDENTITY);
    elbow.rotation = Animated::new(
        Quat::IDENTITY,
        RawTrack::new(vec![Key::new(0.0, Quat::IDENTITY), Key::new(1.0, Quat::from_rotation_z(1.0))]),
    );
    arm.skeleton = Some(Skeleton::new(vec![elbow]));
    scene.objects.push(arm);
    scene.name_unnamed_keys("Bend");
    scene.new_action(0, "Rest").expect("Rest");
    scene.objects[0].clip_tracks.push(ClipTrack {
        name: "Base".into(),
        strips: vec![Strip::new("Bend", 0.0, 0.0, 30.0)],
        ..ClipTrack::default()
    });
    scene
}

fn problems_of(edit: impl FnOnce(&mut Scene)) -> Vec<String> {
    let mut s = scene();
    edit(&mut s);
    // Whatever the numbers, the scene evaluates at every frame without panicking.
    let eval = SceneEvaluator::new(&s, &HashMap::new());
    for f in -5..=40 {
        let state = eval.evaluate(f64::from(f) / 30.0, &Overrides::new());
        assert_eq!(state.objects.len(), 1);
    }
    s.problems().into_iter().map(|p| format!("{}: {}", p.path, p.message)).collect()
}

fn strip(edit: impl FnOnce(&mut Strip)) -> Vec<String> {
    problems_of(|s| edit(&mut s.objects[0].clip_tracks[0].strips[0]))
}

#[test]
fn a_good_strip_bends_the_elbow() {
    assert!(problems_of(|_| {}).is_empty());
    let s = scene();
    let eval = SceneEvaluator::new(&s, &HashMap::new());
    let pose = eval.object_at(0, 1.0, &Overrides::new()).expect("arm").pose.expect("pose");
    assert!(pose.local_rotations[0].angle_between(Quat::from_rotation_z(1.0)) < 1e-5);
}

#[test]
fn bad_strips_are_named_where_they_are() {
    let at = "objects[0].clip_tracks[0].strips[0]";
    let has = |problems: Vec<String>, path: &str, words: &str| {
        assert!(
            problems.iter().any(|p| p.starts_with(&format!("{at}.{path}:")) && p.contains(words)),
            "{path} {words}: {problems:?}"
        );
    };
    has(strip(|s| s.action = "Missing".into()), "action", "no action \"Missing\"");
    has(strip(|s| s.speed = 0.0), "speed", "must be > 0");
    has(strip(|s| s.speed = -2.0), "speed", "must be > 0");
    has(strip(|s| s.speed = f64::NAN), "speed", "not a finite number (NaN)");
    has(strip(|s| s.repeat = 0.0), "repeat", "must be > 0");
    has(strip(|s| s.action_out = -1.0), "action_out", "must be after action_in");
    has(strip(|s| s.blend_in = -1.0), "blend_in", "must be ≥ 0");
    has(
        strip(|s| {
            s.blend_in = 20.0;
            s.blend_out = 20.0;
        }),
        "blend_out",
        "longer than the strip",
    );
    has(strip(|s| s.influence = Animated::constant(1.5)), "influence", "outside 0..=1");
    has(
        strip(|s| s.influence = Animated::new(1.0, RawTrack::new(vec![Key::new(0.0, -0.5)]))),
        "influence",
        "outside 0..=1",
    );
    let overlap = problems_of(|s| {
        let mut second = Strip::new("Bend", 10.0, 0.0, 30.0);
        second.speed = 1e300;
        s.objects[0].clip_tracks[0].strips.push(second);
    });
    assert!(
        overlap.iter().any(|p| p.starts_with("objects[0].clip_tracks[0].strips[1].start:")),
        "{overlap:?}"
    );
    let twice = problems_of(|s| {
        let track = s.objects[0].clip_tracks[0].clone();
        s.objects[0].clip_tracks.push(track);
    });
    assert!(twice.iter().any(|p| p.starts_with("objects[0].clip_tracks[1].name:")), "{twice:?}");
}

#[test]
fn bad_layers_are_named_where_they_are() {
    let missing = problems_of(|s| s.layers.push(Layer::new("Fix", "Nothing")));
    assert!(
        missing.iter().any(|p| p.starts_with("layers[0].action:") && p.contains("no action")),
        "{missing:?}"
    );
    let active = problems_of(|s| s.layers.push(Layer::new("Fix", "Rest")));
    assert!(
        active.iter().any(|p| p.starts_with("layers[0].action:") && p.contains("active on")),
        "{active:?}"
    );
    let heavy = problems_of(|s| {
        let mut layer = Layer::new("Fix", "Bend");
        layer.weight = Animated::constant(f32::NAN);
        s.layers.push(layer);
    });
    assert!(heavy.iter().any(|p| p.starts_with("layers[0].weight")), "{heavy:?}");
    // A layer whose action keys an item the scene lacks: the action's stored channel is named.
    let gone = problems_of(|s| {
        s.objects[0].skeleton.as_mut().expect("skeleton").joints[0].name = "wrist".into();
        s.layers.push(Layer::new("Fix", "Bend"));
    });
    assert!(gone.iter().any(|p| p.starts_with("actions[0].channels[0].path")), "{gone:?}");
}
