//! Retargeting (docs/retargeting.md): the CMU 131 walk (BVH, 120 fps) put onto CesiumMan
//! (glTF) and onto the FBX corpus's barbarian, measured independently of the retargeting code
//! through the scene evaluator (keyrig-eval) at every keyed frame:
//!
//! - bone directions: each bone both rigs have (a mapped joint to the mapped joint below it)
//!   points within 5° of the source's bone, except the legs where a planted foot is held;
//! - foot slide: during each contact found in the source, the target's foot joint drifts
//!   horizontally (its largest distance from where it was at the contact's first frame) by at
//!   most 1 % of the target's leg length;
//! - no flipped joints: each knee bends to the side the source's knee bends (the angle between
//!   their bend directions stays under 90° wherever the source knee is bent by 10° or more), and
//!   no driven joint's local rotation jumps by more than 20° from one frame to the next.

use std::path::{Path, PathBuf};

use glam::{Quat, Vec3};
use keyrig_core::Scene;
use keyrig_edit::mirror::Side;
use keyrig_edit::retarget::{retarget, skeleton_slots, BoneMap, Limb, RetargetOptions, RetargetReport, Slot};
use keyrig_eval::{Overrides, SceneEvaluator};

fn corpus(path: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus").join(path)
}

fn cmu_walk() -> Scene {
    keyrig_io::bvh::import_scene(&corpus("bvh/cmu-bvh11/131_01.bvh")).expect("the corpus take reads")
}

fn model(path: &str) -> Scene {
    let path = corpus(path);
    let model = keyrig_io::fbx::import_model_file(&path).expect("the corpus model reads");
    model.to_scene_all(&path.to_string_lossy()).expect("maps to a scene")
}

/// World joint positions and local joint rotations of one object at every keyed frame, through
/// the scene evaluator.
fn evaluated(scene: &Scene, object: usize, frames: usize, fps: f64) -> (Vec<Vec<Vec3>>, Vec<Vec<Quat>>) {
    let evaluator = SceneEvaluator::new(scene, &Default::default());
    let none = Overrides::default();
    (0..frames)
        .map(|k| {
            let state = evaluator.evaluate(k as f64 / fps, &none);
            let object = &state.objects[object];
            let palette = object.palette.as_ref().expect("a palette");
            let positions = palette
                .model_from_joint
                .iter()
                .map(|f| object.world_from_object.transform_point3(f.translation.into()))
                .collect();
            (positions, object.pose.as_ref().expect("a pose").local_rotations.clone())
        })
        .unzip()
}

fn angle_deg(a: Vec3, b: Vec3) -> f32 {
    a.angle_between(b).to_degrees()
}

/// The names of the joints in a slot, source and target.
fn joint_in(scene: &Scene, object: usize, slot: Slot) -> usize {
    let skeleton = scene.objects[object].skeleton.as_ref().unwrap();
    skeleton_slots(skeleton).iter().position(|s| *s == Some(slot)).unwrap_or_else(|| panic!("{slot:?}"))
}

struct Measured {
    /// Largest bone direction difference (degrees) over the bones outside held legs, and over
    /// the held legs' bones.
    body_deg: f32,
    leg_deg: f32,
    /// … and over the bones through a joint only the source has.
    extra_deg: f32,
    /// Largest horizontal foot drift during a contact, as a fraction of the leg length, on the
    /// target and in the source itself.
    target_slide: f32,
    source_slide: f32,
    /// Largest vertical drift of the target's foot during a contact, as a fraction of the leg.
    target_lift: f32,
    /// Largest angle between the target's and the source's knee bend directions (source knee
    /// bent ≥ 10°).
    knee_side_deg: f32,
    /// Largest local rotation change of a driven joint between consecutive frames, on the
    /// target and on the source joints that drive them.
    step_deg: f32,
    source_step_deg: f32,
}

