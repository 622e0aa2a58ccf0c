//! The benefit map (docs/spec.md section 10): when does gyro-driven capture beat
//! what camera users do instead? Cells are light x gait x board; in each,
//! the sharp frames per second of every policy (kept, rendered, all 16 blobs
//! at their true places), the best causal gyro-driven policy (`mmbm`) against
//! the best fixed exposure in hindsight (`oracle`, over the grid), against
//! auto-exposure and against the thesis's fixed rate, each ratio paired over
//! the 2-s blocks of the walks with a 95 % percentile bootstrap over the
//! blocks of all seeds (the headline's [`BLOCK_S`](super::benefit::BLOCK_S), [`RESAMPLES`](super::benefit::RESAMPLES) and
//! [`BOOTSTRAP_SEED`](super::benefit::BOOTSTRAP_SEED): [`bootstrap_indices`](super::benefit::bootstrap_indices)).
//!
//! The trigger times and exposures do not depend on the light (the
//! auto-exposure predicts its level from the scene, see
//! [`crate::trigger::AutoExposure`]), so each frame is rendered once without
//! noise and judged at every light with that light's noise and gain
//! ([`render`]). The best policies of a cell are chosen on all
//! its blocks (point estimates) and then held fixed in the resamples.

pub(crate) mod heat;
pub(crate) mod logs;
pub(crate) mod render;
pub(crate) mod report;
pub(crate) mod verdict;

use super::benefit::{bootstrap_indices, estimate, Estimate, WalkBlocks};
use super::config::ExperimentConfig;
use super::matches::{inliers as match_inliers, true_homography, TRACK_MIN};
use super::walk::{make_walk, Walk};
use crate::camera::Noise;
use crate::error::Result;
use crate::metric::Scene;
use crate::render::Quality;
use crate::trigger::{Frame, PolicyFamily, PolicySpec};
use rayon::prelude::*;
pub use render::Renders;
use render::{judge_at_lights, FrameFeatures, Judged, Light};

/// One policy in one cell.
#[derive(Debug, Clone, PartialEq)]
pub struct CellPolicy {
    /// The policy.
    pub policy: PolicySpec,
    /// Sharp frames per second (all seeds pooled).
    pub sharp_fps: f64,
    /// [`Self::sharp_fps`] with its 95 % block-bootstrap interval (the
    /// headline reads it: docs/spec.md section 11).
    pub sharp_ci: Estimate,
    /// Sharp frames per second over the cell's fixed rate ([`Cell::fixed`]),
    /// paired block by block; None without a fixed rate.
    pub vs_fixed: Option<Estimate>,
    /// Kept frames.
    pub frames: usize,
    /// Sharp frames.
    pub sharp: usize,
    /// Mean exposure of the kept frames, s.
    pub mean_exposure_s: f64,
    /// Kept frames whose gain the sensor's maximum capped (darker than meant).
    pub gain_capped: usize,
    /// Blobs found away from every board place, over all kept frames (clutter, noise).
    pub false_alarms: usize,
    /// Mean corner repeatability of the kept frames with corners
    /// (`corners.rs`; NaN when none had any).
    pub corner_rep: f64,
    /// Frames usable for odometry per second (all seeds pooled), by the
    /// combined rule of docs/spec.md section 11: repeatability at least
    /// `corners::REPEAT_OK` and, after the walk's first kept frame, at
    /// least `matches::TRACK_MIN` inlier matches to the previous kept frame.
    pub vo_fps: f64,
    /// Frames per second with repeatability at least `corners::REPEAT_OK`
    /// (the repeatability half of the rule alone).
    pub rep_fps: f64,
    /// Trackable frames per second: at least `matches::TRACK_MIN` inlier
    /// matches to the previous kept frame (`matches.rs`).
    pub trackable_fps: f64,
    /// Mean inlier matches to the previous kept frame (NaN without a pair).
    pub mean_inliers: f64,
}

