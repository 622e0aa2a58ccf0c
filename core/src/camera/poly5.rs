//! Gyroflow's `poly5` (LensFun's): `x_d = x (1 + k1 r^2 + k2 r^4)`, `r` the
//! pinhole radius (normalised units), `k1, k2` (`distortion_coeffs[0..2]`).
//! Radial: `super::radial` gives its inverse and limit.

use super::radial::Profile;

/// The `poly5` model's `[k1, k2]`.
#[derive(Debug, Clone, Copy)]
pub struct Poly5(pub [f64; 2]);

impl Profile for Poly5 {
    #[inline]
    fn s(&self, r: f64) -> (f64, f64) {
        let [k1, k2] = self.0;
        let r2 = r * r;
        (1.0 + r2 * (k1 + k2 * r2), r * (2.0 * k1 + 4.0 * k2 * r2))
    }
}
