//! Where an imported model goes: beside what the scene already holds, as a layout tool places a
//! new part, instead of on top of it at the origin. The model moves along +X so that its box
//! (its meshes at rest, [`super::import`]) starts a gap past the scene's box (each object as
//! the viewport draws it now), keeping its own height and depth: characters imported one after
//! another stand in a row on the ground. The move is part of the import's one undo step; a
//! model imported into a scene with nothing in it stays where its file put it.
//!
//! Before it is placed, an imported model is scaled by the import scale ([`scale_by`], File ▸
//! Import scale, `keyrig import --scale`), and afterwards its size is compared with what the
//! scene holds ([`size_ratio`], [`size_warning`]): a model modelled in centimetres (the glTF Fox)
//! arrives a hundred times larger than the rest, which the status bar says.

use std::collections::HashMap;
use std::path::Path;

use glam::{Mat4, Vec3};
use keyrig_core::{Animated, Scene};

use super::meshes::FileMesh;
use super::LoadedMesh;
use crate::camera::Bounds;

/// The gap between the scene's box and the placed model, as a fraction of the wider of the
/// two along X (at least [`MIN_GAP`]).
pub const GAP_FRACTION: f32 = 0.25;
/// The smallest gap, metres (scene units).
pub const MIN_GAP: f32 = 0.1;

/// The box of an imported model at rest: its meshes' vertices in world space and the origins
/// of its objects without a mesh; `None` when it has nothing with a place.
#[must_use]
pub fn model_bounds(scene: &Scene, meshes: &[LoadedMesh]) -> Option<Bounds> {
    let meshless = scene.objects.iter().filter(|o| o.mesh.is_none()).map(|o| o.translation.value);
    Bounds::of(rest_points(scene, meshes).into_iter().chain(meshless))
}

/// How far a model whose box is `model` moves to stand beside `scene` (the box of what the
/// scene holds): along +X only, so that the model's left side is a gap past the scene's right
/// side. Zero when the scene holds nothing with a place.
#[must_use]
pub fn offset_beside(scene: Option<Bounds>, model: Bounds) -> Vec3 {
    let Some(scene) = scene else { return Vec3::ZERO };
    let wider = (scene.max.x - scene.min.x).max(model.max.x - model.min.x);
    let gap = (wider * GAP_FRACTION).max(MIN_GAP);
    Vec3::X * (scene.max.x + gap - model.min.x)
}

/// Moves every object and light of `scene` by `offset`: each translation's static value and
/// keys (tangents and cycles are differences, unchanged), each light's position.
pub fn move_by(scene: &mut Scene, offset: Vec3) {
    if offset == Vec3::ZERO {
        return;
    }
    let shift = |a: &mut Animated<Vec3>| {
        a.value += offset;
        if !a.track.keys.is_empty() {
            for key in a.track.keys.iter_mut() {
                key.value += offset;
            }
        }
    };
    for object in &mut scene.objects {
        shift(&mut object.translation);
    }
    for light in &mut scene.lights {
        shift(&mut light.position);
    }
}

/// The smallest and largest import scale taken ([`parse_import_scale`]).
pub const SCALE_LIMITS: (f32, f32) = (1e-6, 1e6);

/// Reads an import scale typed by the user or given to `keyrig import --scale`: a finite
/// number within [`SCALE_LIMITS`]; anything else (0, a negative number, NaN, text) is refused
/// with a message saying what is taken.
///
/// # Errors
/// The message for the user.
pub fn parse_import_scale(text: &str) -> Result<f32, String> {
    let text = text.trim();
    let value: f32 = text.parse().map_err(|_| {
        format!("import scale {text:?} is not a number (1 keeps the file's unit, 0.01 turns centimetres into metres)")
    })?;
    check_import_scale(value)
}

/// Whether `value` is an import scale keyrig takes (finite, within [`SCALE_LIMITS`]).
///
/// # Errors
/// The message for the user.
pub fn check_import_scale(value: f32) -> Result<f32, String> {
    let (low, high) = SCALE_LIMITS;
    if value.is_finite() && (low..=high).contains(&value) {
        Ok(value)
    } else {
        Err(format!(
            "import scale {value} refused: it must be a number from {low:e} to {high:e} (1 keeps the file's unit, 0.01 turns centimetres into metres)"
        ))
    }
}

