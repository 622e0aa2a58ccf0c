//! No-reference image blur metrics on grey images.
//!
//! All metrics work on an 8-bit grey image ([`image::GrayImage`], values
//! 0..255). Colour images are reduced to grey with [`luma`]: the integer
//! Rec. 601 luma of the *sRGB-encoded* 8-bit values (no linearisation, as
//! MATLAB's `rgb2gray` and OpenCV do, which is what the metrics were designed
//! and tuned on): `Y = (299 R + 587 G + 114 B + 500) div 1000`. Grey files are
//! used as they are (16-bit grey is scaled to 8 bits).
//!
//! - [`jnbm()`]: Just Noticeable Blur Metric (Ferzli & Karam 2009) as the
//!   authors' `JNBM_compute.m` computes it (block-local edge maps); higher = sharper.
//! - [`cpbd()`]: Cumulative Probability of Blur Detection (Narvekar & Karam 2011)
//!   as the authors' `CPBD_compute.m` computes it, 0 (blurred) .. 1 (sharp).
//! - [`jnbm_2d()`], [`cpbd_2d()`]: direction-aware variants that measure edge
//!   widths along rows *and* columns (the originals only see horizontal widths,
//!   so they are blind to vertical smear).
//! - `whole_image`: the earlier whole-image approximation of JNBM and CPBD,
//!   kept for comparison.
//! - [`blur_effect()`]: Crete et al. 2007 blur effect exactly as scikit-image's
//!   `skimage.measure.blur_effect` (0 sharp .. 1 blurred).
//! - [`laplacian_var()`]: variance of the 4-neighbour Laplacian (higher = sharper).
//! - [`tenengrad()`]: mean squared Sobel gradient magnitude (higher = sharper).
//!
//! [`assess`] computes all six; JNBM is `None` when it is undefined (no edge
//! block with a measured width, see [`jnbm()`]).

pub(crate) mod blocks;
pub(crate) mod blur_effect;
pub(crate) mod cpbd;
pub mod edges;
pub(crate) mod jnbm;
pub(crate) mod laplacian;
pub mod matlab_edge;
pub(crate) mod tenengrad;
pub(crate) mod whole_image;

use blocks::check_blocks;
pub use blocks::BLOCK;
pub use blur_effect::{blur_effect, blur_effect_axes};
pub use cpbd::{cpbd, cpbd_2d};
pub use jnbm::{jnbm, jnbm_2d, jnbm_2d_report, jnbm_report, JnbmReport};
pub use laplacian::laplacian_var;
pub use tenengrad::tenengrad;
pub use whole_image::{cpbd_whole_image, jnbm_whole_image, jnbm_whole_image_report};

use crate::error::{Error, Result};
use image::{DynamicImage, GrayImage, RgbImage};
use serde::Serialize;
use std::path::Path;

pub use crate::limits::MAX_ASSESS_PIXELS;

/// Integer Rec. 601 luma of an 8-bit sRGB image:
/// `Y = (299 R + 587 G + 114 B + 500) div 1000` (rounded half up, exact).
pub fn luma(img: &RgbImage) -> GrayImage {
    let mut out = GrayImage::new(img.width(), img.height());
    for (o, p) in out.pixels_mut().zip(img.pixels()) {
        let [r, g, b] = p.0;
        let y = (299 * r as u32 + 587 * g as u32 + 114 * b as u32 + 500) / 1000;
        o.0[0] = y as u8;
    }
    out
}

/// Grey version of a decoded image: grey formats as they are (16-bit scaled
/// to 8), colour through [`luma`]; alpha is ignored.
pub fn to_grey(img: &DynamicImage) -> GrayImage {
    match img {
        DynamicImage::ImageLuma8(g) => g.clone(),
        DynamicImage::ImageLuma16(_)
        | DynamicImage::ImageLumaA8(_)
        | DynamicImage::ImageLumaA16(_) => img.to_luma8(),
        _ => luma(&img.to_rgb8()),
    }
}

/// Reads a PNG/JPEG (format guessed from the content) as a grey image,
/// naming the file in errors. An image that declares more than
/// [`MAX_ASSESS_PIXELS`] in its header is refused before it is decoded (the
/// metrics' working memory, about 64 bytes per pixel, stays bounded).
pub fn load_grey(path: &Path) -> Result<GrayImage> {
    let (w, h) = crate::io::input::image_dimensions(path)?;
    if w as u64 * h as u64 > MAX_ASSESS_PIXELS {
        return Err(Error::Image {
            path: path.into(),
            message: format!(
                "the header declares {w} x {h} pixels; assess takes at most {MAX_ASSESS_PIXELS} \
                 (its working memory is about 64 bytes per pixel)"
            ),
        });
    }
    Ok(to_grey(&crate::io::images::decode(path)?))
}

/// The metrics of one image.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Assessment {
    /// JNBM (authors' code; higher = sharper); `None` when undefined (no
    /// edge block with a measured width).
    pub jnbm: Option<f64>,
    /// CPBD (authors' code), 0 (blurred) .. 1 (sharp).
    pub cpbd: f64,
    /// Direction-aware JNBM (widths along rows and columns); `None` when undefined.
    pub jnbm_2d: Option<f64>,
    /// Direction-aware CPBD (widths along rows and columns), 0 .. 1.
    pub cpbd_2d: f64,
    /// Crete et al. blur effect, 0 (sharp) .. 1 (blurred).
    pub blur_effect: f64,
    /// Variance of the 4-neighbour Laplacian, (grey levels)^2.
    pub laplacian_var: f64,
}

/// All metrics (edge maps shared between each metric and its `_2d`
/// variant). Errors when the image is smaller than one 64x64 block (JNBM and
/// CPBD need at least one whole block).
pub fn assess(img: &GrayImage) -> Result<Assessment> {
    use edges::Axes;
    let (nbx, nby) = check_blocks("image", img)?;
    let blocks = jnbm::blocks(img, nbx, nby, Axes::Both);
    let cp = cpbd::CpbdData::new(img, Axes::Both);
    Ok(Assessment {
        jnbm: jnbm::report_from(&blocks, Axes::Rows).jnbm,
        cpbd: cpbd::cpbd_from(&cp, nbx, nby, Axes::Rows),
        jnbm_2d: jnbm::report_from(&blocks, Axes::Both).jnbm,
        cpbd_2d: cpbd::cpbd_from(&cp, nbx, nby, Axes::Both),
        blur_effect: blur_effect(img)?,
        laplacian_var: laplacian_var(img)?,
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn luma_weights_and_rounding() {
        let img = RgbImage::from_raw(3, 1, vec![255, 255, 255, 255, 0, 0, 10, 20, 30]).unwrap();
        let g = luma(&img);
        assert_eq!(g.as_raw(), &vec![255, 76, 18]); // 76.245; 18.15 (2990+11740+3420)/1000
    }

    #[test]
    fn small_image_is_rejected() {
        let g = GrayImage::new(63, 200);
        let e = assess(&g).unwrap_err().to_string();
        assert!(e.contains("64x64"), "{e}");
    }
}
