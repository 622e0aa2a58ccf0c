//! WebDataset output: a verified dataset directory packed into tar shards
//! that stream (the `webdataset` Python package, the Hugging Face hub's
//! WebDataset loader).
//!
//! Layout of `DIR/webdataset/`: `mmbm-000000.tar`, `mmbm-000001.tar`, ...
//! and `index.json` (the fingerprint, the shard size and per shard its
//! first item, item count, bytes and SHA-256). One sample is one item: its
//! members share the key `NNNNNNNN` (the item index, 8 digits) and are
//! `KEY.json` (the item's manifest line, `item.json`) then the item files
//! (`KEY.blurred.exr`, `KEY.blurred.png`, `KEY.sharp.exr`, `KEY.sharp.png`,
//! `KEY.flow.exr`, `KEY.maps.exr`), the WebDataset convention (the key is
//! the name up to its first dot). Items go in index order; a shard is
//! closed before the item that would take it past the shard size (an item
//! larger than that gets a shard of its own).
//!
//! Deterministic: the tar headers carry no time, owner or host (mtime 0,
//! uid/gid 0, mode 0444, ustar), so the same dataset gives the same bytes,
//! and since a sharded run's directory equals a single run's, so do its
//! tar shards. Trust nothing: the directory is verified against its
//! manifest first (`manifest::verify`), and each file's bytes are hashed
//! again as they are packed. All or nothing, one packer at a time: a
//! packing holds `DIR/.lock-pack` (a second one is refused), writes its
//! shards and index into `DIR/.webdataset.partial/` and renames that folder
//! into place when complete, so `webdataset/` is always one whole packing.
//! Resumable: each tar is written under a temporary name and renamed,
//! the partial folder's `index.json` is rewritten after each shard, and a
//! rerun keeps a shard whose file still has the listed size and SHA-256
//! (in the partial folder, or in the folder it replaces).
//! Checking the shards (`--verify`): [`super::tarcheck`].

use super::guard::Record;
use super::item::FILES;
use super::lock::PackLock;
use super::manifest::{each_line, item_dir, verify, ManifestLine};
use super::tarindex::{kind, read_index, sum_regular, Kind, INDEX_FORMAT};
pub use super::tarindex::{shard_name, TarIndex, TarShard, FOLDER};
use crate::error::{show_path, Error, Result};
use crate::io::atomic::write_atomic;
use sha2::{Digest, Sha256};
use std::io::{Read, Write};
use std::path::{Path, PathBuf};

/// Default shard size, bytes (about 1 GB, WebDataset's usual size).
pub const DEFAULT_SHARD_BYTES: u64 = 1_000_000_000;
pub use crate::limits::{MAX_SHARD_BYTES, MIN_SHARD_BYTES};
/// Where a packing writes before it is complete (then renamed to [`FOLDER`]).
const STAGE: &str = ".webdataset.partial";
/// Where the folder it replaces goes for the instant of the swap.
const OLD: &str = ".webdataset.old";
/// Tar block, bytes.
const BLOCK: u64 = 512;

/// What [`pack`] did.
#[derive(Debug, Clone, Copy, PartialEq)]
pub struct PackSummary {
    /// Tar shards of the dataset.
    pub shards: usize,
    /// Of which written now (the rest were complete and kept).
    pub written: usize,
    /// Items packed.
    pub items: u64,
    /// Bytes of all the shards.
    pub bytes: u64,
}

/// The tar member name of item file `file` (e.g. `blurred.exr`) of item `i`.
pub fn member_name(i: u64, file: &str) -> String {
    format!("{i:08}.{file}")
}

/// Bytes a member of `n` bytes takes in a tar (header and padding).
fn member_bytes(n: u64) -> u64 {
    BLOCK + n.div_ceil(BLOCK) * BLOCK
}

/// A tar member: its name, the file it is read from, and the file's
/// expected size and SHA-256 (`None`: checked otherwise).
type Member = (String, PathBuf, Option<(u64, String)>);

