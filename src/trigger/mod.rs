//! Camera trigger policies driven by the MMBM of a gyro log (SPEC section 6,
//! thesis chapters 5-6).
//!
//! # Timing model (thesis Fig. 5.1)
//!
//! A decision is made at a gyro sample `t_i` (the `trigger_t` of a frame).
//! The trigger pulse reaches the camera after the delay `t_d`; the exposure
//! runs over `[t_i + t_d, t_i + t_d + t_e]`; the readout `t_r` follows, after
//! which the camera is free again. A pulse is accepted only when the camera is
//! free at its arrival (`t_i + t_d >= previous exposure end + t_r`); the runner
//! enforces this for every policy. The minimum interval between triggers
//! (default 0.2 s, the thesis's fair comparison with 5 fps) is part of the
//! MMBM-triggered policies' rules (`threshold`, `adaptive`, `oracle`,
//! `forecast`), not of the schedules (`fixed`, `gate`, `deadline`), whose own
//! period spaces the frames. The run stops at the last sample whose exposure
//! still ends inside the log.
//!
//! # Exposure MMBM
//!
//! `mmbm_exposure_mm_s` is the time average over the exposure of the MMBM
//! series linearly interpolated between samples (held constant outside the
//! log), the quantity the instantaneous MMBM at the trigger tries to predict
//! (thesis section 5.2, Table 5.1). It is computed from a prefix integral, so
//! each frame costs two binary searches.
//!
//! # Policies
//!
//! Parsed by [`parse_policy`]; every threshold `X` may be a number (mm/s) or
//! `pNN`, the NN-th percentile (0..100, linear interpolation between order
//! statistics) of the whole log's MMBM series, resolved once before the run:
//! an offline calibration, like choosing the number by looking at the data;
//! the decision rule itself stays causal.
//!
//! | policy | rule |
//! |---|---|
//! | `fixed:FPS[@PHASE]` | trigger at the first sample at or after `t_0 + PHASE + k / FPS` (slots the busy camera cannot take are skipped) |
//! | `threshold:X` | thesis rule: camera free, minimum interval passed, the last three MMBM samples below `X` and strictly decreasing |
//! | `adaptive[:X[:FPS]]` | thesis rule with an adaptive threshold (see [`Adaptive`]); `X` default 0.4, target `FPS` default 2.5 |
//! | `oracle:X[:H]` | perfect future knowledge (see [`Oracle`]); `H` default 0.2 s |
//! | `forecast:X[:H]` | the oracle's rule on a blind periodic forecast (see [`Forecast`]) |
//! | `gate:X[:FPS[@PHASE]]` | `fixed` (default 5 fps), frames whose exposure MMBM is above `X` marked not kept |
//! | `deadline:FPS[:X]` | one frame per fixed-rate slot at the best causal instant (see [`Deadline`]) |

mod bench;
mod policy;
mod predict;
mod rules;
mod stats;

pub use bench::bench;
pub use policy::{parse_policy, Level, LogView, Observation, Policy};
pub use predict::{Forecast, Oracle};
pub use rules::{Adaptive, Deadline, Fixed, Gate, Threshold};
pub use stats::{
    prediction_error, summary, summary_over, write_frames, ErrorStats, Summary, Table51,
    FRAME_HEADER,
};

use crate::error::{Error, Result};
use crate::gyro::GyroSample;
use crate::metric::{Method, Scene};
use crate::series::{eval_batch_cpu, SeriesOptions, BATCH};

/// Camera timing (thesis Fig. 5.1), seconds.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct CameraTiming {
    /// Decision-to-exposure delay `t_d` (thesis: 2-3 ms).
    pub delay: f64,
    /// Exposure `t_e` (thesis: 50 and 70 ms).
    pub exposure: f64,
    /// Readout after the exposure `t_r`; the camera is busy until it ends.
    pub readout: f64,
    /// Minimum interval between triggers of the MMBM-triggered policies.
    pub min_interval: f64,
}

