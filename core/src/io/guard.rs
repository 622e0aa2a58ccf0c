//! One check of a command's outputs, before any work ([`OutputGuard`]).
//!
//! A command names what it writes (file outputs, output folders with the
//! names it writes there) and what it reads (each with the flag or key that
//! gave it). [`OutputGuard::check`] then refuses, naming both paths:
//! - a file output that cannot be written: its directory missing or not
//!   writable (a probe file is created there and removed at once), or a
//!   device path that does not exist (`/proc/nonexistent`);
//! - an output folder that cannot be created or written in;
//! - two outputs on one file ([`super::atomic::check_outputs`]);
//! - a file output inside an output folder (the folder's files are renamed
//!   into place at the end and could replace it);
//! - an output that is an input: the same file by identity (device and
//!   inode: symlinks followed, hard links and `a/../b` included);
//! - an input inside an output folder under a name the command writes there.
//!
//! Nothing is read or written by the check but the probe files.

use super::atomic::{check_output_dir, check_outputs, Destination};
use crate::error::{show_path, Error, Result};
use std::path::{Component, Path, PathBuf};

/// Which paths, relative to an output folder, a command writes there.
pub type Writes = fn(&Path) -> bool;

/// A command's outputs and inputs, checked together by [`Self::check`].
#[derive(Default)]
pub struct OutputGuard {
    files: Vec<(String, PathBuf)>,
    dirs: Vec<(String, PathBuf, Writes)>,
    inputs: Vec<(String, PathBuf)>,
}

impl OutputGuard {
    /// An empty guard.
    pub fn new() -> Self {
        Self::default()
    }

    /// A file output given by `flag` (`-` is stdout).
    pub fn output(mut self, flag: &str, path: Option<&Path>) -> Self {
        if let Some(p) = path {
            self.files.push((flag.into(), p.to_path_buf()));
        }
        self
    }

    /// An output folder given by `flag`, where the command writes the paths
    /// (relative to the folder) for which `writes` is true.
    pub fn output_dir(mut self, flag: &str, path: Option<&Path>, writes: Writes) -> Self {
        if let Some(p) = path {
            self.dirs.push((flag.into(), p.to_path_buf(), writes));
        }
        self
    }

    /// An input given by `flag` (`-` is stdin: never an output's file).
    pub fn input(mut self, flag: &str, path: Option<&Path>) -> Self {
        if let Some(p) = path {
            if p.as_os_str() != "-" && !p.as_os_str().is_empty() {
                self.inputs.push((flag.into(), p.to_path_buf()));
            }
        }
        self
    }

    /// Checks everything (see the module docs); the first problem is the error.
    pub fn check(&self) -> Result<()> {
        let mut dests = Vec::with_capacity(self.files.len());
        for (flag, p) in &self.files {
            let d = Destination::of(p).map_err(|e| named(flag, e))?;
            probe_file(flag, p, &d)?;
            dests.push(d);
        }
        let pairs: Vec<(&str, &Path)> = self
            .files
            .iter()
            .map(|(f, p)| (f.as_str(), p.as_path()))
            .collect();
        check_outputs(&pairs)?;
        for (flag, dir, _) in &self.dirs {
            check_output_dir(dir).map_err(|e| named(flag, e))?;
        }
        for ((flag, p), d) in self.files.iter().zip(&dests) {
            if let Destination::File(target) = d {
                for (dflag, dir, _) in &self.dirs {
                    if resolve(target).starts_with(resolve(dir)) {
                        return Err(Error::invalid(
                            "outputs",
                            format!(
                                "{flag} {} lies inside the output folder {dflag} {}: its files \
                                 could replace it; give {flag} a path outside that folder",
                                show_path(p),
                                show_path(dir)
                            ),
                        ));
                    }
                }
            }
        }
        for (iflag, ip) in &self.inputs {
            let Ok(im) = std::fs::metadata(ip) else {
                // Missing: its reader says so.
                continue;
            };
            for ((flag, p), d) in self.files.iter().zip(&dests) {
                if let Destination::File(target) = d {
                    if std::fs::metadata(target).is_ok_and(|om| same_file(&im, &om)) {
                        return Err(Error::invalid(
                            "outputs",
                            format!(
                                "{flag} {} is the input {iflag} {}: the output would replace it; \
                                 give the output another path",
                                show_path(p),
                                show_path(ip)
                            ),
                        ));
                    }
                }
            }
            let real = resolve(ip);
            for (dflag, dir, writes) in &self.dirs {
                if let Ok(rel) = real.strip_prefix(resolve(dir)) {
                    if !rel.as_os_str().is_empty() && writes(rel) {
                        return Err(Error::invalid(
                            "outputs",
                            format!(
                                "the input {iflag} {} is {} in the output folder {dflag} {}, \
                                 which the command writes: the output would replace it; give \
                                 the output folder another path",
                                show_path(ip),
                                show_path(rel),
                                show_path(dir)
                            ),
                        ));
                    }
                }
            }
        }
        Ok(())
    }
}

/// `e` with the flag in front, when it does not say which output it is.
fn named(flag: &str, e: Error) -> Error {
    match e {
        Error::Io { path, source } => Error::io(
            path,
            std::io::Error::new(source.kind(), format!("{source} ({flag})")),
        ),
        e => e,
    }
}

