//! `mmbm blobs` (being built).

use clap::Args;
use mmbm::error::{Error, Result};

/// (being built)
#[derive(Args, Debug)]
pub struct BlobsArgs {}

pub fn run(_a: BlobsArgs) -> Result<()> {
    Err(Error::invalid("blobs", "not implemented yet"))
}
