//! Object constraints beyond IK (docs/constraints.md): aim at, child of (with keyed switching
//! of the parent), copy location, copy rotation and follow path, each blended into the
//! object's world transform by a keyed influence.
//!
//! This module holds the data (serde, in the scene file as `Object::constraints`) and the pure
//! formulas; the scene evaluator (keyrig-eval) resolves targets, evaluates them first and
//! applies an object's constraints in order after its own keyed transform.
//!
//! ```text
//! W₀ = T·R·S of the object's own channels
//! Wᵢ = blend(Wᵢ₋₁, Cᵢ(Wᵢ₋₁), wᵢ)        Cᵢ: constraint i's result, wᵢ = clamp(influence, 0, 1)
//! blend(A, B, w) = T(lerp(t_A, t_B, w)) · R(slerp(r_A, r_B, w)) · S(lerp(s_A, s_B, w))
//! ```

use glam::{Affine3A, Mat3, Mat4, Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::camera_object::AimTarget;
use crate::key::Animated;

/// One constraint of an object.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ObjectConstraint {
    /// Unique among the object's constraints; used in channel paths
    /// (`object/<o>/constraint/<name>/influence`).
    pub name: String,
    pub kind: ConstraintKind,
    /// Keyed influence in [0, 1]: 0 leaves the transform as it comes in, 1 takes the
    /// constraint's result.
    #[serde(default = "full")]
    pub influence: Animated<f32>,
}

fn full() -> Animated<f32> {
    Animated::constant(1.0)
}

fn y_up() -> Vec3 {
    Vec3::Y
}

/// What a constraint does.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum ConstraintKind {
    /// Turns the object so that its local `axis` points at the target, its local up axis
    /// ([`AimAxis::up`]) as close to the world direction `up` as that allows.
    AimAt {
        target: AimTarget,
        #[serde(default)]
        axis: AimAxis,
        #[serde(default = "y_up")]
        up: Vec3,
    },
    /// Puts the object's origin on the target's world position.
    CopyLocation { target: AimTarget },
    /// Gives the object the target's world rotation (a point target has none: the identity).
    CopyRotation { target: AimTarget },
    /// Carries the object with one of `parents`, chosen by the keyed `parent` channel (Step
    /// keys; the value rounded to the nearest whole number indexes `parents`, anything outside
    /// the list is no parent). Each parent has the offset taken when it was switched to, so
    /// the object does not jump at a switch.
    ChildOf {
        #[serde(default)]
        parents: Vec<ChildOfParent>,
        #[serde(default = "no_parent")]
        parent: Animated<f32>,
    },
    /// Puts the object at a fraction `offset` ∈ [0, 1] of the length of a polyline through
    /// `points` (in the space of the object `space`, or world space), turning its `axis` along
    /// the path when one is given.
    FollowPath {
        points: Vec<Vec3>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        space: Option<String>,
        #[serde(default = "start_of_path")]
        offset: Animated<f32>,
        #[serde(default, skip_serializing_if = "Option::is_none")]
        axis: Option<AimAxis>,
    },
}

fn start_of_path() -> Animated<f32> {
    Animated::constant(0.0)
}

fn no_parent() -> Animated<f32> {
    Animated::constant(-1.0)
}

/// One parent of a child-of constraint.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct ChildOfParent {
    pub target: AimTarget,
    /// Applied between the parent's frame and the incoming transform: the result is
    /// `frame(target) · offset · W` (Blender's Child Of inverse matrix, Maya's parent-constraint
    /// offset). Column-major; the identity when left out.
    #[serde(default = "identity", skip_serializing_if = "is_identity")]
    pub offset: Mat4,
}

fn identity() -> Mat4 {
    Mat4::IDENTITY
}

fn is_identity(m: &Mat4) -> bool {
    *m == Mat4::IDENTITY
}

impl ChildOfParent {
    /// A parent with no offset.
    #[must_use]
    pub fn new(target: AimTarget) -> Self {
        ChildOfParent { target, offset: Mat4::IDENTITY }
    }
}

/// A local axis of an object.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum AimAxis {
    PosX,
    NegX,
    PosY,
    NegY,
    PosZ,
    /// −Z, as a camera looks (the default).
    #[default]
    NegZ,
}

impl AimAxis {
    pub const ALL: [AimAxis; 6] =
        [AimAxis::PosX, AimAxis::NegX, AimAxis::PosY, AimAxis::NegY, AimAxis::PosZ, AimAxis::NegZ];

