//! Datasets that are safe to share (issues 35 and 37): WebDataset packing
//! under a lock and all or nothing, `--verify` trusting no shard (links,
//! a missing index, unlisted shards, a wrong count), `--shard-bytes` checked
//! before any item is made and only with `--format webdataset`, a set that
//! grows (count 6 -> 7 equals a set made at 7), no lock file left after a
//! run, and files made under the process's umask.

use crate::common;

use common::tree;
use mmbm_lab::dataset::{self, DatasetConfig, Shard};
use std::path::{Path, PathBuf};
use std::process::{Command, Output, Stdio};

/// Tiny items (quick to make), `count` of them.
fn tiny(count: u64) -> DatasetConfig {
    DatasetConfig {
        count,
        seed: 5,
        textures: crate::common::repo_root().join("assets/textures"),
        motion: vec!["sim:moderate".to_string(), "sim:fast".to_string()],
        resolution: [24, 18],
        ..DatasetConfig::default()
    }
}

/// Writes `cfg` as `dir/NAME.toml`.
fn toml(dir: &Path, name: &str, cfg: &DatasetConfig) -> PathBuf {
    let p = dir.join(format!("{name}.toml"));
    std::fs::write(&p, cfg.to_toml().unwrap()).unwrap();
    p
}

/// `mmbm dataset ARGS --quiet`.
fn ds(args: &[&str]) -> Command {
    let mut c = common::mmbm_cmd();
    c.arg("dataset").args(args).arg("--quiet");
    c.stdin(Stdio::null());
    c
}

fn run(args: &[&str]) -> Output {
    ds(args).output().unwrap()
}

fn ok(args: &[&str]) -> Output {
    let o = run(args);
    assert!(
        o.status.success(),
        "{args:?}: {}",
        String::from_utf8_lossy(&o.stderr)
    );
    o
}

fn err(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

fn s(p: &Path) -> &str {
    p.to_str().unwrap()
}

/// The names in `dir` starting with `.lock`.
fn lock_files(dir: &Path) -> Vec<String> {
    std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| n.starts_with(".lock"))
        .collect()
}

/// A set of `count` tiny items made in 2 shards and merged (not packed).
fn sharded_set(root: &Path, count: u64) -> PathBuf {
    let cfg = toml(root, "ds", &tiny(count));
    let out = root.join("data");
    for k in ["1/2", "2/2"] {
        ok(&["--config", s(&cfg), "--out", s(&out), "--shard", k]);
    }
    out
}

/// The index's shard size and the shard names it lists.
fn index_of(out: &Path) -> (u64, Vec<String>) {
    let text = std::fs::read_to_string(out.join("webdataset/index.json")).unwrap();
    let v: serde_json::Value = serde_json::from_str(&text).unwrap();
    let names = v["shards"]
        .as_array()
        .unwrap()
        .iter()
        .map(|t| t["name"].as_str().unwrap().to_string())
        .collect();
    (v["shard_bytes"].as_u64().unwrap(), names)
}

/// The files of `out/webdataset` (sorted names), index included.
fn packed_names(out: &Path) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(out.join("webdataset"))
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .collect();
    v.sort();
    v
}

/// Issue 35 item 6: two `--merge --format webdataset` runs with different
/// `--shard-bytes` both exited 0 and left an index listing shards that were
/// not there. Packing takes the dataset's packing lock: while another run
/// holds it, a packing is refused and changes nothing; two packings started
/// together leave one whole packing (each run either packs or is refused).
#[cfg(unix)]
#[test]
fn a_packing_while_another_packs_is_refused_and_the_result_is_whole() {
    let root = tempfile::tempdir().unwrap();
    let out = sharded_set(root.path(), 12);
    let pack = |bytes: &str| {
        ds(&[
            "--merge",
            "--format",
            "webdataset",
            "--shard-bytes",
            bytes,
            "--out",
            s(&out),
        ])
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap()
    };
    // Another run holds the packing lock: refused, nothing packed.
    {
        let f = std::fs::File::create(out.join(".lock-pack")).unwrap();
        fs4::FileExt::lock(&f).unwrap();
        let o = pack("65536").wait_with_output().unwrap();
        assert_eq!(o.status.code(), Some(1), "{}", err(&o));
        assert!(err(&o).contains("another run is writing"), "{}", err(&o));
        assert!(!out.join("webdataset").exists(), "a refused run packed");
    }
    // Two at once, with different shard sizes.
    for round in 0..3 {
        let (a, b) = (pack("65536"), pack("1000000"));
        let results = [a.wait_with_output().unwrap(), b.wait_with_output().unwrap()];
        for o in &results {
            assert!(
                o.status.success() || err(o).contains("another run is writing"),
                "round {round}: {}",
                err(o)
            );
        }
        assert!(results.iter().any(|o| o.status.success()), "round {round}");
        let (bytes, listed) = index_of(&out);
        assert!(bytes == 65536 || bytes == 1_000_000, "{bytes}");
        let mut want: Vec<String> = listed.clone();
        want.push("index.json".into());
        want.sort();
        assert_eq!(
            packed_names(&out),
            want,
            "round {round}: the index lists exactly the shards there"
        );
        ok(&["--verify", "--out", s(&out)]);
        assert!(lock_files(&out).is_empty(), "{:?}", lock_files(&out));
    }
}

