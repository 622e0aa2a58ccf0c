//! The run assembly of `mmbm trigger`, `mmbm live` and Python's `trigger`:
//! a camera (with a log's own readout applied), a scene, the camera timing
//! (with a rolling shutter's line readout added), a metric method and the
//! policies, put together and checked in one place.
//!
//! [`Policies`] is the policies with the timing they run under, over an
//! MMBM series given as it is (Python's `trigger`); [`Session`] adds the
//! camera, the scene and the method, evaluates a log's series and runs
//! every policy over it ([`Session::run`]) or decides live on a stream
//! ([`Session::stream`]).

use super::live::Live;
use super::run::run_px;
use super::spec::PolicySpec;
use super::stream::{Stream, StreamControl, StreamOptions};
use super::timing::{CameraTiming, Frame};
use crate::camera::Camera;
use crate::error::{Error, Result};
use crate::metric::{Method, Scene};
use crate::model::log::{ImuLog, LogReadout, Timed};
use crate::model::motion::Plane;
use crate::series::SeriesOptions;

/// Policies with the camera timing they run under, validated.
#[derive(Debug, Clone, PartialEq)]
pub struct Policies {
    specs: Vec<PolicySpec>,
    timing: CameraTiming,
}

impl Policies {
    /// `specs` under `timing` (checked: [`CameraTiming::validate`]).
    pub fn new(specs: Vec<PolicySpec>, timing: CameraTiming) -> Result<Self> {
        timing.validate()?;
        Ok(Policies { specs, timing })
    }

    /// The policies, in the order given.
    pub fn specs(&self) -> &[PolicySpec] {
        &self.specs
    }

    /// The camera timing, s (and the pixel pitch, mm).
    pub fn timing(&self) -> &CameraTiming {
        &self.timing
    }

    /// Runs every policy over a log ([`super::run()`]): `mmbm_mm_s[i]`
    /// is the MMBM at the time of `samples[i]` (samples, or bare times in
    /// s). One list of frames per policy, in the order of [`Self::specs`].
    pub fn run<S: Timed>(&self, samples: &[S], mmbm_mm_s: &[f64]) -> Result<Vec<Vec<Frame>>> {
        self.run_px(samples, mmbm_mm_s, None)
    }

    /// [`Policies::run`] with the samples' MMBM in px/s too
    /// ([`super::run_px`]: pixel budgets on pixels that are not square).
    pub fn run_px<S: Timed>(
        &self,
        samples: &[S],
        mmbm_mm_s: &[f64],
        px_s: Option<&[f64]>,
    ) -> Result<Vec<Vec<Frame>>> {
        self.specs
            .iter()
            .map(|p| run_px(samples, mmbm_mm_s, px_s, p.build()?.as_mut(), &self.timing))
            .collect()
    }

    /// One live runner per policy ([`Live::new`]: errors for a policy that
    /// needs the future or the whole log).
    pub fn live(&self) -> Result<Vec<Live>> {
        self.specs
            .iter()
            .map(|p| Live::new(p.build()?, self.timing))
            .collect()
    }
}

/// What a [`Session`] is made of. `timing`'s pixel pitch is replaced by the
/// camera's and the camera's rolling readout is added to its readout
/// ([`CameraTiming::for_camera`]).
#[derive(Debug, Clone)]
pub struct SessionConfig {
    /// The camera (before a log's readout is applied).
    pub camera: Camera,
    /// The scene plane, if any (needed with `use_velocity` and no depth column).
    pub plane: Option<Plane>,
    /// Exposure, delay, readout after the exposure and minimum interval, s.
    pub timing: CameraTiming,
    /// The CPU metric method.
    pub method: Method,
    /// Include the log's linear velocity.
    pub use_velocity: bool,
    /// The policies, in output order.
    pub policies: Vec<PolicySpec>,
}

/// A trigger run, assembled and checked: camera, scene, method, timing and
/// policies.
#[derive(Debug, Clone)]
pub struct Session {
    series: SeriesOptions,
    policies: Policies,
    readout_from_log: bool,
}

/// A [`Session`] over one log: its MMBM series and every policy's frames.
#[derive(Debug, Clone, PartialEq)]
pub struct SessionRun {
    /// The MMBM at every sample, mm/s.
    pub mmbm_mm_s: Vec<f64>,
    /// The log's span, last sample's time minus the first's, s.
    pub duration_s: f64,
    /// The frames of every policy, in the session's order.
    pub frames: Vec<Vec<Frame>>,
}

