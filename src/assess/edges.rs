//! Edge maps and Marziliano edge widths shared by JNBM and CPBD.
//!
//! Choices the papers leave open (all follow the authors' MATLAB code as far
//! as it can be read off MATLAB's `edge` defaults):
//!
//! - **Canny** (block classification): [`imageproc::edges::canny`], which
//!   smooths with a Gaussian of sigma 1.4 px and uses 3x3 Sobel gradients
//!   (magnitudes 0..~1140 on the 0..255 scale). Thresholds are chosen
//!   automatically like MATLAB's `edge(I,'canny')`: the gradient magnitudes
//!   (of the same smoothed image) are put in 64 equal bins over `[0, max]`;
//!   the high threshold is the upper end of the first bin at which the
//!   cumulative count exceeds 70 % of the pixels, the low threshold is 0.4 x
//!   the high one. A flat image (max = 0) has no Canny edge.
//! - **Sobel vertical edges** (width measurement), like MATLAB's
//!   `edge(I,'sobel',[],'vertical')`: `gx` = horizontal Sobel derivative / 8
//!   (replicated border), `b = gx^2`, automatic cutoff `4 mean(b)`; a pixel is
//!   an edge when `b > cutoff` and it is a horizontal local maximum of `b`
//!   (`b[x-1] <= b[x] > b[x+1]`, thinning to one pixel per edge).
//! - **Gradient angle** from central differences (MATLAB/NumPy `gradient`),
//!   `atan2(gy, gx)` in degrees, quantised to multiples of 45 deg; only
//!   pixels quantised to 0 (|angle| < 22.5, rising left to right) or +-180
//!   (|angle| >= 157.5, falling) get a width. Pixels with `gx = 0` are
//!   skipped (the authors' code would treat `gx = 0, gy != 0` as angle 0; that
//!   is a vertical gradient, not a horizontal one).
//! - **Width** (Marziliano et al.): from the edge pixel walk left and right
//!   along the row while the intensity keeps falling (rising) away from the
//!   edge, at most 100 steps each way; each side counts `steps + 1`, the
//!   width is the sum (an ideal step edge has width 2, as in the authors'
//!   code). Only pixels at least one pixel away from the image border are
//!   measured; the walk uses the whole row (not only the block).

use image::GrayImage;
use imageproc::edges::canny;
use imageproc::filter::gaussian_blur_f32;
use imageproc::gradients::{horizontal_sobel, vertical_sobel};

/// Sigma of imageproc's Canny smoothing, px.
pub const CANNY_SIGMA: f32 = 1.4;
/// Share of pixels below the automatic high Canny threshold (MATLAB default).
pub const CANNY_NOT_EDGE: f64 = 0.7;
/// Low / high Canny threshold ratio (MATLAB default).
pub const CANNY_LOW_RATIO: f64 = 0.4;
/// Maximum walking steps on each side of an edge pixel.
pub const MAX_STEPS: usize = 100;

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
    let limit = CANNY_NOT_EDGE * mag.len() as f64;
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
    Some(((CANNY_LOW_RATIO as f32) * high, high))
}

/// Canny edge map (true = edge), row-major, automatic thresholds.
pub fn canny_edges(img: &GrayImage) -> Vec<bool> {
    match canny_thresholds(img) {
        None => vec![false; (img.width() * img.height()) as usize],
        Some((lo, hi)) => canny(img, lo, hi).as_raw().iter().map(|&v| v > 0).collect(),
    }
}

/// Vertical Sobel edge map (true = edge), row-major; see the module docs.
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

/// Direction of a horizontal gradient at an edge pixel.
#[derive(Clone, Copy, PartialEq, Eq, Debug)]
enum Dir {
    Rising,
    Falling,
}

fn horizontal_dir(a: &[f64], w: usize, x: usize, y: usize) -> Option<Dir> {
    let gx = (a[y * w + x + 1] - a[y * w + x - 1]) / 2.0;
    let gy = (a[(y + 1) * w + x] - a[(y - 1) * w + x]) / 2.0;
    if gx == 0.0 {
        return None;
    }
    let ang = gy.atan2(gx).to_degrees().abs();
    if ang < 22.5 {
        Some(Dir::Rising)
    } else if ang >= 157.5 {
        Some(Dir::Falling)
    } else {
        None
    }
}

/// Counts one side of an edge: steps taken (at most [`MAX_STEPS`]) + 1.
/// `step` is -1 (left) or +1 (right); `grow` says whether the intensity must
/// keep increasing (true) or decreasing (false) while walking away.
fn side(row: &[f64], x: usize, step: isize, grow: bool) -> usize {
    let n = row.len() as isize;
    for k in 0..MAX_STEPS as isize {
        let inner = x as isize + step * (1 + k);
        let outer = x as isize + step * (2 + k);
        if outer < 0 || outer >= n {
            return k as usize + 1;
        }
        let d = row[outer as usize] - row[inner as usize];
        if (grow && d <= 0.0) || (!grow && d >= 0.0) {
            return k as usize + 1;
        }
    }
    MAX_STEPS + 1
}

