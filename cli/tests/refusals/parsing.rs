//! Issue 35 (reliability), items 4, 5, 11 and 12: lens profiles parsed in
//! linear time with a cap on their lists, a live stream that one bad sample
//! cannot stop, time bases never silent (frames, short logs, frame numbers,
//! readouts, `--lens-focal`, policy keys, Python's integers) and messages that
//! say what is wrong (the missing key; no run of spaces from a source line).

use crate::common;

use mmbm::camera::{CameraFile, CameraOverrides};
use mmbm::Camera;
use serde_json::{json, Value};
use std::path::{Path, PathBuf};
use std::process::Output;
use std::time::{Duration, Instant};

/// A plain Gyroflow profile of a 1920 x 1080 video (fx = fy = 1000 px).
fn profile() -> Value {
    json!({
        "calib_dimension": {"w": 1920, "h": 1080},
        "distortion_model": "opencv_fisheye",
        "fisheye_params": {
            "camera_matrix": [[1000.0, 0.0, 960.0], [0.0, 1000.0, 540.0], [0.0, 0.0, 1.0]],
            "distortion_coeffs": [0.01, 0.0, 0.0, 0.0],
        },
    })
}

fn write(dir: &Path, name: &str, text: &str) -> PathBuf {
    let p = dir.join(name);
    std::fs::write(&p, text).unwrap();
    p
}

fn resolve(path: &Path, video: Option<(u32, u32)>, focal: Option<f64>) -> mmbm::Result<Camera> {
    let over = CameraOverrides {
        keys: CameraFile::default(),
        scale_to: video,
        light_e_per_s: None,
        lens_focal_mm: focal,
    };
    Camera::resolve(Some(path), &over)
}

fn stderr(o: &Output) -> String {
    String::from_utf8_lossy(&o.stderr).into_owned()
}

/// `mmbm ARGS` in `dir`, killed (and the test failed) after `secs`; with
/// its wall time.
fn timed(dir: &Path, args: &[&str], secs: u64) -> (Output, Duration) {
    let start = Instant::now();
    let o = common::mmbm_within(dir, args, Vec::new(), secs);
    (o, start.elapsed())
}

/// The 35,000-entry profile of the probe (940 kB): refused by its cap,
/// naming the key and the count, at once (it ran past 600 s).
#[test]
fn a_profile_of_35000_compatible_settings_is_refused_at_once() {
    let dir = tempfile::tempdir().unwrap();
    let mut p = profile();
    let entries: Vec<Value> = (0..35_000)
        .map(|k| json!({"width": 2 * (k % 4000) + 2, "height": 1080}))
        .collect();
    p["compatible_settings"] = Value::Array(entries);
    let text = p.to_string();
    assert!(text.len() < 1 << 20, "{} bytes", text.len());
    write(dir.path(), "big.json", &text);
    for extra in [&[][..], &["--scale-to", "1280x720"][..]] {
        let mut args = vec!["eval", "--omega", "1,1,1", "--camera", "big.json"];
        args.extend_from_slice(extra);
        let (o, took) = timed(dir.path(), &args, 60);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(1), "{err}");
        assert!(
            err.contains("compatible_settings") && err.contains("35000"),
            "{err}"
        );
        assert!(took < Duration::from_secs(2), "{took:?}");
    }
}

