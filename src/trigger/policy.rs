//! The policy trait, what a policy observes, thresholds and the policy parser.

use super::predict::{Forecast, Oracle};
use super::rules::{Adaptive, Deadline, Fixed, Gate, Threshold};
use super::{CameraTiming, Frame};
use crate::error::{Error, Result};

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
    /// Index of the decision sample.
    pub i: usize,
    /// Sample times `0..=i`, s.
    pub t: &'a [f64],
    /// MMBM of samples `0..=i`, mm/s.
    pub mmbm: &'a [f64],
    /// True when a pulse sent now would find the camera free.
    pub camera_free: bool,
    /// Decision time of the previous frame, s.
    pub last_trigger: Option<f64>,
    /// Frames triggered so far.
    pub frames: usize,
    /// The camera timing.
    pub timing: &'a CameraTiming,
}

impl Observation<'_> {
    /// The decision time `t_i`, s.
    pub fn now(&self) -> f64 {
        self.t[self.t.len() - 1]
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
    /// The policy string exactly as given to [`parse_policy`].
    fn spec(&self) -> &str;
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
}

/// A threshold: an absolute MMBM (mm/s) or a percentile of the log's own series.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Level {
    /// mm/s.
    Abs(f64),
    /// Percentile 0..100 of the whole log's MMBM.
    Percentile(f64),
}

impl Level {
    /// Parses `X` (mm/s, >= 0) or `pNN` (0 <= NN <= 100).
    pub fn parse(s: &str, what: &str) -> Result<Self> {
        let bad = || {
            Error::invalid(
                what,
                format!(
                    "'{s}': expected a threshold in mm/s (e.g. 0.4) or a percentile pNN (e.g. p20)"
                ),
            )
        };
        if let Some(p) = s.strip_prefix(['p', 'P']) {
            let q: f64 = p.parse().map_err(|_| bad())?;
            if !(0.0..=100.0).contains(&q) {
                return Err(bad());
            }
            return Ok(Level::Percentile(q));
        }
        let x: f64 = s.parse().map_err(|_| bad())?;
        if !(x.is_finite() && x >= 0.0) {
            return Err(bad());
        }
        Ok(Level::Abs(x))
    }

    /// The threshold in mm/s for a log whose MMBM series is `mmbm`.
    pub fn resolve(&self, mmbm: &[f64]) -> Result<f64> {
        match *self {
            Level::Abs(x) => Ok(x),
            Level::Percentile(q) => percentile(mmbm, q)
                .ok_or_else(|| Error::invalid("percentile threshold", "the MMBM series is empty")),
        }
    }
}

/// The `q`-th percentile (0..100) with linear interpolation between order
/// statistics (rank `q / 100 * (n - 1)`); None for an empty series.
pub fn percentile(x: &[f64], q: f64) -> Option<f64> {
    if x.is_empty() {
        return None;
    }
    let mut v = x.to_vec();
    v.sort_by(f64::total_cmp);
    let r = (q / 100.0).clamp(0.0, 1.0) * (v.len() - 1) as f64;
    let lo = r.floor() as usize;
    let hi = r.ceil() as usize;
    Some(v[lo] + (r - lo as f64) * (v[hi] - v[lo]))
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

pub(crate) fn parse_num(s: &str, what: &str, spec: &str) -> Result<f64> {
    let x: f64 = s
        .trim()
        .parse()
        .map_err(|_| Error::invalid("policy", format!("'{spec}': {what} '{s}' is not a number")))?;
    if !x.is_finite() {
        return Err(Error::invalid(
            "policy",
            format!("'{spec}': {what} must be finite"),
        ));
    }
    Ok(x)
}

pub(crate) fn parse_pos(s: &str, what: &str, spec: &str) -> Result<f64> {
    let x = parse_num(s, what, spec)?;
    if x <= 0.0 {
        return Err(Error::invalid(
            "policy",
            format!("'{spec}': {what} must be > 0, got {x}"),
        ));
    }
    Ok(x)
}

/// Parses `FPS[@PHASE]`.
pub(crate) fn parse_rate(s: &str, spec: &str) -> Result<(f64, f64)> {
    let (f, p) = match s.split_once('@') {
        Some((f, p)) => (f, parse_num(p, "phase", spec)?),
        None => (s, 0.0),
    };
    let fps = parse_pos(f, "frame rate", spec)?;
    if p < 0.0 {
        return Err(Error::invalid(
            "policy",
            format!("'{spec}': phase must be >= 0 s"),
        ));
    }
    Ok((fps, p))
}

const GRAMMAR: &str = "fixed:FPS[@PHASE], threshold:X, adaptive[:X[:FPS]], oracle:X[:H], \
forecast:X[:H], gate:X[:FPS[@PHASE]] or deadline:FPS[:X] (X in mm/s or pNN)";

/// Parses a policy string (grammar in the module docs). The policy keeps the
/// string exactly as given for the `policy` column.
pub fn parse_policy(spec: &str) -> Result<Box<dyn Policy>> {
    let parts: Vec<&str> = spec.trim().split(':').collect();
    let name = parts[0].to_ascii_lowercase();
    let args = &parts[1..];
    let bad = |msg: &str| Error::invalid("policy", format!("'{spec}': {msg}; expected {GRAMMAR}"));
    let level = |s: &str| Level::parse(s.trim(), &format!("policy '{spec}' threshold"));
    let p: Box<dyn Policy> = match (name.as_str(), args) {
        ("fixed", [r]) => {
            let (fps, phase) = parse_rate(r, spec)?;
            Box::new(Fixed::new(spec, fps, phase))
        }
        ("threshold", [x]) => Box::new(Threshold::new(spec, level(x)?)),
        ("adaptive", []) => Box::new(Adaptive::new(spec, Level::Abs(0.4), 2.5)),
        ("adaptive", [x]) => Box::new(Adaptive::new(spec, level(x)?, 2.5)),
        ("adaptive", [x, f]) => Box::new(Adaptive::new(
            spec,
            level(x)?,
            parse_pos(f, "target frame rate", spec)?,
        )),
        ("oracle", [x]) => Box::new(Oracle::new(spec, level(x)?, 0.2)),
        ("oracle", [x, h]) => {
            Box::new(Oracle::new(spec, level(x)?, parse_pos(h, "horizon", spec)?))
        }
        ("forecast", [x]) => Box::new(Forecast::new(spec, level(x)?, 0.2)),
        ("forecast", [x, h]) => Box::new(Forecast::new(
            spec,
            level(x)?,
            parse_pos(h, "horizon", spec)?,
        )),
        ("gate", [x]) => Box::new(Gate::new(spec, level(x)?, 5.0, 0.0)),
        ("gate", [x, r]) => {
            let (fps, phase) = parse_rate(r, spec)?;
            Box::new(Gate::new(spec, level(x)?, fps, phase))
        }
        ("deadline", [f]) => Box::new(Deadline::new(spec, parse_pos(f, "frame rate", spec)?, None)),
        ("deadline", [f, x]) => Box::new(Deadline::new(
            spec,
            parse_pos(f, "frame rate", spec)?,
            Some(level(x)?),
        )),
        ("fixed" | "threshold" | "adaptive" | "oracle" | "forecast" | "gate" | "deadline", _) => {
            return Err(bad("wrong number of ':' arguments"))
        }
        _ => return Err(bad("unknown policy")),
    };
    Ok(p)
}
