//! The benefit map in the report: its table (the report's first), the
//! detail per cell, the goals checked against it, the lost cells
//! with their reasons (all computed from the map), a heat map, and the few
//! lines the terminal ends with.

use super::super::benefit::{Estimate, BLOCK_S, BOOTSTRAP_SEED, RESAMPLES};
use super::super::corners::{FAST_THRESHOLD, MATCH_PX, NMS_RADIUS, REPEAT_OK};
use super::super::matches::{BRIEF_BITS, INLIER_PX, MAX_FEATURES, RATIO, TRACK_MIN};
pub use super::heat::heat_map_png;
use super::verdict::{column, ratio_text};
use super::{BenefitMap, Cell};
use std::path::Path;

/// Light below which a cell is dim (the goals' "<= 1,000 e-/s"), e-/s.
pub const DIM_LIGHT: f64 = 1_000.0;

fn ci(e: &Estimate) -> String {
    ratio_text(e)
}

fn opt(e: &Option<Estimate>) -> String {
    e.as_ref().map_or("-".into(), ci)
}

/// True when the cell is lost: the best `mmbm` policy is below the best
/// fixed exposure in hindsight or auto-exposure (the ratio's upper bound under 1).
pub fn lost(c: &Cell) -> bool {
    [&c.vs_hindsight, &c.vs_ae]
        .iter()
        .any(|e| e.is_some_and(|e| e.hi < 1.0))
}

/// Does timing pay in cell `c`? `pays` when the best `mmbm` policy's ratio
/// to the best `gyro-exposure` policy has its 95 % interval above 1, `loses`
/// when below 1, `ties` when it reaches 1, `n/a` without both families.
pub fn timing_verdict(c: &Cell) -> &'static str {
    match c.vs_gyro {
        Some(e) if e.lo > 1.0 => "pays",
        Some(e) if e.hi < 1.0 => "loses",
        Some(e) if e.lo.is_finite() && e.hi.is_finite() => "ties",
        _ => "n/a",
    }
}

/// The report's opening: the three lines of [`super::verdict::three_lines`]
/// as a list, then the map's section (`map_md`, with the timing, second-task and goal sections).
pub fn opening_md(m: &BenefitMap, figure: Option<&str>) -> String {
    let mut s = String::new();
    for line in super::verdict::three_lines(m) {
        s += &format!("- {line}\n");
    }
    s += "\n";
    s + &map_md(m, figure)
}

