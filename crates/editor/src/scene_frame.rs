//! The frame's preparation: what the panels draw from, computed before they are laid out and
//! only where something changed.
//!
//! - The model files the scene names are loaded ([`MeshStore::get`]) when the document or the
//!   store changed.
//! - The scene evaluator (keyrig-eval) is brought in step with the document when its revision
//!   or the loaded meshes changed ([`SceneEvaluator::update`] rebuilds only what an edit
//!   changed), and evaluated into one reused [`SceneState`] when the time, the pose overrides
//!   or the evaluator changed ([`SceneEvaluator::evaluate_into`]). An idle frame (nothing
//!   playing, nothing edited) evaluates nothing.
//! - CPU skinning runs only for what asks for it: every mesh for the painter's viewport (no GPU,
//!   or the GPU failed), the selected joint's object for the cross-section readout, every mesh
//!   when framing needs the deformed bounds. The GPU viewport skins on the GPU and gets its
//!   clip planes from [`SceneFrame::depth_bounds`], which needs no skinning.
//!
//! Every panel of a frame reads the same state: the viewport, the GPU view's rig (which shares
//! the evaluator), the motion path, the curve view and the inspector.

use std::cell::RefCell;
use std::collections::HashMap;
use std::path::Path;
use std::sync::Arc;

use glam::Vec3;
use keyrig_core::{DeformerKind, MeshSource, Scene};
use keyrig_eval::{Overrides, SceneEvaluator, SceneState};
use keyrig_skin::SkinnedMesh;

use crate::camera::Bounds;
use crate::document::Document;
use crate::eval::ObjectPose;
use crate::files::{FileMesh, MeshStore};
use crate::skinning::SkinCache;

/// What the evaluator was built from: (document, revision, mesh store generation).
pub type EvalKey = (u64, u64, u64);

/// What the panels of this frame ask the preparation for, besides the evaluated scene.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Wanted {
    /// Every mesh skinned (or morphed) on the CPU: the painter draws the viewport.
    pub cpu_meshes: bool,
    /// This object skinned on the CPU: the cross-section readout of its selected joint.
    pub cpu_object: Option<usize>,
    /// The box that holds the scene for the GPU viewport's clip planes.
    pub depth_bounds: bool,
}

/// The scene as this frame shows it, and the caches that make an unchanged frame cheap.
#[derive(Default)]
pub struct SceneFrame {
    evaluator: RefCell<Option<(EvalKey, Arc<SceneEvaluator>)>>,
    /// The scene at the frame's time, evaluated into the same allocations each time.
    state: Option<SceneState>,
    /// What `state` was evaluated for (evaluator, time bits) and with which overrides.
    state_for: Option<(EvalKey, u64)>,
    overrides: Overrides,
    /// Counts evaluations of `state`: what depends on it is keyed by it.
    generation: u64,
    poses: Vec<Option<ObjectPose>>,
    skin: SkinCache,
    /// The objects skinned or morphed on the CPU for `generation` (by index).
    skinned: Vec<bool>,
    skinned_generation: u64,
    /// Each object's deform error of the last CPU skinning (for `skinned_generation`).
    deform_errors: Vec<Option<String>>,
    /// Files of the scene that could not be loaded, for the document key and store
    /// generation they were checked at.
    file_errors: Vec<String>,
    files_checked: Option<(u64, u64, u64)>,
    /// What could not be drawn, for `errors_generation`.
    errors: Vec<String>,
    errors_generation: Option<(u64, u64)>,
    /// Each object's deformed bounds (world space) for `bounds_generation`.
    bounds: Vec<Option<Bounds>>,
    bounds_generation: Option<u64>,
    depth: Option<(u64, Option<Bounds>)>,
    /// How far each joint's vertices reach from it, per skinned mesh (by mesh identity).
    reach: HashMap<usize, (Arc<SkinnedMesh>, Arc<Vec<f32>>)>,
    /// Object-space boxes of morph and static meshes, by object: (identity, box).
    mesh_boxes: HashMap<usize, (usize, Option<Bounds>)>,
}

