//! Cumulative Probability of Blur Detection (Narvekar & Karam, IEEE TIP
//! 20(9), 2011), following the authors' published code.
//!
//! Same blocks, edge blocks, Canny/Sobel maps and Marziliano widths as JNBM
//! ([`super::edges`], [`super::jnbm`]). For every width `w` in an edge block
//! of contrast `C`, the probability of blur detection is
//! `P_BLUR = 1 - exp(-|w / w_JNB|^beta)`, `beta = 3.6`, with `w_JNB = 5` when
//! `floor(C) <= 50` and `3` otherwise (the CPBD code's table
//! `[5 x 51, 3 x 205]`, indexed by the integer contrast; the JNBM code uses
//! 59, see [`super::jnbm::w_jnb`]). The probabilities are put in 101 bins
//! `round(100 P_BLUR)` (half away from zero) and
//!
//! `CPBD = share of edges with round(100 P_BLUR) <= 63`,
//!
//! i.e. the cumulative probability `P(P_BLUR <= P_JNB = 63 %)`. 0 (blurred) ..
//! 1 (sharp). With no measured edge at all the authors' code returns 0, and
//! so do we.

use super::check_blocks;
use super::edges::EdgeData;
use crate::error::Result;
use image::GrayImage;

/// Shape parameter of the psychometric function.
pub const BETA: f64 = 3.6;

/// `w_JNB` of the CPBD code for a block of contrast `c`: 5 if `floor(c) <= 50`, else 3.
pub fn w_jnb_cpbd(c: f64) -> f64 {
    if c.floor() <= 50.0 {
        5.0
    } else {
        3.0
    }
}

/// Probability of blur detection of one edge of width `w` px.
pub fn p_blur(w: f64, w_jnb: f64) -> f64 {
    1.0 - (-(w / w_jnb).abs().powf(BETA)).exp()
}

/// CPBD of a grey image, 0..1. Errors when the image has no whole 64x64 block.
pub fn cpbd(img: &GrayImage) -> Result<f64> {
    let (nbx, nby) = check_blocks("CPBD", img)?;
    Ok(cpbd_from(&EdgeData::new(img), nbx, nby))
}

/// CPBD from precomputed edge data and block counts.
pub(crate) fn cpbd_from(ed: &EdgeData, nbx: u32, nby: u32) -> f64 {
    let (mut total, mut below) = (0usize, 0usize);
    for by in 0..nby {
        for bx in 0..nbx {
            if !ed.is_edge_block(bx, by) {
                continue;
            }
            let wj = w_jnb_cpbd(ed.contrast(bx, by));
            for w in ed.block_widths(bx, by) {
                total += 1;
                if (p_blur(w, wj) * 100.0).round() <= 63.0 {
                    below += 1;
                }
            }
        }
    }
    if total == 0 {
        0.0
    } else {
        below as f64 / total as f64
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Luma;

    #[test]
    fn p_blur_at_jnb_width_is_63_percent() {
        assert!((p_blur(5.0, 5.0) - (1.0 - (-1.0f64).exp())).abs() < 1e-15);
        assert!(((p_blur(3.0, 3.0) * 100.0).round() - 63.0).abs() < 1e-12);
    }

    #[test]
    fn sharp_step_is_one_flat_is_zero() {
        let img = GrayImage::from_fn(64, 64, |x, _| Luma([if x >= 32 { 220 } else { 20 }]));
        assert_eq!(cpbd(&img).unwrap(), 1.0);
        let flat = GrayImage::from_pixel(64, 64, Luma([3]));
        assert_eq!(cpbd(&flat).unwrap(), 0.0);
    }
}
