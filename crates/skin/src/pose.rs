//! Pose evaluation: from local joint transforms T(j) to the joint palette (docs/design.md §4).
//!
//! T(j) = translate(t_j) · rotate(q_j) · scale(s_j) (identity at rest);
//! F(j) = F(p(j))·R(j)·T(j) with F(root) = Tr·R(root)·T(root), where Tr is the pose's root
//! translation; M(j) = F(j)·A(j)⁻¹ is the skinning matrix ("joint palette").

use glam::{Affine3A, Mat3A, Quat, Vec3, Vec3A};

use crate::dual_quat::DualQuat;
use crate::error::SkinError;
use crate::skeleton::RestSkeleton;

/// Local joint transforms T(j) (identity at rest) and the translation of the root joint(s).
/// The three per-joint lists have one entry per joint of the skeleton, in its joint order.
#[derive(Clone, Debug, PartialEq)]
pub struct Pose {
    /// Translation part of T(j), in the joint's rest frame.
    pub local_translations: Vec<Vec3>,
    /// Rotation part of T(j).
    pub local_rotations: Vec<Quat>,
    /// Scale part of T(j) (applied first).
    pub local_scales: Vec<Vec3>,
    /// Added to the rest translation of every root joint, in the object's (model) space.
    pub root_translation: Vec3,
}

impl Pose {
    /// The rest pose of a skeleton with `joint_count` joints.
    #[must_use]
    pub fn rest(joint_count: usize) -> Self {
        Pose {
            local_translations: vec![Vec3::ZERO; joint_count],
            local_rotations: vec![Quat::IDENTITY; joint_count],
            local_scales: vec![Vec3::ONE; joint_count],
            root_translation: Vec3::ZERO,
        }
    }

    /// A pose that only rotates joints: T(j) = rotate(`rotations[j]`).
    #[must_use]
    pub fn from_rotations(rotations: Vec<Quat>, root_translation: Vec3) -> Self {
        let n = rotations.len();
        Pose {
            local_translations: vec![Vec3::ZERO; n],
            local_rotations: rotations,
            local_scales: vec![Vec3::ONE; n],
            root_translation,
        }
    }

    /// The rest pose with one joint rotated.
    #[must_use]
    pub fn with_rotation(mut self, joint: usize, rotation: Quat) -> Self {
        if let Some(r) = self.local_rotations.get_mut(joint) {
            *r = rotation;
        }
        self
    }

    /// Number of joints the pose is for.
    #[must_use]
    pub fn len(&self) -> usize {
        self.local_rotations.len()
    }

    /// True for a pose of no joints.
    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.local_rotations.is_empty()
    }
}

/// Per-joint data of the bones-blending deformer for joint k (docs/design.md §5):
/// v' = F(j)·R(k)·slerp(I, T(k), t)·A(k)⁻¹·v with j = p(k).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct BonesBlendJoint {
    /// P(k) = F(p(k))·R(k): the joint's frame with the posed parent but without its own
    /// rotation (Tr·R(k) for a root).
    pub posed_from_joint_rest: Affine3A,
    /// A(k)⁻¹.
    pub joint_from_bind_model: Affine3A,
    /// T(k) with w ≥ 0 (the short way from the identity).
    pub rotation: Quat,
    /// Unit rotation axis of T(k) (X when T(k) is the identity).
    pub axis: Vec3A,
    /// Half the rotation angle of T(k), in [0, π/2].
    pub half_angle: f32,
    /// The run-time form of the formula. With φ = t·θ and K the cross-product matrix of the
    /// axis, Rodrigues' formula slerp(I, T(k), t) = I + sin φ·K + (1 − cos φ)·K² gives
    /// v' = (B₀ + sin φ·B₁ + (1 − cos φ)·B₂)·v with B₀ = P(k)·A(k)⁻¹ (= M(p(k)) below a
    /// parent), B₁ = P(k)₃ₓ₃·K·A(k)⁻¹ and B₂ = P(k)₃ₓ₃·K²·A(k)⁻¹: a three-term blend of
    /// per-joint matrices, like a linear blend with weights (1, sin φ, 1 − cos φ).
    pub blend_terms: [Affine3A; 3],
}

/// Everything the deformers need for one pose.
#[derive(Clone, Debug, Default, PartialEq)]
pub struct JointPalette {
    /// F(j): posed model space from joint space.
    pub model_from_joint: Vec<Affine3A>,
    /// M(j) = F(j)·A(j)⁻¹: posed model space from bind model space (the joint palette).
    pub skinning: Vec<Affine3A>,
    /// Inverse-transpose of M(j)'s linear part for normals; `None` when every M(j) is a
    /// rotation times a uniform scale, so that M(j) itself maps normals correctly (after
    /// renormalization).
    pub normal_skinning: Option<Vec<Mat3A>>,
    /// Per-joint data of the bones-blending deformer.
    pub bones_blending: Vec<BonesBlendJoint>,
}

/// Relative tolerance under which a matrix counts as a rotation times a uniform scale.
const UNIFORM_SCALE_TOLERANCE: f32 = 1e-4;