impl SceneFrame {
    /// The document's scene evaluator, brought in step when the document or its loaded meshes
    /// changed (after an edit of the same document only what it changed is rebuilt).
    #[must_use]
    pub fn evaluator(&self, doc: &Document, meshes: &MeshStore) -> Arc<SceneEvaluator> {
        let key = evaluator_key(doc, meshes);
        let mut cache = self.evaluator.borrow_mut();
        if let Some((k, eval)) = &*cache {
            if *k == key {
                return Arc::clone(eval);
            }
        }
        let base_dir = doc.path().and_then(Path::parent);
        let loaded = meshes.loaded_for(base_dir, doc.scene());
        // After an edit of the same document only what it changed is rebuilt (the keys of
        // untouched channels are still shared with the evaluator's copies).
        let eval = match cache.take() {
            Some(((document_before, _, _), mut eval)) if document_before == key.0 => {
                Arc::make_mut(&mut eval).update(doc.scene(), &loaded);
                eval
            }
            _ => Arc::new(SceneEvaluator::new(doc.scene(), &loaded)),
        };
        *cache = Some((key, Arc::clone(&eval)));
        eval
    }

    /// Brings the frame in step with the document, the clock and the overrides, and does what
    /// `wanted` asks; nothing is recomputed that did not change.
    pub fn prepare(
        &mut self,
        doc: &Document,
        meshes: &mut MeshStore,
        time: f64,
        overrides: &Overrides,
        wanted: Wanted,
    ) {
        self.load_files(doc, meshes);
        let eval = self.evaluator(doc, meshes);
        let key = evaluator_key(doc, meshes);
        let state_for = Some((key, time.to_bits()));
        if self.state.is_none() || self.state_for != state_for || self.overrides != *overrides {
            let state = self.state.get_or_insert_with(|| SceneState {
                time,
                objects: Vec::new(),
                lights: Vec::new(),
                cameras: Vec::new(),
            });
            eval.evaluate_into(time, overrides, state);
            self.state_for = state_for;
            self.overrides.clone_from(overrides);
            self.generation += 1;
            self.poses.clear();
            self.poses.extend(state.objects.iter().map(|s| Some(ObjectPose::from_state(s))));
        }
        if self.skinned_generation != self.generation {
            self.skinned.clear();
            self.deform_errors.clear();
            self.skinned_generation = self.generation;
        }
        let scene = doc.scene();
        let base_dir = doc.path().and_then(Path::parent);
        if wanted.cpu_meshes {
            for o in 0..scene.objects.len() {
                self.skin_object(o, scene, &eval, meshes, base_dir);
            }
        } else if let Some(o) = wanted.cpu_object {
            self.skin_object(o, scene, &eval, meshes, base_dir);
        }
        if wanted.cpu_meshes {
            // The painter has every mesh deformed already: its bounds cost one pass over them.
            self.compute_bounds(scene, meshes, base_dir);
        }
        if wanted.depth_bounds && self.depth.as_ref().is_none_or(|(g, _)| *g != self.generation) {
            let depth = self.reach_bounds(scene, &eval, meshes, base_dir);
            self.depth = Some((self.generation, depth));
        }
        self.collect_errors(scene, &eval, meshes, base_dir, wanted.cpu_meshes);
    }

    /// Every object's deformed bounds at the frame's time (world space; joints and origin for
    /// an object without a mesh), skinning on the CPU what is not skinned yet: framing (F, the
    /// camera presets, a new import) asks for them.
    pub fn ensure_bounds(
        &mut self,
        doc: &Document,
        meshes: &mut MeshStore,
        time: f64,
        overrides: &Overrides,
    ) {
        self.prepare(doc, meshes, time, overrides, Wanted { cpu_meshes: true, ..Wanted::default() });
    }

