//! IK posing (issue 19, part 1): the animator selects the end joint of a chain (a hand), turns
//! on IK posing (Shift+I) and drags the handle drawn at that joint; the chain from a root some
//! bones up follows the pointer. This module builds the chain's solver inputs from the
//! evaluated pose ([`PosedChain`]), keeps IK posing's part of the session ([`IkPosing`]: the
//! chain length per end joint and the pole of each chain's last drag) and runs one drag
//! ([`IkDrag`]); the viewport's handle (`panels::viewport::ik_handle`) feeds it pointer positions
//! and the app applies the solved rotations as gizmo rotations are applied
//! ([`crate::app::EditorApp::apply_ik_pose`]).
//!
//! # Solvers
//! Two bones (the default: the end joint's parent and grandparent, shoulder–elbow–wrist) are
//! solved by [`ik::solve_two_bone`], longer chains by [`ik::solve_fabrik`]; both return new local
//! rotations T(j) that keep each joint's twist about its bone (docs/ik.md). The end joint keeps
//! its own rotation, so the hand turns with the forearm (as a Maya IK handle without an orient
//! constraint).
//!
//! # The pole
//! The bend side is fixed for a whole drag, as a direction: the chain's bend at the press (the
//! sum of the inner joints' offsets from the root→end line, [`PosedChain::bend`]), used as a
//! [`Pole::Swivel`] reference with angle 0 — Maya's rotate-plane pole vector, which defaults to
//! the chain's initial bend. So a drag never flips the elbow when the target crosses the chain's
//! plane or passes out of reach and back. The direction is stored, in the frame of the chain
//! root's parent, when the drag ends; a chain that is straight at the next press (it ended a
//! drag out of reach, or was keyed straight) bends the way it bent before. A chain with neither
//! a bend nor a stored pole bends towards its root joint's local +Y (keyrig's bones run along
//! +X and bend about −Z, which moves the middle joint towards +Y), or +Z, or +X: the first of
//! them that is at least 30° off the chain.

use std::collections::HashMap;

use glam::{Affine3A, Quat, Vec3};
use keyrig_core::ik::{self, FabrikSettings, IkChain, IkError, IkReport, Pole};
use keyrig_core::Scene;

use crate::eval::ObjectPose;
use keyrig_edit::channels::ChannelId;

/// Bones of an IK chain unless the animator chooses another length: two, the analytic solver's
/// shoulder–elbow–wrist.
pub const DEFAULT_CHAIN_BONES: usize = 2;

/// A chain whose inner joints are closer to the root→end line than this fraction of the chain's
/// length counts as straight: it shows no bend side (f32 noise on a straight arm is ~1e-7).
const STRAIGHT_RATIO: f32 = 1e-4;

/// Why a joint cannot be posed with IK. The solver's own refusals ([`IkError`]) come with the
/// chain they were found in.
#[derive(Clone, Debug, PartialEq, thiserror::Error)]
pub enum IkPoseError {
    #[error("IK posing: object {object} does not exist")]
    NoObject { object: usize },
    #[error("IK posing: {object} has no skeleton")]
    NoSkeleton { object: String },
    #[error("IK posing: the pose of {object} could not be evaluated")]
    NoPose { object: String },
    #[error("IK posing: joint {joint} has a non-uniform scale; IK chains take uniform joint scales only")]
    NonUniformScale { joint: String },
    #[error("IK on {end}: {source}")]
    Chain { end: String, source: IkError },
    #[error("IK chain {chain}: {source}")]
    Solve { chain: String, source: IkError },
}

/// IK posing's part of the session: whether it is on, the chain length chosen for each end
/// joint, and the pole of each chain's last drag. Not saved, not undone.
#[derive(Clone, Debug, Default)]
pub struct IkPosing {
    /// The viewport shows the IK handle at a selected joint instead of the rotation gizmo.
    pub enabled: bool,
    /// Bones of the chain per end joint (object, joint); [`DEFAULT_CHAIN_BONES`] otherwise.
    chain_bones: HashMap<(usize, usize), usize>,
    /// The pole of the last drag of each chain (object, root joint, end joint): a unit
    /// direction in the frame of the root joint's parent.
    poles: HashMap<(usize, usize, usize), Vec3>,
}