/// The map's section of the report.
pub fn map_md(m: &BenefitMap, figure: Option<&str>) -> String {
    let mut s =
        String::from("## Benefit map: gyro-driven capture against what users do instead\n\n");
    let first = m.cells.first();
    s += &format!(
        "Sharp frames per second (kept, rendered, all 16 blobs at their true places) of the best causal gyro-driven \
         policy (family `mmbm`) over the best fixed exposure in hindsight (family `oracle`: the fixed exposure of the \
         grid {:?} ms with the most sharp frames in the cell), over auto-exposure (`auto-exposure`) and, to ask whether \
         the trigger's *timing* pays, over the best gyro-aware exposure at the fixed rate (`gyro-exposure`: \
         `ae-blur`, `ae-imu`, `fixed:FPS+exp`; docs/spec.md section 11). Frames judged: every kept frame of seeds {:?}, \
         each judged in a window around the board (the blob grid padded by {} blob pitches); the headline below reads \
         this table's cell. {:.0}-s blocks ({} per cell), 95 % percentile bootstrap over {} resamplings of the blocks (bootstrap seed {}), \
         paired block by block; the best policies are chosen on all blocks, then held fixed. Light = electrons per \
         second in a white pixel; gain `K_ref = {} / (light x {:.0} ms)` (white fills the range at the reference \
         exposure), raised by each policy to keep the brightness and capped at {}x the full-well gain ({:.3} DN/e-); \
         read noise {} e-, full well {} e-, {} bits.\n\n",
        m.grid_ms,
        m.seeds,
        super::render::WINDOW_PITCHES,
        BLOCK_S,
        first.map_or(0, |c| c.blocks),
        RESAMPLES,
        BOOTSTRAP_SEED,
        m.sensor.max_dn(),
        m.t_ref_s * 1e3,
        m.max_gain_x,
        m.max_gain_x * m.sensor.max_dn() / m.sensor.full_well_e,
        m.sensor.read_noise_e,
        m.sensor.full_well_e,
        m.sensor.bits,
    );
    let mut cols: Vec<String> = Vec::new();
    for c in &m.cells {
        if !cols.contains(&column(c)) {
            cols.push(column(c));
        }
    }
    s += "| light (e-/s) |";
    for c in &cols {
        s += &format!(" {c} |");
    }
    s += "\n|---|";
    s += &"---|".repeat(cols.len());
    s += "\n";
    for &l in &m.lights {
        s += &format!("| {l} |");
        for col in &cols {
            let Some(c) = m.cells.iter().find(|c| c.light == l && &column(c) == col) else {
                s += " - |";
                continue;
            };
            let w = &c.policies[c.winner];
            s += &format!(
                " {}vs best fixed {}; vs AE {}; timing vs gyro-exposure {} ({}); won: `{}`{}; VO won: `{}` |",
                if lost(c) { "**lost** " } else { "" },
                opt(&c.vs_hindsight),
                opt(&c.vs_ae),
                opt(&c.vs_gyro),
                timing_verdict(c),
                w.policy,
                if c.hindsight == Some(c.winner) {
                    " (best fixed in hindsight)"
                } else {
                    ""
                },
                c.policies[c.vo_winner].policy
            );
        }
        s += "\n";
    }
    if let Some(f) = figure {
        s += &format!("\n![benefit map]({f})\n");
    }
    s += "\n| light | gait, board | best `mmbm` (sharp/s) | best fixed in hindsight (sharp/s) | auto-exposure (sharp/s, % sharp) | `fixed` (sharp/s) | vs `fixed` |\n";
    s += "|---|---|---|---|---|---|---|\n";
    for c in &m.cells {
        let p = |i: Option<usize>| {
            i.map_or("-".into(), |i| {
                format!("`{}` {:.2}", c.policies[i].policy, c.policies[i].sharp_fps)
            })
        };
        let ae = c.ae.map_or("-".into(), |i| {
            let a = &c.policies[i];
            format!(
                "`{}` {:.2}, {:.0} %",
                a.policy,
                a.sharp_fps,
                100.0 * a.sharp as f64 / a.frames.max(1) as f64
            )
        });
        s += &format!(
            "| {} | {} | {} | {} | {} | {} | {} |\n",
            c.light,
            column(c),
            p(c.best_mmbm),
            p(c.hindsight),
            ae,
            p(c.fixed),
            opt(&c.vs_fixed)
        );
    }
    s += "\n";
    s += &timing_md(m);
    s += &second_metric_md(m);
    s += &goals_md(m);
    s += &format!(
        "\nThe map rendered {} frames (each judged at all {} lights) in {:.0} s.\n\n",
        m.renders,
        m.lights.len(),
        m.seconds
    );
    s
}

