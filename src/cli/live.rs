//! `mmbm live`: trigger decisions in real time from an IMU stream (stdin,
//! UDP, or a recorded log replayed at its own pace).

use super::args::{CameraArgs, SceneArgs, TimingArgs};
use super::series::GyroArgs;
use clap::Args;
use mmbm::error::{Error, Result};
use mmbm::io::gyro::GyroSample;
use mmbm::io::lines::LineParser;
use mmbm::metric::Evaluator;
use mmbm::series::{sample_scene, SeriesOptions};
use mmbm::trigger::{self, Event, Live};
use mmbm::{Method, Scene};
use std::io::{BufRead, Write};
use std::path::PathBuf;
use std::sync::Mutex;
use std::time::{Duration, Instant};

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

Causal policies only (no oracle), thresholds in mm/s (no pNN). A malformed line is reported on
stderr with its line number and skipped (--strict: stop, exit code 2); a sample whose time does
not increase is reported and dropped.

Examples:
  mmbm simulate --gait moderate --duration 16 --out walk.csv
  cat walk.csv | mmbm live --policy threshold:0.4 --exposure 0.07
  mmbm live --replay walk.csv --speed 4 --policy adaptive --exposure 0.07 --stats
  mmbm live --udp 127.0.0.1:9870 --policy deadline:5 --exposure 0.02 --angle-unit deg"
)]
pub struct LiveArgs {
    /// Policy (repeat for several; each line's `policy` is the string given).
    #[arg(long, required = true)]
    pub policy: Vec<String>,
    /// Exposure t_e, s.
    #[arg(
        allow_negative_numbers = true,
        long,
        value_name = "S",
        default_value_t = mmbm::trigger::CameraTiming::DEFAULT_EXPOSURE_S
    )]
    pub exposure: f64,
    #[command(flatten)]
    pub timing: TimingArgs,
    /// CPU metric: riemann[:NUxNV], gauss[:N] or exact[:TOL].
    /// Limits: 1,048,576 grid points, 1024 Gauss nodes per side.
    #[arg(long, default_value = "riemann:8x6")]
    pub method: String,
    /// Include the samples' vx,vy,vz (needs depth, --depth or --plane).
    #[arg(long)]
    pub use_velocity: bool,
    /// Listen on this UDP address (e.g. 127.0.0.1:9870) instead of stdin.
    #[arg(long, value_name = "ADDR", conflicts_with = "replay")]
    pub udp: Option<String>,
    /// With --udp: stop after this many seconds without a datagram (default: never).
    #[arg(long, value_name = "S", requires = "udp")]
    pub idle_exit: Option<f64>,
    /// Feed a recorded log (any --gyro format) at its own pace instead of stdin.
    #[arg(long, value_name = "FILE")]
    pub replay: Option<PathBuf>,
    /// With --replay: play X times faster than real time (0: as fast as possible).
    #[arg(long, value_name = "X", default_value_t = 1.0, requires = "replay")]
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

/// Per-sample latency in constant memory: a log-spaced histogram (16
/// buckets per octave of nanoseconds, about 4 % wide) and the exact maximum.
#[derive(Debug, Clone)]
struct Latency {
    buckets: Vec<u64>,
    n: u64,
    max_ns: u64,
}

impl Latency {
    const PER_OCTAVE: f64 = 16.0;

    fn new() -> Self {
        Latency {
            buckets: vec![0; 64 * 16 + 1],
            n: 0,
            max_ns: 0,
        }
    }

    fn add(&mut self, d: Duration) {
        let ns = d.as_nanos().min(u64::MAX as u128) as u64;
        let b = ((ns.max(1) as f64).log2() * Self::PER_OCTAVE) as usize;
        if let Some(c) = self.buckets.get_mut(b.min(64 * 16)) {
            *c += 1;
        }
        self.n += 1;
        self.max_ns = self.max_ns.max(ns);
    }

    /// Upper edge (us) of the bucket holding the `q` quantile (at most the maximum).
    fn quantile_us(&self, q: f64) -> f64 {
        let need = ((q * self.n as f64).ceil() as u64).max(1);
        let mut cum = 0;
        for (b, &c) in self.buckets.iter().enumerate() {
            cum += c;
            if cum >= need {
                let edge = 2f64.powf((b + 1) as f64 / Self::PER_OCTAVE);
                return edge.min(self.max_ns as f64) / 1e3;
            }
        }
        self.max_ns as f64 / 1e3
    }

