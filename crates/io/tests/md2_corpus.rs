//! Every MD2 model of the external corpus imports, has the documented counts and clips, and
//! plays.

use std::path::{Path, PathBuf};

use keyrig_io::md2::{clip_name, frame_range_end, load_md2_file, parse_md2, Md2ErrorKind};

fn corpus(rel: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/md2").join(rel)
}

/// (file, MD2 vertices, triangles, frames, clips, skin file name)
const MODELS: [(&str, usize, usize, usize, usize, &str); 5] = [
    ("ratamahatta/ratamahatta.md2", 344, 666, 198, 16, "ratamahatta.png"),
    ("ratamahatta/weapon.md2", 85, 119, 198, 16, "weapon.png"),
    ("sydney/sydney.md2", 342, 679, 198, 16, "sydney.bmp"),
    ("faerie/faerie.md2", 366, 654, 198, 16, "faerie2.bmp"),
    ("dolphin/dolphin.md2", 324, 500, 59, 2, "dolphin_f.bmp"),
];

#[test]
fn every_corpus_model_imports_with_expected_counts_and_skin() {
    for (file, xyz, tris, frames, clips, skin) in MODELS {
        let model = load_md2_file(&corpus(file)).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(model.frames[0].positions.len(), xyz, "{file}: vertices");
        assert_eq!(model.indices.len(), tris * 3, "{file}: triangles");
        assert_eq!(model.frames.len(), frames, "{file}: frames");
        assert_eq!(model.clips.len(), clips, "{file}: clips {:?}", model.clips);
        let skin_image = model.skin.as_ref().unwrap_or_else(|| panic!("{file}: no skin found"));
        assert_eq!(skin_image.path.file_name().and_then(|n| n.to_str()), Some(skin), "{file}");
        assert_eq!(skin_image.rgba.len(), (skin_image.width * skin_image.height * 4) as usize);
        assert!(model.indices.iter().all(|&i| (i as usize) < model.vertex_count()));
        // Clips cover all frames, in order, and every frame's clip name matches.
        let mut next = 0;
        for clip in &model.clips {
            assert_eq!(clip.frames.start, next);
            next = clip.frames.end;
            for f in clip.frames.clone() {
                assert_eq!(clip_name(&model.frames[f].name), clip.name);
            }
        }
        assert_eq!(next, frames);
    }
}

#[test]
fn ratamahatta_has_the_sixteen_quake2_clips() {
    let model = load_md2_file(&corpus("ratamahatta/ratamahatta.md2")).expect("import");
    let names: Vec<(&str, usize)> = model.clips.iter().map(|c| (c.name.as_str(), c.frames.len())).collect();
    assert_eq!(
        names,
        [
            ("stand", 40),
            ("run", 6),
            ("attack", 8),
            ("pain", 12),
            ("jump", 6),
            ("flip", 12),
            ("salute", 11),
            ("taunt", 17),
            ("wave", 11),
            ("point", 12),
            ("crstand", 19),
            ("crwalk", 6),
            ("crattack", 9),
            ("crpain", 4),
            ("crdeath", 5),
            ("death", 20),
        ]
    );
}

#[test]
fn texcoords_are_normalized_by_the_header_skin_size() {
    for (file, ..) in MODELS {
        let model = load_md2_file(&corpus(file)).expect("import");
        for uv in &model.texcoords {
            assert!(uv.is_finite(), "{file}");
            assert!((-0.01..=1.01).contains(&uv.x) && (-0.01..=1.01).contains(&uv.y), "{file}: uv {uv}");
        }
    }
}

