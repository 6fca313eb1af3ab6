//! From a keyrig `Scene` and a time to a [`FrameInput`]: the glue the `keyrig render` command
//! and the editor share.
//!
//! [`SceneRig::new`] does the once-per-scene work (validates every track, builds the meshes,
//! skeletons and bones-blending bindings); [`SceneRig::frame`] samples the tracks at a time,
//! evaluates each skeleton's joint palette and fills in lights, overlays and draw items.
//! The editor, which has its own transient pose overrides, can evaluate the objects itself and
//! call [`SceneRig::frame_from_states`] instead.
//!
//! Vertex-animated meshes (Quake 2 MD2) come in as a [`MorphMesh`] (every frame's vertices
//! and the named clips) through [`SceneRig::with_loaded`]; an object's `MeshSource::File`
//! `clip` and `fps` choose what plays: scene time `t` shows clip frame `f = t · fps`, looping
//! (the last frame morphs back into the first), drawn by the GPU morph pass as the blend of
//! frames `⌊f⌋` and `⌊f⌋ + 1` with weight `f − ⌊f⌋` ([`MorphMesh::blend_at`]).

use std::collections::HashMap;
use std::ops::Range;

use glam::{Mat4, Quat, Vec3};
use keyrig_core::{AnimatedTrack, Camera, DeformerKind, MeshSource, Scene, TrackError};
use keyrig_skin::{
    mesh_for, BlendZone, JointPalette, MeshBindings, Pose, RestSkeleton, ScenePoseSampler, SkinError,
    SkinnedMesh,
};
use thiserror::Error;

use crate::overlay::{grid_spacing_for, LightGizmo, MotionPath, SkeletonOverlay};
use crate::renderer::{Deform, DrawItem, FrameInput, LightInput, MeshData, MeshId, RenderStyle, Renderer};
use crate::skinning::{joint_poses, OwnedSkinInput, SkinnedVertex};
use crate::RenderError;

/// Most samples a motion path takes over the frame range.
const MAX_PATH_SAMPLES: i64 = 2000;

/// Albedo of the n-th mesh object (linear RGB), cycling.
const OBJECT_COLOURS: [Vec3; 4] = [
    Vec3::new(0.72, 0.62, 0.55),
    Vec3::new(0.35, 0.55, 0.8),
    Vec3::new(0.5, 0.75, 0.4),
    Vec3::new(0.8, 0.7, 0.3),
];

/// What went wrong turning a scene into frames; every variant names the place in the scene.
#[derive(Debug, Error)]
pub enum SceneFrameError {
    #[error("{path}: {source}")]
    Track { path: String, source: TrackError },
    #[error("{path}: {source}")]
    Skin { path: String, source: SkinError },
    #[error("{path}: {source}")]
    Render { path: String, source: RenderError },
    #[error(
        "objects[{object}] ({name}): the mesh file `{file}` was not loaded; pass it to \
         SceneRig::with_meshes (model files are loaded by keyrig-io)"
    )]
    MeshNotLoaded { object: usize, name: String, file: String },
    #[error("{path}: {message}")]
    Invalid { path: String, message: String },
    #[error("{path}: {source}")]
    Morph { path: String, source: MorphError },
}

/// What is wrong with a [`MorphMesh`] or a request to play it.
#[derive(Debug, Clone, PartialEq, Error)]
pub enum MorphError {
    #[error("the mesh has no frames")]
    NoFrames,
    #[error("frame {frame} has {len} vertices, frame 0 has {expected}")]
    FrameLength { frame: usize, len: usize, expected: usize },
    #[error("{count} triangle indices is not a multiple of 3")]
    IndexCount { count: usize },
    #[error("triangle index {index} is out of range (the mesh has {vertices} vertices)")]
    Index { index: u32, vertices: usize },
    #[error("clip `{name}` covers frames {start}..{end}, outside the {frames} frames (or empty)")]
    ClipRange { name: String, start: usize, end: usize, frames: usize },
    #[error("no clip named `{name}` (clips: {available})")]
    NoSuchClip { name: String, available: String },
    #[error("playback rate must be finite and > 0 frames per second, got {0}")]
    BadFps(f64),
    #[error("time must be finite, got {0}")]
    BadTime(f64),
}