fn measure(
    source: &Scene,
    target: &Scene,
    object: usize,
    map: &BoneMap,
    report: &RetargetReport,
) -> Measured {
    let src_skeleton = source.objects[0].skeleton.as_ref().unwrap();
    let tgt_skeleton = target.objects[object].skeleton.as_ref().unwrap();
    let bones = map.bones(src_skeleton, tgt_skeleton).expect("the map resolves");
    let frames = report.frames;
    let (src, src_rotations) = evaluated(source, 0, frames, report.fps);
    let (tgt, tgt_rotations) = evaluated(target, object, frames, report.fps);
    let held_legs: Vec<usize> = [Side::Left, Side::Right]
        .into_iter()
        .filter(|side| !report.not_held.contains(side))
        .flat_map(|side| {
            let slot = |limb| match side {
                Side::Left => Slot::Left(limb),
                Side::Right => Slot::Right(limb),
            };
            [slot(Limb::UpperLeg), slot(Limb::LowerLeg)]
        })
        .filter_map(|slot| skeleton_slots(tgt_skeleton).iter().position(|s| *s == Some(slot)))
        .collect();
    let (mut body_deg, mut leg_deg, mut extra_deg) = (0.0f32, 0.0f32, 0.0f32);
    let target_slots = skeleton_slots(tgt_skeleton);
    // A side bone whose source runs through a joint the map leaves out (CMU's `LHipJoint` and
    // `LeftCollar`, which CesiumMan does not have) is not a bone both rigs have.
    let extra_joint = |bone: &keyrig_edit::retarget::MappedBone| {
        src_skeleton.joints[bone.source.1].parent != Some(bone.source.0)
            && !target_slots[bone.target.1].is_some_and(Slot::is_central)
    };
    if std::env::var("RETARGET_DEBUG").is_ok() {
        for bone in &bones {
            let (worst, at) = (0..frames)
                .map(|k| {
                    (
                        angle_deg(
                            src[k][bone.source.1] - src[k][bone.source.0],
                            tgt[k][bone.target.1] - tgt[k][bone.target.0],
                        ),
                        k,
                    )
                })
                .fold((0.0f32, 0), |a, b| if b.0 > a.0 { b } else { a });
            eprintln!(
                "  bone {} → {}: {worst:.2}° at {at}",
                tgt_skeleton.joints[bone.target.0].name, tgt_skeleton.joints[bone.target.1].name
            );
        }
    }
    for k in 0..frames {
        for bone in &bones {
            let s = src[k][bone.source.1] - src[k][bone.source.0];
            let t = tgt[k][bone.target.1] - tgt[k][bone.target.0];
            let a = angle_deg(s, t);
            if extra_joint(bone) {
                extra_deg = extra_deg.max(a);
            } else if held_legs.contains(&bone.target.0) {
                leg_deg = leg_deg.max(a);
            } else {
                body_deg = body_deg.max(a);
            }
        }
    }
    let horizontal = |v: Vec3| Vec3::new(v.x, 0.0, v.z);
    let (mut target_slide, mut source_slide, mut target_lift) = (0.0f32, 0.0f32, 0.0f32);
    for contact in &report.contacts {
        let slot = match contact.side {
            Side::Left => Slot::Left(Limb::Foot),
            Side::Right => Slot::Right(Limb::Foot),
        };
        let (sf, tf) = (joint_in(source, 0, slot), joint_in(target, object, slot));
        let (mut t_slide, mut s_slide) = (0.0f32, 0.0f32);
        for k in contact.first..=contact.last {
            target_lift = target_lift.max((tgt[k][tf].y - tgt[contact.first][tf].y).abs());
            t_slide = t_slide.max(horizontal(tgt[k][tf] - tgt[contact.first][tf]).length());
            s_slide = s_slide.max(horizontal(src[k][sf] - src[contact.first][sf]).length());
        }
        if std::env::var("RETARGET_DEBUG").is_ok() {
            eprintln!(
                "  contact {:?} {}..={}: target {:.3} %, source {:.3} %",
                contact.side,
                contact.first,
                contact.last,
                100.0 * t_slide / report.target_leg,
                100.0 * s_slide / report.source_leg
            );
        }
        target_slide = target_slide.max(t_slide);
        source_slide = source_slide.max(s_slide);
    }
    let mut knee_side_deg = 0.0f32;
    for side in [Side::Left, Side::Right] {
        let slot = |limb| match side {
            Side::Left => Slot::Left(limb),
            Side::Right => Slot::Right(limb),
        };
        let joints = |scene: &Scene, o: usize| {
            let slots = skeleton_slots(scene.objects[o].skeleton.as_ref().unwrap());
            let find = |l| slots.iter().position(|s| *s == Some(slot(l)));
            Some((find(Limb::UpperLeg)?, find(Limb::LowerLeg)?, find(Limb::Foot)?))
        };
        let (Some((sh, sk, sa)), Some((th, tk, ta))) = (joints(source, 0), joints(target, object)) else {
            continue;
        };
        let bend = |p: &[Vec3], h: usize, k: usize, a: usize| {
            let axis = (p[a] - p[h]).normalize();
            let v = p[k] - p[h];
            v - axis * v.dot(axis)
        };
        for k in 0..frames {
            let knee_angle = angle_deg(src[k][sk] - src[k][sh], src[k][sa] - src[k][sk]);
            if knee_angle >= 10.0 {
                let a = angle_deg(bend(&src[k], sh, sk, sa), bend(&tgt[k], th, tk, ta));
                if a > 90.0 && std::env::var("RETARGET_DEBUG").is_ok() {
                    eprintln!("  knee {side:?} frame {k}: {a:.1}° (source knee {knee_angle:.1}°)");
                }
                knee_side_deg = knee_side_deg.max(a);
            }
        }
    }
    let (mut step_deg, mut source_step_deg) = (0.0f32, 0.0f32);
    for &(s, j) in &report.pairs {
        for k in 1..frames {
            let step = tgt_rotations[k - 1][j].angle_between(tgt_rotations[k][j]).to_degrees();
            let source_step = src_rotations[k - 1][s].angle_between(src_rotations[k][s]).to_degrees();
            if step > 20.0 && std::env::var("RETARGET_DEBUG").is_ok() {
                eprintln!(
                    "  step {} at frame {k}: {step:.1}° (source {source_step:.1}°)",
                    tgt_skeleton.joints[j].name
                );
            }
            step_deg = step_deg.max(step);
            source_step_deg = source_step_deg.max(source_step);
        }
    }
    let leg = report.target_leg;
    Measured {
        body_deg,
        leg_deg,
        extra_deg,
        target_slide: target_slide / leg,
        target_lift: target_lift / leg,
        source_slide: source_slide / report.source_leg,
        knee_side_deg,
        step_deg,
        source_step_deg,
    }
}