    /// The union of the bounds of `objects` (all when `None`) as last computed.
    #[must_use]
    pub fn bounds_of(&self, objects: Option<&[usize]>) -> Option<Bounds> {
        let pick = |o: usize| self.bounds.get(o).copied().flatten();
        match objects {
            Some(objects) => objects.iter().filter_map(|&o| pick(o)).reduce(Bounds::union),
            None => (0..self.bounds.len()).filter_map(pick).reduce(Bounds::union),
        }
    }

    /// Each object's deformed bounds as last computed, by object index.
    #[must_use]
    pub fn object_bounds(&self) -> &[Option<Bounds>] {
        &self.bounds
    }

    /// Forgets the bounds (objects were removed: indices shift).
    pub fn forget_bounds(&mut self) {
        self.bounds.clear();
        self.bounds_generation = None;
    }

    /// A box that holds every mesh at the frame's time without skinning it: for the GPU
    /// viewport's clip planes ([`crate::camera::OrbitCamera::depth_range`]). A skinned mesh is
    /// held by the boxes around its joints, each grown by how far the joint's vertices reach
    /// from it at rest, scaled by the joint's palette: a linear-blended vertex Σ wⱼ·M(j)·v lies
    /// in the convex hull of the points M(j)·v, each within that reach of joint j's posed
    /// position (rigid skinning is one such point; the other deformers turn the same vertices
    /// about the same joints and stay near that hull). Morph meshes use the box of all their
    /// frames, static meshes their own box.
    #[must_use]
    pub fn depth_bounds(&self) -> Option<Bounds> {
        self.depth.as_ref().and_then(|(g, b)| (*g == self.generation).then_some(*b)).flatten()
    }

    /// The scene evaluated at the frame's time (empty before the first preparation).
    #[must_use]
    pub fn state(&self) -> Option<&SceneState> {
        self.state.as_ref()
    }

    /// Each object's pose as the panels read it.
    #[must_use]
    pub fn poses(&self) -> &[Option<ObjectPose>] {
        &self.poses
    }

    /// Object `o`'s pose this frame.
    #[must_use]
    pub fn pose(&self, o: usize) -> Option<&ObjectPose> {
        self.poses.get(o)?.as_ref()
    }

    /// What the viewport could not draw this frame: files that did not load, poses without a
    /// palette, deformers that refused a pose, the evaluator's first problems.
    #[must_use]
    pub fn errors(&self) -> &[String] {
        &self.errors
    }

    /// The CPU-skinned (or morphed) frames of the objects.
    #[must_use]
    pub fn skin_cache(&self) -> &SkinCache {
        &self.skin
    }

    /// Whether object `o` was skinned or morphed on the CPU for this frame's state.
    #[must_use]
    pub fn is_skinned_now(&self, o: usize) -> bool {
        self.skinned_generation == self.generation && self.skinned.get(o).copied().unwrap_or(false)
    }

