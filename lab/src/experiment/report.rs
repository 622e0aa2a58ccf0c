//! What the experiment produced ([`Outcome`]) and its text: `frames.csv`
//! and `report.md` (findings computed from the data, the thesis's Tables
//! 5.1, 6.1 and 6.2 recomputed per walk and policy).

pub use super::frames_csv::frames_csv;

use super::config::ExperimentConfig;
use super::measure::{FrameMeasure, FrameRecord};
use super::walk::Walk;
use crate::stats;
use crate::trigger::{prediction_error, summary_over, PolicySpec};
use std::fmt::Write as _;

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
    pub policy: PolicySpec,
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
    /// Frames with all 16 blobs by the fixed-threshold detector.
    pub blobs_ok_fixed: usize,
    /// Mean ground-truth blur of the frames with all 16 blobs (adaptive), px.
    pub mean_blur_ok: f64,
    /// Mean ground-truth blur of the frames without, px.
    pub mean_blur_failed: f64,
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

/// Mean of `v`; NaN when empty.
fn mean(v: &[f64]) -> f64 {
    stats::mean(v).unwrap_or(f64::NAN)
}

/// The `q`-th percentile of `v` ([`stats::percentile`]); NaN when empty.
fn percentile(v: &[f64], q: f64) -> f64 {
    stats::percentile(v, q).unwrap_or(f64::NAN)
}

