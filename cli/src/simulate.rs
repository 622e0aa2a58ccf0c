//! `mmbm simulate`: a seeded gyro log of a simulated hexapod walk.

use clap::Args;
use mmbm::error::Result;
use mmbm::sim::{self, Gait, GaitConfig};
use std::path::PathBuf;

/// Simulate a legged gait: gyro CSV `t,wx,wy,wz,vx,vy,vz` (camera frame).
#[derive(Args, Debug)]
#[command(after_help = "Examples:
  mmbm simulate --gait moderate --duration 16 --out walk.csv
  mmbm simulate --gait fast --duration 60 --rate 1000 --seed 7 --out fast.csv
  mmbm simulate --gait slow --config examples/gait.toml --duration 35 --out slow.csv
  mmbm simulate --gait moderate --print-config")]
pub struct SimulateArgs {
    /// slow (0.085 m/s), moderate (0.17 m/s) or fast (0.53 m/s).
    #[arg(long, default_value = "moderate")]
    pub gait: Gait,
    /// Duration, s (at most 1e8 samples in all).
    #[arg(allow_negative_numbers = true, long, default_value_t = 16.0)]
    pub duration: f64,
    /// Sample rate, Hz (a config's step_hz: at most 100 steps/s).
    #[arg(allow_negative_numbers = true, long, default_value_t = 600.0)]
    pub rate: f64,
    /// Random seed (same seed, same log).
    #[arg(long, default_value_t = 0)]
    pub seed: u64,
    /// TOML file overriding the preset's parameters (see examples/gait.toml).
    #[arg(long, value_name = "FILE")]
    pub config: Option<PathBuf>,
    /// Output CSV.
    #[arg(long, value_name = "FILE", required_unless_present = "print_config")]
    pub out: Option<PathBuf>,
    /// Print the effective gait parameters as TOML and exit.
    #[arg(long)]
    pub print_config: bool,
}

pub fn run(a: SimulateArgs) -> Result<()> {
    // The output's place, against the config, before any work.
    mmbm::io::guard::OutputGuard::new()
        .output("--out", a.out.as_deref())
        .input("--config", a.config.as_deref())
        .check()?;
    let gait = a.gait;
    let cfg = match &a.config {
        Some(p) => GaitConfig::load(p, gait)?,
        None => GaitConfig::preset(gait),
    };
    cfg.validate()?;
    if a.print_config {
        print!("{}", cfg.to_toml()?);
        return Ok(());
    }
    // Streamed: constant memory up to the cap (1e8 samples).
    let samples = sim::samples(&cfg, a.duration, a.rate, a.seed)?;
    if let Some(out) = &a.out {
        let n = sim::write_samples(out, samples)?;
        eprintln!(
            "{n} samples ({} s at {} Hz, gait {gait}, seed {}) -> {}",
            a.duration,
            a.rate,
            a.seed,
            out.display()
        );
    }
    Ok(())
}
