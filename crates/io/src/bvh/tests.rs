//! The reader on small and hostile files: every error is typed, placed and never a panic.

use super::*;

const SMALL: &str = "HIERARCHY
ROOT Hips
{
\tOFFSET 0 0 0
\tCHANNELS 6 Xposition Yposition Zposition Zrotation Xrotation Yrotation
\tJOINT Chest
\t{
\t\tOFFSET 0 1 0
\t\tCHANNELS 3 Xrotation Yrotation Zrotation
\t\tEnd Site
\t\t{
\t\t\tOFFSET 0 0.5 0
\t\t}
\t}
}
MOTION
Frames: 2
Frame Time: 0.0333333
1 2 3 10 20 30 40 50 60
4 5 6 -10 -20 -30 -40 -50 -60
";

fn err(text: &str) -> BvhError {
    match parse_bvh(text, Some(Path::new("t.bvh"))) {
        Ok(f) => panic!("accepted: {f:?}"),
        Err(e) => e,
    }
}

/// The error's text, which must name the file and a place.
fn placed(text: &str) -> String {
    let e = err(text);
    assert!(e.place.is_some(), "no place: {e}");
    let s = e.to_string();
    assert!(s.starts_with("t.bvh:"), "{s}");
    s
}

#[test]
fn a_small_file_reads_with_its_channels_and_orders() {
    let f = parse_bvh(SMALL, None).expect("valid");
    assert_eq!(f.joints.len(), 3);
    assert_eq!((f.frames, f.channel_count, f.fps), (2, 9, 30.0));
    assert_eq!(f.joints[0].euler_order(), Some(EulerOrder::YXZ), "Z X Y listed: Y turns first");
    assert_eq!(f.joints[1].euler_order(), Some(EulerOrder::ZYX), "X Y Z listed: Z turns first");
    assert!(f.joints[2].end_site);
    assert_eq!(f.joint_values(0, 1, false), Vec3::new(4.0, 5.0, 6.0));
    // Zrotation Xrotation Yrotation = -10 -20 -30: z = -10, x = -20, y = -30.
    assert_eq!(f.joint_values(0, 1, true), Vec3::new(-20.0, -30.0, -10.0));
    assert_eq!(f.joint_values(1, 0, true), Vec3::new(40.0, 50.0, 60.0));
    let scene = f.to_scene("small");
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    let s = scene.objects[0].skeleton.as_ref().expect("skeleton");
    let names: Vec<&str> = s.joints.iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names, ["Hips", "Chest", "Chest_end"]);
    assert_eq!(s.joints[2].rest_translation, Vec3::new(0.0, 0.5, 0.0));
    assert_eq!(scene.frame_range, keyrig_core::FrameRange { start: 0, end: 1 });
    let euler = s.joints[0].rotation_euler.as_ref().expect("Euler keys");
    assert_eq!(euler.track.keys[1].time, 1.0 / 30.0);
    assert_eq!(euler.track.keys[1].interpolation, Interpolation::Linear);
}

#[test]
fn the_euler_order_is_the_bvh_product_in_listed_order() {
    // R = Rz(a)·Rx(b)·Ry(c) for `Zrotation Xrotation Yrotation a b c`.
    let f = parse_bvh(SMALL, None).expect("valid");
    let order = f.joints[0].euler_order().expect("order");
    let (a, b, c) = (-10f32.to_radians(), -20f32.to_radians(), -30f32.to_radians());
    let bvh = Quat::from_rotation_z(a) * Quat::from_rotation_x(b) * Quat::from_rotation_y(c);
    let keyrig = order.to_quat(f.joint_values(0, 1, true));
    assert!(bvh.dot(keyrig).abs() > 1.0 - 1e-6, "{bvh} vs {keyrig}");
    // Fewer rotation channels: the missing axes go last.
    let two = SMALL.replace("CHANNELS 3 Xrotation Yrotation Zrotation", "CHANNELS 2 Zrotation Xrotation");
    let two = two.replace("40 50 60\n", "40 50\n").replace("-40 -50 -60\n", "-40 -50\n");
    let f = parse_bvh(&two, None).expect("valid");
    assert_eq!(f.joints[1].euler_order(), Some(EulerOrder::XZY));
    let v = f.joint_values(1, 0, true);
    let bvh = Quat::from_rotation_z(40f32.to_radians()) * Quat::from_rotation_x(50f32.to_radians());
    assert!(bvh.dot(EulerOrder::XZY.to_quat(v)).abs() > 1.0 - 1e-6);
}