/// At the cap, a profile parses in milliseconds: each entry is matched by
/// its size, only the chosen one copied (8192 entries took about 16 s).
#[test]
fn compatible_settings_at_the_cap_parse_in_linear_time() {
    let dir = tempfile::tempdir().unwrap();
    let mut p = profile();
    let n = mmbm::limits::MAX_PROFILE_ENTRIES;
    // Every entry but the last of another size; the last 1280 x 720
    // (the same aspect: the matrix scales by 2/3).
    let mut entries: Vec<Value> = (0..n - 1)
        .map(|k| json!({"width": 2 * (k % 500) + 2, "height": 2 * (k % 7) + 2}))
        .collect();
    entries.push(json!({"width": 1280, "height": 720, "frame_readout_time": 12.0}));
    p["compatible_settings"] = Value::Array(entries);
    let path = write(dir.path(), "cap.json", &p.to_string());
    let start = Instant::now();
    let c = resolve(&path, Some((1280, 720)), None).unwrap();
    let took = start.elapsed();
    assert_eq!((c.width, c.height, c.shutter.readout_s), (1280, 720, 0.012));
    assert!(
        (c.fx_px() - 1000.0 * 2.0 / 3.0).abs() < 1e-9,
        "{}",
        c.fx_px()
    );
    // Python's Camera.from_file and every command read it the same way.
    let start_plain = Instant::now();
    let plain = resolve(&path, None, None).unwrap();
    let took_plain = start_plain.elapsed();
    assert_eq!((plain.width, plain.shutter.readout_s), (1920, 0.0));
    eprintln!("{n} entries: {took:?} with --scale-to, {took_plain:?} without");
    assert!(took < Duration::from_secs(2), "{took:?}");
    assert!(took_plain < Duration::from_secs(2), "{took_plain:?}");
    // One more entry is refused by the cap.
    let mut q = p.clone();
    q["compatible_settings"]
        .as_array_mut()
        .unwrap()
        .push(json!({}));
    let path = write(dir.path(), "over.json", &q.to_string());
    let e = resolve(&path, None, None).unwrap_err().to_string();
    assert!(
        e.contains("compatible_settings") && e.contains(&format!("{}", n + 1)),
        "{e}"
    );
}

/// Many `interpolations` (a zoom lens every 0.001 mm, fx = 100 px/mm x f):
/// `--lens-focal` between two entries is their linear interpolation, in
/// milliseconds (the whole profile was copied per entry).
#[test]
fn many_interpolations_parse_in_linear_time() {
    let dir = tempfile::tempdir().unwrap();
    let mut p = profile();
    let n = mmbm::limits::MAX_PROFILE_ENTRIES;
    let mut map = serde_json::Map::new();
    for k in 0..n {
        let f = 10.0 + k as f64 * 0.001;
        let fx = 100.0 * f;
        map.insert(
            format!("{f:.3}"),
            json!({"camera_matrix": [[fx, 0, 960], [0, fx, 540], [0, 0, 1]], "focal_length": f}),
        );
    }
    p["interpolations"] = Value::Object(map);
    let text = p.to_string();
    assert!(text.len() < 1 << 20, "{} bytes", text.len());
    let path = write(dir.path(), "zoom.json", &text);
    let start = Instant::now();
    let c = resolve(&path, None, Some(12.3455)).unwrap();
    let took = start.elapsed();
    assert!((c.fx_px() - 1234.55).abs() < 1e-6, "{}", c.fx_px());
    assert!((c.focal_mm - 12.3455).abs() < 1e-9, "{}", c.focal_mm);
    eprintln!("{n} interpolations: {took:?}");
    assert!(took < Duration::from_secs(2), "{took:?}");
    // The CLI (eval, series, ...) the same, well under a second.
    let (o, took) = timed(
        dir.path(),
        &[
            "eval",
            "--omega",
            "1,1,1",
            "--camera",
            "zoom.json",
            "--lens-focal",
            "12.3455",
        ],
        60,
    );
    assert!(o.status.success(), "{}", stderr(&o));
    assert!(took < Duration::from_secs(2), "{took:?}");
    // Over the cap: refused by key and count.
    let mut q = p.clone();
    q["interpolations"]["99"] = json!({"camera_matrix": [[1, 0, 1], [0, 1, 1], [0, 0, 1]]});
    let path = write(dir.path(), "zoom_over.json", &q.to_string());
    let e = resolve(&path, None, Some(12.0)).unwrap_err().to_string();
    assert!(
        e.contains("interpolations") && e.contains(&format!("{}", n + 1)),
        "{e}"
    );
}

