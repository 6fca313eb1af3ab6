//! BVH export: one object's skeleton and its animation, sampled at every frame of the scene's
//! frame range through the scene evaluator (so IK constraints, cycles and muted channels play
//! as keyrig shows them).
//!
//! Per joint: OFFSET = rest translation (a non-root joint's static translation added); the
//! rotation written is the joint's R(j)·T(j) rotation (`rest_rotation · rotation`) as Euler
//! angles in the joint's own order when its `rotation_mode` is Euler (the BVH listing is the
//! order reversed: keyrig `XYZ` is written `Zrotation Yrotation Xrotation`), in keyrig `YXZ`
//! (`Zrotation Xrotation Yrotation`) for quaternion joints. Euler keys are written as keyed
//! (unwrapped angles stay unwrapped) wherever the joint's rest rotation is the identity and
//! nothing (IK) changed the rotation; elsewhere the angles are the ones nearest the previous
//! frame's ([`EulerOrder::angles_near`]), so they stay continuous.
//!
//! The root gets six channels and OFFSET 0 0 0: its positions are the whole root position
//! (skeleton root translation + rest translation + rest rotation · animated translation), so
//! readers that take the root's position channels as absolute and readers that add them to the
//! OFFSET read the same place. Another joint with translation keys gets position channels
//! (`rest_rotation · translation`, added to its OFFSET). A leaf joint that is not animated (no
//! keys, identity rotation) is written as an End Site; a leaf joint that is animated gets an
//! End Site at its own origin. Joint scale and the object's transform are not written (BVH has
//! neither): the skeleton is written in the object's space.

use std::collections::HashMap;
use std::fmt::Write as _;
use std::io::Write;
use std::path::Path;

use glam::{Quat, Vec3};
use keyrig_core::channel_id::ChannelId;
use keyrig_core::channel_value::ChannelValue;
use keyrig_core::{EulerOrder, Joint, Scene};
use keyrig_eval::{Overrides, SceneEvaluator};

use super::{BvhError, BvhErrorKind};

/// Which object to export: by index or by name.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ExportTarget<'a> {
    Index(usize),
    Name(&'a str),
}

impl From<usize> for ExportTarget<'_> {
    fn from(i: usize) -> Self {
        ExportTarget::Index(i)
    }
}

impl<'a> From<&'a str> for ExportTarget<'a> {
    fn from(name: &'a str) -> Self {
        ExportTarget::Name(name)
    }
}

/// The Euler order quaternion joints are written in: keyrig `YXZ`, BVH `Zrotation Xrotation
/// Yrotation`, the listing most BVH files use.
pub const QUATERNION_JOINT_ORDER: EulerOrder = EulerOrder::YXZ;

fn export_error(message: String) -> BvhError {
    BvhError { file: None, place: None, kind: BvhErrorKind::Export(message) }
}

/// How one joint is written.
struct Written {
    end_site: bool,
    order: EulerOrder,
    position: bool,
}

/// A joint a BVH End Site can stand for: no keys anywhere, identity rotations, unit scale.
fn is_tip(j: &Joint) -> bool {
    j.parent.is_some()
        && !j.translation.is_animated()
        && !j.rotation.is_animated()
        && j.rotation_euler.as_ref().is_none_or(|e| !e.is_animated() && e.value == Vec3::ZERO)
        && !j.scale.is_animated()
        && j.scale.value == Vec3::ONE
        && quat_is_identity(j.rotation.value)
        && quat_is_identity(j.rest_rotation)
}

fn quat_is_identity(q: Quat) -> bool {
    let q = q.normalize();
    q.is_finite() && q.w.abs() >= 1.0 - 1e-7
}

/// A joint name as one BVH token: white space and braces become `_`.
fn token_name(name: &str) -> String {
    name.chars().map(|c| if c.is_whitespace() || c == '{' || c == '}' { '_' } else { c }).collect()
}

/// The BVH text of object `object` of `scene` (module documentation).
///
/// # Errors
/// No such object, no skeleton, or the scene has problems ([`keyrig_core::Scene::problems`]).
pub fn bvh_text<'a>(scene: &Scene, object: impl Into<ExportTarget<'a>>) -> Result<String, BvhError> {
    let mut out = Vec::new();
    write_bvh(&mut out, scene, object)?;
    String::from_utf8(out).map_err(|e| export_error(format!("the text is not UTF-8: {e}")))
}

