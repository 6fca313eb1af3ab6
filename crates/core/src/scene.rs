//! The scene document: what a `.ron` scene file holds and what the editor edits.
//!
//! Plain serializable data with no invariants of its own; [`Scene::problems`] lists what is
//! wrong with it (non-finite numbers, bad joint parents, keys out of order) with the path of
//! each problem, so that loaders and `keyrig info` can report them.

use glam::{Quat, Vec3};
use serde::{Deserialize, Serialize};

use crate::attributes::{LightAttributes, ObjectAttributes};
use crate::camera_object::{Marker, RenderSize, SceneCamera};
use crate::key::{Animated, RawTrack};
use crate::object_constraint::ObjectConstraint;
use crate::rotation_mode::RotationMode;

/// A whole scene: timing, animated objects, lights and a camera.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Scene {
    /// Frames per second of the timeline. Key times are stored in seconds.
    pub fps: f64,
    /// First and last frame of the playback range (inclusive).
    pub frame_range: FrameRange,
    /// Ambient light colour (linear RGB), added to every lit surface.
    #[serde(default = "default_ambient")]
    pub ambient: Vec3,
    #[serde(default)]
    pub objects: Vec<Object>,
    #[serde(default)]
    pub lights: Vec<Light>,
    #[serde(default)]
    pub camera: Camera,
    /// Cameras placed in the scene (not the viewport's view, [`Scene::camera`]). Left out of
    /// a scene file while empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub cameras: Vec<SceneCamera>,
    /// The camera active before the first marker bound to a camera; `None`: the first camera.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub active_camera: Option<String>,
    /// Named timeline markers, optionally switching the active camera.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub markers: Vec<Marker>,
    /// The size `keyrig render` renders at when not told (`None`: 1280×720).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub render_size: Option<RenderSize>,
    /// Sound clips on the timeline (docs/scene-format.md); none in most scenes.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub sounds: Vec<crate::sound::SoundClip>,
    /// The preview range: the frames playback loops over while it is set, inside
    /// `frame_range` (Blender's preview range); renders and exports keep the frame range.
    /// Left out of a scene file while unset.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub preview_range: Option<FrameRange>,
    /// The pose library: named poses saved with the scene. Left out of a scene file while
    /// empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub poses: Vec<crate::pose_library::NamedPose>,
    /// An image shown behind the scene in the editor's viewport. Left out of a scene file
    /// while unset.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub reference_image: Option<crate::pose_library::ReferenceImage>,
    /// The actions (docs/actions.md): every named set of keys, with the channels that are not
    /// playing. Left out of a scene file while empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub actions: Vec<crate::action_keys::Action>,
    /// Animation layers (docs/clips.md), bottom-up, above every object's clip tracks and
    /// active action. Left out of a scene file while empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub layers: Vec<crate::clip::Layer>,
}

fn default_ambient() -> Vec3 {
    Vec3::splat(0.1)
}

impl Default for Scene {
    fn default() -> Self {
        Scene {
            fps: 30.0,
            frame_range: FrameRange { start: 0, end: 60 },
            ambient: default_ambient(),
            objects: Vec::new(),
            lights: Vec::new(),
            camera: Camera::default(),
            cameras: Vec::new(),
            active_camera: None,
            markers: Vec::new(),
            render_size: None,
            sounds: Vec::new(),
            preview_range: None,
            poses: Vec::new(),
            reference_image: None,
            actions: Vec::new(),
            layers: Vec::new(),
        }
    }
}

impl Scene {
    /// The frames playback runs over: the preview range where one is set and overlaps the
    /// frame range (cut to it), else the frame range.
    #[must_use]
    pub fn playback_range(&self) -> FrameRange {
        let range = self.frame_range;
        match self.preview_range {
            Some(p) if p.start <= p.end && p.start <= range.end && p.end >= range.start => {
                FrameRange { start: p.start.max(range.start), end: p.end.min(range.end) }
            }
            _ => range,
        }
    }
}

