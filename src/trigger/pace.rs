//! Replay pacing: a recorded log's samples released at their own times
//! (scaled by a speed), with waits that saturate instead of overflowing and
//! that end early when the stream is told to stop.

use crate::error::{Error, Result};
pub use crate::limits::{MAX_REPLAY_SPEED, MIN_REPLAY_SPEED};
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

/// The last stretch of a wait spent spinning rather than asleep: a thread
/// woken from a long sleep runs its first microseconds on a cold core, which
/// a real driver's read loop would not.
const SPIN: Duration = Duration::from_micros(300);

/// The longest single sleep: how soon a stop request is seen during a wait.
pub(crate) const SLICE: Duration = Duration::from_millis(50);

/// Checks a replay speed: 0 (as fast as possible) or a finite number in
/// [`MIN_REPLAY_SPEED`, `MAX_REPLAY_SPEED`] (a slower replay would wait
/// forever: `--speed 1e-300`).
pub fn check_speed(speed: f64) -> Result<f64> {
    if speed == 0.0 || (MIN_REPLAY_SPEED..=MAX_REPLAY_SPEED).contains(&speed) {
        Ok(speed)
    } else {
        Err(Error::invalid(
            "replay speed",
            format!(
                "must be 0 (as fast as possible) or from {MIN_REPLAY_SPEED} to {MAX_REPLAY_SPEED:e} \
                 times real time, got {speed}"
            ),
        ))
    }
}

/// When a sample `offset_s` seconds after the first is due at `speed` (> 0),
/// counted from the replay's start: `Duration::MAX` when that is beyond what
/// a `Duration` holds (about 5.8e11 years), zero for a negative offset.
pub(crate) fn due(offset_s: f64, speed: f64) -> Duration {
    Duration::try_from_secs_f64((offset_s / speed).max(0.0)).unwrap_or(Duration::MAX)
}

/// Releases samples at their times since the first, divided by a speed.
#[derive(Debug)]
pub(crate) struct Pacer {
    speed: f64,
    start: Instant,
    t0: Option<f64>,
}

impl Pacer {
    /// A pacer starting now; `speed` 0 never waits.
    pub(crate) fn new(speed: f64) -> Result<Self> {
        Ok(Pacer {
            speed: check_speed(speed)?,
            start: Instant::now(),
            t0: None,
        })
    }

    /// Waits until the sample at time `t` (s) is due: asleep in slices of
    /// at most [`SLICE`] (watching `stop`), then spinning for the last
    /// [`SPIN`]. False when `stop` was set first.
    pub(crate) fn wait(&mut self, t: f64, stop: &AtomicBool) -> bool {
        if self.speed == 0.0 {
            return true;
        }
        let t0 = *self.t0.get_or_insert(t);
        let due = due(t - t0, self.speed);
        while let Some(left) = due.checked_sub(self.start.elapsed() + SPIN) {
            if stop.load(Ordering::Relaxed) {
                return false;
            }
            std::thread::sleep(left.min(SLICE));
        }
        while self.start.elapsed() < due {
            std::hint::spin_loop();
        }
        true
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn waits_saturate() {
        assert_eq!(due(1.0, 4.0), Duration::from_millis(250));
        assert_eq!(due(-1.0, 1.0), Duration::ZERO);
        assert_eq!(due(0.01, 1e-300), Duration::MAX);
        assert_eq!(due(0.01, 5e-324), Duration::MAX);
        assert_eq!(due(1.7e308, 1.0), Duration::MAX);
        assert_eq!(due(f64::INFINITY, 1.0), Duration::MAX);
    }

    #[test]
    fn speeds_checked() {
        for ok in [0.0, 1e-3, 4.0, 1e6] {
            assert_eq!(check_speed(ok).unwrap(), ok);
        }
        for bad in [
            -1.0,
            f64::NAN,
            f64::INFINITY,
            -0.0 - 1e-300,
            1e-300,
            5e-324,
            9.99e-4,
            1.01e6,
        ] {
            let e = check_speed(bad).unwrap_err().to_string();
            assert!(e.contains("replay speed"), "{e}");
        }
    }

    #[test]
    fn an_endless_wait_ends_at_stop() {
        let stop = AtomicBool::new(false);
        let mut p = Pacer::new(MIN_REPLAY_SPEED).unwrap();
        assert!(p.wait(0.0, &stop), "the first sample is due at once");
        std::thread::scope(|s| {
            s.spawn(|| {
                std::thread::sleep(Duration::from_millis(100));
                stop.store(true, Ordering::Relaxed);
            });
            assert!(!p.wait(1000.0, &stop));
        });
    }

    #[test]
    fn due_samples_wait_for_their_time() {
        let stop = AtomicBool::new(false);
        let mut p = Pacer::new(10.0).unwrap();
        let t = Instant::now();
        assert!(p.wait(5.0, &stop));
        assert!(p.wait(5.5, &stop));
        assert!(t.elapsed() >= Duration::from_millis(50));
        let mut fast = Pacer::new(0.0).unwrap();
        assert!(fast.wait(1e300, &stop));
    }
}
