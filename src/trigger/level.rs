//! A policy's MMBM threshold: a number (mm/s) or a percentile of the log's
//! own series ([`Level`]).

use crate::error::{Error, Result};
use crate::stats::percentile;

/// A threshold: an absolute MMBM (mm/s) or a percentile of the log's own series.
#[derive(Debug, Clone, Copy, PartialEq)]
pub enum Level {
    /// mm/s.
    Abs(f64),
    /// Percentile 0..100 of the whole log's MMBM.
    Percentile(f64),
}

impl Level {
    /// Parses `X` (mm/s, >= 0) or `pNN` (0 <= NN <= 100).
    pub fn parse(s: &str, what: &str) -> Result<Self> {
        let bad = || {
            Error::invalid(
                what,
                format!(
                    "'{s}': expected a threshold in mm/s (e.g. 0.4) or a percentile pNN (e.g. p20)"
                ),
            )
        };
        if let Some(p) = s.strip_prefix(['p', 'P']) {
            let q: f64 = p.parse().map_err(|_| bad())?;
            if !(0.0..=100.0).contains(&q) {
                return Err(bad());
            }
            return Ok(Level::Percentile(q));
        }
        let x: f64 = s.parse().map_err(|_| bad())?;
        if !(x.is_finite() && x >= 0.0) {
            return Err(bad());
        }
        Ok(Level::Abs(x))
    }

    /// The threshold in mm/s for a log whose MMBM series is `mmbm`.
    pub fn resolve(&self, mmbm: &[f64]) -> Result<f64> {
        match *self {
            Level::Abs(x) => Ok(x),
            Level::Percentile(q) => percentile(mmbm, q)
                .ok_or_else(|| Error::invalid("percentile threshold", "the MMBM series is empty")),
        }
    }
}
