//! The IMU log (docs/spec.md section 5), validated once: its samples in the camera
//! frame ([`GyroSample`]), strictly increasing finite times, the gap rule
//! (an interval over [`GAP_FACTOR`] x the median is a gap), the log's own
//! rolling-shutter readout where the file carries one (a Gyroflow `.gcsv`),
//! and the exposure average of a piecewise-linear series ([`Integral`]).
//!
//! Every reader (CSV, `.gcsv`, MCAP, a line stream) yields these samples;
//! [`ImuLog::new`] is the one place a whole log's times are checked, and
//! [`check_times`] the one place a bare time column is.

use crate::camera::{Camera, Readout};
use crate::error::{Error, Result};
use glam::DVec3;

/// One gyro sample in the camera frame.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct GyroSample {
    /// Time, s.
    pub t: f64,
    /// Angular velocity, rad/s.
    pub omega: DVec3,
    /// Linear velocity, m/s, when the log has `vx, vy, vz`.
    pub velocity: Option<DVec3>,
    /// Scene depth, m, when the log has `depth`.
    pub depth: Option<f64>,
}

/// Anything with a time stamp (s): a sample, or a bare time.
pub trait Timed {
    /// The time stamp, s.
    fn time(&self) -> f64;
}

impl Timed for GyroSample {
    fn time(&self) -> f64 {
        self.t
    }
}

impl Timed for f64 {
    fn time(&self) -> f64 {
        *self
    }
}

/// An interval longer than this many median intervals is a gap: no motion is
/// known inside it.
pub const GAP_FACTOR: f64 = 5.0;

/// True when the interval `dt` (s) is a gap for a log whose median interval
/// is `median_dt` (s).
pub fn is_gap(dt: f64, median_dt: f64) -> bool {
    dt > GAP_FACTOR * median_dt
}

/// How many intervals the streamed gap rule reads for its reference (the
/// first 101 of a long log); a shorter log uses all it has.
pub const GAP_REFERENCE_INTERVALS: usize = 101;

/// The fewest intervals (3 samples) the gap rule needs for a reference.
pub const MIN_GAP_INTERVALS: usize = 2;

/// The reference interval of the gap rule over `intervals` (s, sorted in
/// place): their median, the lower one of an even count (of 2 intervals,
/// the shorter: a 5 s gap after 10 ms is a gap). None for fewer than
/// [`MIN_GAP_INTERVALS`]. Of [`GAP_REFERENCE_INTERVALS`] (odd) it is the
/// middle one.
pub fn gap_reference(intervals: &mut [f64]) -> Option<f64> {
    if intervals.len() < MIN_GAP_INTERVALS {
        return None;
    }
    intervals.sort_by(f64::total_cmp);
    Some(intervals[(intervals.len() - 1) / 2])
}

/// Checks a time column: every time finite and strictly after the one before.
/// `what` names the series in the error (e.g. `"gyro log"`); the error gives
/// the index and both times.
pub fn check_times<T: Timed>(samples: &[T], what: &str) -> Result<()> {
    let mut prev: Option<f64> = None;
    for (i, s) in samples.iter().enumerate() {
        let t = s.time();
        if !t.is_finite() {
            return Err(Error::invalid(
                what,
                format!("time {t} at sample {i} is not finite"),
            ));
        }
        if let Some(p) = prev {
            if t <= p {
                return Err(Error::invalid(
                    what,
                    format!("time not strictly increasing at sample {i} (t = {t} s after {p} s)"),
                ));
            }
        }
        prev = Some(t);
    }
    Ok(())
}

/// The median interval between consecutive times, s (None for fewer than 2).
pub fn median_interval<T: Timed>(samples: &[T]) -> Option<f64> {
    let intervals: Vec<f64> = samples
        .windows(2)
        .map(|w| w[1].time() - w[0].time())
        .collect();
    crate::stats::percentile(&intervals, 50.0)
}