/// A named run of consecutive frames of a [`MorphMesh`] (an MD2 clip: `stand`, `run`, …).
#[derive(Clone, Debug, PartialEq, Eq)]
pub struct MorphClip {
    pub name: String,
    /// Indices into [`MorphMesh::frames`].
    pub frames: Range<usize>,
}

/// Which two frames of a morph mesh are blended, and with what weight of the second.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MorphBlend {
    pub frame_a: u32,
    pub frame_b: u32,
    pub t: f32,
}

/// A vertex-animated mesh (vertex morphing, as MD2 stores it): the same triangles over
/// frames of positions and normals, grouped into named clips.
///
/// # Invariants
/// At least one frame; every frame has as many vertices as frame 0; indices are triangles
/// of vertices that exist; every clip is a non-empty range of existing frames. Checked by
/// [`MorphMesh::new`].
#[derive(Clone, Debug, PartialEq)]
pub struct MorphMesh {
    frames: Vec<Vec<SkinnedVertex>>,
    indices: Vec<u32>,
    clips: Vec<MorphClip>,
}

impl MorphMesh {
    /// A morph mesh from its frames, triangles and clips.
    ///
    /// # Errors
    /// A broken invariant (see the type's documentation).
    pub fn new(
        frames: Vec<Vec<SkinnedVertex>>,
        indices: Vec<u32>,
        clips: Vec<MorphClip>,
    ) -> Result<Self, MorphError> {
        let Some(first) = frames.first() else { return Err(MorphError::NoFrames) };
        let expected = first.len();
        if let Some((frame, f)) = frames.iter().enumerate().find(|(_, f)| f.len() != expected) {
            return Err(MorphError::FrameLength { frame, len: f.len(), expected });
        }
        if !indices.len().is_multiple_of(3) {
            return Err(MorphError::IndexCount { count: indices.len() });
        }
        if let Some(&index) = indices.iter().find(|&&i| i as usize >= expected) {
            return Err(MorphError::Index { index, vertices: expected });
        }
        if let Some(clip) = clips.iter().find(|c| c.frames.is_empty() || c.frames.end > frames.len()) {
            return Err(MorphError::ClipRange {
                name: clip.name.clone(),
                start: clip.frames.start,
                end: clip.frames.end,
                frames: frames.len(),
            });
        }
        Ok(MorphMesh { frames, indices, clips })
    }

    /// Every frame's vertices.
    #[must_use]
    pub fn frames(&self) -> &[Vec<SkinnedVertex>] {
        &self.frames
    }

    /// Triangles, three vertex indices each.
    #[must_use]
    pub fn indices(&self) -> &[u32] {
        &self.indices
    }

    /// The named clips, in frame order.
    #[must_use]
    pub fn clips(&self) -> &[MorphClip] {
        &self.clips
    }

    /// Vertices per frame.
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.frames[0].len()
    }

    /// The frames clip `clip` plays; every frame for `None`.
    ///
    /// # Errors
    /// [`MorphError::NoSuchClip`] listing the clips there are.
    pub fn clip_frames(&self, clip: Option<&str>) -> Result<Range<usize>, MorphError> {
        match clip {
            None => Ok(0..self.frames.len()),
            Some(name) => {
                self.clips.iter().find(|c| c.name == name).map(|c| c.frames.clone()).ok_or_else(|| {
                    MorphError::NoSuchClip {
                        name: name.to_owned(),
                        available: self.clips.iter().map(|c| c.name.as_str()).collect::<Vec<_>>().join(", "),
                    }
                })
            }
        }
    }

    /// Seconds one loop of `clip` lasts at `fps`: frames / fps (looping, the last frame morphs
    /// back into the first).
    ///
    /// # Errors
    /// An unknown clip or a rate that is not finite and > 0.
    pub fn clip_duration(&self, clip: Option<&str>, fps: f64) -> Result<f64, MorphError> {
        let frames = self.clip_frames(clip)?;
        if !(fps.is_finite() && fps > 0.0) {
            return Err(MorphError::BadFps(fps));
        }
        Ok(frames.len() as f64 / fps)
    }

    /// The frames to blend at `time` seconds when `clip` plays at `fps`, looping:
    /// f = (time · fps) mod n over the clip's n frames; frames ⌊f⌋ and ⌊f⌋ + 1 (the clip's
    /// first after its last) with weight t = f − ⌊f⌋. A pure function of its inputs.
    ///
    /// # Errors
    /// An unknown clip, a rate that is not finite and > 0, a time that is not finite.
    pub fn blend_at(&self, clip: Option<&str>, fps: f64, time: f64) -> Result<MorphBlend, MorphError> {
        let frames = self.clip_frames(clip)?;
        if !(fps.is_finite() && fps > 0.0) {
            return Err(MorphError::BadFps(fps));
        }
        let f = time * fps;
        if !f.is_finite() {
            return Err(MorphError::BadTime(time));
        }
        let n = frames.len();
        let f = f.rem_euclid(n as f64);
        let a = (f.floor() as usize).min(n - 1);
        let b = (a + 1) % n;
        let t = ((f - a as f64) as f32).clamp(0.0, 1.0);
        Ok(MorphBlend { frame_a: (frames.start + a) as u32, frame_b: (frames.start + b) as u32, t })
    }

    /// Positions and normals of `blend` computed on the CPU (the same linear blend as the GPU
    /// morph pass; normals renormalized).
    #[must_use]
    pub fn blended(&self, blend: MorphBlend) -> (Vec<Vec3>, Vec<Vec3>) {
        let last = self.frames.len() - 1;
        let a = &self.frames[(blend.frame_a as usize).min(last)];
        let b = &self.frames[(blend.frame_b as usize).min(last)];
        a.iter()
            .zip(b)
            .map(|(va, vb)| {
                let n = va.normal().lerp(vb.normal(), blend.t);
                (va.position().lerp(vb.position(), blend.t), n.normalize_or(va.normal()))
            })
            .unzip()
    }
}

