//! The benefit map as a heat map with two panels, one per task
//! (docs/spec.md section 11): left, sharp frames per second by the blob
//! verdict (the best `mmbm` policy over the best fixed exposure in
//! hindsight); right, frames usable for visual odometry per second (the best
//! `mmbm` policy over the strongest baseline by that count). Rows are
//! lights, columns gait x board; a colour bar gives the scale (log, 0.5x ..
//! 2x, red below 1, blue above) and each cell's text is white on dark
//! colours and black on light ones ([`crate::plot::text_on`]).

use super::super::benefit::Estimate;
use super::report::{lost, timing_verdict};
use super::verdict::column;
use super::{BenefitMap, Cell};
use crate::error::Result;
use crate::io::atomic::write_atomic_path;
use crate::plot::{ensure_font, plot_error, ratio_colour, text_on};
use plotters::prelude::*;
use std::path::Path;

/// Width of one column of one panel, px.
const COL_W: u32 = 330;
/// Height of one row, px.
const ROW_H: u32 = 96;
/// Width of the colour bar's strip, px.
const BAR_W: u32 = 120;

/// Writes the two-panel heat map of `m` to `path`.
pub fn heat_map_png(path: &Path, m: &BenefitMap) -> Result<()> {
    ensure_font()?;
    let mut cols: Vec<String> = Vec::new();
    for c in &m.cells {
        if !cols.contains(&column(c)) {
            cols.push(column(c));
        }
    }
    let (nc, nr) = (cols.len().max(1) as u32, m.lights.len().max(1) as u32);
    let panel_w = 130 + COL_W * nc;
    write_atomic_path(path, |tmp| {
        let e = plot_error(path);
        let root =
            BitMapBackend::new(tmp, (2 * panel_w + BAR_W, 110 + ROW_H * nr)).into_drawing_area();
        root.fill(&WHITE).map_err(&e)?;
        let (panels, bar) = root.split_horizontally(2 * panel_w);
        let (left, right) = panels.split_horizontally(panel_w);
        let tasks: [(&DrawingArea<_, _>, &str, bool); 2] = [
            (
                &left,
                "blob task: best mmbm / best fixed in hindsight (sharp frames/s)",
                false,
            ),
            (
                &right,
                "odometry task: best mmbm / strongest baseline (VO frames/s)",
                true,
            ),
        ];
        for (area, title, vo) in tasks {
            let mut chart = ChartBuilder::on(area)
                .caption(title, ("sans-serif", 15))
                .margin(10)
                .x_label_area_size(40)
                .y_label_area_size(110)
                .build_cartesian_2d(-0.5..nc as f64 - 0.5, -0.5..nr as f64 - 0.5)
                .map_err(&e)?;
            let lights = m.lights.clone();
            let colnames = cols.clone();
            chart
                .configure_mesh()
                .disable_mesh()
                .x_labels(nc as usize)
                .y_labels(nr as usize)
                .x_label_formatter(&|x| {
                    colnames
                        .get(x.round().max(0.0) as usize)
                        .filter(|_| (x - x.round()).abs() < 0.01)
                        .cloned()
                        .unwrap_or_default()
                })
                .y_label_formatter(&|y| {
                    lights
                        .get(y.round().max(0.0) as usize)
                        .filter(|_| (y - y.round()).abs() < 0.01)
                        .map(|l| format!("{l} e-/s"))
                        .unwrap_or_default()
                })
                .draw()
                .map_err(&e)?;
            for c in &m.cells {
                let (Some(ci), Some(ri)) = (
                    cols.iter().position(|x| *x == column(c)),
                    m.lights.iter().position(|&l| l == c.light),
                ) else {
                    continue;
                };
                let r = if vo {
                    c.vo_vs_baseline.map_or(f64::NAN, |r| r.0.value)
                } else {
                    c.vs_hindsight.map_or(f64::NAN, |r| r.value)
                };
                let colour = ratio_colour(r);
                let ink = text_on(colour);
                let (x, y) = (ci as f64, ri as f64);
                chart
                    .draw_series(std::iter::once(Rectangle::new(
                        [(x - 0.5, y - 0.5), (x + 0.5, y + 0.5)],
                        colour.filled(),
                    )))
                    .map_err(&e)?;
                let lines = if vo { vo_labels(c) } else { heat_labels(c) };
                for (k, line) in lines.iter().enumerate() {
                    let size = if k == 0 { 16 } else { 13 };
                    chart
                        .draw_series(std::iter::once(Text::new(
                            line.clone(),
                            (x - 0.46, y + 0.40 - 0.22 * k as f64),
                            ("sans-serif", size).into_font().color(&ink),
                        )))
                        .map_err(&e)?;
                }
            }
        }
        colour_bar(&bar).map_err(&e)?;
        root.present().map_err(&e)?;
        Ok(())
    })
}