impl IkPosing {
    /// Bones of the chain that ends at `joint` of `object`.
    #[must_use]
    pub fn chain_bones(&self, object: usize, joint: usize) -> usize {
        self.chain_bones.get(&(object, joint)).copied().unwrap_or(DEFAULT_CHAIN_BONES)
    }

    /// Chooses the length of the chain that ends at `joint` of `object`.
    pub fn set_chain_bones(&mut self, object: usize, joint: usize, bones: usize) {
        self.chain_bones.insert((object, joint), bones);
    }

    /// The stored pole of `chain` (a unit direction in its root's parent frame), if it was dragged.
    #[must_use]
    pub fn pole(&self, chain: &PosedChain) -> Option<Vec3> {
        self.poles.get(&chain.key()).copied()
    }

    /// Remembers the pole a drag of `chain` used, given in world space.
    pub fn remember_pole(&mut self, chain: &PosedChain, world_pole: Vec3) {
        if let Some(local) = chain.world_from_parent.inverse().transform_vector3(world_pole).try_normalize() {
            self.poles.insert(chain.key(), local);
        }
    }

    /// The same settings for another document: on or off, nothing about its joints.
    #[must_use]
    pub fn for_new_document(&self) -> Self {
        IkPosing { enabled: self.enabled, ..IkPosing::default() }
    }

    /// Forgets what it keeps per joint (after objects were removed, indices shift).
    pub fn forget_joints(&mut self) {
        self.chain_bones.clear();
        self.poles.clear();
    }
}

/// An IK chain of a posed skeleton, root first: what [`IkChain`] borrows, taken from the
/// scene's rest skeleton and the evaluated pose (keys, pose overrides) at one time. Targets and
/// poles are in world space. Built only for chains the solvers accept.
#[derive(Clone, Debug)]
pub struct PosedChain {
    pub object: usize,
    /// Skeleton indices of the chain's joints, root first, end joint last.
    pub joints: Vec<usize>,
    /// Their names.
    pub names: Vec<String>,
    /// World from the frame of the root joint's parent (the object's transform and the
    /// skeleton's root translation for a skeleton's root joint).
    pub world_from_parent: Affine3A,
    /// Each joint's origin in its parent's frame (the parent's uniform scale folded in).
    pub translations: Vec<Vec3>,
    /// R(j)'s rotation of each joint.
    pub rest_rotations: Vec<Quat>,
    /// T(j)'s rotation of each joint now.
    pub rotations: Vec<Quat>,
}

