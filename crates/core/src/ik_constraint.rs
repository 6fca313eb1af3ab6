//! IK constraints (issue 19): a [`crate::IkConstraint`] of a scene skeleton solved on a local
//! pose, after forward kinematics, and blended with it. The scene evaluator (keyrig-eval) runs
//! [`ConstraintChain::solve`] every frame; baking writes its result as rotation keys.
//!
//! # One solve
//! With `q_j` the keyed (FK) rotations of the chain's joints, the chain is handed to
//! [`ik::solve_two_bone`] (2 bones) or [`ik::solve_fabrik`] (more), starting from the FK pose,
//! with the target in the object's space; the solved rotations `q'_j` are blended per joint:
//!
//! ```text
//! q_j ← slerp(q_j, q'_j, w)      w = clamp(blend, 0, 1);  w = 0 leaves the pose untouched
//! ```
//!
//! The end joint keeps its own rotation. Without a pole the chain bends the way its FK pose bends
//! (the sum of the inner joints' offsets from the root→end line), or towards its root joint's
//! +Y, +Z or +X when the FK chain is straight (the first at least 30° off the chain), as the
//! editor's IK posing does.

use glam::{Affine3A, Quat, Vec3};

use crate::ik::{self, FabrikSettings, IkChain, IkError, IkReport, Pole};
use crate::scene::{IkConstraint, Skeleton};

/// A chain whose inner joints are closer to the root→end line than this fraction of its length
/// counts as straight: it shows no bend side.
const STRAIGHT_RATIO: f32 = 1e-4;

/// Why a constraint's chain cannot be built from a skeleton, or cannot be solved on a pose.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum ConstraintError {
    #[error("end joint {end} is outside the skeleton ({joints} joints)")]
    EndOutOfRange { end: usize, joints: usize },
    #[error("an IK constraint needs a chain of at least 2 bones; this one has {bones}")]
    TooFewBones { bones: usize },
    #[error("a chain of {bones} bones is too long: joint {end} ({name:?}) has {above} joint(s) above it")]
    ChainTooLong { bones: usize, end: usize, name: String, above: usize },
    #[error("joint {joint} ({name:?}) sits on its parent: a zero-length bone has no direction to aim")]
    ZeroLengthBone { joint: usize, name: String },
    #[error("joint {joint} has a non-uniform scale; IK chains take uniform joint scales only")]
    NonUniformScale { joint: usize },
    #[error("the pose does not fit the skeleton ({found} joints for {expected})")]
    PoseMismatch { expected: usize, found: usize },
    #[error("{0}")]
    Solve(#[from] IkError),
}

/// The local pose of a skeleton (the T(j) parts of docs/design.md §4, one entry per joint) that a
/// constraint is solved on; its rotations are written.
#[derive(Debug)]
pub struct LocalPose<'a> {
    pub translations: &'a [Vec3],
    pub rotations: &'a mut [Quat],
    pub scales: &'a [Vec3],
    pub root_translation: Vec3,
}

/// A constraint's chain, taken from the skeleton's rest data once: the chain's joints (root
/// first, end last) and the joints above the chain's root, whose pose places the chain.
#[derive(Clone, Debug, PartialEq)]
pub struct ConstraintChain {
    /// Skeleton indices of the chain's joints, root first, end joint last.
    pub joints: Vec<usize>,
    /// Skeleton indices of the joints above the chain's root, the skeleton's root first.
    ancestors: Vec<usize>,
    /// Rest translation and rotation (R(j)) of every joint of the skeleton.
    rest: Vec<(Vec3, Quat)>,
}

