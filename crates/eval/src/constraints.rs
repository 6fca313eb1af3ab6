//! Object constraints that need the evaluator (docs/constraints.md): switching a child-of
//! constraint's parent without a jump, and baking constraints to keys for formats that have
//! none (glTF, VRML).

use std::collections::HashMap;

use glam::{Affine3A, Mat4, Quat, Vec3};
use keyrig_core::object_constraint::ConstraintKind;
use keyrig_core::{AimTarget, Animated, AnimatedTrack, ChildOfParent, Interpolation, Key, RawTrack, Scene};

use crate::bake::BakeError;
use crate::evaluator::constraints::resolve_target;
use crate::evaluator::{Overrides, SceneEvaluator};

/// Why a child-of switch cannot be made.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum SwitchError {
    #[error("objects[{object}] has no child-of constraint {constraint}")]
    NotChildOf { object: usize, constraint: usize },
    #[error("cannot switch the parent to {target}: {message}")]
    BadTarget { target: String, message: String },
    #[error("cannot switch at time {0}: not a finite time")]
    BadTime(f64),
    #[error("the offset for the new parent cannot be computed at time {time} (a parent or the object has no invertible transform)")]
    Singular { time: f64 },
}

/// Makes `target` the parent of child-of constraint `constraint` of `object` from `time` on,
/// without moving the object at `time` (Blender's Child Of *Set Inverse*, taken at the
/// switch): a parent entry is added with the offset
///
/// ```text
/// offset = F_new(t)⁻¹ · C(t) · W_in(t)⁻¹
/// ```
///
/// (`W_in`: the transform going into the constraint, `C`: the constraint's result with the
/// parent it had at `t`; [`SceneEvaluator::constraint_frames`]), and the `parent` channel is
/// keyed at `time` with a Step key selecting it. Releasing the object to the world is a switch
/// to the point target at the origin. When the channel had no keys yet, its old value is kept
/// before `time` by a Step key at the start of the frame range (or a frame before `time`).
/// Returns the new parent's index.
///
/// # Errors
/// [`SwitchError`]: not a child-of constraint, an unknown target (or the object itself), a
/// time that is not finite, transforms that cannot be inverted.
pub fn switch_parent(
    scene: &mut Scene,
    object: usize,
    constraint: usize,
    time: f64,
    target: AimTarget,
) -> Result<usize, SwitchError> {
    let not_child_of = SwitchError::NotChildOf { object, constraint };
    if !time.is_finite() {
        return Err(SwitchError::BadTime(time));
    }
    let c =
        scene.objects.get(object).and_then(|o| o.constraints.get(constraint)).ok_or(not_child_of.clone())?;
    if !matches!(c.kind, ConstraintKind::ChildOf { .. }) {
        return Err(not_child_of);
    }
    let mut problems = Vec::new();
    let resolved = resolve_target(scene, &target, "target", &mut problems);
    let bad = |message: String| SwitchError::BadTarget { target: format!("{target:?}"), message };
    if let Some(p) = problems.first() {
        return Err(bad(p.message.clone()));
    }
    if keyrig_core::object_constraint::target_object(scene, &target) == Some(object) {
        return Err(bad("an object cannot be its own parent".to_owned()));
    }
    let evaluator = SceneEvaluator::new(scene, &HashMap::new());
    let none = Overrides::new();
    let (incoming, current) =
        evaluator.constraint_frames(object, constraint, time, &none).ok_or(not_child_of.clone())?;
    let frame =
        evaluator.frame_of(&resolved, time, &none).ok_or_else(|| bad("it cannot be evaluated".to_owned()))?;
    let (frame_det, in_det) = (frame.matrix3.determinant(), incoming.matrix3.determinant());
    if !(frame_det.abs() > 1e-12 && in_det.abs() > 1e-12) {
        return Err(SwitchError::Singular { time });
    }
    let offset: Affine3A = frame.inverse() * current * incoming.inverse();
    let fps = scene.fps;
    let start = f64::from(scene.frame_range.start) / fps;
    let Some(ConstraintKind::ChildOf { parents, parent }) =
        scene.objects.get_mut(object).and_then(|o| o.constraints.get_mut(constraint)).map(|c| &mut c.kind)
    else {
        return Err(not_child_of);
    };
    parents.push(ChildOfParent { target, offset: Mat4::from(offset) });
    let index = parents.len() - 1;
    if parent.track.is_empty() {
        let before = if start < time { start } else { time - 1.0 / fps.max(1.0) };
        if parent.value.round() as i64 != index as i64 {
            set_step_key(parent, before, parent.value);
        }
    }
    set_step_key(parent, time, index as f32);
    Ok(index)
}

