//! Hostile VRML97, X3D and Open Inventor files: every reader answers with an error that names
//! the file, the line and column (and byte) and what is wrong — never a panic, a hang or memory
//! the file cannot justify. The cases every reader here faces: deep nesting, `USE` of itself,
//! PROTO recursion, a DEF/USE graph that doubles at every level, a million-element array,
//! 70,000-character names, truncated and non-UTF-8 files, FIFOs and `/dev/zero`.

use std::io::Write;
use std::path::{Path, PathBuf};

use keyrig_io::vrml::{import_vrml_file, import_vrml_slice, ErrorPlace, VrmlErrorKind};

fn corpus() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus")
}

/// Writes `bytes` to `name` in a fresh folder and imports it.
fn import_bytes(
    name: &str,
    bytes: &[u8],
) -> (tempfile::TempDir, Result<keyrig_io::vrml::VrmlModel, keyrig_io::vrml::VrmlError>) {
    let dir = tempfile::tempdir().unwrap();
    let path = dir.path().join(name);
    std::fs::write(&path, bytes).unwrap();
    let result = import_vrml_file(&path);
    (dir, result)
}

/// The error's text names the file and a line and column; returns (line, column, text).
fn located(name: &str, bytes: &[u8]) -> (usize, usize, String) {
    let (_dir, result) = import_bytes(name, bytes);
    let e = result.err().unwrap_or_else(|| panic!("{name}: accepted"));
    let text = e.to_string();
    assert!(text.contains(name), "{text}");
    assert!(text.len() < 600, "a short message: {} bytes", text.len());
    match e.place {
        ErrorPlace::Text { line, column, .. } => {
            assert!(text.contains(&format!("line {line}, column {column}")), "{text}");
            (line, column, text)
        }
        ErrorPlace::File => panic!("{name}: no line and column: {text}"),
    }
}

#[test]
fn deep_nesting_is_refused_where_it_gets_too_deep() {
    let depth = 100_000;
    let text = format!("#VRML V2.0 utf8\n{}", "Group { children [\n".repeat(depth));
    let (line, _, text) = located("deep.wrl", text.as_bytes());
    assert!(text.contains("nested more than"), "{text}");
    assert!(line > 2 && line < 1000, "{line}");
    let xml = format!("<X3D><Scene>{}</Scene></X3D>", "<Group>".repeat(5000) + &"</Group>".repeat(5000));
    let (_, _, text) = located("deep.x3d", xml.as_bytes());
    assert!(text.contains("nested more than") || text.contains("XML"), "{text}");
    let iv = format!("#Inventor V2.1 ascii\n{}", "Separator {\n".repeat(depth));
    let (_, _, text) = located("deep.iv", iv.as_bytes());
    assert!(text.contains("nested more than"), "{text}");
}

#[test]
fn a_node_cannot_use_itself() {
    let (line, column, text) =
        located("self.wrl", b"#VRML V2.0 utf8\nDEF A Group {\n  children [ USE A ]\n}\n");
    assert_eq!((line, column), (3, 18), "{text}");
    assert!(text.contains("USE A") && text.contains("cannot USE itself"), "{text}");
    let xml = br#"<X3D><Scene><Group DEF="A"><Group USE="A"/></Group></Scene></X3D>"#;
    let (_, _, text) = located("self.x3d", xml);
    assert!(text.contains("cannot USE itself"), "{text}");
}

/// A PROTO is declared when its body is complete, so a PROTO that names itself in its body
/// names an unknown node (listed, not imported); recursion is still possible through
/// EXTERNPROTO files, and is refused by the nesting limit.
#[test]
fn proto_recursion_is_refused() {
    let text = b"#VRML V2.0 utf8\nPROTO Loop [ ] { Group { children [ Loop { } ] } }\nLoop { }\n";
    let (_dir, model) = import_bytes("loop.wrl", text);
    let skipped = model.unwrap().skipped_lines().join("\n");
    assert!(skipped.contains("Loop at loop.wrl:2:") && skipped.contains("not imported"), "{skipped}");
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("p.wrl"),
        "#VRML V2.0 utf8\nEXTERNPROTO Again [ ] \"p.wrl#P\"\nPROTO P [ ] { Group { children Again { } } }\n",
    )
    .unwrap();
    let main = dir.path().join("main.wrl");
    std::fs::write(&main, "#VRML V2.0 utf8\nEXTERNPROTO P [ ] \"p.wrl#P\"\nP { }\n").unwrap();
    let e = import_vrml_file(&main).unwrap_err();
    let message = e.to_string();
    assert!(message.contains("nested more than") || message.contains("more than"), "{message}");
    assert!(matches!(e.place, ErrorPlace::Text { .. }), "{message}");
}

