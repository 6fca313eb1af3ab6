//! The editor's camera and marker commands: look through a camera, set a camera to the view,
//! add a camera, add or remove a marker, bind a camera to a marker
//! ([`crate::camera_edits`] holds the scene edits they share with renaming and deleting).

use keyrig_core::{Marker, SceneCamera};

use crate::app::{unique_name, EditorApp};
use crate::camera_edits::{add_marker, view_as_camera};
use crate::channels::{ChannelId, ChannelValue};
use crate::session::Selected;

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
                .filter(|&c| c < scene.cameras.len())
                .or_else(|| scene.active_camera_at(self.session.playback.frame)),
        }
    }

    /// Looks through the selected (else the active) scene camera, or back through the orbit
    /// camera when already looking through one.
    pub fn toggle_look_through(&mut self) {
        if self.view.look_through.take().is_some() {
            self.info("Looking through the view again");
            return;
        }
        match self.command_camera() {
            Some(c) => {
                self.view.look_through = Some(c);
                let name = self.doc.scene().cameras[c].name.clone();
                self.info(format!("Looking through {name} (0 or orbiting leaves it)"));
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
