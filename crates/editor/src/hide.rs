//! The hide commands (H, Alt+H) on the editor: hide the selected objects in the viewport, show
//! every hidden one again ([`crate::hidden`] says what hiding means).

use crate::app::EditorApp;
use crate::session::Selected;

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
}