/// Writes object `object` of `scene` as BVH to `out` (module documentation).
///
/// # Errors
/// As [`bvh_text`], or a write error.
pub fn write_bvh<'a>(
    out: &mut dyn Write,
    scene: &Scene,
    object: impl Into<ExportTarget<'a>>,
) -> Result<(), BvhError> {
    let o = match object.into() {
        ExportTarget::Index(i) if i < scene.objects.len() => i,
        ExportTarget::Index(i) => {
            return Err(export_error(format!("no object {i}: the scene has {} objects", scene.objects.len())))
        }
        ExportTarget::Name(name) => scene
            .objects
            .iter()
            .position(|x| x.name == name)
            .ok_or_else(|| export_error(format!("no object named {name:?}")))?,
    };
    let problems = scene.problems();
    if let Some(first) = problems.first() {
        return Err(export_error(format!(
            "the scene has {} problem(s), the first: {}: {}",
            problems.len(),
            first.path,
            first.message
        )));
    }
    let object = &scene.objects[o];
    let skeleton = object
        .skeleton
        .as_ref()
        .filter(|s| !s.joints.is_empty())
        .ok_or_else(|| export_error(format!("object {:?} has no skeleton to write", object.name)))?;
    let joints = &skeleton.joints;
    let n = joints.len();
    let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
    for (j, joint) in joints.iter().enumerate() {
        if let Some(p) = joint.parent {
            children[p].push(j);
        }
    }
    let written: Vec<Written> = (0..n)
        .map(|j| {
            let joint = &joints[j];
            Written {
                end_site: children[j].is_empty() && is_tip(joint),
                order: joint.rotation_mode.euler().unwrap_or(QUATERNION_JOINT_ORDER),
                position: joint.parent.is_none() || joint.translation.is_animated(),
            }
        })
        .collect();
    let w = |e: std::io::Error| BvhError { file: None, place: None, kind: BvhErrorKind::Write(e) };

    let range_start = scene.frame_range.start;
    // HIERARCHY, depth first without recursion: (joint, depth, closing?).
    let mut text = String::from("HIERARCHY\n");
    let mut stack: Vec<(usize, usize, bool)> = vec![(0, 0, false)];
    let mut channel_order: Vec<usize> = Vec::new();
    while let Some((j, depth, closing)) = stack.pop() {
        let pad = "\t".repeat(depth);
        if closing {
            let _ = writeln!(text, "{pad}}}");
            continue;
        }
        let info = &written[j];
        let joint = &joints[j];
        if info.end_site {
            let offset = joint.rest_translation + joint.translation.value;
            check_range(offset, &joint.name, range_start, "End Site OFFSET")?;
            let _ = writeln!(text, "{pad}End Site\n{pad}{{\n{pad}\tOFFSET {}\n{pad}}}", vec3(offset));
            continue;
        }
        let keyword = if joint.parent.is_none() { "ROOT" } else { "JOINT" };
        let offset = if joint.parent.is_none() {
            Vec3::ZERO
        } else if info.position {
            joint.rest_translation
        } else {
            joint.rest_translation + joint.rest_rotation * joint.translation.value
        };
        check_range(offset, &joint.name, range_start, "OFFSET")?;
        let _ = writeln!(
            text,
            "{pad}{keyword} {}\n{pad}{{\n{pad}\tOFFSET {}",
            token_name(&joint.name),
            vec3(offset)
        );
        let mut names: Vec<&str> = Vec::new();
        if info.position {
            names.extend(["Xposition", "Yposition", "Zposition"]);
        }
        names.extend(info.order.axes().iter().rev().map(|&a| ["Xrotation", "Yrotation", "Zrotation"][a]));
        let _ = writeln!(text, "{pad}\tCHANNELS {} {}", names.len(), names.join(" "));
        channel_order.push(j);
        stack.push((j, depth, true));
        if children[j].is_empty() {
            let _ = writeln!(text, "{pad}\tEnd Site\n{pad}\t{{\n{pad}\t\tOFFSET 0 0 0\n{pad}\t}}");
        }
        for &c in children[j].iter().rev() {
            stack.push((c, depth + 1, false));
        }
    }

    let range = scene.frame_range;
    let frames = i64::from(range.end) - i64::from(range.start) + 1;
    let _ = write!(text, "MOTION\nFrames: {frames}\nFrame Time: {}\n", 1.0 / scene.fps);
    out.write_all(text.as_bytes()).map_err(w)?;

    let evaluator = SceneEvaluator::new(scene, &HashMap::new());
    let none = Overrides::default();
    let mut previous: Vec<Option<Vec3>> = vec![None; n];
    let mut row = String::new();
    for frame in range.start..=range.end {
        let time = f64::from(frame) / scene.fps;
        let state = evaluator
            .object_at(o, time, &none)
            .and_then(|s| s.pose)
            .ok_or_else(|| export_error(format!("object {:?} has no pose at frame {frame}", object.name)))?;
        row.clear();
        for &j in &channel_order {
            let joint = &joints[j];
            let info = &written[j];
            let t = state.local_translations.get(j).copied().unwrap_or(Vec3::ZERO);
            let q = state.local_rotations.get(j).copied().unwrap_or(Quat::IDENTITY);
            if info.position {
                let p = if joint.parent.is_none() {
                    state.root_translation + joint.rest_translation + joint.rest_rotation * t
                } else {
                    joint.rest_rotation * t
                };
                check_range(p, &joint.name, frame, "position")?;
                let _ = write!(row, "{} {} {} ", p.x, p.y, p.z);
            }
            let rotation = (joint.rest_rotation.normalize() * q).normalize();
            let angles =
                keyed_angles(&evaluator, o, j, joint, info.order, time, rotation).unwrap_or_else(|| {
                    match previous[j] {
                        Some(near) => info.order.angles_near(rotation, near),
                        None => info.order.angles(rotation),
                    }
                });
            check_range(angles, &joint.name, frame, "rotation")?;
            previous[j] = Some(angles);
            for &axis in info.order.axes().iter().rev() {
                let _ = write!(row, "{} ", angles[axis]);
            }
        }
        row.pop();
        row.push('\n');
        out.write_all(row.as_bytes()).map_err(w)?;
    }
    out.flush().map_err(w)
}

