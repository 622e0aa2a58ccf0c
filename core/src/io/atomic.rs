//! Writing outputs without ever destroying what an output path points at.
//!
//! Where an output goes depends on what the path is ([`Destination`]):
//! - `-`: standard output;
//! - a regular file, or a path that does not exist yet: written to a
//!   temporary file beside it (`.mmbm-*.tmp`), renamed over it on success, so
//!   a failed run never leaves a half-written file under its final name;
//! - a symlink: the same, on the file the link points to (the link stays);
//! - anything else (`/dev/null`, `/dev/stdout`, a FIFO, process substitution
//!   `>(cmd)`, any path under `/dev/` or `/proc/`): written in place, never
//!   replaced;
//! - a directory: an error.
//!
//! [`all_or_nothing`] defers the renames of every write made inside it until
//! all of them succeeded. Temporary files still on disk when the process is
//! interrupted are removed by [`remove_pending`] (the CLI calls it on Ctrl-C).

use crate::error::{show_path, Error, Result};
use std::cell::RefCell;
use std::collections::HashSet;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::sync::Mutex;

/// Where an output path leads.
#[derive(Debug, Clone, PartialEq, Eq)]
pub enum Destination {
    /// `-`: standard output.
    Stdout,
    /// A regular file (existing or new), replaced atomically; for a symlink,
    /// the file it points to.
    File(PathBuf),
    /// Not a regular file (device, FIFO, pipe): written in place.
    InPlace(PathBuf),
}

impl Destination {
    /// Classifies `path` (see the module docs). Errors for a directory, a
    /// missing parent directory or an empty path.
    pub fn of(path: &Path) -> Result<Self> {
        if path.as_os_str() == "-" {
            return Ok(Destination::Stdout);
        }
        if path.as_os_str().is_empty() {
            return Err(Error::invalid("output path", "is empty"));
        }
        if path.starts_with("/dev") || path.starts_with("/proc") {
            return Ok(Destination::InPlace(path.to_path_buf()));
        }
        let link = std::fs::symlink_metadata(path);
        let target = match &link {
            Ok(m) if m.file_type().is_symlink() => match std::fs::canonicalize(path) {
                Ok(t) => t,
                // A dangling link: create the file it names.
                Err(_) => {
                    let t = std::fs::read_link(path).map_err(|e| Error::io(path, e))?;
                    match path.parent() {
                        Some(d) if t.is_relative() => d.join(t),
                        _ => t,
                    }
                }
            },
            _ => path.to_path_buf(),
        };
        match std::fs::metadata(&target) {
            Ok(m) if m.is_dir() => Err(Error::io(
                path,
                std::io::Error::other("is a directory, expected a file"),
            )),
            Ok(m) if m.is_file() => Ok(Destination::File(target)),
            Ok(_) => Ok(Destination::InPlace(target)),
            Err(_) => {
                let dir = parent_dir(&target);
                match std::fs::metadata(dir) {
                    Ok(m) if m.is_dir() => Ok(Destination::File(target)),
                    _ => Err(Error::io(
                        path,
                        std::io::Error::new(
                            std::io::ErrorKind::NotFound,
                            format!("directory '{}' does not exist", dir.display()),
                        ),
                    )),
                }
            }
        }
    }
}

/// Checks, before any work, that `path` can take an output: `-`, an
/// existing non-directory, or a new file in an existing directory.
pub fn check_output(path: &Path) -> Result<()> {
    Destination::of(path).map(|_| ())
}

/// Checks, before any work, every output of one command: each as
/// [`check_output`], and no two on one destination (one would silently
/// replace the other). `outputs` pairs each path with the flag that gave it,
/// for the message. Several outputs may go to `/dev/null`.
pub fn check_outputs(outputs: &[(&str, &Path)]) -> Result<()> {
    let mut seen: Vec<(&str, &Path, Identity)> = Vec::new();
    for &(flag, path) in outputs {
        let Some(id) = Identity::of(&Destination::of(path)?) else {
            continue;
        };
        if let Some((f0, p0, _)) = seen.iter().find(|s| s.2 == id) {
            return Err(Error::invalid(
                "outputs",
                format!(
                    "{f0} {} and {flag} {} are one file: one output would replace the other; \
                     give each output its own path",
                    show_path(p0),
                    show_path(path)
                ),
            ));
        }
        seen.push((flag, path, id));
    }
    Ok(())
}

