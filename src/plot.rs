//! Figures with plotters.

use crate::error::{Error, Result};
use crate::tables::GridErrorRow;
use std::path::Path;

/// Fig. 4.6-style plot (being built).
pub fn grid_error_plot(_rows: &[GridErrorRow], _path: &Path) -> Result<()> {
    Err(Error::invalid("--plot", "not implemented yet"))
}
