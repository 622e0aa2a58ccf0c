//! Checking WebDataset tar shards against their index without trusting
//! either (`mmbm dataset --verify`).
//!
//! A shard is read only when it is a regular file under its own name: a
//! symlink (wherever it leads), a pipe, a device or a directory among the
//! shards is refused unread, a file changed into a link between the look
//! and the open is caught (the open file must be the inode looked at). The
//! index is required whenever `DIR/webdataset/` exists; every shard it lists
//! must be there with its size and SHA-256, every file there must be listed,
//! and its item count must be the dataset's.

use super::guard::{short, Record};
use super::manifest::Problems;
use super::tarindex::{kind, read_index, shard_name, sum_regular, Kind, FOLDER, INDEX_FORMAT};
use crate::error::{show_path, Error, Result};
use std::collections::BTreeSet;
use std::path::Path;

/// Checks `out/webdataset/` against its `index.json`: the index present,
/// for this dataset, complete and of its item count; each listed shard a
/// regular file (not a link: refused unread) with its size and SHA-256; no
/// file there that the index does not list. Returns the number of shards,
/// `None` when there is no `webdataset/` folder.
pub fn verify_tars(out: &Path) -> Result<Option<usize>> {
    let dir = out.join(FOLDER);
    match kind(&dir)? {
        Kind::Missing => return Ok(None),
        Kind::Other if dir.is_dir() => {}
        _ => {
            return Err(Error::invalid(
                show_path(&dir),
                "is not a directory (a link or a file): not read",
            ))
        }
    }
    let index = dir.join("index.json");
    if matches!(kind(&index)?, Kind::Missing) {
        return Err(Error::invalid(
            show_path(&dir),
            "has no index.json, so its shards cannot be checked: pack again with \
             --merge --format webdataset (or remove the folder)",
        ));
    }
    let rec = Record::read(out)?;
    let ix = read_index(&index)?;
    let bad = |m: String| Err(Error::invalid(show_path(&index), m));
    if ix.format != INDEX_FORMAT || ix.fingerprint != rec.fingerprint {
        return bad(format!(
            "made from another dataset (fingerprint {})",
            short(&ix.fingerprint)
        ));
    }
    if !ix.complete {
        return bad(
            "incomplete (a packing run was stopped): rerun with --format webdataset".into(),
        );
    }
    let mut problems = Problems::default();
    if ix.count != rec.count {
        problems.push(format!(
            "index.json lists count {} where the dataset (dataset.json) has {}",
            ix.count, rec.count
        ));
    }
    let mut next = 0u64;
    let mut listed = BTreeSet::new();
    for (s, t) in ix.shards.iter().enumerate() {
        if t.name != shard_name(s) || t.first != next || t.items == 0 {
            return bad(format!(
                "shard {s} listed as {} from item {}",
                t.name, t.first
            ));
        }
        next = next.saturating_add(t.items);
        listed.insert(t.name.clone());
        let p = dir.join(&t.name);
        let shown = &t.name;
        match kind(&p)? {
            Kind::Missing => problems.push(format!("{shown} is missing")),
            Kind::Symlink => problems.push(format!("{shown} is a symbolic link, not read")),
            Kind::Other => problems.push(format!("{shown} is not a regular file, not read")),
            Kind::File(b) if b != t.bytes => problems.push(format!(
                "{shown}: {b} bytes where the index lists {}",
                t.bytes
            )),
            Kind::File(_) => match sum_regular(&p)? {
                Some((_, sha)) if sha == t.sha256 => {}
                Some((b, sha)) => problems.push(format!(
                    "{shown}: {b} bytes, SHA-256 {}, where the index lists {} bytes, {}",
                    short(&sha),
                    t.bytes,
                    short(&t.sha256)
                )),
                None => problems.push(format!("{shown} changed while being checked, not read")),
            },
        }
    }
    if next != rec.count {
        problems.push(format!(
            "the shards hold {next} items where the dataset has {}",
            rec.count
        ));
    }
    let rd = std::fs::read_dir(&dir).map_err(|e| Error::io(&dir, e))?;
    for e in rd {
        let e = e.map_err(|e| Error::io(&dir, e))?;
        let name = e.file_name().to_string_lossy().into_owned();
        if name != "index.json" && !listed.contains(&name) {
            problems.push(format!(
                "{} is not listed in index.json (not a shard of this packing)",
                crate::error::quote(&name)
            ));
        }
    }
    problems.result(&index)?;
    Ok(Some(ix.shards.len()))
}