/// One cell of the map.
#[derive(Debug, Clone, PartialEq)]
pub struct Cell {
    /// Light, e-/s for a white pixel.
    pub light: f64,
    /// Gait.
    pub gait: String,
    /// Board (`blobs:0.5` or `blobs`).
    pub board: String,
    /// Every policy, in the map's order.
    pub policies: Vec<CellPolicy>,
    /// Index of the best `mmbm` policy.
    pub best_mmbm: Option<usize>,
    /// Index of the best fixed exposure in hindsight (over the grid).
    pub hindsight: Option<usize>,
    /// Index of the best auto-exposure.
    pub ae: Option<usize>,
    /// Index of the thesis's fixed rate.
    pub fixed: Option<usize>,
    /// Index of the best `gyro-exposure` policy (fixed rate, exposure from the gyro).
    pub gyro: Option<usize>,
    /// Best `mmbm` over the best fixed exposure in hindsight.
    pub vs_hindsight: Option<Estimate>,
    /// Best `mmbm` over auto-exposure.
    pub vs_ae: Option<Estimate>,
    /// Best `mmbm` over the fixed rate.
    pub vs_fixed: Option<Estimate>,
    /// Does timing pay? Best `mmbm` (trigger timing from the gyro) over the
    /// best `gyro-exposure` policy (docs/spec.md section 11).
    pub vs_gyro: Option<Estimate>,
    /// Index of the policy with the most sharp frames per second.
    pub winner: usize,
    /// Index of the policy with the most frames usable for odometry per
    /// second (the second task's winner).
    pub vo_winner: usize,
    /// Second task: the best `mmbm` policy by VO frames/s over the strongest
    /// baseline by VO frames/s (the most VO frames/s among the hindsight
    /// grid, auto-exposure and `gyro-exposure`), with its interval, and the
    /// indices `(best mmbm, strongest baseline)` it compares.
    pub vo_vs_baseline: Option<(Estimate, usize, usize)>,
    /// Blocks resampled.
    pub blocks: usize,
}

/// The whole map.
#[derive(Debug, Clone, PartialEq)]
pub struct BenefitMap {
    /// The cells, light-major (lights in configuration order, then gait, then board).
    pub cells: Vec<Cell>,
    /// Light levels, e-/s.
    pub lights: Vec<f64>,
    /// Gaits.
    pub gaits: Vec<String>,
    /// Boards.
    pub boards: Vec<String>,
    /// Seeds.
    pub seeds: Vec<u64>,
    /// The sensor (read noise, full well, bits, noise seed).
    pub sensor: Noise,
    /// The reference exposure, s.
    pub t_ref_s: f64,
    /// The maximum gain in units of the full-well gain.
    pub max_gain_x: f64,
    /// The fixed-exposure grid, ms.
    pub grid_ms: Vec<f64>,
    /// The frame rate of `fixed` and of the grid, frames/s.
    pub fps: f64,
    /// Frames rendered (each judged at every light).
    pub renders: usize,
    /// Wall time, s.
    pub seconds: f64,
}

/// The map's policies: the configured ones, the fixed rate and the grid
/// (`fixed:FPS@Tms`; the grid's `T_ref` is the fixed rate itself).
pub fn map_policies(cfg: &ExperimentConfig) -> Result<Vec<PolicySpec>> {
    let m = &cfg.map;
    let mut out: Vec<PolicySpec> = Vec::new();
    let mut push = |p: PolicySpec| {
        if !out.iter().any(|q| q.as_str() == p.as_str()) {
            out.push(p);
        }
    };
    push(PolicySpec::fixed(m.fps, None)?);
    for p in &m.policies {
        push(p.clone());
    }
    for &t in &m.grid_ms {
        if (t * 1e-3 - cfg.exposure_s).abs() > 1e-9 {
            push(PolicySpec::fixed(m.fps, Some(t))?);
        }
    }
    Ok(out)
}

