//! The bad-input suite, round 3 (issue #23): time bases too coarse for what
//! is timed on them, results that are not finite numbers, outputs sharing
//! one file, unbounded echoes, endless and gigantic inputs. Same contract as
//! cli/tests/refusals/robustness.rs: exit code 1 (2 for a malformed command line), an
//! `error:` line that says what and where, nothing left behind.

use crate::common;
use crate::robust;

use common::mmbm_in;
use robust::{files, one_red_pixel_png, unclear_errors};
use std::process::{Command, Stdio};

/// Issue #23 item 1: a log at t = 1e308 made `trigger --policy fixed:5` (and
/// gate, gate0) loop forever; nanosecond epoch stamps read as seconds gave
/// 2000 frames "all kept" with a 0.00 ms exposure. Both are now refused with
/// a hint at `--time-unit`, quickly, through the CLI and the library alike.
#[test]
fn time_bases_too_coarse_for_the_exposure_are_refused() {
    let dir = tempfile::tempdir().unwrap();
    std::fs::write(
        dir.path().join("huge.csv"),
        "t,wx,wy,wz\n1e308,0.1,0,0\n1.0000001e308,0.1,0,0\n1.0000002e308,0.1,0,0\n",
    )
    .unwrap();
    // 2000 samples 1 ms apart, stamped in nanoseconds since the epoch.
    let mut ns = String::from("t,wx,wy,wz\n");
    for k in 0..2000u64 {
        ns += &format!(
            "{},0.1,0.2,0\n",
            1_700_000_000_000_000_000u64 + k * 1_000_000
        );
    }
    std::fs::write(dir.path().join("ns.csv"), &ns).unwrap();
    for policy in [
        "fixed:5",
        "gate:0.4",
        "gate0:0.4",
        "threshold:0.4",
        "deadline:5",
    ] {
        for log in ["huge.csv", "ns.csv"] {
            let o = mmbm_in(
                dir.path(),
                &["trigger", "--gyro", log, "--policy", policy, "--summary"],
            );
            let err = String::from_utf8_lossy(&o.stderr);
            assert_eq!(o.status.code(), Some(1), "{policy} {log}: {err}");
            assert!(err.contains("--time-unit"), "{policy} {log}: {err}");
        }
    }
    // The same stamps with their unit: 2 s of log, frames at 5 fps.
    let o = mmbm_in(
        dir.path(),
        &[
            "trigger",
            "--gyro",
            "ns.csv",
            "--time-unit",
            "ns",
            "--policy",
            "fixed:5",
            "--summary",
            "--out",
            "f.csv",
        ],
    );
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("fixed:5: 10 frames"), "{out}");
    // live: no sample is decided with a zero exposure; each is reported
    // with the hint and skipped (issue 35: one bad sample does not stop a
    // stream), and --strict stops at the first (exit 2).
    for (strict, code) in [(false, 0), (true, 2)] {
        let o = common::mmbm_cmd()
            .current_dir(dir.path())
            .args([
                "live", "--replay", "ns.csv", "--speed", "0", "--policy", "fixed:5",
            ])
            .args(strict.then_some("--strict"))
            .output()
            .unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(code), "{err}");
        assert!(err.contains("--time-unit") && o.stdout.is_empty(), "{err}");
    }
}

/// A small render every output case shares (CPU, 32 x 24: seconds at most);
/// `R` at the start of a case below stands for it.
const RENDER: &str = "render --omega 0.1,0,0 --exposure 0.05 --target checker:0.02 --distance 1 \
                      --resolution 32x24 --backend cpu";

