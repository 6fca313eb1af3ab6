//! Curve clean-up (docs/cleanup.md): key reduction of the CMU 131 walk within 0.5° and 1 mm,
//! checked independently through the scene evaluator at every frame; the Butterworth filter
//! against its analytic magnitude and against scipy's numbers; and the edge cases.

// scipy's numbers are kept as it printed them (17 significant digits).
#![allow(clippy::excessive_precision)]

use std::path::Path;

use glam::{DQuat, Quat, Vec3};
use keyrig_core::{Animated, Interpolation, Key, Object, RawTrack, Scene};
use keyrig_edit::channels::{self, ChannelId, ChannelValue};
use keyrig_edit::cleanup::{
    butterworth_lowpass, filtfilt, key_total, keyed_channels, reduce_keys, smooth_keys, CleanupError,
    ReduceTolerance, Skipped,
};
use keyrig_edit::SceneEdit;
use keyrig_eval::{Overrides, SceneEvaluator};

/// Metres per unit of the CMU BVH files converted by cgspeed (the corpus take): the CMU
/// skeletons are in units of 1/0.45 inch (mocap.cs.cmu.edu FAQ: "(1.0/0.45)*2.54/100"), which
/// the take's hips height of about 16.9 units (0.95 m) agrees with.
const CMU_METRES_PER_UNIT: f64 = (1.0 / 0.45) * 2.54 / 100.0;

fn cmu_take() -> Scene {
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../../tests/corpus/bvh/cmu-bvh11/131_01.bvh");
    keyrig_io::bvh::import_scene(&path).expect("the corpus take reads")
}

/// The angle (degrees) between two rotations, computed here from the quaternions.
fn angle_deg(a: Quat, b: Quat) -> f64 {
    let (a, b) = (a.as_dquat().normalize(), b.as_dquat().normalize());
    let d = a.dot(b).abs().min(1.0);
    // acos is ill-conditioned near 1: use the half-angle sine of the difference instead.
    let b = if a.dot(b) < 0.0 { -b } else { b };
    let s = (a - b).length() / 2.0; // = sin(θ/4)·… exactly: |a − b| = 2·sin(θ/4)
    let from_chord = 4.0 * s.asin();
    assert!((from_chord - 2.0 * d.acos()).abs() < 1e-3, "the two formulas agree");
    from_chord.to_degrees()
}

/// Largest differences between two scenes' joint channels, through the scene evaluator at
/// every frame of the range: (rotation angle in degrees, translation distance in scene units).
fn max_deviation(original: &Scene, reduced: &Scene) -> (f64, f64) {
    let none = Overrides::default();
    let a = SceneEvaluator::new(original, &Default::default());
    let b = SceneEvaluator::new(reduced, &Default::default());
    let joints = original.objects[0].skeleton.as_ref().unwrap().joints.len();
    let (mut angle, mut distance) = (0.0f64, 0.0f64);
    for frame in original.frame_range.start..=original.frame_range.end {
        let t = f64::from(frame) / original.fps;
        for joint in 0..joints {
            let rotation = ChannelId::JointRotation { object: 0, joint };
            let (Some(ChannelValue::Rotation(qa)), Some(ChannelValue::Rotation(qb))) =
                (a.value(rotation, t, &none), b.value(rotation, t, &none))
            else {
                panic!("joint {joint} has a rotation")
            };
            angle = angle.max(angle_deg(qa, qb));
            let translation = ChannelId::JointTranslation { object: 0, joint };
            let (Some(ChannelValue::Vec3(pa)), Some(ChannelValue::Vec3(pb))) =
                (a.value(translation, t, &none), b.value(translation, t, &none))
            else {
                panic!("joint {joint} has a translation")
            };
            distance = distance.max(f64::from((pa - pb).length()));
        }
    }
    (angle, distance)
}

