//! The MMBM metric (thesis eq. 3.11): the mean image-plane flow speed over the
//! sensor, mm/s. Several methods behind one API:
//!
//! - [`Method::Riemann`]: midpoint rule on an `n_u x n_v` grid of equal cells
//!   (thesis eq. 4.1, MMBM*; the thesis used 8 x 6);
//! - [`Method::Gauss`]: tensor Gauss-Legendre, `n_u x n_v` nodes (a real-time rule);
//! - [`Method::Exact`]: adaptive Gauss-Kronrod cubature to a relative tolerance,
//!   with an error estimate;
//!
//! [`AnyMethod`] adds `gpu[:WxH]`, the full-resolution per-pixel field on the
//! GPU (evaluated by `crate::field::mmbm_gpu`, not here), for the doors that
//! offer it (`eval`, `series`, Python's `metric`).

mod avx2;
mod exact;
mod grid;

pub use exact::{exact, exact_with, roll_mean_closed_form, ExactResult};
pub use grid::{gauss, gauss_legendre, gauss_points, riemann, riemann_points, GridRule};

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::model::flow::FlowPoly;
use crate::model::motion::{Plane, Twist};
use std::fmt;
use std::str::FromStr;

/// How MMBM is computed.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Method {
    /// Midpoint grid of `nu x nv` cells (`riemann[:NUxNV]`, default 8x6).
    Riemann {
        /// Cells across the sensor.
        nu: u32,
        /// Cells down the sensor.
        nv: u32,
    },
    /// Tensor Gauss-Legendre with `nu x nv` nodes (`gauss[:N]` = N x N, or `gauss:NUxNV`).
    Gauss {
        /// Nodes across the sensor.
        nu: u32,
        /// Nodes down the sensor.
        nv: u32,
    },
    /// Adaptive cubature to relative tolerance `tol` (`exact[:TOL]`, default 1e-9).
    Exact {
        /// Relative tolerance of the adaptive cubature.
        tol: f64,
    },
}

/// A CPU [`Method`] or the full field on the GPU (`gpu[:WxH]`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum AnyMethod {
    /// A CPU rule.
    Cpu(Method),
    /// Full field on the GPU at `width x height` samples (`gpu` = sensor resolution, or `gpu:WxH`).
    Gpu {
        /// Samples per row (0: the sensor's width).
        width: u32,
        /// Rows (0: the sensor's height).
        height: u32,
    },
}

impl Default for AnyMethod {
    fn default() -> Self {
        AnyMethod::Cpu(Method::default())
    }
}

impl FromStr for AnyMethod {
    type Err = Error;

    /// Parses `gpu[:WxH]` or a CPU [`Method`].
    fn from_str(s: &str) -> Result<Self> {
        let (name, arg) = match s.split_once(':') {
            Some((n, a)) => (n, Some(a)),
            None => (s, None),
        };
        match (name.trim().to_ascii_lowercase().as_str(), arg) {
            ("gpu", None) => Ok(AnyMethod::Gpu {
                width: 0,
                height: 0,
            }),
            ("gpu", Some(a)) => {
                let (width, height) = parse_dims(a, "grid")?;
                Ok(AnyMethod::Gpu { width, height })
            }
            ("riemann" | "gauss" | "exact", _) => s.parse::<Method>().map(AnyMethod::Cpu),
            _ => Err(Error::invalid(
                "method",
                format!("'{s}': expected {ALL_METHODS}"),
            )),
        }
    }
}

impl fmt::Display for AnyMethod {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            AnyMethod::Cpu(m) => m.fmt(f),
            AnyMethod::Gpu { width: 0, .. } => write!(f, "gpu"),
            AnyMethod::Gpu { width, height } => write!(f, "gpu:{width}x{height}"),
        }
    }
}

const CPU_METHODS: &str = "riemann[:NUxNV], gauss[:N] or exact[:TOL]";
const ALL_METHODS: &str = "riemann[:NUxNV], gauss[:N], exact[:TOL] or gpu[:WxH]";

