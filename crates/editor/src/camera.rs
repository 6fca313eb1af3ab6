//! The viewport's orbit camera and the world → screen projection used to draw the overlay
//! (grid, bones, lights) and to drive the gizmo.

use egui::{Pos2, Rect};
use glam::{Mat4, Vec3};
use keyrig_core::Camera;

/// Pitch stays inside ±89.9° so the view never flips at the poles.
const PITCH_LIMIT: f32 = 89.9;
const NEAR: f32 = 0.01;
const FAR: f32 = 1000.0;
/// Orbit distances the zoom and framing keep to (a 1 mm part to a 10 km scene).
const MIN_DISTANCE: f32 = 0.001;
const MAX_DISTANCE: f32 = 10_000.0;

/// An axis-aligned world box (deformed meshes, joints), for framing and clip planes.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Bounds {
    pub min: Vec3,
    pub max: Vec3,
}

impl Bounds {
    /// The box of `points` (`None` when there are none or none is finite).
    #[must_use]
    pub fn of(points: impl IntoIterator<Item = Vec3>) -> Option<Bounds> {
        let mut b = Bounds { min: Vec3::MAX, max: Vec3::MIN };
        for p in points.into_iter().filter(|p| p.is_finite()) {
            b.min = b.min.min(p);
            b.max = b.max.max(p);
        }
        b.is_valid().then_some(b)
    }

    /// The box holding both.
    #[must_use]
    pub fn union(self, other: Bounds) -> Bounds {
        Bounds { min: self.min.min(other.min), max: self.max.max(other.max) }
    }

    #[must_use]
    pub fn is_valid(&self) -> bool {
        self.min.is_finite() && self.max.is_finite() && self.min.cmple(self.max).all()
    }

    #[must_use]
    pub fn centre(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Half the diagonal.
    #[must_use]
    pub fn radius(&self) -> f32 {
        (self.max - self.min).length() * 0.5
    }

    /// How far from `from` (inside or outside the box) along the unit direction `dir` the
    /// ray leaves the box; 0 when it misses or leaves behind `from`.
    #[must_use]
    pub fn exit_distance(&self, from: Vec3, dir: Vec3) -> f32 {
        let mut t_exit = f32::INFINITY;
        let mut t_enter = f32::NEG_INFINITY;
        for axis in 0..3 {
            let (o, d) = (from[axis], dir[axis]);
            if d.abs() < 1e-12 {
                if o < self.min[axis] || o > self.max[axis] {
                    return 0.0;
                }
                continue;
            }
            let (a, b) = ((self.min[axis] - o) / d, (self.max[axis] - o) / d);
            t_enter = t_enter.max(a.min(b));
            t_exit = t_exit.min(a.max(b));
        }
        if t_exit < t_enter.max(0.0) || !t_exit.is_finite() {
            0.0
        } else {
            t_exit
        }
    }
}

/// The editor's controls of the scene's one camera type ([`keyrig_core::Camera`], an orbit
/// around a target): orbit, pan, zoom and framing, and the matrices of the overlay. The view
/// and the eye come from keyrig-render's camera functions, so the overlay, the gizmo and the
/// GPU viewport see through the same camera.
pub trait OrbitCamera {
    /// The camera with non-finite fields replaced by the defaults and the angles, distance
    /// and field of view inside what the controls keep to (a scene file's camera).
    #[must_use]
    fn sanitized(self) -> Camera;
    /// Where the camera is, world space.
    fn eye(&self) -> Vec3;
    /// View matrix (camera from world).
    fn camera_from_world(&self) -> Mat4;
    /// Projection matrix (clip from camera) for the overlay and the gizmo.
    fn clip_from_camera(&self, aspect: f32) -> Mat4;
    /// Near and far planes fitted to `bounds` (see the implementation).
    fn depth_range(&self, bounds: Option<Bounds>) -> [f32; 2];
    /// The orbit distance at which a sphere of `radius` fills the view.
    fn distance_to_fit(&self, radius: f32, aspect: f32) -> f32;
    /// Centres on `bounds` and moves back until they fill the view (keeps the angles).
    fn frame(&mut self, bounds: Bounds, aspect: f32);
    /// Rotates the view by a mouse drag (degrees per point).
    fn orbit(&mut self, dx: f32, dy: f32);
    /// Moves the target in the view plane by a drag in points.
    fn pan(&mut self, dx: f32, dy: f32, height: f32);
    /// Zooms by a scroll amount (positive moves closer).
    fn zoom(&mut self, scroll: f32);
}

impl OrbitCamera for Camera {
    fn sanitized(self) -> Camera {
        let c = self;
        let finite_or = |v: f32, d: f32| if v.is_finite() { v } else { d };
        Camera {
            target: if c.target.is_finite() { c.target } else { Vec3::ZERO },
            yaw_deg: finite_or(c.yaw_deg, 30.0),
            pitch_deg: finite_or(c.pitch_deg, 20.0).clamp(-PITCH_LIMIT, PITCH_LIMIT),
            distance: finite_or(c.distance, 5.0).max(0.05),
            fov_y_deg: finite_or(c.fov_y_deg, 45.0).clamp(5.0, 150.0),
        }
    }