impl PosedChain {
    /// The chain of `bones` bones that ends at joint `end` of `object` (fewer when the skeleton's
    /// root comes first), from the object's evaluated `pose`. Refuses a chain the solvers
    /// would refuse (too short, a zero-length bone, a broken rotation) with their message.
    pub fn new(
        scene: &Scene,
        pose: &ObjectPose,
        object: usize,
        end: usize,
        bones: usize,
    ) -> Result<Self, IkPoseError> {
        let item = scene.objects.get(object).ok_or(IkPoseError::NoObject { object })?;
        let skeleton =
            item.skeleton.as_ref().ok_or_else(|| IkPoseError::NoSkeleton { object: item.name.clone() })?;
        let joint_name =
            |j: usize| skeleton.joints.get(j).map_or_else(|| format!("#{j}"), |x| x.name.clone());
        let chain_error = |source| IkPoseError::Chain { end: joint_name(end), source };
        // `bones` parents up, stopping at the skeleton's root (or a parent index that is not
        // before its child, which `chain_joints` refuses).
        let mut root = end;
        for _ in 0..bones {
            match skeleton.joints.get(root).and_then(|j| j.parent) {
                Some(p) if p < root => root = p,
                Some(p) => {
                    root = p;
                    break;
                }
                None => break,
            }
        }
        let joints = ik::chain_joints(skeleton, root, end).map_err(chain_error)?;
        let n = skeleton.joints.len();
        if pose.object_from_joint.len() != n || pose.pose.len() != n {
            return Err(IkPoseError::NoPose { object: item.name.clone() });
        }
        let world_from_parent = match skeleton.joints[root].parent {
            Some(p) => pose.world_from_object * pose.object_from_joint[p],
            None => pose.world_from_object * Affine3A::from_translation(pose.pose.root_translation),
        };
        let mut translations = Vec::with_capacity(joints.len());
        for (i, &j) in joints.iter().enumerate() {
            let joint = &skeleton.joints[j];
            let mut origin = joint.rest_translation + joint.rest_rotation * pose.pose.local_translations[j];
            if i > 0 {
                let parent = joints[i - 1];
                let s = pose.pose.local_scales[parent];
                let uniform = (s.max_element() - s.min_element()).abs() <= 1e-6 * s.abs().max_element();
                if !uniform {
                    return Err(IkPoseError::NonUniformScale { joint: joint_name(parent) });
                }
                origin *= s.x;
            }
            translations.push(origin);
        }
        let chain = PosedChain {
            object,
            names: joints.iter().map(|&j| joint_name(j)).collect(),
            rest_rotations: joints.iter().map(|&j| skeleton.joints[j].rest_rotation).collect(),
            rotations: joints.iter().map(|&j| pose.pose.local_rotations[j]).collect(),
            joints,
            world_from_parent,
            translations,
        };
        // The solvers check every input before they solve: one pass towards where the end is.
        let mut out = vec![Quat::IDENTITY; chain.joints.len()];
        let settings = FabrikSettings { max_iterations: 1, ..FabrikSettings::default() };
        let here = chain.positions().last().copied().unwrap_or(Vec3::ZERO);
        ik::solve_fabrik(&chain.as_ik(&chain.rotations), here, None, &settings, &mut out)
            .map_err(|source| chain.solve_error(source))?;
        Ok(chain)
    }

    /// The borrowed solver input, starting from `rotations` (one per joint).
    #[must_use]
    pub fn as_ik<'a>(&'a self, rotations: &'a [Quat]) -> IkChain<'a> {
        IkChain {
            world_from_parent: self.world_from_parent,
            translations: &self.translations,
            rest_rotations: &self.rest_rotations,
            rotations,
        }
    }

    /// Number of bones.
    #[must_use]
    pub fn bones(&self) -> usize {
        self.joints.len() - 1
    }

    /// The joints from root to end, "elbow → forearm → wrist".
    #[must_use]
    pub fn describe(&self) -> String {
        self.names.join(" → ")
    }

