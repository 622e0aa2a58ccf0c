//! `mmbm dataset`: shards equal one run byte for byte, a killed run resumes
//! to the same bytes, manifest parameters re-render the same item, and bad
//! inputs are clear errors that leave nothing half-written.

use crate::common;

use common::tree;

use common::mmbm_in;
use mmbm_lab::dataset::item::{make, FILES};
use mmbm_lab::dataset::{self, DatasetConfig, ManifestLine, Shard, Sources};
use std::collections::BTreeMap;
use std::path::{Path, PathBuf};

fn textures() -> PathBuf {
    crate::common::repo_root().join("assets/textures")
}

fn small(count: u64) -> DatasetConfig {
    let mut motion = vec!["sim:moderate".to_string(), "sim:fast".to_string()];
    if let Some(p) = common::shared_log("running_phone") {
        motion.push(format!("log:{}", p.display()));
    }
    DatasetConfig {
        count,
        textures: textures(),
        motion,
        resolution: [48, 36],
        ..DatasetConfig::default()
    }
}

fn items_and_manifest(dir: &Path) -> BTreeMap<String, Vec<u8>> {
    tree(dir)
        .into_iter()
        .filter(|(k, _)| k.starts_with("items/") || k == "manifest.jsonl")
        .collect()
}

#[test]
fn four_shards_equal_one_run_byte_for_byte() {
    let cfg = small(24);
    let whole = tempfile::tempdir().unwrap();
    let s = dataset::run(&cfg, whole.path(), Shard::ALL, false).unwrap();
    assert_eq!((s.items, s.made), (24, 24));
    assert_eq!(dataset::verify(whole.path()).unwrap(), 24);

    let parts = tempfile::tempdir().unwrap();
    for k in 1..=4 {
        let s = dataset::run(&cfg, parts.path(), Shard::new(k, 4).unwrap(), false).unwrap();
        assert_eq!(s.items, 6);
        assert!(parts
            .path()
            .join(format!("manifest.part-{k}-of-4.jsonl"))
            .exists());
    }
    assert_eq!(dataset::merge(parts.path()).unwrap(), 24);
    let (a, b) = (
        items_and_manifest(whole.path()),
        items_and_manifest(parts.path()),
    );
    assert_eq!(a.len(), 24 * (FILES.len() + 1) + 1);
    assert_eq!(a.keys().collect::<Vec<_>>(), b.keys().collect::<Vec<_>>());
    for (k, v) in &a {
        assert!(
            v == &b[k],
            "{k} differs between the sharded and the whole run"
        );
    }
    // A rerun makes nothing and changes nothing.
    let s = dataset::run(&cfg, whole.path(), Shard::ALL, false).unwrap();
    assert_eq!(s.made, 0);
    assert_eq!(items_and_manifest(whole.path()), a);
}

#[test]
fn manifest_parameters_rerender_the_same_item() {
    let cfg = small(3);
    let d = tempfile::tempdir().unwrap();
    dataset::run(&cfg, d.path(), Shard::ALL, false).unwrap();
    let src = Sources::open(&cfg).unwrap();
    let text = std::fs::read_to_string(d.path().join("manifest.jsonl")).unwrap();
    for line in text.lines() {
        let l: ManifestLine = serde_json::from_str(line).unwrap();
        let again = tempfile::tempdir().unwrap();
        let m = make(&l.params, &src, again.path()).unwrap();
        assert_eq!(m, l.measures);
        for f in FILES {
            let x = std::fs::read(again.path().join(f)).unwrap();
            let y = std::fs::read(d.path().join(&l.dir).join(f)).unwrap();
            assert!(x == y, "item {} {f} differs when re-rendered", l.index);
        }
    }
}

#[test]
fn a_killed_run_resumes_to_the_same_bytes() {
    let cfg = small(10);
    let d = tempfile::tempdir().unwrap();
    let toml = d.path().join("ds.toml");
    std::fs::write(&toml, cfg.to_toml().unwrap()).unwrap();
    let out = d.path().join("out");
    let start = || {
        common::mmbm_cmd()
            .args(["dataset", "--quiet", "--config"])
            .arg(&toml)
            .arg("--out")
            .arg(&out)
            .spawn()
            .unwrap()
    };
    let mut child = start();
    // Kill it once a few items are done, most likely in the middle of one.
    let items = out.join("items");
    for _ in 0..600 {
        std::thread::sleep(std::time::Duration::from_millis(20));
        let n = std::fs::read_dir(&items).map(|r| r.count()).unwrap_or(0);
        if n >= 3 {
            break;
        }
    }
    child.kill().unwrap();
    child.wait().unwrap();
    let done = std::fs::read_dir(&items).map(|r| r.count()).unwrap_or(0);
    assert!(done < 10, "the run finished before it could be killed");
    // No half item under a final name.
    for e in std::fs::read_dir(&items).unwrap() {
        assert!(e.unwrap().path().join("item.json").exists());
    }
    let st = start().wait().unwrap();
    assert!(st.success());
    let whole = tempfile::tempdir().unwrap();
    dataset::run(&cfg, whole.path(), Shard::ALL, false).unwrap();
    let a = items_and_manifest(whole.path());
    let b = items_and_manifest(&out);
    assert_eq!(a, b, "resumed run differs from an uninterrupted one");
    assert!(!tree(&out).keys().any(|k| k.contains(".partial")));
}

