//! Report figures: the MMBM trace with trigger instants and shaded exposures
//! (thesis Figs. 5.2 and 5.6), the blur ECDF per policy, and each policy's
//! sharpest and most blurred frame, labelled (`frame_figure`).

use super::config::ExperimentConfig;
use super::measure::FrameRecord;
use super::walk::Walk;
use crate::error::Result;
use crate::gpu::Backend;
use crate::io::atomic::write_atomic_path;
use crate::metric::Scene;
use crate::plot::{ensure_font, plot_error};
use crate::trigger::Family;
use plotters::prelude::*;
use std::collections::HashMap;
use std::path::Path;

pub use super::frame_figure::Extremes;

/// Writes every figure of the report into `out`: per walk the MMBM traces of
/// the main policies, the blur ECDF, the sharpest/most blurred frame
/// figure (from `extremes`, keyed by `(walk, policy)` index) and a flow
/// quiver at the sample of highest MMBM. Returns the file names.
pub fn write_all(
    out: &Path,
    cfg: &ExperimentConfig,
    walks: &[Walk],
    records: &[FrameRecord],
    extremes: &HashMap<(usize, usize), Extremes>,
) -> Result<Vec<String>> {
    let cam = cfg.camera();
    let mut figs = Vec::new();
    for (wi, w) in walks.iter().enumerate() {
        let t: Vec<f64> = w.samples.iter().map(|s| s.t).collect();
        let t0 = t.first().copied().unwrap_or(0.0);
        let window = (
            t0 + 2.0,
            (t0 + 8.0).min(t.last().copied().unwrap_or(t0 + 8.0)),
        );
        for (p, frames) in &w.runs {
            if !(p.is_baseline()
                || p.is_thesis_rule()
                || matches!(p.family, Family::Oracle | Family::Phase))
            {
                continue;
            }
            let ex: Vec<Exposure> = frames
                .iter()
                .filter(|f| f.kept)
                .map(|f| (f.trigger_t, f.exposure_start, f.exposure_end))
                .collect();
            let th = p.threshold_mm_s();
            let name = format!(
                "trace_{}_{}.png",
                w.name,
                p.as_str().replace([':', '.', '@', '+'], "_")
            );
            mmbm_trace(
                &out.join(&name),
                &format!(
                    "{} walk, {p}: MMBM, triggers (x), exposures (shaded); t = {:.0}-{:.0} s of a {:.0} s walk",
                    w.name,
                    window.0 - t0,
                    window.1 - t0,
                    t.last().copied().unwrap_or(t0) - t0
                ),
                &t,
                &w.mmbm,
                window,
                &ex,
                th,
            )?;
            figs.push(name);
        }
        let series: Vec<(String, Vec<f64>)> = w
            .runs
            .iter()
            .map(|(p, _)| {
                let v = records
                    .iter()
                    .filter(|r| r.walk == w.name && r.frame.policy == *p)
                    .filter_map(|r| r.measure.as_ref().map(|m| m.blur_px))
                    .collect();
                (p.to_string(), v)
            })
            .collect();
        let name = format!("blur_hist_{}.png", w.name);
        blur_ecdf(&out.join(&name), &series)?;
        figs.push(name);
        // Sharpest and most blurred frame per policy, labelled, cropped to the board.
        let rows: Vec<(String, &Extremes)> = w
            .runs
            .iter()
            .enumerate()
            .filter_map(|(pi, (p, _))| extremes.get(&(wi, pi)).map(|e| (p.to_string(), e)))
            .collect();
        if !rows.is_empty() {
            let name = format!("frames_{}.png", w.name);
            super::frame_figure::frames_png(&out.join(&name), cam.width, cam.height, &rows)?;
            figs.push(name);
        }
        // Flow quiver at the sample of highest MMBM.
        if let Some((k, _)) = w.mmbm.iter().enumerate().max_by(|a, b| a.1.total_cmp(b.1)) {
            let tw = crate::model::motion::Twist::new(w.samples[k].omega, glam::DVec3::ZERO);
            // The field on the GPU, or its CPU twin when there is no adapter.
            let scene = Scene {
                camera: cam,
                plane: None,
            };
            let f = crate::field::flow_field(&scene, &tw, 0, 0, Backend::Auto)?;
            let (u, v) = (f.u, f.v);
            {
                let name = format!("quiver_{}.png", w.name);
                crate::plot::quiver::quiver_png(&cam, &u, &v, cfg.exposure_s, &out.join(&name))?;
                figs.push(name);
            }
        }
    }
    Ok(figs)
}

/// One exposure to shade on the trace: `(trigger_t, exposure_start, exposure_end)`, s.
pub type Exposure = (f64, f64, f64);

