//! `phase:X[:H]`: a forecast that learns the gait's cycle from touchdowns.

use super::policy::{thesis_rule, Level, LogView, Observation, Policy};
use super::predict::{estimate_period, Forecast};
use super::timing::{CameraTiming, Integral};
use crate::error::Result;
use crate::stats::percentile;
use std::collections::VecDeque;

/// `phase:X[:H]`: the oracle's rule on a forecast folded over the last gait
/// cycles by their phase, using only the samples up to the decision.
///
/// - **Touchdowns**: a step of a legged gait starts with a sharp rise of the
///   MMBM (the foot strike). Every [`Forecast::REESTIMATE`] s the period `P`
///   is estimated as [`Forecast`] does (autocorrelation of the last
///   [`Forecast::WINDOW`] s; the shortest peak reaching [`Phase::SHORTEST`]
///   of the highest) and a level `L = p25 + 0.5 (p99 - p25)` of the
///   same 10-ms bins is set. A **touchdown** is an upward crossing of `L`
///   (time interpolated between the samples) at least
///   [`Phase::REFRACTORY`] times the median interval of the known touchdowns
///   (`P` before there are three) after the previous one, so the ringing of
///   one transient counts once. The last [`Phase::CYCLES`] + 1 are kept.
/// - **Clock**: a legged robot's gait clock does not drift, so the touchdown
///   times are fitted by least squares to `T_k = T_0 + k P_c` (step numbers
///   `k` by rounding on the median interval); `sigma_c` is the residual
///   deviation, the jitter of a touchdown about its tick.
/// - **Fold**: with `T_n` the last touchdown, `s = t_i - T_n` the phase of
///   now, and `E_j(x)` the measured MMBM averaged over `[x + t_d, x + t_d +
///   t_e]`, a trigger at `t_i + u` is forecast from the same phase of the
///   previous cycles in two ways: after the last touchdown, `E_j(T_j + s + u)`
///   over `j = n-1 .. n-K`; before the next one, `E_j(tick_j - r)` over the
///   ticks of the known touchdowns, with `r` the time from `t_i + u` to the
///   next tick (which folds each touchdown's jitter about its tick into the
///   spread). The two are blended linearly from the first to the second as
///   `(s + u) / P` goes from 0.3 to 0.7, and the forecast is mean plus
///   [`Phase::RISK`] standard deviations over the folded cycles (a phase
///   where some cycles were shaken is avoided). An exposure ending less than
///   [`Phase::MARGIN`] `sigma_c` before the next tick is not taken.
/// - **Amplitude**: the fold is scaled by the ratio of the current cycle's
///   peak MMBM (since `T_n`, once [`Phase::PEAK_AFTER`] s have passed) to the
///   mean peak of the folded cycles (over their same span), clamped to
///   `[0.5, 2]`: a harder foot strike predicts a shakier step.
/// - **Decision** (the oracle's rule on the forecast `Ê`): camera free,
///   minimum interval passed, `Ê(0) < X` and `Ê(0) <= Ê(q H / Q)` for
///   `q = 1..Q` ([`Forecast::GRID`] = Q).
/// - **Fallback** to the thesis rule with `X` while fewer than `MIN_CYCLES + 1`
///   touchdowns are known, when the log is not periodic, when the clock does
///   not fit the touchdowns (residual deviation above [`Phase::LOCK`] of its
///   period) or the last touchdown is more than two clock periods old (lock lost).
/// - **Robustness**: with five or more touchdowns the clock is fitted
///   robustly (see `Phase::clock`: touchdowns more than [`Phase::OUTLIER`]
///   robust deviations off the first fit, a stumble or a double crossing,
///   are left out of the refit and of the fold); an outlying last touchdown
///   is replaced by its tick, and when none came [`Phase::MISSED`] periods
///   after the last, the one due is taken as missed (the fold aligned on its tick).
/// - **Exposure control** (`phase:X+exp:B`): [`Phase::forecast_exposure`]
///   forecasts the exposure MMBM for any exposure, which
///   [`Exposure`](super::Exposure) uses instead of the decision sample.
#[derive(Debug, Clone)]
pub struct Phase {
    spec: String,
    level: Level,
    horizon: f64,
    x: f64,
    hist: Integral,
    period: Option<f64>,
    crossing: Option<f64>,
    estimated_at: f64,
    bins: Vec<f64>,
    touchdowns: VecDeque<f64>,
    prev: Option<(f64, f64)>,
}

