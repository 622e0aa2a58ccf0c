//! # mmbm-lab — the research apparatus of mmbm
//!
//! The thesis experiment end to end, its tables and figures, and blur
//! datasets at scale, on top of the [`mmbm`] library, with their own
//! dependencies (plotters, tar, sha2, fs4) so that a program that computes
//! the metric, fields or renders links none of them.
//!
//! # Layers
//!
//! Modules import only from their own layer or the ones below it, in this
//! crate or the library below it (checked by `tests/layers.rs`):
//!
//! | layer | modules | holds |
//! |---|---|---|
//! | 2 | [`plot`] | figures |
//! | 3 | [`tables`] | thesis tables |
//! | 6 | [`experiment`], [`dataset`], [`pickers`] | the thesis experiment end to end; blur datasets at scale; the frame-picking benchmark (docs/pickers.md) |
//!
//! # Features
//!
//! `experiment` (default; implies `plot`) builds [`experiment`]; `plot`
//! (default) builds [`plot`] and `tables::grid_error_plot` with plotters.
//! `--no-default-features` leaves the datasets and the tables, without
//! plotters.
#![deny(unsafe_code)]
#![warn(missing_docs)]

pub mod dataset;
#[cfg(feature = "experiment")]
pub mod experiment;
pub mod pickers;
#[cfg(feature = "plot")]
pub mod plot;
pub mod tables;

// The library's modules at the paths the moved code uses (`crate::render::...`).
use mmbm::{
    camera, cancel, check, diagnostics, error, field, io, limits, metric, model, render, sim,
    Result,
};
// Those only the experiment uses.
#[cfg(feature = "experiment")]
use mmbm::{assess, board, gpu, series, stats, telemetry, trigger};