/// The item's members: `KEY.json` (from `item.json`) then [`FILES`], each
/// with its path in `DIR` and its expected size and SHA-256 (`None` for
/// `item.json`, checked by `verify` against the line).
fn members(out: &Path, l: &ManifestLine) -> Result<Vec<Member>> {
    let dir = out.join(item_dir(l.index));
    let mut m = vec![(member_name(l.index, "json"), dir.join("item.json"), None)];
    for f in FILES {
        let sum = l.files.get(f).ok_or_else(|| {
            Error::invalid(
                show_path(&out.join("manifest.jsonl")),
                format!("item {} lists no {f}", l.index),
            )
        })?;
        m.push((
            member_name(l.index, f),
            dir.join(f),
            Some((sum.bytes, sum.sha256.clone())),
        ));
    }
    Ok(m)
}

/// Cuts the items into shards of at most `shard_bytes` (an item larger
/// than that alone); returns per shard (first item, items).
fn plan(sizes: &[(u64, u64)], shard_bytes: u64) -> Vec<(u64, u64)> {
    let mut out = Vec::new();
    let (mut first, mut n, mut bytes) = (0u64, 0u64, 0u64);
    for &(i, b) in sizes {
        if n > 0 && bytes + b > shard_bytes.saturating_sub(2 * BLOCK) {
            out.push((first, n));
            (n, bytes) = (0, 0);
        }
        if n == 0 {
            first = i;
        }
        n += 1;
        bytes += b;
    }
    if n > 0 {
        out.push((first, n));
    }
    out
}

/// A header with nothing of the machine or the time in it.
fn header(name: &str, size: u64) -> Result<tar::Header> {
    let mut h = tar::Header::new_ustar();
    h.set_path(name)
        .map_err(|e| Error::invalid("webdataset", format!("member name {name}: {e}")))?;
    h.set_size(size);
    h.set_mode(0o444);
    h.set_mtime(0);
    h.set_uid(0);
    h.set_gid(0);
    h.set_entry_type(tar::EntryType::Regular);
    h.set_cksum();
    Ok(h)
}

/// Reads file `p` whole (its size first checked against `want`), checking
/// its SHA-256.
fn read_checked(p: &Path, want: Option<&(u64, String)>) -> Result<Vec<u8>> {
    let cap = want.map_or(crate::io::input::MAX_TEXT_BYTES, |w| w.0);
    let mut buf = Vec::new();
    crate::io::input::open_file(p)?
        .take(cap + 1)
        .read_to_end(&mut buf)
        .map_err(|e| Error::io(p, e))?;
    if let Some((bytes, sha)) = want {
        let got = format!("{:x}", Sha256::digest(&buf));
        if buf.len() as u64 != *bytes || got != *sha {
            return Err(Error::invalid(
                show_path(p),
                format!(
                    "changed since the manifest was checked ({} bytes, SHA-256 {}, where the manifest \
                     lists {bytes} bytes, {}): run --verify",
                    buf.len(),
                    &got[..12],
                    &sha[..sha.len().min(12)]
                ),
            ));
        }
    } else if buf.len() as u64 > cap {
        return Err(Error::invalid(
            show_path(p),
            format!("longer than {cap} bytes, the most read"),
        ));
    }
    Ok(buf)
}

/// Writes the tar shard of `lines` to `path` (atomically); returns its size
/// and SHA-256.
fn write_shard(out: &Path, lines: &[ManifestLine], path: &Path) -> Result<(u64, String)> {
    struct Hashing<'a> {
        w: &'a mut dyn Write,
        h: Sha256,
        n: u64,
    }
    impl Write for Hashing<'_> {
        fn write(&mut self, b: &[u8]) -> std::io::Result<usize> {
            let k = self.w.write(b)?;
            self.h.update(&b[..k]);
            self.n += k as u64;
            Ok(k)
        }
        fn flush(&mut self) -> std::io::Result<()> {
            self.w.flush()
        }
    }
    let mut sum = (0, String::new());
    write_atomic(path, |w| {
        let mut hw = Hashing {
            w,
            h: Sha256::new(),
            n: 0,
        };
        {
            let mut b = tar::Builder::new(&mut hw);
            for l in lines {
                crate::cancel::check()?;
                for (name, file, want) in members(out, l)? {
                    let data = read_checked(&file, want.as_ref())?;
                    let mut h = header(&name, data.len() as u64)?;
                    b.append_data(&mut h, &name, data.as_slice())
                        .map_err(|e| Error::io(path, e))?;
                }
            }
            b.finish().map_err(|e| Error::io(path, e))?;
        }
        sum = (hw.n, format!("{:x}", hw.h.finalize()));
        Ok(())
    })?;
    Ok(sum)
}

