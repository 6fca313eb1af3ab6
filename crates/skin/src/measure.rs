//! Measures of a deformed mesh used by the paper's table and shown live in the editor.

use glam::{DVec3, Vec3, Vec3A};

use crate::error::SkinError;
use crate::mesh::SkinnedMesh;
use crate::pose::JointPalette;

/// Enclosed volume of a closed, consistently oriented triangle mesh: the sum of the signed
/// volumes of the tetrahedra (origin, a, b, c), Σ a·(b × c)/6, in f64. Positive for
/// outward-facing triangles.
pub fn enclosed_volume(positions: &[Vec3], indices: &[u32]) -> Result<f64, SkinError> {
    let mut sum = 0.0f64;
    for (triangle, tri) in indices.chunks_exact(3).enumerate() {
        let mut p = [DVec3::ZERO; 3];
        for (slot, &index) in p.iter_mut().zip(tri) {
            let v = positions.get(index as usize).ok_or(SkinError::TriangleIndexOutOfRange {
                triangle,
                index,
                vertex_count: positions.len(),
            })?;
            *slot = v.as_dvec3();
        }
        sum += p[0].dot(p[1].cross(p[2]));
    }
    Ok(sum / 6.0)
}

/// The size of a limb's cross-section at a joint, at rest and posed.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CrossSection {
    /// Mean distance of the section's vertices from the joint in the rest pose.
    pub rest_radius: f32,
    /// Mean distance of the same vertices from the posed joint.
    pub posed_radius: f32,
    /// How many vertices the section has.
    pub vertex_count: usize,
}

impl CrossSection {
    /// posed / rest: 1 keeps the limb's thickness, near 0 is the "candy wrapper" collapse.
    #[must_use]
    pub fn ratio(&self) -> f32 {
        self.posed_radius / self.rest_radius
    }
}

/// Relative width of the band (of the joint's bone length) that still counts as "the ring
/// nearest the joint": absorbs rounding when two rings are equally far on either side.
const SECTION_BAND: f32 = 1e-3;