/// The map's simulated gaits: `map.gaits`, else the experiment's walks
/// (none with the experiment's `gyro` log: it is a column of its own,
/// [`logs::map_logs`]).
pub fn map_gaits(cfg: &ExperimentConfig) -> Vec<String> {
    if !cfg.map.gaits.is_empty() {
        cfg.map.gaits.clone()
    } else if cfg.gyro.is_some() {
        Vec::new()
    } else {
        cfg.walks.clone()
    }
}

/// True when policy `p` is in the hindsight grid.
fn in_grid(cfg: &ExperimentConfig, p: &PolicySpec) -> bool {
    match p.policy_family() {
        PolicyFamily::FixedExposure => true,
        PolicyFamily::Fixed => cfg
            .map
            .grid_ms
            .iter()
            .any(|&t| (t * 1e-3 - cfg.exposure_s).abs() <= 1e-9),
        _ => false,
    }
}

/// Per light and policy: what its kept frames gave.
#[derive(Debug, Clone, Copy, Default)]
struct Tally {
    frames: usize,
    sharp: usize,
    exposure_s: f64,
    capped: usize,
    false_alarms: usize,
    rep_sum: f64,
    rep_n: usize,
    /// Frames with repeatability at least `corners::REPEAT_OK`.
    rep_ok: usize,
    /// Inlier matches to the previous kept frame, summed over `pairs` frames.
    inliers: usize,
    pairs: usize,
    /// Frames with at least `TRACK_MIN` inliers to the previous kept frame.
    trackable: usize,
    /// Frames usable for odometry by the combined rule.
    vo: usize,
}

/// Per block: its seconds and, per light and policy, its sharp frames and
/// its frames usable for odometry.
struct Block {
    seconds: f64,
    sharp: Vec<f64>,
    vo: Vec<f64>,
}

/// Runs the map (None when `map.lights_e_per_s` is empty): each frame's
/// judged window rendered once for all lights ([`Renders::Shared`]).
pub fn benefit_map(
    cfg: &ExperimentConfig,
    quality: Quality,
    progress: bool,
) -> Result<Option<BenefitMap>> {
    benefit_map_with(cfg, quality, progress, Renders::Shared)
}

