//! `assets/showcase.ron`, the shipped scene of issue 31 item 4: a camera that dollies and
//! zooms, a marker that cuts to a second camera tracking the twisting arm, a spot light that
//! changes colour and cone, a cube that fades out and is hidden, and the arm's deformer
//! switching from linear blend to bones blending in the middle of its twist, then its blend
//! zone widening. The file opens
//! without problems, is in the scene writer's own form (saving it writes the same bytes), and
//! the scene evaluator plays each of those changes at the times the guide names.
//! (`crates/editor/tests/cli_showcase.rs` renders it through its cameras.)

use std::collections::HashMap;
use std::path::Path;

use keyrig_core::channel::{ChannelPath, ChannelValue};
use keyrig_core::{AimTarget, DeformerKind, Lens, LightKind, Projection};
use keyrig_eval::SceneEvaluator;
use keyrig_io::scene_file;
use keyrig_skin::BlendZone;

fn path() -> std::path::PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/showcase.ron")
}

#[test]
fn showcase_opens_in_the_writers_form() {
    let text = std::fs::read_to_string(path()).expect("read assets/showcase.ron");
    let scene = scene_file::load(&path()).expect("assets/showcase.ron opens without problems");
    let written = scene_file::to_string(&scene).expect("serialize");
    let first_difference = written.lines().zip(text.lines()).position(|(a, b)| a != b);
    assert!(written == text, "saving the showcase changes it (from line {first_difference:?} on)");
    let eval = SceneEvaluator::new(&scene, &HashMap::new());
    assert!(eval.problems().is_empty(), "{:?}", eval.problems());
}

fn sample(scene: &keyrig_core::Scene, path: &str, time: f64) -> ChannelValue {
    ChannelPath::parse(path).expect("path").resolve(scene).expect("channel").sample(time)
}

fn scalar(value: ChannelValue) -> f32 {
    match value {
        ChannelValue::Scalar(v) => v,
        other => panic!("not a scalar: {other:?}"),
    }
}