#[test]
fn playback_hits_frames_and_interpolates_between_them() {
    let model = load_md2_file(&corpus("ratamahatta/ratamahatta.md2")).expect("import");
    let run = model.clip_index("run").expect("run clip");
    let first = model.clips[run].frames.start;
    let fps = 10.0;
    // At t = k / fps the pose is exactly frame k of the clip.
    for k in 0..6 {
        let pose = model.sample_clip(run, fps, k as f64 / fps, true).expect("sample");
        let frame = model.frame_pose(first + k).expect("frame");
        assert_eq!(pose.positions, frame.positions, "frame {k}");
    }
    // Half way between frames 2 and 3: the midpoint of each vertex.
    let mid = model.sample_clip(run, fps, 2.5 / fps, true).expect("sample");
    let (a, b) = (model.frame_pose(first + 2).expect("a"), model.frame_pose(first + 3).expect("b"));
    for i in 0..mid.positions.len() {
        let expected = (a.positions[i] + b.positions[i]) * 0.5;
        assert!((mid.positions[i] - expected).length() < 1e-4, "vertex {i}");
        assert!((mid.normals[i].length() - 1.0).abs() < 1e-4);
    }
    // Looping: the last frame blends into the first; t = 6 / fps is frame 0 again.
    let wrapped = model.sample_clip(run, fps, 6.0 / fps, true).expect("sample");
    assert_eq!(wrapped.positions, model.frame_pose(first).expect("frame").positions);
    // Not looping: clamped at the last frame, and between frames a blend as when looping.
    let clamped = model.sample_clip(run, fps, 100.0, false).expect("sample");
    assert_eq!(clamped.positions, model.frame_pose(first + 5).expect("frame").positions);
    let quarter = model.sample_clip(run, fps, 2.25 / fps, false).expect("sample");
    for i in 0..quarter.positions.len() {
        let expected = a.positions[i] * 0.75 + b.positions[i] * 0.25;
        assert!((quarter.positions[i] - expected).length() < 1e-4, "vertex {i}");
    }
    // The model's last clip, clamped at its end, blends nothing from beyond it.
    let last = model.clips.len() - 1;
    let end = model.clips[last].frames.end;
    let held = model.sample_clip(last, fps, 100.0, false).expect("sample");
    assert_eq!(held.positions, model.frame_pose(end - 1).expect("frame").positions);
    // Six frames: 0.6 s looping (the last frame blends back into the first), 0.5 s once.
    assert_eq!(model.clip_duration(run, fps, true), Some(0.6));
    assert_eq!(model.clip_duration(run, fps, false), Some(0.5));
    assert_eq!(model.clip_duration(99, fps, true), None);
    // Bad input is an error, not a panic.
    assert!(model.sample_clip(99, fps, 0.0, true).is_err());
    assert!(model.sample_clip(run, 0.0, 0.0, true).is_err());
    assert!(model.sample_clip(run, fps, f64::NAN, true).is_err());
}

#[test]
fn every_clip_of_every_model_plays_finite() {
    for (file, ..) in MODELS {
        let model = load_md2_file(&corpus(file)).expect("import");
        for clip in 0..model.clips.len() {
            for step in 0..20 {
                let pose = model.sample_clip(clip, 9.0, step as f64 * 0.137, true).expect("sample");
                assert_eq!(pose.positions.len(), model.vertex_count());
                assert!(
                    pose.positions.iter().all(|p| p.is_finite() && p.abs().max_element() < 1e4),
                    "{file}"
                );
                assert!(pose.normals.iter().all(|n| (n.length() - 1.0).abs() < 1e-3), "{file}");
            }
        }
    }
}

#[test]
fn header_checks_name_the_byte() {
    let data = std::fs::read(corpus("dolphin/dolphin.md2")).expect("read");
    let mut bad = data.clone();
    bad[0] = b'X';
    let e = parse_md2(&bad).expect_err("bad magic");
    assert_eq!(e.offset, 0);
    assert!(matches!(e.kind, Md2ErrorKind::BadMagic { .. }));

    let mut bad = data.clone();
    bad[4] = 7;
    let e = parse_md2(&bad).expect_err("bad version");
    assert_eq!((e.offset, e.kind.clone()), (4, Md2ErrorKind::BadVersion { found: 7 }));

    let e = parse_md2(&data[..data.len() - 1]).expect_err("size");
    assert_eq!(e.offset, 64);
    assert!(matches!(e.kind, Md2ErrorKind::FileSizeMismatch { .. }));
    assert!(e.to_string().starts_with("byte 64: "), "{e}");
}