fn track_err(path: String) -> impl FnOnce(TrackError) -> SceneFrameError {
    move |source| SceneFrameError::Track { path, source }
}

fn skin_err(path: String) -> impl FnOnce(SkinError) -> SceneFrameError {
    move |source| SceneFrameError::Skin { path, source }
}

/// What is selected in the viewport (highlighted; its motion path is drawn).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub enum Selection {
    #[default]
    None,
    Object(usize),
    Joint {
        object: usize,
        joint: usize,
    },
    Light(usize),
}

/// View settings that are not part of the scene.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ViewOptions {
    pub style: RenderStyle,
    /// Overrides every object's deformer when set.
    pub deformer: Option<DeformerKind>,
    pub grid: bool,
    pub skeletons: bool,
    /// Draw the motion path of the selected object or joint.
    pub motion_path: bool,
    /// Draw lights as gizmos.
    pub lights: bool,
    pub selection: Selection,
    /// Replaces the scene's camera when set (the editor's orbit camera).
    pub camera: Option<Camera>,
    /// Near and far planes fitted to the scene (view-space distances); `None`: from the
    /// camera's orbit distance.
    pub depth_range: Option<[f32; 2]>,
}

impl Default for ViewOptions {
    fn default() -> Self {
        ViewOptions {
            style: RenderStyle::Solid,
            deformer: None,
            grid: true,
            skeletons: true,
            motion_path: true,
            lights: true,
            selection: Selection::None,
            camera: None,
            depth_range: None,
        }
    }
}

struct MeshRig {
    mesh: SkinnedMesh,
    bindings: MeshBindings,
}

/// A morph mesh and what of it plays.
struct MorphRig {
    mesh: MorphMesh,
    clip: Option<String>,
    fps: f64,
}

struct ObjectRig {
    translation: AnimatedTrack<Vec3>,
    rotation: AnimatedTrack<Quat>,
    scale: AnimatedTrack<Vec3>,
    mesh: Option<MeshRig>,
    morph: Option<MorphRig>,
    skeleton: Option<ScenePoseSampler>,
    rest: Option<RestSkeleton>,
    deformer: DeformerKind,
    colour: Vec3,
}

struct LightRig {
    kind: keyrig_core::LightKind,
    enabled: bool,
    position: AnimatedTrack<Vec3>,
    direction: AnimatedTrack<Vec3>,
    colour: AnimatedTrack<Vec3>,
    intensity: AnimatedTrack<f32>,
}

/// The evaluated state of one object at a time, as [`SceneRig::frame_from_states`] takes it.
#[derive(Clone, Debug, PartialEq)]
pub struct ObjectState {
    /// World from object (T·R·S).
    pub world_from_model: Mat4,
    /// The skeleton's pose (one rotation per joint, root translation); `None` when the object
    /// has no skeleton.
    pub pose: Option<Pose>,
}

