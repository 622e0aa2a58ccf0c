//! Gyroflow's digital lenses: a warp the camera applies to its optical image
//! before recording (GoPro's SuperView and HyperView, a plain stretch). In
//! Gyroflow the recorded pixel is the warp of the optical pixel
//! `K distort(ray)`, in the video's centred coordinates `c = pixel / size -
//! 0.5` (`c` in `[-0.5, 0.5]` over the frame). Each warp is given, as in
//! Gyroflow, from the recorded to the optical ("wide") image, [`to_wide`],
//! explicitly; the other way is its inverse (Newton's method, [`to_recorded`]).
//!
//! - `gopro_superview`: `w = superview(c)`, then `w_x /= 4/3`, with
//!   `superview(x, y) = (x (1.2100393 - 1.2758402 x^2 + 1.7751845 x^4),
//!   y (0.9364505 + 0.4465308 y^2 - 0.7683315 y^4 + (-0.3574087 + 1.1584653 y^2
//!   + 0.3529348 x^2) x^2))`;
//! - `gopro6_superview`: `x' = x (1 - 0.48 |x|)`, `w_x = 0.943396 x' (1 +
//!   0.157895 |x'|)`, `w_y = 0.943396 y (1 + 0.06 |2 y|)`;
//! - `gopro_hyperview`: `w_x = x (1.5805143 + x^2 (-8.1668825 + x^2 (74.5198746
//!   + x^2 (-451.5002441 + x^2 (1551.2922363 + x^2 (-2735.5422363 + x^2
//!     1923.1572266))))) - 0.1086027 y^2) / 1.555555555`, `w_y = y (1.0238225 -
//!     0.1025671 y^2 + x^2 (-0.2639930 + 0.2979266 x^2))`;
//! - `gopro_warp`: GoPro's in-camera MAPX/MAPY polynomials from
//!   `digital_lens_params` (`p[0..8]` for x, `p[8..14]` for y, `p[14]` the
//!   horizontal factor), argument clamped to the frame and continued with
//!   slope 1 beyond it, as Gyroflow;
//! - `digital_stretch`: the optical pixel times `(p[0], p[1])`.
//!
//! The centred coordinate of a distorted normalised point `(x_d, y_d)` is
//! `c = (ax x_d + ox, ay y_d + oy)` with `ax = fx / W`, `ox = cx / W - 0.5`
//! (and the same in y), the camera's at its video size ([`Warp`]).

use serde::{Deserialize, Serialize};

/// Gyroflow's digital lens names.
#[derive(Debug, Clone, Copy, PartialEq, Eq, Serialize, Deserialize)]
#[serde(rename_all = "snake_case")]
pub enum Lens {
    /// `gopro_superview`.
    GoproSuperview,
    /// `gopro6_superview`.
    Gopro6Superview,
    /// `gopro_hyperview`.
    GoproHyperview,
    /// `gopro_warp` (GoPro's MAPX/MAPY polynomials in `params`).
    GoproWarp,
    /// `digital_stretch` (`params[0]`, `params[1]`).
    DigitalStretch,
}

impl Lens {
    /// Gyroflow's name of the lens.
    pub fn name(self) -> &'static str {
        match self {
            Lens::GoproSuperview => "gopro_superview",
            Lens::Gopro6Superview => "gopro6_superview",
            Lens::GoproHyperview => "gopro_hyperview",
            Lens::GoproWarp => "gopro_warp",
            Lens::DigitalStretch => "digital_stretch",
        }
    }

    /// The lens of a Gyroflow name.
    pub fn from_name(s: &str) -> Option<Self> {
        [
            Lens::GoproSuperview,
            Lens::Gopro6Superview,
            Lens::GoproHyperview,
            Lens::GoproWarp,
            Lens::DigitalStretch,
        ]
        .into_iter()
        .find(|l| l.name() == s)
    }
}

/// A digital lens on a camera: the warp and where the optical image lies in
/// the video's centred coordinates.
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Warp {
    /// The warp.
    pub lens: Lens,
    /// Gyroflow's `digital_lens_params` (zeros when absent).
    #[serde(default)]
    pub params: [f64; 16],
    /// `[ax, ay, ox, oy]`: `c = (ax x_d + ox, ay y_d + oy)` (`fx / W`, `fy / H`,
    /// `cx / W - 0.5`, `cy / H - 0.5`).
    pub frame: [f64; 4],
}

type Jac = [[f64; 2]; 2];

const SUPERVIEW_FACTOR: f64 = 1.333333333;
const HYPERVIEW_FACTOR: f64 = 1.555555555;