impl Default for Method {
    fn default() -> Self {
        Method::Riemann { nu: 8, nv: 6 }
    }
}

fn parse_dims(s: &str, what: &str) -> Result<(u32, u32)> {
    let bad = || {
        Error::invalid(
            "method",
            format!("'{s}': expected {what} as NxM with positive integers, e.g. 8x6"),
        )
    };
    let (a, b) = s.split_once(['x', 'X']).ok_or_else(bad)?;
    let a: u32 = a.trim().parse().map_err(|_| bad())?;
    let b: u32 = b.trim().parse().map_err(|_| bad())?;
    if a == 0 || b == 0 {
        return Err(bad());
    }
    Ok((a, b))
}

impl FromStr for Method {
    type Err = Error;

    /// Parses `riemann[:NUxNV]`, `gauss[:N|:NUxNV]` or `exact[:TOL]` (grid
    /// rules within [`MAX_GRID_POINTS`] and [`MAX_GAUSS_NODES`]). `gpu` is
    /// refused with a pointer to [`AnyMethod`]'s doors.
    fn from_str(s: &str) -> Result<Self> {
        let (name, arg) = match s.split_once(':') {
            Some((n, a)) => (n, Some(a)),
            None => (s, None),
        };
        let m = match (name.trim().to_ascii_lowercase().as_str(), arg) {
            ("riemann", None) => Ok(Method::default()),
            ("riemann", Some(a)) => {
                let (nu, nv) = parse_dims(a, "grid")?;
                Ok(Method::Riemann { nu, nv })
            }
            ("gauss", None) => Ok(Method::Gauss { nu: 4, nv: 3 }),
            ("gauss", Some(a)) => {
                if a.contains(['x', 'X']) {
                    let (nu, nv) = parse_dims(a, "nodes")?;
                    Ok(Method::Gauss { nu, nv })
                } else {
                    let n: u32 = a.trim().parse().ok().filter(|&n| n > 0).ok_or_else(|| {
                        Error::invalid(
                            "method",
                            format!("'{s}': gauss:N needs a positive integer N"),
                        )
                    })?;
                    Ok(Method::Gauss { nu: n, nv: n })
                }
            }
            ("exact", None) => Ok(Method::Exact { tol: 1e-9 }),
            ("exact", Some(a)) => {
                let tol: f64 = a
                    .trim()
                    .parse()
                    .ok()
                    .filter(|t: &f64| *t > 0.0 && t.is_finite())
                    .ok_or_else(|| {
                        Error::invalid(
                            "method",
                            format!("'{s}': exact:TOL needs a positive tolerance, e.g. exact:1e-9"),
                        )
                    })?;
                Ok(Method::Exact { tol })
            }
            ("gpu", _) => Err(Error::invalid(
                "method",
                format!(
                    "'{s}': the GPU field is not a CPU method (only eval, series and Python's metric \
                     offer gpu); expected {CPU_METHODS}"
                ),
            )),
            _ => Err(Error::invalid(
                "method",
                format!("'{s}': expected {CPU_METHODS}"),
            )),
        }?;
        let too_big = |what: String| {
            Err(Error::invalid(
                "method",
                format!("'{s}': {what} (limits: riemann and gauss at most {MAX_GRID_POINTS} points, gauss at most {MAX_GAUSS_NODES} nodes per side)"),
            ))
        };
        match m {
            Method::Riemann { nu, nv } | Method::Gauss { nu, nv }
                if nu as u64 * nv as u64 > MAX_GRID_POINTS =>
            {
                too_big(format!("{nu} x {nv} = {} points", nu as u64 * nv as u64))
            }
            Method::Gauss { nu, nv } if nu.max(nv) > MAX_GAUSS_NODES => {
                too_big(format!("{} nodes on one side", nu.max(nv)))
            }
            m => Ok(m),
        }
    }
}

