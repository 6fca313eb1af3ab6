//! [`SceneEvaluator`]: the validated runtime form of a scene, answering "the scene at time t".

use std::collections::HashMap;
use std::sync::Arc;

use glam::{Affine3A, Quat, Vec3};
use keyrig_core::channel_id::{ChannelId, ChannelValue};
use keyrig_core::ik_constraint::{ConstraintChain, LocalPose};
use keyrig_core::{DeformerKind, DeformerSettings, LightKind, MeshSource, Scene};
use keyrig_skin::{
    mesh_for, BlendZone, JointPalette, MeshBindings, Pose, RestSkeleton, SkinError, SkinnedMesh,
};

use crate::camera::{CameraRig, CameraState, Target};
use crate::clips::{ObjectMix, PoseValues};
use crate::morph::{MorphBlend, MorphClips, MorphError};

mod attributes;
pub(crate) mod constraints;
pub use attributes::ObjectLook;
use attributes::{LightAttributeRig, ObjectAttributeRig};
use constraints::ConstraintRigs;

pub use crate::slot::{EvalProblem, Overrides};
use crate::slot::{RotationSlot, Slot, SlotEval};

/// What a model file gave for an object whose mesh is `MeshSource::File` (keyrig-io loads it;
/// the evaluator reads no files).
#[derive(Clone, Debug)]
pub enum LoadedMesh {
    /// A skinned mesh bound to its skin's skeleton (a glTF skin's inverse bind matrices).
    Skinned(Arc<SkinnedMesh>),
    /// Vertex animation (MD2): its frames and clips.
    Morph(Arc<MorphClips>),
    /// A mesh that neither skins nor morphs.
    Static,
}

/// A skinned mesh with its deformer bindings, shared by everything that draws or deforms it.
#[derive(Clone, Debug)]
pub struct SkinRig {
    pub mesh: Arc<SkinnedMesh>,
    pub bindings: Arc<MeshBindings>,
}

/// What of a vertex-animated mesh plays.
#[derive(Clone, Debug)]
pub struct MorphRig {
    pub clips: Arc<MorphClips>,
    pub clip: Option<String>,
    pub fps: f64,
}

#[derive(Clone, Debug)]
struct JointSlots {
    translation: Slot<Vec3>,
    rotation: RotationSlot,
    scale: Slot<Vec3>,
}

/// An IK constraint: its chain (`None` when the skeleton cannot hold it; the problem is
/// listed), what the chain was built from, its pole and its two channels.
#[derive(Clone, Debug)]
struct ConstraintRig {
    chain: Option<ConstraintChain>,
    end: usize,
    bones: usize,
    pole: Option<Vec3>,
    target: Slot<Vec3>,
    blend: Slot<f32>,
    problem: Option<EvalProblem>,
}

impl ConstraintRig {
    fn new(skeleton: &keyrig_core::Skeleton, o: usize, c: usize) -> Self {
        let constraint = &skeleton.ik_constraints[c];
        let (chain, problem) = match ConstraintChain::new(skeleton, constraint) {
            Ok(chain) => (Some(chain), None),
            Err(e) => (
                None,
                Some(EvalProblem {
                    path: format!("objects[{o}].skeleton.ik_constraints[{c}]"),
                    message: e.to_string(),
                }),
            ),
        };
        ConstraintRig {
            chain,
            end: constraint.end,
            bones: constraint.bones,
            pole: constraint.pole,
            target: Slot::new(&constraint.target, ChannelId::IkTarget { object: o, constraint: c }),
            blend: Slot::new(&constraint.blend, ChannelId::IkBlend { object: o, constraint: c }),
            problem,
        }
    }

    /// Rebuilds what changed (the skeleton's rest data is known to be the same); returns the
    /// number of channels rebuilt.
    fn refresh(&mut self, skeleton: &keyrig_core::Skeleton, o: usize, c: usize) -> usize {
        let constraint = &skeleton.ik_constraints[c];
        if (constraint.end, constraint.bones) != (self.end, self.bones) {
            *self = ConstraintRig::new(skeleton, o, c);
            return 2;
        }
        self.pole = constraint.pole;
        usize::from(self.target.refresh(&constraint.target, ChannelId::IkTarget { object: o, constraint: c }))
            + usize::from(
                self.blend.refresh(&constraint.blend, ChannelId::IkBlend { object: o, constraint: c }),
            )
    }
}

#[derive(Clone, Debug)]
struct SkeletonRig {
    root_translation: Slot<Vec3>,
    joints: Vec<JointSlots>,
    /// IK constraints, solved in order after forward kinematics.
    constraints: Vec<ConstraintRig>,
    /// The skeleton the palette is evaluated on: the skinned mesh's (a glTF file's inverse bind
    /// matrices) or the scene's rest skeleton; `None` when neither is valid.
    rest: Option<RestSkeleton>,
}

#[derive(Clone, Debug)]
struct ObjectRig {
    translation: Slot<Vec3>,
    rotation: RotationSlot,
    scale: Slot<Vec3>,
    skeleton: Option<SkeletonRig>,
    skin: Option<SkinRig>,
    /// The palette of a skinned mesh without a scene skeleton (its rest pose), computed once.
    rest_palette: Option<JointPalette>,
    morph: Option<MorphRig>,
    deformer: DeformerKind,
    /// Visibility, colour, opacity, morph weights, keyed deformer; `None` while all default.
    attributes: Option<Box<ObjectAttributeRig>>,
    /// What the skeleton's rest data, the mesh and its bindings were built from: when an edit
    /// leaves these as they were, they are kept.
    built_from: RestSource,
    /// Problems of the skeleton, the mesh or the clip (channel problems live in the slots).
    problems: Vec<EvalProblem>,
    /// Clip tracks and layers (docs/clips.md); `None` while the object has no tracks and the
    /// scene no layers.
    mix: Option<Box<ObjectMix>>,
}

/// The parts of an object that its rest data, mesh and bindings depend on.
#[derive(Clone, Debug, PartialEq)]
struct RestSource {
    mesh: Option<MeshSource>,
    deformer: DeformerSettings,
    /// Per joint: parent, rest translation, rest rotation; `None` without a skeleton.
    joints: Option<Vec<(Option<usize>, Vec3, Quat)>>,
    /// The loaded mesh, by identity.
    loaded: Option<LoadedKey>,
}

