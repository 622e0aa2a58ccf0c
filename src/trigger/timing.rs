//! The camera's timing (thesis Fig. 5.1), a triggered [`Frame`], and the
//! exposure average of the MMBM series ([`Integral`]).

use crate::error::{Error, Result};

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
    /// Pixel pitch, mm: turns an MMBM (mm/s) times an exposure into a blur
    /// length in px for exposure control (`+exp:B`).
    pub pitch_mm: f64,
}

impl Default for CameraTiming {
    /// Delay 2.5 ms, exposure 70 ms (thesis ch. 6), readout 12.5 ms (a
    /// 640 x 480 Flea2 at its 80 fps maximum; an assumption, the thesis gives
    /// none), minimum interval 0.2 s, the thesis camera's 4.65 um pitch.
    fn default() -> Self {
        CameraTiming {
            delay: 0.0025,
            exposure: 0.07,
            readout: 0.0125,
            min_interval: 0.2,
            pitch_mm: 0.00465,
        }
    }
}

impl CameraTiming {
    /// The timing of a rolling-shutter camera (SPEC 9): its last line's
    /// exposure ends `rolling_readout_s` after the first line's, so the camera
    /// is busy that much longer before the readout `t_r` that follows.
    pub fn with_rolling_readout(self, rolling_readout_s: f64) -> Self {
        CameraTiming {
            readout: self.readout + rolling_readout_s,
            ..self
        }
    }

    /// Checks that the times are finite, the exposure positive and the others non-negative.
    pub fn validate(&self) -> Result<()> {
        crate::error::positive("exposure", self.exposure)?;
        crate::error::positive("pixel pitch (mm)", self.pitch_mm)?;
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
    /// The policy string exactly as given to [`parse_policy`](crate::trigger::parse_policy).
    pub policy: String,
    /// Index of the gyro sample the decision was made on.
    pub index: usize,
    /// Time of that sample, s.
    pub trigger_t: f64,
    /// `trigger_t + delay`, s.
    pub exposure_start: f64,
    /// `exposure_start` plus the frame's exposure (the camera's, or the one
    /// an exposure-controlled policy chose), s.
    pub exposure_end: f64,
    /// MMBM of the decision sample, mm/s.
    pub mmbm_trigger_mm_s: f64,
    /// MMBM averaged over the exposure, mm/s.
    pub mmbm_exposure_mm_s: f64,
    /// False when a quality gate discarded the frame.
    pub kept: bool,
    /// Sensor gain relative to the nominal exposure's (1 unless an
    /// exposure-controlled policy shortened the exposure: then
    /// `nominal / chosen`, which keeps the image as bright).
    pub gain: f64,
}

impl Frame {
    /// The frame's exposure, s.
    pub fn exposure_s(&self) -> f64 {
        self.exposure_end - self.exposure_start
    }
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

    /// Time of the last sample, s.
    pub fn last_time(&self) -> Option<f64> {
        self.t.last().copied()
    }

    /// Forgets samples before `t` (s), keeping the last one at or before it,
    /// so means over windows from `t` on are unchanged (bit for bit: the
    /// running integral is kept as it was). Drops in bulk, once at least half
    /// of the samples are stale: amortised O(1) per sample.
    pub fn trim_before(&mut self, t: f64) {
        let j = self.t.partition_point(|&s| s <= t).saturating_sub(1);
        if j > 0 && 2 * j >= self.t.len() {
            self.t.drain(..j);
            self.m.drain(..j);
            self.cum.drain(..j);
        }
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
