//! Scene format version 1, frozen: the document types as version 1 wrote them, and their
//! conversion to the current [`Scene`].
//!
//! Version 2 gave joints animated translation and scale beside their rotation (full joint
//! poses, for imported characters). A version-1 joint had only a rotation, so it becomes a
//! joint with zero translation and unit scale, which evaluates to the same pose.

use glam::{Quat, Vec3};
use keyrig_core::{Animated, Camera, DeformerSettings, FrameRange, Light, MeshSource, Scene};
use serde::Deserialize;

/// A version-1 document: version first, then the scene.
#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
pub(crate) struct SceneFileV1 {
    #[allow(dead_code, reason = "checked before this struct is read")]
    version: u32,
    scene: SceneV1,
}

impl SceneFileV1 {
    /// The scene as the current version holds it.
    pub(crate) fn into_current(self) -> Scene {
        let s = self.scene;
        Scene {
            fps: s.fps,
            frame_range: s.frame_range,
            ambient: s.ambient,
            objects: s.objects.into_iter().map(ObjectV1::into_current).collect(),
            lights: s.lights,
            camera: s.camera,
            ..Scene::default()
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SceneV1 {
    fps: f64,
    frame_range: FrameRange,
    #[serde(default = "default_ambient")]
    ambient: Vec3,
    #[serde(default)]
    objects: Vec<ObjectV1>,
    #[serde(default)]
    lights: Vec<Light>,
    #[serde(default)]
    camera: Camera,
}

fn default_ambient() -> Vec3 {
    Vec3::splat(0.1)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct ObjectV1 {
    name: String,
    translation: Animated<Vec3>,
    rotation: Animated<Quat>,
    scale: Animated<Vec3>,
    #[serde(default)]
    mesh: Option<MeshSource>,
    #[serde(default)]
    skeleton: Option<SkeletonV1>,
    #[serde(default)]
    deformer: DeformerSettings,
}

impl ObjectV1 {
    fn into_current(self) -> keyrig_core::Object {
        keyrig_core::Object {
            name: self.name,
            translation: self.translation,
            rotation: self.rotation,
            rotation_mode: keyrig_core::RotationMode::default(),
            rotation_euler: None,
            scale: self.scale,
            mesh: self.mesh,
            skeleton: self.skeleton.map(|s| keyrig_core::Skeleton {
                joints: s.joints.into_iter().map(JointV1::into_current).collect(),
                root_translation: s.root_translation,
                ik_constraints: Vec::new(),
            }),
            deformer: self.deformer,
            attributes: keyrig_core::ObjectAttributes::default(),
            action: None,
            clip_tracks: Vec::new(),
            constraints: Vec::new(),
        }
    }
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct SkeletonV1 {
    joints: Vec<JointV1>,
    #[serde(default = "zero_translation")]
    root_translation: Animated<Vec3>,
}

fn zero_translation() -> Animated<Vec3> {
    Animated::constant(Vec3::ZERO)
}

#[derive(Deserialize)]
#[serde(deny_unknown_fields)]
struct JointV1 {
    name: String,
    parent: Option<usize>,
    rest_translation: Vec3,
    rest_rotation: Quat,
    rotation: Animated<Quat>,
}

impl JointV1 {
    fn into_current(self) -> keyrig_core::Joint {
        keyrig_core::Joint {
            rotation: self.rotation,
            ..keyrig_core::Joint::new(self.name, self.parent, self.rest_translation, self.rest_rotation)
        }
    }
}
