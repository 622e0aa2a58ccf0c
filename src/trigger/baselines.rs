//! The baselines camera users reach for instead of gyro-driven triggering
//! (docs/spec.md section 10): a fixed short exposure with the gain raised
//! (`fixed:FPS@Tms`) and a motion-blind auto-exposure (`ae:FPS:cap=Tms`).
//! Both keep the fixed-rate schedule; neither reads the gyro.
//!
//! Gains are relative to the camera's nominal gain `K_ref` (the one that
//! fills the range with white at the camera's exposure `T_ref`). The sensor's
//! maximum gain is the camera's business, not the policy's: the experiment
//! caps `K_ref * gain` there (see `experiment::map`).

pub use super::ae_params::AeParams;
use super::numbers::parse_pos;
use super::policy::{LogView, Observation, Policy};
use super::rules::Fixed;
use super::timing::CameraTiming;
use crate::error::{Error, Result};

/// `fixed:FPS[@PHASE]@Tms`: the fixed-rate schedule with every frame exposed
/// for `T` (at most the camera's exposure `T_ref`; a longer `T` is clamped
/// to it) and the gain raised by `T_ref / T`, so the image is as bright as at
/// `T_ref` (and as noisy as `T`'s photons make it).
pub struct FixedExposure {
    inner: Fixed,
    exposure_s: f64,
}

impl FixedExposure {
    /// The schedule `fps`/`phase` (s) at exposure `exposure_s` (s).
    pub fn new(spec: &str, fps: f64, phase: f64, exposure_s: f64) -> Self {
        FixedExposure {
            inner: Fixed::new(spec, fps, phase),
            exposure_s,
        }
    }
}

impl Policy for FixedExposure {
    fn label(&self) -> &str {
        self.inner.label()
    }
    fn prepare(&mut self, log: &LogView, timing: &CameraTiming) -> Result<()> {
        self.inner.prepare(log, timing)
    }
    fn decide(&mut self, obs: &Observation) -> bool {
        self.inner.decide(obs)
    }
    fn exposure(&self, obs: &Observation) -> (f64, f64) {
        let t_ref = obs.timing.exposure;
        let te = self.exposure_s.min(t_ref);
        (te, t_ref / te)
    }
}

/// `ae:FPS[:cap=Tms][:target=F][:damp=F][:scene=F]`: a motion-blind
/// auto-exposure on the fixed-rate schedule, as cameras do it. The state is
/// the exposure-times-gain product `P` relative to `T_ref` at the nominal
/// gain (1 at the start). After each frame, its mean level `m = scene * P`
/// (predicted from the scene's mean radiance: the frame's level in the
/// noiseless linear model, before the sensor's gain cap and the full well)
/// moves `P` toward the target: `ln P += damping * ln(target / m)`. The next
/// frame's exposure is `min(P * T_ref, cap)` (exposure first), its gain
/// `P * T_ref / exposure` (then gain; the camera caps it at its maximum).
/// Since the exposure saturates at the cap before any gain is added, the
/// exposures are the same whether or not the camera's gain cap binds.
pub struct AutoExposure {
    inner: Fixed,
    params: AeParams,
    log_p: f64,
}

impl AutoExposure {
    /// The schedule `fps`/`phase` (s) with auto-exposure `params`.
    pub fn new(spec: &str, fps: f64, phase: f64, params: AeParams) -> Self {
        AutoExposure {
            inner: Fixed::new(spec, fps, phase),
            params,
            log_p: 0.0,
        }
    }

    /// The exposure-times-gain product the auto-exposure wants now,
    /// relative to `T_ref` at the nominal gain (1 at the start).
    pub(crate) fn product(&self) -> f64 {
        self.log_p.exp()
    }

    /// The longest exposure it may choose under a camera exposure `t_ref` (s): `min(cap, t_ref)`.
    pub(crate) fn longest(&self, t_ref: f64) -> f64 {
        self.params.cap_s.unwrap_or(t_ref).min(t_ref)
    }