/// Inclusive frame range.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct FrameRange {
    pub start: i32,
    pub end: i32,
}

impl Scene {
    /// The scene with every Euler-keyed rotation replaced by quaternion keys that follow it
    /// ([`crate::rotation_mode::quaternion_keys_following`] over `range`, seconds): what
    /// exporters write, since glTF, VRML and X3D rotations are quaternions or axis–angles.
    /// Borrowed as it is when nothing has Euler keys.
    ///
    /// # Errors
    /// The field path of Euler keys that are invalid, with the problem.
    pub fn with_quaternion_keys(
        &self,
        range: (f64, f64),
        tolerance_deg: f64,
    ) -> Result<std::borrow::Cow<'_, Scene>, (String, crate::TrackError)> {
        let has_euler = self.objects.iter().any(|o| {
            o.rotation_euler.is_some()
                || o.skeleton.as_ref().is_some_and(|s| s.joints.iter().any(|j| j.rotation_euler.is_some()))
        });
        if !has_euler {
            return Ok(std::borrow::Cow::Borrowed(self));
        }
        let mut out = self.clone();
        let convert = |path: String,
                       rotation: &mut Animated<Quat>,
                       euler: &mut Option<Animated<Vec3>>,
                       mode: RotationMode| {
            if let Some(keys) = euler.take() {
                let order = mode.euler().unwrap_or_default();
                *rotation =
                    crate::rotation_mode::quaternion_keys_following(&keys, order, range, tolerance_deg)
                        .map_err(|e| (path, e))?;
            }
            Ok(())
        };
        for (o, object) in out.objects.iter_mut().enumerate() {
            convert(
                format!("objects[{o}].rotation_euler"),
                &mut object.rotation,
                &mut object.rotation_euler,
                object.rotation_mode,
            )?;
            if let Some(skeleton) = &mut object.skeleton {
                for (j, joint) in skeleton.joints.iter_mut().enumerate() {
                    convert(
                        format!("objects[{o}].skeleton.joints[{j}].rotation_euler"),
                        &mut joint.rotation,
                        &mut joint.rotation_euler,
                        joint.rotation_mode,
                    )?;
                }
            }
        }
        Ok(std::borrow::Cow::Owned(out))
    }
}

/// An object in the scene: a keyed transform, optionally a mesh and a skeleton that deforms it.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Object {
    pub name: String,
    pub translation: Animated<Vec3>,
    pub rotation: Animated<Quat>,
    /// How the rotation reads and is typed (Euler order or quaternion). Left out of a scene
    /// file at its default, XYZ Euler.
    #[serde(default, skip_serializing_if = "RotationMode::is_default")]
    pub rotation_mode: RotationMode,
    /// Euler keys (docs/channels.md, "Euler keys"): when set, the rotation is these three
    /// angles (x, y, z in degrees, each interpolated on its own) turned in `rotation_mode`'s
    /// order, and `rotation` holds no keys. `None` (left out of the file): the quaternion keys
    /// of `rotation`, interpolated by Squad.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotation_euler: Option<Animated<Vec3>>,
    pub scale: Animated<Vec3>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub mesh: Option<MeshSource>,
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub skeleton: Option<Skeleton>,
    #[serde(default)]
    pub deformer: DeformerSettings,
    /// Visibility, material colour and opacity, morph weights, keyed deformer
    /// (`crate::attributes`); left out of the file while nothing is set.
    #[serde(default, skip_serializing_if = "ObjectAttributes::is_default")]
    pub attributes: ObjectAttributes,
    /// The object's active action (docs/actions.md): its keyed channels are that action's
    /// keys. `None` (left out of the file): keys that belong to no named action.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub action: Option<String>,
    /// Clip tracks (docs/clips.md), bottom-up: strips of actions that play below the active
    /// action. Left out of the file while empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub clip_tracks: Vec<crate::clip::ClipTrack>,
    /// Constraints applied in order after the object's own transform (aim at, child of, copy
    /// location or rotation, follow path; docs/constraints.md); left out of the file while
    /// there are none.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub constraints: Vec<ObjectConstraint>,
}

