//! The generator of the gait model (equations in the parent module) and the log writer.

use super::GaitConfig;
use crate::error::{Error, Result};
use crate::io::gyro::GyroSample;
use glam::DVec3;
use rand::rngs::StdRng;
use rand::{Rng, SeedableRng};
use rand_distr::{Distribution, Normal, StandardNormal};
use std::f64::consts::TAU;
use std::path::Path;

/// Header of the logs written by [`write_log`] (when the samples carry velocity).
pub const LOG_HEADER: &str = "t,wx,wy,wz,vx,vy,vz";

/// Most samples one call may produce (about 46 hours at 600 Hz).
pub const MAX_SAMPLES: f64 = 1e8;

/// One step (stance of one tripod).
#[derive(Debug, Clone, Copy)]
struct Step {
    start: f64,
    amp: f64,
    side: f64,
}

/// Generates the steps lazily from their own random stream, so a longer run
/// extends a shorter one with the same seed instead of changing it.
struct Steps {
    rng: StdRng,
    nominal: f64,
    clock0: f64,
    jitter: f64,
    amplitude_jitter: f64,
    steps: Vec<Step>,
}

impl Steps {
    fn new(cfg: &GaitConfig, seed: u64) -> Self {
        let mut rng = StdRng::seed_from_u64(seed);
        let nominal = 1.0 / cfg.step_hz;
        let clock0 = -rng.gen::<f64>() * nominal;
        let mut s = Steps {
            rng,
            nominal,
            clock0,
            jitter: cfg.touchdown_jitter,
            amplitude_jitter: cfg.amplitude_jitter,
            steps: Vec::new(),
        };
        s.push();
        s.push();
        s
    }

    fn push(&mut self) {
        let k = self.steps.len();
        let n: f64 = StandardNormal.sample(&mut self.rng);
        let m: f64 = StandardNormal.sample(&mut self.rng);
        let start = self.clock0 + (k as f64 + self.jitter * n.clamp(-3.0, 3.0)) * self.nominal;
        let amp = (1.0 + self.amplitude_jitter * m).max(0.0);
        let side = if k % 2 == 0 { 1.0 } else { -1.0 };
        self.steps.push(Step { start, amp, side });
    }

    /// Index of the step containing `t` (generating steps as needed), from
    /// `hint` on; step `k + 1` then exists too.
    fn locate(&mut self, t: f64, mut hint: usize) -> usize {
        loop {
            if hint + 2 >= self.steps.len() {
                self.push();
            }
            if t < self.steps[hint + 1].start {
                return hint;
            }
            hint += 1;
        }
    }
}

/// The touchdown transient shape `g(tau)` of the module docs (first peak 1).
struct Transient {
    decay: f64,
    omega: f64,
    inv_peak: f64,
    horizon: f64,
}

impl Transient {
    fn new(decay: f64, freq_hz: f64) -> Self {
        let omega = TAU * freq_hz;
        let t_peak = (omega * decay).atan() / omega;
        let peak = (-t_peak / decay).exp() * (omega * t_peak).sin();
        Transient {
            decay,
            omega,
            inv_peak: 1.0 / peak,
            horizon: 12.0 * decay,
        }
    }

    #[inline]
    fn at(&self, tau: f64) -> f64 {
        (-tau / self.decay).exp() * (self.omega * tau).sin() * self.inv_peak
    }
}

/// Simulates `duration_s` seconds of the walk at `rate_hz` samples per second
/// with random seed `seed`. Sample `i` is at `t = i / rate_hz` s, for
/// `i < round(duration_s * rate_hz)`. Every sample carries the linear velocity
/// (m/s) and no depth. Deterministic per (config, rate, seed); a longer
/// duration extends a shorter one sample for sample. ([`samples`] yields the
/// same samples one at a time, in constant memory.)
pub fn simulate(
    cfg: &GaitConfig,
    duration_s: f64,
    rate_hz: f64,
    seed: u64,
) -> Result<Vec<GyroSample>> {
    let it = samples(cfg, duration_s, rate_hz, seed)?;
    let mut out = Vec::with_capacity(it.len());
    for (k, s) in it.enumerate() {
        // A stop request (crate::cancel) is seen every 2^16 samples.
        if k % (1 << 16) == 0 {
            crate::cancel::check()?;
        }
        out.push(s);
    }
    Ok(out)
}

/// The samples of [`simulate`], generated one at a time (constant memory);
/// the same checks (at most [`MAX_SAMPLES`]).
pub fn samples(cfg: &GaitConfig, duration_s: f64, rate_hz: f64, seed: u64) -> Result<Samples> {
    cfg.validate()?;
    crate::check::positive("duration", duration_s)?;
    crate::check::positive("rate", rate_hz)?;
    let n_f = (duration_s * rate_hz).round();
    if n_f < 2.0 {
        return Err(Error::invalid(
            "duration",
            format!("{duration_s} s at {rate_hz} Hz gives fewer than 2 samples"),
        ));
    }
    if n_f > MAX_SAMPLES {
        return Err(Error::invalid(
            "duration",
            format!("{duration_s} s at {rate_hz} Hz is more than {MAX_SAMPLES:e} samples"),
        ));
    }
    let noise =
        Normal::new(0.0, cfg.noise_std).map_err(|e| Error::invalid("noise_std", e.to_string()))?;
    Ok(Samples {
        steps: Steps::new(cfg, seed),
        noise_rng: StdRng::seed_from_u64(seed ^ 0x9E37_79B9_7F4A_7C15),
        noise,
        tr: Transient::new(cfg.touchdown_decay_s, cfg.touchdown_freq_hz),
        cfg: cfg.clone(),
        rate_hz,
        n: n_f as usize,
        i: 0,
        k: 0,
    })
}

