//! Camera intrinsics: focal length (mm), pixel pitch (mm), resolution,
//! principal point and skew (pixels). Coordinates follow SPEC section 1:
//! x right, y down, z forward; sensor coordinates `(u, v)` in mm.

use crate::error::{finite, positive, Error, Result};
use serde::{Deserialize, Serialize};
use std::path::Path;

/// Pinhole camera intrinsics.
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
}

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
    }

    /// Rejects zero/negative/NaN focal length or pitch, an empty sensor, a non-finite principal point.
    pub fn validate(&self) -> Result<()> {
        positive("focal length (mm)", self.focal_mm)?;
        positive("pixel pitch x (mm)", self.pitch_x_mm)?;
        positive("pixel pitch y (mm)", self.pitch_y_mm)?;
        finite("principal point cx", self.cx)?;
        finite("principal point cy", self.cy)?;
        finite("skew", self.skew)?;
        if self.width == 0 || self.height == 0 {
            return Err(Error::invalid(
                "resolution",
                format!("must be at least 1x1, got {}x{}", self.width, self.height),
            ));
        }
        Ok(())
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

    /// Loads a camera from a TOML (`.toml`) or JSON (any other extension) file.
    /// Missing principal point fields default to the sensor centre.
    pub fn load(path: &Path) -> Result<Self> {
        let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
        let file: CameraFile = if path.extension().is_some_and(|e| e == "toml") {
            toml::from_str(&text).map_err(|e| Error::Config {
                path: path.into(),
                message: e.to_string(),
            })?
        } else {
            serde_json::from_str(&text).map_err(|e| Error::Config {
                path: path.into(),
                message: e.to_string(),
            })?
        };
        let cam = file.into_camera();
        cam.validate().map_err(|e| Error::Config {
            path: path.into(),
            message: e.to_string(),
        })?;
        Ok(cam)
    }
}

/// On-disk camera description; pitch may be given once for square pixels.
#[derive(Debug, Deserialize)]
#[serde(deny_unknown_fields)]
struct CameraFile {
    focal_mm: f64,
    pitch_mm: Option<f64>,
    pitch_x_mm: Option<f64>,
    pitch_y_mm: Option<f64>,
    width: u32,
    height: u32,
    cx: Option<f64>,
    cy: Option<f64>,
    #[serde(default)]
    skew: f64,
}

impl CameraFile {
    fn into_camera(self) -> Camera {
        let p = self.pitch_mm.unwrap_or(f64::NAN);
        Camera {
            focal_mm: self.focal_mm,
            pitch_x_mm: self.pitch_x_mm.unwrap_or(p),
            pitch_y_mm: self.pitch_y_mm.unwrap_or(p),
            width: self.width,
            height: self.height,
            cx: self.cx.unwrap_or(self.width as f64 / 2.0),
            cy: self.cy.unwrap_or(self.height as f64 / 2.0),
            skew: self.skew,
        }
    }
}
