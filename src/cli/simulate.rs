//! `mmbm simulate` (being built).

use clap::Args;
use mmbm::error::{Error, Result};

/// (being built)
#[derive(Args, Debug)]
pub struct SimulateArgs {}

pub fn run(_a: SimulateArgs) -> Result<()> {
    Err(Error::invalid("simulate", "not implemented yet"))
}
