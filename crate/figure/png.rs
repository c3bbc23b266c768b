use std::path::Path;

use image::{ImageEncoder, RgbImage};

use super::FigureError;
use crate::data::write_atomic;

/// `width × height × 3` RGB bytes as a PNG file's bytes.
pub fn encode_png(rgb: &[u8], width: u32, height: u32) -> Result<Vec<u8>, FigureError> {
    let mut out = Vec::new();
    image::codecs::png::PngEncoder::new(&mut out)
        .write_image(rgb, width, height, image::ExtendedColorType::Rgb8)
        .map_err(|e| FigureError::Draw(format!("cannot encode a {width}x{height} PNG: {e}")))?;
    Ok(out)
}

/// Writes `image` as a PNG at `path`, atomically (temporary file, then rename).
pub fn save_png(path: &Path, image: &RgbImage) -> Result<(), FigureError> {
    let bytes = encode_png(image.as_raw(), image.width(), image.height())?;
    write_atomic(path, &bytes).map_err(|e| FigureError::Write {
        path: path.to_path_buf(),
        reason: e.to_string(),
    })
}
