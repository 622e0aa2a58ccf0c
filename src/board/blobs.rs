//! Red blob extraction for the thesis target (thesis ch. 6, Table 6.2).
//!
//! The target: a 4 x 4 grid of identical red squares (10 cm with 2 cm gaps on
//! the full board, half that on the small one) on a white board.
//!
//! **Colour threshold.** On the 8-bit *sRGB-encoded* values (as the camera
//! delivers them, no linearisation) the redness of a pixel is
//! `r = R - max(G, B)` (0 for white, grey and black; ~170 for a saturated
//! red). A pixel is red when `r > t`. With [`BlobParams::threshold`] `None`
//! (the default) `t` is adaptive: `t = max(min_threshold, fraction x
//! P99.9(r))`, i.e. half (by default) of the redness of the reddest pixels of
//! the image, which keeps a blurred square's red/white boundary near its
//! true edge whatever the exposure; `min_threshold` (default 40) stops a red-free
//! image from being segmented at noise level.
//!
//! **Components.** 8-connected components of the red mask
//! ([`imageproc::region_labelling::connected_components`]); components with
//! fewer than `min_area` pixels (default 4) or more than `max_area_fraction`
//! of the image (default 0.25) are dropped. A blob's centre is the mean of
//! its pixel centres `(i + 0.5, j + 0.5)` (the camera module's convention:
//! pixel `(i, j)` covers `[i, i+1) x [j, j+1)`).
//!
//! **Success** ([`evaluate`]): exactly as many blobs as expected centres (16)
//! and each expected centre has a blob closer than half the blob pitch
//! (centre-to-centre distance, projected into pixels). Because expected
//! centres are one pitch apart, a blob can match at most one of them.

use crate::check::{finite, positive};
use crate::error::{Error, Result};
use image::{GrayImage, Luma, RgbImage};
use imageproc::region_labelling::{connected_components, Connectivity};
use serde::Serialize;

/// Parameters of [`extract`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct BlobParams {
    /// Fixed redness threshold (0..255); `None` = adaptive (module docs).
    pub threshold: Option<f64>,
    /// Adaptive threshold as a fraction of the 99.9th-percentile redness.
    pub fraction: f64,
    /// Lower bound of the adaptive threshold (0..255).
    pub min_threshold: f64,
    /// Smallest blob kept, pixels.
    pub min_area: u32,
    /// Largest blob kept, as a fraction of the image area.
    pub max_area_fraction: f64,
}

impl Default for BlobParams {
    fn default() -> Self {
        BlobParams {
            threshold: None,
            fraction: 0.5,
            min_threshold: 40.0,
            min_area: 4,
            max_area_fraction: 0.25,
        }
    }
}

impl BlobParams {
    /// Rejects NaN/out-of-range values, naming the parameter.
    pub fn validate(&self) -> Result<()> {
        if let Some(t) = self.threshold {
            finite("blob threshold", t)?;
            if !(0.0..255.0).contains(&t) {
                return Err(Error::invalid(
                    "blob threshold",
                    format!("must be in [0, 255), got {t}"),
                ));
            }
        }
        positive("blob threshold fraction", self.fraction)?;
        if self.fraction > 1.0 {
            return Err(Error::invalid(
                "blob threshold fraction",
                format!("must be in (0, 1], got {}", self.fraction),
            ));
        }
        finite("blob min threshold", self.min_threshold)?;
        positive("blob max area fraction", self.max_area_fraction)?;
        Ok(())
    }
}

/// One extracted blob.
#[derive(Debug, Clone, Copy, PartialEq, Serialize)]
pub struct Blob {
    /// Centroid in pixel coordinates (`(0, 0)` = top-left corner of the image).
    pub centre: (f64, f64),
    /// Area, pixels.
    pub area: u32,
    /// Bounding box `(x_min, y_min, x_max, y_max)`, inclusive pixel indices.
    pub bbox: (u32, u32, u32, u32),
}

/// Redness `R - max(G, B)` of an 8-bit sRGB pixel (negative values clamp to 0).
pub fn redness(p: [u8; 3]) -> f64 {
    (p[0] as f64 - p[1].max(p[2]) as f64).max(0.0)
}

