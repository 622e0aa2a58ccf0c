//! The WebDataset index (`DIR/webdataset/index.json`: [`TarIndex`]) and
//! reading shard files without trusting them: what a name is without
//! following a link, a regular file's size and SHA-256, the index parsed.
//! Shared by packing (`webdataset`) and checking (`tarcheck`).

use super::guard::read_json_file;
use crate::error::{show_path, Error, Result};
use serde::{Deserialize, Serialize};
use std::fs::File;
use std::path::Path;

/// The folder, under the dataset directory.
pub const FOLDER: &str = "webdataset";
/// The `format` of `index.json`.
pub(crate) const INDEX_FORMAT: &str = "mmbm-webdataset-1";

/// One tar shard, as `index.json` lists it.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TarShard {
    /// File name in `DIR/webdataset/`.
    pub name: String,
    /// Index of its first item.
    pub first: u64,
    /// Items in it (consecutive indices).
    pub items: u64,
    /// File size, bytes.
    pub bytes: u64,
    /// SHA-256 of the file, hex.
    pub sha256: String,
}

/// `DIR/webdataset/index.json`.
#[derive(Debug, Clone, PartialEq, Serialize, Deserialize)]
#[serde(deny_unknown_fields)]
pub struct TarIndex {
    /// `mmbm-webdataset-1`.
    pub format: String,
    /// The dataset's fingerprint (`dataset.json`).
    pub fingerprint: String,
    /// The shard size the shards were cut at, bytes.
    pub shard_bytes: u64,
    /// Items in the dataset.
    pub count: u64,
    /// The shards made so far, in order.
    pub shards: Vec<TarShard>,
    /// True once every item is in a shard.
    pub complete: bool,
}

/// The name of tar shard `s` (0-based).
pub fn shard_name(s: usize) -> String {
    format!("mmbm-{s:06}.tar")
}

/// What a name in the shard folder is (links not followed).
pub(crate) enum Kind {
    /// Nothing by that name.
    Missing,
    /// A symbolic link.
    Symlink,
    /// A pipe, device, socket or directory.
    Other,
    /// A regular file of this many bytes.
    File(u64),
}

/// What `p` is, without following a link.
pub(crate) fn kind(p: &Path) -> Result<Kind> {
    match std::fs::symlink_metadata(p) {
        Ok(m) if m.file_type().is_symlink() => Ok(Kind::Symlink),
        Ok(m) if m.is_file() => Ok(Kind::File(m.len())),
        Ok(_) => Ok(Kind::Other),
        Err(e) if e.kind() == std::io::ErrorKind::NotFound => Ok(Kind::Missing),
        Err(e) => Err(Error::io(p, e)),
    }
}

/// Opens `p` when it is a regular file under its own name (not a link);
/// `None` otherwise. The opened file is checked to be the one looked at.
fn open_regular(p: &Path) -> Result<Option<File>> {
    let Ok(seen) = std::fs::symlink_metadata(p) else {
        return Ok(None);
    };
    if !seen.is_file() {
        return Ok(None);
    }
    let f = File::open(p).map_err(|e| Error::io(p, e))?;
    let got = f.metadata().map_err(|e| Error::io(p, e))?;
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        if (got.dev(), got.ino()) != (seen.dev(), seen.ino()) {
            return Ok(None);
        }
    }
    Ok(got.is_file().then_some(f))
}

/// Size and SHA-256 of `p` when it is a regular file under its own name,
/// `None` otherwise (missing, a link, not a regular file).
pub(crate) fn sum_regular(p: &Path) -> Result<Option<(u64, String)>> {
    match open_regular(p)? {
        Some(mut f) => super::guard::sha256_of(&mut f, p).map(Some),
        None => Ok(None),
    }
}

/// Reads and parses `DIR/webdataset/index.json` (a regular file under its
/// own name).
pub(crate) fn read_index(index: &Path) -> Result<TarIndex> {
    if !matches!(kind(index)?, Kind::File(_)) {
        return Err(Error::invalid(
            show_path(index),
            "is not a regular file (a link or another kind of file is not read)",
        ));
    }
    let text = read_json_file(index)?;
    serde_json::from_str(&text).map_err(|e| Error::Config {
        path: index.into(),
        message: crate::error::clip(&e.to_string(), crate::error::MAX_MESSAGE),
    })
}