/// A loaded mesh compared by identity (the same shared data), not by contents.
#[derive(Clone, Debug)]
enum LoadedKey {
    Skinned(Arc<SkinnedMesh>),
    Morph(Arc<MorphClips>),
    Static,
}

impl PartialEq for LoadedKey {
    fn eq(&self, other: &Self) -> bool {
        match (self, other) {
            (LoadedKey::Skinned(a), LoadedKey::Skinned(b)) => Arc::ptr_eq(a, b),
            (LoadedKey::Morph(a), LoadedKey::Morph(b)) => Arc::ptr_eq(a, b),
            (LoadedKey::Static, LoadedKey::Static) => true,
            _ => false,
        }
    }
}

impl RestSource {
    fn of(object: &keyrig_core::Object, loaded: Option<&LoadedMesh>) -> Self {
        RestSource {
            mesh: object.mesh.clone(),
            deformer: object.deformer,
            joints: object
                .skeleton
                .as_ref()
                .map(|s| s.joints.iter().map(|j| (j.parent, j.rest_translation, j.rest_rotation)).collect()),
            loaded: loaded.map(|l| match l {
                LoadedMesh::Skinned(m) => LoadedKey::Skinned(Arc::clone(m)),
                LoadedMesh::Morph(c) => LoadedKey::Morph(Arc::clone(c)),
                LoadedMesh::Static => LoadedKey::Static,
            }),
        }
    }
}

/// What [`SceneEvaluator::update`] rebuilt.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Rebuilt {
    /// Channels whose tracks were validated again.
    pub channels: usize,
    /// Objects whose skeleton rest data, mesh and bindings were built again.
    pub meshes: usize,
}

#[derive(Clone, Debug)]
struct LightRig {
    kind: LightKind,
    enabled: bool,
    position: Slot<Vec3>,
    direction: Slot<Vec3>,
    colour: Slot<Vec3>,
    intensity: Slot<f32>,
    attributes: Option<Box<LightAttributeRig>>,
}

/// The state of one object at a time.
#[derive(Clone, Debug)]
pub struct ObjectState {
    /// World from object: T·R·S of the object's channels.
    pub world_from_object: Affine3A,
    /// The skeleton's local joint transforms and root translation (`None` without a skeleton).
    pub pose: Option<Pose>,
    /// The joint palette of the object's skin (its skinned mesh's skeleton, or the scene
    /// skeleton for an object without a mesh); a skinned mesh without a skeleton gets its rest
    /// palette. `F(j)` is `palette.model_from_joint[j]`, composed once per evaluation.
    pub palette: Option<JointPalette>,
    /// Why the pose has no palette (a zero quaternion set as an override, a non-finite value).
    pub palette_error: Option<SkinError>,
    /// The frames a vertex-animated mesh shows.
    pub morph: Option<Result<MorphBlend, MorphError>>,
    /// Visibility, opacity, colour, deformer, morph weights and blend zone at this time.
    pub look: ObjectLook,
    /// Bindings of the skinned mesh for a keyed bones-blending zone (`look.blend_zone`) with
    /// the zone they were built for; `None` while the zone is not keyed (the rig's own
    /// bindings apply) or the mesh's bindings do not depend on it (glTF skins). An evaluation
    /// into a state that holds bindings for the same zone keeps them.
    pub zone_bindings: Option<(BlendZone, Arc<MeshBindings>)>,
}

impl ObjectState {
    /// A state to evaluate into: at the origin, with no pose, palette or morph.
    fn empty() -> Self {
        ObjectState {
            world_from_object: Affine3A::IDENTITY,
            pose: None,
            palette: None,
            palette_error: None,
            morph: None,
            look: ObjectLook::new(DeformerKind::LinearBlend),
            zone_bindings: None,
        }
    }

    /// The bindings to deform object's skin `skin` with at this time: those of the keyed blend
    /// zone, else the skin's own.
    #[must_use]
    pub fn bindings<'a>(&'a self, skin: &'a SkinRig) -> &'a Arc<MeshBindings> {
        self.zone_bindings.as_ref().map_or(&skin.bindings, |(_, b)| b)
    }
}

/// The state of one light at a time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct LightState {
    pub kind: LightKind,
    pub enabled: bool,
    pub position: Vec3,
    /// As keyed (not normalized).
    pub direction: Vec3,
    pub colour: Vec3,
    pub intensity: f32,
    /// False: the light does not light anything at this time.
    pub visible: bool,
    /// Distance beyond which the light has no effect (glTF's smooth range falloff); `None`:
    /// unlimited. A spot's `kind` holds its cone at this time.
    pub range: Option<f32>,
}

/// The scene at one time.
#[derive(Clone, Debug)]
pub struct SceneState {
    pub time: f64,
    pub objects: Vec<ObjectState>,
    pub lights: Vec<LightState>,
    /// The scene cameras, by index.
    pub cameras: Vec<CameraState>,
}

/// The validated runtime form of a [`Scene`]: every channel's track (tangents and Squad
/// controls precomputed), each skeleton's rest data, each skinned mesh with its deformer
/// bindings, each morph mesh's clips. It answers "the scene at time t" —
/// object world transforms, light states, each skeleton's joint palette, morph frames — for the
/// viewport, motion paths, the curve view, `sample`, `deform`, `render` and glTF export alike.
///
/// Building it is lenient: what cannot be evaluated is listed in
/// [`SceneEvaluator::problems`] and evaluates to its static value (or without skinning);
/// strict consumers (the command line) refuse a scene with problems.
#[derive(Clone, Debug)]
pub struct SceneEvaluator {
    fps: f64,
    objects: Vec<ObjectRig>,
    lights: Vec<LightRig>,
    cameras: Vec<CameraRig>,
    /// Object constraints (aim at, child of, copy, follow path) and the order objects are
    /// evaluated in so that targets come first.
    constraints: ConstraintRigs,
    problems: Vec<EvalProblem>,
}

impl SceneEvaluator {
    /// Validates `scene`. `meshes` gives, by object index, what keyrig-io loaded for objects
    /// whose mesh is a model file; procedural meshes are generated here, bound to the object's
    /// skeleton.
    #[must_use]
    pub fn new(scene: &Scene, meshes: &HashMap<usize, LoadedMesh>) -> Self {
        let mut eval = SceneEvaluator {
            fps: scene.fps,
            objects: (0..scene.objects.len()).map(|o| ObjectRig::new(scene, o, meshes.get(&o))).collect(),
            lights: scene.lights.iter().enumerate().map(|(l, light)| LightRig::new(l, light)).collect(),
            cameras: (0..scene.cameras.len()).map(|c| CameraRig::new(scene, c)).collect(),
            constraints: ConstraintRigs::build(scene),
            problems: Vec::new(),
        };
        eval.collect_problems();
        eval
    }