/// `benefit_map` (the crate's default: shared renders) with the frames rendered as `renders` says (the numbers
/// do not depend on it; [`Renders::PerLight`] is the slow reference).
pub fn benefit_map_with(
    cfg: &ExperimentConfig,
    quality: Quality,
    progress: bool,
    renders_how: Renders,
) -> Result<Option<BenefitMap>> {
    let m = &cfg.map;
    if m.lights_e_per_s.is_empty() {
        return Ok(None);
    }
    let t_start = std::time::Instant::now();
    let policies = map_policies(cfg)?;
    let np = policies.len();
    let mut gaits = map_gaits(cfg);
    let map_logs = logs::map_logs(cfg);
    logs::check_logs(cfg, &gaits)?;
    let seeds = if m.seeds.is_empty() {
        cfg.seed_list()
    } else {
        m.seeds.clone()
    };
    let sensor = cfg.camera.noise.unwrap_or_else(|| Noise::at_light(1.0));
    let surround: crate::render::Background = cfg.background.parse()?;
    let lights: Vec<Light> = m
        .lights_e_per_s
        .iter()
        .map(|&phi| Light::new(&sensor, phi, cfg.exposure_s, m.max_gain_x))
        .collect();
    let nl = lights.len();
    let cam = crate::camera::Camera {
        noise: None,
        ..cfg.camera()
    };
    let scene = Scene {
        camera: cam,
        plane: None,
    };
    let mcfg = ExperimentConfig {
        policies: policies.clone(),
        gyro: None,
        ..cfg.clone()
    };
    let mut walks: Vec<(usize, Walk)> = Vec::new();
    for (gi, g) in gaits.iter().enumerate() {
        for &s in &seeds {
            walks.push((gi, make_walk(&mcfg, g, s, true, &scene)?));
        }
    }
    for p in &map_logs {
        let w = logs::log_walk(&mcfg, p, &scene)?;
        for _ in &seeds {
            walks.push((gaits.len(), w.clone()));
        }
        gaits.push(w.gait);
    }
    let kept = |w: &Walk| -> usize {
        w.runs
            .iter()
            .map(|(_, f)| f.iter().filter(|f| f.kept).count())
            .sum()
    };
    let total: usize = walks.iter().map(|(_, w)| kept(w)).sum::<usize>() * m.boards.len();
    let bar = crate::diagnostics::progress(progress, "benefit map: frames", total as u64);
    let mut cells = Vec::new();
    // Per (gait, board): the blocks of all seeds; per light, the cells.
    let mut per_column: Vec<Vec<Cell>> = Vec::new();
    let mut renders = 0usize;
    for (gi, g) in gaits.iter().enumerate() {
        for board in &m.boards {
            let mut blocks: Vec<Block> = Vec::new();
            // Per light and policy.
            let mut tally = vec![Tally::default(); nl * np];
            for (_, w) in walks.iter().filter(|(wg, _)| *wg == gi) {
                let wb = WalkBlocks::of(w);
                let first = blocks.len();
                for &seconds in &wb.seconds {
                    blocks.push(Block {
                        seconds,
                        sharp: vec![0.0; nl * np],
                        vo: vec![0.0; nl * np],
                    });
                }
                // Each policy's kept frames are judged in parallel, and so are
                // the policies (no core waits at the end of a policy); each
                // frame's seed is its place in the serial order (policies in
                // order, frames in order), so the result does not depend on
                // the thread count. A policy keeps only what the tally needs
                // (the verdicts and the inliers to its previous kept frame),
                // then the frames are tallied in order.
                let kept: Vec<Vec<&Frame>> = w
                    .runs
                    .iter()
                    .map(|(_, frames)| frames.iter().filter(|f| f.kept).collect())
                    .collect();
                // Each policy's first seed: the frames counted before it.
                let seed0s: Vec<usize> = kept
                    .iter()
                    .map(|k| {
                        renders += k.len();
                        renders - k.len()
                    })
                    .collect();
                let judged: Vec<Vec<Tallied>> = kept
                    .par_iter()
                    .zip(&seed0s)
                    .map(|(kept, &seed0)| -> Result<Vec<Tallied>> {
                        if let Some(f) = kept.first() {
                            bar.message(&format!("{g} {board} {}", f.policy));
                        }
                        let judged: Vec<(Vec<Judged>, FrameFeatures)> = kept
                            .par_iter()
                            .enumerate()
                            .map(|(j, f)| {
                                judge_at_lights(
                                    board,
                                    surround,
                                    w,
                                    f,
                                    cam,
                                    quality,
                                    (seed0 + j) as u32,
                                    &lights,
                                    renders_how,
                                )
                            })
                            .collect::<Result<_>>()?;
                        bar.advance(kept.len() as u64);
                        // Inlier matches to the previous kept frame, per
                        // light (None for the policy's first in the walk).
                        let mut out = Vec::with_capacity(judged.len());
                        let mut prev: Option<FrameFeatures> = None;
                        for (js, feats) in judged {
                            out.push((js, prev.as_ref().map(|p| tracked(p, &feats))));
                            prev = Some(feats);
                        }
                        Ok(out)
                    })
                    .collect::<Result<_>>()?;
                for (pi, (kept, judged)) in kept.iter().zip(&judged).enumerate() {
                    for (f, (js, inl)) in kept.iter().zip(judged) {
                        let b = wb.index(f.trigger_t);
                        for (li, j) in js.iter().enumerate() {
                            let k = li * np + pi;
                            blocks[first + b].sharp[k] += f64::from(u8::from(j.ok));
                            let t = &mut tally[k];
                            t.frames += 1;
                            t.sharp += usize::from(j.ok);
                            t.exposure_s += f.exposure_s();
                            t.capped += usize::from(lights[li].capped(f.gain));
                            t.false_alarms += j.false_alarms;
                            let inliers = inl.as_ref().map(|v| v[li]);
                            if let Some(i) = inliers {
                                t.inliers += i;
                                t.pairs += 1;
                                t.trackable += usize::from(i >= TRACK_MIN);
                            }
                            if j.corner_rep.is_finite() {
                                t.rep_sum += j.corner_rep;
                                t.rep_n += 1;
                                let rep = j.corner_rep >= super::corners::REPEAT_OK;
                                t.rep_ok += usize::from(rep);
                                let vo = rep && inliers.is_none_or(|i| i >= TRACK_MIN);
                                t.vo += usize::from(vo);
                                blocks[first + b].vo[k] += f64::from(u8::from(vo));
                            }
                        }
                    }
                }
            }
            let mut column = Vec::new();
            for (li, light) in m.lights_e_per_s.iter().enumerate() {
                column.push(cell(
                    cfg,
                    &policies,
                    &blocks,
                    li,
                    &tally[li * np..(li + 1) * np],
                    (*light, g, board),
                ));
            }
            per_column.push(column);
        }
    }
    drop(bar);
    for li in 0..nl {
        for col in &per_column {
            cells.push(col[li].clone());
        }
    }
    Ok(Some(BenefitMap {
        cells,
        lights: m.lights_e_per_s.clone(),
        gaits,
        boards: m.boards.clone(),
        seeds,
        sensor,
        t_ref_s: cfg.exposure_s,
        max_gain_x: m.max_gain_x,
        grid_ms: m.grid_ms.clone(),
        fps: m.fps,
        renders,
        seconds: t_start.elapsed().as_secs_f64(),
    }))
}