/// The colour scale: a vertical strip from 0.5x (bottom) to 2x (top) with
/// ticks at 0.5, 0.71, 1, 1.41 and 2.
fn colour_bar<DB: DrawingBackend>(
    area: &DrawingArea<DB, plotters::coord::Shift>,
) -> std::result::Result<(), DrawingAreaErrorKind<DB::ErrorType>> {
    let (_, h) = area.dim_in_pixel();
    let (top, bottom) = (50i32, h as i32 - 60);
    let (x0, x1) = (14i32, 38i32);
    area.draw(&Text::new(
        "ratio (log)",
        (6, top - 30),
        ("sans-serif", 13).into_font(),
    ))?;
    let span = (bottom - top).max(1);
    for y in top..bottom {
        // log2 ratio from 1 (top) to -1 (bottom).
        let t = 1.0 - 2.0 * f64::from(y - top) / f64::from(span);
        area.draw(&Rectangle::new(
            [(x0, y), (x1, y + 1)],
            ratio_colour(2f64.powf(t)).filled(),
        ))?;
    }
    area.draw(&Rectangle::new(
        [(x0, top), (x1, bottom)],
        BLACK.stroke_width(1),
    ))?;
    for (r, name) in [
        (2.0, "2x"),
        (2f64.sqrt(), "1.41x"),
        (1.0, "1x"),
        (0.5f64.sqrt(), "0.71x"),
        (0.5, "0.5x"),
    ] {
        let y = top + ((1.0 - f64::log2(r)) / 2.0 * f64::from(span)) as i32;
        area.draw(&PathElement::new(
            vec![(x1, y), (x1 + 5, y)],
            BLACK.stroke_width(1),
        ))?;
        area.draw(&Text::new(
            name,
            (x1 + 8, y - 7),
            ("sans-serif", 13).into_font(),
        ))?;
    }
    area.draw(&Text::new(
        "grey: n/a",
        (6, bottom + 14),
        ("sans-serif", 12).into_font(),
    ))?;
    Ok(())
}

fn short(e: &Option<Estimate>) -> String {
    match e {
        Some(e) if e.value.is_finite() && e.lo.is_finite() => {
            format!(
                "{:.2}x [{}, {}]",
                e.value,
                super::super::benefit::bound_text(e.lo),
                super::super::benefit::bound_text(e.hi)
            )
        }
        Some(e) if e.value.is_finite() => format!("{:.2}x", e.value),
        Some(e) if e.value == f64::INFINITY => "unbounded".into(),
        _ => "n/a".into(),
    }
}

/// The lines a heat-map cell of the blob task is labelled with: the best
/// `mmbm` policy over the best fixed exposure in hindsight with its 95 %
/// interval (and `lost` where [`lost`]), over auto-exposure, over the best
/// `gyro-exposure` policy with [`timing_verdict`], and the policy with the
/// most sharp frames per second with that rate.
pub fn heat_labels(c: &Cell) -> Vec<String> {
    let mut first = format!("vs hindsight {}", short(&c.vs_hindsight));
    if lost(c) {
        first += " lost";
    }
    let mut out = vec![
        first,
        format!("vs auto-exposure {}", short(&c.vs_ae)),
        format!(
            "timing vs gyro-exposure {} {}",
            short(&c.vs_gyro),
            timing_verdict(c)
        ),
    ];
    if let Some(w) = c.policies.get(c.winner) {
        out.push(format!("won by {} ({:.2} /s)", w.policy, w.sharp_fps));
    }
    out
}

/// The lines a heat-map cell of the odometry task is labelled with: the
/// best `mmbm` policy by VO frames/s over the strongest baseline by VO
/// frames/s (named), and the policy with the most VO frames per second.
pub fn vo_labels(c: &Cell) -> Vec<String> {
    let mut out = Vec::new();
    match c.vo_vs_baseline {
        Some((r, a, b)) => {
            out.push(format!("VO ratio {}", short(&Some(r))));
            out.push(format!(
                "{} over {}",
                c.policies[a].policy, c.policies[b].policy
            ));
        }
        None => out.push("VO ratio n/a".into()),
    }
    if let Some(w) = c.policies.get(c.vo_winner) {
        out.push(format!("won by {} ({:.2} VO/s)", w.policy, w.vo_fps));
    }
    out
}
