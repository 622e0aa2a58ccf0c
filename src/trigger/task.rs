//! `task:FPS:light=E[:read=E][:tmin=Tms]`: the exposure and the trigger
//! instant that maximise the predicted probability that a frame is sharp
//! (all blobs found), from the blur the gyro predicts and the signal-to-noise
//! ratio the light gives (docs/spec.md section 10; the EMVA 1288 model of
//! `camera::noise`).

use super::numbers::parse_pos;
use super::policy::{rate_slot, LogView, Observation, Policy};
pub use super::task_model::TaskModel;
use super::timing::CameraTiming;
use crate::error::{Error, Result};

impl TaskModel {
    /// What the model predicts for a run's kept `frames` on pixels of
    /// `pitch_mm` (mm): each frame's white-pixel SNR from its exposure
    /// ([`Self::snr`]; the gain does not add photons) and its probability of
    /// being sharp from its blur over the exposure (exposure MMBM / pitch x
    /// exposure, px) and that SNR ([`Self::p_sharp`]). The camera's gain cap
    /// is not modelled (where it binds, frames are darker than predicted).
    pub fn predict(&self, frames: &[super::timing::Frame], pitch_mm: f64) -> Prediction {
        let mut p = Prediction {
            kept: 0,
            mean_snr: f64::NAN,
            min_snr: f64::NAN,
            sharp: 0.0,
        };
        let mut snr_sum = 0.0;
        for f in frames.iter().filter(|f| f.kept) {
            let te = f.exposure_s();
            let snr = self.snr(te);
            let blur = crate::camera::blur_px(f.mmbm_exposure_mm_s, te, pitch_mm);
            p.kept += 1;
            snr_sum += snr;
            p.min_snr = if p.min_snr.is_nan() {
                snr
            } else {
                p.min_snr.min(snr)
            };
            p.sharp += self.p_sharp(blur, te);
        }
        if p.kept > 0 {
            p.mean_snr = snr_sum / p.kept as f64;
        }
        p
    }
}

/// [`TaskModel::predict`]'s answer for one run.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct Prediction {
    /// Kept frames.
    pub kept: usize,
    /// Mean white-pixel SNR over the kept frames (NaN without frames).
    pub mean_snr: f64,
    /// Lowest white-pixel SNR (NaN without frames).
    pub min_snr: f64,
    /// Expected sharp frames: the sum of the kept frames' probabilities.
    pub sharp: f64,
}

/// `task:FPS:light=E[:read=E][:tmin=Tms]`: one frame per slot of the fixed
/// rate, like `deadline:FPS` (observe the first `1/e` of the slot, then take
/// the first sample whose predicted success beats the best observed, or the
/// slot's last one), scored by the highest predicted probability over the
/// exposures ([`TaskModel::best`]) at the decision sample's MMBM; the frame
/// is exposed for that exposure with the gain raised by `T / t_e`.
pub struct Task {
    spec: String,
    fps: f64,
    model: TaskModel,
    slot: i64,
    taken: bool,
    obs_max: f64,
}

impl Task {
    /// One frame per slot at `fps` with the success model `model`.
    pub fn new(spec: &str, fps: f64, model: TaskModel) -> Self {
        Task {
            spec: spec.to_string(),
            fps,
            model,
            slot: -1,
            taken: false,
            obs_max: f64::NEG_INFINITY,
        }
    }
}

impl Policy for Task {
    fn label(&self) -> &str {
        &self.spec
    }
    fn prepare(&mut self, _log: &LogView, _timing: &CameraTiming) -> Result<()> {
        self.slot = -1;
        self.taken = false;
        self.obs_max = f64::NEG_INFINITY;
        Ok(())
    }
    fn decide(&mut self, obs: &Observation) -> bool {
        let (t0, now) = (obs.t0, obs.now());
        let period = 1.0 / self.fps;
        let (slot, start) = rate_slot(t0, self.fps, now);
        if slot != self.slot {
            self.slot = slot;
            self.taken = false;
            self.obs_max = f64::NEG_INFINITY;
        }
        let score = self
            .model
            .best(obs.current(), obs.timing.exposure, obs.pitch_mm)
            .1;
        let observing = now < start + period / std::f64::consts::E;
        if observing {
            self.obs_max = self.obs_max.max(score);
        }
        if self.taken || !obs.camera_free {
            return false;
        }
        let dt = obs.previous_time().map_or(0.0, |p| now - p);
        let deadline = now + 1.5 * dt >= start + period;
        if (!observing && score > self.obs_max) || deadline {
            self.taken = true;
            return true;
        }
        false
    }
    fn exposure(&self, obs: &Observation) -> (f64, f64) {
        let t_ref = obs.timing.exposure;
        let te = self.model.best(obs.current(), t_ref, obs.pitch_mm).0;
        (te, t_ref / te)
    }
}

