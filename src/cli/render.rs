//! `mmbm render` (being built).

use clap::Args;
use mmbm::error::{Error, Result};

/// (being built)
#[derive(Args, Debug)]
pub struct RenderArgs {}

pub fn run(_a: RenderArgs) -> Result<()> {
    Err(Error::invalid("render", "not implemented yet"))
}
