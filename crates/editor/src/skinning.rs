//! CPU skinning of the scene's procedural meshes for the viewport, through keyrig-skin: the
//! mesh and its bindings are built when the object's mesh, rest skeleton or blend zone change;
//! each frame only the joint palette and the deformer run. Also the cross-section measure of
//! DESIGN.md §6 for the selected joint.
//!
//! keyrig-skin builds its procedural meshes in centimetres with their own rest skeleton; a
//! scene skeleton may use other units (the demo uses metres). The mesh is fitted to the
//! object's skeleton by the ratio of the two skeletons' chain lengths, then bound to the
//! object's rest skeleton.
//!
//! Vertex-animated (MD2) meshes are morphed here too, on the CPU, for the painter fallback
//! and for tests ([`SkinCache::morph`]); the GPU viewport morphs them in keyrig-render.

use std::collections::HashMap;

use glam::{Affine3A, Vec3};
use keyrig_core::{DeformerKind, DeformerSettings, ProceduralMesh, Skeleton};
use keyrig_skin::{
    deform_mesh_into, joint_cross_section, mesh_for, BlendZone, CrossSection, Deformed, Execution,
    JointPalette, MeshBindings, RestSkeleton, SkinnedMesh,
};

use crate::eval::ObjectPose;

/// Where an object's mesh comes from, as the cache compares it.
#[derive(Clone, Debug, PartialEq)]
enum MeshKey {
    Procedural(ProceduralMesh),
    File(String, Option<usize>),
}

/// The mesh of an object, resolved by the caller (file meshes come from
/// [`crate::files::MeshStore`]).
pub enum MeshInput<'a> {
    Procedural(ProceduralMesh),
    File { path: &'a str, mesh: Option<usize>, data: &'a crate::files::FileMesh },
}

/// One object's skinned mesh, rebuilt only when its inputs change.
struct Entry {
    kind: MeshKey,
    skeleton: Skeleton,
    settings: DeformerSettings,
    mesh: SkinnedMesh,
    bindings: MeshBindings,
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
    statics: Vec<(ProceduralMesh, Vec<Vec3>, Vec<u32>)>,
    /// Morphed positions of the last frame of vertex-animated objects.
    morphs: HashMap<usize, Vec<Vec3>>,
}

fn build_entry(
    input: &MeshInput<'_>,
    skeleton: &Skeleton,
    settings: DeformerSettings,
) -> Result<Option<Entry>, String> {
    let (key, mesh) = match input {
        MeshInput::Procedural(kind) => (MeshKey::Procedural(*kind), fit_procedural(*kind, skeleton)?),
        MeshInput::File { path, mesh, data } => match data {
            // A file's skinned mesh keeps the skeleton and inverse bind matrices of its skin.
            crate::files::FileMesh::Skinned(m) => (MeshKey::File((*path).to_owned(), *mesh), (**m).clone()),
            crate::files::FileMesh::Static { .. } | crate::files::FileMesh::Morph(_) => return Ok(None),
        },
    };
    let zone = BlendZone::from_settings(&settings).map_err(|e| format!("blend zone: {e}"))?;
    let bindings = mesh.bindings(zone).map_err(|e| format!("bindings: {e}"))?;
    Ok(Some(Entry {
        kind: key,
        skeleton: skeleton.clone(),
        settings,
        mesh,
        bindings,
        palette: JointPalette::default(),
        deformed: Deformed::default(),
    }))
}

/// A procedural mesh scaled to the object's skeleton and bound to it.
fn fit_procedural(kind: ProceduralMesh, skeleton: &Skeleton) -> Result<SkinnedMesh, String> {
    let rest = RestSkeleton::from_scene(skeleton).map_err(|e| format!("skeleton: {e}"))?;
    mesh_for(kind).fit_to_skeleton(rest).map_err(|e| format!("mesh does not fit the skeleton: {e}"))
}

impl SkinCache {
    /// Skins object `index` (a mesh with a skeleton) in `pose` with `kind`. `Ok(None)` for
    /// objects without a skinned mesh.
    pub fn skin(
        &mut self,
        index: usize,
        object: &keyrig_core::Object,
        input: Option<MeshInput<'_>>,
        pose: &ObjectPose,
        kind: DeformerKind,
    ) -> Result<Option<SkinnedView<'_>>, String> {
        self.morphs.remove(&index);
        let (Some(input), Some(skeleton)) = (input, &object.skeleton) else {
            self.entries.remove(&index);
            return Ok(None);
        };
        let key = match &input {
            MeshInput::Procedural(k) => MeshKey::Procedural(*k),
            MeshInput::File { path, mesh, .. } => MeshKey::File((*path).to_owned(), *mesh),
        };
        let stale = match self.entries.get(&index) {
            Some(e) => e.kind != key || &e.skeleton != skeleton || e.settings != object.deformer,
            None => true,
        };
        if stale {
            self.entries.remove(&index);
            match build_entry(&input, skeleton, object.deformer)? {
                Some(entry) => {
                    self.entries.insert(index, entry);
                }
                None => return Ok(None),
            }
        }
        let Some(entry) = self.entries.get_mut(&index) else { return Ok(None) };
        entry.palette.update(&entry.mesh.skeleton, &pose.pose).map_err(|e| format!("pose: {e}"))?;
        deform_mesh_into(
            &entry.mesh,
            &entry.bindings,
            &entry.palette,
            kind,
            Execution::Parallel,
            &mut entry.deformed,
        )
        .map_err(|e| format!("{}: {e}", kind.label()))?;
        Ok(Some(SkinnedView {
            positions: &entry.deformed.positions,
            normals: &entry.deformed.normals,
            indices: &entry.mesh.indices,
        }))
    }

    /// The cross-section at `joint` of the object's last skinned frame, relative to rest.
    #[must_use]
    pub fn cross_section(&self, index: usize, joint: usize) -> Option<Result<CrossSection, String>> {
        let entry = self.entries.get(&index)?;
        if entry.deformed.positions.len() != entry.mesh.vertex_count() {
            return None;
        }
        Some(
            joint_cross_section(&entry.mesh, &entry.palette, joint, &entry.deformed.positions)
                .map_err(|e| e.to_string()),
        )
    }

    /// Positions and triangles of an unskinned procedural mesh (the cube), built once.
    pub fn static_mesh(&mut self, kind: ProceduralMesh) -> (&[Vec3], &[u32]) {
        let i = match self.statics.iter().position(|(k, _, _)| *k == kind) {
            Some(i) => i,
            None => {
                let mesh = mesh_for(kind);
                self.statics.push((kind, mesh.positions, mesh.indices));
                self.statics.len() - 1
            }
        };
        let (_, positions, indices) = &self.statics[i];
        (positions, indices)
    }

    /// Morphs object `index`'s vertex-animated mesh to `time` seconds, playing `clip` (every
    /// frame when `None`) at `fps` model frames per second, looping (keyrig-render's
    /// [`keyrig_render::MorphMesh::blend_at`]); returns the positions in object space.
    ///
    /// # Errors
    /// An unknown clip, a bad rate or time.
    pub fn morph(
        &mut self,
        index: usize,
        mesh: &keyrig_render::MorphMesh,
        clip: Option<&str>,
        fps: f64,
        time: f64,
    ) -> Result<&[Vec3], String> {
        let blend = mesh.blend_at(clip, fps, time).map_err(|e| e.to_string())?;
        let (positions, _normals) = mesh.blended(blend);
        Ok(self.morphs.entry(index).insert_entry(positions).into_mut())
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