#[test]
fn automatic_maps_of_the_corpus_rigs() {
    let cmu = cmu_walk();
    let cesium = model("gltf/CesiumMan/CesiumMan.glb");
    let map = BoneMap::automatic(
        cmu.objects[0].skeleton.as_ref().unwrap(),
        cesium.objects[0].skeleton.as_ref().unwrap(),
    );
    let pairs: Vec<(&str, &str)> = map.pairs.iter().map(|p| (p.source.as_str(), p.target.as_str())).collect();
    assert_eq!(
        pairs,
        [
            ("Hips", "Skeleton_torso_joint_1"),
            ("lowerback", "Skeleton_torso_joint_2"),
            ("LeftHip", "leg_joint_L_1"),
            ("RightHip", "leg_joint_R_1"),
            ("Chest2", "torso_joint_3"),
            ("LeftKnee", "leg_joint_L_2"),
            ("RightKnee", "leg_joint_R_2"),
            ("Neck", "Skeleton_neck_joint_1"),
            ("LeftShoulder", "Skeleton_arm_joint_L__4_"),
            ("RightShoulder", "Skeleton_arm_joint_R"),
            ("LeftAnkle", "leg_joint_L_3"),
            ("RightAnkle", "leg_joint_R_3"),
            ("Head", "Skeleton_neck_joint_2"),
            ("LeftElbow", "Skeleton_arm_joint_L__3_"),
            ("RightElbow", "Skeleton_arm_joint_R__2_"),
            ("LeftToe", "leg_joint_L_5"),
            ("RightToe", "leg_joint_R_5"),
            ("LeftWrist", "Skeleton_arm_joint_L__2_"),
            ("RightWrist", "Skeleton_arm_joint_R__3_"),
        ]
    );
}