impl Phase {
    /// Previous cycles folded into the forecast.
    pub const CYCLES: usize = 8;
    /// The forecast is the fold's mean plus this many standard deviations.
    pub const RISK: f64 = 2.5;
    /// Exposures must end this many clock residual deviations before the next tick.
    pub const MARGIN: f64 = 3.0;
    /// Lock: the clock's residual deviation at most this share of its period.
    pub const LOCK: f64 = 0.15;
    /// A period is the shortest autocorrelation peak reaching this share of the highest.
    pub const SHORTEST: f64 = 0.5;
    /// The first period estimate needs this much log, s (later ones use
    /// [`Forecast::WINDOW`], or the whole log while it is shorter).
    pub const FIRST_WINDOW: f64 = 2.5;
    /// Fewest previous cycles before the fold is used.
    pub const MIN_CYCLES: usize = 2;
    /// Shortest interval between touchdowns, in periods.
    pub const REFRACTORY: f64 = 0.6;
    /// Time after a touchdown at which its peak is taken as known, s.
    pub const PEAK_AFTER: f64 = 0.1;
    /// A touchdown this many robust deviations off the clock is an outlier.
    pub const OUTLIER: f64 = 3.0;
    /// The robust deviation is at least this share of the period.
    pub const OUTLIER_FLOOR: f64 = 0.02;
    /// No touchdown this many periods after the last: the one due is taken as missed.
    pub const MISSED: f64 = 1.3;

    /// Threshold `level` on the forecast exposure average, look-ahead `horizon` s.
    pub fn new(spec: &str, level: Level, horizon: f64) -> Self {
        Phase {
            spec: spec.to_string(),
            level,
            horizon,
            x: f64::NAN,
            hist: Integral::default(),
            period: None,
            crossing: None,
            estimated_at: f64::NEG_INFINITY,
            bins: Vec::new(),
            touchdowns: VecDeque::new(),
            prev: None,
        }
    }

