//! Camera intrinsics: focal length (mm), pixel pitch (mm), resolution,
//! principal point and skew (pixels), and the real-camera parts of docs/spec.md
//! section 9 (distortion, rolling shutter, noise, lens). Coordinates follow
//! docs/spec.md section 1: x right, y down, z forward; sensor coordinates `(u, v)` in
//! mm, which are `f` times the normalised coordinates `(x, y)`.

use super::distortion::{Distortion, Jac};
use super::lens::Lens;
use super::noise::Noise;
use super::shutter::Shutter;
use crate::check::{finite, positive};
use crate::error::{Error, Result};
use serde::{Deserialize, Serialize};

/// A camera: pinhole intrinsics plus, optionally, lens distortion, a rolling
/// shutter, sensor noise and a thin lens (all off by default: the thesis's
/// ideal camera, whose results are bit-for-bit those without these fields).
#[derive(Debug, Clone, Copy, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Camera {
    /// Focal length, mm.
    pub focal_mm: f64,
    /// Horizontal pixel pitch, mm.
    pub pitch_x_mm: f64,
    /// Vertical pixel pitch, mm.
    pub pitch_y_mm: f64,
    /// Sensor width, pixels.
    pub width: u32,
    /// Sensor height, pixels.
    pub height: u32,
    /// Principal point column, pixels (default `width / 2`).
    pub cx: f64,
    /// Principal point row, pixels (default `height / 2`).
    pub cy: f64,
    /// Skew in pixels (OpenCV's `K[0][1]`): pixel column `= fx*x + skew*y + cx`. Default 0.
    #[serde(default)]
    pub skew: f64,
    /// Lens distortion (default none).
    #[serde(default, skip_serializing_if = "Distortion::is_none")]
    pub distortion: Distortion,
    /// Shutter (default global).
    #[serde(default, skip_serializing_if = "Shutter::is_global")]
    pub shutter: Shutter,
    /// Sensor noise (default none: noiseless linear images).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub noise: Option<Noise>,
    /// Thin lens for defocus (default none: infinite depth of field).
    #[serde(default, skip_serializing_if = "Option::is_none")]
    pub lens: Option<Lens>,
}

/// The range a focal length or pixel pitch must lie in, mm (1 nm to 1 km):
/// every physical camera, with the derived quantities (focal length in
/// pixels, sensor size and area in mm, the flow's powers of the sensor
/// coordinates) far from overflow and underflow.
pub const LENGTH_RANGE_MM: [f64; 2] = [1e-6, 1e6];

impl Default for Camera {
    fn default() -> Self {
        Self::thesis()
    }
}

/// Axis-aligned rectangle on the sensor, mm: `[u0, u1] x [v0, v1]`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct SensorRect {
    /// Left edge, mm.
    pub u0: f64,
    /// Right edge, mm.
    pub u1: f64,
    /// Top edge, mm.
    pub v0: f64,
    /// Bottom edge, mm.
    pub v1: f64,
}

impl SensorRect {
    /// Area, mm^2.
    pub fn area(&self) -> f64 {
        (self.u1 - self.u0) * (self.v1 - self.v0)
    }
}

impl Camera {
    /// The thesis camera: f = 4.2548 mm, 4.65 um pixels, 640 x 480, centred principal point.
    pub fn thesis() -> Self {
        Self::new(4.2548, 0.00465, 640, 480)
    }

    /// Square pixels, principal point at the sensor centre, no skew.
    pub fn new(focal_mm: f64, pitch_mm: f64, width: u32, height: u32) -> Self {
        Camera {
            focal_mm,
            pitch_x_mm: pitch_mm,
            pitch_y_mm: pitch_mm,
            width,
            height,
            cx: width as f64 / 2.0,
            cy: height as f64 / 2.0,
            skew: 0.0,
            distortion: Distortion::None,
            shutter: Shutter::global(),
            noise: None,
            lens: None,
        }
    }

    /// True for the thesis's ideal pinhole with a global shutter (no distortion,
    /// no readout); noise and lens do not change the geometry.
    pub fn is_ideal_geometry(&self) -> bool {
        self.distortion.is_none() && self.shutter.is_global()
    }

    /// The same camera scaled to a `width x height` sensor, as a calibration
    /// made at one resolution is used for a video at another: the focal length
    /// in pixels, the principal point and the skew scale with the size (the
    /// pixel pitch grows by the inverse factor, so `focal_mm` and the field of
    /// view are unchanged).
    pub fn scaled_to(&self, width: u32, height: u32) -> Self {
        let (sx, sy) = (
            width as f64 / self.width as f64,
            height as f64 / self.height as f64,
        );
        Camera {
            width,
            height,
            pitch_x_mm: self.pitch_x_mm / sx,
            pitch_y_mm: self.pitch_y_mm / sy,
            cx: self.cx * sx,
            cy: self.cy * sy,
            skew: self.skew * sx,
            ..*self
        }
        .refit_digital()
    }