/// Sets a Step key of value `value` at `time`, replacing a key at that time.
fn set_step_key(animated: &mut Animated<f32>, time: f64, value: f32) {
    let mut keys: Vec<Key<f32>> = animated.track.keys.iter().filter(|k| k.time != time).cloned().collect();
    let at = keys.partition_point(|k| k.time < time);
    keys.insert(at, Key::new(time, value).with_interpolation(Interpolation::Step));
    animated.track = RawTrack::new(keys);
}

/// Whether an object constraint moves anything: its influence is keyed or not 0.
#[must_use]
pub fn constraint_has_effect(scene: &Scene, object: usize, constraint: usize) -> bool {
    scene
        .objects
        .get(object)
        .and_then(|o| o.constraints.get(constraint))
        .is_some_and(|c| c.influence.is_animated() || c.influence.value != 0.0)
}

/// Bakes every object constraint of the scene (docs/constraints.md, "Baking"): each object
/// with a constraint that has an effect gets its evaluated world transform — constraints
/// applied — as LINEAR keys of its translation, rotation and scale at every frame of
/// `start..=end` (keys inside that range replaced, those outside kept; an object with Euler
/// keys gets Euler keys, the angles nearest the previous frame's), and its constraints are
/// removed. Every object is sampled from the scene as it was, so an object constrained to a
/// constrained object bakes what was shown. Returns the number of objects baked.
///
/// # Errors
/// An empty range or a scene without a positive fps.
pub fn bake_object_constraints(scene: &mut Scene, start: i32, end: i32) -> Result<usize, BakeError> {
    let constrained: Vec<usize> = (0..scene.objects.len())
        .filter(|&o| (0..scene.objects[o].constraints.len()).any(|c| constraint_has_effect(scene, o, c)))
        .collect();
    if constrained.is_empty() {
        for o in &mut scene.objects {
            o.constraints.clear();
        }
        return Ok(0);
    }
    if start > end {
        return Err(BakeError::EmptyRange { start, end });
    }
    if !(scene.fps.is_finite() && scene.fps > 0.0) {
        return Err(BakeError::BadFps(scene.fps));
    }
    let fps = scene.fps;
    let evaluator = SceneEvaluator::new(scene, &HashMap::new());
    let none = Overrides::new();
    let mut sampled: Vec<Vec<(f64, Vec3, Quat, Vec3)>> = Vec::new();
    for &object in &constrained {
        let mut keys = Vec::with_capacity((end - start) as usize + 1);
        let mut last = Quat::IDENTITY;
        for frame in start..=end {
            let time = f64::from(frame) / fps;
            let state =
                evaluator.object_at(object, time, &none).ok_or(BakeError::NoPose { object, frame })?;
            let (s, mut r, t) = state.world_from_object.to_scale_rotation_translation();
            // The same hemisphere as the previous key: LINEAR keys slerp the short way anyway,
            // but sign flips would read as jumps in the curve view.
            if !keys.is_empty() && r.dot(last) < 0.0 {
                r = -r;
            }
            last = r;
            keys.push((time, t, r.normalize(), s));
        }
        sampled.push(keys);
    }
    let (t0, t1) = (f64::from(start) / fps, f64::from(end) / fps);
    let slack = 0.5 / fps;
    for (&object, keys) in constrained.iter().zip(sampled) {
        let o = &mut scene.objects[object];
        splice(&mut o.translation, keys.iter().map(|k| linear(k.0, k.1)).collect(), t0 - slack, t1 + slack);
        splice(&mut o.scale, keys.iter().map(|k| linear(k.0, k.3)).collect(), t0 - slack, t1 + slack);
        match (&mut o.rotation_euler, o.rotation_mode.euler()) {
            (Some(euler), Some(order)) => {
                let mut e = AnimatedTrack::new(euler).map_or(euler.value, |track| track.sample(t0));
                let angles = keys.iter().map(|k| {
                    e = order.angles_near(k.2, e);
                    linear(k.0, e)
                });
                splice(euler, angles.collect(), t0 - slack, t1 + slack);
            }
            _ => splice(
                &mut o.rotation,
                keys.iter().map(|k| linear(k.0, k.2)).collect(),
                t0 - slack,
                t1 + slack,
            ),
        }
    }
    for o in &mut scene.objects {
        o.constraints.clear();
    }
    Ok(constrained.len())
}

fn linear<T>(time: f64, value: T) -> Key<T> {
    Key::new(time, value).with_interpolation(Interpolation::Linear)
}

/// Replaces the keys of `animated` between `from` and `to` with `new_keys`.
fn splice<T: Clone>(animated: &mut Animated<T>, new_keys: Vec<Key<T>>, from: f64, to: f64) {
    let old = animated.track.keys.iter();
    let before = old.clone().filter(|k| k.time < from).cloned();
    let after = old.filter(|k| k.time > to).cloned();
    animated.track = RawTrack::new(before.chain(new_keys).chain(after).collect());
}
