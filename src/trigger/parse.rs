//! The policy parser: `name:args` strings (grammar in the module docs of
//! [`crate::trigger`]) to a typed [`PolicySpec`], parsed once, which knows
//! its family, rate, threshold, causality and exposure control, and builds
//! the boxed [`Policy`] that runs.

use super::baselines::{parse_ae, split_exposure, AutoExposure, FixedExposure};
use super::exposure::Exposure;
use super::grad_ae::{parse_white, GradientAe};
use super::gyro_ae::{parse_imu, split_keys, AeVariant, BlurCappedAe, ImuTradeAe};
use super::numbers::{parse_num, parse_pos};
use super::phase::Phase;
use super::policy::{Level, Policy};
use super::predict::{Forecast, Oracle};
use super::rules::{Adaptive, Deadline, Fixed, Gate, Threshold};
use super::specified::Specified;
use super::task::{parse_task, Task, TaskModel};
use crate::error::{Error, Result};

use super::family::Family;
use super::spec::{ExposureControl, PolicySpec, Rate};

/// Highest frame rate a policy accepts, frames/s.
pub const MAX_FPS: f64 = 1000.0;

/// A frame rate in `(0, MAX_FPS]`.
fn parse_fps(s: &str, what: &str, spec: &str) -> Result<f64> {
    check_fps(parse_pos(s, what, spec)?, what, spec)
}

/// Refuses a frame rate above [`MAX_FPS`] (`fps` already > 0 and finite).
pub(super) fn check_fps(fps: f64, what: &str, spec: &str) -> Result<f64> {
    if fps > MAX_FPS {
        return Err(Error::invalid(
            "policy",
            format!("'{spec}': {what} {fps} is above the limit of {MAX_FPS} frames/s"),
        ));
    }
    Ok(fps)
}

/// Refuses a `key=value` argument whose key was given before (`ae:5:cap=10ms:cap=3ms`):
/// neither value silently wins.
fn unique_keys(keys: &[&str], spec: &str) -> Result<()> {
    let mut seen = std::collections::HashSet::new();
    for kv in keys {
        let Some((k, _)) = kv.split_once('=') else {
            continue;
        };
        let k = k.trim();
        if !seen.insert(k) {
            return Err(Error::invalid(
                "policy",
                format!("'{spec}': key '{k}' is given twice; give each key once"),
            ));
        }
    }
    Ok(())
}