    /// A digital lens's warp placed on this camera's frame (its `[fx / W, fy
    /// / H, cx / W - 0.5, cy / H - 0.5]`, `super::digital`); the camera
    /// unchanged without one.
    pub fn refit_digital(mut self) -> Self {
        if let Distortion::Digital { ref mut warp, .. } = self.distortion {
            let (w, h) = (self.width as f64, self.height as f64);
            warp.frame = [
                self.focal_mm / self.pitch_x_mm / w,
                self.focal_mm / self.pitch_y_mm / h,
                self.cx / w - 0.5,
                self.cy / h - 0.5,
            ];
        }
        self
    }

    /// The camera turned to the other orientation, as Gyroflow's
    /// `LensProfile::swapped` turns a landscape profile for a portrait video:
    /// width and height, the pitches (so fx and fy) and the principal point's
    /// coordinates swap; skew, distortion coefficients and the readout
    /// direction are kept (as Gyroflow keeps them).
    pub fn transposed(&self) -> Self {
        Camera {
            width: self.height,
            height: self.width,
            pitch_x_mm: self.pitch_y_mm,
            pitch_y_mm: self.pitch_x_mm,
            cx: self.cy,
            cy: self.cx,
            ..*self
        }
        .refit_digital()
    }

    /// [`Camera::scaled_to`] a `width x height` video, transposed first
    /// ([`Camera::transposed`]) when the video is portrait and the camera
    /// landscape or the other way round (Gyroflow's rule for a profile).
    pub fn fitted_to(&self, width: u32, height: u32) -> Self {
        let turned = (width > height && self.width < self.height)
            || (width < height && self.width > self.height);
        if turned {
            self.transposed().scaled_to(width, height)
        } else {
            self.scaled_to(width, height)
        }
    }

    /// Same focal length and pixel pitch, a `width x height` sensor with the
    /// principal point at its centre (what `--resolution` does).
    pub fn with_resolution(&self, width: u32, height: u32) -> Self {
        Camera {
            width,
            height,
            cx: width as f64 / 2.0,
            cy: height as f64 / 2.0,
            ..*self
        }
        .refit_digital()
    }

    /// A sensor size from integers as another door gives them (Python): each
    /// side must fit the camera's `u32` (a zero side is then refused by
    /// [`Camera::validate`]).
    pub fn size_from(width: i64, height: i64) -> Result<(u32, u32)> {
        match (u32::try_from(width), u32::try_from(height)) {
            (Ok(w), Ok(h)) => Ok((w, h)),
            _ => Err(Error::invalid(
                "resolution",
                format!(
                    "{width}x{height}: width and height must be whole numbers of pixels from 1 to {}",
                    u32::MAX
                ),
            )),
        }
    }

    /// Rejects zero/negative/NaN focal length or pitch, lengths outside
    /// `LENGTH_RANGE_MM` (their squares and ratios, the sensor's area and
    /// the focal length in pixels, must stay far from the float range), an
    /// empty sensor, a non-finite principal point.
    pub fn validate(&self) -> Result<()> {
        for (what, x) in [
            ("focal length (mm)", self.focal_mm),
            ("pixel pitch x (mm)", self.pitch_x_mm),
            ("pixel pitch y (mm)", self.pitch_y_mm),
        ] {
            positive(what, x)?;
            let [lo, hi] = LENGTH_RANGE_MM;
            if !(lo..=hi).contains(&x) {
                return Err(Error::invalid(
                    what,
                    format!(
                        "must be between {lo:e} and {hi:e} mm, got {x:e} (the sensor's \
                         geometry in mm and pixels would not be representable)"
                    ),
                ));
            }
        }
        finite("principal point cx", self.cx)?;
        finite("principal point cy", self.cy)?;
        finite("skew", self.skew)?;
        if self.width == 0 || self.height == 0 {
            return Err(Error::invalid(
                "resolution",
                format!("must be at least 1x1, got {}x{}", self.width, self.height),
            ));
        }
        self.shutter.validate()?;
        if let Some(n) = &self.noise {
            n.validate()?;
        }
        if let Some(l) = &self.lens {
            l.validate(self.focal_mm)?;
        }
        self.distortion.validate()?;
        if !self.distortion.is_none() {
            self.check_distortion_invertible()?;
        }
        Ok(())
    }

