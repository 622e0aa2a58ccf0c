//! GPU flow field (shaders/flow.wgsl) and its CPU twin. (Being built.)

use crate::error::{Error, Result};
use crate::metric::{Mmbm, Scene};
use crate::motion::Twist;
use crate::series::{BatchFn, SeriesOptions};

/// Mean speed of the full field on the GPU.
pub fn mmbm_gpu(_scene: &Scene, _tw: &Twist, _w: u32, _h: u32) -> Result<Mmbm> {
    Err(Error::Gpu("gpu method not implemented yet".into()))
}

/// A series batch evaluator on the GPU.
pub fn series_evaluator(_opts: SeriesOptions, _w: u32, _h: u32) -> Result<Box<BatchFn<'static>>> {
    Err(Error::Gpu("gpu method not implemented yet".into()))
}

/// GPU benchmarks.
pub fn bench() -> Result<()> {
    Err(Error::Gpu("gpu bench not implemented yet".into()))
}
