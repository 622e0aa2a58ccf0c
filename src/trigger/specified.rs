//! A built policy with the spec it was built from ([`Specified`]).

use super::policy::{LogView, Observation, Policy};
use super::spec::PolicySpec;
use super::timing::{CameraTiming, Frame};
use crate::error::Result;

/// A policy with the spec it was built from (`PolicySpec::build`): its
/// [`Policy::spec`] is that spec, everything else the built policy's.
pub(super) struct Specified {
    /// The spec `inner` was built from.
    pub(super) spec: PolicySpec,
    /// The policy.
    pub(super) inner: Box<dyn Policy>,
}

impl Policy for Specified {
    fn label(&self) -> &str {
        self.spec.as_str()
    }
    fn spec(&self) -> PolicySpec {
        self.spec.clone()
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
        self.inner.exposure(obs)
    }
    fn forecast_exposure_mmbm(&self, obs: &Observation, exposure_s: f64) -> Option<f64> {
        self.inner.forecast_exposure_mmbm(obs, exposure_s)
    }
}
