//! The `mmbm` command: a thin layer over the `mmbm` library. Command-line
//! parsing (clap derive), progress bars (indicatif), signals (ctrlc) and
//! dispatch to the subcommands, one module each. See `mmbm --help`.

mod progress;

mod args;
mod assess;
mod blobs;
mod choose;
mod clip;
mod dataset;
mod demo;
mod eval;
mod experiment;
mod flow;
mod frames;
mod info;
mod light;
mod live;
mod render;
mod series;
mod simulate;
mod sync;
mod tables;
mod trigger;

use clap::{Parser, Subcommand};
use mmbm::trigger::StreamControl;
use std::time::Duration;

/// Camera motion blur: the MMBM metric, GPU flow fields, a ground-truth blur
/// renderer, gait simulation and trigger policies.
#[derive(Parser)]
#[command(name = "mmbm", version, about, long_about = None, after_help = EXAMPLES)]
struct Cli {
    #[command(subcommand)]
    command: Command,
}

const EXAMPLES: &str = "Examples:
  mmbm demo                                   # the thesis experiment on defaults, report in mmbm-report/
  mmbm eval --omega 1,1,1 --method exact --json
  mmbm eval --omega 0,0,0 --velocity 0.25,0.125,-1 --depth 1
  mmbm series --gyro ../shared/data/running_phone/gyro.csv --out mmbm.csv
  mmbm tables --plot fig46.png
  mmbm simulate --gait moderate --duration 30 --out walk.csv
  mmbm trigger --gyro walk.csv --policy threshold:0.4 --exposure 0.07 --summary
  mmbm render --omega 0.3,-0.2,0.5 --exposure 0.05 --target checker:0.02 --distance 1 --out blur.png
  mmbm info";

#[derive(Subcommand)]
enum Command {
    /// MMBM of one twist (rotation, optional translation with a depth or plane).
    Eval(eval::EvalArgs),
    /// MMBM for every sample of a gyro log (CSV out).
    Series(series::SeriesArgs),
    /// Exposure MMBM and blur of every frame of a real video (rolling shutter), --select the sharpest.
    Frames(Box<frames::FramesArgs>),
    /// Regenerate the thesis sensitivity tables 4.1-4.5 and the Fig. 4.6 grid error.
    Tables(tables::TablesArgs),
    /// List GPU adapters and show which one mmbm uses.
    Info,
    /// Per-pixel flow field at sensor resolution on the GPU (EXR, optional quiver PNG).
    Flow(flow::FlowArgs),
    /// The gyro-to-video clock offset (and readout) from the video's motion (ffmpeg).
    Sync(sync::SyncArgs),
    /// Render a ground-truth motion-blurred image of a planar target.
    Render(render::RenderArgs),
    /// Render a gyro log as a video (MP4 through ffmpeg), with each frame's true blur.
    Clip(clip::ClipArgs),
    /// Simulate a legged gait: a seeded gyro log.
    Simulate(simulate::SimulateArgs),
    /// Run a trigger policy on a gyro log.
    Trigger(trigger::TriggerArgs),
    /// Electrons per second in a white pixel from lux, f-number, pixel pitch and QE.
    Light(light::LightArgs),
    /// Image blur metrics (JNBM, CPBD, blur effect, Laplacian variance).
    Assess(assess::AssessArgs),
    /// Extract the 16 red blobs of the thesis target from an image.
    Blobs(blobs::BlobsArgs),
    /// The thesis experiment from a config: walk, triggers, rendered frames, report.
    Experiment(experiment::ExperimentArgs),
    /// The experiment with built-in defaults (the README's first command).
    Demo(demo::DemoArgs),
    /// Trigger decisions in real time from an IMU stream (stdin, UDP, replay).
    Live(live::LiveArgs),
    /// Blur datasets: sharp/blurred pairs, flow and blur maps, sharded on SLURM or Kubernetes.
    Dataset(dataset::DatasetArgs),
}

/// How long the Ctrl-C handler waits for a live stream to end by itself.
const INTERRUPT_GRACE: Duration = Duration::from_millis(500);

/// Removes temporary output files after an interrupt and says so; returns
/// the exit code (130).
fn interrupted() -> i32 {
    let n = mmbm::io::atomic::remove_pending();
    eprintln!("interrupted; removed {n} temporary file(s)");
    130
}

fn main() {
    std::process::exit(run());
}

/// Parses arguments, runs, prints errors; returns the exit code.
fn run() -> i32 {
    progress::install();
    mmbm::diagnostics::log_to_stderr();
    let cli = Cli::parse();
    // Ctrl-C (SIGINT): stop a live stream, which ends within its poll
    // (`live` then prints its statistics and exits 130 itself); otherwise, or
    // when the stream is blocked on a silent input, print the statistics so
    // far, remove temporary output files and exit 130 here.
    let control = StreamControl::default();
    let handler = control.clone();
    let _ = ctrlc::set_handler(move || {
        handler.stop();
        if handler.wait_ended(INTERRUPT_GRACE) {
            return;
        }
        if let Some(l) = handler.latency() {
            eprintln!("{}", l.report());
        }
        std::process::exit(interrupted());
    });
    let r = match cli.command {
        Command::Eval(a) => eval::run(a),
        Command::Series(a) => series::run(a),
        Command::Frames(a) => frames::run(*a),
        Command::Tables(a) => tables::run(a),
        Command::Info => info::run(),
        Command::Flow(a) => flow::run(a),
        Command::Render(a) => render::run(a),
        Command::Clip(a) => clip::run(a),
        Command::Sync(a) => sync::run(a),
        Command::Simulate(a) => simulate::run(a),
        Command::Trigger(a) => trigger::run(a),
        Command::Light(a) => light::run(a),
        Command::Assess(a) => assess::run(a),
        Command::Blobs(a) => blobs::run(a),
        Command::Experiment(a) => experiment::run(a),
        Command::Demo(a) => demo::run(a),
        Command::Live(a) => match live::run(a, &control) {
            Ok(code) => return code,
            Err(e) => Err(e),
        },
        Command::Dataset(a) => dataset::run(a),
    };
    match r {
        Ok(()) => 0,
        // An error after Ctrl-C or SIGTERM (its removal of a staging folder
        // under a write) is the interrupt: 130, as the handler exits.
        Err(_) if control.is_stopped() => interrupted(),
        Err(e) => {
            eprintln!("error: {e}");
            1
        }
    }
}
