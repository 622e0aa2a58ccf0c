//! Manifests: writing them, merging shard parts, and verifying a dataset
//! directory against its manifest.
//!
//! A manifest is input (it may come from anywhere): `--verify` reads only
//! `DIR/dataset.json`, `DIR/manifest.jsonl` and the files of
//! `DIR/items/NNNNNNNN/` named by each line's index. A line's `dir` must be
//! exactly `items/NNNNNNNN` for its index, its `files` exactly the
//! [`FILES`] (each listed, nothing else), every file a non-empty regular
//! file inside `DIR` (a symlink leading out is refused, unread), its size
//! and SHA-256 as listed, `item.json` equal to the line, and the line's
//! fingerprint the directory's.

use super::guard::{sha256_of, short, Record, RECORD};
use super::item::{ItemMeasures, ItemParams, FILES};
use super::shard::Shard;
use crate::error::{quote, show_path, Error, Result};
use crate::io::atomic::write_atomic;
use crate::io::input::{line_too_long, open_file, read_line, Line, MAX_LINE_BYTES};
use serde::{Deserialize, Serialize};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

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
    /// The fingerprint of the configuration the item was made with (see
    /// `guard`).
    pub fingerprint: String,
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

/// Size and SHA-256 of the regular file `p`, read in bounded memory.
pub(crate) fn sum_file(p: &Path) -> Result<FileSum> {
    let mut f = open_file(p)?;
    let (bytes, sha256) = sha256_of(&mut f, p)?;
    Ok(FileSum { bytes, sha256 })
}

/// Writes `lines` as the manifest `path` (atomically).
pub(crate) fn write_manifest(path: &Path, lines: &[ManifestLine]) -> Result<()> {
    write_atomic(path, |w| {
        for l in lines {
            serde_json::to_writer(&mut *w, l)
                .map_err(|e| Error::invalid("manifest", e.to_string()))?;
            w.write_all(b"\n").map_err(|e| Error::io(path, e))?;
        }
        Ok(())
    })
}

/// Calls `f` with each line (1-based number, parsed) of the manifest
/// `path`, blank lines skipped; more than `max` lines, or one longer than
/// [`MAX_LINE_BYTES`], is an error. Returns the number of lines.
pub(crate) fn each_line(
    path: &Path,
    max: u64,
    mut f: impl FnMut(u64, ManifestLine) -> Result<()>,
) -> Result<u64> {
    let mut r = std::io::BufReader::new(open_file(path)?);
    let mut buf = Vec::new();
    let (mut number, mut n) = (0u64, 0u64);
    loop {
        number += 1;
        match read_line(&mut r, &mut buf, MAX_LINE_BYTES).map_err(|e| Error::io(path, e))? {
            Line::Eof => return Ok(n),
            Line::TooLong => return Err(line_too_long(path, number, MAX_LINE_BYTES)),
            Line::Read => {}
        }
        if buf.iter().all(u8::is_ascii_whitespace) {
            continue;
        }
        n += 1;
        if n > max {
            return Err(Error::invalid(
                path.display().to_string(),
                format!("more than {max} lines, the items it can list"),
            ));
        }
        let l = serde_json::from_slice(&buf).map_err(|e| Error::Parse {
            path: path.into(),
            line: number,
            column: "-".into(),
            message: crate::error::clip(&e.to_string(), crate::error::MAX_MESSAGE),
        })?;
        f(number, l)?;
    }
}

/// The `(K, N)` of `manifest.part-K-of-N.jsonl`, `None` for another name.
fn part_name(name: &str) -> Option<std::result::Result<(u64, u64), ()>> {
    let rest = name
        .strip_prefix("manifest.part-")?
        .strip_suffix(".jsonl")?;
    let parsed = rest
        .split_once("-of-")
        .and_then(|(k, n)| Some((k.parse().ok()?, n.parse().ok()?)));
    Some(parsed.ok_or(()))
}

