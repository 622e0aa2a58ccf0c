//! Host-side structs shared with `field.wgsl` (`Params`, `Twist`;
//! `LensSample` is in [`super::table`]), with layout asserts, and the sample
//! grid they describe.

use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::gpu::lens::LensGpu;
use crate::model::motion::{Plane, Twist};
use bytemuck::{Pod, Zeroable};

/// Threads per workgroup of both kernels (`WG` in the shader).
pub const WG: u32 = 64;
/// Samples per thread of `flow_tiles` (`CHUNK` in the shader).
pub const CHUNK: u32 = 32;
/// Samples per workgroup of `flow_tiles` (`TILE` in the shader).
pub const TILE: u32 = WG * CHUNK;
/// Most workgroups along one dispatch dimension (WebGPU default limit).
pub const MAX_DISPATCH: u32 = 65_535;

/// The shader's `Params`: camera intrinsics (f32) and the sample grid.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct FlowParams {
    /// Focal length, mm.
    pub f_mm: f32,
    /// Horizontal pixel pitch, mm.
    pub pitch_x: f32,
    /// Vertical pixel pitch, mm.
    pub pitch_y: f32,
    /// Principal point column, px.
    pub cx: f32,
    /// Principal point row, px.
    pub cy: f32,
    /// Skew (px) divided by the focal length (mm).
    pub skew_over_f: f32,
    /// Grid cell width, px (1 at sensor resolution).
    pub step_x: f32,
    /// Grid cell height, px.
    pub step_y: f32,
    /// Samples per grid row.
    pub grid_w: u32,
    /// Grid rows.
    pub grid_h: u32,
    /// Twists in the dispatch.
    pub n_twists: u32,
    /// Tiles of `TILE` samples per twist (`flow_tiles`).
    pub tiles: u32,
    /// Workgroups along x per dispatch row (`flow_tiles`).
    pub tiles_x: u32,
    /// 1 to write the field (one twist), else 0.
    pub write_field: u32,
    /// Padding (to align `lens`).
    pub pad: [u32; 2],
    /// The lens ([`crate::gpu::lens`]): none, OpenCV or fisheye analytic,
    /// else the lens table (every other model, and masked cameras:
    /// `super::table`).
    pub lens: LensGpu,
}

/// The shader's `Twist`: one camera twist and its scene's inverse depth.
#[repr(C)]
#[derive(Debug, Clone, Copy, PartialEq, Pod, Zeroable)]
pub struct TwistGpu {
    /// Angular velocity (rad/s) in xyz; w unused.
    pub omega: [f32; 4],
    /// Linear velocity (m/s) in xyz; w unused.
    pub velocity: [f32; 4],
    /// Inverse depth `1/z = a + b*u + c*v` (1/m, u and v in mm) as `[a, b, c, 0]`;
    /// all zero for rotation only (no plane).
    pub inv_depth: [f32; 4],
}

const _: () = assert!(std::mem::size_of::<FlowParams>() == 96);
const _: () = assert!(std::mem::offset_of!(FlowParams, pad) == 56);
const _: () = assert!(std::mem::offset_of!(FlowParams, lens) == 64);
const _: () = assert!(std::mem::offset_of!(FlowParams, step_y) == 28);
const _: () = assert!(std::mem::offset_of!(FlowParams, grid_w) == 32);
const _: () = assert!(std::mem::offset_of!(FlowParams, write_field) == 52);
const _: () = assert!(std::mem::size_of::<TwistGpu>() == 48);
const _: () = assert!(std::mem::offset_of!(TwistGpu, velocity) == 16);
const _: () = assert!(std::mem::offset_of!(TwistGpu, inv_depth) == 32);

impl TwistGpu {
    /// The twist for focal length `f` mm; `plane = None` drops the translation
    /// (rotation only, like [`crate::model::flow::flow_at`]).
    pub fn new(f: f64, tw: &Twist, plane: Option<&Plane>) -> Self {
        let (a, b, c) = plane.map_or((0.0, 0.0, 0.0), |p| p.inverse_depth_coeffs(f));
        let w = tw.omega.as_vec3();
        let v = if plane.is_some() {
            tw.velocity.as_vec3()
        } else {
            glam::Vec3::ZERO
        };
        TwistGpu {
            omega: [w.x, w.y, w.z, 0.0],
            velocity: [v.x, v.y, v.z, 0.0],
            inv_depth: [a as f32, b as f32, c as f32, 0.0],
        }
    }
}

/// A grid of `width x height` equal cells over the sensor, sampled at the cell
/// centres (like `riemann:WxH`); at the camera's resolution the samples are
/// the pixel centres. Cells are laid out in pixel coordinates, so skew is
/// handled as in [`Camera::pixel_to_mm`].
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Grid {
    /// The camera.
    pub camera: Camera,
    /// Cells per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// The kernel reads a lens table ([`Grid::uses_table`]).
    table: bool,
}

