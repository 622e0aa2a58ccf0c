//! The headline: sharp frames per second and ground-truth blur per policy,
//! paired against the fixed-rate baseline, with bootstrap confidence
//! intervals.
//!
//! A sharp frame is a kept, rendered frame in which all 16 blobs were found
//! at their true places. Every walk (one per gait and seed) is cut into
//! [`BLOCK_S`]-second blocks; a block holds, per policy, its sharp frames and
//! the blur of its rendered frames. The statistics are ratios of sums over
//! blocks (sharp frames / seconds, blur sum / frames), and the 95 % interval
//! is the percentile interval of [`RESAMPLES`] resamplings of the blocks with
//! replacement (seeded with [`BOOTSTRAP_SEED`]). Resampling blocks (all
//! policies together) keeps the pairing: the policies share the walk's motion
//! within a block. Blocks of 2 s hold about two gait cycles, so the
//! dependence between frames is mostly inside them.

use super::measure::FrameRecord;
use super::walk::Walk;
use crate::stats::percentile;
use crate::trigger::{Family, PolicySpec, DEFAULT_HORIZON_S};
use rand::{Rng, SeedableRng};

/// Block length, s.
pub const BLOCK_S: f64 = 2.0;

/// A walk cut into [`BLOCK_S`]-second blocks from its first sample to its
/// last (the last block may be shorter; a walk has at least one).
pub(crate) struct WalkBlocks {
    /// The walk's first sample time, s.
    t0: f64,
    /// Each block's length, s.
    pub seconds: Vec<f64>,
}

impl WalkBlocks {
    /// The blocks of `w`.
    pub(crate) fn of(w: &Walk) -> Self {
        let (t0, t1) = (
            w.samples.first().map_or(0.0, |s| s.t),
            w.samples.last().map_or(0.0, |s| s.t),
        );
        let n = (((t1 - t0) / BLOCK_S).ceil() as usize).max(1);
        let seconds = (0..n)
            .map(|b| {
                let a = t0 + b as f64 * BLOCK_S;
                (t1.min(a + BLOCK_S) - a).max(0.0)
            })
            .collect();
        WalkBlocks { t0, seconds }
    }

    /// The block that time `t` (s) falls in (times past the end: the last).
    pub(crate) fn index(&self, t: f64) -> usize {
        (((t - self.t0) / BLOCK_S) as usize).min(self.seconds.len() - 1)
    }
}
/// Bootstrap resamples.
pub const RESAMPLES: usize = 2000;
/// Seed of the bootstrap's random numbers.
pub const BOOTSTRAP_SEED: u64 = 20_261_123;

/// The [`RESAMPLES`] bootstrap resamplings of `n` blocks: each a list of `n`
/// block indices drawn with replacement, from [`BOOTSTRAP_SEED`] (the same
/// draws for every table that resamples `n` blocks).
pub fn bootstrap_indices(n: usize) -> Vec<Vec<usize>> {
    let mut rng = rand::rngs::StdRng::seed_from_u64(BOOTSTRAP_SEED);
    (0..RESAMPLES)
        .map(|_| (0..n).map(|_| rng.gen_range(0..n)).collect())
        .collect()
}

/// A point estimate with its 95 % bootstrap interval.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Estimate {
    /// On all blocks.
    pub value: f64,
    /// 2.5th percentile of the resamples.
    pub lo: f64,
    /// 97.5th percentile of the resamples.
    pub hi: f64,
}

/// A bound of a ratio's interval as the reports write it: two decimals, and
/// more (up to six) where two would print `1.00` for a bound that is not 1,
/// so that a bound reads on the side of 1 where the verdicts place it
/// (`[0.99, 0.998]`, not `[0.99, 1.00]`, for an interval below 1).
pub fn bound_text(x: f64) -> String {
    let mut d = 2;
    let mut t = format!("{x:.2}");
    while d < 6 && x != 1.0 && x.is_finite() && t.parse::<f64>() == Ok(1.0) {
        d += 1;
        t = format!("{x:.d$}");
    }
    t
}

