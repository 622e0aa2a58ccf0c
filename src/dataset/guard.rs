//! What keeps a dataset directory to one configuration and each shard to
//! one writer.
//!
//! - The **fingerprint** ([`Record`], `DIR/dataset.json`): SHA-256 of the
//!   canonical JSON of everything that determines the items, that is every
//!   configuration key except the texture folder's path, the texture files'
//!   names, sizes and SHA-256 in its place, and each `log:` source's decoded
//!   samples. The first run writes it (create-only, so two first runs at once
//!   cannot both win); a run with another fingerprint is refused, naming
//!   both; every manifest line carries it, so `--merge` and `--verify` refuse
//!   items of another configuration.
//! - The **lock** ([`RunLock`]): a run holds an exclusive advisory lock
//!   (`flock`) on `DIR/.lock-K-of-N` and a shared one on `DIR/.lock-of-N`;
//!   the operating system drops them when the process ends, however it ends
//!   (kill -9 included). A second run of the same shard, or a run with
//!   another shard count while one is writing, is refused.

use super::config::{DatasetConfig, MotionSource};
use super::item::Sources;
use super::shard::Shard;
use crate::error::{show_path, Error, Result};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use sha2::{Digest, Sha256};
use std::fs::File;
use std::path::{Path, PathBuf};

/// The fingerprint file in a dataset directory.
pub const RECORD: &str = "dataset.json";

/// The `format` of a [`Record`].
pub const FORMAT: &str = "mmbm-dataset-fingerprint-1";

/// `DIR/dataset.json`: the fingerprint of the inputs the items are made
/// from, and those inputs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Record {
    /// `FORMAT`.
    pub format: String,
    /// SHA-256 (hex) of the canonical JSON of `inputs`.
    pub fingerprint: String,
    /// Items of the dataset (the configuration's `count`).
    pub count: u64,
    /// The configuration (texture folder as its files) and the logs' digests.
    pub inputs: Value,
}

/// Streams `r` into SHA-256; returns (bytes, hex digest).
pub(crate) fn sha256_of(r: &mut dyn std::io::Read, path: &Path) -> Result<(u64, String)> {
    let mut h = Sha256::new();
    let n = std::io::copy(r, &mut h).map_err(|e| Error::io(path, e))?;
    Ok((n, format!("{:x}", h.finalize())))
}

/// Reads a JSON file of the dataset directory (`dataset.json`, an
/// `item.json`): a regular file only (a pipe there would block), at most
/// [`crate::io::input::MAX_TEXT_BYTES`].
pub(crate) fn read_json_file(p: &Path) -> Result<String> {
    use std::io::Read;
    let cap = crate::io::input::MAX_TEXT_BYTES;
    let mut s = String::new();
    crate::io::input::open_file(p)?
        .take(cap + 1)
        .read_to_string(&mut s)
        .map_err(|e| Error::io(p, e))?;
    if s.len() as u64 > cap {
        return Err(Error::invalid(
            show_path(p),
            format!("longer than {cap} bytes, the most read"),
        ));
    }
    Ok(s)
}

/// `v` as JSON with every object's keys sorted (whatever map type
/// serde_json was built with).
fn canonical(v: &Value) -> String {
    match v {
        Value::Object(m) => {
            let mut keys: Vec<&String> = m.keys().collect();
            keys.sort();
            let body: Vec<String> = keys
                .iter()
                .map(|k| format!("{}:{}", Value::String((*k).clone()), canonical(&m[*k])))
                .collect();
            format!("{{{}}}", body.join(","))
        }
        Value::Array(a) => {
            let body: Vec<String> = a.iter().map(canonical).collect();
            format!("[{}]", body.join(","))
        }
        other => other.to_string(),
    }
}

fn digest(v: &Value) -> String {
    format!("{:x}", Sha256::digest(canonical(v).as_bytes()))
}

