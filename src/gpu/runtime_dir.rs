//! A valid `XDG_RUNTIME_DIR` for the system's GPU stack. The Vulkan loader
//! and its drivers (through libwayland, probing for a display) print
//! `error: XDG_RUNTIME_DIR is invalid or not set in the environment.` two to
//! four times when it is unset or not an absolute path, then carry on: noise
//! a user reads as an error. Before the first wgpu instance is made, an
//! unset or invalid `XDG_RUNTIME_DIR` is set, for this process only, to a
//! private directory: `$TMPDIR/mmbm-runtime-UID` (mode 0700, owned by this
//! user, created once and reused; nothing is written into it). A valid one
//! is left as it is; where no private directory can be had (another owner,
//! a symlink, a read-only temp dir) nothing is changed.

use std::path::{Path, PathBuf};
use std::sync::Once;

/// Sets `XDG_RUNTIME_DIR` to a private directory when it is unset or
/// invalid (not an absolute path to a directory); once per process, before
/// the GPU stack is loaded.
pub fn ensure() {
    static ONCE: Once = Once::new();
    ONCE.call_once(|| {
        let valid = std::env::var_os("XDG_RUNTIME_DIR")
            .is_some_and(|v| Path::new(&v).is_absolute() && Path::new(&v).is_dir());
        if !valid {
            if let Some(dir) = private_dir() {
                // Before any wgpu instance, hence before the driver's threads.
                std::env::set_var("XDG_RUNTIME_DIR", dir);
            }
        }
    });
}

/// `$TMPDIR/mmbm-runtime-UID`, created with mode 0700 if missing; `None`
/// unless it is a real directory (not a symlink) of this user with no
/// access for others.
#[cfg(unix)]
fn private_dir() -> Option<PathBuf> {
    use std::os::unix::fs::{DirBuilderExt, MetadataExt};
    let uid = std::fs::metadata("/proc/self").ok()?.uid();
    let dir = std::env::temp_dir().join(format!("mmbm-runtime-{uid}"));
    if !dir.is_absolute() {
        return None;
    }
    let _ = std::fs::DirBuilder::new().mode(0o700).create(&dir);
    let m = std::fs::symlink_metadata(&dir).ok()?;
    (m.is_dir() && m.uid() == uid && m.mode() & 0o077 == 0).then_some(dir)
}

#[cfg(not(unix))]
fn private_dir() -> Option<PathBuf> {
    None
}