/// One policy's headline on one gait (all its seeds pooled).
#[derive(Debug, Clone, PartialEq)]
pub struct Headline {
    /// Gait (or log) name.
    pub gait: String,
    /// The policy.
    pub policy: PolicySpec,
    /// Seeds pooled.
    pub seeds: Vec<u64>,
    /// Blocks resampled.
    pub blocks: usize,
    /// Sharp frames per second.
    pub sharp_fps: Estimate,
    /// Sharp frames per second over the baseline's (None without a baseline).
    pub ratio: Option<Estimate>,
    /// Mean ground-truth blur of the rendered frames, px.
    pub blur_px: Estimate,
    /// Rendered frames (all kept frames rendered?).
    pub rendered: usize,
    /// Kept frames.
    pub kept: usize,
}

/// Per block and policy: (sharp frames, blur sum, rendered frames, kept
/// frames); and the block's seconds.
struct Block {
    seconds: f64,
    per_policy: Vec<(f64, f64, f64, f64)>,
}

/// Sharp frames per second from `sharp` of `rendered` frames among `kept`
/// kept frames over `seconds`: with every kept frame rendered, `sharp /
/// seconds`; with a subsample (`max_frames_per_policy`), the subsample's
/// sharp share times the kept frames per second, so the rate is computed on
/// the frames that were judged, not read as if the others had failed.
pub(crate) fn sharp_rate(sharp: f64, rendered: f64, kept: f64, seconds: f64) -> f64 {
    if rendered > 0.0 && rendered < kept {
        sharp / rendered * kept / seconds
    } else {
        sharp / seconds
    }
}

/// The baseline policy: `fixed:5` if run, else the first `fixed:*`.
pub fn baseline(policies: &[PolicySpec]) -> Option<usize> {
    policies
        .iter()
        .position(|p| p.as_str() == "fixed:5")
        .or_else(|| policies.iter().position(|p| p.is_baseline()))
}

/// `value` with the 2.5th and 97.5th percentiles of the bootstrap `draws`.
/// A ratio's draw is `+inf` where the resampled baseline got no sharp frame
/// and the policy some: it is kept (it is the resample's ratio, and dropping
/// it would pull the interval down); NaN draws (neither got any) carry no
/// comparison and are dropped. Both bounds NaN when no draw is left.
pub(crate) fn estimate(value: f64, mut draws: Vec<f64>) -> Estimate {
    draws.retain(|x| !x.is_nan());
    if draws.is_empty() {
        return Estimate {
            value,
            lo: f64::NAN,
            hi: f64::NAN,
        };
    }
    draws.sort_by(f64::total_cmp);
    Estimate {
        value,
        lo: percentile(&draws, 2.5).unwrap_or(f64::NAN),
        hi: percentile(&draws, 97.5).unwrap_or(f64::NAN),
    }
}

