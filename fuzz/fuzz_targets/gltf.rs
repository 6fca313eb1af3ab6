//! The whole glTF import path (GLB container, JSON, validation, accessors, buffers, skins,
//! animations) on arbitrary bytes; an accepted model is also posed and skinned.
#![no_main]

use libfuzzer_sys::fuzz_target;

fuzz_target!(|data: &[u8]| {
    if let Ok(model) = keyrig_io::gltf_import::import_gltf_slice(data) {
        let animation = if model.animations.is_empty() { None } else { Some(0) };
        for node in 0..model.nodes.len().min(8) {
            let _ = model.deformed_positions(node, animation, 0.5);
        }
        let _ = model.to_scene("fuzz.glb", animation);
    }
});