/// Most points of a `riemann` or `gauss` rule (memory and time grow with it).
pub const MAX_GRID_POINTS: u64 = 1 << 20;
/// Most Gauss-Legendre nodes along one side (their computation is quadratic).
pub const MAX_GAUSS_NODES: u32 = 1024;

impl fmt::Display for Method {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match *self {
            Method::Riemann { nu, nv } => write!(f, "riemann:{nu}x{nv}"),
            Method::Gauss { nu, nv } => write!(f, "gauss:{nu}x{nv}"),
            Method::Exact { tol } => write!(f, "exact:{tol:e}"),
        }
    }
}

/// One MMBM value.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Mmbm {
    /// Mean flow speed over the sensor, mm/s.
    pub mm_s: f64,
    /// Mean true pixel speed over the sensor, px/s: the mean of `|(u', v')|`
    /// where `(u', v')` is the flow in px/s on each axis (`u` over `pitch_x`
    /// plus the skew term, `v` over `pitch_y`: [`pixel_map`]). With square,
    /// unskewed pixels it is `mm_s / pitch`; otherwise it is computed with the
    /// same method, and is what a flow field's mean speed estimates.
    pub px_s: f64,
    /// Error estimate (mm/s), for the exact method.
    pub error_estimate: Option<f64>,
    /// Number of integrand evaluations used.
    pub evaluations: u64,
}

/// The scene and camera an MMBM value is computed for.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Scene {
    /// Camera intrinsics.
    pub camera: Camera,
    /// Scene plane; required when the twist has translation.
    pub plane: Option<Plane>,
}

impl Scene {
    /// Thesis camera, no plane (rotation-only).
    pub fn thesis() -> Self {
        Scene {
            camera: Camera::thesis(),
            plane: None,
        }
    }

    /// Validates the camera, the plane and that a plane exists when `tw` translates.
    pub fn validate_for(&self, tw: &Twist) -> Result<()> {
        self.camera.validate()?;
        tw.validate()?;
        match &self.plane {
            Some(p) => p.validate_for(&self.camera),
            None if !tw.is_rotation_only() => Err(Error::invalid(
                "depth",
                "the twist has a linear velocity, so a scene depth (--depth Z) or plane (--plane) is required",
            )),
            None => Ok(()),
        }
    }

    /// The flow polynomial for twist `tw` in this scene.
    pub fn flow_poly(&self, tw: &Twist) -> FlowPoly {
        FlowPoly::new(self.camera.focal_mm, tw, self.plane.as_ref())
    }
}

/// Computes MMBM with a CPU method. Validates inputs first. (The GPU field
/// is `crate::field::mmbm_gpu`.)
///
/// ```
/// use mmbm_core::{mmbm, Camera, Method, Scene, Twist};
/// let scene = Scene { camera: Camera::thesis(), plane: None };
/// // Pitching at 1 rad/s: every point moves at least f = 4.2548 mm/s on the sensor.
/// let m = mmbm(&scene, &Twist::rotation(1.0, 0.0, 0.0), Method::Exact { tol: 1e-9 })?;
/// assert!(m.mm_s > 4.2548 && m.mm_s < 5.0);
/// assert!(m.error_estimate.unwrap() < 1e-6);
/// # Ok::<(), mmbm_core::Error>(())
/// ```
pub fn mmbm(scene: &Scene, tw: &Twist, method: Method) -> Result<Mmbm> {
    scene.validate_for(tw)?;
    let poly = scene.flow_poly(tw);
    mmbm_poly(&scene.camera, &poly, method)
}