/// Parses `FPS[@PHASE]`.
fn parse_rate(s: &str, spec: &str) -> Result<(f64, f64)> {
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

const GRAMMAR: &str = "fixed:FPS[@PHASE][@Tms], ae:FPS[@PHASE][:cap=Tms][:target=F][:damp=F][:scene=F], \
ae-blur:FPS[@PHASE]:B[:ae keys], ae-imu:FPS[@PHASE][:w=W][:w0=W0][:ae keys], ae-grad:FPS[@PHASE][:white=F][:cap=Tms][:scene=F], threshold:X, adaptive[:X[:FPS]], oracle:X[:H], \
forecast:X[:H], phase:X[:H], gate:X[:FPS[@PHASE]], gate0:X[:FPS[@PHASE]], deadline:FPS[:X] (X in mm/s or pNN) or task:FPS:light=E[:read=E][:tmin=Tms], \
each optionally followed by +exp:B[:TMIN] (exposure control: blur budget B px, shortest exposure TMIN s)";

/// Parses a policy string (grammar in the module docs) and builds the policy.
/// The policy keeps the string exactly as given for the `policy` column.
pub fn parse_policy(spec: &str) -> Result<Box<dyn Policy>> {
    PolicySpec::parse(spec)?.build()
}

/// The thesis's rule at its threshold (thesis ch. 6): three falling MMBM
/// samples below 0.4 mm/s.
pub const THESIS_POLICY: &str = "threshold:0.4";

/// A gate's schedule when its string gives none: 5 fps from the log's start.
const DEFAULT_GATE_RATE: Rate = Rate {
    fps: 5.0,
    phase: 0.0,
};
/// `adaptive`'s target frame rate when its string gives none.
const DEFAULT_ADAPTIVE_RATE: Rate = Rate {
    fps: 2.5,
    phase: 0.0,
};
/// The forecast horizon of `oracle`, `forecast` and `phase` when their string gives none, s.
pub const DEFAULT_HORIZON_S: f64 = 0.2;

impl PolicySpec {
    /// Parses a policy string (grammar in the module docs of [`crate::trigger`]).
    ///
    /// ```
    /// use mmbm::trigger::{Family, PolicySpec};
    /// let p = PolicySpec::parse("deadline:5+exp:3:0.02")?;
    /// assert_eq!(p.family, Family::Deadline);
    /// assert_eq!(p.rate.map(|r| r.fps), Some(5.0));
    /// assert_eq!(p.exposure.map(|e| e.budget_px), Some(3.0));
    /// assert!(p.is_causal() && !p.is_baseline());
    /// assert!(PolicySpec::parse("fixed:5").unwrap().is_baseline());
    /// # Ok::<(), mmbm::Error>(())
    /// ```
    pub fn parse(spec: &str) -> Result<Self> {
        if let Some((base, modifier)) = spec.split_once('+') {
            let bad = |msg: &str| {
                Error::invalid("policy", format!("'{spec}': {msg}; expected {GRAMMAR}"))
            };
            let mut inner = PolicySpec::parse(base)?;
            if inner.fixed_exposure_s.is_some() || inner.ae.is_some() || inner.task.is_some() {
                return Err(bad(
                    "a fixed exposure (@Tms), auto-exposure (ae) or task sets its own exposure; +exp does not apply",
                ));
            }
            let parts: Vec<&str> = modifier.trim().split(':').collect();
            let (budget, tmin) = match parts.as_slice() {
                ["exp", b] => (*b, None),
                ["exp", b, t] => (*b, Some(*t)),
                _ => return Err(bad("after '+' expected exp:B[:TMIN]")),
            };
            let budget_px = parse_pos(budget, "blur budget (px)", spec)?;
            let min_exposure_s = match tmin {
                Some(t) => parse_pos(t, "shortest exposure (s)", spec)?,
                None => Exposure::MIN_EXPOSURE,
            };
            inner.text = spec.into();
            inner.exposure = Some(ExposureControl {
                budget_px,
                min_exposure_s,
            });
            return Ok(inner);
        }
        let parts: Vec<&str> = spec.trim().split(':').collect();
        let name = parts[0].to_ascii_lowercase();
        let args = &parts[1..];
        let bad =
            |msg: &str| Error::invalid("policy", format!("'{spec}': {msg}; expected {GRAMMAR}"));
        let level = |s: &str| Level::parse(s.trim(), &format!("policy '{spec}' threshold"));
        let rate = |r: &str| -> Result<Rate> {
            let (fps, phase) = parse_rate(r, spec)?;
            Ok(Rate { fps, phase })
        };
        let fps_only = |f: &str, what: &str| -> Result<Rate> {
            Ok(Rate {
                fps: parse_fps(f, what, spec)?,
                phase: 0.0,
            })
        };
        let Some(family) = Family::from_name(&name) else {
            return Err(bad("unknown policy"));
        };
        let mut out = PolicySpec {
            text: spec.into(),
            base_len: spec.len(),
            family,
            rate: None,
            threshold: None,
            horizon: None,
            exposure: None,
            fixed_exposure_s: None,
            ae: None,
            ae_variant: None,
            task: None,
        };
        match (family, args) {
            (Family::Fixed, [r]) => {
                let (r, te) = split_exposure(r, spec)?;
                out.rate = Some(rate(r)?);
                out.fixed_exposure_s = te;
            }
            (Family::Ae, [r, keys @ ..]) => {
                unique_keys(keys, spec)?;
                out.rate = Some(rate(r)?);
                out.ae = Some(parse_ae(keys, spec)?);
            }
            (Family::AeBlur, [r, b, keys @ ..]) if !b.contains('=') => {
                unique_keys(keys, spec)?;
                out.rate = Some(rate(r)?);
                out.ae = Some(parse_ae(keys, spec)?);
                out.ae_variant = Some(AeVariant::BlurCap {
                    budget_px: parse_pos(b, "blur budget (px)", spec)?,
                });
            }
            (Family::AeBlur, _) => return Err(bad("ae-blur needs its blur budget: ae-blur:FPS:B")),
            (Family::AeImu, [r, keys @ ..]) => {
                unique_keys(keys, spec)?;
                out.rate = Some(rate(r)?);
                let (own, rest) = split_keys(keys, &["w", "w0"], &[], spec)?;
                out.ae = Some(parse_ae(&rest, spec)?);
                out.ae_variant = Some(parse_imu(&own, spec)?);
            }
            (Family::AeGrad, [r, keys @ ..]) => {
                unique_keys(keys, spec)?;
                out.rate = Some(rate(r)?);
                let (own, rest) = split_keys(keys, &["white"], &["target", "damp"], spec)?;
                let ae = parse_ae(&rest, spec)?;
                out.ae_variant = Some(AeVariant::Gradient {
                    white: parse_white(&own, ae.scene_mean, spec)?,
                });
                out.ae = Some(ae);
            }
            (Family::Task, [f, keys @ ..]) => {
                unique_keys(keys, spec)?;
                out.rate = Some(fps_only(f, "frame rate")?);
                out.task = Some(parse_task(keys, spec)?);
            }
            (Family::Threshold, [x]) => out.threshold = Some(level(x)?),
            (Family::Adaptive, []) => {
                out.threshold = Some(Level::Abs(0.4));
                out.rate = Some(DEFAULT_ADAPTIVE_RATE);
            }
            (Family::Adaptive, [x]) => {
                out.threshold = Some(level(x)?);
                out.rate = Some(DEFAULT_ADAPTIVE_RATE);
            }
            (Family::Adaptive, [x, f]) => {
                out.threshold = Some(level(x)?);
                out.rate = Some(fps_only(f, "target frame rate")?);
            }
            (Family::Oracle | Family::Forecast | Family::Phase, [x]) => {
                out.threshold = Some(level(x)?);
                out.horizon = Some(DEFAULT_HORIZON_S);
            }
            (Family::Oracle | Family::Forecast | Family::Phase, [x, h]) => {
                out.threshold = Some(level(x)?);
                out.horizon = Some(parse_pos(h, "horizon", spec)?);
            }
            (Family::Gate | Family::Gate0, [x]) => {
                out.threshold = Some(level(x)?);
                out.rate = Some(DEFAULT_GATE_RATE);
            }
            (Family::Gate | Family::Gate0, [x, r]) => {
                out.threshold = Some(level(x)?);
                out.rate = Some(rate(r)?);
            }
            (Family::Deadline, [f]) => out.rate = Some(fps_only(f, "frame rate")?),
            (Family::Deadline, [f, x]) => {
                out.rate = Some(fps_only(f, "frame rate")?);
                out.threshold = Some(level(x)?);
            }
            _ => return Err(bad("wrong number of ':' arguments")),
        }
        Ok(out)
    }

    /// The policy, ready to run: its [`Policy::spec`] is this spec (which
    /// every frame it triggers carries), its [`Policy::label`]
    /// [`Self::as_str`]. Errors for a [`Self::custom`] spec, which names a
    /// policy it cannot build.
    pub fn build(&self) -> Result<Box<dyn Policy>> {
        let inner = self.build_base()?;
        let inner = match self.exposure {
            Some(e) => Box::new(Exposure::new(
                &self.text,
                inner,
                e.budget_px,
                e.min_exposure_s,
            )),
            None => inner,
        };
        Ok(Box::new(Specified {
            spec: self.clone(),
            inner,
        }))
    }

    fn build_base(&self) -> Result<Box<dyn Policy>> {
        let spec = &self.text[..self.base_len];
        let level = self.threshold.unwrap_or(Level::Abs(0.0));
        let rate = self.rate.unwrap_or(DEFAULT_GATE_RATE);
        let h = self.horizon.unwrap_or(DEFAULT_HORIZON_S);
        Ok(match self.family {
            Family::Fixed => match self.fixed_exposure_s {
                Some(te) => Box::new(FixedExposure::new(spec, rate.fps, rate.phase, te)),
                None => Box::new(Fixed::new(spec, rate.fps, rate.phase)),
            },
            Family::Ae => Box::new(AutoExposure::new(
                spec,
                rate.fps,
                rate.phase,
                self.ae.unwrap_or_default(),
            )),
            Family::AeBlur | Family::AeImu | Family::AeGrad => {
                let ae = self.ae.unwrap_or_default();
                let (fps, phase) = (rate.fps, rate.phase);
                match self.ae_variant {
                    Some(AeVariant::BlurCap { budget_px }) => {
                        Box::new(BlurCappedAe::new(spec, fps, phase, ae, budget_px))
                    }
                    Some(AeVariant::ImuTrade {
                        weight_px,
                        offset_px,
                    }) => Box::new(ImuTradeAe::new(spec, fps, phase, ae, weight_px, offset_px)),
                    Some(AeVariant::Gradient { white }) => {
                        Box::new(GradientAe::new(spec, fps, phase, ae, white))
                    }
                    None => Box::new(AutoExposure::new(spec, fps, phase, ae)),
                }
            }
            Family::Threshold => Box::new(Threshold::new(spec, level)),
            Family::Adaptive => Box::new(Adaptive::new(spec, level, rate.fps)),
            Family::Oracle => Box::new(Oracle::new(spec, level, h)),
            Family::Forecast => Box::new(Forecast::new(spec, level, h)),
            Family::Phase => Box::new(Phase::new(spec, level, h)),
            Family::Gate => Box::new(Gate::new(spec, level, rate.fps, rate.phase)),
            Family::Gate0 => Box::new(Gate::at_start(spec, level, rate.fps, rate.phase)),
            Family::Deadline => Box::new(Deadline::new(spec, rate.fps, self.threshold)),
            Family::Task => Box::new(Task::new(
                spec,
                rate.fps,
                self.task.unwrap_or(TaskModel::at_light(1.0)),
            )),
            Family::Custom => {
                return Err(Error::invalid(
                    "policy",
                    format!(
                        "'{}' is a custom policy's label, not a built-in policy; run the custom policy itself",
                        self.text
                    ),
                ))
            }
        })
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn spec(s: &str) -> PolicySpec {
        PolicySpec::parse(s).unwrap_or_else(|e| panic!("{s}: {e}"))
    }

    #[test]
    fn typed_fields() {
        let f = spec("fixed:5@0.1");
        assert_eq!(f.family, Family::Fixed);
        assert_eq!(
            f.rate,
            Some(Rate {
                fps: 5.0,
                phase: 0.1
            })
        );
        assert!(f.is_baseline() && f.is_causal() && f.threshold.is_none());
        let e = spec("fixed:5+exp:0.001:0.02");
        assert!(!e.is_baseline());
        assert_eq!(e.as_str(), "fixed:5+exp:0.001:0.02");
        assert_eq!(
            e.exposure,
            Some(ExposureControl {
                budget_px: 0.001,
                min_exposure_s: 0.02
            })
        );
        // `deadline:5` has a rate, not a 5 mm/s threshold.
        let d = spec("deadline:5");
        assert_eq!(d.threshold_mm_s(), None);
        assert_eq!(d.rate.map(|r| r.fps), Some(5.0));
        assert_eq!(
            spec("deadline:5:p30").threshold,
            Some(Level::Percentile(30.0))
        );
        let o = spec("oracle:0.4");
        assert!(!o.is_causal());
        assert_eq!((o.threshold_mm_s(), o.horizon), (Some(0.4), Some(0.2)));
        assert!(!spec("oracle:0.4+exp:3").is_causal());
        assert_eq!(
            spec("gate:0.5").rate,
            Some(Rate {
                fps: 5.0,
                phase: 0.0
            })
        );
        assert_eq!(spec("adaptive").rate.map(|r| r.fps), Some(2.5));
        assert!(spec(THESIS_POLICY).is_thesis_rule());
        assert!(!spec("threshold:0.4+exp:2").is_thesis_rule());
        assert_eq!(spec("PHASE:0.3:0.5").family, Family::Phase);
    }

    #[test]
    fn build_keeps_the_string_and_causality() {
        for s in [
            "fixed:5",
            "threshold:p20",
            "adaptive:0.4:3",
            "oracle:0.4:0.3",
            "forecast:0.4",
            "phase:0.4",
            "gate:0.4:5@0.1",
            "gate0:0.4",
            "deadline:5:0.3",
            "deadline:5+exp:3:0.02",
            "fixed:5@3ms",
            "ae:5:cap=10ms",
            "ae-blur:5@0.1:1:cap=10ms",
            "ae-imu:5:w=0.5:w0=1:damp=0.25",
            "ae-grad:5:white=0.9",
        ] {
            let p = spec(s);
            let b = p.build().unwrap();
            assert_eq!(b.label(), s);
            assert_eq!(b.spec(), p, "{s}");
            assert_eq!(b.is_causal(), p.is_causal(), "{s}");
            assert_eq!(p.to_string(), s);
        }
    }

    #[test]
    fn bad_strings_are_refused() {
        for s in [
            "",
            "fixed",
            "fixed:0",
            "fixed:5:1",
            "nope:1",
            "threshold:-1",
            "fixed:5+exp",
            "fixed:5+exp:0",
            "gate:0.4:5@-1",
            "deadline:2000",
            "fixed:5@0ms",
            "fixed:5@xms",
            "fixed:5@3ms+exp:2",
            "ae",
            "ae:5:cap=10",
            "ae:5:cap=-1ms",
            "ae:5:target=2",
            "ae:5:damp=0",
            "ae:5:speed=1",
            "ae:5:10ms",
            "ae:5+exp:2",
            "ae-blur:5",
            "ae-blur:5:cap=10ms",
            "ae-blur:5:-1",
            "ae-imu:5:w=x",
            "ae-imu:5:speed=1",
            "ae-grad:5:target=0.2",
            "ae-grad:5:white=0.1",
            "ae-grad:5+exp:1",
        ] {
            assert!(PolicySpec::parse(s).is_err(), "{s}");
        }
    }
}