/// The `key=value` arguments of `task:FPS:...` (`light` required).
pub(crate) fn parse_task(keys: &[&str], spec: &str) -> Result<TaskModel> {
    let mut light = None;
    let mut m = TaskModel::at_light(1.0);
    for kv in keys {
        let Some((k, v)) = kv.split_once('=') else {
            return Err(Error::invalid(
                "policy",
                format!("'{spec}': '{kv}' is not key=value (light=E, read=E or tmin=Tms)"),
            ));
        };
        match k.trim() {
            "light" => {
                let l = parse_pos(v, "light (e-/s)", spec)?;
                if l > crate::limits::MAX_LIGHT_E_PER_S {
                    return Err(Error::invalid(
                        "policy",
                        format!(
                            "'{spec}': light {l:e} e-/s is above the cap of {:e} e-/s",
                            crate::limits::MAX_LIGHT_E_PER_S
                        ),
                    ));
                }
                light = Some(l);
            }
            "read" => m.read_noise_e = parse_pos(v, "read noise (e-)", spec)?,
            "tmin" => {
                let Some(ms) = v.trim().strip_suffix("ms") else {
                    return Err(Error::invalid(
                        "policy",
                        format!("'{spec}': tmin '{v}' needs its unit, e.g. tmin=0.5ms"),
                    ));
                };
                m.min_exposure_s = parse_pos(ms, "shortest exposure (ms)", spec)? * 1e-3;
            }
            other => {
                return Err(Error::invalid(
                    "policy",
                    format!("'{spec}': unknown task key '{other}' (light, read, tmin)"),
                ))
            }
        }
    }
    let Some(light) = light else {
        return Err(Error::invalid(
            "policy",
            format!("'{spec}': the light must be stated, e.g. task:5:light=20000 (e-/s for a white pixel)"),
        ));
    };
    m.light_e_per_s = light;
    Ok(m)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trigger::{run, Family, PolicyFamily, PolicySpec};

    #[test]
    fn model_trades_blur_against_noise() {
        let m = TaskModel::at_light(1000.0);
        // More light or less blur: more likely sharp.
        assert!(m.p_sharp(2.0, 0.05) > m.p_sharp(12.0, 0.05));
        assert!(TaskModel::at_light(20_000.0).p_sharp(2.0, 0.005) > m.p_sharp(2.0, 0.005));
        // Still camera: the longest exposure (the most photons) wins.
        assert_eq!(m.best(0.0, 0.07, 0.00465).0, 0.07);
        // Fast motion in dim light: a shorter exposure, but not the shortest.
        let (te, p) = m.best(1.0, 0.07, 0.00465);
        assert!(te < 0.07 && te > 0.001, "{te}");
        assert!(p > m.p_sharp(crate::camera::blur_px(1.0, 0.07, 0.00465), 0.07));
        // Bright light: shorter than in dim light at the same motion.
        assert!(TaskModel::at_light(100_000.0).best(1.0, 0.07, 0.00465).0 < te);
    }

    #[test]
    fn parse_round_trip_and_errors() {
        let p = PolicySpec::parse("task:5:light=1000:read=3:tmin=0.5ms").unwrap();
        assert_eq!(p.family, Family::Task);
        assert_eq!(p.policy_family(), PolicyFamily::Mmbm);
        assert_eq!(p.rate.map(|r| r.fps), Some(5.0));
        let t = p.task.unwrap();
        assert_eq!(
            (t.light_e_per_s, t.read_noise_e, t.min_exposure_s),
            (1000.0, 3.0, 0.0005)
        );
        assert_eq!(p.to_string(), "task:5:light=1000:read=3:tmin=0.5ms");
        assert_eq!(p.build().unwrap().spec(), p);
        assert_eq!(PolicySpec::parse(p.as_str()).unwrap(), p);
        for (s, needle) in [
            ("task:5", "light must be stated"),
            ("task:5:light=0", "must be > 0"),
            ("task:5:light=1000:tmin=1", "needs its unit"),
            ("task:5:lux=3", "unknown task key 'lux'"),
            ("task:5:1000", "not key=value"),
            ("task:5:light=1000+exp:2", "+exp does not apply"),
        ] {
            let e = PolicySpec::parse(s).unwrap_err().to_string();
            assert!(e.contains(needle), "{s}: {e}");
        }
    }

    #[test]
    fn one_frame_per_slot_at_the_quiet_instant() {
        // 600 Hz, 10 s: MMBM 2 mm/s except a quiet 30 ms dip (0.05 mm/s) in
        // the second half of every 0.2-s slot.
        let t: Vec<f64> = (0..6000).map(|k| k as f64 / 600.0).collect();
        let m: Vec<f64> = t
            .iter()
            .map(|&x| {
                let s = (x * 5.0).fract();
                if (0.6..0.75).contains(&s) {
                    0.05
                } else {
                    2.0
                }
            })
            .collect();
        let spec = PolicySpec::parse("task:5:light=1000").unwrap();
        let mut p = spec.build().unwrap();
        let f = run(&t, &m, p.as_mut(), &CameraTiming::default()).unwrap();
        assert!(f.len() >= 45, "{}", f.len());
        let quiet = f.iter().filter(|x| x.mmbm_trigger_mm_s < 0.1).count();
        assert!(quiet + 2 >= f.len(), "{quiet} of {}", f.len());
        // Quiet and dim: exposures past the SNR cliff (16 e- at 1000 e-/s),
        // far above the shortest; each frame's gain keeps the brightness.
        let model = TaskModel::at_light(1000.0);
        for x in f.iter().filter(|x| x.mmbm_trigger_mm_s < 0.1) {
            assert!(x.exposure_s() > 0.016, "{x:?}");
            assert!(model.snr(x.exposure_s()) > 1.1 * model.s50, "{x:?}");
            assert!((x.gain * x.exposure_s() - 0.07).abs() < 1e-9);
        }
    }
}
