//! Radial lens models in the pinhole radius `r = |(x, y)|` (normalised
//! units): the distorted point is `s(r) (x, y)`. Shared by Gyroflow's
//! `poly3`, `poly5`, `ptlens`, `sony` and `generic_polynomial`
//! (files `poly3.rs`, `poly5.rs`, `ptlens.rs`, `sony.rs`), each of which
//! gives its `s(r)` and `ds/dr` ([`Profile`]).
//!
//! The model is one-to-one only up to its turning point, the first ray
//! angle `theta = atan r` (rad) where `d(r s(r))/dr <= 0`, and below 90
//! degrees; [`limit`] is the distorted radius there, the radial distortion
//! limit (infinite when the distorted radius grows without bound). The
//! inverse [`solve`] is `super::newton::solve_rising` in `theta` (Newton safeguarded by bisection)
//! on `[0, turning point]`, as for the fisheye.

use super::fisheye::THETA_MAX;

/// A radial model: `s(r)` and `ds/dr` at the pinhole radius `r >= 0`.
pub trait Profile {
    /// `(s, ds/dr)` at `r`.
    fn s(&self, r: f64) -> (f64, f64);
}

/// The distorted point of the pinhole point `(x, y)`.
#[inline]
pub fn distort(p: &dyn Profile, x: f64, y: f64) -> (f64, f64) {
    let s = p.s(x.hypot(y)).0;
    (s * x, s * y)
}

/// The Jacobian of [`distort`] at `(x, y)`: `s I + (ds/dr) (x x^T) / r`
/// (`s(0) I` on the axis).
#[inline]
pub fn jacobian(p: &dyn Profile, x: f64, y: f64) -> [[f64; 2]; 2] {
    let r = x.hypot(y);
    let (s, ds) = p.s(r);
    if r == 0.0 {
        return [[s, 0.0], [0.0, s]];
    }
    let q = ds / r;
    [[s + q * x * x, q * x * y], [q * x * y, s + q * y * y]]
}

/// Distorted radius at the ray angle `th` (rad).
fn rd(p: &dyn Profile, th: f64) -> f64 {
    let r = th.tan();
    r * p.s(r).0
}

/// `d rd / d theta` at `th`.
fn slope(p: &dyn Profile, th: f64) -> f64 {
    let r = th.tan();
    let (s, ds) = p.s(r);
    (s + r * ds) * (1.0 + r * r)
}

/// The ray angle (rad) up to which the distorted radius grows: the first
/// zero of its slope in `(0, THETA_MAX]` (a scan of 256 steps, then
/// bisection to 1e-15 rad), or `THETA_MAX`.
pub fn turning_point(p: &dyn Profile) -> f64 {
    super::fisheye::first_slope_zero(256, |th| slope(p, th))
}

/// The radial distortion limit (normalised distorted radius): the distorted
/// radius at the [`turning_point`]; infinite when there is none and the
/// radius at 90 degrees is beyond 1e12 (it grows without bound).
pub fn limit(p: &dyn Profile) -> f64 {
    let top = turning_point(p);
    let v = rd(p, top);
    if top == THETA_MAX && !(v.is_finite() && v < 1e12) {
        f64::INFINITY
    } else {
        v
    }
}

/// The pinhole radius `r` with `r s(r) = target` on the first branch, to
/// `tol` in the distorted radius; `None` beyond the [`limit`].
pub fn solve(p: &dyn Profile, target: f64, tol: f64) -> Option<f64> {
    let top = turning_point(p);
    if target.is_nan() || target < 0.0 || rd(p, top) < target - tol {
        return None;
    }
    // Start at the pinhole angle of the target (the model is near identity there).
    let th = super::newton::solve_rising(
        |th| rd(p, th),
        |th| slope(p, th),
        target,
        top,
        target.atan(),
        tol,
        300,
    );
    Some(th.tan())
}

#[cfg(test)]
mod tests {
    use super::*;

    /// `s = 1 - r^2 / 3`: `rd = r - r^3 / 3`, turning point at `r = 1`.
    struct Cubic;
    impl Profile for Cubic {
        fn s(&self, r: f64) -> (f64, f64) {
            (1.0 - r * r / 3.0, -2.0 * r / 3.0)
        }
    }

    #[test]
    fn turning_point_limit_and_solve() {
        let top = turning_point(&Cubic);
        assert!((top.tan() - 1.0).abs() < 1e-12, "{}", top.tan());
        assert!((limit(&Cubic) - 2.0 / 3.0).abs() < 1e-12);
        for &t in &[1e-9, 0.1, 0.5, 0.66] {
            let r = solve(&Cubic, t, 1e-15).unwrap();
            assert!(
                r <= 1.0 && (r - r * r * r / 3.0 - t).abs() < 1e-14,
                "{t}: {r}"
            );
        }
        assert_eq!(solve(&Cubic, 0.7, 1e-15), None);
    }
}