    /// Brings the evaluator in step with `scene` after an edit, rebuilding only what the edit
    /// changed: a channel whose keys are still the list it was built from (keyrig-core's
    /// copy-on-write [`Keys`]) and whose static value is unchanged keeps its validated track;
    /// an object whose mesh source, deformer settings, skeleton rest pose and loaded mesh are
    /// unchanged keeps its mesh and bindings. Returns what was rebuilt.
    pub fn update(&mut self, scene: &Scene, meshes: &HashMap<usize, LoadedMesh>) -> Rebuilt {
        let mut rebuilt = Rebuilt::default();
        self.fps = scene.fps;
        self.objects.truncate(scene.objects.len());
        for o in 0..scene.objects.len() {
            let loaded = meshes.get(&o);
            let object = &scene.objects[o];
            let same_rest =
                self.objects.get(o).is_some_and(|rig| rig.built_from == RestSource::of(object, loaded));
            if same_rest {
                rebuilt.channels += self.objects[o].refresh(scene, o);
            } else {
                let rig = ObjectRig::new(scene, o, loaded);
                rebuilt.channels += rig.channel_count();
                rebuilt.meshes += 1;
                if o < self.objects.len() {
                    self.objects[o] = rig;
                } else {
                    self.objects.push(rig);
                }
            }
        }
        self.lights.truncate(scene.lights.len());
        for (l, light) in scene.lights.iter().enumerate() {
            match self.lights.get_mut(l) {
                Some(rig) => rebuilt.channels += rig.refresh(l, light),
                None => {
                    self.lights.push(LightRig::new(l, light));
                    rebuilt.channels += 4;
                }
            }
        }
        self.cameras.truncate(scene.cameras.len());
        for c in 0..scene.cameras.len() {
            match self.cameras.get_mut(c) {
                Some(rig) => rebuilt.channels += rig.refresh(scene, c),
                None => {
                    let rig = CameraRig::new(scene, c);
                    rebuilt.channels += rig.channel_count();
                    self.cameras.push(rig);
                }
            }
        }
        // Object constraints are few and cheap to build: they are built again (targets
        // resolved by name) on every update.
        self.constraints = ConstraintRigs::build(scene);
        self.collect_problems();
        rebuilt
    }

    fn collect_problems(&mut self) {
        self.problems.clear();
        for rig in &self.objects {
            self.problems.extend(rig.problems.iter().cloned());
            rig.for_each_problem(&mut |p| self.problems.push(p.clone()));
        }
        for rig in &self.lights {
            for p in [&rig.position.problem, &rig.direction.problem, &rig.colour.problem]
                .into_iter()
                .chain([&rig.intensity.problem])
                .flatten()
            {
                self.problems.push(p.clone());
            }
            if let Some(a) = &rig.attributes {
                a.for_each_problem(&mut |p| self.problems.push(p.clone()));
            }
        }
        for rig in &self.cameras {
            rig.for_each_problem(&mut |p| self.problems.push(p.clone()));
        }
        self.constraints.for_each_problem(&mut |p| self.problems.push(p.clone()));
    }

    /// What could not be evaluated, with field paths; empty for a valid scene.
    #[must_use]
    pub fn problems(&self) -> &[EvalProblem] {
        &self.problems
    }

    /// Frames per second of the scene's timeline.
    #[must_use]
    pub fn fps(&self) -> f64 {
        self.fps
    }

    /// The skinned mesh of object `o` with its bindings (procedural meshes and loaded skinned
    /// meshes).
    #[must_use]
    pub fn skin(&self, o: usize) -> Option<&SkinRig> {
        self.objects.get(o)?.skin.as_ref()
    }

    /// What of object `o`'s vertex-animated mesh plays.
    #[must_use]
    pub fn morph(&self, o: usize) -> Option<&MorphRig> {
        self.objects.get(o)?.morph.as_ref()
    }

    /// The deformer object `o` uses.
    #[must_use]
    pub fn deformer(&self, o: usize) -> Option<DeformerKind> {
        self.objects.get(o).map(|r| r.deformer)
    }

    /// The skeleton object `o`'s palette is evaluated on.
    #[must_use]
    pub fn rest_skeleton(&self, o: usize) -> Option<&RestSkeleton> {
        self.objects.get(o)?.skeleton.as_ref()?.rest.as_ref()
    }