#[test]
fn cmu_walk_onto_cesium_man() {
    let source = cmu_walk();
    let mut target = model("gltf/CesiumMan/CesiumMan.glb");
    let map = BoneMap::automatic(
        source.objects[0].skeleton.as_ref().unwrap(),
        target.objects[0].skeleton.as_ref().unwrap(),
    );
    let report =
        retarget(&source, 0, &mut target, 0, &map, &RetargetOptions::new("Walk")).expect("retargets");
    assert!(target.problems().is_empty(), "{:?}", target.problems());
    assert_eq!(target.objects[0].action.as_deref(), Some("Walk"));
    assert!(target.action_index("animation0").is_some(), "the model's own animation is kept");
    let m = measure(&source, &target, 0, &map, &report);
    eprintln!(
        "CMU 131 → CesiumMan: {} frames, leg ratio {:.5} ({:.3} → {:.4}), {} contacts, {} IK solves ({} unreachable)\n\
         bone directions: {:.3}° (body), {:.3}° (held legs), {:.3}° (through a source-only joint); foot slide {:.4} % of the leg (source {:.3} %), vertical {:.3} %;\n\
         knee side {:.2}°, largest step {:.2}° (source {:.2}°)",
        report.frames,
        report.leg_ratio,
        report.source_leg,
        report.target_leg,
        report.contacts.len(),
        report.ik_solves,
        report.ik_unreachable,
        m.body_deg,
        m.leg_deg,
        m.extra_deg,
        100.0 * m.target_slide,
        100.0 * m.source_slide,
        100.0 * m.target_lift,
        m.knee_side_deg,
        m.step_deg,
        m.source_step_deg
    );
    assert!(report.contacts.len() >= 6, "a walk of 8 s plants each foot several times");
    assert!(m.body_deg <= 5.0, "{}", m.body_deg);
    assert!(m.target_slide <= 0.01, "{}", m.target_slide);
    assert!(m.knee_side_deg < 90.0, "{}", m.knee_side_deg);
    // The source's own right wrist turns by 54.8° between two frames (frame 237), and the
    // target follows it: no joint turns by more than its source.
    assert!(m.step_deg <= m.source_step_deg + 0.5, "{} {}", m.step_deg, m.source_step_deg);
}