#[test]
fn cmu_walk_reduced_within_half_a_degree_and_a_millimetre_keeps_a_tenth_of_its_keys() {
    let original = cmu_take();
    assert_eq!(original.fps.round(), 120.0);
    let channels = keyed_channels(&original, None);
    // 31 joints with rotation keys, and the hips' position.
    assert_eq!(channels.len(), 32);
    let before = key_total(&original, &channels);
    assert_eq!(before, 32 * 994);
    let millimetre = 0.001 / CMU_METRES_PER_UNIT;
    let tolerance = ReduceTolerance { angle_deg: 0.5, distance: millimetre, value: millimetre };
    let mut reduced = original.clone();
    let report = reduce_keys(&mut reduced, &channels, tolerance).unwrap();
    let after = key_total(&reduced, &channels);
    eprintln!(
        "CMU 131_01: {before} keys → {after} ({:.1} %), report {report:?}",
        100.0 * after as f64 / before as f64
    );
    assert!(report.skipped.is_empty(), "{:?}", report.skipped);
    assert_eq!((report.keys_before, report.keys_after), (before, after));
    assert!(after * 10 <= before, "{after} of {before} keys kept");
    let (angle, distance) = max_deviation(&original, &reduced);
    eprintln!(
        "through the evaluator: {angle:.4}° and {:.4} mm at most",
        distance * CMU_METRES_PER_UNIT * 1000.0
    );
    assert!(angle <= 0.5, "{angle}°");
    assert!(distance <= millimetre, "{distance} units");
    assert!(report.max_angle_deg <= 0.5 && report.max_distance <= millimetre);
    // The evaluator's numbers and the report's agree (the same samples: every frame).
    assert!((report.max_angle_deg - angle).abs() < 1e-3, "{} vs {angle}", report.max_angle_deg);
}

/// scipy 1.17.1, `signal.butter(2, fc / (fs / 2))` (printed with 17 digits).
const SCIPY_BUTTER: [(f64, f64, [f64; 3], [f64; 3]); 2] = [
    (
        6.0,
        120.0,
        [0.020083365564211232, 0.040166731128422464, 0.020083365564211232],
        [1.0, -1.5610180758007182, 0.64135153805756306],
    ),
    (
        10.0,
        30.0,
        [0.46515307716504667, 0.93030615433009334, 0.46515307716504667],
        [1.0, 0.62020410288672834, 0.24040820577345734],
    ),
];

#[test]
fn butterworth_coefficients_are_scipys() {
    for (fc, fs, b, a) in SCIPY_BUTTER {
        let f = butterworth_lowpass(fc, fs).unwrap();
        for i in 0..3 {
            assert!((f.b[i] - b[i]).abs() < 1e-14, "{fc} Hz at {fs}: b{i} {} vs {}", f.b[i], b[i]);
            assert!((f.a[i] - a[i]).abs() < 1e-14, "{fc} Hz at {fs}: a{i} {} vs {}", f.a[i], a[i]);
        }
    }
}

#[test]
fn filtfilt_matches_scipy_on_a_short_signal() {
    // scipy: x = [sin(0.3 i) + 0.5 sin(2.9 i) + 0.01 i² for i in range(25)];
    // signal.filtfilt(*signal.butter(2, 6 / 60), x).
    let x: Vec<f64> =
        (0..25).map(f64::from).map(|i| (0.3 * i).sin() + 0.5 * (2.9 * i).sin() + 0.01 * i * i).collect();
    let scipy = [
        0.0053959270070289313,
        0.22254691344879513,
        0.42443798385130405,
        0.60310959998307812,
        0.75238151732481884,
        0.86869362690261853,
        0.95175493097145913,
        1.0049116593883187,
        1.0351720166761758,
        1.052882141499196,
        1.0710711411091149,
        1.1045337523351524,
        1.1687299255475538,
        1.2786101538059773,
        1.4474689400402219,
        1.6859293453743751,
        2.0011396463285798,
        2.3962361748820165,
        2.8700970817159499,
        3.4173680032020002,
        4.0287165595134713,
        4.6912294424311805,
        5.3888612626480912,
        6.1028214748974481,
        6.811812449940124,
    ];
    let y = filtfilt(&butterworth_lowpass(6.0, 120.0).unwrap(), &x);
    assert_eq!(y.len(), scipy.len());
    for (i, (got, want)) in y.iter().zip(scipy).enumerate() {
        assert!((got - want).abs() < 1e-12, "sample {i}: {got} vs scipy's {want}");
    }
}

/// The analytic magnitude of an order-n Butterworth low-pass run forwards and backwards:
/// `|H(f)|² = 1 / (1 + (f/fc)^(2n))`, with the bilinear transform's frequency warping
/// (`f → tan(π f / fs)`, the cutoff pre-warped the same way).
fn filtfilt_gain(f: f64, fc: f64, fs: f64) -> f64 {
    let w = (std::f64::consts::PI * f / fs).tan() / (std::f64::consts::PI * fc / fs).tan();
    1.0 / (1.0 + w.powi(4))
}

/// Amplitude of the `f` Hz component of `y` (sampled at `fs`), by projection on sine and
/// cosine over whole periods.
fn amplitude(y: &[f64], f: f64, fs: f64) -> f64 {
    let w = 2.0 * std::f64::consts::PI * f / fs;
    let (mut s, mut c) = (0.0, 0.0);
    for (i, v) in y.iter().enumerate() {
        s += v * (w * i as f64).sin();
        c += v * (w * i as f64).cos();
    }
    2.0 * (s * s + c * c).sqrt() / y.len() as f64
}

