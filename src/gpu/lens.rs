//! The kernels' one lens: `lens.wgsl` (joined at build in front of every
//! kernel that evaluates a lens: the field and maps kernels,
//! `crate::field::gpu::FIELD_WGSL`, `crate::series::maps::gpu::MAPS_WGSL`,
//! and the renderer's, `crate::render::RENDER_WGSL`,
//! `crate::render::TEXTURE_WGSL`, after which comes the renderer's
//! prelude), its host struct [`LensGpu`] (each of these kernels' `Params`
//! holds one) and the CPU twin of each of its functions, with the same
//! names and f32 operations.
//!
//! One strategy for every kernel: the two models with a formula in the
//! module (OpenCV `k1, k2, p1, p2, k3` and the OpenCV fisheye) run
//! analytically; every other model is table mode ([`MODEL_TABLE`]): the
//! host computes the lens with the library's f64 camera code and the kernel
//! reads its table (the field kernel's per grid sample,
//! `crate::field::table`; the maps kernel's over the undistorted plane,
//! `crate::series::maps::table`; the renderer's per pixel,
//! `crate::render::kernel::pixel_maps`). The field kernel also uses table
//! mode for a camera whose radial distortion limit masks part of the
//! sensor, the renderer for one with a pixel centre beyond it.

use bytemuck::{Pod, Zeroable};

/// The WGSL source of the lens module (`Lens`, `distort`, `jacobian`,
/// `undistort`), valid alone.
pub const LENS_WGSL: &str = include_str!("lens.wgsl");

/// [`LensGpu::model`]: no distortion.
pub const MODEL_NONE: u32 = 0;
/// [`LensGpu::model`]: OpenCV `k1, k2, p1, p2` in `dist`, `k3` in `k3`.
pub const MODEL_OPENCV: u32 = 1;
/// [`LensGpu::model`]: OpenCV fisheye `k1..k4` in `dist`.
pub const MODEL_FISHEYE: u32 = 2;
/// [`LensGpu::model`]: the kernel's lens table (every other model).
pub const MODEL_TABLE: u32 = 3;

/// The shader's `Lens` (32 bytes, 16-aligned in a uniform): the model and
/// its coefficients (dimensionless, normalised coordinates).
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct LensGpu {
    /// OpenCV `k1, k2, p1, p2`; fisheye `k1..k4`; zeros otherwise.
    pub dist: [f32; 4],
    /// OpenCV `k3`.
    pub k3: f32,
    /// [`MODEL_NONE`], [`MODEL_OPENCV`], [`MODEL_FISHEYE`] or [`MODEL_TABLE`].
    pub model: u32,
    /// Padding to 32 bytes.
    pub pad: [u32; 2],
}

const _: () = assert!(std::mem::size_of::<LensGpu>() == 32);
const _: () = assert!(std::mem::offset_of!(LensGpu, k3) == 16);
const _: () = assert!(std::mem::offset_of!(LensGpu, model) == 20);

impl LensGpu {
    /// The lens of a model code and coefficients as
    /// `crate::camera::Distortion::coefficients` gives them
    /// (`[k1, k2, p1, p2, k3]` or `[k1, k2, k3, k4, 0]`), or
    /// [`LensGpu::table`] for `None`.
    pub fn new(coefficients: Option<(u32, [f64; 5])>) -> Self {
        let Some((model, k)) = coefficients else {
            return Self::table();
        };
        LensGpu {
            dist: [k[0] as f32, k[1] as f32, k[2] as f32, k[3] as f32],
            k3: k[4] as f32,
            model,
            pad: [0; 2],
        }
    }

    /// Table mode ([`MODEL_TABLE`], no coefficients).
    pub fn table() -> Self {
        LensGpu {
            model: MODEL_TABLE,
            ..Self::zeroed()
        }
    }
}

/// Newton steps of the shader's `undistort` (`UNDISTORT_STEPS`).
pub const UNDISTORT_STEPS: u32 = 16;

/// Twin of the shader's `atan_poly`: atan(x) for x >= 0 (Abramowitz & Stegun
/// 4.4.49, |error| <= 2e-8 on [0, 1]; reflected above 1).
#[inline(always)]
#[allow(clippy::excessive_precision)]
pub fn atan_poly(x: f32) -> f32 {
    let inv = x > 1.0;
    let z = if inv { 1.0 / x } else { x };
    let z2 = z * z;
    let p = 1.0
        + z2 * (-0.3333314528
            + z2 * (0.1999355085
                + z2 * (-0.1420889944
                    + z2 * (0.1065626393
                        + z2 * (-0.0752896400
                            + z2 * (0.0429096138 + z2 * (-0.0161657367 + z2 * 0.0028662257)))))));
    let a = z * p;
    if inv {
        std::f32::consts::FRAC_PI_2 - a
    } else {
        a
    }
}

