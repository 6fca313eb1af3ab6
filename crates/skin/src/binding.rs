//! Precomputed per-vertex skinning data (computed when the mesh or rest pose changes, never per
//! frame): bones-blending bindings (joint k, blend parameter t) and smooth weights.
//!
//! **Single-weight meshes** (the seed's method, generalized): a vertex bound to bone b is
//! assigned the joint k nearest to it among the joints of that bone — b's own joint (between
//! p(b) and b) and each of b's children (the nearest child at a branching joint). In k's rest
//! frame, t' = n·(A(k)⁻¹·v) is the signed distance along the parent bone's axis n from the
//! joint, and t = clamp((t' − t_min)/(t_max − t_min), 0, 1) with the blend zone
//! [t_min, t_max] = [−f_parent·|R(k)|, f_child·len(k)] reaching a fraction into the parent
//! bone and into the child bone.
//!
//! **Multi-weight meshes** (glTF skins): of the two largest influences, when one joint is the
//! other's parent, k is the child and t = w_child / (w_parent + w_child); otherwise the vertex
//! follows its dominant joint rigidly (t = 1).
//!
//! **Smooth weights for single-weight meshes**: the same (k, t) read as linear-blend weights,
//! w(k) = t and w(p(k)) = 1 − t, so that linear blend and dual quaternion work on every mesh
//! and agree with bones blending at rest.

use glam::{Vec3, Vec3A};

use crate::error::SkinError;
use crate::influences::{validate_influences, BonesBlendVertex};
use crate::skeleton::RestSkeleton;

/// The bones-blending zone around each joint, as fractions of the parent bone's and the child
/// bone's length (docs/design.md §5; `DeformerSettings::blend_parent_fraction` / `…child_fraction`).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BlendZone {
    pub parent_fraction: f32,
    pub child_fraction: f32,
}

impl Default for BlendZone {
    fn default() -> Self {
        BlendZone { parent_fraction: 0.25, child_fraction: 0.25 }
    }
}

impl BlendZone {
    /// Both fractions must be finite and in [0, 1].
    pub fn new(parent_fraction: f32, child_fraction: f32) -> Result<Self, SkinError> {
        let ok = |f: f32| f.is_finite() && (0.0..=1.0).contains(&f);
        if ok(parent_fraction) && ok(child_fraction) {
            Ok(BlendZone { parent_fraction, child_fraction })
        } else {
            Err(SkinError::BadBlendZone { parent_fraction, child_fraction })
        }
    }

    /// The zone of an object's deformer settings.
    pub fn from_settings(settings: &keyrig_core::DeformerSettings) -> Result<Self, SkinError> {
        Self::new(settings.blend_parent_fraction, settings.blend_child_fraction)
    }
}

/// Unit axis of the parent bone arriving at joint k, in k's rest frame.
fn parent_axis_in_joint(skeleton: &RestSkeleton, k: usize) -> Vec3A {
    let r = skeleton.parent_from_joint()[k];
    let joint_from_parent = r.matrix3.inverse();
    if let Some(axis) = (joint_from_parent * r.translation).try_normalize() {
        return axis;
    }
    // The joint sits on its parent: use the direction to its first child instead.
    skeleton
        .children(k)
        .iter()
        .find_map(|&c| skeleton.parent_from_joint()[c].translation.try_normalize())
        .unwrap_or(Vec3A::X)
}

/// The bones-blending parameter t of a rest-pose model-space point for joint k (which must
/// have a parent).
#[must_use]
pub fn blend_parameter(skeleton: &RestSkeleton, k: usize, zone: BlendZone, point: Vec3) -> f32 {
    let axis = parent_axis_in_joint(skeleton, k);
    let local = skeleton.joint_from_bind_model()[k].transform_point3a(Vec3A::from(point));
    let t_prime = axis.dot(local);
    let parent_length = skeleton.parent_from_joint()[k].translation.length();
    let t_min = -zone.parent_fraction * parent_length;
    let t_max = zone.child_fraction * skeleton.bone_lengths()[k];
    if t_max - t_min > 0.0 {
        ((t_prime - t_min) / (t_max - t_min)).clamp(0.0, 1.0)
    } else if t_prime >= 0.0 {
        1.0
    } else {
        0.0
    }
}

