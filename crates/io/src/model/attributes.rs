//! What [`super::ImportedModel::to_scene`] takes from a glTF file beyond transforms: node
//! visibility (`KHR_node_visibility`, static and animated) of objects, lights and cameras,
//! material base colour and opacity, light colour, intensity, range and spot cone, a camera's
//! `yfov` / `ymag` (`KHR_animation_pointer`), and morph-target weights, as keyrig-core
//! attributes and camera channels.
//!
//! Every mapping is key for key with the file's interpolation: a component of a vector track
//! (alpha of a base colour, one weight of a weights track) is the same curve on that component,
//! and radians → degrees is linear, so STEP, LINEAR and CUBICSPLINE curves are kept exactly
//! (tangents through the same linear map).
//!
//! glTF hides a node's whole subtree when the node is invisible. keyrig objects, lights and
//! cameras have no parents, so each gets the visibility of its node and every ancestor combined: hidden when
//! any of them is. Animated visibilities of several ancestors are combined on the union of their
//! key times (Step keys, so the combination is exact).

use glam::{Vec3, Vec4};
use keyrig_core::{Animated, Interpolation, Key, RawTrack};

use super::{ChannelTarget, ImportedModel, ModelAnimation, PrimitiveMode};
use crate::gltf_pointer::{PointerKeys, PointerTarget};

/// Maps each key's value and tangents through `f` (linear in the value).
fn map_keys<A: Copy, B>(track: &RawTrack<A>, f: impl Fn(A) -> B) -> RawTrack<B> {
    RawTrack::new(
        track
            .keys
            .iter()
            .map(|k| Key {
                time: k.time,
                value: f(k.value),
                interpolation: k.interpolation,
                tcb: k.tcb,
                in_tangent: k.in_tangent.map(&f),
                out_tangent: k.out_tangent.map(&f),
                spin: None,
                key_type: k.key_type,
            })
            .collect(),
    )
}

/// A keyed value whose static value is its first key's.
fn keyed<T: Copy>(track: RawTrack<T>, fallback: T) -> Animated<T> {
    let value = track.keys.first().map_or(fallback, |k| k.value);
    Animated::new(value, track)
}

/// The value of a Step track at `t` (the first key's before it).
fn step_at(track: &RawTrack<f32>, t: f64) -> f32 {
    let i = track.keys.partition_point(|k| k.time <= t);
    track.keys[i.saturating_sub(1)].value
}

/// Visibility of a node and its ancestors combined: hidden when any is hidden.
fn combined_visibility(model: &ImportedModel, anim: Option<&ModelAnimation>, node: usize) -> Animated<f32> {
    let mut tracks: Vec<&RawTrack<f32>> = Vec::new();
    let mut shown = true;
    let mut cur = Some(node);
    let mut steps = 0;
    while let Some(n) = cur.filter(|&n| n < model.nodes.len() && steps <= model.nodes.len()) {
        let animated = anim.and_then(|a| {
            a.pointers.iter().find_map(|p| match (&p.target, &p.keys) {
                (PointerTarget::NodeVisible(m), PointerKeys::Scalar(t)) if *m == n && !t.keys.is_empty() => {
                    Some(t)
                }
                _ => None,
            })
        });
        match animated {
            Some(t) => tracks.push(t),
            None => shown &= model.nodes[n].visible,
        }
        cur = model.nodes[n].parent;
        steps += 1;
    }
    if !shown {
        return Animated::constant(0.0);
    }
    match tracks.as_slice() {
        [] => Animated::constant(1.0),
        [one] => keyed((*one).clone(), 1.0),
        many => {
            let mut times: Vec<f64> = many.iter().flat_map(|t| t.keys.iter().map(|k| k.time)).collect();
            times.sort_by(f64::total_cmp);
            times.dedup();
            let keys = times
                .into_iter()
                .map(|t| {
                    let v = if many.iter().all(|track| step_at(track, t) >= 0.5) { 1.0 } else { 0.0 };
                    Key::new(t, v).with_interpolation(Interpolation::Step)
                })
                .collect();
            keyed(RawTrack::new(keys), 1.0)
        }
    }
}

/// The triangle material of mesh `mesh` (the one its drawn primitive uses).
fn mesh_material(model: &ImportedModel, mesh: usize) -> Option<usize> {
    model.meshes.get(mesh)?.primitives.iter().find(|p| p.mode == PrimitiveMode::Triangles)?.material
}

