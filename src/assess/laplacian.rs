//! Variance of the Laplacian (Pech-Pacheco et al. 2000), the usual
//! "focus measure": the 4-neighbour Laplacian
//! `L = I(x-1,y) + I(x+1,y) + I(x,y-1) + I(x,y+1) - 4 I(x,y)` on the grey
//! values (0..255), border reflect-101 (`c b | a b c | b a`: OpenCV's default
//! `BORDER_REFLECT_101`, SciPy's mode `mirror`), then the *population*
//! variance (divide by N) over all pixels. Units: grey levels squared.
//! Higher = sharper.

use crate::error::{Error, Result};
use image::GrayImage;

/// Index into `0..n` with a reflect-101 border (`n = 1` maps everything to 0).
pub(crate) fn mirror(i: isize, n: usize) -> usize {
    if n == 1 {
        return 0;
    }
    let p = 2 * (n as isize - 1);
    let m = i.rem_euclid(p);
    if m >= n as isize {
        (p - m) as usize
    } else {
        m as usize
    }
}

/// 4-neighbour Laplacian, reflect-101 border, row-major.
pub fn laplacian(img: &GrayImage) -> Vec<f64> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    let a = img.as_raw();
    let at = |x: isize, y: isize| a[mirror(y, h) * w + mirror(x, w)] as f64;
    let mut out = Vec::with_capacity(w * h);
    for y in 0..h as isize {
        for x in 0..w as isize {
            out.push(at(x - 1, y) + at(x + 1, y) + at(x, y - 1) + at(x, y + 1) - 4.0 * at(x, y));
        }
    }
    out
}

/// Population variance of `laplacian`. Errors on an empty image.
pub fn laplacian_var(img: &GrayImage) -> Result<f64> {
    if img.width() == 0 || img.height() == 0 {
        return Err(Error::invalid("Laplacian variance", "empty image"));
    }
    let l = laplacian(img);
    let n = l.len() as f64;
    let mean = l.iter().sum::<f64>() / n;
    Ok(l.iter().map(|v| (v - mean) * (v - mean)).sum::<f64>() / n)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn mirror_is_reflect_101() {
        let got: Vec<usize> = (-3..6).map(|i| mirror(i, 3)).collect();
        assert_eq!(got, vec![1, 2, 1, 0, 1, 2, 1, 0, 1]);
    }

    #[test]
    fn single_bright_pixel() {
        // 3x3 zeros with a 9 in the centre: L = -36 at the centre, +18 at its 4
        // neighbours (the mirrored border counts the 9 twice), 0 at the corners;
        // mean 4, var = (40^2 + 4 * 14^2 + 4 * 4^2) / 9 = 272 (scipy agrees)
        let mut g = GrayImage::new(3, 3);
        g.put_pixel(1, 1, image::Luma([9]));
        let v = laplacian_var(&g).unwrap();
        assert!((v - 272.0).abs() < 1e-12, "{v}");
    }
}