impl JointPalette {
    /// Evaluates a pose on a skeleton.
    pub fn new(skeleton: &RestSkeleton, pose: &Pose) -> Result<Self, SkinError> {
        let mut palette = JointPalette::default();
        palette.update(skeleton, pose)?;
        Ok(palette)
    }

    /// Re-evaluates in place, reusing the allocations.
    pub fn update(&mut self, skeleton: &RestSkeleton, pose: &Pose) -> Result<(), SkinError> {
        let n = skeleton.len();
        for (what, found) in [
            ("pose rotations", pose.local_rotations.len()),
            ("pose translations", pose.local_translations.len()),
            ("pose scales", pose.local_scales.len()),
        ] {
            if found != n {
                return Err(SkinError::LengthMismatch { what, expected: n, found });
            }
        }
        if !pose.root_translation.is_finite() {
            return Err(SkinError::BadRootTranslation);
        }
        self.model_from_joint.clear();
        self.skinning.clear();
        self.bones_blending.clear();
        let root_shift = Affine3A::from_translation(pose.root_translation);
        let mut uniform = true;
        for j in 0..n {
            let q = pose.local_rotations[j];
            let length = q.length();
            if !length.is_finite() || length < 1e-6 {
                return Err(SkinError::BadPoseRotation { joint: j });
            }
            let mut t = q / length;
            if t.w < 0.0 {
                t = -t;
            }
            let (translation, scale) = (pose.local_translations[j], pose.local_scales[j]);
            if !translation.is_finite() || !scale.is_finite() {
                return Err(SkinError::BadPoseTransform { joint: j });
            }
            let r = skeleton.parent_from_joint()[j];
            // Bones blending turns the vertex by part of T(j)'s rotation only; the joint's own
            // translation and scale are applied in full (exact for uniform scales, which
            // commute with the rotation).
            let posed_from_joint_rest = match skeleton.parents()[j] {
                Some(p) => self.model_from_joint[p] * r,
                None => root_shift * r,
            } * Affine3A::from_translation(translation)
                * Affine3A::from_scale(scale);
            let f = match skeleton.parents()[j] {
                Some(p) => self.model_from_joint[p] * r,
                None => root_shift * r,
            } * Affine3A::from_scale_rotation_translation(scale, t, translation);
            let a_inv = skeleton.joint_from_bind_model()[j];
            let m = f * a_inv;
            uniform &= is_uniform_scale(&m.matrix3);
            self.model_from_joint.push(f);
            self.skinning.push(m);
            let (axis, angle) = t.to_axis_angle();
            let (axis, half_angle) = if angle.is_finite() && angle > 0.0 && axis.is_finite() {
                (Vec3A::from(axis), (0.5 * angle).min(std::f32::consts::FRAC_PI_2))
            } else {
                (Vec3A::X, 0.0)
            };
            let k = Mat3A::from_cols(
                Vec3A::new(0.0, axis.z, -axis.y),
                Vec3A::new(-axis.z, 0.0, axis.x),
                Vec3A::new(axis.y, -axis.x, 0.0),
            );
            let p_lin = posed_from_joint_rest.matrix3;
            let term = |l: Mat3A| Affine3A {
                matrix3: p_lin * l * a_inv.matrix3,
                translation: p_lin * l * a_inv.translation,
            };
            let blend_terms = [posed_from_joint_rest * a_inv, term(k), term(k * k)];
            self.bones_blending.push(BonesBlendJoint {
                blend_terms,
                posed_from_joint_rest,
                joint_from_bind_model: a_inv,
                rotation: t,
                axis,
                half_angle,
            });
        }
        self.normal_skinning = if uniform {
            None
        } else {
            Some(self.skinning.iter().map(|m| m.matrix3.inverse().transpose()).collect())
        };
        Ok(())
    }

    /// Number of joints.
    #[must_use]
    pub fn len(&self) -> usize {
        self.skinning.len()
    }

    #[must_use]
    pub fn is_empty(&self) -> bool {
        self.skinning.is_empty()
    }

    /// Posed model-space position of joint j (the origin of F(j)).
    #[must_use]
    pub fn joint_position(&self, j: usize) -> Vec3 {
        self.model_from_joint[j].translation.into()
    }

    /// The palette as unit dual quaternions, for the dual-quaternion deformer. Fails when an
    /// M(j) is not rigid (scale differs from 1 by more than 1e-3).
    pub fn dual_quaternions(&self) -> Result<Vec<DualQuat>, SkinError> {
        self.skinning
            .iter()
            .enumerate()
            .map(|(joint, m)| DualQuat::try_from_affine(m).map_err(|e| e.at_joint(joint)))
            .collect()
    }
}