fn superview(x: f64, y: f64) -> ((f64, f64), Jac) {
    let (x2, y2) = (x * x, y * y);
    let px = 1.2100393 + x2 * (-1.2758402 + x2 * 1.7751845);
    let dpx = x2 * (-2.0 * 1.2758402 + 4.0 * 1.7751845 * x2); // x dpx/dx
    let py = 0.9364505
        + (0.4465308 - 0.7683315 * y2) * y2
        + (-0.3574087 + 1.1584653 * y2 + 0.3529348 * x2) * x2;
    let py_x = 2.0 * x * (-0.3574087 + 1.1584653 * y2 + 2.0 * 0.3529348 * x2);
    let py_y = 2.0 * y * (0.4465308 - 2.0 * 0.7683315 * y2 + 1.1584653 * x2);
    let f = SUPERVIEW_FACTOR;
    (
        (x * px / f, y * py),
        [[(px + dpx) / f, 0.0], [y * py_x, py + y * py_y]],
    )
}

fn superview6(x: f64, y: f64) -> ((f64, f64), Jac) {
    let x1 = x * (1.0 - 0.48 * x.abs());
    let dx1 = 1.0 - 0.96 * x.abs();
    let wx = 0.943396 * x1 * (1.0 + 0.157895 * x1.abs());
    let dwx = 0.943396 * (1.0 + 2.0 * 0.157895 * x1.abs()) * dx1;
    let wy = 0.943396 * y * (1.0 + 0.06 * (2.0 * y).abs());
    let dwy = 0.943396 * (1.0 + 0.24 * y.abs());
    ((wx, wy), [[dwx, 0.0], [0.0, dwy]])
}

fn hyperview(x: f64, y: f64) -> ((f64, f64), Jac) {
    let (x2, y2) = (x * x, y * y);
    const C: [f64; 7] = [
        1.5805143,
        -8.1668825,
        74.5198746,
        -451.5002441,
        1551.2922363,
        -2735.5422363,
        1923.1572266,
    ];
    let (mut p, mut dp) = (0.0, 0.0); // polynomial in x2 and its x2-derivative
    for &c in C.iter().rev() {
        dp = dp * x2 + p;
        p = p * x2 + c;
    }
    let px = p - 0.1086027 * y2;
    let py = 1.0238225 - 0.1025671 * y2 + x2 * (-0.2639930 + 0.2979266 * x2);
    let f = HYPERVIEW_FACTOR;
    (
        (x * px / f, y * py),
        [
            [(px + 2.0 * x2 * dp) / f, -2.0 * 0.1086027 * x * y / f],
            [
                y * x * (2.0 * -0.2639930 + 4.0 * 0.2979266 * x2),
                py - 2.0 * 0.1025671 * y2,
            ],
        ],
    )
}

fn gopro_warp(p: &[f64; 16], u: f64, v: f64) -> ((f64, f64), Jac) {
    let (x, y) = (u.clamp(-0.5, 0.5), v.clamp(-0.5, 0.5));
    let (ix, iy) = (
        if x == u { 1.0 } else { 0.0 },
        if y == v { 1.0 } else { 0.0 },
    );
    let (x2, y2) = (x * x, y * y);
    let (mut px, mut dpx) = (0.0, 0.0);
    for &c in p[..7].iter().rev() {
        dpx = dpx * x2 + px;
        px = px * x2 + c;
    }
    let f = if p[14] != 0.0 { p[14] } else { 1.0 };
    let wx = x * (px + p[7] * y2) + (u - x);
    let qy = p[8] + p[9] * y2 + p[10] * y2 * y2 + x2 * (p[11] + p[12] * y2 + p[13] * x2);
    let wy = y * qy + (v - y);
    let dwx_dx = px + 2.0 * x2 * dpx + p[7] * y2;
    let dwx_dy = 2.0 * x * y * p[7];
    let dwy_dx = y * x * (2.0 * p[11] + 2.0 * p[12] * y2 + 4.0 * p[13] * x2);
    let dwy_dy = qy + y2 * (2.0 * p[9] + 4.0 * p[10] * y2 + 2.0 * p[12] * x2);
    (
        (wx / f, wy),
        [
            [(ix * dwx_dx + (1.0 - ix)) / f, iy * dwx_dy / f],
            [ix * dwy_dx, iy * dwy_dy + (1.0 - iy)],
        ],
    )
}

/// The warp from the recorded frame to the optical image in centred
/// coordinates, and its Jacobian there.
pub fn to_wide(lens: Lens, p: &[f64; 16], c: (f64, f64)) -> ((f64, f64), Jac) {
    match lens {
        Lens::GoproSuperview => superview(c.0, c.1),
        Lens::Gopro6Superview => superview6(c.0, c.1),
        Lens::GoproHyperview => hyperview(c.0, c.1),
        Lens::GoproWarp => gopro_warp(p, c.0, c.1),
        Lens::DigitalStretch => (
            ((c.0 + 0.5) / p[0] - 0.5, (c.1 + 0.5) / p[1] - 0.5),
            [[1.0 / p[0], 0.0], [0.0, 1.0 / p[1]]],
        ),
    }
}