/// A scene prepared for rendering frames.
pub struct SceneRig {
    scene: Scene,
    objects: Vec<ObjectRig>,
    lights: Vec<LightRig>,
}

impl SceneRig {
    /// Prepares a scene whose meshes are all procedural.
    ///
    /// # Errors
    /// An invalid track, skeleton or mesh binding (with its path in the scene), or a mesh file
    /// (see [`SceneRig::with_meshes`]).
    pub fn new(scene: &Scene) -> Result<Self, SceneFrameError> {
        Self::with_meshes(scene, &HashMap::new())
    }

    /// Prepares a scene; `loaded` gives the meshes of objects whose mesh is a file, by object
    /// index. A loaded mesh keeps its own rest skeleton (e.g. a glTF file's inverse bind
    /// matrices) for skinning; the object's scene skeleton, whose tracks pose it, must list the
    /// same joints in the same order.
    ///
    /// # Errors
    /// As [`SceneRig::new`]; [`SceneFrameError::MeshNotLoaded`] for a file mesh missing from
    /// `loaded`.
    pub fn with_meshes(scene: &Scene, loaded: &HashMap<usize, SkinnedMesh>) -> Result<Self, SceneFrameError> {
        Self::with_loaded(scene, loaded, &HashMap::new())
    }

    /// Prepares a scene whose file meshes are skinned (`loaded`) or vertex-animated
    /// (`morphs`, e.g. MD2 models), by object index. A morph object plays its
    /// `MeshSource::File` `clip` (every frame when `None`) at its `fps`
    /// ([`keyrig_core::MD2_DEFAULT_FPS`] when `None`).
    ///
    /// # Errors
    /// As [`SceneRig::with_meshes`]; [`SceneFrameError::Morph`] for a clip the mesh does not
    /// have or a bad rate, with the field's path.
    pub fn with_loaded(
        scene: &Scene,
        loaded: &HashMap<usize, SkinnedMesh>,
        morphs: &HashMap<usize, MorphMesh>,
    ) -> Result<Self, SceneFrameError> {
        if !(scene.fps.is_finite() && scene.fps > 0.0) {
            return Err(SceneFrameError::Invalid {
                path: "fps".into(),
                message: format!("{} is not > 0", scene.fps),
            });
        }
        let mut objects = Vec::with_capacity(scene.objects.len());
        let mut mesh_count = 0usize;
        for (i, object) in scene.objects.iter().enumerate() {
            let at = |field: &str| format!("objects[{i}].{field}");
            let translation =
                AnimatedTrack::new(&object.translation).map_err(track_err(at("translation")))?;
            let rotation = AnimatedTrack::new(&object.rotation).map_err(track_err(at("rotation")))?;
            let scale = AnimatedTrack::new(&object.scale).map_err(track_err(at("scale")))?;
            let (skeleton, rest) = match &object.skeleton {
                Some(skeleton) => {
                    let sampler = ScenePoseSampler::new(skeleton).map_err(|e| match e {
                        SkinError::JointTrack { joint, property, source, .. } => {
                            track_err(at(&format!("skeleton.joints[{joint}].{property}")))(source)
                        }
                        SkinError::RootTranslationTrack(source) => {
                            track_err(at("skeleton.root_translation"))(source)
                        }
                        other => skin_err(at("skeleton"))(other),
                    })?;
                    let rest = RestSkeleton::from_scene(skeleton).map_err(skin_err(at("skeleton")))?;
                    (Some(sampler), Some(rest))
                }
                None => (None, None),
            };
            let morph = match (&object.mesh, morphs.get(&i)) {
                (Some(MeshSource::File { clip, fps, .. }), Some(mesh)) => {
                    let fps = fps.unwrap_or(keyrig_core::MD2_DEFAULT_FPS);
                    if !(fps.is_finite() && fps > 0.0) {
                        return Err(SceneFrameError::Morph {
                            path: at("mesh.fps"),
                            source: MorphError::BadFps(fps),
                        });
                    }
                    mesh.clip_frames(clip.as_deref())
                        .map_err(|source| SceneFrameError::Morph { path: at("mesh.clip"), source })?;
                    mesh_count += 1;
                    Some(MorphRig { mesh: mesh.clone(), clip: clip.clone(), fps })
                }
                _ => None,
            };
            let mesh = match &object.mesh {
                None => None,
                Some(_) if morph.is_some() => None,
                Some(source) => {
                    let mesh = match source {
                        MeshSource::Procedural(kind) => match &rest {
                            Some(rest) => mesh_for(*kind)
                                .fit_to_skeleton(rest.clone())
                                .map_err(skin_err(at("mesh (bound to the object's skeleton)")))?,
                            None => mesh_for(*kind),
                        },
                        // A loaded mesh keeps its own skeleton (a glTF file's inverse bind
                        // matrices); the scene skeleton must have its joints in the same order.
                        MeshSource::File { path, .. } => match loaded.get(&i) {
                            Some(mesh) => {
                                if let Some(rest) = &rest {
                                    if rest.len() != mesh.skeleton.len() {
                                        return Err(SceneFrameError::Invalid {
                                            path: at("skeleton"),
                                            message: format!(
                                                "{} joints, but the mesh from `{path}` is bound to {}",
                                                rest.len(),
                                                mesh.skeleton.len()
                                            ),
                                        });
                                    }
                                }
                                mesh.clone()
                            }
                            None => {
                                return Err(SceneFrameError::MeshNotLoaded {
                                    object: i,
                                    name: object.name.clone(),
                                    file: path.clone(),
                                })
                            }
                        },
                    };
                    let zone =
                        BlendZone::from_settings(&object.deformer).map_err(skin_err(at("deformer")))?;
                    let bindings = mesh.bindings(zone).map_err(skin_err(at("mesh")))?;
                    mesh_count += 1;
                    Some(MeshRig { mesh, bindings })
                }
            };
            objects.push(ObjectRig {
                translation,
                rotation,
                scale,
                mesh,
                morph,
                skeleton,
                rest,
                deformer: object.deformer.kind,
                colour: OBJECT_COLOURS[(mesh_count.max(1) - 1) % OBJECT_COLOURS.len()],
            });
        }
        let lights = scene
            .lights
            .iter()
            .enumerate()
            .map(|(i, light)| {
                let at = |field: &str| format!("lights[{i}].{field}");
                Ok(LightRig {
                    kind: light.kind,
                    enabled: light.enabled,
                    position: AnimatedTrack::new(&light.position).map_err(track_err(at("position")))?,
                    direction: AnimatedTrack::new(&light.direction).map_err(track_err(at("direction")))?,
                    colour: AnimatedTrack::new(&light.colour).map_err(track_err(at("colour")))?,
                    intensity: AnimatedTrack::new(&light.intensity).map_err(track_err(at("intensity")))?,
                })
            })
            .collect::<Result<Vec<_>, SceneFrameError>>()?;
        Ok(SceneRig { scene: scene.clone(), objects, lights })
    }

