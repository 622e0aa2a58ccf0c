//! Making and resuming a dataset directory (merging and verifying:
//! [`super::manifest`]).
//!
//! Layout of `DIR`: `dataset.json` (the configuration's fingerprint, see
//! [`super::guard`]), `items/NNNNNNNN/` (the [`FILES`] and `item.json`, its
//! manifest line), `manifest.jsonl` (one line per item, by index) or, for a
//! shard, `manifest.part-K-of-N.jsonl`, and the lock files `.lock-K-of-N`,
//! `.lock-of-N`. An item directory is made under a hidden name and renamed
//! when complete, so a killed run never leaves a half item under its final
//! name, and a rerun skips complete items.

use super::config::DatasetConfig;
use super::guard::{short, Record};
use super::item::{make, plan, Sources, FILES};
use super::lock::RunLock;
use super::manifest::{item_dir, sum_file, write_manifest, ManifestLine};
use super::shard::Shard;
use crate::error::{show_path, Error, Result};
use crate::io::atomic::{write_atomic, PendingDir};
use std::collections::BTreeMap;
use std::path::Path;

/// Makes item `i` under `out` unless it is complete; returns its line.
/// A complete item must carry the run's fingerprint.
fn ensure_item(
    cfg: &DatasetConfig,
    src: &Sources,
    rec: &Record,
    out: &Path,
    i: u64,
) -> Result<ManifestLine> {
    let rel = item_dir(i);
    let fin = out.join(&rel);
    let json = fin.join("item.json");
    if json.exists() {
        let text = super::guard::read_json_file(&json)?;
        let line: ManifestLine = serde_json::from_str(&text).map_err(|e| Error::Config {
            path: json.clone(),
            message: crate::error::clip(&e.to_string(), crate::error::MAX_MESSAGE),
        })?;
        if line.index != i || line.fingerprint != rec.fingerprint {
            return Err(Error::invalid(
                show_path(&json),
                format!(
                    "item {} made with the configuration of fingerprint {}, where this run is \
                     item {i} of {}: use a new --out",
                    line.index,
                    short(&line.fingerprint),
                    rec.short()
                ),
            ));
        }
        return Ok(line);
    }
    let partial = out.join(format!(".partial-{i:08}"));
    if partial.exists() {
        // Left by a killed run of this item: the run lock makes this run the
        // only one making it.
        std::fs::remove_dir_all(&partial).map_err(|e| Error::io(&partial, e))?;
    }
    // Registered: an interrupt (SIGINT, SIGTERM, SIGHUP) removes it.
    let _guard = PendingDir::create(&partial)?;
    let result = make_item(cfg, src, rec, i, &partial).and_then(|line| {
        std::fs::rename(&partial, &fin).map_err(|e| Error::io(&fin, e))?;
        Ok(line)
    });
    if result.is_err() {
        let _ = std::fs::remove_dir_all(&partial);
    }
    result
}

/// Makes item `i` of the dataset into the existing directory `dir`: its
/// [`FILES`] and `item.json` (its manifest line, which it returns), the
/// same bytes `run` gives the item (the Python `BlurDataset` makes items
/// with it).
pub fn make_item(
    cfg: &DatasetConfig,
    src: &Sources,
    rec: &Record,
    i: u64,
    dir: &Path,
) -> Result<ManifestLine> {
    let params = plan(cfg, src, i)?;
    let measures = make(&params, src, dir)?;
    let mut files = BTreeMap::new();
    for f in FILES {
        files.insert(f.to_string(), sum_file(&dir.join(f))?);
    }
    let line = ManifestLine {
        index: i,
        dir: item_dir(i),
        fingerprint: rec.fingerprint.clone(),
        params,
        measures,
        files,
    };
    let text =
        serde_json::to_string(&line).map_err(|e| Error::invalid("manifest", e.to_string()))?;
    write_atomic(&dir.join("item.json"), |w| {
        writeln!(w, "{text}").map_err(|e| Error::io("item.json", e))
    })?;
    Ok(line)
}

/// True for a path (relative to the dataset folder) a run, `--merge` or
/// `--format webdataset` writes: `dataset.json`, the manifests, the lock
/// files and everything under `items/` and `webdataset/`.
pub fn writes(rel: &Path) -> bool {
    let mut parts = rel.components();
    let Some(first) = parts.next() else {
        return false;
    };
    let first = first.as_os_str().to_string_lossy();
    if first == "items" || first == "webdataset" {
        return true;
    }
    parts.next().is_none()
        && (first == super::guard::RECORD
            || first.starts_with(".lock-")
            || (first.starts_with("manifest") && first.ends_with(".jsonl")))
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
/// complete ones, then writes the shard's manifest. Refused: more shards
/// than items, another configuration than the one `out` was made with (its
/// fingerprint), and a run while another run of this shard (or of another
/// shard count) is writing `out`.
pub fn run(cfg: &DatasetConfig, out: &Path, shard: Shard, progress: bool) -> Result<RunSummary> {
    cfg.validate()?;
    shard.check_count(cfg.count)?;
    // The folder writable and no input (textures, logs) under a name
    // written there, before any work.
    let mut guard = crate::io::guard::OutputGuard::new()
        .output_dir("--out", Some(out), writes)
        .input("textures", Some(&cfg.textures));
    let logs: Vec<_> = cfg
        .motion
        .iter()
        .filter_map(|m| match super::config::MotionSource::parse(m) {
            Ok(super::config::MotionSource::Log(p)) => Some(p),
            _ => None,
        })
        .collect();
    for p in &logs {
        guard = guard.input("motion log:", Some(p));
    }
    guard.check()?;
    let src = Sources::open(cfg)?;
    let rec = Record::of(cfg, &src)?;
    std::fs::create_dir_all(out).map_err(|e| Error::io(out, e))?;
    let _lock = RunLock::take(out, shard)?;
    rec.claim(out)?;
    let items = out.join("items");
    std::fs::create_dir_all(&items).map_err(|e| Error::io(&items, e))?;
    let n_mine = shard.items(cfg.count);
    // n <= MAX_SHARDS: the step fits any usize of 32 bits or more.
    let mine = (shard.k - 1..cfg.count).step_by(shard.n as usize);
    let bar = crate::diagnostics::progress(progress, "items", n_mine);
    let t0 = std::time::Instant::now();
    let mut lines = Vec::new();
    let mut made = 0;
    for i in mine {
        let existed = out.join(item_dir(i)).join("item.json").exists();
        lines.push(ensure_item(cfg, &src, &rec, out, i)?);
        made += u64::from(!existed);
        bar.advance(1);
    }
    drop(bar);
    write_manifest(&out.join(shard.manifest_name()), &lines)?;
    Ok(RunSummary {
        items: n_mine,
        made,
        seconds: t0.elapsed().as_secs_f64(),
    })
}
