//! The gyro-aware exposure controls camera makers and papers use (docs/spec.md
//! section 11, family `gyro-exposure`): fixed rate, the exposure and gain
//! from the gyro. Both wrap the motion-blind auto-exposure of
//! [`AutoExposure`] (same state, same update, same keys) and change only how
//! its exposure-times-gain product is split into exposure and gain.
//!
//! - [`BlurCappedAe`] (`ae-blur:FPS[@PHASE]:B[:ae keys]`): the exposure the
//!   auto-exposure wants, capped where the gyro-predicted blur passes `B` px,
//!   the gain making up the light (FotoNation, US 11,812,146 B2).
//! - [`ImuTradeAe`] (`ae-imu:FPS[@PHASE][:w=W][:w0=W0][:ae keys]`): the
//!   exposure/gain split that minimises predicted blur plus weighted gain
//!   (after Bégin & Hunter, Sensors 22(3):835, 2022).
//!
//! The image speed the gyro predicts is the decision sample's, `v = M / p`
//! px/s ([`Observation::current`] over [`Observation::pitch_mm`]), as for
//! `+exp`. Gains are relative to the camera's nominal gain; the camera caps
//! them at its maximum (then the frame is darker).

pub use super::ae_params::AeVariant;
use super::baselines::{AeParams, AutoExposure};
use super::numbers::parse_pos;
use super::policy::{LogView, Observation, Policy};
use super::timing::CameraTiming;
use crate::error::{Error, Result};

/// The image speed the gyro predicts at the decision sample, px/s (0 when
/// the sample is still or the pitch is not positive).
fn image_speed_px_s(obs: &Observation) -> f64 {
    let (m, p) = (obs.current(), obs.pitch_mm);
    if m > 0.0 && p > 0.0 && m.is_finite() {
        m / p
    } else {
        0.0
    }
}

/// `ae-blur:FPS[@PHASE]:B[:cap=Tms][:target=F][:damp=F][:scene=F]`: the
/// auto-exposure of [`AutoExposure`] chooses `(T0, K0)`; the gyro predicts
/// the blur of an exposure `T` as `b(T) = v T` px; when `b(T0) > B` the frame
/// is exposed for `T = T0 B / b(T0)` (so `b(T) = B`) with gain `K0 T0 / T`
/// (the same product). The auto-exposure's state is not touched: it keeps
/// predicting the level from the product, which the cap keeps.
pub struct BlurCappedAe {
    ae: AutoExposure,
    budget_px: f64,
}

impl BlurCappedAe {
    /// The schedule `fps`/`phase` (s), auto-exposure `params`, blur budget `budget_px` (px).
    pub fn new(spec: &str, fps: f64, phase: f64, params: AeParams, budget_px: f64) -> Self {
        BlurCappedAe {
            ae: AutoExposure::new(spec, fps, phase, params),
            budget_px,
        }
    }
}

impl Policy for BlurCappedAe {
    fn label(&self) -> &str {
        self.ae.label()
    }
    fn prepare(&mut self, log: &LogView, timing: &CameraTiming) -> Result<()> {
        self.ae.prepare(log, timing)
    }
    fn decide(&mut self, obs: &Observation) -> bool {
        self.ae.decide(obs)
    }
    fn exposure(&self, obs: &Observation) -> (f64, f64) {
        let (t0, k0) = self.ae.setting(obs.timing.exposure);
        let b0 = image_speed_px_s(obs) * t0;
        if b0 > self.budget_px {
            let t = t0 * self.budget_px / b0;
            (t, k0 * t0 / t)
        } else {
            (t0, k0)
        }
    }
}

/// `ae-imu:FPS[@PHASE][:w=W][:w0=W0][:cap=Tms][:target=F][:damp=F][:scene=F]`:
/// the auto-exposure of [`AutoExposure`] wants the product `c = T K` (s at
/// the nominal gain); the exposure and gain minimise `v T + w (K - 1)`
/// subject to `T K = c`, i.e. `K = sqrt((v c + w0) / w)` (`w0 = 0` is the
/// exact minimiser), clamped to `K >= max(1, c / T_max)` (`T_max` the
/// auto-exposure's longest exposure), and `T = c / K`. Still (`v = 0`,
/// `w0 = 0`) it is the auto-exposure itself.
pub struct ImuTradeAe {
    ae: AutoExposure,
    weight_px: f64,
    offset_px: f64,
}

