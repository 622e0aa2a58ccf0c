//! `mmbm demo` (being built).

use clap::Args;
use mmbm::error::{Error, Result};

/// (being built)
#[derive(Args, Debug)]
pub struct DemoArgs {}

pub fn run(_a: DemoArgs) -> Result<()> {
    Err(Error::invalid("demo", "not implemented yet"))
}