/// What two output paths must not share.
#[derive(Debug, PartialEq, Eq)]
enum Identity {
    Stdout,
    /// An existing file (device and inode: hard links and `a/../b` included).
    #[cfg(unix)]
    Inode(u64, u64),
    /// A file still to be created: its directory's canonical path and its name.
    Path(PathBuf),
}

impl Identity {
    /// `None` for `/dev/null`, which takes any number of outputs.
    fn of(d: &Destination) -> Option<Self> {
        let p = match d {
            Destination::Stdout => return Some(Identity::Stdout),
            Destination::InPlace(p) if p == Path::new("/dev/null") => return None,
            Destination::File(p) | Destination::InPlace(p) => p,
        };
        #[cfg(unix)]
        if let Ok(m) = std::fs::metadata(p) {
            use std::os::unix::fs::MetadataExt;
            return Some(Identity::Inode(m.dev(), m.ino()));
        }
        let dir = parent_dir(p);
        let dir = std::fs::canonicalize(dir).unwrap_or_else(|_| dir.to_path_buf());
        Some(Identity::Path(match p.file_name() {
            Some(n) => dir.join(n),
            None => dir,
        }))
    }
}

/// Checks, before any work, that the directory `path` can take outputs: an
/// existing directory or one that can be created (its nearest existing
/// ancestor is a directory), which this process can write in (a probe file
/// is created there and removed at once).
pub fn check_output_dir(path: &Path) -> Result<()> {
    let not_found = |dir: &Path| {
        Error::io(
            path,
            std::io::Error::new(
                std::io::ErrorKind::NotFound,
                format!("no existing directory above '{}'", show_path(dir)),
            ),
        )
    };
    let mut dir = path;
    loop {
        match std::fs::metadata(dir) {
            Ok(m) if m.is_dir() => break,
            Ok(_) => {
                return Err(Error::io(
                    path,
                    std::io::Error::other(format!(
                        "'{}' exists and is not a directory",
                        show_path(dir)
                    )),
                ))
            }
            Err(e) if e.kind() == std::io::ErrorKind::NotFound => {
                let up = parent_dir(dir);
                if up == dir {
                    return Err(not_found(dir));
                }
                dir = up;
            }
            Err(e) => return Err(Error::io(dir, e)),
        }
    }
    probe_dir(dir, path, None)
}

/// Checks that a file can be created in `dir` (a probe file, removed at
/// once); an error names `path` (the output asked for), the directory and,
/// when given, the `flag` the output came from.
pub(crate) fn probe_dir(dir: &Path, path: &Path, flag: Option<&str>) -> Result<()> {
    tempfile::Builder::new()
        .prefix(".mmbm-probe-")
        .tempfile_in(dir)
        .map(drop)
        .map_err(|e| {
            let flag = flag.map(|f| format!(" ({f})")).unwrap_or_default();
            Error::io(
                path,
                std::io::Error::new(
                    e.kind(),
                    format!("cannot write in '{}'{flag}: {}", show_path(dir), plain(&e)),
                ),
            )
        })
}

/// The directory `path` lies in (`.` for a bare file name).
pub(crate) fn parent_dir(path: &Path) -> &Path {
    match path.parent() {
        Some(d) if !d.as_os_str().is_empty() => d,
        _ => Path::new("."),
    }
}

/// Temporary files not yet renamed or removed (for [`remove_pending`]).
static PENDING: Mutex<Option<HashSet<PathBuf>>> = Mutex::new(None);

fn pending(f: impl FnOnce(&mut HashSet<PathBuf>)) {
    if let Ok(mut g) = PENDING.lock() {
        f(g.get_or_insert_with(HashSet::new));
    }
}

/// Temporary directories (a dataset item being made) not yet renamed or removed.
static PENDING_DIRS: Mutex<Option<HashSet<PathBuf>>> = Mutex::new(None);