/// Checks that file output `p` (`d`) can be written, before any work: a
/// probe file in its directory for a regular file, existence for a device.
fn probe_file(flag: &str, p: &Path, d: &Destination) -> Result<()> {
    match d {
        Destination::Stdout => Ok(()),
        Destination::InPlace(t) => match std::fs::metadata(t) {
            Ok(_) => Ok(()),
            Err(e) => Err(Error::io(
                p,
                std::io::Error::new(e.kind(), format!("cannot write ({flag}): {e}")),
            )),
        },
        Destination::File(t) => {
            super::atomic::probe_dir(super::atomic::parent_dir(t), p, Some(flag))
        }
    }
}

/// One file by identity (device and inode).
fn same_file(a: &std::fs::Metadata, b: &std::fs::Metadata) -> bool {
    #[cfg(unix)]
    {
        use std::os::unix::fs::MetadataExt;
        a.dev() == b.dev() && a.ino() == b.ino()
    }
    #[cfg(not(unix))]
    {
        let _ = (a, b);
        false
    }
}

/// `p` with its longest existing prefix made canonical (symlinks followed)
/// and the rest appended with `.` and `..` taken lexically: where `p` is or
/// would be, for comparing places.
pub fn resolve(p: &Path) -> PathBuf {
    let abs = if p.is_absolute() {
        p.to_path_buf()
    } else {
        std::env::current_dir().unwrap_or_default().join(p)
    };
    let parts: Vec<Component> = abs.components().collect();
    for k in (1..=parts.len()).rev() {
        let head: PathBuf = parts[..k].iter().collect();
        if let Ok(mut out) = std::fs::canonicalize(&head) {
            for part in &parts[k..] {
                match part {
                    Component::ParentDir => {
                        out.pop();
                    }
                    Component::CurDir => {}
                    c => out.push(c),
                }
            }
            return out;
        }
    }
    abs
}

#[cfg(test)]
mod tests {
    use super::*;

    fn never(_: &Path) -> bool {
        false
    }

    fn always(_: &Path) -> bool {
        true
    }

    #[test]
    fn output_over_input_refused_by_name_also_through_links() {
        let d = tempfile::tempdir().unwrap();
        let g = d.path().join("g.csv");
        std::fs::write(&g, "t,wx,wy,wz\n").unwrap();
        let hard = d.path().join("hard.csv");
        std::fs::hard_link(&g, &hard).unwrap();
        let sub = d.path().join("sub");
        std::fs::create_dir(&sub).unwrap();
        let dotdot = sub.join("..").join("g.csv");
        #[cfg(unix)]
        let soft = {
            let s = d.path().join("soft.csv");
            std::os::unix::fs::symlink(&g, &s).unwrap();
            s
        };
        #[cfg(not(unix))]
        let soft = g.clone();
        for out in [&g, &hard, &dotdot, &soft] {
            let e = OutputGuard::new()
                .input("--gyro", Some(&g))
                .output("--out", Some(out))
                .check()
                .unwrap_err()
                .to_string();
            assert!(
                e.contains("--out") && e.contains("is the input --gyro"),
                "{e}"
            );
        }
        // Another file beside it is fine, and nothing is left by the probe.
        OutputGuard::new()
            .input("--gyro", Some(&g))
            .output("--out", Some(&d.path().join("o.csv")))
            .check()
            .unwrap();
        let mut names: Vec<String> = std::fs::read_dir(d.path())
            .unwrap()
            .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
            .collect();
        names.sort();
        let mut want = vec!["g.csv", "hard.csv", "sub"];
        if cfg!(unix) {
            want.insert(2, "soft.csv");
        }
        assert_eq!(names, want);
    }

    #[test]
    fn file_inside_output_folder_and_input_named_like_its_files() {
        let d = tempfile::tempdir().unwrap();
        let maps = d.path().join("maps");
        let e = OutputGuard::new()
            .output("--out", Some(&maps.join("t.csv")))
            .output_dir("--maps", Some(&maps), never)
            .check();
        // The folder does not exist yet: the file's directory is missing.
        assert!(e.is_err());
        std::fs::create_dir(&maps).unwrap();
        let e = OutputGuard::new()
            .output("--out", Some(&maps.join("t.csv")))
            .output_dir("--maps", Some(&maps), never)
            .check()
            .unwrap_err()
            .to_string();
        assert!(e.contains("inside the output folder --maps"), "{e}");
        let input = maps.join("x.csv");
        std::fs::write(&input, "x").unwrap();
        let e = OutputGuard::new()
            .input("--gyro", Some(&input))
            .output_dir("--maps", Some(&maps), always)
            .check()
            .unwrap_err()
            .to_string();
        assert!(e.contains("the input --gyro"), "{e}");
        OutputGuard::new()
            .input("--gyro", Some(&input))
            .output_dir("--maps", Some(&maps), never)
            .check()
            .unwrap();
    }

    #[test]
    fn resolve_takes_dot_dot_and_missing_tails() {
        let d = tempfile::tempdir().unwrap();
        let c = std::fs::canonicalize(d.path()).unwrap();
        assert_eq!(resolve(&d.path().join("a/b/../c")), c.join("a/c"));
        assert_eq!(resolve(&d.path().join("./x")), c.join("x"));
    }

    #[test]
    fn missing_device_path_refused() {
        let e = OutputGuard::new()
            .output("--out", Some(Path::new("/proc/mmbm-no-such-file")))
            .check()
            .unwrap_err()
            .to_string();
        assert!(e.contains("--out"), "{e}");
    }
}