/// The headline of every gait and policy (policies in configuration order).
pub fn headlines(
    walks: &[Walk],
    records: &[FrameRecord],
    policies: &[PolicySpec],
) -> Vec<Headline> {
    let mut gaits: Vec<&str> = Vec::new();
    for w in walks {
        if !gaits.contains(&w.gait.as_str()) {
            gaits.push(&w.gait);
        }
    }
    let base = baseline(policies);
    let mut out = Vec::new();
    for gait in gaits {
        let ws: Vec<&Walk> = walks.iter().filter(|w| w.gait == gait).collect();
        let mut blocks = Vec::new();
        for w in &ws {
            let wb = WalkBlocks::of(w);
            let first = blocks.len();
            for &seconds in &wb.seconds {
                blocks.push(Block {
                    seconds,
                    per_policy: vec![(0.0, 0.0, 0.0, 0.0); policies.len()],
                });
            }
            for r in records.iter().filter(|r| r.walk == w.name) {
                let Some(pi) = policies.iter().position(|p| *p == r.frame.policy) else {
                    continue;
                };
                if !r.frame.kept {
                    continue;
                }
                let b = wb.index(r.frame.trigger_t);
                let c = &mut blocks[first + b].per_policy[pi];
                c.3 += 1.0;
                if let Some(m) = r.measure.as_ref() {
                    c.0 += f64::from(u8::from(m.blobs_ok));
                    c.1 += m.blur_px;
                    c.2 += 1.0;
                }
            }
        }
        let stat = |idx: &[usize], pi: usize| {
            let (mut ok, mut secs, mut blur, mut n, mut kept) = (0.0, 0.0, 0.0, 0.0, 0.0);
            for &k in idx {
                let c = blocks[k].per_policy[pi];
                ok += c.0;
                blur += c.1;
                n += c.2;
                kept += c.3;
                secs += blocks[k].seconds;
            }
            (sharp_rate(ok, n, kept, secs), blur / n)
        };
        let all: Vec<usize> = (0..blocks.len()).collect();
        let samples = bootstrap_indices(blocks.len());
        let mut seeds: Vec<u64> = ws.iter().map(|w| w.seed).collect();
        seeds.sort_unstable();
        for (pi, p) in policies.iter().enumerate() {
            let (fps, blur) = stat(&all, pi);
            let draws: Vec<(f64, f64)> = samples.iter().map(|s| stat(s, pi)).collect();
            let ratio = base.map(|bi| {
                let (bf, _) = stat(&all, bi);
                let rd = samples
                    .iter()
                    .map(|s| stat(s, pi).0 / stat(s, bi).0)
                    .collect();
                estimate(fps / bf, rd)
            });
            let recs = records
                .iter()
                .filter(|r| r.frame.policy == *p && ws.iter().any(|w| w.name == r.walk));
            let (mut rendered, mut kept) = (0, 0);
            for r in recs {
                kept += usize::from(r.frame.kept);
                rendered += usize::from(r.frame.kept && r.measure.is_some());
            }
            out.push(Headline {
                gait: gait.to_string(),
                policy: p.clone(),
                seeds: seeds.clone(),
                blocks: blocks.len(),
                sharp_fps: estimate(fps, draws.iter().map(|d| d.0).collect()),
                ratio,
                blur_px: estimate(blur, draws.iter().map(|d| d.1).collect()),
                rendered,
                kept,
            });
        }
    }
    out
}

fn ci(e: &Estimate, digits: usize) -> String {
    if !e.value.is_finite() {
        "-".into()
    } else if e.lo.is_finite() {
        format!("{:.d$} [{:.d$}, {:.d$}]", e.value, e.lo, e.hi, d = digits)
    } else {
        format!("{:.d$}", e.value, d = digits)
    }
}

/// A ratio as `1.23x [1.01, 1.50]` (`-` when undefined).
fn ratio_ci(e: &Estimate) -> String {
    match ci(e, 2).split_once(' ') {
        Some((v, rest)) => format!("{v}x {rest}"),
        None if e.value.is_finite() => format!("{}x", ci(e, 2)),
        None => "-".into(),
    }
}

/// The headline section of the report (its numbers and its sentences both
/// computed from `hs`), for an experiment without a map: the frames judged
/// are the experiment's own.
pub fn headline_md(hs: &[Headline], policies: &[PolicySpec]) -> String {
    headline_md_titled(
        hs,
        policies,
        "Headline: sharp frames per second",
        "Frames judged: the experiment's walks, each kept frame rendered whole and judged over the whole frame.",
    )
}