fn taken(set: &Mutex<Option<HashSet<PathBuf>>>) -> Vec<PathBuf> {
    match set.lock() {
        Ok(mut g) => g
            .take()
            .map(|s| s.into_iter().collect())
            .unwrap_or_default(),
        Err(_) => Vec::new(),
    }
}

/// Removes every temporary output file and directory this process still has
/// on disk (called on interrupt: SIGINT, SIGTERM, SIGHUP); returns how many
/// were removed.
pub fn remove_pending() -> usize {
    let files = taken(&PENDING)
        .iter()
        .filter(|p| std::fs::remove_file(p).is_ok())
        .count();
    // A writer may still be adding a file to a folder being removed: try
    // again a few times.
    let dirs = taken(&PENDING_DIRS)
        .iter()
        .filter(|p| (0..4).any(|_| std::fs::remove_dir_all(p).is_ok() || !p.exists()))
        .count();
    files + dirs
}

/// A temporary directory, created now and registered for [`remove_pending`]
/// until the guard drops (after the directory was renamed into place, or
/// removed).
pub struct PendingDir(PathBuf);

impl PendingDir {
    /// Registers `path`, then creates it (and its parents): an interrupt at
    /// any moment finds it registered.
    pub fn create(path: &Path) -> Result<Self> {
        if let Ok(mut g) = PENDING_DIRS.lock() {
            g.get_or_insert_with(HashSet::new)
                .insert(path.to_path_buf());
        }
        let guard = PendingDir(path.to_path_buf());
        std::fs::create_dir_all(path).map_err(|e| Error::io(path, e))?;
        Ok(guard)
    }

    /// The directory.
    pub fn path(&self) -> &Path {
        &self.0
    }
}

impl Drop for PendingDir {
    fn drop(&mut self) {
        if let Ok(mut g) = PENDING_DIRS.lock() {
            if let Some(s) = g.as_mut() {
                s.remove(&self.0);
            }
        }
    }
}

/// A builder of temporary files (`PREFIX*SUFFIX`) created with mode 0666
/// less the process's umask, as any new file (`tempfile`'s default, 0600,
/// would make every output private): 0644 under the usual umask 022, 0640
/// under 027. The mode is the kernel's, applied at creation.
pub fn temp_builder<'a>(prefix: &'a str, suffix: &'a str) -> tempfile::Builder<'a, 'a> {
    let mut b = tempfile::Builder::new();
    b.prefix(prefix).suffix(suffix);
    #[cfg(unix)]
    {
        use std::os::unix::fs::PermissionsExt;
        b.permissions(std::fs::Permissions::from_mode(0o666));
    }
    b
}

/// A temporary file registered in [`PENDING`] for its lifetime.
struct Temp {
    file: Option<tempfile::NamedTempFile>,
    path: PathBuf,
}

impl Temp {
    fn new_in(dir: &Path, ext: &str) -> Result<Self> {
        let suffix = format!(".tmp{ext}");
        let file = temp_builder(".mmbm-", &suffix)
            .tempfile_in(dir)
            .map_err(|e| Error::io(dir, e))?;
        let path = file.path().to_path_buf();
        pending(|s| {
            s.insert(path.clone());
        });
        Ok(Temp {
            file: Some(file),
            path,
        })
    }

    fn path(&self) -> &Path {
        &self.path
    }

    fn file_mut(&mut self) -> Result<&mut std::fs::File> {
        self.file
            .as_mut()
            .map(|f| f.as_file_mut())
            .ok_or_else(|| Error::io(&self.path, std::io::Error::other("temporary file closed")))
    }

    /// Renames onto `path` (its permissions those of any new file: see
    /// [`temp_builder`]).
    fn publish(mut self, path: &Path) -> Result<()> {
        match self.file.take() {
            Some(f) => f
                .persist(path)
                .map(|_| ())
                .map_err(|e| Error::io(path, e.error)),
            None => Err(Error::io(
                &self.path,
                std::io::Error::other("temporary file closed"),
            )),
        }
    }
}

impl Drop for Temp {
    fn drop(&mut self) {
        pending(|s| {
            s.remove(&self.path);
        });
    }
}

thread_local! {
    /// Renames deferred by [`all_or_nothing`] on this thread.
    static DEFERRED: RefCell<Option<Vec<(Temp, PathBuf)>>> = const { RefCell::new(None) };
}