    /// `(exposure s, relative gain)` for the current state.
    pub(crate) fn setting(&self, t_ref: f64) -> (f64, f64) {
        let p = self.log_p.exp();
        let te = (p * t_ref)
            .min(self.params.cap_s.unwrap_or(t_ref))
            .min(t_ref);
        (te, p * t_ref / te)
    }
}

impl Policy for AutoExposure {
    fn label(&self) -> &str {
        self.inner.label()
    }
    fn prepare(&mut self, log: &LogView, timing: &CameraTiming) -> Result<()> {
        self.log_p = 0.0;
        self.inner.prepare(log, timing)
    }
    fn decide(&mut self, obs: &Observation) -> bool {
        let go = self.inner.decide(obs);
        if go && obs.frames > 0 {
            // The previous frame's level corrects the product for this one.
            let level = self.params.scene_mean * self.log_p.exp();
            self.log_p += self.params.damping * (self.params.target / level).ln();
        }
        go
    }
    fn exposure(&self, obs: &Observation) -> (f64, f64) {
        self.setting(obs.timing.exposure)
    }
}

/// Splits `FPS[@PHASE]@Tms` into `FPS[@PHASE]` and the exposure (s); a
/// last `@` part that does not end in `ms` is the phase.
pub(crate) fn split_exposure<'a>(r: &'a str, spec: &str) -> Result<(&'a str, Option<f64>)> {
    match r.rsplit_once('@') {
        Some((head, t)) if t.trim().ends_with("ms") => {
            let ms = parse_pos(t.trim().trim_end_matches("ms"), "exposure (ms)", spec)?;
            Ok((head, Some(ms * 1e-3)))
        }
        _ => Ok((r, None)),
    }
}

/// The `key=value` arguments of `ae:FPS[...]`.
pub(crate) fn parse_ae(keys: &[&str], spec: &str) -> Result<AeParams> {
    let mut p = AeParams::default();
    let unit = |v: &str, what: &str| -> Result<f64> {
        let x = parse_pos(v, what, spec)?;
        if x > 1.0 {
            return Err(Error::invalid(
                "policy",
                format!("'{spec}': {what} must be in (0, 1], got {x}"),
            ));
        }
        Ok(x)
    };
    for kv in keys {
        let Some((k, v)) = kv.split_once('=') else {
            return Err(Error::invalid(
                "policy",
                format!("'{spec}': '{kv}' is not key=value (cap=Tms, target=F, damp=F or scene=F)"),
            ));
        };
        match k.trim() {
            "cap" => {
                let Some(ms) = v.trim().strip_suffix("ms") else {
                    return Err(Error::invalid(
                        "policy",
                        format!("'{spec}': cap '{v}' needs its unit, e.g. cap=10ms"),
                    ));
                };
                p.cap_s = Some(parse_pos(ms, "exposure cap (ms)", spec)? * 1e-3);
            }
            "target" => p.target = unit(v, "target level")?,
            "damp" => p.damping = unit(v, "damping")?,
            "scene" => p.scene_mean = unit(v, "scene mean radiance")?,
            other => {
                return Err(Error::invalid(
                    "policy",
                    format!(
                        "'{spec}': unknown auto-exposure key '{other}' (cap, target, damp, scene)"
                    ),
                ))
            }
        }
    }
    Ok(p)
}

#[cfg(test)]
mod tests {
    use super::*;

    use crate::trigger::{PolicyFamily, PolicySpec};

    fn parse(s: &str) -> PolicySpec {
        PolicySpec::parse(s).unwrap_or_else(|e| panic!("{s}: {e}"))
    }

