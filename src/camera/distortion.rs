//! Lens distortion (SPEC section 9): the two models users have calibrations
//! for, as maps of normalised pinhole coordinates `(x, y) = (X/Z, Y/Z)` to
//! distorted normalised coordinates `(x_d, y_d)`; pixels are then
//! `K [x_d, y_d, 1]`.
//!
//! - OpenCV / Brown-Conrady `k1, k2, p1, p2, k3`;
//! - OpenCV fisheye / Kannala-Brandt `k1..k4` (`theta_d = theta (1 + k1 theta^2 + ...)`).
//!
//! Each model has its forward map, its Jacobian (derived by hand from the
//! definitions; tests compare it with finite differences) and an iterative
//! inverse ([`Distortion::undistort`], Newton's method to [`UNDISTORT_TOL`]).

use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// Undistortion stops when the distorted point of the estimate is within this
/// distance (normalised units, i.e. `tol * f` mm or about `tol * fx` pixels)
/// of the target: 1e-12 is about 1e-9 px for a 1000 px focal length.
pub const UNDISTORT_TOL: f64 = 1e-12;
/// Newton iterations before undistortion gives up.
const MAX_ITER: usize = 60;

/// A lens distortion model. `None` (the default) is the ideal pinhole.
#[derive(Debug, Clone, Copy, PartialEq, Default, Serialize, Deserialize)]
#[serde(tag = "model", rename_all = "lowercase", deny_unknown_fields)]
pub enum Distortion {
    /// No distortion (the thesis camera).
    #[default]
    None,
    /// OpenCV's standard model (Brown-Conrady): radial `k1, k2, k3`, tangential `p1, p2`.
    Opencv {
        /// Radial coefficient of `r^2`.
        #[serde(default)]
        k1: f64,
        /// Radial coefficient of `r^4`.
        #[serde(default)]
        k2: f64,
        /// Tangential coefficient 1.
        #[serde(default)]
        p1: f64,
        /// Tangential coefficient 2.
        #[serde(default)]
        p2: f64,
        /// Radial coefficient of `r^6`.
        #[serde(default)]
        k3: f64,
    },
    /// OpenCV's standard model with all 12 coefficients of Gyroflow's
    /// `opencv_standard`, `[k1, k2, p1, p2, k3, k4, k5, k6, s1, s2, s3, s4]`
    /// (rational radial and thin prism terms, `super::opencv`). The CPU
    /// methods and the renderer take it; the GPU kernel does not.
    #[serde(rename = "opencv_standard")]
    OpencvStandard {
        /// The 12 coefficients in OpenCV's order.
        k: [f64; 12],
    },
    /// OpenCV's fisheye model (Kannala-Brandt), equidistant with a polynomial in `theta`.
    Fisheye {
        /// Coefficient of `theta^3`.
        #[serde(default)]
        k1: f64,
        /// Coefficient of `theta^5`.
        #[serde(default)]
        k2: f64,
        /// Coefficient of `theta^7`.
        #[serde(default)]
        k3: f64,
        /// Coefficient of `theta^9`.
        #[serde(default)]
        k4: f64,
    },
}

/// A 2x2 Jacobian, row-major: `[[dxd/dx, dxd/dy], [dyd/dx, dyd/dy]]`.
pub type Jac = [[f64; 2]; 2];

const IDENTITY: Jac = [[1.0, 0.0], [0.0, 1.0]];

impl Distortion {
    /// A wide-angle module's OpenCV distortion (barrel `k1..k3` with
    /// tangential `p1, p2`; the one of `tests/fixtures/camera/opencv.toml`):
    /// the example the unit tests and the benchmarks share.
    pub const WIDE_ANGLE: Distortion = Distortion::Opencv {
        k1: -0.28,
        k2: 0.07,
        p1: 0.001,
        p2: -0.0015,
        k3: -0.008,
    };

    /// Gyroflow's `opencv_standard` from its 12 coefficients: the
    /// five-coefficient [`Distortion::Opencv`] when `k4..s4` are zero (the GPU
    /// kernel takes that one), else [`Distortion::OpencvStandard`].
    pub fn opencv_standard(k: [f64; 12]) -> Self {
        if k[5..].iter().all(|&c| c == 0.0) {
            Distortion::Opencv {
                k1: k[0],
                k2: k[1],
                p1: k[2],
                p2: k[3],
                k3: k[4],
            }
        } else {
            Distortion::OpencvStandard { k }
        }
    }

