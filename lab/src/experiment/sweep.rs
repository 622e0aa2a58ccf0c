//! The exposure trade-off the thesis opens with (its Fig. 1.1): the same
//! frames of the fixed-rate schedule re-rendered at several exposures with
//! the configured camera. A shorter exposure blurs less; with sensor noise
//! (`[camera.noise]`, a light level) it is also darker and noisier, and blob
//! extraction says which wins.

use super::config::ExperimentConfig;
use super::measure::render_and_measure;
use super::walk::Walk;
use crate::error::Result;
use crate::render::Quality;
use crate::trigger::Frame;

/// One exposure of the sweep.
#[derive(Debug, Clone, PartialEq)]
pub struct SweepRow {
    /// Exposure, s.
    pub exposure_s: f64,
    /// Frames rendered (those whose window stays inside the log).
    pub frames: usize,
    /// Frames with all 16 blobs correct, %.
    pub success_pct: f64,
    /// Mean ground-truth blur (sensor mean of the image path), px.
    pub mean_blur_px: f64,
}

/// Re-renders up to `cfg.sweep_frames` frames of the first walk's first
/// fixed-rate policy (else its first policy), evenly spread, at every
/// exposure of `cfg.sweep_exposures_s`.
pub fn exposure_sweep(
    cfg: &ExperimentConfig,
    walks: &[Walk],
    quality: Quality,
) -> Result<Vec<SweepRow>> {
    let Some(walk) = walks.first() else {
        return Ok(Vec::new());
    };
    let Some((_, frames)) = walk
        .runs
        .iter()
        .find(|(p, _)| p.is_baseline())
        .or_else(|| walk.runs.first())
    else {
        return Ok(Vec::new());
    };
    let n = cfg.sweep_frames.min(frames.len());
    let picks: Vec<usize> = (0..n).map(|k| k * frames.len() / n.max(1)).collect();
    let cam = cfg.camera();
    let last = walk.samples.last().map_or(f64::NEG_INFINITY, |s| s.t);
    let mut rows = Vec::new();
    for &e in &cfg.sweep_exposures_s {
        let (mut count, mut ok, mut blur) = (0usize, 0usize, 0.0);
        for (k, &fi) in picks.iter().enumerate() {
            let f = &frames[fi];
            // The camera is busy for the exposure plus its readout.
            if f.exposure_start + cam.shutter.busy_s(e) > last {
                continue;
            }
            // The same trigger, exposed for `e` at the nominal gain.
            let f = Frame {
                exposure_end: f.exposure_start + e,
                ..f.clone()
            };
            let r = render_and_measure(cfg, walk, &f, cam, quality, k as u32)?;
            count += 1;
            ok += r.measure.blobs_ok as usize;
            blur += r.measure.blur_px;
        }
        rows.push(SweepRow {
            exposure_s: e,
            frames: count,
            success_pct: 100.0 * ok as f64 / count.max(1) as f64,
            mean_blur_px: blur / count.max(1) as f64,
        });
    }
    Ok(rows)
}

/// The sweep as a Markdown section; the sentences are computed from the rows.
pub fn sweep_md(cfg: &ExperimentConfig, rows: &[SweepRow]) -> String {
    if rows.is_empty() {
        return String::new();
    }
    let mut s = String::from("\n## Exposure sweep (thesis Fig. 1.1)\n\n");
    let light = match &cfg.camera.noise {
        Some(n) => format!(
            "sensor noise at a light level of {} e-/s for a white pixel (read noise {} e-, full well {} e-, {} bits, seed {})",
            n.phi_e_per_s, n.read_noise_e, n.full_well_e, n.bits, n.seed
        ),
        None => "a noiseless camera (no `[camera.noise]`: shorter exposures cost nothing here but light)".into(),
    };
    s += &format!(
        "The same {} frames of the fixed-rate schedule re-rendered at each exposure, {light}.\n\n",
        rows.iter().map(|r| r.frames).max().unwrap_or(0)
    );
    s += "| exposure (ms) | frames | blob success | mean blur (px) |\n|---|---|---|---|\n";
    for r in rows {
        s += &format!(
            "| {:.0} | {} | {:.0} % | {:.2} |\n",
            r.exposure_s * 1e3,
            r.frames,
            r.success_pct,
            r.mean_blur_px
        );
    }
    if let (Some(best), Some(first), Some(last)) = (
        rows.iter().filter(|r| r.frames > 0).max_by(|a, b| {
            a.success_pct
                .total_cmp(&b.success_pct)
                .then(b.exposure_s.total_cmp(&a.exposure_s))
        }),
        rows.first(),
        rows.last(),
    ) {
        s += &format!(
            "\nBlur grows from {:.2} px at {:.0} ms to {:.2} px at {:.0} ms; blob success is highest ({:.0} %) at {:.0} ms{}.\n",
            first.mean_blur_px,
            first.exposure_s * 1e3,
            last.mean_blur_px,
            last.exposure_s * 1e3,
            best.success_pct,
            best.exposure_s * 1e3,
            if rows.iter().filter(|r| r.success_pct == best.success_pct).count() > 1 {
                " (the shortest of the exposures that tie)"
            } else {
                ""
            }
        );
    }
    s
}
