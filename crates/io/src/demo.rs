//! The built-in demo scene (DESIGN.md §7): the paper's 4-bone arm bending at the elbow and
//! twisting 180° at the forearm joint, a spinning cube, a moving spot light and a sun.
//!
//! [`demo_scene`] builds it in code; `assets/demo.ron` is that scene saved with
//! [`crate::scene_file::to_string`], and a test keeps the two byte-identical (regenerate the
//! file with `KEYRIG_REGENERATE_DEMO=1 cargo test -p keyrig-io --test scene_demo`).
//!
//! Units are metres and seconds; the arm runs along +X from its root joint, 1.60158 m long in
//! four bones of 0.400395 m (DESIGN.md §6 gives 160.158 cm). keyrig-skin builds the procedural
//! arms in centimetres; the renderer and the editor scale a procedural mesh to the object's
//! skeleton, and a test checks that this skeleton is keyrig-skin's arm × 0.01.

use glam::{Quat, Vec3};
use keyrig_core::{
    Animated, Camera, DeformerKind, DeformerSettings, FrameRange, Interpolation, Joint, Key, Light,
    LightKind, MeshSource, Object, ProceduralMesh, RawTrack, Scene, Skeleton, Tcb,
};

/// The demo scene as saved in `assets/demo.ron`.
pub const DEMO_RON: &str = include_str!("../../../assets/demo.ron");

/// Length of the paper's test arm in metres.
pub const ARM_LENGTH: f32 = 1.60158;

/// Number of bones (and joints) of the arm's chain.
pub const ARM_BONES: usize = 4;

/// Names of the arm's joints, root first: keyrig-skin's procedural arm names them the same.
/// Joint i sits at x = i · [`ARM_LENGTH`] / 4 in the arm's rest pose; its bone reaches to the
/// next joint (the last one to the tip).
pub use keyrig_skin::ARM_JOINT_NAMES;

const FPS: f64 = 30.0;

/// Seconds of a frame at the demo's 30 fps.
fn at(frame: u32) -> f64 {
    f64::from(frame) / FPS
}

fn deg_about(axis: Vec3, degrees: f32) -> Quat {
    Quat::from_axis_angle(axis, degrees.to_radians())
}

/// The arm's rest skeleton: four joints in a chain along +X, not animated.
#[must_use]
pub fn arm_rest_skeleton() -> Skeleton {
    let bone = ARM_LENGTH / ARM_BONES as f32;
    let joints = ARM_JOINT_NAMES
        .iter()
        .enumerate()
        .map(|(i, name)| {
            let rest_translation = if i == 0 { Vec3::ZERO } else { Vec3::new(bone, 0.0, 0.0) };
            Joint::new(*name, i.checked_sub(1), rest_translation, Quat::IDENTITY)
        })
        .collect();
    Skeleton { joints, root_translation: Animated::constant(Vec3::ZERO) }
}

/// Builds the demo scene (frames 0–90 at 30 fps, 3 s).
#[must_use]
pub fn demo_scene() -> Scene {
    Scene {
        fps: FPS,
        frame_range: FrameRange { start: 0, end: 90 },
        ambient: Vec3::splat(0.08),
        objects: vec![arm(), cube()],
        lights: vec![spot_light(), sun()],
        camera: Camera {
            target: Vec3::new(0.0, 1.0, 0.0),
            yaw_deg: 25.0,
            pitch_deg: 15.0,
            distance: 3.2,
            fov_y_deg: 45.0,
        },
    }
}

fn arm() -> Object {
    let mut skeleton = arm_rest_skeleton();
    let bend = |d| deg_about(Vec3::NEG_Z, d);
    let twist = |d| deg_about(Vec3::X, d);

    // The shoulder lifts the arm a little and lets it fall back.
    skeleton.joints[0].rotation.track = RawTrack::new(vec![
        Key::new(at(0), Quat::IDENTITY),
        Key::new(at(45), deg_about(Vec3::Z, 15.0)).with_tcb(Tcb::new(0.0, 0.0, 0.5)),
        Key::new(at(90), Quat::IDENTITY),
    ]);
    // The elbow bends to 90° about −Z (the paper's bend pose), holds, and straightens again.
    skeleton.joints[1].rotation.track = RawTrack::new(vec![
        Key::new(at(0), bend(0.0)),
        Key::new(at(15), bend(45.0)).with_tcb(Tcb::new(0.5, 0.0, 0.3)),
        Key::new(at(30), bend(90.0)).with_tcb(Tcb::new(0.0, -0.5, 0.0)),
        Key::new(at(45), bend(90.0)).with_tcb(Tcb::new(1.0, 0.0, 0.0)),
        Key::new(at(75), bend(20.0)).with_tcb(Tcb::new(-0.3, 0.0, -0.4)),
        Key::new(at(90), bend(0.0)),
    ]);
    // The forearm joint twists about the bone axis to 180° and back (the paper's candy-wrapper
    // pose). Consecutive keys are at most 60° apart: a single key pair cannot express 180°.
    skeleton.joints[2].rotation.track = RawTrack::new(vec![
        Key::new(at(0), twist(0.0)),
        Key::new(at(20), twist(0.0)).with_tcb(Tcb::new(1.0, 0.0, 0.0)),
        Key::new(at(35), twist(60.0)).with_tcb(Tcb::new(0.0, 0.0, 0.5)),
        Key::new(at(50), twist(120.0)).with_tcb(Tcb::new(0.0, 0.3, 0.0)),
        Key::new(at(60), twist(180.0)).with_tcb(Tcb::new(0.5, 0.0, 0.0)),
        Key::new(at(70), twist(120.0)).with_tcb(Tcb::new(0.0, 0.0, -0.5)),
        Key::new(at(80), twist(60.0)).with_tcb(Tcb::new(-0.5, 0.0, 0.0)),
        Key::new(at(90), twist(0.0)),
    ]);

    let mut arm = Object::new("Arm");
    // Centre the arm over the origin, one metre up.
    arm.translation = Animated::constant(Vec3::new(-ARM_LENGTH / 2.0, 1.0, 0.0));
    arm.mesh = Some(MeshSource::Procedural(ProceduralMesh::ArmHighPoly));
    arm.skeleton = Some(skeleton);
    arm.deformer = DeformerSettings {
        kind: DeformerKind::BonesBlending,
        blend_parent_fraction: 0.25,
        blend_child_fraction: 0.25,
    };
    arm
}

