//! Object constraints at evaluation time (docs/constraints.md): each object's constraints
//! resolved to indices, and applied in order to its world transform once its targets are
//! evaluated.

use glam::{Affine3A, Vec3};
use keyrig_core::channel_id::{ChannelId, ChannelValue, ConstraintProperty};
use keyrig_core::object_constraint::{
    aim_axis_rotation, blend_transforms, evaluation_order, path_point, with_rotation, with_translation,
    AimAxis, ConstraintKind,
};
use keyrig_core::{AimTarget, Scene};

use crate::camera::Target;
use crate::slot::{EvalProblem, Overrides, Slot};

/// A constraint's kind with its targets resolved.
#[derive(Clone, Debug)]
enum Resolved {
    AimAt {
        target: Target,
        axis: AimAxis,
        up: Vec3,
    },
    CopyLocation(Target),
    CopyRotation(Target),
    ChildOf {
        parents: Vec<(Target, Affine3A)>,
    },
    FollowPath {
        points: Vec<Vec3>,
        space: Option<Target>,
        axis: Option<AimAxis>,
    },
    /// On a cycle of constraints: not applied.
    Off,
}

/// One object constraint's runtime form.
#[derive(Clone, Debug)]
pub(crate) struct ConstraintRig {
    kind: Resolved,
    influence: Slot<f32>,
    /// The child-of parent index or the follow-path offset.
    value: Option<(ConstraintProperty, Slot<f32>)>,
    problems: Vec<EvalProblem>,
}

/// Resolves a target by name; a name that is not there is a problem at `path`.
pub(crate) fn resolve_target(
    scene: &Scene,
    target: &AimTarget,
    path: &str,
    problems: &mut Vec<EvalProblem>,
) -> Target {
    match target {
        AimTarget::Point(p) => Target::Point(*p),
        AimTarget::Object(name) => match scene.objects.iter().position(|o| &o.name == name) {
            Some(o) => Target::Object(o),
            None => {
                problems.push(EvalProblem {
                    path: path.to_owned(),
                    message: format!("no object named {name:?}"),
                });
                Target::Missing
            }
        },
        AimTarget::Joint { object, joint } => {
            let found = scene.objects.iter().position(|o| &o.name == object).and_then(|o| {
                let skeleton = scene.objects[o].skeleton.as_ref()?;
                Some((o, skeleton.joints.iter().position(|j| &j.name == joint)?))
            });
            match found {
                Some((object, joint)) => Target::Joint { object, joint },
                None => {
                    problems.push(EvalProblem {
                        path: path.to_owned(),
                        message: format!("no joint {object:?}/{joint:?}"),
                    });
                    Target::Missing
                }
            }
        }
    }
}

impl ConstraintRig {
    fn new(scene: &Scene, o: usize, c: usize, on_cycle: bool) -> Self {
        let constraint = &scene.objects[o].constraints[c];
        let path = format!("objects[{o}].constraints[{c}]");
        let mut problems = Vec::new();
        let id = |property| ChannelId::Constraint { object: o, constraint: c, property };
        let mut value = None;
        let kind = match &constraint.kind {
            _ if on_cycle => Resolved::Off,
            ConstraintKind::AimAt { target, axis, up } => Resolved::AimAt {
                target: resolve_target(scene, target, &format!("{path}.kind.target"), &mut problems),
                axis: *axis,
                up: *up,
            },
            ConstraintKind::CopyLocation { target } => Resolved::CopyLocation(resolve_target(
                scene,
                target,
                &format!("{path}.kind.target"),
                &mut problems,
            )),
            ConstraintKind::CopyRotation { target } => Resolved::CopyRotation(resolve_target(
                scene,
                target,
                &format!("{path}.kind.target"),
                &mut problems,
            )),
            ConstraintKind::ChildOf { parents, parent } => {
                value = Some((ConstraintProperty::Parent, Slot::new(parent, id(ConstraintProperty::Parent))));
                Resolved::ChildOf {
                    parents: parents
                        .iter()
                        .enumerate()
                        .map(|(i, p)| {
                            let t = resolve_target(
                                scene,
                                &p.target,
                                &format!("{path}.kind.parents[{i}].target"),
                                &mut problems,
                            );
                            (t, Affine3A::from_mat4(p.offset))
                        })
                        .collect(),
                }
            }
            ConstraintKind::FollowPath { points, space, offset, axis } => {
                value = Some((ConstraintProperty::Offset, Slot::new(offset, id(ConstraintProperty::Offset))));
                Resolved::FollowPath {
                    points: points.clone(),
                    space: space.as_ref().map(|s| {
                        resolve_target(
                            scene,
                            &AimTarget::Object(s.clone()),
                            &format!("{path}.kind.space"),
                            &mut problems,
                        )
                    }),
                    axis: *axis,
                }
            }
        };
        if on_cycle {
            problems.push(EvalProblem {
                path,
                message: "the object's constraints form a cycle with their targets' constraints: not applied"
                    .to_owned(),
            });
        }
        ConstraintRig {
            kind,
            influence: Slot::new(&constraint.influence, id(ConstraintProperty::Influence)),
            value,
            problems,
        }
    }

    pub(crate) fn for_each_problem(&self, f: &mut dyn FnMut(&EvalProblem)) {
        self.problems.iter().for_each(&mut *f);
        if let Some(p) = &self.influence.problem {
            f(p);
        }
        if let Some((_, slot)) = &self.value {
            if let Some(p) = &slot.problem {
                f(p);
            }
        }
    }