    /// The value of channel `id` at `time` seconds; an override wins. `None` when the channel
    /// does not exist.
    #[must_use]
    pub fn value(&self, id: ChannelId, time: f64, overrides: &Overrides) -> Option<ChannelValue> {
        if let Some(v) = overrides.get(&id) {
            return Some(*v);
        }
        let vec3 = |slot: &Slot<Vec3>| Some(ChannelValue::Vec3(slot.sample(time)));
        let joint =
            |object: usize, joint: usize| self.objects.get(object)?.skeleton.as_ref()?.joints.get(joint);
        match id {
            ChannelId::ObjectTranslation(o) => vec3(&self.objects.get(o)?.translation),
            ChannelId::ObjectRotation(o) => Some(ChannelValue::Rotation(rotation_value(
                &self.objects.get(o)?.rotation,
                id,
                time,
                overrides,
            ))),
            ChannelId::ObjectEuler(o) => euler_value(&self.objects.get(o)?.rotation, id, time, overrides),
            ChannelId::ObjectScale(o) => vec3(&self.objects.get(o)?.scale),
            ChannelId::RootTranslation(o) => vec3(&self.objects.get(o)?.skeleton.as_ref()?.root_translation),
            ChannelId::JointTranslation { object, joint: j } => vec3(&joint(object, j)?.translation),
            ChannelId::JointRotation { object, joint: j } => {
                Some(ChannelValue::Rotation(rotation_value(&joint(object, j)?.rotation, id, time, overrides)))
            }
            ChannelId::JointEuler { object, joint: j } => {
                euler_value(&joint(object, j)?.rotation, id, time, overrides)
            }
            ChannelId::JointScale { object, joint: j } => vec3(&joint(object, j)?.scale),
            ChannelId::LightPosition(l) => vec3(&self.lights.get(l)?.position),
            ChannelId::LightDirection(l) => vec3(&self.lights.get(l)?.direction),
            ChannelId::LightColour(l) => vec3(&self.lights.get(l)?.colour),
            ChannelId::LightIntensity(l) => {
                Some(ChannelValue::Scalar(self.lights.get(l)?.intensity.sample(time)))
            }
            ChannelId::IkTarget { object, constraint } => {
                vec3(&self.objects.get(object)?.skeleton.as_ref()?.constraints.get(constraint)?.target)
            }
            ChannelId::IkBlend { object, constraint } => Some(ChannelValue::Scalar(
                self.objects.get(object)?.skeleton.as_ref()?.constraints.get(constraint)?.blend.sample(time),
            )),
            ChannelId::Attribute(a) => match a.owner() {
                Ok(o) => ObjectAttributeRig::value(self.objects.get(o)?.attributes.as_deref(), a, time),
                Err(l) => LightAttributeRig::value(self.lights.get(l)?.attributes.as_deref(), a, time),
            },
            ChannelId::CameraTranslation(c) => vec3(&self.cameras.get(c)?.translation),
            ChannelId::CameraRotation(c) => {
                Some(ChannelValue::Rotation(self.cameras.get(c)?.rotation.sample(time)))
            }
            ChannelId::CameraLens(c) => Some(ChannelValue::Scalar(self.cameras.get(c)?.lens.sample(time))),
            ChannelId::CameraRoll(c) => {
                Some(ChannelValue::Scalar(self.cameras.get(c)?.aim.as_ref()?.roll.sample(time)))
            }
            ChannelId::CameraAimInfluence(c) => {
                Some(ChannelValue::Scalar(self.cameras.get(c)?.aim.as_ref()?.influence.sample(time)))
            }
            ChannelId::CameraVisible(c) => {
                Some(ChannelValue::Scalar(self.cameras.get(c)?.visible.sample(time)))
            }
            ChannelId::Constraint { object, constraint, property } => Some(ChannelValue::Scalar(
                self.constraints.objects.get(object)?.get(constraint)?.value(property, time)?,
            )),
        }
    }

    /// For a rotation channel with spin keys: the unwrapped angle (degrees) turned since the
    /// start of the spin segment at `time` (keyrig-core's `Track::spin_degrees`); `None`
    /// outside spin segments and for other channels.
    #[must_use]
    pub fn spin_degrees(&self, id: ChannelId, time: f64) -> Option<f64> {
        let slot = match id {
            ChannelId::ObjectRotation(o) => self.objects.get(o)?.rotation.quat()?,
            ChannelId::JointRotation { object, joint } => {
                self.objects.get(object)?.skeleton.as_ref()?.joints.get(joint)?.rotation.quat()?
            }
            ChannelId::CameraRotation(c) => &self.cameras.get(c)?.rotation,
            _ => return None,
        };
        match &*slot.eval {
            SlotEval::Track(track) => track.track()?.spin_degrees(time),
            SlotEval::Fallback(_) => None,
        }
    }

    /// The whole scene at `time` seconds.
    #[must_use]
    pub fn evaluate(&self, time: f64, overrides: &Overrides) -> SceneState {
        let mut state = SceneState { time, objects: Vec::new(), lights: Vec::new(), cameras: Vec::new() };
        self.evaluate_into(time, overrides, &mut state);
        state
    }

    /// [`SceneEvaluator::evaluate`] into `state`, reusing its allocations (each object's pose
    /// and joint palette vectors): the same values, without allocating once the state has held
    /// this scene. What a frame calls when the time, the overrides or the scene changed.
    pub fn evaluate_into(&self, time: f64, overrides: &Overrides, state: &mut SceneState) {
        state.time = time;
        state.objects.truncate(self.objects.len());
        state.objects.resize_with(self.objects.len(), ObjectState::empty);
        // Objects in dependency order, so that every constraint's targets are evaluated (and
        // constrained) before it.
        for &o in &self.constraints.order {
            let Some(rig) = self.objects.get(o) else { continue };
            Self::fill_object(rig, o, time, overrides, usize::MAX, &mut state.objects[o]);
            let rigs = self.constraints.objects.get(o).map_or(&[][..], Vec::as_slice);
            if !rigs.is_empty() {
                let mut world = state.objects[o].world_from_object;
                let objects = &state.objects;
                constraints::apply(rigs, o, time, overrides, usize::MAX, &mut world, &|t| {
                    Self::frame_in(objects, t)
                });
                state.objects[o].world_from_object = world;
            }
        }
        state.lights.clear();
        state.lights.extend((0..self.lights.len()).filter_map(|l| self.light_at(l, time, overrides)));
        state.cameras.clear();
        let objects = &state.objects;
        state.cameras.extend(
            self.cameras
                .iter()
                .enumerate()
                .map(|(c, rig)| rig.state(c, time, overrides, |target| Self::target_in(objects, target))),
        );
    }

    /// Scene camera `c` at `time` seconds; `None` when there is no such camera. An aimed
    /// camera evaluates the object it looks at.
    #[must_use]
    pub fn camera_at(&self, c: usize, time: f64, overrides: &Overrides) -> Option<CameraState> {
        let rig = self.cameras.get(c)?;
        Some(rig.state(c, time, overrides, |target| match *target {
            Target::Object(o) | Target::Joint { object: o, .. } => {
                let state = self.object_at(o, time, overrides)?;
                let mut objects = vec![ObjectState::empty(); o];
                objects.push(state);
                Self::target_in(&objects, target)
            }
            Target::Point(p) => Some(p),
            Target::Missing => None,
        }))
    }

    /// The number of scene cameras.
    #[must_use]
    pub fn camera_count(&self) -> usize {
        self.cameras.len()
    }

    /// The frame of a constraint target in evaluated objects: an object's world transform, a
    /// joint's (world from object · model from joint), a point's translation.
    fn frame_in(objects: &[ObjectState], target: &Target) -> Option<Affine3A> {
        match *target {
            Target::Point(p) => Some(Affine3A::from_translation(p)),
            Target::Object(o) => Some(objects.get(o)?.world_from_object),
            Target::Joint { object, joint } => Self::joint_frame(objects.get(object)?, joint),
            Target::Missing => None,
        }
    }

    fn joint_frame(state: &ObjectState, joint: usize) -> Option<Affine3A> {
        Some(state.world_from_object * *state.palette.as_ref()?.model_from_joint.get(joint)?)
    }

