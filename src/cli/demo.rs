//! `mmbm demo`: the experiment on built-in defaults (the README's first command).

use super::experiment::run_and_print;
use clap::Args;
use mmbm::error::Result;
use mmbm::experiment::ExperimentConfig;
use std::path::PathBuf;

/// The thesis experiment with built-in defaults: a simulated moderate walk
/// (18 s, 6 m -> 3 m from the blob board), all trigger policies, every
/// policy's frames rendered (up to 24 per policy) and judged, report written.
#[derive(Args, Debug)]
#[command(after_help = "Examples:
  mmbm demo
  mmbm demo --out /tmp/report --seed 7")]
pub struct DemoArgs {
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "mmbm-report")]
    pub out: PathBuf,
    /// Simulation seed.
    #[arg(long, default_value_t = 1)]
    pub seed: u64,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

pub fn run(a: DemoArgs) -> Result<()> {
    let cfg = ExperimentConfig {
        seed: a.seed,
        ..ExperimentConfig::demo()
    };
    run_and_print(&cfg, &a.out, !a.quiet)
}
