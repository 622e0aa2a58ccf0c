//! Flow fields (`field.wgsl`): the per-pixel image-plane flow of docs/spec.md
//! section 2 at full sensor resolution, its mean speed (MMBM, mm/s), and
//! batched MMBM for many twists in one dispatch.
//!
//! The same shape as the renderer: `kernel` holds the host structs shared
//! with WGSL (with layout asserts), `gpu` the compiled kernels and their
//! runner, [`cpu`] the CPU twins written from the same formula, and
//! [`flow_field`] picks one by [`Backend`].
//!
//! The field is computed in f32; per-thread and per-workgroup sums are f32
//! (at most 32 and 64 terms), and the partial sums are added in f64 on the
//! host.
//!
//! Lens distortion: the kernel has OpenCV's five-coefficient model and the
//! fisheye analytically; every other model (and any camera with a radial
//! distortion limit that masks part of the sensor) runs in table mode, where
//! the host gives the kernel each sample's undistorted point and Jacobian
//! ([`LensTable`]). Masked samples are out of the mean and NaN in the field.

pub mod cpu;
pub(crate) mod gpu;
pub(crate) mod kernel;
pub(crate) mod table;

pub use crate::gpu::Backend;
pub use cpu::FieldMean;
pub use gpu::{FlowRunner, FIELD_WGSL};
pub use kernel::{FlowParams, Grid, TwistGpu};
pub use table::{LensSample, LensTable};

use crate::error::{Error, Result};
use crate::gpu::Resolved;
use crate::metric::{Mmbm, Scene};
use crate::model::motion::Twist;
use std::sync::atomic::AtomicBool;

/// A flow field on a grid (px/s) and its MMBM.
#[derive(Debug, Clone, PartialEq)]
pub struct FlowField {
    /// Samples per row.
    pub width: u32,
    /// Rows.
    pub height: u32,
    /// Horizontal flow, px/s (+ right), row-major, top row first.
    pub u: Vec<f32>,
    /// Vertical flow, px/s (+ down).
    pub v: Vec<f32>,
    /// The share of the samples beyond the lens's radial distortion limit:
    /// NaN in `u` and `v`, out of the mean (0 without a limit).
    pub masked: f64,
    /// Mean speed of the field's samples: `mm_s` on the sensor, `px_s` the
    /// mean of [`FlowField::speed`] (the true pixel speed; `mm_s / pitch`
    /// with square, unskewed pixels).
    pub mmbm: Mmbm,
}

impl FlowField {
    /// Per-sample speed `|(u, v)|`, px/s.
    pub fn speed(&self) -> Vec<f32> {
        self.u
            .iter()
            .zip(&self.v)
            .map(|(a, b)| a.hypot(*b))
            .collect()
    }
}

/// The MMBM of a field's samples: `mean_mm_s`, and in px/s `mean_mm_s / pitch`
/// with square pixels, else the mean of the samples' px/s speeds `field`
/// (which [`needs_field`] says must then be computed) over the valid ones
/// (`lens`: masked samples are out of the mean).
fn to_mmbm(
    scene: &Scene,
    mean_mm_s: f64,
    grid: &Grid,
    field: &[[f32; 2]],
    lens: Option<&LensTable>,
) -> Result<Mmbm> {
    let px_s = if needs_field(scene) {
        let ok = |k: usize| lens.is_none_or(|t| t.valid[k]);
        let sum: f64 = (0..field.len())
            .filter(|&k| ok(k))
            .map(|k| field[k][0].hypot(field[k][1]) as f64)
            .sum();
        let px = sum / table::valid_len(grid, lens) as f64;
        if !px.is_finite() {
            return Err(Error::invalid(
                "MMBM",
                format!("the field's mean pixel speed is {px}, not a finite number"),
            ));
        }
        px
    } else {
        crate::camera::checked_px_s(mean_mm_s, scene.camera.pitch_x_mm)?
    };
    Ok(Mmbm {
        mm_s: mean_mm_s,
        px_s,
        error_estimate: None,
        evaluations: grid.len() as u64,
    })
}

/// True when the MMBM in px/s needs the field's px/s samples (pixels not
/// square or skewed: [`crate::metric::pixel_map`]).
fn needs_field(scene: &Scene) -> bool {
    crate::metric::pixel_map(&scene.camera).is_some()
}

static ANNOUNCED: AtomicBool = AtomicBool::new(false);