#[test]
fn bad_inputs_are_clear_errors() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    std::fs::create_dir(p.join("empty")).unwrap();
    std::fs::create_dir(p.join("broken")).unwrap();
    std::fs::write(p.join("broken/a.png"), "not a png").unwrap();
    std::fs::write(p.join("short.csv"), "t,wx,wy,wz\n0,0,0,0\n0.001,0,0,0\n").unwrap();
    let tex = textures();
    let cases: Vec<(String, &str, Vec<&str>)> = vec![
        (
            "textures = \"empty\"\ncount = 1\n".into(),
            "",
            vec!["empty", "no texture images"],
        ),
        (
            "textures = \"broken\"\ncount = 1\n".into(),
            "",
            vec!["a.png", "not a readable image"],
        ),
        (
            format!(
                "textures = \"{}\"\nmotion = [\"log:short.csv\"]\ncount = 1\n",
                tex.display()
            ),
            "",
            vec!["short.csv", "shorter than the longest exposure"],
        ),
        (
            format!("textures = \"{}\"\ncount = 4\n", tex.display()),
            "5/4",
            vec!["5/4", "1..=4"],
        ),
        ("count = 0\n".into(), "", vec!["count"]),
        ("motion = [\"walk\"]\n".into(), "", vec!["motion", "walk"]),
        ("colour = 1\n".into(), "", vec!["ds.toml", "colour"]),
    ];
    for (toml, shard, words) in cases {
        std::fs::write(p.join("ds.toml"), &toml).unwrap();
        let mut args = vec!["dataset", "--quiet", "--config", "ds.toml", "--out", "out"];
        if !shard.is_empty() {
            args.extend(["--shard", shard]);
        }
        let o = mmbm_in(p, &args);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{toml}: {err}");
        for w in words {
            assert!(err.contains(w), "{toml}: '{w}' not in {err}");
        }
        let items = p.join("out/items");
        let n = std::fs::read_dir(&items).map(|r| r.count()).unwrap_or(0);
        assert_eq!(n, 0, "{toml}: items written");
    }
    // Merge with a missing part, verify of a damaged file.
    let cfg = small(4);
    let out = p.join("parts");
    dataset::run(&cfg, &out, Shard::new(1, 2).unwrap(), false).unwrap();
    let e = dataset::merge(&out).unwrap_err().to_string();
    assert!(e.contains("2/2"), "{e}");
    dataset::run(&cfg, &out, Shard::new(2, 2).unwrap(), false).unwrap();
    dataset::merge(&out).unwrap();
    std::fs::write(out.join("items/00000003/flow.exr"), "x").unwrap();
    let e = dataset::verify(&out).unwrap_err().to_string();
    assert!(e.contains("00000003") && e.contains("flow.exr"), "{e}");
}

#[test]
fn scheduler_environments_pick_the_shard() {
    let d = tempfile::tempdir().unwrap();
    let toml = d.path().join("ds.toml");
    let cfg = DatasetConfig {
        count: 3,
        ..small(3)
    };
    std::fs::write(&toml, cfg.to_toml().unwrap()).unwrap();
    let run = |env: &[(&str, &str)], extra: &[&str]| {
        let mut c = common::mmbm_cmd();
        c.args(["dataset", "--quiet", "--config"])
            .arg(&toml)
            .arg("--out")
            .arg(d.path().join("out"))
            .args(extra)
            .env_remove("SLURM_ARRAY_TASK_ID")
            .env_remove("JOB_COMPLETION_INDEX");
        for (k, v) in env {
            c.env(k, v);
        }
        c.output().unwrap()
    };
    let o = run(
        &[
            ("SLURM_ARRAY_TASK_ID", "4"),
            ("SLURM_ARRAY_TASK_MIN", "3"),
            ("SLURM_ARRAY_TASK_COUNT", "3"),
        ],
        &[],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(String::from_utf8_lossy(&o.stderr).contains("shard 2/3 (SLURM job array)"));
    assert!(d.path().join("out/manifest.part-2-of-3.jsonl").exists());
    let o = run(&[("JOB_COMPLETION_INDEX", "0")], &["--shard-count", "3"]);
    assert!(String::from_utf8_lossy(&o.stderr).contains("shard 1/3 (Kubernetes Indexed Job)"));
    let o = run(&[("JOB_COMPLETION_INDEX", "0")], &[]);
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stderr).contains("--shard-count"));
}