/// The shortest interval between consecutive times, s (None for fewer than 2).
pub fn min_interval<T: Timed>(samples: &[T]) -> Option<f64> {
    samples
        .windows(2)
        .map(|w| w[1].time() - w[0].time())
        .reduce(f64::min)
}

/// An interval a log's times must resolve is at least this many times the
/// spacing of its time stamps (f64 values near its largest |t|): 0.1 %.
pub const MIN_STEPS_PER_INTERVAL: f64 = 1000.0;

/// The spacing of f64 time stamps near `t` (s): the resolution of a time base
/// whose stamps reach `|t|`.
pub fn time_resolution(t: f64) -> f64 {
    let a = t.abs();
    if !a.is_finite() {
        return f64::INFINITY;
    }
    f64::from_bits(a.to_bits() + 1) - a
}

/// Checks that `interval_s` (an exposure, a frame interval, a delay; `what`
/// names it) is at least [`MIN_STEPS_PER_INTERVAL`] x the resolution of time
/// stamps that reach `t_max_abs` (s). Nanosecond epoch stamps read as
/// seconds (about 1.7e18 s, resolved to 256 s) fail here, with a hint.
pub fn check_resolution(t_max_abs: f64, interval_s: f64, what: &str) -> Result<()> {
    let res = time_resolution(t_max_abs);
    if interval_s > 0.0 && interval_s < MIN_STEPS_PER_INTERVAL * res {
        return Err(Error::invalid(
            "time base",
            format!(
                "the log's time stamps reach {t_max_abs:e} s, where f64 times are {res:e} s apart: \
                 too coarse for {what} of {interval_s} s (it needs stamps {MIN_STEPS_PER_INTERVAL} x finer). \
                 Are the stamps in another unit? Nanoseconds read as seconds are about 1.7e18: \
                 try --time-unit ns (or us, ms)"
            ),
        ));
    }
    Ok(())
}

/// The largest |t| of a time column (0 when empty).
pub fn max_abs_time<T: Timed>(samples: &[T]) -> f64 {
    match (samples.first(), samples.last()) {
        (Some(a), Some(b)) => a.time().abs().max(b.time().abs()),
        _ => 0.0,
    }
}

/// A log's own rolling-shutter readout (a `.gcsv` header's
/// `frame_readout_time` and `frame_readout_direction`).
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct LogReadout {
    /// Readout of the whole frame, s.
    pub readout_s: f64,
    /// Direction (None: not given; Gyroflow then assumes top to bottom).
    pub direction: Option<Readout>,
}

impl LogReadout {
    /// `camera` with `readout` where the camera has none (a global shutter);
    /// the camera's own readout, when it has one, wins. Returns the camera
    /// and whether the log's readout was applied.
    pub fn apply(readout: Option<LogReadout>, mut camera: Camera) -> Result<(Camera, bool)> {
        match readout {
            Some(r) if camera.shutter.is_global() => {
                camera.shutter.readout_s = r.readout_s;
                if let Some(d) = r.direction {
                    camera.shutter.direction = d;
                }
                camera.validate()?;
                Ok((camera, true))
            }
            _ => Ok((camera, false)),
        }
    }
}

/// A whole gyro log, validated: at least one sample, times finite and
/// strictly increasing, every value finite. Derefs to its samples.
#[derive(Debug, Clone, PartialEq, Default)]
pub struct ImuLog {
    samples: Vec<GyroSample>,
    median_dt: Option<f64>,
    min_dt: Option<f64>,
    readout: Option<LogReadout>,
}

