//! Point-spread function at one pixel (thesis section 5.3.2): the image a
//! point light at the scene point seen at that pixel's centre at exposure
//! start would leave on the sensor over the exposure (box shutter). The track
//! is sampled at uniform times (steps of at most 0.02 px) and splatted
//! bilinearly into a square grid of whole pixels whose centre pixel holds the
//! start point; weights sum to 1. (The blur kernel that maps the sharp image
//! to the blurred one at that pixel is this PSF mirrored through its centre.)

use super::maps::{max_path_px, track};
use super::target::Target;
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::model::trajectory::Trajectory;

/// A PSF image.
#[derive(Debug, Clone, PartialEq)]
pub struct Psf {
    /// Side of the square grid, px (odd).
    pub size: u32,
    /// Weights, row-major, sum 1.
    pub weights: Vec<f32>,
}

/// The PSF at pixel `(x, y)` (column, row; its centre is `(x + 0.5, y + 0.5)`).
pub fn psf(cam: &Camera, target: &Target, traj: &Trajectory, x: f64, y: f64) -> Result<Psf> {
    if !(x >= 0.0 && y >= 0.0 && x < cam.width as f64 && y < cam.height as f64) {
        return Err(Error::invalid(
            "--psf",
            format!(
                "pixel ({x}, {y}) is outside the {}x{} sensor",
                cam.width, cam.height
            ),
        ));
    }
    let lmax = max_path_px(cam, target, traj);
    let steps = ((lmax / 0.02).ceil() as usize).clamp(256, 1 << 20);
    let tr = track(cam, target, traj, x + 0.5, y + 0.5, steps).ok_or_else(|| {
        Error::invalid(
            "--psf",
            format!("the scene point at pixel ({x}, {y}) is not on the target or leaves the view"),
        )
    })?;
    let (x0, y0) = tr[0];
    let ext = tr
        .iter()
        .map(|p| (p.0 - x0).abs().max((p.1 - y0).abs()))
        .fold(0.0, f64::max);
    let half = ext.ceil() as i64 + 1;
    if half > 2048 {
        return Err(Error::invalid(
            "--psf",
            format!("blur too long for a PSF image ({ext:.0} px)"),
        ));
    }
    let size = (2 * half + 1) as u32;
    let mut wts = vec![0.0f64; (size * size) as usize];
    // time weights: trapezoid over the uniform samples
    let m = tr.len() - 1;
    for (k, p) in tr.iter().enumerate() {
        let wt = if k == 0 || k == m { 0.5 } else { 1.0 } / m as f64;
        let gx = p.0 - x0 + half as f64;
        let gy = p.1 - y0 + half as f64;
        let (ix, iy) = (gx.floor() as i64, gy.floor() as i64);
        let (fx, fy) = (gx - ix as f64, gy - iy as f64);
        for (dx, dy, f) in [
            (0, 0, (1.0 - fx) * (1.0 - fy)),
            (1, 0, fx * (1.0 - fy)),
            (0, 1, (1.0 - fx) * fy),
            (1, 1, fx * fy),
        ] {
            let (xx, yy) = (ix + dx, iy + dy);
            if xx >= 0 && yy >= 0 && xx < size as i64 && yy < size as i64 {
                wts[(yy * size as i64 + xx) as usize] += wt * f;
            }
        }
    }
    let sum: f64 = wts.iter().sum();
    Ok(Psf {
        size,
        weights: wts.iter().map(|w| (w / sum) as f32).collect(),
    })
}