/// [`headline_md`] under the section title `title`, opening with `judged`
/// (the sentence that says which frames the table judged).
pub fn headline_md_titled(
    hs: &[Headline],
    policies: &[PolicySpec],
    title: &str,
    judged: &str,
) -> String {
    let mut s = format!("## {title}\n\n{judged}\n\n");
    let Some(first) = hs.first() else {
        return s + "No frames.\n\n";
    };
    let base = baseline(policies).map(|b| policies[b].clone());
    s += &format!(
        "Sharp frame = kept, rendered, all 16 blobs found at their true places. Mean over the walk's {:.0}-s \
         blocks pooled over seeds {:?} ({} blocks per gait), with 95 % percentile bootstrap intervals from {} \
         resamplings of the blocks (bootstrap seed {}){}.\n\n",
        BLOCK_S,
        first.seeds,
        first.blocks,
        RESAMPLES,
        BOOTSTRAP_SEED,
        match &base {
            Some(b) => format!("; the ratio is paired against `{b}` block by block"),
            None => "; no fixed-rate baseline was run, so no ratio".into(),
        }
    );
    let (rendered, kept): (usize, usize) = hs
        .iter()
        .fold((0, 0), |(r, k), h| (r + h.rendered, k + h.kept));
    if rendered < kept {
        s += &format!(
            "**A subsample was judged**: {rendered} of the {kept} kept frames were rendered \
             (`max_frames_per_policy`); every rate and ratio below is the rendered frames' sharp share times \
             the kept frames per second (docs/spec.md section 11).\n\n"
        );
    }
    s += "| walk | policy | family | sharp frames/s [95 % CI] | vs baseline [95 % CI] | mean blur px [95 % CI] | rendered / kept |\n";
    s += "|---|---|---|---|---|---|---|\n";
    for h in hs {
        s += &format!(
            "| {} | {} | {} | {} | {} | {} | {} / {} |\n",
            h.gait,
            h.policy,
            h.policy.policy_family(),
            ci(&h.sharp_fps, 2),
            h.ratio.as_ref().map_or("-".into(), ratio_ci),
            ci(&h.blur_px, 2),
            h.rendered,
            h.kept
        );
    }
    s.push('\n');
    // The best causal policy per gait, by the ratio's point estimate.
    let mut gaits: Vec<&str> = hs.iter().map(|h| h.gait.as_str()).collect();
    gaits.dedup();
    for g in gaits {
        let best = hs
            .iter()
            .filter(|h| h.gait == g && Some(&h.policy) != base.as_ref())
            .filter(|h| h.policy.is_causal())
            .filter_map(|h| h.ratio.map(|r| (h, r)))
            .max_by(|a, b| a.1.value.total_cmp(&b.1.value));
        if let (Some((h, r)), Some(b)) = (best, &base) {
            let goal = if r.value >= 1.5 && r.lo > 1.0 {
                "meets the 1.5x goal, with the interval's lower bound above 1".to_string()
            } else if r.lo > 1.0 {
                format!("is better than `{b}` (lower bound above 1) but short of the 1.5x goal")
            } else if r.hi < 1.0 {
                format!("is worse than `{b}` (upper bound below 1)")
            } else {
                format!("is not distinguishable from `{b}` (the interval contains 1)")
            };
            s += &format!(
                "- {g}: the best causal policy, `{}`, gets {:.2}x the sharp frames per second of `{b}` \
                 (95 % CI {}-{}): it {goal}.\n",
                h.policy,
                r.value,
                bound_text(r.lo),
                bound_text(r.hi)
            );
        }
        // The ceiling: at the baseline's rate no policy gets more frames.
        let fps = base.as_ref().and_then(|b| b.rate.map(|r| r.fps));
        let bh = hs
            .iter()
            .find(|h| h.gait == g && Some(&h.policy) == base.as_ref());
        if let (Some(fps), Some(bh), Some(b)) = (fps, bh, &base) {
            let cap = fps / bh.sharp_fps.value;
            if cap.is_finite() {
                s += &format!(
                    "- {g}: at `{b}`'s rate a policy takes at most {fps} frames/s, and `{b}` already gets {:.2} \
                     sharp frames/s ({:.0} % of its frames), so no policy at that rate can exceed {cap:.2}x here{}.\n",
                    bh.sharp_fps.value,
                    100.0 * bh.sharp_fps.value / fps,
                    if cap < 1.5 {
                        ": the 1.5x goal is out of reach with this camera and light"
                    } else {
                        ""
                    }
                );
            }
        }
    }
    // The predictors' share of the oracle's gain (blur) over the thesis rule,
    // for every forecast:X or phase:X run beside threshold:X and oracle:X.
    // (Without exposure control: the comparison is between decision rules.)
    for h in hs.iter().filter(|h| {
        matches!(h.policy.family, Family::Forecast | Family::Phase) && h.policy.exposure.is_none()
    }) {
        // The thesis rule and the oracle at the same threshold (the oracle at
        // its default horizon), neither with exposure control.
        let find = |family: Family| {
            hs.iter().find(|o| {
                o.gait == h.gait
                    && o.policy.family == family
                    && o.policy.threshold == h.policy.threshold
                    && o.policy.exposure.is_none()
                    && (family != Family::Oracle || o.policy.horizon == Some(DEFAULT_HORIZON_S))
            })
        };
        if let (Some(t), Some(o)) = (find(Family::Threshold), find(Family::Oracle)) {
            let gain = t.blur_px.value - o.blur_px.value;
            if gain > 0.0 {
                s += &format!(
                    "- {}: `{}` recovers {:.0} % of the oracle's blur reduction over `{}` (mean blur {:.2} px against \
                     {:.2} for the thesis rule and {:.2} for `{}`), with {} kept frames against the oracle's {}.\n",
                    h.gait,
                    h.policy,
                    100.0 * (t.blur_px.value - h.blur_px.value) / gain,
                    t.policy,
                    h.blur_px.value,
                    t.blur_px.value,
                    o.blur_px.value,
                    o.policy,
                    h.kept,
                    o.kept
                );
            }
        }
    }
    s.push('\n');
    s
}

