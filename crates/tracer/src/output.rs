//! Writing images: 8-bit sRGB PNG and linear float OpenEXR, chosen by file extension.

use crate::{Error, Result};
use std::path::Path;

/// Image formats the renderer writes.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum ImageFormat {
    /// 8-bit sRGB-encoded PNG (values clamped to [0, 1]).
    Png,
    /// 32-bit float linear-sRGB OpenEXR.
    Exr,
}

impl ImageFormat {
    /// The format a path's extension names.
    pub fn from_path(path: &Path) -> Result<Self> {
        match path.extension().and_then(|e| e.to_str()).map(str::to_ascii_lowercase).as_deref() {
            Some("png") => Ok(Self::Png),
            Some("exr") => Ok(Self::Exr),
            other => Err(Error::Setting(format!(
                "{}: unsupported image extension {:?} (use .png or .exr)",
                path.display(),
                other.unwrap_or("")
            ))),
        }
    }
}

/// Writes a linear-sRGB float image (row-major RGB) to `path`, as PNG or EXR by extension.
pub fn write_image(path: &Path, width: u32, height: u32, rgb: &[f32]) -> Result<()> {
    let err = |e: image::ImageError| Error::Image { path: path.to_path_buf(), message: e.to_string() };
    match ImageFormat::from_path(path)? {
        ImageFormat::Png => {
            let bytes: Vec<u8> = rgb.iter().map(|&v| spectral::srgb_to_u8(v)).collect();
            image::RgbImage::from_raw(width, height, bytes)
                .ok_or_else(|| Error::Setting("image buffer size mismatch".into()))?
                .save(path)
                .map_err(err)
        }
        ImageFormat::Exr => image::Rgb32FImage::from_raw(width, height, rgb.to_vec())
            .ok_or_else(|| Error::Setting("image buffer size mismatch".into()))?
            .save(path)
            .map_err(err),
    }
}

/// Reads an EXR (or any float image the `image` crate knows) as linear RGB floats.
pub fn read_rgb32f(path: &Path) -> Result<(u32, u32, Vec<f32>)> {
    let img = image::open(path).map_err(|e| Error::Image { path: path.to_path_buf(), message: e.to_string() })?;
    let rgb = img.into_rgb32f();
    Ok((rgb.width(), rgb.height(), rgb.into_raw()))
}
