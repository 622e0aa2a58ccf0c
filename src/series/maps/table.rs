//! The maps kernel's lens table (table mode, [`crate::gpu::lens::MODEL_TABLE`]
//! in `maps.wgsl`): for every lens model without a formula in the lens
//! module (Gyroflow's 12-coefficient `opencv_standard`, `poly3`, `poly5`,
//! `ptlens`, `insta360`, `sony`, `generic_polynomial`, digital lenses), the
//! distortion map on a regular grid of the undistorted normalised plane,
//! computed once per camera with the library's f64 camera code
//! ([`crate::camera::Distortion::distort`] and its Jacobian), and the CPU
//! twin of the kernel's bicubic Hermite interpolation (`table_cell`,
//! `table_move`, `table_sum`, `table_distort`: the same f32 operations).
//! The flow's Jacobian at each pixel's ray is tabled per pixel
//! ([`MapsTable::jac`], as the field kernel's lens table): the
//! interpolant's derivative would lose digits to the nodes' f32 rounding
//! over the spacing (measured 1.8e-5 relative, above the flow's 1e-5).
//!
//! The grid covers the camera's rays with a margin of [`MARGIN`] of their
//! extent on each side (a track leaves its pixel's ray by its blur); points
//! beyond it continue the border cells' cubics. Its spacing `h` puts
//! [`SIDE`] nodes on the longer side: the interpolation error, about
//! `h^4 / 384` times the map's fourth derivative, is below f32 rounding for
//! the smooth models (a 4 mm-wide span of 6 normalised units has h = 0.012,
//! 5e-11); a warp with a kink (`gopro6_superview`'s `|x|`) is exact only
//! to `h^2` in the cells that hold it.
//!
//! Unlike the field kernel's table (one entry per grid sample, for a flow
//! at the sample only), the maps kernel evaluates the lens along each
//! pixel's moving track, hence a table over the plane.

use super::MapRays;
use crate::camera::Camera;
use crate::error::{Error, Result};
use bytemuck::{Pod, Zeroable};
use rayon::prelude::*;

/// Nodes on the longer side of the table (at most `SIDE^2` nodes of 32
/// bytes: 8 MiB).
pub const SIDE: usize = 512;
/// Margin around the rays' extent, as a share of the extent, each side.
pub const MARGIN: f64 = 0.25;

/// The shader's `Node`: the distorted point at a node and its derivatives
/// (normalised units; `dx`, `dy` times the spacing, `dxy` times its square).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct NodeGpu {
    /// Distorted point `(xd, yd)`.
    pub d: [f32; 2],
    /// `h d/dx (xd, yd)`.
    pub dx: [f32; 2],
    /// `h d/dy (xd, yd)`.
    pub dy: [f32; 2],
    /// `h^2 d2/dxdy (xd, yd)`.
    pub dxy: [f32; 2],
}

const _: () = assert!(std::mem::size_of::<NodeGpu>() == 32);
const _: () = assert!(std::mem::offset_of!(NodeGpu, dxy) == 24);

/// A camera's lens table.
#[derive(Debug, Clone, PartialEq)]
pub struct MapsTable {
    /// The shader's `table`: node (0, 0) at `(x, y)`, `1 / h`, `h`.
    pub geometry: [f32; 4],
    /// The shader's `table_n`: nodes along x, along y, 0, 0.
    pub n: [u32; 4],
    /// Row-major nodes.
    pub nodes: Vec<NodeGpu>,
    /// Per pixel (row-major) the rows of the distortion's Jacobian at its
    /// ray, `[dxd/dx, dxd/dy, dyd/dx, dyd/dy]` (zeros without a ray).
    pub jac: Vec<[f32; 4]>,
}

