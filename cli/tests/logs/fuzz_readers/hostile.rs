//! Hostile inputs built on purpose (not random): camera files from JSON and
//! TOML made to hurt parsers, and dataset manifests whose lines lie (issue
//! #23). Each is refused quickly with a short error, through the library and
//! the CLI, and nothing is written.

use crate::common;
use mmbm::Camera;
use proptest::prelude::*;
use std::path::{Path, PathBuf};

fn fixture(name: &str) -> PathBuf {
    crate::common::repo_root().join(name)
}

fn write(dir: &Path, name: &str, bytes: &[u8]) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, bytes).unwrap();
    p
}

/// What a hostile input must get: an error (not a panic, not a value), shown
/// in bounded length, found within `secs`, with each of `words`.
fn refused<T>(what: &str, secs: f64, words: &[&str], f: impl FnOnce() -> mmbm::Result<T>) {
    let t0 = std::time::Instant::now();
    let r = std::panic::catch_unwind(std::panic::AssertUnwindSafe(f));
    let took = t0.elapsed().as_secs_f64();
    let e = match r {
        Ok(Ok(_)) => panic!("{what}: accepted"),
        Ok(Err(e)) => e.to_string(),
        Err(_) => panic!("{what}: panicked"),
    };
    assert!(took < secs, "{what}: {took:.2} s to refuse");
    assert!(
        e.len() <= 2 * mmbm::error::MAX_SHOWN,
        "{what}: {} bytes of error",
        e.len()
    );
    for w in words {
        assert!(e.contains(w), "{what}: '{w}' not in: {e}");
    }
}

/// The CLI door for the same input: exit 1, a short `error:` line, no
/// panic, within 60 s in 600 MB of address space.
#[cfg(unix)]
fn cli_refuses(dir: &Path, args: &str, words: &[&str]) {
    let o = std::process::Command::new("sh")
        .current_dir(dir)
        .arg("-c")
        .arg(format!(
            "ulimit -v 600000 && exec timeout 60 '{}' {args}",
            common::bin().display()
        ))
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{args}: {err}");
    assert!(
        err.starts_with("error:") && !err.contains("panicked"),
        "{args}: {err}"
    );
    assert!(
        err.len() <= 2 * mmbm::error::MAX_SHOWN,
        "{args}: {} bytes",
        err.len()
    );
    for w in words {
        assert!(err.contains(w), "{args}: '{w}' not in: {err}");
    }
}

const DEEP: usize = 100_000;

/// Issue #23: camera files from hostile JSON and TOML (deep nesting, huge
/// numbers, NaN and infinity, wrong types, huge arrays, devices, files over
/// the cap) are refused quickly, naming the file, through the library and
/// the CLI. A 6 MB TOML array used to take 5.7 s and 530 MB to refuse, and
/// `--camera /dev/zero` read until memory ran out.
#[test]
fn hostile_camera_files() {
    let d = tempfile::tempdir().unwrap();
    let open = |s: &str| format!("{{{s}, \"pitch_mm\": 0.00465, \"width\": 640, \"height\": 480}}");
    let toml = |s: &str| format!("{s}\npitch_mm = 0.00465\nwidth = 640\nheight = 480\n");
    let zeros = |n: usize| vec!["0"; n].join(",");
    let cases: Vec<(&str, String, &[&str])> = vec![
        ("deep.json", "[".repeat(DEEP) + &"]".repeat(DEEP), &["recursion limit"]),
        ("deepkey.json", open(&format!("\"focal_mm\": {}", "[".repeat(DEEP))), &["recursion limit"]),
        ("gyroflow.json", format!("{{\"fisheye_params\": {}}}", "{\"a\":".repeat(DEEP)), &["recursion limit"]),
        ("nan.json", open("\"focal_mm\": \"NaN\""), &["invalid type"]),
        ("huge.json", open("\"focal_mm\": 1e400"), &["out of range"]),
        ("tiny.json", open("\"focal_mm\": 1e-400"), &["focal"]),
        ("type.json", open("\"focal_mm\": true"), &["invalid type"]),
        ("wide.json", "{\"focal_mm\": 4.2, \"pitch_mm\": 0.00465, \"width\": 4294967296, \"height\": 480}".into(), &["expected u32"]),
        ("array.json", open(&format!("\"focal_mm\": [{}]", zeros(400_000))), &["invalid type"]),
        ("gf-types.json", "{\"fisheye_params\": {\"camera_matrix\": \"x\"}, \"calib_dimension\": {\"w\": -1, \"h\": 1e300}}".into(), &[]),
        ("deep.toml", format!("a = {}{}\n", "[".repeat(DEEP), "]".repeat(DEEP)), &["TOML parse error"]),
        ("inline.toml", format!("a = {}1{}\n", "{b = ".repeat(DEEP), "}".repeat(DEEP)), &["TOML parse error"]),
        ("tables.toml", format!("[{}a]\n", "a.".repeat(DEEP)), &["TOML parse error"]),
        ("nan.toml", toml("focal_mm = nan"), &["finite"]),
        ("inf.toml", toml("focal_mm = -inf"), &["finite"]),
        ("nanstr.toml", toml("focal_mm = \"NaN\""), &["invalid type"]),
        ("huge.toml", toml("focal_mm = 1e400"), &["TOML parse error"]),
        ("int.toml", "focal_mm = 4.2\npitch_mm = 0.00465\nwidth = 99999999999999999999\nheight = 4\n".into(), &["TOML parse error"]),
        ("array.toml", toml(&format!("focal_mm = [{}]", zeros(400_000))), &["TOML parse error"]),
        ("string.toml", toml(&format!("focal_mm = \"{}\"", "x".repeat(900_000))), &["TOML parse error"]),
        ("long.toml", toml(&format!("focal_mm = [{}]", zeros(3_000_000))), &["longer than 1048576 bytes"]),
    ];
    for (name, text, words) in &cases {
        let p = write(d.path(), name, text.as_bytes());
        let mut w = words.to_vec();
        w.push(name);
        refused(name, 5.0, &w, || Camera::load(&p));
    }
    let p = write(d.path(), "bytes.toml", b"focal_mm = \xff\xfe\n");
    refused("bytes.toml", 5.0, &["bytes.toml", "not UTF-8"], || {
        Camera::load(&p)
    });
    refused(
        "/dev/zero",
        5.0,
        &["/dev/zero", "expected a regular file or a pipe"],
        || Camera::load(Path::new("/dev/zero")),
    );
    #[cfg(unix)]
    for (f, w) in [
        ("deep.toml", "TOML parse error"),
        ("array.toml", "TOML parse error"),
        ("long.toml", "longer than"),
        ("deep.json", "recursion limit"),
        ("/dev/zero", "expected a regular file or a pipe"),
    ] {
        cli_refuses(
            d.path(),
            &format!("eval --omega 1,1,1 --camera {f}"),
            &[f, w],
        );
    }
}