/// Joins the shard manifests `manifest.part-K-of-N.jsonl` of `out` into
/// `manifest.jsonl` (by index). Every part of one `N` must be there, `N`
/// within the shard cap ([`super::shard::MAX_SHARDS`], and at most one shard
/// per item), each part's lines items of its shard made with the
/// directory's fingerprint, and the whole exactly the items `0..count`.
pub fn merge(out: &Path) -> Result<usize> {
    let rec = Record::read(out)?;
    let here = out.display().to_string();
    let rd = std::fs::read_dir(out).map_err(|e| Error::io(out, e))?;
    let mut parts: BTreeMap<u64, BTreeMap<u64, PathBuf>> = BTreeMap::new();
    for e in rd {
        let e = e.map_err(|e| Error::io(out, e))?;
        let name = e.file_name().to_string_lossy().into_owned();
        let bad = |m: String| Error::invalid(show_path(&e.path()), m);
        let (k, n) = match part_name(&name) {
            None => continue,
            Some(Err(())) => {
                return Err(bad(
                    "not a shard manifest name (manifest.part-K-of-N.jsonl)".into(),
                ))
            }
            Some(Ok(kn)) => kn,
        };
        let sh = Shard::new(k, n).map_err(|x| bad(x.to_string()))?;
        sh.check_count(rec.count).map_err(|x| bad(x.to_string()))?;
        parts.entry(n).or_default().insert(k, e.path());
    }
    let Some((&n, found)) = parts.iter().next() else {
        return Err(Error::invalid(
            here,
            "no shard manifests (manifest.part-K-of-N.jsonl) to merge",
        ));
    };
    if parts.len() > 1 {
        let ns: Vec<String> = parts.keys().map(|n| n.to_string()).collect();
        return Err(Error::invalid(
            here,
            format!(
                "shard manifests of different shard counts ({}): merge one set",
                ns.join(", ")
            ),
        ));
    }
    // n is at most MAX_SHARDS here: counting the missing ones is bounded.
    let missing = (1..=n).filter(|k| !found.contains_key(k));
    let count = missing.clone().count();
    if count > 0 {
        let first: Vec<String> = missing.take(10).map(|k| format!("{k}/{n}")).collect();
        return Err(Error::invalid(
            here,
            format!(
                "{count} shard(s) not finished (no manifest part): {}{}",
                first.join(", "),
                if count > 10 { ", ..." } else { "" }
            ),
        ));
    }
    let mut all = Vec::new();
    for (&k, p) in found {
        let sh = Shard { k, n };
        each_line(p, sh.items(rec.count), |number, l| {
            let at = || format!("{}:{number}", show_path(p));
            if l.fingerprint != rec.fingerprint {
                return Err(Error::invalid(
                    at(),
                    format!(
                        "item {} was made with another configuration (fingerprint {}; {} has {}): \
                         parts of different configurations cannot be merged",
                        l.index,
                        short(&l.fingerprint),
                        RECORD,
                        rec.short()
                    ),
                ));
            }
            if l.index >= rec.count || !sh.has(l.index) {
                return Err(Error::invalid(
                    at(),
                    format!(
                        "item {} is not an item of shard {k}/{n} of {}",
                        l.index, rec.count
                    ),
                ));
            }
            all.push(l);
            Ok(())
        })?;
    }
    all.sort_by_key(|l| l.index);
    if let Some(w) = all.windows(2).find(|w| w[0].index == w[1].index) {
        return Err(Error::invalid(
            here,
            format!("item {} is listed twice", w[0].index),
        ));
    }
    if all.len() as u64 != rec.count {
        let gap = (0..rec.count)
            .zip(
                all.iter()
                    .map(|l| Some(l.index))
                    .chain(std::iter::repeat(None)),
            )
            .find(|(i, l)| Some(*i) != *l)
            .map_or(0, |(i, _)| i);
        return Err(Error::invalid(
            here,
            format!(
                "the parts list {} of {} items (item {gap} is missing): rerun its shard",
                all.len(),
                rec.count
            ),
        ));
    }
    write_manifest(&out.join("manifest.jsonl"), &all)?;
    Ok(all.len())
}

/// The problems `--verify` found: how many, and the first few.
#[derive(Default)]
pub(crate) struct Problems {
    n: u64,
    first: Vec<String>,
}

impl Problems {
    const SHOWN: usize = 4;

    pub(crate) fn push(&mut self, p: String) {
        self.n += 1;
        if self.first.len() < Self::SHOWN {
            self.first.push(p);
        }
    }

    /// `Ok(())` when there are none, else the error for `what`: how many,
    /// and the first few.
    pub(crate) fn result(&self, what: &Path) -> Result<()> {
        if self.n == 0 {
            return Ok(());
        }
        Err(Error::invalid(
            what.display().to_string(),
            format!(
                "{} problem(s): {}{}",
                self.n,
                self.first.join("; "),
                if self.n > Self::SHOWN as u64 {
                    "; ..."
                } else {
                    ""
                }
            ),
        ))
    }
}

