//! The standing bad-input suite: every subcommand against a table of bad and
//! edge-case inputs. A bad input must give exit code 1 (2 for a malformed
//! command line, as clap reports it; never 101, a panic, or 134, an abort), an `error:` line naming the file and line/column or the
//! parameter or key, and leave no output and no temporary file behind.

mod common;

use common::mmbm_in;
use std::path::Path;
use std::process::{Command, Stdio};

/// A gyro log with a 5 s gap after its first second.
fn gap_log() -> String {
    let mut s = String::from("t,wx,wy,wz\n");
    for k in 0..600 {
        s += &format!("{},0.1,0.2,0.3\n", k as f64 * 0.002);
    }
    for k in 0..600 {
        s += &format!("{},0.1,0.2,0.3\n", 6.2 + k as f64 * 0.002);
    }
    s
}

/// Input files every case can name (relative to its working directory).
fn files(dir: &Path) {
    let w = |name: &str, text: &str| std::fs::write(dir.join(name), text).unwrap();
    w(
        "good.csv",
        "t,wx,wy,wz\n0,0.1,0.2,0.3\n0.01,0.1,0.2,0.3\n0.02,0.1,0.2,0.3\n0.03,0.1,0.2,0.3\n",
    );
    w("dup.csv", "t,wx,wy,wz,wx\n0,1,2,3,4\n");
    w("nonum.csv", "t,wx,wy,wz\n0,0.1,0.2,0.3\n0.01,abc,0.2,0.3\n");
    w("ragged.csv", "t,wx,wy,wz\n0,0.1,0.2,0.3\n0.01,0.1,0.2\n");
    w("nan.csv", "t,wx,wy,wz\n0,0.1,0.2,0.3\n0.01,0.1,NaN,0.3\n");
    w(
        "backwards.csv",
        "t,wx,wy,wz\n0,0.1,0.2,0.3\n0.02,0.1,0.2,0.3\n0.01,0.1,0.2,0.3\n",
    );
    w("empty.csv", "t,wx,wy,wz\n");
    w("nocol.csv", "t,wx,wy\n0,1,2\n");
    w(
        "huge.csv",
        "t,wx,wy,wz\n0,1e308,1e308,0\n0.01,1e308,1e308,0\n",
    );
    w(
        "longfield.csv",
        &format!("t,wx,wy,wz\n0,{},0,0\n", "9".repeat(3_000_000) + "x"),
    );
    w("gap.csv", &gap_log());
    w("calm.csv", &{
        let mut s = String::from("t,wx,wy,wz\n");
        for k in 0..2000 {
            s += &format!("{},2,2,2\n", k as f64 * 0.002);
        }
        s
    });
    w("gait.toml", "step_hz = 1e9\n");
    w("gait_type.toml", "step_hz = \"fast\"\n");
    w(
        "camera0.toml",
        "focal_mm = 0\npitch_mm = 0.00465\nwidth = 640\nheight = 480\n",
    );
    w("camera_key.toml", "focal = 4.2\n");
    w("exp_key.toml", "walkz = [\"slow\"]\n");
    w("exp_val.toml", "policies = [\"fixed:0\"]\n");
    w("not.png", "this is not an image");
    std::fs::write(dir.join("one.png"), one_red_pixel_png()).unwrap();
}

/// A 1x1 red PNG, written with the `image` crate.
fn one_red_pixel_png() -> Vec<u8> {
    let img = image::RgbImage::from_pixel(1, 1, image::Rgb([255, 0, 0]));
    let mut out = std::io::Cursor::new(Vec::new());
    img.write_to(&mut out, image::ImageFormat::Png).unwrap();
    out.into_inner()
}

/// Names in `dir` besides the input files.
fn leftovers(dir: &Path, before: &[String]) -> Vec<String> {
    let mut v: Vec<String> = std::fs::read_dir(dir)
        .unwrap()
        .map(|e| e.unwrap().file_name().to_string_lossy().into_owned())
        .filter(|n| !before.contains(n))
        .collect();
    v.sort();
    v
}

