//! The paper's test as a measured table (docs/design.md §6; seed text 000, chapter V): both arms ×
//! four deformers × four poses of one inner joint, with the cross-section radius at that joint
//! and the enclosed volume, each relative to rest.

use glam::{Quat, Vec3};
use keyrig_core::{DeformerKind, ProceduralMesh};

use crate::binding::BlendZone;
use crate::deform::Execution;
use crate::deformer::{deform_mesh_into, Deformed};
use crate::error::SkinError;
use crate::measure::{enclosed_volume, joint_cross_section};
use crate::mesh::mesh_for;
use crate::pose::{JointPalette, Pose};

/// The posed joint: `forearm` (index 2), the middle joint of the arm (x = 80.079 cm).
pub const PAPER_JOINT: usize = 2;

/// The four poses of the paper's test.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum PaperPose {
    Rest,
    /// 90° about −Z.
    Bend90,
    /// 90° about X.
    Twist90,
    /// 180° about X.
    Twist180,
}

impl PaperPose {
    pub const ALL: [PaperPose; 4] =
        [PaperPose::Rest, PaperPose::Bend90, PaperPose::Twist90, PaperPose::Twist180];

    /// T(k) of the posed joint.
    #[must_use]
    pub fn rotation(self) -> Quat {
        use std::f32::consts::{FRAC_PI_2, PI};
        match self {
            PaperPose::Rest => Quat::IDENTITY,
            PaperPose::Bend90 => Quat::from_axis_angle(-Vec3::Z, FRAC_PI_2),
            PaperPose::Twist90 => Quat::from_axis_angle(Vec3::X, FRAC_PI_2),
            PaperPose::Twist180 => Quat::from_axis_angle(Vec3::X, PI),
        }
    }

    #[must_use]
    pub fn label(self) -> &'static str {
        match self {
            PaperPose::Rest => "rest",
            PaperPose::Bend90 => "bend 90° about −Z",
            PaperPose::Twist90 => "twist 90° about X",
            PaperPose::Twist180 => "twist 180° about X",
        }
    }
}

/// One row of the table.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PaperRow {
    pub model: ProceduralMesh,
    pub deformer: DeformerKind,
    pub pose: PaperPose,
    /// Cross-section radius at the joint, posed / rest.
    pub radius_ratio: f32,
    /// Enclosed volume, posed / rest.
    pub volume_ratio: f64,
}

/// Measures the whole table with the default blend zone (a quarter of each bone).
pub fn paper_table() -> Result<Vec<PaperRow>, SkinError> {
    let zone = BlendZone::default();
    let mut rows = Vec::new();
    for model in [ProceduralMesh::ArmLowPoly, ProceduralMesh::ArmHighPoly] {
        let mesh = mesh_for(model);
        let bindings = mesh.bindings(zone)?;
        let rest_volume = enclosed_volume(&mesh.positions, &mesh.indices)?;
        let mut out = Deformed::default();
        for deformer in DeformerKind::ALL {
            for pose in PaperPose::ALL {
                let p = Pose::rest(mesh.skeleton.len()).with_rotation(PAPER_JOINT, pose.rotation());
                let palette = JointPalette::new(&mesh.skeleton, &p)?;
                deform_mesh_into(&mesh, &bindings, &palette, deformer, Execution::Reference, &mut out)?;
                let section = joint_cross_section(&mesh, &palette, PAPER_JOINT, &out.positions)?;
                let volume = enclosed_volume(&out.positions, &mesh.indices)?;
                rows.push(PaperRow {
                    model,
                    deformer,
                    pose,
                    radius_ratio: section.ratio(),
                    volume_ratio: volume / rest_volume,
                });
            }
        }
    }
    Ok(rows)
}