impl Session {
    /// Assembles a session: `log_readout` (a log's own rolling-shutter
    /// readout, e.g. a Gyroflow `.gcsv` header's) applies when the camera
    /// has none ([`LogReadout::apply`]); then the timing takes the camera's
    /// pitch and rolling readout and is checked.
    pub fn new(cfg: SessionConfig, log_readout: Option<LogReadout>) -> Result<Self> {
        let (camera, readout_from_log) = LogReadout::apply(log_readout, cfg.camera)?;
        let policies = Policies::new(cfg.policies, cfg.timing.for_camera(&camera))?;
        Ok(Session {
            series: SeriesOptions {
                scene: Scene {
                    camera,
                    plane: cfg.plane,
                },
                method: cfg.method,
                use_velocity: cfg.use_velocity,
            },
            policies,
            readout_from_log,
        })
    }

    /// The camera (with the log's readout when it was applied).
    pub fn camera(&self) -> &Camera {
        &self.series.scene.camera
    }

    /// Whether the log's readout was applied to the camera.
    pub fn readout_from_log(&self) -> bool {
        self.readout_from_log
    }

    /// The series options: scene, method, velocity.
    pub fn series(&self) -> &SeriesOptions {
        &self.series
    }

    /// The camera timing the policies run under.
    pub fn timing(&self) -> &CameraTiming {
        self.policies.timing()
    }

    /// The policies with their timing.
    pub fn policies(&self) -> &Policies {
        &self.policies
    }

    /// The MMBM series of `log`, mm/s per sample.
    pub fn evaluate(&self, log: &ImuLog) -> Result<Vec<f64>> {
        crate::series::mmbm_series_with(log, &self.series)
    }

    /// Evaluates the series of `log` and runs every policy over it.
    pub fn run(&self, log: &ImuLog) -> Result<SessionRun> {
        let (first, last) = match (log.first(), log.last()) {
            (Some(a), Some(b)) => (a.t, b.t),
            _ => return Err(Error::invalid("gyro log", "no samples")),
        };
        let mmbm_mm_s = self.evaluate(log)?;
        // Pixels not square: each sample's px/s for the pixel budgets.
        let px_s = match crate::metric::pixel_map(self.camera()) {
            None => None,
            Some(_) => {
                let ev = crate::metric::Evaluator::new(self.camera(), self.series.method)?;
                let px = log.samples().iter().zip(&mmbm_mm_s).map(|(s, &m)| {
                    crate::series::sample_px(s, &self.series, &ev, m).map(|p| p.unwrap_or(0.0))
                });
                Some(px.collect::<Result<Vec<f64>>>()?)
            }
        };
        let frames = self.policies.run_px(log, &mmbm_mm_s, px_s.as_deref())?;
        Ok(SessionRun {
            mmbm_mm_s,
            duration_s: last - first,
            frames,
        })
    }