#[test]
fn a_doubling_def_use_graph_is_bounded() {
    let mut text = String::from("#VRML V2.0 utf8\nDEF L0 Shape { geometry Box { } }\n");
    for level in 1..=40 {
        text += &format!("DEF L{level} Group {{ children [ USE L{} USE L{} ] }}\n", level - 1, level - 1);
    }
    let start = std::time::Instant::now();
    let (_, _, message) = located("doubling.wrl", text.as_bytes());
    assert!(message.contains("expands to more than"), "{message}");
    assert!(start.elapsed().as_secs() < 60, "bounded work");
}

#[test]
fn a_million_element_array_imports() {
    let n = 1_000_000;
    let mut text =
        String::from("#VRML V2.0 utf8\nShape { geometry IndexedFaceSet { coord Coordinate { point [ ");
    for i in 0..n / 3 {
        text += &format!("{} 0 {} ", i % 100, i / 100);
    }
    text += "] } coordIndex [ 0 1 100 -1 ] } }\n";
    let (_dir, model) = import_bytes("million.wrl", text.as_bytes());
    let model = model.unwrap();
    assert_eq!(model.meshes.len(), 1);
    assert_eq!(model.meshes[0].indices.len(), 3);
    // The same array with a face indexing past it: listed, not imported.
    let bad = text.replace("coordIndex [ 0 1 100 -1 ]", "coordIndex [ 0 1 999999 -1 ]");
    let (_dir, model) = import_bytes("million_bad.wrl", bad.as_bytes());
    let model = model.unwrap();
    assert!(model.meshes.is_empty());
    let skipped = model.skipped_lines().join("\n");
    assert!(skipped.contains("out of range") && skipped.contains("million_bad.wrl:2:"), "{skipped}");
}

/// X3D's spline and squad interpolators with 200,000 unevenly spaced, wildly turning keys:
/// the squad is resampled within bounded work (at most a million pieces besides the keys),
/// and a key list longer than its values is listed.
#[test]
fn huge_spline_and_squad_interpolators_stay_bounded() {
    let n = 200_000;
    let key: Vec<String> =
        (0..n).map(|i| format!("{}", (i as f64 + 0.3 * ((i % 3) as f64)) / (n as f64 + 1.0))).collect();
    let rotations: Vec<String> =
        (0..n).map(|i| format!("{} 1 {} {}", i % 7, i % 5, (i % 11) as f64 * 0.5)).collect();
    let scalars: Vec<String> = (0..n).map(|i| format!("{}", (i % 13) as f64 / 13.0)).collect();
    let text = format!(
        "#X3D V3.3 utf8\nPROFILE Immersive\nDEF T TimeSensor {{ cycleInterval 10 loop TRUE }}\n\
         DEF S SquadOrientationInterpolator {{ key [ {k} ] keyValue [ {r} ] }}\n\
         DEF A SplineScalarInterpolator {{ key [ {k} ] keyValue [ {s} ] }}\n\
         DEF B SplineScalarInterpolator {{ key [ {k} ] keyValue [ 0.5 ] }}\n\
         DEF X Transform {{ children Shape {{ geometry Box {{ }} }} }}\n\
         DEF L PointLight {{ }}\nDEF M PointLight {{ }}\n\
         ROUTE T.fraction_changed TO S.set_fraction\nROUTE T.fraction_changed TO A.set_fraction\n\
         ROUTE T.fraction_changed TO B.set_fraction\nROUTE S.value_changed TO X.set_rotation\n\
         ROUTE A.value_changed TO L.set_intensity\nROUTE B.value_changed TO M.set_intensity\n",
        k = key.join(" "),
        r = rotations.join(", "),
        s = scalars.join(" ")
    );
    let start = std::time::Instant::now();
    let (_dir, model) = import_bytes("squad.x3dv", text.as_bytes());
    let model = model.unwrap();
    let keys = model.objects[0].rotation.track.keys.len();
    assert!(keys > n && keys <= n + 1_000_002, "{keys} rotation keys");
    assert!(model.lights[0].intensity.track.keys.len() >= n);
    let skipped = model.skipped_lines().join("\n");
    assert!(skipped.contains("SplineScalarInterpolator") && skipped.contains("fewer values"), "{skipped}");
    assert!(start.elapsed().as_secs() < 120, "bounded work");
}