/// What is wrong with the item file `p` (`want`: its listed sum, `None`
/// for `item.json`), confined to `root` (canonical); `None` if nothing.
fn check_file(root: &Path, p: &Path, want: Option<&FileSum>) -> Option<String> {
    let shown = show_path(p);
    let canon = match std::fs::canonicalize(p) {
        Ok(c) => c,
        Err(e) => return Some(format!("{shown}: {e}")),
    };
    if !canon.starts_with(root) {
        return Some(format!(
            "{shown}: leads outside the dataset directory (to {}), not read",
            show_path(&canon)
        ));
    }
    let len = match std::fs::metadata(&canon) {
        Ok(m) if m.is_file() => m.len(),
        Ok(_) => return Some(format!("{shown}: is not a regular file")),
        Err(e) => return Some(format!("{shown}: {e}")),
    };
    if len == 0 || want.is_some_and(|w| w.bytes == 0) {
        return Some(format!("{shown}: is empty"));
    }
    let want = want?;
    if len != want.bytes {
        return Some(format!(
            "{shown}: {len} bytes where the manifest lists {}",
            want.bytes
        ));
    }
    match sum_file(&canon) {
        Ok(got) if got.sha256 == want.sha256 => None,
        Ok(_) => Some(format!("{shown}: SHA-256 differs")),
        Err(e) => Some(e.to_string()),
    }
}

/// Checks one manifest line (the `k`-th, 0-based) of the dataset `out`.
fn check_line(out: &Path, root: &Path, rec: &Record, k: u64, l: &ManifestLine, p: &mut Problems) {
    if l.index != k || l.params.index != l.index {
        p.push(format!(
            "line {}: index {} where {k} was expected",
            k + 1,
            l.index
        ));
    }
    if l.fingerprint != rec.fingerprint {
        p.push(format!(
            "line {}: made with another configuration (fingerprint {}; {RECORD} has {})",
            k + 1,
            short(&l.fingerprint),
            rec.short()
        ));
    }
    if l.dir != item_dir(l.index) {
        p.push(format!(
            "line {}: dir {} is not {} (an item's directory is named by its index; \
             nothing else is read)",
            k + 1,
            quote(&l.dir),
            item_dir(l.index)
        ));
        return;
    }
    for name in l.files.keys().filter(|n| !FILES.contains(&n.as_str())) {
        p.push(format!(
            "line {}: {} is not a file of an item ({})",
            k + 1,
            quote(name),
            FILES.join(", ")
        ));
    }
    let unlisted: Vec<&str> = FILES
        .into_iter()
        .filter(|f| !l.files.contains_key(*f))
        .collect();
    if !unlisted.is_empty() {
        p.push(format!(
            "line {}: {} not listed (every item has {})",
            k + 1,
            unlisted.join(", "),
            FILES.join(", ")
        ));
    }
    let dir = out.join(&l.dir);
    for (f, want) in FILES.iter().filter_map(|f| Some((f, l.files.get(*f)?))) {
        if let Some(e) = check_file(root, &dir.join(f), Some(want)) {
            p.push(e);
        }
    }
    let json = dir.join("item.json");
    if let Some(e) = check_file(root, &json, None) {
        return p.push(e);
    }
    let same = super::guard::read_json_file(&json)
        .ok()
        .and_then(|t| serde_json::from_str::<ManifestLine>(&t).ok())
        .is_some_and(|x| &x == l);
    if !same {
        p.push(format!(
            "{}: differs from its manifest line",
            show_path(&json)
        ));
    }
}

/// Checks `out/manifest.jsonl` against the files (see the module docs):
/// every item `0..count` once, in order. Returns the number of items; the
/// error counts the problems and shows the first few.
pub fn verify(out: &Path) -> Result<usize> {
    let rec = Record::read(out)?;
    let root = std::fs::canonicalize(out).map_err(|e| Error::io(out, e))?;
    let mut problems = Problems::default();
    let mut k = 0u64;
    each_line(&out.join("manifest.jsonl"), rec.count, |_, l| {
        check_line(out, &root, &rec, k, &l, &mut problems);
        k += 1;
        Ok(())
    })?;
    if k != rec.count {
        problems.push(format!(
            "{k} items listed where the configuration ({RECORD}) has {}",
            rec.count
        ));
    }
    problems.result(out)?;
    Ok(k as usize)
}
