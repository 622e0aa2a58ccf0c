//! Cumulative Probability of Blur Detection (Narvekar & Karam, IEEE TIP
//! 20(9), 2011), following the authors' MATLAB code (`CPBD_compute.m`, IVU
//! Lab, October 2009; embedded in NTIA's NRMetricFramework as
//! `reports/nrff_cpbd.m`).
//!
//! Unlike JNBM, the edge maps and widths are computed **once on the whole
//! image** and then gathered per 64x64 block:
//!
//! - **Edge blocks**: MATLAB `edge(I, 'canny')` on the whole image
//!   ([`super::matlab_edge::canny`]); a whole 64x64 block is an edge block
//!   when more than 0.2 % of its pixels are Canny edges. (The code's
//!   `threshold = 0.002` is this share, not a Sobel threshold.)
//! - **Edge pixels**: MATLAB `edge(I, 'Sobel', [2], 'vertical')`: a *fixed*
//!   threshold of 2 on the gradient magnitude `|bx|` (Sobel / 8, i.e. grey
//!   levels per pixel on the 0..255 scale: `cutoff = 2^2` on `bx^2`), with
//!   MATLAB's thinning ([`super::matlab_edge::sobel_vertical`]). An ideal
//!   step has `|bx| = height / 2` beside it, so a step of 4 grey levels or
//!   less gives no edge pixel at all.
//! - **Widths**: Marziliano walk along whole image rows ([`super::edges`]);
//!   the angle rule is the CPBD code's: rounded angle 0 rising, rounded 180
//!   *or* -180 falling (unlike JNBM's), zero horizontal central difference
//!   counts as angle 0 ([`super::edges::AngleRule::Cpbd`]).
//! - For every width `w` at an edge pixel of an edge block of contrast
//!   `C = max - min`, `P_BLUR = 1 - exp(-|w / w_JNB|^beta)`, `beta = 3.6`,
//!   with `w_JNB = 5` when `floor(C) <= 50` and `3` otherwise (the code's
//!   table `[5 x 51, 3 x 205]` indexed by `C + 1`; the JNBM code uses 59, see
//!   [`super::jnbm::w_jnb`]). The probabilities go into 101 bins
//!   `round(100 P_BLUR)` (half away from zero) and
//!
//!   `CPBD = share of edges with round(100 P_BLUR) <= 63`,
//!
//!   i.e. `P(P_BLUR <= P_JNB = 63 %)`. 0 (blurred) .. 1 (sharp). With no
//!   measured edge at all the code returns 0, and so do we.
//!
//! Where we must guess: MATLAB's Canny (current release, not the 2009 one;
//! see [`super::matlab_edge`]), which only decides the edge blocks; the grey
//! conversion as in [`super::jnbm`](mod@super::jnbm).
//!
//! [`cpbd_2d`] is the direction-aware variant: the same fixed-threshold
//! Sobel map and widths computed on the transposed image as well
//! (horizontal edges walked down the columns), both sets of widths pooled in
//! the same histogram. The original cannot see blur along the columns.

use super::blocks::check_blocks;
use super::blocks::BLOCK;
use super::edges::{edge_widths, is_edge_block, transpose, AngleRule, Axes};
use super::matlab_edge::{canny, sobel_vertical};
use crate::error::Result;
use image::GrayImage;

/// Shape parameter of the psychometric function.
pub const BETA: f64 = 3.6;
/// The fixed Sobel threshold of the authors' CPBD code (gradient magnitude,
/// grey levels per pixel).
pub const SOBEL_THRESHOLD: f64 = 2.0;

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

/// Whole-image maps the CPBD code works on.
pub(crate) struct CpbdData {
    w: usize,
    a: Vec<f64>,
    canny: Vec<bool>,
    /// Width map along rows (vertical edges).
    rows: Vec<u32>,
    /// Width map along columns (horizontal edges), in image coordinates;
    /// empty unless [`Axes::Both`] was asked for.
    cols: Vec<u32>,
}

impl CpbdData {
    pub(crate) fn new(img: &GrayImage, axes: Axes) -> Self {
        let (w, h) = (img.width() as usize, img.height() as usize);
        let a = super::blocks::to_f64(img);
        let canny = canny(&a, w, h);
        let e = sobel_vertical(&a, w, h, Some(SOBEL_THRESHOLD));
        let rows = edge_widths(&a, w, h, &e, AngleRule::Cpbd);
        let cols = if axes == Axes::Both {
            let t = transpose(&a, w, h);
            let e = sobel_vertical(&t, h, w, Some(SOBEL_THRESHOLD));
            transpose(&edge_widths(&t, h, w, &e, AngleRule::Cpbd), h, w)
        } else {
            Vec::new()
        };
        CpbdData {
            w,
            a,
            canny,
            rows,
            cols,
        }
    }
}

/// CPBD from the whole-image maps, pooling the widths of `axes`.
pub(crate) fn cpbd_from(d: &CpbdData, nbx: u32, nby: u32, axes: Axes) -> f64 {
    let n = BLOCK as usize;
    let (mut total, mut below) = (0usize, 0usize);
    for by in 0..nby as usize {
        for bx in 0..nbx as usize {
            // row ranges of the block in the row-major maps
            let rows = (by * n..by * n + n).map(|y| y * d.w + bx * n..y * d.w + bx * n + n);
            let mut cn = 0;
            let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
            for r in rows.clone() {
                cn += d.canny[r.clone()].iter().filter(|&&e| e).count();
                for &v in &d.a[r] {
                    lo = lo.min(v);
                    hi = hi.max(v);
                }
            }
            if !is_edge_block(cn, n * n) {
                continue;
            }
            let wj = w_jnb_cpbd(hi - lo);
            let mut count = |wi: u32| {
                if wi > 0 {
                    total += 1;
                    if (p_blur(wi as f64, wj) * 100.0).round() <= 63.0 {
                        below += 1;
                    }
                }
            };
            for r in rows {
                d.rows[r.clone()].iter().for_each(|&wi| count(wi));
                if axes == Axes::Both {
                    d.cols[r].iter().for_each(|&wi| count(wi));
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

fn run(img: &GrayImage, axes: Axes) -> Result<f64> {
    let (nbx, nby) = check_blocks("CPBD", img)?;
    Ok(cpbd_from(&CpbdData::new(img, axes), nbx, nby, axes))
}

/// CPBD following the authors' code, 0..1. Errors when the image has no
/// whole 64x64 block.
pub fn cpbd(img: &GrayImage) -> Result<f64> {
    run(img, Axes::Rows)
}

/// Direction-aware CPBD (widths along rows and columns), 0..1; see the
/// module docs.
pub fn cpbd_2d(img: &GrayImage) -> Result<f64> {
    run(img, Axes::Both)
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
        assert_eq!(cpbd_2d(&img).unwrap(), 1.0);
        let flat = GrayImage::from_pixel(64, 64, Luma([3]));
        assert_eq!(cpbd(&flat).unwrap(), 0.0);
        assert_eq!(cpbd_2d(&flat).unwrap(), 0.0);
    }

    #[test]
    fn contrast_rule_follows_authors_code() {
        assert_eq!(w_jnb_cpbd(50.9), 5.0);
        assert_eq!(w_jnb_cpbd(51.0), 3.0);
    }
}
