//! `mmbm experiment`: the thesis experiment from a configuration file.

use clap::Args;
use mmbm::error::Result;
use mmbm_lab::experiment::{self, ExperimentConfig};
use std::path::PathBuf;

/// The thesis experiment: walk -> triggers -> rendered frames -> report.
#[derive(Args, Debug)]
#[command(after_help = "Examples:
  mmbm experiment --config examples/experiment.toml --out report/
  mmbm experiment --print-config > my.toml     # the defaults, to edit
  mmbm experiment --config examples/map-my-robot.toml --out report/   # the map with my gyro log ([map] logs)

Writes DIR/frames.csv, DIR/report.md and PNG figures.")]
pub struct ExperimentArgs {
    /// TOML configuration (missing keys take the defaults; see --print-config).
    #[arg(long, value_name = "FILE", required_unless_present = "print_config")]
    pub config: Option<PathBuf>,
    /// Output directory.
    #[arg(long, value_name = "DIR", required_unless_present = "print_config")]
    pub out: Option<PathBuf>,
    /// Print the default configuration as TOML and exit.
    #[arg(long)]
    pub print_config: bool,
    /// No progress bar.
    #[arg(long)]
    pub quiet: bool,
}

pub fn run(a: ExperimentArgs) -> Result<()> {
    if a.print_config {
        print!("{}", ExperimentConfig::default().to_toml());
        return Ok(());
    }
    let (Some(config), Some(out)) = (a.config, a.out) else {
        return Err(mmbm::Error::invalid(
            "experiment",
            "--config FILE and --out DIR are required",
        ));
    };
    let cfg = ExperimentConfig::load(&config)?;
    // The config may lie in the output folder, but not under a name written there.
    mmbm::io::guard::OutputGuard::new()
        .output_dir("--out", Some(&out), experiment::writes)
        .input("--config", Some(&config))
        .check()?;
    run_and_print(&cfg, &out, !a.quiet)
}

/// Runs the experiment and prints where the report is and its headline table.
pub fn run_and_print(cfg: &ExperimentConfig, out: &std::path::Path, progress: bool) -> Result<()> {
    let o = experiment::run(cfg, out, progress)?;
    eprintln!(
        "{} frames rendered in {:.1} s; wrote {}/frames.csv and {}/report.md",
        o.rendered,
        o.seconds,
        out.display(),
        out.display()
    );
    println!("{}", o.answer(&out.join("report.md")));
    Ok(())
}
