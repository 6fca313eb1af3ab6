//! Scene edits for cameras that keep the scene valid: markers and the active camera follow a
//! renamed or deleted camera, aims follow a renamed object or joint and are dropped with a
//! deleted object; and the orbit view as a camera (set camera to view, add camera).

use glam::{Quat, Vec3};
use keyrig_core::{AimTarget, Camera, Marker, Scene};

/// Removes camera `c`; markers bound to it are unbound and the active camera forgotten when it
/// was this one (a marker or `active_camera` naming a missing camera is a scene problem).
pub fn remove_camera(scene: &mut Scene, c: usize) {
    if c >= scene.cameras.len() {
        return;
    }
    let name = scene.cameras.remove(c).name;
    for marker in &mut scene.markers {
        if marker.camera.as_deref() == Some(name.as_str()) {
            marker.camera = None;
        }
    }
    if scene.active_camera.as_deref() == Some(name.as_str()) {
        scene.active_camera = None;
    }
}

/// Renames camera `c` to `name`, and the markers and active camera that named it.
pub fn rename_camera(scene: &mut Scene, c: usize, name: String) {
    let Some(camera) = scene.cameras.get_mut(c) else { return };
    let old = std::mem::replace(&mut camera.name, name.clone());
    for marker in &mut scene.markers {
        if marker.camera.as_deref() == Some(old.as_str()) {
            marker.camera = Some(name.clone());
        }
    }
    if scene.active_camera.as_deref() == Some(old.as_str()) {
        scene.active_camera = Some(name);
    }
}

/// Renames what cameras aim at: the object `object` (when `joint` is `None`) or its joint
/// `joint`, to `new`.
pub fn rename_aim_targets(scene: &mut Scene, object: &str, joint: Option<&str>, new: &str) {
    for aim in scene.cameras.iter_mut().filter_map(|c| c.aim.as_mut()) {
        match (&mut aim.target, joint) {
            (AimTarget::Object(o), None) if o == object => *o = new.to_owned(),
            (AimTarget::Joint { object: o, .. }, None) if o == object => *o = new.to_owned(),
            (AimTarget::Joint { object: o, joint: j }, Some(old)) if o == object && j == old => {
                *j = new.to_owned();
            }
            _ => {}
        }
    }
}

/// Cameras aimed at the deleted object `object` (or one of its joints) keep their keyed
/// rotation: their aim is removed, so the scene stays valid.
pub fn forget_aim_targets(scene: &mut Scene, object: &str) {
    for camera in &mut scene.cameras {
        let aimed_at_it = camera.aim.as_ref().is_some_and(|aim| match &aim.target {
            AimTarget::Object(o) | AimTarget::Joint { object: o, .. } => o == object,
            AimTarget::Point(_) => false,
        });
        if aimed_at_it {
            camera.aim = None;
        }
    }
}

/// The world position and rotation of the orbit view `camera` as a scene camera (looking down
/// its −Z, +Y up): what "set camera to current view" keys.
#[must_use]
pub fn view_as_camera(camera: &Camera) -> (Vec3, Quat) {
    let eye = keyrig_render::camera::eye_position(camera);
    let rotation = keyrig_core::camera_object::aim_rotation(eye, camera.target, Vec3::Y, 0.0)
        .or_else(|| keyrig_core::camera_object::aim_rotation(eye, camera.target, Vec3::NEG_Z, 0.0))
        .unwrap_or(Quat::IDENTITY);
    (eye, rotation)
}

/// Adds `marker`, keeping the markers in frame order.
pub fn add_marker(scene: &mut Scene, marker: Marker) {
    let at = scene.markers.partition_point(|m| m.frame <= marker.frame);
    scene.markers.insert(at, marker);
}

#[cfg(test)]
mod tests {
    use super::*;
    use keyrig_core::{Marker, SceneCamera};

    fn scene() -> Scene {
        Scene {
            cameras: vec![SceneCamera::new("A", Vec3::Z), SceneCamera::new("B", Vec3::X)],
            active_camera: Some("B".into()),
            markers: vec![
                Marker { name: "one".into(), frame: 5, camera: Some("B".into()) },
                Marker { name: "two".into(), frame: 9, camera: Some("A".into()) },
            ],
            ..Scene::default()
        }
    }

    #[test]
    fn renaming_and_removing_keep_markers_valid() {
        let mut s = scene();
        rename_camera(&mut s, 1, "Close".into());
        assert_eq!(s.active_camera.as_deref(), Some("Close"));
        assert_eq!(s.markers[0].camera.as_deref(), Some("Close"));
        assert_eq!(s.problems(), Vec::new());
        remove_camera(&mut s, 1);
        assert_eq!(s.active_camera, None);
        assert_eq!(s.markers[0].camera, None);
        assert_eq!(s.markers[1].camera.as_deref(), Some("A"));
        assert_eq!(s.problems(), Vec::new());
    }

    #[test]
    fn aims_follow_renames_and_deletions() {
        let mut s = scene();
        s.objects.push(keyrig_core::Object::new("Arm"));
        s.cameras[0].aim = Some(keyrig_core::Aim::at(AimTarget::Object("Arm".into())));
        s.cameras[1].aim =
            Some(keyrig_core::Aim::at(AimTarget::Joint { object: "Arm".into(), joint: "hand".into() }));
        rename_aim_targets(&mut s, "Arm", Some("hand"), "wrist");
        rename_aim_targets(&mut s, "Arm", None, "Leg");
        assert_eq!(s.cameras[0].aim.as_ref().unwrap().target, AimTarget::Object("Leg".into()));
        assert_eq!(
            s.cameras[1].aim.as_ref().unwrap().target,
            AimTarget::Joint { object: "Leg".into(), joint: "wrist".into() }
        );
        forget_aim_targets(&mut s, "Leg");
        assert!(s.cameras.iter().all(|c| c.aim.is_none()));
    }

    #[test]
    fn the_view_as_a_camera_sees_what_the_view_sees() {
        let view = Camera {
            target: Vec3::new(1.0, 0.5, 0.0),
            yaw_deg: 30.0,
            pitch_deg: 20.0,
            distance: 6.0,
            fov_y_deg: 45.0,
        };
        let (eye, rotation) = view_as_camera(&view);
        let state = keyrig_eval::CameraState {
            world_from_camera: glam::Affine3A::from_rotation_translation(rotation, eye),
            lens: keyrig_core::Lens::Perspective { fov_y: 45f32.to_radians() },
            near: 0.1,
            far: Some(100.0),
            visible: true,
        };
        // The same view matrix as the orbit camera's (keyrig-render's look-at).
        let orbit = keyrig_render::camera::view_from_world(&view);
        assert!(state.view_from_world().abs_diff_eq(orbit, 1e-4), "{} vs {orbit}", state.view_from_world());
    }
}
