//! `frames.csv` and `report.md`: the thesis's Tables 5.1, 6.1 and 6.2
//! recomputed per walk and policy.

use super::run::{FrameMeasure, FrameRecord, Walk};
use crate::trigger::{prediction_error, summary_over};
use std::fmt::Write as _;

/// Columns of `frames.csv` (the first six are the contract).
pub const FRAMES_HEADER: &str = "policy,trigger_t,blur_px,jnbm,blobs_found,blobs_ok,walk,exposure_start,exposure_end,\
mmbm_trigger_mm_s,mmbm_exposure_mm_s,kept,rendered,distance_m,disp_px,cpbd,blur_effect,laplacian_var,\
blobs_matched,samples_per_pixel,render_ms,pose_err_m,pose_err_deg";

fn num(x: f64) -> String {
    if x.is_finite() {
        format!("{x}")
    } else {
        String::new()
    }
}

/// `frames.csv` text.
pub fn frames_csv(records: &[FrameRecord]) -> String {
    let mut s = String::from(FRAMES_HEADER);
    s.push('\n');
    for r in records {
        let f = &r.frame;
        let m = r.measure.as_ref();
        let g = |x: Option<f64>| x.map_or(String::new(), num);
        let _ = writeln!(
            s,
            "{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{},{}",
            f.policy,
            f.trigger_t,
            g(m.map(|m| m.blur_px)),
            g(m.map(|m| m.jnbm)),
            m.map_or(String::new(), |m| m.blobs_found.to_string()),
            m.map_or(String::new(), |m| (m.blobs_ok as u8).to_string()),
            r.walk,
            f.exposure_start,
            f.exposure_end,
            f.mmbm_trigger_mm_s,
            f.mmbm_exposure_mm_s,
            f.kept as u8,
            m.is_some() as u8,
            g(m.map(|m| m.distance_m)),
            g(m.map(|m| m.disp_px)),
            g(m.map(|m| m.cpbd)),
            g(m.map(|m| m.blur_effect)),
            g(m.map(|m| m.laplacian_var)),
            m.map_or(String::new(), |m| m.blobs_matched.to_string()),
            m.map_or(String::new(), |m| m.samples_per_pixel.to_string()),
            g(m.map(|m| m.render_ms)),
            g(m.map(|m| m.pose_err_m)),
            g(m.map(|m| m.pose_err_deg)),
        );
    }
    s
}

impl PolicyStats {
    /// Share of rendered frames with all 16 blobs, %; NaN when none was rendered.
    pub fn success_pct(&self) -> f64 {
        if self.rendered > 0 {
            100.0 * self.blobs_ok as f64 / self.rendered as f64
        } else {
            f64::NAN
        }
    }
}

/// Per (walk, policy) statistics over the rendered frames.
#[derive(Debug, Clone)]
pub struct PolicyStats {
    /// Walk name.
    pub walk: String,
    /// Policy string.
    pub policy: String,
    /// Frames triggered.
    pub triggered: usize,
    /// Frames kept (a gate discards some).
    pub kept: usize,
    /// Frames rendered and measured.
    pub rendered: usize,
    /// Kept frames per second of walk.
    pub fps: f64,
    /// Rendered frames with all 16 blobs extracted.
    pub blobs_ok: usize,
    /// Mean JNBM over rendered frames with a defined JNBM.
    pub mean_jnbm: f64,
    /// Mean CPBD.
    pub mean_cpbd: f64,
    /// Mean Crete blur effect (0 sharp .. 1 blurred).
    pub mean_blur_effect: f64,
    /// Mean ground-truth blur, px.
    pub mean_blur: f64,
    /// 95th percentile of the ground-truth blur, px.
    pub p95_blur: f64,
    /// Largest ground-truth blur, px.
    pub max_blur: f64,
    /// Mean exposure MMBM of kept frames, mm/s.
    pub mean_exposure_mmbm: f64,
    /// Mean camera-position error of the pose from the 16 blobs (frames with all 16), m.
    pub mean_pose_err_m: f64,
    /// Mean orientation error of that pose, degrees.
    pub mean_pose_err_deg: f64,
}

fn mean(v: &[f64]) -> f64 {
    if v.is_empty() {
        f64::NAN
    } else {
        v.iter().sum::<f64>() / v.len() as f64
    }
}

/// Nearest-rank percentile (0..100) of `v`; NaN when empty.
pub fn percentile(v: &[f64], q: f64) -> f64 {
    if v.is_empty() {
        return f64::NAN;
    }
    let mut s = v.to_vec();
    s.sort_by(f64::total_cmp);
    let k = ((q / 100.0 * s.len() as f64).ceil() as usize).clamp(1, s.len());
    s[k - 1]
}