    #[test]
    fn baselines_and_families() {
        let f = parse("fixed:5@3ms");
        assert_eq!(f.fixed_exposure_s, Some(0.003));
        assert_eq!(f.rate.map(|r| (r.fps, r.phase)), Some((5.0, 0.0)));
        assert_eq!(f.policy_family(), PolicyFamily::FixedExposure);
        assert!(!f.is_baseline());
        let f = parse("fixed:5@0.1@2.5ms");
        assert_eq!(f.fixed_exposure_s, Some(0.0025));
        assert_eq!(f.rate.map(|r| r.phase), Some(0.1));
        assert_eq!(parse("fixed:5@0.1").fixed_exposure_s, None);
        let a = parse("ae:5:cap=10ms:damp=0.25");
        let p = a.ae.unwrap();
        assert_eq!(p.cap_s, Some(0.01));
        assert_eq!((p.damping, p.target), (0.25, AeParams::TARGET));
        assert_eq!(a.policy_family(), PolicyFamily::AutoExposure);
        assert_eq!(parse("ae:5").ae.unwrap().cap_s, None);
        for (s, fam) in [
            ("fixed:5", "fixed"),
            ("fixed:5+exp:2", "gyro-exposure"),
            ("threshold:0.4", "mmbm"),
            ("deadline:5+exp:3:0.02", "mmbm"),
            ("oracle:0.4", "oracle"),
            ("fixed:5@10ms", "fixed-exposure"),
            ("ae:5:cap=3ms", "auto-exposure"),
        ] {
            assert_eq!(parse(s).policy_family().name(), fam, "{s}");
        }
        // The error names what is wrong.
        let e = PolicySpec::parse("ae:5:cap=10").unwrap_err().to_string();
        assert!(e.contains("cap=10ms"), "{e}");
        let e = PolicySpec::parse("ae:5:speed=1").unwrap_err().to_string();
        assert!(e.contains("unknown auto-exposure key 'speed'"), "{e}");
    }

    fn run(p: &mut dyn Policy) -> Vec<crate::trigger::Frame> {
        let t: Vec<f64> = (0..=6000).map(|k| k as f64 / 600.0).collect();
        let m = vec![0.5; t.len()];
        crate::trigger::run(&t, &m, p, &CameraTiming::default()).unwrap()
    }

    #[test]
    fn fixed_exposure_keeps_the_brightness() {
        let f = run(&mut FixedExposure::new("fixed:5@3ms", 5.0, 0.0, 0.003));
        assert_eq!(f.len(), 50);
        for x in &f {
            assert!((x.exposure_s() - 0.003).abs() < 1e-12);
            assert!((x.gain * x.exposure_s() - 0.07).abs() < 1e-12);
        }
        // Longer than the camera's exposure: clamped to it, gain 1.
        let f = run(&mut FixedExposure::new("fixed:5@90ms", 5.0, 0.0, 0.09));
        assert!((f[0].exposure_s() - 0.07).abs() < 1e-12 && f[0].gain == 1.0);
    }

    #[test]
    fn auto_exposure_converges_exposure_first() {
        let p = AeParams {
            cap_s: Some(0.01),
            ..AeParams::default()
        };
        let f = run(&mut AutoExposure::new("ae:5:cap=10ms", 5.0, 0.0, p));
        // The first frame at the camera's brightness (P = 1: the 10 ms cap,
        // gain 7), then toward P = 0.18 / 0.25 = 0.72: the cap, gain 5.04.
        assert!((f[0].exposure_s() - 0.01).abs() < 1e-12 && (f[0].gain - 7.0).abs() < 1e-9);
        let last = f.last().unwrap();
        assert!((last.exposure_s() - 0.01).abs() < 1e-12);
        assert!((last.gain - 0.72 * 7.0).abs() < 1e-6, "{}", last.gain);
        // Damped: the level approaches the target monotonically.
        let levels: Vec<f64> = f
            .iter()
            .map(|x| 0.25 * x.gain * x.exposure_s() / 0.07)
            .collect();
        assert!(levels
            .windows(2)
            .all(|w| w[1] <= w[0] + 1e-12 && w[1] >= 0.18 - 1e-9));
        assert!((levels[1] - 0.25 * (0.72f64).sqrt()).abs() < 1e-9);
        // Without a cap: exposure only, 50.4 ms at gain 1.
        let f = run(&mut AutoExposure::new(
            "ae:5",
            5.0,
            0.0,
            AeParams::default(),
        ));
        let last = f.last().unwrap();
        assert!((last.exposure_s() - 0.0504).abs() < 1e-6 && (last.gain - 1.0).abs() < 1e-9);
    }
}