/// Issue 23, items 5, 7 and 8: results that are not finite numbers, two
/// outputs on one path, outputs that cannot be written, and error messages
/// that would echo whole inputs: clear errors, before any work, bounded.
/// Each case: the arguments, then ` | ` and each word the error must say.
const ROUND_3: &[&str] = &[
    // Results and cameras that are not finite numbers.
    "eval --omega 1,1,1 --pitch 1e-308 --exposure 0.05 | pixel pitch | between",
    "eval --omega 1,1,1 --exposure 1e308 --json | blur | not a finite number",
    "eval --omega 1,1,1 --camera tiny_focal.json | tiny_focal.json | focal length | 1e-300",
    "series --gyro good.csv --exposure 1e308 --out o.csv | t = 0 s | blur | not a finite",
    // Two outputs on one path (a name, a hard link, a symlink), before any work.
    "R --out x.png --sharp x.png | --out x.png | --sharp x.png | one file",
    "R --out x.exr --maps ./x.exr | --out | --maps | one file",
    "R --out x.png --psf 5,5:x.png | --psf | one file",
    "R --out old.png --sharp hard.png | old.png | hard.png | one file",
    "flow --omega 1,1,1 --out f.exr --quiver q.png | --quiver q.png | one file",
    // An experiment's output place, checked before rendering.
    "experiment --config small.toml --out afile --quiet | afile | not a directory",
    // What an error echoes is bounded and printable.
    "series --gyro wide.csv | wide.csv:1 | wz | bytes in all",
    "series --gyro nul.csv | nul.csv:1 | \\x00",
    "series --gyro nogx.gcsv | nogx.gcsv | gx | bytes in all",
    "eval --omega 1,1,1 --camera long_line.toml | long_line.toml | line 1 | bytes in all",
    "dataset --config tex.toml --out data --quiet | caf\\xe9.png | not valid UTF-8",
];

#[cfg(unix)]
#[test]
fn non_finite_results_shared_outputs_and_huge_echoes_are_clear_errors() {
    use std::os::unix::ffi::OsStrExt;
    let d = tempfile::tempdir().unwrap();
    files(d.path());
    let w = |name: &str, text: &str| std::fs::write(d.path().join(name), text).unwrap();
    let profile = |extra: &str| {
        format!(
            "{{\"calib_dimension\": {{\"w\": 640, \"h\": 480}}, \"fisheye_params\": \
             {{\"camera_matrix\": [[500, 0, 320], [0, 500, 240], [0, 0, 1]]}}{extra}}}"
        )
    };
    w("tiny_focal.json", &profile(", \"focal_length\": 1e-300"));
    w("real_focal.json", &profile(", \"focal_length\": 2.5"));
    w("profile.json", &profile(""));
    let cols: Vec<String> = (0..200_000).map(|i| format!("c{i}")).collect();
    w(
        "wide.csv",
        &format!("t,wx,wy,{}\n0,1,2,3\n", cols.join(",")),
    );
    w("nul.csv", &"\0".repeat(1000));
    let gcsv = "GYROFLOW IMU LOG\nversion,1.3\ntscale,0.001\ngscale,1\nt,";
    // A column line of 2 fields (t and one huge name): fewer than t,gx,gy,gz.
    w("nogx.gcsv", &format!("{gcsv}{}\n0,1,2,3\n", cols.join("")));
    w(
        "long_line.toml",
        // Under the camera file's cap (1 MiB), so that the parser's message
        // about the one long line is what must be clipped.
        &format!("focal_mm = 4{}\n", "x".repeat(1_000_000)),
    );
    w(
        "small.toml",
        "duration_s = 3.0\npolicies = [\"fixed:5\"]\nresolution = [32, 24]\nquality = \"fast\"\n\
         max_frames_per_policy = 1\nsweep_exposures_s = [0.05]\nsweep_frames = 1\n",
    );
    w("afile", "not a directory");
    // A texture whose name is not UTF-8 (a readable PNG all the same).
    std::fs::create_dir(d.path().join("tex")).unwrap();
    let odd = std::ffi::OsStr::from_bytes(b"caf\xe9.png");
    std::fs::write(d.path().join("tex").join(odd), one_red_pixel_png()).unwrap();
    w(
        "tex.toml",
        "textures = \"tex\"\ncount = 1\nmotion = [\"sim:slow\"]\n",
    );
    // One file under two names: a hard link, and a dangling symlink to a new one.
    w("old.png", "old");
    std::fs::hard_link(d.path().join("old.png"), d.path().join("hard.png")).unwrap();
    std::os::unix::fs::symlink("f.exr", d.path().join("q.png")).unwrap();
    let cases: Vec<(String, Vec<&str>)> = ROUND_3
        .iter()
        .map(|c| {
            let mut parts = c.split(" | ");
            let args = parts.next().unwrap();
            let args = args
                .strip_prefix("R ")
                .map_or(args.to_string(), |r| format!("{RENDER} {r}"));
            (args, parts.collect())
        })
        .collect();
    let table: Vec<(&str, &[&str])> = cases
        .iter()
        .map(|(a, w)| (a.as_str(), w.as_slice()))
        .collect();
    let failures = unclear_errors(d.path(), &table);
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
    assert_eq!(std::fs::read(d.path().join("old.png")).unwrap(), b"old");
    // A profile without a focal length in mm, or with a real one, has its
    // answer, the same in px/s (they do not depend on the pitch); a finite
    // blur is printed as before.
    let eval = |args: &[&str]| -> serde_json::Value {
        let argv = [&["eval", "--omega", "1,1,1", "--json"], args].concat();
        serde_json::from_slice(&common::mmbm_ok_in(d.path(), &argv).stdout).unwrap()
    };
    let px_s = |camera: &str| eval(&["--camera", camera])["mmbm_px_s"].as_f64().unwrap();
    let (nominal, real) = (px_s("profile.json"), px_s("real_focal.json"));
    assert!(
        nominal > 100.0 && (nominal - real).abs() < 1e-9 * nominal,
        "{nominal} {real}"
    );
    let v = eval(&["--exposure", "0.05"]);
    assert!(v["blur_px"].as_f64().is_some_and(f64::is_finite), "{v}");
}

