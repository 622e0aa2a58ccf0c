//! `mmbm demo`: the experiment on built-in defaults (the README's first command).

use super::experiment::run_and_print;
use clap::Args;
use mmbm::error::Result;
use mmbm_lab::experiment::ExperimentConfig;
use std::path::PathBuf;

/// The thesis experiment with built-in defaults: a simulated moderate walk
/// (16 s, 6 m -> 3.3 m from the half-size blob board before a poster), all trigger policies, every kept
/// frame rendered at the `default` preset and judged, report written.
#[derive(Args, Debug)]
#[command(
    after_help = "A simulated 16 s moderate walk (the half-size board of thesis Table 6.2), every policy (the thesis's, the learned phase
predictor, exposure control), every kept frame rendered with the thesis camera and sensor noise
at 20,000 e-/s, the board in front of a textured poster (clutter and corners). The report leads with the
benefit map (light x gait x board against the best fixed exposure, auto-exposure and gyro-aware exposure; sharp
frames/s by the blob verdict and VO frames/s), then the headline: sharp frames per second per policy against fixed:5,
read from the map's cell at 20,000 e-/s (the same frames, seeds, window and verdict), with 95 % bootstrap intervals
over 2-s blocks of the walks; then the experiment's own frames (its seed, judged whole: a different sample). --full runs the whole map: the slow
(35 s), moderate (16 s) and fast (5 s) walks, both boards, six lights from 500 to 100,000 e-/s, seeds 1-5, at the
fast render preset (the report measures it against default); the experiment's own frames stay the demo's.

Time on the 2-core VM (docs/performance.md): about 2 min (measured 2026-12-04); --full about 28 min (2026-12-04).

Examples:
  mmbm demo
  mmbm demo --out /tmp/report --seed 7
  mmbm demo --full --out report-full-map"
)]
pub struct DemoArgs {
    /// Output directory.
    #[arg(long, value_name = "DIR", default_value = "mmbm-report")]
    pub out: PathBuf,
    /// Simulation seed.
    #[arg(long, default_value_t = 1, conflicts_with = "full")]
    pub seed: u64,
    /// The whole benefit map: three gaits, both boards, six lights, seeds 1 to 5 (docs/experiment.md).
    #[arg(long)]
    pub full: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

pub fn run(a: DemoArgs) -> Result<()> {
    let cfg = if a.full {
        ExperimentConfig::demo_full()
    } else {
        ExperimentConfig {
            seed: a.seed,
            ..ExperimentConfig::demo()
        }
    };
    run_and_print(&cfg, &a.out, !a.quiet)
}