/// A profile without `fisheye_params` names that key, not
/// "unknown field calib_dimension".
#[test]
fn a_profile_without_fisheye_params_names_the_missing_key() {
    let dir = tempfile::tempdir().unwrap();
    let mut p = profile();
    p.as_object_mut().unwrap().remove("fisheye_params");
    let path = write(dir.path(), "nofp.json", &p.to_string());
    let e = resolve(&path, None, None).unwrap_err().to_string();
    assert!(
        e.contains("fisheye_params") && e.contains("missing") && !e.contains("unknown field"),
        "{e}"
    );
    assert!(e.contains("nofp.json"), "{e}");
}

/// `--lens-focal` on a profile without `interpolations` is refused, not
/// ignored.
#[test]
fn lens_focal_without_interpolations_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(dir.path(), "plain.json", &profile().to_string());
    let e = resolve(&path, None, Some(20.0)).unwrap_err().to_string();
    assert!(
        e.contains("no interpolations") && e.contains("--lens-focal"),
        "{e}"
    );
    // Without the flag the profile reads as before.
    assert!(resolve(&path, None, None).is_ok());
}

fn json_lines(o: &Output) -> Vec<Value> {
    String::from_utf8_lossy(&o.stdout)
        .lines()
        .map(|l| serde_json::from_str(l).unwrap())
        .collect()
}

/// The probe's stream: a sample at t = 1e308 (no time base resolves an
/// exposure there), then good ones.
const BAD_THEN_GOOD: &str = "t,wx,wy,wz\n1e308,0.1,0.2,0.3\n0.01,0.1,0.2,0.3\n0.02,0.1,0.2,0.3\n";

/// Without --strict the bad sample is reported (its line and why) and
/// skipped and the later samples are read; with --strict it stops (exit 2).
#[test]
fn live_skips_a_bad_sample_on_stdin() {
    let dir = tempfile::tempdir().unwrap();
    let args = ["live", "--policy", "fixed:5", "--all"];
    let o = common::mmbm_within(dir.path(), &args, BAD_THEN_GOOD.into(), 30);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(
        err.contains("<stdin>:2:") && err.contains("time base") && err.contains("skipped"),
        "{err}"
    );
    let ts: Vec<f64> = json_lines(&o)
        .iter()
        .map(|v| v["t"].as_f64().unwrap())
        .collect();
    assert_eq!(ts, vec![0.01, 0.02], "{err}");
    let strict = ["live", "--policy", "fixed:5", "--all", "--strict"];
    let o = common::mmbm_within(dir.path(), &strict, BAD_THEN_GOOD.into(), 30);
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(2), "{err}");
    assert!(
        err.contains("error:") && err.contains("<stdin>:2:"),
        "{err}"
    );
    assert!(json_lines(&o).is_empty());
}

/// The same sample in a UDP datagram on 127.0.0.1 no longer ends the listener.
#[test]
fn live_skips_a_bad_datagram() {
    let (child, sock, addr) = common::udp_live();
    for d in [
        "t,wx,wy,wz",
        "1e308,0.1,0.2,0.3",
        "0.01,0.1,0.2,0.3\n0.02,0.1,0.2,0.3",
    ] {
        sock.send_to(d.as_bytes(), &addr).unwrap();
    }
    let o = child.wait_with_output().unwrap();
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(0), "{err}");
    assert!(
        err.contains("<udp>:2:") && err.contains("time base") && err.contains("skipped"),
        "{err}"
    );
    let ts: Vec<f64> = json_lines(&o)
        .iter()
        .map(|v| v["t"].as_f64().unwrap())
        .collect();
    assert_eq!(ts, vec![0.01, 0.02], "{err}");
}