    /// Which solver drags it.
    #[must_use]
    pub fn solver_label(&self) -> &'static str {
        if self.bones() == 2 {
            "two-bone solver"
        } else {
            "FABRIK"
        }
    }

    /// The rotation channels a drag sets: every joint but the end, whose rotation is its own.
    #[must_use]
    pub fn turned_channels(&self) -> Vec<ChannelId> {
        let object = self.object;
        self.joints[..self.bones()].iter().map(|&joint| ChannelId::JointRotation { object, joint }).collect()
    }

    fn key(&self) -> (usize, usize, usize) {
        (self.object, self.joints[0], self.joints[self.bones()])
    }

    fn solve_error(&self, source: IkError) -> IkPoseError {
        IkPoseError::Solve { chain: self.describe(), source }
    }

    /// World positions of the joints with the chain's own rotations.
    #[must_use]
    pub fn positions(&self) -> Vec<Vec3> {
        self.positions_with(&self.rotations)
    }

    /// World positions of the joints with `rotations` (T(j), one per joint): p₀ = o₀,
    /// W_i = W_{i−1}·r_i·q_i, p_{i+1} = p_i + W_i·o_{i+1} (docs/ik.md), mapped to world.
    #[must_use]
    pub fn positions_with(&self, rotations: &[Quat]) -> Vec<Vec3> {
        let mut out = Vec::with_capacity(self.joints.len());
        let mut p = self.translations[0];
        let mut w = Quat::IDENTITY;
        out.push(self.world_from_parent.transform_point3(p));
        let bones = self.rest_rotations.iter().zip(rotations).zip(&self.translations[1..]);
        for ((rest, rotation), offset) in bones {
            w = (w * *rest * *rotation).normalize();
            p += w * *offset;
            out.push(self.world_from_parent.transform_point3(p));
        }
        out
    }

    /// The side the chain bends to, world space: the sum of the inner joints' offsets from the
    /// root→end line, unit; `None` for a chain that is straight (or folded onto that line).
    #[must_use]
    pub fn bend(&self) -> Option<Vec3> {
        let p = self.positions();
        let n = self.bones();
        let axis = (p[n] - p[0]).try_normalize()?;
        let length: f32 = p.windows(2).map(|w| w[0].distance(w[1])).sum();
        let bend: Vec3 = p[1..n].iter().map(|q| reject(*q - p[0], axis)).sum();
        (bend.length() > STRAIGHT_RATIO * length).then(|| bend.normalize())
    }

    /// The pole for a drag starting now, world space: the chain's bend, else the pole stored
    /// from its last drag, else the root joint's +Y, +Z or +X (the first at least 30° off the
    /// chain). Always perpendicular enough to the chain to tell a side.
    #[must_use]
    pub fn pole_for_drag(&self, stored: Option<Vec3>) -> Vec3 {
        let p = self.positions();
        let axis = (p[self.bones()] - p[0]).try_normalize().unwrap_or(Vec3::X);
        let off_axis = |v: Vec3| v.try_normalize().filter(|v| reject(*v, axis).length() > 0.5);
        let stored = stored.and_then(|local| off_axis(self.world_from_parent.transform_vector3(local)));
        let root_frame = self.rest_rotations[0] * self.rotations[0];
        self.bend()
            .or(stored)
            .or_else(|| {
                [Vec3::Y, Vec3::Z, Vec3::X]
                    .into_iter()
                    .find_map(|a| off_axis(self.world_from_parent.transform_vector3(root_frame * a)))
            })
            .unwrap_or_else(|| axis.any_orthonormal_vector())
    }

    /// Solves the chain for `target` (world) starting from `rotations`, the bend towards
    /// `pole` (a world direction): the two-bone solver for two bones, FABRIK for more.
    pub fn solve(
        &self,
        rotations: &[Quat],
        target: Vec3,
        pole: Vec3,
        out: &mut [Quat],
    ) -> Result<IkReport, IkPoseError> {
        let chain = self.as_ik(rotations);
        let pole = Pole::Swivel { angle: 0.0, reference: pole };
        let solved = if self.bones() == 2 {
            ik::solve_two_bone(&chain, target, pole, out)
        } else {
            ik::solve_fabrik(&chain, target, Some(pole), &FabrikSettings::default(), out)
        };
        solved.map_err(|source| self.solve_error(source))
    }
}

/// `v` without its part along the unit vector `axis`.
fn reject(v: Vec3, axis: Vec3) -> Vec3 {
    v - axis * v.dot(axis)
}

/// What a press on the IK handle grabbed, until the button is released.
#[derive(Clone, Debug)]
pub enum IkGrab {
    /// A drag of a valid chain.
    Dragging(Box<IkDrag>),
    /// The chain was refused (the status bar says why): the press still belongs to the handle,
    /// so the camera does not orbit.
    Refused,
}

/// One drag of an IK handle: the chain as it was at the press, the plane the handle moves in
/// (through the end joint, facing the camera), the grip (where on the handle it was pressed)
/// and the pole, fixed for the drag.
#[derive(Clone, Debug)]
pub struct IkDrag {
    pub chain: PosedChain,
    /// A point of the plane the handle moves in: the end joint at the press.
    pub plane_point: Vec3,
    /// The plane's normal: the camera's view direction at the press.
    pub plane_normal: Vec3,
    /// From the pointer's point on the plane to the end joint at the press: the handle keeps
    /// its grip instead of jumping to the pointer.
    grip: Vec3,
    /// The bend side for the whole drag, world space.
    pub pole: Vec3,
    /// The rotations of the last solve (the chain's own before the first).
    solved: Vec<Quat>,
    /// The target of the last solve and how it went.
    pub last: Option<(Vec3, IkReport)>,
}