/// Scales a model's scene about the origin by `factor` (> 0), as one more parent over all of
/// it would: each object's translation and scale (static values, keys and tangents, and the
/// stored keys of its actions), each light's position and range, each scene camera's
/// translation (and an orthographic camera's view height), the orbit camera's target and
/// distance. Rotations, and everything inside an object (its mesh, its skeleton's rest pose and
/// joint keys, its IK targets), are in the object's own space, which its scale carries: a
/// skinned character is scaled whole, bones and all.
pub fn scale_by(scene: &mut Scene, factor: f32) {
    if factor == 1.0 || !factor.is_finite() || factor <= 0.0 {
        return;
    }
    fn scale_vec3(a: &mut Animated<Vec3>, factor: f32) {
        a.value *= factor;
        for key in a.track.keys.iter_mut() {
            key.value *= factor;
            if let Some(t) = &mut key.in_tangent {
                *t *= factor;
            }
            if let Some(t) = &mut key.out_tangent {
                *t *= factor;
            }
        }
    }
    fn scale_f32(a: &mut Animated<f32>, factor: f32) {
        a.value *= factor;
        for key in a.track.keys.iter_mut() {
            key.value *= factor;
            if let Some(t) = &mut key.in_tangent {
                *t *= factor;
            }
            if let Some(t) = &mut key.out_tangent {
                *t *= factor;
            }
        }
    }
    for object in &mut scene.objects {
        scale_vec3(&mut object.translation, factor);
        scale_vec3(&mut object.scale, factor);
    }
    for light in &mut scene.lights {
        scale_vec3(&mut light.position, factor);
        if let Some(range) = &mut light.attributes.range {
            scale_f32(range, factor);
        }
    }
    for camera in &mut scene.cameras {
        scale_vec3(&mut camera.translation, factor);
        if camera.projection == keyrig_core::Projection::Orthographic {
            scale_f32(&mut camera.lens, factor);
        }
    }
    scene.camera.target *= factor;
    scene.camera.distance *= factor;
    // Keys of actions not playing now: an object's translation and scale, a light's position.
    for action in &mut scene.actions {
        for channel in &mut action.channels {
            use keyrig_core::channel::{ChannelPath, LightProperty, ObjectProperty};
            let scaled = matches!(
                ChannelPath::parse(&channel.path),
                Ok(ChannelPath::Object { property: ObjectProperty::Translation | ObjectProperty::Scale, .. }
                    | ChannelPath::Light { property: LightProperty::Position, .. })
            );
            if let (true, keyrig_core::ActionKeys::Vec3(keys)) = (scaled, &mut channel.keys) {
                scale_vec3(keys, factor);
            }
        }
    }
}

/// How much larger the imported objects `model` are than the scene's other objects `scene`
/// (each an object's box as drawn, `None` where it has none): the median size (box diagonal)
/// of the one over the median size of the other, so that how the objects are spread out does
/// not count, only how large each is. `None` when either has no object with a size.
#[must_use]
pub fn size_ratio(scene: &[Option<Bounds>], model: &[Option<Bounds>]) -> Option<f32> {
    fn median_size(boxes: &[Option<Bounds>]) -> Option<f32> {
        let mut sizes: Vec<f32> = boxes
            .iter()
            .flatten()
            .map(|b| (b.max - b.min).length())
            .filter(|s| s.is_finite() && *s > 1e-6)
            .collect();
        if sizes.is_empty() {
            return None;
        }
        sizes.sort_by(f32::total_cmp);
        let n = sizes.len();
        Some(if n % 2 == 1 { sizes[n / 2] } else { (sizes[n / 2 - 1] + sizes[n / 2]) * 0.5 })
    }
    let ratio = median_size(model)? / median_size(scene)?;
    ratio.is_finite().then_some(ratio)
}

/// How far the sizes may differ before the status bar says so: ten times larger or smaller.
pub const SIZE_WARNING_RATIO: f32 = 10.0;

/// The status bar's warning for a model `ratio` times the size of the scene's objects
/// ([`size_ratio`]) imported with scale `scale`, with the scale that would make it fit (the
/// power of ten nearest to undoing the ratio); `None` within [`SIZE_WARNING_RATIO`].
#[must_use]
pub fn size_warning(name: &str, ratio: f32, scale: f32) -> Option<String> {
    if !ratio.is_finite() || ratio <= 0.0 || (1.0 / SIZE_WARNING_RATIO..=SIZE_WARNING_RATIO).contains(&ratio)
    {
        return None;
    }
    let power = ratio.log10().round();
    let suggested = scale * 10f32.powf(-power);
    let how = if ratio > 1.0 {
        format!("about {}× larger than", round_ratio(ratio))
    } else {
        format!("about {}× smaller than", round_ratio(1.0 / ratio))
    };
    Some(format!(
        "{name} is {how} the scene's objects; undo (Ctrl+Z) and import with scale {} (File ▸ Import scale)",
        format_scale(suggested)
    ))
}