/// The index in `dir` (an earlier packing's) if it is for this dataset
/// and shard size; `None` when there is none, or it is unreadable (then it
/// counts for nothing: its shards are made again).
fn previous(dir: &Path, rec: &Record, shard_bytes: u64) -> Result<Option<TarIndex>> {
    let index = dir.join("index.json");
    if !matches!(kind(&index)?, Kind::File(_)) {
        return Ok(None);
    }
    let Ok(ix) = read_index(&index) else {
        return Ok(None);
    };
    if ix.format != INDEX_FORMAT || ix.fingerprint != rec.fingerprint {
        return Err(Error::invalid(
            show_path(&index),
            format!(
                "made from another dataset (format {}, fingerprint {}): remove {} first",
                ix.format,
                super::guard::short(&ix.fingerprint),
                show_path(dir)
            ),
        ));
    }
    Ok((ix.shard_bytes == shard_bytes).then_some(ix))
}

/// The shard `name` as `ix` lists it, if it holds the items `first..first +
/// n` and the file `dir/name` is a regular file with the listed size and
/// SHA-256.
fn intact(
    ix: Option<&TarIndex>,
    dir: &Path,
    name: &str,
    first: u64,
    n: u64,
) -> Result<Option<TarShard>> {
    let Some(t) = ix.and_then(|ix| ix.shards.iter().find(|t| t.name == name)) else {
        return Ok(None);
    };
    if t.first != first || t.items != n {
        return Ok(None);
    }
    let ok = sum_regular(&dir.join(name))?.is_some_and(|(b, sha)| b == t.bytes && sha == t.sha256);
    Ok(ok.then(|| t.clone()))
}

/// True when `dir` holds exactly the complete packing `cuts` of this
/// dataset (its index complete, of `count` items, each shard intact, no
/// other file): nothing to do.
fn up_to_date(dir: &Path, rec: &Record, shard_bytes: u64, cuts: &[(u64, u64)]) -> Result<bool> {
    let Some(ix) = previous(dir, rec, shard_bytes)? else {
        return Ok(false);
    };
    if !ix.complete || ix.count != rec.count || ix.shards.len() != cuts.len() {
        return Ok(false);
    }
    for (s, &(first, n)) in cuts.iter().enumerate() {
        if intact(Some(&ix), dir, &shard_name(s), first, n)?.is_none() {
            return Ok(false);
        }
    }
    let files = std::fs::read_dir(dir)
        .map_err(|e| Error::io(dir, e))?
        .count();
    Ok(files == cuts.len() + 1)
}

/// Puts `stage` (a complete packing) in the place of `dir`: `dir` (if any)
/// is renamed aside, `stage` renamed to `dir`, the old one removed. A
/// reader sees the old packing, then no folder for an instant, then the
/// new one; never a mix.
fn swap_in(stage: &Path, dir: &Path, old: &Path) -> Result<()> {
    if std::fs::symlink_metadata(dir).is_ok() {
        std::fs::rename(dir, old).map_err(|e| Error::io(dir, e))?;
    }
    std::fs::rename(stage, dir).map_err(|e| Error::io(dir, e))?;
    if std::fs::symlink_metadata(old).is_ok() {
        remove_any(old)?;
    }
    Ok(())
}

/// Removes `p`, a folder (with its files) or anything else.
fn remove_any(p: &Path) -> Result<()> {
    let m = std::fs::symlink_metadata(p).map_err(|e| Error::io(p, e))?;
    if m.is_dir() {
        std::fs::remove_dir_all(p).map_err(|e| Error::io(p, e))
    } else {
        std::fs::remove_file(p).map_err(|e| Error::io(p, e))
    }
}