impl Grid {
    /// `width x height` cells; `0 x 0` means the camera's resolution.
    /// Rejects a half-zero size and grids of 2^32 samples or more.
    pub fn new(camera: &Camera, width: u32, height: u32) -> Result<Self> {
        camera.validate()?;
        let (w, h) = match (width, height) {
            (0, 0) => (camera.width, camera.height),
            (0, _) | (_, 0) => {
                return Err(Error::invalid(
                    "gpu grid",
                    format!("{width}x{height}: both sides must be positive (or both 0 for the sensor resolution)"),
                ))
            }
            s => s,
        };
        let n = w as u64 * h as u64;
        if n + TILE as u64 >= u32::MAX as u64 {
            return Err(Error::invalid(
                "gpu grid",
                format!("{w}x{h} has {n} samples; at most about 4.29e9 are supported"),
            ));
        }
        Ok(Grid {
            camera: *camera,
            width: w,
            height: h,
            table: camera.distortion.coefficients().is_none() || camera.masked_fraction() > 0.0,
        })
    }

    /// True when the kernel reads a lens table (lens model 3,
    /// [`super::table::LensTable`]): for the models without an analytic
    /// path in the kernel, and for every camera with a radial distortion
    /// limit that masks part of the sensor.
    pub fn uses_table(&self) -> bool {
        self.table
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.width as usize * self.height as usize
    }

    /// True for an empty grid (never, after [`Grid::new`]).
    pub fn is_empty(&self) -> bool {
        self.len() == 0
    }

    /// Tiles of `TILE` samples.
    pub fn tiles(&self) -> u32 {
        (self.len() as u64).div_ceil(TILE as u64) as u32
    }

    /// Cell size in pixels `(x, y)`.
    pub fn step(&self) -> (f64, f64) {
        (
            self.camera.width as f64 / self.width as f64,
            self.camera.height as f64 / self.height as f64,
        )
    }

    /// The shader parameters for `n_twists` twists.
    pub fn params(&self, n_twists: u32, write_field: bool) -> FlowParams {
        let c = &self.camera;
        let (sx, sy) = self.step();
        let tiles = self.tiles();
        let lens = match c.distortion.coefficients() {
            Some(m) if !self.table => LensGpu::new(Some(m)),
            _ => LensGpu::table(),
        };
        FlowParams {
            f_mm: c.focal_mm as f32,
            pitch_x: c.pitch_x_mm as f32,
            pitch_y: c.pitch_y_mm as f32,
            cx: c.cx as f32,
            cy: c.cy as f32,
            skew_over_f: (c.skew / c.focal_mm) as f32,
            step_x: sx as f32,
            step_y: sy as f32,
            grid_w: self.width,
            grid_h: self.height,
            n_twists,
            tiles,
            tiles_x: tiles.min(MAX_DISPATCH),
            write_field: write_field as u32,
            pad: [0; 2],
            lens,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::gpu::compute::shader_const;

    #[test]
    fn grid_sizes_and_params() {
        let cam = Camera::thesis();
        let g = Grid::new(&cam, 0, 0).unwrap();
        assert_eq!((g.width, g.height, g.len()), (640, 480, 307_200));
        assert_eq!(g.tiles(), 150);
        let p = Grid::new(&cam, 8, 6).unwrap().params(3, false);
        assert_eq!(
            (p.step_x, p.step_y, p.tiles, p.n_twists),
            (80.0, 80.0, 1, 3)
        );
        assert!(Grid::new(&cam, 0, 6).is_err());
        assert!(Grid::new(&cam, 100_000, 100_000).is_err());
    }

    #[test]
    fn shader_constants_match_host() {
        // The workgroup geometry is written in both places; this ties them.
        let m = naga::front::wgsl::parse_str(crate::field::gpu::FIELD_WGSL).expect("parses");
        assert_eq!(shader_const(&m, "WG"), WG);
        assert_eq!(shader_const(&m, "CHUNK"), CHUNK);
        assert_eq!(shader_const(&m, "TILE"), TILE);
        assert_eq!(
            shader_const(&m, "UNDISTORT_STEPS"),
            super::super::cpu::UNDISTORT_STEPS
        );
        assert_eq!(m.entry_points.len(), 2);
        for ep in &m.entry_points {
            assert_eq!(ep.workgroup_size, [WG, 1, 1], "{}", ep.name);
        }
    }

    #[test]
    fn twist_without_plane_drops_translation() {
        let tw = Twist::new(glam::DVec3::new(1.0, 2.0, 3.0), glam::DVec3::ONE);
        let g = TwistGpu::new(4.0, &tw, None);
        assert_eq!(g.velocity, [0.0; 4]);
        assert_eq!(g.omega, [1.0, 2.0, 3.0, 0.0]);
        let p = Plane {
            normal: glam::DVec3::new(0.5, 0.25, 1.0),
            d: 2.0,
        };
        let g = TwistGpu::new(4.0, &tw, Some(&p));
        assert_eq!(g.inv_depth, [0.5, 0.0625, 0.03125, 0.0]);
    }
}
