//! Staple commands on the editor: hide the selected objects in the viewport and show every
//! hidden one again (H, Alt+H; [`crate::hidden`] says what hiding means); turn the preview
//! range on or off (Ctrl+Alt+P; [`crate::widgets::preview_range`]); add an item from the Add
//! menu ([`keyrig_edit::scene_add`]).

use crate::app::{unique_name, EditorApp};
use crate::session::Selected;
use keyrig_edit::scene_add::{AddKind, Added};

impl EditorApp {
    /// H: hides the selected objects (a joint, its object) in the viewport and deselects them.
    pub fn hide_selected(&mut self) {
        let scene = self.doc.scene();
        let mut objects: Vec<usize> = self
            .session
            .selection
            .items()
            .filter_map(|item| match item {
                Selected::Object(o) | Selected::Joint { object: o, .. } => Some(o),
                Selected::Light(_) | Selected::Camera(_) => None,
            })
            .filter(|&o| o < scene.objects.len())
            .collect();
        objects.sort_unstable();
        objects.dedup();
        if objects.is_empty() {
            self.info("Hide: select an object or joint to hide (Alt+H shows hidden objects)");
            return;
        }
        let names: Vec<String> = objects.iter().map(|&o| scene.objects[o].name.clone()).collect();
        for name in &names {
            self.session.hidden.hide(name);
        }
        self.session.selection.select_only(None);
        self.info(format!("Hid {} in the viewport (Alt+H shows it again)", names.join(", ")));
    }

    /// Alt+H: shows every hidden object again.
    pub fn show_hidden(&mut self) {
        let shown = self.session.hidden.show_all(self.doc.scene());
        if shown == 0 {
            self.info("Nothing is hidden");
        } else {
            self.info(format!("Showed {shown} hidden object(s)"));
        }
    }

    /// Ctrl+Alt+P: sets the preview range (over the selected keys, else from the current frame
    /// to the range's end) or clears it; one undo step either way.
    pub fn toggle_preview_range(&mut self) {
        let scene = self.doc.scene();
        if let Some(p) = scene.preview_range {
            self.doc.edit("clear preview range", |s| s.preview_range = None);
            self.info(format!(
                "Preview range {}–{} cleared: playback runs over the frame range",
                p.start, p.end
            ));
            return;
        }
        let fps = scene.fps.max(1e-9);
        // The selected keys are ordered by channel: each channel's times are read once.
        let mut frames = Vec::new();
        let mut times: Option<(keyrig_edit::channels::ChannelId, Vec<f64>)> = None;
        for k in &self.session.selection.keys {
            if times.as_ref().is_none_or(|(c, _)| *c != k.channel) {
                times = Some((k.channel, keyrig_edit::channels::key_times(scene, k.channel)));
            }
            if let Some(t) = times.as_ref().and_then(|(_, t)| t.get(k.index)) {
                frames.push((t * fps).round() as i32);
            }
        }
        let preview = crate::widgets::preview_range::initial_preview(
            scene,
            &frames,
            self.session.playback.whole_frame(),
        );
        self.doc.edit(&format!("preview range {}–{}", preview.start, preview.end), |s| {
            s.preview_range = Some(preview);
        });
        let frame = self.session.playback.whole_frame();
        if frame < preview.start || frame > preview.end {
            self.set_frame(preview.start);
        }
        self.info(format!(
            "Preview range {}–{}: playback, Home and End keep to it (Ctrl+Alt+P clears it)",
            preview.start, preview.end
        ));
    }

    /// Adds what the Add menu's `kind` adds where the view looks, as one undo step, and selects
    /// it.
    pub fn add_item(&mut self, kind: AddKind) {
        if kind == AddKind::Camera {
            self.add_camera();
            return;
        }
        let scene = self.doc.scene();
        let base = kind.base_name();
        let taken: Vec<&str> = if kind.is_light() {
            scene.lights.iter().map(|l| l.name.as_str()).collect()
        } else {
            scene.objects.iter().map(|o| o.name.as_str()).collect()
        };
        let name = if taken.contains(&base) { unique_name(base, taken.into_iter()) } else { base.to_owned() };
        let Some(added) = keyrig_edit::scene_add::build(kind, name.clone(), self.view.camera.target) else {
            return;
        };
        let label = format!("add {} {name}", kind.label().to_lowercase());
        let selected = match added {
            Added::Object(object) => {
                let o = scene.objects.len();
                self.doc.edit(&label, move |s| s.objects.push(*object));
                Selected::Object(o)
            }
            Added::Light(light) => {
                let l = scene.lights.len();
                self.doc.edit(&label, move |s| s.lights.push(light));
                Selected::Light(l)
            }
        };
        self.session.selection.select_only(Some(selected));
        self.session.selection.keys.clear();
        self.info(format!("Added {name}"));
    }
}
