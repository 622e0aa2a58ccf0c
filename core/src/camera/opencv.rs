//! OpenCV's standard model with all 12 of Gyroflow's `opencv_standard`
//! coefficients `k = [k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4]`
//! (OpenCV's order): rational radial, tangential and thin prism terms, in
//! normalised coordinates, `r^2 = x^2 + y^2`:
//!
//! ```text
//! R   = (1 + k1 r^2 + k2 r^4 + k3 r^6) / (1 + k4 r^2 + k5 r^4 + k6 r^6)
//! x_d = x R + 2 p1 x y + p2 (r^2 + 2 x^2) + s1 r^2 + s2 r^4
//! y_d = y R + p1 (r^2 + 2 y^2) + 2 p2 x y + s3 r^2 + s4 r^4
//! ```
//!
//! With `k4 = k5 = k6 = s1..s4 = 0` this is the five-coefficient
//! Brown-Conrady model (`Distortion::Opencv`).

/// A 2x2 Jacobian, row-major (the same type as `distortion::Jac`, which uses this file).
type Jac = [[f64; 2]; 2];

/// The distorted point `(x_d, y_d)` of the pinhole point `(x, y)`.
#[inline]
pub fn distort(k: &[f64; 12], x: f64, y: f64) -> (f64, f64) {
    let [k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4] = *k;
    let r2 = x * x + y * y;
    let num = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    let den = 1.0 + r2 * (k4 + r2 * (k5 + r2 * k6));
    let radial = num / den;
    (
        x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x) + r2 * (s1 + r2 * s2),
        y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y + r2 * (s3 + r2 * s4),
    )
}

/// The Jacobian of [`distort`] at `(x, y)` (derived by hand: `dR/d(r^2) =
/// (N' D - N D') / D^2`, `d(r^2)/dx = 2 x`).
#[inline]
pub fn jacobian(k: &[f64; 12], x: f64, y: f64) -> Jac {
    let [k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4] = *k;
    let r2 = x * x + y * y;
    let num = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    let den = 1.0 + r2 * (k4 + r2 * (k5 + r2 * k6));
    let dnum = k1 + r2 * (2.0 * k2 + r2 * 3.0 * k3);
    let dden = k4 + r2 * (2.0 * k5 + r2 * 3.0 * k6);
    let radial = num / den;
    let drad = (dnum * den - num * dden) / (den * den); // d R / d r^2
    let dpx = s1 + 2.0 * s2 * r2; // d (s1 r^2 + s2 r^4) / d r^2
    let dpy = s3 + 2.0 * s4 * r2;
    [
        [
            radial + 2.0 * x * x * drad + 2.0 * p1 * y + 6.0 * p2 * x + 2.0 * x * dpx,
            2.0 * x * y * drad + 2.0 * p1 * x + 2.0 * p2 * y + 2.0 * y * dpx,
        ],
        [
            2.0 * x * y * drad + 2.0 * p1 * x + 2.0 * p2 * y + 2.0 * x * dpy,
            radial + 2.0 * y * y * drad + 6.0 * p1 * y + 2.0 * p2 * x + 2.0 * y * dpy,
        ],
    ]
}

#[cfg(test)]
mod tests {
    use super::*;

    const K: [f64; 12] = [
        -0.21, 0.05, 0.0012, -0.0009, -0.004, 0.08, -0.02, 0.006, 0.0021, -0.0007, -0.0015, 0.0004,
    ];

    #[test]
    fn each_term_as_written() {
        // Only k4: x R with R = 1 / (1 + k4 r^2).
        let mut k = [0.0; 12];
        k[5] = 0.5;
        let (xd, yd) = distort(&k, 0.3, 0.4);
        assert!((xd - 0.3 / 1.125).abs() < 1e-15 && (yd - 0.4 / 1.125).abs() < 1e-15);
        // Only s1 and s4: x + s1 r^2, y + s4 r^4.
        let mut k = [0.0; 12];
        k[8] = 0.1;
        k[11] = 0.2;
        let (xd, yd) = distort(&k, 0.3, 0.4);
        assert!((xd - (0.3 + 0.1 * 0.25)).abs() < 1e-15);
        assert!((yd - (0.4 + 0.2 * 0.0625)).abs() < 1e-15);
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let h = 1e-6;
        for &(x, y) in &[(0.3, -0.2), (-0.5, 0.4), (0.0, 0.0), (0.6, 0.45)] {
            let j = jacobian(&K, x, y);
            let (a, b) = (distort(&K, x + h, y), distort(&K, x - h, y));
            let (c, e) = (distort(&K, x, y + h), distort(&K, x, y - h));
            let fd = [
                [(a.0 - b.0) / (2.0 * h), (c.0 - e.0) / (2.0 * h)],
                [(a.1 - b.1) / (2.0 * h), (c.1 - e.1) / (2.0 * h)],
            ];
            for r in 0..2 {
                for q in 0..2 {
                    assert!((j[r][q] - fd[r][q]).abs() < 1e-8, "({x},{y}) [{r}][{q}]");
                }
            }
        }
    }
}
