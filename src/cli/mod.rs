//! Command-line parsing (clap derive) and dispatch to the subcommands.

mod args;
mod bench;
mod eval;
mod info;
mod series;
mod tables;

use clap::{Parser, Subcommand};

/// Camera motion blur: the MMBM metric, GPU flow fields, a ground-truth blur
/// renderer, gait simulation and trigger policies.
#[derive(Parser)]
#[command(name = "mmbm", version, about, long_about = None, after_help = EXAMPLES)]
pub struct Cli {
    #[command(subcommand)]
    command: Command,
}

const EXAMPLES: &str = "Examples:
  mmbm eval --omega 1,1,1 --method exact --json
  mmbm eval --omega 0,0,0 --velocity 0.25,0.125,-1 --depth 1
  mmbm series --gyro ../shared/data/running_phone/gyro.csv --out mmbm.csv
  mmbm tables --plot fig46.png
  mmbm info";

#[derive(Subcommand)]
enum Command {
    /// MMBM of one twist (rotation, optional translation with a depth or plane).
    Eval(eval::EvalArgs),
    /// MMBM for every sample of a gyro log (CSV out).
    Series(series::SeriesArgs),
    /// Regenerate the thesis sensitivity tables 4.1-4.5 and the Fig. 4.6 grid error.
    Tables(tables::TablesArgs),
    /// List GPU adapters and show which one mmbm uses.
    Info,
    /// Measure throughput of the metric methods (and GPU kernels).
    Bench(bench::BenchArgs),
}

/// Parses arguments, runs, prints errors; returns the exit code.
pub fn main() -> i32 {
    let cli = Cli::parse();
    let r = match cli.command {
        Command::Eval(a) => eval::run(a),
        Command::Series(a) => series::run(a),
        Command::Tables(a) => tables::run(a),
        Command::Info => info::run(),
        Command::Bench(a) => bench::run(a),
    };
    match r {
        Ok(()) => 0,
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}
