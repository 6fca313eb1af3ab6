//! From a keyrig `Scene` and a time to a [`FrameInput`]: the glue the `keyrig render` command
//! and the editor share.
//!
//! [`SceneRig`] holds the scene's [`SceneEvaluator`] (keyrig-eval: validated tracks, skeletons,
//! skinned meshes with their bindings, morph clips) and what only drawing needs (colours, the
//! vertices of morph meshes). [`SceneRig::upload`] sends vertex and index buffers once;
//! [`SceneRig::frame_from_state`] turns an evaluated [`SceneState`] into draw items — joint
//! palettes, morph frames, lights, overlays — without evaluating anything again. The editor
//! evaluates with its pose overrides and hands the state in; [`SceneRig::frame`] evaluates the
//! scene's own tracks.
//!
//! Vertex-animated meshes (Quake 2 MD2) come in as a [`MorphMesh`] (every frame's vertices
//! and the named clips) through [`SceneRig::with_loaded`]; an object's `MeshSource::File`
//! `clip` and `fps` choose what plays: scene time `t` shows clip frame `f = t · fps`, looping
//! (the last frame morphs back into the first), drawn by the GPU morph pass as the blend of
//! frames `⌊f⌋` and `⌊f⌋ + 1` with weight `f − ⌊f⌋` ([`MorphClips::blend_at`]).

use std::collections::HashMap;
use std::sync::Arc;

use glam::{Mat4, Vec2, Vec3};
use keyrig_core::{Camera, DeformerKind, Material, MeshSource, Scene, TrackError};
use keyrig_eval::morph::MorphClips;
pub use keyrig_eval::morph::{MorphBlend, MorphClip, MorphError};
use keyrig_eval::{LoadedMesh, ObjectState, Overrides, SceneEvaluator, SceneState};
use keyrig_skin::{SkinError, SkinnedMesh};
use thiserror::Error;

use crate::overlay::{grid_spacing_for, CameraGizmo, LightGizmo, MotionPath, SkeletonOverlay};
use crate::renderer::{
    Deform, DrawItem, FrameInput, Ghost, LightInput, MeshData, MeshId, RenderStyle, Renderer,
};
use crate::skinning::{joint_poses, OwnedSkinInput, SkinnedVertex};
use crate::RenderError;

/// Most samples a motion path takes over the frame range.
const MAX_PATH_SAMPLES: i64 = 2000;

/// The first mesh id of onion-skin ghosts ([`SceneRig::ghost_mesh`]).
pub const GHOST_MESHES: MeshId = 1 << 32;
/// The most ghosts one object can have.
pub const MAX_GHOSTS: usize = 16;

/// Albedo of the n-th mesh object (linear RGB), cycling.
const OBJECT_COLOURS: [Vec3; 4] = [
    Vec3::new(0.72, 0.62, 0.55),
    Vec3::new(0.35, 0.55, 0.8),
    Vec3::new(0.5, 0.75, 0.4),
    Vec3::new(0.8, 0.7, 0.3),
];

/// The colour the renderer gives the `drawn`-th drawn object (counting from 1) that has no
/// material: the palette, cycling.
#[must_use]
pub fn palette_colour(drawn: usize) -> Vec3 {
    OBJECT_COLOURS[(drawn.max(1) - 1) % OBJECT_COLOURS.len()]
}