#[test]
fn smoothing_a_channel_attenuates_as_the_analytic_butterworth_magnitude_squared() {
    // A scalar channel keyed at every frame of 10 s at 120 fps: 1 Hz (passes) plus 20 Hz
    // (well above a 6 Hz cutoff).
    let fs = 120.0;
    let (low, high, fc) = (1.0, 20.0, 6.0);
    let value = |t: f64| {
        (2.0 * std::f64::consts::PI * low * t).sin() + 0.5 * (2.0 * std::f64::consts::PI * high * t).sin()
    };
    let keys: Vec<Key<Vec3>> = (0..1200)
        .map(|f| {
            let t = f64::from(f) / fs;
            Key::new(t, Vec3::new(value(t) as f32, 0.0, 0.0)).with_interpolation(Interpolation::Linear)
        })
        .collect();
    let mut scene = Scene { fps: fs, ..Scene::default() };
    let mut object = Object::new("Box".to_owned());
    object.scale = Animated::new(Vec3::ONE, RawTrack::new(keys));
    scene.objects.push(object);
    let id = ChannelId::ObjectScale(0);
    let report = smooth_keys(&mut scene, &[id], fc).unwrap();
    assert_eq!((report.channels, report.keys_before, report.keys_after), (1, 1200, 1200));
    let y: Vec<f64> = (0..1200)
        .map(|i| match channels::key_value(&scene, id, i) {
            Some(ChannelValue::Vec3(v)) => f64::from(v.x),
            other => panic!("{other:?}"),
        })
        .collect();
    // Away from the ends (the padding's transient), whole periods of both components.
    let middle = &y[120..1080];
    let (a_low, a_high) = (amplitude(middle, low, fs), amplitude(middle, high, fs));
    let (g_low, g_high) = (filtfilt_gain(low, fc, fs), filtfilt_gain(high, fc, fs));
    eprintln!("1 Hz: {a_low:.6} (expected {g_low:.6}); 20 Hz: {:.6} (expected {g_high:.6})", a_high / 0.5);
    assert!((a_low - g_low).abs() < 2e-3, "{a_low} vs {g_low}");
    assert!((a_high / 0.5 - g_high).abs() < 2e-3, "{} vs {g_high}", a_high / 0.5);
    assert!(g_high < 0.01, "20 Hz is cut to under 1 %");
    // Without the bilinear warping the textbook |H|² at 20 Hz would be 1/(1 + (20/6)⁴).
    assert!((1.0 / (1.0 + (high / fc).powi(4)) - g_high).abs() < 0.01);
}

#[test]
fn smoothing_quaternion_keys_keeps_them_unit_and_removes_jitter() {
    let fs = 30.0;
    let keys: Vec<Key<Quat>> = (0..90)
        .map(|f| {
            let jitter = if f % 2 == 0 { 2.0f32 } else { -2.0 };
            let q = Quat::from_rotation_y((f as f32 * 1.0 + jitter).to_radians());
            // Every other key in the other hemisphere: the same rotation.
            let q = if f % 3 == 0 { -q } else { q };
            Key::new(f64::from(f) / fs, q).with_interpolation(Interpolation::Linear)
        })
        .collect();
    let mut scene = Scene { fps: fs, ..Scene::default() };
    let mut object = Object::new("Spinner".to_owned());
    object.rotation = Animated::new(Quat::IDENTITY, RawTrack::new(keys));
    scene.objects.push(object);
    let id = ChannelId::ObjectRotation(0);
    smooth_keys(&mut scene, &[id], 3.0).unwrap();
    for f in 10..80 {
        let Some(ChannelValue::Rotation(q)) = channels::key_value(&scene, id, f) else { panic!() };
        assert!((q.length() - 1.0).abs() < 1e-5);
        // The ±2° jitter at 15 Hz is gone: the key is within 0.1° of the steady 1° per frame.
        let want = Quat::from_rotation_y((f as f32).to_radians());
        assert!(angle_deg(q, want) < 0.1, "frame {f}: {}°", angle_deg(q, want));
    }
}