    /// Touchdown times detected so far (the last [`Phase::CYCLES`] + 1), s.
    pub fn touchdowns(&self) -> impl Iterator<Item = f64> + '_ {
        self.touchdowns.iter().copied()
    }

    /// Appends a sample and detects a touchdown at an upward crossing of the level.
    fn push(&mut self, t: f64, m: f64) {
        self.hist.push(t, m);
        if let (Some((tp, mp)), Some(l), Some(p)) = (self.prev, self.crossing, self.period) {
            if mp < l && m >= l {
                let tc = tp + (l - mp) / (m - mp) * (t - tp);
                let step = self.step_interval().unwrap_or(p);
                if self
                    .touchdowns
                    .back()
                    .is_none_or(|&last| tc - last >= Self::REFRACTORY * step)
                {
                    self.touchdowns.push_back(tc);
                    if self.touchdowns.len() > Self::CYCLES + 1 {
                        self.touchdowns.pop_front();
                    }
                }
            }
        }
        self.prev = Some((t, m));
    }

    /// Median interval between the known touchdowns, s (None with fewer than 3).
    fn step_interval(&self) -> Option<f64> {
        let mut d: Vec<f64> = self
            .touchdowns
            .iter()
            .zip(self.touchdowns.iter().skip(1))
            .map(|(a, b)| b - a)
            .collect();
        if d.len() < 2 {
            return None;
        }
        d.sort_by(f64::total_cmp);
        Some(d[d.len() / 2])
    }

    /// Peak MMBM over `[a, b]` from 10-ms box means (robust to gyro noise).
    fn peak(&self, a: f64, b: f64) -> f64 {
        let n = ((b - a) / Forecast::BIN).floor().max(1.0) as usize;
        (0..n)
            .map(|k| {
                let lo = a + k as f64 * Forecast::BIN;
                self.hist.mean(lo, lo + Forecast::BIN)
            })
            .fold(0.0, f64::max)
    }

    /// Mean and standard deviation of the measured exposure averages of
    /// triggers at `starts` (only those whose exposure ended by `now`).
    fn fold(
        &self,
        starts: impl Iterator<Item = f64>,
        now: f64,
        timing: &CameraTiming,
        exposure_s: f64,
    ) -> Option<(f64, f64)> {
        let (mut sum, mut sum2, mut k) = (0.0, 0.0, 0);
        for t in starts {
            let a = t + timing.delay;
            let b = a + exposure_s;
            if b <= now {
                let e = self.hist.mean(a, b);
                sum += e;
                sum2 += e * e;
                k += 1;
            }
        }
        if k == 0 {
            return None;
        }
        let mean = sum / k as f64;
        Some((mean, (sum2 / k as f64 - mean * mean).max(0.0).sqrt()))
    }

    /// The gait clock fitted to the known touchdowns (least squares of their
    /// times on their step numbers); `None` when they do not fit one. With
    /// five or more touchdowns the fit is made robust: touchdowns further than
    /// [`Phase::OUTLIER`] robust deviations (1.4826 median absolute residuals,
    /// at least [`Phase::OUTLIER_FLOOR`] of the period) from the first fit are
    /// marked outliers and the clock refitted on the others.
    fn clock(&self, p: f64) -> Option<Clock> {
        let first = *self.touchdowns.front()?;
        let ks: Vec<f64> = self
            .touchdowns
            .iter()
            .map(|&t| ((t - first) / p).round())
            .collect();
        let all = vec![true; ks.len()];
        let (origin, period, _) = fit_line(&ks, &self.touchdowns, &all)?;
        let res: Vec<f64> = ks
            .iter()
            .zip(&self.touchdowns)
            .map(|(k, t)| t - origin - k * period)
            .collect();
        let mut inlier = all;
        if ks.len() >= 5 {
            let mut a: Vec<f64> = res.iter().map(|r| r.abs()).collect();
            a.sort_by(f64::total_cmp);
            let sd_r = (1.4826 * a[a.len() / 2]).max(Self::OUTLIER_FLOOR * period);
            for (f, r) in inlier.iter_mut().zip(&res) {
                *f = r.abs() <= Self::OUTLIER * sd_r;
            }
        }
        let (origin, period, sd) = fit_line(&ks, &self.touchdowns, &inlier)?;
        if !(0.8 * p..=1.25 * p).contains(&period) {
            return None;
        }
        Some(Clock {
            sd,
            origin,
            first,
            period,
            inlier,
        })
    }

    /// The forecast exposure MMBM (mm/s, mean plus [`Phase::RISK`] standard
    /// deviations over the folded cycles, as in the decision) of a frame
    /// triggered at `now` and exposed for `exposure_s`; `None` while the
    /// fold cannot be made (the decision falls back to the thesis rule then).
    /// Infinite when such an exposure would end within [`Phase::MARGIN`]
    /// clock deviations of the next touchdown.
    pub fn forecast_exposure(
        &self,
        now: f64,
        timing: &CameraTiming,
        exposure_s: f64,
    ) -> Option<f64> {
        self.forecast(now, &[0.0], timing, exposure_s).map(|v| v[0])
    }

    /// The folded forecast for triggers at `now + u` for each `u` in `us`,
    /// exposed for `exposure_s`; `None` when it cannot be made.
    fn forecast(
        &self,
        now: f64,
        us: &[f64],
        timing: &CameraTiming,
        exposure_s: f64,
    ) -> Option<Vec<f64>> {
        let p = self.period?;
        let n = self.touchdowns.len();
        if n < Self::MIN_CYCLES + 1 {
            return None;
        }
        let clock = self.clock(self.step_interval()?)?;
        let raw_last = self.touchdowns[n - 1];
        if clock.sd > Self::LOCK * clock.period || now - raw_last > 2.0 * clock.period {
            return None;
        }
        // An outlying last touchdown is replaced by its tick; a missed one
        // (no crossing a period and more after the last) by the tick due.
        let mut last = if clock.inlier[n - 1] {
            raw_last
        } else {
            clock.tick(clock.index(raw_last))
        };
        if now - last > Self::MISSED * clock.period {
            last = clock.tick(clock.index(last) + ((now - last) / clock.period).floor());
        }
        let s = now - last;
        let past: Vec<f64> = self
            .touchdowns
            .iter()
            .zip(&clock.inlier)
            .take(n - 1)
            .filter(|(_, &ok)| ok)
            .map(|(&t, _)| t)
            .collect();
        if past.len() < Self::MIN_CYCLES {
            return None;
        }
        // Amplitude of the current cycle against the folded ones.
        let span = s.min(p);
        let scale = if s >= Self::PEAK_AFTER {
            let mean_peak =
                past.iter().map(|&tj| self.peak(tj, tj + span)).sum::<f64>() / past.len() as f64;
            let now_peak = self.peak(last, last + span);
            if mean_peak > 0.0 {
                (now_peak / mean_peak).clamp(0.5, 2.0)
            } else {
                1.0
            }
        } else {
            1.0
        };
        let next_tick = clock.tick(clock.index(last) + 1.0);
        // Ticks of the known inlying touchdowns but the first: the ends of the folded cycles.
        let ticks: Vec<f64> = self
            .touchdowns
            .iter()
            .zip(&clock.inlier)
            .skip(1)
            .filter(|(_, &ok)| ok)
            .map(|(&tj, _)| clock.tick(clock.index(tj)))
            .collect();
        let mut out = Vec::with_capacity(us.len());
        for &u in us {
            // After the last touchdown: aligned on it; before the next: on the clock.
            let post = self.fold(past.iter().map(|&tj| tj + s + u), now, timing, exposure_s)?;
            let r = next_tick - (now + u);
            let pre = self.fold(ticks.iter().map(|&tk| tk - r), now, timing, exposure_s);
            let w = (((s + u) / p - 0.3) / 0.4).clamp(0.0, 1.0);
            if now + u + timing.delay + exposure_s > next_tick - Self::MARGIN * clock.sd {
                out.push(f64::INFINITY);
                continue;
            }
            let (mean, sd) = match pre {
                Some(pre) => (
                    (1.0 - w) * post.0 + w * pre.0,
                    (1.0 - w) * post.1 + w * pre.1,
                ),
                None => post,
            };
            out.push(scale * (mean + Self::RISK * sd));
        }
        Some(out)
    }
}

