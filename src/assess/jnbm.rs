//! Just Noticeable Blur Metric (Ferzli & Karam, IEEE TIP 18(4), 2009),
//! following the authors' MATLAB code (`JNBM_compute.m`, IVU Lab, 2009; the
//! same file is embedded in NTIA's NRMetricFramework as
//! `reports/nrff_jnb.m`).
//!
//! The grey image (0..255) is cut into whole 64x64 blocks (a partial last row
//! or column of pixels is ignored). **Everything below is computed on the
//! block's own 64x64 sub-image**, as the code does, not on the whole image:
//!
//! - **Edge block**: MATLAB `edge(block, 'canny')` with automatic thresholds
//!   chosen from the block's own gradients ([`super::matlab_edge::canny`]);
//!   an edge block has more than 0.2 % Canny pixels (at least 9 of 4096).
//! - **Edge pixels**: MATLAB `edge(block, 'sobel', [], 'vertical')`: the
//!   automatic cutoff `4 mean(bx^2)` is the *block's* mean, and thinning
//!   follows MATLAB ([`super::matlab_edge::sobel_vertical`]).
//! - **Widths**: Marziliano walk along the block's rows ([`super::edges`]):
//!   a walk stops at the block border, so an edge that crosses a block border
//!   is measured as two shorter edges, one in each block; block-border pixels
//!   (rows/columns 1 and 64) are never measured. The angle rule is the
//!   code's: rounded angle 0 is a rising edge; a falling edge is measured
//!   when the rounded angle is 180 or the *unrounded* angle is -180, which
//!   in practice means only falling edges whose brightness does not decrease
//!   down the column ([`super::edges::AngleRule::Jnbm`]); pixels with a
//!   zero horizontal central difference count as angle 0.
//! - **Contrast** `C = max - min` of the block; `w_JNB = 5` when
//!   `floor(C) <= 59` and `3` otherwise (the code's table
//!   `widthjnb(C + 1)`; the paper says `C <= 50`).
//! - Block distortion `D_b = (sum_i |w_i / w_JNB|^beta)^(1/beta)`,
//!   `beta = 3.6`, and
//!
//!   `JNBM = L / (sum_b D_b^beta)^(1/beta)`
//!
//!   with `L` the number of whole blocks in the image (edge blocks or not).
//!   Higher = sharper. A single sharp edge (width 2) in a one-block image
//!   gives `JNBM = 1.5 / 62^(1/3.6)` (62 measured rows, `w_JNB = 3`).
//!
//! Where we differ from or must guess about the code:
//!
//! - With no edge block at all the code fails (`temp` is never assigned);
//!   with edge blocks but no width it returns +infinity. We report the metric
//!   as undefined in both cases: [`jnbm`] returns an error and
//!   [`jnbm_report`] a `None` value (never NaN or infinity).
//! - MATLAB's Canny: we emulate the current (R2011a and later) `edge`, not
//!   the 2009 one; see [`super::matlab_edge`]. This can move a block in or
//!   out of the set of edge blocks, never change a width.
//! - Grey input: our luma ([`super::luma`]) instead of MATLAB's `rgb2gray`
//!   weights (0.2989, 0.5870, 0.1140); on 8-bit values the two differ by at
//!   most one grey level.
//!
//! [`jnbm_2d`] is the direction-aware variant: the original only measures
//! widths along rows, at vertical edges, so it cannot see blur along the
//! columns (vertical smear leaves it unchanged). `jnbm_2d` also runs the
//! same Sobel/width measurement on the transposed block (horizontal edges,
//! walked down the columns, same angle rule with the axes swapped) and pools
//! both sets of widths in the same `D_b` and `JNBM` formulas; blocks, Canny
//! decision and contrast are unchanged. JNBM sums distortion over edges
//! (it is not an average), so pooling more widths can only lower it:
//! `jnbm_2d <= jnbm` on every image. Compare `jnbm_2d` values with each
//! other, not with `jnbm`.