impl Record {
    /// The record of `cfg` with its opened sources: reads every texture file
    /// once (SHA-256).
    pub fn of(cfg: &DatasetConfig, src: &Sources) -> Result<Self> {
        let bad = |e: serde_json::Error| Error::invalid("dataset config", e.to_string());
        let mut inputs = serde_json::to_value(cfg).map_err(bad)?;
        let mut textures = Vec::new();
        for name in &src.textures {
            let (bytes, sha256) = src.texture_sum(name)?;
            textures.push(serde_json::json!({"name": name, "bytes": bytes, "sha256": sha256}));
        }
        let mut logs = serde_json::Map::new();
        for m in &cfg.motion {
            if let MotionSource::Log(p) = MotionSource::parse(m)? {
                logs.insert(m.clone(), Value::String(src.log_digest(&p)?));
            }
        }
        let obj = inputs
            .as_object_mut()
            .ok_or_else(|| Error::invalid("dataset config", "is not a table"))?;
        obj.insert("textures".into(), Value::Array(textures));
        // `sharp = "start"` was what every configuration made before the key
        // existed: left out, so those directories keep their fingerprint.
        if cfg.sharp.is_start() {
            obj.remove("sharp");
        }
        obj.insert("logs".into(), Value::Object(logs));
        Ok(Record {
            format: FORMAT.into(),
            fingerprint: digest(&inputs),
            count: cfg.count,
            inputs,
        })
    }

    /// Reads and checks `DIR/dataset.json` (its fingerprint must be the
    /// digest of its inputs).
    pub fn read(out: &Path) -> Result<Self> {
        let p = out.join(RECORD);
        if !p.exists() {
            return Err(Error::invalid(
                out.display().to_string(),
                format!(
                    "no {RECORD} (the fingerprint of the configuration the items were made \
                     with): not a dataset directory, or made by an older mmbm"
                ),
            ));
        }
        let text = read_json_file(&p)?;
        let r: Record = serde_json::from_str(&text).map_err(|e| Error::Config {
            path: p.clone(),
            message: crate::error::clip(&e.to_string(), crate::error::MAX_MESSAGE),
        })?;
        let wrong = |m: String| Err(Error::invalid(p.display().to_string(), m));
        if r.format != FORMAT {
            return wrong(format!("format '{}' is not {FORMAT}", r.format));
        }
        if r.count == 0 || r.count > super::config::MAX_COUNT {
            return wrong(format!(
                "count {} is not in 1..={}",
                r.count,
                super::config::MAX_COUNT
            ));
        }
        if digest(&r.inputs) != r.fingerprint
            || r.inputs.get("count") != Some(&Value::from(r.count))
        {
            return wrong(
                "the fingerprint is not the digest of the inputs recorded: the file was edited"
                    .into(),
            );
        }
        Ok(r)
    }

    /// The first 16 hex digits, for messages.
    pub fn short(&self) -> &str {
        short(&self.fingerprint)
    }

    /// Records `self` in `out` if it has no record yet (create-only), else
    /// checks that the recorded fingerprint is this one. A directory with
    /// items but no record is refused (their configuration is unknown).
    pub fn claim(&self, out: &Path) -> Result<()> {
        let p = out.join(RECORD);
        if !p.exists() {
            let items = out.join("items");
            let any = std::fs::read_dir(&items).is_ok_and(|mut r| r.next().is_some());
            if any {
                return Err(Error::invalid(
                    out.display().to_string(),
                    format!(
                        "has items but no {RECORD}, so the configuration they were made with \
                         is unknown (made by an older mmbm?): use a new --out"
                    ),
                ));
            }
            let text = serde_json::to_string_pretty(self)
                .map_err(|e| Error::invalid("dataset.json", e.to_string()))?;
            let mut tmp = tempfile::Builder::new()
                .prefix(".mmbm-")
                .suffix(".tmp.json")
                .tempfile_in(out)
                .map_err(|e| Error::io(out, e))?;
            std::io::Write::write_all(&mut tmp, format!("{text}\n").as_bytes())
                .map_err(|e| Error::io(&p, e))?;
            match tmp.persist_noclobber(&p) {
                Ok(_) => return Ok(()),
                // Another first run recorded one meanwhile: compare with it.
                Err(e) if e.error.kind() == std::io::ErrorKind::AlreadyExists => {}
                Err(e) => return Err(Error::io(&p, e.error)),
            }
        }
        let old = Record::read(out)?;
        if old.fingerprint == self.fingerprint {
            return Ok(());
        }
        Err(Error::invalid(
            out.display().to_string(),
            format!(
                "was made with another configuration (fingerprint {} in {}), not this one \
                 (fingerprint {}; differs in: {}): use a new --out for this configuration, \
                 or rerun with the one the directory was made with",
                old.short(),
                show_path(&p),
                self.short(),
                differences(&old.inputs, &self.inputs)
            ),
        ))
    }
}

