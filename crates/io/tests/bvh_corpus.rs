//! BVH import and export checked against an independent reading of the format.
//!
//! `reference` below is a BVH reader written from the format's description (Biovision's
//! hierarchy: each joint's local transform is translate(OFFSET + its position channels) times
//! its rotation channels' matrices multiplied in the order they are listed, column vectors;
//! a joint's world transform is its parent's times its local one; End Sites are points at
//! their OFFSET). It shares no code with keyrig-io's reader and uses plain f64 matrices, no
//! glam. keyrig's side is the scene evaluator's joint palette (F(j), `model_from_joint`) of
//! the imported scene, placed by the object's `world_from_object`, at every frame.

use std::collections::HashMap;
use std::path::{Path, PathBuf};

use keyrig_eval::{Overrides, SceneEvaluator};

type M4 = [[f64; 4]; 4];

fn identity() -> M4 {
    let mut m = [[0.0; 4]; 4];
    for (i, row) in m.iter_mut().enumerate() {
        row[i] = 1.0;
    }
    m
}

fn mul(a: &M4, b: &M4) -> M4 {
    let mut m = [[0.0; 4]; 4];
    for i in 0..4 {
        for j in 0..4 {
            m[i][j] = (0..4).map(|k| a[i][k] * b[k][j]).sum();
        }
    }
    m
}

fn translate(x: f64, y: f64, z: f64) -> M4 {
    let mut m = identity();
    m[0][3] = x;
    m[1][3] = y;
    m[2][3] = z;
    m
}

/// Rotation by `deg` degrees about axis 0 (X), 1 (Y) or 2 (Z), right-handed.
fn rotate(axis: usize, deg: f64) -> M4 {
    let (s, c) = deg.to_radians().sin_cos();
    let mut m = identity();
    let (a, b) = match axis {
        0 => (1, 2),
        1 => (2, 0),
        _ => (0, 1),
    };
    m[a][a] = c;
    m[a][b] = -s;
    m[b][a] = s;
    m[b][b] = c;
    m
}

/// A joint of the reference reading.
struct RefJoint {
    name: String,
    parent: Option<usize>,
    offset: [f64; 3],
    /// (axis, is rotation) per channel, as listed.
    channels: Vec<(usize, bool)>,
}

/// The reference reading of a whole file: joints (End Sites included, named `""`) in file
/// order, the frame time and every frame's values.
struct Reference {
    joints: Vec<RefJoint>,
    frame_time: f64,
    frames: Vec<Vec<f64>>,
}

fn reference(text: &str) -> Reference {
    let mut tokens = text.split_whitespace().peekable();
    let mut joints: Vec<RefJoint> = Vec::new();
    let mut open: Vec<usize> = Vec::new();
    let mut next_is_end_site = false;
    while let Some(t) = tokens.next() {
        match t {
            "HIERARCHY" | "{" => {}
            "ROOT" | "JOINT" => {
                let name = tokens.next().expect("name").to_owned();
                joints.push(RefJoint {
                    name,
                    parent: open.last().copied(),
                    offset: [0.0; 3],
                    channels: vec![],
                });
                open.push(joints.len() - 1);
            }
            "End" => {
                assert_eq!(tokens.next(), Some("Site"));
                next_is_end_site = true;
                joints.push(RefJoint {
                    name: String::new(),
                    parent: open.last().copied(),
                    offset: [0.0; 3],
                    channels: vec![],
                });
                open.push(joints.len() - 1);
            }
            "OFFSET" => {
                let j = *open.last().expect("in a joint");
                for k in 0..3 {
                    joints[j].offset[k] = tokens.next().expect("offset").parse().expect("number");
                }
            }
            "CHANNELS" => {
                let j = *open.last().expect("in a joint");
                let n: usize = tokens.next().expect("count").parse().expect("count");
                for _ in 0..n {
                    let c = tokens.next().expect("channel");
                    let axis = match &c[..1] {
                        "X" => 0,
                        "Y" => 1,
                        _ => 2,
                    };
                    joints[j].channels.push((axis, c.ends_with("rotation")));
                }
            }
            "}" => {
                open.pop();
                next_is_end_site = false;
            }
            "MOTION" => break,
            other => panic!("unexpected {other}"),
        }
    }
    assert!(!next_is_end_site && open.is_empty());
    assert_eq!(tokens.next(), Some("Frames:"));
    let count: usize = tokens.next().expect("frames").parse().expect("frames");
    assert_eq!((tokens.next(), tokens.next()), (Some("Frame"), Some("Time:")));
    let frame_time: f64 = tokens.next().expect("time").parse().expect("time");
    let per_frame: usize = joints.iter().map(|j| j.channels.len()).sum();
    let values: Vec<f64> = tokens.map(|t| t.parse().expect("value")).collect();
    assert_eq!(values.len(), count * per_frame);
    let frames = values.chunks(per_frame.max(1)).map(<[f64]>::to_vec).take(count).collect();
    Reference { joints, frame_time, frames }
}