use super::blocks::check_blocks;
use super::blocks::BLOCK;
use super::edges::{edge_widths, is_edge_block, transpose, AngleRule, Axes};
use super::matlab_edge::{canny, sobel_vertical};
use crate::error::{Error, Result};
use image::GrayImage;
use rayon::prelude::*;
use serde::Serialize;

/// Shape parameter of the psychometric function.
pub const BETA: f64 = 3.6;

/// `w_JNB` for a block of contrast `c` (grey levels): 5 if `floor(c) <= 59`, else 3.
pub fn w_jnb(c: f64) -> f64 {
    if c.floor() <= 59.0 {
        5.0
    } else {
        3.0
    }
}

/// JNBM with its intermediate counts.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct JnbmReport {
    /// The metric; `None` when the total distortion is 0 (see the module docs).
    pub jnbm: Option<f64>,
    /// Whole 64x64 blocks in the image (`L`).
    pub blocks: usize,
    /// Edge blocks among them.
    pub edge_blocks: usize,
    /// Edge widths measured in the edge blocks.
    pub edges: usize,
    /// Mean of those widths, px (0 when none).
    pub mean_width: f64,
}

/// One 64x64 block as the authors' code sees it.
pub(crate) struct Block {
    /// More than 0.2 % Canny pixels (block-local Canny).
    edge: bool,
    /// `max - min`, grey levels.
    contrast: f64,
    /// Non-zero widths along rows (vertical edges); empty unless `edge`.
    rows: Vec<u32>,
    /// Non-zero widths along columns (horizontal edges); empty unless `edge`
    /// and [`Axes::Both`] was asked for.
    cols: Vec<u32>,
}

fn nonzero(w: Vec<u32>) -> Vec<u32> {
    w.into_iter().filter(|&v| v > 0).collect()
}

/// Block-local edge data of one block (`a`: its 64x64 grey values).
fn block(a: &[f64], axes: Axes) -> Block {
    let n = BLOCK as usize;
    let (lo, hi) = a
        .iter()
        .fold((f64::INFINITY, f64::NEG_INFINITY), |(l, h), &v| {
            (l.min(v), h.max(v))
        });
    let cn = canny(a, n, n).iter().filter(|&&e| e).count();
    let edge = is_edge_block(cn, n * n);
    let (mut rows, mut cols) = (Vec::new(), Vec::new());
    if edge {
        let e = sobel_vertical(a, n, n, None);
        rows = nonzero(edge_widths(a, n, n, &e, AngleRule::Jnbm));
        if axes == Axes::Both {
            let t = transpose(a, n, n);
            let e = sobel_vertical(&t, n, n, None);
            cols = nonzero(edge_widths(&t, n, n, &e, AngleRule::Jnbm));
        }
    }
    Block {
        edge,
        contrast: hi - lo,
        rows,
        cols,
    }
}

/// All whole blocks of `img`, row-major by block, with their edge data.
pub(crate) fn blocks(img: &GrayImage, nbx: u32, nby: u32, axes: Axes) -> Vec<Block> {
    let a = super::blocks::to_f64(img);
    let w = img.width() as usize;
    let n = BLOCK as usize;
    (0..nbx * nby)
        .into_par_iter()
        .map(|k| {
            let (x0, y0) = ((k % nbx) as usize * n, (k / nbx) as usize * n);
            let mut sub = Vec::with_capacity(n * n);
            for y in y0..y0 + n {
                sub.extend_from_slice(&a[y * w + x0..y * w + x0 + n]);
            }
            block(&sub, axes)
        })
        .collect()
}

