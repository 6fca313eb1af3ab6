//! Automatic binding (`keyrig_skin::BindJob`, docs/binding.md) on the paper's high-poly arm:
//! bound by each method to its own skeleton, bent 90° and twisted 90° at joint `forearm`, and
//! deformed by linear blend beside the same pose with the arm's own smooth weights
//! (`smooth_weights`: a linear ramp across each joint over a quarter of each bone). The figure
//! is the largest vertex distance over the arm's length (160.158 cm); printed with
//! `--nocapture`.

use glam::Quat;
use keyrig_core::{DeformerKind, ProceduralMesh};
use keyrig_skin::{deform_mesh, mesh_for, BindJob, BindMethod, BlendZone, JointPalette, Pose};

#[test]
fn the_arm_bound_automatically_bends_like_its_own_weights() {
    let arm = mesh_for(ProceduralMesh::ArmHighPoly);
    let length = keyrig_skin::ARM_LENGTH_CM;
    let forearm = arm.skeleton.find("forearm").expect("forearm");
    let poses = [
        ("bend 90°", Quat::from_rotation_z(-std::f32::consts::FRAC_PI_2)),
        ("twist 90°", Quat::from_rotation_x(std::f32::consts::FRAC_PI_2)),
    ];
    let own = arm.bindings(BlendZone::default()).expect("bindings");
    let (mut report, mut failures) = (Vec::new(), Vec::new());
    for method in BindMethod::ALL {
        let mut bound = arm.clone();
        bound.influences =
            BindJob::new(&arm.positions, &arm.indices, &arm.skeleton, method).run().expect("bind");
        bound.bones = None;
        let bindings = bound.bindings(BlendZone::default()).expect("bindings");
        for (name, rotation) in poses {
            let pose = Pose::rest(arm.skeleton.len()).with_rotation(forearm, rotation);
            let palette = JointPalette::new(&arm.skeleton, &pose).expect("palette");
            let want = deform_mesh(&arm, &own, &palette, DeformerKind::LinearBlend).expect("own");
            let got = deform_mesh(&bound, &bindings, &palette, DeformerKind::LinearBlend).expect("bound");
            let worst =
                got.positions.iter().zip(&want.positions).map(|(a, b)| a.distance(*b)).fold(0.0f32, f32::max)
                    / length;
            report.push(format!("{:>8} {name}: worst {:.2} % of the length", method.name(), 100.0 * worst));
            failures.extend((worst > allowed(method)).then(|| report.last().cloned().unwrap_or_default()));
        }
    }
    println!("{}", report.join("\n"));
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}

/// Both methods bind the arm to its own bones; they differ from the hand-set ramp in how wide
/// and how smooth the blend across the joint is (the envelope's (d₁/d)⁴ blends over a wider
/// zone than a quarter of each bone).
fn allowed(method: BindMethod) -> f32 {
    match method {
        BindMethod::Envelope => 0.078,
        BindMethod::Heat => 0.065,
    }
}