    /// True for the ideal pinhole.
    pub fn is_none(&self) -> bool {
        matches!(self, Distortion::None)
    }

    /// The model's coefficients in a fixed order (`[k1, k2, p1, p2, k3]` or
    /// `[k1, k2, k3, k4, 0]`) and a model code (0 none, 1 opencv, 2 fisheye),
    /// the form the GPU kernel takes; `None` for a model the kernel does not
    /// have ([`Distortion::OpencvStandard`]).
    pub fn coefficients(&self) -> Option<(u32, [f64; 5])> {
        Some(match *self {
            Distortion::None => (0, [0.0; 5]),
            Distortion::Opencv { k1, k2, p1, p2, k3 } => (1, [k1, k2, p1, p2, k3]),
            Distortion::Fisheye { k1, k2, k3, k4 } => (2, [k1, k2, k3, k4, 0.0]),
            Distortion::OpencvStandard { .. } => return None,
        })
    }

    /// Rejects non-finite coefficients, naming the key.
    pub fn validate(&self) -> Result<()> {
        if let Distortion::OpencvStandard { k } = self {
            if let Some(i) = k.iter().position(|v| !v.is_finite()) {
                return Err(Error::invalid(
                    format!("distortion.k[{i}]"),
                    format!("must be a finite number, got {}", k[i]),
                ));
            }
            return Ok(());
        }
        let (model, c) = self.coefficients().unwrap_or((0, [0.0; 5]));
        let names: &[&str] = match model {
            1 => &["k1", "k2", "p1", "p2", "k3"],
            2 => &["k1", "k2", "k3", "k4"],
            _ => &[],
        };
        for (n, v) in names.iter().zip(c) {
            if !v.is_finite() {
                return Err(Error::invalid(
                    format!("distortion.{n}"),
                    format!("must be a finite number, got {v}"),
                ));
            }
        }
        Ok(())
    }

    /// Distorted normalised coordinates of the pinhole point `(x, y)`.
    pub fn distort(&self, x: f64, y: f64) -> (f64, f64) {
        match *self {
            Distortion::None => (x, y),
            Distortion::Opencv { k1, k2, p1, p2, k3 } => {
                let r2 = x * x + y * y;
                let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
                (
                    x * radial + 2.0 * p1 * x * y + p2 * (r2 + 2.0 * x * x),
                    y * radial + p1 * (r2 + 2.0 * y * y) + 2.0 * p2 * x * y,
                )
            }
            Distortion::OpencvStandard { k } => super::opencv::distort(&k, x, y),
            Distortion::Fisheye { .. } => {
                let s = self.fisheye_scale(x, y).0;
                (s * x, s * y)
            }
        }
    }

    /// The fisheye's `[k1, k2, k3, k4]` (zeros for the other models).
    pub fn fisheye_k(&self) -> [f64; 4] {
        match *self {
            Distortion::Fisheye { k1, k2, k3, k4 } => [k1, k2, k3, k4],
            _ => [0.0; 4],
        }
    }

    /// The radial distortion limit (normalised distorted radius) beyond
    /// which no pinhole ray is seen, Gyroflow's `radial_distortion_limit`:
    /// the fisheye's `fisheye::limit`; infinite for the other models.
    pub fn radial_limit(&self) -> f64 {
        match self {
            Distortion::Fisheye { .. } => super::fisheye::limit(self.fisheye_k()),
            _ => f64::INFINITY,
        }
    }