/// The cross-section of `mesh` at joint `joint`: the vertices nearest to the joint along the
/// bone axis (the ring at the joint, or the two rings equally far either side), among those
/// whose dominant joint is `joint` or its parent; its radius is their mean distance from the
/// joint, at rest (`mesh.positions`, A(k)) and posed (`posed`, F(k)).
pub fn joint_cross_section(
    mesh: &SkinnedMesh,
    palette: &JointPalette,
    joint: usize,
    posed: &[Vec3],
) -> Result<CrossSection, SkinError> {
    let skeleton = &mesh.skeleton;
    if joint >= skeleton.len() || joint >= palette.len() {
        return Err(SkinError::NoSuchJoint { joint, joint_count: skeleton.len().min(palette.len()) });
    }
    if posed.len() != mesh.vertex_count() {
        return Err(SkinError::LengthMismatch {
            what: "posed positions",
            expected: mesh.vertex_count(),
            found: posed.len(),
        });
    }
    let parent = skeleton.parents()[joint];
    let belongs = |v: usize| {
        let j = match &mesh.bones {
            Some(bones) => bones[v] as usize,
            None => {
                let ws = mesh.influences.weights()[v];
                mesh.influences.joints()[v][(1..4).fold(0, |best, i| if ws[i] > ws[best] { i } else { best })]
                    as usize
            }
        };
        j == joint || Some(j) == parent
    };
    let r = skeleton.parent_from_joint()[joint];
    let axis = (r.matrix3.inverse() * r.translation).try_normalize().unwrap_or(Vec3A::X);
    let joint_from_model = skeleton.joint_from_bind_model()[joint];
    let axial: Vec<(usize, f32)> = (0..mesh.vertex_count())
        .filter(|&v| belongs(v))
        .map(|v| (v, axis.dot(joint_from_model.transform_point3a(Vec3A::from(mesh.positions[v]))).abs()))
        .collect();
    let nearest = axial.iter().map(|a| a.1).fold(f32::INFINITY, f32::min);
    if !nearest.is_finite() {
        return Err(SkinError::NoSuchJoint { joint, joint_count: skeleton.len() });
    }
    let band = nearest + SECTION_BAND * skeleton.bone_lengths()[joint];
    let rest_centre = skeleton.rest_position(joint);
    let posed_centre = palette.joint_position(joint);
    let (mut rest_sum, mut posed_sum, mut count) = (0.0f64, 0.0f64, 0usize);
    for &(v, a) in &axial {
        if a <= band {
            rest_sum += f64::from(mesh.positions[v].distance(rest_centre));
            posed_sum += f64::from(posed[v].distance(posed_centre));
            count += 1;
        }
    }
    let n = count as f64;
    Ok(CrossSection {
        rest_radius: (rest_sum / n) as f32,
        posed_radius: (posed_sum / n) as f32,
        vertex_count: count,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::mesh::mesh_for;
    use crate::pose::Pose;
    use keyrig_core::ProceduralMesh;

    #[test]
    fn cross_section_of_the_rest_arm_is_its_ring() {
        let arm = mesh_for(ProceduralMesh::ArmLowPoly);
        let palette = JointPalette::new(&arm.skeleton, &Pose::rest(4)).unwrap();
        let section = joint_cross_section(&arm, &palette, 2, &arm.positions).unwrap();
        // Ring 6 (6 vertices) lies exactly on joint 2.
        assert_eq!(section.vertex_count, 6);
        assert_eq!(section.ratio(), 1.0);
        let expected: f32 =
            arm.positions[36..42].iter().map(|p| p.distance(arm.skeleton.rest_position(2))).sum::<f32>()
                / 6.0;
        assert!((section.rest_radius - expected).abs() < 1e-4);
        // A collapsed copy has ratio 0.
        let mut collapsed = arm.positions.clone();
        for p in &mut collapsed[36..42] {
            *p = arm.skeleton.rest_position(2);
        }
        assert_eq!(joint_cross_section(&arm, &palette, 2, &collapsed).unwrap().ratio(), 0.0);
        // The section takes the vertices of the joint's bone and its parent's within a
        // thousandth of the bone (0.04 cm here) of the nearest ring: vertices of the next ring
        // (bone 2) and the previous one (bone 1) moved to 0.02 cm from the joint join it, two
        // of the child bone's (3) do not.
        let bones = arm.bones.as_ref().unwrap();
        assert_eq!([bones[30], bones[42], bones[60], bones[61]], [1, 2, 3, 3]);
        let x = arm.skeleton.rest_position(2).x;
        let mut near = arm.clone();
        (near.positions[42].x, near.positions[30].x) = (x + 0.02, x - 0.02);
        (near.positions[60].x, near.positions[61].x) = (x + 0.01, x - 0.01);
        assert_eq!(joint_cross_section(&near, &palette, 2, &near.positions).unwrap().vertex_count, 8);
        near.positions[42].x = x + 0.06;
        assert_eq!(joint_cross_section(&near, &palette, 2, &near.positions).unwrap().vertex_count, 7);
    }

    #[test]
    fn measures_reject_bad_input() {
        let arm = mesh_for(ProceduralMesh::ArmLowPoly);
        let palette = JointPalette::new(&arm.skeleton, &Pose::rest(4)).unwrap();
        assert_eq!(
            joint_cross_section(&arm, &palette, 9, &arm.positions),
            Err(SkinError::NoSuchJoint { joint: 9, joint_count: 4 })
        );
        // A joint of the mesh's skeleton that the palette (of another, smaller skeleton) lacks.
        let short = JointPalette::new(&arm.skeleton, &Pose::rest(4)).map(|mut p| {
            p.model_from_joint.truncate(2);
            p.skinning.truncate(2);
            p.bones_blending.truncate(2);
            p
        });
        assert_eq!(
            joint_cross_section(&arm, &short.unwrap(), 3, &arm.positions),
            Err(SkinError::NoSuchJoint { joint: 3, joint_count: 2 })
        );
        assert!(matches!(
            joint_cross_section(&arm, &palette, 1, &arm.positions[..10]),
            Err(SkinError::LengthMismatch { expected: 78, found: 10, .. })
        ));
        assert_eq!(
            enclosed_volume(&arm.positions[..3], &[0, 1, 7]),
            Err(SkinError::TriangleIndexOutOfRange { triangle: 0, index: 7, vertex_count: 3 })
        );
    }
}