    fn eye(&self) -> Vec3 {
        keyrig_render::camera::eye_position(self)
    }

    fn camera_from_world(&self) -> Mat4 {
        keyrig_render::camera::view_from_world(self)
    }

    /// Projection matrix (clip from camera) for a viewport of the given aspect ratio (for
    /// the overlay and the gizmo: planes wide enough for any zoom).
    fn clip_from_camera(&self, aspect: f32) -> Mat4 {
        let near = NEAR.min(self.distance * 1e-3).max(1e-6);
        let far = FAR.max(self.distance * 1e3);
        Mat4::perspective_rh(self.fov_y_deg.to_radians(), aspect.max(1e-3), near, far)
    }

    /// Near and far planes (view-space distances) for the orbit distance d: near = d / 100,
    /// far = 100·d, with the far plane pushed out to hold the world box `bounds` (the
    /// scene's deformed meshes) when the scene is larger than that, as when a 100 m model
    /// is looked at from a metre; the ratio far / near stays within 10⁶ for depth
    /// precision.
    fn depth_range(&self, bounds: Option<Bounds>) -> [f32; 2] {
        let d = self.distance.max(1e-6);
        let near = d * 0.01;
        let far = match bounds.filter(Bounds::is_valid) {
            Some(b) => (d * 100.0).max((self.eye().distance(b.centre()) + b.radius()) * 1.5),
            None => d * 100.0,
        };
        [near.max(far * 1e-6), far]
    }

    /// The orbit distance at which a sphere of `radius` fills the view (with a margin), for
    /// framing.
    fn distance_to_fit(&self, radius: f32, aspect: f32) -> f32 {
        let half_y = (self.fov_y_deg.to_radians() * 0.5).clamp(0.01, 1.5);
        let half_x = (half_y.tan() * aspect.max(0.1)).atan();
        (radius.max(1e-3) / half_y.min(half_x).sin() * 1.1).clamp(MIN_DISTANCE, MAX_DISTANCE)
    }

    /// Centres on `bounds` and moves back until they fill the view (keeps the angles).
    fn frame(&mut self, bounds: Bounds, aspect: f32) {
        if bounds.is_valid() {
            self.target = bounds.centre();
            self.distance = self.distance_to_fit(bounds.radius(), aspect);
        }
    }

    /// Rotates the view by a mouse drag (degrees per point).
    fn orbit(&mut self, dx: f32, dy: f32) {
        self.yaw_deg = (self.yaw_deg - dx * 0.4).rem_euclid(360.0);
        self.pitch_deg = (self.pitch_deg + dy * 0.4).clamp(-PITCH_LIMIT, PITCH_LIMIT);
    }

    /// Moves the target in the view plane by a drag in points, for a viewport `height` points high.
    fn pan(&mut self, dx: f32, dy: f32, height: f32) {
        let view = self.camera_from_world().inverse();
        let right = view.transform_vector3(Vec3::X);
        let up = view.transform_vector3(Vec3::Y);
        let world_per_point =
            2.0 * self.distance * (self.fov_y_deg.to_radians() / 2.0).tan() / height.max(1.0);
        self.target += (-right * dx + up * dy) * world_per_point;
    }

