//! The two calls of MATLAB's `edge` (Image Processing Toolbox) that the
//! authors' JNBM and CPBD code makes, on grey values as `f64` (0..255, not
//! rescaled: `edge` keeps a `double` image as it is), row-major, `w x h`.
//!
//! # `edge(A, 'sobel', thresh, 'vertical')` -> [`sobel_vertical`]
//!
//! Followed exactly (this is plain arithmetic, and for 8-bit input every
//! value below is an exact binary fraction, so ties break as in MATLAB):
//!
//! - `bx`, `by`: correlation with the Sobel masks divided by 8 (so `bx` is
//!   the horizontal derivative in grey levels per pixel), replicated border.
//! - `b = bx^2` (the `'vertical'` direction sets `kx = 1`, `ky = 0` in
//!   `b = kx bx^2 + ky by^2`).
//! - `cutoff = thresh^2` when a threshold is given: `thresh` bounds the
//!   gradient *magnitude* `|bx|` (grey levels per pixel), not its square;
//!   with `[]` the automatic `cutoff = 4 mean(b)`.
//! - Thinning (MATLAB's `computeedge`/`edgethinning`, after Pratt): a pixel is
//!   an edge when `b > cutoff` and either
//!   (a) `|bx| >= kx |by| - 100 eps` and `b` is a horizontal local maximum
//!   (`b[x-1] <= b[x] > b[x+1]`), or
//!   (b) `|by| >= ky |bx| - 100 eps` and `b` is a vertical local maximum
//!   (`b[y-1] <= b[y] > b[y+1]`).
//!   With `ky = 0` condition (b) needs only the vertical maximum, so MATLAB's
//!   "vertical" Sobel map also keeps pixels where `bx^2` peaks along the
//!   *column*; and (a) drops horizontal maxima where `|by| > |bx|`.
//!   A comparison that would leave the image counts as true (current
//!   MATLAB); older releases differed there, which only changes border
//!   pixels, and those are never measured.
//!
//! # `edge(A, 'canny')` -> [`canny`]
//!
//! MATLAB's Canny as shipped since R2011a (the version anyone running the
//! authors' code today gets):
//!
//! - Derivative-of-Gaussian gradients, `sigma = sqrt(2)`: a 13-tap Gaussian
//!   (`x = -6..6`, `ceil(4 sigma) = 6`) normalised to sum 1, and its
//!   numerical `gradient` normalised so that its first 7 taps sum to 1;
//!   `dx` = smooth along columns then differentiate along rows, `dy` the
//!   transpose; convolution with replicated borders.
//! - `mag = hypot(dx, dy) / max` (an image with `max = 0` has no edge; we
//!   compute `sqrt(dx^2 + dy^2)`, which can differ from `hypot` in the last bit).
//! - Thresholds: `imhist(mag, 64)` (64 bins centred on `k/63`, i.e. bin
//!   `round(63 mag)`: our reading of `imhist` for floating-point images); the
//!   high threshold is `k/64` for the first bin `k` (1-based) at which the
//!   cumulative count exceeds 70 % of the pixels, the low one is `0.4` times
//!   that.
//! - Non-maximum suppression on interior pixels with `mag > low`: `mag` must
//!   be `>=` both values linearly interpolated between the axis neighbour and
//!   the diagonal neighbour along and against the gradient (this is the same
//!   comparison as MATLAB's four octant cases, ties included). Border pixels
//!   are never edges.
//! - Hysteresis: the 8-connected groups of suppressed-edge pixels that hold
//!   a pixel with `mag > high` (`imreconstruct(mag > high, E, 8)`; the marker
//!   is clipped to `E`).
//!
//! Where we must guess: the authors wrote their code in 2009, when MATLAB's
//! Canny used `sigma = 1` and a different kernel (changed in R2011a); the
//! `imhist` binning above; and floating-point summation order (MATLAB's
//! filters may round differently in the last bit, which can flip a
//! non-maximum-suppression tie on real images). The Canny map only decides
//! which blocks are edge blocks, so these guesses move a block in or out of
//! the metric, never a width.

use rayon::prelude::*;
use std::collections::VecDeque;

