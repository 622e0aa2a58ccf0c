//! `mmbm trigger`: run trigger policies on a gyro log.

use super::args::{CameraArgs, SceneArgs, TimingArgs};
use super::series::GyroArgs;
use clap::Args;
use mmbm::error::{Error, Result};
use mmbm::trigger::{self, Frame, PolicySpec, Session, SessionConfig};
use mmbm::Method;
use std::io::Write;
use std::path::PathBuf;

/// Run trigger policies on a gyro log: CSV of frames, summary.
#[derive(Args, Debug)]
#[command(
    after_help = "Policies (X in mm/s, or pNN = NN-th percentile of the whole log's MMBM, an offline calibration that
looks at the future, so not causal: `mmbm live` refuses it; FPS at most 1000):
  fixed:FPS[@PHASE]  threshold:X  adaptive[:X[:FPS]]  oracle:X[:H]  forecast:X[:H]  phase:X[:H]
  gate:X[:FPS[@PHASE]]  gate0:X[:FPS[@PHASE]]  deadline:FPS[:X]
  fixed:FPS[@PHASE]@Tms  ae:FPS[@PHASE][:cap=Tms][:target=F][:damp=F][:scene=F]
  ae-blur:FPS[@PHASE]:B[:ae keys]  ae-imu:FPS[@PHASE][:w=W][:w0=W0][:ae keys]
  ae-grad:FPS[@PHASE][:white=F][:cap=Tms][:scene=F]  task:FPS:light=E[:read=E][:tmin=Tms]
  (gate keeps a fixed-rate frame when its exposure-averaged MMBM is <= X; gate0, the thesis's test, when
  the MMBM at the exposure start, i.e. of the decision sample, is; phase learns the gait's cycle from
  its touchdowns; fixed:FPS@Tms exposes every frame for T ms, gain raised by --exposure / T; ae is a
  motion-blind auto-exposure on the fixed schedule: exposure up to cap (default --exposure) first, then
  gain, toward a mean level target (default 0.18) with damping damp (0.5), the scene's mean radiance
  scene (0.25); ae-blur is that auto-exposure with each exposure capped where the gyro-predicted blur
  passes B px, the gain making up the light (camera makers' gyro AE, e.g. FotoNation US 11,812,146 B2);
  ae-imu splits the auto-exposure's exposure x gain c by K = sqrt((v c + w0) / w), T = c / K, v the
  gyro's image speed px/s (after Begin & Hunter, Sensors 22(3):835, 2022; w default 0.1 px, w0 0);
  ae-grad is a motion-blind gradient auto-exposure: each frame the product among x{1, 0.71, 1.41, 0.5, 2}
  with the most predicted gradient after gamma 2.2 of a scene whose brightest radiance is white (1.0);
  families: fixed, fixed-exposure, auto-exposure (ae, ae-grad), gyro-exposure (ae-blur, ae-imu,
  fixed:FPS+exp), mmbm (trigger timing from the gyro), oracle; task picks each slot's instant and exposure for the highest predicted chance of a sharp
  frame at the stated light E e-/s (at most 1e12; read noise read e-, default 2.5; shortest exposure
  tmin, default 0.2ms))
Exposure control: any policy followed by +exp:B[:TMIN] exposes each frame for
  clamp(B x pitch / MMBM, TMIN, --exposure) s (predicted blur within B px; TMIN default 0.001) and raises
  the gain by --exposure / that; the CSV's gain column says by how much.
With --light E (e-/s; see mmbm light) the summary adds each policy's white-pixel SNR and the task model's
  predicted sharp frames (the model of task:, fitted on the demo's board), so short exposures pay their noise.
Output: the CSV goes to --out FILE, else to stdout; the summary goes to stderr, or to stdout with
  --summary when --out names a file (the CSV is never dropped).

Examples:
  mmbm simulate --gait moderate --duration 16 --out walk.csv
  mmbm trigger --gyro walk.csv --policy fixed:5 --policy threshold:0.4 --exposure 0.07 --out frames.csv
  mmbm trigger --gyro walk.csv --policy oracle:0.4 --policy phase:0.4 --exposure 0.07 --out f.csv --summary
  mmbm trigger --gyro walk.csv --policy fixed:5+exp:2:0.02 --policy deadline:5+exp:3 --exposure 0.07 \\
      --out f.csv --summary
  mmbm trigger --gyro walk.csv --policy fixed:5@10ms --policy ae:5:cap=10ms --policy task:5:light=20000 \\
      --exposure 0.07 --out frames.csv --summary
  mmbm trigger --gyro walk.csv --policy ae-blur:5:1:cap=10ms --policy ae-imu:5:w=0.1 --policy ae-grad:5 \\
      --exposure 0.07 --out frames.csv --summary
  mmbm trigger --gyro ../shared/data/running_phone/gyro.csv --policy threshold:p20 --exposure 0.02 \\
      --out f.csv --summary"
)]
pub struct TriggerArgs {
    /// Gyro log: CSV t,wx,wy,wz[,vx,vy,vz][,depth]; also a ROS 2 .mcap or a
    /// Gyroflow .gcsv IMU log (t*tscale s, g*gscale rad/s, its orientation).
    #[arg(long, value_name = "FILE")]
    pub gyro: PathBuf,
    /// Policy (repeat for several; each row's `policy` column is the string given).
    #[arg(long, required = true)]
    pub policy: Vec<PolicySpec>,
    #[command(flatten)]
    pub timing: TimingArgs,
    /// Output CSV of frames (default or `-`: stdout).
    #[arg(long, value_name = "FILE")]
    pub out: Option<PathBuf>,
    /// Print the summary on stdout when the CSV goes to a file (--out FILE);
    /// the summary is otherwise on stderr, and the CSV is never dropped.
    #[arg(long)]
    pub summary: bool,
    /// MMBM method (CPU): riemann[:NUxNV], gauss[:N], exact[:TOL].
    /// Limits: 1,048,576 grid points, 1024 Gauss nodes per side.
    #[arg(long, default_value = "riemann:8x6")]
    pub method: Method,
    /// Include the log's vx,vy,vz (needs a depth column, --depth or --plane).
    #[arg(long)]
    pub use_velocity: bool,
    #[command(flatten)]
    pub scene: SceneArgs,
    #[command(flatten)]
    pub gyro_opts: GyroArgs,
    #[command(flatten)]
    pub camera: CameraArgs,
}

