//! Scene cameras at a time: [`CameraState`] (where a camera is, where it looks, its lens) and
//! its view and projection matrices, and the evaluator's runtime form of a camera.
//!
//! Conventions: a camera looks down its local −Z with +Y up (glTF's, and keyrig's viewport);
//! clip space is wgpu's (right-handed view space, depth 0 at the near plane, 1 at the far
//! plane). The projections are glTF 2.0's (§3.10.3, "Projection matrices") with the depth
//! range mapped from OpenGL's −1..1 to 0..1.

use glam::{Affine3A, Mat4, Quat, Vec3};
use keyrig_core::channel_id::{ChannelId, ChannelValue};
use keyrig_core::{AimTarget, Lens, Projection, Scene, SceneCamera};

use crate::slot::{EvalProblem, Overrides, Slot};

/// A scene camera at one time.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CameraState {
    /// World from camera: the camera's rotation and translation (no scale).
    pub world_from_camera: Affine3A,
    pub lens: Lens,
    /// Near plane, view-space distance.
    pub near: f32,
    /// Far plane; `None` for an infinite one.
    pub far: Option<f32>,
    /// Its visibility channel at this time (a hidden camera's frustum is not drawn; it can
    /// still be looked and rendered through).
    pub visible: bool,
}

impl CameraState {
    /// The camera's position in world space.
    #[must_use]
    pub fn eye(&self) -> Vec3 {
        self.world_from_camera.translation.into()
    }

    /// The world direction the camera looks in (its −Z), unit length.
    #[must_use]
    pub fn forward(&self) -> Vec3 {
        self.world_from_camera.transform_vector3(Vec3::NEG_Z).normalize_or(Vec3::NEG_Z)
    }

    /// View space from world space.
    #[must_use]
    pub fn view_from_world(&self) -> Mat4 {
        Mat4::from(self.world_from_camera.inverse())
    }

    /// Clip space from view space for an image `aspect` = width / height.
    #[must_use]
    pub fn clip_from_view(&self, aspect: f32) -> Mat4 {
        let aspect = if aspect.is_finite() && aspect > 0.0 { aspect } else { 1.0 };
        match self.lens {
            Lens::Perspective { fov_y } => match self.far {
                Some(far) => Mat4::perspective_rh(fov_y, aspect, self.near, far),
                None => Mat4::perspective_infinite_rh(fov_y, aspect, self.near),
            },
            Lens::Orthographic { height } => {
                let (half_h, far) = (height * 0.5, self.far.unwrap_or(self.near * 1e6));
                let half_w = half_h * aspect;
                Mat4::orthographic_rh(-half_w, half_w, -half_h, half_h, self.near, far)
            }
        }
    }

    /// Clip space from world space.
    #[must_use]
    pub fn clip_from_world(&self, aspect: f32) -> Mat4 {
        self.clip_from_view(aspect) * self.view_from_world()
    }

    /// The world-space corners of the image rectangle at view distance `depth` in front of
    /// the camera (bottom left, bottom right, top right, top left): what a viewport draws as
    /// the camera's frustum.
    #[must_use]
    pub fn image_corners(&self, aspect: f32, depth: f32) -> [Vec3; 4] {
        let half_h = match self.lens {
            Lens::Perspective { fov_y } => depth * (fov_y * 0.5).tan(),
            Lens::Orthographic { height } => height * 0.5,
        };
        let half_w = half_h * aspect;
        [(-1.0, -1.0), (1.0, -1.0), (1.0, 1.0), (-1.0, 1.0)]
            .map(|(x, y)| self.world_from_camera.transform_point3(Vec3::new(x * half_w, y * half_h, -depth)))
    }

    /// Whether every number is finite and the lens and planes can be projected.
    #[must_use]
    pub fn is_usable(&self) -> bool {
        let lens_ok = match self.lens {
            Lens::Perspective { fov_y } => fov_y.is_finite() && fov_y > 0.0 && fov_y < std::f32::consts::PI,
            Lens::Orthographic { height } => height.is_finite() && height > 0.0,
        };
        lens_ok
            && self.world_from_camera.is_finite()
            && self.near.is_finite()
            && self.near > 0.0
            && self.far.is_none_or(|f| f.is_finite() && f > self.near)
    }
}