/// `--speed 1e-300` waited for ever; it is refused at parse (exit 2),
/// naming the flag and the range.
#[test]
fn a_replay_speed_out_of_range_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    write(
        dir.path(),
        "g.csv",
        "t,wx,wy,wz\n0,0.1,0.2,0.3\n0.01,0.1,0.2,0.3\n",
    );
    for speed in ["1e-300", "5e-324", "1e-4", "1e7"] {
        let args = [
            "live", "--policy", "fixed:5", "--replay", "g.csv", "--speed", speed,
        ];
        let (o, _) = timed(dir.path(), &args, 30);
        let err = stderr(&o);
        assert_eq!(o.status.code(), Some(2), "{speed}: {err}");
        assert!(
            err.contains("--speed") && err.contains("0.001") && err.contains("1e6"),
            "{speed}: {err}"
        );
    }
}

/// A gyro log at 100 Hz (0.01 s) whose times are `t0 + k * step`.
fn gyro_log(t0: f64, step: f64, n: usize) -> String {
    let mut s = String::from("t,wx,wy,wz\n");
    for k in 0..n {
        s += &format!("{},0.3,-0.2,0.5\n", t0 + k as f64 * step);
    }
    s
}

/// Nanosecond epoch stamps read as seconds (1.7e18 s, 256 s apart): frames
/// refuses them with trigger's hint, and series with --exposure too.
#[test]
fn frames_on_nanosecond_stamps_are_refused_with_the_hint() {
    let dir = tempfile::tempdir().unwrap();
    let t0 = 1.7e18;
    write(dir.path(), "ns.csv", &gyro_log(t0, 1e7, 200));
    let table = format!("t_start,exposure_s\n{},0.01\n{},0.01\n", t0 + 1e8, t0 + 2e8);
    write(dir.path(), "frames.csv", &table);
    let o = common::mmbm_in(
        dir.path(),
        &["frames", "--gyro", "ns.csv", "--frames", "frames.csv"],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(
        err.contains("time base") && err.contains("--time-unit"),
        "{err}"
    );
    assert!(o.stdout.is_empty());
    let o = common::mmbm_in(
        dir.path(),
        &["series", "--gyro", "ns.csv", "--exposure", "0.01"],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("--time-unit"), "{err}");
    // With --time-unit ns the same stamps (1.7e9 s) time the exposure.
    // (The table is in seconds of the same clock: 1.7e9 s.)
    let table = format!(
        "t_start,exposure_s\n{},0.01\n{},0.01\n",
        1.7e9 + 0.1,
        1.7e9 + 0.2
    );
    write(dir.path(), "frames_s.csv", &table);
    let o = common::mmbm_in(
        dir.path(),
        &[
            "frames",
            "--gyro",
            "ns.csv",
            "--frames",
            "frames_s.csv",
            "--time-unit",
            "ns",
        ],
    );
    assert!(o.status.success(), "{}", stderr(&o));
}

/// A 5 s gap in a short 100 Hz log (40 samples, fewer than the 101 the
/// streamed gap rule read first) is a warning naming its line.
#[test]
fn a_gap_in_a_short_log_is_warned() {
    let dir = tempfile::tempdir().unwrap();
    let mut s = gyro_log(0.0, 0.01, 20);
    for k in 0..20 {
        s += &format!("{},0.3,-0.2,0.5\n", 5.19 + k as f64 * 0.01);
    }
    write(dir.path(), "short.csv", &s);
    let o = common::mmbm_ok_in(dir.path(), &["series", "--gyro", "short.csv"]);
    let err = stderr(&o);
    assert!(
        err.contains("gap of 5.0") && err.contains("short.csv:22"),
        "{err}"
    );
    // Without the gap: no warning; 2 samples (1 interval): no rule.
    write(dir.path(), "even.csv", &gyro_log(0.0, 0.01, 40));
    let o = common::mmbm_ok_in(dir.path(), &["series", "--gyro", "even.csv"]);
    assert!(!stderr(&o).contains("gap"), "{}", stderr(&o));
    write(dir.path(), "two.csv", "t,wx,wy,wz\n0,0,0,1\n5,0,0,1\n");
    let o = common::mmbm_ok_in(dir.path(), &["series", "--gyro", "two.csv"]);
    assert!(!stderr(&o).contains("gap"), "{}", stderr(&o));
    // Three samples: a 5 s interval after 10 ms is a gap.
    write(
        dir.path(),
        "three.csv",
        "t,wx,wy,wz\n0,0,0,1\n0.01,0,0,1\n5.01,0,0,1\n",
    );
    let o = common::mmbm_ok_in(dir.path(), &["series", "--gyro", "three.csv"]);
    assert!(stderr(&o).contains("gap of 5.0"), "{}", stderr(&o));
}

/// `--frame-start` whose last frame number passes u64::MAX wrapped the
/// names; it is refused by name before any work.
#[test]
fn a_frame_start_that_overflows_is_refused() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "g.csv", &gyro_log(0.0, 0.01, 100));
    write(
        dir.path(),
        "f.csv",
        "t_start,exposure_s\n0.1,0.01\n0.2,0.01\n",
    );
    let run = |start: &str| {
        common::mmbm_in(
            dir.path(),
            &[
                "frames",
                "--gyro",
                "g.csv",
                "--frames",
                "f.csv",
                "--select",
                "2",
                "--image-list",
                "list.txt",
                "--frame-start",
                start,
            ],
        )
    };
    let o = run("18446744073709551615");
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("--frame-start"), "{err}");
    assert!(!dir.path().join("list.txt").exists());
    // The largest start that fits: the last frame is u64::MAX.
    let o = run("18446744073709551614");
    assert!(o.status.success(), "{}", stderr(&o));
    let list = std::fs::read_to_string(dir.path().join("list.txt")).unwrap();
    assert_eq!(
        list,
        "frame_18446744073709551614.png\nframe_18446744073709551615.png\n"
    );
}

