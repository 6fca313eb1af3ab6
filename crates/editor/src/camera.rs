//! The viewport's orbit camera and the world → screen projection used to draw the overlay
//! (grid, bones, lights) and to drive the gizmo.

use egui::{Pos2, Rect};
use glam::{Mat4, Vec3};

/// An orbit camera: a target point, yaw about world Y, pitch above the ground, a distance.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OrbitCamera {
    pub target: Vec3,
    pub yaw_deg: f32,
    pub pitch_deg: f32,
    pub distance: f32,
    pub fov_y_deg: f32,
}

/// Pitch stays inside ±89.9° so the view never flips at the poles.
const PITCH_LIMIT: f32 = 89.9;
const NEAR: f32 = 0.01;
const FAR: f32 = 1000.0;

impl From<keyrig_core::Camera> for OrbitCamera {
    fn from(c: keyrig_core::Camera) -> Self {
        let finite_or = |v: f32, d: f32| if v.is_finite() { v } else { d };
        OrbitCamera {
            target: if c.target.is_finite() { c.target } else { Vec3::ZERO },
            yaw_deg: finite_or(c.yaw_deg, 30.0),
            pitch_deg: finite_or(c.pitch_deg, 20.0).clamp(-PITCH_LIMIT, PITCH_LIMIT),
            distance: finite_or(c.distance, 5.0).max(0.05),
            fov_y_deg: finite_or(c.fov_y_deg, 45.0).clamp(5.0, 150.0),
        }
    }
}

impl OrbitCamera {
    /// Where the camera is, world space.
    #[must_use]
    pub fn eye(&self) -> Vec3 {
        let (yaw, pitch) = (self.yaw_deg.to_radians(), self.pitch_deg.to_radians());
        let dir = Vec3::new(pitch.cos() * yaw.sin(), pitch.sin(), pitch.cos() * yaw.cos());
        self.target + dir * self.distance
    }

    /// View matrix (camera from world).
    #[must_use]
    pub fn camera_from_world(&self) -> Mat4 {
        Mat4::look_at_rh(self.eye(), self.target, Vec3::Y)
    }

    /// Projection matrix (clip from camera) for a viewport of the given aspect ratio.
    #[must_use]
    pub fn clip_from_camera(&self, aspect: f32) -> Mat4 {
        Mat4::perspective_rh(self.fov_y_deg.to_radians(), aspect.max(1e-3), NEAR, FAR)
    }

    /// Rotates the view by a mouse drag (degrees per point).
    pub fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw_deg = (self.yaw_deg - dx * 0.4).rem_euclid(360.0);
        self.pitch_deg = (self.pitch_deg + dy * 0.4).clamp(-PITCH_LIMIT, PITCH_LIMIT);
    }

    /// Moves the target in the view plane by a drag in points, for a viewport `height` points high.
    pub fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let view = self.camera_from_world().inverse();
        let right = view.transform_vector3(Vec3::X);
        let up = view.transform_vector3(Vec3::Y);
        let world_per_point =
            2.0 * self.distance * (self.fov_y_deg.to_radians() / 2.0).tan() / height.max(1.0);
        self.target += (-right * dx + up * dy) * world_per_point;
    }

    /// Zooms by a scroll amount (positive moves closer).
    pub fn zoom(&mut self, scroll: f32) {
        self.distance = (self.distance * (-scroll * 0.002).exp()).clamp(0.05, 500.0);
    }
}

/// World → screen projection for one frame of one viewport rect.
#[derive(Clone, Copy, Debug)]
pub struct Projection {
    pub rect: Rect,
    pub clip_from_world: Mat4,
    pub camera_from_world: Mat4,
    pub clip_from_camera: Mat4,
}

impl Projection {
    #[must_use]
    pub fn new(camera: &OrbitCamera, rect: Rect) -> Self {
        let camera_from_world = camera.camera_from_world();
        let clip_from_camera = camera.clip_from_camera(rect.width() / rect.height().max(1.0));
        Projection {
            rect,
            clip_from_world: clip_from_camera * camera_from_world,
            camera_from_world,
            clip_from_camera,
        }
    }

    /// Screen position of a world point, `None` behind the camera.
    #[must_use]
    pub fn project(&self, p: Vec3) -> Option<Pos2> {
        let clip = self.clip_from_world * p.extend(1.0);
        if clip.w <= NEAR {
            return None;
        }
        let ndc = clip.truncate() / clip.w;
        if !ndc.is_finite() {
            return None;
        }
        Some(Pos2::new(
            self.rect.left() + (ndc.x * 0.5 + 0.5) * self.rect.width(),
            self.rect.top() + (0.5 - ndc.y * 0.5) * self.rect.height(),
        ))
    }

    /// Projects a segment, clipped against the near plane; `None` when fully behind.
    #[must_use]
    pub fn project_segment(&self, a: Vec3, b: Vec3) -> Option<[Pos2; 2]> {
        let wa = (self.clip_from_world * a.extend(1.0)).w;
        let wb = (self.clip_from_world * b.extend(1.0)).w;
        let near = NEAR * 2.0;
        if wa < near && wb < near {
            return None;
        }
        let (a, b) = if wa < near {
            (b + (a - b) * ((wb - near) / (wb - wa)), b)
        } else if wb < near {
            (a, a + (b - a) * ((wa - near) / (wa - wb)))
        } else {
            (a, b)
        };
        Some([self.project(a)?, self.project(b)?])
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn target_projects_to_the_centre() {
        let camera = OrbitCamera {
            target: Vec3::new(1.0, 2.0, 3.0),
            yaw_deg: 40.0,
            pitch_deg: 20.0,
            distance: 4.0,
            fov_y_deg: 45.0,
        };
        let rect = Rect::from_min_size(Pos2::new(10.0, 20.0), egui::vec2(400.0, 300.0));
        let p = Projection::new(&camera, rect).project(camera.target).expect("in front");
        assert!((p - rect.center()).length() < 1e-3, "{p:?}");
    }

    #[test]
    fn points_behind_the_camera_do_not_project() {
        let camera =
            OrbitCamera { target: Vec3::ZERO, yaw_deg: 0.0, pitch_deg: 0.0, distance: 4.0, fov_y_deg: 45.0 };
        let rect = Rect::from_min_size(Pos2::ZERO, egui::vec2(400.0, 300.0));
        assert!(Projection::new(&camera, rect).project(Vec3::new(0.0, 0.0, 10.0)).is_none());
    }
}