/// The recorded point `c` whose [`to_wide`] is `w` (Newton's method from
/// `w`, to 1e-14); NaN where it does not converge.
pub fn to_recorded(lens: Lens, p: &[f64; 16], w: (f64, f64)) -> (f64, f64) {
    let mut c = w;
    for _ in 0..60 {
        let ((fx, fy), j) = to_wide(lens, p, c);
        let (ex, ey) = (fx - w.0, fy - w.1);
        if ex.hypot(ey) < 1e-14 {
            return c;
        }
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if det.is_nan() || det.abs() <= 1e-300 {
            break;
        }
        c.0 -= (j[1][1] * ex - j[0][1] * ey) / det;
        c.1 -= (-j[1][0] * ex + j[0][0] * ey) / det;
    }
    let ((fx, fy), _) = to_wide(lens, p, c);
    if (fx - w.0).hypot(fy - w.1) < 1e-12 {
        c
    } else {
        (f64::NAN, f64::NAN)
    }
}

impl Warp {
    /// The recorded (video) normalised point of the optical distorted point
    /// `(xd, yd)`, and the Jacobian of that map there.
    pub fn record(&self, xd: f64, yd: f64) -> ((f64, f64), Jac) {
        let [ax, ay, ox, oy] = self.frame;
        let w = (ax * xd + ox, ay * yd + oy);
        let c = to_recorded(self.lens, &self.params, w);
        let (_, j) = to_wide(self.lens, &self.params, c);
        // d(recorded)/d(optical) = S^-1 J^-1 S, S = diag(ax, ay).
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        let inv = [
            [j[1][1] / det, -j[0][1] / det],
            [-j[1][0] / det, j[0][0] / det],
        ];
        (
            ((c.0 - ox) / ax, (c.1 - oy) / ay),
            [
                [inv[0][0], inv[0][1] * ay / ax],
                [inv[1][0] * ax / ay, inv[1][1]],
            ],
        )
    }

    /// The optical distorted point seen at the recorded normalised point `(xv, yv)`.
    pub fn unrecord(&self, xv: f64, yv: f64) -> (f64, f64) {
        let [ax, ay, ox, oy] = self.frame;
        let ((wx, wy), _) = to_wide(self.lens, &self.params, (ax * xv + ox, ay * yv + oy));
        ((wx - ox) / ax, (wy - oy) / ay)
    }

    /// The warp on the camera turned to the other orientation (the frame's
    /// axes swap; the warp stays in the video's axes, as Gyroflow applies it).
    pub fn transposed(&self) -> Self {
        let [ax, ay, ox, oy] = self.frame;
        Warp {
            frame: [ay, ax, oy, ox],
            ..*self
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn lenses() -> Vec<(Lens, [f64; 16])> {
        let mut warp = [0.0; 16];
        // A GoPro-like MAPX/MAPY: near SuperView's first terms.
        warp[0] = 1.21;
        warp[1] = -1.27;
        warp[2] = 1.77;
        warp[7] = 0.01;
        warp[8] = 0.93;
        warp[9] = 0.44;
        warp[11] = -0.35;
        warp[14] = 4.0 / 3.0;
        let mut stretch = [0.0; 16];
        stretch[0] = 1.2;
        stretch[1] = 0.9;
        vec![
            (Lens::GoproSuperview, [0.0; 16]),
            (Lens::Gopro6Superview, [0.0; 16]),
            (Lens::GoproHyperview, [0.0; 16]),
            (Lens::GoproWarp, warp),
            (Lens::DigitalStretch, stretch),
        ]
    }

    #[test]
    fn jacobians_match_finite_differences_and_inverse_round_trips() {
        let h = 1e-7;
        for (lens, p) in lenses() {
            for &(x, y) in &[(0.1, -0.2), (-0.45, 0.3), (0.3, 0.45), (-0.2, -0.05)] {
                let (_, j) = to_wide(lens, &p, (x, y));
                let (a, b) = (
                    to_wide(lens, &p, (x + h, y)).0,
                    to_wide(lens, &p, (x - h, y)).0,
                );
                let (c, d) = (
                    to_wide(lens, &p, (x, y + h)).0,
                    to_wide(lens, &p, (x, y - h)).0,
                );
                let fd = [
                    [(a.0 - b.0) / (2.0 * h), (c.0 - d.0) / (2.0 * h)],
                    [(a.1 - b.1) / (2.0 * h), (c.1 - d.1) / (2.0 * h)],
                ];
                for r in 0..2 {
                    for q in 0..2 {
                        assert!(
                            (j[r][q] - fd[r][q]).abs() < 1e-6,
                            "{lens:?} ({x},{y}) [{r}][{q}]"
                        );
                    }
                }
                let w = to_wide(lens, &p, (x, y)).0;
                let back = to_recorded(lens, &p, w);
                assert!((back.0 - x).hypot(back.1 - y) < 1e-12, "{lens:?}: {back:?}");
            }
        }
    }

    #[test]
    fn names_round_trip() {
        for (lens, _) in lenses() {
            assert_eq!(Lens::from_name(lens.name()), Some(lens));
        }
        assert_eq!(Lens::from_name("gopro_linear"), None);
    }
}
