//! Predictive triggering (thesis section 5.2): the oracle with perfect
//! knowledge of the future, and a blind forecast of the quasi-periodic gait.

use super::policy::{thesis_rule, Level, LogView, Observation, Policy};
use super::timing::{exposure_means, CameraTiming, Integral};
use crate::error::Result;
use std::collections::VecDeque;

/// `oracle:X[:H]`: perfect knowledge of the future (not causal), the upper
/// bound of thesis Table 5.1. With `E(i)` the exposure-averaged MMBM of a
/// trigger at sample `i` (exactly what the frame will get), trigger at `i`
/// when:
///
/// - the camera is free and the minimum interval has passed (as `threshold`),
/// - `E(i) < X`, and
/// - `E(i) <= E(j)` for every later sample `j` with `t_j <= t_i + H`
///   (waiting up to `H` seconds, default 0.2, would not give a better frame).
///
/// So each frame sits at the minimum of `E` within the next `H`, among the
/// instants with `E` below `X`.
#[derive(Debug, Clone)]
pub struct Oracle {
    spec: String,
    level: Level,
    horizon: f64,
    x: f64,
    e: Vec<f64>,
    future_min: Vec<f64>,
}

impl Oracle {
    /// Threshold `level` on the exposure average, look-ahead `horizon` s.
    pub fn new(spec: &str, level: Level, horizon: f64) -> Self {
        Oracle {
            spec: spec.to_string(),
            level,
            horizon,
            x: f64::NAN,
            e: Vec::new(),
            future_min: Vec::new(),
        }
    }
}

/// `out[i]` = min of `v[j]` over `j > i` with `t[j] <= t[i] + h` (infinity if none).
fn forward_window_min(t: &[f64], v: &[f64], h: f64) -> Vec<f64> {
    let n = t.len();
    let mut out = vec![f64::INFINITY; n];
    let mut dq: VecDeque<usize> = VecDeque::new();
    let mut next = 0; // next index to push
    for i in 0..n {
        while next < n && t[next] <= t[i] + h {
            while dq.back().is_some_and(|&b| v[b] >= v[next]) {
                dq.pop_back();
            }
            dq.push_back(next);
            next += 1;
        }
        while dq.front().is_some_and(|&f| f <= i) {
            dq.pop_front();
        }
        if let Some(&f) = dq.front() {
            out[i] = v[f];
        }
    }
    out
}

impl Policy for Oracle {
    fn label(&self) -> &str {
        &self.spec
    }
    fn is_causal(&self) -> bool {
        false
    }
    fn prepare(&mut self, log: &LogView, timing: &CameraTiming) -> Result<()> {
        self.x = self.level.resolve(log.mmbm)?;
        self.e = exposure_means(log.t, log.mmbm, timing);
        self.future_min = forward_window_min(log.t, &self.e, self.horizon);
        Ok(())
    }
    fn decide(&mut self, obs: &Observation) -> bool {
        let e = self.e[obs.i];
        obs.camera_free && obs.interval_passed() && e < self.x && e <= self.future_min[obs.i]
    }
}

/// The gait period (s) from the last `window` s of `hist` before `now`:
/// box-averaged into [`Forecast::BIN`]-s bins (left in `bins`, raw), the mean
/// removed, the normalised autocorrelation over lags [`Forecast::MIN_LAG`] ..
/// `window / 2`; the shortest lag at a local maximum reaching `ratio` of the
/// highest correlation, refined by a parabola. `None` before `window` s of
/// log or when the highest correlation is below
/// [`Forecast::MIN_CORR`] (not periodic).
pub(super) fn estimate_period(
    hist: &Integral,
    bins: &mut Vec<f64>,
    t0: f64,
    now: f64,
    ratio: f64,
    window: f64,
) -> Option<f64> {
    if now - t0 < window {
        return None;
    }
    let nb = (window / Forecast::BIN).round() as usize;
    let a = now - window;
    bins.clear();
    for b in 0..nb {
        let lo = a + b as f64 * Forecast::BIN;
        bins.push(hist.mean(lo, lo + Forecast::BIN));
    }
    let mean = bins.iter().sum::<f64>() / nb as f64;
    let x: Vec<f64> = bins.iter().map(|v| v - mean).collect();
    let lmin = (Forecast::MIN_LAG / Forecast::BIN).ceil() as usize;
    let lmax = nb / 2;
    let corr = |l: usize| {
        let (mut s, mut s0, mut s1) = (0.0, 0.0, 0.0);
        for k in 0..nb - l {
            s += x[k] * x[k + l];
            s0 += x[k] * x[k];
            s1 += x[k + l] * x[k + l];
        }
        if s0 > 0.0 && s1 > 0.0 {
            s / (s0 * s1).sqrt()
        } else {
            0.0
        }
    };
    let c: Vec<f64> = (lmin - 1..=lmax + 1).map(corr).collect();
    let best = c[1..c.len() - 1].iter().copied().fold(f64::MIN, f64::max);
    if best < Forecast::MIN_CORR {
        return None;
    }
    for j in 1..c.len() - 1 {
        if c[j] >= ratio * best && c[j] >= c[j - 1] && c[j] >= c[j + 1] {
            let den = c[j - 1] - 2.0 * c[j] + c[j + 1];
            let off = if den < 0.0 {
                (0.5 * (c[j - 1] - c[j + 1]) / den).clamp(-0.5, 0.5)
            } else {
                0.0
            };
            let lag = (lmin - 1 + j) as f64 + off;
            return Some(lag * Forecast::BIN);
        }
    }
    None
}

