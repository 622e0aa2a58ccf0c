//! Issue #37: `mmbm dataset` works outside the repository (built-in default
//! textures, relative paths resolved against the configuration file's
//! folder, errors naming the key, `--count`), its items' JSON loads anywhere
//! (no number beyond int64), and the sharp frame follows the GoPro / REDS
//! convention by default (`sharp = "mid"`), recorded per item and in the
//! fingerprint.

use crate::common;

use common::{mmbm_in, tree};
use mmbm::render::SharpAt;
use mmbm_lab::dataset::{self, DatasetConfig, Record, Shard, Sources};
use serde_json::Value;
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn repo_textures() -> PathBuf {
    crate::common::repo_root().join("assets/textures")
}

fn json(p: &Path) -> Value {
    serde_json::from_str(&std::fs::read_to_string(p).unwrap()).unwrap()
}

/// Every file of `dir` but the lock files.
fn files(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    tree(dir)
        .into_iter()
        .filter(|(k, _)| !k.starts_with(".lock"))
        .collect()
}

/// A gyro CSV of a constant rotation `w` (rad/s) for 1 s at 200 Hz.
fn steady_csv(path: &Path, w: [f64; 3]) {
    let mut s = String::from("t,wx,wy,wz\n");
    for k in 0..=200 {
        s += &format!("{},{},{},{}\n", k as f64 / 200.0, w[0], w[1], w[2]);
    }
    std::fs::write(path, s).unwrap();
}

/// Every number in `v` (recursively) is an integer within int64 or a float.
fn numbers_fit_int64(v: &Value, at: &str) {
    match v {
        Value::Number(n) => assert!(
            n.is_i64() || n.is_f64(),
            "{at}: {n} does not fit int64 (Arrow, pandas, a C long)"
        ),
        Value::Array(a) => a
            .iter()
            .enumerate()
            .for_each(|(i, x)| numbers_fit_int64(x, &format!("{at}[{i}]"))),
        Value::Object(m) => m
            .iter()
            .for_each(|(k, x)| numbers_fit_int64(x, &format!("{at}.{k}"))),
        _ => {}
    }
}

/// With no configuration, from an empty directory far from the repository,
/// the defaults make items (the textures are built in); each item's JSON
/// records `sharp = "mid"`, and its seed as a decimal string.
#[test]
fn defaults_work_from_an_empty_directory() {
    let d = tempfile::tempdir().unwrap();
    let o = mmbm_in(
        d.path(),
        &["dataset", "--quiet", "--out", "data", "--count", "1"],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let item = d.path().join("data/items/00000000");
    for f in dataset::item::FILES {
        assert!(item.join(f).is_file(), "{f} missing");
    }
    let line = json(&item.join("item.json"));
    assert_eq!(line["params"]["sharp"], "mid");
    assert_eq!(line["params"]["resolution"], serde_json::json!([640, 480]));
    let seed = line["params"]["seed"].as_str().expect("seed as a string");
    assert_eq!(
        seed.parse::<u64>().unwrap(),
        dataset::item::item_seed(1, 0),
        "the default seed is 1"
    );
    numbers_fit_int64(&line, "item.json");
    assert_eq!(json(&d.path().join("data/dataset.json"))["count"], 1);
}

/// The built-in textures are the files of `assets/textures/`: a run with
/// the default `textures` equals one with that folder byte for byte (every
/// item file, the manifest, the fingerprint), over items that draw several
/// of the textures. This is what the default run inside the repository
/// gave, with that folder as `textures`.
#[test]
fn builtin_textures_give_the_bytes_of_the_folder() {
    let base = DatasetConfig {
        count: 12,
        resolution: [40, 30],
        ..DatasetConfig::default()
    };
    assert_eq!(base.textures, PathBuf::from("builtin:"));
    let folder = DatasetConfig {
        textures: repo_textures(),
        ..base.clone()
    };
    let (a, b) = (tempfile::tempdir().unwrap(), tempfile::tempdir().unwrap());
    dataset::run(&base, a.path(), Shard::ALL, false).unwrap();
    dataset::run(&folder, b.path(), Shard::ALL, false).unwrap();
    let (ta, tb) = (files(a.path()), files(b.path()));
    assert_eq!(ta.keys().collect::<Vec<_>>(), tb.keys().collect::<Vec<_>>());
    for (k, v) in &ta {
        assert!(
            v == &tb[k],
            "{k} differs between built-in and folder textures"
        );
    }
    let used: std::collections::BTreeSet<String> =
        std::fs::read_to_string(a.path().join("manifest.jsonl"))
            .unwrap()
            .lines()
            .map(|l| serde_json::from_str::<Value>(l).unwrap()["params"]["texture"].to_string())
            .collect();
    assert!(used.len() >= 3, "only {used:?} drawn");
    // The names are the folder's.
    let names: Vec<String> = std::fs::read_dir(repo_textures())
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !n.ends_with(".md"))
        .collect();
    let mut names = names;
    names.sort();
    assert_eq!(Sources::open(&base).unwrap().textures, names);
}