/// Least squares `t = origin + k period` over the points `use_` marks:
/// `(origin, period, residual deviation)`; `None` without two distinct `k`.
fn fit_line(ks: &[f64], ts: &VecDeque<f64>, use_: &[bool]) -> Option<(f64, f64, f64)> {
    let pts = || {
        ks.iter()
            .zip(ts)
            .zip(use_)
            .filter(|(_, &u)| u)
            .map(|((&k, &t), _)| (k, t))
    };
    let n = pts().count() as f64;
    if n < 2.0 {
        return None;
    }
    let (mk, mt) = (
        pts().map(|(k, _)| k).sum::<f64>() / n,
        pts().map(|(_, t)| t).sum::<f64>() / n,
    );
    let (mut skk, mut skt) = (0.0, 0.0);
    for (k, t) in pts() {
        skk += (k - mk) * (k - mk);
        skt += (k - mk) * (t - mt);
    }
    if skk <= 0.0 {
        return None;
    }
    let period = skt / skk;
    let origin = mt - period * mk;
    let res2 = pts()
        .map(|(k, t)| (t - origin - k * period).powi(2))
        .sum::<f64>();
    Some((origin, period, (res2 / (n - 2.0).max(1.0)).sqrt()))
}

/// A gait clock: touchdown `k` is due at `origin + k period`.
#[derive(Debug, Clone)]
struct Clock {
    sd: f64,
    origin: f64,
    first: f64,
    period: f64,
    /// Per known touchdown: false for an outlier of the robust fit.
    inlier: Vec<bool>,
}

impl Clock {
    /// Step number of a time (counted from the first known touchdown).
    fn index(&self, t: f64) -> f64 {
        ((t - self.first) / self.period).round()
    }
    /// Due time of step `k`, s.
    fn tick(&self, k: f64) -> f64 {
        self.origin + k * self.period
    }
}

