//! Camera twist (angular + linear velocity in the camera frame) and the scene plane.

use crate::camera::Camera;
use crate::check::finite;
use crate::error::{Error, Result};
use glam::DVec3;

/// Instantaneous camera motion in the camera frame (x right, y down, z forward).
#[derive(Debug, Clone, Copy, PartialEq, Default)]
pub struct Twist {
    /// Angular velocity, rad/s.
    pub omega: DVec3,
    /// Linear velocity, m/s.
    pub velocity: DVec3,
}

impl Twist {
    /// Rotation only.
    pub fn rotation(wx: f64, wy: f64, wz: f64) -> Self {
        Twist {
            omega: DVec3::new(wx, wy, wz),
            velocity: DVec3::ZERO,
        }
    }

    /// Full 6-DoF twist: `w` rad/s, `v` m/s.
    pub fn new(omega: DVec3, velocity: DVec3) -> Self {
        Twist { omega, velocity }
    }

    /// True when the linear velocity is exactly zero (depth is then not needed).
    pub fn is_rotation_only(&self) -> bool {
        self.velocity == DVec3::ZERO
    }

    /// Rejects NaN and infinite components.
    pub fn validate(&self) -> Result<()> {
        for (name, x) in [
            ("wx", self.omega.x),
            ("wy", self.omega.y),
            ("wz", self.omega.z),
            ("vx", self.velocity.x),
            ("vy", self.velocity.y),
            ("vz", self.velocity.z),
        ] {
            finite(name, x)?;
        }
        Ok(())
    }
}

/// Scene plane `n . X = d` in the camera frame (X in metres). The normal need
/// not be unit length. A fronto-parallel plane at depth `z` is `n = (0,0,1), d = z`.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Plane {
    /// Plane normal (camera frame).
    pub normal: DVec3,
    /// Offset, metres (for a unit normal: distance from the camera centre).
    pub d: f64,
}

impl Plane {
    /// Fronto-parallel plane at depth `z` metres.
    pub fn fronto(z: f64) -> Self {
        Plane {
            normal: DVec3::Z,
            d: z,
        }
    }

    /// Inverse depth `1/z` (1/m) of the ray through sensor point `(u, v)` mm,
    /// for focal length `f` mm: `(n . (u/f, v/f, 1)) / d`.
    pub fn inverse_depth(&self, f: f64, u: f64, v: f64) -> f64 {
        (self.normal.x * u / f + self.normal.y * v / f + self.normal.z) / self.d
    }

    /// The inverse depth as an affine function of the sensor point:
    /// `1/z = a + b u + c v` (1/m, with `u, v` in mm), returned as `(a, b, c)`.
    pub fn inverse_depth_coeffs(&self, f: f64) -> (f64, f64, f64) {
        (
            self.normal.z / self.d,
            self.normal.x / (f * self.d),
            self.normal.y / (f * self.d),
        )
    }

    /// Checks that the plane is finite and lies in front of the camera at
    /// every point of the sensor (depth strictly positive at the four corners;
    /// inverse depth is affine in `(u, v)`, so that covers the whole sensor).
    pub fn validate_for(&self, cam: &Camera) -> Result<()> {
        for (n, x) in [
            ("plane nx", self.normal.x),
            ("plane ny", self.normal.y),
            ("plane nz", self.normal.z),
            ("plane d", self.d),
        ] {
            finite(n, x)?;
        }
        if self.normal.length_squared() == 0.0 {
            return Err(Error::invalid("plane", "normal is the zero vector"));
        }
        if self.d == 0.0 {
            return Err(Error::invalid(
                "plane",
                "d = 0: the plane passes through the camera centre",
            ));
        }
        let r = cam.sensor_rect();
        for (u, v) in [(r.u0, r.v0), (r.u1, r.v0), (r.u0, r.v1), (r.u1, r.v1)] {
            let iz = self.inverse_depth(cam.focal_mm, u, v);
            if iz.is_nan() || iz <= 0.0 {
                return Err(Error::invalid(
                    "plane",
                    format!(
                        "n=({}, {}, {}), d={} is behind the camera or parallel to the view \
                         at sensor point ({u:.4}, {v:.4}) mm (depth = {:.4} m); \
                         depth must be positive over the whole sensor",
                        self.normal.x,
                        self.normal.y,
                        self.normal.z,
                        self.d,
                        1.0 / iz
                    ),
                ));
            }
        }
        Ok(())
    }
}
