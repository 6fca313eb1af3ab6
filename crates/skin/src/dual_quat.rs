//! Unit dual quaternions for rigid transforms (Kavan, Collins, Žára, O'Sullivan, "Geometric
//! Skinning with Approximate Dual Quaternion Blending", ACM TOG 2008).
//!
//! A rigid transform x ↦ r·x + t is q̂ = r + ε·d with d = ½·(t, 0)·r.

use glam::{Affine3A, Quat, Vec3, Vec3A};

use crate::error::SkinError;

/// How far the scale of a transform may differ from 1 and still count as rigid.
const RIGID_TOLERANCE: f32 = 1e-3;

/// A dual quaternion `real + ε·dual`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DualQuat {
    pub real: Quat,
    pub dual: Quat,
}

/// Why an affine transform is not a rigid motion.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum NotRigid {
    NonFinite,
    Scale(f32),
}

impl NotRigid {
    /// The error for joint `joint` of a palette.
    #[must_use]
    pub fn at_joint(self, joint: usize) -> SkinError {
        match self {
            NotRigid::NonFinite => SkinError::NonFiniteTransform { joint },
            NotRigid::Scale(scale) => SkinError::NonRigidTransform { joint, scale },
        }
    }
}

impl DualQuat {
    pub const IDENTITY: DualQuat =
        DualQuat { real: Quat::IDENTITY, dual: Quat::from_xyzw(0.0, 0.0, 0.0, 0.0) };

    /// The rigid transform x ↦ rotation·x + translation.
    #[must_use]
    pub fn from_rotation_translation(rotation: Quat, translation: Vec3) -> Self {
        let t = Quat::from_xyzw(translation.x, translation.y, translation.z, 0.0);
        DualQuat { real: rotation, dual: (t * rotation) * 0.5 }
    }

    /// The dual quaternion of a rigid affine transform; fails on scale or shear beyond 1e-3.
    pub fn try_from_affine(m: &Affine3A) -> Result<Self, NotRigid> {
        if !m.is_finite() {
            return Err(NotRigid::NonFinite);
        }
        let (scale, rotation, translation) = m.to_scale_rotation_translation();
        let worst = (scale - Vec3::ONE).abs().max_element();
        if worst > RIGID_TOLERANCE || !rotation.is_finite() {
            return Err(NotRigid::Scale(if (scale.x - 1.0).abs() >= worst {
                scale.x
            } else {
                scale.max_element()
            }));
        }
        Ok(Self::from_rotation_translation(rotation.normalize(), translation))
    }

    /// Rotation part and translation of a unit dual quaternion.
    #[must_use]
    pub fn to_rotation_translation(self) -> (Quat, Vec3) {
        let t = (self.dual * 2.0) * self.real.conjugate();
        (self.real, Vec3::new(t.x, t.y, t.z))
    }

    /// Divides by the length of the real part, so that the real part is a unit quaternion.
    /// (The dual part is not projected to be orthogonal to the real part; for a blend of unit
    /// dual quaternions the transform below ignores that component, as in Kavan et al.)
    #[must_use]
    pub fn normalize(self) -> Self {
        let inv = 1.0 / self.real.length();
        DualQuat { real: self.real * inv, dual: self.dual * inv }
    }

    /// Transforms a point with a unit dual quaternion: rotate, then translate by
    /// t = 2·(w_r·d⃗ − w_d·r⃗ + r⃗ × d⃗).
    #[inline]
    #[must_use]
    pub fn transform_point3a(&self, p: Vec3A) -> Vec3A {
        let r = Vec3A::new(self.real.x, self.real.y, self.real.z);
        let d = Vec3A::new(self.dual.x, self.dual.y, self.dual.z);
        let rw = self.real.w;
        let dw = self.dual.w;
        let rotated = p + 2.0 * r.cross(r.cross(p) + rw * p);
        let translation = 2.0 * (rw * d - dw * r + r.cross(d));
        rotated + translation
    }

    /// Rotates a vector by the real part (for normals).
    #[inline]
    #[must_use]
    pub fn transform_vector3a(&self, v: Vec3A) -> Vec3A {
        let r = Vec3A::new(self.real.x, self.real.y, self.real.z);
        v + 2.0 * r.cross(r.cross(v) + self.real.w * v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn round_trips_a_rigid_transform() {
        let rotation = Quat::from_axis_angle(Vec3::new(1.0, 2.0, -0.5).normalize(), 1.1);
        let translation = Vec3::new(3.0, -4.0, 0.5);
        let m = Affine3A::from_rotation_translation(rotation, translation);
        let dq = DualQuat::try_from_affine(&m).unwrap();
        let p = Vec3A::new(0.3, 0.7, -1.9);
        assert!(dq.transform_point3a(p).abs_diff_eq(m.transform_point3a(p), 1e-5));
        assert!(dq.transform_vector3a(p).abs_diff_eq(m.transform_vector3a(p), 1e-5));
        let (r, t) = dq.to_rotation_translation();
        assert!(t.abs_diff_eq(translation, 1e-5));
        assert!(r.dot(rotation).abs() > 0.99999);
    }

    #[test]
    fn scale_is_rejected() {
        let m = Affine3A::from_scale(Vec3::new(1.0, 2.0, 1.0));
        assert_eq!(DualQuat::try_from_affine(&m), Err(NotRigid::Scale(2.0)));
        // The error reports the x scale when it is (one of) the worst, else the largest.
        let m = Affine3A::from_scale(Vec3::new(0.5, 1.0, 1.2));
        assert_eq!(DualQuat::try_from_affine(&m), Err(NotRigid::Scale(0.5)));
        let mut m = Affine3A::IDENTITY;
        m.translation.x = f32::NAN;
        assert_eq!(DualQuat::try_from_affine(&m), Err(NotRigid::NonFinite));
    }
}
