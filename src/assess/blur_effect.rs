//! The blur effect of Crete, Dolmiere, Ladret & Nicolas (SPIE 6492, 2007),
//! computed exactly as scikit-image's `skimage.measure.blur_effect` with its
//! defaults (`h_size = 11`, `channel_axis = None` on the grey image,
//! `reduce_func = np.max`).
//!
//! The grey image is scaled to 0..1 (`img_as_float`). For each axis
//! (0 = rows/vertical, 1 = columns/horizontal):
//!
//! 1. re-blur: `F` = mean over `h_size` samples along the axis, centred
//!    (`scipy.ndimage.uniform_filter1d`, boundary mode `reflect`, i.e.
//!    half-sample symmetric `d c b a | a b c d`);
//! 2. `S = max(eps, |sobel(I)|)`, `Bl = max(eps, |sobel(F)|)` where `sobel` along
//!    the axis is `[1, 0, -1]` along it times `[1, 2, 1] / 4` across it
//!    (`skimage.filters.sobel(axis=...)`, `ndimage.convolve`, mode `reflect`)
//!    and `eps` = 2^-52;
//! 3. `T = max(0, S - Bl)`; over the interior `[2, n-1)` on both axes,
//!    `M1 = sum S`, `M2 = sum T`, `B_axis = |M1 - M2| / M1`.
//!
//! The result is `max(B_0, B_1)`: 0 (sharp) .. 1 (blurred).

use crate::error::{Error, Result};
use image::GrayImage;

/// Default re-blurring filter length, px (scikit-image default).
pub const H_SIZE: usize = 11;

/// Index into `0..n` with scipy's `reflect` boundary (half-sample symmetric).
fn reflect(i: isize, n: usize) -> usize {
    let n2 = 2 * n as isize;
    let m = i.rem_euclid(n2);
    if m >= n as isize {
        (n2 - 1 - m) as usize
    } else {
        m as usize
    }
}

/// `uniform_filter1d(a, size, axis, mode='reflect')` on a `w x h` row-major image.
fn uniform_1d(a: &[f64], w: usize, h: usize, size: usize, axis: usize) -> Vec<f64> {
    // scipy: window [i - size/2, i - size/2 + size) for origin 0
    let lo = (size / 2) as isize;
    let mut out = vec![0.0; w * h];
    for y in 0..h {
        for x in 0..w {
            let mut s = 0.0;
            for k in 0..size as isize {
                let d = k - lo;
                let v = if axis == 0 {
                    a[reflect(y as isize + d, h) * w + x]
                } else {
                    a[y * w + reflect(x as isize + d, w)]
                };
                s += v;
            }
            out[y * w + x] = s / size as f64;
        }
    }
    out
}

/// `|skimage.filters.sobel(a, axis)|` with mode `reflect`.
fn abs_sobel(a: &[f64], w: usize, h: usize, axis: usize) -> Vec<f64> {
    let at = |x: isize, y: isize| a[reflect(y, h) * w + reflect(x, w)];
    let mut out = vec![0.0; w * h];
    for y in 0..h as isize {
        for x in 0..w as isize {
            let v = if axis == 0 {
                let up = at(x - 1, y - 1) + 2.0 * at(x, y - 1) + at(x + 1, y - 1);
                let dn = at(x - 1, y + 1) + 2.0 * at(x, y + 1) + at(x + 1, y + 1);
                (dn - up) / 4.0
            } else {
                let l = at(x - 1, y - 1) + 2.0 * at(x - 1, y) + at(x - 1, y + 1);
                let r = at(x + 1, y - 1) + 2.0 * at(x + 1, y) + at(x + 1, y + 1);
                (r - l) / 4.0
            };
            out[y as usize * w + x as usize] = v.abs();
        }
    }
    out
}

/// Blur effect along axis 0 (rows, vertical) and axis 1 (columns, horizontal),
/// with re-blur length `h_size` px. Errors for an image under 4x4 px or `h_size = 0`.
pub fn blur_effect_axes(img: &GrayImage, h_size: usize) -> Result<[f64; 2]> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    if w < 4 || h < 4 {
        return Err(Error::invalid(
            "blur effect",
            format!("image is {w}x{h} px; at least 4x4 is needed"),
        ));
    }
    if h_size == 0 {
        return Err(Error::invalid("blur effect h_size", "must be >= 1"));
    }
    let a: Vec<f64> = img.as_raw().iter().map(|&v| v as f64 / 255.0).collect();
    let eps = f64::EPSILON;
    let mut b = [0.0; 2];
    for (ax, out) in b.iter_mut().enumerate() {
        let f = uniform_1d(&a, w, h, h_size, ax);
        let s = abs_sobel(&a, w, h, ax);
        let bl = abs_sobel(&f, w, h, ax);
        let (mut m1, mut m2) = (0.0, 0.0);
        for y in 2..h - 1 {
            for x in 2..w - 1 {
                let i = y * w + x;
                let si = s[i].max(eps);
                let bi = bl[i].max(eps);
                m1 += si;
                m2 += (si - bi).max(0.0);
            }
        }
        *out = (m1 - m2).abs() / m1;
    }
    Ok(b)
}

/// Blur effect with scikit-image's defaults: `max` over both axes, `h_size = 11`.
pub fn blur_effect(img: &GrayImage) -> Result<f64> {
    let b = blur_effect_axes(img, H_SIZE)?;
    Ok(b[0].max(b[1]))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn reflect_matches_scipy() {
        // scipy 'reflect' on n = 3: ... b a | a b c | c b ...
        let got: Vec<usize> = (-4..7).map(|i| reflect(i, 3)).collect();
        assert_eq!(got, vec![2, 2, 1, 0, 0, 1, 2, 2, 1, 0, 0]);
    }

    #[test]
    fn flat_image_is_fully_blurred_not_nan() {
        let g = GrayImage::from_pixel(8, 8, image::Luma([9]));
        assert_eq!(blur_effect(&g).unwrap(), 1.0);
        assert!(blur_effect(&GrayImage::new(3, 9)).is_err());
    }
}