impl Reference {
    /// World positions of every joint (End Sites included) at a frame.
    fn positions(&self, frame: usize) -> Vec<[f64; 3]> {
        let values = &self.frames[frame];
        let mut column = 0;
        let mut world: Vec<M4> = Vec::with_capacity(self.joints.len());
        for j in &self.joints {
            let mut position = j.offset;
            let mut rotation = identity();
            for &(axis, is_rotation) in &j.channels {
                let v = values[column];
                column += 1;
                if is_rotation {
                    rotation = mul(&rotation, &rotate(axis, v));
                } else {
                    position[axis] += v;
                }
            }
            let local = mul(&translate(position[0], position[1], position[2]), &rotation);
            let parent = j.parent.map_or(identity(), |p| world[p]);
            world.push(mul(&parent, &local));
        }
        world.iter().map(|m| [m[0][3], m[1][3], m[2][3]]).collect()
    }

    /// Diagonal of the box around the joints at rest (every channel zero).
    fn size(&self) -> f64 {
        let mut rest = Reference { joints: vec![], frame_time: self.frame_time, frames: vec![] };
        rest.joints = self
            .joints
            .iter()
            .map(|j| RefJoint { name: j.name.clone(), parent: j.parent, offset: j.offset, channels: vec![] })
            .collect();
        rest.frames.push(vec![]);
        let p = rest.positions(0);
        let mut lo = [f64::MAX; 3];
        let mut hi = [f64::MIN; 3];
        for q in &p {
            for k in 0..3 {
                lo[k] = lo[k].min(q[k]);
                hi[k] = hi[k].max(q[k]);
            }
        }
        (0..3).map(|k| (hi[k] - lo[k]).powi(2)).sum::<f64>().sqrt()
    }
}

/// The largest distance, over every frame and joint, between the reference positions of
/// `expected` and keyrig's evaluation of `scene` (object 0, joints in the same order).
fn max_error(expected: &Reference, scene: &keyrig_core::Scene) -> f64 {
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    let evaluator = SceneEvaluator::new(scene, &HashMap::new());
    let none = Overrides::default();
    let skeleton = scene.objects[0].skeleton.as_ref().expect("a skeleton");
    assert_eq!(skeleton.joints.len(), expected.joints.len());
    for (k, r) in skeleton.joints.iter().zip(&expected.joints) {
        if !r.name.is_empty() {
            assert_eq!(k.name, r.name);
        }
    }
    assert_eq!(scene.frame_range.end as usize + 1, expected.frames.len());
    let mut worst = 0.0f64;
    for frame in 0..expected.frames.len() {
        let state = evaluator.object_at(0, frame as f64 / scene.fps, &none).expect("object 0");
        let palette = state.palette.as_ref().expect("a palette: the skeleton is valid");
        let want = expected.positions(frame);
        for (j, w) in want.iter().enumerate() {
            let got = state.world_from_object.transform_point3a(palette.model_from_joint[j].translation);
            let d = (0..3).map(|k| (f64::from(got[k]) - w[k]).powi(2)).sum::<f64>().sqrt();
            worst = worst.max(d);
        }
    }
    worst
}

fn corpus(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/bvh").join(name)
}

