//! The learned phase predictor's share of the oracle's gain (issue 27's
//! goal): on seeded 60 s moderate walks (600 Hz, the thesis camera and
//! timing: 70 ms exposure), the mean exposure MMBM of `threshold:0.4` (the
//! thesis rule), `oracle:0.4` and each predictor; the share is
//! `(thesis - predictor) / (thesis - oracle)` per walk, with the predictor's
//! kept frames against the oracle's.
//!
//! `cargo run --release -p mmbm-lab --example phase_share -- [SEEDS] [POLICIES...]`
//! (SEEDS e.g. `1-5` or `1,3,7`; default 1-5 and `phase:0.4`).

use mmbm::series::mmbm_series;
use mmbm::sim::{simulate, Gait, GaitConfig};
use mmbm::trigger::{parse_policy, run, summary_over, CameraTiming, Summary};
use mmbm::{Method, Scene};

fn seeds(s: &str) -> Vec<u64> {
    match s.split_once('-') {
        Some((a, b)) => (a.parse().unwrap_or(1)..=b.parse().unwrap_or(5)).collect(),
        None => s.split(',').filter_map(|x| x.parse().ok()).collect(),
    }
}

fn main() -> mmbm::Result<()> {
    let args: Vec<String> = std::env::args().skip(1).collect();
    let seeds = seeds(args.first().map_or("1-5", String::as_str));
    let mut predictors: Vec<String> = args.iter().skip(1).cloned().collect();
    if predictors.is_empty() {
        predictors.push("phase:0.4".into());
    }
    let duration_s = 60.0;
    let timing = CameraTiming::default();
    let mut shares = vec![Vec::new(); predictors.len()];
    for &seed in &seeds {
        let walk = simulate(&GaitConfig::preset(Gait::Moderate), duration_s, 600.0, seed)?;
        let series = mmbm_series(&walk, &Scene::thesis(), Method::default())?;
        let go = |spec: &str| -> mmbm::Result<Summary> {
            let mut p = parse_policy(spec)?;
            Ok(summary_over(
                &run(&walk, &series, p.as_mut(), &timing)?,
                duration_s,
            ))
        };
        let (thesis, oracle) = (go("threshold:0.4")?, go("oracle:0.4")?);
        let mut line = format!(
            "seed {seed}: thesis {:.4} mm/s, oracle {:.4} ({} frames)",
            thesis.mean_mm_s, oracle.mean_mm_s, oracle.kept
        );
        for (k, spec) in predictors.iter().enumerate() {
            let p = go(spec)?;
            let share = (thesis.mean_mm_s - p.mean_mm_s) / (thesis.mean_mm_s - oracle.mean_mm_s);
            shares[k].push(share);
            line += &format!(
                "; {spec} {:.4} ({} frames, {:.0} % of the oracle's): {:.0} %",
                p.mean_mm_s,
                p.kept,
                100.0 * p.kept as f64 / oracle.kept as f64,
                100.0 * share
            );
        }
        println!("{line}");
    }
    for (spec, s) in predictors.iter().zip(&shares) {
        let mean = s.iter().sum::<f64>() / s.len() as f64;
        let min = s.iter().copied().fold(f64::INFINITY, f64::min);
        println!(
            "{spec}: mean share {:.0} %, lowest walk {:.0} %",
            100.0 * mean,
            100.0 * min
        );
    }
    Ok(())
}
