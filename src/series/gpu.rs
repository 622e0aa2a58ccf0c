//! MMBM of a log on the GPU: each batch's twists evaluated by the flow
//! kernels ([`crate::field::FlowRunner::batch_means`]) in one dispatch (or a
//! few, for large grids).

use super::{sample_scene, BatchFn, SeriesOptions};
use crate::error::Result;
use crate::field::{FlowRunner, Grid, TwistGpu};
use crate::io::gyro::GyroSample;

/// The GPU twists of a batch of gyro samples under `opts` (each sample
/// checked by [`sample_scene`]).
pub fn batch_twists<M>(batch: &[GyroSample], opts: &SeriesOptions<M>) -> Result<Vec<TwistGpu>> {
    let f = opts.scene.camera.focal_mm;
    batch
        .iter()
        .map(|s| {
            let (tw, scene) = sample_scene(s, opts)?;
            Ok(TwistGpu::new(f, &tw, scene.plane.as_ref()))
        })
        .collect()
}

/// A series batch evaluator on the GPU: MMBM (mm/s) of each sample on a
/// `w x h` grid of cell centres (`0 x 0`: sensor resolution), the whole
/// batch in one dispatch (or a few, for large grids). The options' method,
/// of any type `M`, is not used.
pub fn series_evaluator<M: Send + 'static>(
    opts: SeriesOptions<M>,
    w: u32,
    h: u32,
) -> Result<Box<BatchFn<'static>>> {
    opts.scene.camera.validate()?;
    let grid = Grid::new(&opts.scene.camera, w, h)?;
    let mut runner = FlowRunner::new()?;
    Ok(Box::new(move |batch: &[GyroSample]| {
        if batch.is_empty() {
            return Ok(Vec::new());
        }
        let twists = batch_twists(batch, &opts)?;
        let v = runner.batch_means(&grid, &twists)?;
        super::check_values(batch, &v)?;
        Ok(v)
    }))
}