impl ImuLog {
    /// Validates `samples` (the one place a whole log is checked).
    ///
    /// ```
    /// use glam::DVec3;
    /// use mmbm_core::model::log::{GyroSample, ImuLog};
    /// let s = |t| GyroSample { t, omega: DVec3::new(0.1, 0.0, 0.0), velocity: None, depth: None };
    /// let log = ImuLog::new(vec![s(0.0), s(0.005), s(0.01)])?;
    /// assert_eq!(log.median_interval(), Some(0.005));
    /// assert!(ImuLog::new(vec![s(0.0), s(0.0)]).is_err()); // time must increase
    /// # Ok::<(), mmbm_core::Error>(())
    /// ```
    pub fn new(samples: Vec<GyroSample>) -> Result<Self> {
        if samples.is_empty() {
            return Err(Error::invalid("gyro log", "no samples"));
        }
        check_times(&samples, "gyro log")?;
        for (i, s) in samples.iter().enumerate() {
            let finite = s.omega.is_finite()
                && s.velocity.is_none_or(|v| v.is_finite())
                && s.depth.is_none_or(f64::is_finite);
            if !finite {
                return Err(Error::invalid(
                    "gyro log",
                    format!("sample {i} (t = {} s) has a value that is not finite", s.t),
                ));
            }
        }
        let median_dt = median_interval(&samples);
        let min_dt = min_interval(&samples);
        Ok(ImuLog {
            samples,
            median_dt,
            min_dt,
            readout: None,
        })
    }

    /// The same log, carrying the file's own readout.
    pub fn with_readout(self, readout: Option<LogReadout>) -> Self {
        ImuLog { readout, ..self }
    }

    /// The samples.
    pub fn samples(&self) -> &[GyroSample] {
        &self.samples
    }

    /// The samples, owned.
    pub fn into_samples(self) -> Vec<GyroSample> {
        self.samples
    }

    /// The median interval between samples, s (None for one sample).
    pub fn median_interval(&self) -> Option<f64> {
        self.median_dt
    }

    /// The shortest interval between samples, s (None for one sample).
    pub fn min_interval(&self) -> Option<f64> {
        self.min_dt
    }

    /// The log's own readout, if its file gives one.
    pub fn readout(&self) -> Option<LogReadout> {
        self.readout
    }

    /// `camera` with the log's readout where the camera has none (a global
    /// shutter); the camera's own readout, when it has one, wins. Returns the
    /// camera and whether the log's readout was applied.
    pub fn apply_readout(&self, camera: Camera) -> Result<(Camera, bool)> {
        LogReadout::apply(self.readout, camera)
    }
}

impl std::ops::Deref for ImuLog {
    type Target = [GyroSample];
    fn deref(&self) -> &[GyroSample] {
        &self.samples
    }
}

impl<'a> IntoIterator for &'a ImuLog {
    type Item = &'a GyroSample;
    type IntoIter = std::slice::Iter<'a, GyroSample>;
    fn into_iter(self) -> Self::IntoIter {
        self.samples.iter()
    }
}

impl IntoIterator for ImuLog {
    type Item = GyroSample;
    type IntoIter = std::vec::IntoIter<GyroSample>;
    fn into_iter(self) -> Self::IntoIter {
        self.samples.into_iter()
    }
}

impl From<ImuLog> for Vec<GyroSample> {
    fn from(log: ImuLog) -> Self {
        log.samples
    }
}

impl TryFrom<Vec<GyroSample>> for ImuLog {
    type Error = Error;
    fn try_from(samples: Vec<GyroSample>) -> Result<Self> {
        ImuLog::new(samples)
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
        s.rebuild(t, m);
        s
    }

