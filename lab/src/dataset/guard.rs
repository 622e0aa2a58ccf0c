//! What keeps a dataset directory to one configuration.
//!
//! The **fingerprint** ([`Record`], `DIR/dataset.json`): SHA-256 of the
//! canonical JSON of everything that determines the items, that is every
//! configuration key except `count` and the texture folder's path, the
//! texture files' names, sizes and SHA-256 in its place, and each `log:`
//! source's decoded samples. `count` is left out because item `i` depends
//! only on the configuration and `i`: a set grows (a run with a larger
//! `count` adds items and keeps the others byte for byte, and records the
//! new count), and a set of 7 grown from 6 is the set made at 7 at once. A
//! smaller `count` than recorded is refused (items would be left out of the
//! manifest while still on disk). The first run writes the record; a run with
//! another fingerprint is refused, naming both; every manifest line carries
//! it, so `--merge` and `--verify` refuse items of another configuration.
//! The record is read and updated under a lock on the directory
//! ([`super::lock::DirLock`]), so two runs growing a set at once cannot
//! shrink it again.
//!
//! The locks that keep each shard to one writer: [`super::lock`].

use super::config::{DatasetConfig, MotionSource};
use super::item::Sources;
use super::lock::DirLock;
use crate::error::{show_path, Error, Result};
use serde::{Deserialize, Serialize};
use serde_json::Value;
use sha2::{Digest, Sha256};
use std::path::Path;

/// The fingerprint file in a dataset directory.
pub const RECORD: &str = "dataset.json";

/// The `format` of a [`Record`].
pub const FORMAT: &str = "mmbm-dataset-fingerprint-2";

/// The record format of mmbm before sets could grow (its fingerprint covered
/// `count`).
const FORMAT_1: &str = "mmbm-dataset-fingerprint-1";

/// `DIR/dataset.json`: the fingerprint of the inputs the items are made
/// from, and those inputs.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct Record {
    /// `FORMAT`.
    pub format: String,
    /// SHA-256 (hex) of the canonical JSON of `inputs`.
    pub fingerprint: String,
    /// Items of the dataset (the configuration's `count`; not in the
    /// fingerprint).
    pub count: u64,
    /// The configuration (texture folder as its files, no `count`) and the
    /// logs' digests.
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
        obj.remove("count");
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
        if r.format == FORMAT_1 {
            return wrong(format!(
                "made by an older mmbm (format {FORMAT_1}, whose fingerprint covered count): \
                 remake the set in a new --out"
            ));
        }
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
        if digest(&r.inputs) != r.fingerprint || r.inputs.get("count").is_some() {
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

    /// Records `self` in `out` if it has no record yet, else checks that the
    /// recorded fingerprint is this one and that `count` is at least the
    /// recorded one (a larger one is recorded: the set grows). A directory
    /// with items but no record is refused (their configuration is unknown).
    /// Done under `DirLock`, so concurrent runs see each other's record.
    pub fn claim(&self, out: &Path) -> Result<()> {
        let p = out.join(RECORD);
        let _dir = DirLock::take(out)?;
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
            if self.write(out, false)? {
                return Ok(());
            }
            // Recorded meanwhile (a file system without locks): compare.
        }
        let old = Record::read(out)?;
        if old.fingerprint != self.fingerprint {
            return Err(Error::invalid(
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
            ));
        }
        if self.count < old.count {
            return Err(Error::invalid(
                "count",
                format!(
                    "{} is less than the {} items {} records: a set grows but does not \
                     shrink (its manifest would leave out items still on disk); use count = {} \
                     or more, or a new --out for a smaller set",
                    self.count,
                    old.count,
                    show_path(&p),
                    old.count
                ),
            ));
        }
        if self.count > old.count {
            self.write(out, true)?;
        }
        Ok(())
    }

    /// Writes `self` as `out/dataset.json` (a temporary file renamed: over
    /// an existing one when `replace`, else create-only), with the
    /// permissions a new file gets under the process's umask. `Ok(false)`:
    /// create-only, and a record was there already.
    fn write(&self, out: &Path, replace: bool) -> Result<bool> {
        let p = out.join(RECORD);
        let text = serde_json::to_string_pretty(self)
            .map_err(|e| Error::invalid("dataset.json", e.to_string()))?;
        let mut tmp = crate::io::atomic::temp_builder(".mmbm-", ".tmp.json")
            .tempfile_in(out)
            .map_err(|e| Error::io(out, e))?;
        std::io::Write::write_all(&mut tmp, format!("{text}\n").as_bytes())
            .map_err(|e| Error::io(&p, e))?;
        let r = if replace {
            tmp.persist(&p).map(drop)
        } else {
            tmp.persist_noclobber(&p).map(drop)
        };
        match r {
            Ok(()) => Ok(true),
            Err(e) if !replace && e.error.kind() == std::io::ErrorKind::AlreadyExists => Ok(false),
            Err(e) => Err(Error::io(&p, e.error)),
        }
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
