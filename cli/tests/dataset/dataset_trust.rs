//! Datasets that cannot be fooled (issue #23 item 6): a directory keeps to
//! the configuration it was made with (its fingerprint), merge joins only
//! parts of one configuration and shard count, `--verify` treats the manifest
//! as input (every path confined to the directory), shard counts are capped,
//! and one shard has one writer at a time.

use crate::common;

use common::tree;

use common::mmbm_in;
use mmbm_lab::dataset::{self, DatasetConfig, Shard, Sources};
use std::path::Path;

/// A config of tiny items (quick to make), `count` of them, seed `seed`.
fn tiny(count: u64, seed: u64) -> DatasetConfig {
    DatasetConfig {
        count,
        seed,
        textures: crate::common::repo_root().join("assets/textures"),
        motion: vec!["sim:moderate".to_string(), "sim:fast".to_string()],
        resolution: [24, 18],
        ..DatasetConfig::default()
    }
}

/// Issue #23 item 6: a rerun with another configuration into an existing
/// `--out` kept the old items ("0 made, 8 already complete"). The directory
/// records the fingerprint of what determines its items; another one is
/// refused, naming both, and the same one resumes.
#[test]
fn a_rerun_with_another_configuration_is_refused() {
    let d = tempfile::tempdir().unwrap();
    let (a, b) = (tiny(4, 1), tiny(4, 2));
    dataset::run(&a, d.path(), Shard::ALL, false).unwrap();
    let before = tree(d.path());
    let old = dataset::Record::read(d.path()).unwrap();
    let new = dataset::Record::of(&b, &Sources::open(&b).unwrap()).unwrap();
    assert_ne!(old.fingerprint, new.fingerprint);
    let e = dataset::run(&b, d.path(), Shard::ALL, false)
        .unwrap_err()
        .to_string();
    for w in [old.short(), new.short(), "seed", "--out"] {
        assert!(e.contains(w), "'{w}' not in {e}");
    }
    assert_eq!(
        tree(d.path()),
        before,
        "a refused run changed the directory"
    );
    // Through the CLI: exit 1, no "already complete".
    let toml = d.path().join("b.toml");
    std::fs::write(&toml, b.to_toml().unwrap()).unwrap();
    let o = common::mmbm_cmd()
        .args(["dataset", "--quiet", "--config"])
        .arg(&toml)
        .arg("--out")
        .arg(d.path())
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("another configuration") && !err.contains("complete"),
        "{err}"
    );
    // The same configuration resumes; an item of another one is refused.
    assert_eq!(
        dataset::run(&a, d.path(), Shard::ALL, false).unwrap().made,
        0
    );
    let other = tempfile::tempdir().unwrap();
    dataset::run(&b, other.path(), Shard::ALL, false).unwrap();
    let item = d.path().join("items/00000001");
    std::fs::remove_dir_all(&item).unwrap();
    copy_dir(&other.path().join("items/00000001"), &item);
    let e = dataset::run(&a, d.path(), Shard::ALL, false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("00000001") && e.contains(new.short()), "{e}");
    // A directory of items without a record (older mmbm) is refused too.
    std::fs::remove_file(d.path().join("dataset.json")).unwrap();
    let e = dataset::run(&a, d.path(), Shard::ALL, false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("no dataset.json"), "{e}");
}

fn copy_dir(from: &Path, to: &Path) {
    std::fs::create_dir_all(to).unwrap();
    for e in std::fs::read_dir(from).unwrap() {
        let e = e.unwrap();
        std::fs::copy(e.path(), to.join(e.file_name())).unwrap();
    }
}

/// Issue #23 item 6: `--merge` joined part 1/2 of one configuration with
/// part 2/2 of another. Every line carries its fingerprint; merge refuses
/// lines of another configuration, items of another shard and a short set.
#[test]
fn parts_of_different_configurations_are_not_merged() {
    let (a, b) = (tiny(4, 1), tiny(4, 2));
    let (p, q) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    let (p, q) = (p.path(), q.path());
    let half = |k| Shard::new(k, 2).unwrap();
    dataset::run(&a, p, half(1), false).unwrap();
    dataset::run(&b, q, half(2), false).unwrap();
    // Into one directory: the second configuration is refused at once.
    assert!(dataset::run(&b, p, half(2), false).is_err());
    // Copied together: merge refuses, and writes no manifest.
    std::fs::copy(
        q.join("manifest.part-2-of-2.jsonl"),
        p.join("manifest.part-2-of-2.jsonl"),
    )
    .unwrap();
    for i in [1, 3] {
        copy_dir(
            &q.join(format!("items/0000000{i}")),
            &p.join(format!("items/0000000{i}")),
        );
    }
    let e = dataset::merge(p).unwrap_err().to_string();
    assert!(
        e.contains("another configuration") && e.contains("part-2-of-2"),
        "{e}"
    );
    assert!(!p.join("manifest.jsonl").exists());
    // A part listing an item of another shard, or too few items.
    let good1 = std::fs::read_to_string(p.join("manifest.part-1-of-2.jsonl")).unwrap();
    let first = good1.lines().next().unwrap();
    std::fs::write(p.join("manifest.part-2-of-2.jsonl"), format!("{first}\n")).unwrap();
    let e = dataset::merge(p).unwrap_err().to_string();
    assert!(e.contains("item 0 is not an item of shard 2/2"), "{e}");
    std::fs::write(p.join("manifest.part-2-of-2.jsonl"), "").unwrap();
    let e = dataset::merge(p).unwrap_err().to_string();
    assert!(
        e.contains("2 of 4 items") && e.contains("item 1 is missing"),
        "{e}"
    );
    // Made right, the parts merge and verify.
    for i in [1, 3] {
        std::fs::remove_dir_all(p.join(format!("items/0000000{i}"))).unwrap();
    }
    dataset::run(&a, p, half(2), false).unwrap();
    assert_eq!(dataset::merge(p).unwrap(), 4);
    assert_eq!(dataset::verify(p).unwrap(), 4);
}