/// Checks `--shard-bytes` against [`MIN_SHARD_BYTES`]..=[`MAX_SHARD_BYTES`].
pub fn check_shard_bytes(shard_bytes: u64) -> Result<()> {
    if !(MIN_SHARD_BYTES..=MAX_SHARD_BYTES).contains(&shard_bytes) {
        return Err(Error::invalid(
            "--shard-bytes",
            format!(
                "{shard_bytes}: the tar shard size must be in {MIN_SHARD_BYTES}..={MAX_SHARD_BYTES} bytes"
            ),
        ));
    }
    Ok(())
}

/// Packs the dataset directory `out` (complete and merged: it is verified
/// first) into WebDataset tar shards of at most `shard_bytes` in
/// `out/webdataset/`, all or nothing: under the packing lock
/// ([`PackLock`]: a second packer is refused), the shards and the index are
/// written into `out/.webdataset.partial/` and that folder is renamed into
/// place when complete. Intact shards of the folder there are kept (linked
/// into the new one), and so are those of a stopped packing's partial
/// folder, which a rerun resumes.
pub fn pack(out: &Path, shard_bytes: u64, progress: bool) -> Result<PackSummary> {
    check_shard_bytes(shard_bytes)?;
    let _lock = PackLock::take(out)?;
    let n_items = verify(out)?;
    let rec = Record::read(out)?;
    let mut lines = Vec::with_capacity(n_items);
    each_line(&out.join("manifest.jsonl"), rec.count, |_, l| {
        lines.push(l);
        Ok(())
    })?;
    let mut sizes = Vec::with_capacity(lines.len());
    for l in &lines {
        let json = out.join(item_dir(l.index)).join("item.json");
        let json_bytes = std::fs::metadata(&json)
            .map_err(|e| Error::io(&json, e))?
            .len();
        let b =
            member_bytes(json_bytes) + l.files.values().map(|f| member_bytes(f.bytes)).sum::<u64>();
        sizes.push((l.index, b));
    }
    let cuts = plan(&sizes, shard_bytes);
    let (dir, stage, old) = (out.join(FOLDER), out.join(STAGE), out.join(OLD));
    // A packing stopped between the two renames of `swap_in`: the old
    // folder is all there is.
    if std::fs::symlink_metadata(&old).is_ok() {
        if std::fs::symlink_metadata(&dir).is_err() {
            std::fs::rename(&old, &dir).map_err(|e| Error::io(&dir, e))?;
        } else {
            remove_any(&old)?;
        }
    }
    let summary = |written: usize, ix: &TarIndex| PackSummary {
        shards: cuts.len(),
        written,
        items: lines.len() as u64,
        bytes: ix.shards.iter().map(|t| t.bytes).sum(),
    };
    if up_to_date(&dir, &rec, shard_bytes, &cuts)? {
        if std::fs::symlink_metadata(&stage).is_ok() {
            remove_any(&stage)?;
        }
        let ix = read_index(&dir.join("index.json"))?;
        return Ok(summary(0, &ix));
    }
    let current = if matches!(kind(&dir)?, Kind::Other) && dir.is_dir() {
        previous(&dir, &rec, shard_bytes)?
    } else {
        None
    };
    // The partial folder is this packer's alone (the lock): resume it when
    // it is one of this packing, else start it afresh.
    let staged = match kind(&stage)? {
        Kind::Other if stage.is_dir() => previous(&stage, &rec, shard_bytes).unwrap_or(None),
        Kind::Missing => None,
        _ => {
            remove_any(&stage)?;
            None
        }
    };
    if staged.is_none() && std::fs::symlink_metadata(&stage).is_ok() {
        remove_any(&stage)?;
    }
    std::fs::create_dir_all(&stage).map_err(|e| Error::io(&stage, e))?;
    let mut ix = TarIndex {
        format: INDEX_FORMAT.into(),
        fingerprint: rec.fingerprint.clone(),
        shard_bytes,
        count: rec.count,
        shards: Vec::new(),
        complete: false,
    };
    let bar = crate::diagnostics::progress(progress, "shards", cuts.len() as u64);
    let mut written = 0;
    let mut at = 0usize;
    for (s, &(first, n)) in cuts.iter().enumerate() {
        let name = shard_name(s);
        let path = stage.join(&name);
        let entry = match intact(staged.as_ref(), &stage, &name, first, n)? {
            Some(t) => t,
            None => match link_kept(current.as_ref(), &dir, &path, &name, first, n)? {
                Some(t) => t,
                None => {
                    if std::fs::symlink_metadata(&path).is_ok() {
                        remove_any(&path)?;
                    }
                    let (bytes, sha256) = write_shard(out, &lines[at..at + n as usize], &path)?;
                    written += 1;
                    TarShard {
                        name,
                        first,
                        items: n,
                        bytes,
                        sha256,
                    }
                }
            },
        };
        at += n as usize;
        ix.shards.push(entry);
        ix.complete = s + 1 == cuts.len();
        write_index(&stage.join("index.json"), &ix)?;
        bar.advance(1);
    }
    drop(bar);
    // Nothing in the new folder but its shards and index.
    let keep: Vec<String> = ix.shards.iter().map(|t| t.name.clone()).collect();
    for e in std::fs::read_dir(&stage).map_err(|e| Error::io(&stage, e))? {
        let e = e.map_err(|e| Error::io(&stage, e))?;
        let name = e.file_name().to_string_lossy().into_owned();
        if name != "index.json" && !keep.contains(&name) {
            remove_any(&e.path())?;
        }
    }
    swap_in(&stage, &dir, &old)?;
    Ok(summary(written, &ix))
}