/// Imports `path`, checks it against the reference at every frame, exports it, checks the
/// exported file's reference reading and its re-import against the original's reference.
/// Returns the three errors relative to the skeleton's size.
fn check_file(path: &Path) -> [f64; 3] {
    let text = std::fs::read_to_string(path).expect("read");
    let expected = reference(&text);
    let size = expected.size();
    assert!(size > 0.0);
    println!("{}: skeleton size (rest-pose box diagonal) {size:.4}", path.display());
    let scene = keyrig_io::bvh::import_scene(path).expect("import");
    let imported = max_error(&expected, &scene) / size;

    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("out.bvh");
    keyrig_io::bvh::export_scene(&scene, 0, &out).expect("export");
    let exported_text = std::fs::read_to_string(&out).expect("exported");
    let exported = reference(&exported_text);
    assert_eq!(exported.frames.len(), expected.frames.len());
    assert!((exported.frame_time - expected.frame_time).abs() < 1e-6);
    let mut worst = 0.0f64;
    for frame in 0..expected.frames.len() {
        for (a, b) in expected.positions(frame).iter().zip(exported.positions(frame)) {
            worst = worst.max((0..3).map(|k| (a[k] - b[k]).powi(2)).sum::<f64>().sqrt());
        }
    }
    let reference_of_export = worst / size;
    let again = keyrig_io::bvh::import_scene(&out).expect("re-import");
    let reimported = max_error(&expected, &again) / size;
    assert_eq!(again.fps, scene.fps);
    // The same skeleton with the same orders.
    let (a, b) = (&scene.objects[0].skeleton, &again.objects[0].skeleton);
    let modes = |s: &Option<keyrig_core::Skeleton>| {
        s.as_ref().map(|s| s.joints.iter().map(|j| (j.name.clone(), j.rotation_mode)).collect::<Vec<_>>())
    };
    assert_eq!(modes(a), modes(b));
    [imported, reference_of_export, reimported]
}

#[test]
fn cmu_131_01_matches_the_reference_at_every_frame_and_round_trips() {
    let path = corpus("cmu-bvh11/131_01.bvh");
    let scene = keyrig_io::bvh::import_scene(&path).expect("import");
    assert_eq!(scene.fps, 120.0);
    assert_eq!(scene.frame_range, keyrig_core::FrameRange { start: 0, end: 993 });
    let skeleton = scene.objects[0].skeleton.as_ref().expect("skeleton");
    assert_eq!(skeleton.joints.len(), 31 + 7, "31 joints and 7 End Sites as tips");
    assert_eq!(scene.objects[0].name, "131_01");
    let errors = check_file(&path);
    println!(
        "131_01: max joint position error / skeleton size: import {:.3e}, export (reference reading) {:.3e}, export re-imported {:.3e}",
        errors[0], errors[1], errors[2]
    );
    for e in errors {
        assert!(e <= 1e-4, "{errors:?}");
    }
}

/// A small deterministic generator of angles and offsets.
struct Lcg(u64);

impl Lcg {
    fn next(&mut self) -> f64 {
        self.0 = self.0.wrapping_mul(6364136223846793005).wrapping_add(1442695040888963407);
        ((self.0 >> 11) as f64 / (1u64 << 53) as f64) * 2.0 - 1.0
    }
}