/// The second task metric per cell, next to the blob metric: for the best
/// `mmbm` policy, the best fixed exposure in hindsight and auto-exposure,
/// sharp frames per second (blobs), frames usable for odometry per second
/// (the VO rule: corner repeatability at least [`REPEAT_OK`] and, after the
/// walk's first kept frame, at least [`TRACK_MIN`] inlier matches to the
/// previous kept frame), the mean repeatability, the trackable frames per
/// second, the mean inliers and the false alarms per frame; then, computed from the table, the policy
/// with the most odometry frames per second in each cell.
pub fn second_metric_md(m: &BenefitMap) -> String {
    let mut s = format!(
        "Second task metric (visual odometry): FAST-9 corners (threshold {}, non-maximum suppression over {} px) \
         of each frame against those of the sharp, noiseless frame at its mid-exposure pose, in the same window; \
         repeatability = share of the sharp frame's corners re-found within {} px by the frame's strongest corners \
         (as many as the sharp frame has, so that noise corners do not match by chance). Feature matches between \
         consecutive kept frames (what odometry consumes): the strongest {} FAST-9 corners of each frame described by \
         {}-bit BRIEF (imageproc, fixed test pairs), each matched to its nearest descriptor in the previous kept frame \
         of the same policy and walk, kept by the ratio test (nearest < {} x second nearest), and counted as inliers \
         when the true homography between the two frames (the board's plane, fitted to its 16 blob centres at both \
         mid-exposure poses) carries the match within {} px; a frame is trackable at >= {} inliers. \
         **VO rule**: a frame is usable for odometry (VO) when its repeatability is >= {} and, after the walk's first \
         kept frame, it is trackable; the VO winner and the VO ratios use this rule. Per policy: sharp frames/s by \
         the blob verdict, VO frames/s, mean repeatability, trackable frames/s and mean inliers, false alarms per \
         frame (blobs found away from every board place).\n\n",
        FAST_THRESHOLD,
        NMS_RADIUS,
        MATCH_PX,
        MAX_FEATURES,
        BRIEF_BITS,
        RATIO,
        INLIER_PX,
        TRACK_MIN,
        REPEAT_OK
    );
    s += "| light | gait, board | best `mmbm` | best fixed in hindsight | auto-exposure | most VO frames/s | VO: best `mmbm` over the strongest baseline |\n";
    s += "|---|---|---|---|---|---|---|\n";
    let show = |c: &Cell, i: Option<usize>| {
        i.map_or("-".into(), |i| {
            let p = &c.policies[i];
            format!(
                "`{}` {:.2} sharp/s, {:.2} VO/s, rep. {:.2}, {:.2} trackable/s, {:.1} inliers, {:.2} false/frame",
                p.policy,
                p.sharp_fps,
                p.vo_fps,
                p.corner_rep,
                p.trackable_fps,
                p.mean_inliers,
                p.false_alarms as f64 / p.frames.max(1) as f64
            )
        })
    };
    for c in &m.cells {
        let vo = c
            .policies
            .get(c.vo_winner)
            .map_or("-".into(), |p| format!("`{}` {:.2}", p.policy, p.vo_fps));
        s += &format!(
            "| {} | {} | {} | {} | {} | {} | {} |\n",
            c.light,
            column(c),
            show(c, c.best_mmbm),
            show(c, c.hindsight),
            show(c, c.ae),
            vo,
            vo_ratio(c)
        );
    }
    // Where the best `mmbm` policy leads on odometry frames too.
    let (mut lead, mut n) = (0, 0);
    for c in &m.cells {
        if let (Some(b), Some(h)) = (c.best_mmbm, c.hindsight) {
            n += 1;
            lead += usize::from(c.policies[b].vo_fps >= c.policies[h].vo_fps);
        }
    }
    s += &format!(
        "\nThe best `mmbm` policy (chosen by the blob metric) gets at least as many VO frames per second as the \
         best fixed exposure in hindsight in {lead} of {n} cells.\n\n"
    );
    s
}

/// The reason a cell is lost, from its numbers.
fn reason(c: &Cell) -> String {
    let w = &c.policies[c.winner];
    let Some(b) = c.best_mmbm.map(|i| &c.policies[i]) else {
        return "no `mmbm` policy was run".into();
    };
    let share = |p: &super::CellPolicy| 100.0 * p.sharp as f64 / p.frames.max(1) as f64;
    format!(
        "`{}` gets {:.2} sharp/s ({:.0} % of {} frames sharp, mean exposure {:.1} ms, {} frames gain-capped) against \
         `{}`'s {:.2} ({:.0} % of {}, mean exposure {:.1} ms, {} gain-capped)",
        w.policy,
        w.sharp_fps,
        share(w),
        w.frames,
        w.mean_exposure_s * 1e3,
        w.gain_capped,
        b.policy,
        b.sharp_fps,
        share(b),
        b.frames,
        b.mean_exposure_s * 1e3,
        b.gain_capped
    )
}

