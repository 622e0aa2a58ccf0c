//! Figures with plotters (bitmap backend). Labels use the bundled DejaVu Sans
//! (`assets/DejaVuSans.ttf`, licence beside it), registered once per process.

use crate::error::{Error, Result};
use crate::output::write_atomic_path;
use crate::tables::GridErrorRow;
use plotters::prelude::*;
use std::path::Path;
use std::sync::OnceLock;

static FONT: &[u8] = include_bytes!("../assets/DejaVuSans.ttf");

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

/// Fig. 4.6-style plot: max |relative error| (%) of the riemann and gauss
/// rules against the exact value, versus the number of points (log-log).
pub fn grid_error_plot(rows: &[GridErrorRow], path: &Path) -> Result<()> {
    ensure_font()?;
    write_atomic_path(path, |tmp| {
        let e = plot_error(path);
        let root = BitMapBackend::new(tmp, (800, 500)).into_drawing_area();
        root.fill(&WHITE).map_err(&e)?;
        let ymin = rows
            .iter()
            .map(|r| r.max_abs_pct.max(1e-6))
            .fold(f64::INFINITY, f64::min);
        let ymax = rows.iter().map(|r| r.max_abs_pct).fold(0.0, f64::max);
        let xmax = rows
            .iter()
            .map(|r| (r.nu * r.nv) as f64)
            .fold(0.0, f64::max);
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Error of real-time MMBM rules vs exact (thesis camera)",
                ("sans-serif", 22),
            )
            .margin(15)
            .x_label_area_size(45)
            .y_label_area_size(70)
            .build_cartesian_2d(
                (3.0..xmax * 1.3).log_scale(),
                (ymin * 0.5..ymax * 2.0).log_scale(),
            )
            .map_err(&e)?;
        chart
            .configure_mesh()
            .x_desc("points per evaluation (grid nu x nv)")
            .y_desc("max |100 (mu - mu*) / mu| over 70 rotations (%)")
            .label_style(("sans-serif", 14))
            .draw()
            .map_err(&e)?;
        for (rule, color) in [("riemann", RED), ("gauss", BLUE)] {
            let pts: Vec<(f64, f64)> = rows
                .iter()
                .filter(|r| r.rule == rule)
                .map(|r| ((r.nu * r.nv) as f64, r.max_abs_pct.max(1e-6)))
                .collect();
            chart
                .draw_series(LineSeries::new(pts.clone(), color.stroke_width(2)))
                .map_err(&e)?
                .label(rule)
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], color.stroke_width(2))
                });
            chart
                .draw_series(pts.iter().map(|&p| Circle::new(p, 4, color.filled())))
                .map_err(&e)?;
        }
        chart
            .configure_series_labels()
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 16))
            .draw()
            .map_err(&e)?;
        root.present().map_err(&e)?;
        Ok(())
    })
}