impl Object {
    /// An object at the origin, not animated, with no mesh.
    #[must_use]
    pub fn new(name: impl Into<String>) -> Self {
        Object {
            name: name.into(),
            translation: Animated::constant(Vec3::ZERO),
            rotation: Animated::constant(Quat::IDENTITY),
            rotation_mode: RotationMode::default(),
            rotation_euler: None,
            scale: Animated::constant(Vec3::ONE),
            mesh: None,
            skeleton: None,
            deformer: DeformerSettings::default(),
            attributes: ObjectAttributes::default(),
            action: None,
            clip_tracks: Vec::new(),
            constraints: Vec::new(),
        }
    }
}

/// Where an object's mesh comes from.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
pub enum MeshSource {
    /// A mesh generated in code (the paper's test arms, a hand, a cube).
    Procedural(ProceduralMesh),
    /// A model file (glTF, MD2) with a path relative to the scene file.
    File {
        path: String,
        /// Index of the mesh inside the file; `None` takes the first.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        mesh: Option<usize>,
        /// MD2 only: the clip (frame group, e.g. `run`) that plays; `None` plays every frame
        /// of the file in order.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        clip: Option<String>,
        /// MD2 only: playback rate of the model's frames, frames per second (finite, > 0);
        /// `None` means [`MD2_DEFAULT_FPS`]. Scene time `t` shows model frame `t · fps` of the
        /// clip, looping, morphing linearly between neighbouring frames.
        #[serde(default, skip_serializing_if = "Option::is_none")]
        fps: Option<f64>,
    },
}

/// The frame rate MD2 models play at when a scene does not say: Quake 2 animated its models
/// at 10 frames per second.
pub const MD2_DEFAULT_FPS: f64 = 10.0;

impl MeshSource {
    /// A model file's mesh: `mesh` of the file at `path`, with no MD2 clip or rate.
    #[must_use]
    pub fn file(path: impl Into<String>, mesh: Option<usize>) -> Self {
        MeshSource::File { path: path.into(), mesh, clip: None, fps: None }
    }
}

/// Meshes keyrig can generate (docs/design.md §6).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Serialize, Deserialize)]
pub enum ProceduralMesh {
    /// 78 vertices, 152 triangles, 4 bones along X, 160.158 cm.
    ArmLowPoly,
    /// 1250 vertices, 2496 triangles, 4 bones along X, 160.158 cm.
    ArmHighPoly,
    /// A palm with three fingers: a branching skeleton.
    Hand,
    /// A unit cube centred on the origin.
    Cube,
    /// A UV sphere of diameter 1 centred on the origin (16 rings of 32 vertices between the
    /// poles), smooth-shaded.
    Sphere,
    /// A 1 × 1 square in the XZ plane centred on the origin, facing +Y (a ground or a card).
    Plane,
}

/// A joint hierarchy with its rest pose and animation. Joints are stored parents first.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Skeleton {
    pub joints: Vec<Joint>,
    /// Translation of the root joint over time (in the object's space), added to its rest
    /// translation.
    #[serde(default = "zero_translation")]
    pub root_translation: Animated<Vec3>,
    /// IK constraints solved every frame after forward kinematics, in order (docs/ik.md, "IK
    /// constraints"). Left out of a scene file while empty.
    #[serde(default, skip_serializing_if = "Vec::is_empty")]
    pub ik_constraints: Vec<IkConstraint>,
}

impl Skeleton {
    /// A skeleton with these joints, no root translation and no IK constraints.
    #[must_use]
    pub fn new(joints: Vec<Joint>) -> Self {
        Skeleton { joints, root_translation: zero_translation(), ik_constraints: Vec::new() }
    }