#[test]
fn frame_times_snap_to_whole_rates_only_when_the_digits_say_so() {
    assert_eq!(fps_of_frame_time(0.0083333, ".0083333"), 120.0);
    assert_eq!(fps_of_frame_time(0.033333, "0.033333"), 30.0);
    assert_eq!(fps_of_frame_time(1.0 / 120.0, "0.008333333333333333"), 120.0);
    assert_eq!(fps_of_frame_time(0.04, "0.04"), 25.0);
    let ntsc = fps_of_frame_time(0.0333667, "0.0333667");
    assert!((ntsc - 29.97).abs() < 0.01 && ntsc != 30.0, "{ntsc}");
    assert_eq!(fps_of_frame_time(0.008, "0.008"), 125.0);
    // Four decimals cannot tell 120 from 120.48: 1/120 written to four decimals is 0.0083.
    assert_eq!(fps_of_frame_time(0.0083, "0.0083"), 120.0);
    // Eight decimals can: 1/81 is 0.01234568.
    let f = fps_of_frame_time(0.01234567, "0.01234567");
    assert!(f != 81.0 && (f - 81.0).abs() < 1e-3, "{f}");
    assert_eq!(fps_of_frame_time(1.0 / 90.0, "1.1111111e-2"), 90.0);
}

#[test]
fn empty_and_truncated_files_are_errors() {
    let e = err("");
    assert!(matches!(e.kind, BvhErrorKind::Truncated(_)), "{e}");
    assert!(err("   \n\n").to_string().contains("empty"));
    // Every prefix of the small file is refused (or, cut inside the last number, read with
    // that number shorter), never a panic.
    for cut in 0..SMALL.len() {
        let text = &SMALL[..cut];
        if let Err(e) = parse_bvh(text, None) {
            assert!(e.place.is_some(), "cut {cut}: {e}");
        } else {
            assert!(cut > SMALL.len() - 5, "cut {cut} accepted");
        }
    }
    let s = placed(&SMALL[..SMALL.len() - 20]);
    assert!(s.contains("truncated") && s.contains("frame 1"), "{s}");
}

#[test]
fn a_channel_count_that_disagrees_with_the_data_is_refused() {
    let short = SMALL.replace("4 5 6 -10", "4 5 -10");
    let s = placed(&short);
    assert!(s.contains("frame 1 has 8 values") && s.contains(":20:"), "{s}");
    let long = SMALL.replace("1 2 3 10", "1 2 3 0 10");
    let s = placed(&long);
    assert!(s.contains("more than 9 values"), "{s}");
    // CHANNELS says 3 but names 2: the third name is the next keyword.
    let s =
        placed(&SMALL.replace("CHANNELS 3 Xrotation Yrotation Zrotation", "CHANNELS 3 Xrotation Yrotation"));
    assert!(s.contains("expected a channel name") && s.contains("`End`"), "{s}");
    let s = placed(&SMALL.replace("CHANNELS 3 X", "CHANNELS 7 X"));
    assert!(s.contains("0 to 6 channels"), "{s}");
    let s = placed(&SMALL.replace("Xrotation Yrotation Zrotation", "Xrotation Xrotation Zrotation"));
    assert!(s.contains("listed twice"), "{s}");
    let s = placed(&SMALL.replace("Frames: 2", "Frames: 3"));
    assert!(s.contains("truncated"), "{s}");
    let s = placed(&SMALL.replace("Frames: 2", "Frames: 1"));
    assert!(s.contains("after the last of the 1 frames"), "{s}");
}

