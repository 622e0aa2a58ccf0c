//! Gyroflow's `ptlens` (LensFun's PTLens): `x_d = x (1 + c r + b r^2 + a r^3)`,
//! `r` the pinhole radius (normalised units), `distortion_coeffs = [a, b, c]`.
//! Radial: `super::radial` gives its inverse and limit.

use super::radial::Profile;

/// The `ptlens` model's `[a, b, c]` (Gyroflow's order).
#[derive(Debug, Clone, Copy)]
pub struct Ptlens(pub [f64; 3]);

impl Profile for Ptlens {
    #[inline]
    fn s(&self, r: f64) -> (f64, f64) {
        let [a, b, c] = self.0;
        (
            1.0 + r * (c + r * (b + r * a)),
            c + r * (2.0 * b + 3.0 * a * r),
        )
    }
}