/// Bones-blending bindings of a single-weight mesh: `bones[v]` is the joint (bone) vertex v
/// is bound to.
pub fn bind_single_weights(
    skeleton: &RestSkeleton,
    positions: &[Vec3],
    bones: &[u16],
    zone: BlendZone,
) -> Result<Vec<BonesBlendVertex>, SkinError> {
    if positions.len() != bones.len() {
        return Err(SkinError::LengthMismatch {
            what: "single-weight joints",
            expected: positions.len(),
            found: bones.len(),
        });
    }
    let joint_count = skeleton.len();
    let mut out = Vec::with_capacity(positions.len());
    for (vertex, (&p, &b)) in positions.iter().zip(bones).enumerate() {
        let b = b as usize;
        if b >= joint_count {
            return Err(SkinError::JointOutOfRange { vertex, influence: 0, joint: b, joint_count });
        }
        if !p.is_finite() {
            return Err(SkinError::NonFiniteVertex { vertex, what: "position" });
        }
        let own = skeleton.parents()[b].map(|_| b);
        let nearest = own
            .into_iter()
            .chain(skeleton.children(b).iter().copied())
            .map(|k| (k, p.distance_squared(skeleton.rest_position(k))))
            .min_by(|a, b| a.1.total_cmp(&b.1))
            .map(|(k, _)| k);
        out.push(match nearest {
            Some(k) => BonesBlendVertex { joint: k as u32, t: blend_parameter(skeleton, k, zone, p) },
            None => BonesBlendVertex { joint: b as u32, t: 1.0 },
        });
    }
    Ok(out)
}

/// Bones-blending bindings derived from ordinary multi-weight data (see the module docs).
pub fn bind_from_weights<const N: usize>(
    skeleton: &RestSkeleton,
    joints: &[[u16; N]],
    weights: &[[f32; N]],
) -> Result<Vec<BonesBlendVertex>, SkinError> {
    validate_influences(joints, weights, skeleton.len())?;
    let parents = skeleton.parents();
    Ok(joints
        .iter()
        .zip(weights)
        .map(|(js, ws)| {
            // The two largest influences, summing weights of repeated joints.
            let mut best: [(usize, f32); 2] = [(0, -1.0); 2];
            for i in 0..N {
                let j = js[i] as usize;
                if js[..i].contains(&js[i]) {
                    continue;
                }
                let w: f32 = (i..N).filter(|&m| js[m] as usize == j).map(|m| ws[m]).sum();
                if w > best[0].1 {
                    best[1] = best[0];
                    best[0] = (j, w);
                } else if w > best[1].1 {
                    best[1] = (j, w);
                }
            }
            let (a, wa) = best[0];
            let (b, wb) = best[1];
            if wb > 0.0 && parents[b] == Some(a) {
                BonesBlendVertex { joint: b as u32, t: wb / (wa + wb) }
            } else if wb > 0.0 && parents[a] == Some(b) {
                BonesBlendVertex { joint: a as u32, t: wa / (wa + wb) }
            } else {
                BonesBlendVertex { joint: a as u32, t: 1.0 }
            }
        })
        .collect())
}

/// Linear-blend weights equivalent to bones-blending bindings: w(k) = t, w(p(k)) = 1 − t.
/// Unused influences have joint 0 and weight 0.
#[must_use]
pub fn weights_from_bindings(
    skeleton: &RestSkeleton,
    bindings: &[BonesBlendVertex],
) -> (Vec<[u16; 4]>, Vec<[f32; 4]>) {
    bindings
        .iter()
        .map(|b| {
            let k = b.joint as usize;
            match skeleton.parents().get(k).copied().flatten() {
                Some(j) if b.t < 1.0 => ([k as u16, j as u16, 0, 0], [b.t, 1.0 - b.t, 0.0, 0.0]),
                _ => ([k as u16, 0, 0, 0], [1.0, 0.0, 0.0, 0.0]),
            }
        })
        .unzip()
}

/// Four joint indices and four weights per vertex.
pub type Influences = (Vec<[u16; 4]>, Vec<[f32; 4]>);