/// `forecast:X[:H]`: the oracle's rule applied to a blind forecast of the
/// quasi-periodic gait, using only the samples up to the decision.
///
/// - Period: every [`Forecast::REESTIMATE`] s (while the camera is free and
///   the minimum interval has passed), the last [`Forecast::WINDOW`] s of MMBM
///   are box-averaged into [`Forecast::BIN`]-s bins, the mean removed, and the
///   normalised autocorrelation computed for lags [`Forecast::MIN_LAG`] ..
///   `WINDOW / 2`. The period `P` is the shortest lag at a local maximum
///   reaching 0.8 of the highest correlation, refined by a parabola through
///   its neighbours. A highest correlation below [`Forecast::MIN_CORR`] means
///   "not periodic".
/// - Forecast: `Ê(τ)` = mean over `k = 1..=K` ([`Forecast::PERIODS`], 1) of
///   the worst, over shifts `δ` in `{-S, -S/2, 0, S/2, S}` ([`Forecast::SLACK`]
///   = S, 40 ms, against the gait's timing jitter), of the measured MMBM
///   averaged over `[τ + t_d - kP + δ, τ + t_d + t_e - kP + δ]`, using only
///   windows that lie entirely in the past.
/// - Decision: camera free, minimum interval passed, `Ê(t_i) < X`, and
///   `Ê(t_i) <= Ê(t_i + q H / Q)` for `q = 1..Q` ([`Forecast::GRID`] = Q).
/// - Fallback (no period yet, or not periodic): the thesis rule with `X`.
#[derive(Debug, Clone)]
pub struct Forecast {
    spec: String,
    level: Level,
    horizon: f64,
    x: f64,
    hist: Integral,
    period: Option<f64>,
    estimated_at: f64,
    bins: Vec<f64>,
}

impl Forecast {
    /// Autocorrelation window, s.
    pub const WINDOW: f64 = 4.0;
    /// Bin width of the resampled series, s.
    pub const BIN: f64 = 0.01;
    /// Shortest period considered, s.
    pub const MIN_LAG: f64 = 0.15;
    /// Minimum normalised autocorrelation for a period.
    pub const MIN_CORR: f64 = 0.3;
    /// How often the period is re-estimated, s.
    pub const REESTIMATE: f64 = 0.25;
    /// Periods averaged in the forecast.
    pub const PERIODS: usize = 1;
    /// Timing uncertainty of the forecast, s: each forecast window is the worst
    /// of the windows shifted by -SLACK, -SLACK/2, 0, SLACK/2, SLACK.
    pub const SLACK: f64 = 0.04;
    /// Look-ahead grid points.
    pub const GRID: usize = 20;

    /// Threshold `level` on the forecast exposure average, look-ahead `horizon` s.
    pub fn new(spec: &str, level: Level, horizon: f64) -> Self {
        Forecast {
            spec: spec.to_string(),
            level,
            horizon,
            x: f64::NAN,
            hist: Integral::default(),
            period: None,
            estimated_at: f64::NEG_INFINITY,
            bins: Vec::new(),
        }
    }

    /// The period estimated last, s (None when not periodic or not yet known).
    pub fn period(&self) -> Option<f64> {
        self.period
    }

    /// Forecast exposure average for a trigger at `tau`; None without a past window.
    fn predict(&self, tau: f64, p: f64, now: f64, t0: f64, timing: &CameraTiming) -> Option<f64> {
        let (mut s, mut n) = (0.0, 0);
        for k in 1..=Self::PERIODS {
            // Pessimistic over the timing uncertainty: the worst of the
            // windows shifted by -SLACK..=SLACK.
            let mut worst: Option<f64> = None;
            for q in -2..=2 {
                let a = tau + timing.delay - k as f64 * p + q as f64 * 0.5 * Self::SLACK;
                let b = a + timing.exposure;
                if b <= now && a >= t0 {
                    let e = self.hist.mean(a, b);
                    worst = Some(worst.map_or(e, |w: f64| w.max(e)));
                }
            }
            if let Some(w) = worst {
                s += w;
                n += 1;
            }
        }
        (n > 0).then(|| s / n as f64)
    }
}

impl Policy for Forecast {
    fn label(&self) -> &str {
        &self.spec
    }
    fn prepare(&mut self, log: &LogView, _timing: &CameraTiming) -> Result<()> {
        self.x = self.level.resolve(log.mmbm)?;
        self.hist = Integral::default();
        self.period = None;
        self.estimated_at = f64::NEG_INFINITY;
        Ok(())
    }
    fn decide(&mut self, obs: &Observation) -> bool {
        for k in obs.unseen(self.hist.last_time()) {
            self.hist.push(obs.t[k], obs.mmbm[k]);
        }
        // The forecast looks back at most WINDOW (period estimate) or a
        // period plus the slack (< WINDOW): older samples are dropped, so
        // memory stays constant on an endless stream.
        self.hist.trim_before(obs.now() - Self::WINDOW - 1.0);
        if !(obs.camera_free && obs.interval_passed()) {
            return false;
        }
        let (t0, now) = (obs.t0, obs.now());
        if now - self.estimated_at >= Self::REESTIMATE {
            self.period = estimate_period(&self.hist, &mut self.bins, t0, now, 0.8, Self::WINDOW);
            self.estimated_at = now;
        }
        let timing = obs.timing;
        let Some(p) = self.period else {
            return thesis_rule(obs.mmbm, self.x);
        };
        let Some(e_now) = self.predict(now, p, now, t0, timing) else {
            return thesis_rule(obs.mmbm, self.x);
        };
        if e_now >= self.x {
            return false;
        }
        (1..=Self::GRID).all(|q| {
            let tau = now + q as f64 * self.horizon / Self::GRID as f64;
            self.predict(tau, p, now, t0, timing)
                .is_none_or(|e| e_now <= e)
        })
    }
}