/// Twin of the shader's `fisheye_theta_d`: `theta_d(theta)` and its derivative.
#[inline(always)]
fn fisheye_theta_d(l: &LensGpu, th: f32) -> (f32, f32) {
    let k = l.dist;
    let t2 = th * th;
    let poly = 1.0 + t2 * (k[0] + t2 * (k[1] + t2 * (k[2] + t2 * k[3])));
    let d = 1.0 + t2 * (3.0 * k[0] + t2 * (5.0 * k[1] + t2 * (7.0 * k[2] + t2 * 9.0 * k[3])));
    (th * poly, d)
}

/// Twin of the shader's `fisheye_scale`: `s = theta_d / r` and `(ds/dr) / r`.
#[inline(always)]
fn fisheye_scale(l: &LensGpu, x: f32, y: f32) -> (f32, f32) {
    let k = l.dist;
    let r2 = x * x + y * y;
    if r2 < 1e-4 {
        let c = k[0] - 1.0 / 3.0;
        let e = 0.2 - k[0] + k[1];
        return (1.0 + r2 * (c + r2 * e), 2.0 * c + 4.0 * e * r2);
    }
    let r = r2.sqrt();
    let (td, dtd) = fisheye_theta_d(l, atan_poly(r));
    let s = td / r;
    (s, (dtd / (1.0 + r2) - s) / r2)
}

/// Twin of the shader's `distort` (normalised coordinates; model 1 or 2).
#[inline(always)]
pub fn distort(l: &LensGpu, x: f32, y: f32) -> (f32, f32) {
    if l.model == MODEL_OPENCV {
        let k = l.dist;
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (k[0] + r2 * (k[1] + r2 * l.k3));
        return (
            x * radial + 2.0 * k[2] * x * y + k[3] * (r2 + 2.0 * x * x),
            y * radial + k[2] * (r2 + 2.0 * y * y) + 2.0 * k[3] * x * y,
        );
    }
    let s = fisheye_scale(l, x, y).0;
    (s * x, s * y)
}

/// Twin of the shader's `jacobian`: rows `(dxd/dx, dxd/dy), (dyd/dx, dyd/dy)`
/// (model 1 or 2).
#[inline(always)]
pub fn jacobian(l: &LensGpu, x: f32, y: f32) -> [[f32; 2]; 2] {
    if l.model == MODEL_OPENCV {
        let k = l.dist;
        let r2 = x * x + y * y;
        let radial = 1.0 + r2 * (k[0] + r2 * (k[1] + r2 * l.k3));
        let drad = k[0] + r2 * (2.0 * k[1] + r2 * 3.0 * l.k3);
        let off = 2.0 * x * y * drad + 2.0 * k[2] * x + 2.0 * k[3] * y;
        return [
            [
                radial + 2.0 * x * x * drad + 2.0 * k[2] * y + 6.0 * k[3] * x,
                off,
            ],
            [
                off,
                radial + 2.0 * y * y * drad + 6.0 * k[2] * y + 2.0 * k[3] * x,
            ],
        ];
    }
    let (s, g) = fisheye_scale(l, x, y);
    let off = g * x * y;
    [[s + g * x * x, off], [off, s + g * y * y]]
}

/// Twin of the shader's `undistort`: `UNDISTORT_STEPS` Newton steps
/// (model 1 or 2).
#[inline(always)]
pub fn undistort(l: &LensGpu, xd: f32, yd: f32) -> (f32, f32) {
    if l.model == MODEL_FISHEYE {
        let rd = (xd * xd + yd * yd).sqrt();
        if rd == 0.0 {
            return (xd, yd);
        }
        // Newton on r: theta_d(atan(r)) = r_d, d/dr = theta_d'(theta) / (1 + r^2).
        let mut r = rd;
        for _ in 0..UNDISTORT_STEPS {
            let (td, dtd) = fisheye_theta_d(l, atan_poly(r));
            r = (r - (td - rd) * (1.0 + r * r) / dtd).max(0.0);
        }
        let s = r / rd;
        return (xd * s, yd * s);
    }
    let (mut x, mut y) = (xd, yd);
    for _ in 0..UNDISTORT_STEPS {
        let (fx, fy) = distort(l, x, y);
        let (ex, ey) = (fx - xd, fy - yd);
        let j = jacobian(l, x, y);
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        x -= (j[1][1] * ex - j[0][1] * ey) / det;
        y -= (-j[1][0] * ex + j[0][0] * ey) / det;
    }
    (x, y)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn lens_struct_size_matches_wgsl() {
        assert_eq!(
            crate::gpu::compute::struct_size(LENS_WGSL, "Lens"),
            std::mem::size_of::<LensGpu>()
        );
    }

    #[test]
    fn new_takes_the_coefficients_or_the_table() {
        let l = LensGpu::new(Some((MODEL_OPENCV, [0.1, 0.2, 0.3, 0.4, 0.5])));
        assert_eq!((l.dist, l.k3, l.model), ([0.1, 0.2, 0.3, 0.4], 0.5, 1));
        assert_eq!(LensGpu::new(None).model, MODEL_TABLE);
    }
}
