//! The three lines the report and the terminal open with (docs/spec.md
//! section 11): where gyro-driven capture pays (by how much, against what),
//! where it ties, where it loses, computed from the benefit map's cells.
//!
//! In each cell the best `mmbm` policy is held against the strongest of the
//! baselines the map compares it with: the best fixed exposure in hindsight,
//! the best auto-exposure and the best `gyro-exposure` policy (the smallest
//! ratio). It **pays** when every ratio's 95 % interval lies above 1, it
//! **loses** when one lies below 1, and it **ties** otherwise. A baseline
//! that gets no sharp frame where the policy gets some is a ratio of `+inf`
//! with the interval `[inf, inf]` (above 1); where neither gets one the
//! ratio is NaN and neither above nor below 1.

use super::super::benefit::{bound_text, Estimate};
use super::{BenefitMap, Cell};

/// A cell's verdict.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub enum Verdict {
    /// Every ratio's interval above 1.
    Pays,
    /// Some interval reaches 1, none lies below.
    Ties,
    /// Some interval below 1.
    Loses,
}

/// The verdict of cell `c` and its strongest baseline: `(name of the
/// comparison, ratio, baseline policy index)`; `None` when the cell has no
/// `mmbm` policy or no baseline.
pub fn cell_verdict(c: &Cell) -> Option<(Verdict, &'static str, Estimate, usize)> {
    let rs: Vec<(&'static str, Estimate, usize)> = [
        (
            "the best fixed exposure in hindsight",
            c.vs_hindsight,
            c.hindsight,
        ),
        ("auto-exposure", c.vs_ae, c.ae),
        ("gyro-aware exposure", c.vs_gyro, c.gyro),
    ]
    .into_iter()
    .filter_map(|(n, e, i)| Some((n, e?, i?)))
    .collect();
    c.best_mmbm?;
    let strongest = rs
        .iter()
        .copied()
        .min_by(|a, b| a.1.value.total_cmp(&b.1.value))?;
    let verdict = if rs.iter().any(|r| r.1.hi < 1.0) {
        Verdict::Loses
    } else if rs.iter().all(|r| r.1.lo > 1.0) {
        Verdict::Pays
    } else {
        Verdict::Ties
    };
    Some((verdict, strongest.0, strongest.1, strongest.2))
}

/// A ratio with its interval as the report writes it: `1.26x [1.14, 1.40]`
/// (an upper bound `inf` where some resamples leave the baseline without a
/// sharp frame); `unbounded` where the baseline gets no sharp frame at all
/// and the policy some (it pays against that baseline: its interval is
/// `[inf, inf]`); `n/a` where neither gets one.
pub fn ratio_text(e: &Estimate) -> String {
    if e.value == f64::INFINITY {
        "unbounded (the baseline gets none)".into()
    } else if !e.value.is_finite() {
        "n/a (neither gets any)".into()
    } else if e.lo.is_finite() {
        format!(
            "{:.2}x [{}, {}]",
            e.value,
            bound_text(e.lo),
            bound_text(e.hi)
        )
    } else {
        format!("{:.2}x", e.value)
    }
}

/// The three lines: pays, ties, loses (each naming its cells with the ratio
/// to the strongest baseline, its interval and that baseline).
pub fn three_lines(m: &BenefitMap) -> [String; 3] {
    let n = m.cells.len();
    let mut parts: [Vec<String>; 3] = Default::default();
    for c in &m.cells {
        let Some((v, name, e, bi)) = cell_verdict(c) else {
            continue;
        };
        let b = &c.policies[c.best_mmbm.unwrap_or(0)];
        let k = match v {
            Verdict::Pays => 0,
            Verdict::Ties => 1,
            Verdict::Loses => 2,
        };
        parts[k].push(format!(
            "{} e-/s, {}: `{}` {} over {name} (`{}`)",
            c.light,
            column(c),
            b.policy,
            ratio_text(&e),
            c.policies[bi].policy
        ));
    }
    let line = |what: &str, p: &Vec<String>| {
        if p.is_empty() {
            format!("{what} in no cell of {n}.")
        } else {
            format!("{what} in {} of {n} cells: {}.", p.len(), p.join("; "))
        }
    };
    [
        line(
            "Gyro-driven capture (the best `mmbm` policy, sharp frames/s) pays against the strongest baseline",
            &parts[0],
        ),
        line("It ties", &parts[1]),
        line("It loses", &parts[2]),
    ]
}

/// The cell's column name: gait and board.
pub fn column(c: &Cell) -> String {
    format!("{}, {}", c.gait, board_name(&c.board))
}