/// Statistics of every (walk, policy).
pub fn policy_stats(walks: &[Walk], records: &[FrameRecord]) -> Vec<PolicyStats> {
    let mut out = Vec::new();
    for w in walks {
        let dur = w.samples.last().map_or(0.0, |s| s.t) - w.samples.first().map_or(0.0, |s| s.t);
        for (p, frames) in &w.runs {
            let rs: Vec<_> = records
                .iter()
                .filter(|r| r.walk == w.name && r.frame.policy == *p)
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
                blobs_ok_fixed: rs.iter().filter(|m| m.blobs_ok_fixed).count(),
                mean_blur_ok: mean(
                    &rs.iter()
                        .filter(|m| m.blobs_ok)
                        .map(|m| m.blur_px)
                        .collect::<Vec<_>>(),
                ),
                mean_blur_failed: mean(
                    &rs.iter()
                        .filter(|m| !m.blobs_ok)
                        .map(|m| m.blur_px)
                        .collect::<Vec<_>>(),
                ),
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
        "| walk | policy | frames kept | discarded by a gate | fps | frames lost vs fixed | rendered | all 16 blobs | success % | success % fixed threshold | mean JNBM | mean CPBD | mean blur effect | mean blur px | p95 blur px | max blur px | mean exposure MMBM mm/s | pose error cm | pose error deg |\n|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|---|\n",
    );
    for st in stats {
        let fixed = stats
            .iter()
            .find(|x| x.walk == st.walk && x.policy.is_baseline())
            .map(|x| x.kept as i64);
        let lost = fixed.map_or("-".into(), |k| (k - st.kept as i64).to_string());
        let succ = st.success_pct();
        let _ = writeln!(
            s,
            "| {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} | {} |",
            st.walk,
            st.policy,
            st.kept,
            st.triggered - st.kept,
            f(st.fps, 2),
            lost,
            st.rendered,
            st.blobs_ok,
            f(succ, 1),
            f(100.0 * st.blobs_ok_fixed as f64 / st.rendered.max(1) as f64, 1),
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

/// The heat map's file name in the output directory.
pub const MAP_FIGURE: &str = "benefit_map.png";

/// What the experiment produced.
pub struct Outcome {
    /// The walks with every policy's frames.
    pub walks: Vec<Walk>,
    /// Every frame with its measurements.
    pub records: Vec<FrameRecord>,
    /// Per (walk, policy) statistics.
    pub stats: Vec<PolicyStats>,
    /// Wall time, s.
    pub seconds: f64,
    /// Frames rendered.
    pub rendered: usize,
    /// The exposure sweep (empty when not configured).
    pub sweep: Vec<super::sweep::SweepRow>,
    /// Where the frames were rendered (`gpu: <adapter>` or `cpu (N threads)`).
    pub backend: String,
    /// The benefit map (when `[map]` has lights).
    pub map: Option<super::benefit_map::BenefitMap>,
}

impl Outcome {
    /// The few lines the terminal ends with: the benefit map's headline
    /// ratios (or, without a map, each gait's best causal policy against the
    /// fixed rate) with their intervals, and where the report is.
    pub fn answer(&self, report: &std::path::Path) -> String {
        if let Some(m) = &self.map {
            return super::benefit_map::report::answer(m, report).join("\n");
        }
        let policies: Vec<PolicySpec> = self
            .walks
            .first()
            .map(|w| w.runs.iter().map(|(p, _)| p.clone()).collect())
            .unwrap_or_default();
        let hs = super::benefit::headlines(&self.walks, &self.records, &policies);
        let mut out = Vec::new();
        let mut gaits: Vec<&str> = hs.iter().map(|h| h.gait.as_str()).collect();
        gaits.dedup();
        for g in gaits {
            let best = hs
                .iter()
                .filter(|h| h.gait == g && h.policy.is_causal() && !h.policy.is_baseline())
                .filter_map(|h| h.ratio.map(|r| (h, r)))
                .max_by(|a, b| a.1.value.total_cmp(&b.1.value));
            if let Some((h, r)) = best {
                out.push(format!(
                    "{g}: best causal policy `{}`: {:.2} sharp frames/s, {:.2}x the fixed rate [95 % CI {}, {}]",
                    h.policy,
                    h.sharp_fps.value,
                    r.value,
                    super::benefit::bound_text(r.lo),
                    super::benefit::bound_text(r.hi)
                ));
            }
        }
        out.push(format!("Report: {}", report.display()));
        out.join("\n")
    }
}

/// The baseline's blob success with both detectors and the blur that
/// separates its failures from its successes (computed; the thesis's
/// baseline succeeded in about half of its frames).
pub fn baseline_note(stats: &[PolicyStats]) -> String {
    let mut s = String::new();
    for st in stats
        .iter()
        .filter(|x| x.policy.is_baseline() && x.rendered > 0)
    {
        let pct = |k: usize| 100.0 * k as f64 / st.rendered as f64;
        let _ = write!(
            s,
            "\nBaseline `{}` ({}): {:.0} % of its {} rendered frames have all 16 blobs with the adaptive threshold, \
             {:.0} % with the fixed threshold {} (a global threshold like the thesis's OpenCV one; the thesis measured \
             about 50 % on its robot). ",
            st.policy,
            st.walk,
            pct(st.blobs_ok),
            st.rendered,
            pct(st.blobs_ok_fixed),
            super::measure::FIXED_BLOB_THRESHOLD
        );
        if st.blobs_ok < st.rendered {
            let _ = writeln!(
                s,
                "Its failed frames have a mean ground-truth blur of {} px against {} px for the successful ones.",
                f(st.mean_blur_failed, 1),
                f(st.mean_blur_ok, 1)
            );
        } else {
            s.push('\n');
        }
    }
    s
}

/// The render-quality note: the preset and its measured error against the default preset.
pub fn quality_note(cfg: &ExperimentConfig, check: Option<(f64, f64, f64)>) -> String {
    match check {
        Some((mean, p99, blur)) => format!(
            "- Render quality preset `{}`: measured against the `default` preset on the central 160 x 120 window of the most blurred \
             baseline frame ({blur:.1} px mean blur), both without sensor noise, mean |difference| {:.2}/255 and 99th percentile {:.2}/255 (linear 0..1 values x 255). \
             `default` itself is within mean 0.5/255 and p99 3/255 of the exact integral (tests/render_exact.rs).\n",
            cfg.quality,
            mean * 255.0,
            p99 * 255.0
        ),
        None if cfg.quality == "default" => "- Render quality preset `default`: the renderer's accuracy contract, within mean 0.5/255 \
             and p99 3/255 of the exact area-and-time integral (tests/render_exact.rs).\n"
            .to_string(),
        None => format!("- Render quality preset `{}` (not compared with `default`: no frame to compare).\n", cfg.quality),
    }
}

/// Prose: what the simulation found, compared with the thesis.
pub fn findings(stats: &[PolicyStats]) -> String {
    let mut s = String::from("## Findings\n\n");
    for st in stats.iter().filter(|x| x.policy.is_baseline()) {
        let others: Vec<&PolicyStats> = stats
            .iter()
            .filter(|x| x.walk == st.walk && !x.policy.is_baseline())
            .collect();
        s += &format!(
            "- {} walk, baseline `{}`: {} frames, blob success {:.0} %, mean JNBM {:.3}, mean blur {:.1} px (p95 {:.1}).\n",
            st.walk, st.policy, st.kept, st.success_pct(), st.mean_jnbm, st.mean_blur, st.p95_blur
        );
        for o in others {
            s += &format!(
                "  - `{}`: {} frames ({:+} vs baseline), success {:.0} %, mean JNBM {:.3}, mean blur {:.1} px (p95 {:.1}).\n",
                o.policy,
                o.kept,
                o.kept as i64 - st.kept as i64,
                o.success_pct(),
                o.mean_jnbm,
                o.mean_blur,
                o.p95_blur
            );
        }
    }
    // The headline comparison of the thesis: fixed 5 fps against MMBM triggering at 0.4.
    for base in stats.iter().filter(|x| x.policy.is_baseline()) {
        let Some(th) = stats
            .iter()
            .find(|x| x.walk == base.walk && x.policy.is_thesis_rule())
        else {
            continue;
        };
        s += &format!(
            "\nOn the {} walk, MMBM triggering at 0.4 mm/s (`{}`, the thesis rule) against `{}`: \
             blob success {:.0} % -> {:.0} %, mean ground-truth blur {:.1} -> {:.1} px (p95 {:.1} -> {:.1}), \
             mean blur effect {:.3} -> {:.3} (lower = sharper), mean JNBM {:.3} -> {:.3}, with {} instead of {} frames. \
             The thesis (real SensoRHex, chapter 6) found blob success rising from about 50 % to 62-82 % and mean \
             JNBM from 0.36 to 0.49.\n",
            base.walk,
            th.policy,
            base.policy,
            base.success_pct(),
            th.success_pct(),
            base.mean_blur,
            th.mean_blur,
            base.p95_blur,
            th.p95_blur,
            base.mean_blur_effect,
            th.mean_blur_effect,
            base.mean_jnbm,
            th.mean_jnbm,
            th.kept,
            base.kept
        );
    }
    s += "\nWhy the numbers differ from the thesis: the gait is simulated, calibrated only to the thesis's MMBM \
          range and trigger rates; the rendered camera is the one configured (see the configuration below: an \
          ideal camera unless `[camera]` adds noise, a rolling shutter, distortion or defocus); the blob detectors \
          are ours (the adaptive one and a fixed threshold like the thesis's). How the image metrics follow the \
          ground truth is measured in the next section.\n";
    s
}

/// `report.md` text: the findings, Tables 5.1, 6.1 and 6.2, figures, method
/// and configuration.
pub fn report_md(
    cfg: &ExperimentConfig,
    o: &Outcome,
    figs: &[String],
    check: Option<(f64, f64, f64)>,
) -> String {
    let (walks, stats, records, seconds, rendered) =
        (&o.walks, &o.stats, &o.records, o.seconds, o.rendered);
    let render_ms: Vec<f64> = records
        .iter()
        .filter_map(|r| r.measure.as_ref().map(|m| m.render_ms))
        .collect();
    let mean_ms = render_ms.iter().sum::<f64>() / render_ms.len().max(1) as f64;
    let mut s = String::new();
    s += "# mmbm experiment report\n\n";
    s += &format!(
        "Rendered {rendered} frames in {seconds:.1} s (mean render {mean_ms:.0} ms per frame, quality preset `{}`).\n\n",
        cfg.quality
    );
    let policies: Vec<PolicySpec> = walks
        .first()
        .map(|w| w.runs.iter().map(|(p, _)| p.clone()).collect())
        .unwrap_or_default();
    if let Some(m) = &o.map {
        s += &super::benefit_map::report::opening_md(
            m,
            figs.iter()
                .find(|f| f.as_str() == MAP_FIGURE)
                .map(String::as_str),
        );
    }
    let own = super::benefit::headlines(walks, records, &policies);
    match o
        .map
        .as_ref()
        .and_then(|m| super::headline_view::headline_view_md(cfg, m))
    {
        // With a map the headline is the map's cell; the experiment's own
        // frames keep their table, labelled as the different sample they are.
        Some(view) => {
            s += &view;
            let mut seeds: Vec<u64> = walks.iter().map(|w| w.seed).collect();
            seeds.sort_unstable();
            seeds.dedup();
            s += &super::benefit::headline_md_titled(
                &own,
                &policies,
                "The experiment's own frames (a different sample from the headline)",
                &format!(
                    "Frames judged here: the experiment's walks (seeds {seeds:?}), each kept frame rendered whole and \
                     judged over the whole frame (board, poster and all): a different sample from the headline and the \
                     map, which judge seeds {:?} in a window around the board. Its rates are not the headline's; \
                     this table is kept for the ground-truth blur, which only these renders measure.",
                    o.map.as_ref().map(|m| m.seeds.clone()).unwrap_or_default()
                ),
            );
        }
        None => s += &super::benefit::headline_md(&own, &policies),
    }
    s += &super::clutter_report::clutter_md(&cfg.background, walks, records);
    s += &findings(stats);
    s += "\n## Table 5.1: instantaneous MMBM at the trigger vs the exposure average\n\n";
    s += "Error = exposure-averaged MMBM - MMBM of the decision sample (mm/s); % relative to the exposure average.\n\n";
    s += &table_5_1(walks);
    s += "\n## Tables 6.1 and 6.2: frames, blob extraction, JNBM and ground-truth blur\n\n";
    s += "Blur = sensor mean of each pixel's image path length over the exposure (px), from the renderer's blur maps. \
          Success = all 16 blobs found, each within half a blob pitch of its true centre (projected at mid-exposure). \
          Pose error: camera position and orientation estimated from the 16 blob centres (planar homography) \
          against the true mid-exposure pose, over frames with all 16 blobs. JNBM and CPBD (the authors' code): higher = sharper; blur effect: 0 sharp .. 1 blurred.\n\n";
    s += &table_6(stats);
    s += &baseline_note(stats);
    s += &super::truth::metrics_md(records);
    s += &super::sweep::sweep_md(cfg, &o.sweep);
    s += "\n## Figures\n\n";
    for f in figs {
        s += &format!("![{f}]({f})\n\n");
    }
    s += "Frames figure: for each policy in configuration order, the sharpest (left) and the most blurred (right) rendered frame, cropped to the board with the full frame as an inset (the crop outlined), labelled with the trigger time, the ground-truth blur and the blob verdict.\n\n";
    s += "## Method and simplifications\n\n";
    s += "- Walks are simulated by `mmbm simulate` (seeded); the log is both the measurement the policies see and the true motion the renderer follows (its gyro noise included).\n";
    s += "- Policies decide on the rotation-only MMBM (thesis camera, 8x6 grid) of each gyro sample.\n";
    s += &format!(
        "- Each kept frame is rendered from the log window of its exposure, rotation and translation integrated on SE(3), on a hardware GPU when there is one, else with the renderer's CPU twin (also on a software adapter such as lavapipe, where the twin is faster and the driver's memory grows per dispatch); this run: {}.\n",
        if o.backend.is_empty() { "no frame rendered" } else { &o.backend }
    );
    s += "- At every exposure start the camera looks at the board's centre; the board's distance follows the walked distance from the start distance.\n";
    s += &quality_note(cfg, check);
    s += "\n## Configuration\n\n```toml\n";
    s += &cfg.to_toml();
    s += "```\n";
    s
}