    /// Object `o`'s mesh as the painter draws it: object-space positions (deformed this frame)
    /// and triangles; `None` without a mesh it can draw.
    #[must_use]
    pub fn cpu_mesh<'a>(
        &'a self,
        o: usize,
        scene: &Scene,
        meshes: &'a MeshStore,
        base_dir: Option<&Path>,
    ) -> Option<(&'a [Vec3], &'a [u32])> {
        let Some(MeshSource::File { path, mesh, .. }) = scene.objects.get(o).and_then(|x| x.mesh.as_ref())
        else {
            return self.skinned_now(o);
        };
        match meshes.peek(base_dir, path, *mesh)? {
            FileMesh::Morph(morph) => {
                let positions = self.skin.deformed_positions(o).filter(|_| self.is_skinned_now(o))?;
                Some((positions, morph.indices()))
            }
            FileMesh::Skinned(_) => self.skinned_now(o),
        }
    }

    fn skinned_now(&self, o: usize) -> Option<(&[Vec3], &[u32])> {
        if !self.is_skinned_now(o) {
            return None;
        }
        Some((self.skin.deformed_positions(o)?, self.skin.indices(o)?))
    }

    /// Loads the model files the scene names (the evaluator reads no files); a file that
    /// cannot be loaded is kept with its error and reported over the viewport.
    fn load_files(&mut self, doc: &Document, meshes: &mut MeshStore) {
        let (document, revision) = doc.cache_key();
        if self.files_checked == Some((document, revision, meshes.generation())) {
            return;
        }
        let base_dir = doc.path().and_then(Path::parent);
        self.file_errors.clear();
        for object in &doc.scene().objects {
            if let Some(MeshSource::File { path, mesh, .. }) = &object.mesh {
                if let Err(e) = meshes.get(base_dir, path, *mesh) {
                    self.file_errors.push(format!("{}: {e}", object.name));
                }
            }
        }
        self.files_checked = Some((document, revision, meshes.generation()));
        self.errors_generation = None;
    }

    /// Skins or morphs object `o` on the CPU for this frame's state, once.
    fn skin_object(
        &mut self,
        o: usize,
        scene: &Scene,
        eval: &SceneEvaluator,
        meshes: &MeshStore,
        base_dir: Option<&Path>,
    ) {
        if self.is_skinned_now(o) {
            return;
        }
        let (Some(object), Some(state)) =
            (scene.objects.get(o), self.state.as_ref().and_then(|s| s.objects.get(o)))
        else {
            return;
        };
        if self.skinned.len() <= o {
            self.skinned.resize(o + 1, false);
            self.deform_errors.resize(o + 1, None);
        }
        self.errors_generation = None;
        self.skinned[o] = true;
        self.deform_errors[o] = None;
        if let (Some(skin), Some(palette)) = (eval.skin(o), &state.palette) {
            let (bindings, deformer, weights) =
                (state.bindings(skin), state.look.deformer, &state.look.morph_weights);
            if let Err(e) = self.skin.skin(o, skin, bindings, palette, deformer, weights) {
                self.deform_errors[o] = Some(format!("{}: {e}", object.name));
            }
            return;
        }
        self.skin.forget(o);
        let Some(MeshSource::File { path, mesh, .. }) = &object.mesh else { return };
        if let (Some(FileMesh::Morph(morph)), Some(Ok(blend))) =
            (meshes.peek(base_dir, path, *mesh), &state.morph)
        {
            self.skin.morph(o, morph, *blend);
        }
    }

    /// World bounds of each object as this frame deforms it: the deformed mesh's box, or for an
    /// object without a mesh its joints and origin.
    fn compute_bounds(&mut self, scene: &Scene, meshes: &MeshStore, base_dir: Option<&Path>) {
        if self.bounds_generation == Some(self.generation) {
            return;
        }
        let mut bounds: Vec<Option<Bounds>> = self
            .poses
            .iter()
            .map(|pose| {
                let pose = pose.as_ref()?;
                let origin: Vec3 = pose.world_from_object.translation.into();
                Bounds::of(std::iter::once(origin).chain(
                    pose.object_from_joint.iter().map(|f| (pose.world_from_object * *f).translation.into()),
                ))
            })
            .collect();
        for (o, slot) in bounds.iter_mut().enumerate() {
            let Some(pose) = self.pose(o) else { continue };
            let Some((positions, _)) = self.cpu_mesh(o, scene, meshes, base_dir) else { continue };
            let world = pose.world_from_object;
            // A mesh's own box: its joints may sit outside it (a root far below the feet).
            if let Some(mesh) = Bounds::of(positions.iter().map(|&p| world.transform_point3(p))) {
                *slot = Some(mesh);
            }
        }
        self.bounds = bounds;
        self.bounds_generation = Some(self.generation);
    }

    /// [`SceneFrame::depth_bounds`] for this frame's state.
    fn reach_bounds(
        &mut self,
        scene: &Scene,
        eval: &SceneEvaluator,
        meshes: &MeshStore,
        base_dir: Option<&Path>,
    ) -> Option<Bounds> {
        let mut all: Option<Bounds> = None;
        let states = self.state.as_ref()?.objects.len();
        for o in 0..states.min(scene.objects.len()) {
            let Some(pose) = self.pose(o) else { continue };
            let world = pose.world_from_object;
            let joints = Bounds::of(
                std::iter::once(Vec3::ZERO)
                    .chain(pose.object_from_joint.iter().map(|f| Vec3::from(f.translation))),
            );
            let mesh = self.object_space_mesh_box(o, scene, eval, meshes, base_dir);
            let Some(local) = [joints, mesh].into_iter().flatten().reduce(Bounds::union) else { continue };
            let corners = (0..8).map(|i| {
                let pick = |bit: usize, lo: f32, hi: f32| if i & bit == 0 { lo } else { hi };
                world.transform_point3(Vec3::new(
                    pick(1, local.min.x, local.max.x),
                    pick(2, local.min.y, local.max.y),
                    pick(4, local.min.z, local.max.z),
                ))
            });
            if let Some(b) = Bounds::of(corners) {
                all = Some(all.map_or(b, |a| a.union(b)));
            }
        }
        all
    }

    /// The object-space box holding object `o`'s mesh at this frame's state (see
    /// [`SceneFrame::depth_bounds`]).
    fn object_space_mesh_box(
        &mut self,
        o: usize,
        scene: &Scene,
        eval: &SceneEvaluator,
        meshes: &MeshStore,
        base_dir: Option<&Path>,
    ) -> Option<Bounds> {
        let state = self.state.as_ref()?.objects.get(o)?;
        if let (Some(skin), Some(palette)) = (eval.skin(o), &state.palette) {
            let reach = match self.reach.get(&o) {
                Some((mesh, reach)) if Arc::ptr_eq(mesh, &skin.mesh) => Arc::clone(reach),
                _ => {
                    let reach = Arc::new(joint_reach(&skin.mesh));
                    self.reach.insert(o, (Arc::clone(&skin.mesh), Arc::clone(&reach)));
                    reach
                }
            };
            return skinned_reach_box(palette, &reach);
        }
        let Some(MeshSource::File { path, mesh, .. }) = scene.objects.get(o)?.mesh.as_ref() else {
            return None;
        };
        let file = meshes.peek(base_dir, path, *mesh)?;
        let identity = match file {
            FileMesh::Morph(m) => Arc::as_ptr(m) as usize,
            FileMesh::Skinned(m) => Arc::as_ptr(m) as usize,
        };
        if let Some((id, b)) = self.mesh_boxes.get(&o) {
            if *id == identity {
                return *b;
            }
        }
        let b = match file {
            FileMesh::Morph(m) => {
                Bounds::of(m.frames().iter().flatten().map(keyrig_render::SkinnedVertex::position))
            }
            FileMesh::Skinned(m) => Bounds::of(m.positions.iter().copied()),
        };
        self.mesh_boxes.insert(o, (identity, b));
        b
    }

    /// What could not be drawn this frame, in the viewport's order: files, then each object's
    /// deformer, pose or morph problem, then the evaluator's first three problems. Without CPU
    /// skinning a deformer is asked only what can fail per pose (a dual quaternion of a scaled
    /// joint), in O(joints).
    fn collect_errors(
        &mut self,
        scene: &Scene,
        eval: &SceneEvaluator,
        meshes: &MeshStore,
        base_dir: Option<&Path>,
        all_skinned: bool,
    ) {
        let key = (self.generation, u64::from(all_skinned));
        if self.errors_generation == Some(key) {
            return;
        }
        let Some(state) = self.state.as_ref() else { return };
        let mut errors = self.file_errors.clone();
        for (o, object_state) in state.objects.iter().enumerate() {
            let Some(object) = scene.objects.get(o) else { continue };
            if let (Some(_), Some(palette)) = (eval.skin(o), &object_state.palette) {
                if self.is_skinned_now(o) {
                    errors.extend(self.deform_errors.get(o).cloned().flatten());
                } else if object.deformer.kind == DeformerKind::DualQuaternion {
                    if let Err(source) = palette.dual_quaternions() {
                        let e = crate::skinning::DeformError { kind: object.deformer.kind, source };
                        errors.push(format!("{}: {e}", object.name));
                    }
                }
                continue;
            }
            if let Some(e) = &object_state.palette_error {
                errors.push(format!("{}: pose: {e}", object.name));
            }
            let Some(MeshSource::File { path, mesh, .. }) = &object.mesh else { continue };
            if let (Some(FileMesh::Morph(_)), Some(Err(e))) =
                (meshes.peek(base_dir, path, *mesh), &object_state.morph)
            {
                errors.push(format!("{}: {e}", object.name));
            }
        }
        for problem in eval.problems().iter().take(3) {
            errors.push(problem.to_string());
        }
        self.errors = errors;
        self.errors_generation = Some(key);
    }
}