    /// Fisheye: `s = theta_d / r` and `(ds/dr) / r` at `(x, y)`.
    fn fisheye_scale(&self, x: f64, y: f64) -> (f64, f64) {
        let Distortion::Fisheye { k1, k2, k3, k4 } = *self else {
            return (1.0, 0.0);
        };
        let r2 = x * x + y * y;
        if r2 < 1e-6 {
            // Near the axis the closed form cancels; its series instead:
            // theta = r - r^3/3 + r^5/5, theta_d = theta + k1 theta^3 + k2 theta^5 + ...,
            // so s = 1 + c r^2 + e r^4 + h r^6 + O(r^8) (k4 enters at r^8).
            let c = k1 - 1.0 / 3.0;
            let e = 0.2 - k1 + k2;
            let h = -1.0 / 7.0 + 14.0 / 15.0 * k1 - 5.0 / 3.0 * k2 + k3;
            return (
                1.0 + r2 * (c + r2 * (e + r2 * h)),
                2.0 * c + r2 * (4.0 * e + 6.0 * h * r2),
            );
        }
        let r = r2.sqrt();
        let th = r.atan();
        let t2 = th * th;
        let poly = 1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4)));
        let thd = th * poly;
        let dthd = 1.0 + t2 * (3.0 * k1 + t2 * (5.0 * k2 + t2 * (7.0 * k3 + t2 * 9.0 * k4)));
        let s = thd / r;
        let ds_dr = (dthd / (1.0 + r2) - s) / r;
        (s, ds_dr / r)
    }

    /// Jacobian of [`Distortion::distort`] at the pinhole point `(x, y)`.
    pub fn jacobian(&self, x: f64, y: f64) -> Jac {
        match *self {
            Distortion::None => IDENTITY,
            Distortion::Opencv { k1, k2, p1, p2, k3 } => {
                let r2 = x * x + y * y;
                let radial = 1.0 + r2 * (k1 + r2 * (k2 + r2 * k3));
                let drad = k1 + r2 * (2.0 * k2 + r2 * 3.0 * k3); // d radial / d r2
                [
                    [
                        radial + 2.0 * x * x * drad + 2.0 * p1 * y + 6.0 * p2 * x,
                        2.0 * x * y * drad + 2.0 * p1 * x + 2.0 * p2 * y,
                    ],
                    [
                        2.0 * x * y * drad + 2.0 * p1 * x + 2.0 * p2 * y,
                        radial + 2.0 * y * y * drad + 6.0 * p1 * y + 2.0 * p2 * x,
                    ],
                ]
            }
            Distortion::OpencvStandard { k } => super::opencv::jacobian(&k, x, y),
            Distortion::Fisheye { .. } => {
                let (s, g) = self.fisheye_scale(x, y);
                [[s + g * x * x, g * x * y], [g * x * y, s + g * y * y]]
            }
        }
    }

    /// The pinhole point whose distorted image is `(xd, yd)`, by Newton's
    /// method from `(xd, yd)` to `UNDISTORT_TOL`; `None` when it does not
    /// converge (the model folds over or the point is outside its range).
    pub fn undistort(&self, xd: f64, yd: f64) -> Option<(f64, f64)> {
        if self.is_none() {
            return Some((xd, yd));
        }
        if let Distortion::Fisheye { .. } = *self {
            // Radial: solve theta_d(theta) = r_d for theta on [0, the turning point].
            let rd = (xd * xd + yd * yd).sqrt();
            if rd == 0.0 {
                return Some((0.0, 0.0));
            }
            let th = super::fisheye::solve(self.fisheye_k(), rd, UNDISTORT_TOL * 1e-2)?;
            let r = th.tan();
            let (x, y) = (xd * r / rd, yd * r / rd);
            return self.converged(x, y, xd, yd);
        }
        let (mut x, mut y) = (xd, yd);
        for _ in 0..MAX_ITER {
            let (fx, fy) = self.distort(x, y);
            let (ex, ey) = (fx - xd, fy - yd);
            if ex.hypot(ey) < UNDISTORT_TOL * 1e-2 {
                break;
            }
            let j = self.jacobian(x, y);
            let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
            if det.abs() < 1e-300 || !det.is_finite() {
                return None;
            }
            x -= (j[1][1] * ex - j[0][1] * ey) / det;
            y -= (-j[1][0] * ex + j[0][0] * ey) / det;
        }
        self.converged(x, y, xd, yd)
    }

    fn converged(&self, x: f64, y: f64, xd: f64, yd: f64) -> Option<(f64, f64)> {
        let (fx, fy) = self.distort(x, y);
        let ok = x.is_finite() && y.is_finite() && (fx - xd).hypot(fy - yd) <= UNDISTORT_TOL;
        ok.then_some((x, y))
    }
}