/// The colour object `o` is drawn with when it has no material and no keyed colour
/// ([`palette_colour`] of its place among the objects the evaluator skins or morphs): what
/// *Animate colour* starts from, so the object keeps the colour it shows.
#[must_use]
pub fn object_palette_colour(eval: &SceneEvaluator, o: usize) -> Vec3 {
    let drawn = (0..=o).filter(|&i| eval.morph(i).is_some() || eval.skin(i).is_some()).count();
    palette_colour(drawn)
}

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
    clips: Arc<MorphClips>,
    /// One texture coordinate per vertex (the same in every frame).
    uvs: Option<Vec<Vec2>>,
    /// The model's look (an MD2 skin).
    material: Option<Arc<Material>>,
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
        let clips = Arc::new(MorphClips::new(frames.len(), clips)?);
        Ok(MorphMesh { frames, indices, clips, uvs: None, material: None })
    }

    /// The mesh with one texture coordinate per vertex (MD2: s / skin width, t / skin
    /// height) and the material that textures it.
    ///
    /// # Errors
    /// [`MorphError::UvCount`] when `uvs` does not have one entry per vertex.
    pub fn with_look(mut self, uvs: Vec<Vec2>, material: Option<Arc<Material>>) -> Result<Self, MorphError> {
        if uvs.len() != self.vertex_count() {
            return Err(MorphError::UvCount { count: uvs.len(), vertices: self.vertex_count() });
        }
        self.uvs = Some(uvs);
        self.material = material;
        Ok(self)
    }

    /// The mesh with its frames shown at their own times (a VRML/X3D
    /// `CoordinateInterpolator`; [`keyrig_eval::morph::MorphClips::with_key_times`]).
    ///
    /// # Errors
    /// [`MorphError::KeyTimes`] when the times do not fit the frames.
    pub fn with_key_times(mut self, times: Vec<f64>, period: Option<f64>) -> Result<Self, MorphError> {
        self.clips = Arc::new((*self.clips).clone().with_key_times(times, period)?);
        Ok(self)
    }

    /// Texture coordinates, one per vertex, when the mesh has them.
    #[must_use]
    pub fn uvs(&self) -> Option<&[Vec2]> {
        self.uvs.as_deref()
    }

    /// The mesh's material (an MD2 skin), when it has one.
    #[must_use]
    pub fn material(&self) -> Option<&Arc<Material>> {
        self.material.as_ref()
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
        self.clips.clips()
    }

    /// The clips with the frame count: what the scene evaluator plays.
    #[must_use]
    pub fn playback(&self) -> &Arc<MorphClips> {
        &self.clips
    }

    /// Vertices per frame.
    #[must_use]
    pub fn vertex_count(&self) -> usize {
        self.frames[0].len()
    }

    /// See [`MorphClips::clip_frames`].
    ///
    /// # Errors
    /// An unknown clip.
    pub fn clip_frames(&self, clip: Option<&str>) -> Result<std::ops::Range<usize>, MorphError> {
        self.clips.clip_frames(clip)
    }

    /// See [`MorphClips::clip_duration`].
    ///
    /// # Errors
    /// An unknown clip or a bad rate.
    pub fn clip_duration(&self, clip: Option<&str>, fps: f64) -> Result<f64, MorphError> {
        self.clips.clip_duration(clip, fps)
    }

    /// See [`MorphClips::blend_at`].
    ///
    /// # Errors
    /// An unknown clip, a bad rate or time.
    pub fn blend_at(&self, clip: Option<&str>, fps: f64, time: f64) -> Result<MorphBlend, MorphError> {
        self.clips.blend_at(clip, fps, time)
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

/// A scene item that can be selected: an object, a joint of an object's skeleton, or a light.
/// The editor's selection and what the renderer highlights (and draws the motion path of)
/// are this one type; `None` where nothing is selected.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
pub enum Selected {
    Object(usize),
    Joint {
        object: usize,
        joint: usize,
    },
    Light(usize),
    /// A scene camera (`Scene::cameras`).
    Camera(usize),
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
    pub selection: Option<Selected>,
    /// Replaces the scene's camera when set (the editor's orbit camera).
    pub camera: Option<Camera>,
    /// Near and far planes fitted to the scene (view-space distances); `None`: from the
    /// camera's orbit distance.
    pub depth_range: Option<[f32; 2]>,
    /// Draw materials (base colour and texture: glTF base colour, MD2 skins); `false` draws
    /// every object in its plain per-object colour.
    pub textures: bool,
    /// Look through this scene camera (an index of `Scene::cameras`) instead of the orbit
    /// camera.
    pub look_through: Option<usize>,
    /// Draw scene cameras as frustums (all but the one looked through).
    pub cameras: bool,
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
            selection: None,
            camera: None,
            depth_range: None,
            textures: true,
            look_through: None,
            cameras: true,
        }
    }
}