#[cfg(test)]
mod tests {
    use super::*;

    /// Two decimals unless a bound that is not 1 would print as `1.00`.
    #[test]
    fn bounds_near_one_show_their_side() {
        for (x, want) in [
            (0.5, "0.50"),
            (1.0, "1.00"),
            (1.2345, "1.23"),
            (0.996, "0.996"),
            (1.004, "1.004"),
            (0.9996, "0.9996"),
            (0.999_999_9, "1.000000"),
            (0.994, "0.99"),
            (f64::INFINITY, "inf"),
        ] {
            assert_eq!(bound_text(x), want, "{x}");
        }
    }
    use crate::experiment::measure::FrameMeasure;
    use crate::io::gyro::GyroSample;
    use crate::trigger::Frame;

    fn walk(seed: u64) -> Walk {
        let samples = crate::model::log::ImuLog::new(
            (0..=200)
                .map(|k| GyroSample {
                    t: k as f64 * 0.1,
                    omega: glam::DVec3::ZERO,
                    velocity: None,
                    depth: None,
                })
                .collect(),
        )
        .unwrap();
        Walk {
            name: format!("w-s{seed}"),
            gait: "w".into(),
            seed,
            samples,
            mmbm: vec![],
            distance: vec![],
            runs: vec![],
        }
    }

    fn record(seed: u64, policy: &str, t: f64, ok: bool, blur: f64) -> FrameRecord {
        FrameRecord {
            walk: format!("w-s{seed}"),
            seed,
            frame: Frame {
                policy: policy.parse().unwrap(),
                index: 0,
                trigger_t: t,
                exposure_start: t,
                exposure_end: t + 0.07,
                mmbm_trigger_mm_s: 0.0,
                mmbm_exposure_mm_s: 0.0,
                kept: true,
                gain: 1.0,
            },
            measure: Some(FrameMeasure {
                distance_m: 3.0,
                blur_px: blur,
                disp_px: blur,
                jnbm: 0.5,
                cpbd: 0.5,
                blur_effect: 0.3,
                laplacian_var: 1.0,
                blobs_found: 16,
                blobs_matched: 16,
                blobs_ok: ok,
                blobs_ok_fixed: ok,
                pose_err_m: 0.0,
                pose_err_deg: 0.0,
                samples_per_pixel: 1,
                render_ms: 1.0,
                ..FrameMeasure::default()
            }),
        }
    }

    #[test]
    fn infinite_draws_are_kept_nan_draws_dropped() {
        let inf = f64::INFINITY;
        // 40 resamples: 38 finite ratios 1..=38, two where the baseline got
        // nothing (+inf), two where neither did (NaN, dropped).
        let mut draws: Vec<f64> = (1..=38).map(f64::from).collect();
        draws.extend([inf, inf, f64::NAN, f64::NAN]);
        let e = estimate(2.0, draws);
        // Rank 0.025 x 39 = 0.975 lies between 1 and 2: 1.975; rank
        // 0.975 x 39 = 38.025 between the two infinities: inf.
        assert!((e.lo - 1.975).abs() < 1e-12, "{e:?}");
        assert_eq!(e.hi, inf);
        let none = estimate(f64::NAN, vec![f64::NAN; 3]);
        assert!(none.lo.is_nan() && none.hi.is_nan());
    }

