//! Thin-lens defocus (docs/spec.md section 9): aperture diameter `A = f / N`; a point
//! at depth `z` focused at `s` spreads over a disc of diameter
//! `c = A f / (s - f) |z - s| / z` on the sensor.

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// The lens's aperture and focus (none given: infinite depth of field).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Lens {
    /// f-number `N` (focal length / aperture diameter).
    pub f_number: f64,
    /// Focus distance `s`, m.
    pub focus_m: f64,
}

impl Lens {
    /// Rejects a non-positive f-number or a focus distance not beyond the focal length.
    pub fn validate(&self, focal_mm: f64) -> Result<()> {
        if !(self.f_number.is_finite() && self.f_number > 0.0) {
            return Err(Error::invalid(
                "lens.f_number",
                format!("must be a positive number, got {}", self.f_number),
            ));
        }
        if !(self.focus_m.is_finite() && self.focus_m * 1000.0 > focal_mm) {
            return Err(Error::invalid(
                "lens.focus_m",
                format!(
                    "must be a finite distance beyond the focal length ({focal_mm} mm), got {} m",
                    self.focus_m
                ),
            ));
        }
        Ok(())
    }

    /// Aperture diameter, mm, for focal length `focal_mm`.
    pub fn aperture_mm(&self, focal_mm: f64) -> f64 {
        focal_mm / self.f_number
    }

    /// Diameter (mm on the sensor) of the blur disc of a point at depth `z_m` metres.
    pub fn coc_mm(&self, focal_mm: f64, z_m: f64) -> f64 {
        let (f, s, z) = (focal_mm, self.focus_m * 1000.0, z_m * 1000.0);
        self.aperture_mm(f) * f / (s - f) * (z - s).abs() / z
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn in_focus_is_sharp_and_far_tends_to_the_limit() {
        let l = Lens {
            f_number: 2.0,
            focus_m: 1.0,
        };
        assert_eq!(l.coc_mm(4.0, 1.0), 0.0);
        // z -> infinity: c -> A f / (s - f).
        let lim = 2.0 * 4.0 / (1000.0 - 4.0);
        assert!((l.coc_mm(4.0, 1e9) - lim).abs() < 1e-9);
        assert!(l.validate(4.0).is_ok());
        assert!(Lens { f_number: 0.0, ..l }.validate(4.0).is_err());
        assert!(Lens {
            focus_m: 0.001,
            ..l
        }
        .validate(4.0)
        .is_err());
    }
}
