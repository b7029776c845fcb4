//! The PNG preview: sRGB, scaled by an exposure.

use super::atomic::{stage, Staged};
use crate::error::OutputError;
use crate::film::Film;
use std::path::Path;

fn srgb(linear: f32) -> u8 {
    let c = linear.max(0.0);
    let s = if c <= 0.003_130_8 {
        12.92 * c
    } else {
        1.055 * c.powf(1.0 / 2.4) - 0.055
    };
    (s.clamp(0.0, 1.0) * 255.0 + 0.5) as u8
}

/// A PNG of AOV `k` in sRGB, scaled by 2^`exposure`.
pub fn write_png(path: &Path, film: &Film, k: usize, exposure: f32) -> Result<(), OutputError> {
    stage_png(path, film, k, exposure)?.commit()
}

/// [`write_png`] up to the rename: the file written and synced beside `path`.
pub fn stage_png(path: &Path, film: &Film, k: usize, exposure: f32) -> Result<Staged, OutputError> {
    let rgb = [film.channel(k, 0), film.channel(k, 1), film.channel(k, 2)];
    stage_png_rgb(path, film.width, film.height, &rgb, exposure)
}

/// A PNG of three linear planes in sRGB, scaled by 2^`exposure`.
pub fn write_png_rgb(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[Vec<f32>; 3],
    exposure: f32,
) -> Result<(), OutputError> {
    stage_png_rgb(path, width, height, rgb, exposure)?.commit()
}

/// [`write_png_rgb`] up to the rename.
pub fn stage_png_rgb(
    path: &Path,
    width: u32,
    height: u32,
    rgb: &[Vec<f32>; 3],
    exposure: f32,
) -> Result<Staged, OutputError> {
    let scale = 2f32.powf(exposure);
    let mut bytes = Vec::with_capacity(rgb[0].len() * 3);
    for ((r, g), b) in rgb[0].iter().zip(&rgb[1]).zip(&rgb[2]) {
        bytes.extend_from_slice(&[srgb(r * scale), srgb(g * scale), srgb(b * scale)]);
    }
    stage(path, |file| {
        let mut out = std::io::BufWriter::new(file);
        image::write_buffer_with_format(
            &mut out,
            &bytes,
            width,
            height,
            image::ColorType::Rgb8,
            image::ImageFormat::Png,
        )
        .map_err(|e| OutputError::Encode {
            path: path.to_path_buf(),
            reason: e.to_string(),
        })?;
        std::io::Write::flush(&mut out).map_err(|source| OutputError::Write {
            path: path.to_path_buf(),
            source,
        })
    })
}