#[test]
fn non_finite_and_absurd_values_are_refused() {
    for bad in
        ["NaN", "nan", "inf", "-inf", "infinity", "1e300", "1e39", "2e6", "-1000001", "0x10", "1,5", "--1"]
    {
        let in_motion = SMALL.replace("1 2 3 10", &format!("1 2 {bad} 10"));
        let s = placed(&in_motion);
        assert!(s.contains(":19:"), "{bad}: {s}");
        let in_offset = SMALL.replace("OFFSET 0 1 0", &format!("OFFSET 0 {bad} 0"));
        let s = placed(&in_offset);
        assert!(s.contains(":8:"), "{bad}: {s}");
    }
    for bad in ["0", "-0.1", "NaN", "inf", "1e-9", "7200"] {
        let s = placed(&SMALL.replace("0.0333333", bad));
        assert!(s.contains("frame time") || s.contains("expected"), "{bad}: {s}");
    }
}

#[test]
fn a_billion_declared_frames_allocate_nothing() {
    let text = SMALL.replace("Frames: 2", "Frames: 1000000000");
    let s = placed(&text);
    assert!(s.contains("declares 1000000000 frames") && s.contains("hold at most"), "{s}");
    let s = placed(&SMALL.replace("Frames: 2", "Frames: 99999999999999999999"));
    assert!(s.contains("frame count"), "{s}");
    let s = placed(&SMALL.replace("Frames: 2", "Frames: 4000000000"));
    assert!(s.contains("frame numbers go up to"), "{s}");
    // Without channels nothing is read per frame, and nothing is allocated for them either.
    let none =
        "HIERARCHY\nROOT a\n{\nOFFSET 0 0 0\nCHANNELS 0\n}\nMOTION\nFrames: 2000000000\nFrame Time: 1\n";
    let f = parse_bvh(none, None).expect("valid");
    assert!(f.values.is_empty());
    let scene = f.to_scene("x");
    assert_eq!(scene.frame_range.end, 1_999_999_999);
    assert!(scene.problems().is_empty());
}

#[test]
fn a_10000_deep_hierarchy_reads_without_recursion() {
    let depth = 10_000;
    let mut text = String::from("HIERARCHY\n");
    for i in 0..depth {
        text.push_str(if i == 0 { "ROOT j0\n{\nOFFSET 0 0 0\nCHANNELS 6 Xposition Yposition Zposition Zrotation Yrotation Xrotation\n" } else { "" });
        if i > 0 {
            text.push_str(&format!("JOINT j{i}\n{{\nOFFSET 0 0.01 0\nCHANNELS 1 Zrotation\n"));
        }
    }
    text.push_str("End Site\n{\nOFFSET 0 0.01 0\n}\n");
    text.push_str(&"}\n".repeat(depth));
    text.push_str("MOTION\nFrames: 1\nFrame Time: 0.1\n0 0 0 0 0 0");
    text.push_str(&" 1".repeat(depth - 1));
    text.push('\n');
    // A small stack, so recursion would show.
    let handle = std::thread::Builder::new()
        .stack_size(256 << 10)
        .spawn(move || {
            let f = parse_bvh(&text, None).expect("valid");
            let scene = f.to_scene("deep");
            (
                f.joints.len(),
                scene.problems().len(),
                scene.objects[0].skeleton.as_ref().map(|s| s.joints.len()),
            )
        })
        .expect("thread");
    let (joints, problems, scene_joints) = handle.join().expect("no stack overflow");
    assert_eq!((joints, problems, scene_joints), (depth + 1, 0, Some(depth + 1)));
}

#[test]
fn long_names_are_kept_and_quoted_short() {
    let name = "n".repeat(70_000);
    let text = SMALL.replace("JOINT Chest", &format!("JOINT {name}"));
    let f = parse_bvh(&text, None).expect("valid");
    assert_eq!(f.joints[1].name.len(), 70_000);
    let scene = f.to_scene("long");
    assert!(scene.problems().is_empty());
    assert_eq!(scene.objects[0].skeleton.as_ref().map(|s| s.joints[2].name.len()), Some(70_004));
    // A 70,000-character token where a keyword belongs: the message quotes it clipped.
    let s = placed(&SMALL.replace("\t\tEnd Site", &format!("\t\t{name}")));
    assert!(s.len() < 400 && s.contains("(70002 bytes)"), "{}", &s[..s.len().min(400)]);
}