/// Drawing data of one object beside its evaluation.
struct ObjectDraw {
    colour: Vec3,
    /// The object's material: its base colour replaces `colour`, its texture multiplies it.
    material: Option<Arc<Material>>,
    /// The vertices of a vertex-animated mesh (its clips play through the evaluator).
    morph: Option<Arc<MorphMesh>>,
}

/// A scene prepared for rendering frames: its [`SceneEvaluator`] and what drawing needs.
pub struct SceneRig {
    scene: Scene,
    eval: Arc<SceneEvaluator>,
    objects: Vec<ObjectDraw>,
}

impl SceneRig {
    /// Prepares a scene whose meshes are all procedural.
    ///
    /// # Errors
    /// See [`SceneRig::with_loaded`].
    pub fn new(scene: &Scene) -> Result<Self, SceneFrameError> {
        Self::with_meshes(scene, &HashMap::new())
    }

    /// Prepares a scene; `loaded` gives the meshes of objects whose mesh is a file, by object
    /// index. A loaded mesh keeps its own rest skeleton (e.g. a glTF file's inverse bind
    /// matrices) for skinning; the object's scene skeleton, whose tracks pose it, must list the
    /// same joints in the same order.
    ///
    /// # Errors
    /// See [`SceneRig::with_loaded`].
    pub fn with_meshes(scene: &Scene, loaded: &HashMap<usize, SkinnedMesh>) -> Result<Self, SceneFrameError> {
        Self::with_loaded(scene, loaded, &HashMap::new())
    }