/// MMBM of a pre-expanded flow polynomial (no validation; the hot path).
/// Through lens distortion the rules average `|J flow|` at the undistorted
/// points of their nodes on the (distorted) sensor rectangle (docs/spec.md section 9).
pub fn mmbm_poly(cam: &Camera, poly: &FlowPoly, method: Method) -> Result<Mmbm> {
    let rect = cam.sensor_rect();
    let pinhole = cam.distortion.is_none();
    let (mm_s, err, evals) = match method {
        Method::Riemann { nu, nv } if pinhole => {
            (riemann(poly, &rect, nu, nv), None, (nu * nv) as u64)
        }
        Method::Gauss { nu, nv } if pinhole => (gauss(poly, &rect, nu, nv), None, (nu * nv) as u64),
        Method::Riemann { nu, nv } => (
            GridRule::riemann(&rect, nu, nv)
                .distorted(cam)?
                .mean_speed(poly),
            None,
            (nu * nv) as u64,
        ),
        Method::Gauss { nu, nv } => (
            GridRule::gauss(&rect, nu, nv)
                .distorted(cam)?
                .mean_speed(poly),
            None,
            (nu * nv) as u64,
        ),
        Method::Exact { tol } => {
            // Pinhole: the polynomial directly (a branch per evaluation in
            // the integrand costs the cubature about 60 %).
            let r = if pinhole {
                exact(poly, &rect, tol)
            } else {
                masked_exact(cam, poly, tol, None)
            };
            (r.value, Some(r.error), r.evaluations)
        }
    };
    if !mm_s.is_finite() {
        return Err(Error::invalid(
            "motion",
            format!("MMBM is {mm_s}: the flow overflows f64 (a velocity near 1e308?)"),
        ));
    }
    Ok(Mmbm {
        mm_s,
        px_s: mean_px_speed(cam, poly, method, mm_s)?,
        error_estimate: err,
        evaluations: evals,
    })
}

/// The camera's map from sensor velocity (mm/s) to pixel velocity (px/s),
/// row-major: `(u', v') = (m[0] du + m[1] dv, m[2] du + m[3] dv)` with
/// `m = [1/pitch_x, skew/focal, 0, 1/pitch_y]` (as
/// [`Camera::mm_to_px_velocity`]). None for square, unskewed pixels, where
/// px/s is mm/s over the pitch.
pub fn pixel_map(cam: &Camera) -> Option<[f64; 4]> {
    if cam.pitch_x_mm == cam.pitch_y_mm && cam.skew == 0.0 {
        return None;
    }
    Some([
        1.0 / cam.pitch_x_mm,
        cam.skew / cam.focal_mm,
        0.0,
        1.0 / cam.pitch_y_mm,
    ])
}

/// The MMBM in px/s ([`Mmbm::px_s`]) of `poly` with `method`, given its
/// value `mm_s` in mm/s (all it needs with square pixels).
fn mean_px_speed(cam: &Camera, poly: &FlowPoly, method: Method, mm_s: f64) -> Result<f64> {
    let Some(m) = pixel_map(cam) else {
        return crate::camera::checked_px_s(mm_s, cam.pitch_x_mm);
    };
    let rect = cam.sensor_rect();
    let px = match method {
        Method::Riemann { nu, nv } => GridRule::riemann(&rect, nu, nv)
            .distorted(cam)?
            .mean_mapped_speed(poly, m),
        Method::Gauss { nu, nv } => GridRule::gauss(&rect, nu, nv)
            .distorted(cam)?
            .mean_mapped_speed(poly, m),
        Method::Exact { tol } if cam.distortion.is_none() => {
            exact(&poly.mapped(m), &rect, tol).value
        }
        Method::Exact { tol } => masked_exact(cam, poly, tol, Some(m)).value,
    };
    if px.is_finite() {
        Ok(px)
    } else {
        Err(Error::invalid(
            "MMBM",
            format!("{mm_s:?} mm/s is {px} px/s on this camera's pixels, not a finite number"),
        ))
    }
}

/// Flow speed (mm/s) at the sensor point `(u, v)` mm of `cam` (through its
/// distortion, if any; NaN where a point does not undistort).
#[inline]
pub fn point_speed(cam: &Camera, poly: &FlowPoly, u: f64, v: f64) -> f64 {
    if cam.distortion.is_none() {
        poly.speed(u, v)
    } else {
        distorted_speed(cam, poly, u, v, None)
    }
}

