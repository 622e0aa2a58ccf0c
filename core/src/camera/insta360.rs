//! Gyroflow's `insta360` model: the unified (Mei) projection with `xi`, then
//! OpenCV's radial and tangential terms. With `distortion_coeffs = [k1, k2,
//! k3, p1, p2, xi]`, the ray `(x, y, 1)` of length `l = sqrt(1 + r^2)`:
//!
//! ```text
//! (x', y') = (x, y) / (1 + xi l)
//! x_d = x' R + 2 p1 x' y' + p2 (r'^2 + 2 x'^2),   R = 1 + k1 r'^2 + k2 r'^4 + k3 r'^6
//! y_d = y' R + 2 p2 x' y' + p1 (r'^2 + 2 y'^2)
//! ```
//!
//! Not radial (the tangential terms); its inverse is the general Newton
//! iteration of `Distortion::undistort`, and it has no radial limit (as in
//! Gyroflow). The Jacobian is the product of the two stages' (by hand).

/// The unified stage: `m = 1 / (1 + xi l)` and `(dm/dr) / r`.
#[inline]
fn unified(xi: f64, x: f64, y: f64) -> (f64, f64) {
    let l = (1.0 + x * x + y * y).sqrt();
    let m = 1.0 / (1.0 + xi * l);
    (m, -xi * m * m / l)
}

/// The distorted point of the pinhole point `(x, y)`; `k = [k1, k2, k3, p1, p2, xi]`.
#[inline]
pub fn distort(k: &[f64; 6], x: f64, y: f64) -> (f64, f64) {
    let [k1, k2, k3, p1, p2, xi] = *k;
    let m = unified(xi, x, y).0;
    let (x, y) = (m * x, m * y);
    let r2 = x * x + y * y;
    let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    (
        x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
        y * radial + 2.0 * p2 * x * y + p1 * (r2 + 2.0 * y * y),
    )
}

/// The Jacobian of [`distort`] at `(x, y)`.
#[inline]
pub fn jacobian(k: &[f64; 6], x: f64, y: f64) -> [[f64; 2]; 2] {
    let [k1, k2, k3, p1, p2, xi] = *k;
    let (m, q) = unified(xi, x, y);
    let ju = [[m + q * x * x, q * x * y], [q * x * y, m + q * y * y]];
    let (a, b) = (m * x, m * y);
    let r2 = a * a + b * b;
    let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
    let drad = k1 + r2 * (2.0 * k2 + r2 * 3.0 * k3);
    let jb = [
        [
            radial + 2.0 * a * a * drad + 2.0 * p1 * b + 6.0 * p2 * a,
            2.0 * a * b * drad + 2.0 * p1 * a + 2.0 * p2 * b,
        ],
        [
            2.0 * a * b * drad + 2.0 * p2 * b + 2.0 * p1 * a,
            radial + 2.0 * b * b * drad + 2.0 * p2 * a + 6.0 * p1 * b,
        ],
    ];
    [
        [
            jb[0][0] * ju[0][0] + jb[0][1] * ju[1][0],
            jb[0][0] * ju[0][1] + jb[0][1] * ju[1][1],
        ],
        [
            jb[1][0] * ju[0][0] + jb[1][1] * ju[1][0],
            jb[1][0] * ju[0][1] + jb[1][1] * ju[1][1],
        ],
    ]
}
