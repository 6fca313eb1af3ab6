//! CPU skinning of the scene's skinned meshes for the viewport, through keyrig-skin: the mesh,
//! its bindings and the joint palette come from the scene evaluator (keyrig-eval), built when
//! the document changes; here only the deformer runs, into buffers kept from frame to frame.
//! Also the cross-section measure of docs/design.md §6 for the selected joint.
//!
//! Vertex-animated (MD2) meshes are morphed here too, on the CPU, for the painter fallback
//! and for tests ([`SkinCache::morph`]); the GPU viewport morphs them in keyrig-render. A glTF
//! mesh's morph targets are applied before it is skinned, with the weights the evaluator gives
//! ([`SkinCache::skin`]), as keyrig-render does on the GPU path.

use std::collections::HashMap;
use std::sync::Arc;

use glam::{Affine3A, Vec3};
use keyrig_core::DeformerKind;
use keyrig_eval::SkinRig;
use keyrig_skin::{
    deform_mesh_into, joint_cross_section, CrossSection, Deformed, Execution, JointPalette, MeshBindings,
    SkinnedMesh,
};

/// One object's last skinned frame.
struct Entry {
    mesh: Arc<SkinnedMesh>,
    /// A copy of `mesh` morphed by the frame's morph-target weights (glTF targets), reused from
    /// frame to frame; `None` while no target weighs.
    morphed: Option<SkinnedMesh>,
    palette: JointPalette,
    deformed: Deformed,
}

/// What the viewport draws for one skinned object this frame.
pub struct SkinnedView<'a> {
    /// Deformed positions in object (model) space.
    pub positions: &'a [Vec3],
    pub normals: &'a [Vec3],
    pub indices: &'a [u32],
}

/// Skinned meshes of the scene's objects, by object index.
#[derive(Default)]
pub struct SkinCache {
    entries: HashMap<usize, Entry>,
    /// Morphed positions of the last frame of vertex-animated objects.
    morphs: HashMap<usize, Vec<Vec3>>,
}

/// A deformer that refused the mesh or pose, with its name.
#[derive(Debug, thiserror::Error)]
#[error("{}: {source}", kind.label())]
pub struct DeformError {
    pub kind: DeformerKind,
    pub source: keyrig_skin::SkinError,
}

impl SkinCache {
    /// Skins object `index`'s mesh (`skin`, from the evaluator) with `palette`, `kind` and
    /// `bindings` (the skin's own, or those of a keyed blend zone: `ObjectState::bindings`),
    /// morphed first by `morph_weights` (the evaluator's `look.morph_weights`; glTF morph
    /// targets) when any of its targets weighs.
    ///
    /// # Errors
    /// The deformer's error (e.g. a dual quaternion of a scaled joint), with the deformer.
    pub fn skin(
        &mut self,
        index: usize,
        skin: &SkinRig,
        bindings: &MeshBindings,
        palette: &JointPalette,
        kind: DeformerKind,
        morph_weights: &[f32],
    ) -> Result<SkinnedView<'_>, DeformError> {
        self.morphs.remove(&index);
        let entry = self.entries.entry(index).or_insert_with(|| Entry {
            mesh: Arc::clone(&skin.mesh),
            morphed: None,
            palette: JointPalette::default(),
            deformed: Deformed::default(),
        });
        if !Arc::ptr_eq(&entry.mesh, &skin.mesh) {
            entry.mesh = Arc::clone(&skin.mesh);
            entry.morphed = None;
        }
        entry.palette.clone_from(palette);
        let mesh: &SkinnedMesh = match skin.mesh.morphed(morph_weights) {
            Some((positions, normals)) => {
                let morphed = entry.morphed.get_or_insert_with(|| (*skin.mesh).clone());
                morphed.positions = positions;
                morphed.normals = normals;
                morphed
            }
            None => &skin.mesh,
        };
        deform_mesh_into(mesh, bindings, palette, kind, Execution::Parallel, &mut entry.deformed)
            .map_err(|source| DeformError { kind, source })?;
        Ok(SkinnedView {
            positions: &entry.deformed.positions,
            normals: &entry.deformed.normals,
            indices: &entry.mesh.indices,
        })
    }

    /// Forgets object `index`'s skinned frame (it has no skinned mesh now).
    pub fn forget(&mut self, index: usize) {
        self.entries.remove(&index);
    }

    /// The cross-section at `joint` of the object's last skinned frame, relative to rest.
    #[must_use]
    pub fn cross_section(
        &self,
        index: usize,
        joint: usize,
    ) -> Option<Result<CrossSection, keyrig_skin::SkinError>> {
        let entry = self.entries.get(&index)?;
        if entry.deformed.positions.len() != entry.mesh.vertex_count() {
            return None;
        }
        Some(joint_cross_section(&entry.mesh, &entry.palette, joint, &entry.deformed.positions))
    }

    /// Morphs object `index`'s vertex-animated mesh to the frames the evaluator chose
    /// ([`keyrig_eval::ObjectState::morph`]); returns the positions in object space.
    pub fn morph(
        &mut self,
        index: usize,
        mesh: &keyrig_render::MorphMesh,
        blend: keyrig_eval::morph::MorphBlend,
    ) -> &[Vec3] {
        self.entries.remove(&index);
        let (positions, _normals) = mesh.blended(blend);
        self.morphs.entry(index).insert_entry(positions).into_mut()
    }

    /// The triangles of object `index`'s last skinned mesh.
    #[must_use]
    pub fn indices(&self, index: usize) -> Option<&[u32]> {
        self.entries.get(&index).map(|e| e.mesh.indices.as_slice())
    }

    /// Deformed positions (object space) of the last skinned or morphed frame of an object.
    #[must_use]
    pub fn deformed_positions(&self, index: usize) -> Option<&[Vec3]> {
        self.entries
            .get(&index)
            .map(|e| e.deformed.positions.as_slice())
            .or_else(|| self.morphs.get(&index).map(Vec::as_slice))
    }
}

/// Transforms object-space points to world space.
#[must_use]
pub fn to_world(world_from_object: Affine3A, points: &[Vec3]) -> Vec<Vec3> {
    points.iter().map(|&p| world_from_object.transform_point3(p)).collect()
}