/// `|J flow|` (mm/s) at the distorted sensor point `(ud, vd)` mm, or
/// `|m J flow|` with a map `m` (row-major, e.g. [`pixel_map`]: px/s); NaN
/// where it does not undistort (the caller reports a non-finite result).
fn distorted_speed(cam: &Camera, poly: &FlowPoly, ud: f64, vd: f64, m: Option<[f64; 4]>) -> f64 {
    match cam.undistort_mm(ud, vd) {
        Some((u, v)) => {
            let (a, b) =
                crate::camera::distortion::apply(&cam.distortion_jacobian(u, v), poly.eval(u, v));
            let (a, b) = match m {
                Some(m) => (m[0] * a + m[1] * b, m[2] * a + m[3] * b),
                None => (a, b),
            };
            (a * a + b * b).sqrt()
        }
        None => f64::NAN,
    }
}

/// The exact mean through the distortion over the sensor's unmasked part:
/// the speed is 0 beyond the radial distortion limit and the integral is
/// divided by the unmasked share of the area ([`Camera::valid_fraction`]).
/// With a map `m`, the mean of `|m J flow|` instead (e.g. px/s).
fn masked_exact(cam: &Camera, poly: &FlowPoly, tol: f64, m: Option<[f64; 4]>) -> ExactResult {
    let valid = cam.valid_fraction();
    let speed = |u: f64, v: f64| {
        if cam.is_masked_mm(u, v) {
            0.0
        } else {
            distorted_speed(cam, poly, u, v, m)
        }
    };
    let mut r = exact_with(speed, &cam.sensor_rect(), tol);
    r.value /= valid;
    r.error /= valid;
    r
}

/// A prepared CPU method for many evaluations with one camera: the grid rules
/// are built once (structure-of-arrays, vectorised), which is what `series`
/// and the trigger policies use per gyro sample.
#[derive(Debug, Clone)]
pub struct Evaluator {
    camera: Camera,
    method: Method,
    rule: Option<GridRule>,
}

impl Evaluator {
    /// Prepares `method` for `camera`.
    pub fn new(camera: &Camera, method: Method) -> Result<Self> {
        camera.validate()?;
        let r = camera.sensor_rect();
        let rule = match method {
            Method::Riemann { nu, nv } => Some(GridRule::riemann(&r, nu, nv).distorted(camera)?),
            Method::Gauss { nu, nv } => Some(GridRule::gauss(&r, nu, nv).distorted(camera)?),
            Method::Exact { .. } => None,
        };
        Ok(Evaluator {
            camera: *camera,
            method,
            rule,
        })
    }

    /// MMBM, mm/s, of a flow polynomial.
    #[inline]
    pub fn mean_speed(&self, poly: &FlowPoly) -> f64 {
        match (&self.rule, self.method) {
            (Some(rule), _) => rule.mean_speed(poly),
            (None, Method::Exact { tol }) if self.camera.distortion.is_none() => {
                exact(poly, &self.camera.sensor_rect(), tol).value
            }
            (None, Method::Exact { tol }) => masked_exact(&self.camera, poly, tol, None).value,
            _ => unreachable!("Evaluator::new accepts only CPU methods"),
        }
    }

    /// MMBM in px/s ([`Mmbm::px_s`]) of a flow polynomial whose MMBM in mm/s
    /// is `mm_s` (from [`Evaluator::mean_speed`]): `mm_s / pitch` with square
    /// pixels, else the mean true pixel speed by the same method.
    pub fn mean_px_speed(&self, poly: &FlowPoly, mm_s: f64) -> Result<f64> {
        match (&self.rule, pixel_map(&self.camera)) {
            (Some(rule), Some(m)) => Ok(rule.mean_mapped_speed(poly, m)),
            _ => mean_px_speed(&self.camera, poly, self.method, mm_s),
        }
    }

    /// The camera.
    pub fn camera(&self) -> &Camera {
        &self.camera
    }
}

#[cfg(test)]
mod tests;