/// MMBM trace (mm/s) over `[t0, t1]` with a horizontal threshold line (if
/// any), crosses at trigger instants and shaded exposures.
pub fn mmbm_trace(
    path: &Path,
    title: &str,
    t: &[f64],
    mmbm: &[f64],
    window: (f64, f64),
    exposures: &[Exposure],
    threshold: Option<f64>,
) -> Result<()> {
    ensure_font()?;
    write_atomic_path(path, |tmp| {
        let e = plot_error(path);
        let root = BitMapBackend::new(tmp, (1000, 400)).into_drawing_area();
        root.fill(&WHITE).map_err(&e)?;
        let (t0, t1) = window;
        let ymax = t
            .iter()
            .zip(mmbm)
            .filter(|(x, _)| **x >= t0 && **x <= t1)
            .map(|(_, y)| *y)
            .fold(0.1, f64::max)
            * 1.1;
        let mut chart = ChartBuilder::on(&root)
            .caption(title, ("sans-serif", 20))
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(55)
            .build_cartesian_2d(t0..t1, 0.0..ymax)
            .map_err(&e)?;
        chart
            .configure_mesh()
            .x_desc("time (s)")
            .y_desc("MMBM (mm/s)")
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(&e)?;
        let shade = RGBColor(120, 170, 255).mix(0.35);
        chart
            .draw_series(
                exposures
                    .iter()
                    .filter(|x| x.2 >= t0 && x.1 <= t1)
                    .map(|&(_, s, en)| {
                        Rectangle::new([(s.max(t0), 0.0), (en.min(t1), ymax)], shade.filled())
                    }),
            )
            .map_err(&e)?;
        let pts: Vec<(f64, f64)> = t
            .iter()
            .zip(mmbm)
            .filter(|(x, _)| **x >= t0 && **x <= t1)
            .map(|(x, y)| (*x, *y))
            .collect();
        chart
            .draw_series(LineSeries::new(pts.clone(), BLUE.stroke_width(1)))
            .map_err(&e)?;
        if let Some(th) = threshold {
            chart
                .draw_series(LineSeries::new(
                    vec![(t0, th), (t1, th)],
                    RED.stroke_width(1),
                ))
                .map_err(&e)?;
        }
        let at = |x: f64| {
            let i = t.partition_point(|&v| v < x).min(t.len().saturating_sub(1));
            mmbm.get(i).copied().unwrap_or(0.0)
        };
        chart
            .draw_series(
                exposures
                    .iter()
                    .filter(|x| x.0 >= t0 && x.0 <= t1)
                    .map(|&(tr, _, _)| Cross::new((tr, at(tr)), 5, BLACK.stroke_width(2))),
            )
            .map_err(&e)?;
        root.present().map_err(&e)?;
        Ok(())
    })
}

/// The empirical cumulative distribution (ECDF) of per-frame blur (px), one
/// step line per series: at blur `x`, the share of the series' rendered
/// frames with blur at most `x` (a curve further left is sharper; no bins,
/// and the lines do not hide each other as overlaid histograms do).
pub fn blur_ecdf(path: &Path, series: &[(String, Vec<f64>)]) -> Result<()> {
    ensure_font()?;
    write_atomic_path(path, |tmp| {
        let e = plot_error(path);
        let root = BitMapBackend::new(tmp, (900, 500)).into_drawing_area();
        root.fill(&WHITE).map_err(&e)?;
        let xmax = series
            .iter()
            .flat_map(|s| s.1.iter().copied())
            .filter(|x| x.is_finite())
            .fold(1.0, f64::max)
            * 1.05;
        let mut chart = ChartBuilder::on(&root)
            .caption(
                "Ground-truth blur per frame: ECDF (share of frames with blur <= x)",
                ("sans-serif", 20),
            )
            .margin(10)
            .x_label_area_size(40)
            .y_label_area_size(55)
            .build_cartesian_2d(0.0..xmax, 0.0..1.02)
            .map_err(&e)?;
        chart
            .configure_mesh()
            .x_desc("blur (px)")
            .y_desc("share of frames with blur <= x")
            .label_style(("sans-serif", 13))
            .draw()
            .map_err(&e)?;
        for (k, (name, v)) in series.iter().enumerate() {
            let c = Palette99::pick(k).to_rgba();
            chart
                .draw_series(LineSeries::new(ecdf_steps(v, xmax), c.stroke_width(2)))
                .map_err(&e)?
                .label(name.clone())
                .legend(move |(x, y)| {
                    PathElement::new(vec![(x, y), (x + 20, y)], c.stroke_width(2))
                });
        }
        chart
            .configure_series_labels()
            .position(SeriesLabelPosition::LowerRight)
            .background_style(WHITE.mix(0.8))
            .border_style(BLACK)
            .label_font(("sans-serif", 14))
            .draw()
            .map_err(&e)?;
        root.present().map_err(&e)?;
        Ok(())
    })
}

/// The ECDF of `v` as the corners of its step line from 0 to `xmax`: at each
/// sorted value `x_i` (the `i`-th of `n`, from 1) the share rises from
/// `(i - 1) / n` to `i / n`; non-finite values are left out.
pub fn ecdf_steps(v: &[f64], xmax: f64) -> Vec<(f64, f64)> {
    let mut xs: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    xs.sort_by(f64::total_cmp);
    let n = xs.len().max(1) as f64;
    let mut pts = vec![(0.0, 0.0)];
    for (i, &x) in xs.iter().enumerate() {
        pts.push((x, i as f64 / n));
        pts.push((x, (i + 1) as f64 / n));
    }
    let last = pts.last().map_or(0.0, |p| p.1);
    pts.push((xmax, last));
    pts
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn ecdf_rises_by_one_over_n_at_each_value() {
        let p = ecdf_steps(&[3.0, 1.0, f64::NAN, 2.0, 2.0], 5.0);
        assert_eq!(
            p,
            [
                (0.0, 0.0),
                (1.0, 0.0),
                (1.0, 0.25),
                (2.0, 0.25),
                (2.0, 0.5),
                (2.0, 0.5),
                (2.0, 0.75),
                (3.0, 0.75),
                (3.0, 1.0),
                (5.0, 1.0)
            ]
        );
    }
}
