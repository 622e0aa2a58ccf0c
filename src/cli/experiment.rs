//! `mmbm experiment` (being built).

use clap::Args;
use mmbm::error::{Error, Result};

/// (being built)
#[derive(Args, Debug)]
pub struct ExperimentArgs {}

pub fn run(_a: ExperimentArgs) -> Result<()> {
    Err(Error::invalid("experiment", "not implemented yet"))
}