    fn report(&self) -> String {
        if self.n == 0 {
            return "latency: no samples".into();
        }
        format!(
            "latency (line read to decision written) over {} samples: p50 {:.1} us, p99 {:.1} us, max {:.1} us",
            self.n,
            self.quantile_us(0.5),
            self.quantile_us(0.99),
            self.max_ns as f64 / 1e3
        )
    }
}

/// The last stretch of a replay's wait spent spinning rather than asleep.
const SPIN: Duration = Duration::from_micros(300);

/// The statistics printed when the run is interrupted (Ctrl-C).
static STATS: Mutex<Option<Latency>> = Mutex::new(None);

/// Prints the live statistics, if a `live --stats` run is in progress (the
/// Ctrl-C handler calls this before exiting).
pub fn on_interrupt() {
    if let Ok(g) = STATS.lock() {
        if let Some(l) = g.as_ref() {
            eprintln!("{}", l.report());
        }
    }
}

/// The decision machinery: the metric per sample and one [`Live`] per policy.
struct Decider {
    opts: SeriesOptions,
    eval: Evaluator,
    runs: Vec<Live>,
    all: bool,
}

impl Decider {
    /// Decides on `s` and writes the lines it produces.
    fn take(&mut self, s: &GyroSample, out: &mut impl Write) -> Result<()> {
        let (tw, scene) = sample_scene(s, &self.opts)?;
        let m = self.eval.mean_speed(&scene.flow_poly(&tw));
        if !m.is_finite() {
            return Err(Error::invalid(
                format!("sample at t = {} s", s.t),
                format!("MMBM is {m}"),
            ));
        }
        let mut text = String::new();
        for live in self.runs.iter_mut() {
            let events = live.push(s.t, m)?;
            let triggered = events.iter().any(|e| matches!(e, Event::Trigger(..)));
            for e in events {
                let v = match e {
                    Event::Trigger(k, f) => serde_json::json!({
                        "t": f.trigger_t, "policy": f.policy, "trigger": true, "frame": k,
                        "mmbm_mm_s": f.mmbm_trigger_mm_s, "exposure_start": f.exposure_start,
                        "exposure_end": f.exposure_end, "gain": f.gain,
                    }),
                    Event::Exposed(k, f) => serde_json::json!({
                        "t": s.t, "policy": f.policy, "exposed": true, "frame": k,
                        "trigger_t": f.trigger_t, "mmbm_exposure_mm_s": f.mmbm_exposure_mm_s,
                        "kept": f.kept,
                    }),
                };
                text.push_str(&v.to_string());
                text.push('\n');
            }
            if self.all && !triggered {
                let v = serde_json::json!({
                    "t": s.t, "policy": live.spec(), "trigger": false, "mmbm_mm_s": m,
                });
                text.push_str(&v.to_string());
                text.push('\n');
            }
        }
        if !text.is_empty() {
            out.write_all(text.as_bytes())
                .and_then(|_| out.flush())
                .map_err(|e| Error::io("<stdout>", e))?;
        }
        Ok(())
    }
}