impl IkDrag {
    /// A drag of `chain` pressed at `pressed_at` (the pointer's point on the plane through the
    /// end joint with the normal `view_direction`), bending towards `pole` (world).
    #[must_use]
    pub fn new(chain: PosedChain, pressed_at: Vec3, view_direction: Vec3, pole: Vec3) -> Self {
        let end = chain.positions().last().copied().unwrap_or(pressed_at);
        let solved = chain.rotations.clone();
        IkDrag {
            chain,
            plane_point: end,
            plane_normal: view_direction,
            grip: end - pressed_at,
            pole,
            solved,
            last: None,
        }
    }

    /// The target for the pointer at `on_plane` (its point on the drag's plane).
    #[must_use]
    pub fn target_for(&self, on_plane: Vec3) -> Vec3 {
        on_plane + self.grip
    }

    /// Solves for `target` and returns the new rotation of each joint the drag turns (all but
    /// the end), or `None` when the target is the last one solved. Two bones are solved from
    /// the pose at the press, so the drag's result depends only on where the pointer is; FABRIK
    /// starts from the last solve, as it is meant to (docs/ik.md).
    pub fn drag_to(&mut self, target: Vec3) -> Result<Option<Vec<(ChannelId, Quat)>>, IkPoseError> {
        if self.last.is_some_and(|(t, _)| t == target) {
            return Ok(None);
        }
        let from = if self.chain.bones() == 2 { &self.chain.rotations } else { &self.solved };
        let mut out = vec![Quat::IDENTITY; self.chain.joints.len()];
        let report = self.chain.solve(from, target, self.pole, &mut out)?;
        self.solved = out;
        self.last = Some((target, report));
        Ok(Some(self.chain.turned_channels().into_iter().zip(self.solved.iter().copied()).collect()))
    }

    /// World positions of the chain's joints as last solved (as at the press before the first
    /// solve).
    #[must_use]
    pub fn solved_positions(&self) -> Vec<Vec3> {
        self.chain.positions_with(&self.solved)
    }