/// A ratio for the status bar: two significant digits (87, 120, 1500).
fn round_ratio(ratio: f32) -> String {
    let digits = ratio.log10().floor() as i32 - 1;
    let unit = 10f32.powi(digits.max(0));
    format!("{}", (ratio / unit).round() * unit)
}

/// A scale as the user types it: no trailing zeros, no exponent for the usual ones (0.01,
/// 100, 0.0254).
#[must_use]
pub fn format_scale(scale: f32) -> String {
    if (1e-4..1e6).contains(&scale) {
        let text = format!("{scale:.6}");
        text.trim_end_matches('0').trim_end_matches('.').to_owned()
    } else {
        format!("{scale:e}")
    }
}

/// The name of a length unit of `metres` metres, for what the status bar says of a file's
/// unit ("centimetres"), else the length itself.
#[must_use]
pub fn unit_name(metres: f32) -> String {
    const UNITS: [(f32, &str); 7] = [
        (1.0, "metres"),
        (0.01, "centimetres"),
        (0.001, "millimetres"),
        (0.1, "decimetres"),
        (1000.0, "kilometres"),
        (0.0254, "inches"),
        (0.3048, "feet"),
    ];
    UNITS
        .iter()
        .find(|(m, _)| (metres / m - 1.0).abs() < 1e-4)
        .map_or_else(|| format!("units of {} m", format_scale(metres)), |(_, name)| (*name).to_owned())
}

/// The world positions at rest (un-animated transforms, [`FileMesh::rest_positions`]) of every
/// vertex of the meshes of `scene`'s model-file objects found in `meshes`.
pub(super) fn rest_points(scene: &Scene, meshes: &[LoadedMesh]) -> Vec<Vec3> {
    let mut points = Vec::new();
    // Found by key, not by a search per object (quadratic for 100,000 objects).
    let by_key: HashMap<(&Path, Option<usize>), &FileMesh> = meshes
        .iter()
        .filter_map(|((path, mesh), loaded)| Some(((path.as_path(), *mesh), &loaded.as_ref().ok()?.0)))
        .collect();
    for object in &scene.objects {
        let Some(keyrig_core::MeshSource::File { path, mesh, .. }) = &object.mesh else { continue };
        let Some(data) = by_key.get(&(Path::new(path), *mesh)) else {
            continue;
        };
        let world = rest_world_from_object(object);
        points.extend(data.rest_positions().into_iter().map(|p| world.transform_point3(p)));
    }
    points
}

/// An object's world transform from its un-animated translation, rotation and scale.
#[must_use]
pub fn rest_world_from_object(object: &keyrig_core::Object) -> Mat4 {
    Mat4::from_scale_rotation_translation(
        object.scale.value,
        object.rotation.value.normalize(),
        object.translation.value,
    )
}

#[cfg(test)]
mod tests {
    use super::*;
    use keyrig_core::{Key, Object, RawTrack};

    fn bounds(min: [f32; 3], max: [f32; 3]) -> Bounds {
        Bounds { min: Vec3::from(min), max: Vec3::from(max) }
    }

    #[test]
    fn the_model_starts_a_gap_past_the_scene() {
        // Scene 2 m wide (−1 … 1), model 1 m wide centred on the origin: the gap is a quarter
        // of the wider (0.5 m), so the model's left side lands at 1.5 and its centre at 2.0.
        let offset = offset_beside(
            Some(bounds([-1.0, 0.0, -1.0], [1.0, 2.0, 1.0])),
            bounds([-0.5, 0.0, -0.3], [0.5, 1.7, 0.3]),
        );
        assert_eq!(offset, Vec3::new(2.0, 0.0, 0.0));
        // Tiny boxes keep the smallest gap.
        let offset = offset_beside(Some(bounds([0.0; 3], [0.01; 3])), bounds([0.0; 3], [0.01; 3]));
        assert!((offset.x - (0.01 + MIN_GAP)).abs() < 1e-6, "{offset}");
        assert_eq!(offset_beside(None, bounds([-1.0; 3], [1.0; 3])), Vec3::ZERO, "an empty scene");
    }

