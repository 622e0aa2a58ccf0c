//! One output guard (issue 35): an output never replaces an input, every
//! output is checked before the work, and `frames --maps` writes all or
//! nothing. Each case runs the `mmbm` command in a folder of its own.

use crate::common;
use crate::robust;

use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::{Duration, Instant};

/// A fresh folder for one test.
fn folder(name: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("mmbm-output-guard-{name}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A gyro log: `n` samples 1/200 s apart, turning at a steady rate.
fn gyro_log(n: usize) -> String {
    let mut s = String::from("t,wx,wy,wz\n");
    for k in 0..n {
        s += &format!("{},0.3,-0.2,0.1\n", k as f64 * 0.005);
    }
    s
}

/// A frame table of `n` frames 0.004 s apart from 0.05 s, 2 ms exposures.
fn frame_table(n: usize) -> String {
    let mut s = String::from("t_start,exposure_s\n");
    for k in 0..n {
        s += &format!("{},0.002\n", 0.05 + k as f64 * 0.004);
    }
    s
}

const CAMERA: &str = "focal_mm = 4.2548\npitch_mm = 0.00465\nwidth = 64\nheight = 48\n";

/// The inputs every case may name: g.csv (gyro), f.csv (frames), cam.toml,
/// tex.png (a texture), gait.toml (a gait config), with a symlink and a
/// hard link to g.csv and a sub-folder for `sub/../g.csv`.
fn inputs(d: &Path) {
    std::fs::write(d.join("g.csv"), gyro_log(400)).unwrap();
    std::fs::write(d.join("f.csv"), frame_table(3)).unwrap();
    std::fs::write(d.join("cam.toml"), CAMERA).unwrap();
    std::fs::write(d.join("gait.toml"), "").unwrap();
    image::RgbImage::from_pixel(32, 32, image::Rgb([200, 100, 50]))
        .save(d.join("tex.png"))
        .unwrap();
    std::fs::hard_link(d.join("g.csv"), d.join("hard.csv")).unwrap();
    #[cfg(unix)]
    std::os::unix::fs::symlink("g.csv", d.join("soft.csv")).unwrap();
    std::fs::create_dir_all(d.join("sub")).unwrap();
}

/// Every file under `d` (relative paths, sorted, as [`names`] lists them)
/// with its bytes ("link" for a symlink, nothing for a folder).
fn snapshot(d: &Path) -> Vec<(PathBuf, Vec<u8>)> {
    names(d)
        .into_iter()
        .map(|p| {
            let path = d.join(&p);
            let t = std::fs::symlink_metadata(&path).unwrap().file_type();
            let bytes = if t.is_dir() {
                Vec::new()
            } else if t.is_symlink() {
                b"link".to_vec()
            } else {
                std::fs::read(&path).unwrap()
            };
            (p, bytes)
        })
        .collect()
}

/// Every path under `d` (relative, sorted), read while the command may still
/// be writing: an entry that is renamed or removed between the listing and
/// the look at it (a temporary becoming its map) is skipped, not an error.
fn names(d: &Path) -> Vec<PathBuf> {
    let mut v = Vec::new();
    let mut stack = vec![d.to_path_buf()];
    while let Some(p) = stack.pop() {
        let entries = match std::fs::read_dir(&p) {
            Err(e) if p != d && e.kind() == std::io::ErrorKind::NotFound => continue,
            r => r.unwrap(),
        };
        for e in entries.flatten() {
            let path = e.path();
            if e.file_type().is_ok_and(|t| t.is_dir()) {
                stack.push(path.clone());
            }
            v.push(path.strip_prefix(d).unwrap().to_path_buf());
        }
    }
    v.sort();
    v
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// Runs each case in `d` and returns how each one that does not refuse with
/// `words`, leaving every file as it was, fails.
fn refused(d: &Path, cases: &[(String, &[&str])]) -> Vec<String> {
    let mut failures = Vec::new();
    for (args, words) in cases {
        let before = snapshot(d);
        let argv: Vec<&str> = args.split_whitespace().collect();
        let o = common::mmbm_in(d, &argv);
        let mut why = robust::refusal_faults(&o, &[1], words);
        let after = snapshot(d);
        if after != before {
            let changed: Vec<_> = after
                .iter()
                .filter(|f| !before.contains(f))
                .map(|f| f.0.display().to_string())
                .collect();
            why.push(format!("files changed or added: {changed:?}"));
            // Back as it was for the next case.
            let _ = std::fs::remove_dir_all(d);
            std::fs::create_dir_all(d).unwrap();
            inputs(d);
        }
        if !why.is_empty() {
            failures.push(robust::failure(args, &why, &o));
        }
    }
    failures
}

/// Every output flag of every command over every input it reads (also
/// through a symlink, a hard link and `sub/..`) is refused by name before
/// any work, and every file stays as it was.
#[test]
fn output_over_an_input_is_refused_by_name() {
    let d = folder("over");
    inputs(&d);
    let frames = "frames --gyro g.csv --frames f.csv --camera cam.toml";
    let mut cases: Vec<(String, &[&str])> = Vec::new();
    let is_input = |flag: &'static str, input: &'static str| -> Vec<&'static str> {
        vec![flag, "is the input", input]
    };
    let words: Vec<(String, Vec<&str>)> = {
        let mut v = Vec::new();
        for (input, flag) in [
            ("g.csv", "--gyro"),
            ("f.csv", "--frames"),
            ("cam.toml", "--camera"),
        ] {
            v.push((format!("{frames} --out {input}"), is_input("--out", flag)));
            v.push((
                format!("{frames} --select 1 --image-list {input}"),
                is_input("--image-list", flag),
            ));
            v.push((
                format!("{frames} --select 1 --ffmpeg-select {input}"),
                is_input("--ffmpeg-select", flag),
            ));
            v.push((
                format!("{frames} --worst 1 --worst-list {input}"),
                is_input("--worst-list", flag),
            ));
            v.push((
                format!("{frames} --worst 1 --worst-ffmpeg-select {input}"),
                is_input("--worst-ffmpeg-select", flag),
            ));
        }
        for link in ["hard.csv", "soft.csv", "sub/../g.csv", "./g.csv"] {
            v.push((
                format!("{frames} --out {link}"),
                is_input("--out", "--gyro"),
            ));
            v.push((
                format!("series --gyro g.csv --out {link}"),
                is_input("--out", "--gyro"),
            ));
            v.push((
                format!("trigger --gyro g.csv --policy fixed:5 --out {link}"),
                is_input("--out", "--gyro"),
            ));
        }
        v.push((
            "series --gyro soft.csv --out g.csv".into(),
            is_input("--out", "--gyro"),
        ));
        v.push((
            "series --gyro g.csv --camera cam.toml --out cam.toml".into(),
            is_input("--out", "--camera"),
        ));
        v.push((
            "trigger --gyro g.csv --camera cam.toml --policy fixed:5 --out cam.toml".into(),
            is_input("--out", "--camera"),
        ));
        let render = "render --omega 0.3,0,0 --exposure 0.01 --distance 2 --sensor 64x48 \
                      --target image:tex.png:1";
        v.push((
            format!("{render} --out tex.png"),
            is_input("--out", "--target image:"),
        ));
        v.push((
            format!("{render} --out o.png --sharp tex.png"),
            is_input("--sharp", "--target image:"),
        ));
        v.push((
            format!("{render} --out o.png --psf 3,3:tex.png"),
            is_input("--psf", "--target image:"),
        ));
        v.push((
            "blobs tex.png --mask tex.png".into(),
            is_input("--mask", "IMAGE"),
        ));
        v.push((
            "simulate --config gait.toml --duration 1 --out gait.toml".into(),
            is_input("--out", "--config"),
        ));
        v
    };
    for (a, w) in &words {
        cases.push((a.clone(), w.as_slice()));
    }
    let failures = refused(&d, &cases);
    assert!(
        failures.is_empty(),
        "{} of {} cases not refused cleanly:\n{}",
        failures.len(),
        cases.len(),
        failures.join("\n")
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// `frames --maps DIR`: a file output inside DIR, or an input named like a
/// map in DIR, is refused before any work, and DIR stays as it was.
#[test]
fn maps_folder_takes_no_other_output_and_no_input() {
    let d = folder("inside");
    inputs(&d);
    std::fs::create_dir_all(d.join("m")).unwrap();
    std::fs::write(d.join("m/frame_000000.exr"), gyro_log(400)).unwrap();
    let frames = "frames --gyro g.csv --frames f.csv --camera cam.toml --maps m --backend cpu";
    let cases: Vec<(String, &[&str])> = vec![
        (
            format!("{frames} --out m/t.csv"),
            &["--out", "inside the output folder --maps"],
        ),
        (
            format!("{frames} --out t.csv --select 1 --image-list m/list.txt"),
            &["--image-list", "inside the output folder --maps"],
        ),
        (
            "frames --gyro m/frame_000000.exr --frames f.csv --camera cam.toml --maps m \
             --backend cpu --out t.csv"
                .into(),
            &["the input --gyro", "--maps"],
        ),
    ];
    let failures = refused(&d, &cases);
    assert!(failures.is_empty(), "{}", failures.join("\n"));
    let _ = std::fs::remove_dir_all(&d);
}

/// Paths under `d` whose names end in `.exr` or start with `.mmbm`.
fn maps_or_temporaries(d: &Path) -> Vec<String> {
    names(d)
        .into_iter()
        .map(|p| p.display().to_string())
        .filter(|p| {
            p.ends_with(".exr")
                || Path::new(p)
                    .file_name()
                    .is_some_and(|n| n.to_string_lossy().starts_with(".mmbm"))
        })
        .collect()
}

/// `frames --maps DIR --out /dev/full`: the table fails, and no map is
/// left behind (nor a temporary); the same with a folder that exists.
#[cfg(target_os = "linux")]
#[test]
fn failed_table_leaves_no_maps() {
    let d = folder("full");
    inputs(&d);
    for maps in ["new/m", "old"] {
        std::fs::create_dir_all(d.join("old")).unwrap();
        let o = common::mmbm_in(
            &d,
            &[
                "frames",
                "--gyro",
                "g.csv",
                "--frames",
                "f.csv",
                "--camera",
                "cam.toml",
                "--maps",
                maps,
                "--backend",
                "cpu",
                "--out",
                "/dev/full",
            ],
        );
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(err.contains("/dev/full"), "{err}");
        assert_eq!(
            maps_or_temporaries(&d),
            Vec::<String>::new(),
            "{maps}: {err}"
        );
        assert!(!d.join("new").exists(), "{maps}: new/ was created");
    }
    // The same run to a file writes the table and its maps together.
    let o = common::mmbm_ok_in(
        &d,
        &[
            "frames",
            "--gyro",
            "g.csv",
            "--frames",
            "f.csv",
            "--camera",
            "cam.toml",
            "--maps",
            "new/m",
            "--backend",
            "cpu",
            "--out",
            "t.csv",
        ],
    );
    let mut left = maps_or_temporaries(&d);
    left.sort();
    assert_eq!(
        left,
        [
            "new/m/frame_000001.exr",
            "new/m/frame_000002.exr",
            "new/m/frame_000003.exr"
        ],
        "{}",
        stderr(&o)
    );
    assert_eq!(
        std::fs::read_to_string(d.join("t.csv"))
            .unwrap()
            .lines()
            .count(),
        4
    );
    let _ = std::fs::remove_dir_all(&d);
}

/// A folder where even root cannot create a file: sysfs refuses new files
/// to everyone. `None` (the test then has nothing to show) elsewhere.
fn unwritable_dir() -> Option<PathBuf> {
    let d = Path::new("/sys");
    let probe = d.join(format!("mmbm-probe-{}", std::process::id()));
    match std::fs::File::create(&probe) {
        Ok(_) => {
            let _ = std::fs::remove_file(&probe);
            None
        }
        Err(_) if d.is_dir() => Some(d.to_path_buf()),
        Err(_) => None,
    }
}

/// An output into a folder that cannot be written fails before the work:
/// at once, naming the flag and the folder, having written nothing (a
/// render of 2^20 pixels, or 40 frames' maps, would take seconds first).
#[test]
fn unwritable_output_fails_before_the_work() {
    let Some(ro) = unwritable_dir() else {
        common::skip("no folder here refuses new files to this user");
        return;
    };
    let d = folder("ro");
    inputs(&d);
    std::fs::write(d.join("f40.csv"), frame_table(40)).unwrap();
    let out = |name: &str| ro.join(name).display().to_string();
    let cases: Vec<Vec<String>> = vec![
        [
            "render",
            "--omega",
            "2,1,3",
            "--exposure",
            "0.05",
            "--distance",
            "2",
            "--sensor",
            "1024x1024",
            "--target",
            "checker:0.05",
            "--backend",
            "cpu",
            "--out",
        ]
        .iter()
        .map(|s| s.to_string())
        .chain([out("mmbm-x.png")])
        .collect(),
        ["flow", "--omega", "1,0,0", "--sensor", "1024x1024", "--out"]
            .iter()
            .map(|s| s.to_string())
            .chain([out("mmbm-x.exr")])
            .collect(),
        [
            "frames",
            "--gyro",
            "g.csv",
            "--frames",
            "f40.csv",
            "--maps",
            "m",
            "--backend",
            "cpu",
            "--out",
        ]
        .iter()
        .map(|s| s.to_string())
        .chain([out("mmbm-t.csv")])
        .collect(),
    ];
    for args in &cases {
        let argv: Vec<&str> = args.iter().map(String::as_str).collect();
        let t0 = Instant::now();
        let o = common::mmbm_in(&d, &argv);
        let secs = t0.elapsed().as_secs_f64();
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{args:?}: {err}");
        assert!(
            err.contains("cannot write in") && err.contains("(--out)"),
            "{args:?}: {err}"
        );
        assert!(secs < 2.0, "{args:?}: took {secs:.2} s");
        assert!(!d.join("m").exists(), "{args:?}: maps written");
    }
    let _ = std::fs::remove_dir_all(&d);
}

/// SIGTERM while `frames --maps` writes: no map and no temporary is left,
/// and the run exits with 130.
#[cfg(unix)]
#[test]
fn sigterm_during_maps_leaves_nothing() {
    let d = folder("term");
    inputs(&d);
    std::fs::write(d.join("g.csv"), gyro_log(3000)).unwrap();
    std::fs::write(d.join("f.csv"), frame_table(3000)).unwrap();
    std::fs::write(
        d.join("cam.toml"),
        "focal_mm = 4.2548\npitch_mm = 0.00465\nwidth = 320\nheight = 240\n",
    )
    .unwrap();
    let mut child = common::mmbm_cmd()
        .args([
            "frames",
            "--gyro",
            "g.csv",
            "--frames",
            "f.csv",
            "--camera",
            "cam.toml",
            "--maps",
            "m",
            "--backend",
            "cpu",
            "--out",
            "t.csv",
        ])
        .current_dir(&d)
        .stdin(std::process::Stdio::null())
        .stdout(std::process::Stdio::null())
        .stderr(std::process::Stdio::piped())
        .spawn()
        .unwrap();
    // Wait for some maps to be on disk (wherever they are written).
    let t0 = Instant::now();
    while maps_or_temporaries(&d)
        .iter()
        .filter(|p| p.ends_with(".exr"))
        .count()
        < 3
    {
        assert!(
            t0.elapsed() < Duration::from_secs(120),
            "no maps after 120 s"
        );
        assert!(
            child.try_wait().unwrap().is_none(),
            "ended before the signal"
        );
        std::thread::sleep(Duration::from_millis(20));
    }
    let k = std::process::Command::new("kill")
        .args(["-TERM", &child.id().to_string()])
        .status()
        .unwrap();
    assert!(k.success());
    let o = child.wait_with_output().unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(130), "{err}");
    assert_eq!(maps_or_temporaries(&d), Vec::<String>::new(), "{err}");
    assert!(!d.join("m").exists() && !d.join("t.csv").exists(), "{err}");
    let _ = std::fs::remove_dir_all(&d);
}

/// `[map] fps` above the trigger's cap (1000 frames/s) is refused before
/// the run, naming the key, and no report folder is made.
#[test]
fn map_fps_above_the_cap_is_refused_up_front() {
    let d = folder("fps");
    std::fs::write(
        d.join("c.toml"),
        "[map]\nlights_e_per_s = [1000.0]\nfps = 1e9\n",
    )
    .unwrap();
    let t0 = Instant::now();
    let o = common::mmbm_in(
        &d,
        &[
            "experiment",
            "--config",
            "c.toml",
            "--out",
            "rep",
            "--quiet",
        ],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("[map] fps") && err.contains("1000"), "{err}");
    assert!(!err.contains("fixed:1000000000"), "{err}");
    assert!(t0.elapsed() < Duration::from_secs(5), "{err}");
    assert!(!d.join("rep").exists());
    // At the cap it passes the check (the run itself is not started here:
    // the library check alone).
    let mut cfg = mmbm_lab::experiment::ExperimentConfig::default();
    cfg.map.lights_e_per_s = vec![1000.0];
    cfg.map.fps = 1000.0;
    cfg.map.validate(cfg.exposure_s).unwrap();
    cfg.map.fps = 1000.5;
    let e = cfg.map.validate(cfg.exposure_s).unwrap_err().to_string();
    assert!(e.contains("[map] fps"), "{e}");
    let _ = std::fs::remove_dir_all(&d);
}

/// `experiment --out DIR` (and `dataset --out DIR`) over its config under a
/// name it writes there is refused, leaving the folder as it was.
#[test]
fn experiment_output_folder_spares_its_inputs() {
    let d = folder("exp");
    std::fs::create_dir_all(d.join("rep")).unwrap();
    // A config named like the report it would replace.
    std::fs::write(d.join("rep/report.md"), "exposure_s = 0.07\n").unwrap();
    let o = common::mmbm_in(
        &d,
        &[
            "experiment",
            "--config",
            "rep/report.md",
            "--out",
            "rep",
            "--quiet",
        ],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("the input --config"), "{err}");
    assert_eq!(
        std::fs::read_to_string(d.join("rep/report.md")).unwrap(),
        "exposure_s = 0.07\n"
    );
    // The same for a dataset folder: its config named like its manifest.
    std::fs::create_dir_all(d.join("ds")).unwrap();
    std::fs::write(d.join("ds/manifest.jsonl"), "count = 1\n").unwrap();
    let o = common::mmbm_in(
        &d,
        &[
            "dataset",
            "--config",
            "ds/manifest.jsonl",
            "--out",
            "ds",
            "--quiet",
        ],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("the input --config"), "{err}");
    assert_eq!(
        std::fs::read_to_string(d.join("ds/manifest.jsonl")).unwrap(),
        "count = 1\n"
    );
    assert_eq!(std::fs::read_dir(d.join("ds")).unwrap().count(), 1);
    let _ = std::fs::remove_dir_all(&d);
}