/// The FBX corpus's humanoid, `blender_293_barbarian`: a low-poly rig without knees or elbows
/// (`jambe` → `pied`, `bras` → `main`), in two skinned objects that each carry the skeleton.
/// Its legs are one bone each, so a planted foot is held by turning the leg about its root
/// towards the planted point, which it reaches only where the distance allows.
#[test]
fn cmu_walk_onto_the_fbx_barbarian() {
    let source = cmu_walk();
    let mut target = model("fbx/ufbx/blender_293_barbarian_7400_binary.fbx");
    let body = target.objects.iter().position(|o| o.name == "body").expect("the body object");
    let map = BoneMap::automatic(
        source.objects[0].skeleton.as_ref().unwrap(),
        target.objects[body].skeleton.as_ref().unwrap(),
    );
    let pairs: Vec<(&str, &str)> = map.pairs.iter().map(|p| (p.source.as_str(), p.target.as_str())).collect();
    assert_eq!(
        pairs,
        [
            ("Hips", "bassin"),
            ("lowerback", "torse"),
            ("LeftHip", "jambe gauche"),
            ("RightHip", "jambe droite"),
            ("Head", "tête"),
            ("RightShoulder", "bras droit"),
            ("LeftShoulder", "bras gauche"),
            ("LeftAnkle", "pied gauche"),
            ("RightAnkle", "pied droit"),
            ("RightWrist", "main droite"),
            ("LeftWrist", "main gauche"),
        ]
    );
    let report =
        retarget(&source, 0, &mut target, body, &map, &RetargetOptions::new("Walk")).expect("retargets");
    assert!(target.problems().is_empty(), "{:?}", target.problems());
    assert!(report.not_held.is_empty());
    let m = measure(&source, &target, body, &map, &report);
    eprintln!(
        "CMU 131 → barbarian: leg ratio {:.5} ({:.3} → {:.4}), {} contacts, {} holds ({} out of reach)\n\
         bone directions: {:.3}° (body), {:.3}° (through a source-only joint); foot slide {:.3} % of the leg (source {:.3} %), vertical {:.2} %;\n\
         largest step {:.2}° (source {:.2}°)",
        report.leg_ratio,
        report.source_leg,
        report.target_leg,
        report.contacts.len(),
        report.ik_solves,
        report.ik_unreachable,
        m.body_deg,
        m.extra_deg,
        100.0 * m.target_slide,
        100.0 * m.source_slide,
        100.0 * m.target_lift,
        m.step_deg,
        m.source_step_deg
    );
    assert!(m.body_deg <= 5.0, "{}", m.body_deg);
    assert!(m.step_deg <= m.source_step_deg + 0.5, "{} {}", m.step_deg, m.source_step_deg);
}

/// A rig retargeted onto itself with its arms lowered 40° at rest (a T-pose source, an A-pose
/// target): the rest alignment brings every bone back onto the source's, and the root
/// follows the source's exactly (leg ratio 1).
#[test]
fn a_pose_copy_of_the_source_follows_it_bone_for_bone() {
    let source = cmu_walk();
    let mut target = source.clone();
    target.objects[0].name = "Copy".to_owned();
    let skeleton = target.objects[0].skeleton.as_mut().unwrap();
    for (name, angle) in [("LeftShoulder", -40.0f32), ("RightShoulder", 40.0)] {
        let joint = skeleton.joints.iter_mut().find(|j| j.name == name).unwrap();
        joint.rest_rotation = Quat::from_rotation_z(angle.to_radians()) * joint.rest_rotation;
    }
    let map = BoneMap::automatic(
        source.objects[0].skeleton.as_ref().unwrap(),
        target.objects[0].skeleton.as_ref().unwrap(),
    );
    let options = RetargetOptions { contacts: None, ..RetargetOptions::new("Walk") };
    let report = retarget(&source, 0, &mut target, 0, &map, &options).expect("retargets");
    assert!((report.leg_ratio - 1.0).abs() < 1e-6, "{}", report.leg_ratio);
    let m = measure(&source, &target, 0, &map, &report);
    assert!(m.body_deg < 0.1, "{}", m.body_deg);
    assert!(m.leg_deg < 0.1, "{}", m.leg_deg);
    let (src, _) = evaluated(&source, 0, report.frames, report.fps);
    let (tgt, _) = evaluated(&target, 0, report.frames, report.fps);
    let hips = joint_in(&source, 0, Slot::Hips);
    // The copy walks the source's path from where its rest pose stands (the ground at its rest
    // feet): a constant offset.
    let offset = tgt[0][hips] - src[0][hips];
    for k in 0..report.frames {
        let expected = src[k][hips] + offset;
        assert!(tgt[k][hips].distance(expected) < 1e-3, "frame {k}: {} {}", tgt[k][hips], expected);
    }
}