impl Policy for Phase {
    fn label(&self) -> &str {
        &self.spec
    }
    fn forecast_exposure_mmbm(&self, obs: &Observation, exposure_s: f64) -> Option<f64> {
        self.forecast_exposure(obs.now(), obs.timing, exposure_s)
    }
    fn prepare(&mut self, log: &LogView, _timing: &CameraTiming) -> Result<()> {
        self.x = self.level.resolve(log.mmbm)?;
        *self = Phase {
            x: self.x,
            ..Phase::new(&self.spec, self.level, self.horizon)
        };
        Ok(())
    }
    fn decide(&mut self, obs: &Observation) -> bool {
        for k in obs.unseen(self.hist.last_time()) {
            self.push(obs.t[k], obs.mmbm[k]);
        }
        let (t0, now) = (obs.t0, obs.now());
        // The fold looks back at most CYCLES + 1 periods of at most WINDOW / 2.
        let keep = Forecast::WINDOW.max((Self::CYCLES as f64 + 2.0) * Forecast::WINDOW / 2.0);
        self.hist.trim_before(now - keep - 1.0);
        if now - self.estimated_at >= Forecast::REESTIMATE {
            self.period = estimate_period(
                &self.hist,
                &mut self.bins,
                t0,
                now,
                Self::SHORTEST,
                Forecast::WINDOW.min(now - t0).max(Self::FIRST_WINDOW),
            );
            self.crossing = match (percentile(&self.bins, 25.0), percentile(&self.bins, 99.0)) {
                (Some(lo), Some(hi)) if self.period.is_some() && hi > lo => {
                    Some(lo + 0.5 * (hi - lo))
                }
                _ => None,
            };
            self.estimated_at = now;
        }
        if !(obs.camera_free && obs.interval_passed()) {
            return false;
        }
        let us: Vec<f64> = (0..=Forecast::GRID)
            .map(|q| q as f64 * self.horizon / Forecast::GRID as f64)
            .collect();
        let Some(e) = self.forecast(now, &us, obs.timing, obs.timing.exposure) else {
            return thesis_rule(obs.mmbm, self.x);
        };
        e[0] < self.x && e[1..].iter().all(|&v| e[0] <= v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::trigger::{parse_policy, run};

    /// A clocked gait (0.8 s, touchdowns jittered by up to 30 ms): a sharp
    /// transient per step on a 0.2 mm/s floor; `extra` adds spurious
    /// transients (a stumble) at the given times.
    fn gait(secs: f64, extra: &[f64]) -> (Vec<f64>, Vec<f64>) {
        let t: Vec<f64> = (0..(600.0 * secs) as usize)
            .map(|k| k as f64 / 600.0)
            .collect();
        let jitter = [0.0, 0.03, -0.02, 0.01, -0.03, 0.02, 0.0, -0.01];
        let mut td: Vec<f64> = (0..(secs / 0.8) as usize + 1)
            .map(|k| 0.8 * k as f64 + jitter[k % 8])
            .collect();
        td.extend_from_slice(extra);
        td.sort_by(f64::total_cmp);
        let m = t
            .iter()
            .map(|&x| {
                let k = td.partition_point(|&d| d <= x);
                let s = if k == 0 { 10.0 } else { x - td[k - 1] };
                0.2 + 1.5 * (-s / 0.03).exp()
            })
            .collect();
        (t, m)
    }

    #[test]
    fn robust_clock_ignores_a_stumble() {
        // A spurious transient 0.5 s after the touchdown at 16 s: a touchdown
        // off the clock, which the robust fit marks and the fold leaves out.
        let (t, m) = gait(17.0, &[16.5]);
        let mut p = Phase::new("phase:0.4", Level::Abs(0.4), 0.2);
        run(&t, &m, &mut p, &CameraTiming::default()).unwrap();
        assert!(p.touchdowns().any(|x| (x - 16.5).abs() < 0.01));
        let step = p.step_interval().unwrap();
        let c = p.clock(step).unwrap();
        let bad: Vec<f64> = p
            .touchdowns()
            .zip(&c.inlier)
            .filter(|(_, &ok)| !ok)
            .map(|(x, _)| x)
            .collect();
        assert_eq!(bad.len(), 1, "{bad:?}");
        assert!((bad[0] - 16.5).abs() < 0.01, "{bad:?}");
        assert!((c.period - 0.8).abs() < 0.01 && c.sd < 0.03, "{c:?}");
    }

    #[test]
    fn exposure_control_on_the_phase_forecast() {
        // Once locked, the forecast over the exposure sees the next
        // touchdown coming: frames triggered late in a step get an exposure
        // short enough to end before it, so the realised blur stays within
        // the budget far more often than with the decision sample's rule.
        let (t, m) = gait(40.0, &[]);
        let timing = CameraTiming::default();
        let over = |spec: &str| {
            let mut p = parse_policy(spec).unwrap();
            let f = run(&t, &m, p.as_mut(), &timing).unwrap();
            let late: Vec<_> = f.into_iter().filter(|f| f.trigger_t > 12.0).collect();
            let n = late
                .iter()
                .filter(|f| {
                    crate::camera::blur_px(f.mmbm_exposure_mm_s, f.exposure_s(), timing.pitch_mm)
                        > 3.5
                })
                .count();
            (n, late.len())
        };
        let (n_phase, k_phase) = over("phase:0.4+exp:3");
        assert!(k_phase >= 20, "{k_phase}");
        assert!(
            n_phase * 10 <= k_phase,
            "{n_phase} of {k_phase} over budget"
        );
        // Mid-step, a short exposure is forecast on the floor; one that
        // would end within the margin of the next tick is refused (infinite).
        let mut p = Phase::new("phase:0.4", Level::Abs(0.4), 0.2);
        let cut = t.partition_point(|&x| x < 20.5);
        run(&t[..cut], &m[..cut], &mut p, &timing).unwrap();
        let now = t[cut - 1];
        let c = p.clock(p.step_interval().unwrap()).unwrap();
        let last = p.touchdowns().last().unwrap();
        let next = c.tick(c.index(last) + 1.0);
        let short = p.forecast_exposure(now, &timing, 0.01).unwrap();
        assert!(short < 0.3, "{short}");
        let cross = next - now - timing.delay + 0.005;
        assert!(cross > 0.01 && cross < 0.4, "{cross}");
        assert_eq!(
            p.forecast_exposure(now, &timing, cross),
            Some(f64::INFINITY)
        );
    }
}