/// The skin names stored in each header (64-byte NUL-terminated strings at `ofs_skins`), read
/// here from the bytes as the format describes them.
#[test]
fn skin_names_are_read_from_the_header() {
    let mut named = 0;
    for (file, ..) in MODELS {
        let data = std::fs::read(corpus(file)).expect("read");
        let field =
            |i: usize| u32::from_le_bytes(data[4 * i..4 * i + 4].try_into().expect("4 bytes")) as usize;
        let (count, offset) = (field(5), field(11));
        let expected: Vec<String> = (0..count)
            .map(|i| {
                let raw = &data[offset + 64 * i..offset + 64 * (i + 1)];
                let end = raw.iter().position(|&b| b == 0).unwrap_or(64);
                String::from_utf8_lossy(&raw[..end]).into_owned()
            })
            .collect();
        let model = parse_md2(&data).unwrap_or_else(|e| panic!("{file}: {e}"));
        assert_eq!(model.skin_names, expected, "{file}");
        named += expected.iter().filter(|n| !n.is_empty()).count();
    }
    assert!(named > 0, "no corpus model stores a skin name: the test checked nothing");
}

/// The 162 MD2 vertex normals (Quake 2's `anorms.h`): unit vectors, all different, and the
/// set is symmetric under reflecting any axis — so an entry with a sign lost or flipped would
/// duplicate another. The first rows are id Software's.
#[test]
fn the_normal_table_is_quake2s_symmetric_set_of_unit_vectors() {
    use keyrig_io::md2::ANORMS;
    assert_eq!(ANORMS[0], [-0.525731, 0.000000, 0.850651]);
    assert_eq!(ANORMS[1], [-0.442863, 0.238856, 0.864188]);
    assert_eq!(ANORMS[161], [-0.688191, -0.587785, -0.425325]);
    let key = |v: [f32; 3]| v.map(|x| (x * 1e6).round() as i32);
    let set: std::collections::HashSet<[i32; 3]> = ANORMS.iter().map(|&v| key(v)).collect();
    assert_eq!(set.len(), ANORMS.len(), "two entries are the same vector");
    for v in ANORMS {
        let length = v.iter().map(|x| x * x).sum::<f32>().sqrt();
        assert!((length - 1.0).abs() < 1e-5, "{v:?} has length {length}");
        for axis in 0..3 {
            let mut mirrored = v;
            mirrored[axis] = -mirrored[axis];
            assert!(set.contains(&key(mirrored)), "{v:?} mirrored in axis {axis} is not in the table");
        }
    }
}

/// The frame range that shows a looping clip once: its last frame is the one before the loop
/// starts again; at least frame 1, at most a million, 60 when the length is not a number.
#[test]
fn a_looping_clip_fills_the_frame_range_once() {
    assert_eq!(frame_range_end(4.0, 30.0), 119);
    assert_eq!(frame_range_end(0.6, 24.0), 13);
    assert_eq!(frame_range_end(0.0, 30.0), 1);
    assert_eq!(frame_range_end(1e9, 30.0), 1_000_000);
    assert_eq!(frame_range_end(f64::NAN, 30.0), 60);
}

/// A normal index past the 162 of the table is refused at its byte: the fourth byte of the
/// packed vertex (x, y, z, normal) in the frame's data.
#[test]
fn a_normal_index_past_the_table_names_its_byte() {
    let mut data = std::fs::read(corpus("sydney/sydney.md2")).expect("read");
    let frames = u32::from_le_bytes(data[56..60].try_into().expect("4 bytes")) as usize;
    // A frame: scale (12 bytes), translate (12), name (16), then 4 bytes per vertex.
    let second_vertex_normal = frames + 40 + 4 + 3;
    data[second_vertex_normal] = 200;
    let err = parse_md2(&data).expect_err("normal index 200");
    assert_eq!(err.offset, second_vertex_normal, "{err}");
    assert!(matches!(err.kind, Md2ErrorKind::NormalIndex { index: 200 }), "{err}");
}