/// Cameras, materials and spot cones with values out of every range import into a scene
/// keyrig's validator accepts (lenses, opacities and cone angles kept in their ranges).
#[test]
fn cameras_materials_and_cones_out_of_range_stay_valid() {
    let text = "#VRML V2.0 utf8\n\
        DEF T TimeSensor { cycleInterval 1 loop TRUE }\n\
        DEF V Viewpoint { fieldOfView 1e30 orientation 0 0 0 0 }\n\
        DEF W Viewpoint { fieldOfView -4 }\n\
        DEF F ScalarInterpolator { key [ 0 1 ] keyValue [ -5 1e30 ] }\n\
        Shape { appearance Appearance { material DEF M Material { transparency 9 } } geometry Box { } }\n\
        DEF A ScalarInterpolator { key [ 0 1 ] keyValue [ -3 7 ] }\n\
        DEF S SpotLight { cutOffAngle 3 beamWidth 9 }\n\
        DEF K ScalarInterpolator { key [ 0 1 ] keyValue [ 0 100 ] }\n\
        DEF B ScalarInterpolator { key [ 0 1 ] keyValue [ -1 50 ] }\n\
        ROUTE T.fraction_changed TO F.set_fraction\nROUTE T.fraction_changed TO A.set_fraction\n\
        ROUTE T.fraction_changed TO K.set_fraction\nROUTE T.fraction_changed TO B.set_fraction\n\
        ROUTE F.value_changed TO V.set_fieldOfView\nROUTE F.value_changed TO W.set_fieldOfView\n\
        ROUTE A.value_changed TO M.set_transparency\n\
        ROUTE K.value_changed TO S.set_cutOffAngle\nROUTE B.value_changed TO S.set_beamWidth\n";
    let model = import_vrml_slice(text.as_bytes(), "ranges.wrl").unwrap();
    let scene = model.to_scene("ranges.wrl");
    assert_eq!(scene.cameras.len(), 2);
    assert!(scene.objects[0].attributes.opacity.is_animated());
    assert!(scene.lights[0].attributes.cutoff_deg.is_some());
    let problems: Vec<String> = scene.problems().iter().map(ToString::to_string).collect();
    assert!(problems.is_empty(), "{problems:?}");
}

#[test]
fn seventy_thousand_character_names_are_clipped_in_messages() {
    let name = "n".repeat(70_000);
    let text = format!("#VRML V2.0 utf8\nDEF {name} Transform {{ }}\nGroup {{ children USE {name}x }}\n");
    let (line, _, message) = located("names.wrl", text.as_bytes());
    assert_eq!(line, 3);
    assert!(message.contains("bytes)"), "{message}");
    // A long name that is fine imports.
    let text =
        format!("#VRML V2.0 utf8\nDEF {name} Transform {{ children Shape {{ geometry Box {{ }} }} }}\n");
    let (_dir, model) = import_bytes("long.wrl", text.as_bytes());
    assert_eq!(model.unwrap().objects[0].name.len(), 70_000);
}

#[test]
fn truncated_files_name_where_they_end() {
    for file in [
        "vrml/vrml2sourcebook/Chapter31Prototypes/Figure31_9SpinGroupPrototype.wrl",
        "x3d/castle-demo-models/animation/simple_tests_interpolation_and_time/worm_crawl.x3dv",
        "iv/sgi-inventor-data/bird.iv",
        "x3d/nist-conformance/Interpolators/CoordinateInterpolator/simple.x3d",
    ] {
        let bytes = std::fs::read(corpus().join(file)).unwrap();
        // Inside the last node and inside the last list: never a complete file.
        let last = |b: u8| bytes.iter().rposition(|&c| c == b).unwrap() + 1;
        let cuts = if file.ends_with(".x3d") {
            vec![bytes.len() / 2, last(b'<') + 3]
        } else {
            vec![last(b'{') + 1, last(b'[') + 3]
        };
        for cut in cuts {
            let mut cut = cut;
            while std::str::from_utf8(&bytes[..cut]).is_err() {
                cut -= 1;
            }
            let name = Path::new(file).file_name().unwrap().to_string_lossy().into_owned();
            let (line, _, message) = located(&name, &bytes[..cut]);
            assert!(line >= 1, "{message}");
        }
    }
}