/// A judged frame as the tally needs it: its verdict at each light and its
/// inlier matches to its policy's previous kept frame at each light (None
/// for the first).
type Tallied = (Vec<Judged>, Option<Vec<usize>>);

/// Inlier matches of `cur` to `prev` at each light, against the true
/// homography between the two frames (0 when the board does not give one).
fn tracked(prev: &FrameFeatures, cur: &FrameFeatures) -> Vec<usize> {
    let h = true_homography(&prev.board_px, &cur.board_px);
    prev.per_light
        .iter()
        .zip(&cur.per_light)
        .map(|(a, b)| h.as_ref().map_or(0, |h| match_inliers(a, b, h)))
        .collect()
}

/// The best policy (highest point estimate; the first of ties) among those `pick` accepts.
fn best(ps: &[CellPolicy], pick: impl Fn(&CellPolicy) -> bool) -> Option<usize> {
    let mut out: Option<usize> = None;
    for (i, p) in ps.iter().enumerate().filter(|(_, p)| pick(p)) {
        if out.is_none_or(|b| p.sharp_fps > ps[b].sharp_fps) {
            out = Some(i);
        }
    }
    out
}

/// One cell from its blocks.
fn cell(
    cfg: &ExperimentConfig,
    policies: &[PolicySpec],
    blocks: &[Block],
    li: usize,
    tally: &[Tally],
    (light, gait, board): (f64, &str, &str),
) -> Cell {
    let np = policies.len();
    // Frames per second of policy `pi` over the blocks `idx`: sharp ones
    // (`vo` false) or ones usable for odometry (`vo` true).
    let rate = |idx: &mut dyn Iterator<Item = usize>, pi: usize, vo: bool| {
        let (mut ok, mut secs) = (0.0, 0.0);
        for k in idx {
            let b = &blocks[k];
            ok += if vo {
                b.vo[li * np + pi]
            } else {
                b.sharp[li * np + pi]
            };
            secs += b.seconds;
        }
        ok / secs
    };
    let fps = |idx: &mut dyn Iterator<Item = usize>, pi: usize| rate(idx, pi, false);
    let samples = bootstrap_indices(blocks.len());
    let fixed = super::benefit::baseline(policies);
    // The ratio of policy `a` to `b` over all blocks with its interval.
    let ratio_of = |a: usize, b: usize, vo: bool| -> Estimate {
        let all = rate(&mut (0..blocks.len()), a, vo) / rate(&mut (0..blocks.len()), b, vo);
        interval(
            all,
            samples
                .iter()
                .map(|s| rate(&mut s.iter().copied(), a, vo) / rate(&mut s.iter().copied(), b, vo)),
        )
    };
    let seconds: f64 = blocks.iter().map(|b| b.seconds).sum();
    let ps: Vec<CellPolicy> = policies
        .iter()
        .enumerate()
        .map(|(pi, p)| CellPolicy {
            policy: p.clone(),
            sharp_fps: fps(&mut (0..blocks.len()), pi),
            sharp_ci: interval(
                fps(&mut (0..blocks.len()), pi),
                samples.iter().map(|s| fps(&mut s.iter().copied(), pi)),
            ),
            vs_fixed: fixed.map(|f| ratio_of(pi, f, false)),
            frames: tally[pi].frames,
            sharp: tally[pi].sharp,
            mean_exposure_s: tally[pi].exposure_s / tally[pi].frames.max(1) as f64,
            gain_capped: tally[pi].capped,
            false_alarms: tally[pi].false_alarms,
            corner_rep: if tally[pi].rep_n > 0 {
                tally[pi].rep_sum / tally[pi].rep_n as f64
            } else {
                f64::NAN
            },
            vo_fps: tally[pi].vo as f64 / seconds,
            rep_fps: tally[pi].rep_ok as f64 / seconds,
            trackable_fps: tally[pi].trackable as f64 / seconds,
            mean_inliers: if tally[pi].pairs > 0 {
                tally[pi].inliers as f64 / tally[pi].pairs as f64
            } else {
                f64::NAN
            },
        })
        .collect();
    let fam = |f: PolicyFamily| move |p: &CellPolicy| p.policy.policy_family() == f;
    let best_mmbm = best(&ps, fam(PolicyFamily::Mmbm));
    let hindsight = best(&ps, |p| in_grid(cfg, &p.policy));
    let ae = best(&ps, fam(PolicyFamily::AutoExposure));
    let gyro = best(&ps, fam(PolicyFamily::GyroExposure));
    let winner = best(&ps, |_| true).unwrap_or(0);
    let ratio = |a: Option<usize>, b: Option<usize>| Some(ratio_of(a?, b?, false));
    // The second task: the most VO frames/s.
    let best_vo = |pick: &dyn Fn(&CellPolicy) -> bool| -> Option<usize> {
        let mut out: Option<usize> = None;
        for (i, p) in ps.iter().enumerate().filter(|(_, p)| pick(p)) {
            if out.is_none_or(|b| p.vo_fps > ps[b].vo_fps) {
                out = Some(i);
            }
        }
        out
    };
    let vo_winner = best_vo(&|_| true).unwrap_or(0);
    let vo_mmbm = best_vo(&|p| p.policy.policy_family() == PolicyFamily::Mmbm);
    let vo_base = best_vo(&|p| {
        in_grid(cfg, &p.policy)
            || matches!(
                p.policy.policy_family(),
                PolicyFamily::AutoExposure | PolicyFamily::GyroExposure
            )
    });
    let vo_vs_baseline = match (vo_mmbm, vo_base) {
        (Some(a), Some(b)) => Some((ratio_of(a, b, true), a, b)),
        _ => None,
    };
    Cell {
        light,
        gait: gait.to_string(),
        board: board.to_string(),
        vs_hindsight: ratio(best_mmbm, hindsight),
        vs_ae: ratio(best_mmbm, ae),
        vs_fixed: ratio(best_mmbm, fixed),
        vs_gyro: ratio(best_mmbm, gyro),
        policies: ps,
        best_mmbm,
        hindsight,
        ae,
        fixed,
        gyro,
        winner,
        vo_winner,
        vo_vs_baseline,
        blocks: blocks.len(),
    }
}

/// A point estimate and the 95 % percentile interval of its `draws`
/// ([`estimate`]: infinite ratios kept, NaN ones dropped).
fn interval(value: f64, draws: impl Iterator<Item = f64>) -> Estimate {
    estimate(value, draws.collect())
}