/// An image list's readout column (`readout_ns`, or `readout_s` in
/// seconds) is each frame's own rolling-shutter readout, as a plain frame
/// table's `readout_s`: the output's readout_s column says so.
#[test]
fn an_image_list_readout_column_is_honoured() {
    let dir = tempfile::tempdir().unwrap();
    write(dir.path(), "g.csv", &gyro_log(0.0, 0.01, 100));
    for (name, text) in [
        (
            "ns.txt",
            "timestamp_ns,exposure_ns,readout_ns\n100000000,10000000,20000000\n200000000,10000000,5000000\n",
        ),
        (
            "s.txt",
            "timestamp_ns,exposure_ns,readout_s\n100000000,10000000,0.02\n200000000,10000000,0.005\n",
        ),
    ] {
        write(dir.path(), name, text);
        let o = common::mmbm_ok_in(
            dir.path(),
            &["frames", "--gyro", "g.csv", "--frames", name],
        );
        let out = String::from_utf8_lossy(&o.stdout);
        let readouts: Vec<&str> = out
            .lines()
            .skip(1)
            .map(|l| l.rsplit(',').next().unwrap())
            .collect();
        assert_eq!(readouts, ["0.02", "0.005"], "{name}: {out}");
    }
    // A negative readout is refused by its column.
    write(
        dir.path(),
        "neg.txt",
        "timestamp_ns,exposure_ns,readout_ns\n100000000,10000000,-1\n",
    );
    let o = common::mmbm_in(
        dir.path(),
        &["frames", "--gyro", "g.csv", "--frames", "neg.txt"],
    );
    let err = stderr(&o);
    assert_eq!(o.status.code(), Some(1), "{err}");
    assert!(err.contains("neg.txt:2:readout_ns"), "{err}");
}