fn board_name(b: &str) -> &str {
    match b {
        "blobs:0.5" | "blobs-half" => "half board",
        "blobs" => "full board",
        other => other,
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::experiment::benefit_map::CellPolicy;
    use crate::trigger::PolicySpec;

    fn cell(h: (f64, f64), g: (f64, f64)) -> Cell {
        let p = |s: &str| CellPolicy {
            policy: PolicySpec::parse(s).unwrap(),
            sharp_fps: 1.0,
            sharp_ci: Estimate {
                value: 1.0,
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
        let e = |(lo, hi): (f64, f64)| Estimate {
            value: (lo + hi) / 2.0,
            lo,
            hi,
        };
        Cell {
            light: 1000.0,
            gait: "moderate".into(),
            board: "blobs:0.5".into(),
            policies: vec![p("fixed:5"), p("deadline:5"), p("ae-blur:5:1")],
            best_mmbm: Some(1),
            hindsight: Some(0),
            ae: None,
            fixed: Some(0),
            gyro: Some(2),
            vs_hindsight: Some(e(h)),
            vs_ae: None,
            vs_fixed: None,
            vs_gyro: Some(e(g)),
            winner: 1,
            vo_winner: 1,
            vo_vs_baseline: None,
            blocks: 8,
        }
    }

    #[test]
    fn pays_ties_loses_against_the_strongest() {
        let (v, name, e, bi) = cell_verdict(&cell((1.5, 2.5), (1.1, 1.3))).unwrap();
        assert_eq!((v, name, bi), (Verdict::Pays, "gyro-aware exposure", 2));
        assert!((e.value - 1.2).abs() < 1e-12);
        assert_eq!(
            cell_verdict(&cell((1.5, 2.5), (0.9, 1.3))).unwrap().0,
            Verdict::Ties
        );
        let (v, name, ..) = cell_verdict(&cell((0.5, 0.9), (1.1, 1.3))).unwrap();
        assert_eq!(
            (v, name),
            (Verdict::Loses, "the best fixed exposure in hindsight")
        );
        let m = BenefitMap {
            cells: vec![cell((1.5, 2.5), (1.1, 1.3)), cell((0.5, 0.9), (1.1, 1.3))],
            lights: vec![1000.0],
            gaits: vec!["moderate".into()],
            boards: vec!["blobs:0.5".into()],
            seeds: vec![1],
            sensor: crate::camera::Noise::at_light(1000.0),
            t_ref_s: 0.07,
            max_gain_x: 256.0,
            grid_ms: vec![70.0],
            fps: 5.0,
            renders: 0,
            seconds: 0.0,
        };
        let [pays, ties, loses] = three_lines(&m);
        assert!(!pays.contains("NaN") && !pays.contains("inf"), "{pays}");
        assert!(pays.contains("in 1 of 2 cells: 1000 e-/s, moderate, half board: `deadline:5` 1.20x [1.10, 1.30] over gyro-aware exposure (`ae-blur:5:1`)"), "{pays}");
        assert_eq!(ties, "It ties in no cell of 2.");
        assert!(
            loses.starts_with("It loses in 1 of 2 cells: 1000 e-/s"),
            "{loses}"
        );
    }

    #[test]
    fn a_baseline_without_sharp_frames_is_beaten_not_tied() {
        let inf = f64::INFINITY;
        let mut c = cell((1.5, 2.5), (1.1, 1.3));
        c.ae = Some(2);
        c.vs_ae = Some(Estimate {
            value: inf,
            lo: inf,
            hi: inf,
        });
        let (v, name, e, _) = cell_verdict(&c).unwrap();
        assert_eq!((v, name), (Verdict::Pays, "gyro-aware exposure"));
        assert!((e.value - 1.2).abs() < 1e-12);
        // Neither gets a sharp frame: no comparison, so no longer a pay.
        c.vs_ae = Some(Estimate {
            value: f64::NAN,
            lo: f64::NAN,
            hi: f64::NAN,
        });
        assert_eq!(cell_verdict(&c).unwrap().0, Verdict::Ties);
        // Only the infinite ratio: it is the strongest, and written as such.
        c.vs_hindsight = None;
        c.vs_gyro = None;
        c.vs_ae = Some(Estimate {
            value: inf,
            lo: inf,
            hi: inf,
        });
        let (v, _, e, _) = cell_verdict(&c).unwrap();
        assert_eq!(v, Verdict::Pays);
        assert_eq!(ratio_text(&e), "unbounded (the baseline gets none)");
    }
}