/// Every header count and offset that is negative is refused at its own field's byte, and an
/// array that reaches past the end of the file at its offset field's byte.
#[test]
fn negative_fields_and_arrays_past_the_end_name_their_header_field() {
    let data = std::fs::read(corpus("dolphin/dolphin.md2")).expect("read");
    let fields = [
        (4, "framesize"),
        (5, "num_skins"),
        (6, "num_xyz"),
        (7, "num_st"),
        (8, "num_tris"),
        (9, "num_glcmds"),
        (10, "num_frames"),
        (11, "ofs_skins"),
        (12, "ofs_st"),
        (13, "ofs_tris"),
        (14, "ofs_frames"),
        (15, "ofs_glcmds"),
    ];
    for (i, field) in fields {
        let mut bad = data.clone();
        bad[4 * i..4 * i + 4].copy_from_slice(&(-3i32).to_le_bytes());
        let e = parse_md2(&bad).expect_err(field);
        assert_eq!((e.offset, e.kind.clone()), (4 * i, Md2ErrorKind::Negative { field, value: -3 }), "{e}");
    }
    let len = data.len();
    // (offset field, its count field, what)
    for (i, count, what) in [
        (11, 5, "skins"),
        (12, 7, "texture coordinates"),
        (13, 8, "triangles"),
        (14, 10, "frames"),
        (15, 9, "GL commands"),
    ] {
        let mut bad = data.clone();
        bad[4 * i..4 * i + 4].copy_from_slice(&(len as i32 - 4).to_le_bytes());
        if bad[4 * count..4 * count + 4] == [0; 4] {
            bad[4 * count..4 * count + 4].copy_from_slice(&1i32.to_le_bytes());
        }
        let e = parse_md2(&bad).expect_err(what);
        assert_eq!(e.offset, 4 * i, "{what}: {e}");
        assert!(
            matches!(e.kind, Md2ErrorKind::ArrayOutOfFile { what: w, start, file_len, .. } if w == what && start == len - 4 && file_len == len),
            "{what}: {e}"
        );
    }
}

/// Looping playback at a time just below 0 (where `time · fps mod n` rounds up to `n`) is the
/// clip's first frame, never a frame of the next clip.
#[test]
fn looping_just_before_zero_is_the_first_frame() {
    let model = load_md2_file(&corpus("ratamahatta/ratamahatta.md2")).expect("load");
    let run = model.clips.iter().position(|c| c.name == "run").expect("run clip");
    let first = model.frame_pose(model.clips[run].frames.start).expect("frame");
    let pose = model.sample_clip(run, 10.0, -1e-300, true).expect("sample");
    assert_eq!(pose.positions.len(), first.positions.len());
    for (got, want) in pose.positions.iter().zip(&first.positions) {
        assert!((*got - *want).length() < 1e-4, "{got} against {want}");
    }
}

/// The skin a project would list for an MD2 file is the image `load_md2_file` loads; a model's
/// skin becomes a white material textured with its pixels.
#[test]
fn the_skin_beside_a_model_is_found_and_becomes_its_material() {
    for (file, .., skin) in MODELS {
        let path = corpus(file);
        let found = keyrig_io::md2::skin_of_file(&path).unwrap_or_else(|| panic!("{file}: no skin"));
        assert_eq!(found.file_name().and_then(|n| n.to_str()), Some(skin), "{file}");
        let model = load_md2_file(&path).expect("load");
        let image = model.skin.as_ref().expect("skin");
        assert_eq!(found, image.path, "{file}");
        let material = image.material().expect("material");
        assert_eq!(material.base_colour, [1.0; 4]);
        let texture = material.base_colour_texture.as_ref().expect("texture");
        assert_eq!((texture.width(), texture.height()), (image.width, image.height), "{file}");
    }
    assert_eq!(keyrig_io::md2::skin_of_file(&corpus("no/such.md2")), None);
}