    /// The frame of `target` at `time`, evaluating the object it names (with its constraints).
    pub(crate) fn frame_of(&self, target: &Target, time: f64, overrides: &Overrides) -> Option<Affine3A> {
        match *target {
            Target::Point(p) => Some(Affine3A::from_translation(p)),
            Target::Object(o) => Some(self.object_at(o, time, overrides)?.world_from_object),
            Target::Joint { object, joint } => {
                Self::joint_frame(&self.object_at(object, time, overrides)?, joint)
            }
            Target::Missing => None,
        }
    }

    /// Object `o`'s world transform at `time` going into its constraint `c` (its own transform
    /// with constraints `0..c` applied) and constraint `c`'s own result for it (unblended; the
    /// incoming transform where the constraint does nothing at this time). `None` when there
    /// is no such object or constraint.
    #[must_use]
    pub fn constraint_frames(
        &self,
        o: usize,
        c: usize,
        time: f64,
        overrides: &Overrides,
    ) -> Option<(Affine3A, Affine3A)> {
        let rigs = self.constraints.objects.get(o)?;
        let rig = rigs.get(c)?;
        let mut state = ObjectState::empty();
        Self::fill_object(self.objects.get(o)?, o, time, overrides, usize::MAX, &mut state);
        let mut world = state.world_from_object;
        let frame_of = |t: &Target| self.frame_of(t, time, overrides);
        constraints::apply(rigs, o, time, overrides, c, &mut world, &frame_of);
        let out = constraints::result(rig, o, c, time, overrides, &world, &frame_of).unwrap_or(world);
        Some((world, out))
    }

    /// The world position of an aim target in evaluated objects.
    fn target_in(objects: &[ObjectState], target: &Target) -> Option<Vec3> {
        match *target {
            Target::Point(p) => Some(p),
            Target::Object(o) => Some(objects.get(o)?.world_from_object.translation.into()),
            Target::Joint { object, joint } => {
                let state = objects.get(object)?;
                let joint_in_model = state.palette.as_ref()?.model_from_joint.get(joint)?.translation;
                Some(state.world_from_object.transform_point3a(joint_in_model).into())
            }
            Target::Missing => None,
        }
    }

    /// Object `o` at `time` seconds; `None` when there is no such object. The skeleton's pose
    /// is its keyed local transforms (with the overrides), then every IK constraint solved on
    /// it in order and blended by its blend channel; the palette is computed from the result.
    #[must_use]
    pub fn object_at(&self, o: usize, time: f64, overrides: &Overrides) -> Option<ObjectState> {
        self.object_at_solving(o, time, overrides, usize::MAX)
    }

    /// Object `o` at `time` seconds with only its first `constraints` IK constraints solved
    /// (0: forward kinematics alone); [`SceneEvaluator::object_at`] solves them all.
    #[must_use]
    pub fn object_at_solving(
        &self,
        o: usize,
        time: f64,
        overrides: &Overrides,
        constraints: usize,
    ) -> Option<ObjectState> {
        let rig = self.objects.get(o)?;
        let mut state = ObjectState::empty();
        Self::fill_object(rig, o, time, overrides, constraints, &mut state);
        let rigs = self.constraints.objects.get(o).map_or(&[][..], Vec::as_slice);
        if !rigs.is_empty() {
            let mut world = state.world_from_object;
            // Targets come before this object in the evaluation order (a cycle's constraints
            // are off), so this recursion ends.
            constraints::apply(rigs, o, time, overrides, usize::MAX, &mut world, &|t| {
                self.frame_of(t, time, overrides)
            });
            state.world_from_object = world;
        }
        Some(state)
    }

    /// Object `o` (whose rig is `rig`) at `time` with its first `constraints` IK constraints
    /// solved, written over `state` (its pose and palette vectors are reused).
    fn fill_object(
        rig: &ObjectRig,
        o: usize,
        time: f64,
        overrides: &Overrides,
        constraints: usize,
        state: &mut ObjectState,
    ) {
        let vec3 = |id: ChannelId, slot: &Slot<Vec3>| match overrides.get(&id) {
            Some(ChannelValue::Vec3(v)) => *v,
            _ => slot.sample(time),
        };
        let quat =
            |id: ChannelId, slot: &RotationSlot| unit_or_identity(rotation_value(slot, id, time, overrides));
        let old_pose = state.pose.take();
        let old_palette = state.palette.take();
        if let Some(mix) = &rig.mix {
            let mut pose = old_pose.unwrap_or_else(|| Pose::rest(0));
            let mut values = PoseValues {
                joint_translations: std::mem::take(&mut pose.local_translations),
                joint_rotations: std::mem::take(&mut pose.local_rotations),
                joint_scales: std::mem::take(&mut pose.local_scales),
                ..PoseValues::default()
            };
            Self::mix_pose(rig, mix, o, time, overrides, &mut values);
            state.world_from_object =
                Affine3A::from_scale_rotation_translation(values.scale, values.rotation, values.translation);
            pose.local_translations = values.joint_translations;
            pose.local_rotations = values.joint_rotations;
            pose.local_scales = values.joint_scales;
            pose.root_translation = values.root;
            Self::finish_object(rig, o, time, overrides, constraints, state, Some(pose), old_palette);
            return;
        }
        let world_from_object = Affine3A::from_scale_rotation_translation(
            vec3(ChannelId::ObjectScale(o), &rig.scale),
            quat(ChannelId::ObjectRotation(o), &rig.rotation),
            vec3(ChannelId::ObjectTranslation(o), &rig.translation),
        );
        state.world_from_object = world_from_object;
        let pose = rig.skeleton.as_ref().map(|skeleton| {
            let n = skeleton.joints.len();
            let mut pose = old_pose.unwrap_or_else(|| Pose::rest(0));
            pose.local_translations.clear();
            pose.local_rotations.clear();
            pose.local_scales.clear();
            pose.local_translations.reserve(n);
            pose.local_rotations.reserve(n);
            pose.local_scales.reserve(n);
            pose.root_translation = vec3(ChannelId::RootTranslation(o), &skeleton.root_translation);
            for (j, slots) in skeleton.joints.iter().enumerate() {
                let (object, joint) = (o, j);
                pose.local_translations
                    .push(vec3(ChannelId::JointTranslation { object, joint }, &slots.translation));
                pose.local_rotations.push(quat(ChannelId::JointRotation { object, joint }, &slots.rotation));
                pose.local_scales.push(vec3(ChannelId::JointScale { object, joint }, &slots.scale));
            }
            pose
        });
        Self::finish_object(rig, o, time, overrides, constraints, state, pose, old_palette);
    }

