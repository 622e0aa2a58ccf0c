//! Per-sample latency of a live stream in constant memory.

use std::time::Duration;

/// Latencies as a log-spaced histogram (16 buckets per octave of
/// nanoseconds, about 4 % wide) and the exact maximum: constant memory on an
/// endless stream.
#[derive(Debug, Clone, PartialEq)]
pub struct Latency {
    buckets: Vec<u64>,
    n: u64,
    max_ns: u64,
}

impl Default for Latency {
    fn default() -> Self {
        Self::new()
    }
}

impl Latency {
    const PER_OCTAVE: f64 = 16.0;
    const BUCKETS: usize = 64 * 16;

    /// No latencies yet.
    pub fn new() -> Self {
        Latency {
            buckets: vec![0; Self::BUCKETS + 1],
            n: 0,
            max_ns: 0,
        }
    }

    /// Adds one latency.
    pub fn add(&mut self, d: Duration) {
        let ns = d.as_nanos().min(u64::MAX as u128) as u64;
        let b = ((ns.max(1) as f64).log2() * Self::PER_OCTAVE) as usize;
        if let Some(c) = self.buckets.get_mut(b.min(Self::BUCKETS)) {
            *c += 1;
        }
        self.n += 1;
        self.max_ns = self.max_ns.max(ns);
    }

    /// Latencies added.
    pub fn len(&self) -> u64 {
        self.n
    }

    /// True before the first latency.
    pub fn is_empty(&self) -> bool {
        self.n == 0
    }

    /// The largest latency, us.
    pub fn max_us(&self) -> f64 {
        self.max_ns as f64 / 1e3
    }

    /// Upper edge (us) of the bucket holding the `q` quantile (at most the maximum).
    pub fn quantile_us(&self, q: f64) -> f64 {
        let need = ((q * self.n as f64).ceil() as u64).max(1);
        let mut cum = 0;
        for (b, &c) in self.buckets.iter().enumerate() {
            cum += c;
            if cum >= need {
                let edge = 2f64.powf((b + 1) as f64 / Self::PER_OCTAVE);
                return edge.min(self.max_ns as f64) / 1e3;
            }
        }
        self.max_us()
    }

    /// The one-line report of `mmbm live --stats`.
    pub fn report(&self) -> String {
        if self.n == 0 {
            return "latency: no samples".into();
        }
        format!(
            "latency (line read to decision written) over {} samples: p50 {:.1} us, p99 {:.1} us, max {:.1} us",
            self.n,
            self.quantile_us(0.5),
            self.quantile_us(0.99),
            self.max_us()
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn quantiles_within_a_bucket_and_never_above_the_maximum() {
        let mut l = Latency::new();
        assert_eq!(l.report(), "latency: no samples");
        for us in 1..=100u64 {
            l.add(Duration::from_micros(us));
        }
        assert_eq!(l.len(), 100);
        let p50 = l.quantile_us(0.5);
        assert!((50.0..=50.0 * 1.05).contains(&p50), "{p50}");
        let p99 = l.quantile_us(0.99);
        assert!((99.0..=100.0).contains(&p99), "{p99}");
        assert_eq!(l.max_us(), 100.0);
        assert!(l.report().contains("over 100 samples"), "{}", l.report());
    }

    #[test]
    fn extreme_durations_are_counted() {
        let mut l = Latency::new();
        l.add(Duration::ZERO);
        l.add(Duration::MAX);
        assert_eq!(l.len(), 2);
        assert_eq!(l.max_us(), u64::MAX as f64 / 1e3);
        assert!(l.quantile_us(0.5) <= 1e-3 * 2.0);
    }
}