/// What an aim constraint looks at, resolved to indices.
#[derive(Clone, Debug)]
pub(crate) enum Target {
    Object(usize),
    Joint {
        object: usize,
        joint: usize,
    },
    Point(Vec3),
    /// The named object or joint does not exist (a problem is listed); the keyed rotation is
    /// used.
    Missing,
}

#[derive(Clone, Debug)]
pub(crate) struct AimRig {
    pub(crate) target: Target,
    up: Vec3,
    pub(crate) roll: Slot<f32>,
    pub(crate) influence: Slot<f32>,
}

/// A scene camera's runtime form.
#[derive(Clone, Debug)]
pub(crate) struct CameraRig {
    projection: Projection,
    near: f32,
    far: Option<f32>,
    pub(crate) translation: Slot<Vec3>,
    pub(crate) rotation: Slot<Quat>,
    pub(crate) lens: Slot<f32>,
    pub(crate) visible: Slot<f32>,
    pub(crate) aim: Option<AimRig>,
    problem: Option<EvalProblem>,
}

fn resolve(scene: &Scene, target: &AimTarget) -> (Target, Option<String>) {
    match target {
        AimTarget::Point(p) => (Target::Point(*p), None),
        AimTarget::Object(name) => match scene.objects.iter().position(|o| &o.name == name) {
            Some(o) => (Target::Object(o), None),
            None => (Target::Missing, Some(format!("no object named {name:?} to aim at"))),
        },
        AimTarget::Joint { object, joint } => {
            let found = scene.objects.iter().position(|o| &o.name == object).and_then(|o| {
                let skeleton = scene.objects[o].skeleton.as_ref()?;
                Some((o, skeleton.joints.iter().position(|j| &j.name == joint)?))
            });
            match found {
                Some((object, joint)) => (Target::Joint { object, joint }, None),
                None => (Target::Missing, Some(format!("no joint {object:?}/{joint:?} to aim at"))),
            }
        }
    }
}

impl CameraRig {
    pub(crate) fn new(scene: &Scene, c: usize) -> Self {
        let camera = &scene.cameras[c];
        let mut rig = CameraRig {
            projection: camera.projection,
            near: camera.near,
            far: camera.far,
            translation: Slot::new(&camera.translation, ChannelId::CameraTranslation(c)),
            rotation: Slot::new(&camera.rotation, ChannelId::CameraRotation(c)),
            lens: Slot::new(&camera.lens, ChannelId::CameraLens(c)),
            visible: Slot::new(&camera.visible, ChannelId::CameraVisible(c)),
            aim: None,
            problem: None,
        };
        rig.refresh(scene, c);
        rig
    }

    /// Brings the rig in step with `scene`'s camera `c`: a channel is rebuilt only where its
    /// keys changed; the settings and the aim target are read again (an object may have been
    /// renamed or removed). Returns the number of channels rebuilt.
    pub(crate) fn refresh(&mut self, scene: &Scene, c: usize) -> usize {
        let camera: &SceneCamera = &scene.cameras[c];
        self.projection = camera.projection;
        self.near = camera.near;
        self.far = camera.far;
        let mut n =
            usize::from(self.translation.refresh(&camera.translation, ChannelId::CameraTranslation(c)))
                + usize::from(self.rotation.refresh(&camera.rotation, ChannelId::CameraRotation(c)))
                + usize::from(self.lens.refresh(&camera.lens, ChannelId::CameraLens(c)))
                + usize::from(self.visible.refresh(&camera.visible, ChannelId::CameraVisible(c)));
        self.problem = None;
        match (&mut self.aim, &camera.aim) {
            (_, None) => self.aim = None,
            (Some(rig), Some(aim)) => {
                n += usize::from(rig.roll.refresh(&aim.roll, ChannelId::CameraRoll(c)))
                    + usize::from(rig.influence.refresh(&aim.influence, ChannelId::CameraAimInfluence(c)));
                rig.up = aim.up;
                let (target, problem) = resolve(scene, &aim.target);
                rig.target = target;
                self.problem =
                    problem.map(|message| EvalProblem { path: format!("cameras[{c}].aim.target"), message });
            }
            (None, Some(aim)) => {
                n += 2;
                let (target, problem) = resolve(scene, &aim.target);
                self.aim = Some(AimRig {
                    target,
                    up: aim.up,
                    roll: Slot::new(&aim.roll, ChannelId::CameraRoll(c)),
                    influence: Slot::new(&aim.influence, ChannelId::CameraAimInfluence(c)),
                });
                self.problem =
                    problem.map(|message| EvalProblem { path: format!("cameras[{c}].aim.target"), message });
            }
        }
        n
    }

