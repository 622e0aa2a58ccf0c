//! `mmbm dataset --format webdataset`: tar shards read back by a tar reader
//! written here from the ustar layout (not the crate that wrote them), one
//! sample per item with the item's files under its key, the same bytes
//! from a sharded run packed at `--merge` as from a single run, a rerun
//! keeping complete shards, and a changed file or shard refused.

use crate::common;

use common::mmbm_in;
use mmbm_lab::dataset::item::FILES;
use mmbm_lab::dataset::{self, DatasetConfig, Shard};
use std::collections::BTreeMap;
use std::path::Path;

fn small(count: u64) -> DatasetConfig {
    DatasetConfig {
        count,
        textures: crate::common::repo_root().join("assets/textures"),
        motion: vec!["sim:moderate".to_string(), "sim:fast".to_string()],
        resolution: [40, 30],
        ..DatasetConfig::default()
    }
}

/// The members of a ustar archive, in order: (name, bytes). Checks each
/// header's checksum and the two closing zero blocks.
fn read_tar(bytes: &[u8]) -> Vec<(String, Vec<u8>)> {
    let mut out = Vec::new();
    let mut at = 0usize;
    loop {
        let h = &bytes[at..at + 512];
        if h.iter().all(|&b| b == 0) {
            assert!(
                bytes[at..].len() >= 1024 && bytes[at..at + 1024].iter().all(|&b| b == 0),
                "the archive ends with two zero blocks"
            );
            assert_eq!(bytes.len(), at + 1024, "nothing after the closing blocks");
            return out;
        }
        let field = |a: usize, b: usize| {
            let f = &h[a..b];
            let end = f.iter().position(|&c| c == 0).unwrap_or(f.len());
            String::from_utf8(f[..end].to_vec()).unwrap()
        };
        let octal = |a: usize, b: usize| u64::from_str_radix(field(a, b).trim(), 8).unwrap();
        let sum: u64 = h
            .iter()
            .enumerate()
            .map(|(i, &c)| {
                if (148..156).contains(&i) {
                    32
                } else {
                    c as u64
                }
            })
            .sum();
        assert_eq!(octal(148, 156), sum, "header checksum of {}", field(0, 100));
        assert_eq!(&h[257..262], b"ustar");
        assert_eq!(h[156], b'0', "regular file");
        assert_eq!(octal(136, 148), 0, "mtime 0");
        assert_eq!(octal(108, 116), 0, "uid 0");
        let size = octal(124, 136) as usize;
        let data = bytes[at + 512..at + 512 + size].to_vec();
        out.push((field(0, 100), data));
        at += 512 + size.div_ceil(512) * 512;
    }
}

/// Every shard file of `dir/webdataset`, by name.
fn shards(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    let mut m = BTreeMap::new();
    for e in std::fs::read_dir(dir.join("webdataset")).unwrap() {
        let p = e.unwrap().path();
        let name = p.file_name().unwrap().to_str().unwrap().to_string();
        if name.ends_with(".tar") {
            m.insert(name, std::fs::read(&p).unwrap());
        }
    }
    m
}

