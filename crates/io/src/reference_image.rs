//! The reference image a scene names ([`keyrig_core::ReferenceImage`]): read with the `image`
//! crate (PNG, JPEG, BMP) into RGBA, refused with an error that names the file and what is wrong
//! — unreadable, not an image keyrig reads, or larger than [`MAX_SIDE`] pixels on a side.

use std::io::Cursor;
use std::path::{Path, PathBuf};
use std::sync::Arc;

use keyrig_core::{Sampler, TextureImage};

/// The largest file read as a reference image.
pub const MAX_REFERENCE_IMAGE_BYTES: u64 = 256 << 20;

/// The largest side of a reference image, pixels (a GPU texture's usual limit).
pub const MAX_SIDE: u32 = 8192;

/// Why a reference image cannot be shown.
#[derive(Debug, thiserror::Error)]
pub enum ReferenceImageError {
    #[error("reference image {}: cannot read: {source}", path.display())]
    Read { path: PathBuf, source: std::io::Error },
    #[error("reference image {}: not a PNG, JPEG or BMP image keyrig can read: {reason}", path.display())]
    Decode { path: PathBuf, reason: String },
}

/// Reads the reference image at `path` as RGBA pixels.
///
/// # Errors
/// [`ReferenceImageError`] naming the file: it cannot be read, or it is not an image of a
/// format keyrig reads, or it is larger than [`MAX_SIDE`] on a side.
pub fn load_reference_image(path: &Path) -> Result<TextureImage, ReferenceImageError> {
    let bytes = crate::file_io::read_regular_file(path, MAX_REFERENCE_IMAGE_BYTES)
        .map_err(|source| ReferenceImageError::Read { path: path.to_path_buf(), source })?;
    let decode_error = |reason: String| ReferenceImageError::Decode { path: path.to_path_buf(), reason };
    let mut reader = image::ImageReader::new(Cursor::new(bytes))
        .with_guessed_format()
        .map_err(|e| decode_error(e.to_string()))?;
    let mut limits = image::Limits::default();
    limits.max_image_width = Some(MAX_SIDE);
    limits.max_image_height = Some(MAX_SIDE);
    reader.limits(limits);
    let rgba = reader.decode().map_err(|e| decode_error(e.to_string()))?.to_rgba8();
    let (width, height) = rgba.dimensions();
    TextureImage::new(width, height, Arc::<[u8]>::from(rgba.into_raw()), Sampler::default())
        .map_err(|e| decode_error(e.to_string()))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_png_reads_and_bad_files_say_what_is_wrong() {
        let dir = tempfile::tempdir().expect("temp dir");
        let png = dir.path().join("ref.png");
        image::RgbaImage::from_pixel(3, 2, image::Rgba([10, 20, 30, 255])).save(&png).expect("write png");
        let image = load_reference_image(&png).expect("a PNG reads");
        assert_eq!((image.width(), image.height()), (3, 2));
        assert_eq!(&image.rgba()[..4], &[10, 20, 30, 255]);

        let junk = dir.path().join("junk.png");
        std::fs::write(&junk, b"not an image at all").expect("write");
        let e = load_reference_image(&junk).expect_err("junk is refused").to_string();
        assert!(e.contains("junk.png") && e.contains("not a PNG, JPEG or BMP"), "{e}");

        let missing = dir.path().join("missing.png");
        let e = load_reference_image(&missing).expect_err("a missing file is refused").to_string();
        assert!(e.contains("missing.png") && e.contains("cannot read"), "{e}");
    }
}
