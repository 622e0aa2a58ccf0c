//! The runner: a policy over a whole log, enforcing the camera's timing.

use super::policy::{LogView, Observation, Policy};
use super::timing::{CameraTiming, Frame, Integral};
use crate::error::{Error, Result};
use crate::model::log::{check_resolution, check_times, max_abs_time, Timed};

/// Runs `policy` over a log: `mmbm_mm_s[i]` is the MMBM at the time of
/// `samples[i]` (gyro samples, or bare times in s: only the times are used).
/// The policy sees, at each sample, only the samples up to it (the oracle
/// also gets the whole log in [`Policy::prepare`]). Returns the frames in
/// time order. Pixel budgets use the timing's pitch ([`run_px`] with the
/// samples' px/s for cameras whose pixels are not square).
pub fn run<S: Timed>(
    samples: &[S],
    mmbm_mm_s: &[f64],
    policy: &mut dyn Policy,
    timing: &CameraTiming,
) -> Result<Vec<Frame>> {
    run_px(samples, mmbm_mm_s, None, policy, timing)
}

/// [`run`] with the samples' MMBM in px/s too (the true pixel speed,
/// `Mmbm::px_s`): pixel budgets then convert each decision sample's mm/s
/// with its own mm per px ([`Observation::pitch_mm`]).
pub fn run_px<S: Timed>(
    samples: &[S],
    mmbm_mm_s: &[f64],
    px_s: Option<&[f64]>,
    policy: &mut dyn Policy,
    timing: &CameraTiming,
) -> Result<Vec<Frame>> {
    timing.validate()?;
    if let Some(px) = px_s.filter(|p| p.len() != mmbm_mm_s.len()) {
        return Err(Error::invalid(
            "mmbm series",
            format!(
                "{} px/s values for {} mm/s values",
                px.len(),
                mmbm_mm_s.len()
            ),
        ));
    }
    if samples.len() != mmbm_mm_s.len() {
        return Err(Error::invalid(
            "mmbm series",
            format!(
                "{} values for {} gyro samples",
                mmbm_mm_s.len(),
                samples.len()
            ),
        ));
    }
    if samples.is_empty() {
        return Err(Error::invalid("gyro log", "no samples"));
    }
    check_times(samples, "gyro log")?;
    let t_max = max_abs_time(samples);
    check_resolution(t_max, timing.exposure, "the exposure")?;
    check_resolution(t_max, timing.delay, "the trigger delay")?;
    let t: Vec<f64> = samples.iter().map(Timed::time).collect();
    for i in 0..t.len() {
        let m = mmbm_mm_s[i];
        if !(m.is_finite() && m >= 0.0) {
            return Err(Error::invalid(
                "mmbm series",
                format!(
                    "value {m} at sample {i} (t = {}) is not a finite number >= 0",
                    t[i]
                ),
            ));
        }
    }
    policy.prepare(
        &LogView {
            t: &t,
            mmbm: mmbm_mm_s,
        },
        timing,
    )?;
    let integral = Integral::new(&t, mmbm_mm_s);
    let t_last = t[t.len() - 1];
    let mut frames = Vec::new();
    let mut free_at = f64::NEG_INFINITY;
    let mut last_trigger = None;
    for i in 0..t.len() {
        // A stop request (crate::cancel) is seen every 4096 samples.
        if i % 4096 == 0 {
            crate::cancel::check()?;
        }
        let start = t[i] + timing.delay;
        let end = start + timing.exposure;
        if end > t_last {
            break;
        }
        let camera_free = start >= free_at;
        let obs = Observation {
            i,
            t0: t[0],
            t: &t[..=i],
            mmbm: &mmbm_mm_s[..=i],
            camera_free,
            last_trigger,
            frames: frames.len(),
            timing,
            pitch_mm: px_s.map_or(timing.pitch_mm, |px| {
                pixel_pitch(mmbm_mm_s[i], px[i], timing.pitch_mm)
            }),
        };
        if policy.decide(&obs) && camera_free {
            let (te, gain) = policy.exposure(&obs);
            let end = start + te;
            let mut f = Frame {
                policy: policy.spec(),
                index: i,
                trigger_t: t[i],
                exposure_start: start,
                exposure_end: end,
                mmbm_trigger_mm_s: mmbm_mm_s[i],
                mmbm_exposure_mm_s: integral.mean(start, end),
                kept: true,
                gain,
            };
            f.kept = policy.keep(&f);
            frames.push(f);
            free_at = end + timing.readout;
            last_trigger = Some(t[i]);
        }
    }
    Ok(frames)
}