/// Issue #23: hostile `manifest.jsonl` lines (over the line cap, nested,
/// wrong types, huge and NaN numbers, paths out of the directory, too many
/// lines) make `--verify` and `--merge` fail quickly with a short error,
/// writing nothing; the good manifest still verifies after.
#[test]
fn hostile_manifests() {
    use mmbm_lab::dataset::{self, DatasetConfig, Shard};
    use serde_json::{json, Value};
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("data");
    let cfg = DatasetConfig {
        count: 2,
        seed: 1,
        textures: fixture("assets/textures"),
        motion: vec!["sim:moderate".to_string()],
        resolution: [24, 18],
        ..DatasetConfig::default()
    };
    dataset::run(&cfg, &out, Shard::ALL, false).unwrap();
    let manifest = out.join("manifest.jsonl");
    let good = std::fs::read_to_string(&manifest).unwrap();
    let lines: Vec<Value> = good
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    // The first line edited by `f`, then the second line as it was.
    let edit = |f: &dyn Fn(&mut Value)| {
        let mut l = lines[0].clone();
        f(&mut l);
        format!("{l}\n{}\n", lines[1])
    };
    let cap = mmbm::io::input::MAX_LINE_BYTES;
    let cases: Vec<(&str, String, &[&str])> = vec![
        (
            "a line over the cap",
            format!("{}\n", "x".repeat(cap + 1)),
            &["longer than"],
        ),
        ("nested arrays", "[".repeat(DEEP) + "\n", &["invalid type"]),
        (
            "nested in a field",
            edit(&|l| l["deep"] = json!("@@")).replace("\"@@\"", &"{\"a\":[".repeat(DEEP)),
            &["recursion limit"],
        ),
        (
            "index a string",
            edit(&|l| l["index"] = json!("0")),
            &["invalid type"],
        ),
        (
            "index negative",
            edit(&|l| l["index"] = json!(-1)),
            &["invalid value"],
        ),
        (
            "index 1e400",
            edit(&|l| l["index"] = json!(0)).replacen("\"index\":0", "\"index\":1e400", 1),
            &["out of range"],
        ),
        (
            "index past u64",
            edit(&|l| l["index"] = json!(0)).replacen(
                "\"index\":0",
                "\"index\":18446744073709551616",
                1,
            ),
            &["manifest.jsonl"],
        ),
        (
            "a NaN string",
            edit(&|l| l["blur_path_px"] = json!("NaN")),
            &["invalid type"],
        ),
        (
            "dir absolute",
            edit(&|l| l["dir"] = json!("/etc")),
            &["is not items/00000000"],
        ),
        (
            "dir up",
            edit(&|l| l["dir"] = json!("../../../../../etc")),
            &["is not items/00000000"],
        ),
        (
            "dir with NUL",
            edit(&|l| l["dir"] = json!("items/0000\u{0}0000")),
            &["is not items/00000000"],
        ),
        (
            "dir of 1 MB",
            edit(&|l| l["dir"] = json!("a/".repeat(500_000))),
            &["is not items/00000000"],
        ),
        (
            "files a list",
            edit(&|l| l["files"] = json!(vec![0; 100_000])),
            &["invalid type"],
        ),
        (
            "file outside",
            edit(&|l| l["files"]["/etc/hostname"] = json!({"bytes": 1, "sha256": "0"})),
            &["is not a file of an item"],
        ),
        (
            "bytes negative",
            edit(&|l| l["files"]["sharp.png"]["bytes"] = json!(-1)),
            &["invalid value"],
        ),
        (
            "bytes 1e30",
            edit(&|l| l["files"]["sharp.png"]["bytes"] = json!(1e30)),
            &["invalid type"],
        ),
        (
            "sha256 a number",
            edit(&|l| l["files"]["sharp.png"]["sha256"] = json!(7)),
            &["invalid type"],
        ),
        (
            "not JSON",
            "\u{0}\u{0}\u{1}\n".repeat(1000),
            &["manifest.jsonl"],
        ),
        (
            "not UTF-8",
            "{\"index\": \"\u{fffd}\"}\n".replace('\u{fffd}', "\u{ff}"),
            &["manifest.jsonl"],
        ),
        (
            "more lines than items",
            good.repeat(1000),
            &["more than 2 lines"],
        ),
    ];
    for (name, text, words) in &cases {
        std::fs::write(&manifest, text).unwrap();
        refused(&format!("verify: {name}"), 10.0, words, || {
            dataset::verify(&out)
        });
        // As a shard part: merge checks what a join needs (JSON lines of
        // this configuration's items, each once) and, refusing, writes no
        // manifest; what it joins anyway (a bad `dir` or `files`), verify
        // refuses after.
        std::fs::remove_file(&manifest).unwrap();
        let part = out.join("manifest.part-1-of-1.jsonl");
        std::fs::write(&part, text).unwrap();
        let t0 = std::time::Instant::now();
        match std::panic::catch_unwind(|| dataset::merge(&out)) {
            Err(_) => panic!("merge: {name}: panicked"),
            Ok(Err(e)) => {
                assert!(
                    e.to_string().len() <= 2 * mmbm::error::MAX_SHOWN,
                    "merge: {name}: {e}"
                );
                assert!(!manifest.exists(), "merge: {name}: wrote a manifest");
            }
            Ok(Ok(_)) => refused(&format!("verify after merge: {name}"), 10.0, words, || {
                dataset::verify(&out)
            }),
        }
        assert!(t0.elapsed().as_secs_f64() < 10.0, "merge: {name}: too slow");
        std::fs::remove_file(&part).unwrap();
    }
    #[cfg(unix)]
    for (name, text, words) in [&cases[0], &cases[1], &cases[19]] {
        std::fs::write(&manifest, text).unwrap();
        cli_refuses(d.path(), "dataset --verify --out data", words);
        let _ = name;
    }
    std::fs::write(&manifest, &good).unwrap();
    assert_eq!(dataset::verify(&out).unwrap(), 2);
}

