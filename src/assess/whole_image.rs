//! The earlier "whole-image" approximation of JNBM and CPBD, kept for
//! comparison with the authors'-code versions ([`super::jnbm()`],
//! [`super::cpbd()`]), which replaced it as the default.
//!
//! Differences from the authors' code:
//!
//! - Canny ([`imageproc::edges::canny`]: Gaussian sigma 1.4, 3x3 Sobel
//!   gradients, 4-direction non-maximum suppression), the vertical Sobel map
//!   and the widths are computed **once over the whole image** and gathered
//!   per block, for JNBM too (the authors' JNBM works inside each block, so
//!   its walks stop at the block border and its Sobel cutoff is per block).
//!   Canny thresholds: MATLAB-like (70 % of the magnitudes below the high
//!   threshold, 64 equal bins over `[0, max]`, low = 0.4 high).
//! - Sobel: automatic cutoff `4 mean(bx^2)` for CPBD too (the authors' CPBD
//!   uses the fixed threshold 2); thinning keeps only horizontal maxima of
//!   `bx^2`, without MATLAB's `|bx| >= |by|` test and without its vertical
//!   maxima.
//! - Angle rule [`AngleRule::Symmetric`]: falling edges at both +-180,
//!   pixels with `Gx = 0` skipped.
//!
//! Formulas (`w_JNB`, `beta`, pooling) are those of
//! [`super::jnbm`](mod@super::jnbm) and [`super::cpbd`](mod@super::cpbd).

use super::blocks::check_blocks;
use super::cpbd::{p_blur, w_jnb_cpbd};
use super::edges::{edge_widths, is_edge_block, AngleRule};
use super::jnbm::{w_jnb, JnbmReport, BETA};
use crate::error::{Error, Result};
use image::GrayImage;
use imageproc::edges::canny;
use imageproc::filter::gaussian_blur_f32;
use imageproc::gradients::{horizontal_sobel, vertical_sobel};

/// Sigma of imageproc's Canny smoothing, px.
pub const CANNY_SIGMA: f32 = 1.4;

/// Automatic `(low, high)` Canny thresholds (imageproc magnitude scale).
/// `None` when the image is flat.
pub fn canny_thresholds(img: &GrayImage) -> Option<(f32, f32)> {
    let blurred = gaussian_blur_f32(img, CANNY_SIGMA);
    let gx = horizontal_sobel(&blurred);
    let gy = vertical_sobel(&blurred);
    let mag: Vec<f32> = gx
        .iter()
        .zip(gy.iter())
        .map(|(h, v)| (*h as f32).hypot(*v as f32))
        .collect();
    let max = mag.iter().copied().fold(0.0f32, f32::max);
    if max <= 0.0 {
        return None;
    }
    let mut hist = [0usize; 64];
    for &m in &mag {
        let b = ((m / max * 64.0) as usize).min(63);
        hist[b] += 1;
    }
    let limit = 0.7 * mag.len() as f64;
    let mut cum = 0usize;
    let mut bin = 63;
    for (k, &h) in hist.iter().enumerate() {
        cum += h;
        if cum as f64 > limit {
            bin = k;
            break;
        }
    }
    let high = (bin + 1) as f32 / 64.0 * max;
    Some((0.4 * high, high))
}

/// Canny edge map (true = edge), row-major, automatic thresholds.
pub fn canny_edges(img: &GrayImage) -> Vec<bool> {
    match canny_thresholds(img) {
        None => vec![false; (img.width() * img.height()) as usize],
        Some((lo, hi)) => canny(img, lo, hi).as_raw().iter().map(|&v| v > 0).collect(),
    }
}

/// Vertical Sobel edge map: `b = (Sobel_x / 8)^2 > 4 mean(b)` and a
/// horizontal local maximum of `b`.
pub fn sobel_vertical_edges(a: &[f64], w: usize, h: usize) -> Vec<bool> {
    let at = |x: isize, y: isize| -> f64 {
        let x = x.clamp(0, w as isize - 1) as usize;
        let y = y.clamp(0, h as isize - 1) as usize;
        a[y * w + x]
    };
    let mut b = vec![0.0; w * h];
    for y in 0..h as isize {
        for x in 0..w as isize {
            let gx = (at(x + 1, y - 1) + 2.0 * at(x + 1, y) + at(x + 1, y + 1))
                - (at(x - 1, y - 1) + 2.0 * at(x - 1, y) + at(x - 1, y + 1));
            let gx = gx / 8.0;
            b[y as usize * w + x as usize] = gx * gx;
        }
    }
    let cutoff = 4.0 * b.iter().sum::<f64>() / b.len() as f64;
    let mut e = vec![false; w * h];
    for y in 0..h {
        for x in 0..w {
            let v = b[y * w + x];
            let left = if x > 0 { b[y * w + x - 1] } else { v };
            let right = if x + 1 < w {
                b[y * w + x + 1]
            } else {
                f64::NEG_INFINITY
            };
            e[y * w + x] = v > cutoff && left <= v && v > right;
        }
    }
    e
}

