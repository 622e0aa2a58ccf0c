//! The 64x64 blocks JNBM and CPBD measure in, and the grey values they read.

use crate::error::{Error, Result};
use image::GrayImage;

/// Side of the square blocks used by JNBM and CPBD, pixels.
pub const BLOCK: u32 = 64;

/// Checks that an image holds at least one whole `BLOCK x BLOCK` block.
pub(crate) fn check_blocks(what: &str, img: &GrayImage) -> Result<(u32, u32)> {
    let (bx, by) = (img.width() / BLOCK, img.height() / BLOCK);
    if bx == 0 || by == 0 {
        return Err(Error::invalid(
            what,
            format!(
                "image is {}x{} px; at least one whole {BLOCK}x{BLOCK} block is needed",
                img.width(),
                img.height()
            ),
        ));
    }
    Ok((bx, by))
}

/// Grey values as `f64` (0..255), row-major.
pub(crate) fn to_f64(img: &GrayImage) -> Vec<f64> {
    img.as_raw().iter().map(|&v| v as f64).collect()
}