/// (arguments, words the error must contain).
const BAD: &[(&str, &[&str])] = &[
    // Malformed logs: file, line and column.
    ("series --gyro nonum.csv", &["nonum.csv:3", "wx"]),
    ("series --gyro ragged.csv", &["ragged.csv:3"]),
    ("series --gyro nan.csv", &["nan.csv:3", "wy"]),
    ("series --gyro backwards.csv", &["backwards.csv:4", "t"]),
    ("series --gyro empty.csv", &["empty.csv", "no samples"]),
    ("series --gyro nocol.csv", &["nocol.csv:1", "wz"]),
    ("series --gyro dup.csv", &["dup.csv:1", "wx", "more than once"]),
    ("series --gyro missing.csv", &["missing.csv"]),
    ("series --gyro longfield.csv", &["longfield.csv:2", "wx"]),
    ("trigger --gyro nonum.csv --policy fixed:5 --exposure 0.05", &["nonum.csv:3"]),
    // Overflow and non-finite results.
    ("eval --omega 1e308,1e308,0", &["overflows"]),
    ("eval --omega 1,nan,0", &["omega"]),
    ("eval --omega 1,2", &["omega"]),
    ("series --gyro huge.csv --out o.csv", &["t = 0 s", "overflows"]),
    ("flow --omega 1e308,1e308,0 --out f.exr", &["overflows", "nothing written"]),
    // Caps on sizes that multiply work or memory.
    ("eval --omega 1,1,1 --method gauss:6000", &["gauss:6000", "limits"]),
    ("eval --omega 1,1,1 --method gauss:100000", &["limits"]),
    ("eval --omega 1,1,1 --method riemann:100000x100000", &["limits"]),
    ("trigger --gyro good.csv --policy fixed:1e17 --exposure 0.05", &["fixed:1e17", "1000 frames/s"]),
    ("trigger --gyro good.csv --policy gate:0.8:1e17 --exposure 0.05", &["gate:0.8:1e17", "limit"]),
    ("trigger --gyro good.csv --policy deadline:1e9 --exposure 0.05", &["limit"]),
    ("simulate --config gait.toml --duration 1 --out s.csv", &["gait.toml", "step_hz", "100"]),
    ("simulate --config gait_type.toml --duration 1 --out s.csv", &["gait_type.toml", "step_hz"]),
    ("simulate --duration 1e12 --out s.csv", &["duration"]),
    ("simulate --rate 1e12 --duration 1 --out s.csv", &["Hz", "samples"]),
    (
        "render --omega 0.1,0,0 --exposure 0.05 --target checker:0.02 --distance 1 --resolution 100000x100000 --backend cpu --out big.png",
        &["resolution", "at most"],
    ),
    // Geometry that has no answer.
    (
        "render --omega 0,0,0 --velocity 0,0,5 --exposure 0.5 --target checker:0.02 --distance 1 --resolution 32x24 --backend cpu --out r.png",
        &["reaches the target plane"],
    ),
    ("eval --omega 0,0,0 --velocity 0,0,1 --plane 0,0,1,-1", &["plane"]),
    ("eval --omega 1,1,1 --focal -1", &["focal", "> 0"]),
    ("eval --omega 1,1,1 --focal=0", &["focal"]),
    ("eval --omega 1,1,1 --camera camera0.toml", &["camera0.toml", "focal"]),
    ("eval --omega 1,1,1 --camera camera_key.toml", &["camera_key.toml", "focal"]),
    (
        "render --gyro gap.csv --at 2.0 --exposure 0.05 --target checker:0.02 --distance 1 --resolution 32x24 --backend cpu --out r.png",
        &["gap"],
    ),
    // Outputs: checked before any work, all or nothing.
    (
        "render --omega 0.1,0,0 --exposure 0.05 --target checker:0.02 --distance 1 --resolution 32x24 --backend cpu --out ok.png --maps nodir/m.exr",
        &["nodir", "does not exist"],
    ),
    ("flow --omega 1,1,1 --out x.png", &["x.png", "exr"]),
    ("series --gyro good.csv --out nodir/o.csv", &["nodir"]),
    ("series --gyro good.csv --out .", &["directory"]),
    // Bad images and configs.
    ("blobs not.png", &["not.png"]),
    ("blobs nothere.png", &["nothere.png"]),
    ("assess not.png", &["not.png"]),
    ("experiment --config exp_key.toml --out rep", &["exp_key.toml", "walkz"]),
    ("experiment --config exp_val.toml --out rep", &["exp_val.toml", "policies", "fixed:0"]),
    ("trigger --gyro good.csv --policy bogus:1 --exposure 0.05", &["bogus:1"]),
    ("live --policy oracle:0.4", &["oracle"]),
    // The real-camera flags (SPEC 9) and `frames`.
    ("eval --omega 1,1,1 --rolling-readout=-1", &["readout_s", ">= 0"]),
    ("eval --omega 1,1,1 --rolling-readout nan", &["readout_s"]),
    ("eval --omega 1,1,1 --light 0", &["noise.phi_e_per_s"]),
    ("eval --omega 1,1,1 --readout-direction sideways", &["readout_direction", "sideways"]),
    ("eval --omega 1,1,1 --scale-to 0x10", &["0x10"]),
    ("frames --gyro good.csv --frames good.csv", &["good.csv:1", "t_start"]),
    ("frames --gyro good.csv --frames nothere.csv", &["nothere.csv"]),
    ("frames --gyro good.csv --frames good.csv --select 2 --gap nan", &["--gap"]),
];