    /// The joints in depth-first order — each joint followed by its children in index order,
    /// each child by its own — with their depth (0 for a root), as an outliner or a dope sheet
    /// lists a hierarchy. Linear in the joint count. A joint whose parent index is not below its
    /// own (a broken file; validation reports it) is walked as a root, so the walk cannot loop.
    #[must_use]
    pub fn depth_first(&self) -> Vec<(usize, usize)> {
        let n = self.joints.len();
        let parent = |j: usize| self.joints[j].parent.filter(|&p| p < j);
        let mut children: Vec<Vec<usize>> = vec![Vec::new(); n];
        for j in 0..n {
            if let Some(p) = parent(j) {
                children[p].push(j);
            }
        }
        let mut out = Vec::with_capacity(n);
        let mut stack: Vec<(usize, usize)> =
            (0..n).rev().filter(|&j| parent(j).is_none()).map(|j| (j, 0)).collect();
        while let Some((j, depth)) = stack.pop() {
            out.push((j, depth));
            stack.extend(children[j].iter().rev().map(|&c| (c, depth + 1)));
        }
        out
    }
}

/// An IK constraint (Blender's IK constraint, Maya's IK handle): the chain of `bones` bones that
/// ends at joint `end` is solved every frame so that `end` reaches `target`, and the solved
/// local rotations are blended with the keyed (FK) ones by `blend`.
///
/// The chain's joints are `end`, its parent, … up `bones` parents; every joint of the chain but
/// `end` is turned (the end joint keeps its own rotation, so the hand turns with the forearm).
/// Two bones are solved analytically, longer chains by FABRIK (`keyrig_core::ik`).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct IkConstraint {
    /// Shown in the editor and used in channel paths (`object/Arm/ik/<name>/target`).
    pub name: String,
    /// Index of the joint put on the target (the hand).
    pub end: usize,
    /// Bones of the chain (at least 2): 2 is shoulder–elbow–wrist, solved analytically.
    pub bones: usize,
    /// Where the end joint goes, in the object's space (before the object's transform, the
    /// space the skeleton's root translation is in).
    pub target: Animated<Vec3>,
    /// A point in the object's space the chain bends towards (Maya's pole vector, Blender's pole
    /// target); `None` bends the chain the way its keyed pose bends.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub pole: Option<Vec3>,
    /// IK/FK blend in [0, 1]: 0 shows the keyed rotations (FK), 1 the solved ones, in between
    /// each joint's rotation is the slerp of the two.
    #[serde(default = "full_blend")]
    pub blend: Animated<f32>,
}

fn full_blend() -> Animated<f32> {
    Animated::constant(1.0)
}

impl IkConstraint {
    /// A constraint named `name` on the chain of `bones` bones ending at `end`, with a fixed
    /// target, no pole and the blend at 1 (fully IK).
    #[must_use]
    pub fn new(name: impl Into<String>, end: usize, bones: usize, target: Vec3) -> Self {
        IkConstraint {
            name: name.into(),
            end,
            bones,
            target: Animated::constant(target),
            pole: None,
            blend: full_blend(),
        }
    }
}

fn zero_translation() -> Animated<Vec3> {
    Animated::constant(Vec3::ZERO)
}

/// One joint: rest transform R(j) relative to its parent and its animated local transform
/// T(j) = translate(translation) · rotate(rotation) · scale(scale), applied after R(j):
/// `F(j) = F(p(j)) · R(j) · T(j)` (docs/design.md §4).
///
/// keyrig's own rigs key `rotation` only; imported characters key all three, exactly as their
/// file does. `translation` and `scale` are left out of a scene file while they are the
/// identity (no keys, value zero / one).
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Joint {
    pub name: String,
    /// Index of the parent joint; `None` for the root. Must be smaller than this joint's index.
    pub parent: Option<usize>,
    /// Rest translation relative to the parent joint (R(j)'s translation).
    pub rest_translation: Vec3,
    /// Rest rotation relative to the parent joint (R(j)'s rotation).
    pub rest_rotation: Quat,
    /// Animated local translation of T(j), in the joint's rest frame (the parent's frame
    /// rotated by `rest_rotation`); zero at rest.
    #[serde(default = "zero_translation", skip_serializing_if = "is_zero_translation")]
    pub translation: Animated<Vec3>,
    /// Animated local rotation of T(j), applied after the rest transform; identity at rest.
    pub rotation: Animated<Quat>,
    /// How the rotation reads and is typed (Euler order or quaternion). Left out of a scene
    /// file at its default, XYZ Euler.
    #[serde(default, skip_serializing_if = "RotationMode::is_default")]
    pub rotation_mode: RotationMode,
    /// Euler keys, as [`Object::rotation_euler`]: when set, the rotation of T(j) is these
    /// angles in `rotation_mode`'s order and `rotation` holds no keys.
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub rotation_euler: Option<Animated<Vec3>>,
    /// Animated local scale of T(j) (applied first); one at rest.
    #[serde(default = "unit_scale", skip_serializing_if = "is_unit_scale")]
    pub scale: Animated<Vec3>,
}