impl ImuTradeAe {
    /// The schedule `fps`/`phase` (s), auto-exposure `params`, weights `w`, `w0` (px).
    pub fn new(
        spec: &str,
        fps: f64,
        phase: f64,
        params: AeParams,
        weight_px: f64,
        offset_px: f64,
    ) -> Self {
        ImuTradeAe {
            ae: AutoExposure::new(spec, fps, phase, params),
            weight_px,
            offset_px,
        }
    }
}

impl Policy for ImuTradeAe {
    fn label(&self) -> &str {
        self.ae.label()
    }
    fn prepare(&mut self, log: &LogView, timing: &CameraTiming) -> Result<()> {
        self.ae.prepare(log, timing)
    }
    fn decide(&mut self, obs: &Observation) -> bool {
        self.ae.decide(obs)
    }
    fn exposure(&self, obs: &Observation) -> (f64, f64) {
        let t_ref = obs.timing.exposure;
        let c = self.ae.product() * t_ref;
        let t_max = self.ae.longest(t_ref);
        let v = image_speed_px_s(obs);
        let k = ((v * c + self.offset_px) / self.weight_px)
            .sqrt()
            .max(1.0)
            .max(c / t_max);
        (c / k, k)
    }
}

/// The variant's own `(key, value)` pairs and the auto-exposure's `key=value` arguments.
type SplitKeys<'a> = (Vec<(&'a str, &'a str)>, Vec<&'a str>);

/// Splits the `ae-*` keys into the variant's own (`own`, e.g. `w`, `w0`) and
/// the auto-exposure's; refuses the auto-exposure keys in `refused` (keys
/// the variant does not use), naming them.
pub(crate) fn split_keys<'a>(
    keys: &[&'a str],
    own: &[&str],
    refused: &[&str],
    spec: &str,
) -> Result<SplitKeys<'a>> {
    let (mut mine, mut rest) = (Vec::new(), Vec::new());
    for kv in keys {
        match kv.split_once('=') {
            Some((k, v)) if own.contains(&k.trim()) => mine.push((k.trim(), v)),
            Some((k, _)) if refused.contains(&k.trim()) => {
                return Err(Error::invalid(
                    "policy",
                    format!("'{spec}': key '{}' does not apply to this policy", k.trim()),
                ))
            }
            _ => rest.push(*kv),
        }
    }
    Ok((mine, rest))
}