/// The ceiling a policy at the map's frame rate meets against the baseline
/// `base` of cell `c`: `fps / sharp_fps` (no policy at that rate takes more
/// than `fps` frames per second); empty when the baseline has no sharp frame.
fn ceiling(m: &BenefitMap, c: &Cell, base: Option<usize>) -> String {
    match base.map(|i| &c.policies[i]) {
        Some(b) if b.sharp_fps > 0.0 => format!(
            " (at {} frames/s no policy can get more than {} / {:.2} = {:.2}x, since `{}` already gets {:.2} sharp \
             frames/s)",
            m.fps,
            m.fps,
            b.sharp_fps,
            m.fps / b.sharp_fps,
            b.policy,
            b.sharp_fps
        ),
        _ => String::new(),
    }
}

/// The benefit map's goals (docs/experiment.md, "The benefit map"), checked
/// against the map (met or not, with the numbers).
pub fn goals_md(m: &BenefitMap) -> String {
    let mut s =
        String::from("Goals (docs/experiment.md, the benefit map), computed from the map:\n\n");
    let met = |b: bool| if b { "met" } else { "not met" };
    // 1. Half board, the demo's light, moderate walk: >= 1.5x fixed, CI above 1.
    let demo = super::super::config::ExperimentConfig::DEMO_LIGHT_E_PER_S;
    match m
        .cells
        .iter()
        .find(|c| c.light == demo && c.gait == "moderate" && c.board == "blobs:0.5")
    {
        Some(c) => {
            if let Some(r) = c.vs_fixed {
                s += &format!(
                    "- Half board, {demo} e-/s, moderate walk: the best `mmbm` policy gets {} the sharp frames per second \
                     of `fixed` (goal >= 1.5x with the CI above 1: {}){}.\n",
                    ci(&r),
                    met(r.value >= 1.5 && r.lo > 1.0),
                    ceiling(m, c, c.fixed)
                );
            }
        }
        None => {
            s += &format!("- The cell half board, {demo} e-/s, moderate walk is not in this map.\n")
        }
    }
    // 2. Every cell: below neither; >= 1.3x AE where AE gets < 80 % sharp.
    let n = m.cells.len();
    let ok_both = m.cells.iter().filter(|c| !lost(c)).count();
    s += &format!(
        "- In {ok_both} of {n} cells the best `mmbm` policy is below neither the best fixed exposure in hindsight nor \
         auto-exposure (each CI reaches 1; goal: every cell, {}).\n",
        met(ok_both == n)
    );
    let weak: Vec<&Cell> = m
        .cells
        .iter()
        .filter(|c| {
            c.ae.is_some_and(|i| {
                let a = &c.policies[i];
                (a.sharp as f64) < 0.8 * a.frames as f64
            })
        })
        .collect();
    let weak_ok = weak
        .iter()
        .filter(|c| c.vs_ae.is_some_and(|r| r.value >= 1.3))
        .count();
    s += &format!(
        "- Auto-exposure gets fewer than 80 % of its frames sharp in {} cells; there the best `mmbm` policy reaches \
         1.3x auto-exposure in {weak_ok} (goal: all, {}).\n",
        weak.len(),
        met(weak_ok == weak.len())
    );
    // 3. Dim cells: >= 1.3x the best fixed exposure in hindsight, CI above 1.
    let dim: Vec<&Cell> = m.cells.iter().filter(|c| c.light <= DIM_LIGHT).collect();
    let dim_ok = dim
        .iter()
        .filter(|c| c.vs_hindsight.is_some_and(|r| r.value >= 1.3 && r.lo > 1.0))
        .count();
    s += &format!(
        "- Dim cells (<= {DIM_LIGHT} e-/s): {dim_ok} of {} reach 1.3x the best fixed exposure in hindsight with the CI \
         above 1 (goal: all, {}){}.\n",
        dim.len(),
        met(!dim.is_empty() && dim_ok == dim.len()),
        dim.iter()
            .map(|c| format!(
                "; {} {}: {}{}",
                c.light,
                column(c),
                opt(&c.vs_hindsight),
                ceiling(m, c, c.hindsight)
            ))
            .collect::<String>()
    );
    // 4. Dim cells, second task: >= 1.5x the strongest baseline's VO frames/s, CI above 1.
    let vo_ok = dim
        .iter()
        .filter(|c| {
            c.vo_vs_baseline
                .is_some_and(|(r, ..)| r.value >= 1.5 && r.lo > 1.0)
        })
        .count();
    s += &format!(
        "- Dim cells (<= {DIM_LIGHT} e-/s), odometry task: {vo_ok} of {} reach 1.5x the VO frames per second (VO rule: \
         repeatability >= {REPEAT_OK} and >= {TRACK_MIN} inliers to the previous kept frame) of the strongest baseline \
         (hindsight grid, auto-exposure, `gyro-exposure`) with the CI above 1 (goal: all, {}){}.\n",
        dim.len(),
        met(!dim.is_empty() && vo_ok == dim.len()),
        dim.iter()
            .map(|c| format!("; {} {}: {}", c.light, column(c), vo_ratio(c)))
            .collect::<String>()
    );
    for c in m.cells.iter().filter(|c| lost(c)) {
        s += &format!("- Lost: {} e-/s, {}: {}.\n", c.light, column(c), reason(c));
    }
    s
}

