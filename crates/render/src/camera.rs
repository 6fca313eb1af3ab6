//! The orbit camera of keyrig_core::Camera as view and projection matrices (Y up,
//! right-handed, wgpu depth range 0..1).

use glam::{Mat4, Vec3};
use keyrig_core::Camera;

/// Near plane as a fraction of the orbit distance; far plane as a multiple of it.
const NEAR_FRACTION: f32 = 0.01;
const FAR_MULTIPLE: f32 = 100.0;

/// World-space eye position: `distance` from the target, `yaw` about +Y (0° looks from +Z
/// towards −Z), `pitch` above the ground plane.
#[must_use]
pub fn eye_position(camera: &Camera) -> Vec3 {
    let yaw = camera.yaw_deg.to_radians();
    let pitch = camera.pitch_deg.to_radians();
    let offset = Vec3::new(pitch.cos() * yaw.sin(), pitch.sin(), pitch.cos() * yaw.cos());
    camera.target + offset * camera.distance
}

/// View matrix (view space from world space).
#[must_use]
pub fn view_from_world(camera: &Camera) -> Mat4 {
    let eye = eye_position(camera);
    // Straight above or below the target, Y cannot be "up": use −Z/+Z instead.
    let forward = (camera.target - eye).normalize_or(Vec3::NEG_Z);
    let up = if forward.cross(Vec3::Y).length_squared() < 1e-8 { Vec3::NEG_Z } else { Vec3::Y };
    Mat4::look_at_rh(eye, camera.target, up)
}

/// Projection (clip space from view space) for an image `aspect` = width / height.
#[must_use]
pub fn clip_from_view(camera: &Camera, aspect: f32) -> Mat4 {
    let distance = camera.distance.abs().max(1e-4);
    let fov = camera.fov_y_deg.clamp(1.0, 170.0).to_radians();
    Mat4::perspective_rh(fov, aspect.max(1e-4), distance * NEAR_FRACTION, distance * FAR_MULTIPLE)
}

/// Clip space from world space.
#[must_use]
pub fn clip_from_world(camera: &Camera, aspect: f32) -> Mat4 {
    clip_from_view(camera, aspect) * view_from_world(camera)
}

/// Clip space from world space with explicit near and far planes (view-space distances, as
/// an editor fits them to the scene's size); the orbit distance's defaults where `depth` is
/// `None` or unusable.
#[must_use]
pub fn clip_from_world_in(camera: &Camera, aspect: f32, depth: Option<[f32; 2]>) -> Mat4 {
    match depth {
        Some([near, far]) if near.is_finite() && far.is_finite() && near > 0.0 && far > near => {
            let fov = camera.fov_y_deg.clamp(1.0, 170.0).to_radians();
            Mat4::perspective_rh(fov, aspect.max(1e-4), near, far) * view_from_world(camera)
        }
        _ => clip_from_world(camera, aspect),
    }
}

/// Checks that a camera has finite numbers and a positive distance.
#[must_use]
pub fn is_usable(camera: &Camera) -> bool {
    camera.target.is_finite()
        && [camera.yaw_deg, camera.pitch_deg, camera.distance, camera.fov_y_deg].iter().all(|x| x.is_finite())
        && camera.distance > 0.0
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn target_projects_to_the_image_centre() {
        let camera = Camera {
            target: Vec3::new(1.0, 2.0, 3.0),
            yaw_deg: 40.0,
            pitch_deg: 25.0,
            distance: 7.0,
            fov_y_deg: 50.0,
        };
        let clip = clip_from_world(&camera, 16.0 / 9.0) * camera.target.extend(1.0);
        let ndc = clip.truncate() / clip.w;
        assert!(ndc.x.abs() < 1e-5 && ndc.y.abs() < 1e-5, "{ndc}");
        assert!((0.0..1.0).contains(&ndc.z));
        assert!((eye_position(&camera).distance(camera.target) - 7.0).abs() < 1e-5);
    }

    #[test]
    fn looking_straight_down_is_finite() {
        let camera = Camera { pitch_deg: 90.0, ..Camera::default() };
        assert!(clip_from_world(&camera, 1.0).is_finite());
    }
}
