//! IK constraints as the editor looks them up.

use keyrig_core::Scene;

/// Indices of object `object`'s IK constraints whose end joint is `joint`.
#[must_use]
pub fn ending_at(scene: &Scene, object: usize, joint: usize) -> Vec<usize> {
    let Some(skeleton) = scene.objects.get(object).and_then(|o| o.skeleton.as_ref()) else {
        return Vec::new();
    };
    (0..skeleton.ik_constraints.len()).filter(|&c| skeleton.ik_constraints[c].end == joint).collect()
}