#[test]
fn bad_inputs_are_clear_errors_that_leave_nothing() {
    let d = tempfile::tempdir().unwrap();
    files(d.path());
    let before = leftovers(d.path(), &[]);
    let mut failures = Vec::new();
    for (args, words) in BAD {
        let argv: Vec<&str> = args.split_whitespace().collect();
        let o = mmbm_in(d.path(), &argv);
        let err = String::from_utf8_lossy(&o.stderr);
        let mut why = Vec::new();
        if !matches!(o.status.code(), Some(1 | 2)) {
            why.push(format!("exit code {:?}", o.status.code()));
        }
        if !err.contains("error:") || err.contains("panicked") {
            why.push("no error line, or a panic".into());
        }
        for w in *words {
            if !err.contains(w) {
                why.push(format!("error does not say '{w}'"));
            }
        }
        if err.len() > 2000 {
            why.push(format!(
                "{} bytes on stderr (echoes must be clipped)",
                err.len()
            ));
        }
        let left = leftovers(d.path(), &before);
        if !left.is_empty() {
            why.push(format!("left {left:?}"));
            for n in left {
                let _ = std::fs::remove_file(d.path().join(&n));
                let _ = std::fs::remove_dir_all(d.path().join(&n));
            }
        }
        if !why.is_empty() {
            failures.push(format!(
                "mmbm {args}: {}\n    {}",
                why.join("; "),
                err.trim()
            ));
        }
    }
    assert!(failures.is_empty(), "\n{}", failures.join("\n"));
}