#[test]
fn shards_hold_each_item_under_its_key_and_equal_a_sharded_run() {
    let cfg = small(7);
    let whole = tempfile::tempdir().unwrap();
    dataset::run(&cfg, whole.path(), Shard::ALL, false).unwrap();
    // Small shards, so that the set takes several.
    let item_bytes: u64 = FILES
        .iter()
        .map(|f| {
            std::fs::metadata(whole.path().join("items/00000000").join(f))
                .unwrap()
                .len()
        })
        .sum();
    let shard_bytes = (3 * item_bytes).max(dataset::MIN_SHARD_BYTES);
    let p = dataset::pack(whole.path(), shard_bytes, false).unwrap();
    assert_eq!((p.items, p.written), (7, p.shards));
    assert!(
        p.shards >= 2,
        "{} shards of at most {shard_bytes} bytes",
        p.shards
    );
    let a = shards(whole.path());
    assert_eq!(a.len(), p.shards);

    // Each sample: KEY.json then the files, equal to the item's files.
    let mut next = 0u64;
    for (name, bytes) in &a {
        assert!(
            bytes.len() as u64 <= shard_bytes || bytes.len() as u64 <= item_bytes * 2,
            "{name}"
        );
        let members = read_tar(bytes);
        assert_eq!(members.len() % (FILES.len() + 1), 0);
        for sample in members.chunks(FILES.len() + 1) {
            let key = format!("{next:08}");
            let dir = whole.path().join("items").join(&key);
            assert_eq!(sample[0].0, format!("{key}.json"));
            assert_eq!(sample[0].1, std::fs::read(dir.join("item.json")).unwrap());
            for (m, f) in sample[1..].iter().zip(FILES) {
                assert_eq!(m.0, format!("{key}.{f}"));
                assert!(m.1 == std::fs::read(dir.join(f)).unwrap(), "{key}.{f}");
            }
            next += 1;
        }
    }
    assert_eq!(next, 7, "every item in exactly one shard, in order");
    assert_eq!(dataset::verify_tars(whole.path()).unwrap(), Some(p.shards));

    // Two machine shards, packed at merge: the same tar bytes.
    let parts = tempfile::tempdir().unwrap();
    for k in 1..=2 {
        dataset::run(&cfg, parts.path(), Shard::new(k, 2).unwrap(), false).unwrap();
    }
    dataset::merge(parts.path()).unwrap();
    dataset::pack(parts.path(), shard_bytes, false).unwrap();
    let b = shards(parts.path());
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (k, v) in &a {
        assert!(
            v == &b[k],
            "{k} differs between the sharded and the single run"
        );
    }
    assert_eq!(
        std::fs::read(whole.path().join("webdataset/index.json")).unwrap(),
        std::fs::read(parts.path().join("webdataset/index.json")).unwrap()
    );

    // A rerun keeps every shard; a removed one is rewritten to the same bytes.
    let again = dataset::pack(whole.path(), shard_bytes, false).unwrap();
    assert_eq!(again.written, 0);
    let first = whole.path().join("webdataset/mmbm-000001.tar");
    std::fs::remove_file(&first).unwrap();
    let again = dataset::pack(whole.path(), shard_bytes, false).unwrap();
    assert_eq!(again.written, 1);
    assert_eq!(shards(whole.path()), a);

    // A changed shard fails --verify, naming it.
    let mut t = std::fs::read(&first).unwrap();
    let mid = t.len() / 2;
    t[mid] ^= 1;
    std::fs::write(&first, &t).unwrap();
    let e = dataset::verify_tars(whole.path()).unwrap_err().to_string();
    assert!(e.contains("mmbm-000001.tar"), "{e}");
    // ... and packing rewrites it.
    assert_eq!(
        dataset::pack(whole.path(), shard_bytes, false)
            .unwrap()
            .written,
        1
    );
    assert_eq!(shards(whole.path()), a);
}

#[test]
fn a_changed_item_file_is_refused_and_nothing_is_packed() {
    let cfg = small(2);
    let d = tempfile::tempdir().unwrap();
    dataset::run(&cfg, d.path(), Shard::ALL, false).unwrap();
    let f = d.path().join("items/00000001/maps.exr");
    let mut b = std::fs::read(&f).unwrap();
    let last = b.len() - 1;
    b[last] ^= 0xff;
    std::fs::write(&f, &b).unwrap();
    let e = dataset::pack(d.path(), dataset::DEFAULT_SHARD_BYTES, false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("00000001") && e.contains("maps.exr"), "{e}");
    assert!(
        !d.path().join("webdataset").exists() || shards(d.path()).is_empty(),
        "no tar written"
    );
    let e = dataset::pack(d.path(), 100, false).unwrap_err().to_string();
    assert!(e.contains("--shard-bytes"), "{e}");
}

#[test]
fn the_command_packs_and_a_sharded_run_packs_at_merge() {
    let cfg = tempfile::tempdir().unwrap();
    let toml = cfg.path().join("ds.toml");
    let text = small(3).to_toml().unwrap();
    std::fs::write(&toml, text).unwrap();
    let out = cfg.path().join("data");
    let o = mmbm_in(
        cfg.path(),
        &[
            "dataset",
            "--config",
            toml.to_str().unwrap(),
            "--out",
            out.to_str().unwrap(),
            "--format",
            "webdataset",
            "--quiet",
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("packed 3 items into 1 WebDataset shard(s)"),
        "{err}"
    );
    assert_eq!(shards(&out).len(), 1);
    let o = mmbm_in(
        cfg.path(),
        &["dataset", "--verify", "--out", out.to_str().unwrap()],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.success() && err.contains("1 WebDataset shard(s)"),
        "{err}"
    );

    let parts = cfg.path().join("parts");
    for k in ["1/2", "2/2"] {
        let o = mmbm_in(
            cfg.path(),
            &[
                "dataset",
                "--config",
                toml.to_str().unwrap(),
                "--out",
                parts.to_str().unwrap(),
                "--shard",
                k,
                "--format",
                "webdataset",
                "--quiet",
            ],
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert!(
            o.status.success() && err.contains("--merge --format webdataset"),
            "{err}"
        );
    }
    assert!(
        !parts.join("webdataset").exists(),
        "a shard run packs nothing"
    );
    let o = mmbm_in(
        cfg.path(),
        &[
            "dataset",
            "--merge",
            "--format",
            "webdataset",
            "--out",
            parts.to_str().unwrap(),
            "--quiet",
        ],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert_eq!(shards(&parts), shards(&out));
}