impl ConstraintChain {
    /// The chain of `constraint` in `skeleton`: `constraint.bones` bones up from
    /// `constraint.end`. Refuses a bad end joint, fewer than 2 bones, a chain longer than the
    /// joints above the end, and a chain with a zero-length bone at rest.
    pub fn new(skeleton: &Skeleton, constraint: &IkConstraint) -> Result<Self, ConstraintError> {
        let joints = skeleton.joints.len();
        let end = constraint.end;
        if end >= joints {
            return Err(ConstraintError::EndOutOfRange { end, joints });
        }
        if constraint.bones < 2 {
            return Err(ConstraintError::TooFewBones { bones: constraint.bones });
        }
        let mut above = Vec::new();
        let mut j = end;
        while let Some(p) = skeleton.joints[j].parent {
            // Parents come before their children in a valid skeleton; stop on anything else.
            if p >= j || above.len() > joints {
                return Err(ik::IkError::NotAChain { root: p, end }.into());
            }
            above.push(p);
            j = p;
        }
        if above.len() < constraint.bones {
            return Err(ConstraintError::ChainTooLong {
                bones: constraint.bones,
                end,
                name: skeleton.joints[end].name.clone(),
                above: above.len(),
            });
        }
        let root = above[constraint.bones - 1];
        let chain = ik::chain_joints(skeleton, root, end)?;
        let mut ancestors: Vec<usize> = above[constraint.bones..].to_vec();
        ancestors.reverse();
        let rest: Vec<(Vec3, Quat)> =
            skeleton.joints.iter().map(|j| (j.rest_translation, j.rest_rotation)).collect();
        let lengths: Vec<f32> = chain[1..].iter().map(|&j| rest[j].0.length()).collect();
        let longest = lengths.iter().copied().fold(0.0, f32::max);
        for (i, &length) in lengths.iter().enumerate() {
            if length.is_nan() || length <= longest * ik::MIN_BONE_LENGTH_RATIO as f32 {
                let joint = chain[i + 1];
                return Err(ConstraintError::ZeroLengthBone {
                    joint,
                    name: skeleton.joints[joint].name.clone(),
                });
            }
        }
        Ok(ConstraintChain { joints: chain, ancestors, rest })
    }

    /// Number of bones.
    #[must_use]
    pub fn bones(&self) -> usize {
        self.joints.len() - 1
    }

    /// The joints a solve turns: every joint of the chain but the end.
    #[must_use]
    pub fn turned_joints(&self) -> &[usize] {
        &self.joints[..self.bones()]
    }

    /// Solves the chain on `pose` for `target` (object space), bending towards `pole` (object
    /// space; `None`: the FK pose's bend), and blends the result into `pose.rotations` by
    /// `blend` (clamped to [0, 1]; NaN counts as 0). Returns the solver's report, `None` when
    /// the blend is 0 and nothing was solved. On an error the pose is left as it was.
    pub fn solve(
        &self,
        pose: &mut LocalPose<'_>,
        target: Vec3,
        pole: Option<Vec3>,
        blend: f32,
    ) -> Result<Option<IkReport>, ConstraintError> {
        let n = self.rest.len();
        for found in [pose.translations.len(), pose.rotations.len(), pose.scales.len()] {
            if found != n {
                return Err(ConstraintError::PoseMismatch { expected: n, found });
            }
        }
        let w = if blend > 0.0 { blend.min(1.0) } else { 0.0 };
        if w == 0.0 {
            return Ok(None);
        }
        let unit = |q: Quat| if q.is_finite() && q.length_squared() > 1e-12 { q.normalize() } else { q };
        // The object from the chain root's parent: the root translation, then R(a)·T(a) of
        // every joint above the chain.
        let mut object_from_parent = Affine3A::from_translation(pose.root_translation);
        for &a in &self.ancestors {
            let (t, r) = self.rest[a];
            object_from_parent = object_from_parent
                * Affine3A::from_rotation_translation(r, t)
                * Affine3A::from_scale_rotation_translation(
                    pose.scales[a],
                    unit(pose.rotations[a]),
                    pose.translations[a],
                );
        }
        // Each chain joint's origin in its parent's frame, the chain joints' (uniform) scales
        // above it folded in.
        let mut translations = Vec::with_capacity(self.joints.len());
        let mut scale = 1.0;
        for (i, &j) in self.joints.iter().enumerate() {
            let (t, r) = self.rest[j];
            translations.push((t + r * pose.translations[j]) * scale);
            if i < self.bones() {
                let s = pose.scales[j];
                let uniform = (s.max_element() - s.min_element()).abs() <= 1e-6 * s.abs().max_element();
                if !uniform {
                    return Err(ConstraintError::NonUniformScale { joint: j });
                }
                scale *= s.x;
            }
        }
        let rest_rotations: Vec<Quat> = self.joints.iter().map(|&j| self.rest[j].1).collect();
        let fk: Vec<Quat> = self.joints.iter().map(|&j| unit(pose.rotations[j])).collect();
        let chain = IkChain {
            world_from_parent: object_from_parent,
            translations: &translations,
            rest_rotations: &rest_rotations,
            rotations: &fk,
        };
        let pole = match pole {
            Some(point) => Pole::Point(point),
            None => Pole::Swivel { angle: 0.0, reference: fk_bend(&chain) },
        };
        let mut out = vec![Quat::IDENTITY; self.joints.len()];
        let report = if self.bones() == 2 {
            ik::solve_two_bone(&chain, target, pole, &mut out)?
        } else {
            ik::solve_fabrik(&chain, target, Some(pole), &FabrikSettings::default(), &mut out)?
        };
        for (i, &j) in self.turned_joints().iter().enumerate() {
            pose.rotations[j] = if w >= 1.0 { out[i] } else { slerp(fk[i], out[i], w) };
        }
        Ok(Some(report))
    }
}

