//! Figures with plotters (bitmap backend): the shared font and error
//! plumbing here, flow-field quivers in [`quiver`]. Labels use the bundled
//! DejaVu Sans (`assets/DejaVuSans.ttf`, licence beside it), registered once
//! per process. Figures of a feature live with it (`tables`, `experiment`).

pub mod quiver;

use crate::error::{Error, Result};
use plotters::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

static FONT: &[u8] = include_bytes!("../../../assets/DejaVuSans.ttf");

/// Registers the bundled font as plotters' `sans-serif` (once per process).
pub fn ensure_font() -> Result<()> {
    static DONE: OnceLock<bool> = OnceLock::new();
    let ok = *DONE.get_or_init(|| {
        plotters::style::register_font("sans-serif", FontStyle::Normal, FONT).is_ok()
    });
    if ok {
        Ok(())
    } else {
        Err(Error::invalid(
            "font",
            "the bundled DejaVuSans.ttf could not be loaded",
        ))
    }
}

/// Turns a plotters error into ours, naming the file.
pub fn plot_error<E: std::fmt::Display>(path: &Path) -> impl Fn(E) -> Error + '_ {
    move |e| Error::Image {
        path: path.into(),
        message: format!("plot: {e}"),
    }
}