#[test]
fn structure_errors_name_the_place() {
    let cases: &[(&str, &str, &str)] = &[
        ("HIERARCHY", "HIERARCH", "starts with `HIERARCHY`"),
        ("ROOT Hips", "ROOT", "needs a name"),
        ("\t\tOFFSET 0 1 0\n", "", "has no OFFSET"),
        ("OFFSET 0 1 0", "OFFSET 0 1 0 OFFSET 0 1 0", "second OFFSET"),
        ("MOTION", "MOTON", "expected `MOTION`"),
        ("Frames: 2", "Frames 2", "expected `:`"),
        ("Frames: 2", "Frames: -2", "frame count"),
        ("Frame Time:", "Frame Tim:", "Frame Time:"),
        ("\t\tEnd Site", "\t\tEnd Sight", "expected `Site`"),
        ("\t\t\tOFFSET 0 0.5 0\n", "\t\t\tOFFSET 0 0.5 0\nCHANNELS 1 Xrotation\n", "in an End Site"),
        ("}\nMOTION", "}\nROOT b\n{\nOFFSET 0 0 0\n}\nMOTION", "one skeleton"),
        ("0.0333333", "0.0333333 7", "after the frame time"),
    ];
    for (from, to, message) in cases {
        assert!(SMALL.contains(from), "{from}");
        let s = placed(&SMALL.replacen(from, to, 1));
        assert!(s.contains(message), "{from} → {to}: {s}");
    }
}

#[test]
fn bytes_that_are_not_utf8_are_refused_with_their_place() {
    let mut bytes = SMALL.as_bytes().to_vec();
    bytes[20] = 0xff;
    let e = parse_bvh_bytes(&bytes, Some(Path::new("x.bvh"))).expect_err("not UTF-8");
    assert!(matches!(e.kind, BvhErrorKind::NotUtf8(_)));
    assert_eq!(e.place.map(|p| p.line), Some(3));
    // A byte-order mark and CR LF line ends are fine.
    let crlf = format!("\u{feff}{}", SMALL.replace('\n', "\r\n"));
    assert_eq!(parse_bvh(&crlf, None).expect("valid").values, parse_bvh(SMALL, None).expect("valid").values);
}

#[test]
fn names_are_made_valid_and_unique() {
    let text = SMALL.replace("JOINT Chest", "JOINT Hips").replace("ROOT Hips", "ROOT a/b");
    let scene = parse_bvh(&text, None).expect("valid").to_scene("");
    assert!(scene.problems().is_empty(), "{:?}", scene.problems());
    let s = scene.objects[0].skeleton.as_ref().expect("skeleton");
    let names: Vec<&str> = s.joints.iter().map(|j| j.name.as_str()).collect();
    assert_eq!(names, ["a_b", "Hips", "Hips_end"]);
    assert_eq!(scene.objects[0].name, "BVH");
    assert!(is_bvh_path(Path::new("a/b.BVH")) && !is_bvh_path(Path::new("a.bvh.ron")));
}

#[test]
fn names_with_spaces_and_braces_on_the_name_line() {
    let text = SMALL.replace("JOINT Chest\n\t{", "JOINT Left Chest {");
    let f = parse_bvh(&text, None).expect("valid");
    assert_eq!(f.joints[1].name, "Left Chest");
    let out = export::bvh_text(&f.to_scene("x"), 0).expect("export");
    assert!(out.contains("JOINT Left_Chest\n"), "{out}");
}

#[test]
fn a_file_without_frames_is_a_rest_pose() {
    let text = SMALL.replace("Frames: 2", "Frames: 0");
    let text = &text[..text.find("1 2 3 10").expect("motion")];
    let f = parse_bvh(text, None).expect("valid");
    let scene = f.to_scene("rest");
    assert!(scene.problems().is_empty());
    assert_eq!(scene.frame_range.end, 0);
    let j = &scene.objects[0].skeleton.as_ref().expect("skeleton").joints[0];
    assert!(j.rotation_euler.is_none() && !j.translation.is_animated());
}