#[test]
fn edge_inputs_that_have_an_answer() {
    let d = tempfile::tempdir().unwrap();
    files(d.path());
    // A 1x1 image: no blobs, no crash.
    let o = mmbm_in(d.path(), &["blobs", "one.png"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // A gap is announced while the log is read.
    let o = mmbm_in(d.path(), &["series", "--gyro", "gap.csv", "--out", "g.csv"]);
    assert!(o.status.success());
    assert!(String::from_utf8_lossy(&o.stderr).contains("gap"));
    // A policy that never triggers summarises as n/a, not NaN.
    let o = mmbm_in(
        d.path(),
        &[
            "trigger",
            "--gyro",
            "calm.csv",
            "--policy",
            "threshold:0.001",
            "--exposure",
            "0.05",
            "--summary",
        ],
    );
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success() && out.contains("0 frames"), "{out}");
    assert!(out.contains("n/a") && !out.contains("NaN"), "{out}");
    // Negative numbers are values, not options.
    let o = mmbm_in(d.path(), &["eval", "--omega", "-1,-0.5,-2", "--json"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    // `-` is stdout for outputs.
    let o = mmbm_in(d.path(), &["series", "--gyro", "good.csv", "--out", "-"]);
    assert!(o.status.success());
    assert_eq!(String::from_utf8_lossy(&o.stdout).lines().count(), 5);
}

#[cfg(unix)]
#[test]
fn outputs_never_replace_what_they_point_at() {
    use std::os::unix::fs::FileTypeExt;
    let d = tempfile::tempdir().unwrap();
    files(d.path());
    // A device stays a device.
    let o = mmbm_in(
        d.path(),
        &["series", "--gyro", "good.csv", "--out", "/dev/null"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let m = std::fs::metadata("/dev/null").unwrap();
    assert!(m.file_type().is_char_device(), "/dev/null was replaced");
    // A symlink stays a link; its target gets the data.
    std::fs::write(d.path().join("real.csv"), "old").unwrap();
    std::os::unix::fs::symlink("real.csv", d.path().join("link.csv")).unwrap();
    let o = mmbm_in(
        d.path(),
        &["series", "--gyro", "good.csv", "--out", "link.csv"],
    );
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let l = std::fs::symlink_metadata(d.path().join("link.csv")).unwrap();
    assert!(
        l.file_type().is_symlink(),
        "the link was replaced by a file"
    );
    let text = std::fs::read_to_string(d.path().join("real.csv")).unwrap();
    assert!(text.starts_with("t,mmbm_mm_s"), "{text}");
    // A FIFO (as `--out >(cat)` gives) is written in place.
    let fifo = d.path().join("pipe");
    let st = Command::new("mkfifo").arg(&fifo).status().unwrap();
    assert!(st.success());
    let reader = {
        let fifo = fifo.clone();
        std::thread::spawn(move || std::fs::read_to_string(fifo).unwrap())
    };
    let o = mmbm_in(d.path(), &["series", "--gyro", "good.csv", "--out", "pipe"]);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    let got = reader.join().unwrap();
    assert_eq!(got.lines().count(), 5, "{got}");
    let m = std::fs::symlink_metadata(&fifo).unwrap();
    assert!(m.file_type().is_fifo(), "the FIFO was replaced");
}

#[cfg(unix)]
#[test]
fn an_interrupt_removes_temporary_files() {
    let d = tempfile::tempdir().unwrap();
    let mut child = common::mmbm_cmd()
        .args(["series", "--gyro", "-", "--out", "o.csv"])
        .current_dir(d.path())
        .stdin(Stdio::piped())
        .stdout(Stdio::null())
        .stderr(Stdio::piped())
        .spawn()
        .unwrap();
    let mut stdin = child.stdin.take().unwrap();
    use std::io::Write;
    let mut text = String::from("t,wx,wy,wz\n");
    for k in 0..100_000 {
        text += &format!("{},0.1,0.2,0.3\n", k as f64 * 0.001);
    }
    stdin.write_all(text.as_bytes()).unwrap();
    stdin.flush().unwrap();
    // Wait until the temporary output exists, then interrupt.
    let mut seen = false;
    for _ in 0..100 {
        std::thread::sleep(std::time::Duration::from_millis(50));
        if leftovers(d.path(), &[]).iter().any(|n| n.contains(".tmp")) {
            seen = true;
            break;
        }
    }
    assert!(
        seen,
        "no temporary file appeared: {:?}",
        leftovers(d.path(), &[])
    );
    let st = Command::new("sh")
        .args(["-c", &format!("kill -INT {}", child.id())])
        .status()
        .unwrap();
    assert!(st.success());
    let o = child.wait_with_output().unwrap();
    drop(stdin);
    assert_eq!(o.status.code(), Some(130));
    assert!(String::from_utf8_lossy(&o.stderr).contains("interrupted"));
    assert_eq!(leftovers(d.path(), &[]), Vec::<String>::new());
}

#[test]
fn real_logs_at_absurd_rates_are_refused_quickly() {
    if let Some(car) = common::shared_log("dashboard_car") {
        let o = common::mmbm_cmd()
            .args([
                "trigger",
                "--policy",
                "fixed:1e9",
                "--exposure",
                "0.03",
                "--gyro",
            ])
            .arg(car)
            .output()
            .unwrap();
        // A malformed flag is clap's error: exit 2 (issue #22).
        assert_eq!(o.status.code(), Some(2));
        assert!(String::from_utf8_lossy(&o.stderr).contains("1000 frames/s"));
    }
}

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
        ],
    );
    let out = String::from_utf8_lossy(&o.stdout);
    assert!(o.status.success(), "{}", String::from_utf8_lossy(&o.stderr));
    assert!(out.contains("fixed:5: 10 frames"), "{out}");
    // live: the first sample is refused (exit 1), not decided with a zero exposure.
    let o = common::mmbm_cmd()
        .current_dir(dir.path())
        .args([
            "live", "--replay", "ns.csv", "--speed", "0", "--policy", "fixed:5",
        ])
        .output()
        .unwrap();
    let err = String::from_utf8_lossy(&o.stderr);
    assert!(!o.status.success() && err.contains("--time-unit"), "{err}");
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
    let cfg = |motion: &str| mmbm::dataset::DatasetConfig {
        textures: tex.clone(),
        motion: vec![motion.into()],
        count: 1,
        ..Default::default()
    };
    let (tx, rx) = std::sync::mpsc::channel();
    let (ok, zero) = (cfg("sim:slow"), cfg("log:/dev/zero"));
    std::thread::spawn(move || {
        let a = mmbm::dataset::Sources::open(&ok).map(|s| s.textures);
        let b = mmbm::dataset::Sources::open(&zero).map(|_| ());
        let _ = tx.send((a, b.map_err(|e| e.to_string())));
    });
    let (a, b) = rx
        .recv_timeout(std::time::Duration::from_secs(20))
        .expect("Sources::open blocked on a FIFO texture");
    assert_eq!(a.unwrap(), ["a.png"]);
    assert!(b.unwrap_err().contains("character device"));
}