/// Images with at least this many pixels are filtered row-parallel.
const PARALLEL_PIXELS: usize = 1 << 16;

/// Canny smoothing, px (MATLAB default since R2011a).
pub const CANNY_SIGMA: f64 = std::f64::consts::SQRT_2;
/// Share of pixels below the automatic high Canny threshold (MATLAB default).
pub const CANNY_NOT_EDGE: f64 = 0.7;
/// Low / high Canny threshold ratio (MATLAB default).
pub const CANNY_LOW_RATIO: f64 = 0.4;
/// Bins of the magnitude histogram used to pick the Canny thresholds.
pub const CANNY_BINS: usize = 64;
/// Scale of the automatic Sobel cutoff (`cutoff = 4 mean(b)`).
pub const SOBEL_SCALE: f64 = 4.0;

/// MATLAB `edge(A, 'sobel', thresh, 'vertical')` with thinning (see the
/// module docs): `thresh = None` is MATLAB's `[]` (automatic cutoff).
/// Returns the edge map, row-major.
pub fn sobel_vertical(a: &[f64], w: usize, h: usize, thresh: Option<f64>) -> Vec<bool> {
    assert_eq!(a.len(), w * h, "image size");
    let n = w * h;
    if n == 0 {
        return Vec::new();
    }
    let at = |x: usize, y: usize, dx: isize, dy: isize| -> f64 {
        let xx = (x as isize + dx).clamp(0, w as isize - 1) as usize;
        let yy = (y as isize + dy).clamp(0, h as isize - 1) as usize;
        a[yy * w + xx]
    };
    let mut bx = vec![0.0; n];
    let mut by = vec![0.0; n];
    for y in 0..h {
        for x in 0..w {
            let gx = (at(x, y, 1, -1) + 2.0 * at(x, y, 1, 0) + at(x, y, 1, 1))
                - (at(x, y, -1, -1) + 2.0 * at(x, y, -1, 0) + at(x, y, -1, 1));
            let gy = (at(x, y, -1, 1) + 2.0 * at(x, y, 0, 1) + at(x, y, 1, 1))
                - (at(x, y, -1, -1) + 2.0 * at(x, y, 0, -1) + at(x, y, 1, -1));
            // magnitudes only matter (MATLAB takes abs before thinning)
            bx[y * w + x] = (gx / 8.0).abs();
            by[y * w + x] = (gy / 8.0).abs();
        }
    }
    let b: Vec<f64> = bx.iter().map(|v| v * v).collect();
    let cutoff = match thresh {
        Some(t) => t * t,
        None => SOBEL_SCALE * b.iter().sum::<f64>() / n as f64,
    };
    let tol = 100.0 * f64::EPSILON;
    let mut e = vec![false; n];
    for y in 0..h {
        for x in 0..w {
            let i = y * w + x;
            let v = b[i];
            if v <= cutoff {
                continue;
            }
            let left = x == 0 || b[i - 1] <= v;
            let right = x + 1 == w || v > b[i + 1];
            let up = y == 0 || b[i - w] <= v;
            let down = y + 1 == h || v > b[i + w];
            // kx = 1, ky = 0
            let horizontal = bx[i] >= by[i] - tol && left && right;
            let vertical = by[i] >= -tol && up && down;
            e[i] = horizontal || vertical;
        }
    }
    e
}

/// The 13-tap Gaussian and derivative-of-Gaussian kernels of MATLAB's Canny.
fn canny_kernels(sigma: f64) -> (Vec<f64>, Vec<f64>) {
    let ext = (4.0 * sigma).ceil() as usize;
    let c = 1.0 / ((2.0 * std::f64::consts::PI).sqrt() * sigma);
    let half: Vec<f64> = (0..=ext)
        .map(|x| c * (-((x * x) as f64) / (2.0 * sigma * sigma)).exp())
        .collect();
    let norm = 2.0 * half[1..].iter().sum::<f64>() + half[0];
    let half: Vec<f64> = half.iter().map(|v| v / norm).collect();
    let mut g: Vec<f64> = half.iter().rev().copied().collect();
    g.extend_from_slice(&half[1..]);
    // numerical gradient: central differences inside, one-sided at the ends
    let len = g.len();
    let mut d = vec![0.0; len];
    d[0] = g[1] - g[0];
    d[len - 1] = g[len - 1] - g[len - 2];
    for i in 1..len - 1 {
        d[i] = (g[i + 1] - g[i - 1]) / 2.0;
    }
    let s: f64 = d[..=ext].iter().sum();
    let d = d.iter().map(|v| v / s).collect();
    (g, d)
}

