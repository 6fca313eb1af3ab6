//! MD2 → glTF morph-target animation: every corpus model converts, passes the Khronos
//! glTF-Validator with zero errors and zero warnings, is wound counter-clockwise (outwards),
//! and the re-imported animation plays like the MD2 clip.

use std::path::{Path, PathBuf};
use std::process::Command;

use glam::Quat;
use keyrig_io::gltf_export::{export_md2, Md2ExportOptions};
use keyrig_io::gltf_import::import_gltf_file;
use keyrig_io::md2::load_md2_file;

fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/md2").join(rel)
}

/// Runs the Khronos glTF-Validator; fails with instructions when it is not installed.
fn validator_errors(file: &Path) -> (u64, u64, String) {
    let dir = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tools/validate-gltf");
    assert!(
        dir.join("node_modules/gltf-validator").is_dir(),
        "the Khronos glTF-Validator is not installed: install Node.js (18 or newer) and run \
         `npm ci --prefix tools/validate-gltf` in the repository root"
    );
    let out = Command::new("node").arg(dir.join("validate.mjs")).arg(file).output().unwrap_or_else(|e| {
        panic!("cannot run `node` ({e}): install Node.js (18 or newer) and run `npm ci --prefix tools/validate-gltf`")
    });
    let stdout = String::from_utf8_lossy(&out.stdout).into_owned();
    let report: serde_json::Value = serde_json::from_str(stdout.trim()).unwrap_or_else(|e| {
        panic!("validator output ({e}): {stdout} {}", String::from_utf8_lossy(&out.stderr))
    });
    (report["errors"].as_u64().expect("errors"), report["warnings"].as_u64().expect("warnings"), stdout)
}

const FILES: [&str; 5] = [
    "ratamahatta/ratamahatta.md2",
    "ratamahatta/weapon.md2",
    "sydney/sydney.md2",
    "faerie/faerie.md2",
    "dolphin/dolphin.md2",
];

#[test]
fn every_corpus_md2_converts_validates_and_plays_like_the_original() {
    let dir = tempfile::tempdir().expect("tempdir");
    let options = Md2ExportOptions { fps: 10.0 };
    let z_up_to_y_up = Quat::from_rotation_x(-std::f32::consts::FRAC_PI_2);
    for file in FILES {
        let md2 = load_md2_file(&corpus(file)).expect("md2 import");
        let exported = export_md2(&md2, options).expect("convert");
        let out = dir.path().join(Path::new(file).with_extension("glb").file_name().expect("name"));
        exported.write(&out).expect("write");
        let (errors, warnings, report) = validator_errors(&out);
        assert_eq!(errors, 0, "{file}: {report}");
        assert_eq!(warnings, 0, "{file}: {report}");

        // Front faces wind counter-clockwise (glTF), so the face normal of the winding points
        // the way the file's vertex normals do on nearly every triangle.
        let base = md2.frame_pose(0).expect("frame 0");
        let agree = md2
            .indices
            .chunks_exact(3)
            .filter(|t| {
                let [a, b, c] = [0, 1, 2].map(|i| base.positions[t[i] as usize]);
                let face = (b - a).cross(c - a);
                let normal: glam::Vec3 = t.iter().map(|&i| base.normals[i as usize]).sum();
                face.dot(normal) > 0.0
            })
            .count();
        let triangles = md2.indices.len() / 3;
        assert!(agree * 10 > triangles * 9, "{file}: only {agree} of {triangles} triangles face outwards");
        let prim = &import_gltf_file(&out).expect("re-import").meshes[0].primitives[0];
        assert_eq!(prim.indices[..], md2.indices[..], "{file}: the converted file keeps the winding");

        let model = import_gltf_file(&out).expect("re-import");
        assert_eq!(model.animations.len(), md2.clips.len(), "{file}");
        assert_eq!(model.meshes[0].primitives[0].morph_targets.len(), md2.frames.len());
        assert!(model.meshes[0].primitives[0].base_colour_texture.is_some(), "{file}: skin texture");
        let size = md2.frames[0].positions.iter().fold(0.0f32, |m, p| m.max(p.abs().max_element()));
        for (c, clip) in md2.clips.iter().enumerate() {
            assert_eq!(model.animations[c].name, clip.name);
            let duration = clip.frames.len() as f64 / options.fps;
            for step in 0..=12 {
                let t = duration * f64::from(step) / 12.0 * 0.999;
                let want = md2.sample_clip(c, options.fps, t, true).expect("md2 sample");
                let got = model.deformed_positions(0, Some(c), t).expect("mesh");
                let worst = want
                    .positions
                    .iter()
                    .zip(&got[0])
                    .map(|(w, g)| (z_up_to_y_up * *w - *g).length())
                    .fold(0.0f32, f32::max);
                assert!(worst < 1e-4 * size.max(1.0), "{file} clip {} t {t}: {worst}", clip.name);
            }
        }
    }
}
