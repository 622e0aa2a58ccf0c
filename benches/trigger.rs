//! Throughput of the trigger policies (`cargo bench --bench trigger`;
//! printed, never asserted).

mod common;

use mmbm::error::Result;
use mmbm::metric::{Method, Scene};
use mmbm::series::mmbm_series;
use mmbm::sim::{simulate, Gait, GaitConfig};
use mmbm::trigger::{parse_policy, run, CameraTiming};
use std::process::ExitCode;
use std::time::Instant;

/// Policies timed by [`bench`].
const POLICIES: [&str; 8] = [
    "fixed:5",
    "threshold:0.4",
    "adaptive",
    "oracle:0.4",
    "forecast:0.4",
    "gate:0.8",
    "deadline:5:0.4",
    "deadline:5",
];

fn main() -> ExitCode {
    common::main(bench)
}

/// Prints policy decisions per second (a 10-minute simulated moderate walk at
/// 600 Hz) and the end-to-end time of a 1-hour 600 Hz log (simulate, MMBM
/// series with `riemann:8x6`, then `threshold:0.4` and `forecast:0.4`).
fn bench() -> Result<()> {
    let cfg = GaitConfig::preset(Gait::Moderate);
    let timing = CameraTiming::default();
    let scene = Scene::thesis();
    let samples = simulate(&cfg, 600.0, 600.0, 1)?;
    let m = mmbm_series(&samples, &scene, Method::default())?;
    println!(
        "trigger policies, 10 min moderate walk at 600 Hz ({} samples), one thread:",
        samples.len()
    );
    for spec in POLICIES {
        let mut p = parse_policy(spec)?;
        let t0 = Instant::now();
        let frames = run(&samples, &m, p.as_mut(), &timing)?;
        let el = t0.elapsed().as_secs_f64();
        println!(
            "  {:<16} {:>8.2} M decisions/s  ({} frames, {:.3} s)",
            spec,
            samples.len() as f64 / el * 1e-6,
            frames.len(),
            el
        );
    }
    println!("1-hour 600 Hz log end to end:");
    let t0 = Instant::now();
    let samples = simulate(&cfg, 3600.0, 600.0, 2)?;
    let t_sim = t0.elapsed().as_secs_f64();
    let t1 = Instant::now();
    let m = mmbm_series(&samples, &scene, Method::default())?;
    let t_series = t1.elapsed().as_secs_f64();
    println!(
        "  simulate {} samples {:.2} s, MMBM series (riemann:8x6, {} threads) {:.2} s",
        samples.len(),
        t_sim,
        rayon::current_num_threads(),
        t_series
    );
    for spec in ["threshold:0.4", "forecast:0.4"] {
        let t2 = Instant::now();
        let frames = run(&samples, &m, parse_policy(spec)?.as_mut(), &timing)?;
        let t_run = t2.elapsed().as_secs_f64();
        println!(
            "  {spec}: trigger {:.2} s ({} frames); total {:.2} s = {:.0}x real time",
            t_run,
            frames.len(),
            t_sim + t_series + t_run,
            3600.0 / (t_sim + t_series + t_run)
        );
    }
    Ok(())
}
