//! The policy trait and what a policy observes.

pub use super::level::Level;
use super::spec::PolicySpec;
use super::timing::{CameraTiming, Frame};
use crate::error::Result;

/// Tolerance (s) on interval comparisons, against rounding in sums of times.
pub(crate) const TIME_EPS: f64 = 1e-9;

/// The whole log, given to [`Policy::prepare`] once before a run.
#[derive(Debug, Clone, Copy)]
pub struct LogView<'a> {
    /// Sample times, s.
    pub t: &'a [f64],
    /// MMBM per sample, mm/s.
    pub mmbm: &'a [f64],
}

/// What a policy sees at the decision sample `i`: nothing after it.
#[derive(Debug, Clone, Copy)]
pub struct Observation<'a> {
    /// Index of the decision sample (counted from the log's first sample).
    pub i: usize,
    /// Time of the log's first sample, s.
    pub t0: f64,
    /// Times of recent samples ending with the decision sample, s: the whole
    /// log up to it offline, at least the last [`Observation::RECENT`] live.
    pub t: &'a [f64],
    /// MMBM of the same samples as `t`, mm/s.
    pub mmbm: &'a [f64],
    /// True when a pulse sent now would find the camera free.
    pub camera_free: bool,
    /// Decision time of the previous frame, s.
    pub last_trigger: Option<f64>,
    /// Frames triggered so far.
    pub frames: usize,
    /// The camera timing.
    pub timing: &'a CameraTiming,
    /// Millimetres on the sensor per pixel of the decision sample's motion:
    /// its MMBM in mm/s over its MMBM in px/s (the true pixel speed,
    /// `Mmbm::px_s`), what pixel budgets convert with; the timing's pitch
    /// with square, unskewed pixels (or a still sample).
    pub pitch_mm: f64,
}

impl Observation<'_> {
    /// The fewest recent samples an observation holds (where the log has them).
    pub const RECENT: usize = 16;

    /// The decision time `t_i`, s.
    pub fn now(&self) -> f64 {
        self.t[self.t.len() - 1]
    }

    /// MMBM at the decision sample, mm/s.
    pub fn current(&self) -> f64 {
        self.mmbm[self.mmbm.len() - 1]
    }

    /// Indices into `t` / `mmbm` of the samples after time `last` (s): the
    /// ones a policy that keeps its own history has not seen yet.
    pub fn unseen(&self, last: Option<f64>) -> std::ops::Range<usize> {
        let last = last.unwrap_or(f64::NEG_INFINITY);
        self.t.partition_point(|&s| s <= last)..self.t.len()
    }

    /// Time of the sample before the decision sample, s.
    pub fn previous_time(&self) -> Option<f64> {
        self.t.len().checked_sub(2).map(|k| self.t[k])
    }

    /// True when no frame was triggered yet or the minimum interval has passed.
    pub fn interval_passed(&self) -> bool {
        self.last_trigger
            .is_none_or(|lt| self.now() - lt >= self.timing.min_interval - TIME_EPS)
    }
}

/// A trigger policy. `decide` is called for every sample in time order (and
/// only while an exposure starting there still ends inside the log); returning
/// true triggers a frame when the camera is free (the runner ignores it
/// otherwise; the built-in policies only return true when it is free).
pub trait Policy {
    /// The policy's label, the `policy` column: for a built-in policy the
    /// policy string exactly as given to [`super::parse_policy`].
    fn label(&self) -> &str;
    /// The typed spec the policy was built from, which every frame it
    /// triggers carries ([`Frame::policy`]): [`PolicySpec::build`]'s
    /// policies return the spec they were built from; any other policy (a
    /// user's own, or a rule's constructor called directly) a
    /// [`PolicySpec::custom`] of its [`Self::label`] (the default).
    fn spec(&self) -> PolicySpec {
        PolicySpec::custom(self.label())
    }
    /// False for policies that use knowledge of the future (the oracle).
    fn is_causal(&self) -> bool {
        true
    }
    /// Called once before each run (resets the state). Causal policies use the
    /// whole log only to resolve percentile thresholds.
    fn prepare(&mut self, log: &LogView, timing: &CameraTiming) -> Result<()>;
    /// The decision at sample `obs.i`.
    fn decide(&mut self, obs: &Observation) -> bool;
    /// Whether a triggered frame is kept (quality gates discard some).
    fn keep(&self, _frame: &Frame) -> bool {
        true
    }
    /// The exposure (s) and relative gain of a frame triggered at `obs`: the
    /// camera's exposure and gain 1, unless the policy controls the exposure
    /// (at most the camera's, which the runner counts on).
    fn exposure(&self, obs: &Observation) -> (f64, f64) {
        (obs.timing.exposure, 1.0)
    }
    /// The policy's forecast of the exposure MMBM (mm/s) of a frame triggered
    /// at `obs` and exposed for `exposure_s` (infinite: an exposure the
    /// policy would not take), for exposure control; `None` (the default)
    /// when the policy has no forecast of its own (exposure control then
    /// uses the MMBM at the decision sample).
    fn forecast_exposure_mmbm(&self, _obs: &Observation, _exposure_s: f64) -> Option<f64> {
        None
    }
}

/// The thesis rule on the last three MMBM samples: all below `x` and strictly decreasing.
pub fn thesis_rule(m: &[f64], x: f64) -> bool {
    let n = m.len();
    n >= 3
        && m[n - 3] < x
        && m[n - 2] < x
        && m[n - 1] < x
        && m[n - 3] > m[n - 2]
        && m[n - 2] > m[n - 1]
}

/// The slot of a fixed rate `fps` (frames/s) that `now` (s) falls in: its
/// index `k` and its start `t0 + k / fps` (s), the latest start at or
/// before `now` (guarded against rounding at slot boundaries). Shared by the
/// one-frame-per-slot policies (`deadline`, `task`).
pub(super) fn rate_slot(t0: f64, fps: f64, now: f64) -> (i64, f64) {
    let period = 1.0 / fps;
    let mut slot = ((now - t0) * fps).floor() as i64;
    if t0 + slot as f64 * period > now {
        slot -= 1;
    }
    (slot, t0 + slot as f64 * period)
}