    /// Prepares a scene whose file meshes are skinned (`loaded`) or vertex-animated
    /// (`morphs`, e.g. MD2 models), by object index, and refuses anything it cannot evaluate.
    /// A morph object plays its `MeshSource::File` `clip` (every frame when `None`) at its
    /// `fps` ([`keyrig_core::MD2_DEFAULT_FPS`] when `None`).
    ///
    /// # Errors
    /// `fps` not > 0; [`SceneFrameError::MeshNotLoaded`] for a file mesh missing from both
    /// maps; otherwise the first of the evaluator's problems (an invalid track, skeleton, mesh
    /// binding, clip or rate), with its path in the scene.
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
        for (i, object) in scene.objects.iter().enumerate() {
            if let Some(MeshSource::File { path, .. }) = &object.mesh {
                if !loaded.contains_key(&i) && !morphs.contains_key(&i) {
                    return Err(SceneFrameError::MeshNotLoaded {
                        object: i,
                        name: object.name.clone(),
                        file: path.clone(),
                    });
                }
            }
        }
        let rig = Self::lenient(scene, loaded, morphs);
        if let Some(problem) = rig.eval.problems().first() {
            return Err(SceneFrameError::Invalid {
                path: problem.path.clone(),
                message: problem.message.clone(),
            });
        }
        Ok(rig)
    }

    /// Prepares a scene as [`SceneRig::with_loaded`] does, but draws what it can: a channel
    /// whose keys are invalid holds its static value, an object whose mesh cannot be bound is
    /// not skinned, and a file mesh that is missing is not drawn ([`SceneRig::evaluator`]
    /// lists the problems). The editor draws scenes while they are being fixed.
    #[must_use]
    pub fn lenient(
        scene: &Scene,
        loaded: &HashMap<usize, SkinnedMesh>,
        morphs: &HashMap<usize, MorphMesh>,
    ) -> Self {
        let mut meshes: HashMap<usize, LoadedMesh> =
            loaded.iter().map(|(&o, m)| (o, LoadedMesh::Skinned(Arc::new(m.clone())))).collect();
        meshes.extend(morphs.iter().map(|(&o, m)| (o, LoadedMesh::Morph(Arc::clone(m.playback())))));
        let morphs = morphs.iter().map(|(&o, m)| (o, Arc::new(m.clone()))).collect();
        Self::with_evaluator(scene, Arc::new(SceneEvaluator::new(scene, &meshes)), &morphs)
    }

    /// A rig around an evaluator built elsewhere (the editor shares its own) for `scene`;
    /// `morphs` gives the vertices of the morph meshes the evaluator plays.
    #[must_use]
    pub fn with_evaluator(
        scene: &Scene,
        eval: Arc<SceneEvaluator>,
        morphs: &HashMap<usize, Arc<MorphMesh>>,
    ) -> Self {
        let mut drawn = 0usize;
        let objects = (0..scene.objects.len())
            .map(|o| {
                let morph = eval.morph(o).and_then(|_| morphs.get(&o).cloned());
                if morph.is_some() || eval.skin(o).is_some() {
                    drawn += 1;
                }
                let material = morph.as_ref().and_then(|m| m.material().cloned());
                ObjectDraw { colour: palette_colour(drawn), material, morph }
            })
            .collect();
        SceneRig { scene: scene.clone(), eval, objects }
    }

    /// The rig with materials for skinned objects, by object index (a morph mesh brings its
    /// own, [`MorphMesh::with_look`]; one given here replaces it). Call before
    /// [`SceneRig::upload`]; indices past the scene's objects are ignored.
    #[must_use]
    pub fn with_materials(mut self, materials: &HashMap<usize, Arc<Material>>) -> Self {
        for (&o, material) in materials {
            if let Some(object) = self.objects.get_mut(o) {
                object.material = Some(Arc::clone(material));
            }
        }
        self
    }

    /// The material object `object` is drawn with, if any.
    #[must_use]
    pub fn material(&self, object: usize) -> Option<&Arc<Material>> {
        self.objects.get(object)?.material.as_ref()
    }

    /// The scene this rig was built from.
    #[must_use]
    pub fn scene(&self) -> &Scene {
        &self.scene
    }

    /// The scene's evaluator: evaluate it (with overrides) and hand the state to
    /// [`SceneRig::frame_from_state`].
    #[must_use]
    pub fn evaluator(&self) -> &SceneEvaluator {
        &self.eval
    }

    /// Seconds at a frame number.
    #[must_use]
    pub fn time_of_frame(&self, frame: f64) -> f64 {
        frame / self.scene.fps
    }

    /// Uploads every object's mesh to `renderer`, with the object's index as its [`MeshId`]:
    /// vertex and index buffers go to the GPU here, once, and frames send only palettes,
    /// morph frames and uniforms.
    ///
    /// # Errors
    /// [`SceneFrameError::Render`] naming the object.
    pub fn upload(&self, renderer: &mut Renderer) -> Result<(), SceneFrameError> {
        self.upload_changed(renderer, None).map(|_| ())
    }

    /// Uploads the meshes that differ from those of `previous` (the rig this one replaces,
    /// whose meshes are on `renderer`) and returns how many it sent: an edit that changed no
    /// mesh, skeleton rest pose or deformer setting sends no vertex or index buffer again.
    /// Meshes are compared by identity (the evaluator shares what an edit did not rebuild).
    ///
    /// # Errors
    /// [`SceneFrameError::Render`] naming the object.
    pub fn upload_changed(
        &self,
        renderer: &mut Renderer,
        previous: Option<&SceneRig>,
    ) -> Result<usize, SceneFrameError> {
        let mut uploaded = 0;
        for (i, object) in self.objects.iter().enumerate() {
            if let Some(previous) = previous {
                let same_morph = match (&object.morph, previous.objects.get(i).and_then(|p| p.morph.as_ref()))
                {
                    (Some(a), Some(b)) => Arc::ptr_eq(a, b),
                    (None, None) => true,
                    _ => false,
                };
                let same_skin = match (self.eval.skin(i), previous.eval.skin(i)) {
                    (Some(a), Some(b)) => {
                        Arc::ptr_eq(&a.mesh, &b.mesh) && Arc::ptr_eq(&a.bindings, &b.bindings)
                    }
                    (None, None) => true,
                    _ => false,
                };
                let same_material =
                    match (&object.material, previous.objects.get(i).and_then(|p| p.material.as_ref())) {
                        (Some(a), Some(b)) => Arc::ptr_eq(a, b),
                        (None, None) => true,
                        _ => false,
                    };
                if same_morph && same_skin && same_material {
                    continue;
                }
            }
            if self.upload_object(renderer, i, i as MeshId)? {
                uploaded += 1;
            }
        }
        Ok(uploaded)
    }

    /// Uploads object `i`'s deformable mesh (skinned or morphing) as mesh `id`, with its
    /// texture; false for an object without one.
    fn upload_object(&self, renderer: &mut Renderer, i: usize, id: MeshId) -> Result<bool, SceneFrameError> {
        let at = |source| SceneFrameError::Render { path: format!("objects[{i}].mesh"), source };
        let Some(object) = self.objects.get(i) else { return Ok(false) };
        if let Some(morph) = &object.morph {
            renderer
                .upload_mesh_with_uvs(
                    id,
                    &MeshData::Morph { frames: &morph.frames, indices: &morph.indices },
                    morph.uvs(),
                )
                .map_err(at)?;
        } else if let Some(skin) = self.eval.skin(i) {
            let input = OwnedSkinInput::from_skinned_mesh(&skin.mesh, &skin.bindings);
            renderer
                .upload_mesh_with_uvs(
                    id,
                    &MeshData::Skinned { skin: input.as_input(), indices: &skin.mesh.indices },
                    skin.mesh.uvs.as_deref(),
                )
                .map_err(at)?;
        } else {
            return Ok(false);
        }
        let texture = object.material.as_ref().and_then(|m| m.base_colour_texture.as_deref());
        renderer.set_texture(id, texture).map_err(at)?;
        Ok(true)
    }

    /// The mesh id of onion-skin ghost `g` of object `o` (ids from [`GHOST_MESHES`] on, above
    /// every object's own).
    #[must_use]
    pub fn ghost_mesh(o: usize, g: usize) -> MeshId {
        GHOST_MESHES + (o as MeshId) * MAX_GHOSTS as MeshId + g as MeshId
    }

    /// Uploads `count` (at most [`MAX_GHOSTS`]) copies of object `o`'s deformable mesh as its
    /// ghost meshes, each with buffers of its own so that every ghost can show another pose in
    /// the same frame. Returns false for an object without a deformable mesh.
    ///
    /// # Errors
    /// [`SceneFrameError::Render`] naming the object.
    pub fn upload_ghosts(
        &self,
        renderer: &mut Renderer,
        o: usize,
        count: usize,
    ) -> Result<bool, SceneFrameError> {
        for g in 0..count.min(MAX_GHOSTS) {
            if !self.upload_object(renderer, o, Self::ghost_mesh(o, g))? {
                return Ok(false);
            }
        }
        Ok(true)
    }

    /// Object `o` as it is in `state` (another frame's, e.g. from
    /// [`SceneEvaluator::object_at`]) drawn as ghost `g` (uploaded by
    /// [`SceneRig::upload_ghosts`]) with `ghost`'s tint and opacity.
    ///
    /// # Errors
    /// As [`SceneRig::frame_from_state`] for that object.
    pub fn ghost_items(
        &self,
        o: usize,
        g: usize,
        state: &ObjectState,
        view: &ViewOptions,
        ghost: Ghost,
    ) -> Result<Vec<DrawItem>, SceneFrameError> {
        if g >= MAX_GHOSTS || o >= self.objects.len() {
            return Ok(Vec::new());
        }
        let mut items = self.object_items(o, state, view, Self::ghost_mesh(o, g))?;
        for item in &mut items {
            item.ghost = Some(ghost);
            item.selected = false;
        }
        Ok(items)
    }

    /// The frame at `time` seconds, from the scene's tracks.
    ///
    /// # Errors
    /// A pose that cannot be evaluated (e.g. a zero quaternion), with the object's path.
    pub fn frame(&self, time: f64, view: &ViewOptions) -> Result<FrameInput, SceneFrameError> {
        let state = self.eval.evaluate(time, &Overrides::new());
        let mut frame = self.frame_from_state(&state, view)?;
        if view.motion_path {
            if let Some(path) = self.motion_path(view.selection, time, &Overrides::new())? {
                frame.motion_paths.push(path);
            }
        }
        if view.lights {
            frame.light_gizmos = self.light_gizmos(view.selection, &state);
        }
        if view.cameras {
            frame.camera_gizmos = self.camera_gizmos(view, &state);
        }
        Ok(frame)
    }

    /// Frustums of the scene cameras of `state` but the one looked through and the hidden ones (the selected one
    /// highlighted, the active one at `state.time` brighter), in the scene's render aspect.
    #[must_use]
    pub fn camera_gizmos(&self, view: &ViewOptions, state: &SceneState) -> Vec<CameraGizmo> {
        let aspect = self.render_aspect();
        let active = self.scene.active_camera_at(state.time * self.scene.fps);
        state
            .cameras
            .iter()
            .enumerate()
            .filter(|&(c, camera)| view.look_through != Some(c) && camera.is_usable() && camera.visible)
            .map(|(c, camera)| CameraGizmo {
                camera: *camera,
                aspect,
                selected: view.selection == Some(Selected::Camera(c)),
                active: active == Some(c),
            })
            .collect()
    }

    /// Width over height of the scene's render size (16:9 when it has none).
    #[must_use]
    pub fn render_aspect(&self) -> f32 {
        self.scene.render_size.map_or(16.0 / 9.0, keyrig_core::RenderSize::aspect)
    }

    /// Gizmos of the enabled lights of `state` (the selected one highlighted).
    #[must_use]
    pub fn light_gizmos(&self, selection: Option<Selected>, state: &SceneState) -> Vec<LightGizmo> {
        state
            .lights
            .iter()
            .enumerate()
            .filter(|(_, l)| l.enabled)
            .map(|(i, l)| LightGizmo {
                kind: l.kind,
                position: l.position,
                direction: l.direction,
                selected: selection == Some(Selected::Light(i)),
            })
            .collect()
    }

    /// The draw items of object `i` in `state` on mesh `mesh` (its own, or a ghost's).
    fn object_items(
        &self,
        i: usize,
        state: &ObjectState,
        view: &ViewOptions,
        mesh: MeshId,
    ) -> Result<Vec<DrawItem>, SceneFrameError> {
        let object = &self.objects[i];
        let mut items = Vec::new();
        let colour = match (state.look.colour, &object.material, view.textures) {
            (Some(keyed), _, _) => keyed,
            (None, Some(material), true) => {
                let [r, g, b, _] = material.base_colour;
                Vec3::new(r, g, b)
            }
            _ => object.colour,
        };
        let opacity = state.look.opacity;
        let world_from_model = Mat4::from(state.world_from_object);
        let selected = matches!(view.selection, Some(Selected::Object(o)) if o == i);
        if let (Some(_), Some(blend)) = (&object.morph, &state.morph) {
            let blend = blend
                .clone()
                .map_err(|source| SceneFrameError::Morph { path: format!("objects[{i}].mesh"), source })?;
            items.push(DrawItem {
                mesh,
                world_from_model,
                deform: Deform::Morph { frame_a: blend.frame_a, frame_b: blend.frame_b, t: blend.t },
                colour,
                opacity,
                selected,
                ghost: None,
            });
        }
        if let Some(error) = &state.palette_error {
            return Err(SceneFrameError::Skin {
                path: format!("objects[{i}].skeleton (pose)"),
                source: error.clone(),
            });
        }
        if let (Some(skin), Some(palette)) = (self.eval.skin(i), &state.palette) {
            // glTF morph targets: the rest vertices morphed by the evaluator's weights.
            let morph = skin.mesh.morphed(&state.look.morph_weights).map(|(positions, normals)| {
                positions.iter().zip(&normals).map(|(&p, &n)| SkinnedVertex::new(p, n)).collect::<Arc<[_]>>()
            });
            items.push(DrawItem {
                mesh,
                world_from_model,
                deform: Deform::Skin {
                    deformer: view.deformer.unwrap_or(state.look.deformer),
                    joints: joint_poses(palette),
                    bindings: state.zone_bindings.as_ref().map(|(_, b)| Arc::clone(b)),
                    morph,
                },
                colour,
                opacity,
                selected,
                ghost: None,
            });
        }
        Ok(items)
    }

    /// The frame for a state the evaluator produced (the editor's, with its pose overrides):
    /// draw items with the state's joint palettes and morph frames, its enabled lights and the
    /// skeleton overlays. Motion paths and light gizmos are not added here; see
    /// [`SceneRig::motion_path`] and [`SceneRig::light_gizmos`].
    ///
    /// # Errors
    /// A state of another scene (wrong object count), a pose the palette could not be built
    /// for, or a morph frame that could not be found (a time that is not finite).
    pub fn frame_from_state(
        &self,
        state: &SceneState,
        view: &ViewOptions,
    ) -> Result<FrameInput, SceneFrameError> {
        if state.objects.len() != self.objects.len() {
            return Err(SceneFrameError::Invalid {
                path: "objects".into(),
                message: format!("{} object states for {} objects", state.objects.len(), self.objects.len()),
            });
        }
        let camera = view.camera.unwrap_or(self.scene.camera);
        let mut frame = FrameInput::new(camera);
        frame.through = view.look_through.and_then(|c| state.cameras.get(c).copied());
        frame.depth_range = view.depth_range;
        frame.style = view.style;
        frame.ambient = self.scene.ambient;
        frame.lights = state
            .lights
            .iter()
            .filter(|l| l.enabled && l.visible)
            .map(|l| LightInput {
                kind: l.kind,
                position: l.position,
                direction: l.direction,
                colour: l.colour,
                intensity: l.intensity,
                range: l.range,
            })
            .collect();
        frame.grid_spacing = view.grid.then(|| grid_spacing_for(camera.distance));
        frame.textures = view.textures;
        for (i, state) in state.objects.iter().enumerate() {
            // A hidden object is not drawn (its skeleton overlay still is, to pose it).
            if state.look.visible {
                frame.items.extend(self.object_items(i, state, view, i as MeshId)?);
            }
            let world_from_model = Mat4::from(state.world_from_object);
            if view.skeletons {
                if let (Some(_), Some(palette), Some(rest)) =
                    (&state.pose, &state.palette, self.eval.rest_skeleton(i))
                {
                    let joints = (0..rest.len())
                        .map(|j| world_from_model.transform_point3(palette.joint_position(j)))
                        .collect();
                    let selected = match view.selection {
                        Some(Selected::Joint { object, joint }) if object == i => Some(joint),
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
    /// markers at its keys and at `time`, evaluated with `overrides` (a value being dragged
    /// moves the path with it); `None` when nothing path-worthy is selected.
    ///
    /// # Errors
    /// A pose that cannot be evaluated.
    pub fn motion_path(
        &self,
        selection: Option<Selected>,
        time: f64,
        overrides: &Overrides,
    ) -> Result<Option<MotionPath>, SceneFrameError> {
        let (object, joint) = match selection {
            Some(Selected::Object(o)) => (o, None),
            Some(Selected::Joint { object, joint }) => (object, Some(joint)),
            None | Some(Selected::Light(_) | Selected::Camera(_)) => return Ok(None),
        };
        let Some(scene_object) = self.scene.objects.get(object) else { return Ok(None) };
        let position_at = |t: f64| -> Result<Option<Vec3>, SceneFrameError> {
            let Some(state) = self.eval.object_at(object, t, overrides) else { return Ok(None) };
            match joint {
                None => Ok(Some(state.world_from_object.translation.into())),
                Some(j) => {
                    if let Some(error) = state.palette_error {
                        return Err(SceneFrameError::Skin {
                            path: format!("objects[{object}].skeleton (pose)"),
                            source: error,
                        });
                    }
                    match (&state.pose, &state.palette) {
                        (Some(_), Some(palette)) if j < palette.len() => {
                            Ok(Some(state.world_from_object.transform_point3(palette.joint_position(j))))
                        }
                        _ => Ok(None),
                    }
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
        let times = |keys: &[keyrig_core::Key<Vec3>]| keys.iter().map(|k| k.time).collect::<Vec<_>>();
        let mut key_times: Vec<f64> = match joint {
            None => [
                times(&scene_object.translation.track.keys),
                scene_object.rotation.track.keys.iter().map(|k| k.time).collect(),
                scene_object.rotation_euler.as_ref().map_or_else(Vec::new, |e| times(&e.track.keys)),
            ]
            .concat(),
            Some(j) => scene_object
                .skeleton
                .as_ref()
                .and_then(|s| s.joints.get(j))
                .map(|joint| {
                    [
                        times(&joint.translation.track.keys),
                        joint.rotation.track.keys.iter().map(|k| k.time).collect(),
                        joint.rotation_euler.as_ref().map_or_else(Vec::new, |e| times(&e.track.keys)),
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
}