#[test]
fn refused_tolerances_and_cutoffs_change_nothing() {
    let original = cmu_take();
    let channels = keyed_channels(&original, None);
    let mut scene = original.clone();
    for bad in [f64::NAN, -1.0, f64::INFINITY] {
        let tolerance = ReduceTolerance { angle_deg: bad, ..ReduceTolerance::DEFAULT };
        assert!(matches!(
            reduce_keys(&mut scene, &channels, tolerance),
            Err(CleanupError::Tolerance { name: "angle", .. })
        ));
        let tolerance = ReduceTolerance { distance: bad, ..ReduceTolerance::DEFAULT };
        assert!(matches!(
            reduce_keys(&mut scene, &channels, tolerance),
            Err(CleanupError::Tolerance { name: "distance", .. })
        ));
        assert!(matches!(smooth_keys(&mut scene, &channels, bad), Err(CleanupError::Cutoff { .. })));
    }
    // At or above the Nyquist frequency (60 Hz at 120 fps), or zero.
    for bad in [0.0, 60.0, 100.0] {
        assert!(matches!(smooth_keys(&mut scene, &channels, bad), Err(CleanupError::Cutoff { .. })));
    }
    assert!(scene == original);
    // As an edit, a refused tolerance leaves the scene as it was.
    let edit = SceneEdit::ReduceKeys {
        channels: channels.clone(),
        tolerance: ReduceTolerance { angle_deg: f64::NAN, ..ReduceTolerance::DEFAULT },
    };
    edit.apply(&mut scene);
    assert!(scene == original);
}

#[test]
fn channels_with_no_one_or_two_keys_are_left_alone() {
    let mut scene = Scene { fps: 24.0, ..Scene::default() };
    let mut a = Object::new("None".to_owned());
    a.translation = Animated::constant(Vec3::X);
    let mut b = Object::new("One".to_owned());
    b.translation = Animated::new(Vec3::ZERO, RawTrack::new(vec![Key::new(0.0, Vec3::Y)]));
    let mut c = Object::new("Two".to_owned());
    c.translation =
        Animated::new(Vec3::ZERO, RawTrack::new(vec![Key::new(0.0, Vec3::Y), Key::new(1.0, Vec3::Z)]));
    scene.objects.extend([a, b, c]);
    let ids: Vec<ChannelId> = (0..3).map(ChannelId::ObjectTranslation).collect();
    let before = scene.clone();
    let report = reduce_keys(&mut scene, &ids, ReduceTolerance::DEFAULT).unwrap();
    assert_eq!(report.channels, 0);
    assert!(report.skipped.is_empty());
    smooth_keys(&mut scene, &ids, 5.0).unwrap();
    assert!(scene == before);
    // Channels that do not exist are reported, not a panic.
    let report =
        reduce_keys(&mut scene, &[ChannelId::ObjectTranslation(7)], ReduceTolerance::DEFAULT).unwrap();
    assert_eq!(report.skipped, vec![(ChannelId::ObjectTranslation(7), Skipped::NotCleanable)]);
}

#[test]
fn a_straight_line_reduces_to_its_ends_and_a_locked_channel_is_kept() {
    let keys: Vec<Key<Vec3>> = (0..=48)
        .map(|f| {
            Key::new(f64::from(f) / 24.0, Vec3::new(f as f32 * 0.1, 1.0, -2.0))
                .with_interpolation(Interpolation::Linear)
        })
        .collect();
    let mut scene = Scene { fps: 24.0, ..Scene::default() };
    let mut a = Object::new("Line".to_owned());
    a.translation = Animated::new(Vec3::ZERO, RawTrack::new(keys.clone()));
    let mut b = Object::new("Locked".to_owned());
    b.translation = Animated { locked: true, ..Animated::new(Vec3::ZERO, RawTrack::new(keys)) };
    scene.objects.extend([a, b]);
    let ids = [ChannelId::ObjectTranslation(0), ChannelId::ObjectTranslation(1)];
    let edit = SceneEdit::ReduceKeys { channels: ids.to_vec(), tolerance: ReduceTolerance::DEFAULT };
    assert_eq!(edit.label(&scene), "reduce keys of 2 channels within 0.5°, 0.001 (distance), 0.001 (value)");
    edit.apply(&mut scene);
    assert_eq!(channels::key_count(&scene, ids[0]), 2);
    assert_eq!(channels::key_count(&scene, ids[1]), 49);
    let report = reduce_keys(&mut scene, &ids, ReduceTolerance::DEFAULT).unwrap();
    assert_eq!(report.skipped, vec![(ids[1], Skipped::Locked)]);
    let smooth = SceneEdit::SmoothKeys { channels: vec![ids[0]], cutoff_hz: 4.0 };
    assert_eq!(smooth.label(&scene), "smooth Line translation below 4 Hz");
    // The quaternion angle helper agrees with glam's for a large angle.
    let q = Quat::from_rotation_x(1.0);
    assert!((angle_deg(Quat::IDENTITY, q) - 1f64.to_degrees()).abs() < 1e-4);
    let _ = DQuat::IDENTITY;
}