    /// The scene this rig was built from.
    #[must_use]
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// Seconds at a frame number.
    #[must_use]
    pub fn time_of_frame(&self, frame: f64) -> f64 {
        frame / self.scene.fps
    }

    /// Uploads every object's mesh to `renderer`, with the object's index as its [`MeshId`].
    ///
    /// # Errors
    /// [`SceneFrameError::Render`] naming the object.
    pub fn upload(&self, renderer: &mut Renderer) -> Result<(), SceneFrameError> {
        for (i, object) in self.objects.iter().enumerate() {
            if let Some(morph) = &object.morph {
                renderer
                    .upload_mesh(
                        i as MeshId,
                        &MeshData::Morph { frames: &morph.mesh.frames, indices: &morph.mesh.indices },
                    )
                    .map_err(|source| SceneFrameError::Render {
                        path: format!("objects[{i}].mesh"),
                        source,
                    })?;
                continue;
            }
            let Some(rig) = &object.mesh else { continue };
            let input = OwnedSkinInput::from_skinned_mesh(&rig.mesh, &rig.bindings);
            renderer
                .upload_mesh(
                    i as MeshId,
                    &MeshData::Skinned { skin: input.as_input(), indices: &rig.mesh.indices },
                )
                .map_err(|source| SceneFrameError::Render { path: format!("objects[{i}].mesh"), source })?;
        }
        Ok(())
    }

    /// Every object's state at `time` seconds, from the scene's tracks.
    #[must_use]
    pub fn object_states(&self, time: f64) -> Vec<ObjectState> {
        (0..self.objects.len()).map(|i| self.object_states_one(i, time)).collect()
    }