/// The redness threshold [`extract`] uses on `img`.
pub fn threshold_for(img: &RgbImage, params: &BlobParams) -> f64 {
    if let Some(t) = params.threshold {
        return t;
    }
    let mut hist = [0usize; 256];
    for p in img.pixels() {
        hist[redness(p.0) as usize] += 1;
    }
    let n = (img.width() as usize) * (img.height() as usize);
    // smallest value with at least 99.9 % of the pixels at or below it
    let need = (0.999 * n as f64).ceil() as usize;
    let mut cum = 0;
    let mut p999 = 255;
    for (v, &h) in hist.iter().enumerate() {
        cum += h;
        if cum >= need {
            p999 = v;
            break;
        }
    }
    (params.fraction * p999 as f64).max(params.min_threshold)
}

/// Binary red mask (255 = red) and the threshold used.
pub fn red_mask(img: &RgbImage, params: &BlobParams) -> Result<(GrayImage, f64)> {
    params.validate()?;
    let t = threshold_for(img, params);
    let mut m = GrayImage::new(img.width(), img.height());
    for (o, p) in m.pixels_mut().zip(img.pixels()) {
        o.0[0] = if redness(p.0) > t { 255 } else { 0 };
    }
    Ok((m, t))
}

/// Blobs of a binary mask (non-zero = foreground), size-filtered, sorted by
/// centre (rows of 0.5 px, then x).
pub fn components(mask: &GrayImage, params: &BlobParams) -> Vec<Blob> {
    // imageproc's labelling asserts on images under 2 px a side: pad those
    // with background on the right and bottom (components do not change).
    let padded;
    let labelled = if mask.width() < 2 || mask.height() < 2 {
        let mut m = GrayImage::new(mask.width().max(2), mask.height().max(2));
        image::imageops::replace(&mut m, mask, 0, 0);
        padded = m;
        &padded
    } else {
        mask
    };
    let labels = connected_components(labelled, Connectivity::Eight, Luma([0u8]));
    let n = labels.pixels().map(|p| p.0[0]).max().unwrap_or(0) as usize;
    // per label: area, sum x, sum y, bbox
    let mut acc = vec![(0u32, 0.0f64, 0.0f64, u32::MAX, u32::MAX, 0u32, 0u32); n + 1];
    for (x, y, p) in labels.enumerate_pixels() {
        let l = p.0[0] as usize;
        if l == 0 {
            continue;
        }
        let a = &mut acc[l];
        a.0 += 1;
        a.1 += x as f64 + 0.5;
        a.2 += y as f64 + 0.5;
        a.3 = a.3.min(x);
        a.4 = a.4.min(y);
        a.5 = a.5.max(x);
        a.6 = a.6.max(y);
    }
    let max_area = params.max_area_fraction * mask.width() as f64 * mask.height() as f64;
    let mut blobs: Vec<Blob> = acc
        .iter()
        .skip(1)
        .filter(|a| a.0 >= params.min_area.max(1) && (a.0 as f64) <= max_area)
        .map(|a| Blob {
            centre: (a.1 / a.0 as f64, a.2 / a.0 as f64),
            area: a.0,
            bbox: (a.3, a.4, a.5, a.6),
        })
        .collect();
    blobs.sort_by(|a, b| {
        a.centre
            .1
            .total_cmp(&b.centre.1)
            .then(a.centre.0.total_cmp(&b.centre.0))
    });
    blobs
}

/// Extracts the red blobs of an sRGB image (module docs).
pub fn extract(img: &RgbImage, params: &BlobParams) -> Result<Vec<Blob>> {
    let (m, _) = red_mask(img, params)?;
    Ok(components(&m, params))
}

/// Outcome of matching blobs to expected centres.
#[derive(Debug, Clone, PartialEq, Serialize)]
pub struct BlobResult {
    /// Blobs extracted.
    pub found: usize,
    /// Expected centres with a blob closer than half a pitch.
    pub matched: usize,
    /// Expected centres without one.
    pub missed: usize,
    /// Blobs not used for a match (fragments, fused or spurious blobs).
    pub false_blobs: usize,
    /// Exactly `expected.len()` blobs and every expected centre matched.
    pub ok: bool,
    /// For each expected centre, the index of its blob.
    pub assignment: Vec<Option<usize>>,
    /// Largest centre error among the matches, px.
    pub max_error_px: Option<f64>,
}