impl Joint {
    /// A joint with the given rest transform and no animation.
    #[must_use]
    pub fn new(
        name: impl Into<String>,
        parent: Option<usize>,
        rest_translation: Vec3,
        rest_rotation: Quat,
    ) -> Self {
        Joint {
            name: name.into(),
            parent,
            rest_translation,
            rest_rotation,
            translation: zero_translation(),
            rotation: Animated::constant(Quat::IDENTITY),
            rotation_mode: RotationMode::default(),
            rotation_euler: None,
            scale: unit_scale(),
        }
    }
}

fn unit_scale() -> Animated<Vec3> {
    Animated::constant(Vec3::ONE)
}

fn is_zero_translation(a: &Animated<Vec3>) -> bool {
    !a.is_animated() && a.value == Vec3::ZERO
}

fn is_unit_scale(a: &Animated<Vec3>) -> bool {
    !a.is_animated() && a.value == Vec3::ONE
}

/// Which skin deformer an object uses, and the deformers' parameters.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct DeformerSettings {
    pub kind: DeformerKind,
    /// Bones blending: how far the blend zone reaches into the parent bone, as a fraction of
    /// the parent bone's length (0..=1).
    #[serde(default = "default_blend_fraction")]
    pub blend_parent_fraction: f32,
    /// Bones blending: how far the blend zone reaches into the child bone, as a fraction of
    /// the child bone's length (0..=1).
    #[serde(default = "default_blend_fraction")]
    pub blend_child_fraction: f32,
}

fn default_blend_fraction() -> f32 {
    0.25
}

impl Default for DeformerSettings {
    fn default() -> Self {
        DeformerSettings {
            kind: DeformerKind::LinearBlend,
            blend_parent_fraction: default_blend_fraction(),
            blend_child_fraction: default_blend_fraction(),
        }
    }
}

/// The four skin deformers (docs/design.md §5).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash, Serialize, Deserialize)]
pub enum DeformerKind {
    /// One weight per vertex: v' = M(j)·v.
    Rigid,
    /// Linear blend skinning: v' = Σ wᵢ·M(jᵢ)·v.
    #[default]
    LinearBlend,
    /// Kavan & Žára's bones blending.
    BonesBlending,
    /// Dual quaternion skinning (Kavan et al. 2008).
    DualQuaternion,
}

impl DeformerKind {
    pub const ALL: [DeformerKind; 4] = [
        DeformerKind::Rigid,
        DeformerKind::LinearBlend,
        DeformerKind::BonesBlending,
        DeformerKind::DualQuaternion,
    ];

    /// The name used on the command line (`rigid`, `linear`, `bones-blending`, `dual-quaternion`).
    #[must_use]
    pub fn cli_name(self) -> &'static str {
        match self {
            DeformerKind::Rigid => "rigid",
            DeformerKind::LinearBlend => "linear",
            DeformerKind::BonesBlending => "bones-blending",
            DeformerKind::DualQuaternion => "dual-quaternion",
        }
    }

    /// The name shown in the editor.
    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            DeformerKind::Rigid => "Rigid",
            DeformerKind::LinearBlend => "Linear blend",
            DeformerKind::BonesBlending => "Bones blending",
            DeformerKind::DualQuaternion => "Dual quaternion",
        }
    }

    /// Parses a command-line name; see [`DeformerKind::cli_name`].
    #[must_use]
    pub fn from_cli_name(name: &str) -> Option<Self> {
        DeformerKind::ALL.into_iter().find(|k| k.cli_name() == name)
    }
}