/// The key the evaluator is built for: the GPU view rebuilds its rig when it changes.
#[must_use]
pub fn evaluator_key(doc: &Document, meshes: &MeshStore) -> EvalKey {
    let (document, revision) = doc.cache_key();
    (document, revision, meshes.generation())
}

/// For each joint of a skinned mesh, the farthest any vertex it moves (weight above 0) sits
/// from the joint's bind position; −1 for a joint that moves none.
fn joint_reach(mesh: &SkinnedMesh) -> Vec<f32> {
    let bind_positions: Vec<Vec3> = mesh
        .skeleton
        .joint_from_bind_model()
        .iter()
        .map(|a_inv| Vec3::from(a_inv.inverse().translation))
        .collect();
    let mut reach = vec![-1.0f32; bind_positions.len()];
    let influences = &mesh.influences;
    for ((joints, weights), &v) in influences.joints().iter().zip(influences.weights()).zip(&mesh.positions) {
        for (&j, &w) in joints.iter().zip(weights) {
            let j = usize::from(j);
            if w > 0.0 && j < reach.len() {
                reach[j] = reach[j].max(v.distance(bind_positions[j]));
            }
        }
    }
    if let Some(bones) = &mesh.bones {
        for (&j, &v) in bones.iter().zip(&mesh.positions) {
            let j = usize::from(j);
            if j < reach.len() {
                reach[j] = reach[j].max(v.distance(bind_positions[j]));
            }
        }
    }
    reach
}

