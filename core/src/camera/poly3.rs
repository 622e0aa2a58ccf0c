//! Gyroflow's `poly3` (LensFun's): `x_d = x (1 + k1 r^2)`, `r` the pinhole
//! radius (normalised units), one coefficient `k1` (`distortion_coeffs[0]`).
//! Radial: `super::radial` gives its inverse and limit.

use super::radial::Profile;

/// The `poly3` model's coefficient.
#[derive(Debug, Clone, Copy)]
pub struct Poly3(pub f64);

impl Profile for Poly3 {
    #[inline]
    fn s(&self, r: f64) -> (f64, f64) {
        (1.0 + self.0 * r * r, 2.0 * self.0 * r)
    }
}
