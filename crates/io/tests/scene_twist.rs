//! `assets/twist.ron`, the twist example of issue 14: the serialized `twist_scene()`, a forearm
//! turning a full revolution with two keys and a spin.
//!
//! After changing `keyrig_io::demo::twist_scene`, regenerate the file with
//! `KEYRIG_REGENERATE_DEMO=1 cargo test -p keyrig-io --test scene_twist`.

use std::path::Path;

use glam::{DQuat, DVec3, Quat, Vec3};
use keyrig_core::channel::ChannelPath;
use keyrig_core::{AnimatedTrack, Key, Spin};
use keyrig_io::demo::{twist_scene, TWIST_RON, TWIST_SECONDS};
use keyrig_io::scene_file;

#[test]
fn committed_twist_file_equals_generated_scene() {
    let generated = scene_file::to_string(&twist_scene()).expect("serialize twist scene");
    if std::env::var_os("KEYRIG_REGENERATE_DEMO").is_some() {
        let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../assets/twist.ron");
        std::fs::write(&path, &generated).expect("write assets/twist.ron");
        return;
    }
    assert!(
        TWIST_RON == generated,
        "assets/twist.ron differs from keyrig_io::demo::twist_scene(); regenerate it with \
         KEYRIG_REGENERATE_DEMO=1 cargo test -p keyrig-io --test scene_twist"
    );
    // The spin is written on the key's line, readably.
    assert!(
        TWIST_RON.contains(
            "(time: 2.0, value: (0.0, 0.0, 0.0, 1.0), spin: Some(Angle(axis: (1.0, 0.0, 0.0), degrees: 360.0))),"
        ),
        "{TWIST_RON}"
    );
}

#[test]
fn twist_scene_loads_and_turns_a_full_revolution_with_two_keys() {
    let scene = scene_file::from_str(TWIST_RON, Path::new("assets/twist.ron")).expect("twist.ron loads");
    assert_eq!(scene, twist_scene());
    assert_eq!(scene.problems(), Vec::new());
    let joints = &scene.objects[0].skeleton.as_ref().expect("a skeleton").joints;
    let forearm = joints.iter().find(|j| j.name == "forearm").expect("a forearm joint");
    assert_eq!(forearm.rotation.track.len(), 2, "exactly two keys");
    assert_eq!(forearm.rotation.track.keys[1].spin, Some(Spin::Angle { axis: Vec3::X, degrees: 360.0 }));

    let track = AnimatedTrack::new(&forearm.rotation).expect("valid");
    let track = track.track().expect("keyed");
    let twist_at = |t: f64| track.spin_degrees(t).expect("in the spin segment");
    // Mid-time: half a turn, about the bone axis (+X) exactly.
    let mid = TWIST_SECONDS / 2.0;
    assert!((twist_at(mid) - 180.0).abs() < 1e-9, "{}", twist_at(mid));
    let half = DQuat::from_axis_angle(DVec3::X, std::f64::consts::PI);
    let q = track.sample_wide(mid);
    assert!((q.dot(half).abs() - 1.0).abs() < 1e-12, "{q:?}");
    // The end: 360° unwrapped, back at the identity.
    assert!((twist_at(TWIST_SECONDS) - 360.0).abs() < 1e-9);
    // (as −1: the key takes the sign of q_0·exp(L), 360° being −1 as a quaternion)
    assert_eq!(track.sample(TWIST_SECONDS), -Quat::IDENTITY);
    // Monotonic in between (TCB eases in and out but never turns back).
    let mut previous = 0.0;
    for k in 1..=120 {
        let t = TWIST_SECONDS * f64::from(k) / 120.0;
        let degrees = twist_at(t);
        assert!(degrees > previous, "t = {t}: {degrees}° after {previous}°");
        // The sampled rotation is that angle about +X.
        let expected = DQuat::from_axis_angle(DVec3::X, degrees.to_radians());
        assert!((track.sample_wide(t).dot(expected).abs() - 1.0).abs() < 1e-12, "t = {t}");
        previous = degrees;
    }
    // The channel API (what `keyrig sample` prints) sees the same angle.
    let channel =
        ChannelPath::parse("object/Arm/joint/forearm/rotation").unwrap().resolve(&scene).expect("channel");
    assert!(channel.has_spin());
    assert_eq!(channel.spin_degrees(mid), Some(twist_at(mid)));
}

