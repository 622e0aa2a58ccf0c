//! Tenengrad (Tenenbaum 1970; Krotkov 1987), the gradient-energy focus
//! measure: the 3x3 Sobel gradients `Gx` (kernel `[-1 0 1; -2 0 2; -1 0 1]`)
//! and `Gy` (its transpose) on the grey values (0..255), border reflect-101
//! as [`super::laplacian_var`], then the mean of `Gx^2 + Gy^2` over all
//! pixels (no threshold). Units: grey levels squared. Higher = sharper.

use super::laplacian::mirror;
use crate::error::{Error, Result};
use image::GrayImage;

/// Mean squared Sobel gradient magnitude of `img` (see the module docs).
/// Errors on an empty image.
pub fn tenengrad(img: &GrayImage) -> Result<f64> {
    let (w, h) = (img.width() as usize, img.height() as usize);
    if w == 0 || h == 0 {
        return Err(Error::invalid("Tenengrad", "empty image"));
    }
    let a = img.as_raw();
    let at = |x: isize, y: isize| a[mirror(y, h) * w + mirror(x, w)] as f64;
    let mut sum = 0.0;
    for y in 0..h as isize {
        for x in 0..w as isize {
            let gx = at(x + 1, y - 1) + 2.0 * at(x + 1, y) + at(x + 1, y + 1)
                - at(x - 1, y - 1)
                - 2.0 * at(x - 1, y)
                - at(x - 1, y + 1);
            let gy = at(x - 1, y + 1) + 2.0 * at(x, y + 1) + at(x + 1, y + 1)
                - at(x - 1, y - 1)
                - 2.0 * at(x, y - 1)
                - at(x + 1, y - 1);
            sum += gx * gx + gy * gy;
        }
    }
    Ok(sum / (w * h) as f64)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ramp_and_constant() {
        // I = 3x: Gx = (1 + 2 + 1) x 2 x 3 = 24 inside; at x = 0 and x = W-1
        // the mirrored border makes Gx = 0; Gy = 0. Mean: (W-2)/W x 576.
        let (w, h) = (10u32, 4u32);
        let img = GrayImage::from_fn(w, h, |x, _| image::Luma([3 * x as u8]));
        let v = tenengrad(&img).unwrap();
        assert!((v - 576.0 * 8.0 / 10.0).abs() < 1e-9, "{v}");
        // The transpose: the same energy from Gy.
        let img = GrayImage::from_fn(h, w, |_, y| image::Luma([3 * y as u8]));
        assert!((tenengrad(&img).unwrap() - v).abs() < 1e-9);
        let flat = GrayImage::from_pixel(5, 5, image::Luma([77]));
        assert_eq!(tenengrad(&flat).unwrap(), 0.0);
        assert!(tenengrad(&GrayImage::new(0, 3)).is_err());
    }
}