    /// The value of the constraint's channel `property` at `time` (no overrides).
    pub(crate) fn value(&self, property: ConstraintProperty, time: f64) -> Option<f32> {
        match property {
            ConstraintProperty::Influence => Some(self.influence.sample(time)),
            _ => self.value.as_ref().filter(|(p, _)| *p == property).map(|(_, s)| s.sample(time)),
        }
    }
}

/// The object constraints of every object and the order objects are evaluated in.
#[derive(Clone, Debug, Default)]
pub(crate) struct ConstraintRigs {
    /// Per object, its constraints.
    pub(crate) objects: Vec<Vec<ConstraintRig>>,
    /// Every object once, each after the objects its constraints read.
    pub(crate) order: Vec<usize>,
}

impl ConstraintRigs {
    /// Builds the rigs again (targets are resolved by name each time: an object may have been
    /// renamed or removed). Returns the number of channels built.
    pub(crate) fn build(scene: &Scene) -> Self {
        let (order, on_cycle) = evaluation_order(scene);
        let objects = scene
            .objects
            .iter()
            .enumerate()
            .map(|(o, object)| {
                (0..object.constraints.len())
                    .map(|c| ConstraintRig::new(scene, o, c, on_cycle.contains(&o)))
                    .collect()
            })
            .collect();
        ConstraintRigs { objects, order }
    }

    pub(crate) fn for_each_problem(&self, f: &mut dyn FnMut(&EvalProblem)) {
        for rig in self.objects.iter().flatten() {
            rig.for_each_problem(f);
        }
    }
}

/// The frame of a target in evaluated objects: an object's world transform, a joint's (world
/// from object · model from joint), a point's translation.
pub(crate) type FrameOf<'a> = dyn Fn(&Target) -> Option<Affine3A> + 'a;

/// Applies object `o`'s constraints `0..upto` to `world` in order, each blended by its
/// influence. `frame_of` gives the frames of the targets at this time.
pub(crate) fn apply(
    rigs: &[ConstraintRig],
    o: usize,
    time: f64,
    overrides: &Overrides,
    upto: usize,
    world: &mut Affine3A,
    frame_of: &FrameOf<'_>,
) {
    for (c, rig) in rigs.iter().enumerate().take(upto) {
        let w = scalar(rig, o, c, ConstraintProperty::Influence, time, overrides);
        if w.is_nan() || w <= 0.0 {
            continue;
        }
        if let Some(result) = result(rig, o, c, time, overrides, world, frame_of) {
            *world = blend_transforms(world, &result, w.min(1.0));
        }
    }
}

/// A constraint channel's value at `time`: an override wins.
fn scalar(
    rig: &ConstraintRig,
    o: usize,
    c: usize,
    property: ConstraintProperty,
    time: f64,
    overrides: &Overrides,
) -> f32 {
    match overrides.get(&ChannelId::Constraint { object: o, constraint: c, property }) {
        Some(ChannelValue::Scalar(v)) => *v,
        _ => rig.value(property, time).unwrap_or(0.0),
    }
}

/// The child-of parent index the `parent` channel value `v` selects among `n` parents.
#[must_use]
pub(crate) fn parent_index(v: f32, n: usize) -> Option<usize> {
    let k = v.round();
    (k.is_finite() && k >= 0.0 && (k as usize) < n).then_some(k as usize)
}

/// Constraint `c`'s own result for the incoming transform `world` (before blending); `None`
/// when it has nothing to do at this time (a missing target, no parent, an aim at its own
/// origin).
pub(crate) fn result(
    rig: &ConstraintRig,
    o: usize,
    c: usize,
    time: f64,
    overrides: &Overrides,
    world: &Affine3A,
    frame_of: &FrameOf<'_>,
) -> Option<Affine3A> {
    match &rig.kind {
        Resolved::Off => None,
        Resolved::CopyLocation(target) => Some(with_translation(world, frame_of(target)?.translation.into())),
        Resolved::CopyRotation(target) => {
            let (_, rotation, _) = frame_of(target)?.to_scale_rotation_translation();
            Some(with_rotation(world, rotation))
        }
        Resolved::AimAt { target, axis, up } => {
            let to = Vec3::from(frame_of(target)?.translation) - Vec3::from(world.translation);
            Some(with_rotation(world, aim_axis_rotation(to, *up, *axis)?))
        }
        Resolved::ChildOf { parents } => {
            let v = scalar(rig, o, c, ConstraintProperty::Parent, time, overrides);
            let (target, offset) = &parents[parent_index(v, parents.len())?];
            Some(frame_of(target)? * *offset * *world)
        }
        Resolved::FollowPath { points, space, axis } => {
            let space = match space {
                Some(t) => frame_of(t)?,
                None => Affine3A::IDENTITY,
            };
            let offset = scalar(rig, o, c, ConstraintProperty::Offset, time, overrides);
            let (p, d) = path_point(points, offset)?;
            let placed = with_translation(world, space.transform_point3(p));
            match (axis, d) {
                (Some(axis), Some(d)) => {
                    let turned = aim_axis_rotation(space.transform_vector3(d), Vec3::Y, *axis);
                    Some(turned.map_or(placed, |r| with_rotation(&placed, r)))
                }
                _ => Some(placed),
            }
        }
    }
}