#[test]
fn showcase_plays_what_the_guide_says() {
    let scene = scene_file::load(&path()).expect("opens");
    let eval = SceneEvaluator::new(&scene, &HashMap::new());
    let at = |t: f64| eval.evaluate(t, &Default::default());
    let fps = scene.fps;

    // Dolly: moves in and zooms from a 20 mm to a 35 mm lens over the first 1.4 s, aimed at
    // the elbow; it is the active camera until the marker at frame 45 cuts to Track.
    let dolly = scene.camera_index("Dolly").expect("Dolly");
    let track = scene.camera_index("Track").expect("Track");
    assert!(matches!(scene.cameras[dolly].projection, Projection::FocalLength { .. }));
    let (start, end) = (at(0.0), at(1.4));
    let travelled = start.cameras[dolly].eye().distance(end.cameras[dolly].eye());
    assert!(travelled > 2.0, "the dolly moves {travelled} units");
    assert_eq!(scalar(sample(&scene, "camera/Dolly/lens", 0.0)), 20.0);
    assert_eq!(scalar(sample(&scene, "camera/Dolly/lens", 1.4)), 35.0);
    let fov = |state: &keyrig_eval::SceneState| match state.cameras[dolly].lens {
        Lens::Perspective { fov_y } => fov_y,
        Lens::Orthographic { .. } => panic!("Dolly is a perspective camera"),
    };
    assert!(fov(&end) < fov(&start), "it zooms in");
    let marker = scene.markers.iter().find(|m| m.camera.as_deref() == Some("Track")).expect("a cut to Track");
    assert_eq!(marker.frame, 45);
    assert_eq!(scene.active_camera_at(44.0), Some(dolly));
    assert_eq!(scene.active_camera_at(45.0), Some(track));

    // Track aims at the twisting arm: at every sampled frame its view axis passes through the
    // wrist joint's world position.
    let aim = scene.cameras[track].aim.as_ref().expect("Track aims");
    assert_eq!(aim.target, AimTarget::Joint { object: "Arm".into(), joint: "wrist".into() });
    let arm = scene.objects.iter().position(|o| o.name == "Arm").expect("Arm");
    for frame in [45, 70, 100, 120] {
        let state = at(f64::from(frame) / fps);
        let object = &state.objects[arm];
        let wrist = object.world_from_object.transform_point3(
            object.palette.as_ref().expect("palette").model_from_joint[3].translation.into(),
        );
        let camera = &state.cameras[track];
        let to_wrist = (wrist - camera.eye()).normalize();
        assert!(to_wrist.dot(camera.forward()) > 0.99999, "frame {frame}: Track looks past the wrist");
    }

    // The forearm turns a full 360° from 1 s to 4 s; the deformer is linear blend (1) until
    // 2.5 s, in the middle of the turn, and bones blending (2) from then on.
    let twist = ChannelPath::parse("object/Arm/joint/forearm/rotation").unwrap().resolve(&scene).unwrap();
    let spin = |t: f64| twist.spin_degrees(t).expect("inside the spin segment");
    assert!((spin(4.0) - 360.0).abs() < 1e-6);
    assert!((spin(2.5) - 180.0).abs() < 1e-3, "the switch is at the half turn: {}", spin(2.5));
    assert_eq!(at(2.5 - 1.0 / fps).objects[arm].look.deformer, DeformerKind::LinearBlend);
    assert_eq!(at(2.5).objects[arm].look.deformer, DeformerKind::BonesBlending);
    assert_eq!(at(0.0).objects[arm].look.deformer, DeformerKind::LinearBlend);
    // Then the bones-blending zone widens from a quarter of each bone to 0.6 over a second.
    assert_eq!(at(2.5).objects[arm].look.blend_zone, Some(BlendZone::default()));
    let wide = at(3.5).objects[arm].look.blend_zone.expect("keyed zone");
    assert!((wide.parent_fraction - 0.6).abs() < 1e-6 && (wide.child_fraction - 0.6).abs() < 1e-6);
    let state = at(3.5);
    let (zone, bindings) = state.objects[arm].zone_bindings.as_ref().expect("bound for the keyed zone");
    assert_eq!(*zone, wide);
    let skin = eval.skin(arm).expect("skinned");
    assert_eq!(**bindings, skin.mesh.bindings(wide).expect("bindings"));
    assert_ne!(bindings.bones_blending, skin.bindings.bones_blending, "a wider zone blends more vertices");

    // The cube fades from opaque (0.2 s) to clear (1 s) and is hidden from 1 s on.
    let cube = scene.objects.iter().position(|o| o.name == "Cube").expect("Cube");
    let look = |t: f64| at(t).objects[cube].look.clone();
    assert_eq!((look(0.2).opacity, look(0.2).visible), (1.0, true));
    assert!((look(0.6).opacity - 0.5).abs() < 1e-6, "half faded at 0.6 s: {}", look(0.6).opacity);
    assert!(look(1.0 - 1.0 / fps).visible);
    assert!(!look(1.0).visible && !look(3.0).visible);

    // The key light turns from warm to cool and its cone opens from 9° to 40°.
    let key = scene.lights.iter().position(|l| l.name == "Key").expect("Key");
    let light = |t: f64| at(t).lights[key];
    let (warm, cool) = (light(0.0).colour, light(4.0).colour);
    assert!(warm.x > warm.z && cool.z > cool.x, "warm {warm} to cool {cool}");
    let cone = |t: f64| match light(t).kind {
        LightKind::Spot { cutoff_deg, inner_angle_deg, .. } => (cutoff_deg, inner_angle_deg),
        other => panic!("Key is a spot light, not {other:?}"),
    };
    assert_eq!(cone(0.0), (9.0, 5.0));
    assert_eq!(cone(3.0), (40.0, 32.0));
}
