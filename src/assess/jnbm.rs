//! Just Noticeable Blur Metric (Ferzli & Karam, IEEE TIP 18(4), 2009).
//!
//! On the grey image (0..255): the image is cut into whole 64x64 blocks
//! (a partial last row/column of pixels is ignored). A block is an *edge
//! block* when more than 0.2 % of its pixels are Canny edges (thresholds in
//! [`super::edges`]). In an edge block with contrast `C = max - min` the just
//! noticeable width is `w_JNB = 5` when `floor(C) <= 59` and `3` otherwise.
//! The paper states `C <= 50`; the authors' published JNBM code uses 59 and we
//! follow the code. Each Marziliano edge width `w_i` measured at a vertical
//! Sobel edge pixel of the block gives the block distortion
//! `D_b = (sum_i |w_i / w_JNB|^beta)^(1/beta)`, `beta = 3.6`, and
//!
//! `JNBM = L / (sum_b D_b^beta)^(1/beta)`
//!
//! with `L` the number of whole blocks in the image (edge blocks or not), as in
//! the authors' code. Higher = sharper. A sharp step edge has width 2, so a
//! single sharp edge in a one-block image gives `JNBM = 1.5` (w_JNB = 3).
//!
//! When the total distortion is 0 (no edge block, or edge blocks without any
//! measured width, e.g. a flat image) the formula would give +infinity; we
//! report the metric as undefined instead: [`jnbm`] returns an error and
//! [`jnbm_report`] a `None` value (never NaN or infinity).

use super::check_blocks;
use super::edges::EdgeData;
use crate::error::{Error, Result};
use image::GrayImage;
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

/// JNBM with counts. Errors only when the image has no whole 64x64 block.
pub fn jnbm_report(img: &GrayImage) -> Result<JnbmReport> {
    let (nbx, nby) = check_blocks("JNBM", img)?;
    Ok(report_from(&EdgeData::new(img), nbx, nby))
}

/// JNBM from precomputed edge data and block counts.
pub(crate) fn report_from(ed: &EdgeData, nbx: u32, nby: u32) -> JnbmReport {
    let mut total = 0.0;
    let (mut edge_blocks, mut edges, mut wsum) = (0usize, 0usize, 0.0);
    for by in 0..nby {
        for bx in 0..nbx {
            if !ed.is_edge_block(bx, by) {
                continue;
            }
            edge_blocks += 1;
            let wj = w_jnb(ed.contrast(bx, by));
            let mut s = 0.0;
            for wi in ed.block_widths(bx, by) {
                s += (wi / wj).abs().powf(BETA);
                edges += 1;
                wsum += wi;
            }
            // D_b^beta = s
            total += s;
        }
    }
    let blocks = (nbx * nby) as usize;
    let distortion = total.powf(1.0 / BETA);
    let jnbm = (distortion > 0.0).then(|| blocks as f64 / distortion);
    JnbmReport {
        jnbm,
        blocks,
        edge_blocks,
        edges,
        mean_width: if edges > 0 { wsum / edges as f64 } else { 0.0 },
    }
}

/// JNBM (higher = sharper). Errors when the image has no whole 64x64 block or
/// no measurable edge in an edge block (the metric is then undefined).
pub fn jnbm(img: &GrayImage) -> Result<f64> {
    jnbm_report(img)?.jnbm.ok_or_else(|| {
        Error::invalid(
            "JNBM",
            "undefined: the image has no edge block with a measurable edge (flat image?)",
        )
    })
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
        let d = (62.0 * (2.0f64 / 3.0).powf(BETA)).powf(1.0 / BETA);
        assert!((r.jnbm.unwrap() - 1.0 / d).abs() < 1e-12);
    }

    #[test]
    fn flat_image_is_undefined_not_nan() {
        let img = GrayImage::from_pixel(128, 64, Luma([90]));
        let r = jnbm_report(&img).unwrap();
        assert_eq!(r.jnbm, None);
        assert_eq!(r.blocks, 2);
        assert!(jnbm(&img).unwrap_err().to_string().contains("undefined"));
    }
}