/// JNBM from block data, pooling the widths of `axes`.
pub(crate) fn report_from(blocks: &[Block], axes: Axes) -> JnbmReport {
    let mut total = 0.0;
    let (mut edge_blocks, mut edges, mut wsum) = (0usize, 0usize, 0.0);
    for b in blocks.iter().filter(|b| b.edge) {
        edge_blocks += 1;
        let wj = w_jnb(b.contrast);
        let cols: &[u32] = if axes == Axes::Both { &b.cols } else { &[] };
        let mut s = 0.0;
        for &wi in b.rows.iter().chain(cols) {
            let wi = wi as f64;
            s += (wi / wj).abs().powf(BETA);
            edges += 1;
            wsum += wi;
        }
        // D_b, then D_b^beta, as the code does
        let d = s.powf(1.0 / BETA);
        total += d.powf(BETA);
    }
    let n = blocks.len();
    let distortion = total.powf(1.0 / BETA);
    let jnbm = (distortion > 0.0).then(|| n as f64 / distortion);
    JnbmReport {
        jnbm,
        blocks: n,
        edge_blocks,
        edges,
        mean_width: if edges > 0 { wsum / edges as f64 } else { 0.0 },
    }
}

fn report(img: &GrayImage, axes: Axes) -> Result<JnbmReport> {
    let (nbx, nby) = check_blocks("JNBM", img)?;
    Ok(report_from(&blocks(img, nbx, nby, axes), axes))
}

fn defined(r: JnbmReport) -> Result<f64> {
    r.jnbm.ok_or_else(|| {
        Error::invalid(
            "JNBM",
            "undefined: the image has no edge block with a measurable edge (flat image?)",
        )
    })
}

/// JNBM (authors' code) with counts. Errors only when the image has no whole
/// 64x64 block.
pub fn jnbm_report(img: &GrayImage) -> Result<JnbmReport> {
    report(img, Axes::Rows)
}

/// JNBM following the authors' code (higher = sharper). Errors when the
/// image has no whole 64x64 block or no measurable edge in an edge block
/// (the metric is then undefined).
pub fn jnbm(img: &GrayImage) -> Result<f64> {
    defined(jnbm_report(img)?)
}

/// Direction-aware JNBM with counts (widths along rows and columns).
pub fn jnbm_2d_report(img: &GrayImage) -> Result<JnbmReport> {
    report(img, Axes::Both)
}

/// Direction-aware JNBM: the authors' JNBM with the widths of horizontal
/// edges (walked along columns) pooled in as well; see the module docs.
pub fn jnbm_2d(img: &GrayImage) -> Result<f64> {
    defined(jnbm_2d_report(img)?)
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Luma;

    #[test]
    fn contrast_rule_follows_authors_code() {
        assert_eq!(w_jnb(0.0), 5.0);
        assert_eq!(w_jnb(59.9), 5.0);
        assert_eq!(w_jnb(60.0), 3.0);
        assert_eq!(w_jnb(255.0), 3.0);
    }

    #[test]
    fn single_step_edge_block() {
        // one 64x64 block, vertical step 20 -> 220 at x = 31|32: widths are all 2,
        // w_JNB = 3; rows 1..62 measured (62 edges): D = (62 (2/3)^3.6)^(1/3.6)
        let img = GrayImage::from_fn(64, 64, |x, _| Luma([if x >= 32 { 220 } else { 20 }]));
        let r = jnbm_report(&img).unwrap();
        assert_eq!(r.blocks, 1);
        assert_eq!(r.edge_blocks, 1);
        assert_eq!(r.edges, 62);
        assert_eq!(r.mean_width, 2.0);
        let d = (62.0 * (2.0f64 / 3.0).powf(BETA)).powf(1.0 / BETA);
        assert!((r.jnbm.unwrap() - 1.0 / d).abs() < 1e-12);
        // the 2d variant sees no horizontal edge here
        assert_eq!(jnbm_2d_report(&img).unwrap(), r);
    }

    #[test]
    fn flat_image_is_undefined_not_nan() {
        let img = GrayImage::from_pixel(128, 64, Luma([90]));
        let r = jnbm_report(&img).unwrap();
        assert_eq!(r.jnbm, None);
        assert_eq!(r.blocks, 2);
        assert_eq!(r.edge_blocks, 0);
        assert!(jnbm(&img).unwrap_err().to_string().contains("undefined"));
        assert!(jnbm_2d(&img).is_err());
    }
}