/// The odometry task's ratio of cell `c`: `1.20x [1.01, 1.40] (`a` over `b`)`.
pub fn vo_ratio(c: &Cell) -> String {
    match c.vo_vs_baseline {
        Some((r, a, b)) => format!(
            "{} (`{}` over `{}`)",
            ci(&r),
            c.policies[a].policy,
            c.policies[b].policy
        ),
        None => "-".into(),
    }
}

/// Timing against gyro-aware exposure, per cell, with the numbers that
/// explain it: for the best `mmbm` policy and the best `gyro-exposure`
/// policy, the share of sharp frames, the mean exposure, the frames whose
/// gain the sensor's maximum capped, and the gain headroom at that light
/// (the maximum gain over the reference gain `K_ref`): an exposure shorter
/// than `T_ref / headroom` cannot be brought back to full brightness, so a
/// policy that shortens the exposure for blur (as `gyro-exposure` does at a
/// fixed rate) gets darker, noisier frames in dim light.
pub fn timing_md(m: &BenefitMap) -> String {
    let mut s = String::from(
        "### Timing against gyro-aware exposure, per cell\n\nWhy the best `mmbm` policy (trigger timing from \
         the gyro) and the best `gyro-exposure` policy (fixed rate, exposure from the gyro) differ, from the map's \
         frames (all seeds pooled):\n\n",
    );
    for c in &m.cells {
        let (Some(a), Some(g)) = (c.best_mmbm, c.gyro) else {
            continue;
        };
        let light = super::render::Light::new(&m.sensor, c.light, m.t_ref_s, m.max_gain_x);
        let headroom = light.max_gain_dn_per_e / light.noise.gain();
        let one = |p: &super::CellPolicy| {
            format!(
                "`{}` {:.0} % of {} frames sharp, mean exposure {:.1} ms, {} gain-capped",
                p.policy,
                100.0 * p.sharp as f64 / p.frames.max(1) as f64,
                p.frames,
                p.mean_exposure_s * 1e3,
                p.gain_capped
            )
        };
        s += &format!(
            "- {} e-/s, {}: timing vs gyro-exposure {} ({}); {} against {}; gain headroom {:.2}x, so exposures under \
             {:.1} ms are darker than meant.\n",
            c.light,
            column(c),
            opt(&c.vs_gyro),
            timing_verdict(c),
            one(&c.policies[a]),
            one(&c.policies[g]),
            headroom,
            m.t_ref_s / headroom * 1e3
        );
    }
    s.push('\n');
    s
}