#[test]
fn keys_hours_apart_at_a_million_fps_are_left_alone_not_sampled() {
    // 3 keys over 2000 s at 10⁶ fps would be 2·10⁹ frames: refused, not allocated.
    let keys: Vec<Key<Vec3>> =
        [0.0, 1000.0, 2000.0].iter().map(|&t| Key::new(t, Vec3::splat(t as f32))).collect();
    let mut scene = Scene { fps: 1.0e6, ..Scene::default() };
    let mut object = Object::new("Far".to_owned());
    object.translation = Animated::new(Vec3::ZERO, RawTrack::new(keys));
    scene.objects.push(object);
    let id = ChannelId::ObjectTranslation(0);
    let before = scene.clone();
    let report = reduce_keys(&mut scene, &[id], ReduceTolerance::DEFAULT).unwrap();
    assert_eq!(report.skipped, vec![(id, Skipped::TooManyFrames)]);
    let report = smooth_keys(&mut scene, &[id], 10.0).unwrap();
    assert_eq!(report.skipped, vec![(id, Skipped::TooManyFrames)]);
    assert!(scene == before);
}

#[test]
fn quaternion_and_scalar_keys_reduce_within_their_tolerances() {
    // A key per frame for 4 s at 60 fps: a rotation wobbling about a turning axis (quaternion
    // keys, Linear, every other key in the other hemisphere) and a scalar light intensity.
    let fps = 60.0;
    let rotation = |t: f64| {
        Quat::from_rotation_y((90.0 * t) as f32 * std::f32::consts::PI / 180.0)
            * Quat::from_rotation_x((20.0 * (3.0 * t).sin()) as f32 * std::f32::consts::PI / 180.0)
    };
    let intensity = |t: f64| (2.0 + (1.5 * t).sin()) as f32;
    let rot_keys: Vec<Key<Quat>> = (0..=240)
        .map(|f| {
            let t = f64::from(f) / fps;
            let q = if f % 2 == 0 { rotation(t) } else { -rotation(t) };
            Key::new(t, q).with_interpolation(Interpolation::Linear)
        })
        .collect();
    let scalar_keys: Vec<Key<f32>> = (0..=240)
        .map(|f| {
            Key::new(f64::from(f) / fps, intensity(f64::from(f) / fps))
                .with_interpolation(Interpolation::Linear)
        })
        .collect();
    let mut scene = Scene { fps, ..Scene::default() };
    let mut object = Object::new("Wobble".to_owned());
    object.rotation = Animated::new(Quat::IDENTITY, RawTrack::new(rot_keys));
    scene.objects.push(object);
    let Some(keyrig_edit::scene_add::Added::Light(light)) = keyrig_edit::scene_add::build(
        keyrig_edit::scene_add::AddKind::PointLight,
        "Lamp".to_owned(),
        Vec3::ZERO,
    ) else {
        panic!("a point light")
    };
    scene.lights.push(light);
    scene.lights[0].intensity = Animated::new(1.0, RawTrack::new(scalar_keys));
    let original = scene.clone();
    let ids = [ChannelId::ObjectRotation(0), ChannelId::LightIntensity(0)];
    let tolerance = ReduceTolerance { angle_deg: 0.5, distance: 0.001, value: 0.01 };
    let report = reduce_keys(&mut scene, &ids, tolerance).unwrap();
    assert!(report.skipped.is_empty(), "{:?}", report.skipped);
    assert!(channels::key_count(&scene, ids[0]) * 4 < 241, "{}", channels::key_count(&scene, ids[0]));
    assert!(channels::key_count(&scene, ids[1]) * 4 < 241, "{}", channels::key_count(&scene, ids[1]));
    // Every frame, through the evaluator.
    let none = Overrides::default();
    let (a, b) = (
        SceneEvaluator::new(&original, &Default::default()),
        SceneEvaluator::new(&scene, &Default::default()),
    );
    for f in 0..=240 {
        let t = f64::from(f) / fps;
        let (Some(ChannelValue::Rotation(qa)), Some(ChannelValue::Rotation(qb))) =
            (a.value(ids[0], t, &none), b.value(ids[0], t, &none))
        else {
            panic!()
        };
        assert!(angle_deg(qa, qb) <= 0.5, "frame {f}: {}°", angle_deg(qa, qb));
        let (Some(ChannelValue::Scalar(x)), Some(ChannelValue::Scalar(y))) =
            (a.value(ids[1], t, &none), b.value(ids[1], t, &none))
        else {
            panic!()
        };
        assert!((x - y).abs() <= 0.01, "frame {f}: {x} vs {y}");
    }
}
