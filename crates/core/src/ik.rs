//! Inverse kinematics for joint chains (issue 19): an analytic two-bone solver with a pole, and
//! FABRIK for chains of any length. Pure functions over the data a skeleton already holds; the
//! math is written out in `docs/ik.md`.
//!
//! # The chain
//! An [`IkChain`] is `n + 1` joints, root first and end joint (the hand) last, each the child of
//! the one before; `n ≥ 2` bones join them. Per joint it borrows what `F(j) = F(p(j))·R(j)·T(j)`
//! needs (docs/design.md §4): the joint's origin in its parent's frame, R(j)'s rotation and T(j)'s
//! rotation (the keyed one). With `W_{−1} = I`, the positions and frames in the chain parent's
//! space are
//!
//! ```text
//! p_0 = o_0,   W_i = W_{i−1}·r_i·q_i,   p_{i+1} = p_i + W_i·o_{i+1}
//! ```
//!
//! so bone `i` (joint `i` to joint `i + 1`) has the length `|o_{i+1}|` and its direction is set
//! by the rotations `q_0 … q_i`. The solvers find new positions for the joints and turn each
//! `q_i` by the *smallest* rotation that aims its bone at the new position
//! (`q_i' = swing_i·q_i`), so every joint keeps its twist about its bone's axis. The end joint's
//! own rotation `q_n` is returned unchanged: keeping the hand's world orientation (or not) is the
//! caller's choice.
//!
//! All arithmetic is done in f64; each rotation is rounded to f32 once, and the joints below it
//! are aimed from the rounded rotation, so rounding does not add up along the chain.
//!
//! # Solvers
//! * [`solve_two_bone`]: shoulder–elbow–wrist by the law of cosines; the bend plane holds the
//!   root→target axis and the [`Pole`], so it never flips when the target crosses the chain's
//!   plane (Maya's rotate-plane solver, Blender's IK constraint with a pole).
//! * [`solve_fabrik`]: Forward And Backward Reaching Inverse Kinematics (Aristidou & Lasenby,
//!   "FABRIK: A fast, iterative solver for the Inverse Kinematics problem", Graphical Models
//!   73(5), 2011), with an optional pole (the chain is laid into the pole's plane) and an
//!   exact finish where the passes converge slowly, near the edges of the reach.
//!
//! Unreachable targets give the straight chain pointing at the target. Invalid input is refused
//! with an [`IkError`]; no input panics.

use glam::{Affine3A, DAffine3, DQuat, DVec3, Quat, Vec3};

use crate::scene::Skeleton;

/// A bone shorter than this fraction of the chain's longest bone counts as zero-length: it has
/// no direction to aim (and a direction computed from it would be rounding noise).
pub const MIN_BONE_LENGTH_RATIO: f64 = 1e-6;

/// Rotations (T(j) or R(j)) shorter than this are refused as zero, as track keys are
/// ([`crate::track::MIN_QUATERNION_NORM`]).
const MIN_ROTATION_NORM: f64 = 1e-6;

/// A pole whose distance from the root→target line is below this fraction of the chain's
/// length (or of the pole's distance from the root) cannot tell a bend side: the solver keeps
/// the current one instead.
const POLE_DEGENERATE_RATIO: f64 = 1e-9;

/// Targets this fraction of the chain's length outside its reach still count as reachable
/// ([`IkReport::reachable`]): the f32 inputs place a target no closer than that.
pub const REACH_SLACK: f64 = 1e-6;

/// FABRIK passes stop (and the finish takes over) once a pass shrinks the end's distance to the
/// target by less than this factor: near the edges of the reach each pass gains only about
/// `1 − c·(1 − d/L)` of it.
const STALL_RATIO: f64 = 0.9;

/// How many times the FABRIK finish may try (each try after the first makes one more pass).
const FINISH_TRIES: usize = 16;

