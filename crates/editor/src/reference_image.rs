//! Choosing the reference image shown behind the scene (View ▸ Reference image…, or an image
//! file dropped on the window): the file is read first, so that one keyrig cannot read is
//! refused with its error in the status bar and the scene is left as it was; otherwise it
//! becomes the scene's [`keyrig_core::ReferenceImage`] (its opacity kept when one is
//! replaced), one undo step. The viewport draws it (`panels::viewport`); the scene file names
//! it relative to its folder, as models ([`keyrig_io::project::save_scene`]).

use std::path::Path;

use keyrig_core::ReferenceImage;

use crate::app::EditorApp;

impl EditorApp {
    /// Shows the image at `path` behind the scene; one undo step.
    pub fn set_reference_image(&mut self, path: &Path) {
        let image = match keyrig_io::reference_image::load_reference_image(path) {
            Ok(image) => image,
            Err(e) => {
                self.error(e.to_string());
                return;
            }
        };
        // In memory the path is absolute, as model paths are: saving makes it relative.
        let absolute = std::path::absolute(path).unwrap_or_else(|_| path.to_path_buf());
        let name =
            path.file_name().map_or_else(|| path.display().to_string(), |n| n.to_string_lossy().into_owned());
        let opacity = self
            .doc
            .scene()
            .reference_image
            .as_ref()
            .map_or_else(keyrig_core::pose_library::default_opacity, |r| r.opacity);
        let reference = ReferenceImage { path: absolute.to_string_lossy().into_owned(), opacity };
        self.doc.edit(&format!("reference image {name}"), |scene| scene.reference_image = Some(reference));
        self.info(format!(
            "Reference image {name} ({}×{} pixels) behind the scene at opacity {opacity:.2}",
            image.width(),
            image.height()
        ));
    }
}