    /// The axis as a unit vector.
    #[must_use]
    pub fn vector(self) -> Vec3 {
        match self {
            AimAxis::PosX => Vec3::X,
            AimAxis::NegX => Vec3::NEG_X,
            AimAxis::PosY => Vec3::Y,
            AimAxis::NegY => Vec3::NEG_Y,
            AimAxis::PosZ => Vec3::Z,
            AimAxis::NegZ => Vec3::NEG_Z,
        }
    }

    /// The local axis kept as close to the world up as aiming allows: +Z when aiming along
    /// ±Y, else +Y.
    #[must_use]
    pub fn up(self) -> Vec3 {
        match self {
            AimAxis::PosY | AimAxis::NegY => Vec3::Z,
            _ => Vec3::Y,
        }
    }

    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            AimAxis::PosX => "+X",
            AimAxis::NegX => "−X",
            AimAxis::PosY => "+Y",
            AimAxis::NegY => "−Y",
            AimAxis::PosZ => "+Z",
            AimAxis::NegZ => "−Z",
        }
    }
}

impl ConstraintKind {
    /// The kind's name shown in the editor.
    #[must_use]
    pub fn label(&self) -> &'static str {
        match self {
            ConstraintKind::AimAt { .. } => "Aim at",
            ConstraintKind::CopyLocation { .. } => "Copy location",
            ConstraintKind::CopyRotation { .. } => "Copy rotation",
            ConstraintKind::ChildOf { .. } => "Child of",
            ConstraintKind::FollowPath { .. } => "Follow path",
        }
    }

    /// Every target the constraint reads (a follow path's space as an object target).
    #[must_use]
    pub fn targets(&self) -> Vec<AimTarget> {
        match self {
            ConstraintKind::AimAt { target, .. }
            | ConstraintKind::CopyLocation { target }
            | ConstraintKind::CopyRotation { target } => vec![target.clone()],
            ConstraintKind::ChildOf { parents, .. } => parents.iter().map(|p| p.target.clone()).collect(),
            ConstraintKind::FollowPath { space, .. } => {
                space.iter().map(|s| AimTarget::Object(s.clone())).collect()
            }
        }
    }
}

impl ObjectConstraint {
    /// A constraint at full influence.
    #[must_use]
    pub fn new(name: impl Into<String>, kind: ConstraintKind) -> Self {
        ObjectConstraint { name: name.into(), kind, influence: full() }
    }
}

/// The world rotation that turns local `axis` onto the direction `forward`, with local
/// `axis.up()` as close to world `up` as possible:
///
/// ```text
/// f = forward/|forward|   r = (f × up)/|f × up|   u = r × f
/// R = [f, u, f × u] · [a, a_up, a × a_up]ᵀ        a = axis, a_up = axis.up()
/// ```
///
/// When `up` is along `forward`, the world axis least aligned with `forward` stands in for it
/// (as [`crate::camera_object::aim_rotation`]). `None` for a zero or non-finite direction.
#[must_use]
pub fn aim_axis_rotation(forward: Vec3, up: Vec3, axis: AimAxis) -> Option<Quat> {
    let f = forward.try_normalize()?;
    let up = up.try_normalize().unwrap_or(Vec3::Y);
    let mut right = f.cross(up);
    if right.length_squared() < 1e-10 {
        let a = f.abs();
        let fallback = if a.x <= a.y && a.x <= a.z {
            Vec3::X
        } else if a.y <= a.z {
            Vec3::Y
        } else {
            Vec3::Z
        };
        right = f.cross(fallback);
    }
    let right = right.try_normalize()?;
    let u = right.cross(f);
    let world = Mat3::from_cols(f, u, f.cross(u));
    let (a, a_up) = (axis.vector(), axis.up());
    let local = Mat3::from_cols(a, a_up, a.cross(a_up));
    Some(Quat::from_mat3(&(world * local.transpose())).normalize())
}

/// The point at fraction `fraction` (clamped to [0, 1]) of the arc length of the polyline
/// through `points`, with the direction of the segment it lies on (the first segment of
/// non-zero length at or after it, else before it). `None` for no points; one point, or
/// points all in one place, give that point and no direction.
#[must_use]
pub fn path_point(points: &[Vec3], fraction: f32) -> Option<(Vec3, Option<Vec3>)> {
    let first = *points.first()?;
    let lengths: Vec<f32> = points.windows(2).map(|w| w[0].distance(w[1])).collect();
    let total: f32 = lengths.iter().sum();
    if total.is_nan() || total <= 0.0 {
        return Some((first, None));
    }
    let fraction = if fraction.is_nan() { 0.0 } else { fraction.clamp(0.0, 1.0) };
    let mut s = fraction * total;
    let last = lengths.iter().rposition(|&l| l > 0.0).expect("the total is > 0");
    for (i, &l) in lengths.iter().enumerate() {
        if l <= 0.0 {
            continue;
        }
        if s <= l || i == last {
            let along = (s / l).clamp(0.0, 1.0);
            let d = points[i + 1] - points[i];
            return Some((points[i] + d * along, Some(d)));
        }
        s -= l;
    }
    // Not reached (the last segment of non-zero length returns); its end, for rounding.
    Some((points[last + 1], Some(points[last + 1] - points[last])))
}

