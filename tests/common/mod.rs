//! Helpers shared by the integration tests (`mod common;` in each binary):
//! the CLI runners, and the getters of the resources a test may lack (a GPU
//! adapter, the real logs of `../shared/data`).
//!
//! A missing resource is a failure under `MMBM_REQUIRE_GPU=1` /
//! `MMBM_REQUIRE_DATA=1` (as in CI). Without them the test returns early and
//! passes, and says so on stderr as `SKIPPED: <test name>: <reason>`, written
//! to the process's stderr directly: libtest captures `println!`/`eprintln!`
//! of passing tests, so a line printed with those would never be seen.

// Each test binary uses some of these helpers, not all of them.
#![allow(dead_code)]

use mmbm::gpu::GpuContext;
use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// The `mmbm` binary under test, as a command to add arguments to.
pub fn mmbm_cmd() -> Command {
    Command::new(env!("CARGO_BIN_EXE_mmbm"))
}

/// Runs `mmbm ARGS` (stdin empty) and returns its output, whatever its status.
pub fn mmbm(args: &[&str]) -> Output {
    mmbm_cmd()
        .args(args)
        .stdin(Stdio::null())
        .output()
        .expect("run mmbm")
}

/// [`mmbm`] in the working directory `dir`.
pub fn mmbm_in(dir: &Path, args: &[&str]) -> Output {
    mmbm_cmd()
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::null())
        .output()
        .expect("run mmbm")
}

/// [`mmbm_in`], asserting that it succeeded (its stderr is the message if not).
pub fn mmbm_ok_in(dir: &Path, args: &[&str]) -> Output {
    let o = mmbm_in(dir, args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

/// The running test's name (libtest names each test's thread after it).
pub fn test_name() -> String {
    std::thread::current()
        .name()
        .unwrap_or("<unnamed test>")
        .to_string()
}

/// True when `VAR=1`: the resource it names is required.
fn required(var: &str) -> bool {
    std::env::var(var).is_ok_and(|v| v == "1")
}

/// Reports that the running test is skipped, past libtest's capture.
pub fn skip(reason: &str) {
    let line = format!("SKIPPED: {}: {reason}\n", test_name());
    std::io::stderr()
        .write_all(line.as_bytes())
        .expect("write the SKIPPED line to stderr");
}

/// A resource the running test lacks: a failure when `var=1`, else a skip.
fn missing(var: &str, reason: &str) {
    if required(var) {
        panic!("{}: {var}=1 but {reason}", test_name());
    }
    skip(reason);
}

/// `../shared/data/NAME/gyro.csv` when it is beside the checkout, else `None`
/// (skipped; a failure under `MMBM_REQUIRE_DATA=1`).
pub fn shared_log(name: &str) -> Option<PathBuf> {
    let p = PathBuf::from(env!("CARGO_MANIFEST_DIR"))
        .join("../shared/data")
        .join(name)
        .join("gyro.csv");
    if p.exists() {
        return Some(p);
    }
    missing("MMBM_REQUIRE_DATA", &format!("{} is missing", p.display()));
    None
}

/// The shared GPU device when an adapter exists, else `None` (skipped, with
/// the adapter error as the reason; a failure under `MMBM_REQUIRE_GPU=1`).
pub fn gpu() -> Option<&'static GpuContext> {
    match mmbm::gpu::gpu() {
        Ok(c) => Some(c),
        Err(e) => {
            missing("MMBM_REQUIRE_GPU", &e.to_string());
            None
        }
    }
}