impl Default for CameraTiming {
    /// Delay 2.5 ms, exposure 70 ms (thesis ch. 6), readout 12.5 ms (a
    /// 640 x 480 Flea2 at its 80 fps maximum; an assumption, the thesis gives
    /// none), minimum interval 0.2 s.
    fn default() -> Self {
        CameraTiming {
            delay: 0.0025,
            exposure: 0.07,
            readout: 0.0125,
            min_interval: 0.2,
        }
    }
}

impl CameraTiming {
    /// Checks that the times are finite, the exposure positive and the others non-negative.
    pub fn validate(&self) -> Result<()> {
        crate::error::positive("exposure", self.exposure)?;
        for (what, x) in [
            ("delay", self.delay),
            ("readout", self.readout),
            ("min-interval", self.min_interval),
        ] {
            crate::error::finite(what, x)?;
            if x < 0.0 {
                return Err(Error::invalid(what, format!("must be >= 0 s, got {x}")));
            }
        }
        Ok(())
    }
}

/// One triggered frame.
#[derive(Debug, Clone, PartialEq)]
pub struct Frame {
    /// The policy string exactly as given to [`parse_policy`].
    pub policy: String,
    /// Index of the gyro sample the decision was made on.
    pub index: usize,
    /// Time of that sample, s.
    pub trigger_t: f64,
    /// `trigger_t + delay`, s.
    pub exposure_start: f64,
    /// `exposure_start + exposure`, s.
    pub exposure_end: f64,
    /// MMBM of the decision sample, mm/s.
    pub mmbm_trigger_mm_s: f64,
    /// MMBM averaged over the exposure, mm/s.
    pub mmbm_exposure_mm_s: f64,
    /// False when a quality gate discarded the frame.
    pub kept: bool,
}

/// The prefix integral of a piecewise-linear series, for exposure averages.
/// Can be built incrementally (`push`), which causal policies use on the
/// samples they have seen.
#[derive(Debug, Clone, Default)]
pub struct Integral {
    t: Vec<f64>,
    m: Vec<f64>,
    cum: Vec<f64>,
}

impl Integral {
    /// The integral of `m` over times `t` (same length, `t` increasing).
    pub fn new(t: &[f64], m: &[f64]) -> Self {
        let mut s = Integral {
            t: Vec::with_capacity(t.len()),
            m: Vec::with_capacity(t.len()),
            cum: Vec::with_capacity(t.len()),
        };
        for (&a, &b) in t.iter().zip(m) {
            s.push(a, b);
        }
        s
    }

    /// Appends one sample (time after the previous one).
    pub fn push(&mut self, t: f64, m: f64) {
        let c = match (self.t.last(), self.m.last(), self.cum.last()) {
            (Some(&t0), Some(&m0), Some(&c0)) => c0 + 0.5 * (t - t0) * (m + m0),
            _ => 0.0,
        };
        self.t.push(t);
        self.m.push(m);
        self.cum.push(c);
    }

    /// Number of samples.
    pub fn len(&self) -> usize {
        self.t.len()
    }

    /// True when empty.
    pub fn is_empty(&self) -> bool {
        self.t.is_empty()
    }

    /// Interpolated value at `x` (held constant outside the samples).
    pub fn value(&self, x: f64) -> f64 {
        let n = self.t.len();
        let j = self.t.partition_point(|&s| s <= x);
        if j == 0 {
            return self.m[0];
        }
        if j == n {
            return self.m[n - 1];
        }
        let (t0, t1) = (self.t[j - 1], self.t[j]);
        let a = (x - t0) / (t1 - t0);
        self.m[j - 1] + a * (self.m[j] - self.m[j - 1])
    }