/// Canny map, width map and grey values of the whole image.
struct EdgeData {
    w: usize,
    a: Vec<f64>,
    canny: Vec<bool>,
    widths: Vec<u32>,
}

impl EdgeData {
    fn new(img: &GrayImage) -> Self {
        let (w, h) = (img.width() as usize, img.height() as usize);
        let a = super::blocks::to_f64(img);
        let sobel = sobel_vertical_edges(&a, w, h);
        let widths = edge_widths(&a, w, h, &sobel, AngleRule::Symmetric);
        EdgeData {
            w,
            canny: canny_edges(img),
            a,
            widths,
        }
    }

    fn block(&self, bx: u32, by: u32) -> impl Iterator<Item = usize> + '_ {
        let b = super::blocks::BLOCK as usize;
        let (x0, y0) = (bx as usize * b, by as usize * b);
        (y0..y0 + b).flat_map(move |y| (x0..x0 + b).map(move |x| y * self.w + x))
    }

    fn is_edge_block(&self, bx: u32, by: u32) -> bool {
        let n = self.block(bx, by).filter(|&i| self.canny[i]).count();
        is_edge_block(n, (super::blocks::BLOCK * super::blocks::BLOCK) as usize)
    }

    fn contrast(&self, bx: u32, by: u32) -> f64 {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for i in self.block(bx, by) {
            lo = lo.min(self.a[i]);
            hi = hi.max(self.a[i]);
        }
        hi - lo
    }

    fn block_widths(&self, bx: u32, by: u32) -> impl Iterator<Item = f64> + '_ {
        self.block(bx, by)
            .map(|i| self.widths[i])
            .filter(|&v| v > 0)
            .map(|v| v as f64)
    }
}

/// Whole-image JNBM with its counts. Errors only when the image has no whole
/// 64x64 block.
pub fn jnbm_whole_image_report(img: &GrayImage) -> Result<JnbmReport> {
    let (nbx, nby) = check_blocks("JNBM", img)?;
    let ed = EdgeData::new(img);
    let mut total = 0.0;
    let (mut edge_blocks, mut edges, mut wsum) = (0usize, 0usize, 0.0);
    for by in 0..nby {
        for bx in 0..nbx {
            if !ed.is_edge_block(bx, by) {
                continue;
            }
            edge_blocks += 1;
            let wj = w_jnb(ed.contrast(bx, by));
            for wi in ed.block_widths(bx, by) {
                total += (wi / wj).abs().powf(BETA);
                edges += 1;
                wsum += wi;
            }
        }
    }
    let blocks = (nbx * nby) as usize;
    let distortion = total.powf(1.0 / BETA);
    Ok(JnbmReport {
        jnbm: (distortion > 0.0).then(|| blocks as f64 / distortion),
        blocks,
        edge_blocks,
        edges,
        mean_width: if edges > 0 { wsum / edges as f64 } else { 0.0 },
    })
}

/// Whole-image JNBM (the earlier approximation; see the module docs).
pub fn jnbm_whole_image(img: &GrayImage) -> Result<f64> {
    jnbm_whole_image_report(img)?
        .jnbm
        .ok_or_else(|| Error::invalid("JNBM", "undefined: no measurable edge in an edge block"))
}

/// Whole-image CPBD (the earlier approximation; see the module docs).
pub fn cpbd_whole_image(img: &GrayImage) -> Result<f64> {
    let (nbx, nby) = check_blocks("CPBD", img)?;
    let ed = EdgeData::new(img);
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
    Ok(if total == 0 {
        0.0
    } else {
        below as f64 / total as f64
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use image::Luma;

    #[test]
    fn single_step_edge_block() {
        let img = GrayImage::from_fn(64, 64, |x, _| Luma([if x >= 32 { 220 } else { 20 }]));
        let r = jnbm_whole_image_report(&img).unwrap();
        assert_eq!((r.blocks, r.edge_blocks, r.edges), (1, 1, 62));
        let d = (62.0 * (2.0f64 / 3.0).powf(BETA)).powf(1.0 / BETA);
        assert!((r.jnbm.unwrap() - 1.0 / d).abs() < 1e-12);
        assert_eq!(cpbd_whole_image(&img).unwrap(), 1.0);
    }

    #[test]
    fn flat_image() {
        let g = GrayImage::from_pixel(64, 64, Luma([77]));
        assert!(canny_thresholds(&g).is_none());
        assert!(canny_edges(&g).iter().all(|&e| !e));
        assert_eq!(jnbm_whole_image_report(&g).unwrap().jnbm, None);
        assert_eq!(cpbd_whole_image(&g).unwrap(), 0.0);
    }
}
