//! OpenCV's fisheye model (Kannala-Brandt) in the radial form Gyroflow's
//! `opencv_fisheye` uses: `theta_d = theta (1 + k1 theta^2 + k2 theta^4 +
//! k3 theta^6 + k4 theta^8)`, `theta` the ray's angle to the axis (rad),
//! `theta_d` the distorted radius in normalised units.
//!
//! The model is one-to-one only up to its turning point (the first angle
//! where `d theta_d / d theta = 0`) and, as a pinhole ray `(x, y, 1)`, below
//! 90 degrees: [`limit`] is the distorted radius there, Gyroflow's radial
//! distortion limit. Pixels beyond it have no ray ([`solve`] gives `None`).

/// The largest angle a pinhole ray `(x, y, 1)` can have, rad (just under 90 degrees).
pub const THETA_MAX: f64 = std::f64::consts::FRAC_PI_2 - 1e-9;

/// `theta_d(theta)`, normalised units.
#[inline]
pub fn theta_d(k: [f64; 4], th: f64) -> f64 {
    let t2 = th * th;
    th * (1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3]))))
}

/// `d theta_d / d theta` (dimensionless).
#[inline]
pub fn slope(k: [f64; 4], th: f64) -> f64 {
    let t2 = th * th;
    1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])))
}

/// The angle (rad) up to which `theta_d` grows: the first zero of its slope
/// in `(0, THETA_MAX]` (a scan of 64 steps, then bisection to 1e-15 rad),
/// or `THETA_MAX` when the slope stays positive.
pub fn turning_point(k: [f64; 4]) -> f64 {
    first_slope_zero(64, |th| slope(k, th))
}

/// The first zero of `slope` in `(0, THETA_MAX]`: a scan of `steps` equal
/// steps to the first one where it is `<= 0` or NaN, then bisection to
/// 1e-15 rad; `THETA_MAX` when it stays positive. Shared by every radial
/// model's turning point.
pub fn first_slope_zero(steps: u32, slope: impl Fn(f64) -> f64) -> f64 {
    let mut lo = 0.0;
    for i in 1..=steps {
        let hi = THETA_MAX * i as f64 / steps as f64;
        let d = slope(hi);
        if d <= 0.0 || d.is_nan() {
            let mut hi = hi;
            while hi - lo > 1e-15 {
                let mid = 0.5 * (lo + hi);
                if slope(mid) > 0.0 {
                    lo = mid;
                } else {
                    hi = mid;
                }
            }
            return lo;
        }
        lo = hi;
    }
    THETA_MAX
}

/// The radial distortion limit: the largest distorted radius (normalised
/// units) with a ray, `theta_d` at the [`turning_point`].
pub fn limit(k: [f64; 4]) -> f64 {
    theta_d(k, turning_point(k))
}

/// The angle `theta` (rad) with `theta_d(theta) = rd` on `[0, turning
/// point]`: [`super::newton::solve_rising`] (Newton safeguarded by bisection), to
/// `tol` in `theta_d`. `None` when `rd` lies beyond the [`limit`] (no ray).
pub fn solve(k: [f64; 4], rd: f64, tol: f64) -> Option<f64> {
    let top = turning_point(k);
    if rd.is_nan() || rd < 0.0 || theta_d(k, top) < rd - tol {
        return None;
    }
    Some(super::newton::solve_rising(
        |th| theta_d(k, th),
        |th| slope(k, th),
        rd,
        top,
        rd,
        tol,
        200,
    ))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn turning_point_is_where_the_slope_vanishes() {
        // theta_d = theta - theta^3 / 3: slope 1 - theta^2, zero at 1 rad.
        let k = [-1.0 / 3.0, 0.0, 0.0, 0.0];
        assert!((turning_point(k) - 1.0).abs() < 1e-12);
        assert!((limit(k) - 2.0 / 3.0).abs() < 1e-12);
        assert_eq!(turning_point([0.0; 4]), THETA_MAX);
    }

    #[test]
    fn solve_finds_the_first_branch_and_refuses_beyond_the_limit() {
        let k = [-1.0 / 3.0, 0.0, 0.0, 0.0];
        for &rd in &[1e-6, 0.1, 0.5, 0.66, 2.0 / 3.0 - 1e-9] {
            let th = solve(k, rd, 1e-14).expect("has a preimage");
            assert!(
                th <= 1.0 && (theta_d(k, th) - rd).abs() <= 1e-14,
                "{rd}: {th}"
            );
        }
        assert_eq!(solve(k, 0.7, 1e-14), None);
        // theta + theta^3 - 0.8 theta^5 (turning point 1 rad): plain Newton from
        // r_d ping-pongs across the bracket here.
        let k = [1.0, -0.8, 0.0, 0.0];
        let rd = 0.7075f64.hypot(0.6725);
        let th = solve(k, rd, 1e-14).unwrap();
        assert!((theta_d(k, th) - rd).abs() <= 1e-14 && th < 1.0);
    }
}