    /// The enabled lights at `time` seconds.
    #[must_use]
    pub fn lights_at(&self, time: f64) -> Vec<LightInput> {
        self.lights
            .iter()
            .filter(|l| l.enabled)
            .map(|l| LightInput {
                kind: l.kind,
                position: l.position.sample(time),
                direction: l.direction.sample(time),
                colour: l.colour.sample(time),
                intensity: l.intensity.sample(time),
            })
            .collect()
    }

    /// The frame at `time` seconds, from the scene's tracks.
    ///
    /// # Errors
    /// A pose that cannot be evaluated (e.g. a zero quaternion), with the object's path.
    pub fn frame(&self, time: f64, view: &ViewOptions) -> Result<FrameInput, SceneFrameError> {
        let states = self.object_states(time);
        let mut frame = self.frame_from_states(&states, self.lights_at(time), view, time)?;
        if view.motion_path {
            if let Some(path) = self.motion_path(view.selection, time)? {
                frame.motion_paths.push(path);
            }
        }
        if view.lights {
            frame.light_gizmos = self.light_gizmos(view.selection, time);
        }
        Ok(frame)
    }

    /// Gizmos of the enabled lights at `time` seconds (the selected one highlighted).
    #[must_use]
    pub fn light_gizmos(&self, selection: Selection, time: f64) -> Vec<LightGizmo> {
        self.lights
            .iter()
            .enumerate()
            .filter(|(_, l)| l.enabled)
            .map(|(i, l)| LightGizmo {
                kind: l.kind,
                position: l.position.sample(time),
                direction: l.direction.sample(time),
                selected: selection == Selection::Light(i),
            })
            .collect()
    }

    /// The frame for object states evaluated elsewhere (the editor's, with its pose overrides);
    /// `time` (seconds) places vertex-animated objects in their clips. Motion paths and light
    /// gizmos are not added here; see [`SceneRig::motion_path`] and
    /// [`SceneRig::light_gizmos`].
    ///
    /// # Errors
    /// A state list of the wrong length, a pose that cannot be evaluated or a time that is not
    /// finite while a morph mesh plays.
    pub fn frame_from_states(
        &self,
        states: &[ObjectState],
        lights: Vec<LightInput>,
        view: &ViewOptions,
        time: f64,
    ) -> Result<FrameInput, SceneFrameError> {
        if states.len() != self.objects.len() {
            return Err(SceneFrameError::Invalid {
                path: "objects".into(),
                message: format!("{} object states for {} objects", states.len(), self.objects.len()),
            });
        }
        let camera = view.camera.unwrap_or(self.scene.camera);
        let mut frame = FrameInput::new(camera);
        frame.depth_range = view.depth_range;
        frame.style = view.style;
        frame.ambient = self.scene.ambient;
        frame.lights = lights;
        frame.grid_spacing = view.grid.then(|| grid_spacing_for(camera.distance));
        for (i, (object, state)) in self.objects.iter().zip(states).enumerate() {
            // Drawing uses the mesh's skeleton (for loaded meshes: the file's inverse bind
            // matrices); without a mesh, the scene skeleton alone gives the overlay.
            let skeleton = object.mesh.as_ref().map(|rig| &rig.mesh.skeleton).or(object.rest.as_ref());
            let palette = match (skeleton, &state.pose) {
                (Some(skeleton), Some(pose)) => Some(
                    JointPalette::new(skeleton, pose)
                        .map_err(skin_err(format!("objects[{i}].skeleton (pose)")))?,
                ),
                _ => None,
            };
            let object_selected = matches!(view.selection, Selection::Object(o) if o == i);
            if let Some(morph) = &object.morph {
                let blend =
                    morph.mesh.blend_at(morph.clip.as_deref(), morph.fps, time).map_err(|source| {
                        SceneFrameError::Morph { path: format!("objects[{i}].mesh"), source }
                    })?;
                frame.items.push(DrawItem {
                    mesh: i as MeshId,
                    world_from_model: state.world_from_model,
                    deform: Deform::Morph { frame_a: blend.frame_a, frame_b: blend.frame_b, t: blend.t },
                    colour: object.colour,
                    selected: object_selected,
                });
            }
            if let Some(rig) = &object.mesh {
                let palette = match &palette {
                    Some(p) => p.clone(),
                    None => JointPalette::new(&rig.mesh.skeleton, &Pose::rest(rig.mesh.skeleton.len()))
                        .map_err(skin_err(format!("objects[{i}].mesh (rest pose)")))?,
                };
                frame.items.push(DrawItem {
                    mesh: i as MeshId,
                    world_from_model: state.world_from_model,
                    deform: Deform::Skin {
                        deformer: view.deformer.unwrap_or(object.deformer),
                        joints: joint_poses(&palette),
                    },
                    colour: object.colour,
                    selected: object_selected,
                });
            }
            if view.skeletons {
                if let (Some(rest), Some(palette)) = (&object.rest, &palette) {
                    let joints = (0..rest.len())
                        .map(|j| state.world_from_model.transform_point3(palette.joint_position(j)))
                        .collect();
                    let selected = match view.selection {
                        Selection::Joint { object, joint } if object == i => Some(joint),
                        _ => None,
                    };
                    frame.skeletons.push(SkeletonOverlay {
                        joints,
                        parents: rest.parents().to_vec(),
                        selected,
                    });
                }
            }
        }
        Ok(frame)
    }

