//! `assets/demo.ron` is exactly the serialized `demo_scene()`.
//!
//! After changing `keyrig_io::demo`, regenerate the file with
//! `KEYRIG_REGENERATE_DEMO=1 cargo test -p keyrig-io --test scene_demo`.

use std::path::Path;

use keyrig_io::demo::{demo_scene, DEMO_RON};
use keyrig_io::scene_file;

#[test]
fn committed_demo_file_equals_generated_scene() {
    let generated = scene_file::to_string(&demo_scene()).expect("serialize demo");
    if std::env::var_os("KEYRIG_REGENERATE_DEMO").is_some() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/demo.ron");
        std::fs::write(&path, &generated).expect("write assets/demo.ron");
        return;
    }
    assert!(
        DEMO_RON == generated,
        "assets/demo.ron differs from keyrig_io::demo::demo_scene(); regenerate it with \
         KEYRIG_REGENERATE_DEMO=1 cargo test -p keyrig-io --test scene_demo"
    );
}

#[test]
fn committed_demo_file_loads_to_the_generated_scene() {
    let scene = scene_file::from_str(DEMO_RON, Path::new("assets/demo.ron")).expect("demo.ron loads");
    assert_eq!(scene, demo_scene());
}

/// The demo arm is keyrig-skin's arm skeleton (centimetres) in metres: same names and parents,
/// rest translations × 0.01, so the procedural mesh fits it after the same scaling.
#[test]
fn demo_arm_matches_the_skin_crates_arm_in_metres() {
    let demo = keyrig_io::demo::arm_rest_skeleton();
    let skin =
        keyrig_skin::scene_skeleton_for(keyrig_core::ProceduralMesh::ArmHighPoly).expect("arm skeleton");
    assert_eq!(demo.joints.len(), skin.joints.len());
    for (d, s) in demo.joints.iter().zip(&skin.joints) {
        assert_eq!(d.name, s.name);
        assert_eq!(d.parent, s.parent, "{}", d.name);
        assert!((d.rest_translation * 100.0 - s.rest_translation).length() < 1e-3, "{}", d.name);
        assert_eq!(d.rest_rotation, s.rest_rotation, "{}", d.name);
    }
    let total: f32 = demo.joints.iter().map(|j| j.rest_translation.length()).sum::<f32>()
        + keyrig_io::demo::ARM_LENGTH / keyrig_io::demo::ARM_BONES as f32;
    assert!((total - 1.60158).abs() < 1e-6, "{total}");
}