fn is_uniform_scale(m: &Mat3A) -> bool {
    let lx = m.x_axis.length_squared();
    let ly = m.y_axis.length_squared();
    let lz = m.z_axis.length_squared();
    let scale = lx.max(ly).max(lz);
    if scale <= 0.0 {
        return false;
    }
    let tol = UNIFORM_SCALE_TOLERANCE * scale;
    (lx - ly).abs() <= tol
        && (lx - lz).abs() <= tol
        && m.x_axis.dot(m.y_axis).abs() <= tol
        && m.x_axis.dot(m.z_axis).abs() <= tol
        && m.y_axis.dot(m.z_axis).abs() <= tol
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::skeleton::RestJoint;

    fn chain() -> RestSkeleton {
        RestSkeleton::new(&[
            RestJoint::new("a", None, Vec3::new(1.0, 0.0, 0.0), Quat::IDENTITY),
            RestJoint::new("b", Some(0), Vec3::new(2.0, 0.0, 0.0), Quat::IDENTITY),
            RestJoint::new("c", Some(1), Vec3::new(2.0, 0.0, 0.0), Quat::from_rotation_z(0.3)),
        ])
        .unwrap()
    }

    #[test]
    fn rest_pose_gives_identity_palette() {
        let skeleton = chain();
        let palette = JointPalette::new(&skeleton, &Pose::rest(3)).unwrap();
        for m in &palette.skinning {
            assert!(m.abs_diff_eq(Affine3A::IDENTITY, 1e-6));
        }
        assert!(palette.normal_skinning.is_none());
    }

    #[test]
    fn rotation_at_a_joint_moves_its_descendants_about_it() {
        let skeleton = chain();
        let pose = Pose::rest(3).with_rotation(1, Quat::from_rotation_z(std::f32::consts::FRAC_PI_2));
        let palette = JointPalette::new(&skeleton, &pose).unwrap();
        // Joint b at (3, 0, 0) stays; joint c (rest (5, 0, 0)) swings to (3, 2, 0).
        assert!(palette.joint_position(1).abs_diff_eq(Vec3::new(3.0, 0.0, 0.0), 1e-5));
        assert!(palette.joint_position(2).abs_diff_eq(Vec3::new(3.0, 2.0, 0.0), 1e-5));
        let moved = palette.skinning[2].transform_point3(Vec3::new(6.0, 0.0, 0.0));
        assert!(moved.abs_diff_eq(Vec3::new(3.0, 3.0, 0.0), 1e-5));
    }

    /// Rotation times a uniform scale is uniform; any scale that differs along one axis, a
    /// shear or a zero matrix is not.
    #[test]
    fn uniform_scale_is_recognised() {
        let rotation = Mat3A::from_quat(Quat::from_rotation_y(0.7));
        assert!(is_uniform_scale(&(rotation * 2.0)));
        for scale in [Vec3::new(1.0, 1.0, 2.0), Vec3::new(1.0, 2.0, 1.0), Vec3::new(2.0, 1.0, 1.0)] {
            assert!(!is_uniform_scale(&(rotation * Mat3A::from_diagonal(scale))), "{scale}");
        }
        let shear = Mat3A::from_cols(Vec3A::X, Vec3A::new(0.5, 1.0, 0.0), Vec3A::Z);
        assert!(!is_uniform_scale(&shear));
        assert!(!is_uniform_scale(&Mat3A::ZERO));
    }

    #[test]
    fn rest_poses_have_one_entry_per_joint() {
        let pose = Pose::rest(3);
        assert_eq!((pose.len(), pose.is_empty()), (3, false));
        assert!(Pose::rest(0).is_empty());
    }

    #[test]
    fn bad_poses_are_typed_errors() {
        let skeleton = chain();
        assert!(matches!(
            JointPalette::new(&skeleton, &Pose::rest(2)),
            Err(SkinError::LengthMismatch { expected: 3, found: 2, .. })
        ));
        let pose = Pose::rest(3).with_rotation(2, Quat::from_xyzw(f32::NAN, 0.0, 0.0, 1.0));
        assert_eq!(JointPalette::new(&skeleton, &pose), Err(SkinError::BadPoseRotation { joint: 2 }));
        let pose = Pose::rest(3).with_rotation(0, Quat::from_xyzw(0.0, 0.0, 0.0, 0.0));
        assert_eq!(JointPalette::new(&skeleton, &pose), Err(SkinError::BadPoseRotation { joint: 0 }));
        let mut pose = Pose::rest(3);
        pose.root_translation.y = f32::INFINITY;
        assert_eq!(JointPalette::new(&skeleton, &pose), Err(SkinError::BadRootTranslation));
        let mut pose = Pose::rest(3);
        pose.local_translations[1].x = f32::NAN;
        assert_eq!(JointPalette::new(&skeleton, &pose), Err(SkinError::BadPoseTransform { joint: 1 }));
        let mut pose = Pose::rest(3);
        pose.local_scales[2].z = f32::INFINITY;
        assert_eq!(JointPalette::new(&skeleton, &pose), Err(SkinError::BadPoseTransform { joint: 2 }));
        for (what, edit) in [
            (
                "pose translations",
                &(|p: &mut Pose| p.local_translations.pop()) as &dyn Fn(&mut Pose) -> Option<Vec3>,
            ),
            ("pose scales", &|p: &mut Pose| p.local_scales.pop()),
        ] {
            let mut pose = Pose::rest(3);
            edit(&mut pose);
            assert_eq!(
                JointPalette::new(&skeleton, &pose),
                Err(SkinError::LengthMismatch { what, expected: 3, found: 2 })
            );
        }
    }
}