    #[test]
    fn moving_shifts_values_and_keys_of_objects_and_lights() {
        let mut scene = Scene::default();
        let mut object = Object::new("walker");
        object.translation = Animated {
            track: RawTrack::new(vec![Key::new(0.0, Vec3::ZERO), Key::new(1.0, Vec3::new(0.0, 0.0, 2.0))]),
            ..Animated::constant(Vec3::new(0.0, 1.0, 0.0))
        };
        scene.objects.push(object);
        // A sun at (0, 3, 0), as a model opened on its own gets.
        super::super::frame_model_scene(&mut scene, std::iter::empty());
        move_by(&mut scene, Vec3::X * 3.0);
        let t = &scene.objects[0].translation;
        assert_eq!(t.value, Vec3::new(3.0, 1.0, 0.0));
        let keys: Vec<Vec3> = t.track.keys.iter().map(|k| k.value).collect();
        assert_eq!(keys, vec![Vec3::new(3.0, 0.0, 0.0), Vec3::new(3.0, 0.0, 2.0)]);
        assert_eq!(scene.lights[0].position.value, Vec3::new(3.0, 3.0, 0.0));
    }

    #[test]
    fn scaling_scales_places_sizes_keys_tangents_and_stored_actions() {
        let mut scene = Scene::default();
        let mut object = Object::new("Fox");
        let mut key = Key::new(1.0, Vec3::new(0.0, 0.0, 200.0));
        key.out_tangent = Some(Vec3::new(0.0, 0.0, 100.0));
        object.translation = Animated {
            track: RawTrack::new(vec![Key::new(0.0, Vec3::ZERO), key]),
            ..Animated::constant(Vec3::new(100.0, 0.0, 0.0))
        };
        scene.objects.push(object);
        scene.actions.push(keyrig_core::Action {
            name: "Run".into(),
            channels: vec![
                keyrig_core::ActionChannel {
                    path: "object/Fox/translation".into(),
                    keys: keyrig_core::ActionKeys::Vec3(Animated::constant(Vec3::splat(50.0))),
                },
                keyrig_core::ActionChannel {
                    path: "object/Fox/joint/hip/translation".into(),
                    keys: keyrig_core::ActionKeys::Vec3(Animated::constant(Vec3::splat(50.0))),
                },
            ],
        });
        super::super::frame_model_scene(&mut scene, [Vec3::ZERO, Vec3::splat(100.0)]);
        let distance = scene.camera.distance;
        scale_by(&mut scene, 0.01);
        let o = &scene.objects[0];
        assert_eq!(o.translation.value, Vec3::new(1.0, 0.0, 0.0));
        assert_eq!(o.translation.track.keys[1].value, Vec3::new(0.0, 0.0, 2.0));
        assert_eq!(o.translation.track.keys[1].out_tangent, Some(Vec3::new(0.0, 0.0, 1.0)));
        assert_eq!(o.scale.value, Vec3::splat(0.01));
        assert!((scene.lights[0].position.value - Vec3::new(0.0, 0.03, 0.0)).length() < 1e-6);
        assert!((scene.camera.distance - distance * 0.01).abs() < 1e-4);
        let stored = |i: usize| match &scene.actions[0].channels[i].keys {
            keyrig_core::ActionKeys::Vec3(a) => a.value,
            other => panic!("{other:?}"),
        };
        assert_eq!(stored(0), Vec3::splat(0.5), "the object's own stored keys scale");
        assert_eq!(
            stored(1),
            Vec3::splat(50.0),
            "joint keys are in the object's space, which its scale carries"
        );
    }

    #[test]
    fn bad_scales_are_refused_with_a_message() {
        assert_eq!(parse_import_scale(" 0.01 "), Ok(0.01));
        for bad in ["0", "-1", "NaN", "inf", "", "cm", "1e9"] {
            let err = parse_import_scale(bad).expect_err(bad);
            assert!(err.contains("import scale"), "{err}");
        }
    }

    #[test]
    fn sizes_far_apart_are_warned_about_with_the_scale_that_fits() {
        let one = Some(bounds([0.0; 3], [1.0, 1.0, 0.0]));
        let fox = Some(bounds([0.0; 3], [100.0, 100.0, 0.0]));
        let ratio = size_ratio(&[one, one, None], &[fox]).expect("sizes");
        assert!((ratio - 100.0).abs() < 1e-3, "{ratio}");
        let warning = size_warning("Fox", ratio, 1.0).expect("a warning");
        assert!(warning.contains("Fox is about 100× larger") && warning.contains("scale 0.01"), "{warning}");
        let warning = size_warning("Ant", 0.02, 1.0).expect("a warning");
        assert!(warning.contains("50× smaller") && warning.contains("scale 100"), "{warning}");
        assert_eq!(size_warning("Box", 3.0, 1.0), None);
        assert_eq!(size_ratio(&[None], &[fox]), None, "nothing to compare with");
        assert_eq!(unit_name(0.01), "centimetres");
        assert_eq!(unit_name(0.0254), "inches");
        assert_eq!(format_scale(0.01), "0.01");
    }
}