/// Relative `textures` and `log:` paths are relative to the configuration
/// file's folder, not to the working directory; items record the motion as
/// written.
#[test]
fn relative_paths_resolve_against_the_configuration_file() {
    let d = tempfile::tempdir().unwrap();
    let conf = d.path().join("conf");
    std::fs::create_dir_all(conf.join("tex")).unwrap();
    std::fs::copy(
        repo_textures().join("brick.png"),
        conf.join("tex/brick.png"),
    )
    .unwrap();
    steady_csv(&conf.join("gyro.csv"), [0.0, 0.5, 0.0]);
    std::fs::write(
        conf.join("ds.toml"),
        "count = 2\ntextures = \"tex\"\nmotion = [\"log:gyro.csv\"]\nresolution = [32, 24]\n",
    )
    .unwrap();
    let elsewhere = d.path().join("elsewhere");
    std::fs::create_dir(&elsewhere).unwrap();
    let o = mmbm_in(
        &elsewhere,
        &[
            "dataset",
            "--quiet",
            "--config",
            "../conf/ds.toml",
            "--out",
            "data",
        ],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(0), "{err}");
    let line = json(&elsewhere.join("data/items/00000001/item.json"));
    assert_eq!(line["params"]["motion"], "log:gyro.csv");
    assert_eq!(line["params"]["texture"], "brick.png");
}

/// A path that is not there is an error naming the key, its value as
/// written, the configuration file and the resolved path; nothing is
/// written.
#[test]
fn errors_name_the_key_and_the_file() {
    let d = tempfile::tempdir().unwrap();
    let cases = [
        (
            "textures = \"no-such-folder\"\ncount = 1\n",
            vec![
                "textures = \"no-such-folder\"",
                "(key 'textures' in ",
                "ds.toml)",
                "conf/no-such-folder",
            ],
        ),
        (
            "motion = [\"log:no-such.csv\"]\ncount = 1\n",
            vec![
                "motion = \"log:no-such.csv\"",
                "(key 'motion' in ",
                "conf/no-such.csv",
            ],
        ),
        (
            "sharp = \"middle\"\n",
            vec!["ds.toml", "sharp", "middle", "mid"],
        ),
    ];
    let conf = d.path().join("conf");
    std::fs::create_dir(&conf).unwrap();
    for (toml, words) in cases {
        std::fs::write(conf.join("ds.toml"), toml).unwrap();
        let o = mmbm_in(
            d.path(),
            &[
                "dataset",
                "--quiet",
                "--config",
                "conf/ds.toml",
                "--out",
                "out",
            ],
        );
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{toml}: {err}");
        // A path's error is one line (a TOML parser's shows the line).
        if !toml.starts_with("sharp") {
            assert_eq!(err.trim().lines().count(), 1, "{toml}: {err}");
        }
        for w in words {
            assert!(err.contains(w), "{toml}: '{w}' not in {err}");
        }
        assert!(!d.path().join("out/items").exists(), "{toml}: items made");
    }
}