    /// Checks that the distortion is one-to-one over the sensor's unmasked
    /// part: every point of a 33 x 33 grid over the sensor (edges included)
    /// within the radial distortion limit ([`Camera::is_masked_mm`])
    /// undistorts, and the Jacobian keeps a positive determinant along the
    /// ray from the principal point to it. A sensor masked whole is refused.
    fn check_distortion_invertible(&self) -> Result<()> {
        const N: u32 = 32;
        let fold = |x: f64, y: f64, why: &str| {
            Err(Error::invalid(
                "distortion",
                format!(
                    "the model folds over inside the sensor near pixel ({x:.1}, {y:.1}): {why}; \
                     check the coefficients (and that they belong to this model and resolution)"
                ),
            ))
        };
        if self.valid_fraction() <= 0.0 {
            return Err(Error::invalid(
                "distortion",
                format!(
                    "the whole sensor lies beyond the lens's radial distortion limit ({:.4} mm \
                     from the principal point): no pixel sees a ray",
                    self.radial_limit_mm()
                ),
            ));
        }
        for j in 0..=N {
            for i in 0..=N {
                let (px, py) = (
                    self.width as f64 * i as f64 / N as f64,
                    self.height as f64 * j as f64 / N as f64,
                );
                let (ud, vd) = self.pixel_to_mm(px, py);
                if self.is_masked_mm(ud, vd) {
                    continue;
                }
                let Some((u, v)) = self.undistort_mm(ud, vd) else {
                    return fold(px, py, "undistortion does not converge");
                };
                // The distorted point must move outward along the ray to it.
                for k in 1..=16 {
                    let s = k as f64 / 16.0;
                    let jac = self.distortion_jacobian(u * s, v * s);
                    let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
                    if det.is_nan() || det <= 0.0 {
                        return fold(px, py, "the Jacobian's determinant is not positive");
                    }
                }
            }
        }
        Ok(())
    }

    /// The radial distortion limit on the sensor, mm from the principal
    /// point: beyond it the lens model has no ray (past its turning point or
    /// 90 degrees; [`Distortion::radial_limit`]). Infinite for models without one.
    pub fn radial_limit_mm(&self) -> f64 {
        self.distortion.radial_limit() * self.focal_mm
    }

    /// True for a distorted sensor point `(ud, vd)` mm beyond the radial
    /// distortion limit: masked, excluded from the metric's mean.
    #[inline]
    pub fn is_masked_mm(&self, ud: f64, vd: f64) -> bool {
        let f = self.focal_mm;
        self.distortion.is_masked(ud / f, vd / f)
    }

    /// The share of the sensor's area within the radial distortion limit
    /// (exact: the area of the rectangle within the disc of that radius,
    /// over the rectangle's); 1 without a limit.
    pub fn valid_fraction(&self) -> f64 {
        let rl = self.radial_limit_mm();
        let r = self.sensor_rect();
        if !rl.is_finite() {
            return 1.0;
        }
        if let Distortion::Digital { warp, .. } = self.distortion {
            // The warp bends the mask's edge: the share of a 512 x 512 grid's cell centres.
            const N: u32 = 512;
            let (f, limit) = (self.focal_mm, self.distortion.radial_limit());
            let mut valid = 0u64;
            for j in 0..N {
                for i in 0..N {
                    let u = r.u0 + (r.u1 - r.u0) * (i as f64 + 0.5) / N as f64;
                    let v = r.v0 + (r.v1 - r.v0) * (j as f64 + 0.5) / N as f64;
                    let (x, y) = warp.unrecord(u / f, v / f);
                    valid += u64::from(x.hypot(y) <= limit);
                }
            }
            return valid as f64 / (N * N) as f64;
        }
        // Area of the disc within [0, a] x [0, b], a, b >= 0.
        let quadrant = |a: f64, b: f64| -> f64 {
            let prim =
                |x: f64| 0.5 * (x * (rl * rl - x * x).max(0.0).sqrt() + rl * rl * (x / rl).asin());
            let x0 = (rl * rl - b * b).max(0.0).sqrt().min(a);
            let x1 = a.min(rl);
            b * x0 + (prim(x1) - prim(x0)).max(0.0)
        };
        // Signed inclusion-exclusion over the four corners (the disc is symmetric).
        let signed = |u: f64, v: f64| quadrant(u.abs(), v.abs()) * u.signum() * v.signum();
        let inside =
            signed(r.u1, r.v1) - signed(r.u0, r.v1) - signed(r.u1, r.v0) + signed(r.u0, r.v0);
        (inside / r.area()).clamp(0.0, 1.0)
    }