proptest! {
    #![proptest_config(ProptestConfig { cases: 64, failure_persistence: None, ..ProptestConfig::default() })]

    /// Random edits of a valid manifest: `--verify` answers (it may accept
    /// an edit that keeps the JSON's meaning, such as added spaces) and
    /// never panics; an error is short.
    #[test]
    fn manifest_mutations(edits in prop::collection::vec((0..3u8, any::<prop::sample::Index>(), any::<u8>()), 1..8)) {
        use mmbm_lab::dataset::{self, DatasetConfig, Shard};
        static DIR: std::sync::OnceLock<(tempfile::TempDir, String)> = std::sync::OnceLock::new();
        let (d, good) = DIR.get_or_init(|| {
            let d = tempfile::tempdir().unwrap();
            let cfg = DatasetConfig {
                count: 2,
                seed: 2,
                textures: fixture("assets/textures"),
                motion: vec!["sim:fast".to_string()],
                resolution: [16, 12],
                ..DatasetConfig::default()
            };
            dataset::run(&cfg, &d.path().join("data"), Shard::ALL, false).unwrap();
            let good = std::fs::read_to_string(d.path().join("data/manifest.jsonl")).unwrap();
            (d, good)
        });
        let mut b = good.clone().into_bytes();
        for (kind, at, byte) in edits {
            let at = at.index(b.len() + 1);
            match kind {
                0 if at < b.len() => b[at] = byte,
                1 => b.insert(at, byte),
                _ if at < b.len() => {
                    b.remove(at);
                }
                _ => b.push(byte),
            }
        }
        let out = d.path().join("data");
        std::fs::write(out.join("manifest.jsonl"), &b).unwrap();
        match std::panic::catch_unwind(|| dataset::verify(&out)) {
            Ok(Ok(n)) => prop_assert_eq!(n, 2),
            Ok(Err(e)) => prop_assert!(e.to_string().len() <= 2 * mmbm::error::MAX_SHOWN),
            Err(_) => prop_assert!(false, "verify panicked"),
        }
    }
}
