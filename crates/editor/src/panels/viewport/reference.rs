//! The reference image behind the scene ([`keyrig_core::ReferenceImage`]): read once per file
//! with keyrig-io ([`keyrig_io::reference_image`]) into an egui texture, fitted inside the
//! viewport (its whole picture shown, centred, its aspect kept) and drawn at its opacity before
//! the scene: under the painter's meshes, or under the GPU image, which is then rendered with a
//! transparent background and blended over it. A file that cannot be read is an error over
//! the viewport (in red, as every error of the viewport), never a panic; the scene is drawn as
//! without one.

use std::path::PathBuf;

use egui::{Color32, Rect, TextureHandle};

use crate::context::FrameCtx;

/// The loaded image: the file it came from and its texture, or why it could not be read.
#[derive(Default)]
pub struct ReferenceView {
    loaded: Option<(PathBuf, Result<TextureHandle, String>)>,
}

impl ReferenceView {
    /// The shape that draws the scene's reference image fitted into `rect` (loading it when its
    /// file changed); `None` without one or when it cannot be read (the error goes to `errors`).
    pub(super) fn shape(
        &mut self,
        ui: &egui::Ui,
        ctx: &FrameCtx<'_>,
        rect: Rect,
        errors: &mut Vec<String>,
    ) -> Option<egui::Shape> {
        let Some(image) = &ctx.scene().reference_image else {
            self.loaded = None;
            return None;
        };
        let file = match ctx.base_dir() {
            Some(dir) => dir.join(&image.path),
            None => PathBuf::from(&image.path),
        };
        if self.loaded.as_ref().is_none_or(|(loaded, _)| *loaded != file) {
            let texture = keyrig_io::reference_image::load_reference_image(&file)
                .map(|pixels| {
                    let size = [pixels.width() as usize, pixels.height() as usize];
                    let colour = egui::ColorImage::from_rgba_unmultiplied(size, pixels.rgba());
                    ui.ctx().load_texture("reference image", colour, egui::TextureOptions::LINEAR)
                })
                .map_err(|e| e.to_string());
            self.loaded = Some((file, texture));
        }
        match &self.loaded.as_ref()?.1 {
            Ok(texture) => {
                let size = texture.size_vec2();
                let scale = (rect.width() / size.x).min(rect.height() / size.y);
                let shown = Rect::from_center_size(rect.center(), size * scale);
                let tint = Color32::WHITE.gamma_multiply(image.opacity.clamp(0.0, 1.0));
                let uv = Rect::from_min_max(egui::pos2(0.0, 0.0), egui::pos2(1.0, 1.0));
                Some(egui::Shape::image(texture.id(), shown, uv, tint))
            }
            Err(e) => {
                errors.push(e.clone());
                None
            }
        }
    }

    /// The size in pixels of the image shown, when one is loaded.
    #[must_use]
    pub fn size(&self) -> Option<[usize; 2]> {
        match &self.loaded {
            Some((_, Ok(texture))) => Some(texture.size()),
            _ => None,
        }
    }
}