/// Issue #23 item 6: `--verify` passed lines with `"files": {}` and hashed
/// whatever a line's `dir` named (`../../../../../etc`). The manifest is
/// input: each item's directory is named by its index, its files are
/// exactly the item files, non-empty regular files inside the directory.
#[test]
fn verify_trusts_nothing_the_manifest_says() {
    let d = tempfile::tempdir().unwrap();
    let out = d.path().join("data");
    dataset::run(&tiny(2, 1), &out, Shard::ALL, false).unwrap();
    let secret = d.path().join("secret.txt");
    std::fs::write(&secret, "not part of the dataset\n").unwrap();
    // The secret's true size and SHA-256: the manifest lines below list
    // them, so only confinement can tell those lines from good ones.
    let sum = || {
        let digest = <sha2::Sha256 as sha2::Digest>::digest(b"not part of the dataset\n");
        serde_json::json!({ "bytes": 24, "sha256": format!("{digest:x}") })
    };
    let manifest = out.join("manifest.jsonl");
    let good = std::fs::read_to_string(&manifest).unwrap();
    let lines: Vec<serde_json::Value> = good
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect();
    type Edit = Box<dyn Fn(&mut Vec<serde_json::Value>, &Path)>;
    let cases: Vec<(&str, Edit, &[&str])> = vec![
        (
            "no files",
            Box::new(|l, _| l[1]["files"] = serde_json::json!({})),
            &["line 2", "not listed"],
        ),
        (
            "a dir outside",
            Box::new(move |l, _| {
                l[0]["dir"] = "..".into();
                l[0]["files"] = serde_json::json!({ "secret.txt": sum() });
            }),
            &["line 1", "is not items/00000000"],
        ),
        (
            "a file name outside",
            Box::new(move |l, _| {
                l[0]["files"]["../../../secret.txt"] = sum();
            }),
            &["line 1", "is not a file of an item"],
        ),
        (
            "a symlink outside",
            Box::new(move |l, out| {
                let f = out.join("items/00000000/flow.exr");
                std::fs::remove_file(&f).unwrap();
                std::os::unix::fs::symlink(out.join("../secret.txt"), &f).unwrap();
                l[0]["files"]["flow.exr"] = sum();
            }),
            &["flow.exr", "leads outside the dataset directory"],
        ),
        (
            "an empty file listed as empty",
            Box::new(|l, out| {
                std::fs::write(out.join("items/00000001/sharp.png"), "").unwrap();
                l[1]["files"]["sharp.png"] = serde_json::json!({
                    "bytes": 0,
                    "sha256": "e3b0c44298fc1c149afbf4c8996fb92427ae41e4649b934ca495991b7852b855",
                });
            }),
            &["sharp.png", "is empty"],
        ),
        (
            "a line missing",
            Box::new(|l, _| drop(l.pop())),
            &["1 items listed", "has 2"],
        ),
        (
            "another configuration",
            Box::new(|l, _| l[0]["fingerprint"] = "0".repeat(64).into()),
            &["line 1", "another configuration"],
        ),
    ];
    let restore = || {
        std::fs::remove_dir_all(&out).unwrap();
        dataset::run(&tiny(2, 1), &out, Shard::ALL, false).unwrap();
    };
    for (name, edit, words) in &cases {
        let mut l = lines.clone();
        edit(&mut l, &out);
        let text: String = l.iter().map(|v| format!("{v}\n")).collect();
        std::fs::write(&manifest, text).unwrap();
        let e = dataset::verify(&out).unwrap_err().to_string();
        for w in *words {
            assert!(e.contains(w), "{name}: '{w}' not in {e}");
        }
        restore();
        assert_eq!(dataset::verify(&out).unwrap(), 2, "{name}: restored");
    }
    // A pipe in place of a file is refused unread (it would block a reader).
    let f = out.join("items/00000000/maps.exr");
    std::fs::remove_file(&f).unwrap();
    assert!(std::process::Command::new("mkfifo")
        .arg(&f)
        .status()
        .unwrap()
        .success());
    let o = common::mmbm_within(
        d.path(),
        &["dataset", "--verify", "--out", "data"],
        vec![],
        60,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("maps.exr: is not a regular file"), "{err}");
    // So is a pipe in place of dataset.json (for --verify, --merge and a run).
    let rec = out.join("dataset.json");
    std::fs::remove_file(&rec).unwrap();
    assert!(std::process::Command::new("mkfifo")
        .arg(&rec)
        .status()
        .unwrap()
        .success());
    for args in [
        &["--verify"][..],
        &["--merge"],
        &["--quiet", "--config", "ds.toml"],
    ] {
        std::fs::write(d.path().join("ds.toml"), tiny(2, 1).to_toml().unwrap()).unwrap();
        let mut argv = vec!["dataset", "--out", "data"];
        argv.extend(args);
        let o = common::mmbm_within(d.path(), &argv, vec![], 60);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains("dataset.json") && err.contains("a pipe"),
            "{args:?}: {err}"
        );
    }
}