/// Most cells of a flow field [`flow_field`] returns (8192 x 8192; about 12
/// bytes each: u, v and the speed), for every door (CLI, dataset, Python).
pub use crate::limits::MAX_FIELD_PIXELS;

/// The flow field (px/s) of `tw` on a `w x h` grid of cell centres (`0 x 0`:
/// every pixel centre of the sensor) and its mean speed, on `backend` (the
/// GPU kernel `flow_tiles` or its CPU twin). Validates the scene (a plane is
/// needed when `tw` translates) and the size (at most [`MAX_FIELD_PIXELS`]).
pub fn flow_field(
    scene: &Scene,
    tw: &Twist,
    w: u32,
    h: u32,
    backend: Backend,
) -> Result<FlowField> {
    scene.validate_for(tw)?;
    let grid = Grid::new(&scene.camera, w, h)?;
    if grid.len() as u64 > MAX_FIELD_PIXELS {
        return Err(Error::invalid(
            "flow field",
            format!(
                "{}x{} cells: a flow field has at most {MAX_FIELD_PIXELS} (use a smaller sensor or grid)",
                grid.width, grid.height
            ),
        ));
    }
    let g = TwistGpu::new(scene.camera.focal_mm, tw, scene.plane.as_ref());
    let lens = LensTable::cached(&grid)?;
    let lens = lens.as_deref();
    let (mean, mut field) = match backend.resolve("flow field", "twin", &ANNOUNCED)? {
        Resolved::Gpu(_) => {
            let (sums, field) = FlowRunner::new()?.tiles(&grid, &[g], true)?;
            (sums[0] / table::valid_len(&grid, lens) as f64, field)
        }
        Resolved::Cpu(threads) => {
            let run = || cpu::flow_tiles(&grid, &g, true);
            let f = match threads {
                None => run(),
                Some(t) => rayon::ThreadPoolBuilder::new()
                    .num_threads(t)
                    .build()
                    .map_err(|e| Error::invalid("threads", e.to_string()))?
                    .install(run),
            }?;
            (f.mean_mm_s, f.field)
        }
    };
    // A stop requested during the pass (crate::cancel): the field is partial.
    crate::cancel::check()?;
    if !mean.is_finite()
        || field
            .iter()
            .any(|x| !(x[0].is_finite() && x[1].is_finite()))
    {
        return Err(Error::invalid(
            "motion",
            "the flow field overflows f32 (velocities too large for the sensor); nothing written",
        ));
    }
    let mmbm = to_mmbm(scene, mean, &grid, &field, lens)?;
    if let Some(t) = lens {
        for (x, ok) in field.iter_mut().zip(&t.valid) {
            if !ok {
                *x = [f32::NAN; 2];
            }
        }
    }
    Ok(FlowField {
        width: grid.width,
        height: grid.height,
        u: field.iter().map(|x| x[0]).collect(),
        v: field.iter().map(|x| x[1]).collect(),
        masked: lens.map_or(0.0, LensTable::masked_share),
        mmbm,
    })
}

/// [`flow_field`] on the GPU (an error without an adapter).
pub fn flow_field_gpu(scene: &Scene, tw: &Twist, w: u32, h: u32) -> Result<FlowField> {
    flow_field(scene, tw, w, h, Backend::Gpu)
}

/// MMBM on the GPU: the mean flow speed over a `w x h` grid of cell centres
/// (`0 x 0`: every pixel centre of the sensor; those beyond the lens's
/// radial distortion limit left out), without writing the field. Validates
/// the scene.
pub fn mmbm_gpu(scene: &Scene, tw: &Twist, w: u32, h: u32) -> Result<Mmbm> {
    scene.validate_for(tw)?;
    let grid = Grid::new(&scene.camera, w, h)?;
    let g = TwistGpu::new(scene.camera.focal_mm, tw, scene.plane.as_ref());
    let mut r = FlowRunner::new()?;
    let lens = r.lens(&grid)?;
    let (sums, field) = r.tiles(&grid, &[g], needs_field(scene))?;
    let mean = sums[0] / table::valid_len(&grid, lens.as_deref()) as f64;
    if !mean.is_finite() {
        return Err(Error::invalid(
            "motion",
            format!("MMBM is {mean}: the flow overflows f32 on the GPU"),
        ));
    }
    to_mmbm(scene, mean, &grid, &field, lens.as_deref())
}