/// The `w=W` / `w0=W0` keys of `ae-imu` (px; `w > 0`, `w0 >= 0`).
pub(crate) fn parse_imu(own: &[(&str, &str)], spec: &str) -> Result<AeVariant> {
    let (mut w, mut w0) = (AeVariant::IMU_WEIGHT_PX, AeVariant::IMU_OFFSET_PX);
    for &(k, v) in own {
        if k == "w" {
            w = parse_pos(v, "gain weight w (px)", spec)?;
        } else {
            let x: f64 = v.trim().parse().unwrap_or(f64::NAN);
            if !(x.is_finite() && x >= 0.0) {
                return Err(Error::invalid(
                    "policy",
                    format!("'{spec}': w0 must be a number >= 0 (px), got '{v}'"),
                ));
            }
            w0 = x;
        }
    }
    Ok(AeVariant::ImuTrade {
        weight_px: w,
        offset_px: w0,
    })
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trigger::{PolicyFamily, PolicySpec};

    /// 10 s at 600 Hz, MMBM `m` mm/s throughout, on the thesis camera
    /// (70 ms, 4.65 um pitch).
    fn run(spec: &str, m: f64) -> Vec<crate::trigger::Frame> {
        let t: Vec<f64> = (0..=6000).map(|k| k as f64 / 600.0).collect();
        let mm = vec![m; t.len()];
        let mut p = PolicySpec::parse(spec).unwrap().build().unwrap();
        crate::trigger::run(&t, &mm, p.as_mut(), &CameraTiming::default()).unwrap()
    }

    #[test]
    fn blur_cap_by_hand() {
        // 0.5 mm/s on 4.65 um pixels: v = 107.53 px/s; a 1 px budget allows
        // 4.65e-3 / 0.5 = 9.3 ms. The auto-exposure (no cap) starts at
        // 70 ms (gain 1) and settles at 0.72 x 70 = 50.4 ms: both capped
        // to 9.3 ms, the gain keeping the product.
        let f = run("ae-blur:5:1", 0.5);
        assert_eq!(f.len(), 50);
        assert!((f[0].exposure_s() - 0.0093).abs() < 1e-12);
        assert!((f[0].gain - 0.07 / 0.0093).abs() < 1e-9);
        let last = f.last().unwrap();
        assert!((last.exposure_s() - 0.0093).abs() < 1e-12);
        assert!((last.gain - 0.0504 / 0.0093).abs() < 1e-6, "{}", last.gain);
        // Within budget (0.05 mm/s: 50.4 ms is 0.54 px): the auto-exposure's own.
        let last = run("ae-blur:5:1", 0.05).pop().unwrap();
        assert!((last.exposure_s() - 0.0504).abs() < 1e-6 && (last.gain - 1.0).abs() < 1e-9);
        // Still: the auto-exposure's.
        let last = run("ae-blur:5:1:cap=10ms", 0.0).pop().unwrap();
        assert!((last.exposure_s() - 0.01).abs() < 1e-12 && (last.gain - 5.04).abs() < 1e-6);
    }

    #[test]
    fn imu_trade_by_hand() {
        // v = 0.5 / 4.65e-3 = 107.53 px/s, settled c = 50.4 ms, w = 0.1 px:
        // K = sqrt(107.53 * 0.0504 / 0.1) = 7.3616, T = 0.0504 / K = 6.846 ms.
        let v = 0.5 / 0.00465;
        let k = (v * 0.0504 / 0.1f64).sqrt();
        let last = run("ae-imu:5", 0.5).pop().unwrap();
        assert!((k - 7.3616).abs() < 1e-4);
        assert!((last.gain - k).abs() < 1e-5, "{} vs {k}", last.gain);
        assert!((last.exposure_s() - 0.0504 / k).abs() < 1e-8);
        // w0 adds to v c: w = 1, w0 = 10 -> K = sqrt(5.4194 + 10) = 3.9268.
        let k = (v * 0.0504 + 10.0f64).sqrt();
        let last = run("ae-imu:5:w=1:w0=10", 0.5).pop().unwrap();
        assert!((last.gain - k).abs() < 1e-5, "{} vs {k}", last.gain);
        // Still: the auto-exposure (gain 1, 50.4 ms) ...
        let last = run("ae-imu:5", 0.0).pop().unwrap();
        assert!((last.exposure_s() - 0.0504).abs() < 1e-6 && (last.gain - 1.0).abs() < 1e-9);
        // ... and with its cap: K = c / cap = 5.04.
        let last = run("ae-imu:5:cap=10ms", 0.0).pop().unwrap();
        assert!((last.exposure_s() - 0.01).abs() < 1e-9 && (last.gain - 5.04).abs() < 1e-6);
    }

    #[test]
    fn families_and_refusals() {
        for (s, fam) in [
            ("ae-blur:5:1", PolicyFamily::GyroExposure),
            ("ae-imu:5:w=0.5", PolicyFamily::GyroExposure),
            ("ae-grad:5", PolicyFamily::AutoExposure),
            ("fixed:5+exp:2", PolicyFamily::GyroExposure),
            ("deadline:5+exp:2", PolicyFamily::Mmbm),
            ("fixed:5", PolicyFamily::Fixed),
        ] {
            assert_eq!(PolicySpec::parse(s).unwrap().policy_family(), fam, "{s}");
        }
        for (s, says) in [
            ("ae-blur:5", "blur budget"),
            ("ae-blur:5:0", "blur budget"),
            ("ae-blur:5:1+exp:2", "+exp does not apply"),
            ("ae-imu:5:w=0", "gain weight"),
            ("ae-imu:5:w0=-1", "w0 must be"),
            ("ae-imu:5:w=1:w=2", "given twice"),
            ("ae-grad:5:white=2", "white"),
            ("ae-grad:5:damp=0.5", "'damp' does not apply"),
        ] {
            let e = PolicySpec::parse(s).unwrap_err().to_string();
            assert!(e.contains(says), "{s}: {e}");
        }
    }
}
