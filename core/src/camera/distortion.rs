//! Lens distortion (docs/spec.md section 9): the two models users have calibrations
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

use super::digital::Warp;
use super::insta360;
use super::models::Model;
use super::poly3::Poly3;
use super::poly5::Poly5;
use super::ptlens::Ptlens;
use super::radial::{self, Profile};
use super::sony::ThetaPoly;
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
    /// Gyroflow's `poly3`: `x (1 + k1 r^2)` (`super::poly3`).
    Poly3 {
        /// Coefficient of `r^2`.
        #[serde(default)]
        k1: f64,
    },
    /// Gyroflow's `poly5`: `x (1 + k1 r^2 + k2 r^4)` (`super::poly5`).
    Poly5 {
        /// Coefficient of `r^2`.
        #[serde(default)]
        k1: f64,
        /// Coefficient of `r^4`.
        #[serde(default)]
        k2: f64,
    },
    /// Gyroflow's `ptlens`: `x (1 + c r + b r^2 + a r^3)` (`super::ptlens`).
    Ptlens {
        /// Coefficient of `r^3`.
        #[serde(default)]
        a: f64,
        /// Coefficient of `r^2`.
        #[serde(default)]
        b: f64,
        /// Coefficient of `r`.
        #[serde(default)]
        c: f64,
    },
    /// Gyroflow's `sony`: `theta_d = k0 theta + ... + k5 theta^6` (`super::sony`).
    Sony {
        /// The 6 coefficients.
        k: [f64; 6],
    },
    /// Gyroflow's `generic_polynomial`: `theta_d = k0 theta + ... + k11 theta^12` (`super::sony`).
    #[serde(rename = "generic_polynomial")]
    GenericPolynomial {
        /// The 12 coefficients.
        k: [f64; 12],
    },
    /// Gyroflow's `insta360`: `[k1, k2, k3, p1, p2, xi]` (`super::insta360`).
    Insta360 {
        /// The 6 coefficients in Gyroflow's order.
        k: [f64; 6],
    },
    /// An optical model under a digital lens's warp (Gyroflow's
    /// `digital_lens`, `super::digital`): the recorded point is the warp of
    /// the optical distorted point.
    Digital {
        /// The warp and the optical image's place in the video frame.
        warp: Warp,
        /// The optical model.
        optical: Model,
        /// Its coefficients (Gyroflow's order, zeros past its count).
        k: [f64; 12],
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
            _ => return None,
        })
    }

    /// The radial profile of the radial models of `super::radial`.
    fn radial(&self) -> Option<Radial> {
        Some(match *self {
            Distortion::Poly3 { k1 } => Radial::P3(Poly3(k1)),
            Distortion::Poly5 { k1, k2 } => Radial::P5(Poly5([k1, k2])),
            Distortion::Ptlens { a, b, c } => Radial::Pt(Ptlens([a, b, c])),
            Distortion::Sony { k } => {
                let mut t = [0.0; 12];
                t[..6].copy_from_slice(&k);
                Radial::Theta(ThetaPoly(t))
            }
            Distortion::GenericPolynomial { k } => Radial::Theta(ThetaPoly(k)),
            _ => return None,
        })
    }

    /// True for a distorted normalised point `(xd, yd)` beyond the radial
    /// distortion limit (for a digital lens: its optical point beyond the
    /// optical model's limit, or a point the warp does not invert).
    pub fn is_masked(&self, xd: f64, yd: f64) -> bool {
        match *self {
            Distortion::Digital { warp, .. } => {
                let (x, y) = warp.unrecord(xd, yd);
                x.hypot(y) > self.optical().radial_limit() || x.is_nan() || y.is_nan()
            }
            _ => xd.hypot(yd) > self.radial_limit(),
        }
    }

    /// Rejects non-finite coefficients, naming the key.
    pub fn validate(&self) -> Result<()> {
        if let Distortion::Digital { warp, .. } = self {
            let frame_ok = warp.frame.iter().all(|v| v.is_finite())
                && warp.frame[0] > 0.0
                && warp.frame[1] > 0.0;
            let stretch_ok = warp.lens != super::digital::Lens::DigitalStretch
                || (warp.params[0] > 0.0 && warp.params[1] > 0.0);
            if !frame_ok || !stretch_ok || !warp.params.iter().all(|v| v.is_finite()) {
                return Err(Error::invalid(
                    "distortion.warp",
                    format!(
                        "the {} warp needs finite parameters (a positive frame scale and \
                         stretch), got params {:?}, frame {:?}",
                        warp.lens.name(),
                        warp.params,
                        warp.frame
                    ),
                ));
            }
        }
        if !matches!(
            self,
            Distortion::None | Distortion::Opencv { .. } | Distortion::Fisheye { .. }
        ) {
            let (m, k) = self.parts();
            if let Some(i) = k.iter().position(|v| !v.is_finite()) {
                return Err(Error::invalid(
                    format!("distortion.k[{i}]"),
                    format!("{} needs finite coefficients, got {}", m.name(), k[i]),
                ));
            }
            return Ok(());
        }
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
            Distortion::Insta360 { k } => insta360::distort(&k, x, y),
            Distortion::Digital { warp, .. } => {
                let (xd, yd) = self.optical().distort(x, y);
                warp.record(xd, yd).0
            }
            _ => match self.radial() {
                Some(p) => radial::distort(p.profile(), x, y),
                None => (x, y),
            },
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
    /// The radial models' (`super::radial`) limit likewise; for a digital
    /// lens the optical model's, on the optical image ([`Distortion::is_masked`]
    /// un-warps first); `insta360` and OpenCV's have none (as in Gyroflow).
    pub fn radial_limit(&self) -> f64 {
        match self {
            Distortion::Fisheye { .. } => super::fisheye::limit(self.fisheye_k()),
            Distortion::Digital { .. } => self.optical().radial_limit(),
            _ => match self.radial() {
                Some(p) => radial::limit(p.profile()),
                None => f64::INFINITY,
            },
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
            Distortion::Insta360 { k } => insta360::jacobian(&k, x, y),
            Distortion::Digital { warp, .. } => {
                let o = self.optical();
                let (xd, yd) = o.distort(x, y);
                let (_, jw) = warp.record(xd, yd);
                mul(&jw, &o.jacobian(x, y))
            }
            _ => match self.radial() {
                Some(p) => radial::jacobian(p.profile(), x, y),
                None => IDENTITY,
            },
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
        if let Distortion::Digital { warp, .. } = *self {
            let (xo, yo) = warp.unrecord(xd, yd);
            let (x, y) = self.optical().undistort(xo, yo)?;
            return self.converged(x, y, xd, yd);
        }
        if let Some(p) = self.radial() {
            let rd = xd.hypot(yd);
            if rd == 0.0 {
                return Some((0.0, 0.0));
            }
            let r = radial::solve(p.profile(), rd, UNDISTORT_TOL * 1e-2)?;
            return self.converged(xd * r / rd, yd * r / rd, xd, yd);
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

/// The radial models' profiles (`super::radial::Profile`), without allocation.
enum Radial {
    P3(Poly3),
    P5(Poly5),
    Pt(Ptlens),
    Theta(ThetaPoly),
}

impl Radial {
    fn profile(&self) -> &dyn Profile {
        match self {
            Radial::P3(p) => p,
            Radial::P5(p) => p,
            Radial::Pt(p) => p,
            Radial::Theta(p) => p,
        }
    }
}

/// The product `a b` of two 2x2 matrices.
#[inline]
pub fn mul(a: &Jac, b: &Jac) -> Jac {
    [
        [
            a[0][0] * b[0][0] + a[0][1] * b[1][0],
            a[0][0] * b[0][1] + a[0][1] * b[1][1],
        ],
        [
            a[1][0] * b[0][0] + a[1][1] * b[1][0],
            a[1][0] * b[0][1] + a[1][1] * b[1][1],
        ],
    ]
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
        crate::camera::parts::samples()
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