/// `demo --out` at a place it cannot write fails at once, not after
/// minutes of rendering (each run is killed after 60 s: a failure).
#[cfg(unix)]
#[test]
fn demo_checks_its_output_place_first() {
    let d = tempfile::tempdir().unwrap();
    std::fs::write(d.path().join("afile"), "x").unwrap();
    let ro = d.path().join("ro");
    std::fs::create_dir(&ro).unwrap();
    use std::os::unix::fs::PermissionsExt;
    std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o555)).unwrap();
    // /proc takes no new files, even for root; a mode-555 directory only
    // stops other users (root writes there: that case is skipped).
    let mut outs = vec![("/proc/mmbm-report".to_string(), "cannot write")];
    outs.push(("afile".into(), "not a directory"));
    if std::fs::write(ro.join("probe"), "x").is_ok() {
        common::skip("running as root: a read-only directory is writable");
    } else {
        outs.push(("ro/report".into(), "Permission denied"));
    }
    for (out, word) in outs {
        let mut child = common::mmbm_cmd()
            .args(["demo", "--quiet", "--out", &out])
            .current_dir(d.path())
            .stdin(Stdio::null())
            .stdout(Stdio::null())
            .stderr(Stdio::piped())
            .spawn()
            .unwrap();
        let t0 = std::time::Instant::now();
        while child.try_wait().unwrap().is_none() {
            if t0.elapsed().as_secs() > 60 {
                let _ = child.kill();
                panic!("demo --out {out}: still running after 60 s (outputs not checked first)");
            }
            std::thread::sleep(std::time::Duration::from_millis(50));
        }
        let o = child.wait_with_output().unwrap();
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "demo --out {out}: {err}");
        assert!(err.contains(word), "demo --out {out}: {err}");
    }
    let _ = std::fs::set_permissions(&ro, std::fs::Permissions::from_mode(0o755));
}