/// The first 16 hex digits of a fingerprint.
pub fn short(f: &str) -> &str {
    f.get(..16).unwrap_or(f)
}

/// The top-level keys whose values differ between two inputs objects.
fn differences(a: &Value, b: &Value) -> String {
    let (Some(a), Some(b)) = (a.as_object(), b.as_object()) else {
        return "everything".into();
    };
    let mut keys: Vec<&String> = a.keys().chain(b.keys()).collect();
    keys.sort();
    keys.dedup();
    let d: Vec<&str> = keys
        .into_iter()
        .filter(|k| a.get(*k) != b.get(*k))
        .map(|k| k.as_str())
        .collect();
    if d.is_empty() {
        "the recorded inputs".into()
    } else {
        d.join(", ")
    }
}

/// The locks a run holds on its dataset directory (released on drop and
/// when the process ends).
#[derive(Debug)]
pub struct RunLock {
    _shard: File,
    _count: File,
}

fn lock_file(p: &Path) -> Result<File> {
    std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(true)
        .truncate(false)
        .open(p)
        .map_err(|e| Error::io(p, e))
}

/// `Ok(true)`: locked; `Ok(false)`: another process holds it.
fn try_lock(f: &File, p: &Path, shared: bool) -> Result<bool> {
    use fs4::FileExt;
    let r = if shared {
        FileExt::try_lock_shared(f)
    } else {
        FileExt::try_lock(f)
    };
    match r {
        Ok(()) => Ok(true),
        Err(fs4::TryLockError::WouldBlock) => Ok(false),
        Err(fs4::TryLockError::Error(e)) => Err(Error::io(p, e)),
    }
}

impl RunLock {
    /// Takes the locks of `shard` on `out` (an existing directory), or
    /// refuses: another run of this shard, or of another shard count, is
    /// writing `out`.
    pub fn take(out: &Path, shard: Shard) -> Result<Self> {
        let busy = |what: String, lock: &Path| {
            Error::invalid(
                out.display().to_string(),
                format!(
                    "another run is writing this directory ({what}; it holds {}): wait for it \
                     to end, or use another --out",
                    show_path(lock)
                ),
            )
        };
        let own = out.join(format!(".lock-{}-of-{}", shard.k, shard.n));
        let shard_file = lock_file(&own)?;
        if !try_lock(&shard_file, &own, false)? {
            return Err(busy(
                format!("a run of shard {}/{}", shard.k, shard.n),
                &own,
            ));
        }
        let count = out.join(format!(".lock-of-{}", shard.n));
        let count_file = lock_file(&count)?;
        if !try_lock(&count_file, &count, true)? {
            return Err(busy(
                format!("a run split into {} shards is probing it", shard.n),
                &count,
            ));
        }
        // Shards of another count make some of the same items: refuse while
        // any such run holds its count's lock (each run takes its own shared
        // lock before looking, so of two such runs at least one sees the other).
        let rd = std::fs::read_dir(out).map_err(|e| Error::io(out, e))?;
        for e in rd {
            let e = e.map_err(|e| Error::io(out, e))?;
            let name = e.file_name().to_string_lossy().into_owned();
            let Some(n) = name.strip_prefix(".lock-of-") else {
                continue;
            };
            if n == shard.n.to_string() {
                continue;
            }
            let p: PathBuf = e.path();
            let f = lock_file(&p)?;
            if !try_lock(&f, &p, false)? {
                return Err(busy(
                    format!(
                        "a run split into {n} shard(s), which shares items with this split into {}",
                        shard.n
                    ),
                    &p,
                ));
            }
        }
        Ok(RunLock {
            _shard: shard_file,
            _count: count_file,
        })
    }
}