/// An IK chain: borrowed per-joint inputs, root first and end joint last (`n + 1` joints for
/// `n` bones; every slice has one entry per joint).
#[derive(Clone, Copy, Debug)]
pub struct IkChain<'a> {
    /// The space of the target and the pole (world or model space: the caller's choice) from
    /// the frame of the root joint's parent: `F(p(root))` of the pose, times the object's
    /// transform for world space. For a skeleton's root joint it is the object's transform
    /// times the skeleton's root translation. It may scale (even non-uniformly), but must be
    /// finite and invertible.
    pub world_from_parent: Affine3A,
    /// Each joint's origin in its parent's frame: `rest_translation + rest_rotation ·
    /// translation` of a scene joint; for the root, in the frame `world_from_parent` maps from.
    /// Joint scales are not modelled: a joint with a uniform scale `s` multiplies the
    /// translations of the chain joints below it by `s` (the caller folds that in).
    pub translations: &'a [Vec3],
    /// R(j)'s rotation (the joint's `rest_rotation`).
    pub rest_rotations: &'a [Quat],
    /// T(j)'s rotation (the joint's keyed `rotation`), the pose the solver starts from and whose
    /// twists it keeps. Need not be normalized (it must not be zero).
    pub rotations: &'a [Quat],
}

/// What decides the bend side (the plane in which the chain bends).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Pole {
    /// A point, in the target's space: the bend plane holds the root→target axis and this
    /// point, and the inner joints bend towards it (Maya's pole vector, Blender's pole target).
    Point(Vec3),
    /// A swivel angle (radians) about the root→target axis, measured from the plane that holds
    /// the axis and `reference` (a direction in the target's space): at angle 0 the middle joint
    /// bends towards `reference`, and a positive angle turns the bend plane right-handedly about
    /// the root→target axis. The angle is measured in the chain parent's frame (the same angle
    /// in the target's space unless `world_from_parent` scales non-uniformly).
    Swivel { angle: f32, reference: Vec3 },
}

/// Bounds of the FABRIK iteration.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FabrikSettings {
    /// At most this many backward-and-forward passes (at least 1).
    pub max_iterations: u32,
    /// Stop when the end joint is this close to the target, as a fraction of the chain's length
    /// (finite, ≥ 0).
    pub tolerance: f64,
}

impl Default for FabrikSettings {
    /// 64 passes, tolerance 1e-7 of the chain's length (a 1.6 m arm: 0.16 µm).
    fn default() -> Self {
        FabrikSettings { max_iterations: 64, tolerance: 1e-7 }
    }
}

/// How a solve went.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct IkReport {
    /// The target is within the chain's reach (between its shortest and longest reach from
    /// the root). When it is not, the chain points at it (straight when it is too far).
    pub reachable: bool,
    /// Distance from the end joint of the solved chain (rotations as returned, in f32) to the
    /// target, in the target's space.
    pub distance: f64,
    /// FABRIK passes made, the finish's included (0 for the analytic solver, for targets out of
    /// reach and at its edges).
    pub iterations: u32,
}