/// The new action is made of ordinary keys: reducing them within 0.1° and 0.5 mm (CesiumMan is
/// in metres) keeps the planted feet within the bound. (Within the default 0.5° and 1 mm the
/// feet slide by up to 2.1 % of the leg: each of the hips, thigh and shin may turn by 0.5°.)
#[test]
fn the_retargeted_walk_reduces_like_any_keys() {
    let source = cmu_walk();
    let mut target = model("gltf/CesiumMan/CesiumMan.glb");
    let map = BoneMap::automatic(
        source.objects[0].skeleton.as_ref().unwrap(),
        target.objects[0].skeleton.as_ref().unwrap(),
    );
    let options = RetargetOptions {
        reduce: Some(keyrig_edit::cleanup::ReduceTolerance {
            angle_deg: 0.1,
            distance: 0.0005,
            ..keyrig_edit::cleanup::ReduceTolerance::DEFAULT
        }),
        ..RetargetOptions::new("Walk")
    };
    let report = retarget(&source, 0, &mut target, 0, &map, &options).expect("retargets");
    let reduced = report.reduced.clone().expect("reduced");
    eprintln!(
        "reduced {} channels from {} to {} keys (largest error {:.3}°, {:.2e})",
        reduced.channels,
        reduced.keys_before,
        reduced.keys_after,
        reduced.max_angle_deg,
        reduced.max_distance
    );
    assert!(reduced.keys_after * 4 < reduced.keys_before);
    let m = measure(&source, &target, 0, &map, &report);
    eprintln!(
        "after reduction: foot slide {:.3} % of the leg, bones {:.3}°",
        100.0 * m.target_slide,
        m.body_deg
    );
    assert!(m.target_slide <= 0.01, "{}", m.target_slide);
    assert!(m.body_deg <= 5.0, "{}", m.body_deg);
}

#[test]
fn what_retargeting_refuses() {
    use keyrig_edit::retarget::{BonePair, RetargetError};
    let source = cmu_walk();
    let mut target = model("gltf/CesiumMan/CesiumMan.glb");
    let options = RetargetOptions::new("Walk");
    let pair = |s: &str, t: &str| BonePair { source: s.to_owned(), target: t.to_owned() };
    let unknown = BoneMap { pairs: vec![pair("Hips", "NoSuchJoint")] };
    assert_eq!(
        retarget(&source, 0, &mut target.clone(), 0, &unknown, &options),
        Err(RetargetError::UnknownJoint { side: "target", name: "NoSuchJoint".to_owned() })
    );
    let twice = BoneMap { pairs: vec![pair("Hips", "Z_UP"), pair("Head", "Z_UP")] };
    assert_eq!(
        retarget(&source, 0, &mut target.clone(), 0, &twice, &options),
        Err(RetargetError::TargetTwice("Z_UP".to_owned()))
    );
    assert_eq!(
        retarget(&source, 0, &mut target.clone(), 0, &BoneMap::default(), &options),
        Err(RetargetError::EmptyMap)
    );
    let bad_name = RetargetOptions::new("a/b");
    let map = BoneMap { pairs: vec![pair("Hips", "Skeleton_torso_joint_1")] };
    assert!(matches!(
        retarget(&source, 0, &mut target.clone(), 0, &map, &bad_name),
        Err(RetargetError::Action(_))
    ));
    assert_eq!(retarget(&source, 3, &mut target, 0, &map, &options), Err(RetargetError::NoObject(3)));

    // Editing the map: one pair replaced, one removed.
    let mut map = BoneMap::automatic(
        source.objects[0].skeleton.as_ref().unwrap(),
        target.objects[0].skeleton.as_ref().unwrap(),
    );
    map.set("Skeleton_neck_joint_2", Some("Neck"));
    assert_eq!(map.source_of("Skeleton_neck_joint_2"), Some("Neck"));
    map.set("Skeleton_neck_joint_2", None);
    assert_eq!(map.source_of("Skeleton_neck_joint_2"), None);
    assert_eq!(map.pairs.len(), 18);
}
