//! Making, resuming, merging and verifying a dataset directory.
//!
//! Layout of `DIR`: `items/NNNNNNNN/` (the [`FILES`] and `item.json`, its
//! manifest line), `manifest.jsonl` (one line per item, by index) or, for a
//! shard, `manifest.part-K-of-N.jsonl`. An item directory is made under a
//! hidden name and renamed when complete, so a killed run never leaves a half
//! item under its final name, and a rerun skips complete items.

use super::config::DatasetConfig;
use super::item::{make, plan, ItemMeasures, ItemParams, Sources, FILES};
use crate::error::{Error, Result};
use crate::io::atomic::{write_atomic, PendingDir};
use serde::{Deserialize, Serialize};
use sha2::{Digest, Sha256};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

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

    /// Checks `1 <= k <= n`.
    pub fn new(k: u64, n: u64) -> Result<Self> {
        if n == 0 || k == 0 || k > n {
            return Err(Error::invalid(
                "shard",
                format!("{k}/{n}: the shard index must be in 1..={n} (and N >= 1)"),
            ));
        }
        Ok(Shard { k, n })
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

/// Size and SHA-256 of an item file.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct FileSum {
    /// Bytes.
    pub bytes: u64,
    /// SHA-256, hex.
    pub sha256: String,
}

/// One manifest line.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
pub struct ManifestLine {
    /// Item index.
    pub index: u64,
    /// Item directory, relative to the dataset directory.
    pub dir: String,
    /// Every parameter.
    pub params: ItemParams,
    /// What the item measured.
    #[serde(flatten)]
    pub measures: ItemMeasures,
    /// Its files.
    pub files: BTreeMap<String, FileSum>,
}

/// `items/NNNNNNNN`.
pub fn item_dir(i: u64) -> String {
    format!("items/{i:08}")
}

fn sum_file(p: &Path) -> Result<FileSum> {
    let bytes = std::fs::read(p).map_err(|e| Error::io(p, e))?;
    Ok(FileSum {
        bytes: bytes.len() as u64,
        sha256: format!("{:x}", Sha256::digest(&bytes)),
    })
}

/// Makes item `i` under `out` unless it is complete; returns its line.
fn ensure_item(cfg: &DatasetConfig, src: &Sources, out: &Path, i: u64) -> Result<ManifestLine> {
    let rel = item_dir(i);
    let fin = out.join(&rel);
    let json = fin.join("item.json");
    if json.exists() {
        let text = std::fs::read_to_string(&json).map_err(|e| Error::io(&json, e))?;
        return serde_json::from_str(&text)
            .map_err(|e| Error::invalid(json.display().to_string(), e.to_string()));
    }
    let partial = out.join(format!(".partial-{i:08}"));
    if partial.exists() {
        // Left by a killed run of this item (items are made by one shard only).
        std::fs::remove_dir_all(&partial).map_err(|e| Error::io(&partial, e))?;
    }
    // Registered: an interrupt (SIGINT, SIGTERM, SIGHUP) removes it.
    let _guard = PendingDir::create(&partial)?;
    let result = (|| {
        let params = plan(cfg, src, i)?;
        let measures = make(&params, src, &partial)?;
        let mut files = BTreeMap::new();
        for f in FILES {
            files.insert(f.to_string(), sum_file(&partial.join(f))?);
        }
        let line = ManifestLine {
            index: i,
            dir: rel.clone(),
            params,
            measures,
            files,
        };
        let text =
            serde_json::to_string(&line).map_err(|e| Error::invalid("manifest", e.to_string()))?;
        write_atomic(&partial.join("item.json"), |w| {
            writeln!(w, "{text}").map_err(|e| Error::io("item.json", e))
        })?;
        std::fs::rename(&partial, &fin).map_err(|e| Error::io(&fin, e))?;
        Ok(line)
    })();
    if result.is_err() {
        let _ = std::fs::remove_dir_all(&partial);
    }
    result
}

/// What a run did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct RunSummary {
    /// Items of this shard.
    pub items: u64,
    /// Of which made now (the rest were complete already).
    pub made: u64,
    /// Wall time, s.
    pub seconds: f64,
}

/// Makes the items of `shard` into `out` (created if needed), skipping
/// complete ones, then writes the shard's manifest.
pub fn run(cfg: &DatasetConfig, out: &Path, shard: Shard, progress: bool) -> Result<RunSummary> {
    cfg.validate()?;
    let src = Sources::open(cfg)?;
    let items = out.join("items");
    std::fs::create_dir_all(&items).map_err(|e| Error::io(&items, e))?;
    let mine: Vec<u64> = (shard.k - 1..cfg.count).step_by(shard.n as usize).collect();
    let bar = crate::diagnostics::progress(progress, "items", mine.len() as u64);
    let t0 = std::time::Instant::now();
    let mut lines = Vec::with_capacity(mine.len());
    let mut made = 0;
    for &i in &mine {
        let existed = out.join(item_dir(i)).join("item.json").exists();
        lines.push(ensure_item(cfg, &src, out, i)?);
        made += u64::from(!existed);
        bar.advance(1);
    }
    drop(bar);
    write_manifest(&out.join(shard.manifest_name()), &lines)?;
    Ok(RunSummary {
        items: mine.len() as u64,
        made,
        seconds: t0.elapsed().as_secs_f64(),
    })
}