#[test]
fn spin_keys_survive_save_and_load_exactly() {
    // Every spin form, odd numbers included, written and read back bit for bit, twice.
    let mut scene = twist_scene();
    let joints = &mut scene.objects[0].skeleton.as_mut().unwrap().joints;
    let q = |deg: f32| Quat::from_axis_angle(Vec3::new(0.3, -0.5, 0.8).normalize(), deg.to_radians());
    let axis = Vec3::new(0.3, -0.5, 0.8);
    joints[1].rotation.track = keyrig_core::RawTrack::new(vec![
        Key::new(0.0, q(0.0)),
        Key::new(0.5, q(30.0)).with_spin(Spin::Turns(-2)),
        Key::new(1.0 / 3.0 + 1.0, q(30.0)).with_spin(Spin::Angle { axis, degrees: 720.0 }),
        Key::new(1.75, q(30.0 + 0.1)).with_spin(Spin::Angle { axis, degrees: -359.9 - 1e-12 }),
        Key::new(2.0, q(40.0)).with_spin(Spin::Turns(1000)),
        Key::new(2.5, q(40.0)).with_spin(Spin::Turns(0)),
    ]);
    let text = scene_file::to_string(&scene).unwrap();
    assert!(text.contains("spin: Some(Turns(-2))"), "{text}");
    assert!(text.contains("spin: Some(Turns(0))"), "{text}");
    let back = scene_file::from_str(&text, Path::new("spin.ron")).expect("loads");
    assert_eq!(back, scene);
    assert_eq!(scene_file::to_string(&back).unwrap(), text);
    // Through a file on disk too (save is atomic, load reads it back).
    let dir = std::env::temp_dir().join(format!("keyrig-spin-{}", std::process::id()));
    std::fs::create_dir_all(&dir).unwrap();
    let path = dir.join("spin.ron");
    scene_file::save(&path, &scene).expect("save");
    assert_eq!(scene_file::load(&path).expect("load"), scene);
    std::fs::remove_dir_all(&dir).ok();
}

mod round_trip {
    use super::*;
    use keyrig_core::{Object, RawTrack, Scene};
    use proptest::prelude::*;

    fn spin() -> impl Strategy<Value = Spin> {
        prop_oneof![
            (-1000..=1000i32).prop_map(Spin::Turns),
            (any::<f32>(), any::<f32>(), any::<f32>(), any::<f64>())
                .prop_filter("finite", |(x, y, z, d)| [*x, *y, *z].iter().all(|v| v.is_finite())
                    && d.is_finite())
                .prop_map(|(x, y, z, degrees)| Spin::Angle { axis: Vec3::new(x, y, z), degrees }),
        ]
    }

    proptest! {
        #![proptest_config(ProptestConfig::with_cases(256))]

        /// Any spin (valid for the keys or not: problems are not the point here) is written
        /// and read back bit for bit, and written again to the same bytes.
        #[test]
        fn save_then_load_keeps_spins_exactly(spins in prop::collection::vec(prop::option::of(spin()), 1..6)) {
            let mut scene = Scene::default();
            let mut o = Object::new("Arm");
            o.rotation.track = RawTrack::new(
                spins.iter().enumerate().map(|(i, s)| {
                    let mut k = Key::new(i as f64 * 0.25, Quat::from_rotation_x(i as f32));
                    k.spin = *s;
                    k
                }).collect(),
            );
            scene.objects.push(o);
            let text = scene_file::to_string(&scene).unwrap();
            let (back, _problems) = scene_file::from_str_lenient(&text, Path::new("spin.ron")).expect("parses");
            let spins_back: Vec<Option<Spin>> = back.objects[0].rotation.track.keys.iter().map(|k| k.spin).collect();
            // Bit for bit (PartialEq would call −0.0 and 0.0 equal).
            let bits = |s: &Option<Spin>| match s {
                None => None,
                Some(Spin::Turns(n)) => Some((0, *n as u64, [0; 3])),
                Some(Spin::Angle { axis, degrees }) => Some((1, degrees.to_bits(), axis.to_array().map(f32::to_bits))),
            };
            prop_assert_eq!(spins.iter().map(bits).collect::<Vec<_>>(), spins_back.iter().map(bits).collect::<Vec<_>>());
            prop_assert_eq!(&back, &scene);
            prop_assert_eq!(scene_file::to_string(&back).unwrap(), text);
        }
    }

    #[test]
    fn a_bad_spin_is_located_in_the_text() {
        let text = TWIST_RON.replace("degrees: 360.0", "degrees: 350.0");
        let err = scene_file::from_str(&text, Path::new("twist.ron")).unwrap_err().to_string();
        assert!(err.contains("joints[2].rotation.track[1].spin"), "{err}");
        assert!(err.contains("Angle arrives at a rotation more than"), "{err}");
        let (_, problems) = scene_file::from_str_lenient(&text, Path::new("twist.ron")).unwrap();
        let line = problems[0].position.expect("located").0;
        assert!(text.lines().nth(line - 1).unwrap().contains("degrees: 350.0"), "line {line}");
    }
}