/// The joint's Euler keys at `time` when they are what it shows: the joint has Euler keys in
/// `order`, an identity rest rotation, and the keyed angles make `rotation` (nothing such as
/// IK turned it).
fn keyed_angles(
    evaluator: &SceneEvaluator,
    object: usize,
    joint: usize,
    j: &Joint,
    order: EulerOrder,
    time: f64,
    rotation: Quat,
) -> Option<Vec3> {
    if j.rotation_euler.is_none()
        || j.rotation_mode.euler() != Some(order)
        || !quat_is_identity(j.rest_rotation)
    {
        return None;
    }
    let Some(ChannelValue::Vec3(angles)) =
        evaluator.value(ChannelId::JointEuler { object, joint }, time, &Overrides::default())
    else {
        return None;
    };
    // Within about 0.002°.
    (order.to_quat(angles).dot(rotation).abs() >= 1.0 - 1e-9).then_some(angles)
}

/// Refuses a value BVH readers would refuse (beyond ±[`super::MAX_ABS_VALUE`] or not finite).
fn check_range(v: Vec3, joint: &str, frame: i32, what: &str) -> Result<(), BvhError> {
    if v.is_finite() && v.abs().max_element() <= super::MAX_ABS_VALUE {
        return Ok(());
    }
    Err(BvhError {
        file: None,
        place: None,
        kind: BvhErrorKind::OutOfRange(
            crate::message::clip_long_tokens(&format!(
                "joint `{joint}` at frame {frame}: {what} {v} lies beyond ±{}, which BVH readers refuse",
                super::MAX_ABS_VALUE
            ))
            .into_owned(),
        ),
    })
}

fn vec3(v: Vec3) -> String {
    format!("{} {} {}", v.x, v.y, v.z)
}

/// Writes object `object` of `scene` as a BVH file at `path`, atomically (a temporary file in
/// the same folder renamed over `path`: [`crate::file_io::write_atomic_with`]). Refuses a
/// `path` that is one of the files the scene reads ([`crate::project::scene_inputs`]); a
/// command that read its scene from a file passes that file to
/// [`crate::file_io::refuse_overwriting`] itself.
///
/// # Errors
/// As [`write_bvh`], the output would replace an input, or the file cannot be written.
pub fn export_scene<'a>(
    scene: &Scene,
    object: impl Into<ExportTarget<'a>>,
    path: &Path,
) -> Result<(), BvhError> {
    let located = |kind: BvhErrorKind| BvhError { file: Some(path.to_path_buf()), place: None, kind };
    crate::file_io::refuse_overwriting(path, &crate::project::scene_inputs(scene, None))
        .map_err(|e| located(BvhErrorKind::Overwrite(e)))?;
    // Write into memory first: an export error leaves no temporary file behind.
    let mut bytes = Vec::new();
    write_bvh(&mut bytes, scene, object).map_err(|e| BvhError { file: Some(path.to_path_buf()), ..e })?;
    crate::file_io::write_atomic(path, &bytes).map_err(|e| located(BvhErrorKind::Write(e)))
}