/// The object-space box that holds a skinned mesh posed by `palette`, from each joint's
/// [`joint_reach`]: M(j) takes joint j's bind position to its posed one, F(j)·0, and stretches
/// distances by at most the length of its longest axis.
fn skinned_reach_box(palette: &keyrig_skin::JointPalette, reach: &[f32]) -> Option<Bounds> {
    palette
        .skinning
        .iter()
        .zip(&palette.model_from_joint)
        .zip(reach)
        .filter(|(_, &r)| r >= 0.0)
        .map(|((m, f), &r)| {
            let axes = m.matrix3;
            let stretch = axes.x_axis.length().max(axes.y_axis.length()).max(axes.z_axis.length());
            let at = Vec3::from(f.translation);
            Bounds { min: at - Vec3::splat(r * stretch), max: at + Vec3::splat(r * stretch) }
        })
        .filter(Bounds::is_valid)
        .reduce(Bounds::union)
}

#[cfg(test)]
mod tests {
    use super::*;

    use glam::Quat;
    use keyrig_core::ProceduralMesh;
    use keyrig_skin::{deform_mesh, mesh_for, JointPalette, Pose};

    /// Issue 31: the painter's CPU path draws a glTF mesh morphed by the weights the evaluator
    /// gives (AnimatedMorphCube's weights channel as the scene's `morph/<i>` channels): the
    /// CPU-deformed positions are the glTF specification's morph of the file at each time
    /// (`base + Σ wᵢ·Δᵢ` with the file's weights, computed from keyrig-io's reading of it).
    #[test]
    fn the_cpu_path_draws_gltf_morph_targets_with_the_evaluated_weights() {
        let file = std::path::Path::new(env!("CARGO_MANIFEST_DIR"))
            .join("../../tests/corpus/gltf/AnimatedMorphCube/AnimatedMorphCube.glb");
        let model = keyrig_io::gltf_import::import_gltf_file(&file).expect("import");
        let name = file.to_str().expect("utf-8 path");
        let scene = model.to_scene(name, Some(0)).expect("scene");
        let doc = Document::new(scene, None);
        let mut meshes = MeshStore::default();
        let mut frame = SceneFrame::default();
        let node = model.nodes.iter().position(|n| n.mesh == Some(0)).expect("mesh node");
        let prim = &model.meshes[0].primitives[0];
        let mut moved = false;
        for time in [0.0, 0.7, 1.4, 2.5] {
            let wanted = Wanted { cpu_meshes: true, ..Wanted::default() };
            frame.prepare(&doc, &mut meshes, time, &Overrides::new(), wanted);
            let (positions, _) = frame.cpu_mesh(0, doc.scene(), &meshes, None).expect("drawn on the CPU");
            let weights = &model.pose_at(Some(0), time).weights[node];
            let want = keyrig_io::model::ImportedModel::morphed_positions(prim, weights);
            assert_eq!(positions.len(), want.len());
            for (p, w) in positions.iter().zip(&want) {
                assert!((*p - *w).length() < 1e-5, "t {time}: {p} vs {w}");
            }
            moved |= positions.iter().zip(&prim.positions[..]).any(|(p, b)| (*p - *b).length() > 1e-3);
        }
        assert!(moved, "the weights move the cube at some time");
    }

