//! GPU flow fields (`shaders/flow.wgsl`): the per-pixel image-plane flow of
//! SPEC section 2 at full sensor resolution, its mean speed (MMBM, mm/s), and
//! batched MMBM for many twists (a gyro log chunk) in one dispatch.
//!
//! The field is computed in f32 on the GPU; per-thread and per-workgroup sums
//! are f32 (at most 32 and 64 terms), and the partial sums are added in f64 on
//! the host. CPU twins of both kernels are in [`super::flow_cpu`].

pub use super::flow_cpu::FieldMean;
pub use super::flow_params::{FlowParams, Grid, TwistGpu};
pub use super::flow_runner::FlowRunner;

use crate::error::{Error, Result};
use crate::gyro::GyroSample;
use crate::metric::{Mmbm, Scene};
use crate::motion::Twist;
use crate::series::{sample_scene, BatchFn, SeriesOptions};

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
    /// Mean speed of the field's samples (mm/s on the sensor; also px/s).
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

fn to_mmbm(scene: &Scene, mean_mm_s: f64, grid: &Grid) -> Mmbm {
    Mmbm {
        mm_s: mean_mm_s,
        px_s: mean_mm_s / scene.camera.pitch_x_mm,
        error_estimate: None,
        evaluations: grid.len() as u64,
    }
}

/// The flow field (px/s) of `tw` on a `w x h` grid of cell centres (`0 x 0`:
/// every pixel centre of the sensor) and its mean speed, on the GPU.
/// Validates the scene (a plane is needed when `tw` translates).
pub fn flow_field_gpu(scene: &Scene, tw: &Twist, w: u32, h: u32) -> Result<FlowField> {
    scene.validate_for(tw)?;
    let grid = Grid::new(&scene.camera, w, h)?;
    let g = TwistGpu::new(scene.camera.focal_mm, tw, scene.plane.as_ref());
    let mut r = FlowRunner::new()?;
    let (sums, field) = r.tiles(&grid, &[g], true)?;
    let mean = sums[0] / grid.len() as f64;
    Ok(FlowField {
        width: grid.width,
        height: grid.height,
        u: field.iter().map(|x| x[0]).collect(),
        v: field.iter().map(|x| x[1]).collect(),
        mmbm: to_mmbm(scene, mean, &grid),
    })
}

/// MMBM on the GPU: the mean flow speed over a `w x h` grid of cell centres
/// (`0 x 0`: every pixel centre of the sensor), without writing the field.
/// Validates the scene.
pub fn mmbm_gpu(scene: &Scene, tw: &Twist, w: u32, h: u32) -> Result<Mmbm> {
    scene.validate_for(tw)?;
    let grid = Grid::new(&scene.camera, w, h)?;
    let g = TwistGpu::new(scene.camera.focal_mm, tw, scene.plane.as_ref());
    let mut r = FlowRunner::new()?;
    let (sums, _) = r.tiles(&grid, &[g], false)?;
    Ok(to_mmbm(scene, sums[0] / grid.len() as f64, &grid))
}

/// The GPU twists of a batch of gyro samples under `opts` (rotation only unless
/// `use_velocity`; then the sample's depth or the scene plane, validated per sample).
pub fn batch_twists(batch: &[GyroSample], opts: &SeriesOptions) -> Result<Vec<TwistGpu>> {
    let f = opts.scene.camera.focal_mm;
    batch
        .iter()
        .map(|s| {
            let (tw, plane) = sample_scene(s, opts)?;
            if let Some(p) = &plane {
                let scene = Scene {
                    plane,
                    ..opts.scene
                };
                scene.validate_for(&tw).map_err(|e| {
                    Error::invalid(format!("sample at t = {} s", s.t), e.to_string())
                })?;
                Ok(TwistGpu::new(f, &tw, Some(p)))
            } else {
                Ok(TwistGpu::new(f, &tw, None))
            }
        })
        .collect()
}

/// A series batch evaluator on the GPU: MMBM (mm/s) of each sample on a
/// `w x h` grid of cell centres (`0 x 0`: sensor resolution), the whole
/// batch in one dispatch (or a few, for large grids).
pub fn series_evaluator(opts: SeriesOptions, w: u32, h: u32) -> Result<Box<BatchFn<'static>>> {
    opts.scene.camera.validate()?;
    let grid = Grid::new(&opts.scene.camera, w, h)?;
    let mut runner = FlowRunner::new()?;
    Ok(Box::new(move |batch: &[GyroSample]| {
        if batch.is_empty() {
            return Ok(Vec::new());
        }
        let twists = batch_twists(batch, &opts)?;
        runner.batch_means(&grid, &twists)
    }))
}

/// GPU benchmarks (printed table; see [`super::flow_bench`]).
pub fn bench() -> Result<()> {
    super::flow_bench::run()
}
