//! The locks that keep a dataset directory to one writer of each thing:
//! each shard's items ([`RunLock`]), the WebDataset packing ([`PackLock`]),
//! and `dataset.json` while a run reads and updates it ([`DirLock`]).
//!
//! Each is an advisory `flock` on a file of `DIR` (on `DIR` itself for
//! [`DirLock`]); the operating system drops it when the process ends,
//! however it ends (kill -9 included).
//!
//! **Lock files are removed when their holder ends** (a run that ends
//! normally, or with an error; a killed one leaves an empty file, removed by
//! the next run that takes and drops it). Removing a lock file safely is a
//! race of its own: a process may have opened the file just before it was
//! unlinked and lock the unlinked inode, while a third creates a new file
//! under the name and locks that: both would think they hold the lock. So:
//! - a holder removes its file only while holding it **exclusively** (a
//!   shared holder first converts its lock without waiting; if another run
//!   still holds it shared, the conversion fails and the file stays), and
//!   only after checking that the name still leads to the inode it holds;
//! - a taker, once its lock is granted, checks that the name still leads to
//!   the inode it locked (device and inode number); if not, the file was
//!   removed meanwhile, and it opens the name again (a few times at most).
//!
//! Together these keep "the file under the name" and "the lock that
//! counts" the same: the name can only change while its inode is held
//! exclusively by the remover, and a lock on an inode no longer under the
//! name is never kept. Two shared holders ending at the same moment may both
//! fail to convert and leave the (empty) file: harmless, it is reused.

use super::shard::Shard;
use crate::error::{show_path, Error, Result};
use std::fs::File;
use std::path::{Path, PathBuf};

/// How many times a taker opens a lock file again when the one it locked
/// was removed meanwhile (each retry needs another run to end in between).
const RETRIES: usize = 16;

/// A lock held on a lock file of the dataset directory; dropping it
/// removes the file when no other process holds it (module docs).
#[derive(Debug)]
pub(crate) struct Held {
    file: File,
    path: PathBuf,
}

/// Opens the lock file `p`; `None` when it does not exist and `create` is
/// false.
fn open(p: &Path, create: bool) -> Result<Option<File>> {
    match std::fs::OpenOptions::new()
        .read(true)
        .write(true)
        .create(create)
        .truncate(false)
        .open(p)
    {
        Ok(f) => Ok(Some(f)),
        Err(e) if !create && e.kind() == std::io::ErrorKind::NotFound => Ok(None),
        Err(e) => Err(Error::io(p, e)),
    }
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

/// True when the name `p` still leads to the open file `f`.
fn is_named(f: &File, p: &Path) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        match (f.metadata(), std::fs::symlink_metadata(p)) {
            (Ok(a), Ok(b)) => a.dev() == b.dev() && a.ino() == b.ino(),
            _ => false,
        }
    }
    #[cfg(not(unix))]
    {
        let _ = f;
        p.exists()
    }
}

/// Takes the lock on `p` without waiting (created if missing and `create`).
/// `Ok(None)`: another process holds it, or (without `create`) there is no
/// such file.
fn acquire(p: &Path, shared: bool, create: bool) -> Result<Option<Held>> {
    for _ in 0..RETRIES {
        let Some(f) = open(p, create)? else {
            return Ok(None);
        };
        if !try_lock(&f, p, shared)? {
            return Ok(None);
        }
        if is_named(&f, p) {
            return Ok(Some(Held {
                file: f,
                path: p.to_path_buf(),
            }));
        }
        // Removed by a run that ended between our open and our lock.
        if !create {
            return Ok(None);
        }
    }
    Err(Error::io(
        p,
        std::io::Error::other(format!(
            "the lock file was removed {RETRIES} times while being locked; try again"
        )),
    ))
}

impl Drop for Held {
    fn drop(&mut self) {
        // Exclusive (converting a shared lock), then unlink while holding it;
        // the file closes (and the lock goes) after this.
        if matches!(try_lock(&self.file, &self.path, false), Ok(true))
            && is_named(&self.file, &self.path)
        {
            let _ = std::fs::remove_file(&self.path);
        }
    }
}

/// The "another run is writing" error.
fn busy(out: &Path, what: String, lock: &Path) -> Error {
    Error::invalid(
        out.display().to_string(),
        format!(
            "another run is writing this directory ({what}; it holds {}): wait for it \
             to end, or use another --out",
            show_path(lock)
        ),
    )
}