    /// Integral from the first sample to `x`.
    fn upto(&self, x: f64) -> f64 {
        let n = self.t.len();
        let j = self.t.partition_point(|&s| s <= x);
        if j == 0 {
            return (x - self.t[0]) * self.m[0];
        }
        let (tj, mj) = (self.t[j - 1], self.m[j - 1]);
        if j == n {
            return self.cum[n - 1] + (x - tj) * mj;
        }
        let a = (x - tj) / (self.t[j] - tj);
        let mx = mj + a * (self.m[j] - mj);
        self.cum[j - 1] + 0.5 * (x - tj) * (mj + mx)
    }

    /// Time average over `[a, b]` (the value at `a` when `b <= a`).
    pub fn mean(&self, a: f64, b: f64) -> f64 {
        if b <= a {
            return self.value(a);
        }
        (self.upto(b) - self.upto(a)) / (b - a)
    }
}

/// The rotation-only MMBM (mm/s) of every sample, the thesis's metric, with
/// `scene`'s camera and a CPU `method` (the thesis used `riemann:8x6`).
pub fn mmbm_series(samples: &[GyroSample], scene: &Scene, method: Method) -> Result<Vec<f64>> {
    mmbm_series_with(
        samples,
        &SeriesOptions {
            scene: *scene,
            method,
            use_velocity: false,
        },
    )
}

/// MMBM of every sample under full series options (e.g. `use_velocity` with
/// the log's velocity and a depth: an option, not the thesis default).
pub fn mmbm_series_with(samples: &[GyroSample], opts: &SeriesOptions) -> Result<Vec<f64>> {
    opts.scene.camera.validate()?;
    let mut out = Vec::with_capacity(samples.len());
    for chunk in samples.chunks(BATCH) {
        out.extend(eval_batch_cpu(chunk, opts)?);
    }
    Ok(out)
}

/// Runs `policy` over a log: `mmbm_mm_s[i]` is the MMBM of `samples[i]`.
/// The policy sees, at each sample, only the samples up to it (the oracle
/// also gets the whole log in [`Policy::prepare`]). Returns the frames in
/// time order.
pub fn run(
    samples: &[GyroSample],
    mmbm_mm_s: &[f64],
    policy: &mut dyn Policy,
    timing: &CameraTiming,
) -> Result<Vec<Frame>> {
    timing.validate()?;
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
    let t: Vec<f64> = samples.iter().map(|s| s.t).collect();
    for i in 0..t.len() {
        crate::error::finite("sample time", t[i])?;
        if i > 0 && t[i] <= t[i - 1] {
            return Err(Error::invalid(
                "gyro log",
                format!("time not strictly increasing at sample {i} (t = {})", t[i]),
            ));
        }
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
        let start = t[i] + timing.delay;
        let end = start + timing.exposure;
        if end > t_last {
            break;
        }
        let camera_free = start >= free_at;
        let obs = Observation {
            i,
            t: &t[..=i],
            mmbm: &mmbm_mm_s[..=i],
            camera_free,
            last_trigger,
            frames: frames.len(),
            timing,
        };
        if policy.decide(&obs) && camera_free {
            let mut f = Frame {
                policy: policy.spec().to_string(),
                index: i,
                trigger_t: t[i],
                exposure_start: start,
                exposure_end: end,
                mmbm_trigger_mm_s: mmbm_mm_s[i],
                mmbm_exposure_mm_s: integral.mean(start, end),
                kept: true,
            };
            f.kept = policy.keep(&f);
            frames.push(f);
            free_at = end + timing.readout;
            last_trigger = Some(t[i]);
        }
    }
    Ok(frames)
}

/// The exposure average `E(i)` for a trigger at every sample (used by the oracle).
pub fn exposure_means(t: &[f64], m: &[f64], timing: &CameraTiming) -> Vec<f64> {
    let integral = Integral::new(t, m);
    t.iter()
        .map(|&ti| {
            let a = ti + timing.delay;
            integral.mean(a, a + timing.exposure)
        })
        .collect()
}