/// The few lines the terminal ends with: the three lines of
/// [`super::verdict::three_lines`], the map's ratios and where the report is.
pub fn answer(m: &BenefitMap, report: &Path) -> Vec<String> {
    let mut out: Vec<String> = super::verdict::three_lines(m).into();
    let won = m.cells.iter().filter(|c| !lost(c)).count();
    out.push(format!(
        "Benefit map ({} cells, seeds {:?}): gyro-driven capture is below neither the best fixed exposure in hindsight \
         nor auto-exposure in {won} of {} cells.",
        m.cells.len(),
        m.seeds,
        m.cells.len()
    ));
    for c in &m.cells {
        out.push(format!(
            "  {:>7} e-/s, {}: vs best fixed {}, vs auto-exposure {}",
            c.light,
            column(c),
            opt(&c.vs_hindsight),
            opt(&c.vs_ae)
        ));
    }
    out.push(format!("Report: {}", report.display()));
    out
}

#[cfg(test)]
mod tests {
    use super::super::heat::heat_labels;
    use super::*;
    use crate::experiment::benefit_map::CellPolicy;
    use crate::trigger::PolicySpec;

    #[test]
    fn heat_map_cells_carry_ratio_interval_and_winner() {
        let p = |s: &str, fps: f64| CellPolicy {
            policy: PolicySpec::parse(s).unwrap(),
            sharp_fps: fps,
            sharp_ci: Estimate {
                value: fps,
                lo: f64::NAN,
                hi: f64::NAN,
            },
            vs_fixed: None,
            frames: 10,
            sharp: 5,
            mean_exposure_s: 0.01,
            gain_capped: 0,
            false_alarms: 0,
            corner_rep: 0.5,
            vo_fps: 1.0,
            rep_fps: 1.0,
            trackable_fps: 1.0,
            mean_inliers: 40.0,
        };
        let mut c = Cell {
            light: 1000.0,
            gait: "moderate".into(),
            board: "blobs:0.5".into(),
            policies: vec![p("fixed:5", 1.0), p("deadline:5", 4.5)],
            best_mmbm: Some(1),
            hindsight: Some(0),
            ae: None,
            fixed: Some(0),
            gyro: None,
            vs_gyro: None,
            vs_hindsight: Some(Estimate {
                value: 1.25,
                lo: 1.05,
                hi: 1.5,
            }),
            vs_ae: None,
            vs_fixed: None,
            winner: 1,
            vo_winner: 1,
            vo_vs_baseline: None,
            blocks: 8,
        };
        assert_eq!(
            heat_labels(&c),
            [
                "vs hindsight 1.25x [1.05, 1.50]",
                "vs auto-exposure n/a",
                "timing vs gyro-exposure n/a n/a",
                "won by deadline:5 (4.50 /s)"
            ]
        );
        c.vs_hindsight = Some(Estimate {
            value: 0.5,
            lo: 0.4,
            hi: 0.6,
        });
        assert!(heat_labels(&c)[0].ends_with("0.50x [0.40, 0.60] lost"));
        // Timing against the best gyro-exposure policy: an interval above 1
        // pays, one below loses, one that reaches 1 ties.
        for ((lo, hi), want) in [
            ((1.1, 1.4), "pays"),
            ((0.5, 0.9), "loses"),
            ((0.9, 1.2), "ties"),
        ] {
            c.vs_gyro = Some(Estimate { value: 1.0, lo, hi });
            assert_eq!(timing_verdict(&c), want);
            assert!(heat_labels(&c)[2].ends_with(want));
        }
    }
}
