//! Scene edits for cameras that keep the scene valid: markers and the active camera follow a
//! renamed or deleted camera, aims follow a renamed object or joint and are dropped with a
//! deleted object; a camera's projection switched with its lens converted.

use keyrig_core::{AimTarget, Marker, Scene};

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

/// Adds `marker`, keeping the markers in frame order.
pub fn add_marker(scene: &mut Scene, marker: Marker) {
    let at = scene.markers.partition_point(|m| m.frame <= marker.frame);
    scene.markers.insert(at, marker);
}

/// Switches a camera to `projection`, converting its lens value and keys so that the view
/// stays as it was where the two can express it (field of view ↔ focal length); an
/// orthographic view height is set from the view's height at distance 5.
pub fn convert_lens(camera: &mut keyrig_core::SceneCamera, projection: keyrig_core::Projection) {
    use keyrig_core::camera_object::{focal_length_from_fov_y, fov_y_from_focal_length};
    use keyrig_core::Projection;
    let fov_of = |old: Projection, v: f32| match old {
        Projection::Perspective => v.to_radians(),
        Projection::FocalLength { sensor_height_mm } => fov_y_from_focal_length(v, sensor_height_mm),
        Projection::Orthographic => 2.0 * (v / 10.0).atan(),
    };
    let old = camera.projection;
    let convert = |v: f32| {
        let fov = fov_of(old, v);
        match projection {
            Projection::Perspective => fov.to_degrees(),
            Projection::FocalLength { sensor_height_mm } => focal_length_from_fov_y(fov, sensor_height_mm),
            Projection::Orthographic => 10.0 * (fov * 0.5).tan(),
        }
    };
    camera.lens.value = convert(camera.lens.value);
    for key in camera.lens.track.keys.iter_mut() {
        key.value = convert(key.value);
        key.in_tangent = None;
        key.out_tangent = None;
        if key.interpolation == keyrig_core::Interpolation::Hermite {
            key.interpolation = keyrig_core::Interpolation::Tcb;
        }
    }
    if projection == Projection::Orthographic && camera.far.is_none() {
        camera.far = Some(1000.0);
    }
    camera.projection = projection;
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
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
    fn converting_the_lens_keeps_the_view() {
        let mut camera = keyrig_core::SceneCamera::new("C", glam::Vec3::Z);
        camera.lens.value = 2.0 * (12f32 / 50.0).atan().to_degrees();
        convert_lens(&mut camera, keyrig_core::Projection::FocalLength { sensor_height_mm: 24.0 });
        assert!((camera.lens.value - 50.0).abs() < 1e-3, "{}", camera.lens.value);
        convert_lens(&mut camera, keyrig_core::Projection::Perspective);
        assert!((camera.lens.value - 26.991_466).abs() < 1e-3);
        camera.far = None;
        convert_lens(&mut camera, keyrig_core::Projection::Orthographic);
        assert_eq!(camera.far, Some(1000.0));
        let scene = keyrig_core::Scene { cameras: vec![camera], ..keyrig_core::Scene::default() };
        assert_eq!(scene.problems(), Vec::new());
    }
}
