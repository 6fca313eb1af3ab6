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
        let bound = arm.clone().rebound(method, None).expect("bind");
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

proptest::proptest! {
    #![proptest_config(proptest::prelude::ProptestConfig::with_cases(64))]
    /// Any triangle soup — repeated, coincident and collinear vertices, triangles sharing one
    /// index twice — binds to any chain without an error, with every weight finite and in
    /// [0, 1] (`Influences` itself guarantees the sums).
    #[test]
    fn any_triangle_soup_binds(
        points in proptest::collection::vec((0i8..6, 0i8..4, 0i8..4), 3..40),
        triangles in proptest::collection::vec((0usize..40, 0usize..40, 0usize..40), 0..60),
        bones in 1usize..5,
        heat in proptest::bool::ANY,
    ) {
        // Coordinates on a coarse grid, so that coincident and collinear vertices are common.
        let positions: Vec<glam::Vec3> =
            points.iter().map(|&(x, y, z)| glam::Vec3::new(f32::from(x), f32::from(y), f32::from(z)) * 0.5).collect();
        let n = positions.len();
        let indices: Vec<u32> =
            triangles.iter().flat_map(|&(a, b, c)| [a % n, b % n, c % n]).map(|i| i as u32).collect();
        let joints: Vec<keyrig_skin::RestJoint> = (0..bones)
            .map(|j| {
                let t = if j == 0 { glam::Vec3::ZERO } else { glam::Vec3::X };
                keyrig_skin::RestJoint::new(format!("j{j}"), j.checked_sub(1), t, Quat::IDENTITY)
            })
            .collect();
        let skeleton = keyrig_skin::RestSkeleton::new(&joints).unwrap();
        let method = if heat { BindMethod::Heat } else { BindMethod::Envelope };
        let influences = BindJob::new(&positions, &indices, &skeleton, method).run().unwrap();
        proptest::prop_assert_eq!(influences.len(), n);
        for ws in influences.weights() {
            proptest::prop_assert!(ws.iter().all(|w| w.is_finite() && (0.0..=1.0 + 1e-6).contains(w)), "{:?}", ws);
        }
    }
}