/// `pitch_mm`: the pixel pitch that turns the mean blur (mm) into px, `None`
/// for pixels that are not square (no single one: the blur is given in um).
fn summary_text(frames: &[Frame], spec: &str, duration: f64, pitch_mm: Option<f64>) -> String {
    let s = trigger::summary_over(frames, duration);
    let t = trigger::prediction_error(frames);
    // Statistics of no frames are undefined: "n/a", never "NaN".
    let n = |x: f64, d: usize| {
        if x.is_finite() {
            format!("{x:.d$}")
        } else {
            "n/a".to_string()
        }
    };
    format!(
        "{spec}: {} frames, {} kept, {} fps over {} s; exposure MMBM mean {} p95 {} max {} mm/s (trigger mean {})\n  \
         blur over the exposure mean {}, exposure mean {} ms\n  \
         Table 5.1 (exposure - trigger): min {} max {} mean {} abs mean {} std {} mm/s; \
         % min {} max {} mean {} abs mean {} std {}\n",
        s.frames,
        s.kept,
        n(s.effective_fps, 3),
        n(s.duration_s, 3),
        n(s.mean_mm_s, 4),
        n(s.p95_mm_s, 4),
        n(s.max_mm_s, 4),
        n(s.mean_trigger_mm_s, 4),
        match pitch_mm {
            Some(p) => n(s.mean_blur_mm / p, 2) + " px",
            None => n(s.mean_blur_mm * 1e3, 3) + " um (pixels not square: no single px/mm)",
        },
        n(s.mean_exposure_s * 1e3, 2),
        n(t.abs.min, 4),
        n(t.abs.max, 4),
        n(t.abs.mean, 4),
        n(t.abs.mean_abs, 4),
        n(t.abs.std, 4),
        n(t.pct.min, 2),
        n(t.pct.max, 2),
        n(t.pct.mean, 2),
        n(t.pct.mean_abs, 2),
        n(t.pct.std, 2)
    )
}

/// The summary's line at `--light`: each kept frame's white-pixel SNR and
/// the task model's predicted verdict (docs/trigger.md, `task:`): expected
/// sharp frames, their share and rate over `duration` s.
fn light_text(frames: &[Frame], light: f64, pitch_mm: f64, duration: f64) -> String {
    let p = trigger::TaskModel::at_light(light).predict(frames, pitch_mm);
    if p.kept == 0 {
        return format!("  at {light} e-/s: no kept frame\n");
    }
    format!(
        "  at {light} e-/s: white-pixel SNR mean {:.1} min {:.1}; predicted sharp (task model) {:.1} of {} kept \
         frames ({:.0} %), {:.2} sharp frames/s\n",
        p.mean_snr,
        p.min_snr,
        p.sharp,
        p.kept,
        100.0 * p.sharp / p.kept as f64,
        p.sharp / duration
    )
}

pub fn run(a: TriggerArgs) -> Result<()> {
    // The output's place, against every input, before any work.
    mmbm::io::guard::OutputGuard::new()
        .output("--out", a.out.as_deref())
        .input("--gyro", Some(&a.gyro))
        .input("--camera", a.camera.camera.as_deref())
        .check()?;
    let camera = a.camera.camera()?;
    let samples = mmbm::telemetry::read_gyro(&a.gyro, &a.gyro_opts.telemetry()?)?;
    let session = Session::new(
        SessionConfig {
            camera,
            plane: a.scene.plane()?,
            timing: a.timing.timing(),
            method: a.method,
            use_velocity: a.use_velocity,
            policies: a.policy.clone(),
        },
        samples.readout(),
    )?;
    super::args::report_log_readout(&session, &a.gyro);
    let run = session.run(&samples)?;
    let mut text = String::new();
    for (frames, spec) in run.frames.iter().zip(&a.policy) {
        text.push_str(&summary_text(
            frames,
            spec.as_str(),
            run.duration_s,
            mmbm::metric::pixel_map(session.camera())
                .is_none()
                .then_some(session.timing().pitch_mm),
        ));
        if let Some(light) = a.camera.light {
            text.push_str(&light_text(
                frames,
                light,
                session.timing().pitch_mm,
                run.duration_s,
            ));
        }
    }
    let all = run.frames;
    let write = |w: &mut dyn Write| -> Result<()> {
        trigger::write_frames(w, &[], true)?;
        for f in &all {
            trigger::write_frames(w, f, false)?;
        }
        Ok(())
    };
    // The CSV always goes somewhere: --out FILE, else stdout. The summary
    // takes stdout only with --summary and a CSV that does not (else stderr).
    let csv_on_stdout = match &a.out {
        Some(p) if p.as_os_str() != "-" => {
            mmbm::io::atomic::write_atomic(p, |w| write(w))?;
            false
        }
        _ => {
            let mut out = std::io::BufWriter::new(std::io::stdout().lock());
            write(&mut out)?;
            out.flush().map_err(|e| Error::io("<stdout>", e))?;
            true
        }
    };
    if a.summary && !csv_on_stdout {
        print!("{text}");
    } else {
        eprint!("{text}");
    }
    Ok(())
}