/// Renames `tmp` onto `path` now, or at the end of the enclosing
/// [`all_or_nothing`].
fn finish(tmp: Temp, path: &Path) -> Result<()> {
    let deferred = DEFERRED.with(|d| {
        let mut d = d.borrow_mut();
        match d.as_mut() {
            Some(list) => {
                list.push((tmp, path.to_path_buf()));
                None
            }
            None => Some(tmp),
        }
    });
    match deferred {
        Some(tmp) => tmp.publish(path),
        None => Ok(()),
    }
}

/// Runs `work`; the files it writes to regular-file destinations appear
/// under their names only if all of it succeeds (otherwise none does).
/// Writes in place (stdout, devices, pipes) cannot be taken back and happen
/// as they come.
pub fn all_or_nothing<T>(work: impl FnOnce() -> Result<T>) -> Result<T> {
    let outer = DEFERRED.with(|d| d.borrow().is_some());
    if outer {
        return work();
    }
    DEFERRED.with(|d| *d.borrow_mut() = Some(Vec::new()));
    let r = work();
    let list = DEFERRED.with(|d| d.borrow_mut().take()).unwrap_or_default();
    let v = r?;
    for (tmp, path) in list {
        tmp.publish(&path)?;
    }
    Ok(v)
}

fn extension(path: &Path) -> String {
    path.extension()
        .map(|e| format!(".{}", e.to_string_lossy()))
        .unwrap_or_default()
}

/// Opens a non-regular destination for writing in place (no truncation).
fn open_in_place(path: &Path) -> Result<std::fs::File> {
    std::fs::OpenOptions::new()
        .write(true)
        .open(path)
        .map_err(|e| Error::io(path, e))
}

/// Runs `write` on a buffered writer to `path` (see the module docs for
/// what each kind of path gets).
pub fn write_atomic<F>(path: &Path, write: F) -> Result<()>
where
    F: FnOnce(&mut dyn Write) -> Result<()>,
{
    match Destination::of(path)? {
        Destination::Stdout => {
            let out = std::io::stdout();
            let mut w = std::io::BufWriter::with_capacity(1 << 16, out.lock());
            write(&mut w)?;
            w.flush().map_err(|e| Error::io("<stdout>", e))
        }
        Destination::InPlace(p) => {
            let mut f = open_in_place(&p)?;
            let mut w = std::io::BufWriter::with_capacity(1 << 16, &mut f);
            write(&mut w)?;
            w.flush().map_err(|e| Error::io(&p, e))
        }
        Destination::File(p) => {
            let mut tmp = Temp::new_in(parent_dir(&p), &extension(&p))?;
            {
                let mut w = std::io::BufWriter::with_capacity(1 << 16, tmp.file_mut()?);
                write(&mut w)?;
                w.flush().map_err(|e| Error::io(&p, e))?;
            }
            finish(tmp, &p)
        }
    }
}

/// For encoders that write to a path (EXR, PNG): `write` gets a temporary
/// path with the same extension; its bytes then go to `path` as
/// [`write_atomic`] would send them.
pub fn write_atomic_path<F>(path: &Path, write: F) -> Result<()>
where
    F: FnOnce(&Path) -> Result<()>,
{
    match Destination::of(path)? {
        Destination::File(p) => {
            let tmp = Temp::new_in(parent_dir(&p), &extension(&p))?;
            write(tmp.path())?;
            finish(tmp, &p)
        }
        _ => {
            let tmp = Temp::new_in(&std::env::temp_dir(), &extension(path))?;
            write(tmp.path())?;
            let bytes = std::fs::read(tmp.path()).map_err(|e| Error::io(tmp.path(), e))?;
            write_atomic(path, |w| {
                w.write_all(&bytes).map_err(|e| Error::io(path, e))
            })
        }
    }
}
/// `e` without the probe file's name that `tempfile` adds.
pub(crate) fn plain(e: &std::io::Error) -> std::io::Error {
    match e.raw_os_error() {
        Some(code) => std::io::Error::from_raw_os_error(code),
        None => std::io::Error::from(e.kind()),
    }
}