/// Statistics of every (walk, policy).
pub fn policy_stats(walks: &[Walk], records: &[FrameRecord]) -> Vec<PolicyStats> {
    let mut out = Vec::new();
    for w in walks {
        let dur = w.samples.last().map_or(0.0, |s| s.t) - w.samples.first().map_or(0.0, |s| s.t);
        for (p, frames) in &w.runs {
            let rs: Vec<_> = records
                .iter()
                .filter(|r| r.walk == w.name && &r.frame.policy == p)
                .filter_map(|r| r.measure.as_ref())
                .collect();
            let blur: Vec<f64> = rs.iter().map(|m| m.blur_px).collect();
            // Mean of one measurement over the frames where it is defined.
            let mean_of = |get: fn(&FrameMeasure) -> f64| {
                let v: Vec<f64> = rs
                    .iter()
                    .map(|m| get(m))
                    .filter(|x| x.is_finite())
                    .collect();
                mean(&v)
            };
            let sm = summary_over(frames, dur);
            out.push(PolicyStats {
                walk: w.name.clone(),
                policy: p.clone(),
                triggered: frames.len(),
                kept: sm.kept,
                rendered: rs.len(),
                fps: sm.effective_fps,
                blobs_ok: rs.iter().filter(|m| m.blobs_ok).count(),
                mean_jnbm: mean_of(|m| m.jnbm),
                mean_cpbd: mean_of(|m| m.cpbd),
                mean_blur_effect: mean_of(|m| m.blur_effect),
                mean_blur: mean(&blur),
                p95_blur: percentile(&blur, 95.0),
                max_blur: blur.iter().copied().fold(f64::NAN, f64::max),
                mean_exposure_mmbm: sm.mean_mm_s,
                mean_pose_err_m: mean_of(|m| m.pose_err_m),
                mean_pose_err_deg: mean_of(|m| m.pose_err_deg),
            });
        }
    }
    out
}

fn f(x: f64, d: usize) -> String {
    if x.is_finite() {
        format!("{x:.d$}")
    } else {
        "-".into()
    }
}

/// Table 5.1 per walk and policy: instantaneous MMBM at the trigger vs the exposure average.
pub fn table_5_1(walks: &[Walk]) -> String {
    let mut s = String::from(
        "| walk | policy | frames | min err | max err | mean err | mean abs err | std | mean abs err % | max abs err % |\n|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for w in walks {
        for (p, frames) in &w.runs {
            let kept: Vec<_> = frames.iter().filter(|f| f.kept).cloned().collect();
            if kept.is_empty() {
                let _ = writeln!(s, "| {} | {p} | 0 | - | - | - | - | - | - | - |", w.name);
                continue;
            }
            let t = prediction_error(&kept);
            let maxpct = t.pct.min.abs().max(t.pct.max.abs());
            let _ = writeln!(
                s,
                "| {} | {p} | {} | {} | {} | {} | {} | {} | {} | {} |",
                w.name,
                t.abs.n,
                f(t.abs.min, 4),
                f(t.abs.max, 4),
                f(t.abs.mean, 4),
                f(t.abs.mean_abs, 4),
                f(t.abs.std, 4),
                f(t.pct.mean_abs, 2),
                f(maxpct, 1)
            );
        }
    }
    s
}

/// Tables 6.1 and 6.2 combined: frames, lost frames against the first fixed
/// policy, blob success, JNBM and blur.
pub fn table_6(stats: &[PolicyStats]) -> String {
    let mut s = String::from(
        "| walk | policy | frames kept | fps | frames lost vs fixed | rendered | all 16 blobs | success % | mean JNBM | mean CPBD | mean blur effect | mean blur px | p95 blur px | max blur px | mean exposure MMBM mm/s | pose error cm | pose error deg |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for st in stats {
        let fixed = stats
            .iter()
            .find(|x| x.walk == st.walk && x.policy.starts_with("fixed"))
            .map(|x| x.kept as i64);
        let lost = fixed.map_or("-".into(), |k| (k - st.kept as i64).to_string());
        let succ = st.success_pct();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            st.walk,
            st.policy,
            st.kept,
            f(st.fps, 2),
            lost,
            st.rendered,
            st.blobs_ok,
            f(succ, 1),
            f(st.mean_jnbm, 3),
            f(st.mean_cpbd, 3),
            f(st.mean_blur_effect, 3),
            f(st.mean_blur, 2),
            f(st.p95_blur, 2),
            f(st.max_blur, 2),
            f(st.mean_exposure_mmbm, 3),
            f(100.0 * st.mean_pose_err_m, 1),
            f(st.mean_pose_err_deg, 2)
        );
    }
    s
}