/// The blend of two transforms: translations and scales interpolated linearly, rotations by
/// slerp (the shorter way), each read from its transform by
/// [`Affine3A::to_scale_rotation_translation`]. `w` is clamped to [0, 1]; 0 gives `a` as it
/// is, 1 gives `b` as it is.
#[must_use]
pub fn blend_transforms(a: &Affine3A, b: &Affine3A, w: f32) -> Affine3A {
    if w.is_nan() || w <= 0.0 {
        return *a;
    }
    if w >= 1.0 {
        return *b;
    }
    let (sa, ra, ta) = a.to_scale_rotation_translation();
    let (sb, rb, tb) = b.to_scale_rotation_translation();
    Affine3A::from_scale_rotation_translation(sa.lerp(sb, w), ra.slerp(rb, w).normalize(), ta.lerp(tb, w))
}

/// `m` with its rotation replaced by `rotation` (its scale and translation kept).
#[must_use]
pub fn with_rotation(m: &Affine3A, rotation: Quat) -> Affine3A {
    let (s, _, t) = m.to_scale_rotation_translation();
    Affine3A::from_scale_rotation_translation(s, rotation, t)
}

/// `m` with its translation replaced by `translation`.
#[must_use]
pub fn with_translation(m: &Affine3A, translation: Vec3) -> Affine3A {
    let mut out = *m;
    out.translation = translation.into();
    out
}

/// The object a target names, by index; `None` for a point or an unknown name.
#[must_use]
pub fn target_object(scene: &crate::Scene, target: &AimTarget) -> Option<usize> {
    let name = match target {
        AimTarget::Object(name) | AimTarget::Joint { object: name, .. } => name,
        AimTarget::Point(_) => return None,
    };
    scene.objects.iter().position(|o| &o.name == name)
}

/// The objects whose transforms object `o`'s constraints read (with repeats).
#[must_use]
pub fn dependencies(scene: &crate::Scene, o: usize) -> Vec<usize> {
    let Some(object) = scene.objects.get(o) else { return Vec::new() };
    object
        .constraints
        .iter()
        .flat_map(|c| c.kind.targets())
        .filter_map(|t| target_object(scene, &t))
        .collect()
}

/// An order to evaluate the scene's objects in so that every constraint's targets come before
/// it, and the objects whose constraints lie on a cycle (an object that, through its targets'
/// constraints, reads itself). Those objects' constraints cannot be evaluated: the order treats
/// them as having none, so every object is in it once. Kahn's algorithm; objects without
/// dependencies keep their scene order.
#[must_use]
pub fn evaluation_order(scene: &crate::Scene) -> (Vec<usize>, Vec<usize>) {
    let n = scene.objects.len();
    let deps: Vec<Vec<usize>> = (0..n).map(|o| dependencies(scene, o)).collect();
    let on_cycle: Vec<usize> = (0..n).filter(|&o| reaches(&deps, o, o)).collect();
    let deps_of = |o: usize| if on_cycle.contains(&o) { &[][..] } else { deps[o].as_slice() };
    let mut order = Vec::with_capacity(n);
    let mut placed = vec![false; n];
    // n passes at most, each placing at least one object (no cycle is left).
    while order.len() < n {
        let before = order.len();
        for o in 0..n {
            if !placed[o] && deps_of(o).iter().all(|&d| placed[d]) {
                placed[o] = true;
                order.push(o);
            }
        }
        if order.len() == before {
            break;
        }
    }
    (order, on_cycle)
}

/// Whether `to` can be reached from `from` through at least one dependency.
fn reaches(deps: &[Vec<usize>], from: usize, to: usize) -> bool {
    let mut seen = vec![false; deps.len()];
    let mut stack: Vec<usize> = deps[from].clone();
    while let Some(o) = stack.pop() {
        if o == to {
            return true;
        }
        if o < deps.len() && !std::mem::replace(&mut seen[o], true) {
            stack.extend(&deps[o]);
        }
    }
    false
}
