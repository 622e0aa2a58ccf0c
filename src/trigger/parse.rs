//! The policy parser: `name:args` strings (grammar in the module docs of
//! [`crate::trigger`]) to boxed [`Policy`] values.

use super::exposure::Exposure;
use super::phase::Phase;
use super::policy::{Level, Policy};
use super::predict::{Forecast, Oracle};
use super::rules::{Adaptive, Deadline, Fixed, Gate, Threshold};
use crate::error::{Error, Result};

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

/// Highest frame rate a policy accepts, frames/s.
pub const MAX_FPS: f64 = 1000.0;

/// A frame rate in `(0, MAX_FPS]`.
fn parse_fps(s: &str, what: &str, spec: &str) -> Result<f64> {
    let fps = parse_pos(s, what, spec)?;
    if fps > MAX_FPS {
        return Err(Error::invalid(
            "policy",
            format!("'{spec}': {what} {fps} is above the limit of {MAX_FPS} frames/s"),
        ));
    }
    Ok(fps)
}

/// Parses `FPS[@PHASE]`.
pub(crate) fn parse_rate(s: &str, spec: &str) -> Result<(f64, f64)> {
    let (f, p) = match s.split_once('@') {
        Some((f, p)) => (f, parse_num(p, "phase", spec)?),
        None => (s, 0.0),
    };
    let fps = parse_fps(f, "frame rate", spec)?;
    if p < 0.0 {
        return Err(Error::invalid(
            "policy",
            format!("'{spec}': phase must be >= 0 s"),
        ));
    }
    Ok((fps, p))
}

const GRAMMAR: &str = "fixed:FPS[@PHASE], threshold:X, adaptive[:X[:FPS]], oracle:X[:H], \
forecast:X[:H], phase:X[:H], gate:X[:FPS[@PHASE]], gate0:X[:FPS[@PHASE]] or deadline:FPS[:X] (X in mm/s or pNN), \
each optionally followed by +exp:B[:TMIN] (exposure control: blur budget B px, shortest exposure TMIN s)";

/// Parses a policy string (grammar in the module docs). The policy keeps the
/// string exactly as given for the `policy` column.
pub fn parse_policy(spec: &str) -> Result<Box<dyn Policy>> {
    if let Some((base, modifier)) = spec.split_once('+') {
        let bad =
            |msg: &str| Error::invalid("policy", format!("'{spec}': {msg}; expected {GRAMMAR}"));
        let inner = parse_policy(base)?;
        let parts: Vec<&str> = modifier.trim().split(':').collect();
        let (budget, tmin) = match parts.as_slice() {
            ["exp", b] => (*b, None),
            ["exp", b, t] => (*b, Some(*t)),
            _ => return Err(bad("after '+' expected exp:B[:TMIN]")),
        };
        let budget = parse_pos(budget, "blur budget (px)", spec)?;
        let tmin = match tmin {
            Some(t) => parse_pos(t, "shortest exposure (s)", spec)?,
            None => Exposure::MIN_EXPOSURE,
        };
        return Ok(Box::new(Exposure::new(spec, inner, budget, tmin)));
    }
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
            parse_fps(f, "target frame rate", spec)?,
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
        ("phase", [x]) => Box::new(Phase::new(spec, level(x)?, 0.2)),
        ("phase", [x, h]) => Box::new(Phase::new(spec, level(x)?, parse_pos(h, "horizon", spec)?)),
        ("gate", [x]) => Box::new(Gate::new(spec, level(x)?, 5.0, 0.0)),
        ("gate", [x, r]) => {
            let (fps, phase) = parse_rate(r, spec)?;
            Box::new(Gate::new(spec, level(x)?, fps, phase))
        }
        ("gate0", [x]) => Box::new(Gate::at_start(spec, level(x)?, 5.0, 0.0)),
        ("gate0", [x, r]) => {
            let (fps, phase) = parse_rate(r, spec)?;
            Box::new(Gate::at_start(spec, level(x)?, fps, phase))
        }
        ("deadline", [f]) => Box::new(Deadline::new(spec, parse_fps(f, "frame rate", spec)?, None)),
        ("deadline", [f, x]) => Box::new(Deadline::new(
            spec,
            parse_fps(f, "frame rate", spec)?,
            Some(level(x)?),
        )),
        (
            "fixed" | "threshold" | "adaptive" | "oracle" | "forecast" | "phase" | "gate" | "gate0"
            | "deadline",
            _,
        ) => return Err(bad("wrong number of ':' arguments")),
        _ => return Err(bad("unknown policy")),
    };
    Ok(p)
}
