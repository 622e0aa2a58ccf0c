//! Live triggering: the runner's decision loop ([`super::run`]) one sample
//! at a time, for samples that arrive as they are measured.
//!
//! At each sample the policy sees exactly what it sees offline (the samples
//! up to it), so a log streamed through [`Live`] gives the triggers of
//! [`super::run`] on that log; the only difference is at the end, where the
//! offline runner knows the log stops and skips exposures that would outlast
//! it. The exposure average (and a gate's verdict) of a frame is known once a
//! sample at or after its exposure end has arrived: [`Live::push`] reports it
//! then, as a second event of the same frame.
//!
//! Not everything works live: the oracle needs the future, and percentile
//! thresholds (`pNN`) need the whole log; both are refused.

use super::policy::{LogView, Observation, Policy};
use super::timing::{CameraTiming, Frame, Integral};
use crate::error::{Error, Result};
use std::collections::VecDeque;

/// What one sample produced.
#[derive(Debug, Clone, PartialEq)]
pub enum Event {
    /// Frame number `k` (0-based) triggered at this sample
    /// (`mmbm_exposure_mm_s` not known yet: NaN).
    Trigger(usize, Frame),
    /// Frame `k`, whose exposure is over: its exposure average and `kept`.
    Exposed(usize, Frame),
}

/// A policy run on a stream of samples.
pub struct Live {
    policy: Box<dyn Policy>,
    timing: CameraTiming,
    /// Recent sample times (s) and MMBM (mm/s): between RECENT and
    /// 2 RECENT samples, so memory stays constant on an endless stream.
    t: Vec<f64>,
    m: Vec<f64>,
    /// Samples taken, and the first one's time.
    n: usize,
    t0: f64,
    integral: Integral,
    free_at: f64,
    last_trigger: Option<f64>,
    frames: usize,
    open: VecDeque<(usize, Frame)>,
}

impl Live {
    /// Prepares `policy` for a stream. Errors for the oracle and for
    /// percentile thresholds.
    pub fn new(mut policy: Box<dyn Policy>, timing: CameraTiming) -> Result<Self> {
        timing.validate()?;
        if !policy.is_causal() {
            return Err(Error::invalid(
                "policy",
                format!(
                    "'{}' needs the future (the oracle); live triggering takes causal policies only",
                    policy.label()
                ),
            ));
        }
        policy
            .prepare(&LogView { t: &[], mmbm: &[] }, &timing)
            .map_err(|_| {
                Error::invalid(
                    "policy",
                    format!(
                        "'{}': a percentile threshold (pNN) needs the whole log; give the threshold in mm/s for live use",
                        policy.label()
                    ),
                )
            })?;
        Ok(Live {
            policy,
            timing,
            t: Vec::new(),
            m: Vec::new(),
            n: 0,
            t0: f64::NAN,
            integral: Integral::default(),
            free_at: f64::NEG_INFINITY,
            last_trigger: None,
            frames: 0,
            open: VecDeque::new(),
        })
    }

    /// The policy's label (the `policy` column: a built-in policy's string).
    pub fn label(&self) -> &str {
        self.policy.label()
    }

    /// The policy's spec ([`Policy::spec`]), which its frames carry.
    pub fn spec(&self) -> super::PolicySpec {
        self.policy.spec()
    }

    /// Samples taken so far.
    pub fn len(&self) -> usize {
        self.n
    }

    /// True before the first sample.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The time of the last sample, s.
    pub fn last_time(&self) -> Option<f64> {
        self.t.last().copied()
    }

    /// Checks a sample before it is taken, changing nothing: its time
    /// finite, resolved by the log's time base for the exposure, after the
    /// previous sample's; its MMBM a finite number >= 0. [`Live::push_px`]
    /// refuses the same samples; a stream checks every policy's runner
    /// first, so that a bad sample is skipped by all or none.
    pub fn check(&self, t: f64, mmbm_mm_s: f64) -> Result<()> {
        crate::check::finite("sample time", t)?;
        crate::model::log::check_resolution(t, self.timing.exposure, "the exposure")?;
        if let Some(prev) = self.last_time() {
            if t <= prev {
                return Err(Error::invalid(
                    "sample time",
                    format!("{t} s is not after the previous sample's {prev} s"),
                ));
            }
        }
        if !(mmbm_mm_s.is_finite() && mmbm_mm_s >= 0.0) {
            return Err(Error::invalid(
                "mmbm",
                format!("value {mmbm_mm_s} at t = {t} s is not a finite number >= 0"),
            ));
        }
        Ok(())
    }

    /// Takes the sample at time `t` (s, after the previous one) with MMBM
    /// `mmbm_mm_s` and returns what it produced: a trigger at it, and frames
    /// whose exposure it completed.
    pub fn push(&mut self, t: f64, mmbm_mm_s: f64) -> Result<Vec<Event>> {
        self.push_px(t, mmbm_mm_s, None)
    }

    /// [`Live::push`] with the sample's MMBM in px/s too (the true pixel
    /// speed): pixel budgets convert with its mm per px
    /// ([`super::policy::Observation::pitch_mm`]), else the timing's pitch.
    pub fn push_px(&mut self, t: f64, mmbm_mm_s: f64, px_s: Option<f64>) -> Result<Vec<Event>> {
        self.check(t, mmbm_mm_s)?;
        if self.t.len() >= 2 * Observation::RECENT {
            self.t.drain(..Observation::RECENT);
            self.m.drain(..Observation::RECENT);
        }
        if self.n == 0 {
            self.t0 = t;
        }
        self.n += 1;
        self.t.push(t);
        self.m.push(mmbm_mm_s);
        self.integral.push(t, mmbm_mm_s);
        let mut events = Vec::new();
        // Exposures this sample completes.
        while self.open.front().is_some_and(|(_, f)| f.exposure_end <= t) {
            if let Some((k, mut f)) = self.open.pop_front() {
                f.mmbm_exposure_mm_s = self.integral.mean(f.exposure_start, f.exposure_end);
                f.kept = self.policy.keep(&f);
                events.push(Event::Exposed(k, f));
            }
        }
        // Exposure means need samples from the oldest open exposure's start
        // (or, with none open, from the next one's: after now).
        let keep_from = self.open.front().map_or(t, |(_, f)| f.exposure_start);
        self.integral.trim_before(keep_from.min(t));
        let i = self.n - 1;
        let start = t + self.timing.delay;
        let camera_free = start >= self.free_at;
        let obs = Observation {
            i,
            t0: self.t0,
            t: &self.t,
            mmbm: &self.m,
            camera_free,
            last_trigger: self.last_trigger,
            frames: self.frames,
            timing: &self.timing,
            pitch_mm: px_s.map_or(self.timing.pitch_mm, |px| {
                super::run::pixel_pitch(mmbm_mm_s, px, self.timing.pitch_mm)
            }),
        };
        if self.policy.decide(&obs) && camera_free {
            let (te, gain) = self.policy.exposure(&obs);
            let end = start + te;
            let f = Frame {
                policy: self.policy.spec(),
                index: i,
                trigger_t: t,
                exposure_start: start,
                exposure_end: end,
                mmbm_trigger_mm_s: mmbm_mm_s,
                mmbm_exposure_mm_s: f64::NAN,
                kept: true,
                gain,
            };
            let k = self.frames;
            self.frames += 1;
            self.free_at = end + self.timing.readout;
            self.last_trigger = Some(t);
            self.open.push_back((k, f.clone()));
            events.push(Event::Trigger(k, f));
        }
        Ok(events)
    }
}
