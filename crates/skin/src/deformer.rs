//! One entry point for all four deformers on a [`SkinnedMesh`], for the editor, the CLI and the
//! paper's table: pick the job by [`DeformerKind`] and run it.

use glam::Vec3;
use keyrig_core::DeformerKind;

use crate::deform::{BonesBlendJob, DualQuatJob, Execution, LinearBlendJob, RigidJob};
use crate::error::SkinError;
use crate::mesh::{MeshBindings, SkinnedMesh};
use crate::pose::JointPalette;

/// Deformed positions and normals, in the mesh's vertex order, posed model space.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct Deformed {
    pub positions: Vec<Vec3>,
    pub normals: Vec<Vec3>,
}

/// Deforms `mesh` with `kind` into `out` (resized to the vertex count). `bindings` comes from
/// [`SkinnedMesh::bindings`] and `palette` from the mesh's skeleton and a pose.
pub fn deform_mesh_into(
    mesh: &SkinnedMesh,
    bindings: &MeshBindings,
    palette: &JointPalette,
    kind: DeformerKind,
    execution: Execution,
    out: &mut Deformed,
) -> Result<(), SkinError> {
    let n = mesh.vertex_count();
    out.positions.resize(n, Vec3::ZERO);
    out.normals.resize(n, Vec3::ZERO);
    let (out_positions, out_normals) = (&mut out.positions[..], &mut out.normals[..]);
    match kind {
        DeformerKind::Rigid => RigidJob {
            palette,
            joints: &bindings.rigid,
            positions: &mesh.positions,
            normals: &mesh.normals,
            out_positions,
            out_normals,
        }
        .run_with(execution),
        DeformerKind::LinearBlend => LinearBlendJob {
            palette,
            influences: &mesh.influences,
            positions: &mesh.positions,
            normals: &mesh.normals,
            out_positions,
            out_normals,
        }
        .run_with(execution),
        DeformerKind::BonesBlending => BonesBlendJob {
            palette,
            parents: mesh.skeleton.parents(),
            bindings: &bindings.bones_blending,
            positions: &mesh.positions,
            normals: &mesh.normals,
            out_positions,
            out_normals,
        }
        .run_with(execution),
        DeformerKind::DualQuaternion => {
            let dual_quaternions = palette.dual_quaternions()?;
            DualQuatJob {
                dual_quaternions: &dual_quaternions,
                influences: &mesh.influences,
                positions: &mesh.positions,
                normals: &mesh.normals,
                out_positions,
                out_normals,
            }
            .run_with(execution)
        }
    }
}

/// [`deform_mesh_into`] into a new buffer, on all cores.
pub fn deform_mesh(
    mesh: &SkinnedMesh,
    bindings: &MeshBindings,
    palette: &JointPalette,
    kind: DeformerKind,
) -> Result<Deformed, SkinError> {
    let mut out = Deformed::default();
    deform_mesh_into(mesh, bindings, palette, kind, Execution::Parallel, &mut out)?;
    Ok(out)
}

#[cfg(test)]
mod tests {
    use glam::Quat;
    use keyrig_core::ProceduralMesh;

    use super::*;
    use crate::binding::BlendZone;
    use crate::mesh::mesh_for;
    use crate::pose::Pose;

    /// `deform_mesh` gives what `deform_mesh_into` gives, on all cores, for every deformer.
    #[test]
    fn deform_mesh_is_deform_mesh_into_on_all_cores() {
        let arm = mesh_for(ProceduralMesh::ArmLowPoly);
        let bindings = arm.bindings(BlendZone::default()).unwrap();
        let pose = Pose::rest(4).with_rotation(2, Quat::from_rotation_x(2.0));
        let palette = JointPalette::new(&arm.skeleton, &pose).unwrap();
        for kind in [
            DeformerKind::Rigid,
            DeformerKind::LinearBlend,
            DeformerKind::BonesBlending,
            DeformerKind::DualQuaternion,
        ] {
            let out = deform_mesh(&arm, &bindings, &palette, kind).unwrap();
            let mut into = Deformed::default();
            deform_mesh_into(&arm, &bindings, &palette, kind, Execution::Reference, &mut into).unwrap();
            assert_eq!(out.positions.len(), arm.vertex_count());
            for (a, b) in out.positions.iter().zip(&into.positions) {
                assert!((*a - *b).length() < 1e-3, "{kind:?}: {a} vs {b}");
            }
        }
    }
}
