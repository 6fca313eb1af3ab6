//! The X3D's XML encoding (roxmltree, then the shared node tree) reader on arbitrary bytes, through the whole import (parsing, PROTO and DEF/USE
//! expansion, geometry, animation mapping): it must return a model or a located error, never
//! panic, hang or take unbounded memory; an accepted model must map onto a scene and give
//! every mesh as a keyrig-skin mesh.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    let mut bytes = b"".to_vec();
    bytes.extend_from_slice(data);
    if let Ok(model) = keyrig_io::vrml::import_vrml_slice(&bytes, "fuzz") {
        let scene = model.to_scene("fuzz");
        let _ = scene.problems();
        for mesh in 0..model.meshes.len().min(8) {
            let _ = model.skinned_mesh(mesh);
        }
    }
});
