//! The lens table of the field kernel's table mode (lens model 3,
//! [`crate::gpu::lens::MODEL_TABLE`], in `field.wgsl`): for every lens model the kernel has no analytic
//! formula for (Gyroflow's 12-coefficient `opencv_standard`, `poly3`,
//! `poly5`, `ptlens`, `insta360`, `sony`, `generic_polynomial`, digital
//! lenses), and for every camera with a radial distortion limit, the host
//! computes per grid sample, with the library's f64 camera code
//! ([`crate::camera::Camera::pixel_to_ray`], [`crate::camera::Distortion::jacobian`]):
//!
//! - `q`, the undistorted normalised point seen at the sample;
//! - `J`, the Jacobian of the whole distortion chain (digital warp included)
//!   at `q`, which maps the pinhole flow to the flow on the recorded sensor;
//! - whether the sample is valid: beyond the radial distortion limit it is
//!   masked (`q = J = 0`, so its flow is 0 in the kernel's sums; the host
//!   divides by the valid count and writes NaN in the field).
//!
//! The kernel (and its twin, `super::cpu`) then does the per-twist part,
//! `J flow(q f)`, for every model alike. A table is built once per grid and
//! camera ([`LensTable::cached`]) and uploaded once per runner.

use super::kernel::Grid;
use crate::error::{Error, Result};
use bytemuck::{Pod, Zeroable};
use rayon::prelude::*;
use std::sync::{Arc, Mutex};

/// The shader's `LensSample`: one grid sample's undistorted point and
/// Jacobian (all zero where masked).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct LensSample {
    /// Undistorted normalised point `(x, y)`.
    pub q: [f32; 2],
    /// First row of the Jacobian: `(dxd/dx, dxd/dy)`.
    pub j0: [f32; 2],
    /// Second row: `(dyd/dx, dyd/dy)`.
    pub j1: [f32; 2],
}

const _: () = assert!(std::mem::size_of::<LensSample>() == 24);
const _: () = assert!(std::mem::offset_of!(LensSample, j0) == 8);
const _: () = assert!(std::mem::offset_of!(LensSample, j1) == 16);

/// The lens table of one grid (row-major, as the field).
#[derive(Debug, Clone, PartialEq)]
pub struct LensTable {
    /// The grid it was built for.
    pub grid: Grid,
    /// One entry per sample.
    pub samples: Vec<LensSample>,
    /// False for a masked sample (beyond the radial distortion limit).
    pub valid: Vec<bool>,
    /// Number of valid samples (at least 1).
    pub n_valid: usize,
}

impl LensTable {
    /// The table of `grid`. Errors where a sample within the radial
    /// distortion limit does not undistort (as the CPU rules do), or when
    /// every sample is masked.
    pub fn new(grid: &Grid) -> Result<Self> {
        let c = grid.camera;
        let (sx, sy) = grid.step();
        let rows: Vec<Result<Vec<Option<LensSample>>>> = (0..grid.height)
            .into_par_iter()
            .map(|j| {
                crate::cancel::check()?;
                (0..grid.width)
                    .map(|i| {
                        let (px, py) = ((i as f64 + 0.5) * sx, (j as f64 + 0.5) * sy);
                        let (ud, vd) = c.pixel_to_mm(px, py);
                        if c.is_masked_mm(ud, vd) {
                            return Ok(None);
                        }
                        let (x, y) = c.pixel_to_ray(px, py).ok_or_else(|| {
                            Error::invalid(
                                "distortion",
                                format!(
                                    "the sensor point at pixel ({px:.1}, {py:.1}) does not \
                                     undistort (the {} model folds over there)",
                                    c.distortion.name()
                                ),
                            )
                        })?;
                        let m = c.distortion.jacobian(x, y);
                        Ok(Some(LensSample {
                            q: [x as f32, y as f32],
                            j0: [m[0][0] as f32, m[0][1] as f32],
                            j1: [m[1][0] as f32, m[1][1] as f32],
                        }))
                    })
                    .collect()
            })
            .collect();
        let mut samples = Vec::with_capacity(grid.len());
        let mut valid = Vec::with_capacity(grid.len());
        for row in rows {
            for s in row? {
                valid.push(s.is_some());
                samples.push(s.unwrap_or_else(LensSample::zeroed));
            }
        }
        let n_valid = valid.iter().filter(|&&v| v).count();
        if n_valid == 0 {
            return Err(Error::invalid(
                "distortion",
                "every sample of the grid lies beyond the lens's radial distortion limit",
            ));
        }
        Ok(LensTable {
            grid: *grid,
            samples,
            valid,
            n_valid,
        })
    }

    /// The table of `grid` when the kernel needs one ([`Grid::uses_table`]),
    /// from a one-entry process-wide cache (the last grid and camera).
    pub fn cached(grid: &Grid) -> Result<Option<Arc<LensTable>>> {
        static LAST: Mutex<Option<Arc<LensTable>>> = Mutex::new(None);
        if !grid.uses_table() {
            return Ok(None);
        }
        if let Some(t) = LAST.lock().ok().and_then(|g| g.clone()) {
            if t.grid == *grid {
                return Ok(Some(t));
            }
        }
        let t = Arc::new(LensTable::new(grid)?);
        if let Ok(mut g) = LAST.lock() {
            *g = Some(t.clone());
        }
        Ok(Some(t))
    }

    /// The share of the grid's samples that are masked.
    pub fn masked_share(&self) -> f64 {
        1.0 - self.n_valid as f64 / self.samples.len() as f64
    }
}

/// Samples a mean divides by: the valid ones of `table`, else all of `grid`.
pub fn valid_len(grid: &Grid, table: Option<&LensTable>) -> usize {
    table.map_or(grid.len(), |t| t.n_valid)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::{Camera, Distortion};

    #[test]
    fn table_holds_the_camera_maps_and_masks() {
        let mut cam = Camera::thesis().with_resolution(48, 36);
        cam.distortion = Distortion::Poly5 {
            k1: -0.05,
            k2: 0.004,
        };
        let g = Grid::new(&cam, 0, 0).unwrap();
        assert!(g.uses_table());
        let t = LensTable::new(&g).unwrap();
        assert_eq!((t.samples.len(), t.n_valid), (48 * 36, 48 * 36));
        let (px, py) = (10.5, 7.5);
        let (x, y) = cam.pixel_to_ray(px, py).unwrap();
        let s = t.samples[7 * 48 + 10];
        assert_eq!(s.q, [x as f32, y as f32]);
        let m = cam.distortion.jacobian(x, y);
        assert_eq!(s.j1, [m[1][0] as f32, m[1][1] as f32]);
        // The analytic models without a limit need no table.
        cam.distortion = Distortion::WIDE_ANGLE;
        assert!(!Grid::new(&cam, 0, 0).unwrap().uses_table());
    }
}
