//! Where an imported model goes: beside what the scene already holds, as a layout tool places a
//! new part, instead of on top of it at the origin. The model moves along +X so that its box
//! (its meshes at rest, [`super::import`]) starts a gap past the scene's box (each object as
//! the viewport draws it now), keeping its own height and depth: characters imported one after
//! another stand in a row on the ground. The move is part of the import's one undo step; a
//! model imported into a scene with nothing in it stays where its file put it.

use glam::Vec3;
use keyrig_core::{Animated, Scene};

use super::import::rest_points;
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
}