/// Sets the attributes of the object made from node `node`.
pub(crate) fn object_attributes(
    model: &ImportedModel,
    anim: Option<&ModelAnimation>,
    node: usize,
    channels: &[&ChannelTarget],
    object: &mut keyrig_core::Object,
) {
    let a = &mut object.attributes;
    a.visible = combined_visibility(model, anim, node);
    let Some(mesh) = model.nodes[node].mesh else { return };
    if let Some(material) = mesh_material(model, mesh) {
        let base = anim.and_then(|a| {
            a.pointers.iter().find_map(|p| match (&p.target, &p.keys) {
                (PointerTarget::MaterialBaseColour(m), PointerKeys::Vec4(t)) if *m == material => Some(t),
                _ => None,
            })
        });
        if let Some(track) = base.filter(|t| !t.keys.is_empty()) {
            a.colour = Some(keyed(map_keys(track, Vec4::truncate), Vec3::ONE));
            a.opacity = keyed(map_keys(track, |v: Vec4| v.w), 1.0);
        }
    }
    // Morph weights: the node's (else the mesh's) defaults, keyed by the weights channel.
    let targets = model.meshes[mesh].primitives.first().map_or(0, |p| p.morph_targets.len());
    if targets > 0 {
        let defaults: Vec<f32> =
            model.nodes[node].weights.clone().unwrap_or_else(|| model.meshes[mesh].weights.clone());
        let weights = channels.iter().find_map(|c| match c {
            ChannelTarget::Weights(w) if w.targets == targets => Some(w),
            _ => None,
        });
        a.morph_weights = (0..targets)
            .map(|k| {
                let rest = defaults.get(k).copied().unwrap_or(0.0);
                match weights {
                    Some(w) => {
                        let keys = w
                            .keys
                            .iter()
                            .map(|key| Key {
                                time: key.time,
                                value: key.value[k],
                                interpolation: key.interpolation,
                                tcb: key.tcb,
                                in_tangent: key.in_tangent.as_ref().map(|t| t[k]),
                                out_tangent: key.out_tangent.as_ref().map(|t| t[k]),
                                spin: None,
                                key_type: key.key_type,
                            })
                            .collect();
                        keyed(RawTrack::new(keys), rest)
                    }
                    None => Animated::constant(rest),
                }
            })
            .collect();
    }
}

/// Sets the keys and attributes of the light made from node `node` (light `light` of the file).
pub(crate) fn light_attributes(
    model: &ImportedModel,
    anim: Option<&ModelAnimation>,
    node: usize,
    light_index: usize,
    light: &mut keyrig_core::Light,
) {
    light.attributes.visible = combined_visibility(model, anim, node);
    if let Some(range) = model.lights[light_index].range.filter(|r| r.is_finite() && *r > 0.0) {
        light.attributes.range = Some(Animated::constant(range));
    }
    let Some(anim) = anim else { return };
    for p in &anim.pointers {
        match (&p.target, &p.keys) {
            (PointerTarget::LightColour(l), PointerKeys::Vec3(t)) if *l == light_index => {
                light.colour = keyed(t.clone(), light.colour.value);
            }
            (PointerTarget::LightIntensity(l), PointerKeys::Scalar(t)) if *l == light_index => {
                light.intensity = keyed(t.clone(), light.intensity.value);
            }
            (PointerTarget::LightRange(l), PointerKeys::Scalar(t)) if *l == light_index => {
                light.attributes.range = Some(keyed(t.clone(), 1.0));
            }
            (PointerTarget::LightInnerCone(l), PointerKeys::Scalar(t)) if *l == light_index => {
                light.attributes.inner_angle_deg = Some(keyed(map_keys(t, f32::to_degrees), 0.0));
            }
            (PointerTarget::LightOuterCone(l), PointerKeys::Scalar(t)) if *l == light_index => {
                light.attributes.cutoff_deg = Some(keyed(map_keys(t, f32::to_degrees), 45.0));
            }
            _ => {}
        }
    }
}

/// Sets the visibility and the keyed lens of the scene camera made from node `node` (camera
/// `camera_index` of the file): `yfov` keys (radians) as field-of-view keys in degrees, `ymag`
/// keys as view-height keys `2·ymag`, key for key (both maps are linear, so every
/// interpolation is kept exactly).
pub(crate) fn camera_attributes(
    model: &ImportedModel,
    anim: Option<&ModelAnimation>,
    node: usize,
    camera_index: usize,
    camera: &mut keyrig_core::SceneCamera,
) {
    camera.visible = combined_visibility(model, anim, node);
    let Some(anim) = anim else { return };
    for p in &anim.pointers {
        match (&p.target, &p.keys, camera.projection) {
            (PointerTarget::CameraYfov(c), PointerKeys::Scalar(t), keyrig_core::Projection::Perspective)
                if *c == camera_index && !t.keys.is_empty() =>
            {
                camera.lens = keyed(map_keys(t, f32::to_degrees), camera.lens.value);
            }
            (PointerTarget::CameraYmag(c), PointerKeys::Scalar(t), keyrig_core::Projection::Orthographic)
                if *c == camera_index && !t.keys.is_empty() =>
            {
                camera.lens = keyed(map_keys(t, |y: f32| 2.0 * y), camera.lens.value);
            }
            _ => {}
        }
    }
}