/// 1-D convolution (kernel flipped, as `imfilter(..., 'conv')`) along rows
/// (`along_x`) or columns, replicated border. Rows of large images are done
/// in parallel.
fn convolve(src: &[f64], w: usize, h: usize, k: &[f64], along_x: bool) -> Vec<f64> {
    let c = k.len() / 2;
    let mut out = vec![0.0; w * h];
    // one output row; terms are added in the same order along x and along
    // y, so convolving the transpose gives exactly the transpose
    let row = |y: usize, o: &mut [f64]| {
        if along_x {
            // out[x] = sum_j k[j] src[x + c - j] on a row padded by replication
            let r = &src[y * w..(y + 1) * w];
            let mut pad = Vec::with_capacity(w + 2 * c);
            pad.extend(std::iter::repeat_n(r[0], c));
            pad.extend_from_slice(r);
            pad.extend(std::iter::repeat_n(r[w - 1], c));
            for (j, &kj) in k.iter().enumerate() {
                let start = 2 * c - j;
                for (ov, &sv) in o.iter_mut().zip(&pad[start..start + w]) {
                    *ov += kj * sv;
                }
            }
        } else {
            for (j, &kj) in k.iter().enumerate() {
                let yy = (y as isize + c as isize - j as isize).clamp(0, h as isize - 1) as usize;
                for (ov, &sv) in o.iter_mut().zip(&src[yy * w..(yy + 1) * w]) {
                    *ov += kj * sv;
                }
            }
        }
    };
    if w * h >= PARALLEL_PIXELS {
        out.par_chunks_mut(w)
            .enumerate()
            .for_each(|(y, o)| row(y, o));
    } else {
        for (y, o) in out.chunks_mut(w).enumerate() {
            row(y, o);
        }
    }
    out
}

/// Smoothed gradients `(dx, dy)` of MATLAB's Canny.
pub fn canny_gradients(a: &[f64], w: usize, h: usize) -> (Vec<f64>, Vec<f64>) {
    let (g, d) = canny_kernels(CANNY_SIGMA);
    let sy = convolve(a, w, h, &g, false);
    let dx = convolve(&sy, w, h, &d, true);
    let sx = convolve(a, w, h, &g, true);
    let dy = convolve(&sx, w, h, &d, false);
    (dx, dy)
}

/// Automatic `(low, high)` thresholds on the normalised magnitude (0..1).
pub fn canny_thresholds(mag: &[f64]) -> (f64, f64) {
    let mut counts = [0usize; CANNY_BINS];
    let top = (CANNY_BINS - 1) as f64;
    for &m in mag {
        let k = ((m * top + 0.5).floor().max(0.0) as usize).min(CANNY_BINS - 1);
        counts[k] += 1;
    }
    let limit = CANNY_NOT_EDGE * mag.len() as f64;
    let mut cum = 0usize;
    let mut bin = CANNY_BINS;
    for (k, &c) in counts.iter().enumerate() {
        cum += c;
        if cum as f64 > limit {
            bin = k + 1;
            break;
        }
    }
    let high = bin as f64 / CANNY_BINS as f64;
    (CANNY_LOW_RATIO * high, high)
}

