//! The standing bad-input suite: every subcommand against a table of bad and
//! edge-case inputs. A bad input must give exit code 1 (2 for a malformed
//! command line, as clap reports it; never 101, a panic, or 134, an abort), an `error:` line naming the file and line/column or the
//! parameter or key, and leave no output and no temporary file behind.

use crate::common;
use crate::robust;

use common::mmbm_in;
use robust::{files, leftovers, unclear_errors};
use std::process::{Command, Stdio};

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
    // The real-camera flags (docs/spec.md section 9) and `frames`.
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
    let failures = unclear_errors(d.path(), BAD);
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
            "--out",
            "calm-frames.csv",
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

/// SIGINT, and SIGTERM and SIGHUP (what `timeout`, systemd and SLURM send;
/// issue #23 item 7) alike: the temporary output is removed, exit 130.
#[cfg(unix)]
#[test]
fn an_interrupt_removes_temporary_files() {
    for sig in ["INT", "TERM", "HUP"] {
        interrupt_removes_temporary_files(sig);
    }
}

#[cfg(unix)]
fn interrupt_removes_temporary_files(sig: &str) {
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
        .args(["-c", &format!("kill -{sig} {}", child.id())])
        .status()
        .unwrap();
    assert!(st.success());
    let o = child.wait_with_output().unwrap();
    drop(stdin);
    assert_eq!(o.status.code(), Some(130), "SIG{sig}");
    assert!(
        String::from_utf8_lossy(&o.stderr).contains("interrupted"),
        "SIG{sig}"
    );
    assert_eq!(leftovers(d.path(), &[]), Vec::<String>::new(), "SIG{sig}");
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
