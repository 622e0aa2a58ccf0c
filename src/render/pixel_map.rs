//! CPU twin of the render kernels' distortion map (`PixelMap`, `pixel_map`
//! in `prelude.wgsl`), used by the lattice and analytic twins
//! (`super::cpu`) and the image twin (`super::exact`).

use super::layout::{GpuHomography, RenderParams};
use crate::gpu::lens::{self, MODEL_TABLE};

/// Twin of the shader's `PixelMap`: a pixel's distortion map, the pinhole
/// pixel point `p` of its centre's ray and the rows `l` of the Jacobian of
/// undistortion (pixel to pinhole pixel) there.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PixelMap {
    /// Pinhole pixel coordinates of the ray through the pixel centre.
    pub p: [f32; 2],
    /// Rows of the Jacobian of undistortion (dimensionless, px per px).
    pub l: [[f32; 2]; 2],
}

/// Twin of the shader's `pixel_map` (`prelude.wgsl`): pixel `(i, j)`'s map,
/// from the lens module's `undistort` and `jacobian` (twins in
/// [`crate::gpu::lens`]) for models 1 and 2, from the table entry at
/// `lattice[2]` in table mode. Only with a lens (model not 0).
#[inline]
pub fn pixel_map(p: &RenderParams, homs: &[GpuHomography], i: u32, j: u32) -> PixelMap {
    if p.distortion.model == MODEL_TABLE {
        let m = &homs[(p.lattice[2] + j * p.dims[0] + i) as usize];
        return PixelMap {
            p: [m.h0[0], m.h0[1]],
            l: [[m.h0[2], m.h0[3]], [m.h1[0], m.h1[1]]],
        };
    }
    let c = p.pixel;
    let skew = p.pixel2[0];
    let dy = j as f32 + 0.5 - c[1];
    let k = skew * c[3];
    let qd = ((i as f32 + 0.5 - c[0] - k * dy) * c[2], dy * c[3]);
    let q = lens::undistort(&p.distortion, qd.0, qd.1);
    let jd = lens::jacobian(&p.distortion, q.0, q.1);
    let det = jd[0][0] * jd[1][1] - jd[0][1] * jd[1][0];
    // J^-1 A, A = [[sx, -k sx], [0, sy]].
    let m00 = jd[1][1] / det * c[2];
    let m01 = -jd[1][1] / det * k * c[2] - jd[0][1] / det * c[3];
    let m10 = -jd[1][0] / det * c[2];
    let m11 = jd[1][0] / det * k * c[2] + jd[0][0] / det * c[3];
    // A^-1 = [[1 / sx, skew], [0, 1 / sy]].
    PixelMap {
        p: [c[0] + q.0 / c[2] + skew * q.1, c[1] + q.1 / c[3]],
        l: [
            [m00 / c[2] + skew * m10, m01 / c[2] + skew * m11],
            [m10 / c[3], m11 / c[3]],
        ],
    }
}
