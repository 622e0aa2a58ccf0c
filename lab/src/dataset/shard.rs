//! Shards: which items one task of a split makes, and the shard cap.

use crate::error::{Error, Result};

/// Most shards a dataset may be split into (and never more than its items):
/// a SLURM job array or a Kubernetes Indexed Job of this many tasks is far
/// beyond what either schedules.
pub const MAX_SHARDS: u64 = 1_000_000;

/// Shard `k` of `n` (1-based `k`): the items `i` with `i mod n = k - 1`.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Shard {
    /// 1..=n.
    pub k: u64,
    /// Number of shards.
    pub n: u64,
}

impl Shard {
    /// The whole set.
    pub const ALL: Shard = Shard { k: 1, n: 1 };

    /// `K/N`.
    pub fn parse(s: &str) -> Result<Self> {
        let bad = |m: String| Error::invalid("--shard", m);
        let (k, n) = s.split_once('/').ok_or_else(|| {
            bad(format!(
                "{}: expected K/N, e.g. 3/8",
                crate::error::quote(s)
            ))
        })?;
        let k: u64 = k
            .trim()
            .parse()
            .map_err(|_| bad(format!("K '{k}' is not a whole number")))?;
        let n: u64 = n
            .trim()
            .parse()
            .map_err(|_| bad(format!("N '{n}' is not a whole number")))?;
        Shard::new(k, n)
    }

    /// Checks `1 <= k <= n <= MAX_SHARDS`.
    pub fn new(k: u64, n: u64) -> Result<Self> {
        if n == 0 || n > MAX_SHARDS {
            return Err(Error::invalid(
                "shard",
                format!("{k}/{n}: the number of shards N must be in 1..={MAX_SHARDS}"),
            ));
        }
        if k == 0 || k > n {
            return Err(Error::invalid(
                "shard",
                format!("{k}/{n}: the shard index must be in 1..={n}"),
            ));
        }
        Ok(Shard { k, n })
    }

    /// Checks that a dataset of `count` items has at least `n` (one item
    /// per shard at least).
    pub fn check_count(&self, count: u64) -> Result<()> {
        if self.n > count {
            return Err(Error::invalid(
                "shard",
                format!(
                    "{}/{}: {} shards for {count} items (at most one shard per item)",
                    self.k, self.n, self.n
                ),
            ));
        }
        Ok(())
    }

    /// How many of the items `0..count` are this shard's.
    pub fn items(&self, count: u64) -> u64 {
        if self.k > count {
            0
        } else {
            (count - self.k) / self.n + 1
        }
    }

    /// True for item `i`.
    pub fn has(&self, i: u64) -> bool {
        i % self.n == self.k - 1
    }

    /// The manifest file this shard writes.
    pub fn manifest_name(&self) -> String {
        if self.n == 1 {
            "manifest.jsonl".into()
        } else {
            format!("manifest.part-{}-of-{}.jsonl", self.k, self.n)
        }
    }
}