/// `--count N` overrides the configuration's count (and is checked).
#[test]
fn count_flag_overrides_the_configuration() {
    let d = tempfile::tempdir().unwrap();
    std::fs::write(
        d.path().join("ds.toml"),
        "count = 50\nresolution = [16, 12]\nmotion = [\"sim:fast\"]\n",
    )
    .unwrap();
    let run = |extra: &[&str]| {
        let mut a = vec!["dataset", "--quiet", "--config", "ds.toml", "--out", "data"];
        a.extend(extra);
        mmbm_in(d.path(), &a)
    };
    let o = run(&["--count", "3"]);
    assert_eq!(
        o.status.code(),
        Some(0),
        "{}",
        String::from_utf8_lossy(&o.stderr)
    );
    let manifest = std::fs::read_to_string(d.path().join("data/manifest.jsonl")).unwrap();
    assert_eq!(manifest.lines().count(), 3);
    assert_eq!(json(&d.path().join("data/dataset.json"))["count"], 3);
    for (n, word) in [("0", "--count"), ("100000001", "--count")] {
        let o = run(&["--count", n]);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{n}: {err}");
        assert!(err.contains(word) && err.contains(n), "{n}: {err}");
    }
    let o = mmbm_in(
        d.path(),
        &["dataset", "--verify", "--out", "data", "--count", "3"],
    );
    assert_ne!(o.status.code(), Some(0));
}

/// The convention is in each item's JSON and in the fingerprint: three
/// values, three datasets. `start` (what every dataset before the key was)
/// leaves the key out of the fingerprint's inputs, so those directories
/// keep theirs.
#[test]
fn sharp_is_recorded_per_item_and_in_the_fingerprint() {
    let mut prints = Vec::new();
    for at in [SharpAt::Start, SharpAt::Mid, SharpAt::End] {
        let cfg = DatasetConfig {
            count: 2,
            resolution: [16, 12],
            sharp: at,
            ..DatasetConfig::default()
        };
        let d = tempfile::tempdir().unwrap();
        dataset::run(&cfg, d.path(), Shard::ALL, false).unwrap();
        let line = json(&d.path().join("items/00000001/item.json"));
        assert_eq!(line["params"]["sharp"], at.name());
        let rec = Record::read(d.path()).unwrap();
        let recorded = rec.inputs.get("sharp");
        match at {
            SharpAt::Start => assert_eq!(recorded, None),
            _ => assert_eq!(recorded, Some(&Value::from(at.name()))),
        }
        // Round trip through TOML keeps it.
        let again = DatasetConfig::from_toml(&cfg.to_toml().unwrap(), "t").unwrap();
        assert_eq!(again.sharp, at);
        prints.push(rec.fingerprint);
    }
    prints.sort();
    prints.dedup();
    assert_eq!(prints.len(), 3);
}

/// Centroid (x, px) of the R channel of an EXR.
fn centroid_x(p: &Path) -> f64 {
    let (w, _h, ch) = mmbm::io::images::read_exr(p).unwrap();
    let r = &ch.iter().find(|(n, _)| n == "R").unwrap().1;
    let (mut m, mut mx) = (0.0, 0.0);
    for (i, &v) in r.iter().enumerate() {
        let x = (i % w) as f64 + 0.5;
        m += v as f64;
        mx += v as f64 * x;
    }
    mx / m
}