    /// Every vertex the linear-blend and rigid deformers move lies in the reach box, for poses
    /// that bend, twist, translate and scale the arm's joints (the deformers are keyrig-skin's,
    /// checked against the paper's formulas there).
    #[test]
    fn the_reach_box_holds_the_linear_blended_and_rigid_mesh() {
        let mesh = mesh_for(ProceduralMesh::ArmLowPoly);
        let bindings = mesh.bindings(keyrig_skin::BlendZone::default()).expect("bindings");
        let reach = joint_reach(&mesh);
        assert_eq!(reach.len(), mesh.skeleton.len());
        assert!(reach.iter().all(|&r| r > 0.0), "every joint of the arm moves vertices: {reach:?}");
        let n = mesh.skeleton.len();
        let mut poses = vec![Pose::rest(n)];
        let mut bent = Pose::rest(n);
        bent.local_rotations[1] = Quat::from_rotation_z(1.4);
        bent.local_rotations[2] = Quat::from_rotation_x(2.5);
        poses.push(bent.clone());
        bent.local_translations[2] = Vec3::new(0.3, -0.2, 0.1);
        bent.local_scales[1] = Vec3::new(1.5, 0.7, 2.0);
        bent.root_translation = Vec3::new(4.0, 1.0, -2.0);
        poses.push(bent);
        for pose in &poses {
            let palette = JointPalette::new(&mesh.skeleton, pose).expect("palette");
            let b = skinned_reach_box(&palette, &reach).expect("a box");
            for kind in [DeformerKind::LinearBlend, DeformerKind::Rigid] {
                let out = deform_mesh(&mesh, &bindings, &palette, kind).expect("deformed");
                for p in &out.positions {
                    let inside =
                        p.cmpge(b.min - Vec3::splat(1e-4)).all() && p.cmple(b.max + Vec3::splat(1e-4)).all();
                    assert!(inside, "{kind:?}: {p} outside {b:?}");
                }
            }
        }
    }
}