/// Issue #23 item 7: SIGTERM (and SIGINT, SIGHUP) during `dataset` removes
/// the item being made (`.partial-*`) and says so, exit 130; a rerun resumes.
#[cfg(unix)]
#[test]
fn a_terminated_run_leaves_no_partial_item() {
    for sig in ["TERM", "INT", "HUP"] {
        let mut cfg = small(50);
        cfg.resolution = [160, 120];
        let d = tempfile::tempdir().unwrap();
        let toml = d.path().join("ds.toml");
        std::fs::write(&toml, cfg.to_toml().unwrap()).unwrap();
        let out = d.path().join("out");
        let child = common::mmbm_cmd()
            .args(["dataset", "--quiet", "--config"])
            .arg(&toml)
            .arg("--out")
            .arg(&out)
            .stderr(std::process::Stdio::piped())
            .spawn()
            .unwrap();
        let partials = || -> Vec<String> {
            std::fs::read_dir(&out)
                .map(|r| {
                    r.filter_map(|e| e.ok())
                        .map(|e| e.file_name().to_string_lossy().into_owned())
                        .filter(|n| n.starts_with(".partial-"))
                        .collect()
                })
                .unwrap_or_default()
        };
        let mut seen = false;
        for _ in 0..1000 {
            std::thread::sleep(std::time::Duration::from_millis(10));
            if !partials().is_empty() {
                seen = true;
                break;
            }
        }
        assert!(seen, "SIG{sig}: no item was being made");
        let st = std::process::Command::new("kill")
            .args([format!("-{sig}"), child.id().to_string()])
            .status()
            .unwrap();
        assert!(st.success());
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(130), "SIG{sig}: {err}");
        assert!(partials().is_empty(), "SIG{sig}: {:?}", partials());
        assert!(!err.contains("removed 0 temporary"), "SIG{sig}: {err}");
    }
}

/// A `[camera]` section (issue #22): its keys are in every item's parameters
/// and in the fingerprint, the items are made with that camera (again from
/// the manifest line alone), and a configuration without it has no `camera`
/// key anywhere. A bad section is an error naming it.
#[test]
fn a_camera_section_makes_another_dataset() {
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    let section =
        "[camera]\nfocal_mm = 3.0\nreadout_s = 0.01\nreadout_direction = \"bottom-to-top\"\n";
    let toml = format!(
        "count = 2\ntextures = \"{}\"\nmotion = [\"sim:fast\"]\nresolution = [48, 36]\n",
        textures().display()
    );
    std::fs::write(p.join("plain.toml"), &toml).unwrap();
    std::fs::write(p.join("cam.toml"), format!("{toml}{section}")).unwrap();
    let plain = DatasetConfig::load(&p.join("plain.toml")).unwrap();
    let cam = DatasetConfig::load(&p.join("cam.toml")).unwrap();
    assert_eq!(cam.camera.focal_mm, Some(3.0));
    assert_eq!(cam.camera().shutter.readout_s, 0.01);
    assert!(!plain.to_toml().unwrap().contains("camera"));
    assert!(cam.to_toml().unwrap().contains("[camera]"));

    let (a, b) = (
        dataset::Record::of(&plain, &Sources::open(&plain).unwrap()).unwrap(),
        dataset::Record::of(&cam, &Sources::open(&cam).unwrap()).unwrap(),
    );
    assert_ne!(a.fingerprint, b.fingerprint);
    assert!(a.inputs.get("camera").is_none());
    assert_eq!(b.inputs["camera"]["focal_mm"], 3.0);

    let (da, db) = (p.join("plain"), p.join("cam"));
    dataset::run(&plain, &da, Shard::ALL, false).unwrap();
    dataset::run(&cam, &db, Shard::ALL, false).unwrap();
    let lines = |dir: &Path| -> Vec<ManifestLine> {
        std::fs::read_to_string(dir.join("manifest.jsonl"))
            .unwrap()
            .lines()
            .map(|l| serde_json::from_str(l).unwrap())
            .collect()
    };
    let raw = std::fs::read_to_string(da.join("manifest.jsonl")).unwrap();
    assert!(!raw.contains("camera"), "{raw}");
    let src = Sources::open(&cam).unwrap();
    for (x, y) in lines(&da).iter().zip(lines(&db)) {
        assert_eq!(x.params.camera, Default::default());
        assert_eq!(y.params.camera, cam.camera);
        // The shorter focal length sees a wider field: a wider texture.
        assert!(y.params.texture_width_m > x.params.texture_width_m);
        let blurred = |dir: &Path, l: &ManifestLine| {
            std::fs::read(dir.join(&l.dir).join("blurred.exr")).unwrap()
        };
        assert!(blurred(&da, x) != blurred(&db, &y), "item {}", x.index);
        // Made again from the line alone: the same bytes.
        let again = tempfile::tempdir().unwrap();
        assert_eq!(make(&y.params, &src, again.path()).unwrap(), y.measures);
        for f in FILES {
            let (u, v) = (
                std::fs::read(again.path().join(f)).unwrap(),
                std::fs::read(db.join(&y.dir).join(f)).unwrap(),
            );
            assert!(u == v, "item {} {f} differs when re-rendered", y.index);
        }
    }

    std::fs::write(
        p.join("bad.toml"),
        format!("{toml}[camera]\nfocal_mm = -1\n"),
    )
    .unwrap();
    let o = mmbm_in(
        p,
        &["dataset", "--quiet", "--config", "bad.toml", "--out", "bad"],
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("bad.toml") && err.contains("camera"), "{err}");
    assert!(
        !p.join("bad/items").exists()
            || std::fs::read_dir(p.join("bad/items")).unwrap().count() == 0
    );
}