/// A hand-made file with other orders (XYZ, YXZ, YZX listings), channels interleaved, a joint
/// with only position channels, one with a single rotation channel, one with none, and angles
/// anywhere in ±400°.
fn hand_made() -> String {
    let hierarchy = "HIERARCHY
ROOT root
{
  OFFSET 0.5 1 -0.25
  CHANNELS 6 Xposition Yposition Zposition Xrotation Yrotation Zrotation
  JOINT spine
  {
    OFFSET 0 1 0
    CHANNELS 3 Yrotation Xrotation Zrotation
    JOINT neck
    {
      OFFSET 0.1 0.8 0
      CHANNELS 6 Zrotation Xposition Yrotation Yposition Xrotation Zposition
      JOINT head
      {
        OFFSET 0 0.3 0.1
        CHANNELS 1 Yrotation
        End Site
        {
          OFFSET 0 0.2 0
        }
      }
    }
    JOINT arm
    {
      OFFSET 0.4 0.6 0
      CHANNELS 3 Yrotation Zrotation Xrotation
      JOINT slide
      {
        OFFSET 0.7 0 0
        CHANNELS 3 Xposition Yposition Zposition
        JOINT hand
        {
          OFFSET 0.3 0 0
          CHANNELS 0
          End Site
          {
            OFFSET 0.1 0 0
          }
        }
      }
    }
  }
}
MOTION
";
    let channels = 6 + 3 + 6 + 1 + 3 + 3;
    let frames = 40;
    let mut text = format!("{hierarchy}Frames: {frames}\nFrame Time: 0.04\n");
    let mut rng = Lcg(7);
    for _ in 0..frames {
        let row: Vec<String> = (0..channels).map(|_| format!("{:.4}", 400.0 * rng.next())).collect();
        text.push_str(&row.join(" "));
        text.push('\n');
    }
    // Positions in metres, not hundreds: the position columns are scaled down.
    let mut lines: Vec<String> = text.lines().map(str::to_owned).collect();
    let positions: &[usize] = &[0, 1, 2, 10, 12, 14, 19, 20, 21];
    let start = lines.iter().position(|l| l.starts_with("Frame Time")).expect("motion") + 1;
    for line in &mut lines[start..] {
        let mut v: Vec<String> = line.split(' ').map(str::to_owned).collect();
        for &p in positions {
            let x: f64 = v[p].parse().expect("number");
            v[p] = format!("{:.5}", x / 400.0);
        }
        *line = v.join(" ");
    }
    lines.join("\n") + "\n"
}

#[test]
fn other_orders_and_mixed_channels_match_the_reference_and_round_trip() {
    let dir = tempfile::tempdir().expect("temp dir");
    let path = dir.path().join("mixed.bvh");
    std::fs::write(&path, hand_made()).expect("write");
    let scene = keyrig_io::bvh::import_scene(&path).expect("import");
    assert_eq!(scene.fps, 25.0);
    let skeleton = scene.objects[0].skeleton.as_ref().expect("skeleton");
    let order =
        |name: &str| skeleton.joints.iter().find(|j| j.name == name).map(|j| j.rotation_mode).expect("joint");
    use keyrig_core::{EulerOrder, RotationMode};
    // Listings X Y Z, Y X Z, Z Y X (neck: Z Y X among its interleaved channels): reversed.
    assert_eq!(order("root"), RotationMode::Euler(EulerOrder::ZYX));
    assert_eq!(order("spine"), RotationMode::Euler(EulerOrder::ZXY));
    assert_eq!(order("neck"), RotationMode::Euler(EulerOrder::XYZ));
    assert_eq!(order("arm"), RotationMode::Euler(EulerOrder::XZY));
    let errors = check_file(&path);
    println!("hand-made: import {:.3e}, export {:.3e}, re-imported {:.3e}", errors[0], errors[1], errors[2]);
    for e in errors {
        assert!(e <= 1e-4, "{errors:?}");
    }
}

#[test]
fn export_refuses_what_it_cannot_write_and_writes_atomically() {
    let path = corpus("cmu-bvh11/131_01.bvh");
    let scene = keyrig_io::bvh::import_scene(&path).expect("import");
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("out.bvh");
    let e = keyrig_io::bvh::export_scene(&scene, 3, &out).expect_err("no object 3");
    assert!(e.to_string().contains("no object 3"), "{e}");
    let e = keyrig_io::bvh::export_scene(&scene, "nobody", &out).expect_err("no such name");
    assert!(e.to_string().contains("no object named"), "{e}");
    let mut no_skeleton = scene.clone();
    no_skeleton.objects[0].skeleton = None;
    let e = keyrig_io::bvh::export_scene(&no_skeleton, 0, &out).expect_err("no skeleton");
    assert!(e.to_string().contains("no skeleton"), "{e}");
    assert!(!out.exists());
    // A root position beyond what BVH readers take (an OFFSET and a translation near the limit).
    let mut far = scene.clone();
    if let Some(s) = far.objects[0].skeleton.as_mut() {
        s.joints[0].rest_translation = glam::Vec3::new(9e5, 0.0, 0.0);
        s.root_translation = keyrig_core::Animated::constant(glam::Vec3::new(9e5, 0.0, 0.0));
    }
    let e = keyrig_io::bvh::export_scene(&far, 0, &out).expect_err("out of range");
    assert!(matches!(e.kind, keyrig_io::bvh::BvhErrorKind::OutOfRange(_)), "{e}");
    assert!(e.to_string().contains("joint `Hips` at frame 0: position"), "{e}");
    assert!(!out.exists());
    keyrig_io::bvh::export_scene(&scene, "131_01", &out).expect("export by name");
    let entries: Vec<_> =
        std::fs::read_dir(dir.path()).expect("dir").map(|e| e.expect("entry").file_name()).collect();
    assert_eq!(entries, [std::ffi::OsString::from("out.bvh")], "no temporary file left");
}