    /// Zooms by a scroll amount (positive moves closer).
    fn zoom(&mut self, scroll: f32) {
        self.distance = (self.distance * (-scroll * 0.002).exp()).clamp(MIN_DISTANCE, MAX_DISTANCE);
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
    pub fn new(camera: &Camera, rect: Rect) -> Self {
        let camera_from_world = camera.camera_from_world();
        let clip_from_camera = camera.clip_from_camera(rect.width() / rect.height().max(1.0));
        Projection {
            rect,
            clip_from_world: clip_from_camera * camera_from_world,
            camera_from_world,
            clip_from_camera,
        }
    }

    /// The projection of scene camera `camera` (looking through it) for `rect`.
    #[must_use]
    pub fn through(camera: &keyrig_eval::CameraState, rect: Rect) -> Self {
        let camera_from_world = camera.view_from_world();
        let clip_from_camera = camera.clip_from_view(rect.width() / rect.height().max(1.0));
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

    /// The view ray through a screen point: the eye and the unit direction (world space) of
    /// the points that [`Projection::project`] puts at `screen`. From the perspective matrix,
    /// a point at camera-space depth −1 lands at NDC `(x, y)` when it is `(x / m₀₀, y / m₁₁, −1)`.
    #[must_use]
    pub fn ray(&self, screen: Pos2) -> Option<(Vec3, Vec3)> {
        let ndc_x = (screen.x - self.rect.left()) / self.rect.width() * 2.0 - 1.0;
        let ndc_y = 1.0 - (screen.y - self.rect.top()) / self.rect.height() * 2.0;
        let (sx, sy) = (self.clip_from_camera.x_axis.x, self.clip_from_camera.y_axis.y);
        let world_from_camera = self.camera_from_world.inverse();
        // An orthographic projection (w does not depend on depth): parallel rays from the
        // point on the camera's plane.
        let orthographic = self.clip_from_camera.z_axis.w == 0.0;
        let (eye, in_camera) = if orthographic {
            (world_from_camera.transform_point3(Vec3::new(ndc_x / sx, ndc_y / sy, 0.0)), Vec3::NEG_Z)
        } else {
            (world_from_camera.transform_point3(Vec3::ZERO), Vec3::new(ndc_x / sx, ndc_y / sy, -1.0))
        };
        let dir = world_from_camera.transform_vector3(in_camera).try_normalize()?;
        (eye.is_finite() && dir.is_finite()).then_some((eye, dir))
    }

    /// Where the view ray through `screen` meets the plane through `point` with the normal
    /// `normal`; `None` when the ray runs parallel to the plane or meets it behind the eye.
    #[must_use]
    pub fn on_plane(&self, screen: Pos2, point: Vec3, normal: Vec3) -> Option<Vec3> {
        let (eye, dir) = self.ray(screen)?;
        let facing = dir.dot(normal);
        if facing.abs() < 1e-6 {
            return None;
        }
        let t = (point - eye).dot(normal) / facing;
        (t > 0.0 && t.is_finite()).then(|| eye + dir * t)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn target_projects_to_the_centre() {
        let camera = Camera {
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

    /// The planes hold a 200 m model seen from 1 m and a 1 cm one seen from 5 cm.
    #[test]
    fn depth_range_holds_the_scene() {
        let big = Bounds { min: Vec3::splat(-100.0), max: Vec3::splat(100.0) };
        let camera =
            Camera { target: Vec3::ZERO, yaw_deg: 0.0, pitch_deg: 0.0, distance: 1.0, fov_y_deg: 45.0 };
        let [near, far] = camera.depth_range(Some(big));
        assert!(far > 1.0 + big.radius() && near < 1.0 && near > 0.0, "{near} {far}");
        let small = Bounds { min: Vec3::splat(-0.005), max: Vec3::splat(0.005) };
        let camera = Camera { distance: 0.05, ..camera };
        let [near, far] = camera.depth_range(Some(small));
        assert!(near > 0.0 && near < 0.05 - small.radius() && far > 0.05 + small.radius() && far < 10.0);
    }

    #[test]
    fn framing_fits_the_box_and_exit_distance_leaves_it() {
        let b = Bounds { min: Vec3::new(-1.0, 0.0, -1.0), max: Vec3::new(1.0, 2.0, 1.0) };
        let mut camera =
            Camera { target: Vec3::ZERO, yaw_deg: 30.0, pitch_deg: 10.0, distance: 1.0, fov_y_deg: 45.0 };
        camera.frame(b, 1.5);
        assert_eq!(camera.target, Vec3::Y);
        assert!(camera.distance > b.radius() / (22.5f32.to_radians().sin()));
        assert!((b.exit_distance(Vec3::ZERO + Vec3::Y, Vec3::X) - 1.0).abs() < 1e-6);
        assert_eq!(b.exit_distance(Vec3::new(5.0, 1.0, 0.0), Vec3::X), 0.0);
    }

    /// A point found on a plane from its screen position projects back to that position, and
    /// lies on the plane.
    #[test]
    fn on_plane_inverts_project() {
        let camera = Camera {
            target: Vec3::new(0.3, 1.0, -0.2),
            yaw_deg: 25.0,
            pitch_deg: 15.0,
            distance: 3.2,
            fov_y_deg: 45.0,
        };
        let rect = Rect::from_min_size(Pos2::new(180.0, 40.0), egui::vec2(820.0, 470.0));
        let projection = Projection::new(&camera, rect);
        let point = Vec3::new(0.5, 0.9, 0.1);
        let normal = (camera.target - camera.eye()).normalize();
        for screen in [rect.center(), Pos2::new(200.0, 60.0), Pos2::new(950.0, 480.0)] {
            let hit = projection.on_plane(screen, point, normal).expect("the plane faces the camera");
            assert!((hit - point).dot(normal).abs() < 1e-5, "on the plane: {hit:?}");
            let back = projection.project(hit).expect("in front");
            assert!((back - screen).length() < 1e-3, "{screen:?} → {hit:?} → {back:?}");
        }
        assert!(
            projection.on_plane(rect.center(), camera.eye() - normal, normal).is_none(),
            "behind the eye"
        );
    }

    #[test]
    fn points_behind_the_camera_do_not_project() {
        let camera =
            Camera { target: Vec3::ZERO, yaw_deg: 0.0, pitch_deg: 0.0, distance: 4.0, fov_y_deg: 45.0 };
        let rect = Rect::from_min_size(Pos2::ZERO, egui::vec2(400.0, 300.0));
        assert!(Projection::new(&camera, rect).project(Vec3::new(0.0, 0.0, 10.0)).is_none());
    }
}