/// Why an IK chain cannot be solved.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum IkError {
    #[error("an IK chain needs at least 2 bones (3 joints); this one has {joints} joint(s)")]
    ChainTooShort { joints: usize },
    #[error("the two-bone IK solver takes exactly 2 bones (3 joints); this chain has {joints} joint(s)")]
    NotTwoBones { joints: usize },
    #[error("IK chain inputs differ in length: {what} has {found} entries for a chain of {expected} joints")]
    LengthMismatch { what: &'static str, expected: usize, found: usize },
    #[error(
        "IK chain joint {joint} sits on its parent joint {}: a zero-length bone has no direction to aim",
        joint.saturating_sub(1)
    )]
    ZeroLengthBone { joint: usize },
    #[error("IK target is not finite: {target}")]
    NonFiniteTarget { target: Vec3 },
    #[error("IK pole is not finite: {pole}")]
    NonFinitePole { pole: Vec3 },
    #[error("IK pole swivel angle is not finite: {angle}")]
    NonFiniteSwivel { angle: f32 },
    #[error("IK pole reference direction is zero: it cannot tell a bend side")]
    ZeroPoleReference,
    #[error("translation of IK chain joint {joint} is not finite")]
    NonFiniteTranslation { joint: usize },
    #[error("{what} of IK chain joint {joint} is not a finite, non-zero quaternion")]
    BadRotation { what: &'static str, joint: usize },
    #[error("the IK chain's parent transform is not finite and invertible")]
    BadParentTransform,
    #[error("FABRIK settings: {0}")]
    BadSettings(&'static str),
    #[error("joint {joint} is outside the skeleton ({joints} joints)")]
    JointOutOfRange { joint: usize, joints: usize },
    #[error("joint {end} is not below joint {root} in the skeleton: they do not make an IK chain")]
    NotAChain { root: usize, end: usize },
}

/// The skeleton indices of the chain from `root` down to `end` (both included, root first):
/// the joints whose entries an [`IkChain`] takes, in its order.
pub fn chain_joints(skeleton: &Skeleton, root: usize, end: usize) -> Result<Vec<usize>, IkError> {
    let joints = skeleton.joints.len();
    for joint in [root, end] {
        if joint >= joints {
            return Err(IkError::JointOutOfRange { joint, joints });
        }
    }
    let mut chain = vec![end];
    let mut j = end;
    while j != root {
        // Parents come before their children in a valid skeleton; the bound also stops a
        // cycle in an invalid one.
        match skeleton.joints[j].parent {
            Some(p) if p < joints && chain.len() <= joints => {
                chain.push(p);
                j = p;
            }
            _ => return Err(IkError::NotAChain { root, end }),
        }
    }
    chain.reverse();
    if chain.len() < 3 {
        return Err(IkError::ChainTooShort { joints: chain.len() });
    }
    Ok(chain)
}

/// The chain's inputs, checked and widened to f64.
struct Checked {
    world_from_parent: DAffine3,
    parent_from_world: DAffine3,
    target: DVec3,
}

fn check(chain: &IkChain<'_>, target: Vec3, pole: Option<Pole>, out_len: usize) -> Result<Checked, IkError> {
    let joints = chain.translations.len();
    for (what, found) in [
        ("rest_rotations", chain.rest_rotations.len()),
        ("rotations", chain.rotations.len()),
        ("the output", out_len),
    ] {
        if found != joints {
            return Err(IkError::LengthMismatch { what, expected: joints, found });
        }
    }
    if joints < 3 {
        return Err(IkError::ChainTooShort { joints });
    }
    for (joint, t) in chain.translations.iter().enumerate() {
        if !t.is_finite() {
            return Err(IkError::NonFiniteTranslation { joint });
        }
    }
    let longest = chain.translations[1..].iter().map(|t| t.as_dvec3().length()).fold(0.0, f64::max);
    for (joint, t) in chain.translations.iter().enumerate().skip(1) {
        if t.as_dvec3().length() <= MIN_BONE_LENGTH_RATIO * longest {
            return Err(IkError::ZeroLengthBone { joint });
        }
    }
    // The end joint's rotations are not used, but a broken one is still a broken input.
    for (what, rotations) in [("rest rotation", chain.rest_rotations), ("rotation", chain.rotations)] {
        for (joint, q) in rotations.iter().enumerate() {
            let norm = q.as_dquat().length();
            if !(norm.is_finite() && norm >= MIN_ROTATION_NORM) {
                return Err(IkError::BadRotation { what, joint });
            }
        }
    }
    if !target.is_finite() {
        return Err(IkError::NonFiniteTarget { target });
    }
    match pole {
        Some(Pole::Point(p)) if !p.is_finite() => return Err(IkError::NonFinitePole { pole: p }),
        Some(Pole::Swivel { angle, .. }) if !angle.is_finite() => {
            return Err(IkError::NonFiniteSwivel { angle })
        }
        Some(Pole::Swivel { reference, .. }) if !reference.is_finite() => {
            return Err(IkError::NonFinitePole { pole: reference })
        }
        Some(Pole::Swivel { reference, .. }) if reference == Vec3::ZERO => {
            return Err(IkError::ZeroPoleReference)
        }
        _ => {}
    }
    let world_from_parent = chain.world_from_parent.as_daffine3();
    let det = world_from_parent.matrix3.determinant();
    if !(world_from_parent.is_finite() && det.is_finite() && det.abs() > f64::from(f32::MIN_POSITIVE)) {
        return Err(IkError::BadParentTransform);
    }
    let parent_from_world = world_from_parent.inverse();
    if !parent_from_world.is_finite() {
        return Err(IkError::BadParentTransform);
    }
    Ok(Checked {
        world_from_parent,
        parent_from_world,
        target: parent_from_world.transform_point3(target.as_dvec3()),
    })
}

/// Unit quaternion in f64 (checked non-zero and finite by [`check`]).
#[inline]
fn unit(q: Quat) -> DQuat {
    q.as_dquat().normalize()
}

/// Joint positions of the chain's current pose, in the parent's frame.
fn forward_positions(chain: &IkChain<'_>, positions: &mut [DVec3]) {
    let mut frame = DQuat::IDENTITY;
    let mut p = chain.translations[0].as_dvec3();
    positions[0] = p;
    for i in 0..chain.translations.len() - 1 {
        frame = frame * unit(chain.rest_rotations[i]) * unit(chain.rotations[i]);
        p += frame * chain.translations[i + 1].as_dvec3();
        positions[i + 1] = p;
    }
}

/// `v` without its component along the unit vector `axis`.
#[inline]
fn reject(v: DVec3, axis: DVec3) -> DVec3 {
    v - axis * v.dot(axis)
}

/// The pole's bend direction for a chain bending about the unit axis `u` from `root`: a unit
/// vector perpendicular to `u`, or `None` when the pole lies on the axis (no side to tell).
fn pole_direction(pole: Pole, checked: &Checked, root: DVec3, u: DVec3, reach: f64) -> Option<DVec3> {
    let (w, angle) = match pole {
        Pole::Point(p) => (checked.parent_from_world.transform_point3(p.as_dvec3()) - root, 0.0),
        Pole::Swivel { angle, reference } => {
            (checked.parent_from_world.transform_vector3(reference.as_dvec3()), f64::from(angle))
        }
    };
    let perp = reject(w, u);
    let len = perp.length();
    if len <= POLE_DEGENERATE_RATIO * reach.max(w.length()) {
        return None;
    }
    let v = perp / len;
    if angle == 0.0 {
        return Some(v);
    }
    let (sin, cos) = angle.sin_cos();
    Some(v * cos + u.cross(v) * sin)
}

/// Turns each joint's rotation by the smallest rotation that aims its bone from where the
/// (already re-aimed) chain puts the joint towards `solved[i + 1]`, writes the rotations to
/// `out` (the end joint's unchanged) and returns the end joint's position in the parent's
/// frame.
fn aim(chain: &IkChain<'_>, solved: &[DVec3], out: &mut [Quat]) -> DVec3 {
    let n = chain.translations.len() - 1;
    let mut parent = DQuat::IDENTITY;
    let mut p = chain.translations[0].as_dvec3();
    for i in 0..n {
        let frame = parent * unit(chain.rest_rotations[i]);
        let q = unit(chain.rotations[i]);
        let offset = chain.translations[i + 1].as_dvec3();
        // The bone as the joint's current rotation points it, and where it should point, both in
        // the joint's frame before its own rotation.
        let current = (q * offset).normalize();
        let wanted = frame.inverse() * (solved[i + 1] - p);
        let turned = match wanted.try_normalize() {
            Some(wanted) => DQuat::from_rotation_arc(current, wanted) * q,
            None => q,
        };
        // Round once; the joints below are aimed from the rounded rotation.
        let rounded = turned.normalize().as_quat();
        out[i] = rounded;
        parent = frame * unit(rounded);
        p += parent * offset;
    }
    out[n] = chain.rotations[n];
    p
}

fn report(checked: &Checked, end: DVec3, reachable: bool, iterations: u32) -> IkReport {
    let world_end = checked.world_from_parent.transform_point3(end);
    let world_target = checked.world_from_parent.transform_point3(checked.target);
    IkReport { reachable, distance: world_end.distance(world_target), iterations }
}

/// Solves a two-bone chain (3 joints: root, middle, end) analytically so that its end joint
/// reaches `target` (in the space `world_from_parent` maps to), bending in the plane the
/// `pole` decides, and writes the new T(j) rotations of the 3 joints to `out` (the end joint's
/// unchanged).
///
/// With `a` the root, `d = |target − a|` clamped to the reach `[|l₁ − l₂|, l₁ + l₂]`,
/// `u` the unit root→target axis and `v` the unit bend direction (the pole's component
/// perpendicular to `u`), the law of cosines places the middle joint at
/// `a + x·u + h·v` with `x = (l₁² − l₂² + d²)/(2d)` and `h = √(l₁² − x²)`, and the end joint at
/// `a + d·u`. Beyond the reach the chain is straight and points at the target; inside the
/// shortest reach it folds back along the axis. Where the pole lies on the root→target line
/// the chain keeps the side its middle joint is on now.
pub fn solve_two_bone(
    chain: &IkChain<'_>,
    target: Vec3,
    pole: Pole,
    out: &mut [Quat],
) -> Result<IkReport, IkError> {
    let checked = check(chain, target, Some(pole), out.len())?;
    let joints = chain.translations.len();
    if joints != 3 {
        return Err(IkError::NotTwoBones { joints });
    }
    let mut current = [DVec3::ZERO; 3];
    forward_positions(chain, &mut current);
    let a = current[0];
    let l1 = chain.translations[1].as_dvec3().length();
    let l2 = chain.translations[2].as_dvec3().length();
    let reach = l1 + l2;
    let shortest = (l1 - l2).abs();

    let to_target = checked.target - a;
    let d = to_target.length();
    // The root→target axis; with the target on the root, the current root→end axis (or, for a
    // chain folded onto itself, the upper bone).
    let u = to_target
        .try_normalize()
        .filter(|_| d > POLE_DEGENERATE_RATIO * reach)
        .or_else(|| (current[2] - a).try_normalize().filter(|_| (current[2] - a).length() > 1e-9 * reach))
        .unwrap_or_else(|| (current[1] - a).normalize());
    let v = pole_direction(pole, &checked, a, u, reach)
        .or_else(|| {
            let elbow = reject(current[1] - a, u);
            (elbow.length() > POLE_DEGENERATE_RATIO * reach).then(|| elbow.normalize())
        })
        .unwrap_or_else(|| u.any_orthonormal_vector());

    let reachable = d >= shortest - REACH_SLACK * reach && d <= reach * (1.0 + REACH_SLACK);
    let dc = d.clamp(shortest, reach);
    let x = if dc > 0.0 { ((l1 * l1 - l2 * l2 + dc * dc) / (2.0 * dc)).clamp(-l1, l1) } else { 0.0 };
    // l₁² − x² as a product: accurate near full extension, where x → l₁.
    let h = ((l1 - x) * (l1 + x)).max(0.0).sqrt();
    let solved = [a, a + u * x + v * h, a + u * dc];
    let end = aim(chain, &solved, out);
    Ok(report(&checked, end, reachable, 0))
}

/// Solves a chain of any length (at least 2 bones) by FABRIK so that its end joint reaches
/// `target`, starting from the chain's current pose, and writes the new T(j) rotations to `out`
/// (the end joint's unchanged).
///
/// Each pass sets the end joint on the target and walks back to the root keeping every bone's
/// length (backward), then puts the root back and walks out again (forward):
/// `p_i ← p_{i+1} + l_i·(p_i − p_{i+1})/|p_i − p_{i+1}|`, then
/// `p_{i+1} ← p_i + l_i·(p_{i+1} − p_i)/|p_{i+1} − p_i|`. It stops when the end joint is within
/// `settings.tolerance × chain length` of the target, after `settings.max_iterations` passes, or
/// once a pass gains less than 10 % of the distance.
///
/// FABRIK converges slowly where the chain must be nearly straight or nearly folded; when the
/// passes stop short of the tolerance, an exact finish closes the gap: a chain too curled to
/// reach is unbent (every bend between consecutive bones scaled by one factor `s ∈ [0, 1]`,
/// found by regula falsi) and turned about the root onto the target; a chain reaching too far
/// is folded at two joints (law of cosines, the sub-chains between them kept rigid). A target
/// beyond the chain's length gives the straight chain pointing at it, and one at (or inside) its
/// shortest reach the flat fold (the longest bone towards the target, the others straight
/// back), both without passes.
///
/// With a pole, the chain is first laid into the pole's plane (the plane through the root that
/// holds the root→target axis and the pole): turned about that axis so that its bend (the sum
/// of the inner joints' offsets from the axis) points at the pole, then flattened onto the
/// plane. The passes and the finish keep it in that plane, so it bends towards the pole like the
/// two-bone solver and does not drift into a helix while it is dragged; if it ends bowed away
/// from the pole it is mirrored across the root→end axis (which keeps every bone's length).
///
/// Without a pole the chain bends as its current pose leans; a chain that is exactly straight
/// along the root→target line has no lean, so give a pole for it.
pub fn solve_fabrik(
    chain: &IkChain<'_>,
    target: Vec3,
    pole: Option<Pole>,
    settings: &FabrikSettings,
    out: &mut [Quat],
) -> Result<IkReport, IkError> {
    let checked = check(chain, target, pole, out.len())?;
    if settings.max_iterations == 0 {
        return Err(IkError::BadSettings("max_iterations must be at least 1"));
    }
    if !(settings.tolerance.is_finite() && settings.tolerance >= 0.0) {
        return Err(IkError::BadSettings("tolerance must be a finite number ≥ 0"));
    }
    let joints = chain.translations.len();
    let n = joints - 1;
    let mut p = vec![DVec3::ZERO; joints];
    forward_positions(chain, &mut p);
    let lengths: Vec<f64> = chain.translations[1..].iter().map(|t| t.as_dvec3().length()).collect();
    let reach: f64 = lengths.iter().sum();
    let longest = lengths.iter().copied().fold(0.0, f64::max);
    let shortest = (2.0 * longest - reach).max(0.0);

    let root = p[0];
    let t = checked.target;
    let d = (t - root).length();
    let u = (t - root).try_normalize().filter(|_| d > POLE_DEGENERATE_RATIO * reach);
    let reachable = d >= shortest - REACH_SLACK * reach && d <= reach * (1.0 + REACH_SLACK);
    let mut iterations = 0;
    if d >= reach {
        // Unreachable (or just reachable): the straight chain pointing at the target.
        let u = u.unwrap_or(DVec3::X);
        for i in 0..n {
            p[i + 1] = p[i] + u * lengths[i];
        }
    } else if shortest > 0.0 && d <= shortest + REACH_SLACK * reach {
        // At (or inside) the shortest reach there is one pose: the longest bone points at the
        // target and every other bone straight back.
        let u = u.unwrap_or(DVec3::X);
        let longest_bone = lengths.iter().position(|l| *l == longest).unwrap_or(0);
        for i in 0..n {
            let sign = if i == longest_bone { 1.0 } else { -1.0 };
            p[i + 1] = p[i] + u * (sign * lengths[i]);
        }
    } else {
        // With a pole, FABRIK works in the pole's plane: all points and the target lie in it, so
        // the passes and the finish keep the chain there.
        let plane = match (pole, u) {
            (Some(pole), Some(u)) => pole_direction(pole, &checked, root, u, reach).map(|v| (u, v)),
            _ => None,
        };
        let fallback = u.unwrap_or(DVec3::X);
        let pass = |p: &mut [DVec3]| {
            p[n] = t;
            for i in (0..n).rev() {
                let dir = (p[i] - p[i + 1]).try_normalize().unwrap_or(-fallback);
                p[i] = p[i + 1] + dir * lengths[i];
            }
            p[0] = root;
            for i in 0..n {
                let dir = (p[i + 1] - p[i]).try_normalize().unwrap_or(fallback);
                p[i + 1] = p[i] + dir * lengths[i];
            }
        };
        let tolerance = settings.tolerance * reach;
        let flattened = plane.is_some_and(|(u, v)| flatten_to_plane(&mut p, u, v, reach) > tolerance);
        let mut gap = p[n].distance(t);
        while (gap > tolerance || (flattened && iterations == 0)) && iterations < settings.max_iterations {
            pass(&mut p);
            iterations += 1;
            let last = gap;
            gap = p[n].distance(t);
            // Converging slowly (near the edges of the reach): leave the rest to the finish.
            if iterations > 1 && gap > STALL_RATIO * last {
                break;
            }
        }
        // The finish. A fold changes two joints only, and near the shortest reach, where the
        // chain must fold flat, one may not be enough: then one more pass and another fold, a
        // few times.
        for tries in 0..FINISH_TRIES {
            if p[n].distance(t) <= tolerance {
                break;
            }
            if tries > 0 {
                pass(&mut p);
                iterations += 1;
            }
            if (p[n] - root).length() < d {
                unbend(&mut p, &lengths, d);
                turn_about_root(&mut p, t);
            } else {
                fold_two_joints(&mut p, t);
            }
        }
        if let Some((_, v)) = plane {
            mirror_to_pole_side(&mut p, v);
        }
    }
    let end = aim(chain, &p, out);
    Ok(report(&checked, end, reachable, iterations))
}

/// Mirrors the chain across the plane through its root→end axis that is perpendicular to the
/// pole's plane when its bend (the sum of the inner joints' offsets from that axis) points away
/// from the pole's side `v`. A mirror keeps every bone's length, the root and the end; FABRIK can
/// leave a chain that must bend little bowed the wrong way.
fn mirror_to_pole_side(p: &mut [DVec3], v: DVec3) {
    let root = p[0];
    let n = p.len() - 1;
    let Some(axis) = (p[n] - root).try_normalize() else { return };
    let Some(side) = reject(v, axis).try_normalize() else { return };
    let bend: f64 = p[1..n].iter().map(|q| (*q - root).dot(side)).sum();
    if bend < 0.0 {
        for q in &mut p[1..n] {
            *q -= side * (2.0 * (*q - root).dot(side));
        }
    }
}

/// Rotates the chain rigidly about its root, by the smallest rotation, so that its end lies on
/// the ray from the root through `t`.
fn turn_about_root(p: &mut [DVec3], t: DVec3) {
    let root = p[0];
    let n = p.len() - 1;
    if let (Some(from), Some(to)) = ((p[n] - root).try_normalize(), (t - root).try_normalize()) {
        let turn = DQuat::from_rotation_arc(from, to);
        for q in &mut p[1..] {
            *q = root + turn * (*q - root);
        }
    }
}

/// Lays the chain into the pole's plane (through the root, spanned by the root→target axis
/// `u` and the unit bend direction `v ⟂ u`): the whole chain is turned about `u` so that its
/// bend (the sum of the inner joints' offsets from `u`) points along `v`, then each joint is
/// projected onto the plane. Bone lengths change only where the chain was not flat (the FABRIK
/// passes restore them); a chain already in the plane, bent towards `v`, does not move. A chain
/// lying straight along the axis is bowed a little (1e-3 of its length) towards `v` so that the
/// passes can bend it. Returns how far the joints moved, at most.
fn flatten_to_plane(p: &mut [DVec3], u: DVec3, v: DVec3, reach: f64) -> f64 {
    let root = p[0];
    let n = p.len() - 1;
    let before = p.to_vec();
    let bend: DVec3 = p[1..n].iter().map(|q| reject(*q - root, u)).sum();
    if bend.length() > POLE_DEGENERATE_RATIO * reach {
        let bend = bend.normalize();
        let angle = u.dot(bend.cross(v)).atan2(bend.dot(v));
        let turn = DQuat::from_axis_angle(u, angle);
        for q in &mut p[1..] {
            *q = root + turn * (*q - root);
        }
    }
    let normal = u.cross(v);
    let mut straight = true;
    for q in &mut p[1..] {
        *q -= normal * (*q - root).dot(normal);
        straight &= reject(*q - root, u).length() <= POLE_DEGENERATE_RATIO * reach;
    }
    if straight {
        for q in &mut p[1..n] {
            *q += v * (1e-3 * reach);
        }
    }
    p.iter().zip(&before).map(|(a, b)| a.distance(*b)).fold(0.0, f64::max)
}

/// Unbends a chain whose end is closer to the root than `d`: every bend between consecutive
/// bones is scaled by one factor `s ∈ [0, 1]` (`s = 0` is the straight chain, `s = 1` the
/// chain as it is) with `s` chosen so that the end is `d` from the root (regula falsi, Illinois
/// variant). The chain's direction is left for [`turn_about_root`].
fn unbend(p: &mut [DVec3], lengths: &[f64], d: f64) {
    let n = lengths.len();
    let root = p[0];
    let dir = |i: usize| (p[i + 1] - p[i]).try_normalize().unwrap_or(DVec3::X);
    let first = dir(0);
    // Each bend as an axis and an angle: dir(i) = rotate(axis_i, angle_i)·dir(i − 1).
    let mut bends = Vec::with_capacity(n - 1);
    let mut previous = first;
    for i in 1..n {
        let next = dir(i);
        let cross = previous.cross(next);
        let sin = cross.length();
        let angle = sin.atan2(previous.dot(next));
        let axis = if sin > 0.0 { cross / sin } else { previous.any_orthonormal_vector() };
        bends.push((axis, angle));
        previous = next;
    }
    let shape = |s: f64, p: Option<&mut [DVec3]>| -> f64 {
        let mut e = first;
        let mut sum = e * lengths[0];
        let mut out = p;
        if let Some(p) = out.as_deref_mut() {
            p[1] = root + sum;
        }
        for (i, (axis, angle)) in bends.iter().enumerate() {
            let (sin, cos) = (s * angle).sin_cos();
            // Rodrigues: v·cos θ + (k × v)·sin θ + k·(k·v)·(1 − cos θ).
            e = (e * cos + axis.cross(e) * sin + *axis * axis.dot(e) * (1.0 - cos)).normalize();
            sum += e * lengths[i + 1];
            if let Some(p) = out.as_deref_mut() {
                p[i + 2] = root + sum;
            }
        }
        sum.length() - d
    };
    let reach: f64 = lengths.iter().sum();
    let (mut lo, mut hi) = (0.0, 1.0);
    let (mut f_lo, mut f_hi) = (shape(lo, None), shape(hi, None));
    if !(f_lo >= 0.0 && f_hi <= 0.0) {
        return;
    }
    let mut s = hi;
    // Regula falsi with the Illinois fix: converges superlinearly; 60 steps bound it.
    let mut side = 0;
    for _ in 0..60 {
        s = (lo * f_hi - hi * f_lo) / (f_hi - f_lo);
        if !s.is_finite() {
            s = 0.5 * (lo + hi);
        }
        let f = shape(s, None);
        if f.abs() <= 1e-14 * reach {
            break;
        }
        if f > 0.0 {
            (lo, f_lo) = (s, f);
            if side == 1 {
                f_hi *= 0.5;
            }
            side = 1;
        } else {
            (hi, f_hi) = (s, f);
            if side == -1 {
                f_lo *= 0.5;
            }
            side = -1;
        }
    }
    shape(s, Some(p));
}

/// Puts the end of a chain that reaches too far on `t` by turning two sub-chains: joints
/// `m₁ < m₂ < end` split the chain into root…m₁ (kept), m₁…m₂ and m₂…end (each kept rigid),
/// and the triangle m₁, m₂, `t` with sides `b = |p_{m₂} − p_{m₁}|`, `c = |p_end − p_{m₂}|` and
/// `e = |t − p_{m₁}|` places m₂ by the law of cosines, on the side it is on now. The pair with
/// the most room, `min(b + c − e, e − |b − c|)`, is used; where even that is negative (a target
/// inside the chain's shortest reach) the triangle is clamped flat and the end comes as close
/// as it can. (`m₁` may be the root; one hinge cannot fold a chain back onto its root, two can.)
fn fold_two_joints(p: &mut [DVec3], t: DVec3) {
    let n = p.len() - 1;
    let mut best: Option<(usize, usize, f64)> = None;
    for m1 in 0..n - 1 {
        let e = (t - p[m1]).length();
        for m2 in m1 + 1..n {
            let (b, c) = ((p[m2] - p[m1]).length(), (p[n] - p[m2]).length());
            let room = (b + c - e).min(e - (b - c).abs());
            if best.is_none_or(|(_, _, r)| room > r) {
                best = Some((m1, m2, room));
            }
        }
    }
    let Some((m1, m2, _)) = best else { return };
    let (pivot, old_middle) = (p[m1], p[m2]);
    let (b, c) = ((old_middle - pivot).length(), (p[n] - old_middle).length());
    let Some(axis) = (t - pivot).try_normalize() else { return };
    let e = (t - pivot).length();
    let v = reject(old_middle - pivot, axis)
        .try_normalize()
        .or_else(|| reject(p[n] - pivot, axis).try_normalize())
        .unwrap_or_else(|| axis.any_orthonormal_vector());
    let x = ((b * b - c * c + e * e) / (2.0 * e)).clamp(-b, b);
    let h = ((b - x) * (b + x)).max(0.0).sqrt();
    let middle = pivot + axis * x + v * h;
    let (Some(from_b), Some(to_b), Some(from_c), Some(to_c)) = (
        (old_middle - pivot).try_normalize(),
        (middle - pivot).try_normalize(),
        (p[n] - old_middle).try_normalize(),
        (t - middle).try_normalize(),
    ) else {
        return;
    };
    let (turn_b, turn_c) = (DQuat::from_rotation_arc(from_b, to_b), DQuat::from_rotation_arc(from_c, to_c));
    for q in &mut p[m2 + 1..] {
        *q = middle + turn_c * (*q - old_middle);
    }
    for q in &mut p[m1 + 1..=m2] {
        *q = pivot + turn_b * (*q - pivot);
    }
}
