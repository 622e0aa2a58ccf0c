//! Exposure control: `POLICY+exp:B[:TMIN]`, the other lever of the thesis's
//! Fig. 1.1 (and of camera makers): predict the blur from the gyro, shorten the
//! exposure and raise the gain.

use super::policy::{LogView, Observation, Policy};
use super::timing::{CameraTiming, Frame};
use crate::error::Result;

/// `POLICY+exp:B[:TMIN]`: the frames of `POLICY` (its timing, its gates),
/// each exposed for
///
/// `t_e = clamp(B p / M, TMIN, T)`
///
/// with `M` the MMBM at the decision sample (mm/s, the blur speed the gyro
/// predicts for the next instants), `p` the pixel pitch (mm), `B` the blur
/// budget (px), `T` the camera's exposure and `TMIN` the shortest exposure
/// (s, default 1 ms). The gain is raised by `T / t_e`, so the image is as
/// bright as at `T`, and as noisy as `t_e`'s photons make it (the sensor noise
/// model sees both). With `M = 0` the exposure is `T`.
///
/// E.g. `fixed:5+exp:2` keeps the fixed rate with at most ~2 px of predicted
/// blur per frame; `phase:0.4+exp:2` combines it with trigger timing.
pub struct Exposure {
    spec: String,
    inner: Box<dyn Policy>,
    budget_px: f64,
    min_exposure: f64,
}

impl Exposure {
    /// Shortest exposure when none is given, s.
    pub const MIN_EXPOSURE: f64 = 0.001;

    /// Wraps `inner` with a blur budget `budget_px` (px) and a shortest exposure `min_exposure` (s).
    pub fn new(spec: &str, inner: Box<dyn Policy>, budget_px: f64, min_exposure: f64) -> Self {
        Exposure {
            spec: spec.to_string(),
            inner,
            budget_px,
            min_exposure,
        }
    }

    /// The exposure (s) for a blur speed `m` (mm/s) under `timing`.
    pub fn exposure_for(&self, m: f64, timing: &CameraTiming) -> f64 {
        let t_max = timing.exposure;
        if m > 0.0 {
            crate::camera::exposure_for_blur(self.budget_px, m, timing.pitch_mm)
                .clamp(self.min_exposure.min(t_max), t_max)
        } else {
            t_max
        }
    }
}

impl Policy for Exposure {
    fn spec(&self) -> &str {
        &self.spec
    }
    fn is_causal(&self) -> bool {
        self.inner.is_causal()
    }
    fn prepare(&mut self, log: &LogView, timing: &CameraTiming) -> Result<()> {
        self.inner.prepare(log, timing)
    }
    fn decide(&mut self, obs: &Observation) -> bool {
        self.inner.decide(obs)
    }
    fn keep(&self, frame: &Frame) -> bool {
        self.inner.keep(frame)
    }
    fn exposure(&self, obs: &Observation) -> (f64, f64) {
        let (t_inner, gain_inner) = self.inner.exposure(obs);
        let te = self.exposure_for(obs.current(), obs.timing).min(t_inner);
        (te, gain_inner * t_inner / te)
    }
}
