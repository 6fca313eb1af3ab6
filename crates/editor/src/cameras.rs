//! The editor's camera and marker commands: look through a camera, set a camera to the view,
//! add a camera, add or remove a marker, bind a camera to a marker
//! ([`keyrig_edit::camera_edits`] holds the scene edits they share with renaming and deleting).

use glam::{Quat, Vec3};
use keyrig_core::{Camera, Marker, SceneCamera};

use crate::app::{unique_name, EditorApp};
use crate::session::Selected;
use crate::view::LookThrough;
use keyrig_edit::camera_edits::add_marker;
use keyrig_edit::channels::{ChannelId, ChannelValue};

impl EditorApp {
    /// The camera the camera commands act on: the selected one, else the one looked through,
    /// else the active one at the current frame.
    fn command_camera(&self) -> Option<usize> {
        let scene = self.doc.scene();
        match self.session.selection.item {
            Some(Selected::Camera(c)) if c < scene.cameras.len() => Some(c),
            _ => self
                .view
                .look_through
                .and_then(|l| l.camera_at(scene, self.session.playback.frame))
                .or_else(|| scene.active_camera_at(self.session.playback.frame)),
        }
    }

    /// Looks through the selected scene camera, else through the active camera (which markers
    /// switch as the playhead passes them, as in Blender), or back through the orbit camera
    /// when already looking through one.
    pub fn toggle_look_through(&mut self) {
        if self.view.look_through.take().is_some() {
            self.info("Looking through the view again");
            return;
        }
        let scene = self.doc.scene();
        let frame = self.session.playback.frame;
        let choice = match self.session.selection.item {
            Some(Selected::Camera(c)) if c < scene.cameras.len() => Some(LookThrough::Camera(c)),
            _ => scene.active_camera_at(frame).map(|_| LookThrough::Active),
        };
        match choice {
            Some(choice) => {
                self.view.look_through = Some(choice);
                let name =
                    choice.camera_at(scene, frame).map(|c| scene.cameras[c].name.clone()).unwrap_or_default();
                let how = match choice {
                    LookThrough::Active => "the active camera; markers cut between cameras",
                    LookThrough::Camera(_) => "0 or orbiting leaves it",
                };
                self.info(format!("Looking through {name} ({how})"));
            }
            None => self.info("Look through camera: the scene has no camera (Ctrl+Shift+C adds one)"),
        }
    }

    /// Puts the command's camera where the view is, as a pose change: keys in record mode.
    pub fn camera_to_view(&mut self) {
        let Some(c) = self.command_camera() else {
            self.info("Set camera to view: the scene has no camera (Ctrl+Shift+C adds one)");
            return;
        };
        let (eye, rotation) = view_as_camera(&self.view.camera);
        let group = format!("camera to view {c}");
        self.apply_pose(ChannelId::CameraTranslation(c), ChannelValue::Vec3(eye), &group);
        if self.doc.scene().cameras[c].aim.is_none() {
            self.apply_pose(ChannelId::CameraRotation(c), ChannelValue::Rotation(rotation), &group);
        }
        self.doc.close_group();
        let name = self.doc.scene().cameras[c].name.clone();
        self.info(format!("{name} set to the view"));
    }

    /// Adds a perspective camera where the view is, with the view's field of view, and selects
    /// it.
    pub fn add_camera(&mut self) {
        let scene = self.doc.scene();
        let name = if scene.camera_index("Camera").is_some() {
            unique_name("Camera", scene.cameras.iter().map(|c| c.name.as_str()))
        } else {
            "Camera".to_owned()
        };
        let (eye, rotation) = view_as_camera(&self.view.camera);
        let mut camera = SceneCamera::new(name.clone(), eye);
        camera.rotation.value = rotation;
        camera.lens.value = self.view.camera.fov_y_deg;
        let index = scene.cameras.len();
        self.doc.edit(&format!("add camera {name}"), |scene| scene.cameras.push(camera));
        self.session.selection.select_only(Some(Selected::Camera(index)));
        self.session.selection.keys.clear();
        self.info(format!("Added {name}"));
    }

    /// Adds a marker at the current frame, or removes the one there.
    pub fn toggle_marker(&mut self) {
        let frame = self.session.playback.whole_frame();
        let scene = self.doc.scene();
        if let Some(m) = scene.markers.iter().position(|m| m.frame == frame) {
            let name = scene.markers[m].name.clone();
            self.doc.edit(&format!("remove marker {name}"), |scene| {
                scene.markers.remove(m);
            });
            self.info(format!("Removed marker {name} at frame {frame}"));
        } else {
            let name = format!("F_{frame:02}");
            let marker = Marker { name: name.clone(), frame, camera: None };
            self.doc.edit(&format!("add marker {name}"), |scene| add_marker(scene, marker));
            self.info(format!("Added marker {name} at frame {frame}"));
        }
    }

    /// Binds the selected camera to the marker at the current frame (adding one), so that it
    /// becomes the active camera there.
    pub fn bind_camera_to_marker(&mut self) {
        let Some(Selected::Camera(c)) = self.session.selection.item else {
            self.info("Bind camera to marker: select a camera first");
            return;
        };
        let frame = self.session.playback.whole_frame();
        let Some(camera) = self.doc.scene().cameras.get(c).map(|x| x.name.clone()) else { return };
        let label = format!("bind {camera} to frame {frame}");
        let bound = camera.clone();
        self.doc.edit(&label, move |scene| match scene.markers.iter_mut().find(|m| m.frame == frame) {
            Some(marker) => marker.camera = Some(bound),
            None => add_marker(scene, Marker { name: bound.clone(), frame, camera: Some(bound) }),
        });
        self.info(format!("{camera} is the active camera from frame {frame}"));
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

#[cfg(test)]
mod tests {
    use super::*;
    use glam::Vec3;
    use keyrig_core::Camera;

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