#[test]
fn non_utf8_bytes_are_located() {
    let mut bytes = b"#VRML V2.0 utf8\nShape {\n  geometry Box { size 1 1 1 }\n  # caf".to_vec();
    bytes.extend_from_slice(&[0xe9, b'\n', b'}']);
    let (line, column, message) = located("latin1.wrl", &bytes);
    assert_eq!((line, column), (4, 8), "{message}");
    assert!(message.contains("0xe9") && message.contains("UTF-8"), "{message}");
}

#[test]
fn fifos_devices_and_binary_inventor_are_refused_at_once() {
    #[cfg(unix)]
    {
        let dir = tempfile::tempdir().unwrap();
        let fifo = dir.path().join("pipe.wrl");
        let c = std::ffi::CString::new(fifo.to_string_lossy().as_bytes()).unwrap();
        // SAFETY: a valid C string; mkfifo only creates the file.
        assert_eq!(unsafe { libc::mkfifo(c.as_ptr(), 0o600) }, 0);
        let e = import_vrml_file(&fifo).unwrap_err();
        assert!(matches!(e.kind, VrmlErrorKind::Io(_)), "{e}");
        assert!(e.to_string().contains("FIFO") && e.to_string().contains("pipe.wrl"), "{e}");
        let e = import_vrml_file(Path::new("/dev/zero")).unwrap_err();
        assert!(e.to_string().contains("character device"), "{e}");
    }
    let e = import_vrml_slice(b"#Inventor V2.1 binary\n\x00\x01", "robot.iv").unwrap_err();
    assert!(e.to_string().contains("binary") && e.to_string().contains("line 1, column 1"), "{e}");
    let e = import_vrml_slice(b"Group { }", "nohead.wrl").unwrap_err();
    assert!(e.to_string().contains("header"), "{e}");
}

#[test]
fn gzipped_files_read_as_their_text() {
    let path = corpus().join("vrml/castle-demo-models/vrml_engine_doc_simple_examples/moving.wrl");
    let text = std::fs::read(&path).unwrap();
    let mut gz = flate2::write::GzEncoder::new(Vec::new(), flate2::Compression::default());
    gz.write_all(&text).unwrap();
    let (_dir, model) = import_bytes("moving.wrz", &gz.finish().unwrap());
    let model = model.unwrap();
    let plain = import_vrml_file(&path).unwrap();
    assert_eq!(model.objects, plain.objects);
    // A broken gzip stream is an error about the file.
    let e = import_vrml_slice(&[0x1f, 0x8b, 8, 0, 1, 2, 3], "broken.wrz").unwrap_err();
    assert!(e.to_string().contains("broken.wrz") && e.to_string().contains("gzip"), "{e}");
}

#[test]
fn inlines_outside_the_folder_and_urls_are_refused_by_name() {
    let dir = tempfile::tempdir().unwrap();
    let inner = dir.path().join("inner");
    std::fs::create_dir(&inner).unwrap();
    std::fs::write(inner.join("piece.wrl"), "#VRML V2.0 utf8\nShape { geometry Box { } }\n").unwrap();
    let main = inner.join("main.wrl");
    std::fs::write(
        &main,
        "#VRML V2.0 utf8\nInline { url \"piece.wrl\" }\nInline { url [ \"http://example.org/x.wrl\" \"/etc/passwd\" ] }\nInline { url \"self.wrl\" }\n",
    )
    .unwrap();
    std::fs::write(inner.join("self.wrl"), "#VRML V2.0 utf8\nInline { url \"self.wrl\" }\n").unwrap();
    let e = import_vrml_file(&main).unwrap_err();
    assert!(e.to_string().contains("includes itself") && e.to_string().contains("self.wrl"), "{e}");
    std::fs::write(&main, "#VRML V2.0 utf8\nInline { url \"piece.wrl\" }\nInline { url [ \"http://example.org/x.wrl\" \"/etc/passwd\" ] }\n").unwrap();
    let model = import_vrml_file(&main).unwrap();
    assert_eq!(model.objects.len(), 1);
    let skipped = model.skipped_lines().join("\n");
    assert!(skipped.contains("http://example.org/x.wrl") && skipped.contains("/etc/passwd"), "{skipped}");
    assert!(skipped.contains("main.wrl:3:"), "{skipped}");
}
