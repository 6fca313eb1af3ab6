//! The pose library: named poses saved with the scene ([`keyrig_core::NamedPose`], by channel
//! path), added from the selection at the current frame, applied to the selection (as keys in
//! record mode, as the pose shown otherwise), optionally mirrored across each character's
//! symmetry plane — the mirrored paste's one path ([`EditorApp::apply_pose_values`],
//! [`keyrig_edit::mirror`]) — renamed and deleted; each one undo step. The inspector's Pose library
//! section drives it (`panels::inspector::pose_library`).

use keyrig_core::channel::ChannelPath;
use keyrig_core::{NamedPose, PoseValue};

use crate::actions::PoseLibraryAction;
use crate::app::EditorApp;
use keyrig_edit::channels::{ChannelId, ChannelValue};

/// The pose's values that find their channel in `scene` (by name), and how many did not.
#[must_use]
pub fn resolve(scene: &keyrig_core::Scene, pose: &NamedPose) -> (Vec<(ChannelId, ChannelValue)>, usize) {
    let mut found = Vec::new();
    let mut missing = 0;
    for v in &pose.values {
        match ChannelPath::parse(&v.channel).and_then(|path| path.id(scene)) {
            Ok(id) => found.push((id, v.value)),
            Err(_) => missing += 1,
        }
    }
    (found, missing)
}

impl EditorApp {
    /// Runs one pose-library action.
    pub fn pose_library(&mut self, action: PoseLibraryAction) {
        match action {
            PoseLibraryAction::Add(name) => self.add_library_pose(&name),
            PoseLibraryAction::Apply { index, mirrored } => self.apply_library_pose(index, mirrored),
            PoseLibraryAction::Rename { index, name } => self.rename_library_pose(index, &name),
            PoseLibraryAction::Delete(index) => self.delete_library_pose(index),
        }
    }

    /// Saves the pose of the selection at the current frame (the channels Copy pose copies) as
    /// a named pose of the library; one undo step.
    pub fn add_library_pose(&mut self, name: &str) {
        let scene = self.doc.scene();
        let values: Vec<PoseValue> = self
            .pose_channels()
            .into_iter()
            .filter_map(|(id, value)| {
                Some(PoseValue { channel: ChannelPath::of(scene, id)?.to_string(), value })
            })
            .collect();
        if values.is_empty() {
            self.info("Pose library: select joints or a character first");
            return;
        }
        let base = match name.trim() {
            "" => "Pose",
            name => name,
        };
        if base.contains('/') {
            self.error(format!("Pose library: a pose name cannot contain '/' ({base:?})"));
            return;
        }
        let taken = |n: &str| scene.poses.iter().any(|p| p.name == n);
        let name = (1..)
            .map(|i| if i == 1 { base.to_owned() } else { format!("{base} {i}") })
            .find(|n| !taken(n))
            .unwrap_or_else(|| base.to_owned());
        let count = values.len();
        let pose = NamedPose { name: name.clone(), values };
        self.doc.edit(&format!("add pose {name} to the library"), |scene| scene.poses.push(pose));
        self.info(format!("Pose library: saved \"{name}\" ({count} channel(s))"));
    }

    /// Applies library pose `index` to the selection at the current frame, mirrored or not;
    /// one undo step. Channels of the pose that the scene no longer has are counted and left
    /// out.
    pub fn apply_library_pose(&mut self, index: usize, mirrored: bool) {
        let scene = self.doc.scene();
        let Some(pose) = scene.poses.get(index) else { return };
        let name = pose.name.clone();
        let (values, missing) = resolve(scene, pose);
        let selected = self.session.selection.key_channels(scene);
        if selected.is_empty() {
            self.info(format!("Apply pose \"{name}\": select joints or a character first"));
            return;
        }
        let what =
            if mirrored { format!("apply pose {name} mirrored") } else { format!("apply pose {name}") };
        let (count, report) = self.apply_pose_values(&values, mirrored, &what, Some(&selected));
        let missing = if missing > 0 {
            format!(" ({missing} channel(s) of the pose are not in this scene)")
        } else {
            String::new()
        };
        match report {
            Some(report) => {
                self.info(format!("Applied \"{name}\" mirrored on {count} channel(s){missing}. {report}"));
            }
            None => self.info(format!("Applied \"{name}\" on {count} channel(s){missing}")),
        }
    }

    /// Renames library pose `index` (names are not empty, have no '/' and are unique); one undo
    /// step.
    pub fn rename_library_pose(&mut self, index: usize, name: &str) {
        let name = name.trim();
        let scene = self.doc.scene();
        let Some(old) = scene.poses.get(index).map(|p| p.name.clone()) else { return };
        if name.is_empty() || name.contains('/') {
            self.error(format!("Rename pose {old}: type a name without '/' in the field first"));
            return;
        }
        if scene.poses.iter().enumerate().any(|(i, p)| i != index && p.name == name) {
            self.error(format!("Rename pose {old}: a pose named {name} exists"));
            return;
        }
        let new = name.to_owned();
        self.doc.edit(&format!("rename pose {old} to {new}"), |scene| scene.poses[index].name = new.clone());
        self.info(format!("Renamed pose {old} to {new}"));
    }

    /// Deletes library pose `index`; one undo step.
    pub fn delete_library_pose(&mut self, index: usize) {
        let Some(name) = self.doc.scene().poses.get(index).map(|p| p.name.clone()) else { return };
        self.doc.edit(&format!("delete pose {name}"), |scene| {
            scene.poses.remove(index);
        });
        self.info(format!("Deleted pose {name}"));
    }
}