    /// The pose of an object with clip tracks or layers at `time` (docs/clips.md, "The
    /// stack"): its static values, the strips bottom-up, its active action's keyed channels,
    /// the layers, then the overrides.
    fn mix_pose(
        rig: &ObjectRig,
        mix: &ObjectMix,
        o: usize,
        time: f64,
        overrides: &Overrides,
        values: &mut PoseValues,
    ) {
        let quat_static = |slot: &RotationSlot| unit_or_identity(slot.static_value());
        values.translation = rig.translation.static_value();
        values.rotation = quat_static(&rig.rotation);
        values.scale = rig.scale.static_value();
        values.joint_translations.clear();
        values.joint_rotations.clear();
        values.joint_scales.clear();
        values.root = Vec3::ZERO;
        if let Some(skeleton) = &rig.skeleton {
            values.root = skeleton.root_translation.static_value();
            for slots in &skeleton.joints {
                values.joint_translations.push(slots.translation.static_value());
                values.joint_rotations.push(quat_static(&slots.rotation));
                values.joint_scales.push(slots.scale.static_value());
            }
        }
        mix.strips_into(values, time);
        // The active action plays above the strips on the channels it keys.
        let keyed_vec3 = |slot: &Slot<Vec3>, v: &mut Vec3| {
            if slot.is_keyed() {
                *v = slot.sample(time);
            }
        };
        let keyed_quat = |slot: &RotationSlot, q: &mut Quat| {
            if slot.is_keyed() {
                *q = unit_or_identity(slot.sample(time));
            }
        };
        keyed_vec3(&rig.translation, &mut values.translation);
        keyed_quat(&rig.rotation, &mut values.rotation);
        keyed_vec3(&rig.scale, &mut values.scale);
        if let Some(skeleton) = &rig.skeleton {
            keyed_vec3(&skeleton.root_translation, &mut values.root);
            for (j, slots) in skeleton.joints.iter().enumerate() {
                keyed_vec3(&slots.translation, &mut values.joint_translations[j]);
                keyed_quat(&slots.rotation, &mut values.joint_rotations[j]);
                keyed_vec3(&slots.scale, &mut values.joint_scales[j]);
            }
        }
        mix.layers_into(values, time);
        if overrides.is_empty() {
            return;
        }
        let vec3 = |id: ChannelId, v: &mut Vec3| {
            if let Some(ChannelValue::Vec3(x)) = overrides.get(&id) {
                *v = *x;
            }
        };
        let quat = |id: ChannelId, slot: &RotationSlot, q: &mut Quat| {
            if let Some(x) = rotation_override(slot, id, overrides) {
                *q = unit_or_identity(x);
            }
        };
        vec3(ChannelId::ObjectTranslation(o), &mut values.translation);
        quat(ChannelId::ObjectRotation(o), &rig.rotation, &mut values.rotation);
        vec3(ChannelId::ObjectScale(o), &mut values.scale);
        if let Some(skeleton) = &rig.skeleton {
            vec3(ChannelId::RootTranslation(o), &mut values.root);
            for (j, slots) in skeleton.joints.iter().enumerate() {
                let (object, joint) = (o, j);
                vec3(ChannelId::JointTranslation { object, joint }, &mut values.joint_translations[j]);
                quat(
                    ChannelId::JointRotation { object, joint },
                    &slots.rotation,
                    &mut values.joint_rotations[j],
                );
                vec3(ChannelId::JointScale { object, joint }, &mut values.joint_scales[j]);
            }
        }
    }

    /// The rest of object `o` once its transform and pose are known: IK constraints, the
    /// palette, morph frames and attributes.
    #[allow(clippy::too_many_arguments)]
    fn finish_object(
        rig: &ObjectRig,
        o: usize,
        time: f64,
        overrides: &Overrides,
        constraints: usize,
        state: &mut ObjectState,
        pose: Option<Pose>,
        old_palette: Option<JointPalette>,
    ) {
        let vec3 = |id: ChannelId, slot: &Slot<Vec3>| match overrides.get(&id) {
            Some(ChannelValue::Vec3(v)) => *v,
            _ => slot.sample(time),
        };
        state.palette_error = None;
        state.morph = None;
        if let (Some(skeleton), Some(mut pose)) = (&rig.skeleton, pose) {
            for (c, constraint) in skeleton.constraints.iter().enumerate().take(constraints) {
                let Some(chain) = &constraint.chain else { continue };
                let blend = match overrides.get(&ChannelId::IkBlend { object: o, constraint: c }) {
                    Some(ChannelValue::Scalar(v)) => *v,
                    _ => constraint.blend.sample(time),
                };
                if blend.is_nan() || blend <= 0.0 {
                    continue;
                }
                let target = vec3(ChannelId::IkTarget { object: o, constraint: c }, &constraint.target);
                let mut local = LocalPose {
                    translations: &pose.local_translations,
                    rotations: &mut pose.local_rotations,
                    scales: &pose.local_scales,
                    root_translation: pose.root_translation,
                };
                // A chain that cannot be solved at this time (a non-finite target, a
                // non-uniform scale) keeps its keyed pose.
                let _ = chain.solve(&mut local, target, constraint.pole, blend);
            }
            if let Some(rest) = &skeleton.rest {
                let mut palette = old_palette.unwrap_or_default();
                match palette.update(rest, &pose) {
                    Ok(()) => state.palette = Some(palette),
                    Err(e) => state.palette_error = Some(e),
                }
            }
            state.pose = Some(pose);
        } else if let Some(rest_palette) = &rig.rest_palette {
            let mut palette = old_palette.unwrap_or_default();
            palette.clone_from(rest_palette);
            state.palette = Some(palette);
        }
        if let Some(morph) = &rig.morph {
            state.morph = Some(morph.clips.blend_at(morph.clip.as_deref(), morph.fps, time));
        }
        ObjectAttributeRig::fill(
            rig.attributes.as_deref(),
            o,
            time,
            overrides,
            &rig.built_from.deformer,
            &mut state.look,
        );
        match (state.look.blend_zone, &rig.skin) {
            (Some(zone), Some(skin)) if skin.mesh.bones.is_some() => {
                if !matches!(&state.zone_bindings, Some((built, _)) if *built == zone) {
                    // The zone is in [0, 1] and the mesh bound once already: this cannot fail;
                    // were it to, the rig's own bindings apply.
                    state.zone_bindings = skin.mesh.bindings(zone).ok().map(|b| (zone, Arc::new(b)));
                }
            }
            _ => state.zone_bindings = None,
        }
    }

