//! `mmbm trigger` (being built).

use clap::Args;
use mmbm::error::{Error, Result};

/// (being built)
#[derive(Args, Debug)]
pub struct TriggerArgs {}

pub fn run(_a: TriggerArgs) -> Result<()> {
    Err(Error::invalid("trigger", "not implemented yet"))
}