pub fn run(a: LiveArgs) -> Result<()> {
    let method: Method = a.method.parse()?;
    let camera = a.camera.camera()?;
    // A rolling shutter keeps the camera busy for its line readout as well.
    let timing = a
        .timing
        .timing(a.exposure, camera.pitch_x_mm)
        .with_rolling_readout(camera.shutter.readout_s);
    timing.validate()?;
    let opts = SeriesOptions {
        scene: Scene {
            camera,
            plane: a.scene.plane()?,
        },
        method,
        use_velocity: a.use_velocity,
    };
    let mut runs = Vec::new();
    for p in &a.policy {
        runs.push(Live::new(trigger::parse_policy(p)?, timing)?);
    }
    let mut d = Decider {
        eval: Evaluator::new(&camera, method)?,
        opts,
        runs,
        all: a.all,
    };
    let gyro_opts = a.gyro_opts.options()?;
    if a.stats {
        if let Ok(mut g) = STATS.lock() {
            *g = Some(Latency::new());
        }
    }
    let stdout = std::io::stdout();
    let mut out = stdout.lock();
    let mut last_t = f64::NEG_INFINITY;
    let mut failed: Option<Error> = None;
    // One sample: order check, decision, latency.
    let mut handle = |s: GyroSample, read_at: Instant, where_: &str, out: &mut dyn Write| {
        if s.t <= last_t {
            eprintln!(
                "{where_}: time {} s does not follow {last_t} s; sample dropped",
                s.t
            );
            return Ok(());
        }
        last_t = s.t;
        let mut w = WriteRef(out);
        d.take(&s, &mut w)?;
        if a.stats {
            if let Ok(mut g) = STATS.lock() {
                if let Some(l) = g.as_mut() {
                    l.add(read_at.elapsed());
                }
            }
        }
        Ok::<(), Error>(())
    };
    if let Some(path) = &a.replay {
        if !(a.speed >= 0.0 && a.speed.is_finite()) {
            return Err(Error::invalid(
                "--speed",
                format!("must be >= 0, got {}", a.speed),
            ));
        }
        let samples = mmbm::io::gyro::read_log(path, gyro_opts)?.into_samples();
        let t0 = samples.first().map_or(0.0, |s| s.t);
        let start = Instant::now();
        for (k, s) in samples.into_iter().enumerate() {
            if a.speed > 0.0 {
                let due = Duration::from_secs_f64(((s.t - t0) / a.speed).max(0.0));
                // Sleep to just before the sample is due, then spin: a
                // thread woken from a long sleep runs its first microseconds
                // on a cold core, which a real driver's read loop would not.
                if let Some(wait) = due.checked_sub(start.elapsed() + SPIN) {
                    std::thread::sleep(wait);
                }
                while start.elapsed() < due {
                    std::hint::spin_loop();
                }
            }
            let at = Instant::now();
            handle(
                s,
                at,
                &format!("{}: sample {}", path.display(), k + 1),
                &mut out,
            )?;
        }
    } else {
        let source = if a.udp.is_some() { "<udp>" } else { "<stdin>" };
        let mut parser = LineParser::new(gyro_opts, source);
        let mut line_no = 0u64;
        let mut on_line = |text: &str, out: &mut dyn Write| -> Result<bool> {
            line_no += 1;
            let at = Instant::now();
            match parser.parse(text, line_no) {
                Ok(Some(s)) => {
                    let src = format!("{source}:{line_no}");
                    handle(s, at, &src, out)?;
                    Ok(true)
                }
                Ok(None) => Ok(true),
                Err(e) if a.strict => {
                    failed = Some(e);
                    Ok(false)
                }
                Err(e) => {
                    eprintln!("{e}; line skipped");
                    Ok(true)
                }
            }
        };
        match &a.udp {
            None => {
                let stdin = std::io::stdin();
                let mut buf = String::new();
                let mut input = stdin.lock();
                loop {
                    buf.clear();
                    // Lines that are not UTF-8 are malformed lines too.
                    let mut raw = Vec::new();
                    let n = input
                        .read_until(b'\n', &mut raw)
                        .map_err(|e| Error::io("<stdin>", e))?;
                    if n == 0 {
                        break;
                    }
                    buf.push_str(&String::from_utf8_lossy(&raw));
                    if !on_line(&buf, &mut out)? {
                        break;
                    }
                }
            }
            Some(addr) => {
                let sock = std::net::UdpSocket::bind(addr)
                    .map_err(|e| Error::io(format!("udp {addr}"), e))?;
                if let Some(s) = a.idle_exit {
                    mmbm::error::positive("--idle-exit (s)", s)?;
                    sock.set_read_timeout(Some(Duration::from_secs_f64(s)))
                        .map_err(|e| Error::io(format!("udp {addr}"), e))?;
                }
                let mut buf = vec![0u8; 65536];
                'recv: loop {
                    let n = match sock.recv(&mut buf) {
                        Ok(n) => n,
                        Err(e)
                            if matches!(
                                e.kind(),
                                std::io::ErrorKind::WouldBlock | std::io::ErrorKind::TimedOut
                            ) =>
                        {
                            break;
                        }
                        Err(e) => return Err(Error::io(format!("udp {addr}"), e)),
                    };
                    let text = String::from_utf8_lossy(&buf[..n]).into_owned();
                    for l in text.lines() {
                        if !on_line(l, &mut out)? {
                            break 'recv;
                        }
                    }
                }
            }
        }
    }
    if a.stats {
        on_interrupt();
    }
    if let Some(e) = failed {
        eprintln!("error: {e} (--strict)");
        std::process::exit(2);
    }
    Ok(())
}

/// `&mut dyn Write` as a sized writer.
struct WriteRef<'a>(&'a mut dyn Write);

impl Write for WriteRef<'_> {
    fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
        self.0.write(b)
    }
    fn flush(&mut self) -> std::io::Result<()> {
        self.0.flush()
    }
}
