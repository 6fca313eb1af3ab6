//! End to end across keyrig-io, keyrig-core and keyrig-skin: the committed demo scene loads
//! from disk, has no problems, and plays through every frame with all four deformers; at the
//! 180° forearm twist linear blend collapses the forearm while bones blending and dual
//! quaternion keep it round (docs/design.md §6, the product's headline).

use std::path::PathBuf;

use glam::Vec3;
use keyrig_core::{DeformerKind, MeshSource, Scene};
use keyrig_eval::{Overrides, SceneEvaluator};
use keyrig_skin::{
    deform_mesh, joint_cross_section, mesh_for, BlendZone, JointPalette, Pose, RestSkeleton, SkinnedMesh,
};

fn demo() -> Scene {
    let path = PathBuf::from(env!("CARGO_MANIFEST_DIR")).join("../assets/demo.ron");
    keyrig_io::scene_file::load(&path).unwrap_or_else(|e| panic!("the demo scene must load: {e}"))
}

struct Arm {
    mesh: SkinnedMesh,
    rest: RestSkeleton,
    /// The scene evaluator and the arm's object index: the poses the editor plays.
    eval: SceneEvaluator,
    index: usize,
    zone: BlendZone,
    forearm: usize,
}

fn arm(scene: &Scene) -> Arm {
    let index = scene.objects.iter().position(|o| o.skeleton.is_some()).expect("the demo has a skinned arm");
    let object = &scene.objects[index];
    let skeleton = object.skeleton.as_ref().unwrap();
    let Some(MeshSource::Procedural(kind)) = object.mesh else { panic!("the demo arm is a procedural mesh") };
    let rest = RestSkeleton::from_scene(skeleton).unwrap();
    let mesh = mesh_for(kind).fit_to_skeleton(rest.clone()).unwrap();
    let forearm = skeleton.joints.iter().position(|j| j.name == "forearm").expect("a joint named forearm");
    Arm {
        mesh,
        rest,
        eval: SceneEvaluator::new(scene, &std::collections::HashMap::new()),
        index,
        zone: BlendZone::from_settings(&object.deformer).unwrap(),
        forearm,
    }
}

impl Arm {
    fn pose(&self, t: f64) -> Pose {
        self.eval.object_at(self.index, t, &Overrides::new()).and_then(|s| s.pose).expect("the arm's pose")
    }
}

fn deformed(arm: &Arm, pose: &Pose, kind: DeformerKind) -> (JointPalette, Vec<Vec3>) {
    let palette = JointPalette::new(&arm.rest, pose).unwrap();
    let bindings = arm.mesh.bindings(arm.zone).unwrap();
    let out = deform_mesh(&arm.mesh, &bindings, &palette, kind).unwrap();
    (palette, out.positions)
}

#[test]
fn the_demo_file_loads_without_problems() {
    let scene = demo();
    assert_eq!(scene.problems(), vec![], "the demo scene must be clean");
    assert!(scene.objects.len() >= 2 && scene.lights.iter().any(|l| l.position.is_animated()));
}

#[test]
fn every_frame_deforms_finitely_with_every_deformer() {
    let scene = demo();
    let arm = arm(&scene);
    // The arm is 1.60158 m long in the scene: no vertex may leave a generous box around it.
    let bound = 3.0;
    for frame in scene.frame_range.start..=scene.frame_range.end {
        let pose = arm.pose(f64::from(frame) / scene.fps);
        for kind in DeformerKind::ALL {
            let (_, positions) = deformed(&arm, &pose, kind);
            assert_eq!(positions.len(), arm.mesh.vertex_count());
            for (v, p) in positions.iter().enumerate() {
                assert!(
                    p.is_finite() && p.abs().max_element() < bound,
                    "frame {frame}, {}: vertex {v} at {p}",
                    kind.label()
                );
            }
        }
    }
}

#[test]
fn at_rest_every_deformer_gives_the_rest_mesh() {
    let scene = demo();
    let arm = arm(&scene);
    let rest_pose = Pose::rest(arm.rest.len());
    for kind in DeformerKind::ALL {
        let (_, positions) = deformed(&arm, &rest_pose, kind);
        for (a, b) in positions.iter().zip(&arm.mesh.positions) {
            assert!((*a - *b).length() < 1e-5, "{}: {a} vs rest {b}", kind.label());
        }
    }
}

#[test]
fn the_demo_twist_collapses_linear_blend_only() {
    let scene = demo();
    let arm = arm(&scene);
    // Frame 60 is the demo's 180° forearm twist.
    let pose = arm.pose(60.0 / scene.fps);
    let ratio = |kind| {
        let (palette, positions) = deformed(&arm, &pose, kind);
        joint_cross_section(&arm.mesh, &palette, arm.forearm, &positions).unwrap().ratio()
    };
    let linear = ratio(DeformerKind::LinearBlend);
    let bones = ratio(DeformerKind::BonesBlending);
    let dual = ratio(DeformerKind::DualQuaternion);
    assert!(
        linear < 0.3,
        "linear blend keeps {linear} of the forearm's section at 180°: expected a collapse"
    );
    assert!(bones > 0.95, "bones blending keeps only {bones}");
    assert!(dual > 0.95, "dual quaternion keeps only {dual}");
}