fn write_manifest(path: &Path, lines: &[ManifestLine]) -> Result<()> {
    let mut text = String::new();
    for l in lines {
        text += &serde_json::to_string(l).map_err(|e| Error::invalid("manifest", e.to_string()))?;
        text.push('\n');
    }
    write_atomic(path, |w| {
        w.write_all(text.as_bytes()).map_err(|e| Error::io(path, e))
    })
}

fn read_manifest(path: &Path) -> Result<Vec<ManifestLine>> {
    let text = std::fs::read_to_string(path).map_err(|e| Error::io(path, e))?;
    text.lines()
        .enumerate()
        .filter(|(_, l)| !l.trim().is_empty())
        .map(|(k, l)| {
            serde_json::from_str(l).map_err(|e| Error::Parse {
                path: path.into(),
                line: k as u64 + 1,
                column: "-".into(),
                message: crate::error::clip(&e.to_string(), crate::error::MAX_MESSAGE),
            })
        })
        .collect()
}

/// Joins the shard manifests `manifest.part-K-of-N.jsonl` of `out` into
/// `manifest.jsonl` (by index); every part of one `N` must be there.
pub fn merge(out: &Path) -> Result<usize> {
    let rd = std::fs::read_dir(out).map_err(|e| Error::io(out, e))?;
    let mut parts: BTreeMap<u64, BTreeMap<u64, PathBuf>> = BTreeMap::new();
    for e in rd {
        let e = e.map_err(|e| Error::io(out, e))?;
        let name = e.file_name().to_string_lossy().into_owned();
        let Some(rest) = name
            .strip_prefix("manifest.part-")
            .and_then(|r| r.strip_suffix(".jsonl"))
        else {
            continue;
        };
        let Some((k, n)) = rest.split_once("-of-") else {
            continue;
        };
        if let (Ok(k), Ok(n)) = (k.parse::<u64>(), n.parse::<u64>()) {
            parts.entry(n).or_default().insert(k, e.path());
        }
    }
    let Some((&n, found)) = parts.iter().next() else {
        return Err(Error::invalid(
            out.display().to_string(),
            "no shard manifests (manifest.part-K-of-N.jsonl) to merge",
        ));
    };
    if parts.len() > 1 {
        let ns: Vec<String> = parts.keys().map(|n| n.to_string()).collect();
        return Err(Error::invalid(
            out.display().to_string(),
            format!(
                "shard manifests of different shard counts ({}): merge one set",
                ns.join(", ")
            ),
        ));
    }
    let missing: Vec<String> = (1..=n)
        .filter(|k| !found.contains_key(k))
        .map(|k| format!("{k}/{n}"))
        .collect();
    if !missing.is_empty() {
        return Err(Error::invalid(
            out.display().to_string(),
            format!(
                "shards not finished (no manifest part): {}",
                missing.join(", ")
            ),
        ));
    }
    let mut all = Vec::new();
    for p in found.values() {
        all.extend(read_manifest(p)?);
    }
    all.sort_by_key(|l| l.index);
    write_manifest(&out.join("manifest.jsonl"), &all)?;
    Ok(all.len())
}

/// Checks `out/manifest.jsonl` against the files: every item directory and
/// file present with its size and SHA-256, indices `0..count` each once.
/// Returns the number of items; the error lists what is wrong.
pub fn verify(out: &Path) -> Result<usize> {
    let lines = read_manifest(&out.join("manifest.jsonl"))?;
    let mut problems = Vec::new();
    for (k, l) in lines.iter().enumerate() {
        if l.index != k as u64 {
            problems.push(format!(
                "line {}: index {} where {k} was expected",
                k + 1,
                l.index
            ));
        }
        for (name, want) in &l.files {
            let p = out.join(&l.dir).join(name);
            match sum_file(&p) {
                Ok(got) if &got == want => {}
                Ok(_) => problems.push(format!("{}: size or SHA-256 differs", p.display())),
                Err(e) => problems.push(e.to_string()),
            }
        }
    }
    if problems.is_empty() {
        return Ok(lines.len());
    }
    let n = problems.len();
    problems.truncate(20);
    Err(Error::invalid(
        out.display().to_string(),
        format!("{n} problem(s): {}", problems.join("; ")),
    ))
}