    /// Light `l` at `time` seconds; `None` when there is no such light.
    #[must_use]
    pub fn light_at(&self, l: usize, time: f64, overrides: &Overrides) -> Option<LightState> {
        let rig = self.lights.get(l)?;
        let vec3 = |id: ChannelId, slot: &Slot<Vec3>| match overrides.get(&id) {
            Some(ChannelValue::Vec3(v)) => *v,
            _ => slot.sample(time),
        };
        let intensity = match overrides.get(&ChannelId::LightIntensity(l)) {
            Some(ChannelValue::Scalar(s)) => *s,
            _ => rig.intensity.sample(time),
        };
        let (visible, range, kind) =
            LightAttributeRig::apply(rig.attributes.as_deref(), l, time, overrides, rig.kind);
        Some(LightState {
            kind,
            visible,
            range,
            enabled: rig.enabled,
            position: vec3(ChannelId::LightPosition(l), &rig.position),
            direction: vec3(ChannelId::LightDirection(l), &rig.direction),
            colour: vec3(ChannelId::LightColour(l), &rig.colour),
            intensity,
        })
    }
}

impl LightRig {
    fn new(l: usize, light: &keyrig_core::Light) -> Self {
        LightRig {
            kind: light.kind,
            enabled: light.enabled,
            position: Slot::new(&light.position, ChannelId::LightPosition(l)),
            direction: Slot::new(&light.direction, ChannelId::LightDirection(l)),
            colour: Slot::new(&light.colour, ChannelId::LightColour(l)),
            intensity: Slot::new(&light.intensity, ChannelId::LightIntensity(l)),
            attributes: LightAttributeRig::new(&light.attributes, l),
        }
    }

    fn refresh(&mut self, l: usize, light: &keyrig_core::Light) -> usize {
        self.kind = light.kind;
        self.enabled = light.enabled;
        usize::from(self.position.refresh(&light.position, ChannelId::LightPosition(l)))
            + usize::from(self.direction.refresh(&light.direction, ChannelId::LightDirection(l)))
            + usize::from(self.colour.refresh(&light.colour, ChannelId::LightColour(l)))
            + usize::from(self.intensity.refresh(&light.intensity, ChannelId::LightIntensity(l)))
            + LightAttributeRig::refresh(&mut self.attributes, &light.attributes, l)
    }
}

impl ObjectRig {
    fn new(scene: &Scene, o: usize, loaded: Option<&LoadedMesh>) -> Self {
        let object = &scene.objects[o];
        let at = |field: &str| format!("objects[{o}].{field}");
        let mut problems = Vec::new();
        let mut problem = |path: String, message: String| problems.push(EvalProblem { path, message });
        let translation = Slot::new(&object.translation, ChannelId::ObjectTranslation(o));
        let rotation = RotationSlot::new(
            &object.rotation,
            object.rotation_euler.as_ref(),
            object.rotation_mode,
            ChannelId::ObjectRotation(o),
        );
        let scale = Slot::new(&object.scale, ChannelId::ObjectScale(o));
        let scene_rest = object.skeleton.as_ref().and_then(|s| match RestSkeleton::from_scene(s) {
            Ok(rest) => Some(rest),
            Err(e) => {
                problem(at("skeleton"), e.to_string());
                None
            }
        });
        let mut skeleton = object.skeleton.as_ref().map(|s| SkeletonRig {
            root_translation: Slot::new(&s.root_translation, ChannelId::RootTranslation(o)),
            constraints: (0..s.ik_constraints.len()).map(|c| ConstraintRig::new(s, o, c)).collect(),
            joints: s
                .joints
                .iter()
                .enumerate()
                .map(|(joint, j)| JointSlots {
                    translation: Slot::new(&j.translation, ChannelId::JointTranslation { object: o, joint }),
                    rotation: RotationSlot::new(
                        &j.rotation,
                        j.rotation_euler.as_ref(),
                        j.rotation_mode,
                        ChannelId::JointRotation { object: o, joint },
                    ),
                    scale: Slot::new(&j.scale, ChannelId::JointScale { object: o, joint }),
                })
                .collect(),
            rest: scene_rest.clone(),
        });
        // The skinned mesh: procedural meshes are generated and bound to the object's skeleton
        // (scaled to its length); loaded ones keep their own skeleton, which must list the
        // scene skeleton's joints in the same order.
        let mesh: Option<SkinnedMesh> = match (&object.mesh, loaded) {
            (Some(MeshSource::Procedural(kind)), _) => match &scene_rest {
                Some(rest) => match mesh_for(*kind).fit_to_skeleton(rest.clone()) {
                    Ok(mesh) => Some(mesh),
                    Err(e) => {
                        problem(at("mesh (bound to the object's skeleton)"), e.to_string());
                        None
                    }
                },
                None if object.skeleton.is_some() => None,
                None => Some(mesh_for(*kind)),
            },
            (Some(MeshSource::File { path, .. }), Some(LoadedMesh::Skinned(mesh))) => match &skeleton {
                Some(s) if s.joints.len() != mesh.skeleton.len() => {
                    problem(
                        at("skeleton"),
                        format!(
                            "{} joints, but the mesh from `{path}` is bound to {}",
                            s.joints.len(),
                            mesh.skeleton.len()
                        ),
                    );
                    None
                }
                _ => Some((**mesh).clone()),
            },
            _ => None,
        };
        let skin = mesh.and_then(|mesh| {
            let bindings = BlendZone::from_settings(&object.deformer).and_then(|zone| mesh.bindings(zone));
            match bindings {
                Ok(bindings) => Some(SkinRig { mesh: Arc::new(mesh), bindings: Arc::new(bindings) }),
                Err(e) => {
                    problem(at("mesh"), e.to_string());
                    None
                }
            }
        });
        if let (Some(skeleton), Some(skin)) = (&mut skeleton, &skin) {
            skeleton.rest = Some(skin.mesh.skeleton.clone());
        }
        let rest_palette = match (&skeleton, &skin) {
            (None, Some(skin)) => {
                JointPalette::new(&skin.mesh.skeleton, &Pose::rest(skin.mesh.skeleton.len())).ok()
            }
            _ => None,
        };
        let morph = match (&object.mesh, loaded) {
            (Some(MeshSource::File { clip, fps, .. }), Some(LoadedMesh::Morph(clips))) => {
                let fps = fps.unwrap_or(keyrig_core::MD2_DEFAULT_FPS);
                if !(fps.is_finite() && fps > 0.0) {
                    problem(at("mesh.fps"), MorphError::BadFps(fps).to_string());
                    None
                } else if let Err(e) = clips.clip_frames(clip.as_deref()) {
                    problem(at("mesh.clip"), e.to_string());
                    None
                } else {
                    Some(MorphRig { clips: Arc::clone(clips), clip: clip.clone(), fps })
                }
            }
            _ => None,
        };
        ObjectRig {
            translation,
            rotation,
            scale,
            skeleton,
            skin,
            rest_palette,
            morph,
            deformer: object.deformer.kind,
            attributes: ObjectAttributeRig::new(&object.attributes, o),
            built_from: RestSource::of(object, loaded),
            problems,
            mix: ObjectMix::new(scene, o).map(Box::new),
        }
    }

