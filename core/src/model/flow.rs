//! The instantaneous image-plane flow of docs/spec.md section 2 (thesis eq. 3.20).
//!
//! For sensor point `(u, v)` mm, focal length `f` mm, twist `w` rad/s, `t` m/s
//! and scene depth `z` m:
//!
//! ```text
//! du/dt =  wz*v - wy*f - (wy/f)*u^2 + (wx/f)*u*v  - (f/z)*vx + (u/z)*vz
//! dv/dt = -wz*u + wx*f - (wy/f)*u*v + (wx/f)*v^2  - (f/z)*vy + (v/z)*vz
//! ```
//!
//! in mm/s. With a plane `n.X = d` the inverse depth is affine in `(u, v)`, so
//! both components are quadratic polynomials in `(u, v)`: [`FlowPoly`] holds
//! their 12 coefficients, the fast form used by the metric's inner loops.

use crate::camera::distortion::apply;
use crate::camera::Camera;
use crate::model::motion::{Plane, Twist};

/// Flow (mm/s) at sensor point `(u, v)` mm, straight from the formula above.
/// `inv_z` is the inverse depth (1/m) of the scene point seen there; it is
/// ignored when the twist has no translation.
#[inline]
pub fn flow_mm(f: f64, u: f64, v: f64, tw: &Twist, inv_z: f64) -> (f64, f64) {
    let w = tw.omega;
    let t = tw.velocity;
    let du = w.z * v - w.y * f - (w.y / f) * u * u + (w.x / f) * u * v - f * inv_z * t.x
        + u * inv_z * t.z;
    let dv = -w.z * u + w.x * f - (w.y / f) * u * v + (w.x / f) * v * v - f * inv_z * t.y
        + v * inv_z * t.z;
    (du, dv)
}

/// Flow at `(u, v)` for a twist and an optional plane (none: rotation only,
/// translation ignored).
#[inline]
pub fn flow_at(f: f64, u: f64, v: f64, tw: &Twist, plane: Option<&Plane>) -> (f64, f64) {
    let iz = plane.map_or(0.0, |p| p.inverse_depth(f, u, v));
    flow_mm(f, u, v, tw, iz)
}

/// Flow (mm/s on the distorted sensor) seen at the distorted sensor point
/// `(ud, vd)` mm (docs/spec.md section 9): the pinhole flow of its undistorted point
/// pushed through the distortion's Jacobian. Without distortion this is
/// exactly [`flow_at`]. `None` where undistortion does not converge.
#[inline]
pub fn flow_distorted(
    cam: &Camera,
    ud: f64,
    vd: f64,
    tw: &Twist,
    plane: Option<&Plane>,
) -> Option<(f64, f64)> {
    if cam.distortion.is_none() {
        return Some(flow_at(cam.focal_mm, ud, vd, tw, plane));
    }
    let (u, v) = cam.undistort_mm(ud, vd)?;
    let fl = flow_at(cam.focal_mm, u, v, tw, plane);
    Some(apply(&cam.distortion_jacobian(u, v), fl))
}

/// The flow as two quadratic polynomials in `(u, v)`: coefficients of
/// `[1, u, v, u^2, u*v, v^2]` for `du/dt` and `dv/dt` (mm/s).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct FlowPoly {
    /// Coefficients of `du/dt`.
    pub du: [f64; 6],
    /// Coefficients of `dv/dt`.
    pub dv: [f64; 6],
}

impl FlowPoly {
    /// Expands the formula for focal length `f` mm. `plane = None` means
    /// rotation only (the translation part is dropped).
    pub fn new(f: f64, tw: &Twist, plane: Option<&Plane>) -> Self {
        let w = tw.omega;
        let (a, b, c) = plane.map_or((0.0, 0.0, 0.0), |p| p.inverse_depth_coeffs(f));
        let t = tw.velocity;
        FlowPoly {
            du: [
                -w.y * f - f * t.x * a,
                -f * t.x * b + t.z * a,
                w.z - f * t.x * c,
                -w.y / f + t.z * b,
                w.x / f + t.z * c,
                0.0,
            ],
            dv: [
                w.x * f - f * t.y * a,
                -w.z - f * t.y * b,
                -f * t.y * c + t.z * a,
                0.0,
                -w.y / f + t.z * b,
                w.x / f + t.z * c,
            ],
        }
    }

    /// Flow components (mm/s) at `(u, v)` mm.
    #[inline(always)]
    pub fn eval(&self, u: f64, v: f64) -> (f64, f64) {
        let p = &self.du;
        let q = &self.dv;
        let du = p[0] + u * (p[1] + p[3] * u + p[4] * v) + v * (p[2] + p[5] * v);
        let dv = q[0] + u * (q[1] + q[3] * u + q[4] * v) + v * (q[2] + q[5] * v);
        (du, dv)
    }

    /// Flow speed (mm/s) at `(u, v)` mm.
    #[inline(always)]
    pub fn speed(&self, u: f64, v: f64) -> f64 {
        let (du, dv) = self.eval(u, v);
        (du * du + dv * dv).sqrt()
    }

    /// The flow seen through the linear map `m` (row-major 2 x 2): the
    /// polynomial of `(m[0] du + m[1] dv, m[2] du + m[3] dv)`, e.g. mm/s to
    /// px/s with a camera's pixel map (`metric::pixel_map`).
    pub fn mapped(&self, m: [f64; 4]) -> FlowPoly {
        FlowPoly {
            du: std::array::from_fn(|k| m[0] * self.du[k] + m[1] * self.dv[k]),
            dv: std::array::from_fn(|k| m[2] * self.du[k] + m[3] * self.dv[k]),
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use glam::DVec3;

    #[test]
    fn poly_matches_formula() {
        let f = 4.2548;
        let tw = Twist::new(DVec3::new(0.3, -1.2, 0.7), DVec3::new(0.2, -0.1, 0.5));
        let plane = Plane {
            normal: DVec3::new(0.1, -0.2, 1.0),
            d: 2.0,
        };
        let poly = FlowPoly::new(f, &tw, Some(&plane));
        for &(u, v) in &[(0.0, 0.0), (1.4, -1.1), (-1.2, 0.9), (0.3, 0.2)] {
            let (a, b) = flow_at(f, u, v, &tw, Some(&plane));
            let (c, d) = poly.eval(u, v);
            assert!(
                (a - c).abs() < 1e-12 && (b - d).abs() < 1e-12,
                "{a} {c} {b} {d}"
            );
        }
    }

    #[test]
    fn rotation_only_ignores_translation_without_plane() {
        let tw = Twist::new(DVec3::new(0.0, 0.0, 1.0), DVec3::new(5.0, 5.0, 5.0));
        let p = FlowPoly::new(4.0, &tw, None);
        assert_eq!(p.eval(1.0, 0.0), (0.0, -1.0));
    }
}