/// A policy key given twice is refused in every key=value form (ae, task),
/// naming the key; once each is accepted.
#[test]
fn a_policy_key_given_twice_is_refused() {
    use mmbm::trigger::PolicySpec;
    for (spec, key) in [
        ("ae:5:cap=10ms:cap=3ms", "cap"),
        ("ae:5:target=0.5:damp=0.5:target=0.4", "target"),
        ("ae:5: scene=0.3:scene =0.3", "scene"),
        ("task:5:light=20000:light=1000", "light"),
        ("task:5:light=20000:tmin=1ms:tmin=2ms", "tmin"),
        ("task:5:light=20000:read=2:read=3+exp:2", "read"),
    ] {
        let e = PolicySpec::parse(spec).unwrap_err().to_string();
        assert!(
            e.contains(&format!("key '{key}' is given twice")),
            "{spec}: {e}"
        );
    }
    for ok in [
        "ae:5:cap=10ms:target=0.4",
        "task:5:light=20000:tmin=1ms:read=2",
    ] {
        assert!(PolicySpec::parse(ok).is_ok(), "{ok}");
    }
}

/// A run of 3 or more spaces in a message is a source line's continuation
/// left in a string literal.
fn has_space_run(s: &str) -> bool {
    s.contains("   ")
}

/// Every message of this suite's bad inputs names what is wrong in one line,
/// with no run of spaces (the `identifier` entry's carried 18).
#[test]
fn messages_have_no_runs_of_spaces() {
    let dir = tempfile::tempdir().unwrap();
    let d = dir.path();
    let mut p = profile();
    p["interpolations"] = json!({"14": {"identifier": "some-lens"}, "24": {"identifier": "other"}});
    write(d, "ident.json", &p.to_string());
    let mut q = profile();
    q.as_object_mut().unwrap().remove("fisheye_params");
    write(d, "nofp.json", &q.to_string());
    write(d, "plain.json", &profile().to_string());
    write(d, "g.csv", &gyro_log(0.0, 0.01, 100));
    write(d, "f.csv", "t_start,exposure_s\n0.1,0.01\n0.2,0.01\n");
    write(d, "ns.csv", &gyro_log(1.7e18, 1e7, 50));
    write(
        d,
        "fns.csv",
        &format!("t_start,exposure_s\n{},0.01\n", 1.7e18 + 1e8),
    );
    let table: &[(&str, &[&str])] = &[
        (
            "eval --omega 1,1,1 --camera ident.json --lens-focal 20",
            &["interpolations.14", "identifier"],
        ),
        ("eval --omega 1,1,1 --camera nofp.json", &["fisheye_params"]),
        (
            "eval --omega 1,1,1 --camera plain.json --lens-focal 20",
            &["--lens-focal"],
        ),
        (
            "trigger --gyro g.csv --policy ae:5:cap=10ms:cap=3ms",
            &["given twice"],
        ),
        (
            "frames --gyro g.csv --frames f.csv --select 1 --image-list l.txt --frame-start 18446744073709551615",
            &["--frame-start"],
        ),
        ("frames --gyro ns.csv --frames fns.csv", &["--time-unit"]),
        (
            "live --policy fixed:5 --replay g.csv --speed 1e-300",
            &["--speed"],
        ),
    ];
    let mut failures = Vec::new();
    for (args, words) in table {
        let argv: Vec<&str> = args.split_whitespace().collect();
        let o = common::mmbm_in(d, &argv);
        let err = stderr(&o);
        if !matches!(o.status.code(), Some(1 | 2)) || !err.contains("error:") {
            failures.push(format!("{args}: exit {:?}: {err}", o.status.code()));
        }
        for w in *words {
            if !err.contains(w) {
                failures.push(format!("{args}: does not say '{w}': {err}"));
            }
        }
        if has_space_run(&err) {
            failures.push(format!("{args}: a run of spaces: {err:?}"));
        }
    }
    assert!(failures.is_empty(), "{}", failures.join("\n"));
}
