//! `mmbm live`: trigger decisions in real time from an IMU stream (stdin,
//! UDP, or a recorded log replayed at its own pace).

use super::args::{CameraArgs, SceneArgs, TimingArgs};
use super::series::GyroArgs;
use clap::Args;
use mmbm::error::Result;
use mmbm::io::gyro::GyroReader;
use mmbm::trigger::{PolicySpec, Session, SessionConfig, StreamControl, StreamEnd, StreamOptions};
use mmbm::Method;
use std::path::PathBuf;

/// Decide camera triggers live from an IMU stream: one JSON line per trigger.
#[derive(Args, Debug)]
#[command(
    after_help = "Input: the gyro CSV (header t,wx,wy,wz[,vx,vy,vz][,depth], then one sample per
line) or JSON lines {\"t\":..,\"wx\":..,\"wy\":..,\"wz\":..}, on stdin (default), one or more
lines per UDP datagram (--udp), or a recorded log fed at real time (--replay).

Output (stdout, one JSON object per line, flushed at once):
  {\"t\":..,\"policy\":..,\"trigger\":true,\"frame\":K,\"mmbm_mm_s\":..,\"exposure_start\":..,\"exposure_end\":..,\"gain\":..}
  {\"t\":..,\"policy\":..,\"exposed\":true,\"frame\":K,\"trigger_t\":..,\"mmbm_exposure_mm_s\":..,\"kept\":..}
    (once a sample at or after the exposure end has arrived)
  {\"t\":..,\"policy\":..,\"trigger\":false,\"mmbm_mm_s\":..}   (every other sample, with --all)

Causal policies only (no oracle), thresholds in mm/s (no pNN). A malformed line, or a sample
whose MMBM is not finite (rates near the float range) or whose time the time base cannot
resolve (t = 1e308), is reported on stderr with its line number and why, and skipped: the
stream goes on (--strict: stop, exit code 2); a sample whose time does not increase is
reported and dropped. A replayed log is read one sample at a time as it is played.

Examples:
  mmbm simulate --gait moderate --duration 16 --out walk.csv
  cat walk.csv | mmbm live --policy threshold:0.4 --exposure 0.07
  mmbm live --replay walk.csv --speed 4 --policy adaptive --exposure 0.07 --stats
  mmbm live --udp 127.0.0.1:9870 --policy deadline:5 --exposure 0.02 --angle-unit deg"
)]
pub struct LiveArgs {
    /// Policy (repeat for several; each line's `policy` is the string given).
    #[arg(long, required = true)]
    pub policy: Vec<PolicySpec>,
    #[command(flatten)]
    pub timing: TimingArgs,
    /// CPU metric: riemann[:NUxNV], gauss[:N] or exact[:TOL].
    /// Limits: 1,048,576 grid points, 1024 Gauss nodes per side.
    #[arg(long, default_value = "riemann:8x6")]
    pub method: Method,
    /// Include the samples' vx,vy,vz (needs depth, --depth or --plane).
    #[arg(long)]
    pub use_velocity: bool,
    /// Listen on this UDP address (e.g. 127.0.0.1:9870) instead of stdin.
    #[arg(long, value_name = "ADDR", conflicts_with = "replay")]
    pub udp: Option<String>,
    /// With --udp: stop after this many seconds without a datagram (default: never).
    #[arg(long, value_name = "S", requires = "udp", value_parser = parse_idle)]
    pub idle_exit: Option<f64>,
    /// Feed a recorded log (any --gyro format) at its own pace instead of stdin.
    #[arg(long, value_name = "FILE")]
    pub replay: Option<PathBuf>,
    /// With --replay: play X times faster than real time (0: as fast as possible;
    /// else 0.001 to 1e6, a slower replay would wait for ever).
    #[arg(long, value_name = "X", default_value_t = 1.0, requires = "replay", value_parser = parse_speed)]
    pub speed: f64,
    /// Write a line for every sample, not only triggers.
    #[arg(long)]
    pub all: bool,
    /// Stop at the first malformed line (exit code 2) instead of skipping it.
    #[arg(long)]
    pub strict: bool,
    /// Print latency statistics (read to decision written) on stderr at the end.
    #[arg(long)]
    pub stats: bool,
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub gyro_opts: GyroArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
}

/// `--speed`: 0, or from `MIN_REPLAY_SPEED` to `MAX_REPLAY_SPEED` (`mmbm::limits`).
fn parse_speed(s: &str) -> std::result::Result<f64, String> {
    let x: f64 = s.parse().map_err(|_| format!("'{s}' is not a number"))?;
    mmbm::trigger::check_speed(x).map_err(|e| e.to_string())
}

/// `--idle-exit`: a finite number of seconds > 0.
fn parse_idle(s: &str) -> std::result::Result<f64, String> {
    let x: f64 = s.parse().map_err(|_| format!("'{s}' is not a number"))?;
    mmbm::check::positive("--idle-exit (s)", x).map_err(|e| e.to_string())
}

/// Runs `mmbm live`, stopped through `control` (the Ctrl-C handler's);
/// returns the exit code: 0, 2 for a `--strict` stop, 130 when interrupted.
pub fn run(a: LiveArgs, control: &StreamControl) -> Result<i32> {
    let gyro = a.gyro_opts.options()?;
    // A replayed log is opened first: its own readout (a .gcsv header's)
    // applies when the camera gives none, as in `trigger` and `frames`.
    let mut reader = match &a.replay {
        Some(path) => Some((path, GyroReader::open(path, gyro.clone())?)),
        None => None,
    };
    let session = Session::new(
        SessionConfig {
            camera: a.camera.camera()?,
            plane: a.scene.plane()?,
            timing: a.timing.timing(),
            method: a.method,
            use_velocity: a.use_velocity,
            policies: a.policy.clone(),
        },
        reader.as_ref().and_then(|(_, r)| r.readout()),
    )?;
    if let Some((path, _)) = &reader {
        super::args::report_log_readout(&session, path);
    }
    let opts = StreamOptions {
        all: a.all,
        strict: a.strict,
        stats: a.stats,
    };
    let mut stream = session.stream(opts, control.clone())?;
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let outcome = if let Some((path, reader)) = reader.as_mut() {
        let name = path.display().to_string();
        let r = stream.replay(reader.by_ref(), &name, a.speed, &mut out);
        reader.print_warnings();
        r?
    } else if let Some(addr) = &a.udp {
        stream.udp(addr, a.idle_exit, gyro, &mut out)?
    } else {
        stream.lines(&mut std::io::stdin().lock(), gyro, "<stdin>", &mut out)?
    };
    if let Some(l) = &outcome.latency {
        eprintln!("{}", l.report());
    }
    Ok(match outcome.end {
        _ if control.is_stopped() => super::interrupted(),
        StreamEnd::Strict(e) => {
            eprintln!("error: {e} (--strict)");
            2
        }
        StreamEnd::Eof | StreamEnd::Idle | StreamEnd::Stopped => 0,
    })
}