/// Issue #23 item 6: `--merge` with a part named `...-of-1000000000000`
/// allocated 3.5 GB, and `--shard 1/18446744073709551615` was accepted.
/// Shard counts are capped (MAX_SHARDS, and no more shards than items)
/// before anything is sized by them.
#[test]
fn shard_counts_are_capped() {
    let e = Shard::parse("1/18446744073709551615")
        .unwrap_err()
        .to_string();
    assert!(e.contains(&format!("1..={}", dataset::MAX_SHARDS)), "{e}");
    assert!(Shard::new(dataset::MAX_SHARDS, dataset::MAX_SHARDS).is_ok());
    assert!(Shard::new(1, dataset::MAX_SHARDS + 1).is_err());
    let d = tempfile::tempdir().unwrap();
    let e = dataset::run(&tiny(3, 1), d.path(), Shard::new(1, 4).unwrap(), false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("4 shards for 3 items"), "{e}");
    let o = mmbm_in(
        d.path(),
        &["dataset", "--out", "x", "--shard", "1/18446744073709551615"],
    );
    assert_eq!(o.status.code(), Some(1));
    dataset::run(&tiny(3, 1), d.path(), Shard::new(1, 3).unwrap(), false).unwrap();
    for (name, words) in [
        ("manifest.part-1-of-1000000000000.jsonl", "1..=1000000"),
        ("manifest.part-1-of-4.jsonl", "4 shards for 3 items"),
        ("manifest.part-7-of-3.jsonl", "1..=3"),
        ("manifest.part-x-of-3.jsonl", "not a shard manifest name"),
    ] {
        std::fs::write(d.path().join(name), "").unwrap();
        let t = std::time::Instant::now();
        let e = dataset::merge(d.path()).unwrap_err().to_string();
        assert!(e.contains(name) && e.contains(words), "{name}: {e}");
        assert!(t.elapsed().as_secs() < 5, "{name}: {:?}", t.elapsed());
        std::fs::remove_file(d.path().join(name)).unwrap();
    }
    let e = dataset::merge(d.path()).unwrap_err().to_string();
    assert!(
        e.contains("2 shard(s) not finished") && e.contains("2/3, 3/3"),
        "{e}"
    );
}

/// Issue #23 item 6: two runs of one shard at once: the second died with
/// "partial does not exist". A run holds a lock on its shard (and its
/// shard count), refused to a second run; kill -9 releases it.
#[cfg(unix)]
#[test]
fn a_second_run_of_a_shard_is_refused_and_kill_9_frees_it() {
    let d = tempfile::tempdir().unwrap();
    let cfg = tiny(200, 1);
    let toml = d.path().join("ds.toml");
    std::fs::write(&toml, cfg.to_toml().unwrap()).unwrap();
    let out = d.path().join("out");
    let start = || {
        common::mmbm_cmd()
            .args(["dataset", "--quiet", "--config"])
            .arg(&toml)
            .arg("--out")
            .arg(&out)
            .stdout(std::process::Stdio::null())
            .stderr(std::process::Stdio::null())
            .spawn()
            .unwrap()
    };
    let mut first = start();
    let items = out.join("items");
    let busy = (0..3000).any(|_| {
        std::thread::sleep(std::time::Duration::from_millis(10));
        std::fs::read_dir(&items).is_ok_and(|r| r.count() >= 1)
    });
    assert!(busy, "the first run made no item");
    let o = common::mmbm_cmd()
        .args(["dataset", "--quiet", "--config"])
        .arg(&toml)
        .arg("--out")
        .arg(&out)
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("another run is writing") && err.contains("shard 1/1"),
        "{err}"
    );
    // Another split of the same items is refused as well.
    let e = dataset::run(&cfg, &out, Shard::new(2, 2).unwrap(), false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("another run is writing"), "{e}");
    assert_eq!(first.try_wait().unwrap(), None, "the first run ended early");
    first.kill().unwrap(); // SIGKILL
    first.wait().unwrap();
    // Nothing stays locked: both locks can be taken at once.
    let lock = dataset::RunLock::take(&out, Shard::ALL).unwrap();
    drop(lock);
    assert!(dataset::RunLock::take(&out, Shard::new(2, 2).unwrap()).is_ok());
}