    pub(crate) fn channel_count(&self) -> usize {
        4 + 2 * usize::from(self.aim.is_some())
    }

    pub(crate) fn for_each_problem(&self, f: &mut dyn FnMut(&EvalProblem)) {
        for p in [
            &self.problem,
            &self.translation.problem,
            &self.rotation.problem,
            &self.lens.problem,
            &self.visible.problem,
        ]
        .into_iter()
        .chain(self.aim.iter().flat_map(|a| [&a.roll.problem, &a.influence.problem]))
        .flatten()
        {
            f(p);
        }
    }

    /// The camera at `time`; `target` gives the world position of what it aims at (`None`
    /// when that cannot be found, which keeps the keyed rotation).
    pub(crate) fn state(
        &self,
        c: usize,
        time: f64,
        overrides: &Overrides,
        target: impl FnOnce(&Target) -> Option<Vec3>,
    ) -> CameraState {
        let eye = match overrides.get(&ChannelId::CameraTranslation(c)) {
            Some(ChannelValue::Vec3(v)) => *v,
            _ => self.translation.sample(time),
        };
        let keyed = match overrides.get(&ChannelId::CameraRotation(c)) {
            Some(ChannelValue::Rotation(q)) => *q,
            _ => self.rotation.sample(time),
        };
        let keyed = if keyed.is_finite() && keyed.length_squared() > 1e-12 {
            keyed.normalize()
        } else {
            Quat::IDENTITY
        };
        let rotation = self
            .aim
            .as_ref()
            .and_then(|aim| {
                let roll = match overrides.get(&ChannelId::CameraRoll(c)) {
                    Some(ChannelValue::Scalar(v)) => *v,
                    _ => aim.roll.sample(time),
                };
                let influence = match overrides.get(&ChannelId::CameraAimInfluence(c)) {
                    Some(ChannelValue::Scalar(v)) => *v,
                    _ => aim.influence.sample(time),
                };
                if influence.is_nan() || influence <= 0.0 {
                    return None;
                }
                let aimed =
                    keyrig_core::camera_object::aim_rotation(eye, target(&aim.target)?, aim.up, roll)?;
                // Keyed influence (docs/constraints.md): slerp from the keyed rotation.
                Some(if influence >= 1.0 { aimed } else { keyed.slerp(aimed, influence).normalize() })
            })
            .unwrap_or(keyed);
        let lens = match overrides.get(&ChannelId::CameraLens(c)) {
            Some(ChannelValue::Scalar(v)) => *v,
            _ => self.lens.sample(time),
        };
        let visible = match overrides.get(&ChannelId::CameraVisible(c)) {
            Some(ChannelValue::Scalar(v)) => *v,
            _ => self.visible.sample(time),
        };
        CameraState {
            world_from_camera: Affine3A::from_rotation_translation(rotation, eye),
            lens: Lens::of(self.projection, lens),
            near: self.near,
            far: self.far,
            visible: visible >= 0.5,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec4;

    /// glTF 2.0 §3.10.3's matrices, written out from the specification (OpenGL clip space,
    /// depth −1..1), row by row.
    fn gltf_perspective(aspect: f32, yfov: f32, znear: f32, zfar: Option<f32>) -> Mat4 {
        let t = (0.5 * yfov).tan();
        let (r2, r3) = match zfar {
            Some(f) => {
                ([0.0, 0.0, (f + znear) / (znear - f), 2.0 * f * znear / (znear - f)], [0.0, 0.0, -1.0, 0.0])
            }
            None => ([0.0, 0.0, -1.0, -2.0 * znear], [0.0, 0.0, -1.0, 0.0]),
        };
        Mat4::from_cols_array_2d(&[[1.0 / (aspect * t), 0.0, 0.0, 0.0], [0.0, 1.0 / t, 0.0, 0.0], r2, r3])
            .transpose()
    }

    fn gltf_orthographic(xmag: f32, ymag: f32, znear: f32, zfar: f32) -> Mat4 {
        Mat4::from_cols_array_2d(&[
            [1.0 / xmag, 0.0, 0.0, 0.0],
            [0.0, 1.0 / ymag, 0.0, 0.0],
            [0.0, 0.0, 2.0 / (znear - zfar), (zfar + znear) / (znear - zfar)],
            [0.0, 0.0, 0.0, 1.0],
        ])
        .transpose()
    }

    /// The same clip position in wgpu's depth range: z' = (z + w) / 2.
    fn to_zero_one(clip: Vec4) -> Vec4 {
        Vec4::new(clip.x, clip.y, 0.5 * (clip.z + clip.w), clip.w)
    }

    fn points() -> [Vec4; 4] {
        [
            Vec4::new(0.3, -0.2, -0.5, 1.0),
            Vec4::new(-2.0, 1.0, -7.0, 1.0),
            Vec4::new(5.0, 4.0, -90.0, 1.0),
            Vec4::new(0.0, 0.0, -0.1, 1.0),
        ]
    }

    fn state(lens: Lens, near: f32, far: Option<f32>) -> CameraState {
        CameraState { world_from_camera: Affine3A::IDENTITY, lens, near, far, visible: true }
    }

    #[test]
    fn perspective_is_gltfs_projection() {
        for far in [Some(100.0), None] {
            let camera = state(Lens::Perspective { fov_y: 0.8 }, 0.1, far);
            let ours = camera.clip_from_view(1.5);
            let theirs = gltf_perspective(1.5, 0.8, 0.1, far);
            for p in points() {
                let (a, b) = (ours * p, to_zero_one(theirs * p));
                assert!(a.abs_diff_eq(b, 1e-4 * b.abs().max_element().max(1.0)), "{far:?} {p}: {a} vs {b}");
            }
        }
    }

    #[test]
    fn orthographic_is_gltfs_projection() {
        // keyrig's lens is the view height; glTF's ymag is half of it, xmag = ymag · aspect.
        let camera = state(Lens::Orthographic { height: 4.0 }, 0.5, Some(50.0));
        let ours = camera.clip_from_view(2.0);
        let theirs = gltf_orthographic(4.0, 2.0, 0.5, 50.0);
        for p in points() {
            let (a, b) = (ours * p, to_zero_one(theirs * p));
            assert!(a.abs_diff_eq(b, 1e-5), "{p}: {a} vs {b}");
        }
    }

    #[test]
    fn view_matrix_is_the_hand_computed_look_at() {
        // A camera at (3, 0, 0) turned +90° about Y looks at the origin down −X. By hand, view
        // space from world: x_v = −z_w, y_v = y_w, z_v = x_w − 3.
        let camera = CameraState {
            world_from_camera: Affine3A::from_rotation_translation(
                Quat::from_rotation_y(std::f32::consts::FRAC_PI_2),
                Vec3::new(3.0, 0.0, 0.0),
            ),
            ..state(Lens::Perspective { fov_y: 1.0 }, 0.1, Some(10.0))
        };
        let by_hand = Mat4::from_cols_array_2d(&[
            [0.0, 0.0, -1.0, 0.0],
            [0.0, 1.0, 0.0, 0.0],
            [1.0, 0.0, 0.0, -3.0],
            [0.0, 0.0, 0.0, 1.0],
        ])
        .transpose();
        assert!(camera.view_from_world().abs_diff_eq(by_hand, 1e-6), "{}", camera.view_from_world());
        assert!(camera.forward().abs_diff_eq(Vec3::NEG_X, 1e-6));
        // The origin lies at the image centre, in front of the near plane.
        let clip = camera.clip_from_world(1.0) * Vec4::W;
        assert!(clip.x.abs() < 1e-6 && clip.y.abs() < 1e-6 && clip.w > 0.0);
    }

    #[test]
    fn image_corners_span_the_field_of_view() {
        let camera = state(Lens::Perspective { fov_y: 90f32.to_radians() }, 0.1, None);
        let [bl, _, tr, _] = camera.image_corners(2.0, 1.0);
        assert!(bl.abs_diff_eq(Vec3::new(-2.0, -1.0, -1.0), 1e-5), "{bl}");
        assert!(tr.abs_diff_eq(Vec3::new(2.0, 1.0, -1.0), 1e-5), "{tr}");
        assert!(camera.is_usable());
        assert!(!state(Lens::Orthographic { height: 0.0 }, 0.1, Some(1.0)).is_usable());
    }
}