#[test]
fn a_scene_made_in_keyrig_exports_and_reads_back_with_the_same_poses() {
    // The demo's arm: quaternion keys (TCB, a spin), exported in YXZ and read back.
    let scene = keyrig_io::demo::demo_scene();
    let arm = scene.objects.iter().position(|o| o.name == "Arm").expect("the demo arm");
    let dir = tempfile::tempdir().expect("temp dir");
    let out = dir.path().join("arm.bvh");
    keyrig_io::bvh::export_scene(&scene, arm, &out).expect("export");
    let back = keyrig_io::bvh::import_scene(&out).expect("import");
    let reference = reference(&std::fs::read_to_string(&out).expect("read"));
    let size = reference.size();
    let error = max_error(&reference, &back) / size;
    assert!(error <= 1e-5, "{error}");
    // Against the demo's own evaluation of the arm, in the object's space.
    let eval = SceneEvaluator::new(&scene, &HashMap::new());
    let none = Overrides::default();
    let back_eval = SceneEvaluator::new(&back, &HashMap::new());
    let n = scene.objects[arm].skeleton.as_ref().map_or(0, |s| s.joints.len());
    let mut worst = 0.0f32;
    for frame in scene.frame_range.start..=scene.frame_range.end {
        let t = f64::from(frame) / scene.fps;
        let a = eval.object_at(arm, t, &none).and_then(|s| s.palette).expect("palette");
        let b = back_eval.object_at(0, t, &none).and_then(|s| s.palette).expect("palette");
        for j in 0..n {
            worst =
                worst.max((a.model_from_joint[j].translation - b.model_from_joint[j].translation).length());
        }
    }
    assert!(worst <= 1e-4 * size as f32, "{worst}");
}

#[test]
fn exported_euler_keys_keep_the_files_angles_unwrapped() {
    // mixed.bvh has 370°, −720° and 90° angles and interleaved channels: the export writes
    // the keyed angles themselves (not 10° or 0°), whatever order its channels come in.
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("tests/fixtures/bvh/mixed.bvh");
    let original = keyrig_io::bvh::read_bvh_file(&path).expect("read");
    let scene = keyrig_io::bvh::import_scene(&path).expect("import");
    let text = keyrig_io::bvh::bvh_text(&scene, 0).expect("export");
    let exported = keyrig_io::bvh::parse_bvh(&text, None).expect("reads back");
    assert_eq!(exported.frames, original.frames);
    let mut compared = 0;
    for (j, joint) in original.joints.iter().enumerate() {
        if joint.end_site || joint.euler_order().is_none() {
            continue;
        }
        assert_eq!(exported.joints[j].euler_order(), joint.euler_order(), "{}", joint.name);
        for f in 0..original.frames {
            let (a, b) = (original.joint_values(j, f, true), exported.joint_values(j, f, true));
            assert!((a - b).abs().max_element() < 1e-3, "{} frame {f}: {a} vs {b}", joint.name);
            compared += 1;
        }
    }
    assert_eq!(compared, 3 * 3, "root, neck and head over three frames");
    assert!(text.contains("370") && text.contains("-720"), "{text}");
}
