//! The Fig. 4.6 study: the error of the grid rules (`riemann`, `gauss`)
//! against the exact value over 70 rotation directions, as numbers and as a
//! log-log plot.

use crate::error::Result;
#[cfg(feature = "plot")]
use crate::io::atomic::write_atomic_path;
use crate::metric::{mmbm, Method, Scene};
use crate::model::motion::Twist;
#[cfg(feature = "plot")]
use crate::plot::{ensure_font, plot_error};
use glam::DVec3;
#[cfg(feature = "plot")]
use plotters::prelude::*;
use serde::Serialize;
#[cfg(feature = "plot")]
use std::path::Path;

/// One point of the grid-error study.
#[derive(Debug, Clone, Serialize)]
pub struct GridErrorRow {
    /// Rule name (`riemann` or `gauss`).
    pub rule: String,
    /// Nodes across.
    pub nu: u32,
    /// Nodes down.
    pub nv: u32,
    /// Mean of `100 (mu - mu*) / mu` over the motions.
    pub mean_pct: f64,
    /// Largest `|100 (mu - mu*) / mu|` over the motions.
    pub max_abs_pct: f64,
}

/// Rotation directions used for the grid-error study: the axes, pairs, the
/// diagonal and 64 pseudo-random unit directions (fixed seed).
pub fn study_motions() -> Vec<DVec3> {
    let mut v = vec![
        DVec3::X,
        DVec3::Y,
        DVec3::Z,
        DVec3::new(1., 0., 1.),
        DVec3::new(1., 1., 0.),
        DVec3::ONE,
    ];
    let mut s = 0x9E37_79B9_7F4A_7C15u64;
    let mut rnd = || {
        s ^= s << 13;
        s ^= s >> 7;
        s ^= s << 17;
        (s >> 11) as f64 / (1u64 << 53) as f64 * 2.0 - 1.0
    };
    while v.len() < 70 {
        let d = DVec3::new(rnd(), rnd(), rnd());
        if d.length() > 0.1 && d.length() <= 1.0 {
            v.push(d.normalize());
        }
    }
    v
}

/// Fig. 4.6 as numbers: error of `riemann:NxM` and `gauss:NxM` against exact,
/// for 4:3 grids from 2x2 (riemann 2x2, then 4x3 ... 64x48).
pub fn grid_error() -> Result<Vec<GridErrorRow>> {
    let s = Scene::thesis();
    let motions = study_motions();
    let exact: Vec<f64> = motions
        .iter()
        .map(|w| {
            Ok(mmbm(
                &s,
                &Twist::new(*w, DVec3::ZERO),
                Method::Exact { tol: 1e-11 },
            )?
            .mm_s)
        })
        .collect::<Result<_>>()?;
    let grids = [
        (2, 2),
        (4, 3),
        (8, 6),
        (12, 9),
        (16, 12),
        (32, 24),
        (64, 48),
    ];
    let mut rows = Vec::new();
    for (nu, nv) in grids {
        for (rule, method) in [
            ("riemann", Method::Riemann { nu, nv }),
            ("gauss", Method::Gauss { nu, nv }),
        ] {
            let errs: Vec<f64> = motions
                .iter()
                .zip(&exact)
                .map(|(w, e)| {
                    Ok(100.0 * (e - mmbm(&s, &Twist::new(*w, DVec3::ZERO), method)?.mm_s) / e)
                })
                .collect::<Result<_>>()?;
            rows.push(GridErrorRow {
                rule: rule.into(),
                nu,
                nv,
                mean_pct: errs.iter().sum::<f64>() / errs.len() as f64,
                max_abs_pct: errs.iter().fold(0.0, |a, b| a.max(b.abs())),
            });
        }
    }
    Ok(rows)
}

#[cfg(feature = "plot")]
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