#[test]
fn a_sensor_section_runs_the_camera_pipeline_on_the_pngs() {
    use mmbm_lab::dataset::SensorPipeline;
    let mut cfg = small(2);
    cfg.camera.noise = Some(mmbm::camera::Noise::at_light(20_000.0));
    cfg.sensor = Some(SensorPipeline {
        response: "gamma:2.2".into(),
        bayer: "rggb".into(),
        jpeg_quality: 80,
        ..SensorPipeline::default()
    });
    let a = tempfile::tempdir().unwrap();
    dataset::run(&cfg, a.path(), Shard::ALL, false).unwrap();
    assert_eq!(dataset::verify(a.path()).unwrap(), 2);
    // Deterministic: a second run gives the same bytes.
    let b = tempfile::tempdir().unwrap();
    dataset::run(&cfg, b.path(), Shard::ALL, false).unwrap();
    assert_eq!(items_and_manifest(a.path()), items_and_manifest(b.path()));
    let line: ManifestLine =
        serde_json::from_slice(&std::fs::read(a.path().join("items/00000000/item.json")).unwrap())
            .unwrap();
    assert_eq!(line.params.sensor, cfg.sensor);
    // The sharp PNG is the pipeline applied to the noise-free sharp EXR.
    let (w, h, ch) =
        mmbm::io::images::read_exr(&a.path().join("items/00000000/sharp.exr")).unwrap();
    let get = |n: &str| &ch.iter().find(|c| c.0 == n).unwrap().1;
    let (r, g, bl) = (get("R"), get("G"), get("B"));
    let rgb: Vec<f32> = (0..w * h).flat_map(|i| [r[i], g[i], bl[i]]).collect();
    let want = cfg
        .sensor
        .as_ref()
        .unwrap()
        .encode(w as u32, h as u32, &rgb)
        .unwrap();
    let png = image::open(a.path().join("items/00000000/sharp.png"))
        .unwrap()
        .to_rgb8()
        .into_raw();
    assert_eq!(png, want);
    // Without the section: no `sensor` key anywhere, and other PNG bytes.
    let plain = tempfile::tempdir().unwrap();
    let mut c2 = cfg.clone();
    c2.sensor = None;
    dataset::run(&c2, plain.path(), Shard::ALL, false).unwrap();
    let text = std::fs::read_to_string(plain.path().join("manifest.jsonl")).unwrap();
    assert!(!text.contains("sensor"));
    assert_ne!(
        std::fs::read(plain.path().join("items/00000000/blurred.png")).unwrap(),
        std::fs::read(a.path().join("items/00000000/blurred.png")).unwrap()
    );
    // Bad keys are clear errors.
    let mut bad = cfg.clone();
    bad.sensor.as_mut().unwrap().bayer = "rgb".into();
    let e = dataset::run(&bad, tempfile::tempdir().unwrap().path(), Shard::ALL, false)
        .unwrap_err()
        .to_string();
    assert!(e.contains("bayer") && e.contains("rggb"), "{e}");
}