fn cube() -> Object {
    let mut cube = Object::new("Cube");
    cube.mesh = Some(MeshSource::Procedural(ProceduralMesh::Cube));
    cube.scale = Animated::constant(Vec3::splat(0.25));
    // A loop in front of the arm; the last key repeats the first so playback loops cleanly.
    cube.translation = Animated {
        value: Vec3::new(-0.8, 0.3, 0.8),
        track: RawTrack::new(vec![
            Key::new(at(0), Vec3::new(-0.8, 0.3, 0.8)),
            Key::new(at(30), Vec3::new(0.0, 0.7, 1.0)).with_tcb(Tcb::new(0.0, 0.0, 0.4)),
            Key::new(at(60), Vec3::new(0.8, 0.3, 0.8)).with_tcb(Tcb::new(-0.4, 0.2, 0.0)),
            Key::new(at(75), Vec3::new(0.0, 0.15, 0.6)).with_tcb(Tcb::new(0.6, 0.0, 0.0)),
            Key::new(at(90), Vec3::new(-0.8, 0.3, 0.8)),
        ]),
    };
    // One full turn about Y at constant speed, in 120° steps.
    cube.rotation = Animated {
        value: Quat::IDENTITY,
        track: RawTrack::new(
            [0.0, 120.0, 240.0, 360.0]
                .into_iter()
                .enumerate()
                .map(|(i, d)| {
                    Key::new(at(30 * i as u32), deg_about(Vec3::Y, d))
                        .with_interpolation(Interpolation::Linear)
                })
                .collect(),
        ),
    };
    cube
}

fn spot_light() -> Light {
    let target = Vec3::new(0.0, 1.0, 0.0);
    let positions =
        [(0, Vec3::new(1.5, 2.5, 1.5)), (45, Vec3::new(-1.5, 2.2, 1.5)), (90, Vec3::new(1.5, 2.5, 1.5))];
    Light {
        name: "Key".to_string(),
        kind: LightKind::Spot { cutoff_deg: 35.0, inner_angle_deg: 25.0, dropoff: 2.0 },
        enabled: true,
        position: Animated {
            value: positions[0].1,
            track: RawTrack::new(positions.iter().map(|&(f, p)| Key::new(at(f), p)).collect()),
        },
        // Aimed at the arm's centre throughout.
        direction: Animated {
            value: target - positions[0].1,
            track: RawTrack::new(positions.iter().map(|&(f, p)| Key::new(at(f), target - p)).collect()),
        },
        colour: Animated::constant(Vec3::new(1.0, 0.92, 0.8)),
        intensity: Animated {
            value: 1.0,
            track: RawTrack::new(vec![
                Key::new(at(0), 1.0),
                Key::new(at(30), 2.5).with_tcb(Tcb::new(0.0, 0.0, -0.5)),
                Key::new(at(60), 1.5).with_interpolation(Interpolation::Step),
                Key::new(at(75), 1.0),
                Key::new(at(90), 1.0),
            ]),
        },
    }
}

fn sun() -> Light {
    Light {
        name: "Sun".to_string(),
        kind: LightKind::Directional,
        enabled: true,
        position: Animated::constant(Vec3::new(0.0, 4.0, 0.0)),
        direction: Animated::constant(Vec3::new(-0.4, -1.0, -0.5)),
        colour: Animated::constant(Vec3::new(0.9, 0.95, 1.0)),
        intensity: Animated::constant(0.6),
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn demo_scene_is_valid() {
        assert_eq!(demo_scene().problems(), Vec::new());
    }

    #[test]
    fn twist_keys_are_less_than_180_degrees_apart() {
        let scene = demo_scene();
        let joints = &scene.objects[0].skeleton.as_ref().map(|s| s.joints.clone()).unwrap_or_default();
        for joint in joints {
            for pair in joint.rotation.track.keys.windows(2) {
                let angle = pair[0].value.angle_between(pair[1].value).to_degrees();
                assert!(angle < 179.0, "{}: {angle}° between consecutive keys", joint.name);
            }
        }
    }
}