/// Matches blobs to expected centres (px) with tolerance `pitch_px / 2`
/// (nearest blob wins per centre).
pub fn evaluate(blobs: &[Blob], expected_px: &[(f64, f64)], pitch_px: f64) -> Result<BlobResult> {
    positive("blob pitch (px)", pitch_px)?;
    if expected_px.is_empty() {
        return Err(Error::invalid("expected blob centres", "list is empty"));
    }
    for (i, &(x, y)) in expected_px.iter().enumerate() {
        if !(x.is_finite() && y.is_finite()) {
            return Err(Error::invalid(
                "expected blob centres",
                format!("centre {i} is not finite: ({x}, {y})"),
            ));
        }
    }
    let tol = pitch_px / 2.0;
    let mut assignment = Vec::with_capacity(expected_px.len());
    let mut max_err: Option<f64> = None;
    for &(ex, ey) in expected_px {
        let best = blobs
            .iter()
            .enumerate()
            .map(|(i, b)| (i, (b.centre.0 - ex).hypot(b.centre.1 - ey)))
            .filter(|&(_, d)| d < tol)
            .min_by(|a, b| a.1.total_cmp(&b.1));
        if let Some((_, d)) = best {
            max_err = Some(max_err.map_or(d, |m: f64| m.max(d)));
        }
        assignment.push(best.map(|(i, _)| i));
    }
    let matched = assignment.iter().filter(|a| a.is_some()).count();
    let found = blobs.len();
    Ok(BlobResult {
        found,
        matched,
        missed: expected_px.len() - matched,
        false_blobs: found - matched,
        ok: found == expected_px.len() && matched == expected_px.len(),
        assignment,
        max_error_px: max_err,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::board::{board_centres_px, Board};
    use crate::camera::Camera;

    #[test]
    fn thesis_board_projection() {
        let (c, pitch) = board_centres_px(&Camera::thesis(), &Board::thesis(), 6.0).unwrap();
        assert_eq!(c.len(), 16);
        // f p_board / (D p) = 4.2548 * 0.12 / 6 / 0.00465
        let want = 4.2548 * 0.12 / 6.0 / 0.00465;
        assert!((pitch - want).abs() < 1e-12);
        // symmetric about the principal point (320, 240)
        assert!((c[0].0 + c[15].0 - 640.0).abs() < 1e-9);
        assert!((c[0].1 + c[15].1 - 480.0).abs() < 1e-9);
        assert!((c[1].0 - c[0].0 - want).abs() < 1e-9);
        assert!(board_centres_px(&Camera::thesis(), &Board::thesis(), 0.0).is_err());
    }

    #[test]
    fn redness_of_colours() {
        assert_eq!(redness([255, 255, 255]), 0.0);
        assert_eq!(redness([200, 30, 50]), 150.0);
        assert_eq!(redness([10, 200, 10]), 0.0);
    }

    #[test]
    fn evaluate_counts() {
        let exp = [(10.0, 10.0), (30.0, 10.0)];
        let b = |x: f64, y: f64| Blob {
            centre: (x, y),
            area: 10,
            bbox: (0, 0, 0, 0),
        };
        let r = evaluate(&[b(11.0, 10.0), b(29.0, 11.0)], &exp, 20.0).unwrap();
        assert!(r.ok);
        assert_eq!(r.assignment, vec![Some(0), Some(1)]);
        // a fragment next to the first centre: still 2 matched but 3 found -> not ok
        let r = evaluate(&[b(11.0, 10.0), b(8.0, 10.0), b(29.0, 11.0)], &exp, 20.0).unwrap();
        assert_eq!((r.found, r.matched, r.false_blobs, r.ok), (3, 2, 1, false));
        // one fused blob in the middle: misses both (distance 10 = half pitch is not < 10)
        let r = evaluate(&[b(20.0, 10.0)], &exp, 20.0).unwrap();
        assert_eq!((r.matched, r.missed, r.false_blobs, r.ok), (0, 2, 1, false));
        assert!(evaluate(&[], &exp, 0.0).is_err());
        assert!(evaluate(&[], &[], 1.0).is_err());
    }
}
