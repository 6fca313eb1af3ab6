//! What a mesh looks like: a base colour and, optionally, a base-colour texture with the way it
//! is sampled (glTF 2.0's `pbrMetallicRoughness.baseColorFactor` / `baseColorTexture` and
//! `sampler`; an MD2 model's skin). Pure data: keyrig-io decodes images into it, keyrig-render
//! uploads it.

use std::sync::Arc;

/// How texture coordinates outside 0..=1 are mapped (glTF `wrapS` / `wrapT`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum WrapMode {
    /// glTF 33071.
    ClampToEdge,
    /// glTF 33648.
    MirroredRepeat,
    /// glTF 10497, the glTF default.
    #[default]
    Repeat,
}

/// Nearest or linear filtering (glTF `magFilter`, and each half of `minFilter`).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
pub enum FilterMode {
    Nearest,
    #[default]
    Linear,
}

/// How a texture is sampled. glTF leaves filters to the implementation when a sampler omits
/// them; keyrig then uses linear filtering with linear mipmaps (the `Default`).
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub struct Sampler {
    /// Along u (glTF s).
    pub wrap_u: WrapMode,
    /// Along v (glTF t).
    pub wrap_v: WrapMode,
    pub mag_filter: FilterMode,
    pub min_filter: FilterMode,
    /// Filtering between mip levels; `None`: no mipmaps (glTF `NEAREST` / `LINEAR` min filters).
    pub mipmap_filter: Option<FilterMode>,
}

impl Default for Sampler {
    fn default() -> Self {
        Sampler {
            wrap_u: WrapMode::Repeat,
            wrap_v: WrapMode::Repeat,
            mag_filter: FilterMode::Linear,
            min_filter: FilterMode::Linear,
            mipmap_filter: Some(FilterMode::Linear),
        }
    }
}

/// A decoded texture image: RGBA8 pixels, sRGB-encoded colour (as PNG and JPEG store them),
/// rows top to bottom, so texture coordinate (0, 0) is the first pixel (glTF's and MD2's
/// convention).
///
/// # Invariants
/// `width` and `height` are at least 1 and `rgba.len() == 4 · width · height`; checked by
/// [`TextureImage::new`].
#[derive(Clone, Debug, PartialEq)]
pub struct TextureImage {
    width: u32,
    height: u32,
    rgba: Arc<[u8]>,
    pub sampler: Sampler,
}

/// Why a [`TextureImage`] cannot be made.
#[derive(Clone, Debug, PartialEq, Eq, thiserror::Error)]
pub enum TextureError {
    #[error("a texture of {width}×{height} pixels has no pixels")]
    Empty { width: u32, height: u32 },
    #[error("{len} bytes of RGBA for {width}×{height} pixels (expected {expected})")]
    Length { width: u32, height: u32, len: usize, expected: u64 },
}

impl TextureImage {
    /// A texture of `width` × `height` RGBA8 pixels.
    ///
    /// # Errors
    /// A zero size, or a pixel buffer of the wrong length.
    pub fn new(
        width: u32,
        height: u32,
        rgba: impl Into<Arc<[u8]>>,
        sampler: Sampler,
    ) -> Result<Self, TextureError> {
        let rgba = rgba.into();
        if width == 0 || height == 0 {
            return Err(TextureError::Empty { width, height });
        }
        let expected = 4 * u64::from(width) * u64::from(height);
        if rgba.len() as u64 != expected {
            return Err(TextureError::Length { width, height, len: rgba.len(), expected });
        }
        Ok(TextureImage { width, height, rgba, sampler })
    }

    #[must_use]
    pub fn width(&self) -> u32 {
        self.width
    }

    #[must_use]
    pub fn height(&self) -> u32 {
        self.height
    }

    /// RGBA8, sRGB-encoded, row-major from the top row.
    #[must_use]
    pub fn rgba(&self) -> &[u8] {
        &self.rgba
    }
}

/// A mesh's look: colour = `base_colour` × the texture's colour at the vertex's texture
/// coordinate (white without a texture), as glTF's base colour is defined.
#[derive(Clone, Debug, PartialEq)]
pub struct Material {
    /// Linear RGBA (glTF `baseColorFactor`; alpha is kept but keyrig draws opaque).
    pub base_colour: [f32; 4],
    pub base_colour_texture: Option<Arc<TextureImage>>,
}

impl Default for Material {
    fn default() -> Self {
        Material { base_colour: [1.0; 4], base_colour_texture: None }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn texture_sizes_are_checked() {
        assert!(TextureImage::new(2, 1, vec![0u8; 8], Sampler::default()).is_ok());
        assert_eq!(
            TextureImage::new(0, 1, Vec::<u8>::new(), Sampler::default()),
            Err(TextureError::Empty { width: 0, height: 1 })
        );
        assert!(matches!(
            TextureImage::new(2, 2, vec![0u8; 8], Sampler::default()),
            Err(TextureError::Length { expected: 16, len: 8, .. })
        ));
    }
}