/// Brings an intact shard of the current folder into the new one (a hard
/// link, or a copy where links are not possible), checked again there.
fn link_kept(
    current: Option<&TarIndex>,
    dir: &Path,
    path: &Path,
    name: &str,
    first: u64,
    n: u64,
) -> Result<Option<TarShard>> {
    let Some(t) = intact(current, dir, name, first, n)? else {
        return Ok(None);
    };
    if std::fs::symlink_metadata(path).is_ok() {
        remove_any(path)?;
    }
    let from = dir.join(name);
    if std::fs::hard_link(&from, path).is_err() {
        std::fs::copy(&from, path).map_err(|e| Error::io(path, e))?;
    }
    let same = sum_regular(path)?.is_some_and(|(b, sha)| b == t.bytes && sha == t.sha256);
    Ok(same.then_some(t))
}

fn write_index(path: &Path, ix: &TarIndex) -> Result<()> {
    let text = serde_json::to_string_pretty(ix)
        .map_err(|e| Error::invalid("webdataset index", e.to_string()))?;
    write_atomic(path, |w| {
        writeln!(w, "{text}").map_err(|e| Error::io(path, e))
    })
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn plan_cuts_before_the_item_that_overflows() {
        let sizes: Vec<(u64, u64)> = (0..5).map(|i| (i, 400)).collect();
        // The archive's two closing blocks (1024 bytes) count.
        assert_eq!(plan(&sizes, 1024 + 1200), vec![(0, 3), (3, 2)]);
        assert_eq!(plan(&sizes, 1024 + 1199), vec![(0, 2), (2, 2), (4, 1)]);
        assert_eq!(plan(&sizes, 1 << 20), vec![(0, 5)]);
        // An item larger than the shard size gets a shard of its own.
        assert_eq!(
            plan(&[(0, 10), (1, 5000), (2, 10)], 2000),
            vec![(0, 1), (1, 1), (2, 1)]
        );
        assert!(plan(&[], 2000).is_empty());
    }

    #[test]
    fn members_are_padded_to_blocks() {
        assert_eq!(member_bytes(0), 512);
        assert_eq!(member_bytes(1), 1024);
        assert_eq!(member_bytes(512), 1024);
        assert_eq!(member_bytes(513), 1536);
    }

    #[test]
    fn headers_carry_no_machine_or_time() {
        let h = header("00000001.blurred.png", 77).unwrap();
        assert_eq!(h.mtime().unwrap(), 0);
        assert_eq!(h.uid().unwrap(), 0);
        assert_eq!(h.mode().unwrap(), 0o444);
        assert_eq!(h.size().unwrap(), 77);
        assert_eq!(h.path().unwrap().to_str(), Some("00000001.blurred.png"));
    }
}
