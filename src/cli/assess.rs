//! `mmbm assess` (being built).

use clap::Args;
use mmbm::error::{Error, Result};

/// (being built)
#[derive(Args, Debug)]
pub struct AssessArgs {}

pub fn run(_a: AssessArgs) -> Result<()> {
    Err(Error::invalid("assess", "not implemented yet"))
}