/// Marziliano edge widths, px, row-major; 0 where there is no measured edge.
pub fn edge_widths(a: &[f64], w: usize, h: usize, edges: &[bool]) -> Vec<u32> {
    let mut out = vec![0u32; w * h];
    if w < 3 || h < 3 {
        return out;
    }
    for y in 1..h - 1 {
        let row = &a[y * w..(y + 1) * w];
        for x in 1..w - 1 {
            if !edges[y * w + x] {
                continue;
            }
            let width = match horizontal_dir(a, w, x, y) {
                // rising left to right: falls going left, rises going right
                Some(Dir::Rising) => side(row, x, -1, false) + side(row, x, 1, true),
                Some(Dir::Falling) => side(row, x, -1, true) + side(row, x, 1, false),
                None => 0,
            };
            out[y * w + x] = width as u32;
        }
    }
    out
}

/// Everything JNBM and CPBD need: Canny map, width map, grey values.
pub(crate) struct EdgeData {
    pub w: usize,
    pub a: Vec<f64>,
    pub canny: Vec<bool>,
    pub widths: Vec<u32>,
}

impl EdgeData {
    pub fn new(img: &GrayImage) -> Self {
        let (w, h) = (img.width() as usize, img.height() as usize);
        let a = super::to_f64(img);
        let sobel = sobel_vertical_edges(&a, w, h);
        let widths = edge_widths(&a, w, h, &sobel);
        EdgeData {
            w,
            canny: canny_edges(img),
            a,
            widths,
        }
    }

    /// Pixel indices of block `(bx, by)` (64x64), row-major.
    pub fn block(&self, bx: u32, by: u32) -> impl Iterator<Item = usize> + '_ {
        let b = super::BLOCK as usize;
        let (x0, y0) = (bx as usize * b, by as usize * b);
        (y0..y0 + b).flat_map(move |y| (x0..x0 + b).map(move |x| y * self.w + x))
    }

    /// Is block `(bx, by)` an edge block (Canny edge pixels > 0.2 %)?
    pub fn is_edge_block(&self, bx: u32, by: u32) -> bool {
        let n = self.block(bx, by).filter(|&i| self.canny[i]).count();
        n as f64 > EDGE_BLOCK_SHARE * (super::BLOCK * super::BLOCK) as f64
    }

    /// Block contrast `max - min`, grey levels.
    pub fn contrast(&self, bx: u32, by: u32) -> f64 {
        let (mut lo, mut hi) = (f64::INFINITY, f64::NEG_INFINITY);
        for i in self.block(bx, by) {
            lo = lo.min(self.a[i]);
            hi = hi.max(self.a[i]);
        }
        hi - lo
    }

    /// Non-zero edge widths in block `(bx, by)`.
    pub fn block_widths(&self, bx: u32, by: u32) -> impl Iterator<Item = f64> + '_ {
        self.block(bx, by)
            .map(|i| self.widths[i])
            .filter(|&v| v > 0)
            .map(|v| v as f64)
    }
}

/// A block is an edge block when more than this share of its pixels are Canny edges.
pub const EDGE_BLOCK_SHARE: f64 = 0.002;

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn step_edge_has_width_two_and_ramp_is_wider() {
        // a horizontal step at x = 10 | 11 and a 6-px ramp elsewhere
        let w = 40;
        let h = 5;
        let mut a = vec![0.0; w * h];
        for y in 0..h {
            for x in 0..w {
                a[y * w + x] = if x > 10 { 200.0 } else { 10.0 };
            }
        }
        let e = sobel_vertical_edges(&a, w, h);
        let wd = edge_widths(&a, w, h, &e);
        let row: Vec<u32> = wd[2 * w..3 * w].to_vec();
        let found: Vec<(usize, u32)> = row
            .iter()
            .copied()
            .enumerate()
            .filter(|p| p.1 > 0)
            .collect();
        assert_eq!(found.len(), 1, "{found:?}");
        assert_eq!(found[0].1, 2);

        // ramp 10 -> 200 over x = 10..=16 (6 rising steps), falling direction mirrored
        for y in 0..h {
            for x in 0..w {
                let t = ((x as f64 - 10.0) / 6.0).clamp(0.0, 1.0);
                a[y * w + x] = 200.0 - 190.0 * t;
            }
        }
        let e = sobel_vertical_edges(&a, w, h);
        let wd = edge_widths(&a, w, h, &e);
        let widths: Vec<u32> = wd[2 * w..3 * w]
            .iter()
            .copied()
            .filter(|&v| v > 0)
            .collect();
        assert!(!widths.is_empty());
        // whichever ramp pixel is the edge, the two walks cover the 6 ramp steps
        assert!(widths.iter().all(|&v| v == 6), "{widths:?}");
    }

    #[test]
    fn flat_image_has_no_edges() {
        let g = GrayImage::from_pixel(64, 64, image::Luma([77]));
        assert!(canny_thresholds(&g).is_none());
        assert!(canny_edges(&g).iter().all(|&e| !e));
    }
}
