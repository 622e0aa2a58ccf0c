//! Blur length on the sensor: the one place an MMBM (mm/s) and an exposure
//! (s) become pixels, and back.

/// Blur length over an exposure, px: the MMBM `mmbm_mm_s` (mm/s on the
/// sensor) over the pixel pitch `pitch_mm` (mm), i.e. the speed in px/s,
/// times the exposure `exposure_s` (s).
///
/// ```
/// // 0.4 mm/s for 70 ms on 4.65 um pixels: about 6 px.
/// let b = mmbm::camera::blur_px(0.4, 0.07, 0.00465);
/// assert!((b - 6.0215).abs() < 1e-3);
/// ```
pub fn blur_px(mmbm_mm_s: f64, exposure_s: f64, pitch_mm: f64) -> f64 {
    mmbm_mm_s / pitch_mm * exposure_s
}

/// The exposure, s, over which an MMBM of `mmbm_mm_s` (mm/s) blurs
/// `budget_px` pixels of pitch `pitch_mm` (mm): the inverse of [`blur_px`].
pub fn exposure_for_blur(budget_px: f64, mmbm_mm_s: f64, pitch_mm: f64) -> f64 {
    budget_px * pitch_mm / mmbm_mm_s
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_of_each_other() {
        for (m, te, p) in [
            (0.4, 0.07, 0.00465),
            (3.0, 0.002, 0.0015),
            (1e-3, 1.0, 0.01),
        ] {
            let b = blur_px(m, te, p);
            assert!((exposure_for_blur(b, m, p) - te).abs() < 1e-15 * te.max(1.0));
        }
        // By hand: 1 mm/s x 0.01 s = 0.01 mm = 2 px of 5 um.
        assert!((blur_px(1.0, 0.01, 0.005) - 2.0).abs() < 1e-12);
    }
}
