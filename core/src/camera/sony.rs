//! Gyroflow's `sony` and `generic_polynomial` models: the distorted radius
//! (normalised units) is a polynomial in the ray's angle `theta = atan r`
//! (rad), `theta_d = k0 theta + k1 theta^2 + ... + k(n-1) theta^n` (`sony`:
//! 6 coefficients, `generic_polynomial`: 12). Radial: `super::radial` gives
//! its inverse and limit.

use super::radial::Profile;

/// A polynomial in `theta` with up to 12 coefficients (zeros past the model's count).
#[derive(Debug, Clone, Copy)]
pub struct ThetaPoly(pub [f64; 12]);

/// `atan(r) / r` and its derivative in `r` (series near the axis, where the
/// closed forms cancel).
#[inline]
fn atan_over_r(r: f64) -> (f64, f64) {
    if r < 1e-3 {
        let r2 = r * r;
        (
            1.0 + r2 * (-1.0 / 3.0 + r2 * (0.2 - r2 / 7.0)),
            r * (-2.0 / 3.0 + r2 * (0.8 - r2 * 6.0 / 7.0)),
        )
    } else {
        let a = r.atan() / r;
        (a, (1.0 / (1.0 + r * r) - a) / r)
    }
}

impl Profile for ThetaPoly {
    #[inline]
    fn s(&self, r: f64) -> (f64, f64) {
        let th = r.atan();
        // P(theta) = theta_d / theta = sum k_i theta^i, and P'.
        let (mut p, mut dp) = (0.0, 0.0);
        for i in (0..12).rev() {
            dp = dp * th + p;
            p = p * th + self.0[i];
        }
        let (a, da) = atan_over_r(r);
        (a * p, da * p + a * dp / (1.0 + r * r))
    }
}