    #[test]
    fn paired_ratio_and_intervals() {
        let policies: Vec<PolicySpec> = ["fixed:5", "threshold:0.4"]
            .iter()
            .map(|p| p.parse().unwrap())
            .collect();
        let walks = vec![walk(1), walk(2)];
        // Same pattern in every 2-s block: fixed 10 frames, 5 sharp (2.5/s,
        // blur 4 px); threshold 8 frames, all sharp (4/s, blur 2 px).
        let mut recs = Vec::new();
        for seed in [1, 2] {
            for k in 0..100 {
                recs.push(record(seed, "fixed:5", k as f64 * 0.2, k % 2 == 0, 4.0));
            }
            for k in 0..80 {
                recs.push(record(seed, "threshold:0.4", k as f64 * 0.25, true, 2.0));
            }
        }
        let hs = headlines(&walks, &recs, &policies);
        assert_eq!(hs.len(), 2);
        assert_eq!(hs[0].blocks, 20);
        let (f, t) = (&hs[0], &hs[1]);
        assert!((f.sharp_fps.value - 2.5).abs() < 1e-12);
        assert!((t.sharp_fps.value - 4.0).abs() < 1e-12);
        let r = t.ratio.unwrap();
        // Identical blocks: every resample gives the same ratio.
        assert!(
            (r.value - 1.6).abs() < 1e-12
                && (r.lo - 1.6).abs() < 1e-12
                && (r.hi - 1.6).abs() < 1e-12
        );
        assert!((t.blur_px.value - 2.0).abs() < 1e-12);
        let md = headline_md(&hs, &policies);
        assert!(md.contains("`threshold:0.4`, gets 1.60x"), "{md}");
        assert!(md.contains("meets the 1.5x goal"), "{md}");

        // Uneven blocks: the interval widens around the pooled value.
        let mut recs2 = recs.clone();
        recs2.retain(|r| {
            !(r.frame.policy == "threshold:0.4" && r.seed == 1 && r.frame.trigger_t < 6.0)
        });
        let hs = headlines(&walks, &recs2, &policies);
        let r = hs[1].ratio.unwrap();
        assert!(r.lo < r.value && r.value < r.hi, "{r:?}");
        assert!(r.value < 1.6 && r.hi > 1.5, "{r:?}");
    }

    #[test]
    fn a_subsample_is_judged_on_its_own_frames() {
        // The case: 12 of fixed:5's 100 kept frames (20 s) rendered,
        // 11 sharp. Not 11 / 20 s = 0.55 sharp frames/s ("11 % of its
        // frames"), but 11/12 of its 5 frames/s = 4.58 /s.
        let policies: Vec<PolicySpec> = vec!["fixed:5".parse().unwrap()];
        let walks = vec![walk(1)];
        let recs: Vec<FrameRecord> = (0..100)
            .map(|k| {
                let mut r = record(1, "fixed:5", k as f64 * 0.2, k != 0, 1.0);
                if k % 8 != 0 || k >= 96 {
                    r.measure = None;
                }
                r
            })
            .collect();
        assert_eq!(recs.iter().filter(|r| r.measure.is_some()).count(), 12);
        let hs = headlines(&walks, &recs, &policies);
        assert_eq!((hs[0].rendered, hs[0].kept), (12, 100));
        assert!((hs[0].sharp_fps.value - 11.0 / 12.0 * 100.0 / 20.0).abs() < 1e-9);
        let md = headline_md(&hs, &policies);
        assert!(
            md.contains("12 of the 100 kept frames were rendered"),
            "{md}"
        );
        // Every kept frame rendered: the plain count over the seconds.
        assert!((sharp_rate(11.0, 12.0, 12.0, 20.0) - 0.55).abs() < 1e-15);
    }
}
