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
/// predicts for the next instants), `p` the pixel pitch (mm; with pixels not
/// square, the decision sample's mm per px of its true pixel speed,
/// [`Observation::pitch_mm`], so `M / p` is its px/s), `B` the blur
/// budget (px), `T` the camera's exposure and `TMIN` the shortest exposure
/// (s, default 1 ms). The gain is raised by `T / t_e`, so the image is as
/// bright as at `T`, and as noisy as `t_e`'s photons make it (the sensor noise
/// model sees both). With `M = 0` the exposure is `T`.
///
/// A policy with a forecast of its own ([`Policy::forecast_exposure_mmbm`]:
/// `phase`) predicts the MMBM over the coming exposure instead: the exposure
/// is the longest of [`Exposure::STEPS`] log-spaced ones from `T` down to
/// `TMIN` whose forecast blur `Ê(t_e) t_e / p` stays within `B` (`p` the
/// decision sample's, as above; `TMIN`
/// when none does; the decision sample's rule while the forecast is not
/// ready).
///
/// E.g. `fixed:5+exp:2` keeps the fixed rate with at most ~2 px of predicted
/// blur per frame; `phase:0.4+exp:2` combines it with trigger timing and the
/// learned phase forecast.
pub struct Exposure {
    spec: String,
    inner: Box<dyn Policy>,
    budget_px: f64,
    min_exposure: f64,
}

impl Exposure {
    /// Shortest exposure when none is given, s.
    pub const MIN_EXPOSURE: f64 = 0.001;
    /// Exposures tried on a forecast, log-spaced from the longest to the shortest.
    pub const STEPS: usize = 24;

    /// Wraps `inner` with a blur budget `budget_px` (px) and a shortest exposure `min_exposure` (s).
    pub fn new(spec: &str, inner: Box<dyn Policy>, budget_px: f64, min_exposure: f64) -> Self {
        Exposure {
            spec: spec.to_string(),
            inner,
            budget_px,
            min_exposure,
        }
    }

    /// The exposure (s) for a blur speed `m` (mm/s) on pixels of `pitch_mm`
    /// (mm per px of the motion) under `timing`.
    pub fn exposure_for(&self, m: f64, pitch_mm: f64, timing: &CameraTiming) -> f64 {
        let t_max = timing.exposure;
        if m > 0.0 {
            crate::camera::exposure_for_blur(self.budget_px, m, pitch_mm)
                .clamp(self.min_exposure.min(t_max), t_max)
        } else {
            t_max
        }
    }
}

impl Exposure {
    /// The exposure (s) from the inner policy's forecast, at most `t_max`;
    /// `None` when it has none now.
    fn forecast_exposure_s(&self, obs: &Observation, t_max: f64) -> Option<f64> {
        let t_min = self.min_exposure.min(t_max);
        let pitch = obs.pitch_mm;
        let mut ready = false;
        for k in 0..Self::STEPS {
            let te = t_max * (t_min / t_max).powf(k as f64 / (Self::STEPS - 1) as f64);
            let Some(m) = self.inner.forecast_exposure_mmbm(obs, te) else {
                if ready {
                    continue;
                }
                return None;
            };
            ready = true;
            if m.is_finite() && crate::camera::blur_px(m, te, pitch) <= self.budget_px {
                return Some(te);
            }
        }
        Some(t_min)
    }
}

impl Policy for Exposure {
    fn label(&self) -> &str {
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
    fn forecast_exposure_mmbm(&self, obs: &Observation, exposure_s: f64) -> Option<f64> {
        self.inner.forecast_exposure_mmbm(obs, exposure_s)
    }
    fn exposure(&self, obs: &Observation) -> (f64, f64) {
        let (t_inner, gain_inner) = self.inner.exposure(obs);
        let te = match self.forecast_exposure_s(obs, t_inner) {
            Some(te) => te,
            None => self
                .exposure_for(obs.current(), obs.pitch_mm, obs.timing)
                .min(t_inner),
        };
        (te, gain_inner * t_inner / te)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trigger::{parse_policy, run, Fixed};

    /// `fixed:5` that forecasts 0.1 mm/s over exposures up to 20 ms and
    /// 1 mm/s over longer ones (a transient due 20 ms after the start).
    struct Foreseeing(Fixed);
    impl Policy for Foreseeing {
        fn label(&self) -> &str {
            self.0.label()
        }
        fn prepare(&mut self, log: &LogView, timing: &CameraTiming) -> Result<()> {
            self.0.prepare(log, timing)
        }
        fn decide(&mut self, obs: &Observation) -> bool {
            self.0.decide(obs)
        }
        fn forecast_exposure_mmbm(&self, _obs: &Observation, te: f64) -> Option<f64> {
            Some(if te <= 0.02 { 0.1 } else { 1.0 })
        }
    }

    #[test]
    fn exposure_follows_the_forecast_over_the_exposure() {
        let t: Vec<f64> = (0..=1200).map(|k| k as f64 / 600.0).collect();
        let m = vec![0.1; t.len()];
        let timing = CameraTiming::default();
        // At the decision sample alone (0.1 mm/s) 3 px allow the full 70 ms.
        let mut plain = parse_policy("fixed:5+exp:3").unwrap();
        let f = run(&t, &m, plain.as_mut(), &timing).unwrap();
        assert!(f.iter().all(|x| (x.exposure_s() - 0.07).abs() < 1e-12));
        // The forecast says the last 50 ms are shaken: at most 20 ms, the
        // longest step of the grid within it (and within 3 px at 0.1 mm/s).
        let inner = Box::new(Foreseeing(Fixed::new("fixed:5", 5.0, 0.0)));
        let mut p = Exposure::new("x", inner, 3.0, Exposure::MIN_EXPOSURE);
        let f = run(&t, &m, &mut p, &timing).unwrap();
        assert!(!f.is_empty());
        for x in &f {
            let te = x.exposure_s();
            assert!(te <= 0.02 + 1e-12 && te > 0.02 * 0.8, "{te}");
            assert!((x.gain * te - 0.07).abs() < 1e-12);
        }
        // A forecast blur over budget at every exposure: the shortest.
        let inner = Box::new(Foreseeing(Fixed::new("fixed:5", 5.0, 0.0)));
        let mut p = Exposure::new("x", inner, 0.01, 0.002);
        let f = run(&t, &m, &mut p, &timing).unwrap();
        assert!(f.iter().all(|x| (x.exposure_s() - 0.002).abs() < 1e-12));
    }
}