/// A dot on black under a steady pan (a constant rotation about y, from a
/// log): the blurred dot's centroid is the image of the dot at mid-exposure.
/// The sharp frame's dot sits there for `mid`, half a streak behind it for
/// `start` and half a streak ahead for `end`. The streak's length is the
/// closed form `f_px * tan(w T)` (the dot at the image centre).
#[test]
fn sharp_frame_offsets_follow_the_convention() {
    let d = tempfile::tempdir().unwrap();
    let tex = d.path().join("tex");
    std::fs::create_dir(&tex).unwrap();
    // 128 x 96 texels over twice a 64 x 48 view: one texel per pixel, the
    // view inside the texture all along; a 4 x 4 white dot at the centre.
    let mut img = image::RgbImage::new(128, 96);
    for y in 46..50 {
        for x in 62..66 {
            img.put_pixel(x, y, image::Rgb([255, 255, 255]));
        }
    }
    img.save(tex.join("dot.png")).unwrap();
    let (f_px, t_s, blur_px) = (4.2548 / 0.00465, 0.04, 16.0);
    let w = blur_px / (f_px * t_s);
    steady_csv(&d.path().join("pan.csv"), [0.0, w, 0.0]);
    let streak = f_px * (w * t_s).tan();
    let mut offsets = Vec::new();
    for at in [SharpAt::Start, SharpAt::Mid, SharpAt::End] {
        let cfg = DatasetConfig {
            count: 1,
            textures: tex.clone(),
            motion: vec![format!("log:{}", d.path().join("pan.csv").display())],
            exposure_s: [t_s, t_s],
            distance_m: [2.0, 2.0],
            tilt_deg: [0.0, 0.0],
            resolution: [64, 48],
            fill: 2.0,
            sharp: at,
            ..DatasetConfig::default()
        };
        let out = d.path().join(at.name());
        dataset::run(&cfg, &out, Shard::ALL, false).unwrap();
        let item = out.join("items/00000000");
        let off = centroid_x(&item.join("blurred.exr")) - centroid_x(&item.join("sharp.exr"));
        offsets.push(off);
    }
    let [start, mid, end] = [offsets[0], offsets[1], offsets[2]];
    assert!(mid.abs() < 0.1, "mid: offset {mid} px (want 0)");
    assert!(
        (start.abs() - streak / 2.0).abs() < 0.05 * streak,
        "start: offset {start} px (want +-{} px)",
        streak / 2.0
    );
    assert!(
        (start + end).abs() < 0.1,
        "start {start} and end {end} px not opposite"
    );
}

/// Items of earlier versions (the seed a JSON number, no `sharp` key: they
/// were all `start`) still read: a `sharp = "start"` directory rewritten in
/// that form verifies, and a rerun resumes it (its fingerprint unchanged),
/// making nothing.
#[test]
fn earlier_items_with_numeric_seeds_still_verify_and_resume() {
    let cfg = DatasetConfig {
        count: 3,
        resolution: [16, 12],
        sharp: SharpAt::Start,
        ..DatasetConfig::default()
    };
    let d = tempfile::tempdir().unwrap();
    dataset::run(&cfg, d.path(), Shard::ALL, false).unwrap();
    let manifest = d.path().join("manifest.jsonl");
    let mut old = String::new();
    for line in std::fs::read_to_string(&manifest).unwrap().lines() {
        let mut v: Value = serde_json::from_str(line).unwrap();
        let p = v["params"].as_object_mut().unwrap();
        let seed: u64 = p["seed"].as_str().unwrap().parse().unwrap();
        p.insert("seed".into(), Value::from(seed));
        assert_eq!(p.remove("sharp"), Some(Value::from("start")));
        let text = serde_json::to_string(&v).unwrap();
        assert!(text.contains(&format!("\"seed\":{seed},")));
        let dir = d.path().join(v["dir"].as_str().unwrap());
        std::fs::write(dir.join("item.json"), format!("{text}\n")).unwrap();
        old += &format!("{text}\n");
    }
    std::fs::write(&manifest, &old).unwrap();
    assert_eq!(dataset::verify(d.path()).unwrap(), 3);
    let s = dataset::run(&cfg, d.path(), Shard::ALL, false).unwrap();
    assert_eq!((s.items, s.made), (3, 0));
}