/// `J v` for a 2x2 Jacobian.
#[inline]
pub fn apply(j: &Jac, v: (f64, f64)) -> (f64, f64) {
    (j[0][0] * v.0 + j[0][1] * v.1, j[1][0] * v.0 + j[1][1] * v.1)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn models() -> Vec<Distortion> {
        vec![
            Distortion::WIDE_ANGLE,
            Distortion::Opencv {
                k1: 0.12,
                k2: -0.03,
                p1: 0.0,
                p2: 0.0,
                k3: 0.0,
            },
            Distortion::Fisheye {
                k1: 0.031,
                k2: 0.06,
                k3: -0.05,
                k4: 0.012,
            },
        ]
    }

    #[test]
    fn jacobian_matches_finite_differences() {
        let h = 1e-6;
        for d in models() {
            for &(x, y) in &[
                (0.3, -0.2),
                (-0.5, 0.4),
                (0.01, 0.02),
                (0.0, 0.0),
                (0.6, 0.45),
            ] {
                let j = d.jacobian(x, y);
                let (a, b) = (d.distort(x + h, y), d.distort(x - h, y));
                let (c, e) = (d.distort(x, y + h), d.distort(x, y - h));
                let fd = [
                    [(a.0 - b.0) / (2.0 * h), (c.0 - e.0) / (2.0 * h)],
                    [(a.1 - b.1) / (2.0 * h), (c.1 - e.1) / (2.0 * h)],
                ];
                for r in 0..2 {
                    for k in 0..2 {
                        assert!(
                            (j[r][k] - fd[r][k]).abs() < 1e-7,
                            "{d:?} at ({x},{y}) J[{r}][{k}] = {} vs {}",
                            j[r][k],
                            fd[r][k]
                        );
                    }
                }
            }
        }
    }

    #[test]
    fn undistort_round_trip() {
        for d in models() {
            let mut worst: f64 = 0.0;
            for i in 0..=20 {
                for k in 0..=20 {
                    let (x, y) = (-0.7 + 0.07 * i as f64, -0.5 + 0.05 * k as f64);
                    let (xd, yd) = d.distort(x, y);
                    let (ux, uy) = d.undistort(xd, yd).expect("converges");
                    worst = worst.max((ux - x).hypot(uy - y));
                }
            }
            assert!(worst < 1e-10, "{d:?}: round trip error {worst}");
        }
    }

    #[test]
    fn fisheye_small_radius_branch_is_continuous() {
        let d = models()[2];
        let Distortion::Fisheye { k1, k2, k3, k4 } = d else {
            unreachable!()
        };
        // Just inside the series branch, against the closed form at the same radius.
        let r: f64 = 0.999e-3;
        let th = r.atan();
        let t2 = th * th;
        let thd = th * (1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))));
        let dthd = 1.0 + t2 * (3.0 * k1 + t2 * (5.0 * k2 + t2 * (7.0 * k3 + t2 * 9.0 * k4)));
        let (s_ref, g_ref) = (thd / r, (dthd / (1.0 + r * r) - thd / r) / (r * r));
        let (s, g) = d.fisheye_scale(r, 0.0);
        assert!((s - s_ref).abs() < 1e-14, "s: {s} vs {s_ref}");
        assert!((g - g_ref).abs() < 1e-6, "(ds/dr)/r: {g} vs {g_ref}");
    }

    #[test]
    fn fisheye_near_axis_series_keeps_k3() {
        // A large k3 makes its r^4 term of (ds/dr)/r visible just inside the
        // series branch: 6 k3 r^4 = 6e-8 at r = 1e-3, k3 = 1e4.
        let (k1, k2, k3, k4) = (0.02, -0.01, 1e4, 0.0);
        let d = Distortion::Fisheye { k1, k2, k3, k4 };
        let r: f64 = 0.999e-3;
        let th = r.atan();
        let t2 = th * th;
        let thd = th * (1.0 + t2 * (k1 + t2 * (k2 + t2 * (k3 + t2 * k4))));
        let dthd = 1.0 + t2 * (3.0 * k1 + t2 * (5.0 * k2 + t2 * (7.0 * k3 + t2 * 9.0 * k4)));
        let g_ref = (dthd / (1.0 + r * r) - thd / r) / (r * r);
        let (_, g) = d.fisheye_scale(r, 0.0);
        assert!((g - g_ref).abs() < 5e-9, "(ds/dr)/r: {g} vs {g_ref}");
    }

    #[test]
    fn none_is_identity() {
        let d = Distortion::None;
        assert_eq!(d.distort(0.3, -0.2), (0.3, -0.2));
        assert_eq!(d.undistort(0.3, -0.2), Some((0.3, -0.2)));
        assert_eq!(d.jacobian(0.3, -0.2), IDENTITY);
    }
}