/// Millimetres per pixel of a sample's motion: `mm_s / px_s`, or `pitch`
/// where that is not a positive finite number (a still sample).
pub fn pixel_pitch(mm_s: f64, px_s: f64, pitch: f64) -> f64 {
    let p = mm_s / px_s;
    if p.is_finite() && p > 0.0 {
        p
    } else {
        pitch
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trigger::{Family, PolicyFamily, PolicySpec};

    /// A 20 s log at 200 Hz whose MMBM swings between 0.1 and 0.9 mm/s at
    /// 1.8 Hz (a walk's rhythm): every family triggers on it.
    fn log() -> (Vec<f64>, Vec<f64>) {
        let t: Vec<f64> = (0..4000).map(|i| i as f64 / 200.0).collect();
        let m = t
            .iter()
            .map(|&t| 0.5 + 0.4 * (std::f64::consts::TAU * 1.8 * t).sin())
            .collect();
        (t, m)
    }

    /// Every frame carries the spec its policy was built from, typed: for
    /// every family the frames' spec equals the spec built, field for field,
    /// and its family and benefit-map family are the spec's own (no string
    /// parsed back).
    #[test]
    fn frames_carry_the_spec_they_were_built_from() {
        let (t, m) = log();
        let timing = CameraTiming::default();
        for s in [
            "fixed:5@0.1",
            "fixed:5@3ms",
            "fixed:5+exp:0.5",
            "ae:5:cap=10ms",
            "ae-blur:5:1",
            "ae-imu:5:w=0.5",
            "ae-grad:5",
            "threshold:0.4",
            "adaptive:p30:3",
            "oracle:0.4",
            "forecast:0.4",
            "phase:0.6",
            "gate:0.5",
            "gate0:0.5:4",
            "deadline:5:0.3",
            "task:5:light=1000",
        ] {
            let spec = PolicySpec::parse(s).unwrap();
            let frames = run(&t, &m, spec.build().unwrap().as_mut(), &timing).unwrap();
            assert!(!frames.is_empty(), "{s}: no frames");
            for f in &frames {
                assert_eq!(f.policy, spec, "{s}");
                assert_eq!(f.policy.family, spec.family, "{s}");
                assert_eq!(f.policy.policy_family(), spec.policy_family(), "{s}");
                assert_eq!(f.policy.to_string(), s);
            }
        }
    }

    /// A user's own policy: its frames carry a custom spec of its label,
    /// written unchanged, in family `custom`; the spec cannot be built.
    #[test]
    fn a_custom_policy_keeps_its_label() {
        struct Every(usize);
        impl Policy for Every {
            fn label(&self) -> &str {
                "every:40 samples"
            }
            fn prepare(&mut self, _: &LogView, _: &CameraTiming) -> Result<()> {
                Ok(())
            }
            fn decide(&mut self, obs: &Observation) -> bool {
                obs.i % self.0 == 0
            }
        }
        let (t, m) = log();
        let frames = run(&t, &m, &mut Every(40), &CameraTiming::default()).unwrap();
        assert!(!frames.is_empty());
        for f in &frames {
            assert_eq!(f.policy, PolicySpec::custom("every:40 samples"));
            assert_eq!(f.policy.family, Family::Custom);
            assert_eq!(f.policy.policy_family(), PolicyFamily::Custom);
            assert_eq!(f.policy.to_string(), "every:40 samples");
        }
        let e = frames[0].policy.build().err().unwrap().to_string();
        assert!(e.contains("'every:40 samples' is a custom policy"), "{e}");
        assert!(PolicySpec::parse("custom").is_err());
    }
}
