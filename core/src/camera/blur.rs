//! Blur length on the sensor: the one place an MMBM (mm/s) and an exposure
//! (s) become pixels, and back.

use crate::error::{Error, Result};

/// Blur length over an exposure, px: the MMBM `mmbm_mm_s` (mm/s on the
/// sensor) over the pixel pitch `pitch_mm` (mm), i.e. the speed in px/s,
/// times the exposure `exposure_s` (s).
///
/// ```
/// // 0.4 mm/s for 70 ms on 4.65 um pixels: about 6 px.
/// let b = mmbm_core::camera::blur_px(0.4, 0.07, 0.00465);
/// assert!((b - 6.0215).abs() < 1e-3);
/// ```
pub fn blur_px(mmbm_mm_s: f64, exposure_s: f64, pitch_mm: f64) -> f64 {
    mmbm_mm_s / pitch_mm * exposure_s
}

/// [`blur_px`], refusing a result that is not a finite number (an exposure
/// or a speed so large that the blur overflows f64, or a NaN input): every
/// door that prints or stores a blur in px uses this one.
///
/// ```
/// assert!(mmbm_core::camera::checked_blur_px(0.4, 1e308, 0.00465).is_err());
/// assert!(mmbm_core::camera::checked_blur_px(0.4, 0.07, 0.00465).is_ok());
/// ```
pub fn checked_blur_px(mmbm_mm_s: f64, exposure_s: f64, pitch_mm: f64) -> Result<f64> {
    finite_blur(blur_px(mmbm_mm_s, exposure_s, pitch_mm), || {
        format!("{mmbm_mm_s:?} mm/s over {exposure_s:?} s on {pitch_mm:?} mm pixels")
    })
}

/// Blur length over an exposure, px, from an MMBM in px/s (the true pixel
/// speed, `Mmbm::px_s`: the one px/s of every door, which is `mm/s / pitch`
/// with square, unskewed pixels, where this equals [`checked_blur_px`]),
/// refusing a result that is not a finite number.
pub fn checked_blur_of_px_s(px_s: f64, exposure_s: f64) -> Result<f64> {
    finite_blur(px_s * exposure_s, || {
        format!("{px_s:?} px/s over {exposure_s:?} s")
    })
}

/// `b` px, or an error saying that `what` (built only then) is not a finite blur.
fn finite_blur(b: f64, what: impl FnOnce() -> String) -> Result<f64> {
    if b.is_finite() {
        Ok(b)
    } else {
        Err(Error::invalid(
            "blur",
            format!(
                "{} is {b} px, not a finite number (an exposure or a speed too large?)",
                what()
            ),
        ))
    }
}

/// An MMBM `mmbm_mm_s` (mm/s) in px/s on pixels of pitch `pitch_mm` (mm),
/// refusing a result that is not a finite number.
pub fn checked_px_s(mmbm_mm_s: f64, pitch_mm: f64) -> Result<f64> {
    let px = mmbm_mm_s / pitch_mm;
    if px.is_finite() {
        Ok(px)
    } else {
        Err(Error::invalid(
            "MMBM",
            format!(
                "{mmbm_mm_s:?} mm/s on {pitch_mm:?} mm pixels is {px} px/s, not a finite number"
            ),
        ))
    }
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
        assert_eq!(
            checked_blur_px(1.0, 0.01, 0.005).unwrap(),
            blur_px(1.0, 0.01, 0.005)
        );
        assert_eq!(checked_px_s(1.0, 0.005).unwrap(), 200.0);
    }

    #[test]
    fn checked_variants_refuse_what_is_not_finite() {
        for (m, te, p) in [
            (0.4, 1e308, 0.00465),
            (1e300, 1e10, 1e-6),
            (f64::NAN, 0.1, 0.005),
        ] {
            let e = checked_blur_px(m, te, p).unwrap_err().to_string();
            assert!(
                e.contains("blur") && e.contains("not a finite number"),
                "{e}"
            );
        }
        assert!(checked_px_s(1e308, 1e-308).is_err());
        assert!(checked_blur_of_px_s(1e300, 1e10).is_err());
        // Square pixels: the same number as from mm/s and the pitch.
        let (m, te, p) = (0.4, 0.07, 0.00465);
        assert_eq!(
            checked_blur_of_px_s(checked_px_s(m, p).unwrap(), te).unwrap(),
            blur_px(m, te, p)
        );
        assert!(checked_px_s(f64::NAN, 0.005).is_err());
    }
}