/// `slerp(a, b, w)` the short way, in f64 and by the relative rotation's angle from `atan2`:
/// glam's f32 slerp takes that angle from an approximate `acos` of the dot product, which is off
/// by a good part of it for angles below ~1e-3 rad.
fn slerp(a: Quat, b: Quat, w: f32) -> Quat {
    let (a, b) = (a.as_dquat(), b.as_dquat());
    let mut d = a.conjugate() * b;
    if d.w < 0.0 {
        d = -d;
    }
    let xyz = glam::DVec3::new(d.x, d.y, d.z);
    let sin_half = xyz.length();
    if sin_half == 0.0 {
        return a.as_quat();
    }
    let angle = 2.0 * sin_half.atan2(d.w);
    (a * glam::DQuat::from_axis_angle(xyz / sin_half, angle * f64::from(w))).normalize().as_quat()
}

/// The side the chain bends to in its FK pose (target space, unit): the sum of the inner
/// joints' offsets from the root→end line; for a straight chain its root joint's +Y, +Z or +X,
/// the first at least 30° off the chain.
fn fk_bend(chain: &IkChain<'_>) -> Vec3 {
    let mut p = vec![chain.translations[0]];
    let mut w = Quat::IDENTITY;
    for ((rest, rotation), offset) in
        chain.rest_rotations.iter().zip(chain.rotations).zip(&chain.translations[1..])
    {
        w = (w * *rest * *rotation).normalize();
        let next = p[p.len() - 1] + w * *offset;
        p.push(next);
    }
    let p: Vec<Vec3> = p.into_iter().map(|x| chain.world_from_parent.transform_point3(x)).collect();
    let n = p.len() - 1;
    let axis = (p[n] - p[0]).try_normalize().unwrap_or(Vec3::X);
    let reject = |v: Vec3| v - axis * v.dot(axis);
    let length: f32 = p.windows(2).map(|w| w[0].distance(w[1])).sum();
    let bend: Vec3 = p[1..n].iter().map(|q| reject(*q - p[0])).sum();
    if bend.length() > STRAIGHT_RATIO * length {
        return bend.normalize();
    }
    let root_frame = chain.rest_rotations[0] * chain.rotations[0];
    [Vec3::Y, Vec3::Z, Vec3::X]
        .into_iter()
        .filter_map(|a| chain.world_from_parent.transform_vector3(root_frame * a).try_normalize())
        .find(|v| reject(*v).length() > 0.5)
        .unwrap_or_else(|| axis.any_orthonormal_vector())
}