impl MapsTable {
    /// The table of `rays`' camera. Errors when no pixel has a ray.
    pub fn new(rays: &MapRays) -> Result<Self> {
        let cam: &Camera = rays.camera();
        let (mut lo, mut hi) = ([f64::INFINITY; 2], [f64::NEG_INFINITY; 2]);
        for &(x, y) in rays.rays() {
            if x.is_finite() && y.is_finite() {
                lo = [lo[0].min(x), lo[1].min(y)];
                hi = [hi[0].max(x), hi[1].max(y)];
            }
        }
        if lo[0] > hi[0] || lo[1] > hi[1] {
            return Err(Error::invalid(
                "distortion",
                "no pixel of the camera has a ray: no lens table for the maps kernel",
            ));
        }
        let ext = (hi[0] - lo[0]).max(hi[1] - lo[1]).max(1e-6);
        let (lo, hi) = (lo.map(|v| v - MARGIN * ext), hi.map(|v| v + MARGIN * ext));
        let h = (1.0 + 2.0 * MARGIN) * ext / (SIDE - 1) as f64;
        let nx = (((hi[0] - lo[0]) / h).ceil() as usize + 1).clamp(2, SIDE);
        let ny = (((hi[1] - lo[1]) / h).ceil() as usize + 1).clamp(2, SIDE);
        let d = cam.distortion;
        // Central differences of the f64 Jacobian for the cross derivative.
        let e = 1e-4 * h;
        let nodes = (0..nx * ny)
            .into_par_iter()
            .with_min_len(1024)
            .map(|k| {
                let (x, y) = (lo[0] + (k % nx) as f64 * h, lo[1] + (k / nx) as f64 * h);
                let p = d.distort(x, y);
                let j = d.jacobian(x, y);
                let (ja, jb) = (d.jacobian(x, y + e), d.jacobian(x, y - e));
                let dxy = [
                    (ja[0][0] - jb[0][0]) / (2.0 * e),
                    (ja[1][0] - jb[1][0]) / (2.0 * e),
                ];
                NodeGpu {
                    d: [p.0 as f32, p.1 as f32],
                    dx: [(h * j[0][0]) as f32, (h * j[1][0]) as f32],
                    dy: [(h * j[0][1]) as f32, (h * j[1][1]) as f32],
                    dxy: [(h * h * dxy[0]) as f32, (h * h * dxy[1]) as f32],
                }
            })
            .collect();
        let jac = rays
            .rays()
            .par_iter()
            .with_min_len(4096)
            .map(|&(x, y)| {
                if x.is_finite() && y.is_finite() {
                    let j = d.jacobian(x, y);
                    [
                        j[0][0] as f32,
                        j[0][1] as f32,
                        j[1][0] as f32,
                        j[1][1] as f32,
                    ]
                } else {
                    [0.0; 4]
                }
            })
            .collect();
        Ok(MapsTable {
            geometry: [lo[0] as f32, lo[1] as f32, (1.0 / h) as f32, h as f32],
            n: [nx as u32, ny as u32, 0, 0],
            nodes,
            jac,
        })
    }

    /// Twin of the shader's `table_cell`: the cell of `(x, y)` (its first
    /// node's column and row, clamped) and the place in it (in spacings).
    #[inline(always)]
    pub fn cell(&self, x: f32, y: f32) -> [f32; 4] {
        let g = self.geometry;
        let u = (x - g[0]) * g[2];
        let v = (y - g[1]) * g[2];
        let i = u.floor().clamp(0.0, (self.n[0] - 2) as f32);
        let j = v.floor().clamp(0.0, (self.n[1] - 2) as f32);
        [i, j, u - i, v - j]
    }

    /// Twin of the shader's `table_move`: the cell of the ray `r + e` from
    /// `r`'s cell `c`.
    #[inline(always)]
    fn moved(&self, c: [f32; 4], e: [f32; 2]) -> [f32; 4] {
        let s = c[2] + e[0] * self.geometry[2];
        let t = c[3] + e[1] * self.geometry[2];
        let i = (c[0] + s.floor()).clamp(0.0, (self.n[0] - 2) as f32);
        let j = (c[1] + t.floor()).clamp(0.0, (self.n[1] - 2) as f32);
        [i, j, s - (i - c[0]), t - (j - c[1])]
    }

    /// Twin of the shader's `table_node`.
    #[inline(always)]
    fn node(&self, c: [f32; 4]) -> &NodeGpu {
        &self.nodes[c[1] as usize * self.n[0] as usize + c[0] as usize]
    }

