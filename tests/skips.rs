//! The shared test helper's resource getters (`tests/common`): a missing GPU
//! adapter or data log is reported as `SKIPPED: <test name>: <reason>` in
//! `cargo test`'s output (past libtest's capture), and is a failure under
//! `MMBM_REQUIRE_GPU=1` / `MMBM_REQUIRE_DATA=1`. The probes run in a child
//! process of this test binary, where the adapter filter matches nothing and
//! the log does not exist, whatever the machine has.

mod common;

use std::process::Output;

const NO_LOG: &str = "no-such-log-for-this-test";

#[test]
#[ignore = "a probe, run in a child process by missing_resources_are_skipped_visibly_or_fail"]
fn probe_gpu() {
    assert!(common::gpu().is_none());
}

#[test]
#[ignore = "a probe, run in a child process by missing_resources_are_skipped_visibly_or_fail"]
fn probe_data() {
    assert!(common::shared_log(NO_LOG).is_none());
}

/// Runs one probe of this binary with `var` set to `value` (unset when `None`).
fn probe(name: &str, var: &str, value: Option<&str>) -> (bool, String, String) {
    let exe = std::env::current_exe().expect("the test binary's path");
    let mut c = std::process::Command::new(exe);
    c.args(["--exact", name, "--include-ignored", "--test-threads=1"])
        .env("MMBM_ADAPTER", "no-such-adapter-for-this-test")
        .env_remove("MMBM_REQUIRE_GPU")
        .env_remove("MMBM_REQUIRE_DATA");
    if let Some(v) = value {
        c.env(var, v);
    }
    let o: Output = c.output().expect("run the probe");
    (
        o.status.success(),
        String::from_utf8_lossy(&o.stdout).into_owned(),
        String::from_utf8_lossy(&o.stderr).into_owned(),
    )
}

#[test]
fn missing_resources_are_skipped_visibly_or_fail() {
    let log = format!("{NO_LOG}/gyro.csv is missing");
    for (name, var, reason) in [
        (
            "probe_gpu",
            "MMBM_REQUIRE_GPU",
            "no GPU adapter found matching MMBM_ADAPTER='no-such-adapter-for-this-test'",
        ),
        ("probe_data", "MMBM_REQUIRE_DATA", log.as_str()),
    ] {
        // Not required (unset, or any value but 1): the test passes, and its
        // stderr (not captured) names it and the reason.
        for value in [None, Some("0")] {
            let (ok, out, err) = probe(name, var, value);
            assert!(ok, "{name} {var}={value:?}:\n{out}\n{err}");
            assert!(out.contains("1 passed"), "{name}: {out}");
            let line = err
                .lines()
                .find(|l| l.starts_with(&format!("SKIPPED: {name}: ")))
                .unwrap_or_else(|| panic!("{name}: no SKIPPED line in\n{err}"));
            assert!(line.contains(reason), "{name}: {line}");
        }
        // Required: the test fails with the reason, and is not reported as skipped.
        let (ok, out, err) = probe(name, var, Some("1"));
        assert!(!ok, "{name} passed under {var}=1:\n{out}\n{err}");
        assert!(out.contains("1 failed"), "{name}: {out}");
        let all = format!("{out}{err}");
        assert!(all.contains(&format!("{name}: {var}=1 but ")), "{all}");
        assert!(all.contains(reason), "{all}");
        assert!(!all.contains("SKIPPED"), "{all}");
    }
}