/// The locks a run holds on its dataset directory (released, and their
/// files removed when no other run holds them, on drop; released when the
/// process ends).
#[derive(Debug)]
pub struct RunLock {
    // Dropped in this order: the shard's own lock first.
    _shard: Held,
    _count: Held,
}

impl RunLock {
    /// Takes the locks of `shard` on `out` (an existing directory): an
    /// exclusive one on `DIR/.lock-K-of-N` and a shared one on
    /// `DIR/.lock-of-N`; or refuses: another run of this shard, or of
    /// another shard count, is writing `out`.
    pub fn take(out: &Path, shard: Shard) -> Result<Self> {
        let own = out.join(format!(".lock-{}-of-{}", shard.k, shard.n));
        let shard_lock = acquire(&own, false, true)?
            .ok_or_else(|| busy(out, format!("a run of shard {}/{}", shard.k, shard.n), &own))?;
        let count = out.join(format!(".lock-of-{}", shard.n));
        let count_lock = acquire(&count, true, true)?.ok_or_else(|| {
            busy(
                out,
                format!("a run split into {} shards is probing it", shard.n),
                &count,
            )
        })?;
        // Shards of another count make some of the same items: refuse while
        // any such run holds its count's lock (each run takes its own shared
        // lock before looking, so of two such runs at least one sees the
        // other). A probe that gets a lock no run holds removes the stale
        // file as it drops it.
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
            let Some(f) = open(&p, false)? else {
                continue; // removed meanwhile by the run that held it
            };
            if !try_lock(&f, &p, false)? {
                return Err(busy(
                    out,
                    format!(
                        "a run split into {n} shard(s), which shares items with this split into {}",
                        shard.n
                    ),
                    &p,
                ));
            }
            drop(Held { file: f, path: p });
        }
        Ok(RunLock {
            _shard: shard_lock,
            _count: count_lock,
        })
    }
}

/// The lock of a WebDataset packing (`DIR/.lock-pack`, exclusive): one
/// packer at a time; its file removed on drop.
#[derive(Debug)]
pub struct PackLock(#[allow(dead_code)] Held);

impl PackLock {
    /// Takes it, or refuses: another run is packing `out`.
    pub fn take(out: &Path) -> Result<Self> {
        let p = out.join(".lock-pack");
        acquire(&p, false, true)?
            .map(PackLock)
            .ok_or_else(|| busy(out, "a run packing its WebDataset shards".into(), &p))
    }
}

/// An exclusive lock on the directory itself (no file of its own), waited
/// for: held only while `dataset.json` is read and updated.
#[derive(Debug)]
pub(crate) struct DirLock(#[allow(dead_code)] File);

impl DirLock {
    /// Waits for and takes the lock on the directory `out`.
    pub(crate) fn take(out: &Path) -> Result<Self> {
        let f = File::open(out).map_err(|e| Error::io(out, e))?;
        #[cfg(unix)]
        fs4::FileExt::lock(&f).map_err(|e| Error::io(out, e))?;
        Ok(DirLock(f))
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn a_lock_on_a_removed_file_is_not_kept() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join(".lock-x");
        let a = acquire(&p, false, true).unwrap().unwrap();
        // Opened by another run just before the holder ends.
        let stale = File::open(&p).unwrap();
        drop(a);
        assert!(!p.exists(), "the holder removes its file");
        // The stale inode can be locked, but it is no longer the name's.
        assert!(try_lock(&stale, &p, false).unwrap());
        assert!(!is_named(&stale, &p));
        // A taker makes a fresh file, and holds it against others.
        let b = acquire(&p, false, true).unwrap().unwrap();
        assert!(is_named(&b.file, &p));
        assert!(acquire(&p, false, true).unwrap().is_none());
        assert!(acquire(&p, true, true).unwrap().is_none());
        drop(b);
        assert!(!p.exists());
        // Without `create`, a missing file is not made.
        assert!(acquire(&p, false, false).unwrap().is_none());
        assert!(!p.exists());
    }

    #[test]
    fn a_shared_lock_file_goes_with_its_last_holder() {
        let d = tempfile::tempdir().unwrap();
        let p = d.path().join(".lock-of-2");
        let a = acquire(&p, true, true).unwrap().unwrap();
        let b = acquire(&p, true, true).unwrap().unwrap();
        assert!(acquire(&p, false, true).unwrap().is_none());
        drop(a);
        assert!(p.exists(), "removed while another run holds it");
        assert!(acquire(&p, false, true).unwrap().is_none());
        drop(b);
        assert!(!p.exists());
    }
}