    /// Rebuilds the channels that changed (the rest data is known to be the same), and the
    /// mix when what it plays changed.
    fn refresh(&mut self, scene: &Scene, o: usize) -> usize {
        let n = self.refresh_channels(scene, o);
        if (n > 0 && self.mix.as_ref().is_some_and(|m| m.plays_active()))
            || !ObjectMix::is_current(self.mix.as_deref(), scene, o)
        {
            self.mix = ObjectMix::new(scene, o).map(Box::new);
            return n + self.mix.as_ref().map_or(0, |m| m.channel_count());
        }
        n
    }

    fn refresh_channels(&mut self, scene: &Scene, o: usize) -> usize {
        let object = &scene.objects[o];
        let mut n =
            usize::from(self.translation.refresh(&object.translation, ChannelId::ObjectTranslation(o)))
                + usize::from(self.rotation.refresh(
                    &object.rotation,
                    object.rotation_euler.as_ref(),
                    object.rotation_mode,
                    ChannelId::ObjectRotation(o),
                ))
                + usize::from(self.scale.refresh(&object.scale, ChannelId::ObjectScale(o)))
                + ObjectAttributeRig::refresh(&mut self.attributes, &object.attributes, o);
        if let (Some(rig), Some(skeleton)) = (&mut self.skeleton, &object.skeleton) {
            n += usize::from(
                rig.root_translation.refresh(&skeleton.root_translation, ChannelId::RootTranslation(o)),
            );
            for (joint, (slots, j)) in rig.joints.iter_mut().zip(&skeleton.joints).enumerate() {
                n += usize::from(
                    slots
                        .translation
                        .refresh(&j.translation, ChannelId::JointTranslation { object: o, joint }),
                ) + usize::from(slots.rotation.refresh(
                    &j.rotation,
                    j.rotation_euler.as_ref(),
                    j.rotation_mode,
                    ChannelId::JointRotation { object: o, joint },
                )) + usize::from(
                    slots.scale.refresh(&j.scale, ChannelId::JointScale { object: o, joint }),
                );
            }
            rig.constraints.truncate(skeleton.ik_constraints.len());
            for c in 0..skeleton.ik_constraints.len() {
                match rig.constraints.get_mut(c) {
                    Some(constraint) => n += constraint.refresh(skeleton, o, c),
                    None => {
                        rig.constraints.push(ConstraintRig::new(skeleton, o, c));
                        n += 2;
                    }
                }
            }
        }
        n
    }

    fn channel_count(&self) -> usize {
        3 + self.skeleton.as_ref().map_or(0, |s| 1 + 3 * s.joints.len() + 2 * s.constraints.len())
            + self.attributes.as_ref().map_or(0, |a| a.channel_count())
    }

    fn for_each_problem(&self, f: &mut dyn FnMut(&EvalProblem)) {
        let mut visit = |p: &Option<EvalProblem>| {
            if let Some(p) = p {
                f(p);
            }
        };
        visit(&self.translation.problem);
        visit(self.rotation.problem());
        visit(&self.scale.problem);
        if let Some(s) = &self.skeleton {
            visit(&s.root_translation.problem);
            for j in &s.joints {
                visit(&j.translation.problem);
                visit(j.rotation.problem());
                visit(&j.scale.problem);
            }
            for c in &s.constraints {
                visit(&c.problem);
                visit(&c.target.problem);
                visit(&c.blend.problem);
            }
        }
        if let Some(a) = &self.attributes {
            a.for_each_problem(f);
        }
    }
}

/// The rotation of rotation channel `id` (slot `slot`) at `time`: an override of the channel
/// wins, then one of its Euler-keys channel (angles typed in the inspector), then the keys.
fn rotation_value(slot: &RotationSlot, id: ChannelId, time: f64, overrides: &Overrides) -> Quat {
    rotation_override(slot, id, overrides).unwrap_or_else(|| slot.sample(time))
}

/// The override of rotation channel `id` or of its Euler-keys channel, if any.
fn rotation_override(slot: &RotationSlot, id: ChannelId, overrides: &Overrides) -> Option<Quat> {
    if let Some(ChannelValue::Rotation(q)) = overrides.get(&id) {
        return Some(*q);
    }
    if let (RotationSlot::Euler(_, order), Some(euler)) = (slot, keyrig_core::channel_id::euler_partner(id)) {
        if let Some(ChannelValue::Vec3(e)) = overrides.get(&euler) {
            return Some(order.to_quat(*e));
        }
    }
    None
}

/// `q` normalized; the identity for a zero or non-finite quaternion.
fn unit_or_identity(q: Quat) -> Quat {
    if q.is_finite() && q.length_squared() > 1e-12 {
        q.normalize()
    } else {
        Quat::IDENTITY
    }
}

/// The angles of Euler-keys channel `id` at `time` (`None` when its rotation has quaternion
/// keys): an override wins; a posed rotation (a gizmo drag overrides the rotation channel)
/// reads as the angles nearest the keyed ones.
fn euler_value(slot: &RotationSlot, id: ChannelId, time: f64, overrides: &Overrides) -> Option<ChannelValue> {
    let (keyed, order) = slot.angles(time)?;
    if let Some(v @ ChannelValue::Vec3(_)) = overrides.get(&id) {
        return Some(*v);
    }
    let posed = keyrig_core::channel_id::euler_partner(id).and_then(|r| overrides.get(&r));
    Some(ChannelValue::Vec3(match posed {
        Some(ChannelValue::Rotation(q)) => order.angles_near(*q, keyed),
        _ => keyed,
    }))
}