/// The iterator of [`samples`].
pub struct Samples {
    cfg: GaitConfig,
    steps: Steps,
    noise_rng: StdRng,
    noise: Normal<f64>,
    tr: Transient,
    rate_hz: f64,
    n: usize,
    i: usize,
    k: usize,
}

impl Iterator for Samples {
    type Item = GyroSample;

    fn next(&mut self) -> Option<GyroSample> {
        if self.i >= self.n {
            return None;
        }
        let (cfg, tr) = (&self.cfg, &self.tr);
        let sign = |j: usize, side: f64| if cfg.alternate[j] { side } else { 1.0 };
        let bias = DVec3::from_array(cfg.bias);
        let t = self.i as f64 / self.rate_hz;
        self.i += 1;
        let steps = &mut self.steps;
        self.k = steps.locate(t, self.k);
        let k = self.k;
        let s = steps.steps[k];
        let period = steps.steps[k + 1].start - s.start;
        let p = (t - s.start) / period;
        let mut w = [0.0; 3];
        for (j, wj) in w.iter_mut().enumerate() {
            *wj = s.amp * sign(j, s.side) * cfg.sway[j] * (TAU * p + cfg.sway_phase[j]).sin();
        }
        for q in (0..=k).rev() {
            let st = steps.steps[q];
            let tau = t - st.start;
            if tau > tr.horizon {
                break;
            }
            let g = st.amp * tr.at(tau);
            for (j, wj) in w.iter_mut().enumerate() {
                *wj += sign(j, st.side) * cfg.touchdown[j] * g;
            }
        }
        let mut omega = DVec3::from_array(w) + bias;
        if cfg.noise_std > 0.0 {
            omega += DVec3::new(
                self.noise.sample(&mut self.noise_rng),
                self.noise.sample(&mut self.noise_rng),
                self.noise.sample(&mut self.noise_rng),
            );
        }
        let ph = TAU * p;
        let vz = cfg.speed_m_s * (1.0 + cfg.surge * ph.cos());
        let vy = -cfg.bob_m * TAU / period * ph.sin();
        Some(GyroSample {
            t,
            omega,
            velocity: Some(DVec3::new(0.0, vy, vz)),
            depth: None,
        })
    }

    fn size_hint(&self) -> (usize, Option<usize>) {
        let left = self.n - self.i;
        (left, Some(left))
    }
}

impl ExactSizeIterator for Samples {}

/// Writes samples as a gyro CSV (docs/spec.md section 5) atomically: header
/// `t,wx,wy,wz` plus `,vx,vy,vz` when every sample has a velocity and
/// `,depth` when every sample has a depth (a mix of samples with and without
/// is an error). Floats use Rust's shortest round-trip formatting, so reading
/// the file back gives the same numbers bit for bit.
pub fn write_log(path: &Path, samples: &[GyroSample]) -> Result<()> {
    let with_v = samples.iter().all(|s| s.velocity.is_some());
    let with_d = samples.iter().all(|s| s.depth.is_some());
    if !with_v && samples.iter().any(|s| s.velocity.is_some()) {
        return Err(Error::invalid(
            "samples",
            "some samples have a velocity and some do not",
        ));
    }
    if !with_d && samples.iter().any(|s| s.depth.is_some()) {
        return Err(Error::invalid(
            "samples",
            "some samples have a depth and some do not",
        ));
    }
    write_rows(path, with_v, with_d, samples.iter().copied())
}

/// Writes the samples of [`samples`] as [`write_log`] writes them, one at a
/// time (constant memory, whatever the duration). Returns how many.
pub fn write_samples(path: &Path, samples: Samples) -> Result<u64> {
    let n = samples.len() as u64;
    write_rows(path, true, false, samples)?;
    Ok(n)
}

/// The CSV of [`write_log`]: the header, then one line per sample.
fn write_rows(
    path: &Path,
    with_v: bool,
    with_d: bool,
    samples: impl Iterator<Item = GyroSample>,
) -> Result<()> {
    crate::io::atomic::write_atomic(path, |w| {
        let e = |e: std::io::Error| Error::io(path, e);
        let mut header = String::from("t,wx,wy,wz");
        if with_v {
            header.push_str(",vx,vy,vz");
        }
        if with_d {
            header.push_str(",depth");
        }
        writeln!(w, "{header}").map_err(e)?;
        let mut line = String::with_capacity(160);
        for s in samples {
            use std::fmt::Write as _;
            line.clear();
            let o = s.omega;
            let _ = write!(line, "{},{},{},{}", s.t, o.x, o.y, o.z);
            if let Some(v) = s.velocity.filter(|_| with_v) {
                let _ = write!(line, ",{},{},{}", v.x, v.y, v.z);
            }
            if let Some(d) = s.depth.filter(|_| with_d) {
                let _ = write!(line, ",{d}");
            }
            line.push('\n');
            w.write_all(line.as_bytes()).map_err(e)?;
        }
        Ok(())
    })
}
