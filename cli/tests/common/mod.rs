//! Helpers of the `mmbm` command's tests (`mod common;` in each binary of
//! `cli/tests/`): the library tests' helpers (`tests/common/mod.rs`: the
//! repository's root, the resource getters) and the CLI runners.
//!
//! The command under test is the one cargo built for this crate's tests
//! (`CARGO_BIN_EXE_mmbm`: `cargo test` builds it before the tests run, so it
//! is never stale), or `MMBM_BIN` when set (another build of the command).

// Each test binary uses some of these helpers, not all of them.
#![allow(dead_code)]

#[path = "../../../tests/common/mod.rs"]
mod library;
pub use library::*;

use std::io::Write;
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// The `mmbm` binary under test: `MMBM_BIN` if set, else the one cargo built
/// for these tests (`CARGO_BIN_EXE_mmbm`).
pub fn bin() -> PathBuf {
    std::env::var_os("MMBM_BIN")
        .map(PathBuf::from)
        .unwrap_or_else(|| PathBuf::from(env!("CARGO_BIN_EXE_mmbm")))
}

/// The `mmbm` binary under test, as a command to add arguments to.
pub fn mmbm_cmd() -> Command {
    Command::new(bin())
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

/// Runs `mmbm ARGS` in `dir` with `stdin` on its standard input; fails the
/// test if it does not end within `secs` seconds (it is killed then).
pub fn mmbm_within(dir: &Path, args: &[&str], stdin: Vec<u8>, secs: u64) -> Output {
    let mut child = mmbm_cmd()
        .args(args)
        .current_dir(dir)
        .stdin(Stdio::piped())
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut input = child.stdin.take().unwrap();
    let feeder = std::thread::spawn(move || {
        // The reader may stop early (an error): a broken pipe is expected.
        let _ = input.write_all(&stdin);
    });
    let start = std::time::Instant::now();
    while child.try_wait().unwrap().is_none() {
        if start.elapsed().as_secs() >= secs {
            child.kill().unwrap();
            panic!("mmbm {args:?} still running after {secs} s");
        }
        std::thread::sleep(std::time::Duration::from_millis(20));
    }
    feeder.join().unwrap();
    child.wait_with_output().unwrap()
}

/// A free local UDP address (`127.0.0.1:PORT`): a port the system handed out
/// a moment ago, for `mmbm live --udp`.
pub fn free_udp_addr() -> String {
    let s = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    format!("127.0.0.1:{}", s.local_addr().unwrap().port())
}

/// `mmbm live --udp` on a free local port (`fixed:5 --all`, idle exit after
/// 1.5 s), a socket to send from, and the address, once it listens.
pub fn udp_live() -> (std::process::Child, std::net::UdpSocket, String) {
    let addr = free_udp_addr();
    let child = mmbm_cmd()
        .args(["live", "--policy", "fixed:5", "--all", "--idle-exit", "1.5"])
        .args(["--udp", &addr])
        .stdout(Stdio::piped())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let sock = std::net::UdpSocket::bind("127.0.0.1:0").unwrap();
    std::thread::sleep(std::time::Duration::from_millis(500));
    (child, sock, addr)
}

/// `mmbm simulate` of a 20 s moderate walk (seed 7) into `dir/walk.csv`.
pub fn simulated_walk(dir: &Path) -> PathBuf {
    let p = dir.join("walk.csv");
    let o = mmbm_cmd()
        .args([
            "simulate",
            "--gait",
            "moderate",
            "--duration",
            "20",
            "--seed",
            "7",
        ])
        .arg("--out")
        .arg(&p)
        .output()
        .unwrap();
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    p
}
