//! Baking IK constraints to rotation keys (issue 19): the rotations the evaluator solves for a
//! constraint's chain are written as ordinary rotation keys on the chain's joints at every frame
//! of a range, and the constraint's blend is set to 0, so the keys alone show what the
//! constraint showed. glTF export bakes every constraint this way (glTF has no IK).
//!
//! Keys of the chain's joints inside the baked time range are replaced; keys outside it are
//! kept. Baking constraint `c` solves constraints `0..=c` (earlier constraints are part of the
//! pose it starts from), so baking every constraint in order reproduces the evaluated pose.

use std::collections::HashMap;

use glam::Quat;
use keyrig_core::ik_constraint::{ConstraintChain, ConstraintError};
use keyrig_core::{Animated, AnimatedTrack, Key, RawTrack, Scene};

use crate::evaluator::{Overrides, SceneEvaluator};

/// Why a constraint cannot be baked.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum BakeError {
    #[error("object {object} has no IK constraint {constraint}")]
    NoConstraint { object: usize, constraint: usize },
    #[error("objects[{object}].skeleton.ik_constraints[{constraint}]: {source}")]
    Chain { object: usize, constraint: usize, source: ConstraintError },
    #[error("cannot bake frames {start}..={end}: the range is empty")]
    EmptyRange { start: i32, end: i32 },
    #[error("cannot bake: fps {0} is not a positive number")]
    BadFps(f64),
    #[error("objects[{object}] could not be evaluated at frame {frame}")]
    NoPose { object: usize, frame: i32 },
}

/// What a bake wrote.
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Baked {
    /// The skeleton indices of the joints that were keyed (the chain but its end joint).
    pub joints: Vec<usize>,
    /// Frames keyed on each of them.
    pub frames: usize,
}

/// Bakes IK constraint `constraint` of object `object` into rotation keys on its chain's joints
/// at every frame of `start..=end` (the scene's fps), then sets its blend to 0 (a constant;
/// its blend keys are removed). The keys are TCB keys (T = C = B = 0): at each baked frame the
/// track passes through the solved rotation exactly; between frames it interpolates.
///
/// # Errors
/// A constraint that does not exist or whose chain the skeleton cannot hold, an empty range, a
/// scene without a positive fps.
pub fn bake_ik_constraint(
    scene: &mut Scene,
    object: usize,
    constraint: usize,
    start: i32,
    end: i32,
) -> Result<Baked, BakeError> {
    if start > end {
        return Err(BakeError::EmptyRange { start, end });
    }
    if !(scene.fps.is_finite() && scene.fps > 0.0) {
        return Err(BakeError::BadFps(scene.fps));
    }
    let missing = BakeError::NoConstraint { object, constraint };
    let skeleton = scene.objects.get(object).and_then(|o| o.skeleton.as_ref()).ok_or(missing.clone())?;
    let c = skeleton.ik_constraints.get(constraint).ok_or(missing)?;
    let chain = ConstraintChain::new(skeleton, c).map_err(|source| BakeError::Chain {
        object,
        constraint,
        source,
    })?;
    let joints = chain.turned_joints().to_vec();
    let evaluator = SceneEvaluator::new(scene, &HashMap::new());
    let none = Overrides::new();
    let fps = scene.fps;
    let mut solved: Vec<Vec<Key<Quat>>> = vec![Vec::new(); joints.len()];
    for frame in start..=end {
        let time = f64::from(frame) / fps;
        let pose = evaluator
            .object_at_solving(object, time, &none, constraint + 1)
            .and_then(|state| state.pose)
            .ok_or(BakeError::NoPose { object, frame })?;
        for (keys, &j) in solved.iter_mut().zip(&joints) {
            keys.push(Key::new(time, pose.local_rotations[j]));
        }
    }
    let (t0, t1) = (f64::from(start) / fps, f64::from(end) / fps);
    // Half a frame of slack: a key closer to the range than that would sit between baked keys.
    let slack = 0.5 / fps;
    let skeleton = scene.objects[object].skeleton.as_mut().expect("checked above");
    for (new_keys, &j) in solved.into_iter().zip(&joints) {
        let joint = &mut skeleton.joints[j];
        match (&mut joint.rotation_euler, joint.rotation_mode.euler()) {
            // Euler keys: each solved rotation as the angles nearest the previous frame's,
            // starting from the curve's angles at the first frame (docs/channels.md).
            (Some(euler), Some(order)) => {
                let mut e = AnimatedTrack::new(euler).map_or(euler.value, |track| track.sample(t0));
                let angles = new_keys.into_iter().map(|k| {
                    e = order.angles_near(k.value, e);
                    Key::new(k.time, e)
                });
                splice_keys(euler, angles.collect(), t0 - slack, t1 + slack);
            }
            _ => splice_keys(&mut joint.rotation, new_keys, t0 - slack, t1 + slack),
        }
    }
    skeleton.ik_constraints[constraint].blend = Animated::constant(0.0);
    Ok(Baked { joints, frames: (end - start) as usize + 1 })
}

/// Replaces the keys of `animated` between `from` and `to` with `new_keys`.
fn splice_keys<T: Clone>(animated: &mut Animated<T>, new_keys: Vec<Key<T>>, from: f64, to: f64) {
    let old = animated.track.keys.iter();
    let before = old.clone().filter(|k| k.time < from).cloned();
    let after = old.filter(|k| k.time > to).cloned();
    let keys: Vec<Key<T>> = before.chain(new_keys).chain(after).collect();
    animated.track = RawTrack::new(keys);
}

/// Bakes every IK constraint of the scene whose blend is not constantly 0, in order, over
/// `start..=end` ([`bake_ik_constraint`]). Returns how many constraints were baked.
///
/// # Errors
/// The first constraint that cannot be baked.
pub fn bake_all_ik(scene: &mut Scene, start: i32, end: i32) -> Result<usize, BakeError> {
    let mut baked = 0;
    for object in 0..scene.objects.len() {
        let count = scene.objects[object].skeleton.as_ref().map_or(0, |s| s.ik_constraints.len());
        for constraint in 0..count {
            if !has_effect(scene, object, constraint) {
                continue;
            }
            bake_ik_constraint(scene, object, constraint, start, end)?;
            baked += 1;
        }
    }
    Ok(baked)
}

/// Whether IK constraint `constraint` of `object` moves anything: its blend is keyed or not 0.
#[must_use]
pub fn has_effect(scene: &Scene, object: usize, constraint: usize) -> bool {
    scene
        .objects
        .get(object)
        .and_then(|o| o.skeleton.as_ref())
        .and_then(|s| s.ik_constraints.get(constraint))
        .is_some_and(|c| c.blend.is_animated() || c.blend.value != 0.0)
}