/// The smoothing heuristic for single-weight meshes: smooth 4-influence weights across each
/// joint, from [`bind_single_weights`] and [`weights_from_bindings`].
pub fn smooth_weights(
    skeleton: &RestSkeleton,
    positions: &[Vec3],
    bones: &[u16],
    zone: BlendZone,
) -> Result<Influences, SkinError> {
    let bindings = bind_single_weights(skeleton, positions, bones, zone)?;
    Ok(weights_from_bindings(skeleton, &bindings))
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::RestJoint;
    use glam::Quat;

    fn chain() -> RestSkeleton {
        RestSkeleton::new(&[
            RestJoint::new("a", None, Vec3::ZERO, Quat::IDENTITY),
            RestJoint::new("b", Some(0), Vec3::new(4.0, 0.0, 0.0), Quat::IDENTITY),
            RestJoint::new("c", Some(1), Vec3::new(4.0, 0.0, 0.0), Quat::IDENTITY),
        ])
        .unwrap()
    }

    #[test]
    fn blend_parameter_ramps_across_the_zone() {
        let s = chain();
        let zone = BlendZone::new(0.25, 0.5).unwrap();
        // Zone around joint b (x = 4): from x = 3 (0.25 of 4 into the parent) to x = 6.
        assert_eq!(blend_parameter(&s, 1, zone, Vec3::new(2.0, 1.0, 0.0)), 0.0);
        assert!((blend_parameter(&s, 1, zone, Vec3::new(3.0, 1.0, 0.0)) - 0.0).abs() < 1e-6);
        assert!((blend_parameter(&s, 1, zone, Vec3::new(4.5, -1.0, 0.0)) - 0.5).abs() < 1e-6);
        assert_eq!(blend_parameter(&s, 1, zone, Vec3::new(7.0, 0.0, 0.0)), 1.0);
        let hard = BlendZone::new(0.0, 0.0).unwrap();
        assert_eq!(blend_parameter(&s, 1, hard, Vec3::new(3.9, 0.0, 0.0)), 0.0);
        assert_eq!(blend_parameter(&s, 1, hard, Vec3::new(4.1, 0.0, 0.0)), 1.0);
        assert!(BlendZone::new(f32::NAN, 0.2).is_err());
        assert!(BlendZone::new(0.2, 1.5).is_err());
        assert!(BlendZone::new(-0.1, 0.2).is_err());
        assert!(BlendZone::new(0.2, f32::INFINITY).is_err());
        assert_eq!(BlendZone::new(1.0, 0.0), Ok(BlendZone { parent_fraction: 1.0, child_fraction: 0.0 }));
    }

    /// An object's deformer settings give its zone, and bad fractions there are refused.
    #[test]
    fn zones_come_from_deformer_settings() {
        let mut settings = keyrig_core::DeformerSettings {
            blend_parent_fraction: 0.1,
            blend_child_fraction: 0.6,
            ..Default::default()
        };
        assert_eq!(
            BlendZone::from_settings(&settings),
            Ok(BlendZone { parent_fraction: 0.1, child_fraction: 0.6 })
        );
        settings.blend_child_fraction = 2.0;
        assert_eq!(
            BlendZone::from_settings(&settings),
            Err(SkinError::BadBlendZone { parent_fraction: 0.1, child_fraction: 2.0 })
        );
    }

    #[test]
    fn single_weight_vertices_bind_to_the_nearest_joint_of_their_bone() {
        let s = chain();
        let positions = [Vec3::new(0.5, 1.0, 0.0), Vec3::new(3.5, 1.0, 0.0), Vec3::new(4.5, 1.0, 0.0)];
        let b = bind_single_weights(&s, &positions, &[0, 0, 1], BlendZone::default()).unwrap();
        // Near the root on bone a: rigid to a (a has no parent joint to blend over).
        assert_eq!(b[0].joint, 1);
        assert_eq!(b[0].t, 0.0);
        assert_eq!(b[1].joint, 1);
        assert!((b[1].t - 0.25).abs() < 1e-6);
        assert_eq!(b[2].joint, 1);
        assert!((b[2].t - 0.75).abs() < 1e-6);
        assert!(matches!(
            bind_single_weights(&s, &positions, &[0, 9, 1], BlendZone::default()),
            Err(SkinError::JointOutOfRange { vertex: 1, joint: 9, .. })
        ));
        assert_eq!(
            bind_single_weights(&s, &positions, &[0, 0], BlendZone::default()),
            Err(SkinError::LengthMismatch { what: "single-weight joints", expected: 3, found: 2 })
        );
        let mut far = positions;
        far[2].z = f32::INFINITY;
        assert_eq!(
            bind_single_weights(&s, &far, &[0, 0, 1], BlendZone::default()),
            Err(SkinError::NonFiniteVertex { vertex: 2, what: "position" })
        );
        let (joints, weights) = weights_from_bindings(&s, &b);
        assert_eq!(joints[1], [1, 0, 0, 0]);
        assert!((weights[1][0] - 0.25).abs() < 1e-6 && (weights[1][1] - 0.75).abs() < 1e-6);
    }

    #[test]
    fn multi_weights_give_joint_and_t() {
        let s = chain();
        let joints = [[1u16, 2, 0, 0], [0, 2, 1, 0], [2, 0, 0, 0]];
        let weights = [[0.7, 0.3, 0.0, 0.0], [0.6, 0.4, 0.0, 0.0], [1.0, 0.0, 0.0, 0.0]];
        let b = bind_from_weights(&s, &joints, &weights).unwrap();
        assert_eq!(b[0].joint, 2);
        assert!((b[0].t - 0.3).abs() < 1e-6);
        // a and c are not parent and child: rigid to the dominant joint.
        assert_eq!(b[1], BonesBlendVertex { joint: 0, t: 1.0 });
        assert_eq!(b[2], BonesBlendVertex { joint: 2, t: 1.0 });
    }
}