/// MATLAB `edge(A, 'canny')` with its automatic thresholds (see the module
/// docs). Returns the edge map, row-major.
pub fn canny(a: &[f64], w: usize, h: usize) -> Vec<bool> {
    assert_eq!(a.len(), w * h, "image size");
    let n = w * h;
    let mut e = vec![false; n];
    if w < 3 || h < 3 {
        return e;
    }
    let (dx, dy) = canny_gradients(a, w, h);
    // MATLAB uses hypot; sqrt(x^2 + y^2) may differ in the last bit only
    // (and is several times faster)
    let mut mag: Vec<f64> = dx
        .iter()
        .zip(&dy)
        .map(|(x, y)| (x * x + y * y).sqrt())
        .collect();
    let max = mag.iter().copied().fold(0.0, f64::max);
    if max <= 0.0 {
        return e;
    }
    for m in &mut mag {
        *m /= max;
    }
    let (low, high) = canny_thresholds(&mag);
    // non-maximum suppression
    for y in 1..h - 1 {
        for x in 1..w - 1 {
            let i = y * w + x;
            let m = mag[i];
            if m <= low {
                continue;
            }
            let (gx, gy) = (dx[i], dy[i]);
            let (sx, sy) = (sign(gx), sign(gy));
            // axis neighbour along the dominant component, diagonal neighbour,
            // interpolation weight d = minor / major
            let (ax, ay, d) = if gx.abs() >= gy.abs() {
                ((sx, 0), (sx, sy), (gy / gx).abs())
            } else {
                ((0, sy), (sx, sy), (gx / gy).abs())
            };
            let get = |(ox, oy): (isize, isize)| -> f64 {
                mag[(y as isize + oy) as usize * w + (x as isize + ox) as usize]
            };
            let fwd = get(ax) * (1.0 - d) + get(ay) * d;
            let bwd = get((-ax.0, -ax.1)) * (1.0 - d) + get((-ay.0, -ay.1)) * d;
            if m >= fwd && m >= bwd {
                e[i] = true;
            }
        }
    }
    // hysteresis: keep 8-connected groups with a strong pixel
    let mut keep = vec![false; n];
    let mut queue = VecDeque::new();
    for i in 0..n {
        if e[i] && mag[i] > high {
            keep[i] = true;
            queue.push_back(i);
        }
    }
    while let Some(i) = queue.pop_front() {
        let (x, y) = ((i % w) as isize, (i / w) as isize);
        for oy in -1..=1 {
            for ox in -1..=1 {
                let (xx, yy) = (x + ox, y + oy);
                if xx < 0 || yy < 0 || xx >= w as isize || yy >= h as isize {
                    continue;
                }
                let j = yy as usize * w + xx as usize;
                if e[j] && !keep[j] {
                    keep[j] = true;
                    queue.push_back(j);
                }
            }
        }
    }
    keep
}