/// Issue #23 item 3: `/dev/zero` as a gyro log (CLI, experiment config,
/// dataset config, the library function Python's `read_gyro` calls) aborted
/// on a 4 GiB allocation; one endless line on stdin grew without bound; a
/// FIFO named `f.png` among a dataset's textures blocked forever. Now only
/// regular files and pipes are read, every line is capped at
/// `MAX_LINE_BYTES`, and image headers are checked before decoding.
#[cfg(unix)]
#[test]
fn endless_and_gigantic_inputs_are_refused_quickly() {
    use mmbm::io::gyro::{read_log, GyroOptions};
    use mmbm::io::input::{MAX_IMAGE_PIXELS, MAX_LINE_BYTES};
    let d = tempfile::tempdir().unwrap();
    let p = d.path();
    files(p);
    // /dev/zero behind every name a log may have, through every door.
    for (name, link) in [
        ("z.csv", true),
        ("z.gcsv", true),
        ("z.mcap", true),
        ("/dev/zero", false),
    ] {
        if link {
            std::os::unix::fs::symlink("/dev/zero", p.join(name)).unwrap();
        }
        let o = common::mmbm_within(p, &["series", "--gyro", name, "--out", "o.csv"], vec![], 20);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{name}: {err}");
        assert!(
            err.contains(name) && err.contains("character device"),
            "{name}: {err}"
        );
        let e = read_log(&p.join(name), GyroOptions::default())
            .unwrap_err()
            .to_string();
        assert!(e.contains("character device"), "{name}: {e}");
    }
    std::fs::write(p.join("e.toml"), "gyro = \"/dev/zero\"\n").unwrap();
    let o = common::mmbm_within(
        p,
        &["experiment", "--config", "e.toml", "--out", "rep"],
        vec![],
        20,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.code() == Some(1) && err.contains("/dev/zero"),
        "{err}"
    );
    // One line a byte over the cap on stdin (`series` streams).
    let mut long = b"t,wx,wy,wz\n0,1,2,".to_vec();
    long.resize(11 + MAX_LINE_BYTES + 1, b'3');
    long.push(b'\n');
    let o = common::mmbm_within(
        p,
        &["series", "--gyro", "-", "--out", "o.csv"],
        long.clone(),
        20,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("<stdin>:2") && err.contains(&format!("longer than {MAX_LINE_BYTES} bytes")),
        "{err}"
    );
    // The same line to `live` is a malformed line, skipped: the stream goes on.
    let mut live = long.clone();
    live.extend_from_slice(b"0.01,0.1,0.2,0.3\n");
    let o = common::mmbm_within(
        p,
        &["live", "--policy", "fixed:5", "--exposure", "0.05"],
        live,
        20,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(o.status.success(), "{err}");
    assert!(
        err.contains("longer than") && err.contains("line skipped"),
        "{err}"
    );
    // A .gcsv header that never reaches its column line.
    let mut gcsv = b"GYROFLOW IMU LOG\n".to_vec();
    gcsv.resize(gcsv.len() + mmbm::io::input::MAX_HEADER_BYTES + 2, b'\n');
    std::fs::write(p.join("endless.gcsv"), &gcsv).unwrap();
    let o = common::mmbm_within(
        p,
        &["series", "--gyro", "endless.gcsv", "--out", "o.csv"],
        vec![],
        20,
    );
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(
        o.status.code() == Some(1) && err.contains("header"),
        "{err}"
    );
    // A decompression bomb: the header claims more pixels than the cap.
    let side = (MAX_IMAGE_PIXELS as f64).sqrt() as u32 + 1;
    std::fs::write(p.join("bomb.png"), common::png_header(side, side)).unwrap();
    for cmd in ["blobs", "assess"] {
        let o = common::mmbm_within(p, &[cmd, "bomb.png"], vec![], 20);
        let err = String::from_utf8_lossy(&o.stderr);
        assert_eq!(o.status.code(), Some(1), "{cmd}: {err}");
        assert!(
            err.contains("bomb.png") && err.contains(&format!("{side} x {side}")),
            "{cmd}: {err}"
        );
    }
    // A dataset: a FIFO named f.png among the textures is not a texture; a
    // log at /dev/zero is refused.
    let tex = p.join("tex");
    std::fs::create_dir(&tex).unwrap();
    std::fs::write(tex.join("a.png"), one_red_pixel_png()).unwrap();
    assert!(Command::new("mkfifo")
        .arg(tex.join("f.png"))
        .status()
        .unwrap()
        .success());
    let cfg = |motion: &str| mmbm_lab::dataset::DatasetConfig {
        textures: tex.clone(),
        motion: vec![motion.into()],
        count: 1,
        ..Default::default()
    };
    let (tx, rx) = std::sync::mpsc::channel();
    let (ok, zero) = (cfg("sim:slow"), cfg("log:/dev/zero"));
    std::thread::spawn(move || {
        let a = mmbm_lab::dataset::Sources::open(&ok).map(|s| s.textures);
        let b = mmbm_lab::dataset::Sources::open(&zero).map(|_| ());
        let _ = tx.send((a, b.map_err(|e| e.to_string())));
    });
    let (a, b) = rx
        .recv_timeout(std::time::Duration::from_secs(20))
        .expect("Sources::open blocked on a FIFO texture");
    assert_eq!(a.unwrap(), ["a.png"]);
    assert!(b.unwrap_err().contains("character device"));
}