    /// Twin of the shader's `table_sum`.
    #[inline(always)]
    fn sum(&self, c: [f32; 4], ws: [f32; 4], wt: [f32; 4]) -> [f32; 2] {
        let nx = self.n[0] as usize;
        let k = c[1] as usize * nx + c[0] as usize;
        let (a, b, e, g) = (
            &self.nodes[k],
            &self.nodes[k + 1],
            &self.nodes[k + nx],
            &self.nodes[k + nx + 1],
        );
        std::array::from_fn(|m| {
            ws[1] * wt[0] * a.dx[m]
                + ws[0] * wt[1] * a.dy[m]
                + ws[1] * wt[1] * a.dxy[m]
                + ws[2] * wt[0] * (b.d[m] - a.d[m])
                + ws[3] * wt[0] * b.dx[m]
                + ws[2] * wt[1] * b.dy[m]
                + ws[3] * wt[1] * b.dxy[m]
                + ws[0] * wt[2] * (e.d[m] - a.d[m])
                + ws[1] * wt[2] * e.dx[m]
                + ws[0] * wt[3] * e.dy[m]
                + ws[1] * wt[3] * e.dxy[m]
                + ws[2] * wt[2] * (g.d[m] - a.d[m])
                + ws[3] * wt[2] * g.dx[m]
                + ws[2] * wt[3] * g.dy[m]
                + ws[3] * wt[3] * g.dxy[m]
        })
    }

    /// Twin of the shader's `table_distort`: the distorted point of the ray
    /// `r + e` less that of `r`'s cell's first node, from `r`'s cell `c`.
    #[inline(always)]
    pub fn distort(&self, c: [f32; 4], e: [f32; 2]) -> (f32, f32) {
        let m = self.moved(c, e);
        let (d, d0) = (self.node(m).d, self.node(c).d);
        let s = self.sum(m, hermite(m[2]), hermite(m[3]));
        ((d[0] - d0[0]) + s[0], (d[1] - d0[1]) + s[1])
    }
}

/// Twin of the shader's `hermite`: `h00, h10, h01, h11` at `s`.
#[inline(always)]
fn hermite(s: f32) -> [f32; 4] {
    let s2 = s * s;
    let s3 = s2 * s;
    [
        2.0 * s3 - 3.0 * s2 + 1.0,
        s3 - 2.0 * s2 + s,
        3.0 * s2 - 2.0 * s3,
        s3 - s2,
    ]
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::camera::Distortion;

    /// The interpolant against the f64 map and Jacobian, on and off the
    /// nodes and beyond the rays (within the margin).
    #[test]
    fn table_interpolates_the_lens() {
        let cam = Camera {
            distortion: Distortion::Poly5 {
                k1: -0.05,
                k2: 0.004,
            },
            ..Camera::thesis().scaled_to(96, 72)
        };
        let rays = MapRays::new(&cam).unwrap();
        let t = MapsTable::new(&rays).unwrap();
        assert!(t.n[0] as usize == SIDE && t.n[1] >= 2);
        let mut wd = 0.0f64;
        for &(x, y) in rays.rays().iter().step_by(37) {
            let c = t.cell(x as f32, y as f32);
            let d0 = cam.distortion.distort(x, y);
            let g0 = t.distort(c, [0.0, 0.0]);
            for (dx, dy) in [(0.0, 0.0), (0.013, -0.007), (-0.08, 0.05)] {
                // Differences of distorted points, as the kernel uses them.
                let e = cam.distortion.distort(x + dx, y + dy);
                let g = t.distort(c, [dx as f32, dy as f32]);
                let (ex, ey) = (e.0 - d0.0, e.1 - d0.1);
                let (gx, gy) = ((g.0 - g0.0) as f64, (g.1 - g0.1) as f64);
                wd = wd.max((gx - ex).abs().max((gy - ey).abs()));
            }
        }
        eprintln!("table vs f64: differences {wd:.2e}");
        // f32 rounding of offsets below 0.1 (1e-8) and of the rays (6e-8 of
        // about 1, times the Jacobian; measured 3.0e-8).
        assert!(wd < 2e-7, "{wd:.2e}");
        assert_eq!(t.jac.len(), rays.rays().len());
    }
}