/// -1, 0 or 1 (0 for zero), as an offset.
fn sign(v: f64) -> isize {
    if v > 0.0 {
        1
    } else if v < 0.0 {
        -1
    } else {
        0
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn img(w: usize, h: usize, f: impl Fn(usize, usize) -> f64) -> Vec<f64> {
        (0..h)
            .flat_map(|y| (0..w).map(move |x| (x, y)))
            .map(|(x, y)| f(x, y))
            .collect()
    }

    #[test]
    fn canny_kernel_is_matlabs() {
        let (g, d) = canny_kernels(CANNY_SIGMA);
        assert_eq!(g.len(), 13);
        assert!((g.iter().sum::<f64>() - 1.0).abs() < 1e-15);
        assert!((d[..7].iter().sum::<f64>() - 1.0).abs() < 1e-15);
        assert_eq!(d[6], 0.0);
        assert!(d[0] > 0.0 && d[12] < 0.0);
        // symmetric Gaussian, antisymmetric derivative
        for i in 0..13 {
            assert!((g[i] - g[12 - i]).abs() < 1e-18);
            assert!((d[i] + d[12 - i]).abs() < 1e-15);
        }
    }

    #[test]
    fn canny_gradient_sign() {
        // a linear ramp rising along x: dx > 0 and the same everywhere away
        // from the border, dy = 0
        let a = img(40, 20, |x, _| 3.0 * x as f64);
        let (dx, dy) = canny_gradients(&a, 40, 20);
        let (i, j) = (10 * 40 + 15, 5 * 40 + 25);
        assert!(dx[i] > 0.0);
        assert!((dx[i] - dx[j]).abs() < 1e-9, "{} {}", dx[i], dx[j]);
        assert!(dy[i].abs() < 1e-12);
    }

    #[test]
    fn canny_finds_a_step_in_every_row() {
        let (w, h) = (64, 64);
        let a = img(w, h, |x, _| if x >= 32 { 200.0 } else { 20.0 });
        let e = canny(&a, w, h);
        for y in 1..h - 1 {
            let xs: Vec<usize> = (0..w).filter(|&x| e[y * w + x]).collect();
            // the step lies between 31 and 32: equal magnitudes, and
            // non-maximum suppression keeps ties (>=)
            assert_eq!(xs, vec![31, 32], "row {y}");
        }
        assert!((0..w).all(|x| !e[x] && !e[(h - 1) * w + x]));
        let flat = vec![7.0; w * h];
        assert!(canny(&flat, w, h).iter().all(|&v| !v));
    }

    #[test]
    fn canny_thresholds_follow_the_histogram() {
        // 80 % zeros: the first bin already exceeds 70 %
        let mut m = vec![0.0; 80];
        m.extend(std::iter::repeat_n(1.0, 20));
        assert_eq!(canny_thresholds(&m), (0.4 / 64.0, 1.0 / 64.0));
        // uniform over the 64 centres: 70 % reached in bin 45 (45 of 64 = 70.3 %)
        let m: Vec<f64> = (0..64).map(|k| k as f64 / 63.0).collect();
        let (lo, hi) = canny_thresholds(&m);
        assert_eq!(hi, 45.0 / 64.0);
        assert!((lo - 0.4 * 45.0 / 64.0).abs() < 1e-15);
    }

    #[test]
    fn sobel_fixed_threshold_bounds_the_magnitude() {
        // step of height s: |bx| = s/2 on the two columns beside it
        let (w, h) = (20, 8);
        for (s, found) in [(4.0, false), (5.0, true)] {
            let a = img(w, h, |x, _| if x >= 10 { 100.0 + s } else { 100.0 });
            let e = sobel_vertical(&a, w, h, Some(2.0));
            let n = e.iter().filter(|&&v| v).count();
            assert_eq!(n > 0, found, "step {s}: {n} edges");
            if found {
                // one per row, on the right-hand column of the tie (the
                // bottom row keeps both: vertical maxima at the border)
                for y in 0..h - 1 {
                    assert!(e[y * w + 10] && !e[y * w + 9], "row {y}");
                }
            }
        }
    }

    #[test]
    fn sobel_thinning_rule_a_needs_bx_to_dominate() {
        // x-step of 10 (|bx| = 5 on columns 7 and 8) crossed by a y-step of
        // 100 at rows 7|8 (|by| = 50 there): the horizontal maximum on
        // column 8 is dropped in rows 7 and 8 only
        let (w, h) = (16, 16);
        let a = img(w, h, |x, y| {
            100.0 * (y >= 8) as u8 as f64 + 10.0 * (x >= 8) as u8 as f64
        });
        let e = sobel_vertical(&a, w, h, None);
        for y in 0..h - 1 {
            let want = !(y == 7 || y == 8);
            assert_eq!(e[y * w + 8], want, "row {y}");
            assert!(!e[y * w + 7], "row {y}");
        }
    }

    #[test]
    fn sobel_thinning_rule_b_keeps_vertical_maxima_of_bx() {
        // x-step of 20, 40 in row 8: |bx| = 15 in row 8, 12.5 in rows 7 and
        // 9, 10 elsewhere, equal on columns 7 and 8. Column 8 is the
        // horizontal maximum in every row; column 7 is kept in row 8 only,
        // as a vertical maximum of bx^2
        let (w, h) = (16, 16);
        let a = img(w, h, |x, y| {
            let s = if y == 8 { 40.0 } else { 20.0 };
            if x >= 8 {
                s
            } else {
                0.0
            }
        });
        let e = sobel_vertical(&a, w, h, None);
        for y in 0..h - 1 {
            assert!(e[y * w + 8], "row {y}");
            assert_eq!(e[y * w + 7], y == 8, "row {y}");
        }
    }
}
