//! What the thesis observed (seed text 000, chapter V), asserted on the measured table.

use keyrig_core::{DeformerKind, ProceduralMesh};
use keyrig_skin::paper::{paper_table, PaperPose, PaperRow};

fn row(rows: &[PaperRow], model: ProceduralMesh, deformer: DeformerKind, pose: PaperPose) -> PaperRow {
    *rows.iter().find(|r| r.model == model && r.deformer == deformer && r.pose == pose).unwrap()
}

#[test]
fn the_thesis_observations_hold_on_both_arms() {
    let rows = paper_table().unwrap();
    assert_eq!(rows.len(), 2 * 4 * 4);
    for model in [ProceduralMesh::ArmLowPoly, ProceduralMesh::ArmHighPoly] {
        // Rest: identical for every deformer.
        for deformer in DeformerKind::ALL {
            let r = row(&rows, model, deformer, PaperPose::Rest);
            assert!(
                (r.radius_ratio - 1.0).abs() < 1e-5,
                "{model:?} {deformer:?} rest radius {}",
                r.radius_ratio
            );
            assert!(
                (r.volume_ratio - 1.0).abs() < 1e-5,
                "{model:?} {deformer:?} rest volume {}",
                r.volume_ratio
            );
        }
        // 180° twist: linear blend collapses the cross-section (the candy wrapper)...
        let lbs = row(&rows, model, DeformerKind::LinearBlend, PaperPose::Twist180);
        assert!(lbs.radius_ratio < 0.3, "{model:?}: linear blend radius ratio {}", lbs.radius_ratio);
        // ...while bones blending and dual quaternion keep it.
        for deformer in [DeformerKind::BonesBlending, DeformerKind::DualQuaternion] {
            for pose in [PaperPose::Twist90, PaperPose::Twist180] {
                let r = row(&rows, model, deformer, pose);
                assert!(
                    (r.radius_ratio - 1.0).abs() < 0.05,
                    "{model:?} {deformer:?} {pose:?}: radius ratio {}",
                    r.radius_ratio
                );
            }
            let r = row(&rows, model, deformer, PaperPose::Twist180);
            assert!(
                r.volume_ratio > lbs.volume_ratio,
                "{model:?} {deformer:?}: volume {} vs linear {}",
                r.volume_ratio,
                lbs.volume_ratio
            );
        }
        // A twist rotates linear blend's section less than 180° loses: 90° already shrinks it.
        let lbs90 = row(&rows, model, DeformerKind::LinearBlend, PaperPose::Twist90);
        assert!(
            lbs90.radius_ratio < 0.9 && lbs90.radius_ratio > lbs.radius_ratio,
            "{model:?}: {}",
            lbs90.radius_ratio
        );
    }
}