    /// Whether the drag has solved anything yet.
    #[must_use]
    pub fn moved(&self) -> bool {
        self.last.is_some()
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use keyrig_core::{Animated, Joint, Object, Skeleton};

    /// A three-bone arm along +X (0.4 each) bent 90° at the elbow about −Z, placed at `at`.
    fn arm_scene(at: Vec3) -> Scene {
        let bone = Vec3::new(0.4, 0.0, 0.0);
        let mut joints = vec![
            Joint::new("shoulder", None, Vec3::ZERO, Quat::IDENTITY),
            Joint::new("elbow", Some(0), bone, Quat::IDENTITY),
            Joint::new("forearm", Some(1), bone, Quat::IDENTITY),
            Joint::new("wrist", Some(2), bone, Quat::IDENTITY),
        ];
        joints[1].rotation = Animated::constant(Quat::from_rotation_z(-std::f32::consts::FRAC_PI_2));
        let mut object = Object::new("Arm");
        object.translation = Animated::constant(at);
        object.skeleton = Some(Skeleton::new(joints));
        Scene { objects: vec![object], ..Scene::default() }
    }

    fn pose_of(scene: &Scene) -> ObjectPose {
        let eval = keyrig_eval::SceneEvaluator::new(scene, &HashMap::new());
        ObjectPose::from_state(&eval.object_at(0, 0.0, &keyrig_eval::Overrides::default()).expect("the arm"))
    }

    fn world_of(pose: &ObjectPose, j: usize) -> Vec3 {
        (pose.world_from_object * pose.object_from_joint[j]).translation.into()
    }

    #[test]
    fn the_chain_is_placed_where_the_evaluator_puts_the_joints() {
        let scene = arm_scene(Vec3::new(-0.8, 1.0, 0.3));
        let pose = pose_of(&scene);
        let chain = PosedChain::new(&scene, &pose, 0, 3, 3).expect("a valid chain");
        assert_eq!(chain.describe(), "shoulder → elbow → forearm → wrist");
        assert_eq!(chain.solver_label(), "FABRIK");
        for (i, p) in chain.positions().iter().enumerate() {
            assert!(p.distance(world_of(&pose, i)) < 1e-6, "joint {i}: {p:?} vs {:?}", world_of(&pose, i));
        }
        let two = PosedChain::new(&scene, &pose, 0, 3, 2).expect("a valid chain");
        assert_eq!(two.joints, vec![1, 2, 3]);
        assert_eq!(two.turned_channels().len(), 2);
        assert!(two.bend().is_none(), "elbow → forearm → wrist is straight");
        let bend = chain.bend().expect("the arm bends at the elbow");
        // Shoulder (0,0), elbow (0.4,0), wrist (0.4,−0.8): the elbow is off the line towards +X+Y.
        let expected = Vec3::new(2.0, 1.0, 0.0).normalize();
        assert!(bend.distance(expected) < 1e-5, "{bend:?}");
    }

    #[test]
    fn a_chain_longer_than_the_skeleton_stops_at_its_root_and_one_too_short_is_refused() {
        let scene = arm_scene(Vec3::ZERO);
        let pose = pose_of(&scene);
        let chain = PosedChain::new(&scene, &pose, 0, 3, 9).expect("up to the root");
        assert_eq!(chain.joints, vec![0, 1, 2, 3]);
        let err = PosedChain::new(&scene, &pose, 0, 1, 2).expect_err("the elbow has one joint above it");
        assert_eq!(
            err.to_string(),
            "IK on elbow: an IK chain needs at least 2 bones (3 joints); this one has 2 joint(s)"
        );
    }

    #[test]
    fn a_zero_length_bone_is_refused_with_the_solvers_message() {
        let mut scene = arm_scene(Vec3::ZERO);
        scene.objects[0].skeleton.as_mut().expect("a skeleton").joints[2].rest_translation = Vec3::ZERO;
        let pose = pose_of(&scene);
        let err = PosedChain::new(&scene, &pose, 0, 3, 2).expect_err("forearm sits on the elbow");
        assert_eq!(
            err.to_string(),
            "IK chain elbow → forearm → wrist: IK chain joint 1 sits on its parent joint 0: a zero-length \
             bone has no direction to aim"
        );
    }

    /// A drag reaches its target, keeps the bend side of the press (the pole), and a drag whose
    /// target runs out of reach and back bends the same way again.
    #[test]
    fn a_drag_follows_the_target_on_the_bend_side_of_the_press() {
        let scene = arm_scene(Vec3::new(0.2, 1.0, 0.0));
        let pose = pose_of(&scene);
        let chain = PosedChain::new(&scene, &pose, 0, 3, 3).expect("a valid chain");
        let start = chain.positions();
        let pole = chain.pole_for_drag(None);
        let mut drag = IkDrag::new(chain.clone(), start[3], Vec3::NEG_Z, pole);
        for target in [start[3] + Vec3::new(0.1, 0.2, 0.0), start[0] + Vec3::new(2.0, 0.0, 0.0), start[3]] {
            let turned = drag.drag_to(target).expect("solves").expect("a new target");
            let rotations: Vec<Quat> =
                turned.iter().map(|(_, q)| *q).chain(std::iter::once(chain.rotations[3])).collect();
            let p = chain.positions_with(&rotations);
            let reach = 1.2;
            if target.distance(start[0]) < reach {
                assert!(p[3].distance(target) < 1e-5, "{:?} vs {target:?}", p[3]);
                let axis = (p[3] - p[0]).normalize();
                let bend: Vec3 = p[1..3].iter().map(|q| reject(*q - p[0], axis)).sum();
                assert!(bend.dot(pole) > 0.0, "bends towards the pole: {bend:?}, pole {pole:?}");
            }
        }
        assert!(drag.drag_to(start[3]).expect("solves").is_none(), "the same target solves nothing");
    }
}