    /// The motion path of the selected object (its origin) or joint over the frame range, with
    /// markers at its keys and at `time`; `None` when nothing path-worthy is selected.
    ///
    /// # Errors
    /// A pose that cannot be evaluated.
    pub fn motion_path(
        &self,
        selection: Selection,
        time: f64,
    ) -> Result<Option<MotionPath>, SceneFrameError> {
        let (object, joint) = match selection {
            Selection::Object(o) => (o, None),
            Selection::Joint { object, joint } => (object, Some(joint)),
            Selection::None | Selection::Light(_) => return Ok(None),
        };
        let Some(rig) = self.objects.get(object) else { return Ok(None) };
        let scene_object = &self.scene.objects[object];
        let position_at = |t: f64| -> Result<Option<Vec3>, SceneFrameError> {
            let state = &self.object_states_one(object, t);
            match joint {
                None => Ok(Some(state.world_from_model.transform_point3(Vec3::ZERO))),
                Some(j) => {
                    let (Some(rest), Some(pose)) = (&rig.rest, &state.pose) else { return Ok(None) };
                    if j >= rest.len() {
                        return Ok(None);
                    }
                    let palette = JointPalette::new(rest, pose)
                        .map_err(skin_err(format!("objects[{object}].skeleton (pose)")))?;
                    Ok(Some(state.world_from_model.transform_point3(palette.joint_position(j))))
                }
            }
        };
        let range = self.scene.frame_range;
        let frames = i64::from(range.end) - i64::from(range.start);
        let step = (frames.max(1) as f64 / MAX_PATH_SAMPLES as f64).max(1.0);
        let mut points = Vec::new();
        let mut f = f64::from(range.start);
        while f <= f64::from(range.end) + 1e-9 {
            match position_at(self.time_of_frame(f))? {
                Some(p) => points.push(p),
                None => return Ok(None),
            }
            f += step;
        }
        let mut key_times: Vec<f64> = match joint {
            None => [
                scene_object.translation.track.keys.iter().map(|k| k.time).collect::<Vec<_>>(),
                scene_object.rotation.track.keys.iter().map(|k| k.time).collect(),
            ]
            .concat(),
            Some(j) => scene_object
                .skeleton
                .as_ref()
                .and_then(|s| s.joints.get(j))
                .map(|joint| {
                    let times =
                        |keys: &[keyrig_core::Key<Vec3>]| keys.iter().map(|k| k.time).collect::<Vec<_>>();
                    [
                        times(&joint.translation.track.keys),
                        joint.rotation.track.keys.iter().map(|k| k.time).collect(),
                        times(&joint.scale.track.keys),
                    ]
                    .concat()
                })
                .unwrap_or_default(),
        };
        key_times.sort_by(f64::total_cmp);
        key_times.dedup();
        let mut keys = Vec::with_capacity(key_times.len());
        for t in key_times {
            if let Some(p) = position_at(t)? {
                keys.push(p);
            }
        }
        Ok(Some(MotionPath { points, keys, current: position_at(time)? }))
    }

    fn object_states_one(&self, index: usize, time: f64) -> ObjectState {
        let object = &self.objects[index];
        ObjectState {
            world_from_model: Mat4::from_scale_rotation_translation(
                object.scale.sample(time),
                object.rotation.sample(time).normalize(),
                object.translation.sample(time),
            ),
            pose: object.skeleton.as_ref().map(|s| s.sample(time)),
        }
    }
}