/// A packed set for the `--verify` tests: several shards.
fn packed_set(root: &Path) -> PathBuf {
    let cfg = toml(root, "ds", &tiny(4));
    let out = root.join("data");
    ok(&[
        "--config",
        s(&cfg),
        "--out",
        s(&out),
        "--format",
        "webdataset",
        "--shard-bytes",
        "65536",
    ]);
    assert!(index_of(&out).1.len() >= 2, "{:?}", index_of(&out));
    ok(&["--verify", "--out", s(&out)]);
    out
}

/// `--verify` on `out`: refused (exit 1) with each of `words` in its message.
fn verify_refuses(out: &Path, words: &[&str]) {
    let o = run(&["--verify", "--out", s(out)]);
    let e = err(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    for w in words {
        assert!(e.contains(w), "'{w}' not in: {e}");
    }
}

/// Issue 35 item 8: a shard that is a symlink out of the dataset was
/// followed and hashed (and passed when it led to the same bytes). It is
/// refused unread.
#[cfg(unix)]
#[test]
fn verify_refuses_a_symlinked_shard_unread() {
    let root = tempfile::tempdir().unwrap();
    let out = packed_set(root.path());
    let shard = out.join("webdataset/mmbm-000000.tar");
    // The same bytes outside, and the shard a link to them.
    let outside = root.path().join("elsewhere.tar");
    std::fs::rename(&shard, &outside).unwrap();
    std::os::unix::fs::symlink(&outside, &shard).unwrap();
    verify_refuses(&out, &["mmbm-000000.tar", "symbolic link", "not read"]);
    // A pipe in a shard's place is not read either (it would block).
    std::fs::remove_file(&shard).unwrap();
    let made = Command::new("mkfifo").arg(&shard).status();
    if made.is_ok_and(|s| s.success()) {
        verify_refuses(&out, &["mmbm-000000.tar", "not a regular file"]);
    }
}

/// Issue 35 item 8: with `index.json` deleted, a tampered shard passed.
/// The index is required wherever `webdataset/` exists.
#[test]
fn verify_requires_the_index() {
    let root = tempfile::tempdir().unwrap();
    let out = packed_set(root.path());
    let shard = out.join("webdataset/mmbm-000001.tar");
    let mut b = std::fs::read(&shard).unwrap();
    b[700] ^= 1;
    std::fs::write(&shard, &b).unwrap();
    std::fs::remove_file(out.join("webdataset/index.json")).unwrap();
    verify_refuses(&out, &["webdataset", "no index.json"]);
}

/// Issue 35 item 8: an extra shard, and a wrong `count` in the index, went
/// unreported.
#[test]
fn verify_reports_an_unlisted_shard_and_a_wrong_count() {
    let root = tempfile::tempdir().unwrap();
    let out = packed_set(root.path());
    let wd = out.join("webdataset");
    let extra = wd.join("mmbm-000099.tar");
    std::fs::copy(wd.join("mmbm-000000.tar"), &extra).unwrap();
    verify_refuses(&out, &["mmbm-000099.tar", "not listed"]);
    std::fs::remove_file(&extra).unwrap();
    ok(&["--verify", "--out", s(&out)]);

    let index = wd.join("index.json");
    let text = std::fs::read_to_string(&index).unwrap();
    let mut v: serde_json::Value = serde_json::from_str(&text).unwrap();
    assert_eq!(v["count"], 4);
    v["count"] = 5.into();
    std::fs::write(&index, serde_json::to_string_pretty(&v).unwrap()).unwrap();
    verify_refuses(&out, &["index.json", "count 5", "has 4"]);
}

/// Issue 35 items 9 and 11: `--shard-bytes 0` was refused only after the
/// whole set was made; `--shard-bytes` without `--format webdataset` was
/// ignored. Both are refused before anything is made, naming the flags.
#[test]
fn shard_bytes_is_checked_before_any_item_is_made() {
    let root = tempfile::tempdir().unwrap();
    let cfg = toml(root.path(), "ds", &tiny(40));
    let out = root.path().join("data");
    for bad in ["0", "65535", "1099511627777", "1e9"] {
        let t = std::time::Instant::now();
        let o = run(&[
            "--config",
            s(&cfg),
            "--out",
            s(&out),
            "--format",
            "webdataset",
            "--shard-bytes",
            bad,
        ]);
        let e = err(&o);
        assert!(!o.status.success(), "--shard-bytes {bad}: {e}");
        assert!(e.contains("--shard-bytes") && e.contains(bad), "{e}");
        assert!(!out.exists(), "--shard-bytes {bad}: the run made {out:?}");
        assert!(t.elapsed().as_secs_f64() < 5.0, "{:?}", t.elapsed());
    }
    for args in [
        vec![
            "--config",
            s(&cfg),
            "--out",
            s(&out),
            "--shard-bytes",
            "100000",
        ],
        vec![
            "--config",
            s(&cfg),
            "--out",
            s(&out),
            "--format",
            "folder",
            "--shard-bytes",
            "100000",
        ],
        vec!["--merge", "--out", s(&out), "--shard-bytes", "100000"],
    ] {
        let o = run(&args);
        let e = err(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {e}");
        assert!(
            e.contains("--shard-bytes") && e.contains("--format webdataset"),
            "{e}"
        );
        assert!(!out.exists(), "{args:?} made {out:?}");
    }
}

/// The item folders, manifest and record of `dir` (relative path -> bytes).
fn set_files(dir: &Path) -> std::collections::BTreeMap<String, Vec<u8>> {
    tree(dir)
        .into_iter()
        .filter(|(k, _)| {
            k.starts_with("items/")
                || k.starts_with("webdataset/")
                || k == "manifest.jsonl"
                || k == "dataset.json"
        })
        .collect()
}

/// Issue 37: raising `count` from 6 to 7 was refused ("differs in: count")
/// though each item depends only on the configuration and its index. A
/// larger count adds items and keeps the others byte for byte: the grown
/// set is the set made at 7 at once (items, manifest, record, tar shards).
/// A smaller count is refused, naming both counts.
#[test]
fn a_set_grows_from_6_to_7_and_equals_one_made_at_7() {
    let root = tempfile::tempdir().unwrap();
    let (six, seven) = (
        toml(root.path(), "six", &tiny(6)),
        toml(root.path(), "seven", &tiny(7)),
    );
    let grown = root.path().join("grown");
    let fresh = root.path().join("fresh");
    let make = |cfg: &Path, out: &Path| {
        ok(&[
            "--config",
            s(cfg),
            "--out",
            s(out),
            "--format",
            "webdataset",
            "--shard-bytes",
            "65536",
        ])
    };
    make(&six, &grown);
    let before = set_files(&grown);
    let o = make(&seven, &grown);
    assert!(
        err(&o).contains("1 made, 6 already complete"),
        "{}",
        err(&o)
    );
    let after = set_files(&grown);
    for i in 0..6 {
        let item = format!("items/{i:08}/");
        let old: Vec<_> = before
            .iter()
            .filter(|(k, _)| k.starts_with(&item))
            .collect();
        let new: Vec<_> = after.iter().filter(|(k, _)| k.starts_with(&item)).collect();
        assert_eq!(old.len(), 7, "{item}");
        assert!(old == new, "{item} changed as the set grew");
    }
    assert!(after.contains_key("items/00000006/item.json"));
    ok(&["--verify", "--out", s(&grown)]);
    make(&seven, &fresh);
    let fresh_files = set_files(&fresh);
    assert_eq!(
        after.keys().collect::<Vec<_>>(),
        fresh_files.keys().collect::<Vec<_>>()
    );
    for (k, v) in &after {
        assert!(*v == fresh_files[k], "{k} differs from the set made at 7");
    }
    // A smaller count is refused, and changes nothing.
    let o = run(&["--config", s(&six), "--out", s(&grown)]);
    let e = err(&o);
    assert_eq!(o.status.code(), Some(1), "{e}");
    assert!(
        e.contains("count") && e.contains('6') && e.contains('7'),
        "{e}"
    );
    assert!(set_files(&grown) == after, "a refused run changed the set");
    // A shard of the grown set needs its new item: merging the old part is refused.
    let parts = root.path().join("parts");
    for k in ["1/2", "2/2"] {
        ok(&["--config", s(&six), "--out", s(&parts), "--shard", k]);
    }
    ok(&["--config", s(&seven), "--out", s(&parts), "--shard", "2/2"]);
    let o = run(&["--merge", "--out", s(&parts)]);
    assert!(err(&o).contains("item 6 is missing"), "{}", err(&o));
    ok(&["--config", s(&seven), "--out", s(&parts), "--shard", "1/2"]);
    ok(&["--merge", "--out", s(&parts)]);
    ok(&["--verify", "--out", s(&parts)]);
}

/// Issue 37: lock files stayed after every run. Each run removes its own
/// as it ends (a shared one only when no other run holds it).
#[test]
fn no_lock_file_stays_after_a_run() {
    let root = tempfile::tempdir().unwrap();
    let out = sharded_set(root.path(), 4);
    assert!(lock_files(&out).is_empty(), "{:?}", lock_files(&out));
    ok(&["--merge", "--format", "webdataset", "--out", s(&out)]);
    assert!(lock_files(&out).is_empty(), "{:?}", lock_files(&out));
    // A refused run leaves none either.
    let o = run(&[
        "--config",
        s(&toml(root.path(), "b", &tiny(3))),
        "--out",
        s(&out),
    ]);
    assert_eq!(o.status.code(), Some(1), "{}", err(&o));
    assert!(lock_files(&out).is_empty(), "{:?}", lock_files(&out));

    // Two shards of one count hold the shared lock: it goes with the last.
    let a = dataset::RunLock::take(&out, Shard::new(1, 2).unwrap()).unwrap();
    let b = dataset::RunLock::take(&out, Shard::new(2, 2).unwrap()).unwrap();
    let mut names = lock_files(&out);
    names.sort();
    assert_eq!(names, [".lock-1-of-2", ".lock-2-of-2", ".lock-of-2"]);
    drop(a);
    let mut names = lock_files(&out);
    names.sort();
    assert_eq!(names, [".lock-2-of-2", ".lock-of-2"]);
    // While b holds its locks, its shard is still refused to another run.
    let e = dataset::RunLock::take(&out, Shard::new(2, 2).unwrap())
        .unwrap_err()
        .to_string();
    assert!(e.contains("another run is writing"), "{e}");
    drop(b);
    assert!(lock_files(&out).is_empty(), "{:?}", lock_files(&out));
    // Taken again after the files went: a fresh file, locked as before.
    let c = dataset::RunLock::take(&out, Shard::ALL).unwrap();
    assert!(dataset::RunLock::take(&out, Shard::new(1, 2).unwrap()).is_err());
    drop(c);
    assert!(lock_files(&out).is_empty());
}

/// The modes of every file and folder under `dir` (relative path -> mode).
#[cfg(unix)]
fn modes(dir: &Path) -> Vec<(String, u32, bool)> {
    use std::os::unix::fs::PermissionsExt;
    let mut out = Vec::new();
    let mut stack = vec![dir.to_path_buf()];
    while let Some(d) = stack.pop() {
        for e in std::fs::read_dir(&d).unwrap() {
            let p = e.unwrap().path();
            let m = std::fs::symlink_metadata(&p).unwrap();
            let rel = p.strip_prefix(dir).unwrap().to_string_lossy().into_owned();
            out.push((rel, m.permissions().mode() & 0o777, m.is_dir()));
            if m.is_dir() {
                stack.push(p);
            }
        }
    }
    out
}

/// Issue 37: `dataset.json` was made mode 0600 (a temporary file's). Every
/// file is made as any new file under the process's umask: 0644 under 022,
/// 0640 under 027 (folders 0755, 0750).
#[cfg(unix)]
#[test]
fn files_are_made_under_the_umask() {
    let root = tempfile::tempdir().unwrap();
    let cfg = toml(root.path(), "ds", &tiny(2));
    for (umask, file, folder) in [("022", 0o644, 0o755), ("027", 0o640, 0o750)] {
        let out = root.path().join(format!("data-{umask}"));
        let o = Command::new("sh")
            .arg("-c")
            .arg(format!(
                "umask {umask} && exec \"$0\" dataset --quiet --config \"$1\" --out \"$2\" \
                 --format webdataset"
            ))
            .arg(common::bin())
            .arg(&cfg)
            .arg(&out)
            .output()
            .unwrap();
        assert!(o.status.success(), "{}", err(&o));
        let got = modes(&out);
        assert!(got.iter().any(|(p, _, _)| p == "dataset.json"));
        assert!(got.iter().any(|(p, _, _)| p.ends_with(".tar")));
        for (p, mode, dir) in got {
            let want = if dir { folder } else { file };
            assert_eq!(mode, want, "umask {umask}: {p} is {mode:o}, not {want:o}");
        }
    }
}
