//! The complete example in docs/scene-format.md is a valid scene file.

use std::path::Path;

use keyrig_core::{LightKind, ProceduralMesh};
use keyrig_io::scene_file;

/// The last ```ron block of the document.
fn example() -> String {
    let doc =
        std::fs::read_to_string(Path::new(env!("CARGO_MANIFEST_DIR")).join("../../docs/scene-format.md"))
            .expect("read docs/scene-format.md");
    let start = doc.rfind("```ron\n").expect("a ```ron block") + "```ron\n".len();
    let len = doc[start..].find("```").expect("closing fence");
    doc[start..start + len].to_string()
}

#[test]
fn documented_example_loads() {
    let scene =
        scene_file::from_str(&example(), Path::new("docs/scene-format.md")).expect("example is valid");
    assert_eq!(scene.fps, 30.0);
    assert_eq!(scene.objects.len(), 2);
    let arm = &scene.objects[0];
    assert_eq!(arm.mesh, Some(keyrig_core::MeshSource::Procedural(ProceduralMesh::ArmLowPoly)));
    let elbow = &arm.skeleton.as_ref().expect("skeleton").joints[1];
    assert_eq!(elbow.rotation.track.len(), 5);
    assert_eq!(elbow.rotation.track.keys[3].interpolation, keyrig_core::Interpolation::Linear);
    assert!(matches!(scene.lights[0].kind, LightKind::Spot { .. }));
    // Its arm mesh binds to its skeleton, and the whole scene evaluates.
    assert_eq!(arm.skeleton.as_ref().unwrap().joints.len(), keyrig_skin::ARM_BONES);
    let eval = keyrig_eval::SceneEvaluator::new(&scene, &std::collections::HashMap::new());
    assert!(eval.problems().is_empty(), "{:?}", eval.problems());
    assert!(eval.skin(0).is_some(), "the arm is skinned");
    // Saving it gives the canonical layout, which reads back to the same scene.
    let text = scene_file::to_string(&scene).unwrap();
    assert_eq!(scene_file::from_str(&text, Path::new("x.ron")).unwrap(), scene);
}