/// A light with keyed position, direction, colour and intensity.
#[derive(Clone, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Light {
    pub name: String,
    pub kind: LightKind,
    #[serde(default = "default_true")]
    pub enabled: bool,
    /// Position in world space (unused by directional lights).
    pub position: Animated<Vec3>,
    /// Direction the light shines in, world space (unused by point lights). Need not be unit.
    pub direction: Animated<Vec3>,
    /// Linear RGB colour.
    pub colour: Animated<Vec3>,
    pub intensity: Animated<f32>,
    /// Visibility, range and keyed spot cone (`crate::attributes`); left out of the file while
    /// nothing is set.
    #[serde(default, skip_serializing_if = "LightAttributes::is_default")]
    pub attributes: LightAttributes,
}

fn default_true() -> bool {
    true
}

/// Kinds of light (seed text 002: directional, point and spot lights).
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
pub enum LightKind {
    Directional,
    /// A point light whose intensity falls off with the square of the distance.
    Point,
    /// A spot light: full intensity inside `inner_angle_deg`, none outside `cutoff_deg`
    /// (half-angles from the direction), falling off as `cos^dropoff` in between.
    Spot {
        cutoff_deg: f32,
        inner_angle_deg: f32,
        dropoff: f32,
    },
}

/// The viewing camera: an orbit around a target point.
#[derive(Clone, Copy, Debug, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    pub target: Vec3,
    /// Rotation about the world Y axis, degrees.
    pub yaw_deg: f32,
    /// Elevation above the ground plane, degrees.
    pub pitch_deg: f32,
    pub distance: f32,
    /// Vertical field of view, degrees.
    pub fov_y_deg: f32,
}

impl Default for Camera {
    fn default() -> Self {
        Camera { target: Vec3::ZERO, yaw_deg: 30.0, pitch_deg: 20.0, distance: 5.0, fov_y_deg: 45.0 }
    }
}

/// Something wrong with a scene, with the path of the field it concerns
/// (e.g. `objects[0].skeleton.joints[2].rotation.track[4].value`).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct Problem {
    pub path: String,
    pub message: String,
}

impl std::fmt::Display for Problem {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        write!(f, "{}: {}", self.path, self.message)
    }
}

/// The raw-track access used when walking a scene.
impl<T> Animated<T> {
    /// The keys of the track.
    #[must_use]
    pub fn keys(&self) -> &RawTrack<T> {
        &self.track
    }
}

