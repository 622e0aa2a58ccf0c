//! `mmbm flow` (being built).

use clap::Args;
use mmbm::error::{Error, Result};

/// (being built)
#[derive(Args, Debug)]
pub struct FlowArgs {}

pub fn run(_a: FlowArgs) -> Result<()> {
    Err(Error::invalid("flow", "not implemented yet"))
}
