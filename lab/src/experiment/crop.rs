//! Where on a rendered frame the board is: the pattern's crop (for the image
//! metrics) and the blob pitch in pixels.

/// The region of the pattern (the bounding box of the expected blob centres,
/// grown by one blob pitch on each side, at least 128 x 128 so that JNBM has
/// whole 64 x 64 blocks), cropped from the frame; the whole frame when no
/// centres are known.
pub fn pattern_crop(img: &image::RgbImage, expected: &[(f64, f64)]) -> image::RgbImage {
    let [cx, cy, cw, ch] = pattern_box(img.width(), img.height(), expected);
    image::imageops::crop_imm(img, cx, cy, cw, ch).to_image()
}

/// [`pattern_crop`]'s region of a `width` x `height` frame: `[x, y, w, h]` px
/// (the whole frame when no centres are known).
pub fn pattern_box(width: u32, height: u32, expected: &[(f64, f64)]) -> [u32; 4] {
    if expected.is_empty() {
        return [0, 0, width, height];
    }
    let p = pitch_px(expected);
    let (mut x0, mut y0, mut x1, mut y1) = (
        f64::INFINITY,
        f64::INFINITY,
        f64::NEG_INFINITY,
        f64::NEG_INFINITY,
    );
    for &(x, y) in expected {
        x0 = x0.min(x - p);
        y0 = y0.min(y - p);
        x1 = x1.max(x + p);
        y1 = y1.max(y + p);
    }
    let (w, h) = (width as f64, height as f64);
    let grow = |a: f64, b: f64, lim: f64| {
        let (c, half) = ((a + b) / 2.0, ((b - a) / 2.0).max(64.0));
        let lo = (c - half).clamp(0.0, (lim - 2.0 * half).max(0.0));
        (lo.floor() as u32, (2.0 * half).min(lim).ceil() as u32)
    };
    let (cx, cw) = grow(x0, x1, w);
    let (cy, ch) = grow(y0, y1, h);
    [cx, cy, cw.min(width - cx), ch.min(height - cy)]
}

/// Blob pitch (px): the smallest distance between two expected centres.
pub(super) fn pitch_px(c: &[(f64, f64)]) -> f64 {
    let mut best = f64::INFINITY;
    for (i, a) in c.iter().enumerate() {
        for b in &c[i + 1..] {
            best = best.min(((a.0 - b.0).powi(2) + (a.1 - b.1).powi(2)).sqrt());
        }
    }
    if best.is_finite() {
        best
    } else {
        1.0
    }
}