    /// The share of the sensor's area beyond the radial distortion limit
    /// (masked: excluded from the metric), `1 - valid_fraction`.
    pub fn masked_fraction(&self) -> f64 {
        1.0 - self.valid_fraction()
    }

    /// Pixel coordinates of the ray `(x, y, 1)` (normalised pinhole
    /// coordinates) through the lens: distorted, then `K`. Without distortion
    /// this is exactly `mm_to_pixel(f x, f y)`.
    #[inline]
    pub fn ray_to_pixel(&self, x: f64, y: f64) -> (f64, f64) {
        let f = self.focal_mm;
        if self.distortion.is_none() {
            return self.mm_to_pixel(f * x, f * y);
        }
        let (xd, yd) = self.distortion.distort(x, y);
        self.mm_to_pixel(f * xd, f * yd)
    }

    /// The ray `(x, y)` (normalised pinhole coordinates, `z = 1`) seen at
    /// pixel coordinates `(px, py)`, undistorted; `None` where undistortion
    /// does not converge. Without distortion: `pixel_to_mm / f`.
    #[inline]
    pub fn pixel_to_ray(&self, px: f64, py: f64) -> Option<(f64, f64)> {
        let (ud, vd) = self.pixel_to_mm(px, py);
        let f = self.focal_mm;
        if self.distortion.is_none() {
            return Some((ud / f, vd / f));
        }
        self.distortion.undistort(ud / f, vd / f)
    }

    /// Distorted sensor point (mm) of the pinhole sensor point `(u, v)` mm.
    #[inline]
    pub fn distort_mm(&self, u: f64, v: f64) -> (f64, f64) {
        let f = self.focal_mm;
        let (xd, yd) = self.distortion.distort(u / f, v / f);
        (xd * f, yd * f)
    }

    /// Pinhole sensor point (mm) seen at the distorted sensor point `(ud, vd)`
    /// mm (Newton's method, to `distortion::UNDISTORT_TOL` in
    /// normalised units); `None` where it does not converge.
    #[inline]
    pub fn undistort_mm(&self, ud: f64, vd: f64) -> Option<(f64, f64)> {
        let f = self.focal_mm;
        self.distortion
            .undistort(ud / f, vd / f)
            .map(|(x, y)| (x * f, y * f))
    }

    /// Jacobian of [`Camera::distort_mm`] at the pinhole point `(u, v)` mm
    /// (dimensionless: the same as in normalised coordinates).
    #[inline]
    pub fn distortion_jacobian(&self, u: f64, v: f64) -> Jac {
        let f = self.focal_mm;
        self.distortion.jacobian(u / f, v / f)
    }

    /// Focal length in horizontal pixels.
    pub fn fx_px(&self) -> f64 {
        self.focal_mm / self.pitch_x_mm
    }

    /// Focal length in vertical pixels.
    pub fn fy_px(&self) -> f64 {
        self.focal_mm / self.pitch_y_mm
    }

    /// The sensor as a rectangle in mm around the principal point.
    pub fn sensor_rect(&self) -> SensorRect {
        SensorRect {
            u0: -self.cx * self.pitch_x_mm,
            u1: (self.width as f64 - self.cx) * self.pitch_x_mm,
            v0: -self.cy * self.pitch_y_mm,
            v1: (self.height as f64 - self.cy) * self.pitch_y_mm,
        }
    }

    /// Sensor coordinates (mm) of a point given in (fractional) pixel
    /// coordinates, where pixel `(i, j)` covers `[i, i+1) x [j, j+1)`.
    /// The centre of pixel `(i, j)` is `pixel_to_mm(i + 0.5, j + 0.5)`.
    pub fn pixel_to_mm(&self, x: f64, y: f64) -> (f64, f64) {
        let v = (y - self.cy) * self.pitch_y_mm;
        let u = (x - self.cx - self.skew * v / self.focal_mm) * self.pitch_x_mm;
        (u, v)
    }

    /// Pixel coordinates (fractional, `(0,0)` = top-left corner) of sensor point `(u, v)` mm.
    pub fn mm_to_pixel(&self, u: f64, v: f64) -> (f64, f64) {
        (
            u / self.pitch_x_mm + self.skew * v / self.focal_mm + self.cx,
            v / self.pitch_y_mm + self.cy,
        )
    }

    /// Converts a sensor-plane velocity (mm/s) into pixel velocity (px/s), skew included.
    pub fn mm_to_px_velocity(&self, du: f64, dv: f64) -> (f64, f64) {
        (
            du / self.pitch_x_mm + self.skew * dv / self.focal_mm,
            dv / self.pitch_y_mm,
        )
    }
}