    /// A live stream deciding every policy ([`Policies::live`]) on the MMBM
    /// of each sample, stopped through `control`.
    pub fn stream(&self, opts: StreamOptions, control: StreamControl) -> Result<Stream> {
        Stream::new(self.policies.live()?, self.series, opts, control)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::sim::{simulate, Gait, GaitConfig};
    use crate::trigger::Exposure;

    fn walk() -> ImuLog {
        let g = GaitConfig::preset(Gait::Moderate);
        ImuLog::new(simulate(&g, 4.0, 200.0, 3).unwrap()).unwrap()
    }

    fn config(camera: Camera, policies: &[&str]) -> SessionConfig {
        SessionConfig {
            camera,
            plane: None,
            timing: CameraTiming::default(),
            method: Method::default(),
            use_velocity: false,
            policies: policies
                .iter()
                .map(|p| PolicySpec::parse(p).unwrap())
                .collect(),
        }
    }

    /// The px/s (true pixel speed) of every sample of `log`.
    fn px_series(s: &Session, log: &ImuLog, m: &[f64]) -> Vec<f64> {
        let ev = crate::metric::Evaluator::new(s.camera(), s.series().method).unwrap();
        log.iter()
            .zip(m)
            .map(|(x, &mm)| {
                crate::series::sample_px(x, s.series(), &ev, mm)
                    .unwrap()
                    .unwrap()
            })
            .collect()
    }

    #[test]
    fn pixel_budgets_use_the_true_pixel_speed() {
        // Anamorphic pixels (fx = 1.5 fy): exposure control keeps the
        // decision sample's px/s x t_e at the budget, not its mm/s over
        // pitch_x x t_e.
        let log = walk();
        let mut camera = Camera::thesis();
        camera.pitch_y_mm = 1.5 * camera.pitch_x_mm;
        let s = Session::new(config(camera, &["fixed:5+exp:0.5"]), None).unwrap();
        let got = s.run(&log).unwrap();
        let m = &got.mmbm_mm_s;
        let px = px_series(&s, &log, m);
        let (mut inside, mut off) = (0, 0);
        for f in &got.frames[0] {
            let te = f.exposure_s();
            if te >= s.timing().exposure * (1.0 - 1e-12) || te <= Exposure::MIN_EXPOSURE {
                continue; // clamped
            }
            inside += 1;
            let blur = px[f.index] * te;
            assert!((blur - 0.5).abs() < 1e-9, "{blur}");
            let old = m[f.index] / camera.pitch_x_mm * te;
            off += usize::from((old - 0.5).abs() > 0.02);
        }
        assert!(
            inside >= 5 && off * 2 >= inside,
            "{inside} frames, {off} off by the old rule"
        );
    }

    #[test]
    fn a_session_runs_what_the_parts_run() {
        let log = walk();
        let mut camera = Camera::thesis();
        camera.pitch_x_mm = 0.003;
        camera.shutter.readout_s = 0.01;
        let s = Session::new(config(camera, &["fixed:5+exp:2", "threshold:0.4"]), None).unwrap();
        assert!(!s.readout_from_log());
        // The timing takes the camera's pitch and its rolling readout.
        assert_eq!(s.timing().pitch_mm, 0.003);
        assert!((s.timing().readout - (CameraTiming::DEFAULT_READOUT_S + 0.01)).abs() < 1e-15);
        let got = s.run(&log).unwrap();
        let m = crate::series::mmbm_series_with(&log, s.series()).unwrap();
        assert_eq!(got.mmbm_mm_s, m);
        assert_eq!(got.duration_s, log[log.len() - 1].t - log[0].t);
        assert_eq!(got.frames.len(), 2);
        // pitch_x != pitch_y: the pixel budget takes each sample's px/s.
        let px = px_series(&s, &log, &m);
        for (frames, p) in got.frames.iter().zip(s.policies().specs()) {
            let want =
                run_px(&log, &m, Some(&px), p.build().unwrap().as_mut(), s.timing()).unwrap();
            assert!(!want.is_empty(), "{}", p.as_str());
            assert_eq!(frames, &want);
        }
    }

    #[test]
    fn a_log_readout_applies_to_a_global_shutter_only() {
        let r = LogReadout {
            readout_s: 0.02,
            direction: None,
        };
        let s = Session::new(config(Camera::thesis(), &["fixed:5"]), Some(r)).unwrap();
        assert!(s.readout_from_log());
        assert_eq!(s.camera().shutter.readout_s, 0.02);
        assert!((s.timing().readout - (CameraTiming::DEFAULT_READOUT_S + 0.02)).abs() < 1e-15);
        let mut rolling = Camera::thesis();
        rolling.shutter.readout_s = 0.005;
        let s = Session::new(config(rolling, &["fixed:5"]), Some(r)).unwrap();
        assert!(!s.readout_from_log());
        assert_eq!(s.camera().shutter.readout_s, 0.005);
    }

    #[test]
    fn bad_timing_and_live_only_policies_are_errors() {
        let mut c = config(Camera::thesis(), &["fixed:5"]);
        c.timing.exposure = -1.0;
        let e = Session::new(c, None).unwrap_err().to_string();
        assert!(e.contains("exposure"), "{e}");
        let s = Session::new(config(Camera::thesis(), &["oracle:0.4"]), None).unwrap();
        let e = s.policies().live().err().expect("the oracle is not causal");
        assert!(e.to_string().contains("oracle:0.4"), "{e}");
    }
}
