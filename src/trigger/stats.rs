//! Summaries of a run, the thesis Table 5.1 analysis, and the frames CSV.

use super::spec::PolicySpec;
use super::timing::Frame;
use crate::error::{Error, Result};
use crate::stats::percentile;
use std::io::Write;

/// Header of the frames CSV written by [`write_frames`].
pub const FRAME_HEADER: &str =
    "policy,trigger_t,exposure_start,exposure_end,mmbm_trigger_mm_s,mmbm_exposure_mm_s,kept,gain";

/// Summary of one policy's frames. The MMBM statistics are over the kept
/// frames' exposure MMBM (NaN when no frame was kept).
#[derive(Debug, Clone, PartialEq)]
pub struct Summary {
    /// The frames' policy ([`Frame::policy`]; `None` when there are no frames).
    pub policy: Option<PolicySpec>,
    /// Frames triggered.
    pub frames: usize,
    /// Frames kept (not discarded by a gate).
    pub kept: usize,
    /// Duration the rate refers to, s.
    pub duration_s: f64,
    /// Kept frames per second over `duration_s`.
    pub effective_fps: f64,
    /// Mean exposure MMBM, mm/s.
    pub mean_mm_s: f64,
    /// 95th percentile of the exposure MMBM (linear interpolation), mm/s.
    pub p95_mm_s: f64,
    /// Largest exposure MMBM, mm/s.
    pub max_mm_s: f64,
    /// Mean MMBM at the trigger sample of the kept frames, mm/s.
    pub mean_trigger_mm_s: f64,
    /// Mean exposure of the kept frames, s (exposure control shortens some).
    pub mean_exposure_s: f64,
    /// Mean blur length on the sensor of the kept frames, exposure MMBM x
    /// exposure, mm (divide by the pixel pitch for px).
    pub mean_blur_mm: f64,
}

/// Summary with the rate over the frames' own span: `duration_s` is
/// `(last - first trigger) * frames / (frames - 1)` (one mean interval per
/// frame), so a fixed 5 fps run reports 5 fps. Prefer [`summary_over`] with
/// the log's duration when it is known.
pub fn summary(frames: &[Frame]) -> Summary {
    let d = match (frames.first(), frames.last()) {
        (Some(a), Some(b)) if frames.len() > 1 => {
            (b.trigger_t - a.trigger_t) * frames.len() as f64 / (frames.len() - 1) as f64
        }
        _ => f64::NAN,
    };
    summary_over(frames, d)
}

/// Summary with the rate over `duration_s` (e.g. the log's duration).
pub fn summary_over(frames: &[Frame], duration_s: f64) -> Summary {
    let kept: Vec<&Frame> = frames.iter().filter(|f| f.kept).collect();
    let e: Vec<f64> = kept.iter().map(|f| f.mmbm_exposure_mm_s).collect();
    let mean = |v: &[f64]| {
        if v.is_empty() {
            f64::NAN
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    let trig: Vec<f64> = kept.iter().map(|f| f.mmbm_trigger_mm_s).collect();
    Summary {
        policy: frames.first().map(|f| f.policy.clone()),
        frames: frames.len(),
        kept: kept.len(),
        duration_s,
        effective_fps: if duration_s > 0.0 {
            kept.len() as f64 / duration_s
        } else {
            f64::NAN
        },
        mean_mm_s: mean(&e),
        p95_mm_s: percentile(&e, 95.0).unwrap_or(f64::NAN),
        max_mm_s: e.iter().copied().fold(f64::NAN, f64::max),
        mean_trigger_mm_s: mean(&trig),
        mean_exposure_s: mean(&kept.iter().map(|f| f.exposure_s()).collect::<Vec<_>>()),
        mean_blur_mm: mean(
            &kept
                .iter()
                .map(|f| f.mmbm_exposure_mm_s * f.exposure_s())
                .collect::<Vec<_>>(),
        ),
    }
}

/// Min, max, mean, mean of absolute values and standard deviation (n - 1) of a sample.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct ErrorStats {
    /// Smallest value.
    pub min: f64,
    /// Largest value.
    pub max: f64,
    /// Mean.
    pub mean: f64,
    /// Mean of |value|.
    pub mean_abs: f64,
    /// Sample standard deviation (NaN for fewer than 2 values).
    pub std: f64,
    /// Number of values.
    pub n: usize,
}

impl ErrorStats {
    /// Statistics of `v` (NaNs everywhere when empty).
    pub fn of(v: &[f64]) -> Self {
        let n = v.len();
        if n == 0 {
            return ErrorStats {
                min: f64::NAN,
                max: f64::NAN,
                mean: f64::NAN,
                mean_abs: f64::NAN,
                std: f64::NAN,
                n,
            };
        }
        let mean = v.iter().sum::<f64>() / n as f64;
        let var = if n > 1 {
            v.iter().map(|x| (x - mean).powi(2)).sum::<f64>() / (n - 1) as f64
        } else {
            f64::NAN
        };
        ErrorStats {
            min: v.iter().copied().fold(f64::INFINITY, f64::min),
            max: v.iter().copied().fold(f64::NEG_INFINITY, f64::max),
            mean,
            mean_abs: v.iter().map(|x| x.abs()).sum::<f64>() / n as f64,
            std: var.sqrt(),
            n,
        }
    }
}

/// Thesis Table 5.1: the error of the instantaneous MMBM at the trigger as a
/// prediction of the exposure-averaged MMBM, over all frames.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Table51 {
    /// `mmbm_exposure - mmbm_trigger`, mm/s.
    pub abs: ErrorStats,
    /// `100 * (mmbm_exposure - mmbm_trigger) / mmbm_trigger`, % (frames with a
    /// trigger MMBM of 0 are left out).
    pub pct: ErrorStats,
}

/// The Table 5.1 analysis of `frames` (all frames, kept or not).
pub fn prediction_error(frames: &[Frame]) -> Table51 {
    let abs: Vec<f64> = frames
        .iter()
        .map(|f| f.mmbm_exposure_mm_s - f.mmbm_trigger_mm_s)
        .collect();
    let pct: Vec<f64> = frames
        .iter()
        .filter(|f| f.mmbm_trigger_mm_s > 0.0)
        .map(|f| 100.0 * (f.mmbm_exposure_mm_s - f.mmbm_trigger_mm_s) / f.mmbm_trigger_mm_s)
        .collect();
    Table51 {
        abs: ErrorStats::of(&abs),
        pct: ErrorStats::of(&pct),
    }
}

/// Writes frames as CSV ([`FRAME_HEADER`]; `kept` is 1 or 0; `gain` the
/// sensor gain relative to the nominal exposure's; floats in
/// shortest round-trip form). `header` false appends rows only.
pub fn write_frames(w: &mut dyn Write, frames: &[Frame], header: bool) -> Result<()> {
    let e = |e: std::io::Error| Error::io("<frames output>", e);
    if header {
        writeln!(w, "{FRAME_HEADER}").map_err(e)?;
    }
    for f in frames {
        writeln!(
            w,
            "{},{},{},{},{},{},{},{}",
            f.policy,
            f.trigger_t,
            f.exposure_start,
            f.exposure_end,
            f.mmbm_trigger_mm_s,
            f.mmbm_exposure_mm_s,
            u8::from(f.kept),
            f.gain
        )
        .map_err(e)?;
    }
    Ok(())
}