impl Scene {
    /// Bytes of key data in `self` that `other` does not share (keys are copy-on-write,
    /// [`crate::Keys`]): what keeping `self` beside `other` costs, e.g. an undo snapshot beside
    /// the edited scene. Tracks are paired by position (object, joint, light index).
    #[must_use]
    pub fn key_bytes_not_shared_with(&self, other: &Scene) -> usize {
        fn cost<T>(a: &Animated<T>, b: Option<&Animated<T>>) -> usize {
            if b.is_some_and(|b| b.track.keys.shares_with(&a.track.keys)) {
                0
            } else {
                a.track.keys.len() * std::mem::size_of::<crate::key::Key<T>>()
            }
        }
        let mut bytes = 0;
        for (o, object) in self.objects.iter().enumerate() {
            let theirs = other.objects.get(o);
            bytes += object.attributes.key_bytes_not_shared_with(theirs.map(|t| &t.attributes));
            bytes += cost(&object.translation, theirs.map(|t| &t.translation))
                + cost(&object.rotation, theirs.map(|t| &t.rotation))
                + cost(&object.scale, theirs.map(|t| &t.scale));
            if let Some(skeleton) = &object.skeleton {
                let their_skeleton = theirs.and_then(|t| t.skeleton.as_ref());
                bytes += cost(&skeleton.root_translation, their_skeleton.map(|s| &s.root_translation));
                for (c, constraint) in skeleton.ik_constraints.iter().enumerate() {
                    let theirs = their_skeleton.and_then(|s| s.ik_constraints.get(c));
                    bytes += cost(&constraint.target, theirs.map(|t| &t.target))
                        + cost(&constraint.blend, theirs.map(|t| &t.blend));
                }
                for (j, joint) in skeleton.joints.iter().enumerate() {
                    let their_joint = their_skeleton.and_then(|s| s.joints.get(j));
                    bytes += cost(&joint.translation, their_joint.map(|t| &t.translation))
                        + cost(&joint.rotation, their_joint.map(|t| &t.rotation))
                        + cost(&joint.scale, their_joint.map(|t| &t.scale));
                }
            }
        }
        for (l, light) in self.lights.iter().enumerate() {
            let theirs = other.lights.get(l);
            bytes += light.attributes.key_bytes_not_shared_with(theirs.map(|t| &t.attributes));
            bytes += cost(&light.position, theirs.map(|t| &t.position))
                + cost(&light.direction, theirs.map(|t| &t.direction))
                + cost(&light.colour, theirs.map(|t| &t.colour))
                + cost(&light.intensity, theirs.map(|t| &t.intensity));
        }
        for (c, camera) in self.cameras.iter().enumerate() {
            let theirs = other.cameras.get(c);
            bytes += cost(&camera.translation, theirs.map(|t| &t.translation))
                + cost(&camera.rotation, theirs.map(|t| &t.rotation))
                + cost(&camera.lens, theirs.map(|t| &t.lens));
            if let Some(aim) = &camera.aim {
                bytes += cost(&aim.roll, theirs.and_then(|t| t.aim.as_ref()).map(|a| &a.roll));
            }
        }
        bytes
    }
}

impl Scene {
    /// The index of the camera named `name`.
    #[must_use]
    pub fn camera_index(&self, name: &str) -> Option<usize> {
        self.cameras.iter().position(|c| c.name == name)
    }

    /// The camera that is active at `frame`: the camera of the last marker at or before
    /// `frame` that is bound to an existing camera; before any, the camera named by
    /// `active_camera`, else the first camera. `None` for a scene without cameras.
    #[must_use]
    pub fn active_camera_at(&self, frame: f64) -> Option<usize> {
        let from_marker = self
            .markers
            .iter()
            .filter(|m| f64::from(m.frame) <= frame)
            .filter_map(|m| Some((m.frame, self.camera_index(m.camera.as_deref()?)?)))
            .max_by_key(|&(f, _)| f)
            .map(|(_, c)| c);
        from_marker
            .or_else(|| self.active_camera.as_deref().and_then(|n| self.camera_index(n)))
            .or_else(|| (!self.cameras.is_empty()).then_some(0))
    }
}

#[cfg(test)]
mod preview_range_tests {
    use super::*;

    #[test]
    fn playback_runs_over_the_preview_range_cut_to_the_frame_range() {
        let range = |start, end| FrameRange { start, end };
        let mut scene = Scene { frame_range: range(0, 90), ..Scene::default() };
        assert_eq!(scene.playback_range(), range(0, 90), "no preview range");
        scene.preview_range = Some(range(20, 40));
        assert_eq!(scene.playback_range(), range(20, 40));
        scene.preview_range = Some(range(-10, 40));
        assert_eq!(scene.playback_range(), range(0, 40), "cut to the frame range");
        scene.preview_range = Some(range(100, 120));
        assert_eq!(scene.playback_range(), range(0, 90), "outside the frame range: ignored");
        scene.preview_range = Some(range(40, 20));
        assert_eq!(scene.playback_range(), range(0, 90), "empty: ignored");
        assert_eq!(scene.problems().len(), 1, "and reported by validation");
    }
}