    /// Makes this the integral of `m` over times `t`, as [`Integral::new`]
    /// does (the same sums, bit for bit), reusing its buffers: no allocation
    /// once they hold `t.len()` samples.
    pub fn rebuild(&mut self, t: &[f64], m: &[f64]) {
        self.t.clear();
        self.m.clear();
        self.cum.clear();
        for (&a, &b) in t.iter().zip(m) {
            self.push(a, b);
        }
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

#[cfg(test)]
mod tests {
    use super::*;

    fn s(t: f64) -> GyroSample {
        GyroSample {
            t,
            omega: DVec3::new(0.1, 0.0, 0.0),
            velocity: None,
            depth: None,
        }
    }

    #[test]
    fn the_gap_reference_of_short_and_long_logs() {
        assert_eq!(gap_reference(&mut [0.01]), None);
        let r = gap_reference(&mut [5.0, 0.01]).unwrap();
        assert_eq!(r, 0.01);
        assert!(is_gap(5.0, r));
        // An odd count: the middle one, as the reference of 101 intervals.
        let mut v: Vec<f64> = (0..GAP_REFERENCE_INTERVALS).map(|i| i as f64).collect();
        v.reverse();
        assert_eq!(gap_reference(&mut v), Some(50.0));
    }

    #[test]
    fn a_log_is_validated_once() {
        let log = ImuLog::new(vec![s(0.0), s(0.01), s(0.02), s(0.1)]).unwrap();
        assert_eq!(log.len(), 4);
        assert_eq!(log.median_interval(), Some(0.01));
        assert!(is_gap(0.08, log.median_interval().unwrap()));
        assert!(!is_gap(0.05, 0.01));
        for bad in [
            vec![],
            vec![s(0.0), s(0.0)],
            vec![s(0.0), s(-1.0)],
            vec![s(f64::NAN)],
            vec![s(0.0), s(f64::INFINITY)],
        ] {
            assert!(ImuLog::new(bad).is_err());
        }
        let mut w = s(1.0);
        w.omega.y = f64::NAN;
        let e = ImuLog::new(vec![s(0.0), w]).unwrap_err().to_string();
        assert!(e.contains("sample 1"), "{e}");
        let e = check_times(&[0.0, 1.0, 1.0], "series")
            .unwrap_err()
            .to_string();
        assert!(e.contains("sample 2"), "{e}");
    }

    #[test]
    fn the_logs_readout_fills_a_global_shutter_only() {
        let log = ImuLog::new(vec![s(0.0), s(0.01)])
            .unwrap()
            .with_readout(Some(LogReadout {
                readout_s: 0.02,
                direction: Some(Readout::LeftToRight),
            }));
        let (cam, applied) = log.apply_readout(Camera::thesis()).unwrap();
        assert!(applied);
        assert_eq!(cam.shutter.readout_s, 0.02);
        assert_eq!(cam.shutter.direction, Readout::LeftToRight);
        let (again, applied) = log.apply_readout(cam).unwrap();
        assert!(!applied && again == cam);
    }

    /// Nanosecond epoch stamps read as seconds cannot time a 70 ms exposure;
    /// the same stamps in seconds can.
    #[test]
    fn a_time_base_too_coarse_for_the_exposure_is_refused() {
        assert_eq!(time_resolution(1.0), f64::EPSILON);
        assert_eq!(time_resolution(1.7e18), 256.0);
        let e = check_resolution(1.7e18, 0.07, "the exposure")
            .unwrap_err()
            .to_string();
        assert!(
            e.contains("--time-unit ns") && e.contains("the exposure"),
            "{e}"
        );
        assert!(check_resolution(1.7e9, 0.07, "the exposure").is_ok());
        assert!(check_resolution(1e308, 0.2, "the frame interval").is_err());
        assert!(check_resolution(f64::MAX, 1.0, "x").is_err());
        assert!(check_resolution(1e6, 1e-6, "x").is_ok());
        assert!(check_resolution(1e6, 1e-7, "x").is_err());
    }

    /// The running integral's mean is exact for a piecewise-linear series
    /// (by hand: the integral over [0.5, 2] of the hat through (0,0), (1,2),
    /// (3,0) is 0.5*(1+2)*0.5 + 0.5*(2+1)*1 = 2.25).
    #[test]
    fn integral_mean_is_exact_for_piecewise_linear() {
        let t = [0.0, 1.0, 3.0];
        let y = [0.0, 2.0, 0.0];
        let i = Integral::new(&t, &y);
        assert!((i.mean(0.5, 2.0) - 2.25 / 1.5).abs() < 1e-15);
        assert_eq!(i.mean(2.0, 2.0), 1.0);
        assert_eq!(i.mean(0.0, 3.0), 1.0);
    }
}
